//! `indices.csv`, `report.md` and `report.html` of a finished study: one-at-a-time ranges and
//! normalised sensitivities with radius courses coloured by parameter value and tornado bars;
//! Morris μ*, σ; Sobol' first-order and total indices with bootstrap intervals.

use super::design::{morris_indices, oat_index, sobol_indices, Method};
use super::run::Results;
use crate::error::Error;
use crate::fit::report::sig;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::plot::{BarChart, LinePlot, Series};
use crate::report::table::{Cell, Column, Table};

/// One row of indices.csv: metric, parameter and the method's numbers.
pub type IndexRow = (String, String, Vec<f64>);

/// The indices of every (metric, parameter): a header and rows of numbers, written with the
/// shortest round-trip decimal (so a merged study's file is byte-identical to the whole one's).
pub fn indices(res: &Results) -> (Vec<&'static str>, Vec<IndexRow>) {
    let spec = &res.spec;
    let k = spec.params.len();
    let y = |m: usize| -> Vec<f64> { res.rows.iter().map(|r| r.metrics[m]).collect() };
    let mut rows = Vec::new();
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
        Method::Morris => vec!["mu_star", "mu", "sigma"],
        Method::Sobol => vec!["s1", "s1_lo95", "s1_hi95", "st", "st_lo95", "st_hi95"],
    };
    for (mi, m) in spec.metrics.iter().enumerate() {
        let ys = y(mi);
        match spec.method {
            Method::Oat => {
                let n = spec.samples;
                let mb = ys[0];
                for (i, p) in spec.params.iter().enumerate() {
                    let lv: Vec<(f64, f64)> = (0..n)
                        .map(|l| {
                            let r = &res.rows[1 + i * n + l];
                            (r.values[i], r.metrics[mi])
                        })
                        .collect();
                    let o = oat_index(&lv, p.base, mb);
                    rows.push((
                        m.name(),
                        p.path.clone(),
                        vec![p.lo, p.hi, p.base, mb, o.min, o.max, o.normalised],
                    ));
                }
            }
            Method::Morris => {
                let pts = spec.points();
                for (p, ix) in spec.params.iter().zip(morris_indices(&pts, &ys, k)) {
                    rows.push((m.name(), p.path.clone(), vec![ix.mu_star, ix.mu, ix.sigma]));
                }
            }
            Method::Sobol => {
                for (p, ix) in spec.params.iter().zip(sobol_indices(&ys, k, spec.seed)) {
                    rows.push((
                        m.name(),
                        p.path.clone(),
                        vec![
                            ix.s1,
                            ix.s1_ci[0],
                            ix.s1_ci[1],
                            ix.st,
                            ix.st_ci[0],
                            ix.st_ci[1],
                        ],
                    ));
                }
            }
        }
    }
    (header, rows)
}

/// `indices.csv` text.
pub fn indices_csv(res: &Results) -> String {
    let (h, rows) = indices(res);
    let mut s = format!("metric,parameter,{}\n", h.join(","));
    for (m, p, v) in rows {
        s.push_str(&format!("{m},{p}"));
        for x in v {
            s.push_str(&format!(",{}", super::num(x)));
        }
        s.push('\n');
    }
    s
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
    set.add("indices.csv", indices_csv(res));
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
    let (h, rows) = indices(res);
    let mut cols = vec![Column::plain("metric"), Column::plain("parameter")];
    cols.extend(h.iter().map(|c| Column::plain(*c)));
    let mut t = Table::new("Indices (indices.csv)", cols);
    for (m, p, v) in &rows {
        let mut r = vec![Cell::text(m.clone()), Cell::text(p.clone())];
        r.extend(v.iter().map(|x| Cell::text(sig(*x, 4))));
        t.push(r).map_err(plot_err)?;
    }
    page.section("Indices");
    page.text(match spec.method {
        Method::Oat => "One at a time (the paper's Fig. 3): each parameter over its range at the given levels, the others at the phantom's values. normalised_sensitivity = (metric at the highest level − at the lowest)/(highest − lowest) × base value / metric at base.",
        Method::Morris => "Morris elementary effects (Morris 1991; μ* of Campolongo et al. 2007) on a 4-level grid, Δ = 2/3 of the range in the sampling coordinate (log for log-uniform parameters); μ*, μ and σ are in metric units per whole range of that coordinate.",
        Method::Sobol => "Sobol' indices from Saltelli's A, B, A_B^i design (Saltelli et al. 2010): first order S1 with their estimator (b), total ST with Jansen's (f); 95 % percentile intervals from 500 bootstrap resamples of the N base rows.",
    });
    page.table(&t);
    for (mi, m) in spec.metrics.iter().enumerate() {
        let mrows: Vec<&IndexRow> = rows.iter().filter(|r| r.0 == m.name()).collect();
        let cats: Vec<String> = mrows.iter().map(|r| r.1.clone()).collect();
        let (groups, values, title, ylab): (Vec<String>, Vec<Vec<f64>>, String, String) =
            match spec.method {
                Method::Oat => (
                    vec![
                        "lowest metric − base".into(),
                        "highest metric − base".into(),
                    ],
                    mrows
                        .iter()
                        .map(|r| vec![r.2[4] - r.2[3], r.2[5] - r.2[3]])
                        .collect(),
                    format!("Tornado: range of {} over each parameter's range", m.name()),
                    format!("{} − base ({})", m.name(), m.unit()),
                ),
                Method::Morris => (
                    vec!["μ*".into(), "σ".into()],
                    mrows.iter().map(|r| vec![r.2[0], r.2[2]]).collect(),
                    format!("Morris μ* and σ of {}", m.name()),
                    format!("{} per range ({})", m.name(), m.unit()),
                ),
                Method::Sobol => (
                    vec![
                        "S1".into(),
                        "S1 upper 95 %".into(),
                        "ST".into(),
                        "ST upper 95 %".into(),
                    ],
                    mrows
                        .iter()
                        .map(|r| vec![r.2[0], r.2[2], r.2[3], r.2[5]])
                        .collect(),
                    format!("Sobol' indices of {}", m.name()),
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
        let svg = chart.to_svg().map_err(plot_err)?;
        page.heading(3, m.name());
        page.figure(
            &svg,
            Some(&file),
            match spec.method {
                Method::Sobol => "Bars: point estimates and the upper ends of their 95 % bootstrap intervals (the lower ends are in the table).",
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
                format!("Radius as {} varies", p.path),
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
                plot = plot.with(Series::new(format!("{} = {}", p.path, sig(v, 3)), pts));
            }
            let file = format!("courses-{i}.svg");
            let svg = plot.to_svg().map_err(plot_err)?;
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
