//! The `discover` report: `discover.toml`, `report.md`, `report.html` and the overlays of every
//! measured bubble against the baseline and the final model.

use super::diagnose::Diagnostics;
use super::search::{CandidateOutcome, Discovery};
use crate::error::Error;
use crate::fit::data::{Experiments, Measurements};
use crate::fit::report::{
    add_overlays, aicc_absent, estimate_stats, estimates_table, finite_estimate, finite_result, sig,
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
    numerical_error_rms_m: f64,
    measurement_sd_from_file: bool,
    alpha: f64,
    observations: usize,
    added: Vec<AddedOut>,
    round: Vec<RoundOut>,
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

/// `discover.toml` text.
pub fn discover_toml(d: &Discovery) -> Result<String, Error> {
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
            absent,
        });
    }
    let mut round = Vec::new();
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
        numerical_error_rms_m: d.numerical.rms,
        measurement_sd_from_file: d.sd_given,
        alpha: d.options.alpha,
        observations: n,
        added,
        round,
    };
    toml::to_string(&file).map_err(|e| Error::Solver(format!("discover.toml: {e}")))
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

fn diagnostics_section(page: &mut Page, title: &str, d: &Diagnostics) -> Result<(), Error> {
    page.heading(3, title);
    if d.signatures.is_empty() {
        page.text(format!("No systematic signature at a Holm-adjusted p < 0.01 over the {} tests below (phases, covariates, each bubble's runs test): the residuals look like noise by every grouping. The tables give the unadjusted p-values.", d.family));
    } else {
        page.text(
            d.signatures
                .iter()
                .map(|s| format!("- {s}"))
                .collect::<Vec<_>>()
                .join("\n"),
        );
    }
    let mut t = Table::new(
        format!("{title}: mean residual (measured − simulated) by phase"),
        vec![
            Column::plain("phase"),
            Column::plain("n"),
            Column::new("mean", "µm"),
            Column::new("std. error", "µm"),
            Column::plain("t-test p"),
        ],
    );
    for g in d.phases.iter().chain(&d.cycles) {
        t.push(vec![
            Cell::text(&g.label),
            Cell::text(g.n.to_string()),
            diag(g.mean * 1e6, 3),
            diag(g.se * 1e6, 3),
            diag(g.p_value, 3),
        ])
        .map_err(Error::Solver)?;
    }
    page.table(&t);
    let mut t = Table::new(
        format!("{title}: residual against covariates"),
        vec![
            Column::plain("covariate"),
            Column::plain("Pearson r"),
            Column::plain("p"),
        ],
    );
    for tr in &d.trends {
        t.push(vec![
            Cell::text(tr.covariate),
            if tr.r.is_finite() {
                Cell::fixed(tr.r, 3)
            } else {
                Cell::text("not defined")
            },
            diag(tr.p_value, 3),
        ])
        .map_err(Error::Solver)?;
    }
    page.table(&t);
    let mut t = Table::new(
        format!("{title}: runs test of each bubble's residual signs"),
        vec![
            Column::plain("experiment"),
            Column::plain("bubble"),
            Column::plain("runs"),
            Column::plain("expected"),
            Column::plain("p"),
        ],
    );
    for r in &d.runs {
        t.push(vec![
            Cell::text(&r.experiment),
            Cell::text(r.bubble.to_string()),
            Cell::text(r.test.runs.to_string()),
            if r.test.expected.is_finite() {
                Cell::fixed(r.test.expected, 1)
            } else {
                Cell::text("not defined")
            },
            diag(r.test.p_value, 3),
        ])
        .map_err(Error::Solver)?;
    }
    page.table(&t);
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
    set.add("discover.toml", discover_toml(d)?);
    let mut page = Page::new("Discovering the effect the model is missing");
    page.pre(command.to_string());
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
            "RMSE (µm)",
            sig(d.baseline.rmse * 1e6, 4),
            sig(d.final_fit.rmse * 1e6, 4),
        ),
        (
            "SSR (weighted)",
            sig(d.baseline.ssr, 5),
            sig(d.final_fit.ssr, 5),
        ),
        (
            "AICc",
            aicc_absent(
                d.baseline.aicc,
                d.baseline.ssr,
                d.baseline.n,
                d.baseline.p(),
            )
            .unwrap_or_else(|| sig(d.baseline.aicc, 6)),
            aicc_absent(
                d.final_fit.aicc,
                d.final_fit.ssr,
                d.final_fit.n,
                d.final_fit.p(),
            )
            .unwrap_or_else(|| sig(d.final_fit.aicc, 6)),
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
        "How an effect is accepted: each round every candidate is refitted on top of the current model; the extra sum-of-squares F-test (nested least-squares models, independent Gaussian errors) compares it with the current model. The best is added only if p < α/m (Bonferroni over the m candidates tried in that round, α = {}) and it lowers the RMSE by more than the simulation's numerical error, {} µm (the Richardson estimate of a first-order scheme: twice the RMS change of the simulated radii when the grid step and every step limit are halved). Every test weights an observation by 1/(sd² + e²), with sd {} and e its bubble's numerical error, so grid error is never read as physics. The 95 % intervals are sandwich (HC1) intervals: covariance (JᵀJ)⁻¹(Σ rᵢ²JᵢᵀJᵢ)(JᵀJ)⁻¹·n/(n − p) on the weighted residuals rᵢ and Jacobian rows Jᵢ (MacKinnon & White 1985), Student t with n − p degrees of freedom, and the delta method for parameters fitted in log space (exponentiated, so asymmetric): the weights carry a numerical error the data may not contain. ΔAICc is the candidate's AICc (K = p + 1) less the current model's, from each fit's own SSR.",
        d.options.alpha,
        sig(d.numerical.rms * 1e6, 3),
        sd_text
    ));
    for a in &d.added {
        page.heading(3, format!("Added: {}", a.effect));
        let fin = |v: f64, why: &str| -> Stat {
            if v.is_finite() {
                Ok(v)
            } else {
                Err(why.to_string())
            }
        };
        page.text(format!(
            "F = {}, p = {}, ΔSSR = {}, ΔAICc = {}. Parameters in the final model:",
            stat_text(&fin(a.f, "not a finite number"), |x| sig(x, 4)),
            stat_text(&fin(a.p_value, "not a finite number"), |x| sig(x, 3)),
            stat_text(&fin(a.delta_ssr, "not a finite number"), |x| sig(x, 4)),
            stat_text(
                &fin(
                    a.delta_aicc,
                    "AICc (K = p + 1) needs n > p + 2 in both models"
                ),
                |x| sig(x, 4)
            ),
        ));
        page.table(&estimates_table(
            &format!("{} parameters", a.effect),
            &a.parameters,
            d.final_fit.inference.singular,
        )?);
    }
    if !d.final_fit.inference.estimates.is_empty() {
        page.table(&estimates_table(
            "Every free parameter of the final model",
            &d.final_fit.inference.estimates,
            d.final_fit.inference.singular,
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
                Column::plain("df"),
                Column::plain("ΔSSR"),
                Column::plain("F"),
                Column::plain("p"),
                Column::plain("ΔAICc"),
                Column::new("RMSE", "µm"),
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
                    .map(|e| format!("{} = {}", e.name, sig(e.value, 3)))
                    .collect::<Vec<_>>()
                    .join("; "),
            };
            let st = cand_stats(o, d.baseline.n);
            let short = |v: &Stat, fmt: &dyn Fn(f64) -> String| match v {
                Ok(x) => fmt(*x),
                Err(m) if o.error.is_some() => format!("— ({m})"),
                Err(m) => format!("not given ({m})"),
            };
            t.push(vec![
                Cell::text(&o.name),
                Cell::text(o.dof.to_string()),
                Cell::text(short(&st.delta_ssr, &|x| sig(x, 4))),
                Cell::text(short(&st.f, &|x| sig(x, 4))),
                Cell::text(short(&st.p_value, &|x| sig(x, 3))),
                Cell::text(short(&st.delta_aicc, &|x| sig(x, 4))),
                Cell::text(short(&st.rmse, &|x| sig(x * 1e6, 4))),
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
