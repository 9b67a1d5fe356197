//! `peak-total-volume`: the largest total volume of the bubbles over the run, mm³.
//!
//! By default (`measure = "growth"`) the growth the schedule causes: the peak over the recorded
//! frames of Σ_b (V_b − V0_b), V0_b = (4/3)π·R0_b³ the volume bubble b was created with (the
//! nuclei at t = 0, or a nucleus at its activation), over the bubbles present in the frame,
//! floored at 0. A run in which nothing grows scores 0, whatever the seed; at the start of a
//! first dive this is "peak volume above the initial total". The absolute peak Σ_b V_b (nuclei
//! included) is reported beside it, and is the value with `measure = "absolute"`.

use super::{params, series, Measure, RiskCriterion, RunData};
use serde::Deserialize;
use std::f64::consts::PI;

/// Peak over recorded frames of Σ_bubbles (V − V0) (growth) or Σ_bubbles V (absolute), mm³.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakTotalVolume {
    /// Growth above R0 (default) or the absolute volume.
    #[serde(default)]
    pub measure: Measure,
}

/// Peak over the frames of Σ_b (V_b − V0_b), m³, floored at 0 (0 without frames).
pub fn peak_growth(run: &RunData) -> f64 {
    run.frames
        .iter()
        .map(|f| {
            f.bubbles
                .iter()
                .map(|b| b.volume - 4.0 / 3.0 * PI * b.initial_radius.powi(3))
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

/// Peak over the frames of Σ_b V_b, m³ (0 without frames).
pub fn peak_absolute(run: &RunData) -> f64 {
    series::peak(&series::total_volume(run.frames)).max(0.0)
}

impl RiskCriterion for PeakTotalVolume {
    fn name(&self) -> &'static str {
        "peak-total-volume"
    }
    fn unit(&self) -> &'static str {
        "mm³"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        1e9 * match self.measure {
            Measure::Growth => peak_growth(run),
            Measure::Absolute => peak_absolute(run),
        }
    }
    fn absolute(&self, run: &RunData) -> Option<f64> {
        (self.measure == Measure::Growth).then(|| 1e9 * peak_absolute(run))
    }
    fn describe(&self) -> String {
        match self.measure {
            Measure::Growth => {
                "peak growth of the total bubble volume above the bubbles' initial volumes (recorded frames)".into()
            }
            Measure::Absolute => "peak total bubble volume, nuclei included (recorded frames)".into(),
        }
    }
}

/// Build from the parameter table (`measure`).
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    Ok(Box::new(params::<PeakTotalVolume>(t)?))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame, grown};
    use super::*;

    fn v(r_um: f64) -> f64 {
        4.0 / 3.0 * PI * r_um.powi(3) * 1e-9
    }

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
        let want = v(90.0) + v(120.0);
        let c = PeakTotalVolume {
            measure: Measure::Absolute,
        };
        let got = c.evaluate(&RunData::new(&f));
        assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
        assert_eq!(c.absolute(&RunData::new(&f)), None);
        assert!(build(toml::Table::new()).is_ok());
        let mut bad = toml::Table::new();
        bad.insert("threshold".into(), 1.0.into());
        assert!(build(bad).unwrap_err().contains("threshold"));
        let mut bad = toml::Table::new();
        bad.insert("measure".into(), "relative".into());
        assert!(build(bad).unwrap_err().contains("relative"));
    }

    #[test]
    fn growth_is_measured_above_each_bubbles_initial_volume() {
        // Two nuclei of 50 µm (V0 each (4/3)π·50³ µm³): compressed to 40 µm at depth, bubble 0
        // grows to 100 µm after surfacing while bubble 1 dissolves (absent from the last
        // frame), and a bubble nucleated at 1 µm reaches 30 µm. Growth by hand:
        //   t=0: 0; t=1: 2·(V(40) − V(50)) < 0; t=2: (V(100) − V(50)) + (V(30) − V(1)).
        let f = vec![
            frame(
                0.0,
                1e5,
                0.0,
                vec![grown(0, 50e-6, 50e-6), grown(1, 50e-6, 50e-6)],
            ),
            frame(
                1.0,
                4e5,
                0.0,
                vec![grown(0, 50e-6, 40e-6), grown(1, 50e-6, 40e-6)],
            ),
            frame(
                2.0,
                1e5,
                0.0,
                vec![grown(0, 50e-6, 100e-6), grown(7, 1e-6, 30e-6)],
            ),
        ];
        let run = RunData::new(&f);
        let c = PeakTotalVolume {
            measure: Measure::Growth,
        };
        let want = v(100.0) - v(50.0) + v(30.0) - v(1.0);
        let got = c.evaluate(&run);
        assert!((got - want).abs() < 1e-12 * want, "{got} vs {want}");
        // the absolute peak beside it: V(100) + V(30) at t = 2 (above 2·V(50) at t = 0)
        let abs = c.absolute(&run).unwrap();
        assert!((abs - (v(100.0) + v(30.0))).abs() < 1e-12 * abs);
        // nothing grows: the nuclei's seed volume does not count
        let still = vec![frame(0.0, 1e5, 0.0, vec![grown(0, 50e-6, 50e-6)])];
        // (0 up to the round-off of V − V0: powi may be folded at compile time in one and not
        // the other)
        assert!(c.evaluate(&RunData::new(&still)).abs() < 1e-12 * v(50.0));
        assert!((c.absolute(&RunData::new(&still)).unwrap() - v(50.0)).abs() < 1e-15);
        assert_eq!(c.evaluate(&RunData::new(&[])), 0.0);
    }
}
