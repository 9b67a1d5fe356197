//! The implicit step: locally-one-dimensional backward Euler, the generic sweep and the
//! planned solver ([`ImplicitSolver`]: line plan, factor tables, the vectorised sweeps; the
//! module doc of [`super`]).

use super::*;

#[derive(Clone, Copy)]
pub(super) struct SyncPtr(*mut f64);
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
pub(super) fn sweep(
    grid: &Grid,
    dir: usize,
    u: &mut [f64],
    cp: &mut [f64],
    r: f64,
    cb: f64,
) -> f64 {
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
pub(super) fn open_face_inflow(grid: &Grid, dir: usize, u: &[f64], r: f64, cb: f64) -> f64 {
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
pub(super) const MAX_TABLE_SEGMENT: usize = (u16::MAX as usize - 1) / 6;

/// Where a cell sits at the plus end of its segment: the plus side is an interior face
/// (`MIDDLE`), or the segment ends there at a sealed or an open face.
pub(super) const MIDDLE: usize = 0;
pub(super) const LAST_SEALED: usize = 1;
pub(super) const LAST_OPEN: usize = 2;

/// A stretch `[start, end)` of one row's cells (positions along the row's contiguous,
/// vectorised index) solved with the factors of table row `idx` for all of them, or with each
/// cell's own table row ([`GATHER`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Run {
    start: u32,
    end: u32,
    idx: u32,
}

/// [`Run::idx`] of a stretch whose cells have different table rows (looked up per cell).
pub(super) const GATHER: u32 = u32::MAX;

/// [`Run::idx`] of a stretch of different table rows that are all middle rows of their
/// segments (linked to the previous row, no open face): only the pivot and the
/// back-substitution weight differ, and only those are looked up per cell.
pub(super) const GATHER_MID: u32 = u32::MAX - 1;

/// Shortest stretch of middle rows that gets its own [`GATHER_MID`] run.
pub(super) const MIN_MID_RUN: usize = 4;

/// Shortest stretch of equal table rows that gets its own broadcast run; shorter stretches
/// join the neighbouring per-cell (gather) run.
pub(super) const MIN_RUN: usize = 8;

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
pub(super) struct LinePlan {
    /// [`Grid::codes_id`] of the codes the plan was built from.
    pub(super) codes_id: u64,
    /// Longest segment in any direction (the table's stride).
    pub(super) max_len: usize,
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
pub(super) fn table_index(c: u8, start_open: bool, k: usize, max_len: usize) -> u16 {
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
pub(super) const START_OPEN: u16 = 1 << 15;

/// The position in its segment and whether the segment begins at an open face, from a value
/// of [`positions`].
#[inline(always)]
pub(super) fn position(v: u16) -> (usize, bool) {
    (usize::from(v & !START_OPEN), v & START_OPEN != 0)
}

/// The table indices of the last cells of segments of `max_len` cells.
pub(super) fn longest_ends(max_len: usize) -> [u16; 4] {
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
pub(super) fn positions(codes: &[u8], pos: &mut [u16], stride: usize) -> Option<usize> {
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
pub(super) fn table_indices(codes: &[u8], out: &mut [u16], max_len: usize) -> usize {
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
    pub(super) fn build(grid: &Grid) -> Option<LinePlan> {
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
    pub(super) fn update(&mut self, grid: &Grid, cells: &[usize]) -> bool {
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
pub(super) fn row_of<'a>(index: &'a [u16], grid: &Grid, dir: usize, r: usize) -> (&'a [u16], u32) {
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
pub(super) fn update_lines(
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
pub(super) fn rerun(
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
pub(super) fn x_row_stride(ny: usize) -> usize {
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
pub(super) fn row_runs(row: &[u16], offset: u32, max_len: usize, runs: &mut Vec<Run>) {
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
pub(super) const OPEN_MINUS: u8 = 1;
/// [`Factor::flags`]: the row adds the open plus face's term.
pub(super) const OPEN_PLUS: u8 = 2;
/// [`Factor::flags`]: the row is linked to the previous one.
pub(super) const LINKED: u8 = 4;

/// One row of a segment's Thomas factors for step ratio r = D·dt/h² and boundary value C_b.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Factor {
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
pub(super) fn fill_table(table: &mut Vec<Factor>, max_len: usize, r: f64, cb: f64) {
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
pub(super) struct Tables {
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
/// The locally-one-dimensional backward-Euler step with each line's Thomas factors taken
/// from a small table instead of being recomputed per cell: the face codes are read once per
/// rebuild (when [`Grid::codes_id`] changes), the inner loops have no divisions, and runs of
/// equal factors use broadcast constants. Gives the same bits as [`implicit_step`], which it
/// replaces in the time loop.
#[derive(Debug, Clone, Default)]
pub struct ImplicitSolver {
    pub(super) plan: Option<LinePlan>,
    /// Set when the grid's segments are too long for the table: the generic sweep is used.
    generic: Option<u64>,
    scratch: Vec<f64>,
    /// Per field of [`Self::steps`] (the first also [`Self::step`]'s): the factor table and the
    /// x-open cells' values after the x sweep (as `grid.open_cells[0]`), for the inflow.
    per_field: Vec<(Tables, Vec<f64>)>,
    /// Plans brought up to date by [`LinePlan::update`] (not built anew).
    #[cfg(test)]
    pub(super) updates: usize,
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

    pub(super) fn step_with(
        &mut self,
        grid: &Grid,
        u: &mut [f64],
        d: f64,
        dt: f64,
        cb: f64,
        isa: Isa,
    ) -> f64 {
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
pub(super) fn planned_step(
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
pub(super) unsafe fn solve_rows(
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
pub(super) unsafe fn mid_fwd(
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
pub(super) unsafe fn mid_back(
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
pub(super) unsafe fn gather8(ix: *const u16, table: *const f64) -> std::arch::x86_64::__m512d {
    use std::arch::x86_64::*;
    let k = _mm512_cvtepu16_epi64(_mm_loadu_si128(ix as *const __m128i));
    _mm512_i64gather_pd::<8>(k, table)
}

/// Four table entries at the u16 indices `ix[0..4]`.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
pub(super) unsafe fn gather4(ix: *const u16, table: *const f64) -> std::arch::x86_64::__m256d {
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
pub(super) unsafe fn fwd<const OM: bool, const OP: bool, const LINK: bool>(
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
pub(super) unsafe fn x_lines(
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
pub(super) unsafe fn x_line_tail(
    row: *mut f64,
    col: *mut f64,
    xs: usize,
    a0: usize,
    a1: usize,
    into_t: bool,
) {
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
pub(super) unsafe fn x_lines_avx(
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
pub(super) unsafe fn xy_plane(
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
pub(super) unsafe fn z_chunk(
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
