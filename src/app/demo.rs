//! `decophantom demo`: the built-in example, written as one report. First a dive: 45 m for
//! 25 min on air planned by ZH-L16C GF 30/85, GF 50/80 and VPM-B +2 (and GF 100/100 as an
//! aggressive reference), each schedule run
//! through the hydrogel-dive phantom under every tissue-elasticity law and scored with
//! `algorithms/criteria/default.toml` (the `evaluate` path). Then the paper's oscillation
//! experiment (§4.1) under each law, and the laws without mass transfer (the paper's Fig. 2a).
//! Every input is compiled in, so the demo runs from any folder.

use crate::error::Error;
use crate::evaluate::link::{PhantomSpec, HYDROGEL_PHANTOM, HYDROGEL_PHANTOM_PATH};
use crate::evaluate::matrix::run_matrix;
use crate::evaluate::report::{add_report, finish_page, ReportContext};
use crate::evaluate::tables::summary_text;
use crate::evaluate::{algorithms_from_text, plan_candidates};
use crate::phantom::config::parse_phantom;
use crate::phantom::elasticity::{law_names, AllLawParams};
use crate::phantom::elasticity_compare::{compare, ElasticityRequest};
use crate::phantom::sim::StepWall;
use crate::profile::toml as profile_toml;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::plot::{LinePlot, Series};
use crate::report::table::{Cell, Column, Table};
use crate::risk::parse_criteria;
use crate::run::files::add_run_files;
use crate::run::plots::radius_plot;
use crate::run::text::{describe, describe_results};
use crate::run::{simulate, SimRun};
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;

/// The built-in oscillation profile (a copy of `profiles/oscillation-30s.toml`, compiled in so
/// the demo runs from any folder).
pub const OSCILLATION_PROFILE: &str = include_str!("../../profiles/oscillation-30s.toml");
/// The built-in phantom (`profiles/phantoms/oscillation.toml`).
pub const OSCILLATION_PHANTOM: &str = include_str!("../../profiles/phantoms/oscillation.toml");
/// The demo's algorithms (text, path named in messages and tables).
pub const DEMO_ALGORITHMS: [(&str, &str); 4] = [
    (
        include_str!("../../algorithms/zhl16c-gf30-85.toml"),
        "algorithms/zhl16c-gf30-85.toml",
    ),
    (
        include_str!("../../algorithms/zhl16c-gf50-80.toml"),
        "algorithms/zhl16c-gf50-80.toml",
    ),
    (
        include_str!("../../algorithms/vpmb-2-baker.toml"),
        "algorithms/vpmb-2-baker.toml",
    ),
    // an aggressive reference (no gradient-factor margin), so the report shows what failing
    // the criteria looks like
    (
        include_str!("../../algorithms/zhl16c-gf100-100.toml"),
        "algorithms/zhl16c-gf100-100.toml",
    ),
];
/// The demo's criteria (`algorithms/criteria/default.toml`).
pub const DEMO_CRITERIA: &str = include_str!("../../algorithms/criteria/default.toml");
/// The demo dive: depth m, bottom time min.
pub const DEMO_DIVE: (f64, f64) = (45.0, 25.0);

fn plot_err(e: impl std::fmt::Display) -> Error {
    Error::Solver(format!("plot: {e}"))
}

/// The grids of the demo's two phantoms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DemoSize {
    /// Grid step of the dive phantom, m (`None`: the file's, 125 µm).
    pub dive_grid_step_m: Option<f64>,
    /// Grid step of the oscillation phantom, m (`None`: the file's, 100 µm).
    pub oscillation_grid_step_m: Option<f64>,
}

impl DemoSize {
    /// The demo as `decophantom demo` runs it.
    pub const FULL: DemoSize = DemoSize {
        dive_grid_step_m: None,
        oscillation_grid_step_m: None,
    };
    /// The same report on grids 2× coarser (8× fewer cells), for tests of the figures: the
    /// numbers differ, every file and figure is there.
    pub const REDUCED: DemoSize = DemoSize {
        dive_grid_step_m: Some(250e-6),
        oscillation_grid_step_m: Some(200e-6),
    };
}

/// Run the demo and write `out`; returns a short text summary. `progress(done, total)` counts
/// phantom runs (dive schedules × laws, then one oscillation run per law).
pub fn run(out: &Path, progress: &mut (dyn FnMut(f64, f64) + Send)) -> Result<String, Error> {
    run_sized(out, DemoSize::FULL, progress)
}

/// [`run`] on the grids of `size`.
pub fn run_sized(
    out: &Path,
    size: DemoSize,
    progress: &mut (dyn FnMut(f64, f64) + Send),
) -> Result<String, Error> {
    // 1. the dive
    let criteria = parse_criteria(DEMO_CRITERIA, Path::new("algorithms/criteria/default.toml"))?;
    let spec = PhantomSpec::from_text(
        HYDROGEL_PHANTOM,
        Path::new(HYDROGEL_PHANTOM_PATH),
        HYDROGEL_PHANTOM_PATH,
        size.dive_grid_step_m,
    )?;
    let laws = spec.resolve_laws(&["all".to_string()])?;
    let algs = algorithms_from_text(&DEMO_ALGORITHMS)?;
    let candidates = plan_candidates(
        &algs,
        DEMO_DIVE.0,
        DEMO_DIVE.1,
        None,
        &[],
        &[],
        &criteria.protocol,
        None,
    )?;
    let dive_runs = laws.len() as f64 * candidates.len() as f64;
    let total_runs = dive_runs + law_names().len() as f64;
    let ev = {
        let mut cb = |d: f64, _: f64| progress(d, total_runs);
        run_matrix(candidates, spec, laws, criteria, &mut cb)?
    };
    let dive = format!("{} m for {} min on air", DEMO_DIVE.0, DEMO_DIVE.1);
    let mut page = Page::new(format!(
        "decophantom demo: a {dive} dive through the hydrogel phantom, and the oscillation experiment"
    ));
    let mut set = OutputSet::new();
    page.text("This report is produced by `cargo run --release -- demo`. Part 1 evaluates one dive planned by three algorithms, and by ZH-L16C GF 100/100 as an aggressive reference, through the hydrogel phantom under every tissue-elasticity law, exactly as `decophantom evaluate --depth 45 --time 25 --algorithm algorithms/zhl16c-gf30-85.toml --algorithm algorithms/zhl16c-gf50-80.toml --algorithm algorithms/vpmb-2-baker.toml --algorithm algorithms/zhl16c-gf100-100.toml --elasticity all --criteria algorithms/criteria/default.toml` does. The phantom is `profiles/phantoms/hydrogel-dive.toml`: the Fig. 5 hydrogel at a grid step of 125 µm instead of 86.5 µm (about 3× fewer cells; the whole demo takes under a minute on two cores) with the nuclei unchanged (R0 = 86.5 µm, R_min = 80 µm). Part 2 is the paper's oscillation experiment (§4.1).");
    page.section(format!("Part 1 — the dive: {dive}"));
    add_report(
        &mut page,
        &mut set,
        "",
        &ev,
        &ReportContext {
            dive: format!("{dive}, planned by each algorithm"),
            criteria_source: "algorithms/criteria/default.toml".into(),
            repeat_after_min: None,
            command: None,
        },
    )?;

    // 2. the oscillation experiment
    let profile = profile_toml::parse(
        OSCILLATION_PROFILE,
        Path::new("profiles/oscillation-30s.toml"),
    )?
    .history;
    let phantom = parse_phantom(
        OSCILLATION_PHANTOM,
        Path::new("profiles/phantoms/oscillation.toml"),
    )?;
    let mut base = phantom.params.clone();
    if let Some(h) = size.oscillation_grid_step_m {
        base.grid_step = h;
    }
    let mu = 40.0;
    let laws = AllLawParams {
        shear_modulus: mu,
        bulk_modulus_per_volume: 5e16,
        bulk_modulus: 2.2e9,
    };
    // one run per elasticity law, in parallel; progress counts runs
    let names = law_names();
    let main_idx = names.iter().position(|n| *n == "hyperelastic").unwrap_or(0);
    let progress = std::sync::Mutex::new((vec![0.0f64; names.len()], progress));
    let runs: Vec<Result<SimRun, Error>> = names
        .par_iter()
        .enumerate()
        .map(|(i, name)| {
            let mut p = base.clone();
            p.elasticity = Arc::from(laws.build(name).map_err(Error::Solver)?);
            p.name = format!("{} ({name})", base.name);
            // the other laws give only bubble 0's radius and the gas balance (the last
            // frame has the gel either way): their frames skip the gel's pass
            p.numerics.record_gel = i == main_idx;
            let mut cb = |t: f64, e: f64| {
                if let Ok(mut g) = progress.lock() {
                    let (fr, cb) = &mut *g;
                    fr[i] = if e > 0.0 {
                        (t / e).clamp(0.0, 1.0)
                    } else {
                        1.0
                    };
                    let done: f64 = fr.iter().sum();
                    (*cb)(dive_runs + done, total_runs)
                }
            };
            simulate(&p, &profile, &mut cb)
        })
        .collect();
    let runs: Vec<SimRun> = runs.into_iter().collect::<Result<_, _>>()?;
    add_run_files(
        &mut set,
        "oscillation/",
        &runs[main_idx],
        &profile.label,
        &base.name,
    )?;

    // elasticity comparison on the oscillation run
    let mut table = Table::new(
        "Elasticity laws on the oscillation experiment (bubble 0, R0 = 200 µm)",
        vec![
            Column::plain("law"),
            Column::new("growth_above_R0", "µm"),
            Column::new("min_radius_last_cycle", "µm"),
            Column::new("final_radius", "µm"),
            Column::plain("gas_balance_error"),
        ],
    );
    let mut overlay = LinePlot::new(
        "Bubble 0 radius under each elasticity law",
        "time (s)",
        "radius (µm)",
    );
    // four of the five laws give nearly the same curve: dashes and markers tell them apart
    overlay.distinct = true;
    for (name, run) in names.iter().zip(&runs) {
        let b0: Vec<(f64, f64)> = run
            .frames
            .iter()
            .filter_map(|f| {
                f.bubbles
                    .iter()
                    .find(|b| b.id == 0)
                    .map(|b| (f.time, b.radius * 1e6))
            })
            .collect();
        // the largest radius is R0 itself when the bubble never grows: report the growth
        let r0 = b0.first().map_or(f64::NAN, |x| x.1);
        let growth = b0.iter().map(|x| x.1 - r0).fold(0.0, f64::max);
        let last_cycle = b0
            .iter()
            .filter(|x| x.0 >= 240.0)
            .map(|x| x.1)
            .fold(f64::NAN, f64::min);
        let fin = b0.last().map_or(f64::NAN, |x| x.1);
        table
            .push(vec![
                Cell::text(*name),
                Cell::fixed(growth, 2),
                Cell::fixed(last_cycle, 2),
                Cell::fixed(fin, 2),
                Cell::sig(run.summary.gas_balance_error, 2),
            ])
            .map_err(Error::Solver)?;
        overlay = overlay.with(Series::new(*name, b0));
    }
    set.add(
        "elasticity-oscillation.csv",
        table.to_csv().map_err(Error::Solver)?,
    );
    // wall times apart from the results, so a regenerated report is byte-identical
    let mut timing = format!("law,wall_s,{}\n", StepWall::CSV_HEADER);
    for (name, run) in names.iter().zip(&runs) {
        timing.push_str(&format!(
            "{name},{},{}\n",
            run.wall_seconds,
            run.phases.csv_fields()
        ));
    }
    set.add("elasticity-oscillation-timing.csv", timing);
    set.add(
        "elasticity-oscillation.svg",
        overlay.to_svg().map_err(plot_err)?,
    );

    // Fig. 2a: no mass transfer, 1e6 -> 1e4 Pa
    let r0: Vec<f64> = (0..=30)
        .map(|i| 1e-6 * 10f64.powf(i as f64 / 10.0))
        .collect();
    let rows = compare(&ElasticityRequest {
        p0: 1e6,
        pf: 1e4,
        gamma: 0.07,
        laws,
        r0,
    })?;
    set.add(
        "elasticity-fig2a.csv",
        crate::phantom::elasticity_compare::to_csv(&rows),
    );
    let mut fig2a = LinePlot::new(
        "Final radius without mass transfer, 1e6 → 1e4 Pa (Fig. 2a)",
        "initial radius R0 (µm)",
        "final radius (µm)",
    );
    fig2a.log_x = true;
    fig2a.log_y = true;
    fig2a.distinct = true;
    for name in &names {
        let pts = rows
            .iter()
            .filter(|r| r.1 == *name)
            .filter_map(|r| r.2.map(|rf| (r.0 * 1e6, rf * 1e6)))
            .collect();
        fig2a = fig2a.with(Series::new(*name, pts));
    }
    set.add("elasticity-fig2a.svg", fig2a.to_svg().map_err(plot_err)?);

    // report
    let main = &runs[main_idx];
    page.section("Why the bubbles grow so little on this dive");
    page.text("The nuclei (R0 = 86.5 µm) are shut below R_min = 80 µm: compressed on the descent, they stay impermeable at depth and through the stops, and reopen only in the last metres of the ascent. Only the gas still in excess in the gel when the diver surfaces can then grow them, so the criteria separate the schedules by how much supersaturation each leaves at the surface — the long shallow stops of GF 30/85, GF 50/80 and VPM-B +2 leave little, GF 100/100 leaves more. Deeper, longer or faster dives, smaller R_min or larger nuclei give larger bubbles; see `decophantom simulate` with `profiles/fig5-dive.toml` for a saturation dive that grows them to several hundred µm.");
    page.section("Part 2 — the oscillation experiment of Walsh et al. 2017 (§4.1)");
    page.text(format!(
        "Profile: **{}** ({}). Phantom: **{}**. {}",
        profile.label,
        "0–20 psi gauge, 30 s half-period, 5 cycles",
        base.name,
        phantom.description.replace('\n', " ")
    ));
    page.heading(3, "Run (hyperelastic law)");
    page.pre(describe_results(main));
    page.figure(
        &radius_plot(&main.frames, "Bubble radius (hyperelastic)")
            .to_svg()
            .map_err(plot_err)?,
        Some("oscillation/radius.svg"),
        "Radius of each bubble over the five pressure cycles.",
    )
    .map_err(Error::Solver)?;
    page.heading(
        3,
        "Elasticity laws on the oscillation experiment (bubble 0, R0 = 200 µm)",
    );
    page.table(&table);
    page.figure(
        &overlay.to_svg().map_err(plot_err)?,
        Some("elasticity-oscillation.svg"),
        "Bubble 0 under each tissue-elasticity law.",
    )
    .map_err(Error::Solver)?;
    page.heading(3, "Elasticity laws without mass transfer (Fig. 2a)");
    page.figure(
        &fig2a.to_svg().map_err(plot_err)?,
        Some("elasticity-fig2a.svg"),
        "Final against initial radius for each law (γ = 0.07 N/m, μ = 40 Pa, M = 5e-2 Pa/µm³, K = 2.2 GPa; gas content fixed by the Laplace balance at 1e6 Pa); a missing point means no physical root. With μ = 40 Pa the shear-modulus forms stay within 2 % of Ω = 0 (measured from elasticity-fig2a.csv: 0.2 %, 1.8 %, 0.3 % for continuity of displacement, reference configuration, hyperelastic); only the Bulk-Modulus form (Ω grows as R³) departs, restricting large bubbles.",
    )
    .map_err(Error::Solver)?;
    page.text("Every number and figure here was produced by `cargo run --release -- demo`.");
    finish_page(&mut page, &mut set, "")?;
    set.commit(out)?;
    Ok(format!(
        "dive {dive}, ranking per elasticity law:\n{}oscillation experiment (hyperelastic):\n{}wrote {}\n",
        summary_text(&ev),
        describe(main),
        out.display()
    ))
}
