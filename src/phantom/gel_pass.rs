//! The gel's pass of a recorded frame, one z-plane at a time ([`plane_gel`]): the largest gas
//! tension Σ_g C_g·R_u·T/L_g, each gas's total and the lowest concentration over the plane's
//! inside cells. With a frame every half second (the oscillation experiment) it runs at almost
//! every step, so it is vectorised: eight consecutive cells side by side, each lane with its own
//! sums and extremes, combined in lane order (eight, not four, so that two vectors' chains run
//! at once: a pass was bound by the latency of each lane's running sum). The AVX2 build and the portable one do the same
//! operations in the same order (no fused multiply–add, the same select for cells outside), so
//! they give the same bits; the extremes are exact whatever the order, and the sums differ from
//! a cell-by-cell sum only in their last bits (they feed the gas-balance check and the frames'
//! grid totals, nothing the model steps on).

use super::grid::{Grid, INSIDE_BIT};
use crate::gas::Gas;

/// Cells side by side (two AVX2 vectors of four).
const LANES: usize = 8;

/// One plane's part of the gel's pass.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct PlaneGel {
    /// Largest Σ_g C_g·R_u·T/L_g over the plane's inside cells, Pa (−∞ with none).
    pub(super) max_tension: f64,
    /// Σ C_g over the plane's inside cells, per gas, mol/m³.
    pub(super) sums: [f64; Gas::ALL.len()],
    /// Lowest concentration of any gas, mol/m³ (+∞ with no inside cell).
    pub(super) min_c: f64,
}

impl Default for PlaneGel {
    /// A plane with no inside cell.
    fn default() -> PlaneGel {
        PlaneGel {
            max_tension: f64::NEG_INFINITY,
            sums: [0.0; Gas::ALL.len()],
            min_c: f64::INFINITY,
        }
    }
}

/// Whether two passes of a plane are the same bits (the first `ng` sums).
pub(super) fn same_plane_gel(a: &PlaneGel, b: &PlaneGel, ng: usize) -> bool {
    a.max_tension.to_bits() == b.max_tension.to_bits()
        && a.min_c.to_bits() == b.min_c.to_bits()
        && (0..ng).all(|g| a.sums[g].to_bits() == b.sums[g].to_bits())
}

/// [`PlaneGel`] of z-plane `kz` of the first `ng` fields, with `k[g]` = R_u·T/L_g.
pub(super) fn plane_gel<F: AsRef<[f64]>>(
    grid: &Grid,
    fields: &[F],
    k: &[f64; Gas::ALL.len()],
    kz: usize,
) -> PlaneGel {
    let (codes, f) = plane_slices(grid, fields, kz);
    plane_gel_of(codes, &f, k)
}

/// [`PlaneGel`] of one plane given as its x-codes (`codes`) and each field's values there
/// (`f[g]`, as long as `codes`): what [`plane_gel`] computes, for a plane the caller holds
/// (the explicit step's fresh output, [`super::diffusion::explicit_steps_into`]).
pub(super) fn plane_gel_of(codes: &[u8], f: &[&[f64]], k: &[f64; Gas::ALL.len()]) -> PlaneGel {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f") {
        // SAFETY: the CPU has AVX-512F (checked above)
        return unsafe { plane_gel_avx512(codes, f, k) };
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU has AVX2 (checked above)
        return unsafe { plane_gel_avx2(codes, f, k) };
    }
    plane_gel_portable(codes, f, k)
}

/// Running per-lane state of a plane.
struct Lanes {
    sums: [[f64; LANES]; Gas::ALL.len()],
    max_t: [f64; LANES],
    min_c: [f64; LANES],
}

impl Lanes {
    fn new() -> Lanes {
        Lanes {
            sums: [[0.0; LANES]; Gas::ALL.len()],
            max_t: [f64::NEG_INFINITY; LANES],
            min_c: [f64::INFINITY; LANES],
        }
    }

    /// Cell `q` of the plane into lane `l`, as one vector lane does it: an outside cell adds
    /// +0 and offers −∞ / +∞ to the extremes; a NaN never replaces an extreme.
    #[inline(always)]
    fn cell(&mut self, l: usize, inside: bool, c: &[f64], k: &[f64]) {
        let mut t = 0.0;
        for (g, (&c, &k)) in c.iter().zip(k).enumerate() {
            self.sums[g][l] += if inside { c } else { 0.0 };
            t += c * k;
            let m = if inside { c } else { f64::INFINITY };
            if m < self.min_c[l] {
                self.min_c[l] = m;
            }
        }
        let t = if inside { t } else { f64::NEG_INFINITY };
        if t > self.max_t[l] {
            self.max_t[l] = t;
        }
    }

    /// The cells after the last whole group of lanes (cell `full + l` into lane `l`), then the
    /// lanes combined in order.
    fn finish(mut self, codes: &[u8], f: &[&[f64]], k: &[f64], full: usize) -> PlaneGel {
        let mut c = [0.0; Gas::ALL.len()];
        for q in full..codes.len() {
            for (cg, fg) in c.iter_mut().zip(f) {
                *cg = fg[q];
            }
            self.cell(q - full, codes[q] & INSIDE_BIT != 0, &c[..f.len()], k);
        }
        let mut out = PlaneGel {
            max_tension: f64::NEG_INFINITY,
            sums: [0.0; Gas::ALL.len()],
            min_c: f64::INFINITY,
        };
        for l in 0..LANES {
            if self.max_t[l] > out.max_tension {
                out.max_tension = self.max_t[l];
            }
            if self.min_c[l] < out.min_c {
                out.min_c = self.min_c[l];
            }
            for g in 0..f.len() {
                out.sums[g] += self.sums[g][l];
            }
        }
        out
    }
}

/// Plane `kz`'s codes and fields.
fn plane_slices<'a, F: AsRef<[f64]>>(
    grid: &'a Grid,
    fields: &'a [F],
    kz: usize,
) -> (&'a [u8], Vec<&'a [f64]>) {
    let plane = grid.n[0] * grid.n[1];
    let z = kz * plane;
    let codes = &grid.codes[0][z..z + plane];
    let f = fields.iter().map(|f| &f.as_ref()[z..z + plane]).collect();
    (codes, f)
}

/// [`plane_gel_of`] without vector instructions (the reference of the vector build's bits).
fn plane_gel_portable(codes: &[u8], f: &[&[f64]], k: &[f64; Gas::ALL.len()]) -> PlaneGel {
    let full = codes.len() - codes.len() % LANES;
    let ng = f.len();
    let mut lanes = Lanes::new();
    let mut c = [0.0; Gas::ALL.len()];
    for q0 in (0..full).step_by(LANES) {
        for l in 0..LANES {
            for (cg, fg) in c.iter_mut().zip(f) {
                *cg = fg[q0 + l];
            }
            lanes.cell(l, codes[q0 + l] & INSIDE_BIT != 0, &c[..ng], &k[..ng]);
        }
    }
    lanes.finish(codes, f, &k[..ng], full)
}

/// `$kernel::<N>(codes, f, k)` for N = the number of fields `f` holds (4 for more than three).
#[cfg(target_arch = "x86_64")]
macro_rules! by_gas_count {
    ($kernel:ident, $codes:expr, $f:expr, $k:expr) => {
        // SAFETY: the caller's instruction set is the kernel's
        match $f.len() {
            1 => unsafe { $kernel::<1>($codes, $f, $k) },
            2 => unsafe { $kernel::<2>($codes, $f, $k) },
            3 => unsafe { $kernel::<3>($codes, $f, $k) },
            _ => unsafe { $kernel::<4>($codes, $f, $k) },
        }
    };
}

/// The cells a vector kernel takes in whole groups of [`LANES`] (the rest go through
/// [`Lanes::finish`]) and its `N` fields' pointers, each checked to hold them.
#[cfg(target_arch = "x86_64")]
fn vector_planes<const N: usize>(codes: &[u8], f: &[&[f64]]) -> (usize, [*const f64; N]) {
    let full = codes.len() - codes.len() % LANES;
    assert_eq!(f.len(), N);
    let fp = std::array::from_fn(|g| {
        assert!(f[g].len() >= full);
        f[g].as_ptr()
    });
    (full, fp)
}

/// [`plane_gel`] with AVX2: lane `l` of each vector is cell `q0 + l`.
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn plane_gel_avx2(codes: &[u8], f: &[&[f64]], k: &[f64; Gas::ALL.len()]) -> PlaneGel {
    // SAFETY: the CPU has AVX2 (this function's own requirement)
    by_gas_count!(plane_gel_avx2_n, codes, f, k)
}

/// [`plane_gel`] with AVX-512F: the eight lanes in one vector (lane `l` is cell `q0 + l`),
/// outside cells masked off instead of blended. The same bits as the AVX2 and portable builds:
/// a masked lane keeps its sum, where they add +0 (the same unless the sum is −0, which a sum
/// started at +0 never is), and keeps its extremes, where they offer ±∞ (which never replace
/// one). About a third of the AVX2 build's instructions per cell.
///
/// # Safety
/// The CPU must have AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn plane_gel_avx512(codes: &[u8], f: &[&[f64]], k: &[f64; Gas::ALL.len()]) -> PlaneGel {
    // SAFETY: the CPU has AVX-512F (this function's own requirement)
    by_gas_count!(plane_gel_avx512_n, codes, f, k)
}

/// [`plane_gel_avx512`] for `N` gases (`f.len() == N`; the gases' loop unrolled).
///
/// # Safety
/// The CPU must have AVX-512F.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
unsafe fn plane_gel_avx512_n<const N: usize>(
    codes: &[u8],
    f: &[&[f64]],
    k: &[f64; Gas::ALL.len()],
) -> PlaneGel {
    use std::arch::x86_64::*;
    let (full, fp) = vector_planes::<N>(codes, f);
    let ng = N;
    let zero = _mm512_setzero_pd();
    let bit = _mm512_set1_epi64(i64::from(INSIDE_BIT));
    let kv: [__m512d; N] = std::array::from_fn(|g| _mm512_set1_pd(k[g]));
    let mut sums = [zero; N];
    let mut max_t = _mm512_set1_pd(f64::NEG_INFINITY);
    // per gas, as the AVX2 build (combined below; a zero among them: the portable build)
    let mut min_g = [_mm512_set1_pd(f64::INFINITY); N];
    for q0 in (0..full).step_by(LANES) {
        // SAFETY: q0 + 7 < full ≤ codes.len(); the eight codes read as one little-endian word
        let c8 = u64::from_le(unsafe { codes.as_ptr().add(q0).cast::<u64>().read_unaligned() });
        let bytes = _mm512_cvtepu8_epi64(_mm_cvtsi64_si128(c8 as i64));
        let inside = _mm512_test_epi64_mask(bytes, bit);
        let mut t = zero;
        for g in 0..N {
            // SAFETY: q0 + 7 < full ≤ every field's plane length (checked above)
            let c = unsafe { _mm512_loadu_pd(fp[g].add(q0)) };
            sums[g] = _mm512_mask_add_pd(sums[g], inside, sums[g], c);
            t = _mm512_add_pd(t, _mm512_mul_pd(c, kv[g]));
            // min(x, acc) gives acc when x is NaN or equal: the scalar `if x < acc`
            min_g[g] = _mm512_mask_min_pd(min_g[g], inside, c, min_g[g]);
        }
        max_t = _mm512_mask_max_pd(max_t, inside, t, max_t);
    }
    let mut min_c = _mm512_set1_pd(f64::INFINITY);
    for m in &min_g[..ng] {
        min_c = _mm512_min_pd(*m, min_c);
    }
    let mut lanes = Lanes::new();
    // SAFETY: eight f64 into eight-element arrays (each store below)
    unsafe {
        _mm512_storeu_pd(lanes.min_c.as_mut_ptr(), min_c);
        _mm512_storeu_pd(lanes.max_t.as_mut_ptr(), max_t);
    }
    for g in 0..ng {
        // SAFETY: as above
        unsafe { _mm512_storeu_pd(lanes.sums[g].as_mut_ptr(), sums[g]) };
    }
    if lanes.min_c.contains(&0.0) {
        // the portable build keeps the one chain: its bits are this kernel's otherwise
        return plane_gel_portable(codes, f, k);
    }
    lanes.finish(codes, f, &k[..ng], full)
}

/// [`plane_gel_avx2`] for `N` gases (`f.len() == N`; the gases' loop unrolled).
///
/// # Safety
/// The CPU must have AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn plane_gel_avx2_n<const N: usize>(
    codes: &[u8],
    f: &[&[f64]],
    k: &[f64; Gas::ALL.len()],
) -> PlaneGel {
    use std::arch::x86_64::*;
    let (full, fp) = vector_planes::<N>(codes, f);
    let ng = N;
    let zero = _mm256_setzero_pd();
    let pos_inf = _mm256_set1_pd(f64::INFINITY);
    let neg_inf = _mm256_set1_pd(f64::NEG_INFINITY);
    let bit = _mm256_set1_epi64x(INSIDE_BIT as i64);
    let kv: [__m256d; N] = std::array::from_fn(|g| _mm256_set1_pd(k[g]));
    // lanes 0–3 in the first vector of each pair, 4–7 in the second
    let mut sums = [[zero; 2]; N];
    let mut max_t = [neg_inf; 2];
    // the lowest value per gas, each in its own chain (one chain through every gas would
    // bound the loop); combined below, which gives the one chain's bits unless the lowest
    // value is a zero (then ±0 depend on the order: the plane is passed again by the portable build)
    let mut min_g = [[pos_inf; 2]; N];
    for q0 in (0..full).step_by(LANES) {
        // SAFETY: q0 + 7 < full ≤ codes.len(); the eight codes read as one little-endian word
        let c8 = u64::from_le(unsafe { codes.as_ptr().add(q0).cast::<u64>().read_unaligned() });
        for (h, c4) in [c8 as u32, (c8 >> 32) as u32].into_iter().enumerate() {
            // the four cells' inside bits as an all-ones / all-zeros mask per lane
            let bytes = _mm256_cvtepu8_epi64(_mm_cvtsi32_si128(c4 as i32));
            let inside = _mm256_castsi256_pd(_mm256_cmpeq_epi64(_mm256_and_si256(bytes, bit), bit));
            let mut t = zero;
            for g in 0..N {
                // SAFETY: q0 + 4h + 3 < full ≤ every field's plane length (checked above)
                let c = unsafe { _mm256_loadu_pd(fp[g].add(q0 + 4 * h)) };
                sums[g][h] = _mm256_add_pd(sums[g][h], _mm256_and_pd(inside, c));
                t = _mm256_add_pd(t, _mm256_mul_pd(c, kv[g]));
                // min(x, acc) gives acc when x is NaN or equal: the scalar `if x < acc`
                min_g[g][h] = _mm256_min_pd(_mm256_blendv_pd(pos_inf, c, inside), min_g[g][h]);
            }
            max_t[h] = _mm256_max_pd(_mm256_blendv_pd(neg_inf, t, inside), max_t[h]);
        }
    }
    let mut lanes = Lanes::new();
    for h in 0..2 {
        let mut min_c = pos_inf;
        for m in &min_g[..ng] {
            min_c = _mm256_min_pd(m[h], min_c);
        }
        // SAFETY: four f64 into four elements of an eight-element array (each store below)
        unsafe {
            _mm256_storeu_pd(lanes.min_c[4 * h..].as_mut_ptr(), min_c);
            _mm256_storeu_pd(lanes.max_t[4 * h..].as_mut_ptr(), max_t[h]);
        }
        for g in 0..ng {
            // SAFETY: as above
            unsafe { _mm256_storeu_pd(lanes.sums[g][4 * h..].as_mut_ptr(), sums[g][h]) };
        }
    }
    if lanes.min_c.contains(&0.0) {
        // the portable build keeps the one chain: its bits are this kernel's otherwise
        return plane_gel_portable(codes, f, k);
    }
    lanes.finish(codes, f, &k[..ng], full)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::grid::{Face, Shape};

    /// The vector build against the portable one (the same bits), and both against a plain
    /// cell-by-cell pass written here: extremes exact, sums within 1e-14 relative. On a cylinder
    /// (planes with outside cells, a length that is not a multiple of four) with cells taken
    /// out of the gel, and with a NaN and −0.0 among the values.
    #[test]
    fn the_plane_pass_matches_a_cell_by_cell_pass() {
        let mut g = Grid::new(
            Shape::Cylinder {
                diameter: 1.3e-3,
                depth: 0.5e-3,
            },
            1e-4,
            &[Face::Top, Face::Side],
        )
        .unwrap();
        assert_ne!(g.n[0] * g.n[1] % LANES, 0);
        let hole: Vec<usize> = (0..g.len()).filter(|i| i % 7 == 3).collect();
        g.set_excluded(&hole, true);
        let fields: Vec<Vec<f64>> = (0..3)
            .map(|f| {
                (0..g.len())
                    .map(|i| ((i * 7919 + 31 * f + 5) % 997) as f64 / 97.0 - 0.5)
                    .collect()
            })
            .collect();
        let mut with_nan = fields.clone();
        let inside: Vec<usize> = (0..g.len()).filter(|&i| g.inside(i)).collect();
        with_nan[1][inside[5]] = f64::NAN;
        with_nan[0][inside[9]] = -0.0;
        // the lowest value a zero, −0 and +0 in several orders among cells and gases (the
        // per-gas minima then need the plane passed again in one chain)
        let mut zeros: Vec<Vec<f64>> = fields
            .iter()
            .map(|f| f.iter().map(|x| x.abs() + 1.0).collect())
            .collect();
        for (n, &q) in inside.iter().enumerate().step_by(5) {
            zeros[n % 3][q] = if n % 2 == 0 { -0.0 } else { 0.0 };
            zeros[(n + 1) % 3][q] = if n % 3 == 0 { 0.0 } else { -0.0 };
        }
        // in every plane, one vector lane meets +0 of gas 1 in a cell before −0 of gas 0 (one
        // chain keeps +0, the gases' own minima combined would give −0)
        let plane = g.n[0] * g.n[1];
        for kz in 0..g.n[2] {
            let lane0: Vec<usize> = (kz * plane..kz * plane + plane - plane % LANES)
                .filter(|&q| (q - kz * plane).is_multiple_of(LANES) && g.inside(q))
                .collect();
            if let [a, .., b] = lane0[..] {
                zeros[1][a] = 0.0;
                zeros[0][b] = -0.0;
            }
        }
        let k = [2.0, 3.0, 0.5];
        for fields in [&fields, &with_nan, &zeros] {
            for ng in 1..=3 {
                for kz in 0..g.n[2] {
                    let (codes, f) = plane_slices(&g, &fields[..ng], kz);
                    let want = plane_gel_portable(codes, &f, &k);
                    let got = plane_gel(&g, &fields[..ng], &k, kz);
                    assert!(same_plane_gel(&want, &got, ng), "plane {kz}");
                    // every vector build this CPU runs, not only the one dispatched
                    #[cfg(target_arch = "x86_64")]
                    {
                        if std::arch::is_x86_feature_detected!("avx2") {
                            // SAFETY: the CPU has AVX2 (checked above)
                            let avx2 = unsafe { plane_gel_avx2(codes, &f, &k) };
                            assert!(same_plane_gel(&want, &avx2, ng), "AVX2, plane {kz}");
                        }
                        if std::arch::is_x86_feature_detected!("avx512f") {
                            // SAFETY: the CPU has AVX-512F (checked above)
                            let avx512 = unsafe { plane_gel_avx512(codes, &f, &k) };
                            assert!(same_plane_gel(&want, &avx512, ng), "AVX-512, plane {kz}");
                        }
                    }
                    // cell by cell
                    let (mut mx, mut mn) = (f64::NEG_INFINITY, f64::INFINITY);
                    let mut sums = [0.0; 4];
                    let mut scale = [0.0; 4];
                    for q in kz * plane..(kz + 1) * plane {
                        if !g.inside(q) {
                            continue;
                        }
                        let mut t = 0.0;
                        for gg in 0..ng {
                            let c = fields[gg][q];
                            sums[gg] += c;
                            scale[gg] += c.abs();
                            t += c * k[gg];
                            if c < mn {
                                mn = c;
                            }
                        }
                        if t > mx {
                            mx = t;
                        }
                    }
                    assert_eq!(mx.to_bits(), got.max_tension.to_bits(), "plane {kz}");
                    // the lanes' order, not the cells', decides between −0 and +0 (the
                    // portable build's bits, checked above, are the reference there)
                    assert!(
                        mn.to_bits() == got.min_c.to_bits() || (mn == 0.0 && got.min_c == 0.0),
                        "plane {kz}: {mn} against {}",
                        got.min_c
                    );
                    for gg in 0..ng {
                        if sums[gg].is_nan() {
                            assert!(got.sums[gg].is_nan());
                        } else {
                            assert!(
                                (got.sums[gg] - sums[gg]).abs() <= 1e-14 * scale[gg],
                                "plane {kz} gas {gg}: {} against {}",
                                got.sums[gg],
                                sums[gg]
                            );
                        }
                    }
                }
            }
        }
    }
}
