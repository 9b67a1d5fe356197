//! Session 23's paired harness (docs/speed-history.md, session 23): two variants of the
//! implicit step in one build, alternated call by call, so that the machine's drift hits both
//! alike. Use: apply docs/experiments/session23-x-sweep.patch, make a cargo project with this
//! file as src/main.rs and `decophantom = { path = "…" }` as its dependency, build it with
//! `--release`, and run it (`X1=1` switches `diffusion::EXP` on in the odd calls, `X2=1`
//! `diffusion::EXP2`; `BOX=1` takes the 128×128×32 box instead of the Fig. 5 cylinder). It
//! prints each variant's p10 and median over the calls, and the ratio of the medians.
use decophantom::phantom::diffusion;
use decophantom::phantom::grid::{Face, Grid, Shape};
use std::sync::atomic::Ordering;
use std::time::Instant;

fn main() {
    let reps: usize = std::env::var("REPS")
        .ok()
        .map(|s| s.parse().expect("REPS: a count"))
        .unwrap_or(400);
    let g = if std::env::var("BOX").is_ok() {
        Grid::new(Shape::Box { size: [128e-4, 128e-4, 32e-4] }, 1e-4, &[Face::Top])
    } else {
        Grid::new(
            Shape::Cylinder { diameter: 11e-3, depth: 5e-3 },
            86.5e-6,
            &[Face::Top, Face::Side],
        )
    }
    .expect("grid");
    let d = 2.5e-9;
    let mut u: Vec<f64> = (0..g.len()).map(|i| 1.0 + (i % 17) as f64 * 0.01).collect();
    let mut solver = diffusion::ImplicitSolver::new();
    let (x1, x2) = (std::env::var_os("X1").is_some(), std::env::var_os("X2").is_some());
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    for rep in 0..reps {
        let b = rep % 2 == 1;
        diffusion::EXP.store(b && x1, Ordering::Relaxed);
        diffusion::EXP2.store(b && x2, Ordering::Relaxed);
        let t0 = Instant::now();
        solver.step(&g, &mut u, d, 20.0, 0.5);
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        // the first calls build the plan and warm the caches
        if rep >= 10 {
            if b { tb.push(ms) } else { ta.push(ms) }
        }
    }
    let stats = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        (v[v.len() / 10], v[v.len() / 2])
    };
    let ((a10, am), (b10, bm)) = (stats(&mut ta), stats(&mut tb));
    println!("A p10 {a10:.3} med {am:.3} ms | B p10 {b10:.3} med {bm:.3} ms | B/A med {:.3}", bm / am);
}
