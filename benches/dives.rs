//! End-to-end wall time of the named runs in the README, through the same library calls as
//! `decophantom simulate`: the paper's oscillation experiment and its Fig. 5 dive.
//! `cargo bench --bench dives` (about 2–3 minutes: ten samples of each).

use criterion::{criterion_group, criterion_main, Criterion};
use decophantom::phantom::config::load_phantom;
use decophantom::profile::{load, LoadOptions};
use decophantom::run::simulate;
use std::path::Path;
use std::time::Duration;

fn run(c: &mut Criterion, name: &str, profile: &str, phantom: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let history = load(&root.join(profile), &LoadOptions::default()).unwrap();
    let params = load_phantom(&root.join(phantom)).unwrap().params;
    let mut group = c.benchmark_group("dives");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    group.bench_function(name, |b| {
        b.iter(|| simulate(&params, &history, &mut |_, _| {}).unwrap())
    });
    group.finish();
}

fn dives(c: &mut Criterion) {
    run(
        c,
        "oscillation_300s_524k_cells",
        "profiles/oscillation-30s.toml",
        "profiles/phantoms/oscillation.toml",
    );
    run(
        c,
        "fig5_dive_6h_733k_cells",
        "profiles/fig5-dive.toml",
        "profiles/phantoms/hydrogel.toml",
    );
}

criterion_group!(benches, dives);
criterion_main!(benches);
