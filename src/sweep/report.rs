//! `indices.csv`, `report.md` and `report.html` of a finished study: one-at-a-time ranges and
//! normalised sensitivities with radius courses coloured by parameter value and tornado bars;
//! Morris μ*, σ; Sobol' first-order and total indices with bootstrap intervals.

use super::design::{morris_indices, oat_index, sobol_indices, Method, BOOTSTRAP, SOBOL_MIN_ROWS};
use super::run::Results;
use crate::error::Error;
use crate::fit::paths;
use crate::fit::report::sig;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::plot::{BarChart, IntervalBars, LinePlot, PlotError, Series};
use crate::report::table::{Cell, Column, Table};

/// One row of indices.csv: metric, parameter and the method's numbers.
pub type IndexRow = (String, String, Vec<f64>);

/// The flag of a Sobol' estimate outside [0, 1].
pub const OUTSIDE_UNIT: &str = "estimate outside [0, 1]: estimator noise";

/// Which of a Sobol' row's indices (`S1`, `ST`) has its estimate outside [0, 1] (numbers as in
/// indices.csv: s1, s1_lo95, s1_hi95, st, st_lo95, st_hi95, …). The indices are fractions of a
/// variance, so they lie in [0, 1]; their estimators do not, and stray outside by their noise:
/// such estimates are flagged, not printed as if they were indices. An interval end outside
/// [0, 1] alone is not flagged: the interval of an index near 0 (or 1) straddles it by its
/// width, as it should. NaN (undefined) is not flagged here: it has its own notes.
pub fn sobol_outside_unit(v: &[f64]) -> Vec<&'static str> {
    let out = |x: &[f64]| x.iter().any(|x| x.is_finite() && !(0.0..=1.0).contains(x));
    let mut w = Vec::new();
    if v.len() >= 6 {
        if out(&v[0..1]) {
            w.push("S1");
        }
        if out(&v[3..4]) {
            w.push("ST");
        }
    }
    w
}

/// The indices of every (metric, parameter): a header and rows of numbers, written with the
/// shortest round-trip decimal (so a merged study's file is byte-identical to the whole one's).
/// Morris and Sobol' rows end with `n_used` and `n_dropped`: the elementary effects (Morris)
/// or base rows (Sobol') the numbers are computed from and those left out because a run
/// failed or its metric is undefined.
pub fn indices(res: &Results) -> (Vec<&'static str>, Vec<IndexRow>) {
    let (h, rows, _) = indices_and_notes(res);
    (h, rows)
}

/// [`indices`] with the notes the report prints about them: which numbers rest on fewer
/// runs than the design's, and which are undefined and why.
///
/// The indices need every run of the design ([`Results::is_whole`]); for a shard's rows
/// (or any other part of the design) there are none: no rows, and a note saying so.
pub fn indices_and_notes(res: &Results) -> (Vec<&'static str>, Vec<IndexRow>, Vec<String>) {
    let spec = &res.spec;
    let k = spec.params.len();
    let y = |m: usize| -> Vec<f64> { res.rows.iter().map(|r| r.metrics[m]).collect() };
    let mut rows = Vec::new();
    let mut notes = Vec::new();
    let header = match spec.method {
        Method::Oat => vec![
            "lo",
            "hi",
            "base",
            "metric_base",
            "metric_min",
            "metric_max",
            "normalised_sensitivity",
        ],
        Method::Morris => vec!["mu_star", "mu", "sigma", "n_used", "n_dropped"],
        Method::Sobol => vec![
            "s1",
            "s1_lo95",
            "s1_hi95",
            "st",
            "st_lo95",
            "st_hi95",
            "n_used",
            "n_dropped",
        ],
    };
    if !res.is_whole() {
        notes.push(format!(
            "no indices: they need every run of the design ({} runs), these are {} of them; merge the shards' folders (decophantom merge)",
            spec.runs().map_or("?".to_string(), |n| n.to_string()),
            res.rows.len()
        ));
        return (header, rows, notes);
    }
    for (mi, m) in spec.metrics.iter().enumerate() {
        let ys = y(mi);
        let name = m.name();
        let all_nan = ys.iter().all(|v| !v.is_finite());
        if all_nan {
            notes.push(format!(
                "**{name}** is undefined in every run (NaN in sensitivity.csv): it has no indices (NaN) and no chart; the other metrics are unaffected."
            ));
        }
        match spec.method {
            Method::Oat => {
                let n = spec.samples;
                let mb = ys[0];
                if !mb.is_finite() && !all_nan {
                    notes.push(format!(
                        "{name}: undefined in the base run, so every normalised_sensitivity of it is NaN."
                    ));
                }
                for (i, p) in spec.params.iter().enumerate() {
                    let lv: Vec<(f64, f64)> = (0..n)
                        .map(|l| {
                            let r = &res.rows[1 + i * n + l];
                            (r.values[i], r.metrics[mi])
                        })
                        .collect();
                    let bad = lv.iter().filter(|l| !l.1.is_finite()).count();
                    if bad == n && !all_nan {
                        notes.push(format!(
                            "{name} / {}: undefined at every level: metric_min, metric_max and normalised_sensitivity are NaN.",
                            p.path
                        ));
                    } else if bad > 0 && !all_nan {
                        notes.push(format!(
                            "{name} / {}: undefined at {bad} of its {n} levels; metric_min and metric_max are over the other {}{}.",
                            p.path,
                            n - bad,
                            if lv[0].1.is_finite() && lv[n - 1].1.is_finite() {
                                ""
                            } else {
                                " and normalised_sensitivity (from the lowest and highest level) is NaN"
                            }
                        ));
                    }
                    let o = oat_index(&lv, p.base, mb);
                    rows.push((
                        name.clone(),
                        p.path.clone(),
                        vec![p.lo, p.hi, p.base, mb, o.min, o.max, o.normalised],
                    ));
                }
            }
            Method::Morris => {
                let pts = spec.points();
                for (p, ix) in spec.params.iter().zip(morris_indices(&pts, &ys, k)) {
                    if ix.n_dropped > 0 && ix.n_used > 0 {
                        notes.push(format!(
                            "{name} / {}: μ*, μ and σ from {} of {} elementary effects ({} touch a run with the metric undefined and are left out).",
                            p.path,
                            ix.n_used,
                            ix.n_used + ix.n_dropped,
                            ix.n_dropped
                        ));
                    } else if ix.n_used == 0 && !all_nan {
                        notes.push(format!(
                            "{name} / {}: no elementary effect is defined (every one touches a run with the metric undefined): μ*, μ, σ are NaN.",
                            p.path
                        ));
                    }
                    rows.push((
                        name.clone(),
                        p.path.clone(),
                        vec![
                            ix.mu_star,
                            ix.mu,
                            ix.sigma,
                            ix.n_used as f64,
                            ix.n_dropped as f64,
                        ],
                    ));
                }
            }
            Method::Sobol => {
                for (p, ix) in spec.params.iter().zip(sobol_indices(&ys, k, spec.seed)) {
                    let n = ix.n_used + ix.n_dropped;
                    let what = format!("{name} / {}", p.path);
                    if all_nan {
                        // said once for the metric above
                    } else if ix.n_used < SOBOL_MIN_ROWS {
                        notes.push(format!(
                            "{what}: {} of {n} base rows usable (fewer than {SOBOL_MIN_ROWS}): S1 and ST undefined (NaN), no interval.",
                            ix.n_used
                        ));
                    } else if !ix.s1.is_finite() {
                        notes.push(format!(
                            "{what}: the metric does not vary over the {} usable base rows: S1 and ST undefined (NaN), no interval.",
                            ix.n_used
                        ));
                    } else {
                        if ix.n_dropped > 0 {
                            notes.push(format!(
                                "{what}: S1 and ST (and their intervals, where given) from {} of {n} base rows ({} left out: f(A), f(B) or f(A_B^i) undefined).",
                                ix.n_used, ix.n_dropped
                            ));
                        }
                        if ix.undefined_resamples > 0 {
                            notes.push(format!(
                                "{what}: no 95 % interval: in {} of {BOOTSTRAP} bootstrap resamples the index is undefined (fewer than {SOBOL_MIN_ROWS} usable rows or a constant metric), too few usable rows for an interval.",
                                ix.undefined_resamples
                            ));
                        }
                    }
                    let v = vec![
                        ix.s1,
                        ix.s1_ci[0],
                        ix.s1_ci[1],
                        ix.st,
                        ix.st_ci[0],
                        ix.st_ci[1],
                        ix.n_used as f64,
                        ix.n_dropped as f64,
                    ];
                    let out = sobol_outside_unit(&v);
                    if !out.is_empty() {
                        let show = |x: &[f64]| {
                            format!("{} [{}, {}]", sig(x[0], 3), sig(x[1], 3), sig(x[2], 3))
                        };
                        notes.push(format!(
                            "{what}: {OUTSIDE_UNIT}: {} from {} usable base rows (S1 {}, ST {}); the indices lie in [0, 1], this estimate does not: the estimator's noise at this N, whose size its 95 % interval shows; more --samples narrow it.",
                            out.join(" and "),
                            ix.n_used,
                            show(&v[0..3]),
                            show(&v[3..6])
                        ));
                    }
                    rows.push((name.clone(), p.path.clone(), v));
                }
            }
        }
    }
    (header, rows, notes)
}

fn csv_text(h: &[&str], rows: &[IndexRow]) -> String {
    let mut s = format!("metric,parameter,{}\n", h.join(","));
    for (m, p, v) in rows {
        s.push_str(&format!("{m},{p}"));
        for x in v {
            s.push_str(&format!(",{}", super::num(*x)));
        }
        s.push('\n');
    }
    s
}

/// `indices.csv` text.
pub fn indices_csv(res: &Results) -> String {
    let (h, rows) = indices(res);
    csv_text(&h, &rows)
}

/// An SVG, or `None` when the plot has no finite data (the caller notes it instead): a
/// metric undefined in every run must not cost the other metrics their report.
fn svg_or_none(r: Result<String, PlotError>) -> Result<Option<String>, Error> {
    match r {
        Ok(s) => Ok(Some(s)),
        Err(PlotError::NoData(_)) => Ok(None),
        Err(e) => Err(plot_err(e)),
    }
}

fn plot_err(e: impl std::fmt::Display) -> Error {
    Error::Solver(format!("report: {e}"))
}

/// Add indices.csv, report.md, report.html and the SVGs.
pub fn add_indices_and_report(
    set: &mut OutputSet,
    res: &Results,
    command: &str,
) -> Result<(), Error> {
    let spec = &res.spec;
    if !res.is_whole() {
        return Err(Error::Solver(format!(
            "report: the indices need every run of the design; {} of them given (a shard is merged first)",
            res.rows.len()
        )));
    }
    let (h, rows, notes) = indices_and_notes(res);
    set.add("indices.csv", csv_text(&h, &rows));
    let mut page = Page::new(format!("Sensitivity ({})", spec.method.name()));
    page.pre(command.to_string());
    let failed = res
        .rows
        .iter()
        .filter(|r| r.metrics.iter().any(|v| !v.is_finite()))
        .count();
    let mut design = Table::new(
        "Parameters",
        vec![
            Column::plain("parameter"),
            Column::plain("low"),
            Column::plain("high"),
            Column::plain("base"),
            Column::plain("sampling"),
        ],
    );
    for p in &spec.params {
        design
            .push(vec![
                Cell::text(p.path.clone()),
                Cell::sig(p.lo, 4),
                Cell::sig(p.hi, 4),
                Cell::sig(p.base, 4),
                Cell::text(if p.log { "log-uniform" } else { "uniform" }),
            ])
            .map_err(plot_err)?;
    }
    page.text(format!(
        "Method **{}**, samples {}, seed {}: {} runs; {} with an undefined metric (a failed run or a growth curve that does not converge: NaN in the CSV).",
        spec.method.name(),
        spec.samples,
        spec.seed,
        res.rows.len(),
        failed
    ));
    page.table(&design);
    let mut cols = vec![Column::plain("metric"), Column::plain("parameter")];
    cols.extend(h.iter().map(|c| Column::plain(*c)));
    let mut t = Table::new("Indices (indices.csv)", cols);
    for (m, p, v) in &rows {
        let mut r = vec![Cell::text(m.clone()), Cell::text(p.clone())];
        r.extend(h.iter().zip(v).map(|(c, x)| {
            // the counts as whole numbers
            Cell::text(if c.starts_with("n_") && x.is_finite() {
                format!("{x:.0}")
            } else {
                sig(*x, 4)
            })
        }));
        t.push(r).map_err(plot_err)?;
    }
    page.section("Indices");
    page.text(match spec.method {
        Method::Oat => "One at a time (the paper's Fig. 3): each parameter over its range at the given levels, the others at the phantom's values. normalised_sensitivity = (metric at the highest level − at the lowest)/(highest − lowest) × base value / metric at base. A level whose metric is undefined is left out of metric_min and metric_max (noted below).".to_string(),
        Method::Morris => "Morris elementary effects (Morris 1991; μ* of Campolongo et al. 2007) on a 4-level grid, Δ = 2/3 of the range in the sampling coordinate (log for log-uniform parameters); μ*, μ and σ are in metric units per whole range of that coordinate. An elementary effect whose two runs do not both have the metric defined is left out: n_used effects (one per trajectory) give μ*, μ and σ, n_dropped are left out; NaN when none is left (σ when fewer than two).".to_string(),
        Method::Sobol => format!("Sobol' indices from Saltelli's A, B, A_B^i design (Saltelli et al. 2010): first order S1 with their estimator (b), total ST with Jansen's (f); 95 % percentile intervals from {BOOTSTRAP} bootstrap resamples of the N base rows. A base row j counts for parameter i only when f(A)_j, f(B)_j and f(A_B^i)_j are all defined: n_used rows give the index (the total variance too), n_dropped are left out, and every bootstrap resample (N rows drawn from all N) leaves out its unusable rows the same way. With fewer than {SOBOL_MIN_ROWS} usable rows the index is NaN; an interval is given only when the index is defined in every resample. The indices lie in [0, 1], their estimators not always: an estimate outside it is noted below (\"{OUTSIDE_UNIT}\")."),
    });
    page.table(&t);
    if !notes.is_empty() {
        page.text(format!(
            "Notes: undefined metrics and indices, estimates outside their range ({} note{}):\n\n{}",
            notes.len(),
            if notes.len() == 1 { "" } else { "s" },
            notes
                .iter()
                .map(|n| format!("- {n}"))
                .collect::<Vec<_>>()
                .join("\n")
        ));
    }
    for (mi, m) in spec.metrics.iter().enumerate() {
        let mrows: Vec<&IndexRow> = rows.iter().filter(|r| r.0 == m.name()).collect();
        // parameters by their symbols and units, the metric in its plot unit (µm, mm³, s)
        let cats: Vec<String> = mrows.iter().map(|r| paths::label(&r.1)).collect();
        let (unit, scale) = m.plot_unit();
        let (groups, values, title, ylab): (Vec<String>, Vec<Vec<f64>>, String, String) =
            match spec.method {
                Method::Oat => (
                    vec![
                        "lowest metric − base".into(),
                        "highest metric − base".into(),
                    ],
                    mrows
                        .iter()
                        .map(|r| vec![(r.2[4] - r.2[3]) * scale, (r.2[5] - r.2[3]) * scale])
                        .collect(),
                    format!(
                        "Tornado: range of the {} over each parameter's range",
                        m.words()
                    ),
                    format!("{} − base ({unit})", m.name()),
                ),
                Method::Morris => (
                    vec!["μ*".into(), "σ".into()],
                    mrows
                        .iter()
                        .map(|r| vec![r.2[0] * scale, r.2[2] * scale])
                        .collect(),
                    format!("Morris μ* and σ of the {}", m.words()),
                    format!("{} per range ({unit})", m.name()),
                ),
                Method::Sobol => (
                    vec!["S1".into(), "ST".into()],
                    mrows.iter().map(|r| vec![r.2[0], r.2[3]]).collect(),
                    format!("Sobol' indices of the {}", m.words()),
                    "index".into(),
                ),
            };
        let chart = BarChart {
            title,
            x_label: "parameter".into(),
            y_label: ylab,
            categories: cats,
            groups,
            values,
            reference: None,
            size: (960, 480),
        };
        let file = format!("bars-{mi}.svg");
        page.heading(3, m.name());
        let drawn = match spec.method {
            // the point estimates as bars, their bootstrap 95 % intervals as error bars
            Method::Sobol => IntervalBars {
                chart,
                intervals: mrows
                    .iter()
                    .map(|r| vec![(r.2[1], r.2[2]), (r.2[4], r.2[5])])
                    .collect(),
            }
            .to_svg(),
            _ => chart.to_svg(),
        };
        let Some(svg) = svg_or_none(drawn)? else {
            page.text(format!(
                "No chart: no index of {} is defined (see the notes above).",
                m.name()
            ));
            continue;
        };
        page.figure(
            &svg,
            Some(&file),
            match spec.method {
                Method::Sobol => "Bars: point estimates; error bars: their 95 % bootstrap percentile intervals (the table gives both ends).",
                Method::Oat => "Change of the metric from its base value at the lowest and highest metric over each parameter's levels.",
                Method::Morris => "μ* (importance) and σ (nonlinearity or interaction).",
            },
        )
        .map_err(plot_err)?;
        set.add(file, svg);
    }
    if spec.method == Method::Oat {
        page.section("Radius time courses");
        page.text("The largest bubble's radius in every run of each parameter's levels (the paper's Fig. 3 panels); series named by the parameter's value, lowest first.");
        let n = spec.samples;
        for (i, p) in spec.params.iter().enumerate() {
            let mut plot = LinePlot::new(
                format!("Radius as {} varies", paths::label(&p.path)),
                "time (s)",
                "radius (µm)",
            );
            for l in 0..n {
                let idx = 1 + i * n + l;
                let pts: Vec<(f64, f64)> = res
                    .courses
                    .iter()
                    .find(|c| c.0 == idx)
                    .map(|c| c.1.iter().map(|(t, r)| (*t, r * 1e6)).collect())
                    .unwrap_or_default();
                let v = res.rows.get(idx).map_or(f64::NAN, |r| r.values[i]);
                plot = plot.with(Series::new(paths::with_value(&p.path, &sig(v, 3)), pts));
            }
            let file = format!("courses-{i}.svg");
            let Some(svg) = svg_or_none(plot.to_svg())? else {
                page.text(format!(
                    "No radius course as {} varies: every run of its levels failed.",
                    p.path
                ));
                continue;
            };
            page.figure(
                &svg,
                Some(&file),
                format!("{} over {}..{}", p.path, p.lo, p.hi),
            )
            .map_err(plot_err)?;
            set.add(file, svg);
        }
    }
    set.add("report.md", page.to_markdown().map_err(plot_err)?);
    set.add("report.html", page.to_html().map_err(plot_err)?);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::run::{Row, Shard};
    use crate::sweep::{Metric, Param, StudySpec};

    /// A Sobol' study of y = 2u0 + u1 (metric `r_max`) and a metric undefined everywhere
    /// (`plateau`), with base row `fail`'s f(A) failed for `r_max` when given.
    fn study(fail: Option<usize>) -> Results {
        let param = |p: &str| Param {
            path: p.into(),
            lo: 0.0,
            hi: 1.0,
            log: false,
            base: 0.5,
        };
        let spec = StudySpec {
            method: Method::Sobol,
            samples: 8,
            seed: 1,
            params: vec![param("a.x"), param("a.y")],
            metrics: vec![
                Metric::parse("r_max").unwrap(),
                Metric::parse("plateau").unwrap(),
            ],
        };
        let rows = spec
            .values()
            .into_iter()
            .enumerate()
            .map(|(index, v)| {
                let failed = fail.is_some_and(|j| index == j * (2 + 2));
                let y = if failed { f64::NAN } else { 2.0 * v[0] + v[1] };
                Row {
                    index,
                    values: v,
                    metrics: vec![y, f64::NAN],
                }
            })
            .collect();
        Results {
            spec,
            shard: Shard::WHOLE,
            rows,
            courses: Vec::new(),
            resumed: 0,
            inputs: None,
        }
    }

    #[test]
    fn sweep_a_shards_rows_give_no_indices_for_any_method_and_no_panic() {
        // each method's design of 2 parameters, cut to a shard's rows (the 1st of 2, the 2nd
        // of 3): the indices need every run, so there are none, a note says why, and the
        // report refuses; the whole design gives one row per parameter
        for method in [Method::Oat, Method::Morris, Method::Sobol] {
            let mut res = study(None);
            res.spec.method = method;
            res.spec.samples = 3;
            res.spec.metrics.truncate(1);
            res.rows = res
                .spec
                .values()
                .into_iter()
                .enumerate()
                .map(|(index, v)| Row {
                    index,
                    metrics: vec![2.0 * v[0] + v[1]],
                    values: v,
                })
                .collect();
            let n = res.rows.len();
            assert!(res.is_whole());
            assert_eq!(indices(&res).1.len(), 2, "{method:?}");
            for shard in [Shard { index: 0, count: 2 }, Shard { index: 1, count: 3 }] {
                let mut part = res.clone();
                part.shard = shard;
                part.rows.retain(|r| shard.range(n).contains(&r.index));
                assert!(!part.is_whole());
                let (h, rows, notes) = indices_and_notes(&part);
                assert!(!h.is_empty() && rows.is_empty(), "{method:?} {shard:?}");
                assert!(notes[0].starts_with("no indices"), "{notes:?}");
                assert!(add_indices_and_report(&mut OutputSet::new(), &part, "t").is_err());
            }
        }
    }

    #[test]
    fn sweep_report_counts_the_rows_used_and_notes_an_undefined_metric() {
        // the numbers themselves are checked in design.rs; here: the columns, the notes, and
        // that a metric undefined in every run leaves the report and the other metric whole
        for fail in [None, Some(3)] {
            let res = study(fail);
            let (h, rows, notes) = indices_and_notes(&res);
            assert_eq!(&h[6..], ["n_used", "n_dropped"]);
            let used = if fail.is_some() { 7.0 } else { 8.0 };
            for r in rows.iter().filter(|r| r.0 == "r_max") {
                assert_eq!(&r.2[6..], [used, 8.0 - used], "{r:?}");
                assert!(r.2[..6].iter().all(|v| v.is_finite()), "{r:?}");
            }
            for r in rows.iter().filter(|r| r.0 == "plateau") {
                assert!(r.2[..6].iter().all(|v| v.is_nan()));
                assert_eq!(&r.2[6..], [0.0, 8.0]);
            }
            assert_eq!(
                notes
                    .iter()
                    .filter(|n| n.contains("**plateau** is undefined in every run"))
                    .count(),
                1,
                "{notes:?}"
            );
            assert_eq!(
                notes
                    .iter()
                    .filter(|n| n.contains("from 7 of 8 base rows (1 left out"))
                    .count(),
                if fail.is_some() { 2 } else { 0 },
                "{notes:?}"
            );
            let mut set = OutputSet::new();
            add_indices_and_report(&mut set, &res, "test").unwrap();
            let md = String::from_utf8(set.get("report.md").unwrap().to_vec()).unwrap();
            assert!(
                md.contains("No chart: no index of plateau is defined"),
                "{md}"
            );
            assert!(set.get("bars-0.svg").is_some() && set.get("bars-1.svg").is_none());
            let csv = String::from_utf8(set.get("indices.csv").unwrap().to_vec()).unwrap();
            assert_eq!(csv, indices_csv(&res));
            assert!(
                csv.contains("plateau,a.x,NaN,NaN,NaN,NaN,NaN,NaN,0,8\n"),
                "{csv}"
            );
        }
    }
}
