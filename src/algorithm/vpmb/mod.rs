//! VPM-B: the Varying Permeability Model with Boyle's-law compensation, as Erik Baker
//! published it in his VPMDECO / VPM-B program (Yount & Hoffman 1986 VPM, extended by
//! Yount, Maiken and Baker 1999–2001; Boyle's-law compensation by Baker).
//!
//! Implemented from the published description of the algorithm:
//! - nuclei of critical radius r0 (N2 0.55 µm, He 0.45 µm; scaled by the conservatism
//!   multipliers 1.0, 1.05, 1.12, 1.22, 1.35 for +0 … +4), surface tension γ, skin
//!   compression γc;
//! - crushing on descent: permeable below the onset of impermeability (8.2 atm gradient),
//!   Boyle's law for the nucleus gas above it; the largest crushing pressure per compartment;
//! - regeneration of the crushed radius with a 20 160 min time constant, the initial
//!   allowable gradient 2γ(γc − γ)/(r γc);
//! - the 16 ZH-L16 compartments for N2 and He, Schreiner's equation on travel, Haldane's
//!   at stops, "other gases" (CO2, O2; 102 mmHg) in every compartment;
//! - the start of the decompression zone, the first stop from the ascent ceiling pushed
//!   deeper until the projected ascent to it breaks no allowable gradient;
//! - at every stop the allowable gradients are compensated for Boyle's-law expansion of a
//!   bubble from the first stop to the next stop;
//! - the critical-volume algorithm: the schedule is recomputed with gradients relaxed by
//!   the phase-volume time (deco time plus each compartment's surface phase-volume time)
//!   until the phase-volume time changes by at most one minute in some compartment;
//! - the stops follow the [`Conventions`]: spacing, last stop, ascent rate, rounding
//!   (Baker: a stop ends on a whole minute of runtime and its minutes include the travel).

mod physics;
mod planner;

pub use physics::{HE_HALF_TIMES_MIN, N2_HALF_TIMES_MIN};

use crate::algorithm::{Conventions, DecoAlgorithm, DivePlan, Schedule};
use crate::error::InputError;
use serde::Deserialize;

/// Critical-radius multipliers for conservatism +0 … +4 (the levels of V-Planner and
/// Subsurface: 1.0, 1.05, 1.12, 1.22, 1.35).
pub const CONSERVATISM_RADIUS_FACTORS: [f64; 5] = [1.0, 1.05, 1.12, 1.22, 1.35];

/// The `[params]` table of a `kind = "vpm-b"` algorithm file, as written.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawVpmbParams {
    /// Conservatism +0 … +4.
    #[serde(default)]
    pub conservatism: i64,
    /// Critical-volume parameter λ, fsw·min (Baker 7500; Subsurface 6500).
    #[serde(default = "default_lambda")]
    pub critical_volume_lambda_fsw_min: f64,
    /// Critical radius of N2 nuclei at +0, µm.
    #[serde(default = "default_r_n2")]
    pub critical_radius_n2_um: f64,
    /// Critical radius of He nuclei at +0, µm.
    #[serde(default = "default_r_he")]
    pub critical_radius_he_um: f64,
    /// Surface tension γ, N/m.
    #[serde(default = "default_gamma")]
    pub surface_tension: f64,
    /// Skin compression γc, N/m.
    #[serde(default = "default_gamma_c")]
    pub skin_compression: f64,
    /// Gradient at the onset of impermeability, atm.
    #[serde(default = "default_onset")]
    pub crushing_onset_atm: f64,
    /// Regeneration time constant, min.
    #[serde(default = "default_regen")]
    pub regeneration_time_constant_min: f64,
    /// Pressure of other gases (CO2, O2) in the compartments, mmHg.
    #[serde(default = "default_other")]
    pub other_gases_mmhg: f64,
    /// Run the critical-volume algorithm (VPM-B); `false` keeps the initial gradients.
    #[serde(default = "default_true")]
    pub critical_volume: bool,
    /// When the critical-volume iteration stops (`baker` or `deco-time`).
    #[serde(default)]
    pub critical_volume_convergence: CvaConvergence,
}

/// When the critical-volume iteration has converged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CvaConvergence {
    /// Baker's VPMDECO: as soon as the phase-volume time of any one compartment changed by
    /// at most 1 min from the previous pass; the final schedule is that pass's gradients
    /// replayed (VPMDECO.FOR, and its faithful ports: bwaite/vpmb, the C ports).
    #[default]
    Baker,
    /// Subsurface's planner (core/planner.cpp, "CVA time converges"): the gradients are
    /// always updated from the last pass's phase-volume times, and the pass after the deco
    /// time fell by less than 10 s between two passes is the final schedule. With whole
    /// minutes at the stop a pass changes the deco time by whole minutes, and Baker's 1-min
    /// test then stops one pass early (a deeper first stop, longer shallow stops).
    DecoTime,
}

fn default_lambda() -> f64 {
    7500.0
}
fn default_r_n2() -> f64 {
    0.55
}
fn default_r_he() -> f64 {
    0.45
}
fn default_gamma() -> f64 {
    0.0179
}
fn default_gamma_c() -> f64 {
    0.257
}
fn default_onset() -> f64 {
    8.2
}
fn default_regen() -> f64 {
    20160.0
}
fn default_other() -> f64 {
    102.0
}
fn default_true() -> bool {
    true
}

impl Default for RawVpmbParams {
    fn default() -> Self {
        RawVpmbParams {
            conservatism: 0,
            critical_volume_lambda_fsw_min: default_lambda(),
            critical_radius_n2_um: default_r_n2(),
            critical_radius_he_um: default_r_he(),
            surface_tension: default_gamma(),
            skin_compression: default_gamma_c(),
            crushing_onset_atm: default_onset(),
            regeneration_time_constant_min: default_regen(),
            other_gases_mmhg: default_other(),
            critical_volume: true,
            critical_volume_convergence: CvaConvergence::Baker,
        }
    }
}

/// Validated VPM-B parameters in SI units (radii already scaled by the conservatism).
#[derive(Debug, Clone, PartialEq)]
pub struct VpmbParams {
    /// Conservatism level 0 … 4.
    pub conservatism: u8,
    /// Critical radius of N2 nuclei after the conservatism multiplier, m.
    pub critical_radius_n2_m: f64,
    /// Critical radius of He nuclei after the conservatism multiplier, m.
    pub critical_radius_he_m: f64,
    /// Surface tension γ, N/m.
    pub surface_tension: f64,
    /// Skin compression γc, N/m.
    pub skin_compression: f64,
    /// Gradient at the onset of impermeability, Pa.
    pub crushing_onset_pa: f64,
    /// Regeneration time constant, min.
    pub regeneration_time_constant_min: f64,
    /// Other gases in the compartments, Pa.
    pub other_gases_pa: f64,
    /// Critical-volume parameter λ, Pa·min.
    pub lambda_pa_min: f64,
    /// Whether the critical-volume algorithm runs.
    pub critical_volume: bool,
    /// When the critical-volume iteration stops.
    pub critical_volume_convergence: CvaConvergence,
}

fn check(field: &str, v: f64, lo: f64, hi: f64, unit: &str) -> Result<f64, String> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(format!(
            "{field}: {v} {unit} is out of range; write a value from {lo} to {hi} {unit}"
        ))
    }
}

impl RawVpmbParams {
    /// Check ranges and convert to SI. Errors name the field.
    pub fn validate(&self) -> Result<VpmbParams, String> {
        if !(0..=4).contains(&self.conservatism) {
            return Err(format!(
                "conservatism: {} is out of range; write 0, 1, 2, 3 or 4",
                self.conservatism
            ));
        }
        let lambda = check(
            "critical_volume_lambda_fsw_min",
            self.critical_volume_lambda_fsw_min,
            100.0,
            100_000.0,
            "fsw·min",
        )?;
        let r_n2 = check(
            "critical_radius_n2_um",
            self.critical_radius_n2_um,
            0.05,
            5.0,
            "µm",
        )?;
        let r_he = check(
            "critical_radius_he_um",
            self.critical_radius_he_um,
            0.05,
            5.0,
            "µm",
        )?;
        let gamma = check("surface_tension", self.surface_tension, 1e-4, 0.1, "N/m")?;
        let gamma_c = check("skin_compression", self.skin_compression, 1e-4, 1.0, "N/m")?;
        if gamma_c <= gamma {
            return Err(format!(
                "skin_compression: {gamma_c} N/m must exceed surface_tension ({gamma} N/m)"
            ));
        }
        let onset = check(
            "crushing_onset_atm",
            self.crushing_onset_atm,
            0.1,
            100.0,
            "atm",
        )?;
        let regen = check(
            "regeneration_time_constant_min",
            self.regeneration_time_constant_min,
            1.0,
            1e7,
            "min",
        )?;
        let other = check(
            "other_gases_mmhg",
            self.other_gases_mmhg,
            0.0,
            400.0,
            "mmHg",
        )?;
        let f = CONSERVATISM_RADIUS_FACTORS[self.conservatism as usize];
        Ok(VpmbParams {
            conservatism: self.conservatism as u8,
            critical_radius_n2_m: r_n2 * 1e-6 * f,
            critical_radius_he_m: r_he * 1e-6 * f,
            surface_tension: gamma,
            skin_compression: gamma_c,
            crushing_onset_pa: onset * crate::units::ATM_PA,
            regeneration_time_constant_min: regen,
            other_gases_pa: other / 760.0 * crate::units::ATM_PA,
            lambda_pa_min: lambda * physics::PA_PER_FSW,
            critical_volume: self.critical_volume,
            critical_volume_convergence: self.critical_volume_convergence,
        })
    }
}

/// The VPM-B algorithm with its parameters and conventions.
#[derive(Debug, Clone)]
pub struct VpmB {
    label: String,
    params: VpmbParams,
    conventions: Conventions,
}

impl VpmB {
    /// Build from validated parameters and conventions (checks the conventions too).
    pub fn new(label: &str, params: VpmbParams, conventions: Conventions) -> Result<Self, String> {
        check_conventions(&conventions)?;
        Ok(VpmB {
            label: label.to_string(),
            params,
            conventions,
        })
    }

    /// The validated parameters.
    pub fn params(&self) -> &VpmbParams {
        &self.params
    }

    /// The conventions.
    pub fn conventions(&self) -> &Conventions {
        &self.conventions
    }

    /// Depth at which the leading compartment enters the decompression zone on a straight
    /// ascent from the bottom, m (Baker prints it above his decompression table).
    pub fn start_of_deco_zone_m(&self, plan: &DivePlan) -> Result<f64, InputError> {
        plan.validate(&self.conventions)?;
        Ok(planner::Planner::new(self, plan).start_of_deco_zone())
    }
}

fn check_conventions(c: &Conventions) -> Result<(), String> {
    let pos = |name: &str, v: f64| {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(format!("conventions.{name}: {v} must be positive"))
        }
    };
    pos("surface_pressure_pa", c.surface_pressure_pa)?;
    pos("pa_per_m", c.pa_per_m)?;
    pos("descent_rate_m_min", c.descent_rate_m_min)?;
    pos("ascent_rate_m_min", c.ascent_rate_m_min)?;
    pos("stop_spacing_m", c.stop_spacing_m)?;
    if !(c.last_stop_m.is_finite() && c.last_stop_m >= 0.0) {
        return Err(format!(
            "conventions.last_stop_m: {} must be zero or positive",
            c.last_stop_m
        ));
    }
    if !(c.water_vapour_pa.is_finite() && (0.0..c.surface_pressure_pa).contains(&c.water_vapour_pa))
    {
        return Err(format!(
            "conventions.water_vapour_pa: {} must be from 0 to the surface pressure",
            c.water_vapour_pa
        ));
    }
    if !(c.min_stop_min.is_finite() && c.min_stop_min >= 0.0) {
        return Err(format!(
            "conventions.min_stop_min: {} must be zero or positive",
            c.min_stop_min
        ));
    }
    Ok(())
}

impl DecoAlgorithm for VpmB {
    fn label(&self) -> String {
        self.label.clone()
    }

    fn plan(&self, plan: &DivePlan) -> Result<Schedule, InputError> {
        plan.validate(&self.conventions)?;
        planner::Planner::new(self, plan).schedule()
    }
}

/// The registry's [`crate::algorithm::Builder`] for `kind = "vpm-b"`: reads `[params]`
/// (unknown keys rejected), validates it, and pairs it with the conventions.
pub fn build(
    label: &str,
    params: toml::Value,
    conventions: Conventions,
) -> Result<Box<dyn DecoAlgorithm>, String> {
    let raw: RawVpmbParams = crate::error::table_into(params)?;
    let p = raw.validate()?;
    Ok(Box::new(VpmB::new(label, p, conventions)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(s: &str) -> toml::Value {
        toml::Value::Table(s.parse::<toml::Table>().unwrap())
    }

    #[test]
    fn defaults_and_conservatism() {
        let p = RawVpmbParams::default().validate().unwrap();
        assert!((p.critical_radius_n2_m - 0.55e-6).abs() < 1e-15);
        assert!((p.lambda_pa_min - 7500.0 * 101_325.0 / 33.0).abs() < 1e-6);
        // 102 mmHg = 13 599 Pa (Baker: 102/760 atm).
        assert!((p.other_gases_pa - 13_599.0).abs() < 1.0);
        let raw: RawVpmbParams = table("conservatism = 3").try_into().unwrap();
        let p = raw.validate().unwrap();
        assert!((p.critical_radius_he_m - 0.45e-6 * 1.22).abs() < 1e-15);
    }

    #[test]
    fn errors_name_the_field() {
        let bad: RawVpmbParams = table("conservatism = 5").try_into().unwrap();
        assert!(bad.validate().unwrap_err().starts_with("conservatism"));
        let bad: RawVpmbParams = table("critical_radius_n2_um = -1.0").try_into().unwrap();
        assert!(bad
            .validate()
            .unwrap_err()
            .starts_with("critical_radius_n2_um"));
        let bad: RawVpmbParams = table("skin_compression = 0.01").try_into().unwrap();
        assert!(bad.validate().unwrap_err().starts_with("skin_compression"));
        let e = table("lamda = 6500")
            .try_into::<RawVpmbParams>()
            .unwrap_err();
        assert!(e.to_string().contains("lamda"), "{e}");
    }
}
