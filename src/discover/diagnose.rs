//! Where a fitted model disagrees with the measurements. Residuals e = measured − simulated
//! (so e > 0: the simulated bubble is too small) are grouped by the profile's phase at each
//! measured time (compression, hold, decompression, and each compression/decompression cycle),
//! and set against the simulated radius, time, dP/dt, the distance to the nearest open face and
//! to the nearest other bubble; a runs test per bubble looks for serial correlation. Each
//! grouping is a test (one-sample t-test of the mean residual; Pearson correlation's t-test; the
//! runs test, or the sign test where every residual of a bubble has one sign), and the signatures
//! that hold at a Holm-adjusted p < 0.01 over the whole family of tests (each phase kind, each
//! covariate tested, every bubble's runs test) are put in words, strongest first. The per-cycle
//! means are outside the family: descriptive, unadjusted, used only to word a phase's signature
//! ("on every decompression"). A covariate not defined at three or more observations, or
//! constant over the data, is dropped (not tested, not in the family) and named with the reason.
//!
//! The radius covariate is the simulated radius, not the measured one: the measurement's noise
//! is in both the measured radius and the residual, so against the measured radius even the true
//! model shows a positive correlation, r ≈ σ/√(Var f + σ²) (on data made by the baseline model
//! itself with 15 µm noise, p < 0.01 in 192 of 200 seeds; against the simulated radius 3 of 200).
//! The tests assume independent residuals; a serially correlated misfit (which the runs test
//! detects) makes the t-tests' p-values too small.

use crate::fit::data::{Experiments, Measurements};
use crate::fit::stats::{
    correlation, holm, is_constant, mean_test, runs_test, RunsMethod, RunsTest,
};
use crate::phantom::grid::Grid;
use crate::phantom::sim::Frame;

/// The phase of the profile at one time.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Phase {
    /// Pressure rising.
    Compression,
    /// Pressure constant.
    Hold,
    /// Pressure falling.
    Decompression,
}

impl Phase {
    /// Name in reports.
    pub fn name(self) -> &'static str {
        match self {
            Phase::Compression => "compression",
            Phase::Hold => "hold",
            Phase::Decompression => "decompression",
        }
    }
}

/// Mean residual of a group with its t-test.
#[derive(Debug, Clone, PartialEq)]
pub struct GroupMean {
    /// Group label (e.g. `compression`, `compression, cycle 3`).
    pub label: String,
    /// Observations.
    pub n: usize,
    /// Mean residual, m.
    pub mean: f64,
    /// Its standard error, m.
    pub se: f64,
    /// Two-sided p-value of mean = 0.
    pub p_value: f64,
    /// Holm-adjusted p-value over the diagnostics' family; `None` for a row outside the family
    /// (the per-cycle means: descriptive only).
    pub holm_p: Option<f64>,
}

/// Correlation of the residuals with a covariate.
#[derive(Debug, Clone, PartialEq)]
pub struct Trend {
    /// Covariate name.
    pub covariate: &'static str,
    /// Observations where the covariate is defined (those correlated).
    pub n: usize,
    /// Pearson r.
    pub r: f64,
    /// Two-sided p-value.
    pub p_value: f64,
    /// Holm-adjusted p-value over the diagnostics' family.
    pub holm_p: f64,
}

/// A covariate left out of the tests, with the reason.
#[derive(Debug, Clone, PartialEq)]
pub struct DroppedCovariate {
    /// Covariate name.
    pub covariate: &'static str,
    /// Why it was not tested, e.g. "constant over the data".
    pub reason: String,
}

/// The runs test of one bubble.
#[derive(Debug, Clone, PartialEq)]
pub struct BubbleRuns {
    /// Experiment.
    pub experiment: String,
    /// Bubble index.
    pub bubble: usize,
    /// The test (the sign test in its place when every residual has one sign).
    pub test: RunsTest,
    /// Holm-adjusted p-value over the diagnostics' family.
    pub holm_p: f64,
}

/// Residual diagnostics of one fit.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostics {
    /// By phase kind.
    pub phases: Vec<GroupMean>,
    /// By phase kind and cycle (a cycle starts at each compression).
    pub cycles: Vec<GroupMean>,
    /// Against covariates (those tested).
    pub trends: Vec<Trend>,
    /// Covariates not tested, with the reason.
    pub dropped: Vec<DroppedCovariate>,
    /// Runs test per bubble.
    pub runs: Vec<BubbleRuns>,
    /// The signatures in words, strongest first: the tests at a Holm-adjusted p < 0.01 over
    /// the `family` tests.
    pub signatures: Vec<String>,
    /// How many tests the Holm adjustment counts: phases, covariates tested and runs tests
    /// (`phases.len() + trends.len() + runs.len()`; the per-cycle means are not in it).
    pub family: usize,
}

/// Phase and cycle number (0 before the first compression) at every breakpoint segment.
fn phase_at(profile: &crate::profile::PressureHistory, t: f64) -> (Phase, usize) {
    let eps = 1e-6 * profile.ambient(t);
    // at a breakpoint, the segment the observation closes (the one just before) decides
    let tt = (t - 1e-9).max(0.0);
    let rate = profile.rate(tt);
    let phase = if rate > eps {
        Phase::Compression
    } else if rate < -eps {
        Phase::Decompression
    } else {
        Phase::Hold
    };
    let seg = profile.segment(tt);
    let mut cycle = 0;
    let mut last_up = false;
    for i in 0..=seg.min(profile.times_s.len().saturating_sub(2)) {
        let up = profile.ambient_pa[i + 1] > profile.ambient_pa[i] + eps;
        if up && !last_up {
            cycle += 1;
        }
        if profile.ambient_pa[i + 1] != profile.ambient_pa[i] {
            last_up = up;
        }
    }
    (phase, cycle)
}

fn distances(
    experiments: &Experiments,
    name: &str,
    first: Option<&Frame>,
    bubble: usize,
) -> (f64, f64) {
    let Some(e) = experiments.get(name) else {
        return (f64::NAN, f64::NAN);
    };
    let Some(f) = first else {
        return (f64::NAN, f64::NAN);
    };
    let Some(b) = f.bubbles.iter().find(|b| b.id == bubble) else {
        return (f64::NAN, f64::NAN);
    };
    let face = crate::fit::data::build_params(&e.phantom, &e.phantom_path)
        .ok()
        .and_then(|p| {
            Grid::new(p.shape, p.grid_step, &p.open_faces)
                .ok()
                .map(|g| (g, p))
        })
        .map_or(f64::NAN, |(g, p)| {
            g.distance_to_faces(b.position)
                .filter(|(face, _)| p.open_faces.contains(face))
                .map(|(_, d)| d)
                .fold(f64::INFINITY, f64::min)
        });
    let other = f
        .bubbles
        .iter()
        .filter(|o| o.id != bubble)
        .map(|o| {
            (0..3)
                .map(|k| (o.position[k] - b.position[k]).powi(2))
                .sum::<f64>()
                .sqrt()
        })
        .fold(f64::INFINITY, f64::min);
    (face, other)
}

/// Diagnose the residuals of `predicted` (measurement order) against `data`. `first_frames`
/// holds each experiment's first recorded frame (bubble positions), in the experiments' order.
pub fn diagnose(
    experiments: &Experiments,
    data: &Measurements,
    predicted: &[f64],
    first_frames: &[Option<Frame>],
) -> Diagnostics {
    let mut res = Vec::new();
    let mut rad = Vec::new();
    let mut time = Vec::new();
    let mut rate = Vec::new();
    let mut face = Vec::new();
    let mut near = Vec::new();
    let mut by_phase: std::collections::BTreeMap<Phase, Vec<f64>> = Default::default();
    let mut by_cycle: std::collections::BTreeMap<(usize, Phase), Vec<f64>> = Default::default();
    let mut runs = Vec::new();
    let mut k = 0;
    for s in &data.series {
        let ei = experiments.index_of(&s.experiment);
        let profile = &experiments.list[ei].profile;
        let (df, dn) = distances(
            experiments,
            &s.experiment,
            first_frames.get(ei).and_then(|f| f.as_ref()),
            s.bubble,
        );
        let mut own = Vec::new();
        for p in &s.points {
            let e = p.radius - predicted[k];
            k += 1;
            let (ph, cyc) = phase_at(profile, p.time);
            by_phase.entry(ph).or_default().push(e);
            by_cycle.entry((cyc, ph)).or_default().push(e);
            res.push(e);
            rad.push(predicted[k - 1]);
            time.push(p.time);
            rate.push(profile.rate((p.time - 1e-9).max(0.0)));
            face.push(df);
            near.push(dn);
            own.push(e);
        }
        runs.push(BubbleRuns {
            experiment: s.experiment.clone(),
            bubble: s.bubble,
            test: runs_test(&own),
            holm_p: f64::NAN,
        });
    }
    let group = |label: String, v: &[f64]| {
        let (mean, se, p) = mean_test(v);
        GroupMean {
            label,
            n: v.len(),
            mean,
            se,
            p_value: p,
            holm_p: None,
        }
    };
    let mut phases: Vec<GroupMean> = by_phase
        .iter()
        .map(|(ph, v)| group(ph.name().to_string(), v))
        .collect();
    let cycles: Vec<GroupMean> = by_cycle
        .iter()
        .filter(|((c, _), _)| *c > 0)
        .map(|((c, ph), v)| group(format!("{}, cycle {c}", ph.name()), v))
        .collect();
    let mut trends = Vec::new();
    let mut dropped = Vec::new();
    // the covariates, each with what an infinite value of it means (a NaN: not known)
    for (name, x, infinite) in [
        ("simulated radius", &rad, ""),
        ("time", &time, ""),
        ("dP/dt", &rate, ""),
        (
            "distance to the nearest open face",
            &face,
            "the phantom has no open face",
        ),
        (
            "distance to the nearest bubble",
            &near,
            "the experiment has no other bubble",
        ),
    ] {
        let pairs: Vec<(f64, f64)> = x
            .iter()
            .zip(&res)
            .filter(|(a, _)| a.is_finite())
            .map(|(a, b)| (*a, *b))
            .collect();
        let (xs, ys): (Vec<f64>, Vec<f64>) = pairs.into_iter().unzip();
        let (r, p) = correlation(&xs, &ys);
        if r.is_finite() {
            trends.push(Trend {
                covariate: name,
                n: xs.len(),
                r,
                p_value: p,
                holm_p: f64::NAN,
            });
        } else {
            dropped.push(DroppedCovariate {
                covariate: name,
                reason: drop_reason(x, &xs, &ys, infinite),
            });
        }
    }
    // Holm over the family, in the order phases, covariates, runs tests
    let family_p: Vec<f64> = phases
        .iter()
        .map(|g| g.p_value)
        .chain(trends.iter().map(|t| t.p_value))
        .chain(runs.iter().map(|r| r.test.p_value))
        .collect();
    let family = family_p.len();
    let adjusted = holm(&family_p);
    let (adj_phases, rest) = adjusted.split_at(phases.len());
    let (adj_trends, adj_runs) = rest.split_at(trends.len());
    for (g, q) in phases.iter_mut().zip(adj_phases) {
        g.holm_p = Some(*q);
    }
    for (t, q) in trends.iter_mut().zip(adj_trends) {
        t.holm_p = *q;
    }
    for (b, q) in runs.iter_mut().zip(adj_runs) {
        b.holm_p = *q;
    }
    let signatures = words(&phases, &cycles, &trends, &runs, family);
    Diagnostics {
        phases,
        cycles,
        trends,
        dropped,
        runs,
        signatures,
        family,
    }
}

/// Why a covariate with values `all` (one per observation) gave no correlation: `xs`, `ys` are
/// the pairs where it is finite, `infinite` what an infinite value of it means.
fn drop_reason(all: &[f64], xs: &[f64], ys: &[f64], infinite: &str) -> String {
    let inf = all.iter().filter(|v| v.is_infinite()).count();
    let nan = all.iter().filter(|v| v.is_nan()).count();
    let mut why = Vec::new();
    if inf > 0 && !infinite.is_empty() {
        why.push(format!("{infinite} ({inf} observations)"));
    } else if inf > 0 {
        why.push(format!("not finite at {inf} observations"));
    }
    if nan > 0 {
        why.push(format!(
            "not known at {nan} observations (no bubble positions)"
        ));
    }
    let causes = if why.is_empty() {
        String::new()
    } else {
        format!(": {}", why.join("; "))
    };
    if xs.is_empty() {
        format!("not defined at any observation{causes}")
    } else if xs.len() < 3 {
        format!(
            "defined at only {} observations, a correlation needs 3{causes}",
            xs.len()
        )
    } else if is_constant(xs) {
        if xs.len() == all.len() {
            "constant over the data".to_string()
        } else {
            format!(
                "constant over the {} observations where it is defined{causes}",
                xs.len()
            )
        }
    } else if is_constant(ys) {
        "the residuals are constant".to_string()
    } else {
        "the correlation is not a finite number".to_string()
    }
}

/// A length in µm to 3 significant digits.
fn um(x: f64) -> String {
    format!("{} µm", crate::fit::report::sig(x * 1e6, 3))
}

fn words(
    phases: &[GroupMean],
    cycles: &[GroupMean],
    trends: &[Trend],
    runs: &[BubbleRuns],
    m: usize,
) -> Vec<String> {
    let holm_note = |p: f64, q: f64| {
        use super::report::p_text;
        format!(
            "p {}, Holm-adjusted over {m} tests p {}",
            p_text(p),
            p_text(q)
        )
    };
    let mut out: Vec<(f64, String)> = Vec::new();
    for (g, q) in phases
        .iter()
        .filter_map(|g| g.holm_p.map(|q| (g, q)))
        .filter(|(_, q)| *q < 0.01)
    {
        let kind = g.label.as_str();
        // same sign in every cycle of this kind?
        let cyc: Vec<&GroupMean> = cycles
            .iter()
            .filter(|c| c.label.starts_with(&format!("{kind},")))
            .collect();
        let every = cyc.len() > 1 && cyc.iter().all(|c| c.mean.signum() == g.mean.signum());
        let verb = match (kind, g.mean > 0.0) {
            ("compression", true) => "simulated bubbles shrink too much",
            ("compression", false) => "simulated bubbles shrink too little",
            ("decompression", true) => "simulated bubbles grow too little",
            ("decompression", false) => "simulated bubbles grow too much",
            (_, true) => "simulated bubbles are too small",
            (_, false) => "simulated bubbles are too large",
        };
        let when = if every {
            format!("on every {kind} ({} cycles)", cyc.len())
        } else {
            format!("during {kind}")
        };
        out.push((
            q,
            format!(
                "{verb} {when}: mean residual (measured − simulated) {} ± {} (t-test {}, n = {})",
                um(g.mean),
                um(g.se),
                holm_note(g.p_value, q),
                g.n
            ),
        ));
    }
    for (t, q) in trends
        .iter()
        .map(|t| (t, t.holm_p))
        .filter(|(_, q)| *q < 0.01)
    {
        let dir = if t.r > 0.0 {
            "the simulated bubbles fall further below the measurements"
        } else {
            "the simulated bubbles rise further above the measurements"
        };
        out.push((
            q,
            format!(
                "as {} increases, {dir} (Pearson r = {:.2}, {})",
                t.covariate,
                t.r,
                holm_note(t.p_value, q)
            ),
        ));
    }
    let correlated: Vec<(&BubbleRuns, f64)> = runs
        .iter()
        .map(|r| (r, r.holm_p))
        .filter(|(r, q)| *q < 0.01 && r.test.clustered())
        .collect();
    if let Some(&(strongest, q)) = correlated.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
        let one_sign = correlated
            .iter()
            .filter(|(r, _)| r.test.method == RunsMethod::SignTest)
            .count();
        let how = if one_sign == 0 {
            String::new()
        } else {
            format!(
                "; every residual of one sign for {one_sign} of them, where the sign test stands in for the runs test"
            )
        };
        let test = if strongest.test.method == RunsMethod::SignTest {
            "sign test"
        } else {
            "runs test"
        };
        out.push((
            q,
            format!(
                "residuals run in long stretches of one sign (systematic misfit, not noise) for {} of {} bubbles{how} (smallest: {} of {} bubble {}, {})",
                correlated.len(),
                runs.len(),
                test,
                strongest.experiment,
                strongest.bubble,
                holm_note(strongest.test.p_value, q)
            ),
        ));
    }
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out.into_iter().map(|(_, s)| s).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A covariate the correlation cannot use is named with why: constant (dP/dt of a profile
    /// that only holds), infinite everywhere (one bubble: no nearest other bubble), not known
    /// (no bubble positions), defined at too few rows (reasons by construction in this test).
    #[test]
    fn dropped_covariates_say_why() {
        let ys: Vec<f64> = (0..5).map(|i| (i as f64).sin()).collect();
        let flat = [0.0; 5];
        assert_eq!(drop_reason(&flat, &flat, &ys, ""), "constant over the data");
        let inf = [f64::INFINITY; 5];
        assert_eq!(
            drop_reason(&inf, &[], &[], "the experiment has no other bubble"),
            "not defined at any observation: the experiment has no other bubble (5 observations)"
        );
        let nan = [f64::NAN; 5];
        assert_eq!(
            drop_reason(&nan, &[], &[], "the phantom has no open face"),
            "not defined at any observation: not known at 5 observations (no bubble positions)"
        );
        let few = [1.0, 2.0, f64::NAN, f64::NAN, f64::NAN];
        assert_eq!(
            drop_reason(&few, &few[..2], &ys[..2], ""),
            "defined at only 2 observations, a correlation needs 3: not known at 3 observations (no bubble positions)"
        );
    }
}
