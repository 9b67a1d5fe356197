//! Session 24's paired harness for the in-place explicit step with one field per thread (the
//! lone small run's kernel; docs/speed-history.md, session 24): the small cube (60³, h = 100 µm,
//! every face open), two fields, steps at 0.9 of the explicit limit, 2 000 calls; the odd calls
//! with `diffusion::EXP` set when X1 is given. Use as session 23's harness: a variant behind a
//! `pub static EXP: AtomicBool` in `src/phantom/diffusion.rs`, a cargo project with this file as
//! src/main.rs and decophantom as a path dependency, `--release`. It prints each half's p10 and
//! median and the ratio of the medians.
use decophantom::phantom::diffusion;
use decophantom::phantom::grid::{Face, Grid, Shape};
use std::sync::atomic::Ordering;
use std::time::Instant;

fn main() {
    let reps: usize = std::env::var("REPS").ok().map(|s| s.parse().unwrap()).unwrap_or(2000);
    let all = [Face::XMinus, Face::XPlus, Face::YMinus, Face::YPlus, Face::Top, Face::Bottom];
    let g = Grid::new(Shape::Box { size: [6e-3, 6e-3, 6e-3] }, 1e-4, &all).expect("grid");
    let d = 2.5e-9;
    let dt = 0.9 * diffusion::explicit_limit(&g, d);
    let mut a: Vec<f64> = (0..g.len()).map(|i| 1.0 + (i % 17) as f64 * 0.01).collect();
    let mut b = a.clone();
    let x1 = std::env::var_os("X1").is_some();
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    let mut inflow = [0.0; 2];
    for rep in 0..reps {
        let odd = rep % 2 == 1;
        diffusion::EXP.store(odd && x1, Ordering::Relaxed);
        let t0 = Instant::now();
        diffusion::explicit_steps_in_place_per_field(
            &g,
            &mut [&mut a[..], &mut b[..]],
            &[(d, 1.0), (d, 0.5)],
            dt,
            &mut inflow,
        );
        let us = t0.elapsed().as_secs_f64() * 1e6;
        if rep >= 20 {
            if odd { tb.push(us) } else { ta.push(us) }
        }
    }
    let stats = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        (v[v.len() / 10], v[v.len() / 2])
    };
    let ((a10, am), (b10, bm)) = (stats(&mut ta), stats(&mut tb));
    println!("A p10 {a10:.1} med {am:.1} µs | B p10 {b10:.1} med {bm:.1} µs | B/A med {:.3}", bm / am);
}
