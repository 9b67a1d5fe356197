//! What a sensitivity study measures of one run: `r_max` (peak radius) and `t_max` (its time),
//! the paper's §2.3.1 outputs; `plateau` and `half_life` of the exponential growth fit
//! R(t) = R_p − (R_p − R_0)e^(−kt) ([`crate::fit::growth::fit_growth`]) over the growth phase;
//! `peak_volume`; `final_radius`. Over all bubbles (the largest at each time; `peak_volume`:
//! the total) or one bubble (`r_max:0`, the 0-based index of the phantom's `[[bubbles]]`).

use crate::error::InputError;
use crate::fit::growth::fit_growth;
use crate::run::SimRun;

/// The metric names.
pub const NAMES: [&str; 6] = [
    "r_max",
    "t_max",
    "plateau",
    "half_life",
    "peak_volume",
    "final_radius",
];

/// A metric, over all bubbles or one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Metric {
    /// One of [`NAMES`].
    pub kind: String,
    /// The bubble, or all.
    pub bubble: Option<usize>,
}

impl Metric {
    /// Parse `NAME` or `NAME:BUBBLE`.
    pub fn parse(text: &str) -> Result<Metric, InputError> {
        let bad = |m: String| {
            InputError::new(m)
                .in_file("<command line>")
                .field("--metric")
        };
        let (kind, bubble) = match text.trim().split_once(':') {
            Some((k, b)) => (
                k,
                Some(b.trim().parse::<usize>().map_err(|_| {
                    bad(format!(
                        "'{text}': the bubble after ':' must be a 0-based index, e.g. r_max:0"
                    ))
                })?),
            ),
            None => (text.trim(), None),
        };
        if !NAMES.contains(&kind) {
            return Err(bad(format!(
                "unknown metric '{kind}'; known: {}",
                NAMES.join(", ")
            )));
        }
        Ok(Metric {
            kind: kind.to_string(),
            bubble,
        })
    }

    /// The name as given (`r_max`, `r_max:0`), also the CSV column.
    pub fn name(&self) -> String {
        match self.bubble {
            Some(b) => format!("{}:{b}", self.kind),
            None => self.kind.clone(),
        }
    }

    /// The quantity in words, for titles (the bubble named when one is chosen).
    pub fn words(&self) -> String {
        let w = match self.kind.as_str() {
            "r_max" => "peak radius R_max",
            "t_max" => "time of the peak radius t_max",
            "plateau" => "growth plateau R_p",
            "half_life" => "growth half-life",
            "peak_volume" => "peak volume",
            _ => "final radius",
        };
        match self.bubble {
            Some(b) => format!("{w} of bubble {b}"),
            None => w.to_string(),
        }
    }

    /// The unit a plot shows the metric in and the factor from its SI value: radii in µm,
    /// volumes in mm³, times in s.
    pub fn plot_unit(&self) -> (&'static str, f64) {
        match self.unit() {
            "m" => ("µm", 1e6),
            "m³" => ("mm³", 1e9),
            u => (u, 1.0),
        }
    }

    /// Unit, for tables and plots.
    pub fn unit(&self) -> &'static str {
        match self.kind.as_str() {
            "t_max" | "half_life" => "s",
            "peak_volume" => "m³",
            _ => "m",
        }
    }

    /// The metric of a run (NaN where it is undefined, e.g. no converged growth fit).
    pub fn of(&self, run: &SimRun) -> f64 {
        let track = track(run, self.bubble);
        let peak = track
            .iter()
            .copied()
            .fold((f64::NAN, f64::NEG_INFINITY), |acc, (t, r)| {
                if r > acc.1 {
                    (t, r)
                } else {
                    acc
                }
            });
        match self.kind.as_str() {
            "r_max" => peak.1,
            "t_max" => peak.0,
            "final_radius" => track.last().map_or(f64::NAN, |p| p.1),
            "peak_volume" => match self.bubble {
                None => run.summary.peak_total_volume.0,
                Some(b) => run
                    .frames
                    .iter()
                    .filter_map(|f| f.bubbles.iter().find(|x| x.id == b).map(|x| x.volume))
                    .fold(0.0, f64::max),
            },
            "plateau" | "half_life" => {
                let g = growth_phase(run, &track);
                match fit_growth(&g, None) {
                    Ok(f) if f.converged => {
                        if self.kind == "plateau" {
                            f.plateau
                        } else {
                            f.half_life
                        }
                    }
                    _ => f64::NAN,
                }
            }
            _ => f64::NAN,
        }
    }
}

/// (time, radius) of one bubble (0 once it is gone) or of the largest bubble at each frame.
pub fn track(run: &SimRun, bubble: Option<usize>) -> Vec<(f64, f64)> {
    run.frames
        .iter()
        .map(|f| {
            let r = match bubble {
                Some(b) => f
                    .bubbles
                    .iter()
                    .find(|x| x.id == b)
                    .map_or(0.0, |x| x.radius),
                None => f.bubbles.iter().map(|x| x.radius).fold(0.0, f64::max),
            };
            (f.time, r)
        })
        .collect()
}

/// The growth phase: the frames from which the ambient pressure stays at its final value
/// (within 1 Pa), i.e. after the last pressure change.
fn growth_phase(run: &SimRun, track: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let Some(last) = run.frames.last() else {
        return Vec::new();
    };
    let start = run
        .frames
        .iter()
        .rposition(|f| (f.ambient - last.ambient).abs() > 1.0)
        .map_or(0, |i| i + 1);
    track[start..].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweep_metric_names_parse_and_refuse() {
        assert_eq!(
            Metric::parse("r_max:2").unwrap(),
            Metric {
                kind: "r_max".into(),
                bubble: Some(2)
            }
        );
        let e = Metric::parse("radius").unwrap_err();
        assert_eq!(e.field.as_deref(), Some("--metric"));
        assert!(Metric::parse("r_max:x").is_err());
    }
}
