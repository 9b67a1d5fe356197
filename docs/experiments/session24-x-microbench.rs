//! Session 24's standalone microbenchmark of the implicit step's x sweep (docs/speed-history.md,
//! session 24). The Fig. 5 cylinder's planes (127 × 127 cells, 58 planes, each x line from its
//! first cell inside the circle), one thread, one field, the same factors for every line
//! (a broadcast per row: no table lookups). Variants, alternated call by call:
//! - A: the current shape, 4 × 4 AVX transposes into a copy of the plane, the rows of the copy
//!   solved, transposed back;
//! - B<G>: in place, G groups of four lines at once, each 4 × 4 block transposed in registers
//!   in the forward pass and again in the back substitution; cells past the shortest line of
//!   the groups one by one (`variant_b::<0>` is the plain per-line reference);
//! - C<G>: as B, the lines' ends masked (`_mm256_maskload_pd`) instead of done one by one.
//!
//! The check compares C<2> bit for bit with the per-line reference. Use: a cargo project with
//! this file as src/main.rs, `cargo run --release` (REPS sets the calls, default 200).
use std::arch::x86_64::*;
use std::time::Instant;

const N: usize = 127;
const NZ: usize = 58;

struct Lines { ext: Vec<(usize, usize)> }

fn cylinder() -> Lines {
    let mut ext = vec![];
    let c = N as f64 / 2.0;
    for j in 0..N {
        let y = j as f64 + 0.5 - c;
        let half = (c * c - y * y).max(0.0).sqrt();
        let s = (c - half).ceil() as usize;
        let e = ((c + half).floor() as usize).min(N);
        ext.push((s, e.max(s)));
    }
    Lines { ext }
}

#[inline(always)]
unsafe fn tr(v0: __m256d, v1: __m256d, v2: __m256d, v3: __m256d) -> [__m256d; 4] {
    let t0 = _mm256_unpacklo_pd(v0, v1);
    let t1 = _mm256_unpackhi_pd(v0, v1);
    let t2 = _mm256_unpacklo_pd(v2, v3);
    let t3 = _mm256_unpackhi_pd(v2, v3);
    [
        _mm256_permute2f128_pd(t0, t2, 0x20),
        _mm256_permute2f128_pd(t1, t3, 0x20),
        _mm256_permute2f128_pd(t0, t2, 0x31),
        _mm256_permute2f128_pd(t1, t3, 0x31),
    ]
}

/// A: transpose in, solve rows, transpose out (the current code's shape)
#[target_feature(enable = "avx2")]
unsafe fn variant_a(plane: *mut f64, t: *mut f64, l: &Lines, inv: &[f64], cneg: &[f64], r: f64) {
    let xs = N;
    let ext = &l.ext;
    let nrows = ext.iter().map(|&(s, e)| e - s).max().unwrap();
    let lines = |into_t: bool| {
        let ny4 = N / 4 * 4;
        for j0 in (0..ny4).step_by(4) {
            let rows: [*mut f64; 4] = std::array::from_fn(|q| plane.add((j0 + q) * N + ext[j0 + q].0));
            let lens: [usize; 4] = std::array::from_fn(|q| ext[j0 + q].1 - ext[j0 + q].0);
            let a4 = lens.iter().min().copied().unwrap() / 4 * 4;
            let col = t.add(j0);
            for a0 in (0..a4).step_by(4) {
                let c = col.add(a0 * xs);
                if into_t {
                    let w = tr(_mm256_loadu_pd(rows[0].add(a0)), _mm256_loadu_pd(rows[1].add(a0)), _mm256_loadu_pd(rows[2].add(a0)), _mm256_loadu_pd(rows[3].add(a0)));
                    for q in 0..4 { _mm256_storeu_pd(c.add(q * xs), w[q]); }
                } else {
                    let w = tr(_mm256_loadu_pd(c), _mm256_loadu_pd(c.add(xs)), _mm256_loadu_pd(c.add(2 * xs)), _mm256_loadu_pd(c.add(3 * xs)));
                    for q in 0..4 { _mm256_storeu_pd(rows[q].add(a0), w[q]); }
                }
            }
            for q in 0..4 {
                for a in a4..lens[q] {
                    if into_t { *col.add(q + a * xs) = *rows[q].add(a); } else { *rows[q].add(a) = *col.add(q + a * xs); }
                }
            }
        }
        for j in ny4..N {
            let (s, e) = ext[j];
            for a in 0..e - s {
                if into_t { *t.add(a * xs + j) = *plane.add(j * N + s + a); } else { *plane.add(j * N + s + a) = *t.add(a * xs + j); }
            }
        }
    };
    lines(true);
    // forward
    for i in 0..N { *t.add(i) *= inv[0]; }
    for a in 1..nrows {
        let cur = t.add(a * xs);
        let prev = t.add((a - 1) * xs);
        let f = inv[a];
        for i in 0..N { *cur.add(i) = (*cur.add(i) + r * *prev.add(i)) * f; }
    }
    for a in (0..nrows - 1).rev() {
        let cur = t.add(a * xs);
        let next = t.add((a + 1) * xs);
        let w = cneg[a];
        for i in 0..N { *cur.add(i) -= w * *next.add(i); }
    }
    lines(false);
}

/// B: in registers, G groups of four lines at once
#[target_feature(enable = "avx2,avx512f,avx512vl")]
unsafe fn variant_b<const G: usize>(plane: *mut f64, l: &Lines, inv: &[f64], cneg: &[f64], r: f64) {
    let ext = &l.ext;
    let rv = _mm256_set1_pd(r);
    let per = 4 * G;
    let nyg = if per == 0 { 0 } else { N / per * per };
    for j0 in (0..nyg).step_by(per.max(1)) {
        let rows: [[*mut f64; 4]; G] = std::array::from_fn(|g| std::array::from_fn(|q| plane.add((j0 + 4 * g + q) * N + ext[j0 + 4 * g + q].0)));
        let lens: [usize; 16] = std::array::from_fn(|q| if q < per { ext[j0 + q].1 - ext[j0 + q].0 } else { usize::MAX });
        let a4 = lens.iter().min().copied().unwrap() / 4 * 4;
        // forward
        let mut prev = [_mm256_setzero_pd(); G];
        for a0 in (0..a4).step_by(4) {
            for g in 0..G {
                let rw = &rows[g];
                let mut w = tr(_mm256_loadu_pd(rw[0].add(a0)), _mm256_loadu_pd(rw[1].add(a0)), _mm256_loadu_pd(rw[2].add(a0)), _mm256_loadu_pd(rw[3].add(a0)));
                let mut p = prev[g];
                for q in 0..4 {
                    let a = a0 + q;
                    let f = _mm256_set1_pd(*inv.get_unchecked(a));
                    let rhs = if a == 0 { w[q] } else { _mm256_add_pd(w[q], _mm256_mul_pd(rv, p)) };
                    p = _mm256_mul_pd(rhs, f);
                    w[q] = p;
                }
                prev[g] = p;
                let o = tr(w[0], w[1], w[2], w[3]);
                for q in 0..4 { _mm256_storeu_pd(rw[q].add(a0), o[q]); }
            }
        }
        // tails forward
        for q in 0..per {
            let row = rows[q / 4][q % 4];
            for a in a4..lens[q] {
                let rhs = if a == 0 { *row.add(a) } else { *row.add(a) + r * *row.add(a - 1) };
                *row.add(a) = rhs * inv[a];
            }
            // back substitution of the tail, down to a4
            let n = lens[q];
            for a in (a4..n.saturating_sub(1)).rev() {
                *row.add(a) -= cneg[a] * *row.add(a + 1);
            }
        }
        // back in blocks
        let mut next: [__m256d; G] = std::array::from_fn(|g| {
            let rw = &rows[g];
            _mm256_set_pd(*rw[3].add(a4), *rw[2].add(a4), *rw[1].add(a4), *rw[0].add(a4))
        });
        for a0 in (0..a4).step_by(4).rev() {
            for g in 0..G {
                let rw = &rows[g];
                let mut w = tr(_mm256_loadu_pd(rw[0].add(a0)), _mm256_loadu_pd(rw[1].add(a0)), _mm256_loadu_pd(rw[2].add(a0)), _mm256_loadu_pd(rw[3].add(a0)));
                let mut nx = next[g];
                for q in (0..4).rev() {
                    let a = a0 + q;
                    // (the line's last cell has cneg 0 in the real table; here lens ≥ a4+1 guaranteed? no: handle below)
                    let c = _mm256_set1_pd(*cneg.get_unchecked(a));
                    nx = _mm256_sub_pd(w[q], _mm256_mul_pd(c, nx));
                    w[q] = nx;
                }
                next[g] = nx;
                let o = tr(w[0], w[1], w[2], w[3]);
                for q in 0..4 { _mm256_storeu_pd(rw[q].add(a0), o[q]); }
            }
        }
    }
    // leftover lines scalar
    for j in nyg..N {
        let (s, e) = ext[j];
        let row = plane.add(j * N + s);
        let n = e - s;
        for a in 0..n {
            let rhs = if a == 0 { *row.add(a) } else { *row.add(a) + r * *row.add(a - 1) };
            *row.add(a) = rhs * inv[a];
        }
        for a in (0..n.saturating_sub(1)).rev() {
            *row.add(a) -= cneg[a] * *row.add(a + 1);
        }
    }
}

fn main() {
    let l = cylinder();
    let r = 2.0;
    let mut inv = vec![0.0; N + 1];
    let mut cneg = vec![0.0; N + 1];
    let mut cp = 0.0;
    for a in 0..=N {
        let b = 1.0 + 2.0 * r;
        let p = 1.0 / (b - r * cp);
        inv[a] = p;
        cp = r * p;
        cneg[a] = -r * p;
    }
    let fill = |u: &mut Vec<f64>| for (i, x) in u.iter_mut().enumerate() { *x = 1.0 + (i % 17) as f64 * 0.01; };
    let mut u = vec![0.0; N * N * NZ];
    let mut t = vec![0.0; N * N];
    let reps: usize = std::env::var("REPS").ok().map(|s| s.parse().unwrap()).unwrap_or(200);
    // check: the two variants agree on one sweep
    // (B treats the last cells' cneg like A when every line's back sweep starts at its own end)
    let mut ua = vec![0.0; N * N * NZ]; fill(&mut ua);
    let mut ub = ua.clone();
    unsafe {
        for k in 0..NZ { variant_b::<0>(ua.as_mut_ptr().add(k * N * N), &l, &inv, &cneg, r); }
        for k in 0..NZ { variant_c::<2>(ub.as_mut_ptr().add(k * N * N), &l, &inv, &cneg, r); }
    }
    let diff = ua.iter().zip(&ub).filter(|(a, b)| a.to_bits() != b.to_bits()).count();
    println!("cells differing: {diff}");
    fill(&mut u);
    let cells: usize = l.ext.iter().map(|&(s, e)| e - s).sum::<usize>() * NZ;
    let mut times = [vec![], vec![], vec![], vec![]];
    for rep in 0..reps {
        let v = rep % 4;
        let t0 = Instant::now();
        unsafe {
            for k in 0..NZ {
                let p = u.as_mut_ptr().add(k * N * N);
                match v {
                    0 => variant_a(p, t.as_mut_ptr(), &l, &inv, &cneg, r),
                    1 => variant_c::<2>(p, &l, &inv, &cneg, r),
                    2 => variant_b::<2>(p, &l, &inv, &cneg, r),
                    _ => variant_c::<1>(p, &l, &inv, &cneg, r),
                }
            }
        }
        let ns = t0.elapsed().as_secs_f64() * 1e9 / cells as f64;
        if rep >= 8 { times[v].push(ns); }
        fill(&mut u);
    }
    for (v, name) in ["A transposed copy", "C G=2", "B G=2", "C G=1"].iter().enumerate() {
        let mut x = times[v].clone();
        x.sort_by(|a, b| a.total_cmp(b));
        println!("{name}: median {:.3} ns/cell, p10 {:.3}", x[x.len() / 2], x[x.len() / 10]);
    }
}

/// C: like B (G groups of 4 lines) but over each group's longest line, masked at line ends.
#[target_feature(enable = "avx2,avx512f,avx512vl")]
pub unsafe fn variant_c<const G: usize>(plane: *mut f64, l: &Lines, inv: &[f64], cneg: &[f64], r: f64) {
    let ext = &l.ext;
    let rv = _mm256_set1_pd(r);
    let per = 4 * G;
    let nyg = N / per * per;
    let lane = _mm256_set_epi64x(3, 2, 1, 0);
    for j0 in (0..nyg).step_by(per) {
        let rows: [[*mut f64; 4]; G] = std::array::from_fn(|g| std::array::from_fn(|q| plane.add((j0 + 4 * g + q) * N + ext[j0 + 4 * g + q].0)));
        let lens: [[i64; 4]; G] = std::array::from_fn(|g| std::array::from_fn(|q| (ext[j0 + 4 * g + q].1 - ext[j0 + 4 * g + q].0) as i64));
        let lenv: [__m256i; G] = std::array::from_fn(|g| _mm256_set_epi64x(lens[g][3], lens[g][2], lens[g][1], lens[g][0]));
        let maxl = lens.iter().flatten().copied().max().unwrap() as usize;
        let minl = lens.iter().flatten().copied().min().unwrap() as usize;
        let a4 = minl / 4 * 4;
        let amax = maxl.div_ceil(4) * 4;
        if maxl == 0 { continue; }
        // mask of line q's lanes a0..a0+4 (as a load of 4 consecutive cells of line q)
        let mask = |g: usize, q: usize, a0: usize| -> __m256i {
            let l = _mm256_set1_epi64x(lens[g][q] - a0 as i64);
            _mm256_cmpgt_epi64(l, lane)
        };
        let _ = lenv;
        let mut prev = [_mm256_setzero_pd(); G];
        let mut a0 = 0;
        while a0 < amax {
            let full = a0 + 4 <= a4;
            for g in 0..G {
                let rw = &rows[g];
                let ld = |q: usize| if full { _mm256_loadu_pd(rw[q].add(a0)) } else { _mm256_maskload_pd(rw[q].add(a0), mask(g, q, a0)) };
                let mut w = tr(ld(0), ld(1), ld(2), ld(3));
                let mut p = prev[g];
                for q in 0..4 {
                    let a = a0 + q;
                    let f = _mm256_set1_pd(*inv.get_unchecked(a));
                    let rhs = _mm256_add_pd(w[q], _mm256_mul_pd(rv, p));
                    p = _mm256_mul_pd(rhs, f);
                    w[q] = p;
                }
                prev[g] = p;
                let o = tr(w[0], w[1], w[2], w[3]);
                for q in 0..4 {
                    if full { _mm256_storeu_pd(rw[q].add(a0), o[q]) } else { _mm256_maskstore_pd(rw[q].add(a0), mask(g, q, a0), o[q]) }
                }
            }
            a0 += 4;
        }
        let mut next = [_mm256_setzero_pd(); G];
        let mut a0 = amax;
        while a0 > 0 {
            a0 -= 4;
            let full = a0 + 4 <= a4;
            for g in 0..G {
                let rw = &rows[g];
                let ld = |q: usize| if full { _mm256_loadu_pd(rw[q].add(a0)) } else { _mm256_maskload_pd(rw[q].add(a0), mask(g, q, a0)) };
                let mut w = tr(ld(0), ld(1), ld(2), ld(3));
                let mut nx = next[g];
                for q in (0..4).rev() {
                    let a = a0 + q;
                    // the last cell of each line: weight 0 (here: a lane mask; in the code, the table's 0)
                    let c = _mm256_and_pd(_mm256_set1_pd(*cneg.get_unchecked(a)), _mm256_castsi256_pd(_mm256_cmpgt_epi64(lenv[g], _mm256_set1_epi64x(a as i64 + 1))));
                    nx = _mm256_sub_pd(w[q], _mm256_mul_pd(c, nx));
                    w[q] = nx;
                }
                next[g] = nx;
                let o = tr(w[0], w[1], w[2], w[3]);
                for q in 0..4 {
                    if full { _mm256_storeu_pd(rw[q].add(a0), o[q]) } else { _mm256_maskstore_pd(rw[q].add(a0), mask(g, q, a0), o[q]) }
                }
            }
        }
    }
    for j in nyg..N {
        let (s, e) = ext[j];
        let row = plane.add(j * N + s);
        let n = e - s;
        for a in 0..n {
            let rhs = if a == 0 { *row.add(a) } else { *row.add(a) + r * *row.add(a - 1) };
            *row.add(a) = rhs * inv[a];
        }
        for a in (0..n.saturating_sub(1)).rev() {
            *row.add(a) -= cneg[a] * *row.add(a + 1);
        }
    }
}
