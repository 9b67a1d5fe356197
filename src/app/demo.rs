//! `decophantom demo`: the built-in example. Runs the paper's oscillation experiment (§4.1)
//! through the hydrogel phantom, compares the tissue-elasticity laws on the same run and
//! without mass transfer (the paper's Fig. 2a), and writes a report folder.

use super::elasticity::{compare, ElasticityRequest};
use super::simulate::{add_run_files, describe, radius_plot, simulate, SimRun};
use crate::error::Error;
use crate::phantom::config::parse_phantom;
use crate::phantom::elasticity::{law_names, AllLawParams};
use crate::profile::toml as profile_toml;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::plot::{LinePlot, Series};
use crate::report::table::{Cell, Column, Table};
use rayon::prelude::*;
use std::path::Path;
use std::sync::Arc;

/// The built-in oscillation profile (a copy of `profiles/oscillation-30s.toml`, compiled in so
/// the demo runs from any folder).
pub const OSCILLATION_PROFILE: &str = include_str!("../../profiles/oscillation-30s.toml");
/// The built-in phantom (`profiles/phantoms/oscillation.toml`).
pub const OSCILLATION_PHANTOM: &str = include_str!("../../profiles/phantoms/oscillation.toml");

fn plot_err(e: impl std::fmt::Display) -> Error {
    Error::Solver(format!("plot: {e}"))
}

/// Run the demo and write `out`; returns a short text summary.
pub fn run(out: &Path, progress: &mut (dyn FnMut(f64, f64) + Send)) -> Result<String, Error> {
    let profile = profile_toml::parse(
        OSCILLATION_PROFILE,
        Path::new("profiles/oscillation-30s.toml"),
    )?
    .history;
    let phantom = parse_phantom(
        OSCILLATION_PHANTOM,
        Path::new("profiles/phantoms/oscillation.toml"),
    )?;
    let base = phantom.params.clone();
    let mu = 40.0;
    let laws = AllLawParams {
        shear_modulus: mu,
        bulk_modulus_per_volume: 5e16,
        bulk_modulus: 2.2e9,
    };
    // one run per elasticity law, in parallel; progress is reported for the first
    let names = law_names();
    let progress = std::sync::Mutex::new(progress);
    let runs: Vec<Result<SimRun, Error>> = names
        .par_iter()
        .enumerate()
        .map(|(i, name)| {
            let mut p = base.clone();
            p.elasticity = Arc::from(laws.build(name).map_err(Error::Solver)?);
            p.name = format!("{} ({name})", base.name);
            let mut cb = |t: f64, e: f64| {
                if i == 0 {
                    if let Ok(mut g) = progress.lock() {
                        (*g)(t, e)
                    }
                }
            };
            simulate(&p, &profile, &mut cb)
        })
        .collect();
    let runs: Vec<SimRun> = runs.into_iter().collect::<Result<_, _>>()?;
    let main_idx = names.iter().position(|n| *n == "hyperelastic").unwrap_or(0);
    let mut set = OutputSet::new();
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
            Column::new("max_radius", "µm"),
            Column::new("min_radius_last_cycle", "µm"),
            Column::new("final_radius", "µm"),
            Column::new("gas_balance_error", ""),
            Column::new("wall", "s"),
        ],
    );
    let mut overlay = LinePlot::new(
        "Bubble 0 radius under each elasticity law",
        "time (s)",
        "radius (µm)",
    );
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
        let max = b0.iter().map(|x| x.1).fold(f64::NAN, f64::max);
        let last_cycle = b0
            .iter()
            .filter(|x| x.0 >= 240.0)
            .map(|x| x.1)
            .fold(f64::NAN, f64::min);
        let fin = b0.last().map_or(f64::NAN, |x| x.1);
        table
            .push(vec![
                Cell::text(*name),
                Cell::fixed(max, 2),
                Cell::fixed(last_cycle, 2),
                Cell::fixed(fin, 2),
                Cell::sci(run.summary.gas_balance_error, 2),
                Cell::fixed(run.wall_seconds, 2),
            ])
            .map_err(Error::Solver)?;
        overlay = overlay.with(Series::new(*name, b0));
    }
    set.add(
        "elasticity-oscillation.csv",
        table.to_csv().map_err(Error::Solver)?,
    );
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
    set.add("elasticity-fig2a.csv", super::elasticity::to_csv(&rows));
    let mut fig2a = LinePlot::new(
        "Final radius without mass transfer, 1e6 → 1e4 Pa (Fig. 2a; γ = 0.07 N/m, μ = 40 Pa, M = 5e-2 Pa/µm³, K = 2.2 GPa)",
        "initial radius R0 (µm, log10)",
        "final radius (µm)",
    );
    fig2a.log_y = true;
    for name in &names {
        let pts = rows
            .iter()
            .filter(|r| r.1 == *name)
            .filter_map(|r| r.2.map(|rf| (r.0.log10() + 6.0, rf * 1e6)))
            .collect();
        fig2a = fig2a.with(Series::new(*name, pts));
    }
    set.add("elasticity-fig2a.svg", fig2a.to_svg().map_err(plot_err)?);

    // report
    let main = &runs[main_idx];
    let mut page =
        Page::new("decophantom demo: the oscillation experiment of Walsh et al. 2017 (§4.1)");
    page.text(format!(
        "Profile: **{}** ({}). Phantom: **{}**. {}",
        profile.label,
        "0–20 psi gauge, 30 s half-period, 5 cycles",
        base.name,
        phantom.description.replace('\n', " ")
    ));
    page.section("Run (hyperelastic law)");
    page.pre(describe(main));
    page.figure(
        &radius_plot(&main.frames, "Bubble radius (hyperelastic)")
            .to_svg()
            .map_err(plot_err)?,
        Some("oscillation/radius.svg"),
        "Radius of each bubble over the five pressure cycles.",
    )
    .map_err(Error::Solver)?;
    page.section("Elasticity laws compared on the same run");
    page.table(&table);
    page.figure(
        &overlay.to_svg().map_err(plot_err)?,
        Some("elasticity-oscillation.svg"),
        "Bubble 0 under each tissue-elasticity law.",
    )
    .map_err(Error::Solver)?;
    page.section("Elasticity laws without mass transfer (Fig. 2a)");
    page.figure(
        &fig2a.to_svg().map_err(plot_err)?,
        Some("elasticity-fig2a.svg"),
        "Final against initial radius for each law; a missing point means no physical root.",
    )
    .map_err(Error::Solver)?;
    page.text("Every number and figure here was produced by `cargo run --release -- demo`.");
    set.add("report.html", page.to_html().map_err(Error::Solver)?);
    set.add("report.md", page.to_markdown().map_err(Error::Solver)?);
    set.commit(out)?;
    Ok(format!("{}wrote {}\n", describe(main), out.display()))
}
