//! Diffusion-kernel throughput (cell-updates per second) and one short end-to-end run.
//! `cargo bench --bench kernel -- --warm-up-time 1 --measurement-time 5`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use decophantom::gas::GasMix;
use decophantom::phantom::diffusion;
use decophantom::phantom::displacement;
use decophantom::phantom::fields::Fields;
use decophantom::phantom::grid::{Face, Grid, Shape};
use decophantom::phantom::params::{BubblePlacement, PhantomParams};
use decophantom::phantom::sim::{Recorder, Simulation};
use decophantom::profile::PressureHistory;
use decophantom::units::PSI_PA;

const H: f64 = 1e-4;
const D: f64 = 2.5e-9;

fn grid(n: [usize; 3]) -> Grid {
    let size = [n[0] as f64 * H, n[1] as f64 * H, n[2] as f64 * H];
    let open = [
        Face::XMinus,
        Face::XPlus,
        Face::YMinus,
        Face::YPlus,
        Face::Top,
    ];
    Grid::new(Shape::Box { size }, H, &open).unwrap()
}

/// The Fig. 5 grid: a cylinder 11 mm across and 5 mm deep at h = 86.5 µm (127×127×58
/// cells), open top and side.
fn fig5_cylinder() -> Grid {
    Grid::new(
        Shape::Cylinder {
            diameter: 11e-3,
            depth: 5e-3,
        },
        86.5e-6,
        &[Face::Top, Face::Side],
    )
    .unwrap()
}

fn kernels(c: &mut Criterion) {
    let mut group = c.benchmark_group("diffusion");
    let cases = [
        ("128x128x32".to_string(), grid([128, 128, 32])),
        ("128x128x128".to_string(), grid([128, 128, 128])),
        ("60x60x60".to_string(), grid([60, 60, 60])),
        ("cyl127x127x58".to_string(), fig5_cylinder()),
    ];
    for (label, g) in &cases {
        let cells = g.len() as u64;
        group.throughput(Throughput::Elements(cells));
        let u0: Vec<f64> = (0..g.len()).map(|i| 1.0 + (i % 17) as f64 * 0.01).collect();
        let dt_explicit = 0.9 * diffusion::explicit_limit(g, D);
        group.bench_with_input(BenchmarkId::new("explicit_step", label), g, |b, g| {
            let u = u0.clone();
            let mut out = vec![0.0; g.len()];
            b.iter(|| diffusion::explicit_step(g, &u, &mut out, D, dt_explicit, 0.5))
        });
        // two gases as the simulation steps them, one field after the other (an iteration is
        // one gas-step): out of place through one scratch field swapped in, and in place
        group.bench_with_input(
            BenchmarkId::new("explicit_step_two_fields", label),
            g,
            |b, g| {
                let mut fields = [u0.clone(), u0.clone()];
                let mut scratch = vec![0.0; g.len()];
                let mut q = 0;
                b.iter(|| {
                    q ^= 1;
                    let f =
                        diffusion::explicit_step(g, &fields[q], &mut scratch, D, dt_explicit, 0.5);
                    std::mem::swap(&mut fields[q], &mut scratch);
                    f
                })
            },
        );
        group.bench_with_input(
            BenchmarkId::new("explicit_step_in_place_two_fields", label),
            g,
            |b, g| {
                let mut fields = [u0.clone(), u0.clone()];
                let mut q = 0;
                b.iter(|| {
                    q ^= 1;
                    diffusion::explicit_step_in_place(g, &mut fields[q], D, dt_explicit, 0.5)
                })
            },
        );
        // two gases with a thread per field, as a run with as many gases as threads steps them
        // (an iteration steps both fields: two gas-steps): each field moved by two planes in
        // its store, and the same with a copy of each plane's old values (session 24)
        let dc = [(D, 0.5), (D, 0.5)];
        group.throughput(Throughput::Elements(2 * cells));
        group.bench_with_input(
            BenchmarkId::new("explicit_steps_per_field_shifting", label),
            g,
            |b, g| {
                let mut fields = Fields::new(vec![u0.clone(), u0.clone()], g.n[0] * g.n[1]);
                let mut inflow = [0.0; 2];
                b.iter(|| {
                    let (mut stores, from) = fields.stores_for_shift();
                    let to = diffusion::explicit_steps_shifting_per_field(
                        g,
                        &mut stores,
                        from,
                        &dc,
                        dt_explicit,
                        &mut inflow,
                    );
                    fields.shifted(to);
                    inflow[0]
                })
            },
        );
        group.bench_with_input(
            BenchmarkId::new("explicit_steps_per_field_copying", label),
            g,
            |b, g| {
                let mut fields = [u0.clone(), u0.clone()];
                let mut inflow = [0.0; 2];
                b.iter(|| {
                    let [f0, f1] = &mut fields;
                    let mut views = [f0.as_mut_slice(), f1.as_mut_slice()];
                    diffusion::explicit_steps_in_place_per_field(
                        g,
                        &mut views,
                        &dc,
                        dt_explicit,
                        &mut inflow,
                    );
                    inflow[0]
                })
            },
        );
        group.throughput(Throughput::Elements(cells));
        group.bench_with_input(BenchmarkId::new("implicit_step", label), g, |b, g| {
            let mut u = u0.clone();
            let mut solver = diffusion::ImplicitSolver::new();
            b.iter(|| solver.step(g, &mut u, D, 20.0, 0.5))
        });
        group.bench_with_input(
            BenchmarkId::new("implicit_step_generic", label),
            g,
            |b, g| {
                let mut u = u0.clone();
                let mut scratch = vec![0.0; g.len()];
                b.iter(|| diffusion::implicit_step(g, &mut u, &mut scratch, D, 20.0, 0.5))
            },
        );
        // memory-bandwidth reference: a parallel triad a = b + s·c over three fields of the
        // grid's size (24 bytes moved per element, plus the write-allocate of `a`)
        group.bench_function(BenchmarkId::new("triad", label), |bch| {
            use rayon::prelude::*;
            let mut a = vec![0.0f64; g.len()];
            let b = u0.clone();
            let cc = u0.clone();
            bch.iter(|| {
                a.par_chunks_mut(4096)
                    .zip(b.par_chunks(4096).zip(cc.par_chunks(4096)))
                    .for_each(|(a, (b, c))| {
                        for ((x, y), z) in a.iter_mut().zip(b).zip(c) {
                            *x = y + 0.5 * z;
                        }
                    });
                a[0]
            })
        });
    }
    group.finish();
}

/// The oscillation experiment's set-up, shortened: 12.8 × 12.8 × 3.2 mm, h = 100 µm, three
/// bubbles, one 0–20 psi gauge cycle (30 s half-period).
fn end_to_end(c: &mut Criterion) {
    let mut params = PhantomParams::box_phantom([12.8e-3, 12.8e-3, 3.2e-3], H);
    params.bubbles = BubblePlacement::Explicit(vec![
        ([4e-3, 4e-3, 1.6e-3], 150e-6),
        ([8e-3, 6e-3, 1.6e-3], 150e-6),
        ([6e-3, 9e-3, 1.6e-3], 150e-6),
    ]);
    params.numerics.record_interval = 1.0;
    let s = 101_325.0;
    let profile = PressureHistory::with_gas(
        "oscillation",
        vec![0.0, 30.0, 60.0],
        vec![s, s + 20.0 * PSI_PA, s],
        GasMix::AIR,
        0.0,
    )
    .unwrap();
    let mut group = c.benchmark_group("end_to_end");
    group.sample_size(10);
    group.bench_function("oscillation_60s_128x128x32", |b| {
        b.iter(|| {
            let mut sim = Simulation::new(&params, &profile).unwrap();
            sim.run(&profile, &mut Recorder::default()).unwrap()
        })
    });
    group.finish();
}

/// The gel's displacement by a grown bubble ([`displacement::remap`]) as the Fig. 5 dive's
/// largest bubble takes it: R = 850 µm growing by 0.1 h in the middle of the Fig. 5 cylinder,
/// its cells taken out of the gel, two gases, out to 3R + 2h (`displace_reach`). Throughput in
/// cells remapped.
fn remap(c: &mut Criterion) {
    let mut g = fig5_cylinder();
    let h = g.h;
    let centre = [5.5e-3, 5.5e-3, 2.5e-3];
    let (r0, r1) = (850e-6, 850e-6 + 0.1 * h);
    let inner = displacement::covered_cells(&g, centre, r0);
    g.set_excluded(&inner, true);
    let fields: Vec<Vec<f64>> = (0..2)
        .map(|f| {
            (0..g.len())
                .map(|i| {
                    if g.inside(i) {
                        1.0 + ((i * (f + 3)) % 29) as f64 * 0.01
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    let reach = 3.0 * r1 + 2.0 * h;
    let n: usize = displacement::remap(&g, &fields, &[1.2, 0.8], centre, r0, r1, reach)
        .iter()
        .map(Vec::len)
        .sum();
    let mut group = c.benchmark_group("displacement");
    group.throughput(Throughput::Elements(n as u64));
    group.bench_function("remap/fig5_R850um", |b| {
        b.iter(|| displacement::remap(&g, &fields, &[1.2, 0.8], centre, r0, r1, reach))
    });
    group.finish();
}

criterion_group!(benches, kernels, remap, end_to_end);
criterion_main!(benches);
