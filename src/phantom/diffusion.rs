//! The gas-transport solver for eq. (2.1), ∂C/∂t = D∇²C, on the cell-centred grid
//! (finite volumes, 7-point stencil). Open faces hold C at the chamber value C_b at
//! half a cell from the outermost centres; sealed faces carry no flux.
//!
//! Two schemes, both conservative to round-off (the interior face fluxes cancel in pairs):
//! - [`explicit_step`]: forward Euler, used when the step the physics asks for is below the
//!   positivity limit dt ≤ h²/(D·w_max) (w_max the largest stencil weight sum, 6 inside,
//!   up to 9 in a corner with three open faces);
//! - [`implicit_step`]: locally one-dimensional backward Euler (x, y, then z tridiagonal
//!   solves, Thomas algorithm), unconditionally stable and positivity-preserving, used when
//!   long holds allow large steps. For a box with uniform D the three 1-D operators commute,
//!   so the splitting adds no error beyond backward Euler's own.
//!
//! Both return the amount that entered through open faces during the step (mol per unit of
//! `cell_volume`, i.e. multiply by h³ for mol), for the gas balance.

use super::grid::{Grid, INSIDE_BIT, SIDE_INTERIOR, SIDE_OPEN, SIDE_SEALED};
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

/// Largest stencil weight sum over the inside cells (the explicit positivity limit is
/// dt ≤ h²/(D·this)).
pub fn max_weight_sum(grid: &Grid) -> f64 {
    let mut m: f64 = 0.0;
    for idx in 0..grid.len() {
        if !grid.inside(idx) {
            continue;
        }
        let mut s = 0.0;
        for d in 0..3 {
            let c = grid.codes[d][idx];
            s += weight(c & 3) + weight((c >> 2) & 3);
        }
        m = m.max(s);
    }
    m
}

/// The largest stable, positivity-preserving forward-Euler step, s.
pub fn explicit_limit(grid: &Grid, d: f64) -> f64 {
    grid.h * grid.h / (d * max_weight_sum(grid))
}

/// One forward-Euler step from `u` into `out` with r = D·dt/h². Returns the boundary inflow
/// (sum of concentration change due to open faces).
pub fn explicit_step(grid: &Grid, u: &[f64], out: &mut [f64], d: f64, dt: f64, cb: f64) -> f64 {
    let r = d * dt / (grid.h * grid.h);
    let [nx, ny, _] = grid.n;
    let plane = nx * ny;
    let strides = [1usize, nx, plane];
    let generic = |idx: usize| -> f64 {
        let c0 = grid.codes[0][idx];
        if c0 & INSIDE_BIT == 0 {
            return u[idx];
        }
        let ui = u[idx];
        let mut acc = 0.0;
        for (dir, stride) in strides.iter().enumerate() {
            let c = grid.codes[dir][idx];
            let m = c & 3;
            let p = (c >> 2) & 3;
            if m == SIDE_INTERIOR {
                acc += u[idx - stride] - ui;
            } else if m == SIDE_OPEN {
                acc += 2.0 * (cb - ui);
            }
            if p == SIDE_INTERIOR {
                acc += u[idx + stride] - ui;
            } else if p == SIDE_OPEN {
                acc += 2.0 * (cb - ui);
            }
        }
        ui + r * acc
    };
    let centre = 1.0 - 6.0 * r;
    out.par_chunks_mut(plane).enumerate().for_each(|(k, slab)| {
        for j in 0..ny {
            let row = j + ny * k;
            let base = row * nx;
            let (i0, i1) = grid.interior_spans[row];
            let (i0, i1) = (i0 as usize, (i1 as usize).max(i0 as usize));
            let orow = &mut slab[j * nx..(j + 1) * nx];
            for i in (0..i0).chain(i1..nx) {
                orow[i] = generic(base + i);
            }
            if i1 > i0 {
                // all six neighbours exist and are inside: plain 7-point stencil, branch-free
                let a = base + i0;
                let b = base + i1;
                let c = &u[a..b];
                let xm = &u[a - 1..b - 1];
                let xp = &u[a + 1..b + 1];
                let ym = &u[a - nx..b - nx];
                let yp = &u[a + nx..b + nx];
                let zm = &u[a - plane..b - plane];
                let zp = &u[a + plane..b + plane];
                for (q, o) in orow[i0..i1].iter_mut().enumerate() {
                    *o = centre * c[q] + r * (xm[q] + xp[q] + ym[q] + yp[q] + zm[q] + zp[q]);
                }
            }
        }
    });
    let mut inflow = 0.0;
    for cells in &grid.open_cells {
        for &(idx, cnt) in cells {
            inflow += r * 2.0 * cnt as f64 * (cb - u[idx as usize]);
        }
    }
    inflow
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

/// Each cell's place in the tridiagonal systems of the three sweeps, which depends on the face
/// codes only: per direction, the index of its row in the factor table
/// (1 + ((start_open·3 + end_kind)·max_len + position in the segment); 0 for a cell outside).
/// Two cells with the same index have the same matrix row and the same Thomas factors: the
/// factors of a segment's first k rows depend only on k, the segment's minus end, and (for
/// its last row) the plus end.
#[derive(Debug, Clone)]
struct LinePlan {
    /// [`Grid::codes_id`] of the codes the plan was built from.
    codes_id: u64,
    /// Longest segment in any direction (the table's stride).
    max_len: usize,
    /// Per direction, per cell: the factor-table index.
    index: [Vec<u16>; 3],
}

impl LinePlan {
    /// The plan of `grid`'s current codes, or `None` when a segment is longer than
    /// [`MAX_TABLE_SEGMENT`].
    fn build(grid: &Grid) -> Option<LinePlan> {
        let [nx, ny, _] = grid.n;
        let strides = [1usize, nx, nx * ny];
        let len = grid.len();
        // pass 1: position of every cell in its segment (cells in index order: the minus
        // neighbour idx − stride always comes first) and the longest segment
        let mut pos: [Vec<u32>; 3] = [vec![0; len], vec![0; len], vec![0; len]];
        let mut max_len = 1usize;
        for dir in 0..3 {
            let codes = &grid.codes[dir];
            let stride = strides[dir];
            let p = &mut pos[dir];
            for idx in 0..len {
                let c = codes[idx];
                if c & INSIDE_BIT != 0 && c & 3 == SIDE_INTERIOR {
                    let k = p[idx - stride] + 1;
                    p[idx] = k;
                    max_len = max_len.max(k as usize + 1);
                }
            }
        }
        if max_len > MAX_TABLE_SEGMENT {
            return None;
        }
        // pass 2: the table index; the segment's minus end is read at its first cell
        let mut index: [Vec<u16>; 3] = [vec![0; len], vec![0; len], vec![0; len]];
        for dir in 0..3 {
            let codes = &grid.codes[dir];
            let stride = strides[dir];
            let p = &pos[dir];
            let out = &mut index[dir];
            for idx in 0..len {
                let c = codes[idx];
                if c & INSIDE_BIT == 0 {
                    continue;
                }
                let k = p[idx] as usize;
                let first = codes[idx - k * stride];
                let start_open = usize::from(first & 3 == SIDE_OPEN);
                let end = match (c >> 2) & 3 {
                    SIDE_INTERIOR => MIDDLE,
                    SIDE_OPEN => LAST_OPEN,
                    _ => LAST_SEALED,
                };
                out[idx] = (1 + (start_open * 3 + end) * max_len + k) as u16;
            }
        }
        Some(LinePlan {
            codes_id: grid.codes_id(),
            max_len,
            index,
        })
    }
}

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
                table[base + k] = Factor {
                    inv,
                    cneg: cm * inv,
                    link: if k > 0 { r } else { 0.0 },
                    open_minus: if m == SIDE_OPEN { k2 } else { 0.0 },
                    open_plus: if p == SIDE_OPEN { k2 } else { 0.0 },
                };
            }
        }
    }
}

/// The locally-one-dimensional backward-Euler step with each line's Thomas factors taken
/// from a small table instead of being recomputed per cell: the face codes are read once per
/// rebuild (when [`Grid::codes_id`] changes), the inner loops have no branches and no
/// divisions. Gives the same bits as [`implicit_step`], which it replaces in the time loop.
#[derive(Debug, Clone, Default)]
pub struct ImplicitSolver {
    plan: Option<LinePlan>,
    /// Set when the grid's segments are too long for the table: the generic sweep is used.
    generic: Option<u64>,
    table: Vec<Factor>,
    scratch: Vec<f64>,
}

impl ImplicitSolver {
    /// A solver with no plan yet (built at the first step).
    pub fn new() -> ImplicitSolver {
        ImplicitSolver::default()
    }

    /// One LOD backward-Euler step of `u` in place (x, y, z sweeps), r = D·dt/h², open faces
    /// at `cb`. Returns the boundary inflow, as [`implicit_step`].
    pub fn step(&mut self, grid: &Grid, u: &mut [f64], d: f64, dt: f64, cb: f64) -> f64 {
        let id = grid.codes_id();
        let stale = self.plan.as_ref().is_none_or(|p| p.codes_id != id);
        if stale && self.generic != Some(id) {
            self.plan = LinePlan::build(grid);
            self.generic = if self.plan.is_none() { Some(id) } else { None };
        }
        let r = d * dt / (grid.h * grid.h);
        let Some(plan) = self.plan.as_ref().filter(|p| p.codes_id == id) else {
            self.scratch.resize(grid.len(), 0.0);
            let mut inflow = 0.0;
            for dir in 0..3 {
                inflow += sweep(grid, dir, u, &mut self.scratch, r, cb);
            }
            return inflow;
        };
        fill_table(&mut self.table, plan.max_len, r, cb);
        let mut inflow = 0.0;
        for dir in 0..3 {
            sweep_planned(grid, dir, &plan.index[dir], &self.table, u);
            inflow += open_face_inflow(grid, dir, u, r, cb);
        }
        inflow
    }
}

/// One direction's tridiagonal solves with the planned factors (see [`sweep`] for the layout
/// of the work items: lines are solved many at a time in lock-step).
fn sweep_planned(grid: &Grid, dir: usize, index: &[u16], table: &[Factor], u: &mut [f64]) {
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    let (n_blocks, n_along, n_inner, block_stride, along_stride, inner_stride) = match dir {
        0 => (nz, nx, ny, plane, 1, nx),
        1 => (nz, ny, nx, plane, nx, 1),
        _ => (1, nz, plane, 0, plane, 1),
    };
    let threads = rayon::current_num_threads().max(1);
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
    let len = u.len();
    items.par_iter().for_each(|&(b, lo, hi)| {
        let base = b * block_stride;
        // SAFETY: the work items cover disjoint sets of lines and each touches only its own
        // cells (as in `sweep`); every index is below `len` (checked in debug builds), and
        // the table indices were built for this grid's size.
        unsafe {
            let u = std::slice::from_raw_parts_mut(up.get(), len);
            let cell = |a: usize, i: usize| base + a * along_stride + i * inner_stride;
            // forward elimination; the first row of a line has no previous row
            for i in lo..hi {
                let idx = cell(0, i);
                let e = *table.get_unchecked(*index.get_unchecked(idx) as usize);
                let rhs = *u.get_unchecked(idx) + e.open_minus + e.open_plus;
                *u.get_unchecked_mut(idx) = rhs * e.inv;
            }
            for a in 1..n_along {
                for i in lo..hi {
                    let idx = cell(a, i);
                    debug_assert!(idx < len);
                    let e = *table.get_unchecked(*index.get_unchecked(idx) as usize);
                    let rhs = *u.get_unchecked(idx)
                        + e.open_minus
                        + e.open_plus
                        + e.link * *u.get_unchecked(idx - along_stride);
                    *u.get_unchecked_mut(idx) = rhs * e.inv;
                }
            }
            // back substitution
            for a in (0..n_along.saturating_sub(1)).rev() {
                for i in lo..hi {
                    let idx = cell(a, i);
                    let e = table.get_unchecked(*index.get_unchecked(idx) as usize);
                    *u.get_unchecked_mut(idx) -= e.cneg * *u.get_unchecked(idx + along_stride);
                }
            }
        }
    });
}

/// The field-error pass of a step ([`super::sim`]'s `diffuse`): with `after` the field at
/// the end of the step and `before_to_error` at its start, stores each inside cell's change
/// δ = after − before in `change` (which held the last step's change δ'), overwrites
/// `before_to_error` with the raw error vector δ − ratio·δ' (0 outside), and returns its
/// largest magnitude (ratio = this step over the last). A max over per-plane maxima:
/// independent of the number of threads.
pub fn change_and_error(
    grid: &Grid,
    after: &[f64],
    before_to_error: &mut [f64],
    change: &mut [f64],
    ratio: f64,
) -> f64 {
    let plane = grid.n[0] * grid.n[1];
    let inside = &grid.codes[0];
    change
        .par_chunks_mut(plane)
        .zip(before_to_error.par_chunks_mut(plane))
        .enumerate()
        .map(|(k, (slab, err))| {
            let lo = k * plane;
            let mut worst: f64 = 0.0;
            for (q, (last, e)) in slab.iter_mut().zip(err.iter_mut()).enumerate() {
                let idx = lo + q;
                if inside[idx] & INSIDE_BIT == 0 {
                    *last = 0.0;
                    *e = 0.0;
                    continue;
                }
                let delta = after[idx] - *e;
                let x = delta - ratio * *last;
                worst = worst.max(x.abs());
                *e = x;
                *last = delta;
            }
            worst
        })
        .reduce(|| 0.0, f64::max)
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

    /// The planned solver against the generic per-cell sweep (an independent elimination of
    /// the same systems): the same bits on a cylinder with open faces and cells excluded.
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
        let hole: Vec<usize> = (0..g.len())
            .filter(|&i| {
                let (x, y, z) = (i % g.n[0], (i / g.n[0]) % g.n[1], i / (g.n[0] * g.n[1]));
                (8..11).contains(&x) && (9..12).contains(&y) && (3..6).contains(&z)
            })
            .collect();
        g.set_excluded(&hole, true);
        let u0: Vec<f64> = (0..g.len())
            .map(|i| ((i * 7919 + 13) % 101) as f64 / 100.0)
            .collect();
        let mut solver = ImplicitSolver::new();
        for (d, dt, cb) in [(2.5e-9, 20.0, 1.5), (1e-9, 3.0, 0.2), (8e-9, 600.0, 0.0)] {
            let mut a = u0.clone();
            let mut s = vec![0.0; g.len()];
            let fa = implicit_step(&g, &mut a, &mut s, d, dt, cb);
            let mut b = u0.clone();
            let fb = solver.step(&g, &mut b, d, dt, cb);
            for i in 0..g.len() {
                assert_eq!(
                    a[i].to_bits(),
                    b[i].to_bits(),
                    "cell {i}: {} vs {}",
                    a[i],
                    b[i]
                );
            }
            assert_eq!(fa.to_bits(), fb.to_bits());
        }
    }
}
