//! `bubble-count`: the peak number of bubbles the schedule has activated, counted over the
//! recorded frames of the window: bubbles active in a frame that were not in the run's first
//! frame (the state at the start of the schedule). Under the `fixed` nucleation model nothing
//! activates and the value is 0; with `critical-radius` it is the count of Fig. 6c and §4.2.4 of
//! the paper. `include_initial = true` counts every active bubble instead (the absolute count).

use super::{params, RiskCriterion, RunData, Window};
use serde::Deserialize;
use std::collections::BTreeSet;

/// Peak number of active bubbles formed during the run (or of all active bubbles).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BubbleCount {
    /// Count the bubbles present at the start too (default false).
    #[serde(default)]
    pub include_initial: bool,
    /// Which frames (default the whole run).
    #[serde(default)]
    pub window: Window,
}

impl RiskCriterion for BubbleCount {
    fn name(&self) -> &'static str {
        "bubble-count"
    }
    fn unit(&self) -> &'static str {
        "bubbles"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        let initial: BTreeSet<usize> = match (self.include_initial, run.frames.first()) {
            (false, Some(f)) => f.bubbles.iter().map(|b| b.id).collect(),
            _ => BTreeSet::new(),
        };
        run.window(self.window)
            .iter()
            .map(|f| {
                f.bubbles
                    .iter()
                    .filter(|b| !initial.contains(&b.id))
                    .count()
            })
            .max()
            .unwrap_or(0) as f64
    }
    fn describe(&self) -> String {
        format!(
            "peak number of active bubbles{}{}",
            if self.include_initial {
                " (all, including those at the start)"
            } else {
                " formed during the run (not present at its start)"
            },
            match self.window {
                Window::WholeRun => "",
                Window::AfterSurfacing => ", after surfacing",
            }
        )
    }
}

/// Build from the parameter table (`include_initial`, `window`).
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    Ok(Box::new(params::<BubbleCount>(t)?))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame};
    use super::*;

    #[test]
    fn counts_the_bubbles_formed_since_the_start() {
        // bubble 0 is there at the start; 1 and 2 form at t = 1 and 2, 1 dissolves at t = 3:
        // formed and active at once at most 2 (t = 2), all active at most 3
        let f = vec![
            frame(0.0, 1e5, 0.0, vec![bubble(0, 50e-6, 0.0)]),
            frame(
                1.0,
                1e5,
                0.0,
                vec![bubble(0, 50e-6, 0.0), bubble(1, 1e-6, 0.0)],
            ),
            frame(
                2.0,
                1e5,
                0.0,
                vec![
                    bubble(0, 50e-6, 0.0),
                    bubble(1, 2e-6, 0.0),
                    bubble(2, 1e-6, 0.0),
                ],
            ),
            frame(3.0, 1e5, 0.0, vec![bubble(2, 3e-6, 0.0)]),
        ];
        let c = |include_initial, window| {
            BubbleCount {
                include_initial,
                window,
            }
            .evaluate(&RunData {
                frames: &f,
                surfaced_s: Some(2.5),
            })
        };
        assert_eq!(c(false, Window::WholeRun), 2.0);
        assert_eq!(c(true, Window::WholeRun), 3.0);
        assert_eq!(c(false, Window::AfterSurfacing), 1.0);
        assert_eq!(
            BubbleCount {
                include_initial: false,
                window: Window::WholeRun
            }
            .evaluate(&RunData::new(&[])),
            0.0
        );
        let mut bad = toml::Table::new();
        bad.insert("include".into(), true.into());
        assert!(build(bad).unwrap_err().contains("include"));
    }
}
