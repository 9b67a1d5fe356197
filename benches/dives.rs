//! End-to-end wall time of the named runs in the README, through the same library calls as
//! `decophantom simulate`: the paper's oscillation experiment, its Fig. 5 dive, and the demo's
//! GF 30/85 dive with its stops (`benches/gf30-85-dive/schedule.toml` through
//! `hydrogel-dive.toml`, whose holds and stops take extrapolated steps).
//! `cargo bench --bench dives` (about 3–4 minutes: ten samples of each).

use criterion::{criterion_group, criterion_main, Criterion};
use decophantom::phantom::config::load_phantom;
use decophantom::profile::LoadOptions;
use decophantom::run::{load_profile_or_schedule, simulate};
use std::path::Path;
use std::time::Duration;

fn run(c: &mut Criterion, name: &str, profile: &str, phantom: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let history = load_profile_or_schedule(&root.join(profile), &LoadOptions::default()).unwrap();
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
        "gf30_85_45m_25min_stops_244k_cells",
        "benches/gf30-85-dive/schedule.toml",
        "profiles/phantoms/hydrogel-dive.toml",
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
