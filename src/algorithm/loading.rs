//! Tissue loading along any schedule, for the dive-profile plot (`plan --plot`): ZH-L16C's
//! 16 compartments (N2 and He, Schreiner's equation, compartment 1b) in the schedule's own
//! conventions, sampled through every leg; the ceiling at a chosen gradient factor and each
//! compartment's fraction of its M-value gradient (the heat map of DecoTengu's `dt-plot` and
//! Subsurface's planner). For a VPM-B schedule this is the Bühlmann view of the same dive,
//! not VPM-B's own criterion (say so where it is shown).

use super::buhlmann::{compartments, FirstCompartment, Variant, ZhL16, COMPARTMENTS};
use super::{Conventions, Schedule};

/// One sample of the loading.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadingSample {
    /// Runtime, min.
    pub time_min: f64,
    /// Depth, m.
    pub depth_m: f64,
    /// Ceiling at the gradient factor asked for, m (0 when the surface is allowed).
    pub ceiling_m: f64,
    /// Each compartment's fraction of its M-value gradient at this depth (fastest first).
    pub gradient: [f64; COMPARTMENTS],
}

/// Sample the ZH-L16C loading along `schedule` every `step_min` minutes (and at every leg
/// end), starting from tissues saturated with air at the surface. `gf` is the gradient factor
/// of the ceiling (1 = the M-value line).
pub fn loading(
    schedule: &Schedule,
    conventions: &Conventions,
    gf: f64,
    step_min: f64,
) -> Vec<LoadingSample> {
    let model = ZhL16::new(
        compartments(Variant::C, FirstCompartment::OneB),
        conventions.water_vapour_pa / 1e5,
    );
    let surface = conventions.surface_pressure_pa / 1e5;
    let bar_per_m = conventions.pa_per_m / 1e5;
    let mut tissues = model.surface_tissues(surface, conventions.surface_tissue_n2_fraction);
    let sample = |t: f64, depth: f64, tis: &super::buhlmann::Tissues| {
        let ceil_bar = model.ceiling(tis, gf);
        LoadingSample {
            time_min: t,
            depth_m: depth,
            ceiling_m: ((ceil_bar - surface) / bar_per_m).max(0.0),
            gradient: model.gradient_fraction(tis, surface + depth * bar_per_m),
        }
    };
    let mut out = vec![sample(0.0, 0.0, &tissues)];
    let mut t0 = 0.0;
    let step = step_min.max(1e-3);
    for leg in schedule.legs.iter().filter(|l| l.duration_s > 0.0) {
        let minutes = leg.duration_s / 60.0;
        let rate_m_min = (leg.end_depth_m - leg.start_depth_m) / minutes;
        let p0 = surface + leg.start_depth_m * bar_per_m;
        let n = (minutes / step).ceil().max(1.0) as usize;
        for k in 1..=n {
            let dt = minutes * k as f64 / n as f64;
            let tis = model.load(&tissues, p0, rate_m_min * bar_per_m, dt, leg.gas);
            let depth = leg.start_depth_m + rate_m_min * dt;
            out.push(sample(t0 + dt, depth, &tis));
            if k == n {
                tissues = tis;
            }
        }
        t0 += minutes;
    }
    out
}
