//! Session 29's paired harness (docs/speed-history.md, session 29): two fields stepped by
//! `ImplicitSolver::steps`, alternating call by call between equal D (solved together in one
//! pass, with docs/experiments/session29-fused-fields.patch applied; it applies to 5e747d2) and
//! D one ulp apart (each field its own pass, side by side: what the code does without the
//! patch). Make a cargo project with this file as src/main.rs and `decophantom = { path = "…" }`
//! as its dependency, build it with `--release`, run it (`BOX=1`: the 128×128×32 box open on
//! its sides and top instead of the Fig. 5 cylinder). It prints each variant's p10 and median
//! over the calls and the ratio of the medians (above 1: solving together is slower).
use decophantom::phantom::diffusion;
use decophantom::phantom::grid::{Face, Grid, Shape};
use std::time::Instant;

fn main() {
    let reps: usize = std::env::var("REPS")
        .ok()
        .map(|s| s.parse().unwrap())
        .unwrap_or(400);
    let g = if std::env::var("BOX").is_ok() {
        Grid::new(
            Shape::Box {
                size: [128e-4, 128e-4, 32e-4],
            },
            1e-4,
            &[
                Face::Top,
                Face::XMinus,
                Face::XPlus,
                Face::YMinus,
                Face::YPlus,
            ],
        )
    } else {
        Grid::new(
            Shape::Cylinder {
                diameter: 11e-3,
                depth: 5e-3,
            },
            86.5e-6,
            &[Face::Top, Face::Side],
        )
    }
    .unwrap();
    let d: f64 = 2.5e-9;
    let d1 = f64::from_bits(d.to_bits() + 1);
    let mut u: Vec<f64> = (0..g.len()).map(|i| 1.0 + (i % 17) as f64 * 0.01).collect();
    let mut v = u.clone();
    let mut solver = diffusion::ImplicitSolver::new();
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    let mut inflow = [0.0; 2];
    for rep in 0..reps {
        let b = rep % 2 == 1;
        let dd = if b { d } else { d1 };
        let t0 = Instant::now();
        let mut fields = [u.as_mut_slice(), v.as_mut_slice()];
        solver.steps(&g, &mut fields, &[(d, 0.5), (dd, 0.2)], 20.0, &mut inflow);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        if rep >= 10 {
            if b {
                tb.push(ms)
            } else {
                ta.push(ms)
            }
        }
    }
    let stats = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        (v[v.len() / 10], v[v.len() / 2])
    };
    let ((a10, am), (b10, bm)) = (stats(&mut ta), stats(&mut tb));
    println!("apart p10 {a10:.3} med {am:.3} ms | together p10 {b10:.3} med {bm:.3} ms | together/apart med {:.3}", bm / am);
}
