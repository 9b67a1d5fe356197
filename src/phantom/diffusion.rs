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
//!
//! # The implicit kernel ([`ImplicitSolver`])
//!
//! Each line segment's Thomas factors depend only on its length class, its ends and the
//! position in it, so a `LinePlan` (rebuilt when [`Grid::codes_id`] changes) gives every
//! cell, per direction, a u16 index into a small factor table (rebuilt per step from r and
//! C_b). Lines are solved many at a time in lock-step along the contiguous index, vectorised
//! across lines (independent systems: the same operations per cell as the generic sweep, in
//! the same order, hence the same bits, for any thread count):
//! - **x and y, per z-plane** (planes in parallel; a 128×128 plane is 128 KiB and stays in
//!   L2): the plane is transposed into a per-thread copy whose rows are x positions (row
//!   stride ny, padded by `x_row_stride` against cache-set conflicts), so the x lines run
//!   across contiguous rows; forward elimination row by row, back substitution in reverse,
//!   transpose back, keep the x-open cells' values (the x inflow is summed afterwards in cell
//!   order, as the generic sweep does), then the y lines the same way on the plane itself.
//! - **z**, in column chunks (in parallel) sized so a chunk's nz planes stay in L2 between
//!   the forward and backward pass.
//!
//! Every row (x: a plane's x position, y: a plane's y position, z: a whole plane) is cut at
//! plan time into `Run`s along its contiguous index: stretches of one table row (in a box,
//! whole rows; in a cylinder, the z rows' inside cells) use broadcast factors and exactly the
//! generic sweep's terms; stretches of middle rows (linked, no open face) look up only the
//! pivot and the back-substitution weight per cell; the rest looks up the full factor row
//! per cell; cells outside are skipped. The inner loops are compiled three times (baseline,
//! AVX2, AVX-512F via `#[target_feature]`, no FMA: Rust never contracts) and the best the
//! CPU has is picked at run time; all variants are tested against the generic sweep.

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
    explicit_step_with(grid, u, out, d, dt, cb, Isa::detect())
}

/// The 7-point stencil over the cells `a..a + o.len()` of `u` into `o`, for cells whose six
/// neighbours are all inside (the same operations in the same order for every instruction
/// set: vectorised across cells only).
#[inline(always)]
fn stencil_span(u: &[f64], o: &mut [f64], a: usize, nx: usize, plane: usize, centre: f64, r: f64) {
    let b = a + o.len();
    let c = &u[a..b];
    let xm = &u[a - 1..b - 1];
    let xp = &u[a + 1..b + 1];
    let ym = &u[a - nx..b - nx];
    let yp = &u[a + nx..b + nx];
    let zm = &u[a - plane..b - plane];
    let zp = &u[a + plane..b + plane];
    for (q, o) in o.iter_mut().enumerate() {
        *o = centre * c[q] + r * (xm[q] + xp[q] + ym[q] + yp[q] + zm[q] + zp[q]);
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
                let (o, a) = (&mut orow[i0..i1], base + i0);
                match isa {
                    Isa::Portable => stencil_span(u, o, a, nx, plane, centre, r),
                    // SAFETY: `Isa::detect` found the instruction set on this CPU
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx2 => unsafe { stencil_span_avx2(u, o, a, nx, plane, centre, r) },
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx512 => unsafe { stencil_span_avx512(u, o, a, nx, plane, centre, r) },
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
/// grid's own order; for x transposed per z-plane (cell (i, j, k) at (k·nx + i)·s + j, s = ny padded by
/// [`x_row_stride`]). In
/// that layout every direction's data is a sequence of rows (x: per plane, one row per i, of
/// ny cells; y: per plane, one row per j, of nx cells; z: one row per k, of nx·ny cells), and
/// `runs` cuts each row into stretches of equal index (broadcast factors) and mixed stretches.
#[derive(Debug, Clone)]
struct LinePlan {
    /// [`Grid::codes_id`] of the codes the plan was built from.
    codes_id: u64,
    /// Longest segment in any direction (the table's stride).
    max_len: usize,
    /// Per direction, per cell (in the kernel's layout): the factor-table index.
    index: [Vec<u16>; 3],
    /// Per direction, the runs of all rows, row after row.
    runs: [Vec<Run>; 3],
    /// Per direction, where each row's runs begin in `runs` (one more entry than rows).
    row_start: [Vec<u32>; 3],
    /// Per z-plane, where its cells begin in `grid.open_cells[0]` (nz + 1 entries).
    xopen_start: Vec<usize>,
}

impl LinePlan {
    /// The plan of `grid`'s current codes, or `None` when a segment is longer than
    /// [`MAX_TABLE_SEGMENT`].
    fn build(grid: &Grid) -> Option<LinePlan> {
        let [nx, ny, nz] = grid.n;
        let plane = nx * ny;
        let strides = [1usize, nx, plane];
        let len = grid.len();
        // pass 1: position of every cell in its segment (cells in index order: the minus
        // neighbour idx − stride always comes first) and the longest segment, kept in the
        // index arrays themselves (no temporary of the grid's size)
        let mut index: [Vec<u16>; 3] = [vec![0; len], vec![0; len], vec![0; len]];
        let mut max_len = 1usize;
        for dir in 0..3 {
            let codes = &grid.codes[dir];
            let stride = strides[dir];
            let p = &mut index[dir];
            for idx in 0..len {
                let c = codes[idx];
                if c & INSIDE_BIT != 0 && c & 3 == SIDE_INTERIOR {
                    let k = p[idx - stride] as usize + 1;
                    if k + 1 > MAX_TABLE_SEGMENT {
                        return None;
                    }
                    p[idx] = k as u16;
                    max_len = max_len.max(k + 1);
                }
            }
        }
        // pass 2, in place: position → table index; the segment's minus end is read at its
        // first cell
        for dir in 0..3 {
            let codes = &grid.codes[dir];
            let stride = strides[dir];
            let out = &mut index[dir];
            for idx in 0..len {
                let c = codes[idx];
                if c & INSIDE_BIT == 0 {
                    continue;
                }
                let k = out[idx] as usize;
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
        // x: transposed per plane (rows of ny cells, `xstride` apart)
        let xstride = x_row_stride(ny);
        let mut xt = vec![0u16; nz * plane];
        for b in 0..nz {
            let (src, dst) = (&index[0][b * plane..], &mut xt[b * plane..]);
            for j in 0..ny {
                for i in 0..nx {
                    dst[i * ny + j] = src[j * nx + i];
                }
            }
        }
        let row_lens = [ny, nx, plane];
        let mut runs: [Vec<Run>; 3] = Default::default();
        let mut row_start: [Vec<u32>; 3] = Default::default();
        (runs[0], row_start[0]) = build_runs(&xt, ny, max_len);
        for dir in 1..3 {
            (runs[dir], row_start[dir]) = build_runs(&index[dir], row_lens[dir], max_len);
        }
        let mut padded = vec![0u16; nz * nx * xstride];
        for (dst, src) in padded.chunks_mut(xstride).zip(xt.chunks(ny)) {
            dst[..ny].copy_from_slice(src);
        }
        index[0] = padded;
        let xopen_start = (0..=nz)
            .map(|b| grid.open_cells[0].partition_point(|&(idx, _)| (idx as usize) < b * plane))
            .collect();
        Some(LinePlan {
            codes_id: grid.codes_id(),
            max_len,
            index,
            runs,
            row_start,
            xopen_start,
        })
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

/// Cut each row of `index` (rows of `row_len` cells, one after the other) into runs: maximal
/// stretches of at least [`MIN_RUN`] equal indices become broadcast runs (none for index 0,
/// cells outside, which keep their values), the cells between them per-cell runs
/// ([`GATHER_MID`] where they are all middle rows, else [`GATHER`]).
fn build_runs(index: &[u16], row_len: usize, max_len: usize) -> (Vec<Run>, Vec<u32>) {
    // a middle row: linked to the previous one (position k > 0), interior plus side
    let mid = |v: u16| {
        v != 0 && {
            let q = v as usize - 1;
            !q.is_multiple_of(max_len) && (q / max_len) % 3 == MIDDLE
        }
    };
    let flush = |runs: &mut Vec<Run>, row: &[u16], g: usize, e: usize| {
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
                    runs.push(Run {
                        start: pending as u32,
                        end: s as u32,
                        idx: GATHER,
                    });
                }
                runs.push(Run {
                    start: s as u32,
                    end: t as u32,
                    idx: GATHER_MID,
                });
                pending = t;
            }
            s = t;
        }
        if pending < e {
            runs.push(Run {
                start: pending as u32,
                end: e as u32,
                idx: GATHER,
            });
        }
    };
    let mut runs = Vec::new();
    let mut row_start = vec![0u32];
    for row in index.chunks(row_len) {
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
                    flush(&mut runs, row, g, s);
                }
                if v != 0 {
                    runs.push(Run {
                        start: s as u32,
                        end: e as u32,
                        idx: u32::from(v),
                    });
                }
            } else if pending.is_none() {
                pending = Some(s);
            }
            s = e;
        }
        if let Some(g) = pending {
            flush(&mut runs, row, g, row.len());
        }
        row_start.push(runs.len() as u32);
    }
    (runs, row_start)
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
    table: Tables,
    scratch: Vec<f64>,
    /// The x-open cells' values after the x sweep (as `grid.open_cells[0]`), for the inflow.
    xvals: Vec<f64>,
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
        self.table.fill(plan.max_len, r, cb);
        self.xvals.resize(grid.open_cells[0].len(), 0.0);
        sweep_xy(grid, plan, &self.table, u, &mut self.xvals, isa);
        // the x inflow from the values right after the x sweep, summed in cell order
        let mut fx = 0.0;
        for (&(_, cnt), &x) in grid.open_cells[0].iter().zip(&self.xvals) {
            fx += r * 2.0 * cnt as f64 * (cb - x);
        }
        let mut inflow = 0.0;
        inflow += fx;
        inflow += open_face_inflow(grid, 1, u, r, cb);
        sweep_z(grid, plan, &self.table, u, isa);
        inflow += open_face_inflow(grid, 2, u, r, cb);
        inflow
    }
}

/// Solve the lines of a stack of rows in place: row a (0 ≤ a < `n_along`) holds cells
/// `buf[a·stride + i]`, lines run across the rows (along a), and the cells `lo ≤ i < hi` of
/// every row are solved in lock-step; `index` is laid out as `buf`, `runs`/`row_start` give
/// each row's runs (row a is `row0 + a`).
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
    tables: &Tables,
) {
    let table = &tables.factors[..];
    let (inv, cneg, r) = (&tables.inv[..], &tables.cneg[..], tables.r);
    let row_runs = |a: usize| -> &[Run] {
        let rr = &runs[row_start[row0 + a] as usize..row_start[row0 + a + 1] as usize];
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
                for i in s..e {
                    let rhs = *cur.add(i) + r * *prev.add(i);
                    *cur.add(i) = rhs * *inv.get_unchecked(*ix.add(i) as usize);
                }
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
                for i in s..e {
                    *cur.add(i) -= *cneg.get_unchecked(*ix.add(i) as usize) * *next.add(i);
                }
            } else if run.idx == GATHER {
                for i in s..e {
                    let f = table.get_unchecked(*ix.add(i) as usize);
                    *cur.add(i) -= f.cneg * *next.add(i);
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

/// Copy the `rows × cols` matrix at `src` (row `r` at `src + r·ss`) transposed into `dst`
/// (row `c` at `dst + c·ds`). With `by_dst` the outer loop walks the destination's rows (its
/// writes stream, the reads scatter), else the source's.
///
/// # Safety
/// `src` and `dst` are valid for the rows and do not overlap.
#[inline(always)]
unsafe fn transpose(
    src: *const f64,
    ss: usize,
    dst: *mut f64,
    ds: usize,
    rows: usize,
    cols: usize,
    by_dst: bool,
) {
    const B: usize = 8;
    let block = |r0: usize, c0: usize| {
        for r in r0..(r0 + B).min(rows) {
            for c in c0..(c0 + B).min(cols) {
                *dst.add(c * ds + r) = *src.add(r * ss + c);
            }
        }
    };
    if by_dst {
        for c0 in (0..cols).step_by(B) {
            for r0 in (0..rows).step_by(B) {
                block(r0, c0);
            }
        }
    } else {
        for r0 in (0..rows).step_by(B) {
            for c0 in (0..cols).step_by(B) {
                block(r0, c0);
            }
        }
    }
}

/// [`transpose`] with 4×4 blocks transposed in AVX registers (the edges element by element).
///
/// # Safety
/// As [`transpose`]; the CPU has AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn transpose_avx(
    src: *const f64,
    ss: usize,
    dst: *mut f64,
    ds: usize,
    rows: usize,
    cols: usize,
    by_dst: bool,
) {
    use std::arch::x86_64::*;
    let (r4, c4) = (rows / 4 * 4, cols / 4 * 4);
    let block = |r0: usize, c0: usize| {
        let s = src.add(r0 * ss + c0);
        let a0 = _mm256_loadu_pd(s);
        let a1 = _mm256_loadu_pd(s.add(ss));
        let a2 = _mm256_loadu_pd(s.add(2 * ss));
        let a3 = _mm256_loadu_pd(s.add(3 * ss));
        let t0 = _mm256_unpacklo_pd(a0, a1);
        let t1 = _mm256_unpackhi_pd(a0, a1);
        let t2 = _mm256_unpacklo_pd(a2, a3);
        let t3 = _mm256_unpackhi_pd(a2, a3);
        let d = dst.add(c0 * ds + r0);
        _mm256_storeu_pd(d, _mm256_permute2f128_pd(t0, t2, 0x20));
        _mm256_storeu_pd(d.add(ds), _mm256_permute2f128_pd(t1, t3, 0x20));
        _mm256_storeu_pd(d.add(2 * ds), _mm256_permute2f128_pd(t0, t2, 0x31));
        _mm256_storeu_pd(d.add(3 * ds), _mm256_permute2f128_pd(t1, t3, 0x31));
    };
    if by_dst {
        for c0 in (0..c4).step_by(4) {
            for r0 in (0..r4).step_by(4) {
                block(r0, c0);
            }
        }
    } else {
        for r0 in (0..r4).step_by(4) {
            for c0 in (0..c4).step_by(4) {
                block(r0, c0);
            }
        }
    }
    for r in 0..rows {
        let c_from = if r < r4 { c4 } else { 0 };
        for c in c_from..cols {
            *dst.add(c * ds + r) = *src.add(r * ss + c);
        }
    }
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
    simd: bool,
) {
    let [nx, ny, _] = grid.n;
    let plane = nx * ny;
    let up = u.add(b * plane);
    let xs = x_row_stride(ny);
    let transpose = |src: *const f64, ss, dst: *mut f64, ds, rows, cols, by_dst| {
        #[cfg(target_arch = "x86_64")]
        if simd {
            return transpose_avx(src, ss, dst, ds, rows, cols, by_dst);
        }
        let _ = simd;
        transpose(src, ss, dst, ds, rows, cols, by_dst)
    };
    // the scattered side of both transposes is the padded copy
    transpose(up, nx, t, xs, ny, nx, false);
    solve_rows(
        t,
        plan.index[0].as_ptr().add(b * nx * xs),
        xs,
        nx,
        0,
        ny,
        &plan.runs[0],
        &plan.row_start[0],
        b * nx,
        table,
    );
    transpose(t, xs, up, nx, nx, ny, true);
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
        table,
    );
}

/// The z sweep of the columns `lo..hi` (plane indices).
///
/// # Safety
/// `u` is the grid's field; no other thread touches these columns.
#[inline(always)]
unsafe fn z_chunk(grid: &Grid, plan: &LinePlan, table: &Tables, u: *mut f64, lo: usize, hi: usize) {
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
        table,
    );
}

/// Instantiate a kernel for an instruction set: `#[target_feature]` lets the compiler
/// vectorise the inlined body with that set's registers (no FMA: Rust never contracts).
macro_rules! isa_variants {
    ($name:ident, $avx2:ident, $avx512:ident, ($($arg:ident: $ty:ty),*)) => {
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2")]
        #[allow(clippy::too_many_arguments)]
        unsafe fn $avx2($($arg: $ty),*) {
            $name($($arg),*)
        }
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx512f")]
        #[allow(clippy::too_many_arguments)]
        unsafe fn $avx512($($arg: $ty),*) {
            $name($($arg),*)
        }
    };
}

isa_variants!(stencil_span, stencil_span_avx2, stencil_span_avx512,
    (u: &[f64], o: &mut [f64], a: usize, nx: usize, plane: usize, centre: f64, r: f64));

isa_variants!(xy_plane, xy_plane_avx2, xy_plane_avx512,
    (grid: &Grid, plan: &LinePlan, table: &Tables, u: *mut f64, xvals: *mut f64, t: *mut f64, b: usize, simd: bool));
isa_variants!(z_chunk, z_chunk_avx2, z_chunk_avx512,
    (grid: &Grid, plan: &LinePlan, table: &Tables, u: *mut f64, lo: usize, hi: usize));

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
                    Isa::Portable => xy_plane(grid, plan, table, up.get(), xp.get(), tp, b, false),
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx2 => xy_plane_avx2(grid, plan, table, up.get(), xp.get(), tp, b, true),
                    #[cfg(target_arch = "x86_64")]
                    Isa::Avx512 => {
                        xy_plane_avx512(grid, plan, table, up.get(), xp.get(), tp, b, true)
                    }
                }
            }
        })
    };
    (0..nz).into_par_iter().for_each(run);
}

/// The z sweep, columns in chunks (in parallel) small enough that a chunk's nz planes stay
/// in the core's L2 cache between the forward and the backward pass.
fn sweep_z(grid: &Grid, plan: &LinePlan, table: &Tables, u: &mut [f64], isa: Isa) {
    let [nx, ny, nz] = grid.n;
    let plane = nx * ny;
    const L2_BUDGET: usize = 256 * 1024;
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
                Isa::Portable => z_chunk(grid, plan, table, up.get(), lo, hi),
                #[cfg(target_arch = "x86_64")]
                Isa::Avx2 => z_chunk_avx2(grid, plan, table, up.get(), lo, hi),
                #[cfg(target_arch = "x86_64")]
                Isa::Avx512 => z_chunk_avx512(grid, plan, table, up.get(), lo, hi),
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

    /// The explicit step compiled for every instruction set this CPU has gives the portable
    /// build's bits (a cylinder with open faces and excluded cells: spans and generic cells).
    #[test]
    fn explicit_step_is_the_same_bits_in_every_instruction_set() {
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
}
