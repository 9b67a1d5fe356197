//! Tests of the planned implicit solver and the explicit kernels' variants against the
//! generic sweep and the plain step.

use super::explicit::*;
use super::implicit::*;
use super::*;
use crate::phantom::grid::{Face, Shape};

/// A 3.1 mm × 1.3 mm cylinder at h = 100 µm, open top and side, with a 3×3×3 block of
/// cells taken out of the gel (spans broken, sealed sides next to the hole).
fn cylinder_with_hole() -> Grid {
    let mut g = Grid::new(
        Shape::Cylinder {
            diameter: 3.1e-3,
            depth: 1.3e-3,
        },
        1e-4,
        &[Face::Top, Face::Side],
    )
    .unwrap();
    let hole: Vec<usize> = (0..g.len())
        .filter(|&i| {
            let (x, y, z) = (i % g.n[0], (i / g.n[0]) % g.n[1], i / (g.n[0] * g.n[1]));
            (12..15).contains(&x) && (13..16).contains(&y) && (4..7).contains(&z)
        })
        .collect();
    g.set_excluded(&hole, true);
    g
}

/// The explicit step compiled for every instruction set this CPU has gives the portable
/// build's bits (a cylinder with open faces and excluded cells: spans and generic cells).
#[test]
fn explicit_step_is_the_same_bits_in_every_instruction_set() {
    let g = cylinder_with_hole();
    let u: Vec<f64> = (0..g.len())
        .map(|i| ((i * 7919 + 13) % 101) as f64 / 100.0)
        .collect();
    let dt = 0.9 * explicit_limit(&g, 2.5e-9);
    let mut want = vec![0.0; g.len()];
    let fw = explicit_step_with(&g, &u, &mut want, 2.5e-9, dt, 1.5, Isa::Portable);
    for isa in Isa::available() {
        let mut got = vec![0.0; g.len()];
        let fg = explicit_step_with(&g, &u, &mut got, 2.5e-9, dt, 1.5, isa);
        assert_eq!(fw.to_bits(), fg.to_bits(), "{isa:?}");
        for i in 0..g.len() {
            assert_eq!(want[i].to_bits(), got[i].to_bits(), "{isa:?}, cell {i}");
        }
    }
}

/// The explicit step against a per-cell reference written here: the plain 7-point form
/// centre·C + r·Σ(neighbours) inside each row's interior span, and outside it the sum of
/// the interior sides' terms C_n − C in x−, x+, y−, y+, z−, z+ order, C + r·sum, with the
/// open sides implicit, (C + r·sum + s·C_b)/(1 + s), s = 2r·(open sides): the same bits,
/// out of place and in place, on boxes (open on every face, on two, sealed, and one with
/// cells taken out at its rows' ends: whole rows, taken in one pass with their ends put
/// right after, beside rows that are not) and on a cylinder with excluded cells. Fails when
/// the two ends' values are swapped or a row with a sealed y side at one end is taken as
/// whole. The inflow is Σ s·(C_b − C') over the open cells (to
/// round-off: the step sums it plane by plane).
#[test]
fn explicit_step_matches_a_per_cell_reference() {
    let reference = |g: &Grid, u: &[f64], r: f64, cb: f64| -> Vec<f64> {
        let [nx, ny, _] = g.n;
        let strides = [1usize, nx, nx * ny];
        let mut out = vec![f64::NAN; g.len()];
        for (idx, o) in out.iter_mut().enumerate() {
            if !g.inside(idx) {
                continue;
            }
            let (i, row) = (idx % nx, idx / nx);
            let (i0, i1) = g.interior_spans[row];
            if (i0 as usize..i1 as usize).contains(&i) {
                let s: f64 = u[idx - 1]
                    + u[idx + 1]
                    + u[idx - nx]
                    + u[idx + nx]
                    + u[idx - strides[2]]
                    + u[idx + strides[2]];
                *o = (1.0 - 6.0 * r) * u[idx] + r * s;
                continue;
            }
            let (mut acc, mut open) = (0.0, 0.0);
            for (d, st) in strides.iter().enumerate() {
                let code = g.codes[d][idx];
                for (side, nb) in [
                    (code & 3, idx.wrapping_sub(*st)),
                    ((code >> 2) & 3, idx + st),
                ] {
                    if side == SIDE_INTERIOR {
                        acc += u[nb] - u[idx];
                    } else if side == SIDE_OPEN {
                        open += 1.0;
                    }
                }
            }
            // C' = C + r·acc + s·(C_b − C') with s = 2r·(open sides)
            let s = 2.0 * open * r;
            *o = if open > 0.0 {
                (u[idx] + r * acc + s * cb) / (1.0 + s)
            } else {
                u[idx] + r * acc
            };
        }
        out
    };
    let cyl = cylinder_with_hole();
    let size = [2.3e-3, 1.1e-3, 0.7e-3];
    // a box with sealed x faces (a cell with an open side is never taken out) and cells
    // taken out at or next to one end of some rows: rows whose two ends differ (one of
    // them with a sealed y or z side), so that only some rows of a plane are whole (the
    // kernel's one-pass stretches)
    let open = [Face::YMinus, Face::YPlus, Face::Bottom, Face::Top];
    let mut notched = Grid::new(Shape::Box { size }, 1e-4, &open).unwrap();
    let [nx, ny, _] = notched.n;
    let at = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
    let taken = [
        at(0, 3, 2),
        at(nx - 1, 5, 4),
        at(0, 7, 3),
        at(1, 2, 4),
        at(nx - 2, 8, 1),
    ];
    notched.set_excluded(&taken, true);
    let grids = [
        cyl,
        Grid::new(Shape::Box { size }, 1e-4, Shape::Box { size }.faces()).unwrap(),
        Grid::new(Shape::Box { size }, 1e-4, &[Face::Top, Face::XMinus]).unwrap(),
        Grid::new(Shape::Box { size }, 1e-4, &[]).unwrap(),
        notched,
    ];
    let (d, cb) = (2.5e-9, 1.5);
    for g in &grids {
        let u: Vec<f64> = (0..g.len())
            .map(|i| ((i * 7919 + 13) % 101) as f64 / 100.0)
            .collect();
        let dt = 0.9 * explicit_limit(g, d);
        let want = reference(g, &u, d * dt / (g.h * g.h), cb);
        for isa in Isa::available() {
            let mut got = vec![f64::NAN; g.len()];
            explicit_step_with(g, &u, &mut got, d, dt, cb, isa);
            let mut inplace = u.clone();
            explicit_step_in_place_with(g, &mut inplace, d, dt, cb, isa);
            for i in (0..g.len()).filter(|&i| g.inside(i)) {
                assert_eq!(want[i].to_bits(), got[i].to_bits(), "{isa:?}, cell {i}");
                assert_eq!(want[i].to_bits(), inplace[i].to_bits(), "{isa:?}, cell {i}");
            }
        }
        // three fields with their own D and boundary value in one pass, with 1 and 3
        // threads: each the reference's bits, its inflow the sum over the open faces
        // r·2·(C_b − C') (C' the new value) written out here
        let dc = [(d, cb), (0.4 * d, 0.3), (0.9 * d, 2.0)];
        let us: Vec<Vec<f64>> = (0..3)
            .map(|f| {
                (0..g.len())
                    .map(|i| ((i * 7919 + 13 * f + 5) % 101) as f64 / 100.0)
                    .collect()
            })
            .collect();
        for threads in [1, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut got = us.clone();
            let mut inflow = [0.0; 3];
            pool.install(|| {
                let mut fields: Vec<&mut [f64]> =
                    got.iter_mut().map(|f| f.as_mut_slice()).collect();
                explicit_steps_in_place(g, &mut fields, &dc, dt, &mut inflow)
            });
            for f in 0..3 {
                let r = dc[f].0 * dt / (g.h * g.h);
                let want = reference(g, &us[f], r, dc[f].1);
                for i in (0..g.len()).filter(|&i| g.inside(i)) {
                    assert_eq!(
                        want[i].to_bits(),
                        got[f][i].to_bits(),
                        "field {f}, cell {i}"
                    );
                }
                // (summed here face by face, in the step plane by plane: to round-off)
                let (mut flow, mut scale) = (0.0, 0.0);
                for cells in &g.open_cells {
                    for &(idx, cnt) in cells {
                        let x = r * 2.0 * cnt as f64 * (dc[f].1 - want[idx as usize]);
                        flow += x;
                        scale += x.abs();
                    }
                }
                assert!(
                    (flow - inflow[f]).abs() <= 1e-13 * scale,
                    "field {f}: inflow {} against {flow}",
                    inflow[f]
                );
            }
        }
    }
}

/// The in-place explicit step against the out-of-place one, in every instruction set this
/// CPU has and with 1, 2 and 3 threads (the blocks of planes cut in different places): the
/// same bits in every inside cell, the same inflow, and the cells outside untouched.
fn assert_in_place_same_bits(g: &Grid) {
    let u0: Vec<f64> = (0..g.len())
        .map(|i| ((i * 7919 + 13) % 101) as f64 / 100.0)
        .collect();
    let d = 2.5e-9;
    let dt = 0.9 * explicit_limit(g, d);
    for isa in Isa::available() {
        let mut want = vec![f64::NAN; g.len()];
        let fw = explicit_step_with(g, &u0, &mut want, d, dt, 1.5, isa);
        for threads in 1..=3 {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut got = u0.clone();
            let fg = pool.install(|| explicit_step_in_place_with(g, &mut got, d, dt, 1.5, isa));
            let at = format!("{isa:?}, {threads} threads, n = {:?}", g.n);
            assert_eq!(fw.to_bits(), fg.to_bits(), "{at}: inflow");
            for i in 0..g.len() {
                let w = if g.inside(i) { want[i] } else { u0[i] };
                assert_eq!(w.to_bits(), got[i].to_bits(), "{at}, cell {i}");
            }
        }
    }
}

#[test]
fn in_place_explicit_step_is_the_out_of_place_steps_bits() {
    let mut g = fig5_cylinder();
    assert_in_place_same_bits(&g);
    // a bubble's hole, and one across the top of the gel
    let n = g.n.map(|x| x as f64);
    let mut hole = ball(&g, [n[0] / 2.0, n[1] / 2.0, n[2] / 2.0], 6.0);
    hole.extend(ball(&g, [n[0] / 3.0, n[1] / 2.0, n[2] - 4.0], 5.0));
    g.set_excluded(&hole, true);
    assert_in_place_same_bits(&g);
    // blocks of one and two planes (a grid has at least 3)
    for nz in [3, 4, 5, 7, 13] {
        assert_in_place_same_bits(&boxed([9, 7, nz], all_box_faces()));
        assert_in_place_same_bits(&boxed([9, 7, nz], &[]));
        assert_in_place_same_bits(&boxed([11, 6, nz], &[Face::Top, Face::XMinus]));
    }
    // a gel one and two planes thick: the bottom and top planes of a sealed box excluded
    for nz in [3, 4] {
        let mut g = boxed([8, 9, nz], &[]);
        let ends: Vec<usize> = (0..g.len())
            .filter(|&i| i / 72 == 0 || i / 72 == nz - 1)
            .collect();
        g.set_excluded(&ends, true);
        assert_in_place_same_bits(&g);
    }
    assert_in_place_same_bits(&boxed([20, 17, 9], &[Face::Bottom, Face::YPlus]));
    let mut g = boxed([19, 16, 12], all_box_faces());
    let cells: Vec<usize> = (0..g.len())
        .filter(|&i| {
            let (x, y, z) = (i % g.n[0], (i / g.n[0]) % g.n[1], i / (g.n[0] * g.n[1]));
            !g.has_open_side(i) && ((x + 2 * y + z) % 3 == 0 || (y % 4 == 1 && x % 2 == 0))
        })
        .collect();
    g.set_excluded(&cells, true);
    assert_in_place_same_bits(&g);
}

/// Many simulations' explicit steps at once, each with its own parallel passes, as a batch
/// runner nests them (runs in parallel, the grid loops parallel inside): every run's fields
/// and inflow are the bits of the same steps run alone. (A thread waiting in one step's
/// pass may run another step; the per-thread halo and plane inflows are therefore taken out
/// for a step, not borrowed across its pass. This test did not make the old borrow fail in
/// three tries, so it guards the bits, not that.)
#[test]
fn nested_explicit_steps_in_a_batch_are_each_runs_bits() {
    let size = [3.2e-3, 3.0e-3, 2.4e-3];
    let g = Grid::new(Shape::Box { size }, 1e-4, Shape::Box { size }.faces()).unwrap();
    let dc = [(2.5e-9, 1.5), (1e-9, 0.5)];
    let dt = 0.9 * explicit_limit(&g, 2.5e-9);
    let start = |run: usize, f: usize| -> Vec<f64> {
        (0..g.len())
            .map(|i| ((i * 7919 + 13 * f + 31 * run) % 101) as f64 / 100.0)
            .collect()
    };
    let steps = |run: usize, into: bool| -> (Vec<Vec<f64>>, [f64; 2]) {
        let mut us: Vec<Vec<f64>> = (0..2).map(|f| start(run, f)).collect();
        let mut inflow = [0.0; 2];
        for _ in 0..6 {
            if into {
                let src = us.clone();
                let src: Vec<&[f64]> = src.iter().map(|u| u.as_slice()).collect();
                let mut dst: Vec<&mut [f64]> = us.iter_mut().map(|u| u.as_mut_slice()).collect();
                explicit_steps_into(&g, &src, &mut dst, &dc, dt, &mut inflow);
            } else {
                let mut fields: Vec<&mut [f64]> = us.iter_mut().map(|u| u.as_mut_slice()).collect();
                explicit_steps_in_place(&g, &mut fields, &dc, dt, &mut inflow);
            }
        }
        (us, inflow)
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    for into in [false, true] {
        let alone: Vec<_> = (0..64)
            .map(|run| pool.install(|| steps(run, into)))
            .collect();
        let batch: Vec<_> = pool.install(|| {
            (0..64)
                .into_par_iter()
                .map(|run| steps(run, into))
                .collect()
        });
        for (run, (a, b)) in alone.iter().zip(&batch).enumerate() {
            assert_eq!(
                a.1.map(f64::to_bits),
                b.1.map(f64::to_bits),
                "run {run}: inflow"
            );
            for f in 0..2 {
                assert!(
                    (0..g.len())
                        .filter(|&i| g.inside(i))
                        .all(|i| a.0[f][i].to_bits() == b.0[f][i].to_bits()),
                    "run {run}, field {f}"
                );
            }
        }
    }
}

/// Several in-place steps in a row (the per-thread buffers reused, grids of different
/// sizes in turn) against out-of-place steps alternating between two fields.
#[test]
fn repeated_in_place_steps_are_the_out_of_place_steps_bits() {
    let grids = [fig5_cylinder(), boxed([9, 7, 5], all_box_faces())];
    let mut fields: Vec<(Vec<f64>, Vec<f64>)> = grids
        .iter()
        .map(|g| {
            let u: Vec<f64> = (0..g.len()).map(|i| (i % 23) as f64 * 0.05).collect();
            (u.clone(), u)
        })
        .collect();
    for step in 0..4 {
        for (g, (a, b)) in grids.iter().zip(&mut fields) {
            let dt = 0.9 * explicit_limit(g, 1e-9);
            let cb = 0.1 * step as f64;
            let mut out = a.clone();
            let fa = explicit_step(g, a, &mut out, 1e-9, dt, cb);
            *a = out;
            let fb = explicit_step_in_place(g, b, 1e-9, dt, cb);
            assert_eq!(fa.to_bits(), fb.to_bits());
            assert!(a
                .iter()
                .zip(b.iter())
                .all(|(x, y)| x.to_bits() == y.to_bits()));
        }
    }
}

/// The planned solver (every instruction-set variant this CPU runs) against the generic
/// per-cell sweep, an independent elimination of the same systems: the same bits, field
/// and inflow, for several steps with one solver.
fn assert_same_bits(g: &Grid) {
    let u0: Vec<f64> = (0..g.len())
        .map(|i| ((i * 7919 + 13) % 101) as f64 / 100.0)
        .collect();
    for isa in Isa::available() {
        let mut solver = ImplicitSolver::new();
        let mut a = u0.clone();
        let mut b = u0.clone();
        for (d, dt, cb) in [(2.5e-9, 20.0, 1.5), (1e-9, 3.0, 0.2), (8e-9, 600.0, 0.0)] {
            let mut s = vec![0.0; g.len()];
            let fa = implicit_step(g, &mut a, &mut s, d, dt, cb);
            let fb = solver.step_with(g, &mut b, d, dt, cb, isa);
            for i in 0..g.len() {
                assert_eq!(
                    a[i].to_bits(),
                    b[i].to_bits(),
                    "{isa:?}, n = {:?}, cell {i}: {} vs {}",
                    g.n,
                    a[i],
                    b[i]
                );
            }
            assert_eq!(fa.to_bits(), fb.to_bits(), "{isa:?}, n = {:?}: inflow", g.n);
        }
    }
}

/// [`ImplicitSolver::steps`] (the fields side by side) against each field stepped alone
/// by [`ImplicitSolver::step`]: the same bits and inflows, for 1, 2 and 3 fields
/// (more fields than threads, too) on 1, 2 and 3 threads, in a cylinder
/// with cells taken out (so the plan is updated between steps) and in an open box.
#[test]
fn fields_stepped_side_by_side_are_each_fields_bits() {
    let dc = [(2.5e-9, 1.5), (1e-9, 0.2), (8e-9, 0.0)];
    for base in [cylinder_with_hole(), boxed([13, 9, 7], all_box_faces())] {
        for nf in 1..=3 {
            for threads in [1, 2, 3] {
                let g = &mut base.clone();
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                let u0: Vec<Vec<f64>> = (0..nf)
                    .map(|f| {
                        (0..g.len())
                            .map(|i| ((i * 7919 + 13 * f + 5) % 101) as f64 / 100.0)
                            .collect()
                    })
                    .collect();
                let (mut alone, mut together) = (u0.clone(), u0);
                let (mut one, mut all) = (ImplicitSolver::new(), ImplicitSolver::new());
                for (step, dt) in [20.0, 3.0, 600.0].into_iter().enumerate() {
                    if step == 1 {
                        // a change of codes between steps: both plans are updated
                        let (c, id) = (g.index(g.n[0] / 2, g.n[1] / 2, g.n[2] / 2), g.codes_id());
                        g.set_excluded(&[c], true);
                        assert_ne!(id, g.codes_id());
                    }
                    let want: Vec<f64> = (0..nf)
                        .map(|f| one.step(g, &mut alone[f], dc[f].0, dt, dc[f].1))
                        .collect();
                    let mut got = vec![0.0; nf];
                    pool.install(|| {
                        let mut fields: Vec<&mut [f64]> =
                            together.iter_mut().map(|f| f.as_mut_slice()).collect();
                        all.steps(g, &mut fields, &dc[..nf], dt, &mut got)
                    });
                    for f in 0..nf {
                        assert_eq!(want[f].to_bits(), got[f].to_bits(), "field {f}: inflow");
                        for i in 0..g.len() {
                            assert_eq!(
                                alone[f][i].to_bits(),
                                together[f][i].to_bits(),
                                "{nf} fields, {threads} threads, step {step}, field {f}, cell {i}"
                            );
                        }
                    }
                }
            }
        }
    }
}

fn boxed(n: [usize; 3], open: &[Face]) -> Grid {
    let size = [n[0] as f64 * 1e-4, n[1] as f64 * 1e-4, n[2] as f64 * 1e-4];
    Grid::new(Shape::Box { size }, 1e-4, open).unwrap()
}

/// Every face of a box (the shape's own list).
fn all_box_faces() -> &'static [Face] {
    Shape::Box { size: [1.0; 3] }.faces()
}

/// A cylinder with open faces and cells excluded (segments begin and end mid-line).
#[test]
fn planned_sweeps_give_the_generic_sweeps_bits() {
    let mut g = Grid::new(
        Shape::Cylinder {
            diameter: 2.1e-3,
            depth: 1.1e-3,
        },
        1e-4,
        &[Face::Top, Face::Side],
    )
    .unwrap();
    assert_same_bits(&g);
    let hole: Vec<usize> = (0..g.len())
        .filter(|&i| {
            let (x, y, z) = (i % g.n[0], (i / g.n[0]) % g.n[1], i / (g.n[0] * g.n[1]));
            (8..11).contains(&x) && (9..12).contains(&y) && (3..6).contains(&z)
        })
        .collect();
    g.set_excluded(&hole, true);
    assert_same_bits(&g);
}

/// Boxes: all faces open, a thin grid (nz = 3), a non-square plane (the x sweep's
/// transpose), rows shorter and longer than a broadcast run, all faces sealed.
#[test]
fn planned_sweeps_give_the_generic_sweeps_bits_in_boxes() {
    assert_same_bits(&boxed([20, 20, 9], all_box_faces()));
    assert_same_bits(&boxed([21, 17, 3], &[Face::Top, Face::XMinus]));
    assert_same_bits(&boxed(
        [23, 11, 7],
        &[Face::XPlus, Face::YMinus, Face::Bottom],
    ));
    assert_same_bits(&boxed([5, 3, 4], all_box_faces()));
    assert_same_bits(&boxed([3, 3, 3], all_box_faces()));
    assert_same_bits(&boxed([13, 9, 10], &[]));
}

/// Segments of length 1 and 2 everywhere: a lattice of excluded cells inside a box with all
/// faces open (the excluded cells never touch an open face).
#[test]
fn planned_sweeps_give_the_generic_sweeps_bits_with_short_segments() {
    for n in [[19, 16, 12], [9, 30, 5]] {
        let mut g = boxed(n, all_box_faces());
        let cells: Vec<usize> = (0..g.len())
            .filter(|&i| {
                let (x, y, z) = (i % g.n[0], (i / g.n[0]) % g.n[1], i / (g.n[0] * g.n[1]));
                !g.has_open_side(i) && (x + 2 * y + z) % 3 == 0 || (y % 4 == 1 && x % 2 == 0)
            })
            .filter(|&i| !g.has_open_side(i))
            .collect();
        g.set_excluded(&cells, true);
        assert_same_bits(&g);
    }
}

/// The Fig. 5 phantom (`profiles/fig5-dive.toml` with `profiles/phantoms/hydrogel.toml`:
/// an 11 mm × 5 mm cylinder, h = 86.5 µm, open top and side; 127×127×58 cells).
fn fig5_cylinder() -> Grid {
    let shape = Shape::Cylinder {
        diameter: 11e-3,
        depth: 5e-3,
    };
    Grid::new(shape, 86.5e-6, &[Face::Top, Face::Side]).unwrap()
}

/// The cells of `g` that a bubble may take (inside the mask, no open side) whose centres lie
/// within `radius` cells of the point `c` (in cells).
fn ball(g: &Grid, c: [f64; 3], radius: f64) -> Vec<usize> {
    let (lo, hi) = g.cell_range(c.map(|x| (x + 0.5) * g.h), radius * g.h);
    let mut cells = Vec::new();
    for k in lo[2]..=hi[2] {
        for j in lo[1]..=hi[1] {
            for i in lo[0]..=hi[0] {
                let d2 = [i, j, k]
                    .iter()
                    .zip(c)
                    .map(|(&x, c)| (x as f64 - c).powi(2))
                    .sum::<f64>();
                let idx = g.index(i, j, k);
                if d2 <= radius * radius && g.inside_phantom(idx) && !g.has_open_side(idx) {
                    cells.push(idx);
                }
            }
        }
    }
    cells
}

/// Set `cells` excluded (or not) in `g`, bring `plan` up to date with the grid's change log
/// and check it against a fresh build (or build it anew if the update declines). Returns
/// whether the update was incremental.
fn change(g: &mut Grid, plan: &mut LinePlan, cells: &[usize], excluded: bool) -> bool {
    g.set_excluded(cells, excluded);
    catch_up(g, plan)
}

/// Bring `plan` up to date with `g` through the change log, as [`change`].
fn catch_up(g: &Grid, plan: &mut LinePlan) -> bool {
    let cells = g
        .changed_since(plan.codes_id)
        .expect("the log reaches back");
    let fresh = LinePlan::build(g).unwrap();
    let updated = plan.update(g, &cells);
    if updated {
        assert!(
            *plan == fresh,
            "n = {:?}: updated plan differs from a fresh build",
            g.n
        );
    } else {
        *plan = fresh;
    }
    updated
}

/// A bubble's life in a grid: two balls taken, part of one given back, a third grown
/// step by step and given back, several changes caught up at once; every update is
/// incremental and equals a fresh build.
fn bubble_sequence(g: &mut Grid) {
    let n = g.n.map(|x| x as f64);
    let mut plan = LinePlan::build(g).unwrap();
    let a = ball(g, [n[0] / 2.0, n[1] / 2.0, n[2] / 2.0], 4.0);
    let b = ball(g, [1.5, n[1] / 2.0 - 1.0, 2.0], 3.0);
    assert!(!a.is_empty() && !b.is_empty());
    assert!(change(g, &mut plan, &a, true));
    assert!(change(g, &mut plan, &b, true));
    let half: Vec<usize> = a.iter().copied().filter(|&c| c % 2 == 0).collect();
    assert!(change(g, &mut plan, &half, false));
    let centre = [n[0] / 3.0, n[1] / 1.6, n[2] / 3.0];
    let mut grown: Vec<usize> = Vec::new();
    for step in 1..=6 {
        let now = ball(g, centre, step as f64);
        let take: Vec<usize> = now.iter().copied().filter(|c| !grown.contains(c)).collect();
        assert!(change(g, &mut plan, &take, true));
        grown = now;
    }
    assert!(change(g, &mut plan, &grown, false));
    // three changes, one update over the union of their boxes
    g.set_excluded(&b, false);
    g.set_excluded(&ball(g, [n[0] / 2.0, 2.0, n[2] - 3.0], 2.0), true);
    g.set_excluded(&a, false);
    assert!(catch_up(g, &mut plan));
    // nothing changed
    assert_eq!(plan.codes_id, g.codes_id());
    assert!(catch_up(g, &mut plan));
}

#[test]
fn updated_plans_are_fresh_plans() {
    bubble_sequence(&mut fig5_cylinder());
    bubble_sequence(&mut boxed([24, 20, 16], all_box_faces()));
    bubble_sequence(&mut boxed([9, 32, 7], all_box_faces()));
}

/// A sealed box's longest segments (x, 16 cells) all cut: the table's stride shrinks to 12
/// (y), and grows back when the cells are given back; both times the update declines.
#[test]
fn a_changed_table_stride_takes_a_fresh_plan() {
    let mut g = boxed([16, 12, 10], &[]);
    let mut plan = LinePlan::build(&g).unwrap();
    assert_eq!(plan.max_len, 16);
    let wall: Vec<usize> = (0..12 * 10).map(|q| g.index(8, q % 12, q / 12)).collect();
    assert!(change(&mut g, &mut plan, &wall[..60], true));
    assert!(!change(&mut g, &mut plan, &wall[60..], true));
    assert_eq!(plan.max_len, 12);
    let some = ball(&g, [3.0, 5.0, 5.0], 2.0);
    assert!(change(&mut g, &mut plan, &some, true));
    assert!(!change(&mut g, &mut plan, &wall[..1], false));
    assert_eq!(plan.max_len, 16);
}

/// The change log keeps the last 64 changes: further back, a full build.
#[test]
fn a_log_too_short_takes_a_fresh_plan() {
    let mut g = boxed([12, 11, 10], all_box_faces());
    let mut solver = ImplicitSolver::new();
    let mut u = vec![1.0; g.len()];
    solver.step(&g, &mut u, 1e-9, 10.0, 0.5);
    let id = g.codes_id();
    let cell = [g.index(5, 5, 5)];
    for q in 0..64 {
        g.set_excluded(&cell, q % 2 == 0);
    }
    assert!(g.changed_since(id).is_some());
    g.set_excluded(&cell, true);
    assert_eq!(g.changed_since(id), None);
    solver.step(&g, &mut u, 1e-9, 10.0, 0.5);
    assert_eq!(solver.updates, 0);
    assert!(*solver.plan.as_ref().unwrap() == LinePlan::build(&g).unwrap());
    g.set_excluded(&cell, false);
    solver.step(&g, &mut u, 1e-9, 10.0, 0.5);
    assert_eq!(solver.updates, 1);
    assert!(*solver.plan.as_ref().unwrap() == LinePlan::build(&g).unwrap());
}

/// The planned solver kept through changes of the codes (its plan updated, not rebuilt)
/// against the generic sweep: the same bits after every change, in every instruction set.
fn assert_same_bits_through(g: &Grid, changes: &[(Vec<usize>, bool)]) {
    let u0: Vec<f64> = (0..g.len())
        .map(|i| ((i * 7919 + 13) % 101) as f64 / 100.0)
        .collect();
    for isa in Isa::available() {
        let mut g = g.clone();
        let mut solver = ImplicitSolver::new();
        let (mut a, mut b) = (u0.clone(), u0.clone());
        let mut s = vec![0.0; g.len()];
        let (d, dt, cb) = (2.5e-9, 20.0, 1.5);
        solver.step_with(&g, &mut b, d, dt, cb, isa);
        implicit_step(&g, &mut a, &mut s, d, dt, cb);
        for (q, (cells, excluded)) in changes.iter().enumerate() {
            g.set_excluded(cells, *excluded);
            let fa = implicit_step(&g, &mut a, &mut s, d, dt, cb);
            let fb = solver.step_with(&g, &mut b, d, dt, cb, isa);
            assert_eq!(solver.updates, q + 1, "{isa:?}: the plan was rebuilt");
            assert_eq!(fa.to_bits(), fb.to_bits(), "{isa:?}, n = {:?}: inflow", g.n);
            for i in 0..g.len() {
                assert_eq!(
                    a[i].to_bits(),
                    b[i].to_bits(),
                    "{isa:?}, n = {:?}, change {q}, cell {i}",
                    g.n
                );
            }
        }
    }
}

/// The x sweep's per-thread copy of a plane keeps what earlier steps left past each line's
/// end: a step whose field was not finite (a run gone wrong in a batch) must not reach a
/// later step on that thread. One thread, so both steps use the same copy; the second
/// against the generic sweep, bit for bit.
#[test]
fn a_step_after_a_non_finite_one_on_the_same_thread_is_the_generic_sweeps_bits() {
    let g = fig5_cylinder();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    pool.install(|| {
        let mut broken = vec![f64::NAN; g.len()];
        ImplicitSolver::new().step(&g, &mut broken, 2.5e-9, 20.0, 1.5);
        let u0: Vec<f64> = (0..g.len())
            .map(|i| ((i * 7919 + 13) % 101) as f64 / 100.0)
            .collect();
        let (mut a, mut b) = (u0.clone(), u0);
        let mut s = vec![0.0; g.len()];
        let fa = implicit_step(&g, &mut a, &mut s, 2.5e-9, 20.0, 1.5);
        let fb = ImplicitSolver::new().step(&g, &mut b, 2.5e-9, 20.0, 1.5);
        assert_eq!(fa.to_bits(), fb.to_bits(), "inflow");
        for i in 0..g.len() {
            assert_eq!(a[i].to_bits(), b[i].to_bits(), "cell {i}");
        }
    });
}

#[test]
fn updated_plans_give_the_generic_sweeps_bits() {
    let grids = [
        fig5_cylinder(),
        Grid::new(
            Shape::Cylinder {
                diameter: 2.1e-3,
                depth: 1.1e-3,
            },
            1e-4,
            &[Face::Top, Face::Side],
        )
        .unwrap(),
        boxed([20, 20, 9], all_box_faces()),
    ];
    for g in grids {
        let n = g.n.map(|x| x as f64);
        let a = ball(&g, [n[0] / 2.0, n[1] / 2.0, n[2] / 2.0], 3.0);
        let b = ball(&g, [n[0] / 3.0, n[1] / 2.0, n[2] / 3.0], 2.0);
        let changes = [
            (a.clone(), true),
            (b, true),
            (a[..a.len() / 2].to_vec(), false),
        ];
        assert_same_bits_through(&g, &changes);
    }
}

/// The step limits' scans, which read one cell per interior span and per edge run, give
/// what a scan of every inside cell's six sides gives (written out here: the largest number
/// of interior sides, and the largest weight sum with an open side counted 2), on boxes with
/// every combination of open faces, a cylinder, and grids with cells taken out by bubbles.
#[test]
fn limit_scans_match_a_scan_of_every_cell() {
    fn every_cell(g: &Grid) -> (f64, f64) {
        let (mut interior, mut weights) = (0u32, 0u32);
        for idx in (0..g.len()).filter(|&i| g.inside(i)) {
            let (mut n, mut w) = (0, 0);
            for d in 0..3 {
                for side in [g.codes[d][idx] & 3, (g.codes[d][idx] >> 2) & 3] {
                    n += u32::from(side == SIDE_INTERIOR);
                    w += match side {
                        SIDE_INTERIOR => 1,
                        SIDE_OPEN => 2,
                        _ => 0,
                    };
                }
            }
            interior = interior.max(n);
            weights = weights.max(w);
        }
        (f64::from(interior.max(1)), f64::from(weights))
    }
    let faces = all_box_faces();
    let mut grids: Vec<Grid> = (0..1u32 << faces.len())
        .map(|m| {
            let open: Vec<Face> = (0..faces.len())
                .filter(|b| m & (1 << b) != 0)
                .map(|b| faces[b])
                .collect();
            boxed([5, 4, 3], &open)
        })
        .collect();
    grids.push(fig5_cylinder());
    grids.push(cylinder_with_hole());
    // a box whose only fully interior cells are taken out: every cell left has a sealed side
    let mut g = boxed([3, 3, 3], faces);
    g.set_excluded(&[13], true);
    grids.push(g);
    for g in &grids {
        let scans = LimitScans::of(g);
        let (interior, weights) = every_cell(g);
        assert_eq!(
            scans.interior_sides, interior,
            "{:?} open {:?}",
            g.n, g.open
        );
        assert_eq!(scans.weight_sum, weights, "{:?} open {:?}", g.n, g.open);
    }
}

/// D and C_b of the per-field tests' three fields.
const PER_FIELD_DC: [(f64, f64); 3] = [(2.5e-9, 1.5), (1e-9, 0.2), (8e-9, 0.0)];

/// Every case of the per-field tests: a cylinder with cells taken out and an open box, 1–3
/// fields, on pools of 1–3 threads, dt 0.9 of the fastest field's explicit limit.
fn per_field_cases(mut case: impl FnMut(&Grid, usize, &rayon::ThreadPool, f64)) {
    for g in [cylinder_with_hole(), boxed([13, 9, 7], all_box_faces())] {
        let dt = 0.9 * explicit_limit(&g, 8e-9);
        for nf in 1..=3 {
            for threads in [1, 2, 3] {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap();
                case(&g, nf, &pool, dt);
            }
        }
    }
}

/// The inflows (`flows`: want, got) and the cells `checked` (the reference `alone`, the
/// fields under test `got`) the same bits.
fn assert_per_field_bits(
    g: &Grid,
    (want, got_flow): (&[f64], &[f64]),
    (alone, got): (&[Vec<f64>], &[&[f64]]),
    checked: impl Fn(usize) -> bool,
    step: usize,
) {
    for f in 0..alone.len() {
        assert_eq!(
            want[f].to_bits(),
            got_flow[f].to_bits(),
            "field {f}: inflow"
        );
        for i in (0..g.len()).filter(|&i| checked(i)) {
            assert_eq!(
                alone[f][i].to_bits(),
                got[f][i].to_bits(),
                "{} fields, step {step}, field {f}, cell {i}",
                alone.len()
            );
        }
    }
}

/// `nf` fields of different values in every cell (0 outside the gel when `zero_outside`).
fn per_field_start(g: &Grid, nf: usize, zero_outside: bool) -> Vec<Vec<f64>> {
    (0..nf)
        .map(|f| {
            (0..g.len())
                .map(|i| {
                    let v = ((i * 7919 + 13 * f + 5) % 101) as f64 / 100.0;
                    if zero_outside && !g.inside(i) {
                        0.0
                    } else {
                        v
                    }
                })
                .collect()
        })
        .collect()
}

/// The per-field steps' reference: each field of `alone` stepped alone out of place by
/// [`explicit_step`] (`dc[f]` its D and C_b); returns the inflows.
fn step_each_alone(g: &Grid, alone: &mut [Vec<f64>], dc: &[(f64, f64)], dt: f64) -> Vec<f64> {
    alone
        .iter_mut()
        .zip(dc)
        .map(|(u, &(d, cb))| {
            let mut out = u.clone();
            let x = explicit_step(g, u, &mut out, d, dt, cb);
            *u = out;
            x
        })
        .collect()
}

/// [`explicit_steps_shifting_per_field`] (a thread per field, each moved by two planes in
/// its store) against each field stepped alone out of place by [`explicit_step`]: the same
/// bits in every inside cell, 0 in every other (the fields start 0 outside the gel, as a
/// simulation's are, [`super::super::fields`]), the same inflows; 1–3 fields on 1–3
/// threads, in a cylinder with cells taken out and in an open box, over five steps (both
/// directions, twice, and once more), and a swap of the stores in between as the out-of-place
/// steps make.
#[test]
fn shifting_per_field_explicit_steps_are_each_fields_bits() {
    use crate::phantom::fields::Fields;
    per_field_cases(|g, nf, pool, dt| {
        let dc = &PER_FIELD_DC[..nf];
        let mut alone = per_field_start(g, nf, true);
        let mut fields = Fields::new(alone.clone(), g.n[0] * g.n[1]);
        for step in 0..5 {
            let want = step_each_alone(g, &mut alone, dc, dt);
            let mut got = vec![0.0; nf];
            let from = fields.offset_planes();
            let to = pool.install(|| {
                let (mut stores, from) = fields.stores_for_shift();
                explicit_steps_shifting_per_field(g, &mut stores, from, dc, dt, &mut got)
            });
            assert_eq!(to, 2 - from);
            fields.shifted(to);
            let views: Vec<&[f64]> = fields.iter().collect();
            assert_per_field_bits(g, (&want, &got), (&alone, &views), |_| true, step);
            if step == 2 {
                // the stores swapped for copies of the views, as an out-of-place step
                // leaves them (the views from the stores' start)
                let mut back = fields.to_vecs();
                fields.swap_stores(&mut back);
                assert_eq!(fields.offset_planes(), 0);
            }
        }
    });
}

/// [`explicit_steps_in_place_per_field`] (a thread per field) against each field stepped
/// alone out of place by [`explicit_step`]: the same bits in every inside cell and the same
/// inflows, for 1, 2 and 3 fields on 1, 2 and 3 threads, in a cylinder with cells taken
/// out and in an open box, over three steps.
#[test]
fn per_field_explicit_steps_are_each_fields_bits() {
    per_field_cases(|g, nf, pool, dt| {
        let dc = &PER_FIELD_DC[..nf];
        let mut alone = per_field_start(g, nf, false);
        let mut together = alone.clone();
        for step in 0..3 {
            let want = step_each_alone(g, &mut alone, dc, dt);
            let mut got = vec![0.0; nf];
            pool.install(|| {
                let mut fields: Vec<&mut [f64]> =
                    together.iter_mut().map(|f| f.as_mut_slice()).collect();
                explicit_steps_in_place_per_field(g, &mut fields, dc, dt, &mut got)
            });
            let views: Vec<&[f64]> = together.iter().map(|f| f.as_slice()).collect();
            assert_per_field_bits(g, (&want, &got), (&alone, &views), |i| g.inside(i), step);
        }
    });
}
