//! The gas-transport solver for eq. (2.1), ∂C/∂t = D∇²C, on the cell-centred grid
//! (finite volumes, 7-point stencil). Open faces hold C at the chamber value C_b at
//! half a cell from the outermost centres; sealed faces carry no flux.
//!
//! Two schemes, both conservative to round-off (the interior face fluxes cancel in pairs):
//! - [`explicit_step`]: forward Euler for the interior sides, the open sides' term
//!   2r·(C_b − C') taken implicitly in the cell itself (a division per boundary cell,
//!   `explicit::open_sides_implicit`), used when the step the physics asks for is below the
//!   positivity limit dt ≤ h²/(6D) (6 the largest number of interior sides; with explicit
//!   open sides, counted 2 each, it was h²/(9D) in a corner with three open faces, which
//!   held every grid with an open corner to ⅔ of the step); the simulation uses
//!   [`explicit_steps_in_place`], the same bits without a second field (z-plane blocks in
//!   parallel, each keeping the old planes it still needs in per-thread buffers), with as
//!   many gases as threads or on one thread [`explicit_steps_shifting_per_field`] (a thread
//!   per field, each moved by two planes in a store with two planes to spare, so that no plane
//!   is copied; [`explicit_steps_in_place_per_field`] is the same with the copy), and on small
//!   grids with more than one thread, when the step ends at a frame with the gel's state, [`explicit_steps_into`] a second set of
//!   fields (`sim::OUT_OF_PLACE_BYTES`), which passes the gel over each plane it has just
//!   written (`explicit_steps_into_passing_gel`); all give the same bits. A row's interior span takes the
//!   plain 7-point stencil; its other cells the per-cell terms, side by side where a run of
//!   them shares its face codes (`uniform_span`). A row with one such cell at each end whose
//!   other sides are interior (`row_ends`: most rows of a box or a cylinder) takes the span's
//!   stencil over its ends too and puts them right after, the two in one SSE2 vector
//!   (`row_end_pair`), and consecutive such rows that fill the plane's width (`whole_row`: a
//!   box between its y faces) take one pass for all of them: the same bits, without a pass and
//!   two cell-by-cell cells per row (on the 60³ cube a row is 60 cells, and the per-row work was
//!   most of the step);
//! - [`implicit_step`]: locally one-dimensional backward Euler (x, y, then z tridiagonal
//!   solves, Thomas algorithm), unconditionally stable and positivity-preserving, used when
//!   long holds allow large steps. For a box with uniform D the three 1-D operators commute,
//!   so the splitting adds no error beyond backward Euler's own to the homogeneous step. With a
//!   source S (the bubbles' deposits) it does: the fixed point of the split step solves
//!   A·u − dt·(A_xA_y + A_yA_z + A_zA_x)·u + dt²·A_xA_yA_z·u = −S, not A·u = −S, so the field
//!   near a steady sink depends on the step (README, "Time stepping": −6 % / −18 % / −38 % in
//!   the depression one to two cells from a point sink at 3.6 / 10 / 30 s steps, h = 100 µm;
//!   on the bubbles' runs the exchange over a long step matters more).
//!
//! Both return the amount that entered through open faces during the step (mol per unit of
//! `cell_volume`, i.e. multiply by h³ for mol), for the gas balance.
//!
//! # The implicit kernel ([`ImplicitSolver`])
//!
//! Each line segment's Thomas factors depend only on its length class, its ends and the
//! position in it, so a `LinePlan` (updated when [`Grid::codes_id`] changes) gives every
//! cell, per direction, a u16 index into a small factor table (rebuilt per step from r and
//! C_b). Lines are solved many at a time in lock-step along the contiguous index, vectorised
//! across lines (independent systems: the same operations per cell as the generic sweep, in
//! the same order, hence the same bits, for any thread count):
//! - **x and y, per z-plane** (planes in parallel; a 128×128 plane is 128 KiB and stays in
//!   L2): the plane is transposed into a per-thread copy whose rows are positions along the
//!   x lines, each line shifted to start at its first cell inside the shape (row stride ny,
//!   padded by `x_row_stride` against cache-set conflicts), so the x lines run across
//!   contiguous rows, and in a cylinder a row's middle cells share one table row (the
//!   shift turned the cylinder's per-cell runs into broadcast ones: Fig. 5 −4 %, README);
//!   only the cells within the lines' extents are copied; forward elimination row by row,
//!   back substitution in reverse,
//!   transpose back, keep the x-open cells' values (the x inflow is summed afterwards in cell
//!   order, as the generic sweep does), then the y lines the same way on the plane itself.
//! - **z**, in column chunks (in parallel) sized so a chunk's nz planes stay in L2 between
//!   the forward and backward pass.
//! - Several gases: [`ImplicitSolver::steps`] solves them side by side (one plan, a table per
//!   gas), each the bits of its own step.
//!
//! Every row (x: a plane's x position, y: a plane's y position, z: a whole plane, in pieces
//! of one y position) is cut at plan time into `Run`s along its contiguous index: stretches
//! of one table row (in a box, whole rows; in a cylinder, the z rows' inside cells of each y
//! position) use broadcast factors and exactly the
//! generic sweep's terms; stretches of middle rows (linked, no open face) look up only the
//! pivot and the back-substitution weight per cell (gathered, 8 or 4 cells per instruction
//! with AVX-512 or AVX2); the rest looks up the full factor row per cell (its back
//! substitution gathered the same way); cells outside are skipped. The inner loops are
//! compiled three times (baseline, AVX2, AVX-512F via `#[target_feature]`, no FMA: Rust never
//! contracts) and the best the CPU has is picked at run time; all variants are tested
//! against the generic sweep.

use super::gel_pass::{plane_gel_of, PlaneGel};

use super::grid::{EdgeRun, Grid, INSIDE_BIT, SIDE_INTERIOR, SIDE_OPEN, SIDE_SEALED};
use crate::gas::Gas;
use rayon::prelude::*;

/// Instantiate a kernel for an instruction set: `#[target_feature]` lets the compiler
/// vectorise the inlined body with that set's registers (no FMA: Rust never contracts).
macro_rules! isa_variants {
    ($name:ident, $avx2:ident, $avx512:ident, ($($arg:ident: $ty:ty),*) $(-> $ret:ty)?) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        #[allow(clippy::too_many_arguments)]
        unsafe fn $avx2($($arg: $ty),*) $(-> $ret)? {
            $name($($arg),*)
        }
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        #[allow(clippy::too_many_arguments)]
        unsafe fn $avx512($($arg: $ty),*) $(-> $ret)? {
            $name($($arg),*)
        }
    };
}

mod explicit;
mod implicit;

pub(super) use explicit::explicit_steps_into_passing_gel;
pub use explicit::{
    explicit_step, explicit_step_in_place, explicit_steps_in_place,
    explicit_steps_in_place_per_field, explicit_steps_into, explicit_steps_shifting_per_field,
};
pub use implicit::{implicit_step, ImplicitSolver};

/// Stencil weight of a side code: sealed 0, interior 1, open 2 (half-cell distance).
#[inline(always)]
fn weight(code: u8) -> f64 {
    match code {
        SIDE_INTERIOR => 1.0,
        SIDE_OPEN => 2.0,
        _ => 0.0,
    }
}

/// The largest over the inside cells of the sum of `side(code)` over their six sides. A cell's
/// sum depends only on its codes, and every inside cell is in its row's interior span (six
/// interior sides) or in one of its row's edge runs, whose cells share their codes
/// ([`Grid::edge_runs`]): one cell per span and per run is enough.
fn max_side_sum(grid: &Grid, side: impl Fn(u8) -> f64 + Sync) -> f64 {
    let sum = |code: [u8; 3]| -> f64 {
        let mut n = 0.0;
        for c in code {
            n += side(c & 3) + side((c >> 2) & 3);
        }
        n
    };
    let full = sum([SIDE_INTERIOR | (SIDE_INTERIOR << 2); 3]);
    // rows in parallel (a maximum of small whole numbers: exact in any order)
    (0..grid.n[1] * grid.n[2])
        .into_par_iter()
        .with_min_len(64)
        .map(|row| {
            let (i0, i1) = grid.interior_spans[row];
            let mut m: f64 = if i1 > i0 { full } else { 0.0 };
            for run in grid.edge_runs.of(row) {
                m = m.max(sum(run.codes));
            }
            m
        })
        .reduce(|| 0.0, f64::max)
}

/// Largest number of interior sides of an inside cell (6 wherever a cell has all its
/// neighbours; at least 1). The explicit step takes open sides implicitly
/// ([`open_sides_implicit`]) and sealed ones carry nothing, so this alone sets its limit.
fn max_interior_sides(grid: &Grid) -> f64 {
    max_side_sum(grid, |c| f64::from(u8::from(c == SIDE_INTERIOR))).max(1.0)
}

/// The two scans of a grid behind the step limits (`max_interior_sides` and the largest
/// stencil weight sum w_max, an open side counted 2), done once for a run's every gas.
#[derive(Debug, Clone, Copy)]
pub struct LimitScans {
    interior_sides: f64,
    weight_sum: f64,
}

impl LimitScans {
    /// The scans of `grid` as its codes are now.
    pub fn of(grid: &Grid) -> LimitScans {
        LimitScans {
            interior_sides: max_interior_sides(grid),
            weight_sum: max_side_sum(grid, weight),
        }
    }

    /// The largest stable, positivity-preserving explicit step, s: dt ≤ h²/(D·n) with n the
    /// largest number of interior sides. Each cell's new value is then a combination of old
    /// values and C_b with non-negative weights (C − r·n·C + r·Σ C_n, divided by 1 + s with its
    /// open sides' s·C_b added), and the step's matrix (I + S)⁻¹(I + r·L_interior) has no
    /// eigenvalue beyond ±1. Before 26 Nov 2026 the open sides were explicit and counted 2
    /// each, which made a corner with three open faces (9) set the limit for the whole grid:
    /// ⅔ of this.
    pub fn explicit_limit(&self, h: f64, d: f64) -> f64 {
        h * h / (d * self.interior_sides)
    }

    /// h²/(D·w_max), w_max the largest stencil weight sum of an inside cell with an open side
    /// counted 2 (9 in a corner with three open faces, 6 where every side is interior): the
    /// forward-Euler limit of the step with explicit open sides, as it was before 26 Nov 2026,
    /// and still the unit of [`super::params::Numerics::implicit_cost_ratio`], so that a step
    /// is implicit from the same length as before on every grid (the verification figures
    /// near bubbles were set with it).
    pub fn implicit_cost_unit(&self, h: f64, d: f64) -> f64 {
        h * h / (d * self.weight_sum)
    }
}

/// [`LimitScans::explicit_limit`] of `grid` for diffusivity `d`, s.
pub fn explicit_limit(grid: &Grid, d: f64) -> f64 {
    LimitScans::of(grid).explicit_limit(grid.h, d)
}

/// The instruction sets the kernel is compiled for; [`Isa::detect`] picks the best the CPU
/// has, once per step. All give the same bits (the same operations per cell, vectorised
/// across independent lines only).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Isa {
    /// The build's baseline (SSE2 on x86_64).
    Portable,
    /// AVX2 (256-bit vectors).
    #[cfg(target_arch = "x86_64")]
    Avx2,
    /// AVX-512F (512-bit vectors).
    #[cfg(target_arch = "x86_64")]
    Avx512,
}

impl Isa {
    fn detect() -> Isa {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                return Isa::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                return Isa::Avx2;
            }
        }
        Isa::Portable
    }

    /// Every variant this CPU can run (for the tests).
    #[cfg(test)]
    fn available() -> Vec<Isa> {
        #[allow(unused_mut)]
        let mut v = vec![Isa::Portable];
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                v.push(Isa::Avx2);
            }
            if std::arch::is_x86_feature_detected!("avx512f") {
                v.push(Isa::Avx512);
            }
        }
        v
    }
}

/// The field-error pass of a step ([`super::sim`]'s `diffuse`): with `after` the field at
/// the end of the step and `before_to_error` at its start, stores each inside cell's change
/// δ = after − before in `change` (which held the last step's change δ'), overwrites
/// `before_to_error` with the raw error vector δ − ratio·δ' (0 outside; ratio = this step
/// over the last).
pub fn change_and_error(
    grid: &Grid,
    after: &[f64],
    before_to_error: &mut [f64],
    change: &mut [f64],
    ratio: f64,
) {
    let plane = grid.n[0] * grid.n[1];
    let inside = &grid.codes[0];
    change
        .par_chunks_mut(plane)
        .zip(before_to_error.par_chunks_mut(plane))
        .enumerate()
        .for_each(|(k, (slab, err))| {
            let lo = k * plane;
            for (q, (last, e)) in slab.iter_mut().zip(err.iter_mut()).enumerate() {
                let idx = lo + q;
                if inside[idx] & INSIDE_BIT == 0 {
                    *last = 0.0;
                    *e = 0.0;
                    continue;
                }
                let delta = after[idx] - *e;
                *e = delta - ratio * *last;
                *last = delta;
            }
        });
}

/// Root mean square of `field` over the inside cells. Per-plane sums added in plane order:
/// independent of the thread count.
pub fn rms_inside(grid: &Grid, field: &[f64]) -> f64 {
    let plane = grid.n[0] * grid.n[1];
    let inside = &grid.codes[0];
    let per_plane: Vec<f64> = field
        .par_chunks(plane)
        .enumerate()
        .map(|(k, slab)| {
            let codes = &inside[k * plane..(k + 1) * plane];
            slab.iter()
                .zip(codes)
                .filter(|(_, c)| *c & INSIDE_BIT != 0)
                .map(|(x, _)| x * x)
                .sum::<f64>()
        })
        .collect();
    (per_plane.iter().sum::<f64>() / grid.n_inside.max(1) as f64).sqrt()
}

/// Weights of the exact solution of the perfusion term over one step, for
/// [`perfusion_step`]: with the blood value C_b(t) linear over the step (C_b0 → C_b1),
/// dC/dt = −k·(C − C_b(t)) integrates exactly to
/// C1 = e·C0 + (φ − e)·C_b0 + (1 − φ)·C_b1, with e = exp(−k·dt) and φ = (1 − e)/(k·dt).
/// All three weights are ≥ 0 and sum to 1, so the phase is unconditionally stable and keeps
/// every cell within the range of C0, C_b0 and C_b1 (positivity-preserving).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PerfusionWeights {
    /// Weight of the old concentration, e = exp(−k·dt).
    pub old: f64,
    /// Weight of the blood value at the start of the step, φ − e.
    pub blood_start: f64,
    /// Weight of the blood value at the end of the step, 1 − φ.
    pub blood_end: f64,
}

impl PerfusionWeights {
    /// Weights for rate `k` (1/s) over step `dt` (s).
    pub fn new(k: f64, dt: f64) -> PerfusionWeights {
        let x = k * dt;
        let e = (-x).exp();
        // φ = (1 − e^{−x})/x, written with expm1 so that it stays accurate as x → 0 (φ → 1)
        let phi = if x > 0.0 { -(-x).exp_m1() / x } else { 1.0 };
        PerfusionWeights {
            old: e,
            blood_start: (phi - e).max(0.0),
            blood_end: (1.0 - phi).max(0.0),
        }
    }
}

/// The perfusion phase of a step, operator-split from diffusion: every inside cell relaxes
/// toward the blood value with the exact weights `w` (see [`PerfusionWeights`]). Returns the
/// gas added to the grid (mol per unit of `cell_volume`: multiply by h³ for mol; negative
/// when perfusion removes gas). The sum is formed per z-plane and then in plane order, so the
/// result does not depend on the number of threads.
pub fn perfusion_step(grid: &Grid, u: &mut [f64], w: PerfusionWeights, cb0: f64, cb1: f64) -> f64 {
    let [nx, ny, _] = grid.n;
    let plane = nx * ny;
    let source = w.blood_start * cb0 + w.blood_end * cb1;
    let inside = &grid.codes[0];
    let per_plane: Vec<f64> = u
        .par_chunks_mut(plane)
        .enumerate()
        .map(|(k, slab)| {
            let mut added = 0.0;
            let codes = &inside[k * plane..(k + 1) * plane];
            for (x, c) in slab.iter_mut().zip(codes) {
                if c & INSIDE_BIT == 0 {
                    continue;
                }
                let new = w.old * *x + source;
                added += new - *x;
                *x = new;
            }
            added
        })
        .collect();
    per_plane.iter().sum()
}

#[cfg(test)]
mod tests {
    use super::super::grid::{Face, Shape};
    use super::explicit::*;
    use super::implicit::*;
    use super::*;

    fn sealed_box(n: usize) -> Grid {
        Grid::new(
            Shape::Box {
                size: [n as f64 * 1e-4; 3],
            },
            1e-4,
            &[],
        )
        .unwrap()
    }

    #[test]
    fn both_schemes_conserve_in_a_sealed_box() {
        let g = sealed_box(9);
        let mut u: Vec<f64> = (0..g.len()).map(|i| ((i * 7919) % 101) as f64).collect();
        let total0 = g.integrate(&u);
        let mut out = vec![0.0; g.len()];
        explicit_step(&g, &u, &mut out, 1e-9, 1.0, 0.0);
        assert!((g.integrate(&out) / total0 - 1.0).abs() < 1e-13);
        let mut s = vec![0.0; g.len()];
        implicit_step(&g, &mut u, &mut s, 1e-9, 50.0, 0.0);
        assert!((g.integrate(&u) / total0 - 1.0).abs() < 1e-13);
    }

    /// Unconditional stability and positivity: backward Euler's matrices are M-matrices, so
    /// the new field stays within the range of the old field and the boundary value (discrete
    /// maximum principle) for any step; forward Euler does so up to its stated limit.
    #[test]
    fn both_schemes_keep_the_maximum_principle() {
        let g = Grid::new(
            Shape::Box {
                size: [1.2e-3, 0.9e-3, 0.6e-3],
            },
            1e-4,
            &[Face::Top, Face::XMinus],
        )
        .unwrap();
        let d = 2.5e-9;
        let u0: Vec<f64> = (0..g.len())
            .map(|i| ((i * 7919 + 13) % 101) as f64 / 100.0)
            .collect();
        let cb = 1.5;
        let (lo, hi) = (0.0f64, cb);
        let limit = explicit_limit(&g, d);
        for factor in [1.0, 10.0, 1e3, 1e6] {
            let mut u = u0.clone();
            let mut s = vec![0.0; g.len()];
            implicit_step(&g, &mut u, &mut s, d, factor * limit, cb);
            for (i, x) in u.iter().enumerate() {
                if g.inside(i) {
                    assert!(
                        *x >= lo - 1e-12 && *x <= hi + 1e-12,
                        "implicit, {factor}× the limit: {x}"
                    );
                }
            }
        }
        let mut out = vec![0.0; g.len()];
        explicit_step(&g, &u0, &mut out, d, limit, cb);
        assert!(out
            .iter()
            .enumerate()
            .all(|(i, x)| !g.inside(i) || (*x >= lo - 1e-12 && *x <= hi + 1e-12)));
    }

    /// The explicit limit with implicit open faces, h²/(6D), is the real stability bound and no
    /// more: on a box open on every face (corners with three open faces, where forward Euler
    /// with explicit open faces needed h²/(9D)), 300 steps at the limit from the checkerboard
    /// ±1 (the mode the bound is about) and from a rough field never raise the largest
    /// |C − C_b| (the maximum principle, hence stability in the max norm), while 300 steps at
    /// 1.1× the limit grow the checkerboard beyond its start (|1 − 12r| > 1 for r > 1/6).
    #[test]
    fn explicit_steps_at_the_limit_are_stable_and_beyond_it_are_not() {
        let size = [1.6e-3, 1.2e-3, 1.0e-3];
        let g = Grid::new(Shape::Box { size }, 1e-4, Shape::Box { size }.faces()).unwrap();
        let (d, cb) = (2.5e-9, 0.0);
        let limit = explicit_limit(&g, d);
        assert!((limit / (g.h * g.h / (6.0 * d)) - 1.0).abs() < 1e-12);
        let [nx, ny, _] = g.n;
        let checker: Vec<f64> = (0..g.len())
            .map(|i| {
                let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
                if (x + y + z) % 2 == 0 {
                    1.0
                } else {
                    -1.0
                }
            })
            .collect();
        let rough: Vec<f64> = (0..g.len())
            .map(|i| ((i * 7919 + 13) % 101) as f64 / 50.0 - 1.0)
            .collect();
        let largest = |u: &[f64]| {
            (0..g.len())
                .filter(|&i| g.inside(i))
                .map(|i| (u[i] - cb).abs())
                .fold(0.0f64, f64::max)
        };
        for start in [&checker, &rough] {
            let mut u = start.clone();
            let mut last = largest(&u);
            for _ in 0..300 {
                explicit_step_in_place(&g, &mut u, d, limit, cb);
                let now = largest(&u);
                assert!(now <= last * (1.0 + 1e-12), "{now} after {last}");
                last = now;
            }
        }
        let mut u = checker.clone();
        for _ in 0..300 {
            explicit_step_in_place(&g, &mut u, d, 1.1 * limit, cb);
        }
        assert!(largest(&u) > 10.0, "1.1× the limit: {}", largest(&u));
    }

    #[test]
    fn implicit_line_solve_matches_dense_solve() {
        // A 1-D open line (5 cells) along x solved as a dense system independently.
        let g = Grid::new(
            Shape::Box {
                size: [5e-4, 3e-4, 3e-4],
            },
            1e-4,
            &[Face::XMinus, Face::XPlus],
        )
        .unwrap();
        let mut u = vec![0.0; g.len()];
        for (i, x) in u.iter_mut().enumerate() {
            *x = (i % 5) as f64;
        }
        let orig = u.clone();
        let (r, cb) = (0.7, 3.0);
        let mut s = vec![0.0; g.len()];
        sweep(&g, 0, &mut u, &mut s, r, cb);
        // dense Gaussian elimination of the same 5x5 system for the first line
        let n = 5;
        let mut a = vec![vec![0.0; n + 1]; n];
        for i in 0..n {
            let wl = if i == 0 { 2.0 } else { 1.0 };
            let wr = if i == n - 1 { 2.0 } else { 1.0 };
            a[i][i] = 1.0 + r * (wl + wr);
            if i > 0 {
                a[i][i - 1] = -r;
            }
            if i < n - 1 {
                a[i][i + 1] = -r;
            }
            a[i][n] = orig[i]
                + if i == 0 || i == n - 1 {
                    2.0 * r * cb
                } else {
                    0.0
                };
        }
        for c in 0..n {
            for rr in c + 1..n {
                let f = a[rr][c] / a[c][c];
                for k in c..=n {
                    a[rr][k] -= f * a[c][k];
                }
            }
        }
        let mut x = vec![0.0; n];
        for i in (0..n).rev() {
            let mut s = a[i][n];
            for k in i + 1..n {
                s -= a[i][k] * x[k];
            }
            x[i] = s / a[i][i];
        }
        for i in 0..n {
            assert!((u[i] - x[i]).abs() < 1e-12, "{} vs {}", u[i], x[i]);
        }
    }
}

#[cfg(test)]
mod planned_tests;
