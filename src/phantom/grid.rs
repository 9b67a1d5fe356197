//! The 3-D cell-centred grid of the phantom: shape, mask, and the face codes the
//! diffusion solver uses. Cell (i, j, k) has its centre at ((i+½)h, (j+½)h, (k+½)h);
//! the flat index is `i + nx·(j + ny·k)`; z points up (k = 0 is the bottom).

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// A face of the phantom.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum Face {
    /// Box face at x = 0.
    #[serde(rename = "x-")]
    XMinus,
    /// Box face at x = L_x.
    #[serde(rename = "x+")]
    XPlus,
    /// Box face at y = 0.
    #[serde(rename = "y-")]
    YMinus,
    /// Box face at y = L_y.
    #[serde(rename = "y+")]
    YPlus,
    /// z = 0 (box or cylinder).
    Bottom,
    /// z = L_z (box or cylinder).
    Top,
    /// The curved wall of a cylinder.
    Side,
}

impl Face {
    /// The name used in TOML and summaries.
    pub fn name(self) -> &'static str {
        match self {
            Face::XMinus => "x-",
            Face::XPlus => "x+",
            Face::YMinus => "y-",
            Face::YPlus => "y+",
            Face::Bottom => "bottom",
            Face::Top => "top",
            Face::Side => "side",
        }
    }
}

/// The phantom's shape.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Shape {
    /// A box [0, L_x] × [0, L_y] × [0, L_z], m.
    Box {
        /// Edge lengths, m.
        size: [f64; 3],
    },
    /// An upright cylinder (axis along z) of the given diameter and depth, m.
    Cylinder {
        /// Diameter, m.
        diameter: f64,
        /// Depth (height), m.
        depth: f64,
    },
}

impl Shape {
    /// The faces this shape has.
    pub fn faces(&self) -> &'static [Face] {
        match self {
            Shape::Box { .. } => &[
                Face::XMinus,
                Face::XPlus,
                Face::YMinus,
                Face::YPlus,
                Face::Bottom,
                Face::Top,
            ],
            Shape::Cylinder { .. } => &[Face::Side, Face::Bottom, Face::Top],
        }
    }
}

/// Face code of one side of a cell: no flux (sealed face or outside).
pub const SIDE_SEALED: u8 = 0;
/// Face code: the neighbour is an inside cell.
pub const SIDE_INTERIOR: u8 = 1;
/// Face code: an open face held at Henry equilibrium with the chamber gas.
pub const SIDE_OPEN: u8 = 2;
/// Most fields [`Grid::interpolate_many`] interpolates at once (one per simulated gas, and a
/// spare).
pub const MAX_FIELDS: usize = 4;

/// Bit set in a direction code when the cell is inside the phantom.
pub const INSIDE_BIT: u8 = 16;

/// A run of neighbouring inside cells [start, end) of one x-row that share their face codes
/// ([`Grid::edge_runs`]), with those codes (x, y, z; as [`Grid::codes`]). The explicit kernel
/// and the step-limit scans read a run's codes here, not from the per-cell arrays (three cache
/// lines per run; on its own no measurable change, docs/speed-history.md, session 22), and the kernel's
/// row ends are recognised from them (`diffusion::row_ends`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeRun {
    /// First cell, as a position along the row.
    pub start: u32,
    /// One past the last cell.
    pub end: u32,
    /// The run's cells' codes per direction.
    pub codes: [u8; 3],
}

/// Per x-row lists of [`EdgeRun`]s, all in one buffer ([`Grid::edge_runs`]): a row's list is
/// rewritten in place when the new one is no longer, else appended, and the buffer is compacted
/// when more than half of it is stale (a `Vec` per row cost about 110 B per row, 23 MB at the
/// cell cap; this, 8 B per row and 12 B per run).
#[derive(Debug, Clone)]
pub struct RowRuns {
    /// Per row, (first, count) in `runs`.
    slots: Vec<(u32, u32)>,
    runs: Vec<EdgeRun>,
    /// Entries of `runs` that no row refers to.
    stale: usize,
}

impl RowRuns {
    /// `rows` empty lists.
    fn new(rows: usize) -> RowRuns {
        RowRuns {
            slots: vec![(0, 0); rows],
            runs: Vec::new(),
            stale: 0,
        }
    }

    /// Row `row`'s runs.
    #[inline]
    pub fn of(&self, row: usize) -> &[EdgeRun] {
        let (a, n) = self.slots[row];
        &self.runs[a as usize..(a + n) as usize]
    }

    /// Replace row `row`'s runs by `runs`.
    fn set(&mut self, row: usize, runs: &[EdgeRun]) {
        let (a, n) = self.slots[row];
        let len = runs.len() as u32;
        if len <= n {
            self.runs[a as usize..(a + len) as usize].copy_from_slice(runs);
            self.stale += (n - len) as usize;
            self.slots[row] = (a, len);
        } else {
            self.stale += n as usize;
            self.slots[row] = (self.runs.len() as u32, len);
            self.runs.extend_from_slice(runs);
            if 2 * self.stale > self.runs.len() {
                self.compact();
            }
        }
    }

    /// Drop the stale entries.
    fn compact(&mut self) {
        let mut runs = Vec::with_capacity(self.runs.len() - self.stale);
        for slot in &mut self.slots {
            let (a, n) = *slot;
            *slot = (runs.len() as u32, n);
            runs.extend_from_slice(&self.runs[a as usize..(a + n) as usize]);
        }
        self.runs = runs;
        self.stale = 0;
    }
}

/// The discretised phantom.
#[derive(Debug, Clone)]
pub struct Grid {
    /// Cells along x, y, z.
    pub n: [usize; 3],
    /// Grid step h, m.
    pub h: f64,
    /// The shape.
    pub shape: Shape,
    /// Open faces.
    pub open: Vec<Face>,
    /// Per direction (x, y, z), per cell: `minus | plus << 2 | INSIDE_BIT` codes.
    pub codes: [Vec<u8>; 3],
    /// Per direction, the inside cells with open sides in that direction and how many (1 or 2).
    pub open_cells: [Vec<(u32, u8)>; 3],
    /// Number of inside cells.
    pub n_inside: usize,
    /// Per x-row (index j + ny·k): the range [i0, i1) of cells whose six sides are all interior
    /// faces (empty when i0 ≥ i1). The explicit kernel runs a branch-free stencil there.
    pub interior_spans: Vec<(u32, u32)>,
    /// Per x-row (index j + ny·k): the range [i0, i1) from the row's first to its last cell
    /// inside the phantom's shape (empty when none is); cells a bubble takes out of the gel
    /// stay within it. The explicit kernel visits no cell of the row outside it.
    pub inside_extents: Vec<(u32, u32)>,
    /// Per x-row (index j + ny·k): the row's inside cells outside its interior span
    /// ([`Grid::interior_spans`]), those of [e0, i0) then those of [i1, e1) from
    /// [`Grid::inside_extents`], cut into maximal runs [a, b) of cells with the same codes in
    /// all three directions. The explicit kernel's path for cells with a side that is not
    /// interior; kept with the codes (it was found at every step: a third of that path's time).
    pub edge_runs: RowRuns,
    /// Cells taken out of the gel by bubbles ([`Grid::set_excluded`]): while excluded a cell is
    /// outside the phantom for the solvers, and its neighbours' faces toward it are sealed. One
    /// bit per cell (bit `idx % 64` of word `idx / 64`), empty until a cell is first excluded:
    /// the remap and the sink kernels ask about every cell near a bubble, which a hashed set
    /// made a tenth of the Fig. 5 dive's displacement phase.
    excluded: Vec<u64>,
    /// The codes the mask gave each cell that exclusion has changed, to restore them.
    base_codes: std::collections::HashMap<u32, [u8; 3]>,
    /// Identity of the current face codes: a fresh number from a process-wide counter at
    /// construction and at every change ([`Grid::set_excluded`]), so a solver's cached line
    /// plan ([`super::diffusion::ImplicitSolver`]) knows when to update.
    codes_id: u64,
    /// The last [`CHANGE_LOG_LEN`] changes of the codes, oldest first: the `codes_id` each set
    /// and the cells whose codes it rewrote (sorted).
    changes: std::collections::VecDeque<(u64, Vec<u32>)>,
    /// `codes_id` of the state before the oldest entry of `changes`.
    changes_from: u64,
}

/// One z-plane's rows in [`Grid::new`]: per row its interior span and inside extent; the rows'
/// edge runs one after the other in one list; and each row's count of runs.
type PlaneRows = (Vec<((u32, u32), (u32, u32))>, Vec<EdgeRun>, Vec<u32>);

/// Most changes a grid's log keeps ([`Grid::changed_since`]).
const CHANGE_LOG_LEN: usize = 64;

/// A number never handed out before in this process (the grids' `codes_id`).
fn fresh_codes_id() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// Most cells a grid may have (0.8 GB per gas field).
pub const MAX_CELLS: usize = 100_000_000;

impl Grid {
    /// Build the grid: the cell count along each axis is the size over h rounded to the
    /// nearest integer (at least 3), so the modelled size is `n·h`.
    pub fn new(shape: Shape, h: f64, open: &[Face]) -> Result<Grid, String> {
        if !(h > 0.0) {
            return Err(format!("grid step must be positive (got {h} m)"));
        }
        let size = match shape {
            Shape::Box { size } => size,
            Shape::Cylinder { diameter, depth } => [diameter, diameter, depth],
        };
        let mut n = [0usize; 3];
        for a in 0..3 {
            if !(size[a] > 0.0) {
                return Err(format!("phantom size must be positive (got {} m)", size[a]));
            }
            let c = (size[a] / h).round();
            if c < 3.0 {
                return Err(format!(
                    "phantom size {} m is less than 3 grid steps of {h} m; use a smaller grid step",
                    size[a]
                ));
            }
            if !(c <= MAX_CELLS as f64) {
                return Err(format!(
                    "{c:.3e} cells along one axis (size {} m over step {} m) is too many (limit {MAX_CELLS} cells in all); use a larger grid step",
                    crate::error::num(size[a]),
                    crate::error::num(h)
                ));
            }
            n[a] = c as usize;
        }
        // 100 M cells is 0.8 GB per gas field (plus scratch): beyond that a 24 GB machine runs
        // out of memory with three gases, and the run would take hours anyway. Checked
        // arithmetic: the product of three large counts must not wrap around to a small one.
        let total = n[0]
            .checked_mul(n[1])
            .and_then(|t| t.checked_mul(n[2]))
            .filter(|t| *t <= MAX_CELLS)
            .ok_or_else(|| {
                format!(
                    "{:.3e} cells ({} × {} × {}) is too many (limit {MAX_CELLS}); use a larger grid step",
                    n[0] as f64 * n[1] as f64 * n[2] as f64,
                    n[0],
                    n[1],
                    n[2]
                )
            })?;
        for f in open {
            if !shape.faces().contains(f) {
                return Err(format!("face '{}' does not exist on this shape", f.name()));
            }
        }
        // the shape's cross-section (every shape is a prism along z), once per (i, j)
        let section: Vec<bool> = (0..n[0] * n[1])
            .map(|q| match shape {
                Shape::Box { .. } => true,
                Shape::Cylinder { .. } => {
                    let (i, j) = (q % n[0], q / n[0]);
                    let c = n[0] as f64 / 2.0;
                    let x = i as f64 + 0.5 - c;
                    let y = j as f64 + 0.5 - c;
                    x * x + y * y <= c * c
                }
            })
            .collect();
        let side = |inside: bool, face: Face| {
            if inside {
                SIDE_INTERIOR
            } else if open.contains(&face) {
                SIDE_OPEN
            } else {
                SIDE_SEALED
            }
        };
        let code_of = |minus: u8, plus: u8| -> (u8, u8) {
            let opens = u8::from(minus == SIDE_OPEN) + u8::from(plus == SIDE_OPEN);
            (minus | (plus << 2) | INSIDE_BIT, opens)
        };
        // Every shape is a prism along z, so a cell's x and y codes depend only on (i, j), one
        // template for every plane, and its z codes only on whether its plane is the bottom or
        // the top one.
        let plane = n[0] * n[1];
        let in_section = |i: usize, j: usize, di: isize, dj: isize| -> bool {
            let (i, j) = (i as isize + di, j as isize + dj);
            i >= 0
                && j >= 0
                && i < n[0] as isize
                && j < n[1] as isize
                && section[i as usize + n[0] * j as usize]
        };
        let faces = match shape {
            Shape::Box { .. } => [[Face::XMinus, Face::XPlus], [Face::YMinus, Face::YPlus]],
            Shape::Cylinder { .. } => [[Face::Side; 2]; 2],
        };
        // per direction x, y: the plane's codes, and its cells with open sides (cell, how many)
        let mut template = [vec![0u8; plane], vec![0u8; plane]];
        let mut template_open: [Vec<(u32, u8)>; 2] = Default::default();
        for j in 0..n[1] {
            for i in 0..n[0] {
                let q = i + n[0] * j;
                if !section[q] {
                    continue;
                }
                for (d, (di, dj)) in [(1, 0), (0, 1)].into_iter().enumerate() {
                    let minus = side(in_section(i, j, -di, -dj), faces[d][0]);
                    let plus = side(in_section(i, j, di, dj), faces[d][1]);
                    let (code, opens) = code_of(minus, plus);
                    template[d][q] = code;
                    if opens > 0 {
                        // MAX_CELLS < 2³²: every index fits
                        template_open[d].push((q as u32, opens));
                    }
                }
            }
        }
        let z_code = |k: usize| code_of(side(k > 0, Face::Bottom), side(k + 1 < n[2], Face::Top));
        let mut codes = [vec![0u8; total], vec![0u8; total], vec![0u8; total]];
        {
            let [cx, cy, cz] = &mut codes;
            cx.par_chunks_mut(plane)
                .zip(cy.par_chunks_mut(plane))
                .zip(cz.par_chunks_mut(plane))
                .enumerate()
                .for_each(|(k, ((px, py), pz))| {
                    px.copy_from_slice(&template[0]);
                    py.copy_from_slice(&template[1]);
                    let (code, _) = z_code(k);
                    for (z, &x) in pz.iter_mut().zip(&template[0]) {
                        if x != 0 {
                            *z = code;
                        }
                    }
                });
        }
        // per direction, the cells with open sides in index order: plane by plane
        let mut open_cells: [Vec<(u32, u8)>; 3] = Default::default();
        for (cells, template) in open_cells.iter_mut().zip(&template_open) {
            cells.reserve(template.len() * n[2]);
            for k in 0..n[2] {
                let base = (k * plane) as u32;
                cells.extend(template.iter().map(|&(q, o)| (base + q, o)));
            }
        }
        for k in 0..n[2] {
            let (_, opens) = z_code(k);
            if opens > 0 {
                let base = k * plane;
                open_cells[2].extend(
                    (0..plane)
                        .filter(|&q| section[q])
                        .map(|q| ((base + q) as u32, opens)),
                );
            }
        }
        let n_inside = section.iter().filter(|&&s| s).count() * n[2];
        let codes_id = fresh_codes_id();
        let mut grid = Grid {
            codes_id,
            changes: Default::default(),
            changes_from: codes_id,
            excluded: Vec::new(),
            base_codes: Default::default(),
            interior_spans: vec![(0u32, 0u32); n[1] * n[2]],
            inside_extents: vec![(0u32, 0u32); n[1] * n[2]],
            edge_runs: RowRuns::new(n[1] * n[2]),
            n,
            h,
            shape,
            open: open.to_vec(),
            codes,
            open_cells,
            n_inside,
        };
        // the rows' spans, extents and edge runs (positions along the row), found for the
        // bottom plane, one middle plane and the top one: every middle plane has the same
        // codes, hence the same rows (n ≥ 3 along z)
        let ny = n[1];
        let rows_of = |k: usize| -> PlaneRows {
            let (mut spans, mut all, mut counts) =
                (Vec::with_capacity(ny), Vec::new(), Vec::with_capacity(ny));
            let mut runs = Vec::new();
            for row in k * ny..(k + 1) * ny {
                let span = grid.interior_span(row);
                let inside = |i: &usize| grid.codes[0][row * n[0] + i] & INSIDE_BIT != 0;
                let extent = match ((0..n[0]).find(inside), (0..n[0]).rev().find(inside)) {
                    (Some(i0), Some(i1)) => (i0 as u32, i1 as u32 + 1),
                    _ => (0, 0),
                };
                grid.edge_runs_between(row, span, extent, &mut runs);
                spans.push((span, extent));
                all.extend_from_slice(&runs);
                counts.push(runs.len() as u32);
            }
            (spans, all, counts)
        };
        let distinct: Vec<PlaneRows> = [0, 1, n[2] - 1].into_par_iter().map(rows_of).collect();
        for k in 0..n[2] {
            let (spans, all, counts) = &distinct[if k == 0 {
                0
            } else if k + 1 == n[2] {
                2
            } else {
                1
            }];
            let mut at = 0;
            for (q, &count) in counts.iter().enumerate() {
                let row = k * ny + q;
                (grid.interior_spans[row], grid.inside_extents[row]) = spans[q];
                let count = count as usize;
                grid.edge_runs.set(row, &all[at..at + count]);
                at += count;
            }
        }
        Ok(grid)
    }

    /// Take cells out of the gel (`excluded = true`: a bubble occupies them) or give them back
    /// (issue 8, item 5). An excluded cell is outside the phantom for both diffusion schemes,
    /// for [`Grid::kernel`], [`Grid::interpolate`] and [`Grid::integrate`]; the faces of its
    /// neighbours toward it become sealed (no flux into the bubble through the grid: the bubble
    /// exchanges gas only through its own flux law). Cells with an open side are never
    /// excluded (the caller filters them with [`Grid::has_open_side`]; a bubble reaching an
    /// open face ends the run anyway). The explicit kernel's interior spans of the rows touched
    /// are recomputed; the change is logged ([`Grid::changed_since`]).
    pub fn set_excluded(&mut self, cells: &[usize], excluded: bool) {
        if cells.is_empty() {
            return;
        }
        let strides = [1usize, self.n[0], self.n[0] * self.n[1]];
        let mut touched: Vec<usize> = Vec::with_capacity(cells.len() * 7);
        for &idx in cells {
            touched.push(idx);
            let base = self.base_of(idx);
            for d in 0..3 {
                if base[d] & 3 == SIDE_INTERIOR {
                    touched.push(idx - strides[d]);
                }
                if (base[d] >> 2) & 3 == SIDE_INTERIOR {
                    touched.push(idx + strides[d]);
                }
            }
        }
        touched.sort_unstable();
        touched.dedup();
        self.codes_id = fresh_codes_id();
        if self.changes.len() == CHANGE_LOG_LEN {
            if let Some((id, _)) = self.changes.pop_front() {
                self.changes_from = id;
            }
        }
        // MAX_CELLS < 2³²: every index fits
        let logged = touched.iter().map(|&idx| idx as u32).collect();
        self.changes.push_back((self.codes_id, logged));
        for &idx in &touched {
            let base = self.base_of(idx);
            self.base_codes.entry(idx as u32).or_insert(base);
        }
        if self.excluded.is_empty() {
            self.excluded = vec![0; self.len().div_ceil(64)];
        }
        for &idx in cells {
            let bit = 1u64 << (idx % 64);
            if excluded {
                self.excluded[idx / 64] |= bit;
            } else {
                self.excluded[idx / 64] &= !bit;
            }
        }
        for &idx in &touched {
            let base = self.base_codes[&(idx as u32)];
            for d in 0..3 {
                self.codes[d][idx] = if self.is_excluded(idx) {
                    0
                } else {
                    let mut m = base[d] & 3;
                    let mut p = (base[d] >> 2) & 3;
                    if m == SIDE_INTERIOR && self.is_excluded(idx - strides[d]) {
                        m = SIDE_SEALED;
                    }
                    if p == SIDE_INTERIOR && self.is_excluded(idx + strides[d]) {
                        p = SIDE_SEALED;
                    }
                    m | (p << 2) | (base[d] & INSIDE_BIT)
                };
            }
        }
        let mut rows: Vec<usize> = touched.iter().map(|idx| idx / self.n[0]).collect();
        rows.dedup();
        rows.sort_unstable();
        rows.dedup();
        let mut runs = Vec::new();
        for row in rows {
            self.interior_spans[row] = self.interior_span(row);
            self.edge_runs_of(row, &mut runs);
            self.edge_runs.set(row, &runs);
        }
    }

    /// The cells taken out of the gel by bubbles, in index order (the grid's codes and interior
    /// spans are a function of this set and the mask: a checkpoint saves only the set).
    pub fn excluded_cells(&self) -> Vec<usize> {
        let mut cells = Vec::new();
        for (w, &word) in self.excluded.iter().enumerate() {
            let mut bits = word;
            while bits != 0 {
                cells.push(w * 64 + bits.trailing_zeros() as usize);
                bits &= bits - 1;
            }
        }
        cells
    }

    /// Whether any cell of z-plane `k` is taken out of the gel by a bubble (a scan of the
    /// plane's words of the exclusion bits: a few hundred words on the Fig. 5 grid).
    pub fn plane_has_excluded(&self, k: usize) -> bool {
        let plane = self.n[0] * self.n[1];
        let (a, b) = (k * plane, (k + 1) * plane);
        let (wa, wb) = (a / 64, b.div_ceil(64).min(self.excluded.len()));
        (wa..wb).any(|w| {
            let mut word = self.excluded[w];
            // the bits of the word that belong to the plane
            if w == a / 64 {
                word &= u64::MAX << (a % 64);
            }
            if w == b / 64 && b % 64 != 0 {
                word &= u64::MAX >> (64 - b % 64);
            }
            word != 0
        })
    }

    /// Whether cell `idx` is taken out of the gel by a bubble.
    #[inline]
    pub fn is_excluded(&self, idx: usize) -> bool {
        self.excluded
            .get(idx / 64)
            .is_some_and(|w| w & (1u64 << (idx % 64)) != 0)
    }

    /// Whether cell `idx` is inside the phantom as the mask made it (excluded or not). Exclusion
    /// keeps a cell's inside bit except on the excluded cell itself: only that one needs the
    /// mask's codes.
    #[inline]
    pub fn inside_phantom(&self, idx: usize) -> bool {
        if self.is_excluded(idx) {
            self.base_of(idx)[0] & INSIDE_BIT != 0
        } else {
            self.inside(idx)
        }
    }

    /// Whether cell `idx` has a side on an open face. Exclusion only seals interior sides, so
    /// the current codes answer for every cell but an excluded one.
    pub fn has_open_side(&self, idx: usize) -> bool {
        let base = if self.is_excluded(idx) {
            self.base_of(idx)
        } else {
            [self.codes[0][idx], self.codes[1][idx], self.codes[2][idx]]
        };
        (0..3).any(|d| base[d] & 3 == SIDE_OPEN || (base[d] >> 2) & 3 == SIDE_OPEN)
    }

    fn base_of(&self, idx: usize) -> [u8; 3] {
        self.base_codes.get(&(idx as u32)).copied().unwrap_or([
            self.codes[0][idx],
            self.codes[1][idx],
            self.codes[2][idx],
        ])
    }

    /// The first run of cells of x-row `row` whose six sides are all interior faces.
    fn interior_span(&self, row: usize) -> (u32, u32) {
        let full = SIDE_INTERIOR | (SIDE_INTERIOR << 2) | INSIDE_BIT;
        let base = row * self.n[0];
        let is_full = |i: usize| (0..3).all(|d| self.codes[d][base + i] == full);
        match (0..self.n[0]).find(|&i| is_full(i)) {
            Some(i0) => {
                let mut i1 = i0;
                while i1 < self.n[0] && is_full(i1) {
                    i1 += 1;
                }
                (i0 as u32, i1 as u32)
            }
            None => (0, 0),
        }
    }

    /// [`Grid::edge_runs`] of x-row `row` from the current codes and interior span, into `runs`
    /// (cleared first; one buffer for all the rows of a build or an exclusion).
    fn edge_runs_of(&self, row: usize, runs: &mut Vec<EdgeRun>) {
        self.edge_runs_between(
            row,
            self.interior_spans[row],
            self.inside_extents[row],
            runs,
        );
    }

    /// [`Self::edge_runs_of`] with the row's interior span and inside extent given.
    fn edge_runs_between(
        &self,
        row: usize,
        (i0, i1): (u32, u32),
        (e0, e1): (u32, u32),
        runs: &mut Vec<EdgeRun>,
    ) {
        runs.clear();
        let base = row * self.n[0];
        let code = |i: usize| [0, 1, 2].map(|d| self.codes[d][base + i]);
        let (i0, i1) = if i1 > i0 { (i0, i1) } else { (e1, e1) };
        for (lo, hi) in [(e0 as usize, i0 as usize), (i1 as usize, e1 as usize)] {
            let mut i = lo;
            while i < hi {
                let c = code(i);
                let mut j = i + 1;
                while j < hi && code(j) == c {
                    j += 1;
                }
                if c[0] & INSIDE_BIT != 0 {
                    runs.push(EdgeRun {
                        start: i as u32,
                        end: j as u32,
                        codes: c,
                    });
                }
                i = j;
            }
        }
    }

    /// Identity of the current face codes: equal ids mean equal codes (a new id at every
    /// change; a clone keeps its original's id until either changes).
    pub fn codes_id(&self) -> u64 {
        self.codes_id
    }

    /// Every cell whose codes changed since the state with codes_id `id`, sorted, each once
    /// (empty if that is the current state), or `None` if `id` is not a state of this grid the
    /// change log reaches back to.
    pub fn changed_since(&self, id: u64) -> Option<Vec<usize>> {
        let skip = if id == self.changes_from {
            0
        } else {
            self.changes.iter().position(|c| c.0 == id)? + 1
        };
        let mut cells: Vec<usize> = self
            .changes
            .iter()
            .skip(skip)
            .flat_map(|(_, cells)| cells.iter().map(|&idx| idx as usize))
            .collect();
        cells.sort_unstable();
        cells.dedup();
        Some(cells)
    }

    /// Total number of cells (inside and outside).
    pub fn len(&self) -> usize {
        self.n[0] * self.n[1] * self.n[2]
    }

    /// True if the grid has no cells (never, after `new`).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Modelled extent along each axis, m.
    pub fn extent(&self) -> [f64; 3] {
        [
            self.n[0] as f64 * self.h,
            self.n[1] as f64 * self.h,
            self.n[2] as f64 * self.h,
        ]
    }

    /// Cell volume h³, m³.
    pub fn cell_volume(&self) -> f64 {
        self.h.powi(3)
    }

    /// Whether cell `idx` is inside the phantom.
    #[inline]
    pub fn inside(&self, idx: usize) -> bool {
        self.codes[0][idx] & INSIDE_BIT != 0
    }

    /// Flat index of (i, j, k).
    #[inline]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        i + self.n[0] * (j + self.n[1] * k)
    }

    /// Whether a point lies inside the modelled phantom.
    pub fn contains(&self, p: [f64; 3]) -> bool {
        self.distance_to_faces(p).all(|(_, d)| d > 0.0)
    }

    /// Distance from a point to every face of the modelled phantom, m (negative outside).
    pub fn distance_to_faces(&self, p: [f64; 3]) -> impl Iterator<Item = (Face, f64)> {
        let e = self.extent();
        // no allocation: the time loop asks it for every bubble at every step
        let (faces, n) = match self.shape {
            Shape::Box { .. } => (
                [
                    (Face::XMinus, p[0]),
                    (Face::XPlus, e[0] - p[0]),
                    (Face::YMinus, p[1]),
                    (Face::YPlus, e[1] - p[1]),
                    (Face::Bottom, p[2]),
                    (Face::Top, e[2] - p[2]),
                ],
                6,
            ),
            Shape::Cylinder { .. } => {
                let c = e[0] / 2.0;
                let r = ((p[0] - c).powi(2) + (p[1] - c).powi(2)).sqrt();
                let top = (Face::Top, e[2] - p[2]);
                (
                    [
                        (Face::Side, c - r),
                        (Face::Bottom, p[2]),
                        top,
                        top,
                        top,
                        top,
                    ],
                    3,
                )
            }
        };
        faces.into_iter().take(n)
    }

    /// Trilinear interpolation of a cell-centred field at point `p`, using inside cells only
    /// (weights renormalised); points beyond the outermost cell centres take the edge value.
    /// Returns `fallback` if no inside cell is among the eight neighbours.
    pub fn interpolate(&self, field: &[f64], p: [f64; 3], fallback: f64) -> f64 {
        self.interpolate_by(p, fallback, |idx| self.inside(idx).then(|| field[idx]))
    }

    /// Trilinear interpolation at `p` of the values `value` gives the eight surrounding cells;
    /// corners it gives `None` are dropped and the weights renormalised; `fallback` if none is
    /// left. Points beyond the outermost cell centres take the edge value.
    pub fn interpolate_by(
        &self,
        p: [f64; 3],
        fallback: f64,
        value: impl Fn(usize) -> Option<f64>,
    ) -> f64 {
        let mut out = [0.0];
        self.interpolate_many(p, &[fallback], &mut out, |idx, v| match value(idx) {
            Some(x) => {
                v[0] = x;
                true
            }
            None => false,
        });
        out[0]
    }

    /// [`Self::interpolate_by`] of several fields at once (one value per field, `out.len()` of
    /// them, at most [`MAX_FIELDS`]): the corners and weights are found once. `value(idx, v)`
    /// writes the fields' values at cell `idx` into `v` and returns false for a corner to drop.
    /// Each field's result is the same bits as [`Self::interpolate_by`] of that field alone.
    #[inline(always)]
    pub fn interpolate_many(
        &self,
        p: [f64; 3],
        fallback: &[f64],
        out: &mut [f64],
        value: impl FnMut(usize, &mut [f64]) -> bool,
    ) {
        let nf = out.len();
        assert!(nf <= MAX_FIELDS && fallback.len() == nf);
        // the sums in registers for the usual counts of gases (the same operations for any)
        match nf {
            1 => self.interpolate_n::<1>(p, fallback, out, value),
            2 => self.interpolate_n::<2>(p, fallback, out, value),
            3 => self.interpolate_n::<3>(p, fallback, out, value),
            _ => self.interpolate_n::<MAX_FIELDS>(p, fallback, out, value),
        }
    }

    /// [`Self::interpolate_many`] for at most `N` fields (`out.len()` of them).
    #[inline(always)]
    fn interpolate_n<const N: usize>(
        &self,
        p: [f64; 3],
        fallback: &[f64],
        out: &mut [f64],
        mut value: impl FnMut(usize, &mut [f64]) -> bool,
    ) {
        let nf = out.len();
        let mut i0 = [0usize; 3];
        let mut t = [0.0f64; 3];
        for a in 0..3 {
            let f = (p[a] / self.h - 0.5).clamp(0.0, (self.n[a] - 1) as f64);
            // f ≥ 0 (or NaN, which both give 0): truncation is its floor, without a libm call
            let base = (f as usize).min(self.n[a] - 2);
            i0[a] = base;
            t[a] = f - base as f64;
        }
        let mut sum = [0.0; N];
        let mut v = [0.0; N];
        let mut wsum = 0.0;
        for dk in 0..2 {
            let wk = if dk == 0 { 1.0 - t[2] } else { t[2] };
            for dj in 0..2 {
                let wj = if dj == 0 { 1.0 - t[1] } else { t[1] };
                for di in 0..2 {
                    let wi = if di == 0 { 1.0 - t[0] } else { t[0] };
                    let w = wi * wj * wk;
                    if w <= 0.0 {
                        continue;
                    }
                    if value(self.index(i0[0] + di, i0[1] + dj, i0[2] + dk), &mut v[..nf]) {
                        for (s, x) in sum[..nf].iter_mut().zip(&v[..nf]) {
                            *s += w * x;
                        }
                        wsum += w;
                    }
                }
            }
        }
        for (o, (s, fb)) in out.iter_mut().zip(sum[..nf].iter().zip(fallback)) {
            *o = if wsum > 1e-12 { s / wsum } else { *fb };
        }
    }

    /// Sum of a field over inside cells times the cell volume (amount of gas, mol, for a
    /// concentration field in mol/m³).
    pub fn integrate(&self, field: &[f64]) -> f64 {
        let v = self.cell_volume();
        let codes = &self.codes[0];
        field
            .iter()
            .zip(codes)
            .filter(|(_, c)| **c & INSIDE_BIT != 0)
            .map(|(x, _)| *x)
            .sum::<f64>()
            * v
    }

    /// Index bounds (inclusive) of the cells whose centres may lie within distance `a` of `p`
    /// (empty along an axis when lo > hi).
    pub fn cell_range(&self, p: [f64; 3], a: f64) -> ([usize; 3], [usize; 3]) {
        let mut lo = [0usize; 3];
        let mut hi = [0usize; 3];
        for ax in 0..3 {
            lo[ax] = (((p[ax] - a) / self.h - 0.5).floor().max(0.0)) as usize;
            hi[ax] = ((((p[ax] + a) / self.h - 0.5).ceil()) as isize)
                .clamp(0, self.n[ax] as isize - 1) as usize;
        }
        (lo, hi)
    }

    /// The part `lo..=hi` (within `range`, inclusive) of the x-row whose cell centres lie at
    /// offsets `y`, `z` from `p` that may hold centres within distance `a` of `p`: a cell
    /// wider on each side than the disc's chord, so that a caller's exact test still decides
    /// (the same cells in the same order as the whole range). None when no centre can.
    #[inline]
    pub fn row_within(
        &self,
        p: [f64; 3],
        a: f64,
        (y, z): (f64, f64),
        range: (usize, usize),
    ) -> Option<(usize, usize)> {
        let left = a * a * (1.0 + 1e-9) - (y * y + z * z);
        if !(left >= 0.0) {
            return None;
        }
        let half = left.sqrt() + self.h;
        let lo = ((p[0] - half) / self.h - 0.5).floor().max(range.0 as f64) as usize;
        let hi = ((p[0] + half) / self.h - 0.5).ceil().min(range.1 as f64);
        if hi < lo as f64 {
            return None;
        }
        Some((lo, hi as usize))
    }

    /// Weights of a spherically symmetric kernel of radius `a` centred at `p`, over inside
    /// cells, summing to one: w ∝ (1 − (d/a)²)² for cell-centre distance d < a. Falls back to
    /// the nearest inside cell if the kernel catches none. Returns the inclusive box (lo, hi
    /// cell coordinates) of the cells in `out`.
    pub fn kernel(
        &self,
        p: [f64; 3],
        a: f64,
        out: &mut Vec<(usize, f64)>,
    ) -> ([usize; 3], [usize; 3]) {
        let mut cells = Vec::new();
        self.ball_cells(p, a, &mut cells);
        self.kernel_of(a, &cells, out)
            .unwrap_or_else(|| self.nearest_cell(p, out))
    }

    /// The inside cells whose centres lie within `a` of `p` (d²/a² < 1), in index order, with
    /// d² and their coordinates.
    fn ball_cells(&self, p: [f64; 3], a: f64, cells: &mut Vec<(usize, f64, [u32; 3])>) {
        cells.clear();
        let h = self.h;
        let (lo, hi) = self.cell_range(p, a);
        for k in lo[2]..=hi[2] {
            let z = (k as f64 + 0.5) * h - p[2];
            for j in lo[1]..=hi[1] {
                let y = (j as f64 + 0.5) * h - p[1];
                let Some((i0, i1)) = self.row_within(p, a, (y, z), (lo[0], hi[0])) else {
                    continue;
                };
                let row = self.index(0, j, k);
                // the cells outside (those a displacing bubble holds, most of its ball) first
                for i in i0..=i1 {
                    if !self.inside(row + i) {
                        continue;
                    }
                    let x = (i as f64 + 0.5) * h - p[0];
                    let d2 = x * x + y * y + z * z;
                    if d2 / (a * a) < 1.0 {
                        cells.push((row + i, d2, [i as u32, j as u32, k as u32]));
                    }
                }
            }
        }
    }

    /// The kernel of radius `a` over those of `cells` ([`Self::ball_cells`] of a radius ≥ a)
    /// within `a`, into `out`; its box, or `None` if none is.
    fn kernel_of(
        &self,
        a: f64,
        cells: &[(usize, f64, [u32; 3])],
        out: &mut Vec<(usize, f64)>,
    ) -> Option<([usize; 3], [usize; 3])> {
        out.clear();
        let (mut blo, mut bhi) = ([usize::MAX; 3], [0usize; 3]);
        let mut total = 0.0;
        for &(idx, d2, c) in cells {
            let q = d2 / (a * a);
            if q < 1.0 {
                let w = (1.0 - q) * (1.0 - q);
                out.push((idx, w));
                total += w;
                for ax in 0..3 {
                    blo[ax] = blo[ax].min(c[ax] as usize);
                    bhi[ax] = bhi[ax].max(c[ax] as usize);
                }
            }
        }
        if !(total > 0.0) {
            return None;
        }
        for (_, w) in out.iter_mut() {
            *w /= total;
        }
        Some((blo, bhi))
    }

    /// The inside cell nearest to `p`, alone in `out` with weight 1, and its coordinates as a box.
    fn nearest_cell(&self, p: [f64; 3], out: &mut Vec<(usize, f64)>) -> ([usize; 3], [usize; 3]) {
        let h = self.h;
        let mut best = (usize::MAX, f64::INFINITY);
        for idx in 0..self.len() {
            if !self.inside(idx) {
                continue;
            }
            let i = idx % self.n[0];
            let j = (idx / self.n[0]) % self.n[1];
            let k = idx / (self.n[0] * self.n[1]);
            let d = ((i as f64 + 0.5) * h - p[0]).powi(2)
                + ((j as f64 + 0.5) * h - p[1]).powi(2)
                + ((k as f64 + 0.5) * h - p[2]).powi(2);
            if d < best.1 {
                best = (idx, d);
            }
        }
        out.clear();
        out.push((best.0, 1.0));
        let c = [
            best.0 % self.n[0],
            (best.0 / self.n[0]) % self.n[1],
            best.0 / (self.n[0] * self.n[1]),
        ];
        (c, c)
    }
}

/// The cells a kernel about one centre may hold ([`Grid::kernel_cached`]): the inside cells
/// within `a_max` of it, in the kernel's order, with their squared distance and coordinates.
#[derive(Debug, Clone, Default)]
pub struct KernelCache {
    /// Centre (m), [`Grid::codes_id`] and `a_max` (m) of `cells`.
    key: Option<([f64; 3], u64, f64)>,
    /// (cell, squared centre distance as [`Grid::kernel`] computes it, its coordinates).
    cells: Vec<(usize, f64, [u32; 3])>,
}

impl Grid {
    /// [`Self::kernel`] through `cache`: the same cells, weights and box, bit for bit. The
    /// candidates (every inside cell within a radius a little beyond `a`) are found again only
    /// when the centre or the grid's codes change or `a` outgrows them; a kernel of a smaller
    /// radius is a subset of the candidates (q = d²/a² < 1 implies d²/a_max² < 1, in floating
    /// point too: both roundings are monotone).
    pub fn kernel_cached(
        &self,
        p: [f64; 3],
        a: f64,
        cache: &mut KernelCache,
        out: &mut Vec<(usize, f64)>,
    ) -> ([usize; 3], [usize; 3]) {
        let id = self.codes_id();
        let fresh = cache
            .key
            .is_some_and(|(cp, cid, amax)| cp == p && cid == id && a <= amax);
        if !fresh {
            // room for half a cell of growth
            let a_max = a + 0.5 * self.h;
            self.ball_cells(p, a_max, &mut cache.cells);
            cache.key = Some((p, id, a_max));
        }
        self.kernel_of(a, &cache.cells, out)
            .unwrap_or_else(|| self.nearest_cell(p, out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `plane_has_excluded` against a scan of every cell's `is_excluded`, for planes whose
    /// cells start and end inside a word of the bits (7 × 5 = 35 cells a plane) and one cell
    /// taken at a time at each end of a plane and in its middle.
    #[test]
    fn plane_has_excluded_is_a_scan_of_the_planes_cells() {
        let open = [Face::Top];
        let mut g = Grid::new(
            Shape::Box {
                size: [7e-4, 5e-4, 9e-4],
            },
            1e-4,
            &open,
        )
        .unwrap();
        let plane = 35;
        let scan = |g: &Grid, k: usize| (k * plane..(k + 1) * plane).any(|i| g.is_excluded(i));
        assert!((0..9).all(|k| !g.plane_has_excluded(k)));
        for k in 0..9 {
            for q in [0, 17, plane - 1] {
                let idx = k * plane + q;
                if g.has_open_side(idx) {
                    continue;
                }
                g.set_excluded(&[idx], true);
                for kk in 0..9 {
                    assert_eq!(
                        g.plane_has_excluded(kk),
                        scan(&g, kk),
                        "cell {idx}, plane {kk}"
                    );
                }
                assert!(g.plane_has_excluded(k));
                g.set_excluded(&[idx], false);
            }
        }
    }

    proptest::proptest! {
        /// `row_within` keeps every cell of the box whose centre is within `a` of `p` (the
        /// exact test its callers apply, both strict and inclusive), for any centre, radius
        /// and row, including rows that graze the sphere and spheres reaching past the grid.
        #[test]
        fn row_within_keeps_every_cell_of_the_chord(
            px in -1.0f64..25.0, py in -1.0f64..25.0, pz in -1.0f64..13.0,
            a in 0.01f64..9.0,
        ) {
            let h = 1e-4;
            let g = Grid::new(Shape::Box { size: [24.0 * h, 24.0 * h, 12.0 * h] }, h, &[]).unwrap();
            let (p, a) = ([px * h, py * h, pz * h], a * h);
            let (lo, hi) = g.cell_range(p, a);
            for k in lo[2]..=hi[2] {
                let z = (k as f64 + 0.5) * h - p[2];
                for j in lo[1]..=hi[1] {
                    let y = (j as f64 + 0.5) * h - p[1];
                    let kept = g.row_within(p, a, (y, z), (lo[0], hi[0]));
                    for i in lo[0]..=hi[0] {
                        let x = (i as f64 + 0.5) * h - p[0];
                        if x * x + y * y + z * z <= a * a {
                            let (i0, i1) = kept.expect("a row with a cell inside was dropped");
                            proptest::prop_assert!(i0 <= i && i <= i1, "cell {i} outside {i0}..={i1}");
                        }
                    }
                }
            }
        }
    }

    /// Every face of the shape once, at the distance worked out by hand.
    #[test]
    fn distances_to_faces_are_each_face_once() {
        let h = 1e-4;
        let b = Grid::new(
            Shape::Box {
                size: [2e-3, 3e-3, 4e-3],
            },
            h,
            &[],
        )
        .unwrap();
        let d: Vec<_> = b.distance_to_faces([0.5e-3, 1e-3, 3e-3]).collect();
        let want = [
            (Face::XMinus, 0.5e-3),
            (Face::XPlus, 1.5e-3),
            (Face::YMinus, 1e-3),
            (Face::YPlus, 2e-3),
            (Face::Bottom, 3e-3),
            (Face::Top, 1e-3),
        ];
        assert_eq!(d.len(), 6);
        for ((f, x), (g, y)) in d.iter().zip(want) {
            assert_eq!(*f, g);
            assert!((x - y).abs() < 1e-15, "{f:?} {x} {y}");
        }
        let c = Grid::new(
            Shape::Cylinder {
                diameter: 2e-3,
                depth: 1e-3,
            },
            h,
            &[],
        )
        .unwrap();
        // 0.3 mm from the axis (at x = y = 1 mm), 0.2 mm above the bottom
        let d: Vec<_> = c.distance_to_faces([1.3e-3, 1e-3, 0.2e-3]).collect();
        assert_eq!(d.len(), 3);
        assert_eq!(
            (d[0].0, d[1].0, d[2].0),
            (Face::Side, Face::Bottom, Face::Top)
        );
        assert!((d[0].1 - 0.7e-3).abs() < 1e-15);
        assert!((d[1].1 - 0.2e-3).abs() < 1e-15);
        assert!((d[2].1 - 0.8e-3).abs() < 1e-15);
    }

    #[test]
    fn cylinder_mask_volume_approaches_pi_r2_h() {
        let g = Grid::new(
            Shape::Cylinder {
                diameter: 11e-3,
                depth: 5e-3,
            },
            86.5e-6,
            &[Face::Top, Face::Side],
        )
        .unwrap();
        let e = g.extent();
        let exact = std::f64::consts::PI * (e[0] / 2.0).powi(2) * e[2];
        let v = g.n_inside as f64 * g.cell_volume();
        assert!((v / exact - 1.0).abs() < 0.01, "{v} vs {exact}");
    }

    #[test]
    fn kernel_weights_sum_to_one_and_centre_is_symmetric() {
        let g = Grid::new(Shape::Box { size: [1e-3; 3] }, 1e-4, &[]).unwrap();
        let mut k = Vec::new();
        g.kernel([5e-4, 5e-4, 5e-4], 2.5e-4, &mut k);
        let s: f64 = k.iter().map(|x| x.1).sum();
        assert!((s - 1.0).abs() < 1e-12);
        // first moment about the centre vanishes by symmetry
        let mut m = [0.0; 3];
        for (idx, w) in &k {
            let i = idx % 10;
            let j = (idx / 10) % 10;
            let kk = idx / 100;
            m[0] += w * ((i as f64 + 0.5) * 1e-4 - 5e-4);
            m[1] += w * ((j as f64 + 0.5) * 1e-4 - 5e-4);
            m[2] += w * ((kk as f64 + 0.5) * 1e-4 - 5e-4);
        }
        assert!(m.iter().all(|x| x.abs() < 1e-15));
    }

    /// The kernel against its definition cell by cell over the whole grid (every inside cell
    /// with centre distance d < a, weight (1 − d²/a²)² normalised, in index order), with a
    /// displacing bubble's cells excluded from the middle of the ball, and the box it returns
    /// against the box of those cells; a ball with no inside cell takes the nearest one.
    #[test]
    fn kernel_is_its_definition_and_returns_its_cells_box() {
        let h = 1e-4;
        let mut g = Grid::new(Shape::Box { size: [2e-3; 3] }, h, &[Face::Top]).unwrap();
        let [nx, ny, _] = g.n;
        let coords = |idx: usize| [idx % nx, (idx / nx) % ny, idx / (nx * ny)];
        let centre = |c: [usize; 3]| c.map(|a| (a as f64 + 0.5) * h);
        let p = [1.03e-3, 0.96e-3, 1.11e-3];
        let hole: Vec<usize> = (0..g.len())
            .filter(|&idx| {
                let c = centre(coords(idx));
                (0..3).map(|a| (c[a] - p[a]).powi(2)).sum::<f64>() < (3.1 * h).powi(2)
            })
            .collect();
        g.set_excluded(&hole, true);
        let mut k = Vec::new();
        for a in [4.2 * h, 6.0 * h, 0.3 * h] {
            let bounds = g.kernel(p, a, &mut k);
            let mut want = Vec::new();
            let mut total = 0.0;
            for idx in 0..g.len() {
                let c = centre(coords(idx));
                let q = (0..3).map(|x| (c[x] - p[x]).powi(2)).sum::<f64>() / (a * a);
                if g.inside(idx) && q < 1.0 {
                    want.push((idx, (1.0 - q) * (1.0 - q)));
                    total += (1.0 - q) * (1.0 - q);
                }
            }
            if want.is_empty() {
                // a = 0.3h inside the hole: the nearest inside cell
                assert_eq!(k.len(), 1);
                assert!(g.inside(k[0].0) && k[0].1 == 1.0);
                let d = |idx: usize| {
                    let c = centre(coords(idx));
                    (0..3).map(|x| (c[x] - p[x]).powi(2)).sum::<f64>()
                };
                let nearest = (0..g.len())
                    .filter(|&i| g.inside(i))
                    .map(d)
                    .fold(f64::INFINITY, f64::min);
                assert!((d(k[0].0) - nearest).abs() < 1e-18);
            } else {
                assert_eq!(k.len(), want.len(), "a = {a}");
                for ((idx, w), (widx, ww)) in k.iter().zip(&want) {
                    assert_eq!(idx, widx);
                    assert!((w - ww / total).abs() < 1e-14, "{w} vs {}", ww / total);
                }
            }
            let (mut lo, mut hi) = ([usize::MAX; 3], [0; 3]);
            for (idx, _) in &k {
                let c = coords(*idx);
                for x in 0..3 {
                    lo[x] = lo[x].min(c[x]);
                    hi[x] = hi[x].max(c[x]);
                }
            }
            assert_eq!(bounds, (lo, hi), "a = {a}");
        }
    }

    /// The cached kernel is the kernel, bit for bit, with its box: a bubble's kernel growing
    /// and shrinking about a centre while cells are excluded and given back (each change of
    /// the codes and every outgrowth of the candidates taking fresh ones), a moved centre, and
    /// radii with no inside cell (the nearest-cell fallback).
    #[test]
    fn cached_kernels_are_the_kernels_bits() {
        let h = 1e-4;
        let mut g = Grid::new(Shape::Box { size: [2.4e-3; 3] }, h, &[Face::Top]).unwrap();
        let mut cache = KernelCache::default();
        let (mut a_out, mut b_out) = (Vec::new(), Vec::new());
        let mut p = [1.21e-3, 1.17e-3, 1.33e-3];
        let mut held: Vec<usize> = Vec::new();
        let mut rebuilt = 0;
        for step in 0..60 {
            let r = 2.5 * h + 0.05 * h * (step as f64)
                - if step > 40 {
                    0.2 * h * (step - 40) as f64
                } else {
                    0.0
                };
            if step % 7 == 3 {
                // the bubble holds the cells within r: exclusion changes the codes
                g.set_excluded(&held, false);
                held = crate::phantom::displacement::covered_cells(&g, p, r - 0.5 * h);
                g.set_excluded(&held, true);
            }
            if step == 50 {
                g.set_excluded(&held, false);
                held.clear();
                p[0] += 0.37 * h;
            }
            for a in [r + h, r + 2.0 * h, 0.2 * h] {
                let before = cache.key;
                let bb = g.kernel_cached(p, a, &mut cache, &mut b_out);
                rebuilt += usize::from(cache.key != before);
                let ba = g.kernel(p, a, &mut a_out);
                assert_eq!(ba, bb, "box, step {step}, a = {a}");
                assert_eq!(a_out.len(), b_out.len(), "step {step}, a = {a}");
                for (x, y) in a_out.iter().zip(&b_out) {
                    assert_eq!(x.0, y.0);
                    assert_eq!(x.1.to_bits(), y.1.to_bits());
                }
            }
        }
        // the three radii alternate, so the candidates were found again often, but not always
        assert!(rebuilt > 10 && rebuilt < 180, "{rebuilt}");
    }

    /// Every row's edge runs, checked cell by cell from the codes: with the interior span they
    /// cover the row's inside cells once each, in order; a run's cells share their codes, and
    /// two runs that touch differ (maximal runs: the explicit kernel's uniform path sees each
    /// run whole).
    fn assert_edge_runs_fit_the_codes(g: &Grid) {
        let nx = g.n[0];
        for row in 0..g.n[1] * g.n[2] {
            let code = |i: usize| [0, 1, 2].map(|d| g.codes[d][row * nx + i]);
            let mut covered = vec![0u8; nx];
            let (i0, i1) = g.interior_spans[row];
            for i in i0..i1 {
                covered[i as usize] += 1;
            }
            let mut last: Option<(usize, [u8; 3])> = None;
            for run in g.edge_runs.of(row) {
                let (a, b) = (run.start as usize, run.end as usize);
                assert!(a < b && b <= nx, "row {row}: run {a}..{b}");
                assert_eq!(run.codes, code(a), "row {row}: the codes of run {a}..{b}");
                if let Some((end, c)) = last {
                    assert!(end <= a, "row {row}: runs out of order");
                    assert!(end < a || c != code(a), "row {row}: run at {a} not maximal");
                }
                for i in a..b {
                    assert_eq!(code(i), code(a), "row {row}: cell {i} of run {a}..{b}");
                    covered[i] += 1;
                }
                last = Some((b, code(a)));
            }
            for (i, &n) in covered.iter().enumerate() {
                let inside = code(i)[0] & INSIDE_BIT != 0;
                assert_eq!(
                    n,
                    u8::from(inside),
                    "row {row}, cell {i}: covered {n} times"
                );
            }
        }
    }

    /// Row lists rewritten shorter, longer and again: each row reads back what was set last
    /// (checked against a `Vec` per row), through the buffer's compactions.
    #[test]
    fn row_runs_read_back_what_was_set_through_compactions() {
        let rows = 7;
        let mut runs = RowRuns::new(rows);
        let mut want: Vec<Vec<EdgeRun>> = vec![Vec::new(); rows];
        let mut compacted = 0;
        for round in 0..40u32 {
            let row = (round as usize * 3) % rows;
            let len = ((round * 5) % 4) as usize;
            let list: Vec<EdgeRun> = (0..len as u32)
                .map(|i| EdgeRun {
                    start: round + i,
                    end: round + i + 1,
                    codes: [round as u8, i as u8, 7],
                })
                .collect();
            let before = runs.runs.len();
            runs.set(row, &list);
            if runs.runs.len() < before {
                compacted += 1;
            }
            want[row] = list;
            for (r, w) in want.iter().enumerate() {
                assert_eq!(runs.of(r), &w[..], "round {round}, row {r}");
            }
        }
        assert!(compacted > 0, "no compaction happened");
    }

    /// A grid's codes, open cells, inside count, inside extents and interior spans are what
    /// each cell's own neighbours and the open faces make them (written out here cell by cell
    /// from the shape's definition: a box is every cell, a cylinder's cross-section the cells
    /// whose centres lie within nx/2 of the axis), and its edge runs fit the codes: boxes with
    /// every combination of open faces and cylinders with each combination of theirs.
    #[test]
    fn grids_are_each_cells_neighbours_and_open_faces() {
        let mut grids = Vec::new();
        let box_faces = Shape::Box { size: [1.0; 3] }.faces();
        for m in 0..1u32 << box_faces.len() {
            let open: Vec<Face> = (0..box_faces.len())
                .filter(|b| m & (1 << b) != 0)
                .map(|b| box_faces[b])
                .collect();
            grids.push(
                Grid::new(
                    Shape::Box {
                        size: [5e-4, 4e-4, 3e-4],
                    },
                    1e-4,
                    &open,
                )
                .unwrap(),
            );
        }
        let cylinder = Shape::Cylinder {
            diameter: 1.1e-3,
            depth: 4e-4,
        };
        let cyl_faces = cylinder.faces();
        for m in 0..1u32 << cyl_faces.len() {
            let open: Vec<Face> = (0..cyl_faces.len())
                .filter(|b| m & (1 << b) != 0)
                .map(|b| cyl_faces[b])
                .collect();
            grids.push(Grid::new(cylinder, 1e-4, &open).unwrap());
        }
        for g in &grids {
            let [nx, ny, nz] = g.n;
            let inside = |i: isize, j: isize, k: isize| -> bool {
                let within = (0..nx as isize).contains(&i)
                    && (0..ny as isize).contains(&j)
                    && (0..nz as isize).contains(&k);
                within
                    && match g.shape {
                        Shape::Box { .. } => true,
                        Shape::Cylinder { .. } => {
                            let c = nx as f64 / 2.0;
                            let (x, y) = (i as f64 + 0.5 - c, j as f64 + 0.5 - c);
                            x * x + y * y <= c * c
                        }
                    }
            };
            let mut open_cells: [Vec<(u32, u8)>; 3] = Default::default();
            let mut n_inside = 0;
            for idx in 0..g.len() {
                let (i, j, k) = (idx % nx, (idx / nx) % ny, idx / (nx * ny));
                let (i, j, k) = (i as isize, j as isize, k as isize);
                if !inside(i, j, k) {
                    for d in 0..3 {
                        assert_eq!(g.codes[d][idx], 0, "cell {idx} outside");
                    }
                    continue;
                }
                n_inside += 1;
                for d in 0..3 {
                    let mut sides = [0u8; 2];
                    let mut opens = 0;
                    for (s, sign) in [-1isize, 1].into_iter().enumerate() {
                        let nb = match d {
                            0 => (i + sign, j, k),
                            1 => (i, j + sign, k),
                            _ => (i, j, k + sign),
                        };
                        let face = match (d, sign, g.shape) {
                            (2, -1, _) => Face::Bottom,
                            (2, _, _) => Face::Top,
                            (_, _, Shape::Cylinder { .. }) => Face::Side,
                            (0, -1, _) => Face::XMinus,
                            (0, _, _) => Face::XPlus,
                            (_, -1, _) => Face::YMinus,
                            _ => Face::YPlus,
                        };
                        sides[s] = if inside(nb.0, nb.1, nb.2) {
                            SIDE_INTERIOR
                        } else if g.open.contains(&face) {
                            opens += 1;
                            SIDE_OPEN
                        } else {
                            SIDE_SEALED
                        };
                    }
                    let code = sides[0] | (sides[1] << 2) | INSIDE_BIT;
                    assert_eq!(
                        g.codes[d][idx], code,
                        "cell {idx}, direction {d}, open {:?}",
                        g.open
                    );
                    if opens > 0 {
                        open_cells[d].push((idx as u32, opens));
                    }
                }
            }
            assert_eq!(g.n_inside, n_inside);
            assert_eq!(g.open_cells, open_cells, "open {:?}", g.open);
            let full = SIDE_INTERIOR | (SIDE_INTERIOR << 2) | INSIDE_BIT;
            for row in 0..ny * nz {
                let cell = |i: usize| row * nx + i;
                let ins: Vec<usize> = (0..nx).filter(|&i| g.codes[0][cell(i)] != 0).collect();
                let extent = match (ins.first(), ins.last()) {
                    (Some(&a), Some(&b)) => (a as u32, b as u32 + 1),
                    _ => (0, 0),
                };
                assert_eq!(g.inside_extents[row], extent, "row {row}");
                let is_full = |i: usize| (0..3).all(|d| g.codes[d][cell(i)] == full);
                let span = match (0..nx).find(|&i| is_full(i)) {
                    Some(a) => {
                        let b = (a..nx).find(|&i| !is_full(i)).unwrap_or(nx);
                        (a as u32, b as u32)
                    }
                    None => (0, 0),
                };
                assert_eq!(g.interior_spans[row], span, "row {row}");
            }
            assert_edge_runs_fit_the_codes(g);
        }
    }

    /// The edge runs of a cylinder with open faces, through cells taken out of the gel at
    /// random and given back: as the codes say at every state, and after the cells are given
    /// back those of a grid that never lost them.
    #[test]
    fn edge_runs_follow_the_codes_through_exclusions() {
        use rand::{Rng, SeedableRng};
        let fresh = Grid::new(
            Shape::Cylinder {
                diameter: 1.5e-3,
                depth: 1e-3,
            },
            1e-4,
            &[Face::Top, Face::Side],
        )
        .unwrap();
        assert_edge_runs_fit_the_codes(&fresh);
        let mut g = fresh.clone();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut taken = Vec::new();
        for _ in 0..20 {
            let cells: Vec<usize> = (0..15)
                .map(|_| rng.gen_range(0..g.len()))
                .filter(|&idx| g.inside(idx) && !taken.contains(&idx))
                .collect::<std::collections::BTreeSet<_>>()
                .into_iter()
                .collect();
            g.set_excluded(&cells, true);
            taken.extend(cells);
            assert_edge_runs_fit_the_codes(&g);
        }
        g.set_excluded(&taken, false);
        assert_edge_runs_fit_the_codes(&g);
        for row in 0..g.n[1] * g.n[2] {
            assert_eq!(g.edge_runs.of(row), fresh.edge_runs.of(row), "row {row}");
        }
    }

    #[test]
    fn changed_since_lists_the_cells_of_the_later_changes() {
        let mut g = Grid::new(Shape::Box { size: [1e-3; 3] }, 1e-4, &[]).unwrap();
        let id0 = g.codes_id();
        assert_eq!(g.changed_since(id0), Some(vec![]));
        // each cell and its six neighbours, by hand
        let star = |g: &Grid, [i, j, k]: [usize; 3]| {
            let mut v = vec![
                g.index(i, j, k),
                g.index(i - 1, j, k),
                g.index(i + 1, j, k),
                g.index(i, j - 1, k),
                g.index(i, j + 1, k),
                g.index(i, j, k - 1),
                g.index(i, j, k + 1),
            ];
            v.sort_unstable();
            v
        };
        g.set_excluded(&[g.index(2, 3, 4)], true);
        let id1 = g.codes_id();
        g.set_excluded(&[g.index(7, 5, 6)], true);
        assert_eq!(g.changed_since(id1), Some(star(&g, [7, 5, 6])));
        let mut both = star(&g, [2, 3, 4]);
        both.extend(star(&g, [7, 5, 6]));
        both.sort_unstable();
        assert_eq!(g.changed_since(id0), Some(both));
        // a cell next to an excluded one: its star less the sealed face's neighbour (whose
        // codes do not change), counted once with the earlier change's cells
        g.set_excluded(&[g.index(3, 3, 4)], true);
        let got = g.changed_since(id0).unwrap();
        assert!(got.windows(2).all(|w| w[0] < w[1]));
        assert!(got.contains(&g.index(4, 3, 4)) && got.contains(&g.index(3, 2, 4)));
        // 0 is never handed out
        assert_eq!(g.changed_since(0), None);
    }
}
