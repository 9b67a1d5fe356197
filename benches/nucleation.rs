//! Cost of the nucleus pool (issue 12, "Performance"): the Fig. 5 dive in the Fig. 5 hydrogel
//! with its 3 fixed bubbles, against the same run with 10 000 `critical-radius` nuclei as well.
//! The nuclei are drawn small (mean radius 1/β = 10 nm), so that the supersaturation of this
//! dive (at most ~9e5 Pa: critical radius 2γ/s ≥ 0.16 µm) activates none of them
//! (expected e^(−16)·10 000 ≈ 1e-3): the bench measures what the pool costs every step (one
//! tension per occupied cell, a threshold compare per nucleus), not the bubbles it would make,
//! which cost as any bubble does. `cargo bench --bench nucleation` (about 15 minutes: 10 runs
//! of ~40 s per case).

use criterion::{criterion_group, criterion_main, Criterion};
use decophantom::phantom::config::load_phantom;
use decophantom::phantom::nucleation::critical_radius::{CriticalRadius, SizeDistribution};
use decophantom::profile::{load, LoadOptions};
use decophantom::run::simulate;
use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

fn nucleation(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let history = load(
        &root.join("profiles/fig5-dive.toml"),
        &LoadOptions::default(),
    )
    .unwrap();
    let fixed = load_phantom(&root.join("profiles/phantoms/hydrogel.toml"))
        .unwrap()
        .params;
    let mut nuclei = fixed.clone();
    // the gel volume of the 11 mm × 5 mm cylinder, π·5.5²·5 mm³ = 475 mm³: 10 000 nuclei
    let volume = std::f64::consts::PI * 5.5e-3f64.powi(2) * 5e-3;
    nuclei.nucleation = Arc::new(CriticalRadius {
        number_density: 10_000.0 / volume,
        distribution: SizeDistribution::Exponential { slope: 1e8 },
        margin: None,
        seed: 2017,
        skin_compression: None,
    });
    let mut group = c.benchmark_group("nucleation");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(20));
    group.bench_function("fig5_dive_3_fixed_bubbles", |b| {
        b.iter(|| simulate(&fixed, &history, &mut |_, _| {}).unwrap())
    });
    group.bench_function("fig5_dive_3_fixed_bubbles_10k_nuclei", |b| {
        b.iter(|| simulate(&nuclei, &history, &mut |_, _| {}).unwrap())
    });
    group.finish();
}

criterion_group!(benches, nucleation);
criterion_main!(benches);
