//! `peak-total-volume`: the largest total volume of all bubbles over the run, mm³.
//! Includes the volume of the initial nuclei (a run in which nothing grows scores their volume).

use super::{params, series, RiskCriterion, RunData};
use serde::Deserialize;

/// Peak over recorded frames of Σ_bubbles V, mm³.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakTotalVolume {}

impl RiskCriterion for PeakTotalVolume {
    fn name(&self) -> &'static str {
        "peak-total-volume"
    }
    fn unit(&self) -> &'static str {
        "mm³"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        let v = series::peak(&series::total_volume(run.frames));
        if v.is_finite() {
            v * 1e9
        } else {
            0.0
        }
    }
    fn describe(&self) -> String {
        "peak total bubble volume (all bubbles, recorded frames)".into()
    }
}

/// Build from the (empty) parameter table.
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    Ok(Box::new(params::<PeakTotalVolume>(t)?))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame};
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn peak_of_the_sum_not_the_sum_of_peaks() {
        // bubble 0 peaks at t = 1 (R = 100 µm), bubble 1 at t = 2 (R = 120 µm); the sum peaks
        // at t = 2: (4/3)π(90³ + 120³) µm³ = (4/3)π·2 457 000 µm³, in mm³ ×1e-9.
        let f = vec![
            frame(
                0.0,
                1e5,
                0.0,
                vec![bubble(0, 50e-6, 0.0), bubble(1, 50e-6, 0.0)],
            ),
            frame(
                1.0,
                1e5,
                0.0,
                vec![bubble(0, 100e-6, 0.0), bubble(1, 60e-6, 0.0)],
            ),
            frame(
                2.0,
                1e5,
                0.0,
                vec![bubble(0, 90e-6, 0.0), bubble(1, 120e-6, 0.0)],
            ),
        ];
        let want = 4.0 / 3.0 * PI * (90f64.powi(3) + 120f64.powi(3)) * 1e-9;
        let got = PeakTotalVolume {}.evaluate(&RunData::new(&f));
        assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
        assert!(build(toml::Table::new()).is_ok());
        let mut bad = toml::Table::new();
        bad.insert("threshold".into(), 1.0.into());
        assert!(build(bad).unwrap_err().contains("threshold"));
    }
}
