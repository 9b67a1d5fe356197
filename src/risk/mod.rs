//! Risk criteria: a bubble history in, a score against a limit out.
//!
//! A [`RiskCriterion`] turns the recorded frames of one phantom run ([`RunData`]) into one
//! number in its own display unit (documented on each criterion). A criteria file
//! (`algorithms/criteria/*.toml`, read by [`config`]) chooses criteria from the
//! [`REGISTRY`] by their TOML `kind`, gives each a limit and its parameters, and fixes the
//! evaluation protocol (how long the phantom is watched after surfacing, the water vapour
//! at its open faces). [`CriteriaSet::score`] scores a run: value, limit, pass (value ≤
//! limit) and margin (limit − value, positive when it passes).
//!
//! Every criterion works on the recorded frames (the phantom's `record_interval`), so a peak
//! between two frames is seen only as far as the frames sample it; time integrals use the
//! piecewise-linear interpolant of the frames ([`series`]).

use crate::phantom::sim::Frame;

pub mod activation_time;
pub mod area_rate;
pub mod bubble_count;
pub mod config;
pub mod hazard;
pub mod peak_radius;
pub mod peak_volume;
pub mod series;
pub mod supersaturation;
pub mod volume_integral;

pub use config::{load_criteria, parse_criteria, ConfiguredCriterion, CriteriaSet, Protocol};

/// What a criterion sees of one phantom run.
#[derive(Debug, Clone, Copy)]
pub struct RunData<'a> {
    /// The recorded frames, in time order (times in s, SI units throughout).
    pub frames: &'a [Frame],
    /// When the (last) dive reached the surface, s; `None` if unknown (e.g. a laboratory
    /// profile). Criteria with `window = "after-surfacing"` look only at frames from then on.
    pub surfaced_s: Option<f64>,
}

impl<'a> RunData<'a> {
    /// Run data without a known surfacing time.
    pub fn new(frames: &'a [Frame]) -> Self {
        RunData {
            frames,
            surfaced_s: None,
        }
    }

    /// The frames of a window: all of them, or those at or after surfacing.
    pub fn window(&self, w: Window) -> &'a [Frame] {
        match (w, self.surfaced_s) {
            (Window::AfterSurfacing, Some(t)) => {
                let k = self.frames.partition_point(|f| f.time < t - 1e-9);
                &self.frames[k..]
            }
            _ => self.frames,
        }
    }
}

/// Which part of a run a criterion looks at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Window {
    /// The whole run (default).
    #[default]
    WholeRun,
    /// From the moment the (last) dive reaches the surface: growth at constant ambient
    /// pressure, i.e. by diffusion only, without the Boyle expansion of the ascent.
    AfterSurfacing,
}

/// What a peak criterion measures (`measure = ...` in its `[[criterion]]` entry).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Measure {
    /// The growth the schedule causes: the value above each bubble's R0 (its radius at
    /// creation: the nucleus at t = 0 or at activation), so a run in which nothing grows scores
    /// 0 whatever the seed (default). The absolute value is reported beside it.
    #[default]
    Growth,
    /// The absolute value, seed included (the scores before issue 12).
    Absolute,
}

/// A risk criterion: one number from a run's bubble history, in [`RiskCriterion::unit`].
pub trait RiskCriterion: Send + Sync + std::fmt::Debug {
    /// The TOML `kind` of the criterion (its registry key).
    fn name(&self) -> &'static str;
    /// The criterion's value for a run, in [`RiskCriterion::unit`] (limits use the same unit).
    fn evaluate(&self, run: &RunData) -> f64;
    /// Display unit of the value and the limit (e.g. `mm³`). Default: dimensionless.
    fn unit(&self) -> &'static str {
        ""
    }
    /// One line saying what is measured, with its parameters, for reports.
    fn describe(&self) -> String {
        self.name().to_string()
    }
    /// For a criterion that scores growth above the starting state: the absolute value behind
    /// it (e.g. the peak volume with the nuclei), in the same unit, reported beside the score.
    /// `None` (default) when the value is itself absolute.
    fn absolute(&self, _run: &RunData) -> Option<f64> {
        None
    }
}

/// A criterion's constructor from its parameter table (every field of its `[[criterion]]`
/// entry except `kind`, `limit` and `label`). The error names the offending field.
pub type Builder = fn(toml::Table) -> Result<Box<dyn RiskCriterion>, String>;

/// The registered criteria, keyed by the `kind` written in a criteria TOML.
pub static REGISTRY: &[(&str, Builder)] = &[
    ("peak-total-volume", peak_volume::build),
    ("peak-radius", peak_radius::build),
    ("peak-area-growth-rate", area_rate::build),
    ("volume-time-above-threshold", volume_integral::build),
    ("peak-supersaturation", supersaturation::build),
    ("hazard", hazard::build),
    ("bubble-count", bubble_count::build),
    ("activation-time", activation_time::build),
];

/// The registered kinds, in registry order.
pub fn kinds() -> Vec<&'static str> {
    REGISTRY.iter().map(|(k, _)| *k).collect()
}

/// Build the criterion registered as `kind` from its parameters.
pub fn build(kind: &str, params: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    let (_, b) = REGISTRY
        .iter()
        .find(|(k, _)| *k == kind)
        .ok_or_else(|| format!("unknown criterion '{kind}'; known: {}", kinds().join(", ")))?;
    b(params)
}

/// Deserialize a criterion's parameter table into its raw struct (`deny_unknown_fields`); the
/// error starts with the key it is about ([`crate::error::table_into`]).
pub(crate) fn params<T: serde::de::DeserializeOwned>(t: toml::Table) -> Result<T, String> {
    crate::error::table_into(toml::Value::Table(t))
}

/// A criterion's score on one run.
#[derive(Debug, Clone, PartialEq)]
pub struct Score {
    /// Label of the criterion (from the file, or its kind).
    pub label: String,
    /// Registry kind.
    pub kind: &'static str,
    /// Display unit of value, limit and margin.
    pub unit: &'static str,
    /// The value, in `unit`.
    pub value: f64,
    /// The limit, in `unit` (> 0).
    pub limit: f64,
    /// True when value ≤ limit.
    pub pass: bool,
    /// limit − value, in `unit` (positive when the criterion passes).
    pub margin: f64,
    /// The absolute value behind a growth score ([`RiskCriterion::absolute`]), in `unit`.
    pub absolute: Option<f64>,
}

impl Score {
    /// value / limit: below 1 passes.
    pub fn ratio(&self) -> f64 {
        self.value / self.limit
    }
}

/// Check scores before they are written or printed: a non-finite value, limit or margin is a
/// bug or a numerical failure, never a result (the binary exits 3 with this message).
pub fn check_finite(scores: &[Score]) -> Result<(), String> {
    for s in scores {
        let abs = s.absolute.unwrap_or(0.0);
        for (what, v) in [
            ("value", s.value),
            ("limit", s.limit),
            ("margin", s.margin),
            ("absolute value", abs),
        ] {
            if !v.is_finite() {
                return Err(format!(
                    "criterion '{}' ({}) gave a non-finite {what} ({v}); nothing was written",
                    s.label, s.kind
                ));
            }
        }
    }
    Ok(())
}

/// Score `value` against `limit`; `absolute` is the absolute value behind a growth score.
pub fn score(
    label: &str,
    c: &dyn RiskCriterion,
    value: f64,
    limit: f64,
    absolute: Option<f64>,
) -> Score {
    Score {
        label: label.to_string(),
        kind: c.name(),
        unit: c.unit(),
        value,
        limit,
        pass: value <= limit,
        margin: limit - value,
        absolute,
    }
}

#[cfg(test)]
pub(crate) mod testing {
    //! Synthetic frames for the criteria's unit tests.
    use crate::phantom::sim::{BubbleFrame, Frame};
    use std::f64::consts::PI;

    /// A bubble of radius `r` (m) with id `id`, gel tension `tension` (Pa).
    pub fn bubble(id: usize, r: f64, tension: f64) -> BubbleFrame {
        BubbleFrame {
            id,
            radius: r,
            initial_radius: r,
            volume: 4.0 / 3.0 * PI * r.powi(3),
            area: 4.0 * PI * r * r,
            moles: vec![0.0],
            gel_tension: tension,
            position: [0.0; 3],
        }
    }

    /// A bubble created at radius `r0` (m), now of radius `r`.
    pub fn grown(id: usize, r0: f64, r: f64) -> BubbleFrame {
        BubbleFrame {
            initial_radius: r0,
            ..bubble(id, r, 0.0)
        }
    }

    /// A frame at `t` (s) with ambient `p` (Pa), gel supersaturation `ss` (Pa) and bubbles.
    pub fn frame(t: f64, p: f64, ss: f64, bubbles: Vec<BubbleFrame>) -> Frame {
        Frame {
            time: t,
            ambient: p,
            bubbles,
            max_supersaturation: ss,
            grid_moles: vec![0.0],
        }
    }
}
