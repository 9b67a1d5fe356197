//! `peak-radius`: the largest radius any single bubble reaches over the run, µm.
//!
//! By default (`measure = "growth"`) the growth: the peak over frames and bubbles of R − R0,
//! R0 the radius the bubble was created with (its nucleus at t = 0 or at activation), floored
//! at 0, so a run in which nothing grows scores 0 whatever the seed. The absolute peak radius
//! is reported beside it, and is the value with `measure = "absolute"`.

use super::{params, Measure, RiskCriterion, RunData};
use serde::Deserialize;

/// Peak over recorded frames and bubbles of R − R0 (growth) or R (absolute), µm.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakRadius {
    /// Growth above R0 (default) or the absolute radius.
    #[serde(default)]
    pub measure: Measure,
}

/// Peak over frames and bubbles of `f(R, R0)`, floored at 0.
fn peak(run: &RunData, f: impl Fn(f64, f64) -> f64) -> f64 {
    run.frames
        .iter()
        .flat_map(|fr| fr.bubbles.iter().map(|b| f(b.radius, b.initial_radius)))
        .fold(0.0, f64::max)
}

impl RiskCriterion for PeakRadius {
    fn name(&self) -> &'static str {
        "peak-radius"
    }
    fn unit(&self) -> &'static str {
        "µm"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        1e6 * match self.measure {
            Measure::Growth => peak(run, |r, r0| r - r0),
            Measure::Absolute => peak(run, |r, _| r),
        }
    }
    fn absolute(&self, run: &RunData) -> Option<f64> {
        (self.measure == Measure::Growth).then(|| 1e6 * peak(run, |r, _| r))
    }
    fn describe(&self) -> String {
        match self.measure {
            Measure::Growth => "peak growth of a single bubble's radius above its R0".into(),
            Measure::Absolute => "peak single-bubble radius".into(),
        }
    }
}

/// Build from the parameter table (`measure`).
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    Ok(Box::new(params::<PeakRadius>(t)?))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame, grown};
    use super::*;

    #[test]
    fn largest_radius_of_any_bubble() {
        let f = vec![
            frame(0.0, 1e5, 0.0, vec![bubble(0, 50e-6, 0.0)]),
            frame(
                1.0,
                1e5,
                0.0,
                vec![bubble(0, 80e-6, 0.0), bubble(3, 130e-6, 0.0)],
            ),
            frame(2.0, 1e5, 0.0, vec![bubble(0, 90e-6, 0.0)]),
            frame(3.0, 1e5, 0.0, vec![]),
        ];
        let c = PeakRadius {
            measure: Measure::Absolute,
        };
        // 130 µm (bubble 3 at t = 1)
        assert!((c.evaluate(&RunData::new(&f)) - 130.0).abs() < 1e-9);
        assert_eq!(c.evaluate(&RunData::new(&[])), 0.0);
    }

    #[test]
    fn growth_is_measured_above_each_bubbles_r0() {
        // bubble 0: R0 = 86.5 µm reaching 120 µm (+33.5); bubble 5, nucleated at 0.5 µm,
        // reaching 60 µm (+59.5, the larger growth though the smaller bubble); the absolute
        // peak is bubble 0's 120 µm.
        let f = vec![
            frame(0.0, 1e5, 0.0, vec![grown(0, 86.5e-6, 86.5e-6)]),
            frame(1.0, 3e5, 0.0, vec![grown(0, 86.5e-6, 70e-6)]),
            frame(
                2.0,
                1e5,
                0.0,
                vec![grown(0, 86.5e-6, 120e-6), grown(5, 0.5e-6, 60e-6)],
            ),
        ];
        let run = RunData::new(&f);
        let c = PeakRadius {
            measure: Measure::Growth,
        };
        assert!((c.evaluate(&run) - 59.5).abs() < 1e-9);
        assert!((c.absolute(&run).unwrap() - 120.0).abs() < 1e-9);
        // compressed only: no growth
        assert_eq!(c.evaluate(&RunData::new(&f[..2])), 0.0);
    }
}
