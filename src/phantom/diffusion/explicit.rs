//! The explicit step: forward Euler with the open sides' term taken implicitly in the cell,
//! up to the positivity limit h²/(6D) (the module doc of [`super`]).

use super::*;

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
pub(super) fn stencil_span(
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
pub(super) fn stencil_plane(
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
pub(super) fn plain_span(
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
pub(super) fn whole_row(grid: &Grid, k: usize, j: usize, saving: bool) -> Option<[EdgeRun; 2]> {
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
pub(super) fn put_row_ends(
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
pub(super) fn generic_cell(
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
pub(super) const BOTH_INTERIOR: u8 = SIDE_INTERIOR | (SIDE_INTERIOR << 2) | INSIDE_BIT;

/// Whether a row's cells outside its interior span `i0..i1` ([`Grid::edge_runs`] `runs`) are one
/// cell at each end of it, i0 − 1 and i1, each with every side interior but its outer x one:
/// then those two runs (the outer x side open or sealed). Such a row has a row of the
/// plane on both sides and planes above and below (those sides are interior), so the span's
/// stencil can be taken over its ends ([`stencil_plane`]). Every row of a box but those along
/// its y and z faces is one, and most of a cylinder's.
#[inline(always)]
pub(super) fn row_ends(runs: &[EdgeRun], i0: usize, i1: usize) -> Option<[EdgeRun; 2]> {
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
pub(super) fn row_end_pair(
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
pub(super) const UNIFORM_RUN: usize = 4;

/// [`stencil_plane`]'s cell-by-cell path for a run of cells `a..a + o.len()` of one plane
/// that share their codes `code` (inside, the same kind of side in each of the six
/// directions), side by side: the same terms added in the same order (x−, x+, y−, y+, z−,
/// z+; an interior side C_n − C, a sealed one nothing; the open ones implicit,
/// [`open_sides_implicit`]), so the same bits, with `o` as the accumulator. Returns what
/// entered the run through open faces, s·Σ(C_b − C') (0 without open sides).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn uniform_span(
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
pub(super) struct OpenSides {
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
pub(super) fn open_sides_implicit(ui: f64, r_acc: f64, sides: OpenSides) -> f64 {
    if sides.s == 0.0 {
        ui + r_acc
    } else {
        (ui + r_acc + sides.s_cb) / (1.0 + sides.s)
    }
}

/// [`explicit_step`] with the interior stencil compiled for `isa`.
pub(super) fn explicit_step_with(
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
pub(super) fn step_plane_from(
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
pub(super) const BLOCKS_PER_THREAD: usize = 2;

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
pub(super) fn take_plane_flows(len: usize) -> Vec<f64> {
    let mut v = PLANE_FLOWS.take();
    v.clear();
    v.resize(len, 0.0);
    v
}

/// [`explicit_step_in_place`] with the interior stencil compiled for `isa`.
pub(super) fn explicit_step_in_place_with(
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
/// ([`crate::phantom::fields`]). Returns where the fields now start (2 − `from`).
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
pub(super) fn step_shifting(
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
pub(super) fn zero_excluded(grid: &Grid, k: usize, out: &mut [f64]) {
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
/// the plane is in cache: `gel.1[k]` gets [`crate::phantom::gel_pass::plane_gel`] of the new values of
/// z-plane `k` (every field; `gel.0[g]` = R_u·T/L_g), the same bits as a pass over the fields
/// after the step.
pub(in crate::phantom) fn explicit_steps_into_passing_gel(
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
pub(super) fn explicit_steps_into_with(
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
pub(super) fn sum_planes(per_plane: &[f64], inflow: &mut [f64]) {
    inflow.fill(0.0);
    for flows in per_plane.chunks(inflow.len()) {
        for (i, x) in inflow.iter_mut().zip(flows) {
            *i += x;
        }
    }
}

/// [`explicit_steps_in_place`] with the interior stencil compiled for `isa`.
pub(super) fn explicit_steps_in_place_with(
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
pub(super) fn explicit_steps_in_blocks(
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
pub(super) fn step_block(
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

isa_variants!(stencil_span, stencil_span_avx2, stencil_span_avx512,
    (zm: &[f64], c: &[f64], zp: &[f64], o: &mut [f64], a: usize, nx: usize, centre: f64, r: f64));

isa_variants!(uniform_span, uniform_span_avx2, uniform_span_avx512,
    (zm: &[f64], c: &[f64], zp: &[f64], o: &mut [f64], a: usize, nx: usize, code: [u8; 3], r: f64, cb: f64) -> f64);
