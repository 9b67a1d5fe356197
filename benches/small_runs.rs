//! Small runs are cheap (issue 13): the reference small case that fits and sweeps run by the
//! thousand, `benches/small-cube/` — one 60 µm nucleus at the centre of a 6 mm hydrogel cube
//! open on every face, h = 100 µm (60³ = 216 000 cells), saturated at 60 psi gauge in air,
//! decompressed to 0 in 10 s and followed for 290 s (300 s in all), frames recorded every step
//! without the gel pass (`record_gel = false`), as `fit` and `discover` record them.
//!
//! - `small_runs/one_run/{1,2}_threads`: one run, its grid loops on one thread
//!   ([`GridThreads::Serial`]) or on the global pool;
//! - `small_runs/8_runs_parallel/{nested,serial}`: 8 runs at once through rayon (run-level
//!   parallelism), each with its grid loops on the same pool (nested) or serial inside
//!   ([`GridThreads::Parallel`] / [`GridThreads::Serial`]).
//!
//! - `small_runs/setup`: what a run costs before its first step, [`Simulation::new`] (the grid,
//!   its step-limit scans, the fields and the bubbles), on the global pool.
//!
//! Runs per second = runs / time. `cargo bench --bench small_runs` (about 2 minutes).
//! `SMALL_RUNS_SIZE_MM=12` (say) runs the same case in a bigger cube (same h), to place the
//! threshold of [`GridThreads::Auto`].

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use decophantom::phantom::config::load_phantom;
use decophantom::phantom::grid::Shape;
use decophantom::phantom::sim::Simulation;
use decophantom::profile::{load, LoadOptions};
use decophantom::run::{simulate, with_grid_threads, GridThreads};
use rayon::prelude::*;
use std::path::Path;
use std::time::Duration;

const RUNS: usize = 8;

fn small_runs(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/small-cube");
    let history = load(&root.join("profile.toml"), &LoadOptions::default()).unwrap();
    let mut params = load_phantom(&root.join("phantom.toml")).unwrap().params;
    params.numerics.record_gel = false;
    let mut tag = String::new();
    if let Some(mm) = std::env::var("SMALL_RUNS_SIZE_MM")
        .ok()
        .and_then(|s| s.parse::<f64>().ok())
    {
        let s = mm * 1e-3;
        params.shape = Shape::Box { size: [s; 3] };
        params.bubbles =
            decophantom::phantom::params::BubblePlacement::Explicit(vec![([s / 2.0; 3], 60e-6)]);
        tag = format!("_{mm}mm");
    }
    let one = |mode: GridThreads| {
        with_grid_threads(mode, &params, || {
            simulate(&params, &history, &mut |_, _| {}).unwrap()
        })
    };
    let mut group = c.benchmark_group("small_runs");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10));
    group.throughput(Throughput::Elements(1));
    group.bench_function(format!("setup{tag}"), |b| {
        b.iter(|| rayon::scope(|_| Simulation::new(&params, &history).unwrap().time()))
    });
    group.bench_function(format!("one_run{tag}/1_thread"), |b| {
        b.iter(|| one(GridThreads::Serial))
    });
    group.bench_function(format!("one_run{tag}/2_threads"), |b| {
        b.iter(|| one(GridThreads::Parallel))
    });
    group.throughput(Throughput::Elements(RUNS as u64));
    for (name, mode) in [
        ("nested", GridThreads::Parallel),
        ("serial", GridThreads::Serial),
    ] {
        group.bench_function(format!("{RUNS}_runs_parallel{tag}/{name}"), |b| {
            b.iter(|| {
                (0..RUNS)
                    .into_par_iter()
                    .map(|_| one(mode).summary.steps)
                    .collect::<Vec<_>>()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, small_runs);
criterion_main!(benches);
