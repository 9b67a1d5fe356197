//! The `fit` report (`fit.toml`, `report.md`, `report.html`, one overlay SVG per bubble) and
//! the pieces `discover` shares with it: parameter tables and measured-vs-simulated overlays.

use super::data::{Experiments, Measurements};
use super::growth::{compare_to_curve, fit_growth, GrowthFit};
use super::lsq::Estimate;
use super::model::{radius_at, Fitted};
use crate::error::Error;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::overlay::Overlay;
use crate::report::table::{Cell, Column, Table};
use crate::run::SimRun;
use serde::Serialize;

/// A number with `sig` significant figures in plain or scientific notation as fits its size.
pub fn sig(v: f64, sig: usize) -> String {
    if !v.is_finite() {
        return format!("{v}");
    }
    if v == 0.0 {
        return "0".into();
    }
    let e = v.abs().log10().floor() as i32;
    if (-3..5).contains(&e) {
        let d = (sig as i32 - 1 - e).max(0) as usize;
        format!("{v:.d$}")
    } else {
        format!("{:.*e}", sig.saturating_sub(1), v)
    }
}

fn cell(v: f64) -> Cell {
    Cell::text(sig(v, 4))
}

/// Table of estimates with standard errors and 95 % intervals.
pub fn estimates_table(title: &str, est: &[Estimate]) -> Result<Table, Error> {
    let mut t = Table::new(
        title,
        vec![
            Column::plain("parameter"),
            Column::plain("estimate"),
            Column::plain("std. error"),
            Column::plain("95 % interval"),
            Column::plain("fitted in"),
            Column::plain("note"),
        ],
    );
    for e in est {
        t.push(vec![
            Cell::text(&e.name),
            cell(e.value),
            cell(e.std_error),
            Cell::text(format!("[{}, {}]", sig(e.ci95[0], 4), sig(e.ci95[1], 4))),
            Cell::text(if e.log { "log space" } else { "linear" }),
            Cell::text(if e.at_bound {
                "at a bound: interval not reliable"
            } else {
                ""
            }),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(t)
}

/// Dense simulated radius of one bubble from a run, µm against s.
pub fn simulated_line(run: &SimRun, bubble: usize) -> Vec<(f64, f64)> {
    let end = run.summary.end_time;
    let n = 600;
    (0..=n)
        .map(|i| {
            let t = end * i as f64 / n as f64;
            (
                t,
                radius_at(&run.frames, &run.summary.events, bubble, t) * 1e6,
            )
        })
        .collect()
}

/// One overlay per measured bubble: measured points (± sd) and one line per labelled set of
/// runs (each set: one run per experiment, in the experiments' order). Added to `set` as
/// `overlay-<experiment>-b<bubble>.svg` and as figures to `page`.
pub fn add_overlays(
    set: &mut OutputSet,
    page: &mut Page,
    experiments: &Experiments,
    data: &Measurements,
    lines: &[(&str, &[SimRun])],
    prefix: &str,
) -> Result<(), Error> {
    for s in &data.series {
        let k = experiments.index_of(&s.experiment);
        let o = Overlay {
            title: format!("{}: bubble {}", s.experiment, s.bubble),
            x_label: "time (s)".into(),
            y_label: "radius (µm)".into(),
            points_label: "measured (± sd)".into(),
            points: s
                .points
                .iter()
                .map(|p| (p.time, p.radius * 1e6, p.sd.unwrap_or(0.0) * 1e6))
                .collect(),
            lines: lines
                .iter()
                .map(|(label, runs)| (label.to_string(), simulated_line(&runs[k], s.bubble)))
                .collect(),
        };
        let svg = o
            .to_svg()
            .map_err(|e| Error::Solver(format!("plot: {e}")))?;
        let file = format!("{prefix}overlay-{}-b{}.svg", s.experiment, s.bubble);
        page.figure(
            &svg,
            Some(&file),
            format!(
                "Measured radius of bubble {} in {} against the simulation ({}).",
                s.bubble,
                s.experiment,
                lines.iter().map(|l| l.0).collect::<Vec<_>>().join("; ")
            ),
        )
        .map_err(Error::Solver)?;
        set.add(file, svg);
    }
    Ok(())
}

/// Growth metrics of one bubble, measured and simulated at the same times.
#[derive(Debug, Clone, Serialize)]
pub struct GrowthRow {
    /// Experiment.
    pub experiment: String,
    /// Bubble.
    pub bubble: usize,
    /// Measured plateau radius, m, and its 95 % interval.
    pub measured_plateau_m: Option<f64>,
    /// Interval.
    pub measured_plateau_ci95_m: Option<[f64; 2]>,
    /// Measured half-life, s.
    pub measured_half_life_s: Option<f64>,
    /// Interval.
    pub measured_half_life_ci95_s: Option<[f64; 2]>,
    /// Simulated plateau radius, m.
    pub simulated_plateau_m: Option<f64>,
    /// Simulated half-life, s.
    pub simulated_half_life_s: Option<f64>,
    /// Extra sum-of-squares F-test: one curve for both against one each; p-value.
    pub same_curve_p_value: Option<f64>,
    /// Why a metric is missing.
    pub note: String,
}

/// The paper's growth metrics for every measured bubble and its simulation at `predicted`, fitted
/// (as the paper did, §4.2) to the growth after the profile's last pressure change: the points
/// from the time the profile reaches its final pressure on.
pub fn growth_rows(
    experiments: &Experiments,
    data: &Measurements,
    predicted: &[f64],
) -> Vec<GrowthRow> {
    let mut k = 0;
    let mut rows = Vec::new();
    for s in &data.series {
        let n = s.points.len();
        let start = experiments
            .get(&s.experiment)
            .map_or(0.0, |e| e.profile.final_arrival_s());
        let keep: Vec<usize> = (0..n).filter(|i| s.points[*i].time >= start).collect();
        let m: Vec<(f64, f64)> = keep
            .iter()
            .map(|i| (s.points[*i].time, s.points[*i].radius))
            .collect();
        let w: Option<Vec<f64>> = keep
            .iter()
            .map(|i| s.points[*i].sd.map(|sd| 1.0 / (sd * sd)))
            .collect();
        let sim: Vec<(f64, f64)> = keep
            .iter()
            .map(|i| (s.points[*i].time, predicted[k + i]))
            .collect();
        k += n;
        if m.len() < 4 {
            rows.push(GrowthRow {
                experiment: s.experiment.clone(),
                bubble: s.bubble,
                measured_plateau_m: None,
                measured_plateau_ci95_m: None,
                measured_half_life_s: None,
                measured_half_life_ci95_s: None,
                simulated_plateau_m: None,
                simulated_half_life_s: None,
                same_curve_p_value: None,
                note: format!(
                    "fewer than 4 points after the profile's last pressure change (t ≥ {start} s)"
                ),
            });
            continue;
        }
        let fm: Option<GrowthFit> = fit_growth(&m, w.as_deref()).ok().filter(|g| g.converged);
        let fs: Option<GrowthFit> = fit_growth(&sim, None).ok().filter(|g| g.converged);
        let p = fs
            .as_ref()
            .and_then(|f| compare_to_curve(&m, w.as_deref(), f).ok())
            .map(|t| t.p_value);
        let note = match (&fm, &fs) {
            (Some(_), Some(_)) => String::new(),
            _ => "the exponential growth curve does not describe this series (no converged fit)"
                .into(),
        };
        rows.push(GrowthRow {
            experiment: s.experiment.clone(),
            bubble: s.bubble,
            measured_plateau_m: fm.as_ref().map(|g| g.plateau),
            measured_plateau_ci95_m: fm.as_ref().map(|g| g.plateau_ci),
            measured_half_life_s: fm.as_ref().map(|g| g.half_life),
            measured_half_life_ci95_s: fm.as_ref().map(|g| g.half_life_ci),
            simulated_plateau_m: fs.as_ref().map(|g| g.plateau),
            simulated_half_life_s: fs.as_ref().map(|g| g.half_life),
            same_curve_p_value: p,
            note,
        });
    }
    rows
}

/// Growth metrics as a table.
pub fn growth_table(rows: &[GrowthRow]) -> Result<Table, Error> {
    let mut t = Table::new(
        "Growth metrics: R(t) = R_p − (R_p − R_0)·e^(−kt), half-life ln 2/k",
        vec![
            Column::plain("experiment"),
            Column::plain("bubble"),
            Column::new("measured R_p", "µm"),
            Column::plain("95 % interval (µm)"),
            Column::new("measured half-life", "s"),
            Column::new("simulated R_p", "µm"),
            Column::new("simulated half-life", "s"),
            Column::plain("same curve? F-test p"),
            Column::plain("note"),
        ],
    );
    let o = |v: Option<f64>, f: f64| v.map_or(Cell::Empty, |x| cell(x * f));
    for r in rows {
        t.push(vec![
            Cell::text(&r.experiment),
            Cell::text(r.bubble.to_string()),
            o(r.measured_plateau_m, 1e6),
            r.measured_plateau_ci95_m.map_or(Cell::Empty, |c| {
                Cell::text(format!("[{}, {}]", sig(c[0] * 1e6, 4), sig(c[1] * 1e6, 4)))
            }),
            o(r.measured_half_life_s, 1.0),
            o(r.simulated_plateau_m, 1e6),
            o(r.simulated_half_life_s, 1.0),
            o(r.same_curve_p_value, 1.0),
            Cell::text(&r.note),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(t)
}

#[derive(Serialize)]
struct FitFile<'a> {
    measurements: String,
    experiments: String,
    observations: usize,
    parameters: usize,
    dof: usize,
    weighted: bool,
    ssr: f64,
    rmse_m: f64,
    aicc: f64,
    residual_variance: f64,
    converged: bool,
    termination: &'a str,
    model_evaluations: usize,
    singular: bool,
    parameter: Vec<ParamOut>,
    correlation: Vec<Vec<f64>>,
    growth: &'a [GrowthRow],
}

#[derive(Serialize)]
struct ParamOut {
    name: String,
    value: f64,
    std_error: f64,
    ci95: [f64; 2],
    log_space: bool,
    at_bound: bool,
}

/// `fit.toml` text.
pub fn fit_toml(
    f: &Fitted,
    experiments: &Experiments,
    data: &Measurements,
    growth: &[GrowthRow],
) -> Result<String, Error> {
    let file = FitFile {
        measurements: data.file.display().to_string(),
        experiments: experiments.file.display().to_string(),
        observations: f.n,
        parameters: f.p(),
        dof: f.dof(),
        weighted: data.has_sd(),
        ssr: f.ssr,
        rmse_m: f.rmse,
        aicc: f.aicc,
        residual_variance: f.inference.s2,
        converged: f.lsq.converged,
        termination: &f.lsq.termination,
        model_evaluations: f.lsq.evaluations,
        singular: f.inference.singular,
        parameter: f
            .inference
            .estimates
            .iter()
            .map(|e| ParamOut {
                name: e.name.clone(),
                value: e.value,
                std_error: e.std_error,
                ci95: e.ci95,
                log_space: e.log,
                at_bound: e.at_bound,
            })
            .collect(),
        correlation: f.inference.correlation.clone(),
        growth,
    };
    toml::to_string(&file).map_err(|e| Error::Solver(format!("fit.toml: {e}")))
}

/// Build the whole `fit` output.
pub fn fit_outputs(
    f: &Fitted,
    start_runs: &[SimRun],
    fitted_runs: &[SimRun],
    experiments: &Experiments,
    data: &Measurements,
    command: &str,
) -> Result<OutputSet, Error> {
    let growth = growth_rows(experiments, data, &f.predicted);
    let mut set = OutputSet::new();
    set.add("fit.toml", fit_toml(f, experiments, data, &growth)?);
    let mut page = Page::new("Fit of the phantom model to measured bubble radii");
    page.text(format!(
        "{} observations of {} bubbles in {} experiments; {} free parameter(s). Weighted least squares ({}), Levenberg–Marquardt (`levenberg-marquardt` crate) with a forward-difference Jacobian.\n\nAssumptions of the intervals: independent Gaussian measurement errors with the given relative weights, and a model close to linear in its parameters near the optimum (asymptotic intervals from the Jacobian, Student t with n − p = {} degrees of freedom; log-space parameters get asymmetric intervals).",
        f.n,
        data.series.len(),
        experiments.list.len(),
        f.p(),
        if data.has_sd() { "weights 1/sd² from the sd_m column" } else { "unweighted: no sd_m column" },
        f.dof()
    ));
    page.pre(command.to_string());
    page.section("Estimates");
    page.table(&estimates_table("Estimates", &f.inference.estimates)?);
    if f.inference.singular {
        page.text("**The Jacobian is singular**: some parameter (or combination) is not determined by these data; its interval is not meaningful.");
    }
    if f.p() > 1 {
        let mut cols = vec![Column::plain("")];
        cols.extend(f.inference.estimates.iter().map(|e| Column::plain(&e.name)));
        let mut t = Table::new("Correlation of the estimates", cols);
        for (i, row) in f.inference.correlation.iter().enumerate() {
            let mut r = vec![Cell::text(&f.inference.estimates[i].name)];
            r.extend(row.iter().map(|c| Cell::fixed(*c, 3)));
            t.push(r).map_err(Error::Solver)?;
        }
        page.table(&t);
    }
    page.section("Goodness of fit");
    let mut t = Table::new(
        "Goodness of fit",
        vec![Column::plain("quantity"), Column::plain("value")],
    );
    for (k, v) in [
        ("observations n", f.n.to_string()),
        ("free parameters p", f.p().to_string()),
        ("SSR (weighted)", sig(f.ssr, 5)),
        ("residual variance s² = SSR/(n − p)", sig(f.inference.s2, 5)),
        ("RMSE (unweighted)", format!("{} µm", sig(f.rmse * 1e6, 4))),
        ("AICc", sig(f.aicc, 6)),
        (
            "converged",
            format!("{} ({})", f.lsq.converged, f.lsq.termination),
        ),
        ("model evaluations", f.lsq.evaluations.to_string()),
    ] {
        t.push(vec![Cell::text(k), Cell::text(v)])
            .map_err(Error::Solver)?;
    }
    page.table(&t);
    page.section("Growth metrics (the paper's §4.2)");
    page.text("The growth after the profile's last pressure change (as the paper fitted it, §4.2): each measured series and its simulation at the same times fitted to R(t) = R_p − (R_p − R_0)·e^(−k(t − t₀)); the last column is the extra sum-of-squares F-test of one curve for both (3 parameters) against one each (6), the comparison of the paper's Fig. 5. Series without such a phase (an oscillation that ends where it changes) have no metrics.");
    page.table(&growth_table(&growth)?);
    page.section("Measured and simulated radii");
    add_overlays(
        &mut set,
        &mut page,
        experiments,
        data,
        &[
            ("simulated, fitted", fitted_runs),
            ("simulated, start values", start_runs),
        ],
        "",
    )?;
    set.add("report.md", page.to_markdown().map_err(Error::Solver)?);
    set.add("report.html", page.to_html().map_err(Error::Solver)?);
    Ok(set)
}
