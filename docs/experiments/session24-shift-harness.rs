//! Session 24's paired harness: the per-field explicit step with the plane copy
//! (`explicit_steps_in_place_per_field`, A) against the one that moves each field by two
//! planes (`explicit_steps_shifting_per_field`, B), alternated call by call on the small cube
//! (60³, h = 100 µm, every face open; BOX=fig5 takes the Fig. 5 cylinder), two fields.
use decophantom::phantom::diffusion;
use decophantom::phantom::fields::Fields;
use decophantom::phantom::grid::{Face, Grid, Shape};
use std::time::Instant;

fn main() {
    let reps: usize = std::env::var("REPS").ok().map(|s| s.parse().unwrap()).unwrap_or(2000);
    let g = if std::env::var("BOX").is_ok_and(|v| v == "fig5") {
        let shape = Shape::Cylinder { diameter: 11e-3, depth: 5e-3 };
        Grid::new(shape, 86.5e-6, &[Face::Top, Face::Side]).expect("grid")
    } else {
        let all = [Face::XMinus, Face::XPlus, Face::YMinus, Face::YPlus, Face::Top, Face::Bottom];
        Grid::new(Shape::Box { size: [6e-3, 6e-3, 6e-3] }, 1e-4, &all).expect("grid")
    };
    let d = 2.5e-9;
    let dt = 0.9 * diffusion::explicit_limit(&g, d);
    let start: Vec<f64> = (0..g.len())
        .map(|i| if g.inside(i) { 1.0 + (i % 17) as f64 * 0.01 } else { 0.0 })
        .collect();
    let mut a = vec![start.clone(), start.clone()];
    let mut b = Fields::new(vec![start.clone(), start], g.n[0] * g.n[1]);
    let dc = [(d, 1.0), (d, 0.5)];
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    let mut inflow = [0.0; 2];
    for rep in 0..reps {
        let t0 = Instant::now();
        if rep % 2 == 0 {
            let mut f: Vec<&mut [f64]> = a.iter_mut().map(|f| f.as_mut_slice()).collect();
            diffusion::explicit_steps_in_place_per_field(&g, &mut f, &dc, dt, &mut inflow);
        } else {
            let (mut stores, from) = b.stores_for_shift();
            let to = diffusion::explicit_steps_shifting_per_field(&g, &mut stores, from, &dc, dt, &mut inflow);
            b.shifted(to);
        }
        let us = t0.elapsed().as_secs_f64() * 1e6;
        if rep >= 20 {
            if rep % 2 == 1 { tb.push(us) } else { ta.push(us) }
        }
    }
    // the same bits after the same number of steps
    let same = a.iter().enumerate().all(|(f, x)| x.iter().zip(&b[f]).all(|(p, q)| p.to_bits() == q.to_bits()));
    let stats = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        (v[v.len() / 10], v[v.len() / 2])
    };
    let ((a10, am), (b10, bm)) = (stats(&mut ta), stats(&mut tb));
    println!("copy p10 {a10:.1} med {am:.1} µs | shift p10 {b10:.1} med {bm:.1} µs | copy/shift med {:.3} | same bits {same}", am / bm);
}
