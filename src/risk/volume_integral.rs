//! `volume-time-above-threshold`: ∫ max(0, V(t) − V_thr) dt over the run, mm³·min, with V the
//! total bubble volume and V_thr the parameter `threshold_mm3` (default 0). Integrated exactly
//! over the piecewise-linear interpolant of the recorded frames.

use super::{params, series, RiskCriterion, RunData};
use serde::Deserialize;

/// Time-integrated total bubble volume above a threshold, mm³·min.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VolumeTimeAboveThreshold {
    /// V_thr, mm³ (≥ 0). Default 0.
    #[serde(default)]
    pub threshold_mm3: f64,
}

/// Total volume in mm³ against time in min.
pub(crate) fn volume_mm3_min(run: &RunData) -> Vec<(f64, f64)> {
    series::total_volume(run.frames)
        .into_iter()
        .map(|(t, v)| (t / 60.0, v * 1e9))
        .collect()
}

impl RiskCriterion for VolumeTimeAboveThreshold {
    fn name(&self) -> &'static str {
        "volume-time-above-threshold"
    }
    fn unit(&self) -> &'static str {
        "mm³·min"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        series::integral_above(&volume_mm3_min(run), self.threshold_mm3)
    }
    fn describe(&self) -> String {
        format!(
            "∫ max(0, V(t) − {} mm³) dt of the total bubble volume V",
            self.threshold_mm3
        )
    }
}

/// Build from `threshold_mm3`.
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    let c: VolumeTimeAboveThreshold = params(t)?;
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

    /// A one-bubble history whose volume is `v(t)` (mm³, t in s), sampled at `times`.
    fn history(times: &[f64], v: impl Fn(f64) -> f64) -> Vec<crate::phantom::sim::Frame> {
        times
            .iter()
            .map(|&t| {
                let r = (3.0 * v(t) * 1e-9 / (4.0 * PI)).cbrt();
                frame(t, 1e5, 0.0, vec![bubble(0, r, 0.0)])
            })
            .collect()
    }

    #[test]
    fn linear_volume_gives_the_analytic_integral() {
        // V(t) = 0.01 + 0.002·t_min mm³ on 0..60 min, uneven sampling; threshold 0.05 mm³ is
        // crossed at t* = 20 min: ∫_{20}^{60} 0.002(t − 20) dt = 0.001·40² = 1.6 mm³·min
        // (exact, the interpolant of a line is the line).
        let times: Vec<f64> = [0.0, 7.0, 19.0, 33.0, 41.5, 60.0]
            .iter()
            .map(|m| m * 60.0)
            .collect();
        let f = history(&times, |t| 0.01 + 0.002 * t / 60.0);
        let c = VolumeTimeAboveThreshold {
            threshold_mm3: 0.05,
        };
        let got = c.evaluate(&RunData::new(&f));
        assert!((got - 1.6).abs() < 1e-9, "{got}");
    }

    #[test]
    fn curved_volume_matches_an_independent_trapezoid_sum() {
        // V(t) = 1e-3·t_min² mm³ sampled every 2 min on 0..30 min, threshold 0: the trapezoid
        // sum Σ ½(V_i + V_{i+1})·2, computed here directly; analytic ∫ = 1e-3·30³/3 = 9 mm³·min,
        // which the trapezoid over-estimates by h²/12·∫V'' = (4/12)·2e-3·30 = 0.02.
        let times: Vec<f64> = (0..=15).map(|i| i as f64 * 120.0).collect();
        let v = |t: f64| 1e-3 * (t / 60.0).powi(2);
        let f = history(&times, v);
        let mut trap = 0.0;
        for w in times.windows(2) {
            trap += 0.5 * (v(w[0]) + v(w[1])) * (w[1] - w[0]) / 60.0;
        }
        let got = VolumeTimeAboveThreshold { threshold_mm3: 0.0 }.evaluate(&RunData::new(&f));
        assert!((got - trap).abs() < 1e-9 * trap, "{got} vs {trap}");
        assert!((got - (9.0 + 0.02)).abs() < 1e-9, "{got}");
    }

    #[test]
    fn negative_threshold_is_refused() {
        let mut t = toml::Table::new();
        t.insert("threshold_mm3".into(), (-1.0).into());
        assert!(build(t).unwrap_err().starts_with("threshold_mm3"));
    }
}
