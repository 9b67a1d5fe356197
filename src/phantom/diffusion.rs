//! The gas-transport solver for eq. (2.1), ∂C/∂t = D∇²C, on the cell-centred grid
//! (finite volumes, 7-point stencil). Open faces hold C at the chamber value C_b at
//! half a cell from the outermost centres; sealed faces carry no flux.
//!
//! Two schemes, both conservative to round-off (the interior face fluxes cancel in pairs):
//! - [`explicit_step`]: forward Euler for the interior sides, the open sides' term
//!   2r·(C_b − C') taken implicitly in the cell itself (a division per boundary cell,
//!   [`open_sides_implicit`]), used when the step the physics asks for is below the
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

/// The two scans of a grid behind the step limits ([`max_interior_sides`] and the largest
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

/// One forward-Euler step from `u` into `out` with r = D·dt/h². Cells outside the gel (outside
/// the phantom, or taken out by a bubble) are not written: nothing reads their values (every
/// pass over the field skips them), and on the Fig. 5 cylinder they are a fifth of the grid.
/// Returns the boundary inflow (sum of concentration change due to open faces).
pub fn explicit_step(grid: &Grid, u: &[f64], out: &mut [f64], d: f64, dt: f64, cb: f64) -> f64 {
    explicit_step_with(grid, u, out, d, dt, cb, Isa::detect())
}

/// [`explicit_step`] in place, without a second field: the same bits in every inside cell and
/// the same inflow (cells outside keep their values). The z-planes are cut into contiguous
/// blocks, one task each; a block goes upward plane by plane, keeping the old values of the
/// plane below and of the current one in per-thread plane buffers, and the old planes just
/// outside it (overwritten by its neighbours) are copied into a halo before the pass.
pub fn explicit_step_in_place(grid: &Grid, u: &mut [f64], d: f64, dt: f64, cb: f64) -> f64 {
    explicit_step_in_place_with(grid, u, d, dt, cb, Isa::detect())
}

/// The 7-point stencil over the cells `a..a + o.len()` of a z-plane into `o`, from the old
/// values of the plane (`c`), the one below (`zm`) and the one above (`zp`), for cells whose
/// six neighbours are all inside (the same operations in the same order for every
/// instruction set: vectorised across cells only).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn stencil_span(
    zm: &[f64],
    c: &[f64],
    zp: &[f64],
    o: &mut [f64],
    a: usize,
    nx: usize,
    centre: f64,
    r: f64,
) {
    let b = a + o.len();
    let xm = &c[a - 1..b - 1];
    let xp = &c[a + 1..b + 1];
    let ym = &c[a - nx..b - nx];
    let yp = &c[a + nx..b + nx];
    let zm = &zm[a..b];
    let zp = &zp[a..b];
    let c = &c[a..b];
    for (q, o) in o.iter_mut().enumerate() {
        *o = centre * c[q] + r * (xm[q] + xp[q] + ym[q] + yp[q] + zm[q] + zp[q]);
    }
}

/// The new values of z-plane `k`'s inside cells into `out` (the plane's slice), from the old
/// values of the plane (`c`), the one below (`zm`) and the one above (`zp`); `zm` (`zp`) may
/// be empty at the bottom (top) plane, where no cell has an interior face below (above).
/// Returns what entered the plane through open faces, Σ s·(C_b − C') over its cells with
/// open sides ([`open_sides_implicit`]), summed row by row in the order the cells are
/// written (a run of cells with the same codes as s·Σ(C_b − C')).
#[allow(clippy::too_many_arguments)]
fn stencil_plane(
    grid: &Grid,
    k: usize,
    zm: &[f64],
    c: &[f64],
    zp: &[f64],
    out: &mut [f64],
    r: f64,
    cb: f64,
    isa: Isa,
    mut save: Option<&mut [f64]>,
) -> f64 {
    let [nx, ny, _] = grid.n;
    let mut inflow = 0.0;
    let centre = 1.0 - 6.0 * r;
    // a row end's outer x side sealed or open ([`row_end_pair`])
    let end_sides = [0, 1].map(|open| OpenSides::new(open, r, cb));
    let planes = (zm, c, zp);
    let saving = save.is_some();
    let mut j = 0;
    while j < ny {
        let mut j2 = j;
        while j2 < ny && whole_row(grid, k, j2, saving).is_some() {
            j2 += 1;
        }
        if j2 > j + 1 {
            let (a, b) = (j * nx, j2 * nx);
            plain_span(planes, &mut out[a..b], a, nx, centre, r, isa);
            if let Some(save) = save.as_deref_mut() {
                save[a..b].copy_from_slice(&zp[a..b]);
            }
            for j in j..j2 {
                let ends = whole_row(grid, k, j, saving).expect("a whole row");
                let row = ([j * nx, j * nx + nx - 1], ends);
                put_row_ends(planes, out, row, nx, (r, cb), end_sides, &mut inflow);
            }
            j = j2;
            continue;
        }
        let row = j + ny * k;
        let base = j * nx;
        if let Some(save) = save.as_deref_mut() {
            // the row above, kept before the pass over this row reads it (it is then in the
            // core's first-level cache for the stencil's z+ neighbours): its cells inside the
            // shape, the only ones the next plane's pass reads
            let (e0, e1) = grid.inside_extents[j + ny * (k + 1)];
            let (a, b) = (base + e0 as usize, base + (e1 as usize).max(e0 as usize));
            save[a..b].copy_from_slice(&zp[a..b]);
        }
        let (i0, i1) = grid.interior_spans[row];
        let (i0, i1) = (i0 as usize, i1 as usize);
        let runs = grid.edge_runs.of(row);
        // a row with one cell outside its span at each end, each with every side interior but
        // its outer x one: the span's stencil taken over them too (their neighbours across
        // that side are other cells of the plane), their values then put right
        let ends = row_ends(runs, i0, i1);
        let (s0, s1) = if ends.is_some() {
            (i0 - 1, i1 + 1)
        } else {
            (i0, i1)
        };
        if s1 > s0 {
            // all six neighbours exist and are inside: plain 7-point stencil, branch-free; first,
            // so that the row's other cells find their neighbours' cache lines loaded
            plain_span(
                planes,
                &mut out[base + s0..base + s1],
                base + s0,
                nx,
                centre,
                r,
                isa,
            );
        }
        if let Some(ends) = ends {
            let row = ([base + s0, base + s1 - 1], ends);
            put_row_ends(planes, out, row, nx, (r, cb), end_sides, &mut inflow);
            j += 1;
            continue;
        }
        // runs of inside cells with the same codes: one branch-free pass per side
        for run in runs {
            let (i, j, code) = (run.start as usize, run.end as usize, run.codes);
            if j - i >= UNIFORM_RUN {
                let (o, a) = (&mut out[base + i..base + j], base + i);
                inflow += match isa {
                    Isa::Portable => uniform_span(zm, c, zp, o, a, nx, code, r, cb),
                    // SAFETY: `Isa::detect` found the instruction set on this CPU
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx2 => unsafe { uniform_span_avx2(zm, c, zp, o, a, nx, code, r, cb) },
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx512 => unsafe { uniform_span_avx512(zm, c, zp, o, a, nx, code, r, cb) },
                };
            } else {
                for q in base + i..base + j {
                    out[q] = generic_cell(planes, q, code, nx, (r, cb), &mut inflow);
                }
            }
        }
        j += 1;
    }
    inflow
}

/// The plain 7-point stencil ([`stencil_span`]) into `o`, the cells `a..a + o.len()` of a
/// plane, compiled for `isa`.
#[inline(always)]
fn plain_span(
    (zm, c, zp): (&[f64], &[f64], &[f64]),
    o: &mut [f64],
    a: usize,
    nx: usize,
    centre: f64,
    r: f64,
    isa: Isa,
) {
    match isa {
        Isa::Portable => stencil_span(zm, c, zp, o, a, nx, centre, r),
        // SAFETY: `Isa::detect` found the instruction set on this CPU
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { stencil_span_avx2(zm, c, zp, o, a, nx, centre, r) },
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => unsafe { stencil_span_avx512(zm, c, zp, o, a, nx, centre, r) },
    }
}

/// Whether row `j` of plane `k` has every cell inside, with one end cell each side as
/// [`row_ends`] (and, when `saving` the plane above, whether that plane's row `j` has every
/// cell inside too): then as [`row_ends`]. Consecutive such rows are one stretch of the plane,
/// which takes one pass of the stencil ([`stencil_plane`]; the rows of a box between its y
/// faces).
#[inline(always)]
fn whole_row(grid: &Grid, k: usize, j: usize, saving: bool) -> Option<[EdgeRun; 2]> {
    let [nx, ny, _] = grid.n;
    let row = j + ny * k;
    let whole = nx >= 3
        && grid.interior_spans[row] == (1, nx as u32 - 1)
        && (!saving || grid.inside_extents[j + ny * (k + 1)] == (0, nx as u32));
    if whole {
        row_ends(grid.edge_runs.of(row), 1, nx - 1)
    } else {
        None
    }
}

/// The end cells `q0`, `q1` of a [`row_ends`] row (`ends` its two runs), put right in `out`
/// after the span's stencil was taken over them: [`row_end_pair`] when their outer x sides are
/// alike (`end_sides[open]` the sides of one open side or none), else [`generic_cell`] each.
#[inline(always)]
fn put_row_ends(
    planes: (&[f64], &[f64], &[f64]),
    out: &mut [f64],
    ([q0, q1], [left, right]): ([usize; 2], [EdgeRun; 2]),
    nx: usize,
    (r, cb): (f64, f64),
    end_sides: [OpenSides; 2],
    inflow: &mut f64,
) {
    #[cfg(target_arch = "x86_64")]
    {
        let open = [left.codes[0] & 3, (right.codes[0] >> 2) & 3].map(|side| side == SIDE_OPEN);
        if open[0] == open[1] {
            let sides = (end_sides[usize::from(open[0])], open[0]);
            [out[q0], out[q1]] = row_end_pair(planes, [q0, q1], nx, r, cb, sides, inflow);
            return;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = end_sides;
    out[q0] = generic_cell(planes, q0, left.codes, nx, (r, cb), inflow);
    out[q1] = generic_cell(planes, q1, right.codes, nx, (r, cb), inflow);
}

/// [`stencil_plane`]'s path for an inside cell `q` of the plane with a side that is not
/// interior, `code` its run's codes (the per-cell arrays are not read), from the old values of
/// the plane below, the plane and the one above (`planes`): forward Euler for the interior
/// sides in the order x−, x+, y−, y+, z−, z+, the open ones implicit ([`open_sides_implicit`]);
/// adds what entered through open faces to `inflow`. A function inlined into the plane's loop
/// (as a closure it was compiled apart and called per cell).
#[inline(always)]
fn generic_cell(
    (zm, c, zp): (&[f64], &[f64], &[f64]),
    q: usize,
    code: [u8; 3],
    nx: usize,
    (r, cb): (f64, f64),
    inflow: &mut f64,
) -> f64 {
    let ui = c[q];
    let mut acc = 0.0;
    let mut open = 0;
    for (dir, code) in code.into_iter().enumerate() {
        let m = code & 3;
        let p = (code >> 2) & 3;
        if m == SIDE_INTERIOR {
            acc += match dir {
                0 => c[q - 1],
                1 => c[q - nx],
                _ => zm[q],
            } - ui;
        } else if m == SIDE_OPEN {
            open += 1;
        }
        if p == SIDE_INTERIOR {
            acc += match dir {
                0 => c[q + 1],
                1 => c[q + nx],
                _ => zp[q],
            } - ui;
        } else if p == SIDE_OPEN {
            open += 1;
        }
    }
    let sides = OpenSides::new(open, r, cb);
    let new = open_sides_implicit(ui, r * acc, sides);
    if open > 0 {
        *inflow += sides.s * (cb - new);
    }
    new
}

/// Both sides of a direction code interior, the cell inside.
const BOTH_INTERIOR: u8 = SIDE_INTERIOR | (SIDE_INTERIOR << 2) | INSIDE_BIT;

/// Whether a row's cells outside its interior span `i0..i1` ([`Grid::edge_runs`] `runs`) are one
/// cell at each end of it, i0 − 1 and i1, each with every side interior but its outer x one:
/// then those two runs (the outer x side open or sealed). Such a row has a row of the
/// plane on both sides and planes above and below (those sides are interior), so the span's
/// stencil can be taken over its ends ([`stencil_plane`]). Every row of a box but those along
/// its y and z faces is one, and most of a cylinder's.
#[inline(always)]
fn row_ends(runs: &[EdgeRun], i0: usize, i1: usize) -> Option<[EdgeRun; 2]> {
    let &[l, r] = runs else { return None };
    let fits = i0 < i1
        && (l.start as usize, l.end as usize) == (i0 - 1, i0)
        && (r.start as usize, r.end as usize) == (i1, i1 + 1)
        && l.codes[1..] == [BOTH_INTERIOR; 2]
        && r.codes[1..] == [BOTH_INTERIOR; 2]
        && (l.codes[0] >> 2) & 3 == SIDE_INTERIOR
        && r.codes[0] & 3 == SIDE_INTERIOR;
    fits.then_some([l, r])
}

/// Both ends `[q0, q1]` of a [`row_ends`] row whose outer x sides are alike (open when `open`,
/// `sides` those of one open side, else sealed and no side), side by side in the two lanes of an
/// SSE2 vector: each lane [`generic_cell`]'s operations for such a cell in its order (the inner
/// x side, y−, y+, z−, z+, then the open side implicit), so its bits, with one division for the
/// two; their inflows added to `inflow` in the order q0, q1.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn row_end_pair(
    (zm, c, zp): (&[f64], &[f64], &[f64]),
    [q0, q1]: [usize; 2],
    nx: usize,
    r: f64,
    cb: f64,
    (sides, open): (OpenSides, bool),
    inflow: &mut f64,
) -> [f64; 2] {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of every x86_64 CPU (the target's baseline), and `out` holds two f64
    let out = unsafe {
        let lanes = |a: f64, b: f64| _mm_set_pd(b, a);
        let u = lanes(c[q0], c[q1]);
        let mut acc = _mm_setzero_pd();
        for nb in [
            lanes(c[q0 + 1], c[q1 - 1]),
            lanes(c[q0 - nx], c[q1 - nx]),
            lanes(c[q0 + nx], c[q1 + nx]),
            lanes(zm[q0], zm[q1]),
            lanes(zp[q0], zp[q1]),
        ] {
            acc = _mm_add_pd(acc, _mm_sub_pd(nb, u));
        }
        let r_acc = _mm_mul_pd(_mm_set1_pd(r), acc);
        // open_sides_implicit, lane by lane
        let new = if sides.s == 0.0 {
            _mm_add_pd(u, r_acc)
        } else {
            let num = _mm_add_pd(_mm_add_pd(u, r_acc), _mm_set1_pd(sides.s_cb));
            _mm_div_pd(num, _mm_set1_pd(1.0 + sides.s))
        };
        let mut out = [0.0; 2];
        _mm_storeu_pd(out.as_mut_ptr(), new);
        out
    };
    if open {
        for o in out {
            *inflow += sides.s * (cb - o);
        }
    }
    out
}

/// Runs of at least this many neighbouring cells with the same codes (a face of the grid, a
/// row along one) take [`uniform_span`]; shorter ones the cell-by-cell path.
const UNIFORM_RUN: usize = 4;

/// [`stencil_plane`]'s cell-by-cell path for a run of cells `a..a + o.len()` of one plane
/// that share their codes `code` (inside, the same kind of side in each of the six
/// directions), side by side: the same terms added in the same order (x−, x+, y−, y+, z−,
/// z+; an interior side C_n − C, a sealed one nothing; the open ones implicit,
/// [`open_sides_implicit`]), so the same bits, with `o` as the accumulator. Returns what
/// entered the run through open faces, s·Σ(C_b − C') (0 without open sides).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn uniform_span(
    zm: &[f64],
    c: &[f64],
    zp: &[f64],
    o: &mut [f64],
    a: usize,
    nx: usize,
    code: [u8; 3],
    r: f64,
    cb: f64,
) -> f64 {
    let b = a + o.len();
    let u = &c[a..b];
    o.fill(0.0);
    let mut open = 0;
    for (d, code) in code.into_iter().enumerate() {
        for (side, plus) in [(code & 3, false), ((code >> 2) & 3, true)] {
            if side == SIDE_INTERIOR {
                // an interior side: the neighbour exists for every cell of the run
                let nb = match (d, plus) {
                    (0, false) => &c[a - 1..b - 1],
                    (0, true) => &c[a + 1..b + 1],
                    (1, false) => &c[a - nx..b - nx],
                    (1, true) => &c[a + nx..b + nx],
                    (_, false) => &zm[a..b],
                    (_, true) => &zp[a..b],
                };
                for ((o, &n), &u) in o.iter_mut().zip(nb).zip(u) {
                    *o += n - u;
                }
            } else if side == SIDE_OPEN {
                open += 1;
            }
        }
    }
    let sides = OpenSides::new(open, r, cb);
    if open == 0 {
        for (o, &u) in o.iter_mut().zip(u) {
            *o = u + r * *o;
        }
        0.0
    } else {
        for (o, &u) in o.iter_mut().zip(u) {
            *o = open_sides_implicit(u, r * *o, sides);
        }
        sides.s * o.iter().fold(0.0, |acc, o| acc + (cb - o))
    }
}

/// A cell's open sides in the explicit step ([`open_sides_implicit`]): s = 2r·(their number)
/// and s·C_b.
#[derive(Clone, Copy)]
struct OpenSides {
    s: f64,
    s_cb: f64,
}

impl OpenSides {
    #[inline(always)]
    fn new(open: u32, r: f64, cb: f64) -> OpenSides {
        let s = (2 * open) as f64 * r;
        OpenSides { s, s_cb: s * cb }
    }
}

/// A cell's value after the explicit step, from its old value `ui` and the interior sides'
/// forward-Euler change `r_acc` = r·Σ(C_n − C), with its open sides (C_b at half a cell,
/// weight 2) taken implicitly: C' = C + r·Σ(C_n − C) + s·(C_b − C'), i.e.
/// C' = (C + r·Σ(C_n − C) + s·C_b)/(1 + s), s = 2r·(open sides). The open sides then add
/// nothing to the positivity limit ([`explicit_limit`]), which the interior sides alone set,
/// and the step still conserves gas exactly: what enters is s·(C_b − C') (summed by
/// [`stencil_plane`]). A cell with no open side is C + r·Σ(C_n − C).
#[inline(always)]
fn open_sides_implicit(ui: f64, r_acc: f64, sides: OpenSides) -> f64 {
    if sides.s == 0.0 {
        ui + r_acc
    } else {
        (ui + r_acc + sides.s_cb) / (1.0 + sides.s)
    }
}

/// [`explicit_step`] with the interior stencil compiled for `isa`.
fn explicit_step_with(
    grid: &Grid,
    u: &[f64],
    out: &mut [f64],
    d: f64,
    dt: f64,
    cb: f64,
    isa: Isa,
) -> f64 {
    let mut inflow = [0.0];
    explicit_steps_into_with(
        grid,
        &[u],
        &mut [out],
        &[(d, cb)],
        dt,
        &mut inflow,
        None,
        isa,
    );
    inflow[0]
}

/// The new values of z-plane `k`'s inside cells into `out` (the plane's slice) from the whole
/// field `u` before the step ([`stencil_plane`] with the plane and its neighbours).
#[allow(clippy::too_many_arguments)]
fn step_plane_from(
    grid: &Grid,
    u: &[f64],
    k: usize,
    out: &mut [f64],
    r: f64,
    cb: f64,
    isa: Isa,
) -> f64 {
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    let zm = if k > 0 {
        &u[(k - 1) * plane..k * plane]
    } else {
        &[]
    };
    let zp = if k + 1 < nz {
        &u[(k + 1) * plane..(k + 2) * plane]
    } else {
        &[]
    };
    let c = &u[k * plane..(k + 1) * plane];
    stencil_plane(grid, k, zm, c, zp, out, r, cb, isa, None)
}

/// Blocks of z-planes per thread in [`explicit_step_in_place`] (one task each): more balance
/// the load, fewer copy fewer halo planes.
const BLOCKS_PER_THREAD: usize = 2;

thread_local! {
    /// Per thread, the old values of three z-planes ([`explicit_step_in_place`]'s block pass).
    static OLD_PLANES: std::cell::RefCell<Vec<f64>> =
        const { std::cell::RefCell::new(Vec::new()) };
    /// The calling thread's halo of [`explicit_step_in_place`]: per block, the old plane below
    /// its first plane and the one above its last. Taken out for the step and put back after
    /// (not borrowed across it: while the thread waits in the step's parallel pass, rayon may
    /// run another simulation's step on it, which then finds it empty and uses its own).
    static HALO: std::cell::Cell<Vec<f64>> = const { std::cell::Cell::new(Vec::new()) };
    /// The calling thread's per-plane inflows of the explicit steps (plane k, field f at
    /// k·nf + f), taken out and put back as `HALO`.
    static PLANE_FLOWS: std::cell::Cell<Vec<f64>> = const { std::cell::Cell::new(Vec::new()) };
}

/// [`PLANE_FLOWS`] taken out, zeroed to `len`.
fn take_plane_flows(len: usize) -> Vec<f64> {
    let mut v = PLANE_FLOWS.take();
    v.clear();
    v.resize(len, 0.0);
    v
}

/// [`explicit_step_in_place`] with the interior stencil compiled for `isa`.
fn explicit_step_in_place_with(
    grid: &Grid,
    u: &mut [f64],
    d: f64,
    dt: f64,
    cb: f64,
    isa: Isa,
) -> f64 {
    let mut inflow = [0.0];
    explicit_steps_in_place_with(grid, &mut [u], &[(d, cb)], dt, &mut inflow, isa);
    inflow[0]
}

/// [`explicit_step_in_place`] of several fields over the same step `dt`, field `f` with
/// diffusivity and boundary value `dc[f] = (D_f, c_b,f)`, its inflow into `inflow[f]`: each
/// field the same bits as stepped alone, in one parallel pass (a block of planes steps every
/// field in turn) instead of two per field.
pub fn explicit_steps_in_place(
    grid: &Grid,
    fields: &mut [&mut [f64]],
    dc: &[(f64, f64)],
    dt: f64,
    inflow: &mut [f64],
) {
    explicit_steps_in_place_with(grid, fields, dc, dt, inflow, Isa::detect())
}

/// [`explicit_steps_in_place`] with a thread per field: the fields in parallel, one task each,
/// each going up all its planes in one block (no halo), the same bits: each core streams its
/// own field once, in place, with no fork and join per plane. Against the plane-parallel steps
/// on the 2-core Intel machine (26 Nov 2026, docs/speed-history.md, session 21, alternated):
/// the lone small run −5 %, Fig. 5 −2 to −4 %. Since session 24 `sim` takes
/// [`explicit_steps_shifting_per_field`] instead (the same without this step's copy of each
/// plane's old values); this one stays as the reference the tests and the kernel bench compare
/// it with.
pub fn explicit_steps_in_place_per_field(
    grid: &Grid,
    fields: &mut [&mut [f64]],
    dc: &[(f64, f64)],
    dt: f64,
    inflow: &mut [f64],
) {
    assert!(dc.len() == fields.len() && inflow.len() == fields.len());
    let isa = Isa::detect();
    fields
        .par_iter_mut()
        .zip(dc.par_iter())
        .zip(inflow.par_iter_mut())
        .for_each(|((u, &dc), inflow)| {
            let mut one = [0.0];
            explicit_steps_in_blocks(grid, &mut [&mut **u], &[dc], dt, &mut one, 1, isa);
            *inflow = one[0];
        });
}

/// [`explicit_steps_in_place_per_field`] without the copy of each plane's old values: the
/// same bits, each field moved by two planes in its store (session 24; the copy was 11–16 % of
/// the small cube's explicit step, docs/speed-history.md). `stores[f]` holds nz + 2 planes with
/// field f in planes `from..from + nz` (`from` = 0 or 2, the same for every field). From 2
/// the step goes up the planes and writes plane k's new values into store plane k; from 0 it
/// goes down and writes them into store plane k + 2. Either way the store plane written held a
/// plane whose old values no later plane reads, and the three it reads are not written before.
/// The inside cells are written, and in a plane with cells taken out by bubbles every other
/// cell is set to 0; the cells outside the phantom's shape (the same in every plane: shapes are
/// prisms along z) keep what that store plane held, 0 when every field is 0 outside the gel
/// ([`super::fields`]). Returns where the fields now start (2 − `from`).
pub fn explicit_steps_shifting_per_field(
    grid: &Grid,
    stores: &mut [&mut [f64]],
    from: usize,
    dc: &[(f64, f64)],
    dt: f64,
    inflow: &mut [f64],
) -> usize {
    assert!(dc.len() == stores.len() && inflow.len() == stores.len());
    assert!(from == 0 || from == 2, "fields start at store plane 0 or 2");
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    assert!(stores.iter().all(|s| s.len() == (nz + 2) * plane));
    let isa = Isa::detect();
    let h2 = grid.h * grid.h;
    // per field, its planes' inflows (the calling thread's buffer, as the other steps')
    let mut per_plane = take_plane_flows(nz * stores.len());
    stores
        .par_iter_mut()
        .zip(dc.par_iter())
        .zip(inflow.par_iter_mut())
        .zip(per_plane.par_chunks_mut(nz))
        .for_each(|(((store, &(d, cb)), inflow), flows)| {
            step_shifting(grid, store, from == 2, d * dt / h2, cb, flows, isa);
            // in plane order, as `sum_planes`
            *inflow = 0.0;
            for x in flows.iter() {
                *inflow += x;
            }
        });
    PLANE_FLOWS.set(per_plane);
    2 - from
}

/// One field's step of [`explicit_steps_shifting_per_field`]: `up` from store planes 2.. to
/// 0.., else from 0.. to 2..; plane k's inflow into `flows[k]`.
fn step_shifting(
    grid: &Grid,
    store: &mut [f64],
    up: bool,
    r: f64,
    cb: f64,
    flows: &mut [f64],
    isa: Isa,
) {
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    let empty: &[f64] = &[];
    if up {
        // old plane k in store plane k + 2, new into store plane k (which held old k − 2)
        for k in 0..nz {
            let (lo, hi) = store.split_at_mut((k + 1) * plane);
            let out = &mut lo[k * plane..];
            let zm = if k > 0 { &hi[..plane] } else { empty };
            let c = &hi[plane..2 * plane];
            let zp = if k + 1 < nz {
                &hi[2 * plane..3 * plane]
            } else {
                empty
            };
            flows[k] = stencil_plane(grid, k, zm, c, zp, out, r, cb, isa, None);
            zero_excluded(grid, k, out);
        }
    } else {
        // old plane k in store plane k, new into store plane k + 2 (which held old k + 2)
        for k in (0..nz).rev() {
            let (lo, hi) = store.split_at_mut((k + 2) * plane);
            let out = &mut hi[..plane];
            let zm = if k > 0 {
                &lo[(k - 1) * plane..k * plane]
            } else {
                empty
            };
            let c = &lo[k * plane..(k + 1) * plane];
            let zp = if k + 1 < nz {
                &lo[(k + 1) * plane..(k + 2) * plane]
            } else {
                empty
            };
            flows[k] = stencil_plane(grid, k, zm, c, zp, out, r, cb, isa, None);
            zero_excluded(grid, k, out);
        }
    }
}

/// The cells of plane `k` that bubbles took out of the gel set to 0 in `out` (the plane's new
/// values in a store plane that held another plane, where those cells may have been inside):
/// every cell not inside, when the plane has any such cell ([`Grid::plane_has_excluded`]).
fn zero_excluded(grid: &Grid, k: usize, out: &mut [f64]) {
    if !grid.plane_has_excluded(k) {
        return;
    }
    let plane = grid.n[0] * grid.n[1];
    let codes = &grid.codes[0][k * plane..(k + 1) * plane];
    for (o, &c) in out[..plane].iter_mut().zip(codes) {
        if c & INSIDE_BIT == 0 {
            *o = 0.0;
        }
    }
}

/// [`explicit_steps_in_place`] out of place: field `f`'s step from `src[f]` into `dst[f]`
/// (the same bits; only the inside cells of `dst` are written), in one parallel pass over
/// z-planes, each plane stepping every field in turn.
pub fn explicit_steps_into(
    grid: &Grid,
    src: &[&[f64]],
    dst: &mut [&mut [f64]],
    dc: &[(f64, f64)],
    dt: f64,
    inflow: &mut [f64],
) {
    explicit_steps_into_with(grid, src, dst, dc, dt, inflow, None, Isa::detect())
}

/// [`explicit_steps_into`] that also passes the gel over each plane it has just written, while
/// the plane is in cache: `gel.1[k]` gets [`super::gel_pass::plane_gel`] of the new values of
/// z-plane `k` (every field; `gel.0[g]` = R_u·T/L_g), the same bits as a pass over the fields
/// after the step.
pub(super) fn explicit_steps_into_passing_gel(
    grid: &Grid,
    src: &[&[f64]],
    dst: &mut [&mut [f64]],
    dc: &[(f64, f64)],
    dt: f64,
    inflow: &mut [f64],
    gel: (&[f64; Gas::ALL.len()], &mut [PlaneGel]),
) {
    explicit_steps_into_with(grid, src, dst, dc, dt, inflow, Some(gel), Isa::detect())
}

/// [`explicit_steps_into`] with the interior stencil compiled for `isa`, and the gel's pass of
/// each new plane when `gel` is given ([`explicit_steps_into_passing_gel`]).
#[allow(clippy::too_many_arguments)]
fn explicit_steps_into_with(
    grid: &Grid,
    src: &[&[f64]],
    dst: &mut [&mut [f64]],
    dc: &[(f64, f64)],
    dt: f64,
    inflow: &mut [f64],
    gel: Option<(&[f64; Gas::ALL.len()], &mut [PlaneGel])>,
    isa: Isa,
) {
    let nf = src.len();
    assert!(dst.len() == nf && dc.len() == nf && inflow.len() == nf);
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    let r: Vec<f64> = dc.iter().map(|(d, _)| d * dt / (grid.h * grid.h)).collect();
    let mut planes: Vec<Vec<&mut [f64]>> = (0..nz).map(|_| Vec::with_capacity(nf)).collect();
    for u in dst.iter_mut() {
        for (k, p) in u.chunks_mut(plane).enumerate() {
            planes[k].push(p);
        }
    }
    // per plane, every field's inflow
    let mut per_plane = take_plane_flows(nz * nf);
    let step = |k: usize, outs: &mut Vec<&mut [f64]>, flows: &mut [f64]| {
        for (f, out) in outs.iter_mut().enumerate() {
            flows[f] = step_plane_from(grid, src[f], k, out, r[f], dc[f].1, isa);
        }
    };
    match gel {
        None => planes
            .into_par_iter()
            .zip(per_plane.par_chunks_mut(nf))
            .enumerate()
            .for_each(|(k, (mut outs, flows))| step(k, &mut outs, flows)),
        Some((kg, slots)) => {
            assert_eq!(slots.len(), nz);
            planes
                .into_par_iter()
                .zip(per_plane.par_chunks_mut(nf))
                .zip(slots.par_iter_mut())
                .enumerate()
                .for_each(|(k, ((mut outs, flows), slot))| {
                    step(k, &mut outs, flows);
                    let mut f: [&[f64]; Gas::ALL.len()] = [&[]; Gas::ALL.len()];
                    for (f, o) in f.iter_mut().zip(&outs) {
                        *f = o;
                    }
                    let codes = &grid.codes[0][k * plane..(k + 1) * plane];
                    *slot = plane_gel_of(codes, &f[..nf], kg);
                })
        }
    }
    sum_planes(&per_plane, inflow);
    PLANE_FLOWS.set(per_plane);
}

/// Every field's inflow, `inflow[f]`, as the sum of its planes' (`per_plane[k·nf + f]`, nf =
/// `inflow.len()`) in plane order: the same bits for any thread count and either pass.
fn sum_planes(per_plane: &[f64], inflow: &mut [f64]) {
    inflow.fill(0.0);
    for flows in per_plane.chunks(inflow.len()) {
        for (i, x) in inflow.iter_mut().zip(flows) {
            *i += x;
        }
    }
}

/// [`explicit_steps_in_place`] with the interior stencil compiled for `isa`.
fn explicit_steps_in_place_with(
    grid: &Grid,
    fields: &mut [&mut [f64]],
    dc: &[(f64, f64)],
    dt: f64,
    inflow: &mut [f64],
    isa: Isa,
) {
    let threads = rayon::current_num_threads().max(1);
    let blocks = if threads == 1 {
        1
    } else {
        (BLOCKS_PER_THREAD * threads).min(grid.n[2])
    };
    explicit_steps_in_blocks(grid, fields, dc, dt, inflow, blocks, isa);
}

/// [`explicit_steps_in_place_with`] with the z-planes cut into `blocks` blocks (one task each;
/// with one block there is no halo to copy).
#[allow(clippy::too_many_arguments)]
fn explicit_steps_in_blocks(
    grid: &Grid,
    fields: &mut [&mut [f64]],
    dc: &[(f64, f64)],
    dt: f64,
    inflow: &mut [f64],
    blocks: usize,
    isa: Isa,
) {
    let nf = fields.len();
    assert!(dc.len() == nf && inflow.len() == nf);
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    let r: Vec<f64> = dc.iter().map(|(d, _)| d * dt / (grid.h * grid.h)).collect();
    let block = nz.div_ceil(blocks);
    let blocks = nz.div_ceil(block);
    // per plane, every field's inflow
    let mut per_plane = take_plane_flows(nz * nf);
    let mut halo = HALO.take();
    {
        // (one block reads no halo: none is kept)
        let per_field = if blocks > 1 { 2 * blocks * plane } else { 0 };
        if halo.len() < nf * per_field {
            halo.resize(nf * per_field, 0.0);
        }
        // per field, halo plane 2b: the plane below block b; 2b + 1: the plane above it
        if blocks > 1 {
            let fields: Vec<&[f64]> = fields.iter().map(|u| &**u).collect();
            halo[..nf * per_field]
                .par_chunks_mut(plane)
                .enumerate()
                .for_each(|(q, h)| {
                    let (f, q) = (q / (2 * blocks), q % (2 * blocks));
                    let b = q / 2;
                    let k = if q % 2 == 0 {
                        (b * block).checked_sub(1)
                    } else {
                        Some((b + 1) * block).filter(|&k| k < nz)
                    };
                    if let Some(k) = k {
                        h.copy_from_slice(&fields[f][k * plane..(k + 1) * plane]);
                    }
                });
        }
        let halo: &[f64] = &halo;
        // per block, its slab of every field
        let mut slabs: Vec<Vec<&mut [f64]>> = (0..blocks).map(|_| Vec::with_capacity(nf)).collect();
        for u in fields.iter_mut() {
            for (b, slab) in u.chunks_mut(block * plane).enumerate() {
                slabs[b].push(slab);
            }
        }
        slabs
            .into_par_iter()
            .zip(per_plane.par_chunks_mut(block * nf))
            .enumerate()
            .for_each(|(b, (mut slabs, flows))| {
                OLD_PLANES.with(|t| {
                    let mut t = t.borrow_mut();
                    if t.len() < 3 * plane {
                        t.resize(3 * plane, 0.0);
                    }
                    for (f, slab) in slabs.iter_mut().enumerate() {
                        let halo = &halo[f * per_field..(f + 1) * per_field];
                        let rc = (r[f], dc[f].1);
                        step_block(grid, b * block, slab, halo, b, &mut t, rc, f, flows, isa);
                    }
                });
            });
    }
    HALO.set(halo);
    sum_planes(&per_plane, inflow);
    PLANE_FLOWS.set(per_plane);
}

/// One block of [`explicit_steps_in_place`] for field `f` (r and C_b in `rc`): planes `k0..` in
/// `slab`, going upward with the old values of the plane below and of the current one in `old`
/// (two planes), the old planes just outside the block in `halo` (planes 2b and 2b + 1); plane
/// k0 + q's inflow into `flows[q·nf + f]`.
#[allow(clippy::too_many_arguments)]
fn step_block(
    grid: &Grid,
    k0: usize,
    slab: &mut [f64],
    halo: &[f64],
    b: usize,
    old: &mut [f64],
    (r, cb): (f64, f64),
    f: usize,
    flows: &mut [f64],
    isa: Isa,
) {
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    let planes = slab.len() / plane;
    let nf = flows.len() / planes;
    // the old values of the plane below (from the second plane on), of the current plane and
    // of the plane above (kept row by row while the current plane is stepped)
    let (mut below, rest) = old[..3 * plane].split_at_mut(plane);
    let (mut cur, mut above) = rest.split_at_mut(plane);
    cur.copy_from_slice(&slab[..plane]);
    for q in 0..planes {
        let k = k0 + q;
        let (done, rest) = slab.split_at_mut((q + 1) * plane);
        let zm: &[f64] = if q > 0 {
            below
        } else if k > 0 {
            &halo[2 * b * plane..(2 * b + 1) * plane]
        } else {
            &[]
        };
        let zp: &[f64] = if q + 1 < planes {
            &rest[..plane]
        } else if k + 1 < nz {
            &halo[(2 * b + 1) * plane..(2 * b + 2) * plane]
        } else {
            &[]
        };
        let save = (q + 1 < planes).then_some(&mut *above);
        flows[q * nf + f] = stencil_plane(
            grid,
            k,
            zm,
            cur,
            zp,
            &mut done[q * plane..],
            r,
            cb,
            isa,
            save,
        );
        // below ← cur, cur ← above (the next plane's old values), above ← the spare
        std::mem::swap(&mut below, &mut cur);
        std::mem::swap(&mut cur, &mut above);
    }
}

#[derive(Clone, Copy)]
struct SyncPtr(*mut f64);
unsafe impl Send for SyncPtr {}
unsafe impl Sync for SyncPtr {}

impl SyncPtr {
    /// The pointer (a method, so that a closure captures the whole `Send` wrapper).
    fn get(self) -> *mut f64 {
        self.0
    }
}

/// Solve (I − r·A_d) u* = u (+ boundary terms) along direction `dir` in place; `cp` is scratch
/// of the grid's length. Lines are independent tridiagonal systems; a line segment begins
/// wherever a cell's minus side is not an interior face.
fn sweep(grid: &Grid, dir: usize, u: &mut [f64], cp: &mut [f64], r: f64, cb: f64) -> f64 {
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    // cell = block·block_stride + along·along_stride + inner·inner_stride. Each work item
    // solves the lines of a range of `inner` together, stepping along them in lock-step, so
    // the elimination's serial chain (one division per cell) is interleaved over many lines.
    // For x the lines are contiguous: interleaving the ny lines of a z-plane (stride nx, the
    // plane stays in cache) is ~4× faster than solving one line after the other.
    let (n_blocks, n_along, n_inner, block_stride, along_stride, inner_stride) = match dir {
        0 => (nz, nx, ny, plane, 1, nx),
        1 => (nz, ny, nx, plane, nx, 1),
        _ => (1, nz, plane, 0, plane, 1),
    };
    let codes = &grid.codes[dir];
    let threads = rayon::current_num_threads().max(1);
    // work items: (block, inner_lo, inner_hi), disjoint sets of cells
    let chunks_per_block = if n_blocks >= 4 * threads {
        1
    } else {
        (4 * threads).div_ceil(n_blocks)
    };
    let chunk = n_inner.div_ceil(chunks_per_block).max(1);
    let items: Vec<(usize, usize, usize)> = (0..n_blocks)
        .flat_map(|b| {
            (0..n_inner)
                .step_by(chunk)
                .map(move |lo| (b, lo, (lo + chunk).min(n_inner)))
        })
        .collect();
    let up = SyncPtr(u.as_mut_ptr());
    let cpp = SyncPtr(cp.as_mut_ptr());
    items.par_iter().for_each(|&(b, lo, hi)| {
        let (up, cpp) = (up, cpp);
        let base = b * block_stride;
        // SAFETY: work items cover disjoint cell sets (distinct blocks, or distinct inner
        // ranges of the same block), and each item only touches its own cells.
        unsafe {
            for a in 0..n_along {
                let row = base + a * along_stride;
                for i in lo..hi {
                    let idx = row + i * inner_stride;
                    let c = *codes.get_unchecked(idx);
                    if c & INSIDE_BIT == 0 {
                        *cpp.0.add(idx) = 0.0;
                        continue;
                    }
                    let m = c & 3;
                    let p = (c >> 2) & 3;
                    let bdiag = 1.0 + r * (weight(m) + weight(p));
                    let mut rhs = *up.0.add(idx);
                    if m == SIDE_OPEN {
                        rhs += 2.0 * r * cb;
                    }
                    if p == SIDE_OPEN {
                        rhs += 2.0 * r * cb;
                    }
                    let cm = if p == SIDE_INTERIOR { -r } else { 0.0 };
                    let denom = if m == SIDE_INTERIOR {
                        let prev = idx - along_stride;
                        rhs += r * *up.0.add(prev);
                        bdiag + r * *cpp.0.add(prev)
                    } else {
                        bdiag
                    };
                    let inv = 1.0 / denom;
                    *cpp.0.add(idx) = cm * inv;
                    *up.0.add(idx) = rhs * inv;
                }
            }
            for a in (0..n_along.saturating_sub(1)).rev() {
                let row = base + a * along_stride;
                for i in lo..hi {
                    let idx = row + i * inner_stride;
                    let cpi = *cpp.0.add(idx);
                    if cpi != 0.0 {
                        *up.0.add(idx) -= cpi * *up.0.add(idx + along_stride);
                    }
                }
            }
        }
    });
    open_face_inflow(grid, dir, u, r, cb)
}

/// What entered through the open faces of direction `dir` in an implicit sweep that ended at
/// `u`: r·2·(C_b − u) per open side (mol per unit of `cell_volume`).
fn open_face_inflow(grid: &Grid, dir: usize, u: &[f64], r: f64, cb: f64) -> f64 {
    let mut inflow = 0.0;
    for &(idx, cnt) in &grid.open_cells[dir] {
        inflow += r * 2.0 * cnt as f64 * (cb - u[idx as usize]);
    }
    inflow
}

/// One locally-one-dimensional backward-Euler step in place (x, y, z sweeps); `scratch`
/// has the grid's length. Returns the boundary inflow.
pub fn implicit_step(
    grid: &Grid,
    u: &mut [f64],
    scratch: &mut [f64],
    d: f64,
    dt: f64,
    cb: f64,
) -> f64 {
    let r = d * dt / (grid.h * grid.h);
    let mut inflow = 0.0;
    for dir in 0..3 {
        inflow += sweep(grid, dir, u, scratch, r, cb);
    }
    inflow
}

/// Largest number of cells in one line segment that [`ImplicitSolver`]'s factor table indexes
/// with 16 bits (1 + 6·this entries); a grid with a longer segment takes the generic sweep.
const MAX_TABLE_SEGMENT: usize = (u16::MAX as usize - 1) / 6;

/// Where a cell sits at the plus end of its segment: the plus side is an interior face
/// (`MIDDLE`), or the segment ends there at a sealed or an open face.
const MIDDLE: usize = 0;
const LAST_SEALED: usize = 1;
const LAST_OPEN: usize = 2;

/// A stretch `[start, end)` of one row's cells (positions along the row's contiguous,
/// vectorised index) solved with the factors of table row `idx` for all of them, or with each
/// cell's own table row ([`GATHER`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Run {
    start: u32,
    end: u32,
    idx: u32,
}

/// [`Run::idx`] of a stretch whose cells have different table rows (looked up per cell).
const GATHER: u32 = u32::MAX;

/// [`Run::idx`] of a stretch of different table rows that are all middle rows of their
/// segments (linked to the previous row, no open face): only the pivot and the
/// back-substitution weight differ, and only those are looked up per cell.
const GATHER_MID: u32 = u32::MAX - 1;

/// Shortest stretch of middle rows that gets its own [`GATHER_MID`] run.
const MIN_MID_RUN: usize = 4;

/// Shortest stretch of equal table rows that gets its own broadcast run; shorter stretches
/// join the neighbouring per-cell (gather) run.
const MIN_RUN: usize = 8;

/// Each cell's place in the tridiagonal systems of the three sweeps, which depends on the face
/// codes only: per direction, the index of its row in the factor table
/// (1 + ((start_open·3 + end_kind)·max_len + position in the segment); 0 for a cell outside).
/// Two cells with the same index have the same matrix row and the same Thomas factors: the
/// factors of a segment's first k rows depend only on k, the segment's minus end, and (for
/// its last row) the plus end.
///
/// The indices are stored in the layout the kernel walks (see the module doc): for y and z the
/// grid's own order; for x transposed per z-plane, each line shifted to begin at its first cell
/// inside the shape (cell (i, j, k) at (k·nx + i − i₀)·s + j, with [i₀, i₁) the x-row's
/// [`Grid::inside_extents`], which exclusion never changes, and s = ny padded by
/// [`x_row_stride`]; positions past the line's extent hold index 0). In that layout every
/// direction's data is a sequence of rows (x: per plane, one row per i, of ny cells; y and z:
/// per plane, one row per j, of nx cells),
/// and `runs` cuts each row into stretches of equal index (broadcast factors) and mixed
/// stretches. The z sweep walks whole planes: a z row's runs count positions from the start of
/// its plane, so a plane's runs are its rows' runs one after the other.
///
/// When the codes change in a few cells ([`Grid::changed_since`]), [`LinePlan::update`]
/// recomputes only the lines through them and the rows of runs holding them.
#[derive(Debug, Clone, PartialEq, Eq)]
struct LinePlan {
    /// [`Grid::codes_id`] of the codes the plan was built from.
    codes_id: u64,
    /// Longest segment in any direction (the table's stride).
    max_len: usize,
    /// Number of segments (all directions) of `max_len` cells.
    n_longest: usize,
    /// Per direction, per cell (in the kernel's layout): the factor-table index.
    index: [Vec<u16>; 3],
    /// Per direction, the runs of all rows, row after row.
    runs: [Vec<Run>; 3],
    /// Per direction, where each row's runs begin in `runs` (one more entry than rows).
    row_start: [Vec<u32>; 3],
    /// Per z-plane, where its cells begin in `grid.open_cells[0]` (nz + 1 entries).
    xopen_start: Vec<usize>,
}

/// The table index of a cell with code `c` at position `k` of a segment whose minus end is
/// open (`start_open`) or not.
#[inline(always)]
fn table_index(c: u8, start_open: bool, k: usize, max_len: usize) -> u16 {
    let start_open = usize::from(start_open);
    let end = match (c >> 2) & 3 {
        SIDE_INTERIOR => MIDDLE,
        SIDE_OPEN => LAST_OPEN,
        _ => LAST_SEALED,
    };
    (1 + (start_open * 3 + end) * max_len + k) as u16
}

/// Bit of a position from [`positions`]: the cell's segment begins at an open face (positions
/// stay below [`MAX_TABLE_SEGMENT`] < 2¹⁵).
const START_OPEN: u16 = 1 << 15;

/// The position in its segment and whether the segment begins at an open face, from a value
/// of [`positions`].
#[inline(always)]
fn position(v: u16) -> (usize, bool) {
    (usize::from(v & !START_OPEN), v & START_OPEN != 0)
}

/// The table indices of the last cells of segments of `max_len` cells.
fn longest_ends(max_len: usize) -> [u16; 4] {
    let last =
        |start_open: usize, end: usize| (1 + (start_open * 3 + end) * max_len + max_len - 1) as u16;
    [
        last(0, LAST_SEALED),
        last(0, LAST_OPEN),
        last(1, LAST_SEALED),
        last(1, LAST_OPEN),
    ]
}

/// Pass 1 of a plan over `codes` (one z-plane for x and y, the whole grid for z): the position
/// of every inside cell in its segment, with [`START_OPEN`] set when the segment begins at an
/// open face (carried along the segment from its first cell), into `pos` (zero on entry);
/// cells in index order, so the minus neighbour idx − `stride` always comes first. Returns the
/// longest segment, or `None` when one is longer than [`MAX_TABLE_SEGMENT`].
fn positions(codes: &[u8], pos: &mut [u16], stride: usize) -> Option<usize> {
    let mut max_len = 1usize;
    for idx in 0..codes.len() {
        let c = codes[idx];
        if c & INSIDE_BIT == 0 {
            continue;
        }
        match c & 3 {
            SIDE_INTERIOR => {
                let before = pos[idx - stride];
                let k = usize::from(before & !START_OPEN) + 1;
                if k + 1 > MAX_TABLE_SEGMENT {
                    return None;
                }
                pos[idx] = k as u16 | (before & START_OPEN);
                max_len = max_len.max(k + 1);
            }
            SIDE_OPEN => pos[idx] = START_OPEN,
            _ => {}
        }
    }
    Some(max_len)
}

/// Pass 2 of a plan, in place on the cells `codes` (one plane's): position → table index.
/// Returns how many segments of `max_len` cells end there.
fn table_indices(codes: &[u8], out: &mut [u16], max_len: usize) -> usize {
    let mut longest = 0;
    for (v, &c) in out.iter_mut().zip(codes) {
        if c & INSIDE_BIT == 0 {
            continue;
        }
        let (k, start_open) = position(*v);
        *v = table_index(c, start_open, k, max_len);
        longest += usize::from(k + 1 == max_len && (c >> 2) & 3 != SIDE_INTERIOR);
    }
    longest
}

impl LinePlan {
    /// The plan of `grid`'s current codes, or `None` when a segment is longer than
    /// [`MAX_TABLE_SEGMENT`]. Planes (and for z's pass 1, the x and y passes) in parallel.
    fn build(grid: &Grid) -> Option<LinePlan> {
        let [nx, ny, nz] = grid.n;
        let plane = nx * ny;
        let len = grid.len();
        // pass 1, kept in the index arrays themselves (no temporary of the grid's size)
        let mut index: [Vec<u16>; 3] = [vec![0; len], vec![0; len], vec![0; len]];
        let [ix, iy, iz] = &mut index;
        let (mz, mxy) = rayon::join(
            || positions(&grid.codes[2], iz, plane),
            || {
                let codes = grid.codes[0]
                    .par_chunks(plane)
                    .zip(grid.codes[1].par_chunks(plane));
                ix.par_chunks_mut(plane)
                    .zip(iy.par_chunks_mut(plane))
                    .zip(codes)
                    .map(|((px, py), (cx, cy))| {
                        Some(positions(cx, px, 1)?.max(positions(cy, py, nx)?))
                    })
                    .reduce(|| Some(1), |a, b| Some(a?.max(b?)))
            },
        );
        let max_len = mz?.max(mxy?);
        // pass 2
        let mut n_longest = 0;
        for (dir, out) in index.iter_mut().enumerate() {
            n_longest += out
                .par_chunks_mut(plane)
                .zip(grid.codes[dir].par_chunks(plane))
                .map(|(out, codes)| table_indices(codes, out, max_len))
                .sum::<usize>();
        }
        // x: transposed per plane (rows of ny cells, `xstride` apart), each line shifted to
        // start at its first cell inside the shape (cells outside the shape have index 0)
        let xstride = x_row_stride(ny);
        let mut padded = vec![0u16; nz * nx * xstride];
        padded
            .par_chunks_mut(nx * xstride)
            .zip(index[0].par_chunks(plane))
            .zip(grid.inside_extents.par_chunks(ny))
            .for_each(|((dst, src), ext)| {
                for (j, &(s, e)) in ext.iter().enumerate() {
                    for (a, i) in (s as usize..e as usize).enumerate() {
                        dst[a * xstride + j] = src[j * nx + i];
                    }
                }
            });
        index[0] = padded;
        let xopen_start = (0..=nz)
            .map(|b| grid.open_cells[0].partition_point(|&(idx, _)| (idx as usize) < b * plane))
            .collect();
        let mut plan = LinePlan {
            codes_id: grid.codes_id(),
            max_len,
            n_longest,
            index,
            runs: Default::default(),
            row_start: Default::default(),
            xopen_start,
        };
        for dir in 0..3 {
            let per = plan.rows_per_plane(grid, dir);
            let parts: Vec<(Vec<Run>, Vec<u32>)> = (0..nz)
                .into_par_iter()
                .map(|k| {
                    let (mut runs, mut ends) = (Vec::new(), Vec::with_capacity(per));
                    for r in k * per..(k + 1) * per {
                        let (row, offset) = row_of(&plan.index[dir], grid, dir, r);
                        row_runs(row, offset, max_len, &mut runs);
                        ends.push(runs.len() as u32);
                    }
                    (runs, ends)
                })
                .collect();
            let mut runs = Vec::with_capacity(parts.iter().map(|p| p.0.len()).sum());
            let mut row_start = Vec::with_capacity(nz * per + 1);
            row_start.push(0);
            for (r, ends) in parts {
                let base = runs.len() as u32;
                row_start.extend(ends.iter().map(|e| e + base));
                runs.extend(r);
            }
            plan.runs[dir] = runs;
            plan.row_start[dir] = row_start;
        }
        Some(plan)
    }

    /// Rows of direction `dir` per z-plane (x: nx rows of ny cells; y, z: ny rows of nx).
    fn rows_per_plane(&self, grid: &Grid, dir: usize) -> usize {
        if dir == 0 {
            grid.n[0]
        } else {
            grid.n[1]
        }
    }

    /// Bring the plan to `grid`'s codes, which changed only in `cells` since the plan's (as
    /// [`Grid::changed_since`] lists them): the lines through those cells, in each direction,
    /// then the rows of runs holding them, are recomputed (a line's indices depend only on the
    /// codes along it); the three directions side by side. Returns false when the table's
    /// stride would change (a segment longer than `max_len`, or none of `max_len` cells left):
    /// the plan is then unusable, build it anew.
    fn update(&mut self, grid: &Grid, cells: &[usize]) -> bool {
        let max_len = self.max_len;
        let LinePlan {
            index,
            runs,
            row_start,
            ..
        } = self;
        let dirs: Vec<_> = index
            .iter_mut()
            .zip(runs)
            .zip(row_start)
            .enumerate()
            .collect();
        let changes: Vec<Option<isize>> = dirs
            .into_par_iter()
            .map(|(dir, ((index, runs), row_start))| {
                let dirty = update_lines(grid, dir, cells, max_len, index)?;
                if dirty.1.contains(&true) {
                    rerun(grid, dir, index, runs, row_start, max_len, &dirty.1);
                }
                Some(dirty.0)
            })
            .collect();
        let mut longest = self.n_longest as isize;
        for change in changes {
            let Some(change) = change else {
                return false;
            };
            longest += change;
        }
        if longest <= 0 {
            return false;
        }
        self.n_longest = longest as usize;
        self.codes_id = grid.codes_id();
        true
    }
}

/// Row `r` of direction `dir`'s indices `index` (in the kernel's layout, [`LinePlan::index`])
/// and the position of its first cell in its runs.
fn row_of<'a>(index: &'a [u16], grid: &Grid, dir: usize, r: usize) -> (&'a [u16], u32) {
    let [nx, ny, _] = grid.n;
    match dir {
        0 => {
            let s = x_row_stride(ny);
            (&index[r * s..r * s + ny], 0)
        }
        1 => (&index[r * nx..(r + 1) * nx], 0),
        _ => (&index[r * nx..(r + 1) * nx], ((r % ny) * nx) as u32),
    }
}

/// [`LinePlan::update`] of direction `dir`'s indices: every line of `dir` through a cell of
/// `cells` computed again from the grid's codes. Returns the change of the count of segments
/// of `max_len` cells ([`LinePlan::n_longest`]) and which rows of runs ([`row_of`]) hold a
/// changed index, or `None` when a segment is now longer than `max_len`.
fn update_lines(
    grid: &Grid,
    dir: usize,
    cells: &[usize],
    max_len: usize,
    index: &mut [u16],
) -> Option<(isize, Vec<bool>)> {
    let n = grid.n;
    let [nx, ny, nz] = n;
    let plane = nx * ny;
    let stride = [1usize, nx, plane][dir];
    let (codes, len) = (&grid.codes[dir], n[dir]);
    let xs = x_row_stride(ny);
    let ends = longest_ends(max_len);
    // rows of runs: x, nx per plane of ny (padded to xs) cells; y and z, ny per plane of nx
    let (rows, row_len) = if dir == 0 {
        (nz * nx, xs)
    } else {
        (nz * ny, nx)
    };
    let mut dirty = vec![false; rows];
    let mut longest = 0isize;
    // the first cell of every line of `dir` through a changed cell, each once
    let mut firsts: Vec<usize> = cells
        .iter()
        .map(|&idx| match dir {
            0 => idx - idx % nx,
            1 => idx - (idx / nx) % ny * nx,
            _ => idx % plane,
        })
        .collect();
    firsts.sort_unstable();
    firsts.dedup();
    let mut line: Vec<u16> = Vec::with_capacity(len);
    let mut line_codes: Vec<u8> = Vec::with_capacity(len);
    for &first in &firsts {
        let cell = |q: usize| first + q * stride;
        // the line's q-th cell in the kernel's layout (x: transposed per plane)
        let (j, k) = ((first / nx) % ny, first / plane);
        // x: the line's cells inside the shape, the first of them in row 0 ([`LinePlan`])
        let (s, e) = if dir == 0 {
            let (s, e) = grid.inside_extents[j + ny * k];
            (s as usize, e as usize)
        } else {
            (0, len)
        };
        let at = |q: usize| {
            if dir == 0 {
                (k * nx + q - s) * xs + j
            } else {
                cell(q)
            }
        };
        // pass 1 on the line's codes, gathered contiguous
        line_codes.clear();
        line_codes.extend((0..len).map(|q| codes[cell(q)]));
        line.clear();
        line.resize(len, 0);
        if positions(&line_codes, &mut line, 1).is_none_or(|m| m > max_len) {
            return None;
        }
        for (q, &kq) in line.iter().enumerate() {
            let cc = line_codes[q];
            let v = if cc & INSIDE_BIT == 0 {
                0
            } else {
                let (k, start_open) = position(kq);
                table_index(cc, start_open, k, max_len)
            };
            if !(s..e).contains(&q) {
                // outside the shape: never inside, and not in the layout
                debug_assert_eq!(v, 0);
                continue;
            }
            let p = at(q);
            let old = &mut index[p];
            if *old != v {
                longest -= isize::from(ends.contains(old));
                longest += isize::from(ends.contains(&v));
                *old = v;
                dirty[p / row_len] = true;
            }
        }
    }
    Some((longest, dirty))
}

/// Recompute the runs of direction `dir`'s rows `r` with `dirty[r]` from `index`; copy the
/// others, each stretch of clean rows in one piece (their starts shifted by what the rows
/// before them grew or shrank).
fn rerun(
    grid: &Grid,
    dir: usize,
    index: &[u16],
    runs: &mut Vec<Run>,
    row_start: &mut Vec<u32>,
    max_len: usize,
    dirty: &[bool],
) {
    let old = std::mem::take(runs);
    let old_start = std::mem::take(row_start);
    let rows = old_start.len() - 1;
    runs.reserve(old.len() + 64);
    row_start.reserve(rows + 1);
    row_start.push(0);
    let mut r = 0;
    while r < rows {
        if dirty[r] {
            let (row, offset) = row_of(index, grid, dir, r);
            row_runs(row, offset, max_len, runs);
            row_start.push(runs.len() as u32);
            r += 1;
            continue;
        }
        let e = dirty[r..].iter().position(|&d| d).map_or(rows, |q| r + q);
        let (a, b) = (old_start[r] as usize, old_start[e] as usize);
        // new start − old start of these rows (mod 2³²: the sum is below 2³²)
        let shift = (runs.len() as u32).wrapping_sub(a as u32);
        runs.extend_from_slice(&old[a..b]);
        row_start.extend(old_start[r + 1..=e].iter().map(|x| x.wrapping_add(shift)));
        r = e;
    }
}

/// Row stride of the x sweep's transposed plane (nx rows of ny cells): ny, padded when its
/// byte length is a multiple of 128 so that the transposes' scattered accesses do not fall
/// into a few cache sets (a 128-cell row is 1 KiB: all columns would share 4 of L1's sets).
fn x_row_stride(ny: usize) -> usize {
    if ny.is_multiple_of(16) {
        ny + 8
    } else {
        ny
    }
}

/// Cut a row of indices into runs, appended to `runs` with positions counted from `offset`:
/// maximal stretches of at least [`MIN_RUN`] equal indices become broadcast runs (none for
/// index 0, cells outside, which keep their values), the cells between them per-cell runs
/// ([`GATHER_MID`] where they are all middle rows, else [`GATHER`]).
fn row_runs(row: &[u16], offset: u32, max_len: usize, runs: &mut Vec<Run>) {
    // a middle row: linked to the previous one (position k > 0), interior plus side
    let mid = |v: u16| {
        v != 0 && {
            let q = v as usize - 1;
            !q.is_multiple_of(max_len) && (q / max_len) % 3 == MIDDLE
        }
    };
    let run = |start: usize, end: usize, idx: u32| Run {
        start: offset + start as u32,
        end: offset + end as u32,
        idx,
    };
    let flush = |runs: &mut Vec<Run>, g: usize, e: usize| {
        let mut s = g;
        let mut pending = g;
        while s < e {
            if !mid(row[s]) {
                s += 1;
                continue;
            }
            let mut t = s + 1;
            while t < e && mid(row[t]) {
                t += 1;
            }
            if t - s >= MIN_MID_RUN {
                if pending < s {
                    runs.push(run(pending, s, GATHER));
                }
                runs.push(run(s, t, GATHER_MID));
                pending = t;
            }
            s = t;
        }
        if pending < e {
            runs.push(run(pending, e, GATHER));
        }
    };
    let mut pending: Option<usize> = None;
    let mut s = 0;
    while s < row.len() {
        let v = row[s];
        let mut e = s + 1;
        while e < row.len() && row[e] == v {
            e += 1;
        }
        if e - s >= MIN_RUN {
            if let Some(g) = pending.take() {
                flush(runs, g, s);
            }
            if v != 0 {
                runs.push(run(s, e, u32::from(v)));
            }
        } else if pending.is_none() {
            pending = Some(s);
        }
        s = e;
    }
    if let Some(g) = pending {
        flush(runs, g, row.len());
    }
}

/// [`Factor::flags`]: the row adds the open minus face's term.
const OPEN_MINUS: u8 = 1;
/// [`Factor::flags`]: the row adds the open plus face's term.
const OPEN_PLUS: u8 = 2;
/// [`Factor::flags`]: the row is linked to the previous one.
const LINKED: u8 = 4;

/// One row of a segment's Thomas factors for step ratio r = D·dt/h² and boundary value C_b.
#[derive(Debug, Clone, Copy, Default)]
struct Factor {
    /// 1/(b − a·c'_{k−1}): the inverse pivot.
    inv: f64,
    /// c'_k = c_k·inv (−r·inv inside the segment, 0 at its end): the back-substitution weight.
    cneg: f64,
    /// r when the row is linked to the previous one (k > 0), else 0.
    link: f64,
    /// 2·r·C_b when the minus side is an open face, else 0.
    open_minus: f64,
    /// 2·r·C_b when the plus side is an open face, else 0.
    open_plus: f64,
    /// Which of the three terms the generic sweep adds for this row ([`OPEN_MINUS`],
    /// [`OPEN_PLUS`], [`LINKED`]): a broadcast run adds exactly those.
    flags: u8,
}

/// Fill `table` with the factors of every row kind of `plan` for ratio `r` and boundary value
/// `cb`: the same arithmetic, in the same order, as the generic sweep's per-cell elimination,
/// so the two give the same bits.
fn fill_table(table: &mut Vec<Factor>, max_len: usize, r: f64, cb: f64) {
    table.clear();
    table.resize(1 + 6 * max_len, Factor::default());
    // row 0: a cell outside the phantom keeps its value
    table[0] = Factor {
        inv: 1.0,
        ..Factor::default()
    };
    let k2 = 2.0 * r * cb;
    for start_open in 0..2 {
        let m0 = if start_open == 1 {
            SIDE_OPEN
        } else {
            SIDE_SEALED
        };
        for end in [MIDDLE, LAST_SEALED, LAST_OPEN] {
            let p = match end {
                MIDDLE => SIDE_INTERIOR,
                LAST_OPEN => SIDE_OPEN,
                _ => SIDE_SEALED,
            };
            let base = 1 + (start_open * 3 + end) * max_len;
            for k in 0..max_len {
                let m = if k == 0 { m0 } else { SIDE_INTERIOR };
                let bdiag = 1.0 + r * (weight(m) + weight(p));
                let denom = if k == 0 {
                    bdiag
                } else {
                    // the previous row of a segment is always a middle row
                    let prev = table[1 + (start_open * 3 + MIDDLE) * max_len + k - 1];
                    bdiag + r * prev.cneg
                };
                let inv = 1.0 / denom;
                let cm = if p == SIDE_INTERIOR { -r } else { 0.0 };
                let mut flags = 0;
                if m == SIDE_OPEN {
                    flags |= OPEN_MINUS;
                }
                if p == SIDE_OPEN {
                    flags |= OPEN_PLUS;
                }
                if k > 0 {
                    flags |= LINKED;
                }
                table[base + k] = Factor {
                    inv,
                    cneg: cm * inv,
                    link: if k > 0 { r } else { 0.0 },
                    open_minus: if m == SIDE_OPEN { k2 } else { 0.0 },
                    open_plus: if p == SIDE_OPEN { k2 } else { 0.0 },
                    flags,
                };
            }
        }
    }
}

/// The factor table and, for the per-cell runs of middle rows, its pivots and
/// back-substitution weights as dense arrays.
#[derive(Debug, Clone, Default)]
struct Tables {
    factors: Vec<Factor>,
    inv: Vec<f64>,
    cneg: Vec<f64>,
    /// r = D·dt/h² (the link of every middle row).
    r: f64,
}

impl Tables {
    fn fill(&mut self, max_len: usize, r: f64, cb: f64) {
        fill_table(&mut self.factors, max_len, r, cb);
        self.inv.clear();
        self.inv.extend(self.factors.iter().map(|f| f.inv));
        self.cneg.clear();
        self.cneg.extend(self.factors.iter().map(|f| f.cneg));
        self.r = r;
    }
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

/// The locally-one-dimensional backward-Euler step with each line's Thomas factors taken
/// from a small table instead of being recomputed per cell: the face codes are read once per
/// rebuild (when [`Grid::codes_id`] changes), the inner loops have no divisions, and runs of
/// equal factors use broadcast constants. Gives the same bits as [`implicit_step`], which it
/// replaces in the time loop.
#[derive(Debug, Clone, Default)]
pub struct ImplicitSolver {
    plan: Option<LinePlan>,
    /// Set when the grid's segments are too long for the table: the generic sweep is used.
    generic: Option<u64>,
    scratch: Vec<f64>,
    /// Per field of [`Self::steps`] (the first also [`Self::step`]'s): the factor table and the
    /// x-open cells' values after the x sweep (as `grid.open_cells[0]`), for the inflow.
    per_field: Vec<(Tables, Vec<f64>)>,
    /// Plans brought up to date by [`LinePlan::update`] (not built anew).
    #[cfg(test)]
    updates: usize,
}

impl ImplicitSolver {
    /// A solver with no plan yet (built at the first step).
    pub fn new() -> ImplicitSolver {
        ImplicitSolver::default()
    }

    /// One LOD backward-Euler step of `u` in place (x, y, z sweeps), r = D·dt/h², open faces
    /// at `cb`. Returns the boundary inflow, as [`implicit_step`].
    pub fn step(&mut self, grid: &Grid, u: &mut [f64], d: f64, dt: f64, cb: f64) -> f64 {
        self.step_with(grid, u, d, dt, cb, Isa::detect())
    }

    fn step_with(&mut self, grid: &Grid, u: &mut [f64], d: f64, dt: f64, cb: f64, isa: Isa) -> f64 {
        assert_eq!(u.len(), grid.len());
        let r = d * dt / (grid.h * grid.h);
        if !self.refresh(grid) {
            self.scratch.resize(grid.len(), 0.0);
            let mut inflow = 0.0;
            for dir in 0..3 {
                inflow += sweep(grid, dir, u, &mut self.scratch, r, cb);
            }
            return inflow;
        }
        if self.per_field.is_empty() {
            self.per_field.push(Default::default());
        }
        let plan = self.plan.as_ref().expect("refreshed");
        let (table, xvals) = &mut self.per_field[0];
        planned_step(grid, plan, table, xvals, u, r, cb, isa)
    }

    /// Several fields' steps over the same grid, field `f` with diffusivity and boundary value
    /// `dc[f] = (D_f, c_b,f)`, each the same bits as [`Self::step`] alone; the fields are
    /// stepped side by side (rayon), so one field's serial parts (its table, its inflow sums)
    /// overlap the other's sweeps. Returns each field's inflow into `inflow[f]`.
    pub fn steps(
        &mut self,
        grid: &Grid,
        fields: &mut [&mut [f64]],
        dc: &[(f64, f64)],
        dt: f64,
        inflow: &mut [f64],
    ) {
        self.steps_with(grid, fields, dc, dt, inflow, Isa::detect())
    }

    fn steps_with(
        &mut self,
        grid: &Grid,
        fields: &mut [&mut [f64]],
        dc: &[(f64, f64)],
        dt: f64,
        inflow: &mut [f64],
        isa: Isa,
    ) {
        let nf = fields.len();
        assert!(dc.len() == nf && inflow.len() == nf);
        if !self.refresh(grid) {
            // the generic sweep, field by field
            for f in 0..nf {
                inflow[f] = self.step_with(grid, fields[f], dc[f].0, dt, dc[f].1, isa);
            }
            return;
        }
        if self.per_field.len() < nf {
            self.per_field.resize_with(nf, Default::default);
        }
        let plan = self.plan.as_ref().expect("refreshed");
        let h2 = grid.h * grid.h;
        fields
            .par_iter_mut()
            .zip(self.per_field.par_iter_mut())
            .zip(dc.par_iter())
            .zip(inflow.par_iter_mut())
            .for_each(|(((u, (table, xvals)), &(d, cb)), inflow)| {
                assert_eq!(u.len(), grid.len());
                *inflow = planned_step(grid, plan, table, xvals, u, d * dt / h2, cb, isa);
            });
    }

    /// Bring the plan level with the grid's codes; false when the grid takes the generic
    /// sweep (segments too long for the table).
    fn refresh(&mut self, grid: &Grid) -> bool {
        let id = grid.codes_id();
        let stale = self.plan.as_ref().is_none_or(|p| p.codes_id != id);
        if stale && self.generic != Some(id) {
            // only the lines through the cells changed since the plan's codes, if the grid's
            // log reaches back to them
            let updated = self.plan.as_mut().is_some_and(|plan| {
                grid.changed_since(plan.codes_id)
                    .is_some_and(|cells| plan.update(grid, &cells))
            });
            if !updated {
                self.plan = LinePlan::build(grid);
            }
            #[cfg(test)]
            {
                self.updates += usize::from(updated);
            }
            self.generic = if self.plan.is_none() { Some(id) } else { None };
        }
        self.plan.as_ref().is_some_and(|p| p.codes_id == id)
    }
}

/// One field's planned LOD step ([`ImplicitSolver::step`]) with its own factor table and
/// x-open values; r = D·dt/h². Returns the boundary inflow.
#[allow(clippy::too_many_arguments)]
fn planned_step(
    grid: &Grid,
    plan: &LinePlan,
    table: &mut Tables,
    xvals: &mut Vec<f64>,
    u: &mut [f64],
    r: f64,
    cb: f64,
    isa: Isa,
) -> f64 {
    table.fill(plan.max_len, r, cb);
    xvals.resize(grid.open_cells[0].len(), 0.0);
    sweep_xy(grid, plan, table, u, xvals, isa);
    // the x inflow from the values right after the x sweep, summed in cell order
    let mut fx = 0.0;
    for (&(_, cnt), &x) in grid.open_cells[0].iter().zip(xvals.iter()) {
        fx += r * 2.0 * cnt as f64 * (cb - x);
    }
    let mut inflow = 0.0;
    inflow += fx;
    inflow += open_face_inflow(grid, 1, u, r, cb);
    sweep_z(grid, plan, table, u, isa);
    inflow += open_face_inflow(grid, 2, u, r, cb);
    inflow
}

/// Solve the lines of a stack of rows in place: row a (0 ≤ a < `n_along`) holds cells
/// `buf[a·stride + i]`, lines run across the rows (along a), and the cells `lo ≤ i < hi` of
/// every row are solved in lock-step; `index` is laid out as `buf`; `runs`/`row_start` give
/// the runs of row a in `rows_per` pieces, from piece (`row0` + a)·`rows_per` on.
///
/// # Safety
/// `buf` and `index` are valid for `(n_along − 1)·stride + hi` elements, the runs lie within
/// the rows, and every table index is below `table.len()`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn solve_rows(
    buf: *mut f64,
    index: *const u16,
    stride: usize,
    n_along: usize,
    lo: usize,
    hi: usize,
    runs: &[Run],
    row_start: &[u32],
    row0: usize,
    rows_per: usize,
    tables: &Tables,
    isa: Isa,
) {
    let table = &tables.factors[..];
    let (inv, cneg, r) = (&tables.inv[..], &tables.cneg[..], tables.r);
    let row_runs = |a: usize| -> &[Run] {
        let (r0, r1) = ((row0 + a) * rows_per, (row0 + a + 1) * rows_per);
        let rr = &runs[row_start[r0] as usize..row_start[r1] as usize];
        // the first run that reaches past `lo`
        let first = if lo == 0 {
            0
        } else {
            rr.partition_point(|r| r.end as usize <= lo)
        };
        &rr[first..]
    };
    // forward elimination
    for a in 0..n_along {
        let cur = buf.add(a * stride);
        let prev = if a > 0 {
            buf.add((a - 1) * stride)
        } else {
            cur
        };
        let ix = index.add(a * stride);
        for run in row_runs(a) {
            let s = (run.start as usize).max(lo);
            let e = (run.end as usize).min(hi);
            if s >= hi {
                break;
            }
            if run.idx == GATHER_MID {
                // a > 0: a middle row has a previous row
                mid_fwd(isa, cur, prev, ix, inv.as_ptr(), r, s, e);
            } else if run.idx == GATHER {
                if a == 0 {
                    for i in s..e {
                        let f = table.get_unchecked(*ix.add(i) as usize);
                        let rhs = *cur.add(i) + f.open_minus + f.open_plus;
                        *cur.add(i) = rhs * f.inv;
                    }
                } else {
                    for i in s..e {
                        let f = table.get_unchecked(*ix.add(i) as usize);
                        let rhs = *cur.add(i) + f.open_minus + f.open_plus + f.link * *prev.add(i);
                        *cur.add(i) = rhs * f.inv;
                    }
                }
            } else {
                let f = *table.get_unchecked(run.idx as usize);
                let (c, p) = (cur.add(s), prev.add(s));
                let n = e - s;
                match f.flags {
                    0 => fwd::<false, false, false>(c, p, n, &f),
                    OPEN_MINUS => fwd::<true, false, false>(c, p, n, &f),
                    OPEN_PLUS => fwd::<false, true, false>(c, p, n, &f),
                    3 => fwd::<true, true, false>(c, p, n, &f),
                    LINKED => fwd::<false, false, true>(c, p, n, &f),
                    5 => fwd::<true, false, true>(c, p, n, &f),
                    6 => fwd::<false, true, true>(c, p, n, &f),
                    _ => fwd::<true, true, true>(c, p, n, &f),
                }
            }
        }
    }
    // back substitution
    for a in (0..n_along.saturating_sub(1)).rev() {
        let cur = buf.add(a * stride);
        let next = buf.add((a + 1) * stride);
        let ix = index.add(a * stride);
        for run in row_runs(a) {
            let s = (run.start as usize).max(lo);
            let e = (run.end as usize).min(hi);
            if s >= hi {
                break;
            }
            if run.idx == GATHER_MID {
                mid_back(isa, cur, next, ix, cneg.as_ptr(), s, e);
            } else if run.idx == GATHER {
                // each cell's own weight, skipped where it is zero (a segment's last cell, a cell
                // outside), as the generic sweep does: the x sweep's copy holds stale values
                // past its lines' ends (`xy_plane`), possibly not finite, which a zero weight
                // times them would carry into the line
                for i in s..e {
                    let w = *cneg.as_ptr().add(*ix.add(i) as usize);
                    if w != 0.0 {
                        *cur.add(i) -= w * *next.add(i);
                    }
                }
            } else {
                let cneg = table.get_unchecked(run.idx as usize).cneg;
                if cneg != 0.0 {
                    for i in s..e {
                        *cur.add(i) -= cneg * *next.add(i);
                    }
                }
            }
        }
    }
}

/// The forward elimination of a run of middle rows, cells `s..e`:
/// cur = (cur + r·prev)·inv\[ix\], the pivots looked up per cell (gathered in the vector sets).
///
/// # Safety
/// The pointers are valid for the cells `s..e`, every index is below the table's length, and
/// the CPU has the instruction set `isa`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn mid_fwd(
    isa: Isa,
    cur: *mut f64,
    prev: *const f64,
    ix: *const u16,
    inv: *const f64,
    r: f64,
    s: usize,
    e: usize,
) {
    #[cfg(target_arch = "x86_64")]
    let s = match isa {
        Isa::Avx512 => mid_fwd_avx512(cur, prev, ix, inv, r, s, e),
        Isa::Avx2 => mid_fwd_avx2(cur, prev, ix, inv, r, s, e),
        Isa::Portable => s,
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = isa;
    for i in s..e {
        let rhs = *cur.add(i) + r * *prev.add(i);
        *cur.add(i) = rhs * *inv.add(*ix.add(i) as usize);
    }
}

/// The back substitution of a run of middle rows, cells `s..e`: cur −= cneg\[ix\]·next.
///
/// # Safety
/// As [`mid_fwd`].
#[inline(always)]
unsafe fn mid_back(
    isa: Isa,
    cur: *mut f64,
    next: *const f64,
    ix: *const u16,
    cneg: *const f64,
    s: usize,
    e: usize,
) {
    #[cfg(target_arch = "x86_64")]
    let s = match isa {
        Isa::Avx512 => mid_back_avx512(cur, next, ix, cneg, s, e),
        Isa::Avx2 => mid_back_avx2(cur, next, ix, cneg, s, e),
        Isa::Portable => s,
    };
    #[cfg(not(target_arch = "x86_64"))]
    let _ = isa;
    for i in s..e {
        *cur.add(i) -= *cneg.add(*ix.add(i) as usize) * *next.add(i);
    }
}

/// The vector forms of [`mid_fwd`] and [`mid_back`] for one instruction set:
/// `$lanes` cells at a time with the pivots or weights gathered (the same operations per
/// cell, so the same bits); each returns where the scalar tail starts.
macro_rules! gathered_mid_runs {
    ($feature:literal, $fwd:ident, $back:ident, $lanes:literal, $gather:ident,
     $set1:ident, $load:ident, $store:ident, $add:ident, $sub:ident, $mul:ident) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feature)]
        unsafe fn $fwd(
            cur: *mut f64,
            prev: *const f64,
            ix: *const u16,
            inv: *const f64,
            r: f64,
            s: usize,
            e: usize,
        ) -> usize {
            use std::arch::x86_64::*;
            let rv = $set1(r);
            let mut i = s;
            while i + $lanes <= e {
                let f = $gather(ix.add(i), inv);
                let p = $mul(rv, $load(prev.add(i)));
                let rhs = $add($load(cur.add(i)), p);
                $store(cur.add(i), $mul(rhs, f));
                i += $lanes;
            }
            i
        }

        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = $feature)]
        unsafe fn $back(
            cur: *mut f64,
            next: *const f64,
            ix: *const u16,
            cneg: *const f64,
            s: usize,
            e: usize,
        ) -> usize {
            use std::arch::x86_64::*;
            let mut i = s;
            while i + $lanes <= e {
                let w = $gather(ix.add(i), cneg);
                let t = $mul(w, $load(next.add(i)));
                $store(cur.add(i), $sub($load(cur.add(i)), t));
                i += $lanes;
            }
            i
        }
    };
}

/// Eight table entries at the u16 indices `ix[0..8]`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn gather8(ix: *const u16, table: *const f64) -> std::arch::x86_64::__m512d {
    use std::arch::x86_64::*;
    let k = _mm512_cvtepu16_epi64(_mm_loadu_si128(ix as *const __m128i));
    _mm512_i64gather_pd::<8>(k, table)
}

/// Four table entries at the u16 indices `ix[0..4]`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn gather4(ix: *const u16, table: *const f64) -> std::arch::x86_64::__m256d {
    use std::arch::x86_64::*;
    let k = _mm_cvtepu16_epi32(_mm_loadl_epi64(ix as *const __m128i));
    _mm256_i32gather_pd::<8>(table, k)
}

gathered_mid_runs!(
    "avx512f",
    mid_fwd_avx512,
    mid_back_avx512,
    8,
    gather8,
    _mm512_set1_pd,
    _mm512_loadu_pd,
    _mm512_storeu_pd,
    _mm512_add_pd,
    _mm512_sub_pd,
    _mm512_mul_pd
);
gathered_mid_runs!(
    "avx2",
    mid_fwd_avx2,
    mid_back_avx2,
    4,
    gather4,
    _mm256_set1_pd,
    _mm256_loadu_pd,
    _mm256_storeu_pd,
    _mm256_add_pd,
    _mm256_sub_pd,
    _mm256_mul_pd
);

/// The forward elimination of a broadcast run of `n` cells: the generic sweep's operations,
/// with the terms the row has.
#[inline(always)]
unsafe fn fwd<const OM: bool, const OP: bool, const LINK: bool>(
    cur: *mut f64,
    prev: *const f64,
    n: usize,
    f: &Factor,
) {
    let (om, op, link, inv) = (f.open_minus, f.open_plus, f.link, f.inv);
    for i in 0..n {
        let mut rhs = *cur.add(i);
        if OM {
            rhs += om;
        }
        if OP {
            rhs += op;
        }
        if LINK {
            rhs += link * *prev.add(i);
        }
        *cur.add(i) = rhs * inv;
    }
}

/// Copy a z-plane's x lines between the plane itself (x-row j at `plane + j·nx`) and the x
/// sweep's transposed copy `t` (row a at `t + a·xs`), each line from its first cell inside the
/// shape: with `ext[j]` = [s, e) ([`Grid::inside_extents`]), cell (s + a, j) sits at
/// `t[a·xs + j]`, so row a holds every line's a-th cell (in a cylinder, the middle cells of one
/// row share a table row, and broadcast). `into_t`: plane → t, else t → plane; nothing outside
/// the lines' extents is read or written.
///
/// # Safety
/// `plane` is valid for `ext.len()` rows of `nx` cells, `t` for `nx` rows of `xs` ≥
/// `ext.len()` cells, every extent lies within its row, and the two do not overlap.
#[inline(always)]
unsafe fn x_lines(
    plane: *mut f64,
    nx: usize,
    t: *mut f64,
    xs: usize,
    ext: &[(u32, u32)],
    into_t: bool,
) {
    for (j, &(s, e)) in ext.iter().enumerate() {
        x_line_tail(
            plane.add(j * nx + s as usize),
            t.add(j),
            xs,
            0,
            e.saturating_sub(s) as usize,
            into_t,
        );
    }
}

/// Cells `a0..a1` of one line of [`x_lines`]: `row` its first cell in the plane, `col` in `t`.
#[inline(always)]
unsafe fn x_line_tail(row: *mut f64, col: *mut f64, xs: usize, a0: usize, a1: usize, into_t: bool) {
    for a in a0..a1 {
        if into_t {
            *col.add(a * xs) = *row.add(a);
        } else {
            *row.add(a) = *col.add(a * xs);
        }
    }
}

/// [`x_lines`] with 4×4 blocks (four lines, four cells of each) transposed in AVX registers;
/// the cells beyond the shortest of the four lines one by one.
///
/// # Safety
/// As [`x_lines`]; the CPU has AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn x_lines_avx(
    plane: *mut f64,
    nx: usize,
    t: *mut f64,
    xs: usize,
    ext: &[(u32, u32)],
    into_t: bool,
) {
    use std::arch::x86_64::*;
    let ny4 = ext.len() / 4 * 4;
    for j0 in (0..ny4).step_by(4) {
        let rows: [*mut f64; 4] =
            std::array::from_fn(|q| plane.add((j0 + q) * nx + ext[j0 + q].0 as usize));
        let lens: [usize; 4] = std::array::from_fn(|q| {
            let (s, e) = ext[j0 + q];
            e.saturating_sub(s) as usize
        });
        let a4 = lens.iter().min().copied().unwrap_or(0) / 4 * 4;
        let col = t.add(j0);
        for a0 in (0..a4).step_by(4) {
            // the 4×4 block: in the plane, line q's cells a0..a0+4; in t, rows a0..a0+4 of
            // columns j0..j0+4 (a block and its transpose swap with the same shuffles)
            let (v0, v1, v2, v3) = if into_t {
                (
                    _mm256_loadu_pd(rows[0].add(a0)),
                    _mm256_loadu_pd(rows[1].add(a0)),
                    _mm256_loadu_pd(rows[2].add(a0)),
                    _mm256_loadu_pd(rows[3].add(a0)),
                )
            } else {
                let c = col.add(a0 * xs);
                (
                    _mm256_loadu_pd(c),
                    _mm256_loadu_pd(c.add(xs)),
                    _mm256_loadu_pd(c.add(2 * xs)),
                    _mm256_loadu_pd(c.add(3 * xs)),
                )
            };
            let t0 = _mm256_unpacklo_pd(v0, v1);
            let t1 = _mm256_unpackhi_pd(v0, v1);
            let t2 = _mm256_unpacklo_pd(v2, v3);
            let t3 = _mm256_unpackhi_pd(v2, v3);
            let w0 = _mm256_permute2f128_pd(t0, t2, 0x20);
            let w1 = _mm256_permute2f128_pd(t1, t3, 0x20);
            let w2 = _mm256_permute2f128_pd(t0, t2, 0x31);
            let w3 = _mm256_permute2f128_pd(t1, t3, 0x31);
            if into_t {
                let c = col.add(a0 * xs);
                _mm256_storeu_pd(c, w0);
                _mm256_storeu_pd(c.add(xs), w1);
                _mm256_storeu_pd(c.add(2 * xs), w2);
                _mm256_storeu_pd(c.add(3 * xs), w3);
            } else {
                _mm256_storeu_pd(rows[0].add(a0), w0);
                _mm256_storeu_pd(rows[1].add(a0), w1);
                _mm256_storeu_pd(rows[2].add(a0), w2);
                _mm256_storeu_pd(rows[3].add(a0), w3);
            }
        }
        for q in 0..4 {
            x_line_tail(rows[q], col.add(q), xs, a4, lens[q], into_t);
        }
    }
    x_lines(plane.add(ny4 * nx), nx, t.add(ny4), xs, &ext[ny4..], into_t);
}

thread_local! {
    /// Per thread, one z-plane transposed (the x sweep's working copy).
    static PLANE: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The x and y sweeps of one z-plane `b` (the plane stays in the core's cache): transpose it
/// into `t` so the x lines run across rows, solve, transpose back, keep the x-open cells'
/// values, solve the y lines.
///
/// # Safety
/// `u` is the grid's field, `xvals` as `grid.open_cells[0]`, `t` has a plane's length; no
/// other thread touches plane `b` or its entries of `xvals`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
unsafe fn xy_plane(
    grid: &Grid,
    plan: &LinePlan,
    table: &Tables,
    u: *mut f64,
    xvals: *mut f64,
    t: *mut f64,
    b: usize,
    isa: Isa,
) {
    let [nx, ny, _] = grid.n;
    let plane = nx * ny;
    let up = u.add(b * plane);
    let xs = x_row_stride(ny);
    let ext = &grid.inside_extents[b * ny..(b + 1) * ny];
    let lines = |into_t: bool| {
        #[cfg(target_arch = "x86_64")]
        if isa != Isa::Portable {
            return x_lines_avx(up, nx, t, xs, ext, into_t);
        }
        x_lines(up, nx, t, xs, ext, into_t)
    };
    // rows of t past the longest line hold no cell
    let n_rows = ext
        .iter()
        .map(|&(s, e)| e.saturating_sub(s) as usize)
        .max()
        .unwrap_or(0);
    // (past each line's extent `t` keeps what an earlier plane, grid or run left there: no
    // cell of the gel reads it, see `solve_rows`)
    lines(true);
    solve_rows(
        t,
        plan.index[0].as_ptr().add(b * nx * xs),
        xs,
        n_rows,
        0,
        ny,
        &plan.runs[0],
        &plan.row_start[0],
        b * nx,
        1,
        table,
        isa,
    );
    lines(false);
    for q in plan.xopen_start[b]..plan.xopen_start[b + 1] {
        *xvals.add(q) = *u.add(grid.open_cells[0].get_unchecked(q).0 as usize);
    }
    solve_rows(
        up,
        plan.index[1].as_ptr().add(b * plane),
        nx,
        ny,
        0,
        nx,
        &plan.runs[1],
        &plan.row_start[1],
        b * ny,
        1,
        table,
        isa,
    );
}

/// The z sweep of the columns `lo..hi` (plane indices).
///
/// # Safety
/// `u` is the grid's field; no other thread touches these columns.
#[inline(always)]
unsafe fn z_chunk(
    grid: &Grid,
    plan: &LinePlan,
    table: &Tables,
    u: *mut f64,
    lo: usize,
    hi: usize,
    isa: Isa,
) {
    let [nx, ny, nz] = grid.n;
    solve_rows(
        u,
        plan.index[2].as_ptr(),
        nx * ny,
        nz,
        lo,
        hi,
        &plan.runs[2],
        &plan.row_start[2],
        0,
        ny,
        table,
        isa,
    );
}

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

isa_variants!(stencil_span, stencil_span_avx2, stencil_span_avx512,
    (zm: &[f64], c: &[f64], zp: &[f64], o: &mut [f64], a: usize, nx: usize, centre: f64, r: f64));

isa_variants!(uniform_span, uniform_span_avx2, uniform_span_avx512,
    (zm: &[f64], c: &[f64], zp: &[f64], o: &mut [f64], a: usize, nx: usize, code: [u8; 3], r: f64, cb: f64) -> f64);

isa_variants!(xy_plane, xy_plane_avx2, xy_plane_avx512,
    (grid: &Grid, plan: &LinePlan, table: &Tables, u: *mut f64, xvals: *mut f64, t: *mut f64, b: usize, isa: Isa));
isa_variants!(z_chunk, z_chunk_avx2, z_chunk_avx512,
    (grid: &Grid, plan: &LinePlan, table: &Tables, u: *mut f64, lo: usize, hi: usize, isa: Isa));

/// The x and y sweeps, plane by plane (planes in parallel).
fn sweep_xy(
    grid: &Grid,
    plan: &LinePlan,
    table: &Tables,
    u: &mut [f64],
    xvals: &mut [f64],
    isa: Isa,
) {
    let [nx, ny, nz] = grid.n;
    let up = SyncPtr(u.as_mut_ptr());
    let xp = SyncPtr(xvals.as_mut_ptr());
    let run = |b: usize| {
        PLANE.with(|t| {
            let mut t = t.borrow_mut();
            if t.len() < nx * x_row_stride(ny) {
                t.resize(nx * x_row_stride(ny), 0.0);
            }
            let tp = t.as_mut_ptr();
            // SAFETY: each plane is handled by one call; `t` is this thread's own; the
            // plan was built for this grid (checked by codes_id); the ISA was detected.
            unsafe {
                match isa {
                    Isa::Portable => xy_plane(grid, plan, table, up.get(), xp.get(), tp, b, isa),
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx2 => xy_plane_avx2(grid, plan, table, up.get(), xp.get(), tp, b, isa),
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx512 => {
                        xy_plane_avx512(grid, plan, table, up.get(), xp.get(), tp, b, isa)
                    }
                }
            }
        })
    };
    (0..nz).into_par_iter().for_each(run);
}

/// The z sweep, columns in chunks (in parallel) small enough that a chunk's nz planes stay
/// in the core's L2 cache between the forward and the backward pass (a quarter of a 2 MiB L2:
/// on the Fig. 5 cylinder 1 136 columns, 9 KiB per plane; half that was 2 % slower on the
/// dive, docs/speed-history.md, session 19).
fn sweep_z(grid: &Grid, plan: &LinePlan, table: &Tables, u: &mut [f64], isa: Isa) {
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    const L2_BUDGET: usize = 512 * 1024;
    let threads = rayon::current_num_threads().max(1);
    let by_cache = (L2_BUDGET / (8 * nz)).max(64);
    let by_threads = plane.div_ceil(4 * threads);
    let chunk = by_cache.min(by_threads).max(8).next_multiple_of(8);
    let up = SyncPtr(u.as_mut_ptr());
    let n_chunks = plane.div_ceil(chunk);
    (0..n_chunks).into_par_iter().for_each(|c| {
        let (lo, hi) = (c * chunk, ((c + 1) * chunk).min(plane));
        // SAFETY: chunks are disjoint column sets; the plan matches the grid.
        unsafe {
            match isa {
                Isa::Portable => z_chunk(grid, plan, table, up.get(), lo, hi, isa),
                #[cfg(target_arch = "x86_64")]
                Isa::Avx2 => z_chunk_avx2(grid, plan, table, up.get(), lo, hi, isa),
                #[cfg(target_arch = "x86_64")]
                Isa::Avx512 => z_chunk_avx512(grid, plan, table, up.get(), lo, hi, isa),
            }
        }
    });
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
mod planned_tests {
    use super::super::grid::{Face, Shape};
    use super::*;

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
                    let mut dst: Vec<&mut [f64]> =
                        us.iter_mut().map(|u| u.as_mut_slice()).collect();
                    explicit_steps_into(&g, &src, &mut dst, &dc, dt, &mut inflow);
                } else {
                    let mut fields: Vec<&mut [f64]> =
                        us.iter_mut().map(|u| u.as_mut_slice()).collect();
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
                            let (c, id) =
                                (g.index(g.n[0] / 2, g.n[1] / 2, g.n[2] / 2), g.codes_id());
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
        use super::super::fields::Fields;
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
}
