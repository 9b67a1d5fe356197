//! Oxygen exposure of a schedule: CNS % (NOAA single-exposure limits) and OTU
//! (Lambertsen's unit pulmonary toxicity dose as formulated by Hamilton).
//!
//! - CNS: each minute at oxygen partial pressure `P` uses `100 / limit(P)` % of the CNS clock,
//!   with `limit` the NOAA single-exposure limit (NOAA Diving Manual, 4th ed. 2001, table 3-3),
//!   interpolated linearly between the table rows; no CNS load at or below 0.5 bar.
//! - OTU: `dOTU/dt = ((P − 0.5) / 0.5)^0.83` per minute for `P > 0.5` bar (Lambertsen's UPTD,
//!   Hamilton's REPEX formulation; Hamilton R.W., "Tolerating exposure to high oxygen levels:
//!   REPEX and other methods", Marine Technology Society Journal 23(4), 1989).
//!
//! Partial pressures are in bar (planners use bar for atm interchangeably) and are taken from
//! the ambient pressure without water vapour. Linear legs are integrated numerically (Simpson).

use super::schedule::Schedule;

/// NOAA single-exposure limits: (ppO2 in bar, minutes). NOAA Diving Manual 4th ed., table 3-3.
pub const NOAA_CNS_LIMITS: [(f64, f64); 11] = [
    (0.6, 720.0),
    (0.7, 570.0),
    (0.8, 450.0),
    (0.9, 360.0),
    (1.0, 300.0),
    (1.1, 240.0),
    (1.2, 210.0),
    (1.3, 180.0),
    (1.4, 150.0),
    (1.5, 120.0),
    (1.6, 45.0),
];

/// Single-exposure limit at `ppo2_bar`, min (`None` at or below 0.5 bar: no CNS load).
/// Between 0.5 and 0.6 bar the 0.6-bar limit is used; above 1.6 bar the 1.6-bar limit
/// (such exposures are rejected by plan validation anyway).
pub fn cns_limit_min(ppo2_bar: f64) -> Option<f64> {
    if ppo2_bar <= 0.5 {
        return None;
    }
    let t = &NOAA_CNS_LIMITS;
    if ppo2_bar <= t[0].0 {
        return Some(t[0].1);
    }
    for w in t.windows(2) {
        let ((p0, l0), (p1, l1)) = (w[0], w[1]);
        if ppo2_bar <= p1 {
            return Some(l0 + (l1 - l0) * (ppo2_bar - p0) / (p1 - p0));
        }
    }
    Some(t[t.len() - 1].1)
}

/// CNS rate, % per minute.
pub fn cns_rate(ppo2_bar: f64) -> f64 {
    cns_limit_min(ppo2_bar).map_or(0.0, |l| 100.0 / l)
}

/// OTU rate, OTU per minute.
pub fn otu_rate(ppo2_bar: f64) -> f64 {
    if ppo2_bar <= 0.5 {
        0.0
    } else {
        ((ppo2_bar - 0.5) / 0.5).powf(0.83)
    }
}

/// The oxygen exposure of a plan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OxygenExposure {
    /// CNS clock, % of the NOAA limit.
    pub cns_percent: f64,
    /// Pulmonary toxicity, OTU.
    pub otu: f64,
}

/// Integrate `f(ppO2)` over a leg whose ppO2 changes linearly from `p0` to `p1` in `minutes`.
fn integrate(f: impl Fn(f64) -> f64, p0: f64, p1: f64, minutes: f64) -> f64 {
    if minutes <= 0.0 {
        return 0.0;
    }
    if (p1 - p0).abs() < 1e-12 {
        return f(p0) * minutes;
    }
    // Composite Simpson; the integrands have kinks (0.5 bar, table rows), so use many panels.
    let n = 400;
    let h = 1.0 / n as f64;
    let mut s = f(p0) + f(p1);
    for i in 1..n {
        let p = p0 + (p1 - p0) * i as f64 * h;
        s += if i % 2 == 1 { 4.0 } else { 2.0 } * f(p);
    }
    s * h / 3.0 * minutes
}

/// CNS % and OTU accumulated over the schedule's legs.
pub fn exposure(schedule: &Schedule) -> OxygenExposure {
    let mut cns = 0.0;
    let mut otu = 0.0;
    for l in &schedule.legs {
        let minutes = l.duration_s / 60.0;
        let p0 = l.gas.o2 * schedule.pressure_at(l.start_depth_m) / 1e5;
        let p1 = l.gas.o2 * schedule.pressure_at(l.end_depth_m) / 1e5;
        cns += integrate(cns_rate, p0, p1, minutes);
        otu += integrate(otu_rate, p0, p1, minutes);
    }
    OxygenExposure {
        cns_percent: cns,
        otu,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::schedule::{Leg, LegKind};
    use crate::gas::GasMix;

    fn sched(legs: Vec<Leg>) -> Schedule {
        Schedule {
            label: "t".into(),
            surface_pressure_pa: 100_000.0,
            pa_per_m: 10_000.0,
            water_vapour_pa: 0.0,
            legs,
            stops: vec![],
        }
    }

    #[test]
    fn constant_exposure_matches_hand_computation() {
        // 30 min of O2 at 4 m (1.4 bar): CNS = 30/150 = 20 % (NOAA 1.4 bar → 150 min);
        // OTU = 30 × (0.9/0.5)^0.83 = 30 × e^(0.83·ln 1.8) = 30 × 1.628831… = 48.865 (by hand).
        let o2 = GasMix::new(1.0, 0.0).unwrap();
        let s = sched(vec![Leg {
            kind: LegKind::Stop,
            start_depth_m: 4.0,
            end_depth_m: 4.0,
            duration_s: 1800.0,
            gas: o2,
        }]);
        let e = exposure(&s);
        assert!((e.cns_percent - 20.0).abs() < 1e-9, "{}", e.cns_percent);
        assert!((e.otu - 48.865).abs() < 1e-3, "{}", e.otu);
        // Interpolated limit: 1.45 bar → 135 min.
        assert!((cns_limit_min(1.45).unwrap() - 135.0).abs() < 1e-9);
        assert_eq!(cns_limit_min(0.45), None);
    }

    #[test]
    fn linear_leg_matches_the_closed_form_otu_integral() {
        // ppO2 1.0 → 1.6 bar linearly in 10 min: ∫ ((p−0.5)/0.5)^0.83 dt
        // = t/(p1−p0) · 0.5/1.83 · [x1^1.83 − x0^1.83], x = (p−0.5)/0.5 (closed form).
        let o2 = GasMix::new(1.0, 0.0).unwrap();
        let s = sched(vec![Leg {
            kind: LegKind::Descent,
            start_depth_m: 0.0,
            end_depth_m: 6.0,
            duration_s: 600.0,
            gas: o2,
        }]);
        let (x0, x1): (f64, f64) = (1.0, 2.2);
        let want = 10.0 / 0.6 * 0.5 / 1.83 * (x1.powf(1.83) - x0.powf(1.83));
        let e = exposure(&s);
        assert!((e.otu - want).abs() < 1e-6, "{} vs {want}", e.otu);
    }
}
