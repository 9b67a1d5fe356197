//! `peak-supersaturation`: the largest supersaturation of the gel over the run, kPa:
//! Σ_gases tension + p_fixed − P_amb, with p_fixed the partial pressure of the gases that are
//! not simulated (water vapour, CO2, venous O2 of the breathed-gas convention; 0 in a lab gel),
//! which tissue holds as the bubbles do. `at = "gel"` (default) takes the largest over every gel cell
//! (the frame's `max_supersaturation`); `at = "bubbles"` the largest at the bubbles' coupling
//! spheres (gel tension around each bubble − P_amb).

use super::{params, series, RiskCriterion, RunData};
use serde::Deserialize;

/// Where the supersaturation is taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Where {
    /// Every cell of the gel.
    #[default]
    Gel,
    /// The gel around each bubble.
    Bubbles,
}

/// Peak supersaturation, kPa.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakSupersaturation {
    /// Where it is taken (default `gel`).
    #[serde(default)]
    pub at: Where,
}

impl RiskCriterion for PeakSupersaturation {
    fn name(&self) -> &'static str {
        "peak-supersaturation"
    }
    fn unit(&self) -> &'static str {
        "kPa"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        let v = match self.at {
            Where::Gel => run
                .frames
                .iter()
                .map(|f| f.max_supersaturation)
                .fold(f64::NEG_INFINITY, f64::max),
            Where::Bubbles => series::peak(&series::supersaturation_at_bubbles(run.frames)),
        };
        if v.is_finite() {
            v * 1e-3
        } else {
            0.0
        }
    }
    fn describe(&self) -> String {
        match self.at {
            Where::Gel => {
                "peak gel supersaturation Σ tension + p_fixed − P_amb (all gel cells)".into()
            }
            Where::Bubbles => {
                "peak gel supersaturation Σ tension + p_fixed − P_amb at the bubbles".into()
            }
        }
    }
}

/// Build from `at`.
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    Ok(Box::new(params::<PeakSupersaturation>(t)?))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame};
    use super::*;

    #[test]
    fn gel_and_bubble_peaks() {
        // gel: max of −5, 30, 12 kPa = 30 kPa; bubbles: tension − ambient = 150−100, 180−120
        // (= 60, the peak), 90−110 kPa.
        let f = vec![
            frame(0.0, 100e3, -5e3, vec![bubble(0, 1e-4, 150e3)]),
            frame(
                1.0,
                120e3,
                30e3,
                vec![bubble(0, 1e-4, 180e3), bubble(1, 1e-4, 100e3)],
            ),
            frame(2.0, 110e3, 12e3, vec![bubble(0, 1e-4, 90e3)]),
        ];
        let run = RunData::new(&f);
        let gel = PeakSupersaturation { at: Where::Gel }.evaluate(&run);
        let bub = PeakSupersaturation { at: Where::Bubbles }.evaluate(&run);
        assert!(
            (gel - 30.0).abs() < 1e-12 && (bub - 60.0).abs() < 1e-12,
            "{gel} {bub}"
        );
        let mut t = toml::Table::new();
        t.insert("at".into(), "surface".into());
        assert!(build(t).is_err());
    }
}
