//! Bubbles displace the gel (issue 8, item 5).
//!
//! A bubble larger than the grid takes the cells inside it out of the gel
//! ([`Grid::set_excluded`]): they stop diffusing and stop feeding it, and the bubble exchanges
//! gas only through its flux law at its own surface. As it grows (or shrinks), the gel around it
//! is pushed outward (or flows back) as an incompressible medium would be: the gel now at
//! distance r from the centre was, before the radius went from R₀ to R₁, at
//! r_b = (r³ − (R₁³ − R₀³))^{1/3} (the volume between the bubble and a gel particle is
//! conserved), and it carries its dissolved gas with it. [`remap`] moves the field accordingly,
//! C_new(r) = C_old(r_b), out to a reach of a few radii beyond which the displacement
//! (∝ 1/r²) meets a field that no longer varies. This is the convection term of Scriven's
//! growth problem (ε = 1: Scriven 1959, Chem. Eng. Sci. 10, 1–13); without it a resolved
//! bubble grows like the ε = 0 solution, 4 % faster at a supersaturation ratio of 9.9.
//!
//! The gel pushed beyond the reach (and the gel the bubble swallows, whose gas the remap has
//! already carried outward) leaves the modelled gel: physically it is the phantom swelling
//! at its free surface. The grid's change of gas from this phase is kept apart in the gas
//! balance (`Simulation::displaced_gas`), so the balance still checks the exchange and the
//! solvers to round-off.

use super::grid::Grid;
use crate::gas::Gas;
use rayon::prelude::*;

/// A bubble's displacement state.
#[derive(Debug, Clone, Default)]
pub struct Displaced {
    /// The radius the gel was last displaced to, m (0: the bubble is still sub-grid and
    /// displaces nothing).
    pub radius: f64,
    /// Centre the cells were taken for, m.
    pub centre: [f64; 3],
    /// The cells the bubble holds out of the gel.
    pub cells: Vec<usize>,
    /// dR/dt over the last step, m/s (the gel's speed at the wall).
    pub wall_speed: f64,
    /// Radius and time at the end of the last step, for `wall_speed`.
    pub last: (f64, f64),
}

/// The factor by which the gel's motion changes the quasi-steady flux through a shell around a
/// bubble: x/(eˣ − 1) with x = R²Ṙ·Σ(1/r_a − 1/r_b)/D over the shell (the steady solution of
/// D∇²C = u·∇C with u = R²Ṙ/r², C' ∝ r⁻² exp(−R²Ṙ/(D r)); exact for one diffusivity). Gel
/// moving outward (growth) carries gas away from the wall: the factor is below 1.
pub fn convection_factor(x: f64) -> f64 {
    if x.abs() < 1e-6 {
        1.0 - 0.5 * x
    } else {
        x / x.exp_m1()
    }
}

/// The cells inside the phantom whose centres lie within distance `r` of `centre`, except cells
/// with a side on an open face (left in the gel: a bubble reaching a face ends the run).
pub fn covered_cells(grid: &Grid, centre: [f64; 3], r: f64) -> Vec<usize> {
    let mut out = Vec::new();
    if !(r > 0.0) {
        return out;
    }
    let h = grid.h;
    let (lo, hi) = grid.cell_range(centre, r);
    for k in lo[2]..=hi[2] {
        let z = (k as f64 + 0.5) * h - centre[2];
        for j in lo[1]..=hi[1] {
            let y = (j as f64 + 0.5) * h - centre[1];
            let Some((i0, i1)) = grid.row_within(centre, r, (y, z), (lo[0], hi[0])) else {
                continue;
            };
            for i in i0..=i1 {
                let x = (i as f64 + 0.5) * h - centre[0];
                if x * x + y * y + z * z < r * r {
                    let idx = grid.index(i, j, k);
                    if grid.inside_phantom(idx) && !grid.has_open_side(idx) {
                        out.push(idx);
                    }
                }
            }
        }
    }
    out
}

/// The displaced field: for every gel cell (not excluded once the bubble has radius `r_new`)
/// at distance r ∈ [r_new, reach] from `centre`, the value of each field at the point the gel
/// there came from, r_b = (r³ − (r_new³ − r_old³))^{1/3} on the same ray ([`interpolate_gases`],
/// with the bubble's cells at the wall value `wall[g]`, Henry's law at its surface). Returns
/// (cell, value per field in field order), per z-plane in plane order (each plane's list
/// built by one task: no copy into one list); the caller writes it after updating which cells
/// the bubble holds.
pub fn remap<F: AsRef<[f64]> + Sync>(
    grid: &Grid,
    fields: &[F],
    wall: &[f64],
    centre: [f64; 3],
    r_old: f64,
    r_new: f64,
    reach: f64,
) -> Vec<Vec<(usize, [f64; Gas::ALL.len()])>> {
    let h = grid.h;
    let dv = r_new.powi(3) - r_old.powi(3);
    let (lo, hi) = grid.cell_range(centre, reach);
    let planes: Vec<usize> = (lo[2]..=hi[2]).collect();
    planes
        .par_iter()
        .map(|&k| {
            let mut out = Vec::new();
            let z = (k as f64 + 0.5) * h - centre[2];
            for j in lo[1]..=hi[1] {
                let y = (j as f64 + 0.5) * h - centre[1];
                let Some((i0, i1)) = grid.row_within(centre, reach, (y, z), (lo[0], hi[0])) else {
                    continue;
                };
                for i in i0..=i1 {
                    let x = (i as f64 + 0.5) * h - centre[0];
                    let d2 = x * x + y * y + z * z;
                    if d2 < r_new * r_new || d2 > reach * reach {
                        continue;
                    }
                    let idx = grid.index(i, j, k);
                    if !grid.inside_phantom(idx) {
                        continue;
                    }
                    let d = d2.sqrt();
                    let rb = (d2 * d - dv).max(0.0).cbrt();
                    let s = if d > 0.0 { rb / d } else { 1.0 };
                    let from = [centre[0] + x * s, centre[1] + y * s, centre[2] + z * s];
                    let mut values = [0.0; Gas::ALL.len()];
                    let mut here = [0.0; Gas::ALL.len()];
                    for (h, f) in here.iter_mut().zip(fields) {
                        *h = f.as_ref()[idx];
                    }
                    let ng = fields.len();
                    interpolate_gases(grid, fields, from, wall, &here[..ng], &mut values[..ng]);
                    out.push((idx, values));
                }
            }
            out
        })
        .collect()
}

/// Trilinear interpolation of each of `fields` at `p` into `out` (one per field), in which
/// cells taken out of the gel count at the field's wall value `wall[g]` (the gel at a bubble's
/// surface is at Henry equilibrium with it: dropping those corners instead would extrapolate
/// the field from farther out, and every displacement would then pull the wall layer toward
/// the far field — measured: dissolution of a bubble of R0 = 4h 1.6 % early). Corners outside
/// the phantom are dropped and the weights renormalised; `fallback[g]` if none is left.
pub fn interpolate_gases<F: AsRef<[f64]>>(
    grid: &Grid,
    fields: &[F],
    p: [f64; 3],
    wall: &[f64],
    fallback: &[f64],
    out: &mut [f64],
) {
    grid.interpolate_many(p, fallback, out, |idx, v| {
        if grid.inside(idx) {
            for (v, f) in v.iter_mut().zip(fields) {
                *v = f.as_ref()[idx];
            }
            true
        } else if grid.is_excluded(idx) {
            v.copy_from_slice(&wall[..v.len()]);
            true
        } else {
            false
        }
    })
}

/// Value for a cell given back to the gel without a remap (a bubble dissolved or merged): the
/// mean of its face neighbours in the gel, or `fallback` if it has none.
pub fn neighbour_mean(grid: &Grid, field: &[f64], idx: usize, fallback: f64) -> f64 {
    let [nx, ny, nz] = grid.n;
    let (i, j, k) = (idx % nx, (idx / nx) % ny, idx / (nx * ny));
    let mut sum = 0.0;
    let mut n = 0;
    let mut visit = |q: usize| {
        if grid.inside(q) {
            sum += field[q];
            n += 1;
        }
    };
    if i > 0 {
        visit(idx - 1);
    }
    if i + 1 < nx {
        visit(idx + 1);
    }
    if j > 0 {
        visit(idx - nx);
    }
    if j + 1 < ny {
        visit(idx + nx);
    }
    if k > 0 {
        visit(idx - nx * ny);
    }
    if k + 1 < nz {
        visit(idx + nx * ny);
    }
    if n > 0 {
        sum / n as f64
    } else {
        fallback
    }
}

#[cfg(test)]
mod tests {
    use super::super::grid::{Grid, Shape};
    use super::*;

    fn cube(n: usize, h: f64) -> Grid {
        Grid::new(
            Shape::Box {
                size: [n as f64 * h; 3],
            },
            h,
            &[],
        )
        .unwrap()
    }

    /// A field linear in x is interpolated exactly by the trilinear rule, so the remap must
    /// return C(x_b) with x_b on the cell's ray at r_b = (r³ − (R₁³ − R₀³))^{1/3}, computed here
    /// from the definition (the gel volume between the bubble and the particle is conserved).
    #[test]
    fn remap_moves_the_gel_along_rays_conserving_its_volume() {
        let h = 1e-4;
        let grid = cube(40, h);
        let c = [2e-3, 2e-3, 2e-3];
        let field: Vec<f64> = (0..grid.len())
            .map(|idx| 1.0 + 100.0 * ((idx % 40) as f64 + 0.5) * h)
            .collect();
        let (r0, r1) = (3e-4, 4e-4);
        let out = remap(
            &grid,
            std::slice::from_ref(&field),
            &[0.0],
            c,
            r0,
            r1,
            1.5e-3,
        );
        // per plane, in plane order: every cell once, planes ascending
        let out = out.concat();
        assert!(out.windows(2).all(|w| w[0].0 < w[1].0));
        assert!(out.len() > 1000);
        let mut checked = 0;
        for (idx, v) in &out {
            let (i, j, k) = (idx % 40, (idx / 40) % 40, idx / 1600);
            let p = [i, j, k].map(|a| (a as f64 + 0.5) * h);
            let x: Vec<f64> = (0..3).map(|a| p[a] - c[a]).collect();
            let r = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
            assert!(r >= r1 && r <= 1.5e-3);
            let rb = (r.powi(3) - (r1.powi(3) - r0.powi(3))).cbrt();
            // the gel between the bubble and the particle keeps its volume
            assert!(((r.powi(3) - r1.powi(3)) / (rb.powi(3) - r0.powi(3)) - 1.0).abs() < 1e-12);
            let want = 1.0 + 100.0 * (c[0] + x[0] * rb / r);
            assert!((v[0] - want).abs() < 1e-12, "{} vs {want}", v[0]);
            checked += 1;
        }
        assert_eq!(checked, out.len());
    }

    /// A uniform gel stays uniform under any displacement (growth or shrinkage), also next to
    /// cells taken out of the gel.
    #[test]
    fn a_uniform_gel_stays_uniform() {
        let h = 1e-4;
        let mut grid = cube(30, h);
        let c = [1.5e-3, 1.5e-3, 1.5e-3];
        let cells = covered_cells(&grid, c, 3.2e-4);
        // 4/3·π·3.2³ ≈ 137 cell volumes; the count of centres inside must be close
        assert!(
            (cells.len() as f64 / 137.26 - 1.0).abs() < 0.1,
            "{}",
            cells.len()
        );
        grid.set_excluded(&cells, true);
        let field: Vec<f64> = (0..grid.len())
            .map(|i| if grid.inside(i) { 3.7 } else { 0.0 })
            .collect();
        for (r0, r1) in [(3.2e-4, 3.6e-4), (3.2e-4, 2.5e-4)] {
            let out = remap(
                &grid,
                std::slice::from_ref(&field),
                &[3.7],
                c,
                r0,
                r1,
                1.2e-3,
            );
            for (_, v) in out.concat() {
                assert!((v[0] - 3.7).abs() < 1e-12);
            }
        }
    }

    /// Excluding cells seals the faces toward them and giving them back restores the mask's
    /// codes exactly (and the explicit kernel's spans).
    #[test]
    fn exclusion_is_undone_exactly() {
        let mut grid = cube(12, 1e-4);
        let codes = grid.codes.clone();
        let spans = grid.interior_spans.clone();
        let cells = covered_cells(&grid, [6e-4; 3], 2.1e-4);
        grid.set_excluded(&cells, true);
        for &idx in &cells {
            assert!(!grid.inside(idx) && grid.is_excluded(idx));
            // a neighbour in the gel sees a sealed face toward it
            if !cells.contains(&(idx + 1)) {
                assert_eq!(grid.codes[0][idx + 1] & 3, 0);
            }
        }
        assert_ne!(grid.interior_spans, spans);
        grid.set_excluded(&cells, false);
        assert_eq!(grid.codes, codes);
        assert_eq!(grid.interior_spans, spans);
    }
}
