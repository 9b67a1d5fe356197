//! The `discover` report: `discover.toml`, `report.md`, `report.html` and the overlays of every
//! measured bubble against the baseline and the final model.

use super::diagnose::Diagnostics;
use super::search::{CandidateOutcome, Discovery};
use crate::error::Error;
use crate::fit::data::{Experiments, Measurements};
use crate::fit::paths;
use crate::fit::report::{
    add_overlays, aicc_absent, data_info, estimate_stats, estimates_table_with_truth,
    exponent_floats, finite_estimate, finite_result, sig, DataInfo, DataOut,
};
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::table::{Cell, Column, Table};
use crate::run::SimRun;
use serde::Serialize;
use std::collections::BTreeMap;

/// `discover.toml`. A statistic that is not a finite number (the F statistic of a candidate
/// that could not be fitted or left no residual degree of freedom, a ΔAICc where an AICc is not
/// defined) is left out and its reason written in the `absent` table beside it.
#[derive(Serialize)]
struct DiscoverFile {
    effects: Vec<String>,
    ssr_before: f64,
    ssr_after: f64,
    rmse_before_m: f64,
    rmse_after_m: f64,
    weighted_rmse_before_m: f64,
    weighted_rmse_after_m: f64,
    numerical_error_rms_m: f64,
    measurement_sd_from_file: bool,
    alpha: f64,
    observations: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    data: Option<DataOut>,
    added: Vec<AddedOut>,
    round: Vec<RoundOut>,
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    bubble_weight: Vec<BubbleWeight>,
    diagnostics: DiagnosticsOut,
}

/// The residual diagnostics' Holm family, dropped covariates and runs tests, of the baseline
/// and of the final model.
#[derive(Serialize)]
struct DiagnosticsOut {
    baseline: DiagnosisOut,
    final_model: DiagnosisOut,
}

#[derive(Serialize)]
struct DiagnosisOut {
    /// Tests in the Holm family.
    holm_family: usize,
    /// The family's tests, by name (`phase: hold`, `covariate: time`, `runs: osc-150 bubble 0`);
    /// the per-cycle means are outside it.
    holm_family_members: Vec<String>,
    /// Holm-adjusted p-values, in the order of `holm_family_members` (1 for a test whose p is
    /// not a number).
    holm_p: Vec<f64>,
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    dropped_covariate: Vec<DroppedOut>,
    runs_test: Vec<RunsOut>,
}

#[derive(Serialize)]
struct DroppedOut {
    covariate: String,
    reason: String,
}

#[derive(Serialize)]
struct RunsOut {
    experiment: String,
    bubble: usize,
    n_plus: usize,
    n_minus: usize,
    runs: usize,
    /// `exact`, `normal approximation`, `sign test` (every residual of one sign) or
    /// `no residual`.
    method: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    p_value: Option<f64>,
    holm_p: f64,
}

fn diagnosis_out(d: &Diagnostics) -> DiagnosisOut {
    let members = d
        .phases
        .iter()
        .map(|g| (format!("phase: {}", g.label), g.holm_p.unwrap_or(f64::NAN)))
        .chain(
            d.trends
                .iter()
                .map(|t| (format!("covariate: {}", t.covariate), t.holm_p)),
        )
        .chain(d.runs.iter().map(|r| {
            (
                format!("runs: {} bubble {}", r.experiment, r.bubble),
                r.holm_p,
            )
        }));
    let (holm_family_members, holm_p): (Vec<String>, Vec<f64>) = members.unzip();
    DiagnosisOut {
        holm_family: d.family,
        holm_family_members,
        holm_p: holm_p
            .into_iter()
            .map(|q| if q.is_finite() { q } else { 1.0 })
            .collect(),
        dropped_covariate: d
            .dropped
            .iter()
            .map(|c| DroppedOut {
                covariate: c.covariate.to_string(),
                reason: c.reason.clone(),
            })
            .collect(),
        runs_test: d
            .runs
            .iter()
            .map(|r| RunsOut {
                experiment: r.experiment.clone(),
                bubble: r.bubble,
                n_plus: r.test.n_plus,
                n_minus: r.test.n_minus,
                runs: r.test.runs,
                method: r.test.method.name().to_string(),
                p_value: Some(r.test.p_value).filter(|p| p.is_finite()),
                holm_p: if r.holm_p.is_finite() { r.holm_p } else { 1.0 },
            })
            .collect(),
    }
}

#[derive(Serialize)]
struct AddedOut {
    effect: String,
    parameter: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    value: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    ci95: Option<[f64; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    p_value: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    f: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    delta_ssr: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    delta_aicc: Option<f64>,
    parameters: Vec<String>,
    values: Vec<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    ci95_all: Option<Vec<[f64; 2]>>,
    alternatives: Vec<String>,
    /// F-test degrees of freedom [numerator, denominator].
    #[serde(skip_serializing_if = "Option::is_none")]
    f_dof: Option<[usize; 2]>,
    /// True values by parameter (synthetic data whose model the final model contains).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    true_values: BTreeMap<String, f64>,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    absent: BTreeMap<&'static str, String>,
}

#[derive(Serialize)]
struct RoundOut {
    current: Vec<String>,
    threshold: f64,
    accepted: String,
    verdict: String,
    candidate: Vec<CandOut>,
}

#[derive(Serialize)]
struct CandOut {
    name: String,
    dof: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    delta_ssr: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    f: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    p_value: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    delta_aicc: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    rmse_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    weighted_rmse_m: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    f_den_dof: Option<usize>,
    parameters: Vec<String>,
    values: Vec<f64>,
    error: String,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    absent: BTreeMap<&'static str, String>,
}

/// A number as written, or why it is not.
type Stat = Result<f64, String>;

/// The statistics of a candidate's refit as written: ΔSSR, F, p, ΔAICc and RMSE, each the
/// number or the reason it is not given.
struct CandStats {
    delta_ssr: Stat,
    f: Stat,
    p_value: Stat,
    delta_aicc: Stat,
    rmse: Stat,
}

fn cand_stats(o: &CandidateOutcome, n: usize) -> CandStats {
    let finite = |v: f64, why: &dyn Fn() -> String| -> Stat {
        if v.is_finite() {
            Ok(v)
        } else {
            Err(why())
        }
    };
    if o.error.is_some() {
        let why = || "not fitted".to_string();
        return CandStats {
            delta_ssr: Err(why()),
            f: Err(why()),
            p_value: Err(why()),
            delta_aicc: Err(why()),
            rmse: Err(why()),
        };
    }
    let t = &o.f_test;
    let f_why = || {
        if t.df_den == 0 {
            "no residual degree of freedom left in the candidate's model".to_string()
        } else if t.df_num == 0 {
            "the candidate adds no degree of freedom".to_string()
        } else {
            "the candidate's SSR is 0: F is not defined".to_string()
        }
    };
    CandStats {
        delta_ssr: finite(o.delta_ssr, &|| "not a finite number".into()),
        f: finite(t.f, &f_why),
        p_value: finite(t.p_value, &f_why),
        delta_aicc: finite(o.delta_aicc, &|| {
            format!("AICc (K = p + 1) needs n > p + 2 in both models (n = {n}, df of the candidate's model {})", t.df_den)
        }),
        rmse: finite(o.rmse, &|| "not a finite number".into()),
    }
}

/// The number (`fmt`) or its reason, for a table or a sentence.
fn stat_text(v: &Stat, fmt: impl Fn(f64) -> String) -> String {
    match v {
        Ok(x) => fmt(*x),
        Err(m) => format!("not given ({m})"),
    }
}

/// Smallest p-value printed as a number: below it a double-precision p-value says nothing
/// more (1 − p is 1 to machine precision, ~1.1e-16, and the F distribution's tail is only as
/// good as the Gaussian error model far out in it), so it is printed as "< 1e-16".
pub const P_FLOOR: f64 = 1e-16;

/// A p-value with its relation, for a sentence: "= 0.434", "= 6.55e-31"… or "< 1e-16".
pub fn p_text(p: f64) -> String {
    if p < P_FLOOR {
        p_cell(p)
    } else {
        format!("= {}", p_cell(p))
    }
}

/// A p-value for a table cell: "0.434", "2.27e-32"… or "< 1e-16".
pub fn p_cell(p: f64) -> String {
    if p < P_FLOOR {
        "< 1e-16".into()
    } else {
        sig(p, 3)
    }
}

/// What the F and p cells say for a candidate whose refit is worse than the current model
/// (ΔSSR < 0): the F statistic is not a test of anything then.
pub const FITS_WORSE: &str = "—, fits worse than the current model";

/// A candidate's fitted parameter for the round table, named in a reader's words
/// ([`paths::with_value_in`], elasticity terms from `own_terms` on named as added ones):
/// `symbol = value unit` with 3 significant digits; `symbol → 0 (at its null)` for a
/// log-space parameter with null 0 that ran below a millionth of the smallest value its scan
/// tried (the effect switched off, not a small effect); `symbol = value unit (at the bound)`
/// for one at a bound of its range.
pub fn candidate_param_text(
    e: &crate::fit::lsq::Estimate,
    p: Option<&super::EffectParam>,
    own_terms: Option<usize>,
) -> String {
    let at_null = p.is_some_and(|p| {
        let least = p
            .scan
            .iter()
            .copied()
            .filter(|x| *x > 0.0)
            .fold(f64::INFINITY, f64::min);
        p.null == 0.0 && e.log && least.is_finite() && e.value.abs() < 1e-6 * least
    });
    let value = paths::with_value_in(&e.name, &sig(e.value, 3), own_terms);
    if at_null {
        format!(
            "{} → 0 (at its null)",
            paths::describe_in(&e.name, own_terms).0
        )
    } else if e.at_bound {
        format!("{value} (at the bound)")
    } else {
        value
    }
}

/// The index of the first elasticity term `discover` adds: the phantom's own terms
/// ([`paths::own_elasticity_terms`]), when every experiment's phantom has the same number.
fn own_terms_of(experiments: &Experiments) -> Option<usize> {
    let mut counts = experiments
        .list
        .iter()
        .map(|e| paths::own_elasticity_terms(&e.phantom));
    let first = counts.next()?;
    counts.all(|c| c == first).then_some(first)
}

/// Estimates and true values with each parameter named in a reader's words
/// ([`paths::label_in`]) for the report's tables; `discover.toml` keeps the paths.
fn readable_estimates(
    est: &[crate::fit::lsq::Estimate],
    truth: &BTreeMap<String, f64>,
    own_terms: Option<usize>,
) -> (Vec<crate::fit::lsq::Estimate>, BTreeMap<String, f64>) {
    let named: Vec<crate::fit::lsq::Estimate> = est
        .iter()
        .map(|e| crate::fit::lsq::Estimate {
            name: paths::label_in(&e.name, own_terms),
            ..e.clone()
        })
        .collect();
    let truth = truth
        .iter()
        .map(|(k, v)| (paths::label_in(k, own_terms), *v))
        .collect();
    (named, truth)
}

/// Weighted RMSE, m: √(Σ wᵢrᵢ² / Σ wᵢ) from a weighted SSR Σ wᵢrᵢ² and the weights (the
/// residuals' RMS with each row counted by its weight 1/(sd² + e²), in the radii's unit).
pub fn weighted_rmse(ssr: f64, weights: &[f64]) -> f64 {
    (ssr / weights.iter().sum::<f64>()).sqrt()
}

/// One bubble's measurement sd, numerical error e and weight 1/(sd² + e²) in the tests.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BubbleWeight {
    /// Experiment.
    pub experiment: String,
    /// Bubble.
    pub bubble: usize,
    /// Its observations.
    pub observations: usize,
    /// Measurement sd, m (the least and the largest over its rows).
    pub sd_m: [f64; 2],
    /// Its numerical error e, m (the RMS of the Richardson estimate over its rows).
    pub numerical_error_m: f64,
    /// Weight 1/(sd² + e²), m⁻² (the least and the largest over its rows).
    pub weight_per_m2: [f64; 2],
    /// Its rows' share of the total weight.
    pub weight_share: f64,
}

/// [`BubbleWeight`] of every measured bubble, in measurement order.
pub fn bubble_weights(d: &Discovery, data: &Measurements) -> Vec<BubbleWeight> {
    let total: f64 = d.weights.iter().sum();
    let mut k = 0;
    let mut out = Vec::new();
    for s in &data.series {
        let n = s.points.len();
        let range = |v: &[f64]| {
            [
                v.iter().copied().fold(f64::INFINITY, f64::min),
                v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ]
        };
        let w = &d.weights[k..k + n];
        out.push(BubbleWeight {
            experiment: s.experiment.clone(),
            bubble: s.bubble,
            observations: n,
            sd_m: range(&d.measurement_sd[k..k + n]),
            numerical_error_m: d
                .numerical
                .per_observation
                .get(k)
                .copied()
                .unwrap_or(f64::NAN),
            weight_per_m2: range(w),
            weight_share: w.iter().sum::<f64>() / total,
        });
        k += n;
    }
    out
}

/// `a` or, when the range is not one value, `a–b` (each with `digits` significant digits).
fn range_text(r: [f64; 2], scale: f64, digits: usize) -> String {
    let (a, b) = (sig(r[0] * scale, digits), sig(r[1] * scale, digits));
    if a == b {
        a
    } else {
        format!("{a}–{b}")
    }
}

/// `discover.toml` text.
pub fn discover_toml(d: &Discovery) -> Result<String, Error> {
    discover_toml_with(d, None, &[])
}

/// `discover.toml` text with the `[data]` table and true values ([`data_info`]) and the
/// bubbles' weights.
fn discover_toml_with(
    d: &Discovery,
    info: Option<&DataInfo>,
    bubbles: &[BubbleWeight],
) -> Result<String, Error> {
    for (what, v) in [
        ("the baseline's weighted SSR", d.baseline.ssr),
        ("the final model's weighted SSR", d.final_fit.ssr),
        ("the baseline's RMSE", d.baseline.rmse),
        ("the final model's RMSE", d.final_fit.rmse),
        ("the numerical-error estimate", d.numerical.rms),
    ] {
        finite_result(what, v)?;
    }
    let n = d.baseline.n;
    let mut added = Vec::new();
    for a in &d.added {
        let mut absent = BTreeMap::new();
        for e in &a.parameters {
            finite_estimate(e)?;
        }
        let singular = d.final_fit.inference.singular;
        let stats: Vec<_> = a
            .parameters
            .iter()
            .map(|e| estimate_stats(e, singular).1)
            .collect();
        let first = a.parameters.first();
        let ci95 = match stats.first() {
            Some(Ok(c)) => Some(*c),
            Some(Err(m)) => {
                absent.insert("ci95", m.clone());
                None
            }
            None => None,
        };
        let ci95_all = match stats.iter().find_map(|c| c.as_ref().err()) {
            None => Some(
                stats
                    .iter()
                    .filter_map(|c| c.as_ref().ok().copied())
                    .collect(),
            ),
            Some(m) => {
                absent.insert("ci95_all", m.clone());
                None
            }
        };
        let mut keep = |key: &'static str, v: f64, why: &str| {
            if v.is_finite() {
                Some(v)
            } else {
                absent.insert(key, why.to_string());
                None
            }
        };
        added.push(AddedOut {
            effect: a.effect.clone(),
            parameter: first.map_or(String::new(), |e| e.name.clone()),
            value: first.map(|e| e.value),
            ci95,
            p_value: keep("p_value", a.p_value, "not a finite number"),
            f: keep("f", a.f, "not a finite number"),
            delta_ssr: keep("delta_ssr", a.delta_ssr, "not a finite number"),
            delta_aicc: keep(
                "delta_aicc",
                a.delta_aicc,
                "AICc (K = p + 1) needs n > p + 2 in both models",
            ),
            parameters: a.parameters.iter().map(|e| e.name.clone()).collect(),
            values: a.parameters.iter().map(|e| e.value).collect(),
            ci95_all,
            alternatives: a.alternatives.iter().map(|x| x.0.clone()).collect(),
            f_dof: added_test(d, &a.effect).map(|t| [t.df_num, t.df_den]),
            true_values: a
                .parameters
                .iter()
                .filter_map(|e| {
                    info.and_then(|i| i.truth.get(&e.name))
                        .map(|v| (e.name.clone(), *v))
                })
                .collect(),
            absent,
        });
    }
    let mut round = Vec::new();
    let _ = bubbles;
    for r in &d.rounds {
        let mut candidate = Vec::new();
        for o in &r.outcomes {
            let st = cand_stats(o, n);
            let mut absent = BTreeMap::new();
            let mut keep = |key: &'static str, v: &Stat| match v {
                Ok(x) => Some(*x),
                Err(m) => {
                    absent.insert(key, m.clone());
                    None
                }
            };
            let (delta_ssr, f, p_value, delta_aicc, rmse_m) = (
                keep("delta_ssr", &st.delta_ssr),
                keep("f", &st.f),
                keep("p_value", &st.p_value),
                keep("delta_aicc", &st.delta_aicc),
                keep("rmse_m", &st.rmse),
            );
            let values: Vec<f64> = o.estimates.iter().map(|e| e.value).collect();
            if values.iter().any(|v| !v.is_finite()) {
                absent.insert("values", "not a finite number".into());
            }
            candidate.push(CandOut {
                name: o.name.clone(),
                dof: o.dof,
                delta_ssr,
                f,
                p_value,
                delta_aicc,
                rmse_m,
                weighted_rmse_m: Some(weighted_rmse(o.ssr, &d.weights)).filter(|x| x.is_finite()),
                f_den_dof: (o.error.is_none()).then_some(o.f_test.df_den),
                parameters: o.estimates.iter().map(|e| e.name.clone()).collect(),
                values: if values.iter().all(|v| v.is_finite()) {
                    values
                } else {
                    Vec::new()
                },
                error: o.error.clone().unwrap_or_default(),
                absent,
            });
        }
        round.push(RoundOut {
            current: r.current.clone(),
            threshold: r.threshold,
            accepted: r.accepted.clone().unwrap_or_default(),
            verdict: r.verdict.clone(),
            candidate,
        });
    }
    let file = DiscoverFile {
        effects: d.effects.clone(),
        ssr_before: d.baseline.ssr,
        ssr_after: d.final_fit.ssr,
        rmse_before_m: d.baseline.rmse,
        rmse_after_m: d.final_fit.rmse,
        weighted_rmse_before_m: weighted_rmse(d.baseline.ssr, &d.weights),
        weighted_rmse_after_m: weighted_rmse(d.final_fit.ssr, &d.weights),
        numerical_error_rms_m: d.numerical.rms,
        measurement_sd_from_file: d.sd_given,
        alpha: d.options.alpha,
        observations: n,
        data: info.map(|i| i.toml.clone()),
        added,
        round,
        bubble_weight: bubbles.to_vec(),
        diagnostics: DiagnosticsOut {
            baseline: diagnosis_out(&d.diagnostics_before),
            final_model: diagnosis_out(&d.diagnostics_after),
        },
    };
    toml::to_string(&file)
        .map(|t| exponent_floats(&t))
        .map_err(|e| Error::Solver(format!("discover.toml: {e}")))
}

/// The F-test of an added effect: its outcome in the round that added it.
fn added_test<'a>(d: &'a Discovery, effect: &str) -> Option<&'a crate::fit::stats::FTest> {
    d.rounds
        .iter()
        .filter(|r| r.accepted.as_deref() == Some(effect))
        .flat_map(|r| r.outcomes.iter())
        .find(|o| o.name == effect)
        .map(|o| &o.f_test)
}

/// "F(ν₁, ν₂) = F" with the test's degrees of freedom.
fn f_text(t: &crate::fit::stats::FTest) -> String {
    format!("F({}, {}) = {}", t.df_num, t.df_den, sig(t.f, 4))
}

/// A diagnostic number for a table, or "not defined" when it is not a finite number (the
/// standard error of a group of one residual, the runs test of a bubble with fewer than two
/// residuals of either sign).
fn diag(v: f64, digits: usize) -> Cell {
    if v.is_finite() {
        Cell::text(sig(v, digits))
    } else {
        Cell::text("not defined")
    }
}

/// A diagnostic p-value for a table: [`p_cell`], or "not defined" when it is not a number.
fn diag_p(p: f64) -> Cell {
    if p.is_finite() {
        Cell::text(p_cell(p))
    } else {
        Cell::text("not defined")
    }
}

/// The Holm family of a diagnosis in words: how many tests, of which kinds, by name
/// ("9 tests: 3 phases (compression, hold, decompression), …").
pub fn family_text(d: &Diagnostics) -> String {
    let plural = |n: usize, one: &str, many: &str| {
        if n == 1 {
            format!("1 {one}")
        } else {
            format!("{n} {many}")
        }
    };
    format!(
        "{}: {} ({}), {} ({}), {} (one per bubble; the sign test in its place for a bubble whose residuals all have one sign)",
        plural(d.family, "test", "tests"),
        plural(d.phases.len(), "phase", "phases"),
        d.phases.iter().map(|g| g.label.as_str()).collect::<Vec<_>>().join(", "),
        plural(d.trends.len(), "covariate", "covariates"),
        d.trends.iter().map(|t| t.covariate).collect::<Vec<_>>().join(", "),
        plural(d.runs.len(), "runs test", "runs tests"),
    )
}

/// The method cell of a bubble's runs test.
fn runs_method_text(t: &crate::fit::stats::RunsTest) -> String {
    use crate::fit::stats::RunsMethod;
    match t.method {
        RunsMethod::SignTest => {
            let n = t.n_plus + t.n_minus;
            format!(
                "all {n} residuals of one sign; sign test p = 2·0.5^{n} {} (two-sided), in place of the degenerate runs test",
                p_text(t.p_value)
            )
        }
        RunsMethod::NoData => "no nonzero residual: no test".into(),
        RunsMethod::Exact => "runs test, exact".into(),
        RunsMethod::Normal => "runs test, normal approximation".into(),
    }
}

fn diagnostics_section(page: &mut Page, title: &str, d: &Diagnostics) -> Result<(), Error> {
    page.heading(3, title);
    let family = family_text(d);
    if d.signatures.is_empty() {
        page.text(format!("No systematic signature at a Holm-adjusted p < 0.01 over the {} tests below (phases, covariates, each bubble's runs test): the residuals look like noise by every grouping. The Holm family has {family}; the rows in it are marked \"yes\" in the column \"in Holm family\", with their Holm-adjusted p beside the unadjusted one.", d.family));
    } else {
        page.text(
            d.signatures
                .iter()
                .map(|s| format!("- {s}"))
                .collect::<Vec<_>>()
                .join("\n"),
        );
        page.text(format!("The Holm family has {family}; the rows in it are marked \"yes\" in the column \"in Holm family\" below, with their Holm-adjusted p beside the unadjusted one. A signature is worded where the Holm-adjusted p < 0.01."));
    }
    let holm_cells = |q: Option<f64>| match q {
        Some(q) => [Cell::text("yes"), diag_p(q)],
        None => [Cell::text("no (descriptive)"), Cell::text("—")],
    };
    let mut t = Table::new(
        format!("{title}: mean residual (measured − simulated) by phase"),
        vec![
            Column::plain("phase"),
            Column::plain("n"),
            Column::new("mean", "µm"),
            Column::new("std. error", "µm"),
            Column::plain("t-test p"),
            Column::plain("in Holm family"),
            Column::plain("Holm-adjusted p"),
        ],
    );
    for g in d.phases.iter().chain(&d.cycles) {
        let mut row = vec![
            Cell::text(&g.label),
            Cell::text(g.n.to_string()),
            diag(g.mean * 1e6, 3),
            diag(g.se * 1e6, 3),
            diag_p(g.p_value),
        ];
        row.extend(holm_cells(g.holm_p));
        t.push(row).map_err(Error::Solver)?;
    }
    page.table(&t);
    if !d.cycles.is_empty() {
        page.text(format!(
            "The per-cycle {} (\"…, cycle k\") {} descriptive: outside the Holm family of {} tests, {} unadjusted and not used for the decision (they only word a phase's signature, e.g. \"on every decompression\").",
            if d.cycles.len() == 1 { "row" } else { "rows" },
            if d.cycles.len() == 1 { "is" } else { "are" },
            d.family,
            if d.cycles.len() == 1 { "its p-value" } else { "their p-values" },
        ));
    }
    let mut t = Table::new(
        format!("{title}: residual against covariates"),
        vec![
            Column::plain("covariate"),
            Column::plain("n"),
            Column::plain("Pearson r"),
            Column::plain("p"),
            Column::plain("in Holm family"),
            Column::plain("Holm-adjusted p"),
        ],
    );
    for tr in &d.trends {
        let mut row = vec![
            Cell::text(tr.covariate),
            Cell::text(tr.n.to_string()),
            if tr.r.is_finite() {
                Cell::fixed(tr.r, 3)
            } else {
                Cell::text("not defined")
            },
            diag_p(tr.p_value),
        ];
        row.extend(holm_cells(Some(tr.holm_p)));
        t.push(row).map_err(Error::Solver)?;
    }
    page.table(&t);
    if !d.dropped.is_empty() {
        page.text(format!(
            "Dropped (not tested, not in the Holm family): {}.",
            d.dropped
                .iter()
                .map(|c| format!("{}: {}", c.covariate, c.reason))
                .collect::<Vec<_>>()
                .join("; ")
        ));
    }
    let mut t = Table::new(
        format!("{title}: runs test of each bubble's residual signs"),
        vec![
            Column::plain("experiment"),
            Column::plain("bubble"),
            Column::plain("n₊, n₋"),
            Column::plain("runs"),
            Column::plain("expected"),
            Column::plain("test"),
            Column::plain("p"),
            Column::plain("in Holm family"),
            Column::plain("Holm-adjusted p"),
        ],
    );
    for r in &d.runs {
        let degenerate = matches!(
            r.test.method,
            crate::fit::stats::RunsMethod::SignTest | crate::fit::stats::RunsMethod::NoData
        );
        let mut row = vec![
            Cell::text(&r.experiment),
            Cell::text(r.bubble.to_string()),
            Cell::text(format!("{}, {}", r.test.n_plus, r.test.n_minus)),
            Cell::text(r.test.runs.to_string()),
            if r.test.expected.is_finite() && !degenerate {
                Cell::fixed(r.test.expected, 1)
            } else {
                Cell::text("—")
            },
            Cell::text(runs_method_text(&r.test)),
            diag_p(r.test.p_value),
        ];
        row.extend(holm_cells(Some(r.holm_p)));
        t.push(row).map_err(Error::Solver)?;
    }
    page.table(&t);
    page.text(format!(
        "The runs test is two-sided, p = 2·min(P(R ≤ r), P(R ≥ r)) capped at 1, from the exact distribution of the number of runs R given n₊ and n₋ (Wald & Wolfowitz 1940, summed in log space) while the rarer sign has at most {} residuals, else from the normal approximation with a continuity correction of ½ run (mean 1 + 2n₊n₋/n, variance 2n₊n₋(2n₊n₋ − n)/(n²(n − 1))). When every residual of a bubble has one sign there is one run and nothing to compare: the two-sided sign test, p = 2·0.5ⁿ (capped at 1), takes the runs test's place, in the table and in the Holm family. A signature is worded only for fewer runs than expected (long stretches of one sign).",
        crate::fit::stats::EXACT_RUNS_MAX_MINORITY
    ));
    Ok(())
}

/// Build the whole `discover` output.
pub fn discover_outputs(
    d: &Discovery,
    baseline_runs: &[SimRun],
    final_runs: &[SimRun],
    experiments: &Experiments,
    data: &Measurements,
    command: &str,
) -> Result<OutputSet, Error> {
    let mut set = OutputSet::new();
    let info = data_info(data, experiments, &d.final_fit.model);
    let bubbles = bubble_weights(d, data);
    let own_terms = own_terms_of(experiments);
    set.add(
        "discover.toml",
        discover_toml_with(d, Some(&info), &bubbles)?,
    );
    let mut page = Page::new("Discovering the effect the model is missing");
    page.pre(command.to_string());
    page.text(info.paragraph.clone());
    page.section("Result");
    if d.effects.is_empty() {
        page.text("**No missing effect found among the candidates tried.**");
    } else {
        page.text(format!(
            "**Effects added, in order: {}.**",
            d.effects.join(", ")
        ));
    }
    let mut t = Table::new(
        "The gap between model and measurements",
        vec![
            Column::plain("quantity"),
            Column::plain("baseline"),
            Column::plain("final model"),
        ],
    );
    for (k, a, b) in [
        (
            "RMSE, unweighted (µm)",
            sig(d.baseline.rmse * 1e6, 4),
            sig(d.final_fit.rmse * 1e6, 4),
        ),
        (
            "RMSE, weighted (µm)",
            sig(weighted_rmse(d.baseline.ssr, &d.weights) * 1e6, 4),
            sig(weighted_rmse(d.final_fit.ssr, &d.weights) * 1e6, 4),
        ),
        (
            "SSR (weighted)",
            sig(d.baseline.ssr, 4),
            sig(d.final_fit.ssr, 4),
        ),
        (
            "AICc",
            aicc_absent(
                d.baseline.aicc,
                d.baseline.ssr,
                d.baseline.n,
                d.baseline.p(),
            )
            .unwrap_or_else(|| sig(d.baseline.aicc, 4)),
            aicc_absent(
                d.final_fit.aicc,
                d.final_fit.ssr,
                d.final_fit.n,
                d.final_fit.p(),
            )
            .unwrap_or_else(|| sig(d.final_fit.aicc, 4)),
        ),
        (
            "free parameters",
            d.baseline.p().to_string(),
            d.final_fit.p().to_string(),
        ),
    ] {
        t.push(vec![Cell::text(k), Cell::text(a), Cell::text(b)])
            .map_err(Error::Solver)?;
    }
    page.table(&t);
    let sd_text = if d.sd_given {
        "the measurement sd of every row (sd_m)".to_string()
    } else {
        format!(
            "a measurement sd of {} µm estimated from the baseline fit (no sd_m column)",
            sig(
                d.measurement_sd.first().copied().unwrap_or(f64::NAN) * 1e6,
                3
            )
        )
    };
    page.text(format!(
        "How an effect is accepted: each round every candidate is refitted on top of the current model; the extra sum-of-squares F-test (nested least-squares models, independent Gaussian errors) compares it with the current model. The best is added only if p < α/m (Bonferroni over the m candidates tried in that round, α = {}) and it lowers the unweighted RMSE by more than the simulation's numerical error, {} µm (the Richardson estimate of a first-order scheme: twice the RMS change of the simulated radii when the grid step and every step limit are halved). Every test weights an observation by 1/(sd² + e²), with sd {} and e its bubble's numerical error, so grid error is never read as physics. The 95 % intervals are sandwich (HC1) intervals: covariance (JᵀJ)⁻¹(Σ rᵢ²JᵢᵀJᵢ)(JᵀJ)⁻¹·n/(n − p) on the weighted residuals rᵢ and Jacobian rows Jᵢ (MacKinnon & White 1985), Student t with n − p degrees of freedom, and the delta method for parameters fitted in log space (exponentiated, so asymmetric): the weights carry a numerical error the data may not contain. ΔAICc is the candidate's AICc (K = p + 1) less the current model's, from each fit's own SSR.",
        d.options.alpha,
        sig(d.numerical.rms * 1e6, 3),
        sd_text
    ));
    let mut t = Table::new(
        "Weights of the tests, by bubble",
        vec![
            Column::plain("experiment"),
            Column::plain("bubble"),
            Column::plain("n"),
            Column::new("sd", "µm"),
            Column::new("numerical error e", "µm"),
            Column::new("weight 1/(sd² + e²)", "µm⁻²"),
            Column::new("share of the total weight", "%"),
        ],
    );
    for b in &bubbles {
        t.push(vec![
            Cell::text(&b.experiment),
            Cell::text(b.bubble.to_string()),
            Cell::text(b.observations.to_string()),
            Cell::text(range_text(b.sd_m, 1e6, 3)),
            Cell::text(sig(b.numerical_error_m * 1e6, 3)),
            Cell::text(range_text(b.weight_per_m2, 1e-12, 3)),
            Cell::text(sig(b.weight_share * 100.0, 3)),
        ])
        .map_err(Error::Solver)?;
    }
    page.table(&t);
    page.text("Two RMSEs are given. The unweighted RMSE, √(Σ rᵢ²/n), counts every row alike; it is the one the numerical-error rule compares. The weighted RMSE, √(Σ wᵢrᵢ²/Σ wᵢ) with the weights above, is the RMS residual the F-tests, ΔSSR and ΔAICc see (Σ wᵢrᵢ² is the weighted SSR). They can disagree: a bubble with a large numerical error e weighs little, so a candidate that fits the heavily weighted bubbles better and a lightly weighted one much worse lowers the weighted SSR (a large F) while raising the unweighted RMSE.");
    for a in &d.added {
        page.heading(3, format!("Added: {}", a.effect));
        let fin = |v: f64, why: &str| -> Stat {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(why.to_string())
            }
        };
        let test = added_test(d, &a.effect);
        page.text(format!(
            "{}, p {}, ΔSSR = {}, ΔAICc = {}. Parameters in the final model:",
            match (test, fin(a.f, "not a finite number")) {
                (Some(t), Ok(_)) => f_text(t),
                (_, f) => format!("F = {}", stat_text(&f, |x| sig(x, 4))),
            },
            match fin(a.p_value, "not a finite number") {
                Ok(p) => p_text(p),
                Err(m) => format!("not given ({m})"),
            },
            stat_text(&fin(a.delta_ssr, "not a finite number"), |x| sig(x, 4)),
            stat_text(
                &fin(
                    a.delta_aicc,
                    "AICc (K = p + 1) needs n > p + 2 in both models"
                ),
                |x| sig(x, 4)
            ),
        ));
        let (named, truth) = readable_estimates(&a.parameters, &info.truth, own_terms);
        page.table(&estimates_table_with_truth(
            &format!("{} parameters", a.effect),
            &named,
            d.final_fit.inference.singular,
            &truth,
        )?);
    }
    if !d.final_fit.inference.estimates.is_empty() {
        let (named, truth) =
            readable_estimates(&d.final_fit.inference.estimates, &info.truth, own_terms);
        page.table(&estimates_table_with_truth(
            "Every free parameter of the final model",
            &named,
            d.final_fit.inference.singular,
            &truth,
        )?);
    }
    page.section("Candidates, round by round");
    for (i, r) in d.rounds.iter().enumerate() {
        page.heading(
            3,
            format!(
                "Round {} (model: {})",
                i + 1,
                if r.current.is_empty() {
                    "baseline".to_string()
                } else {
                    format!("baseline + {}", r.current.join(" + "))
                }
            ),
        );
        let mut t = Table::new(
            format!(
                "Round {}: candidates (Bonferroni threshold α/m = {})",
                i + 1,
                sig(r.threshold, 3)
            ),
            vec![
                Column::plain("candidate"),
                Column::plain("df (ν₁, ν₂)"),
                Column::plain("ΔSSR"),
                Column::plain("F"),
                Column::plain("p"),
                Column::plain("ΔAICc"),
                Column::new("RMSE, unweighted", "µm"),
                Column::new("RMSE, weighted", "µm"),
                Column::plain("fitted parameters"),
            ],
        );
        let mut order: Vec<&CandidateOutcome> = r.outcomes.iter().collect();
        order.sort_by(|a, b| a.f_test.p_value.total_cmp(&b.f_test.p_value));
        for o in order {
            let params = match &o.error {
                Some(e) => format!("not fitted: {e}"),
                None => o
                    .estimates
                    .iter()
                    .enumerate()
                    .map(|(i, e)| candidate_param_text(e, o.params.get(i), own_terms))
                    .collect::<Vec<_>>()
                    .join("; "),
            };
            let worse = o.error.is_none() && o.delta_ssr < 0.0;
            let st = cand_stats(o, d.baseline.n);
            let short = |v: &Stat, fmt: &dyn Fn(f64) -> String| match v {
                Ok(x) => fmt(*x),
                Err(m) if o.error.is_some() => format!("— ({m})"),
                Err(m) => format!("not given ({m})"),
            };
            let wrmse: Stat = if o.error.is_some() {
                Err("not fitted".into())
            } else {
                Some(weighted_rmse(o.ssr, &d.weights))
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| "not a finite number".to_string())
            };
            t.push(vec![
                Cell::text(&o.name),
                Cell::text(if o.error.is_some() {
                    o.dof.to_string()
                } else {
                    format!("{}, {}", o.f_test.df_num, o.f_test.df_den)
                }),
                Cell::text(short(&st.delta_ssr, &|x| sig(x, 4))),
                Cell::text(if worse {
                    FITS_WORSE.to_string()
                } else {
                    short(&st.f, &|x| sig(x, 4))
                }),
                Cell::text(if worse {
                    "—".to_string()
                } else {
                    short(&st.p_value, &p_cell)
                }),
                Cell::text(short(&st.delta_aicc, &|x| sig(x, 4))),
                Cell::text(short(&st.rmse, &|x| sig(x * 1e6, 4))),
                Cell::text(short(&wrmse, &|x| sig(x * 1e6, 4))),
                Cell::text(params),
            ])
            .map_err(Error::Solver)?;
        }
        page.table(&t);
        page.text(format!(
            "{} — {}.",
            r.verdict,
            match &r.accepted {
                Some(a) => format!("**{a} added**"),
                None => "nothing added".into(),
            }
        ));
    }
    page.section("Residual diagnostics");
    diagnostics_section(&mut page, "Baseline", &d.diagnostics_before)?;
    diagnostics_section(&mut page, "Final model", &d.diagnostics_after)?;
    page.section("Measured and simulated radii, before and after");
    add_overlays(
        &mut set,
        &mut page,
        experiments,
        data,
        &[("final model", final_runs), ("baseline", baseline_runs)],
        "",
    )?;
    set.add("report.md", page.to_markdown().map_err(Error::Solver)?);
    set.add("report.html", page.to_html().map_err(Error::Solver)?);
    Ok(set)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::discover::EffectParam;
    use crate::fit::lsq::Estimate;
    use crate::fit::paths::ParamSpec;

    fn est(name: &str, value: f64, log: bool, at_bound: bool) -> Estimate {
        Estimate {
            name: name.into(),
            value,
            std_error: 1.0,
            ci95: [0.0, 1.0],
            log,
            at_bound,
            clipped: false,
        }
    }

    /// p-values below 1e-16 are a bound, above it 3 significant digits: the committed example's
    /// 2.309e-161 and 1.30e-17 print "< 1e-16", its 0.434 and 2.27e-32's neighbour 6.55e-4 print
    /// their digits (reference: the numbers of reports/discover/report.md before this change).
    #[test]
    fn p_values_below_1e_16_print_as_a_bound() {
        assert_eq!(p_text(2.308896500918035e-161), "< 1e-16");
        assert_eq!(p_cell(1.2989377126215483e-17), "< 1e-16");
        assert_eq!(p_text(0.4336), "= 0.434");
        assert_eq!(p_cell(6.55e-4), "6.55e-4");
        assert_eq!(p_cell(1e-16), "1.00e-16");
    }

    /// A candidate's estimate that ran to its null 0 (the committed round 2: a bulk modulus of
    /// 2.24e-239 against a scan from 1e12) prints "→ 0 (at its null)"; a small real value above
    /// a millionth of the scan (perfusion 2.47e-7 against a scan from 1e-5) prints its digits;
    /// one at a bound of its range says so.
    #[test]
    fn estimates_at_their_null_or_a_bound_are_named_not_printed_as_digits() {
        let param = |lo: f64| EffectParam {
            spec: ParamSpec::positive("x", 1.0),
            null: 0.0,
            scan: vec![lo, lo * 10.0],
        };
        let bulk = "material.elasticity.terms.1.bulk_modulus_per_volume";
        let k = est(bulk, 2.238606641606635e-239, true, false);
        assert_eq!(
            candidate_param_text(&k, Some(&param(1e12)), Some(1)),
            "M of the added elasticity term → 0 (at its null)"
        );
        let k = est("perfusion.rate_per_s", 2.47e-7, true, false);
        assert_eq!(
            candidate_param_text(&k, Some(&param(1e-5)), Some(1)),
            "perfusion rate = 2.47e-7 1/s"
        );
        let k = est("material.bubble_fixed_gases_pa", 2788.0, true, true);
        assert_eq!(
            candidate_param_text(&k, Some(&param(1e2)), Some(1)),
            "p_fixed = 2788 Pa (at the bound)"
        );
        // without the candidate's parameters nothing is claimed about the null
        let k = est(bulk, 2.24e-239, true, false);
        assert_eq!(
            candidate_param_text(&k, None, Some(1)),
            "M of the added elasticity term = 2.24e-239 Pa/m³"
        );
        // the committed example's round-1 hyperelastic term (reports/discover/report.md)
        let k = est(
            "material.elasticity.terms.1.shear_modulus",
            21923.0,
            true,
            false,
        );
        assert_eq!(
            candidate_param_text(&k, Some(&param(10.0)), Some(1)),
            "μ of the added elasticity term = 21923 Pa"
        );
        // a path the naming does not know stays itself
        let k = est("bulk", 2.24e-239, true, false);
        assert_eq!(candidate_param_text(&k, None, None), "bulk = 2.24e-239");
    }

    /// The diagnostics tables say which rows are in the Holm family and how many tests it
    /// has, mark the per-cycle rows descriptive, name a dropped covariate with its reason, and
    /// give a bubble whose residuals all have one sign the sign test (p = 2·0.5⁶¹, by hand) in
    /// the runs test's place; the Holm-adjusted p of a row is the one [`holm`] gives over the
    /// family (Holm 1979; `holm` is checked by hand in fit::stats).
    #[test]
    fn diagnostics_tables_state_the_holm_family() {
        use crate::discover::diagnose::{BubbleRuns, DroppedCovariate, GroupMean, Trend};
        use crate::fit::stats::{holm, runs_test, RunsMethod};
        let g = |label: &str, p: f64| GroupMean {
            label: label.into(),
            n: 12,
            mean: 1e-6,
            se: 1e-6,
            p_value: p,
            holm_p: None,
        };
        let one_sign = runs_test(&[1.0; 61]);
        assert_eq!(one_sign.method, RunsMethod::SignTest);
        let mixed = runs_test(&[1.0, -1.0, 1.0, 1.0, -1.0, -1.0, 1.0, -1.0]);
        let ps = [0.2, 0.3, 0.04, 0.5, one_sign.p_value, mixed.p_value];
        let q = holm(&ps);
        let mut phases = vec![
            g("compression", ps[0]),
            g("hold", ps[1]),
            g("decompression", ps[2]),
        ];
        for (x, q) in phases.iter_mut().zip(&q) {
            x.holm_p = Some(*q);
        }
        let d = Diagnostics {
            phases,
            cycles: vec![g("compression, cycle 1", 0.003)],
            trends: vec![Trend {
                covariate: "time",
                n: 36,
                r: 0.1,
                p_value: ps[3],
                holm_p: q[3],
            }],
            dropped: vec![DroppedCovariate {
                covariate: "dP/dt",
                reason: "constant over the data".into(),
            }],
            runs: vec![
                BubbleRuns {
                    experiment: "osc".into(),
                    bubble: 0,
                    test: one_sign,
                    holm_p: q[4],
                },
                BubbleRuns {
                    experiment: "osc".into(),
                    bubble: 1,
                    test: mixed,
                    holm_p: q[5],
                },
            ],
            signatures: vec![],
            family: 6,
        };
        let mut page = Page::new("t");
        diagnostics_section(&mut page, "Final model", &d).unwrap();
        let md = page.to_markdown().unwrap();
        assert!(md.contains("over the 6 tests below"), "{md}");
        assert!(
            md.contains("6 tests: 3 phases (compression, hold, decompression), 1 covariate (time), 2 runs tests"),
            "{md}"
        );
        assert!(md.contains("| in Holm family | Holm-adjusted p |"), "{md}");
        assert!(
            md.contains(
                "| compression, cycle 1 | 12 | 1.00 | 1.00 | 0.00300 | no (descriptive) | — |"
            ),
            "{md}"
        );
        assert!(
            md.contains(&format!(
                "| decompression | 12 | 1.00 | 1.00 | 0.0400 | yes | {} |",
                p_cell(q[2])
            )),
            "{md}"
        );
        assert!(md.contains("outside the Holm family of 6 tests"), "{md}");
        assert!(md.contains("dP/dt: constant over the data"), "{md}");
        // the sign test: 2·0.5⁶¹ = 8.67e-19, below the printed floor
        assert!(
            md.contains("| osc | 0 | 61, 0 | 1 | — | all 61 residuals of one sign; sign test p = 2·0.5^61 \\< 1e-16 (two-sided), in place of the degenerate runs test | \\< 1e-16 | yes | \\< 1e-16 |"),
            "{md}"
        );
        assert!(md.contains("| runs test, exact |"), "{md}");
        assert!(!md.contains("not defined"), "{md}");
    }

    /// The weighted RMSE √(Σ wr²/Σ w), by hand: residuals 2 and 1 with weights 1 and 3 give
    /// SSR 4 + 3 = 7 and √(7/4) = 1.3229; equal weights give the unweighted RMSE √(5/2).
    #[test]
    fn weighted_rmse_by_hand() {
        assert!((weighted_rmse(7.0, &[1.0, 3.0]) - 1.3228756555322954).abs() < 1e-15);
        assert!((weighted_rmse(2.0 * 5.0, &[2.0, 2.0]) - (5.0f64 / 2.0).sqrt()).abs() < 1e-15);
    }
}
