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
use std::collections::BTreeMap;

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

/// Reason given for every standard error and interval of a fit whose Jacobian is singular.
pub const SINGULAR: &str = "not given: the Jacobian is singular at the optimum (these data do not determine this parameter, or a combination of it with others)";

/// The standard error and the 95 % interval of an estimate as written, or why each is not: a
/// singular Jacobian (`singular`), or a value that is not a finite number (no residual degree
/// of freedom, an overflowing covariance, an interval running to 0 or infinity). A statistic
/// that is not a finite number is never written (`fit.toml`, `discover.toml`, the reports).
pub fn estimate_stats(
    e: &Estimate,
    singular: bool,
) -> (Result<f64, String>, Result<[f64; 2], String>) {
    if singular {
        return (Err(SINGULAR.into()), Err(SINGULAR.into()));
    }
    let se = if e.std_error.is_finite() {
        Ok(e.std_error)
    } else {
        Err("not given: the covariance of the estimates is not a finite number here".to_string())
    };
    let ci = if e.ci95.iter().all(|x| x.is_finite()) && se.is_ok() {
        Ok(e.ci95)
    } else if se.is_err() {
        Err("not given: no finite standard error".to_string())
    } else {
        Err(format!(
            "not given: the 95 % interval is not finite ([{}, {}]): these data hardly constrain the parameter",
            e.ci95[0], e.ci95[1]
        ))
    };
    (se, ci)
}

/// Why AICc is not given for a fit of `p` parameters to `n` observations with weighted SSR
/// `ssr`, or `None` when it is a finite number.
pub fn aicc_absent(aicc: f64, ssr: f64, n: usize, p: usize) -> Option<String> {
    if aicc.is_finite() {
        return None;
    }
    Some(if n <= p + 2 {
        format!("not given: AICc = n·ln(SSR/n) + 2K + 2K(K + 1)/(n − K − 1) with K = p + 1 needs n > p + 2 (here n = {n}, p = {p})")
    } else if !(ssr > 0.0) {
        "not given: the weighted SSR is 0 (a perfect fit), so ln(SSR/n) is not finite".into()
    } else {
        "not given: not a finite number".into()
    })
}

/// A statistic for a table: the number, or its reason.
fn stat_cell(v: &Result<f64, String>) -> Cell {
    match v {
        Ok(x) => cell(*x),
        Err(m) => Cell::text(m),
    }
}

/// The estimates whose 95 % interval reaches beyond what the phantom reader accepts for the
/// parameter: each end written into the model's phantom documents (as the fit writes a value,
/// [`crate::fit::model::set_shared`]) and the documents read again, as `fit --param` checks its
/// bounds. Such an end is not a value the model could take (a surface tension above 1 N/m, a
/// bubble outside the phantom): the data do not bound the parameter there, and the interval's
/// symmetric form says nothing beyond it. One sentence per such estimate (empty: none).
pub fn intervals_beyond_accepted(
    docs: &[toml::Table],
    est: &[Estimate],
    singular: bool,
) -> Vec<String> {
    let files = vec![std::path::Path::new("phantom"); docs.len()];
    let refused = |v: f64, path: &str| -> Option<String> {
        super::paths::refused_value(docs, &files, path, v).map(|(_, why)| why)
    };
    est.iter()
        .filter_map(|e| {
            let Ok(ci) = estimate_stats(e, singular).1 else {
                return None;
            };
            let ends: Vec<String> = [("lower", ci[0]), ("upper", ci[1])]
                .into_iter()
                .filter(|(_, v)| v.is_finite())
                .filter_map(|(which, v)| {
                    refused(v, &e.name).map(|why| format!("its {which} end, {}, is refused: {why}", sig(v, 4)))
                })
                .collect();
            (!ends.is_empty()).then(|| {
                format!(
                    "{}: the 95 % interval reaches beyond what the phantom accepts ({}); the data do not bound the parameter there, so read the interval as open on that side, or fit with --param bounds",
                    super::paths::label(&e.name),
                    ends.join("; ")
                )
            })
        })
        .collect()
}

/// Table of estimates with standard errors and 95 % intervals (`singular`: the fit's Jacobian
/// was singular, so neither is given).
pub fn estimates_table(title: &str, est: &[Estimate], singular: bool) -> Result<Table, Error> {
    estimates_table_with_truth(title, est, singular, &BTreeMap::new())
}

/// [`estimates_table`] with a "true value" column after the estimate when `truth` (true values
/// of synthetic data by parameter name, [`DataInfo::truth`]) names any of the estimates; an
/// estimate it does not name gets an empty cell.
pub fn estimates_table_with_truth(
    title: &str,
    est: &[Estimate],
    singular: bool,
    truth: &BTreeMap<String, f64>,
) -> Result<Table, Error> {
    estimates_table_named(title, est, singular, truth, false)
}

/// [`estimates_table_with_truth`] of estimates named by their phantom paths (`fit`'s): each
/// parameter in a reader's words ([`super::paths::label`]: `D_N2 (m²/s)`), then its path as
/// `--param` takes it (`gases.n2.diffusivity`) in a column of its own.
pub fn estimates_table_with_paths(
    title: &str,
    est: &[Estimate],
    singular: bool,
    truth: &BTreeMap<String, f64>,
) -> Result<Table, Error> {
    estimates_table_named(title, est, singular, truth, true)
}

/// The estimates table; `with_paths`: the names are phantom paths, given as labels and paths.
fn estimates_table_named(
    title: &str,
    est: &[Estimate],
    singular: bool,
    truth: &BTreeMap<String, f64>,
    with_paths: bool,
) -> Result<Table, Error> {
    let with_truth = est.iter().any(|e| truth.contains_key(&e.name));
    let mut cols = vec![Column::plain("parameter")];
    if with_paths {
        cols.push(Column::plain("TOML path (--param)"));
    }
    cols.push(Column::plain("estimate"));
    if with_truth {
        cols.push(Column::plain("true value (synth)"));
    }
    cols.extend([
        Column::plain("std. error"),
        Column::plain("95 % interval"),
        Column::plain("fitted in"),
        Column::plain("note"),
    ]);
    let mut t = Table::new(title, cols);
    for e in est {
        finite_estimate(e)?;
        let (se, ci) = estimate_stats(e, singular);
        let mut notes = Vec::new();
        if e.at_bound {
            notes.push("at a bound: interval not reliable");
        }
        if e.clipped && ci.is_ok() {
            notes.push("interval clipped to the bounds given");
        }
        let mut row = if with_paths {
            vec![
                Cell::text(super::paths::label(&e.name)),
                Cell::text(&e.name),
            ]
        } else {
            vec![Cell::text(&e.name)]
        };
        row.push(cell(e.value));
        if with_truth {
            row.push(
                truth
                    .get(&e.name)
                    .map_or(Cell::Empty, |v| Cell::text(crate::error::num(*v))),
            );
        }
        row.extend([
            stat_cell(&se),
            match &ci {
                Ok(c) => Cell::text(format!("[{}, {}]", sig(c[0], 4), sig(c[1], 4))),
                Err(m) => Cell::text(m),
            },
            Cell::text(if e.log { "log space" } else { "linear" }),
            Cell::text(notes.join("; ")),
        ]);
        t.push(row).map_err(Error::Solver)?;
    }
    Ok(t)
}

/// TOML text with every float whose size is below 1e-4 or from 1e16 on rewritten in exponent
/// form (`2.308896500918035e-161` rather than 160 zeros and then the digits;
/// `2.6826799216733474e-5` rather than `0.000026826799216733474`): the `toml` crate writes every
/// float in positional notation and has no option for it. The text is read as a document by
/// `toml_edit` (the `toml` crate's own writer, so everything else is written back as it was:
/// strings, keys, comments, layout) and each such float is given the notation of Rust's `{:e}`,
/// whose shortest round-trip digits read back bit for bit. Text that is not TOML is returned
/// unchanged.
pub fn exponent_floats(text: &str) -> String {
    use toml_edit::visit_mut::VisitMut;
    struct Exponent;
    impl VisitMut for Exponent {
        fn visit_float_mut(&mut self, node: &mut toml_edit::Formatted<f64>) {
            let v = *node.value();
            if v.is_finite() && v != 0.0 && !(1e-4..1e16).contains(&v.abs()) {
                if let Ok(toml_edit::Value::Float(mut f)) = format!("{v:e}").parse() {
                    *f.decor_mut() = node.decor().clone();
                    *node = f;
                }
            }
        }
    }
    match text.parse::<toml_edit::DocumentMut>() {
        Ok(mut doc) => {
            Exponent.visit_document_mut(&mut doc);
            doc.to_string()
        }
        Err(_) => text.to_string(),
    }
}

/// The `[data]` table of `fit.toml` and `discover.toml`: where the data came from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DataOut {
    /// `measured` or `synthetic`.
    pub source: &'static str,
    /// The measurements file.
    pub file: String,
    /// The generator's command (synthetic data).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub generator: Option<String>,
    /// The effects switched on, as `NAME=V[,V2]` (synthetic data; empty: the baseline model).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub effects: Option<Vec<String>>,
    /// Noise sd, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub noise_sd_m: Option<f64>,
    /// Sampling interval, s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub every_s: Option<f64>,
    /// Seed of the noise (left out past the largest TOML integer; the generator has it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub seed: Option<i64>,
    /// Whether the file still ends with synth's matching end marker.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unchanged_since_written: Option<bool>,
    /// Why the generator's settings could not be read from the file.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub settings_unreadable: Option<String>,
    /// Why no true value is given (synthetic data with readable settings).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub true_values_absent: Option<String>,
}

/// Where the data of a report came from ([`data_info`]).
#[derive(Debug, Clone, PartialEq)]
pub struct DataInfo {
    /// The report's "Data" paragraph (Markdown).
    pub paragraph: String,
    /// The `[data]` table.
    pub toml: DataOut,
    /// True values by parameter name: the values `synth` set at the paths of the fitted
    /// model's parameters, when that model contains the one `synth` ran exactly
    /// ([`crate::fit::synth::true_values`]); empty otherwise.
    pub truth: BTreeMap<String, f64>,
}

/// The provenance of `data` for a report of `model` fitted to it: measured (no `# synthetic:`
/// line), or synthetic with the generator's effect(s), noise, interval and seed, and the true
/// values of the model's parameters where they are exact.
pub fn data_info(
    data: &Measurements,
    experiments: &Experiments,
    model: &super::model::Model,
) -> DataInfo {
    let file = data.file.display().to_string();
    let mut out = DataOut {
        source: "measured",
        file: file.clone(),
        generator: None,
        effects: None,
        noise_sd_m: None,
        every_s: None,
        seed: None,
        unchanged_since_written: None,
        settings_unreadable: None,
        true_values_absent: None,
    };
    let mut truth = BTreeMap::new();
    let Some(p) = &data.provenance else {
        return DataInfo {
            paragraph: format!("**Data**: measured radii, read from `{file}` (it holds no `# synthetic:` line, which `decophantom synth` writes into the data it makes)."),
            toml: out,
            truth,
        };
    };
    out.source = "synthetic";
    out.generator = Some(p.command.clone());
    out.unchanged_since_written = Some(p.unchanged);
    let mut text = String::new();
    match &p.settings {
        Err(m) => {
            text.push_str(&format!("**Data**: synthetic, not measured: `{file}` says at line {} that it was generated (`{}`), but its settings cannot be read ({m}), so no generator settings or true values are given.", p.line, p.command));
            out.settings_unreadable = Some(m.clone());
        }
        Ok(st) => {
            let effects: Vec<String> = st
                .effects
                .iter()
                .map(|e| {
                    if e.values.is_empty() {
                        e.name.clone()
                    } else {
                        let v: Vec<String> =
                            e.values.iter().map(|v| crate::error::num(*v)).collect();
                        format!("{}={}", e.name, v.join(","))
                    }
                })
                .collect();
            text.push_str(&format!(
                "**Data**: synthetic, not measured: generated by `{}` (line {} of `{file}`): {}, Gaussian noise of sd {} µm on every radius, sampled every {} s, noise seed {}.",
                p.command,
                p.line,
                if effects.is_empty() {
                    "no effect switched on (the baseline model itself)".to_string()
                } else {
                    format!(
                        "effect{} {} switched on",
                        if effects.len() > 1 { "s" } else { "" },
                        effects.iter().map(|e| format!("`{e}`")).collect::<Vec<_>>().join(", ")
                    )
                },
                sig(st.noise_sd * 1e6, 3),
                crate::error::num(st.every),
                st.seed
            ));
            out.effects = Some(effects);
            out.noise_sd_m = Some(st.noise_sd);
            out.every_s = Some(st.every);
            out.seed = i64::try_from(st.seed).ok();
            match super::synth::true_values(experiments, st, model) {
                Ok(v) => {
                    for (s, t) in model.free.iter().zip(v) {
                        if let Some(t) = t {
                            truth.insert(s.path.clone(), t);
                        }
                    }
                    if truth.is_empty() {
                        let why = "no fitted parameter is one the effects set".to_string();
                        text.push_str(&format!(" No true value is given: {why}."));
                        out.true_values_absent = Some(why);
                    } else {
                        text.push_str(" The parameter tables give the true value (the value synth set) beside each estimate of a parameter the effects set: the fitted model with those values is the model synth ran.");
                    }
                }
                Err(why) => {
                    text.push_str(&format!(" No true value is given: {why}."));
                    out.true_values_absent = Some(why);
                }
            }
        }
    }
    if !p.unchanged {
        text.push_str(" The file does not end with synth's end marker matching the lines above it (edited since it was written, or not written by `synth --out`): the rows may not be those these settings make.");
    }
    DataInfo {
        paragraph: text,
        toml: out,
        truth,
    }
}

/// An estimate that is not a finite number is a failure of the fit (exit 3), never written.
pub fn finite_estimate(e: &Estimate) -> Result<(), Error> {
    if e.value.is_finite() {
        Ok(())
    } else {
        Err(Error::Solver(format!(
            "the estimate of {} is not a finite number ({}); nothing was written",
            e.name, e.value
        )))
    }
}

/// A result of a fit that must be a finite number to be written (an SSR, an RMSE): else exit 3.
pub fn finite_result(what: &str, v: f64) -> Result<f64, Error> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(Error::Solver(format!(
            "{what} is not a finite number ({v}); nothing was written"
        )))
    }
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
        let mut note = match (&fm, &fs) {
            (Some(_), Some(_)) => String::new(),
            _ => "the exponential growth curve does not describe this series (no converged fit)"
                .into(),
        };
        // a metric that is not a finite number (an interval running to infinity, a rate of 0)
        // is left out, and the note says so
        let mut dropped = Vec::new();
        let mut one = |name: &str, v: Option<f64>| {
            v.filter(|x| {
                let ok = x.is_finite();
                if !ok {
                    dropped.push(name.to_string());
                }
                ok
            })
        };
        let measured_plateau_m = one("measured plateau", fm.as_ref().map(|g| g.plateau));
        let measured_half_life_s = one("measured half-life", fm.as_ref().map(|g| g.half_life));
        let simulated_plateau_m = one("simulated plateau", fs.as_ref().map(|g| g.plateau));
        let simulated_half_life_s = one("simulated half-life", fs.as_ref().map(|g| g.half_life));
        let same_curve_p_value = one("F-test p", p);
        let mut pair = |name: &str, v: Option<[f64; 2]>| {
            v.filter(|c| {
                let ok = c.iter().all(|x| x.is_finite());
                if !ok {
                    dropped.push(name.to_string());
                }
                ok
            })
        };
        let measured_plateau_ci95_m = pair(
            "measured plateau interval",
            fm.as_ref().map(|g| g.plateau_ci),
        );
        let measured_half_life_ci95_s = pair(
            "measured half-life interval",
            fm.as_ref().map(|g| g.half_life_ci),
        );
        if !dropped.is_empty() {
            if !note.is_empty() {
                note.push_str("; ");
            }
            note.push_str(&format!(
                "not given, not a finite number: {}",
                dropped.join(", ")
            ));
        }
        rows.push(GrowthRow {
            experiment: s.experiment.clone(),
            bubble: s.bubble,
            measured_plateau_m,
            measured_plateau_ci95_m,
            measured_half_life_s,
            measured_half_life_ci95_s,
            simulated_plateau_m,
            simulated_half_life_s,
            same_curve_p_value,
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

/// `fit.toml`. A statistic that is not a finite number is left out and its reason written in
/// the `absent` table beside it (`[absent]` for the fit, `[parameter.absent]` for an estimate).
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
    #[serde(skip_serializing_if = "Option::is_none")]
    aicc: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    residual_variance: Option<f64>,
    converged: bool,
    termination: &'a str,
    model_evaluations: usize,
    singular: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    correlation: Option<Vec<Vec<f64>>>,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    absent: BTreeMap<&'static str, String>,
    parameter: Vec<ParamOut>,
    growth: &'a [GrowthRow],
    data: DataOut,
}

#[derive(Serialize)]
struct ParamOut {
    name: String,
    value: f64,
    /// The value synth set (synthetic data whose model the fit contains exactly).
    #[serde(skip_serializing_if = "Option::is_none")]
    true_value: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    std_error: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    ci95: Option<[f64; 2]>,
    /// The bounds `NAME=LO..HI` given, if any.
    #[serde(skip_serializing_if = "Option::is_none")]
    bounds: Option<[f64; 2]>,
    /// The interval reached past a bound and was clipped to it.
    ci95_clipped_to_bounds: bool,
    log_space: bool,
    at_bound: bool,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    absent: BTreeMap<&'static str, String>,
}

/// The statistics of a whole fit as written: AICc, residual variance and the correlation
/// matrix, each the number or the reason it is not given.
pub struct FitStats {
    /// AICc.
    pub aicc: Result<f64, String>,
    /// s² = SSR/(n − p).
    pub residual_variance: Result<f64, String>,
    /// Correlation of the estimates.
    pub correlation: Result<Vec<Vec<f64>>, String>,
}

/// [`FitStats`] of `f`; an SSR, RMSE or estimate that is not a finite number is exit 3.
pub fn fit_stats(f: &Fitted) -> Result<FitStats, Error> {
    finite_result("the weighted SSR", f.ssr)?;
    finite_result("the RMSE", f.rmse)?;
    for e in &f.inference.estimates {
        finite_estimate(e)?;
    }
    let aicc = match aicc_absent(f.aicc, f.ssr, f.n, f.p()) {
        None => Ok(f.aicc),
        Some(m) => Err(m),
    };
    let residual_variance = if f.inference.s2.is_finite() {
        Ok(f.inference.s2)
    } else if f.dof() == 0 {
        Err(format!(
            "not given: no residual degree of freedom (n = {} = p)",
            f.n
        ))
    } else {
        Err("not given: not a finite number".into())
    };
    let correlation = if f.inference.singular {
        Err(SINGULAR.replace("this parameter", "every parameter"))
    } else if f
        .inference
        .correlation
        .iter()
        .flatten()
        .all(|c| c.is_finite())
    {
        Ok(f.inference.correlation.clone())
    } else {
        Err("not given: the covariance of the estimates is not a finite number here".into())
    };
    Ok(FitStats {
        aicc,
        residual_variance,
        correlation,
    })
}

/// `fit.toml` text; `info`: where the data came from ([`data_info`]).
pub fn fit_toml(
    f: &Fitted,
    experiments: &Experiments,
    data: &Measurements,
    growth: &[GrowthRow],
    info: &DataInfo,
) -> Result<String, Error> {
    let st = fit_stats(f)?;
    let mut absent = BTreeMap::new();
    let mut keep = |key: &'static str, v: &Result<f64, String>| match v {
        Ok(x) => Some(*x),
        Err(m) => {
            absent.insert(key, m.clone());
            None
        }
    };
    let aicc = keep("aicc", &st.aicc);
    let residual_variance = keep("residual_variance", &st.residual_variance);
    let correlation = match st.correlation {
        Ok(c) => Some(c),
        Err(m) => {
            absent.insert("correlation", m);
            None
        }
    };
    let parameter = f
        .inference
        .estimates
        .iter()
        .zip(&f.model.free)
        .map(|(e, spec)| {
            let (se, ci) = estimate_stats(e, f.inference.singular);
            let mut absent = BTreeMap::new();
            if let Err(m) = &se {
                absent.insert("std_error", m.clone());
            }
            if let Err(m) = &ci {
                absent.insert("ci95", m.clone());
            }
            ParamOut {
                name: e.name.clone(),
                value: e.value,
                true_value: info.truth.get(&e.name).copied(),
                std_error: se.ok(),
                ci95: ci.as_ref().ok().copied(),
                bounds: spec.lower.zip(spec.upper).map(|(a, b)| [a, b]),
                ci95_clipped_to_bounds: e.clipped && ci.is_ok(),
                log_space: e.log,
                at_bound: e.at_bound,
                absent,
            }
        })
        .collect();
    let file = FitFile {
        measurements: data.file.display().to_string(),
        experiments: experiments.file.display().to_string(),
        observations: f.n,
        parameters: f.p(),
        dof: f.dof(),
        weighted: data.has_sd(),
        ssr: f.ssr,
        rmse_m: f.rmse,
        aicc,
        residual_variance,
        converged: f.lsq.converged,
        termination: &f.lsq.termination,
        model_evaluations: f.lsq.evaluations,
        singular: f.inference.singular,
        correlation,
        absent,
        parameter,
        growth,
        data: info.toml.clone(),
    };
    toml::to_string(&file)
        .map(|t| exponent_floats(&t))
        .map_err(|e| Error::Solver(format!("fit.toml: {e}")))
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
    let info = data_info(data, experiments, &f.model);
    let mut set = OutputSet::new();
    set.add("fit.toml", fit_toml(f, experiments, data, &growth, &info)?);
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
    page.text(info.paragraph.clone());
    let st = fit_stats(f)?;
    page.section("Estimates");
    page.table(&estimates_table_with_paths(
        "Estimates",
        &f.inference.estimates,
        f.inference.singular,
        &info.truth,
    )?);
    if f.inference.singular {
        page.text("**The Jacobian is singular**: some parameter (or combination) is not determined by these data; no standard error, interval or correlation is given.");
    }
    let beyond =
        intervals_beyond_accepted(&f.model.docs, &f.inference.estimates, f.inference.singular);
    if !beyond.is_empty() {
        page.text(format!(
            "**Intervals beyond what the model accepts.** {}.",
            beyond.join(". ")
        ));
    }
    let clipped: Vec<String> = f
        .inference
        .estimates
        .iter()
        .zip(&f.model.free)
        .filter(|(e, _)| e.clipped && !f.inference.singular)
        .filter_map(|(e, s)| {
            Some(format!(
                "{} to {}..{}",
                super::paths::label(&e.name),
                crate::error::num(s.lower?),
                crate::error::num(s.upper?)
            ))
        })
        .collect();
    if !clipped.is_empty() {
        page.text(format!(
            "Intervals clipped to the bounds given (the Student-t interval in the fitting coordinates reached past them; a bounded parameter cannot): {}.",
            clipped.join("; ")
        ));
    }
    if f.p() > 1 {
        match &st.correlation {
            Ok(corr) => {
                let mut cols = vec![Column::plain("")];
                let label = |i: usize| super::paths::label(&f.inference.estimates[i].name);
                cols.extend((0..corr.len()).map(|i| Column::plain(label(i))));
                let mut t = Table::new("Correlation of the estimates", cols);
                for (i, row) in corr.iter().enumerate() {
                    let mut r = vec![Cell::text(label(i))];
                    r.extend(row.iter().map(|c| Cell::fixed(*c, 3)));
                    t.push(r).map_err(Error::Solver)?;
                }
                page.table(&t);
            }
            Err(m) => {
                page.text(format!("Correlation of the estimates: {m}."));
            }
        }
    }
    page.section("Goodness of fit");
    let mut t = Table::new(
        "Goodness of fit",
        vec![Column::plain("quantity"), Column::plain("value")],
    );
    for (k, v) in [
        ("observations n", f.n.to_string()),
        ("free parameters p", f.p().to_string()),
        ("SSR (weighted)", sig(f.ssr, 4)),
        (
            "residual variance s² = SSR/(n − p)",
            st.residual_variance
                .as_ref()
                .map_or_else(|m| m.clone(), |v| sig(*v, 4)),
        ),
        ("RMSE (unweighted)", format!("{} µm", sig(f.rmse * 1e6, 4))),
        (
            "AICc",
            st.aicc.as_ref().map_or_else(|m| m.clone(), |v| sig(*v, 4)),
        ),
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

#[cfg(test)]
mod tests {
    use super::*;

    /// An interval end the phantom reader refuses (γ above its 1 N/m) is named; one it
    /// accepts is not; a bubble's position beyond the phantom is refused by the reader too.
    #[test]
    fn intervals_beyond_what_the_phantom_accepts_are_named() {
        let doc: toml::Table = "[geometry]\nshape = \"box\"\nsize_m = [3.2e-3, 3.2e-3, 3.2e-3]\ngrid_step_m = 400e-6\n[material]\nsurface_tension = 0.07\n[gases.n2]\ndiffusivity = 2.5e-9\nostwald = 0.014\n[[bubbles]]\nposition_m = [1.6e-3, 1.6e-3, 1.6e-3]\ninitial_radius_m = 60e-6\n"
            .parse()
            .unwrap();
        let est = |name: &str, value: f64, ci95: [f64; 2]| Estimate {
            name: name.into(),
            value,
            std_error: (ci95[1] - ci95[0]) / 4.0,
            ci95,
            log: false,
            at_bound: false,
            clipped: false,
        };
        let all = [
            est("material.surface_tension", 0.014, [3e-16, 6.3e11]),
            est("material.surface_tension", 0.07, [0.05, 0.09]),
            est("bubbles.0.position_m.0", 1.6e-3, [-1.0, 2.0e-3]),
        ];
        let notes = intervals_beyond_accepted(std::slice::from_ref(&doc), &all, false);
        assert_eq!(notes.len(), 2, "{notes:?}");
        assert!(
            notes[0].contains("upper end, 6.3e11") || notes[0].contains("upper end, 6.300e11"),
            "{}",
            notes[0]
        );
        assert!(!notes[0].contains("lower end"), "{}", notes[0]);
        assert!(notes[1].contains("lower end"), "{}", notes[1]);
        // a singular fit gives no interval to judge
        assert!(intervals_beyond_accepted(&[doc], &all, true).is_empty());
    }

    fn est(se: f64, ci: [f64; 2]) -> Estimate {
        Estimate {
            name: "a".into(),
            value: 1.0,
            std_error: se,
            ci95: ci,
            log: false,
            at_bound: false,
            clipped: false,
        }
    }

    /// A statistic is written only when it is a finite number: a singular Jacobian, a NaN
    /// standard error or an interval running to infinity each give a reason instead; AICc is
    /// not given for n ≤ p + 2 (its denominator n − K − 1 with K = p + 1 is ≤ 0).
    #[test]
    fn statistics_that_are_not_finite_are_given_as_reasons() {
        let good = est(0.1, [0.8, 1.2]);
        assert_eq!(estimate_stats(&good, false), (Ok(0.1), Ok([0.8, 1.2])));
        let (se, ci) = estimate_stats(&good, true);
        assert!(se.unwrap_err().contains("singular") && ci.unwrap_err().contains("singular"));
        let (se, ci) = estimate_stats(&est(f64::NAN, [f64::NAN; 2]), false);
        assert!(se.is_err() && ci.is_err());
        let (se, ci) = estimate_stats(&est(0.1, [0.0, f64::INFINITY]), false);
        assert_eq!(se, Ok(0.1));
        assert!(ci.unwrap_err().contains("not finite"));
        // n = 3, p = 1: K + 1 = 3 = n, so AICc is infinite and not given; n = 4 gives a number
        let a3 = crate::fit::stats::aicc(1.0, 3, 1);
        assert!(aicc_absent(a3, 1.0, 3, 1).unwrap().contains("n > p + 2"));
        let a4 = crate::fit::stats::aicc(1.0, 4, 1);
        assert!(a4.is_finite() && aicc_absent(a4, 1.0, 4, 1).is_none());
        assert!(finite_estimate(&est(0.1, [0.0, 1.0])).is_ok());
        let mut bad = est(0.1, [0.0, 1.0]);
        bad.value = f64::NAN;
        assert!(matches!(finite_estimate(&bad), Err(Error::Solver(_))));
    }

    /// Floats below 1e-4 (and from 1e16) are written in exponent form with their shortest
    /// round-trip digits, so they read back to the same bits (both texts parsed back by `toml`
    /// give the same document); strings and comments holding such numbers and keys with digits
    /// are left alone; ordinary sizes keep positional notation. Reference: the values put in,
    /// and the text the `toml` crate writes for them. (`toml_edit` rewrites the floats in place
    /// of the hand-written scanner before it, byte for byte as the scanner did on
    /// `reports/discover/discover.toml`, two fit.toml files and these cases.)
    #[test]
    fn tiny_floats_are_written_in_exponent_form() {
        #[derive(Serialize)]
        struct T {
            p_value: f64,
            ci95: [f64; 2],
            big: f64,
            note: String,
            value: f64,
        }
        let t = T {
            p_value: 2.308896500918035e-161,
            ci95: [2.6826799216733474e-5, -3.5e-9],
            big: 6.225223095758606e16,
            note: "p = 0.00000000000012 stays".into(),
            value: 29.49538853203191,
        };
        let raw = toml::to_string(&t).unwrap();
        assert!(raw.contains("0.0000000000000000"), "{raw}");
        let out = exponent_floats(&raw);
        assert!(out.contains("p_value = 2.308896500918035e-161\n"), "{out}");
        assert!(
            out.contains("ci95 = [2.6826799216733474e-5, -3.5e-9]"),
            "{out}"
        );
        assert!(out.contains("big = 6.225223095758606e16\n"), "{out}");
        assert!(
            out.contains("note = \"p = 0.00000000000012 stays\""),
            "{out}"
        );
        assert!(out.contains("value = 29.49538853203191\n"), "{out}");
        let back: toml::Table = out.parse().unwrap();
        assert_eq!(back["p_value"].as_float(), Some(2.308896500918035e-161));
        assert_eq!(back["big"].as_float(), Some(6.225223095758606e16));
        assert_eq!(back, raw.parse::<toml::Table>().unwrap());
        // comments, inline tables and layout kept; text that is not TOML is left as it is
        let text = "# p = 0.00001\n[a]\nb = { c = 0.00003, d = \"0.00001\" } # 0.00001\ne = [\n  0.0000002,\n  1.5,\n]\n";
        let out = exponent_floats(text);
        assert_eq!(
            out,
            "# p = 0.00001\n[a]\nb = { c = 3e-5, d = \"0.00001\" } # 0.00001\ne = [\n  2e-7,\n  1.5,\n]\n"
        );
        assert_eq!(
            out.parse::<toml::Table>().unwrap(),
            text.parse::<toml::Table>().unwrap()
        );
        assert_eq!(exponent_floats("a = [0.00001"), "a = [0.00001");
    }
}
