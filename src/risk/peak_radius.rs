//! `peak-radius`: the largest radius any single bubble reaches over the run, µm.

use super::{params, RiskCriterion, RunData};
use serde::Deserialize;

/// Peak over recorded frames and bubbles of R, µm.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakRadius {}

impl RiskCriterion for PeakRadius {
    fn name(&self) -> &'static str {
        "peak-radius"
    }
    fn unit(&self) -> &'static str {
        "µm"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        run.frames
            .iter()
            .flat_map(|f| f.bubbles.iter().map(|b| b.radius))
            .fold(0.0, f64::max)
            * 1e6
    }
    fn describe(&self) -> String {
        "peak single-bubble radius".into()
    }
}

/// Build from the (empty) parameter table.
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    Ok(Box::new(params::<PeakRadius>(t)?))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame};
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
        // 130 µm (bubble 3 at t = 1)
        assert!((PeakRadius {}.evaluate(&RunData::new(&f)) - 130.0).abs() < 1e-9);
        assert_eq!(PeakRadius {}.evaluate(&RunData::new(&[])), 0.0);
    }
}
