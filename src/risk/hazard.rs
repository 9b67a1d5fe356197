//! `hazard`: a probabilistic hazard of the BVM(3) family (Gerth & Vann 1997),
//! P = 1 − exp(−∫ g·max(0, V(t) − V_thr) dt), reported in %, with V the total bubble volume
//! of the phantom (mm³), t in min, the gain g (`gain_per_mm3_min`, 1/(mm³·min)) and the
//! threshold V_thr (`threshold_mm3`, mm³) given by the user.
//!
//! **Not a probability of decompression sickness in people.** g and V_thr are not calibrated
//! to human (or animal) outcome data by this tool; the gel is not tissue. The number ranks
//! schedules on one monotone scale of the phantom's bubble volume; its absolute value means
//! nothing until someone fits g and V_thr to outcomes.

use super::volume_integral::volume_mm3_min;
use super::{params, series, RiskCriterion, RunData};
use serde::Deserialize;

/// P = 1 − exp(−g ∫ max(0, V − V_thr) dt), %.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hazard {
    /// g, 1/(mm³·min) (> 0).
    pub gain_per_mm3_min: f64,
    /// V_thr, mm³ (≥ 0). Default 0.
    #[serde(default)]
    pub threshold_mm3: f64,
}

impl RiskCriterion for Hazard {
    fn name(&self) -> &'static str {
        "hazard"
    }
    fn unit(&self) -> &'static str {
        "%"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        let integral = series::integral_above(&volume_mm3_min(run), self.threshold_mm3);
        100.0 * (-(-self.gain_per_mm3_min * integral).exp_m1())
    }
    fn describe(&self) -> String {
        format!(
            "P = 1 − exp(−∫ g·max(0, V − V_thr) dt), g = {} /(mm³·min), V_thr = {} mm³ (BVM(3) form; g and V_thr NOT calibrated to human data)",
            self.gain_per_mm3_min, self.threshold_mm3
        )
    }
}

/// Build from `gain_per_mm3_min` and `threshold_mm3`.
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    let c: Hazard = params(t)?;
    if !(c.gain_per_mm3_min.is_finite() && c.gain_per_mm3_min > 0.0) {
        return Err(format!(
            "gain_per_mm3_min: must be positive (got {})",
            c.gain_per_mm3_min
        ));
    }
    if !(c.threshold_mm3.is_finite() && c.threshold_mm3 >= 0.0) {
        return Err(format!(
            "threshold_mm3: must be zero or positive (got {})",
            c.threshold_mm3
        ));
    }
    Ok(Box::new(c))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame};
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn closed_form_for_a_linear_volume() {
        // V(t) = 0.002·t_min mm³ on 0..50 min (two frames suffice: it is a line); V_thr = 0.02
        // mm³ is crossed at 10 min; ∫ = 0.001·40² = 1.6 mm³·min; g = 0.5 → P = 1 − e^−0.8
        // = 0.550671 (e^−0.8 = 0.449329).
        let r = |v_mm3: f64| (3.0 * v_mm3 * 1e-9 / (4.0 * PI)).cbrt();
        let f = vec![
            frame(0.0, 1e5, 0.0, vec![bubble(0, 1e-9, 0.0)]),
            frame(3000.0, 1e5, 0.0, vec![bubble(0, r(0.1), 0.0)]),
        ];
        let h = Hazard {
            gain_per_mm3_min: 0.5,
            threshold_mm3: 0.02,
        };
        let got = h.evaluate(&RunData::new(&f));
        let want = 100.0 * (1.0 - (-0.8f64).exp());
        assert!((got - want).abs() < 1e-6, "{got} vs {want}");
        assert!((want - 55.0671).abs() < 1e-3);
    }

    #[test]
    fn gain_is_required_and_positive() {
        assert!(build(toml::Table::new())
            .unwrap_err()
            .contains("gain_per_mm3_min"));
        let mut t = toml::Table::new();
        t.insert("gain_per_mm3_min".into(), 0.0.into());
        assert!(build(t).unwrap_err().starts_with("gain_per_mm3_min"));
    }
}
