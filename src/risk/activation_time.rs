//! `activation-time`: how early in the run the first bubble formed, as the time from that
//! activation to the end of the recorded run, min (0 when no bubble formed). A bubble "forms"
//! when it appears in a frame without being in the run's first frame (the state at the start of
//! the schedule), so under the `fixed` nucleation model the value is 0. Larger is worse: an
//! earlier activation leaves the bubbles longer to grow, so the value fits the criteria's
//! "value ≤ limit passes". The activation is seen at the frame resolution (`record_interval`);
//! its absolute time from the start of the run is [`ActivationTime::first_activation`].

use super::{params, RiskCriterion, RunData};
use serde::Deserialize;
use std::collections::BTreeSet;

/// Time from the first bubble formed during the run to the run's end, min.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActivationTime {}

impl ActivationTime {
    /// Time of the first frame holding a bubble absent from the first frame, s.
    pub fn first_activation(run: &RunData) -> Option<f64> {
        let first = run.frames.first()?;
        let initial: BTreeSet<usize> = first.bubbles.iter().map(|b| b.id).collect();
        run.frames
            .iter()
            .find(|f| f.bubbles.iter().any(|b| !initial.contains(&b.id)))
            .map(|f| f.time)
    }
}

impl RiskCriterion for ActivationTime {
    fn name(&self) -> &'static str {
        "activation-time"
    }
    fn unit(&self) -> &'static str {
        "min"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        match (Self::first_activation(run), run.frames.last()) {
            (Some(t), Some(last)) => (last.time - t) / 60.0,
            _ => 0.0,
        }
    }
    fn describe(&self) -> String {
        "time from the first bubble formed during the run (not present at its start) to the end of the run".into()
    }
}

/// Build from the (empty) parameter table.
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    Ok(Box::new(params::<ActivationTime>(t)?))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame};
    use super::*;

    #[test]
    fn time_from_the_first_new_bubble_to_the_end() {
        // bubble 0 at the start; bubble 4 appears at 120 s; the run ends at 600 s:
        // (600 − 120)/60 = 8 min
        let f = vec![
            frame(0.0, 1e5, 0.0, vec![bubble(0, 50e-6, 0.0)]),
            frame(60.0, 1e5, 0.0, vec![bubble(0, 50e-6, 0.0)]),
            frame(
                120.0,
                1e5,
                0.0,
                vec![bubble(0, 50e-6, 0.0), bubble(4, 1e-6, 0.0)],
            ),
            frame(600.0, 1e5, 0.0, vec![bubble(4, 5e-6, 0.0)]),
        ];
        assert_eq!(ActivationTime {}.evaluate(&RunData::new(&f)), 8.0);
        // nothing formed (the fixed model): 0
        assert_eq!(ActivationTime {}.evaluate(&RunData::new(&f[..2])), 0.0);
        assert_eq!(ActivationTime {}.evaluate(&RunData::new(&[])), 0.0);
    }
}
