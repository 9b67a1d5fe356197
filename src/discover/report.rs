//! The `discover` report: `discover.toml`, `report.md`, `report.html` and the overlays of every
//! measured bubble against the baseline and the final model.

use super::diagnose::Diagnostics;
use super::search::Discovery;
use crate::error::Error;
use crate::fit::data::{Experiments, Measurements};
use crate::fit::report::{add_overlays, estimates_table, sig};
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::table::{Cell, Column, Table};
use crate::run::SimRun;
use serde::Serialize;

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
    value: f64,
    ci95: [f64; 2],
    p_value: f64,
    f: f64,
    delta_ssr: f64,
    delta_aicc: f64,
    parameters: Vec<String>,
    values: Vec<f64>,
    ci95_all: Vec<[f64; 2]>,
    alternatives: Vec<String>,
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
    delta_ssr: f64,
    f: f64,
    p_value: f64,
    delta_aicc: f64,
    rmse_m: f64,
    parameters: Vec<String>,
    values: Vec<f64>,
    error: String,
}

/// `discover.toml` text.
pub fn discover_toml(d: &Discovery) -> Result<String, Error> {
    let file = DiscoverFile {
        effects: d.effects.clone(),
        ssr_before: d.baseline.ssr,
        ssr_after: d.final_fit.ssr,
        rmse_before_m: d.baseline.rmse,
        rmse_after_m: d.final_fit.rmse,
        numerical_error_rms_m: d.numerical.rms,
        measurement_sd_from_file: d.sd_given,
        alpha: d.options.alpha,
        observations: d.baseline.n,
        added: d
            .added
            .iter()
            .map(|a| {
                let first = a.parameters.first();
                AddedOut {
                    effect: a.effect.clone(),
                    parameter: first.map_or(String::new(), |e| e.name.clone()),
                    value: first.map_or(f64::NAN, |e| e.value),
                    ci95: first.map_or([f64::NAN; 2], |e| e.ci95),
                    p_value: a.p_value,
                    f: a.f,
                    delta_ssr: a.delta_ssr,
                    delta_aicc: a.delta_aicc,
                    parameters: a.parameters.iter().map(|e| e.name.clone()).collect(),
                    values: a.parameters.iter().map(|e| e.value).collect(),
                    ci95_all: a.parameters.iter().map(|e| e.ci95).collect(),
                    alternatives: a.alternatives.iter().map(|x| x.0.clone()).collect(),
                }
            })
            .collect(),
        round: d
            .rounds
            .iter()
            .map(|r| RoundOut {
                current: r.current.clone(),
                threshold: r.threshold,
                accepted: r.accepted.clone().unwrap_or_default(),
                verdict: r.verdict.clone(),
                candidate: r
                    .outcomes
                    .iter()
                    .map(|o| CandOut {
                        name: o.name.clone(),
                        dof: o.dof,
                        delta_ssr: o.delta_ssr,
                        f: o.f_test.f,
                        p_value: o.f_test.p_value,
                        delta_aicc: o.delta_aicc,
                        rmse_m: o.rmse,
                        parameters: o.estimates.iter().map(|e| e.name.clone()).collect(),
                        values: o.estimates.iter().map(|e| e.value).collect(),
                        error: o.error.clone().unwrap_or_default(),
                    })
                    .collect(),
            })
            .collect(),
    };
    toml::to_string(&file).map_err(|e| Error::Solver(format!("discover.toml: {e}")))
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
            Cell::text(sig(g.mean * 1e6, 3)),
            Cell::text(sig(g.se * 1e6, 3)),
            Cell::text(sig(g.p_value, 3)),
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
            Cell::fixed(tr.r, 3),
            Cell::text(sig(tr.p_value, 3)),
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
            Cell::fixed(r.test.expected, 1),
            Cell::text(sig(r.test.p_value, 3)),
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
        ("AICc", sig(d.baseline.aicc, 6), sig(d.final_fit.aicc, 6)),
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
        page.text(format!(
            "F = {}, p = {}, ΔSSR = {}, ΔAICc = {}. Parameters in the final model:",
            sig(a.f, 4),
            sig(a.p_value, 3),
            sig(a.delta_ssr, 4),
            sig(a.delta_aicc, 4)
        ));
        page.table(&estimates_table(
            &format!("{} parameters", a.effect),
            &a.parameters,
        )?);
    }
    if !d.final_fit.inference.estimates.is_empty() {
        page.table(&estimates_table(
            "Every free parameter of the final model",
            &d.final_fit.inference.estimates,
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
        let mut order: Vec<&super::search::CandidateOutcome> = r.outcomes.iter().collect();
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
            t.push(vec![
                Cell::text(&o.name),
                Cell::text(o.dof.to_string()),
                Cell::text(sig(o.delta_ssr, 4)),
                Cell::text(sig(o.f_test.f, 4)),
                Cell::text(sig(o.f_test.p_value, 3)),
                Cell::text(sig(o.delta_aicc, 4)),
                Cell::text(sig(o.rmse * 1e6, 4)),
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
