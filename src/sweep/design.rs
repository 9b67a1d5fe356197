//! Sampling designs in the unit cube and the estimators of each method: one-at-a-time
//! (the paper's Fig. 3), Morris elementary effects, and Sobol' indices from Saltelli's
//! A, B, A_B^(i) matrices. Everything here works on unit-cube points and metric values; the
//! mapping to phantom parameters is in [`super::Param`].
//!
//! Sources (the definitions were read, the code is this project's):
//! - Morris, M. D. (1991) Factorial sampling plans for preliminary computational experiments.
//!   *Technometrics* 33: 161–174 (elementary effects, trajectories); Campolongo, Cariboni &
//!   Saltelli (2007) *Environ. Model. Softw.* 22: 1509–1518 (μ*, the mean of |EE|).
//! - Saltelli, A. et al. (2010) Variance based sensitivity analysis of model output. Design and
//!   estimator for the total sensitivity index. *Comput. Phys. Commun.* 181: 259–270: the
//!   A, B, A_B^(i) design, the first-order estimator V_i = (1/N) Σ f(B)_j (f(A_B^i)_j − f(A)_j)
//!   (their Table 2, (b)) and Jansen's total-effect estimator
//!   V_Ti = (1/2N) Σ (f(A)_j − f(A_B^i)_j)² (Table 2, (f)).

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// The sensitivity method.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Method {
    /// One parameter at a time over its range, the others at base values (`samples` levels).
    Oat,
    /// Morris elementary effects with `samples` trajectories.
    Morris,
    /// Sobol' first-order and total indices with `samples` base rows (N(k + 2) runs).
    Sobol,
}

impl Method {
    /// Parse `oat`, `morris` or `sobol`.
    pub fn parse(s: &str) -> Option<Method> {
        match s.trim().to_ascii_lowercase().as_str() {
            "oat" => Some(Method::Oat),
            "morris" => Some(Method::Morris),
            "sobol" => Some(Method::Sobol),
            _ => None,
        }
    }
    /// The name used on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Method::Oat => "oat",
            Method::Morris => "morris",
            Method::Sobol => "sobol",
        }
    }
}

/// Number of grid levels of a Morris trajectory (p = 4, Δ = p / (2(p − 1)) = 2/3, Morris 1991).
pub const MORRIS_LEVELS: usize = 4;

/// Bootstrap resamples for the Sobol' intervals.
pub const BOOTSTRAP: usize = 500;

/// The design: every run's unit-cube point, in run order. For `Oat`, `base` is the unit-cube
/// position of the base values and run 0 is the base run.
pub fn design(method: Method, k: usize, samples: usize, seed: u64, base: &[f64]) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    match method {
        Method::Oat => {
            let mut pts = vec![base.to_vec()];
            for i in 0..k {
                for l in 0..samples {
                    let mut x = base.to_vec();
                    x[i] = if samples > 1 {
                        l as f64 / (samples - 1) as f64
                    } else {
                        0.5
                    };
                    pts.push(x);
                }
            }
            pts
        }
        Method::Morris => {
            let p = MORRIS_LEVELS;
            let delta = p as f64 / (2.0 * (p - 1) as f64);
            // base levels from which +Δ stays in [0, 1]
            let starts: Vec<f64> = (0..p)
                .map(|l| l as f64 / (p - 1) as f64)
                .filter(|v| v + delta <= 1.0 + 1e-12)
                .collect();
            let mut pts = Vec::with_capacity(samples * (k + 1));
            for _ in 0..samples {
                let mut x: Vec<f64> = (0..k)
                    .map(|_| starts[rng.gen_range(0..starts.len())])
                    .collect();
                let mut order: Vec<usize> = (0..k).collect();
                order.shuffle(&mut rng);
                pts.push(x.clone());
                for &i in &order {
                    x[i] += delta;
                    pts.push(x.clone());
                }
            }
            pts
        }
        Method::Sobol => {
            let mut pts = Vec::with_capacity(samples * (k + 2));
            for _ in 0..samples {
                let a: Vec<f64> = (0..k).map(|_| rng.gen::<f64>()).collect();
                let b: Vec<f64> = (0..k).map(|_| rng.gen::<f64>()).collect();
                pts.push(a.clone());
                pts.push(b.clone());
                for i in 0..k {
                    let mut ab = a.clone();
                    ab[i] = b[i];
                    pts.push(ab);
                }
            }
            pts
        }
    }
}

/// Normalised one-at-a-time result of one parameter: the metric's range over the levels and
/// the normalised sensitivity (Δmetric/Δparameter) × (parameter/metric) at the base values,
/// Δ taken between the lowest and highest level.
#[derive(Debug, Clone, PartialEq)]
pub struct OatIndex {
    /// Smallest metric over the levels.
    pub min: f64,
    /// Largest metric over the levels.
    pub max: f64,
    /// (m(hi) − m(lo)) / (x_hi − x_lo) × x_base / m_base.
    pub normalised: f64,
}

/// One-at-a-time indices: `levels` are (parameter value, metric) pairs from lowest to highest.
/// `min` and `max` are over the levels with a finite metric (NaN when none has one).
pub fn oat_index(levels: &[(f64, f64)], x_base: f64, m_base: f64) -> OatIndex {
    let ms = levels.iter().map(|l| l.1).filter(|m| m.is_finite());
    let (min, max) = if ms.clone().next().is_some() {
        (
            ms.clone().fold(f64::INFINITY, f64::min),
            ms.fold(f64::NEG_INFINITY, f64::max),
        )
    } else {
        (f64::NAN, f64::NAN)
    };
    let normalised = match (levels.first(), levels.last()) {
        (Some(lo), Some(hi)) if hi.0 != lo.0 && m_base != 0.0 => {
            (hi.1 - lo.1) / (hi.0 - lo.0) * x_base / m_base
        }
        _ => f64::NAN,
    };
    OatIndex {
        min,
        max,
        normalised,
    }
}

/// Morris μ* (mean |EE|), μ (mean EE) and σ (standard deviation of EE, n − 1) of each
/// parameter, EE in metric units per unit of the unit-cube coordinate. An elementary effect
/// that is not finite (either of its two runs failed or has the metric undefined) is left out
/// and counted in `n_dropped`; the three statistics are those of the `n_used` finite ones
/// (NaN when none is, σ NaN when fewer than two are).
#[derive(Debug, Clone, PartialEq)]
pub struct MorrisIndex {
    /// Mean of the absolute elementary effects.
    pub mu_star: f64,
    /// Mean of the elementary effects.
    pub mu: f64,
    /// Sample standard deviation of the elementary effects.
    pub sigma: f64,
    /// Finite elementary effects the statistics are computed from.
    pub n_used: usize,
    /// Elementary effects left out (not finite).
    pub n_dropped: usize,
}

/// Morris indices from the design's points and outputs (trajectories of k + 1 runs).
pub fn morris_indices(points: &[Vec<f64>], y: &[f64], k: usize) -> Vec<MorrisIndex> {
    let mut ee: Vec<Vec<f64>> = vec![Vec::new(); k];
    let mut dropped = vec![0usize; k];
    for (t, chunk) in points.chunks(k + 1).enumerate() {
        for s in 0..k.min(chunk.len().saturating_sub(1)) {
            let (a, b) = (&chunk[s], &chunk[s + 1]);
            let Some(i) = (0..k).find(|&i| a[i] != b[i]) else {
                continue;
            };
            let (ya, yb) = (y[t * (k + 1) + s], y[t * (k + 1) + s + 1]);
            let e = (yb - ya) / (b[i] - a[i]);
            if e.is_finite() {
                ee[i].push(e);
            } else {
                dropped[i] += 1;
            }
        }
    }
    ee.iter()
        .zip(dropped)
        .map(|(e, n_dropped)| {
            let n = e.len() as f64;
            // 0/0 = NaN when no effect is finite
            let mu = e.iter().sum::<f64>() / n;
            let mu_star = e.iter().map(|v| v.abs()).sum::<f64>() / n;
            let sigma = if e.len() > 1 {
                (e.iter().map(|v| (v - mu).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
            } else {
                f64::NAN
            };
            MorrisIndex {
                mu_star,
                mu,
                sigma,
                n_used: e.len(),
                n_dropped,
            }
        })
        .collect()
}

/// Fewest base rows N a Sobol' study may have (`--samples`; refused below it, exit 2).
///
/// The indices lie in [0, 1], their estimators do not: both are ratios of sample means over N
/// rows to a sample variance of 2N values, whose relative standard error is about √(2/(2N − 1))
/// for a normal metric: 82 % at N = 2 (where a study printed S1 = 1.27 [1.27, 2.06]), 25 % at
/// N = 16. The 95 % intervals are percentiles of [`BOOTSTRAP`] resamples of the N
/// rows, and there are only C(2N − 1, N) distinct resamples (3 at N = 2, 35 at N = 4, 126 at
/// N = 5, 3·10⁸ at N = 16): up to N = 5 fewer than the 500 drawn, so the 2.5 % and 97.5 %
/// percentiles are picked from a handful of repeated values. N = 16 keeps both in hand (a
/// quarter on the variance, resamples that hardly repeat); it is a floor against meaningless
/// numbers, not a
/// recommendation (Saltelli et al. 2010 compare their estimators at far larger N), and
/// estimates outside [0, 1] at any N are flagged in the report
/// ("estimate outside [0, 1]: estimator noise"). `reproduce fig3 --quick` (N = 4, a smoke test of
/// the figure's code) builds its design directly and is not held to it.
pub const SOBOL_MIN_SAMPLES: usize = 16;

/// Fewest usable base rows a Sobol' index is estimated from (in the point estimate and in
/// every bootstrap resample); with fewer the index is NaN.
pub const SOBOL_MIN_ROWS: usize = 2;

/// Sobol' first-order and total indices of one parameter with bootstrap 95 % intervals.
///
/// Failed runs: the index of parameter i uses only the base rows j whose f(A)_j, f(B)_j and
/// f(A_B^i)_j are all finite (`n_used` of them; the variance too is taken over those rows'
/// f(A) and f(B)), so it equals the estimate of the design with the other rows removed. Each
/// bootstrap resample draws N base rows with replacement from all N and applies the same rule
/// (the interval is of the estimator as reported, including the chance of drawing a failed
/// row). The interval is given only when every resample defines the index: with
/// `undefined_resamples` > 0 (a resample with fewer than [`SOBOL_MIN_ROWS`] usable rows or a
/// metric constant over them) it is NaN, never taken from the resamples that happened to work.
#[derive(Debug, Clone, PartialEq)]
pub struct SobolIndex {
    /// First-order index S_i.
    pub s1: f64,
    /// Percentile bootstrap 95 % interval of S_i.
    pub s1_ci: [f64; 2],
    /// Total index S_Ti.
    pub st: f64,
    /// Percentile bootstrap 95 % interval of S_Ti.
    pub st_ci: [f64; 2],
    /// Base rows used (f(A), f(B) and f(A_B^i) all finite).
    pub n_used: usize,
    /// Base rows left out (N − `n_used`).
    pub n_dropped: usize,
    /// Bootstrap resamples in which the index was undefined (then no interval is given).
    pub undefined_resamples: usize,
}

/// Whether base row j can be used for parameter i: f(A)_j, f(B)_j and f(A_B^i)_j finite.
fn sobol_usable(y: &[f64], k: usize, j: usize, i: usize) -> bool {
    let f = |c: usize| y[j * (k + 2) + c];
    f(0).is_finite() && f(1).is_finite() && f(2 + i).is_finite()
}

/// (S_i, S_Ti) of parameter i from the base rows `rows` (a resample may repeat a row), the rows
/// not usable for i left out; `None` when fewer than [`SOBOL_MIN_ROWS`] remain, the metric
/// is constant over them or an index is not finite.
fn sobol_one(rows: &[usize], y: &[f64], k: usize, i: usize) -> Option<(f64, f64)> {
    let f = |j: usize, c: usize| y[j * (k + 2) + c];
    let used: Vec<usize> = rows
        .iter()
        .copied()
        .filter(|&j| sobol_usable(y, k, j, i))
        .collect();
    if used.len() < SOBOL_MIN_ROWS {
        return None;
    }
    let n = used.len() as f64;
    // total variance from f(A) and f(B) together
    let all: Vec<f64> = used.iter().flat_map(|&j| [f(j, 0), f(j, 1)]).collect();
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    let var = all.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / all.len() as f64;
    if !(var > 0.0 && var.is_finite()) {
        return None;
    }
    let (mut v1, mut vt) = (0.0, 0.0);
    for &j in &used {
        let (a, b, ab) = (f(j, 0), f(j, 1), f(j, 2 + i));
        // f(B) centred on the sample mean: the same expectation, far less variance
        // when the output's mean is large against its spread
        v1 += (b - mean) * (ab - a);
        vt += (a - ab).powi(2);
    }
    let (s1, st) = (v1 / n / var, vt / (2.0 * n) / var);
    (s1.is_finite() && st.is_finite()).then_some((s1, st))
}

/// Sobol' indices from outputs in the design's order (rows of A, B, A_B^1 … A_B^k), with
/// `BOOTSTRAP` percentile resamples of the rows drawn from `seed`; failed runs as described
/// at [`SobolIndex`].
pub fn sobol_indices(y: &[f64], k: usize, seed: u64) -> Vec<SobolIndex> {
    let n = y.len() / (k + 2);
    let rows: Vec<usize> = (0..n).collect();
    let point: Vec<Option<(f64, f64)>> = (0..k).map(|i| sobol_one(&rows, y, k, i)).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5EED_B007);
    // boot[b][i]: resample b's indices of parameter i (the same rows for every parameter)
    let mut boot: Vec<Vec<Option<(f64, f64)>>> = Vec::with_capacity(BOOTSTRAP);
    for _ in 0..BOOTSTRAP {
        let r: Vec<usize> = (0..n).map(|_| rng.gen_range(0..n)).collect();
        boot.push((0..k).map(|i| sobol_one(&r, y, k, i)).collect());
    }
    let pct = |mut v: Vec<f64>| -> [f64; 2] {
        v.sort_by(f64::total_cmp);
        let q = |p: f64| v[((p * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)];
        [q(0.025), q(0.975)]
    };
    (0..k)
        .map(|i| {
            let n_used = (0..n).filter(|&j| sobol_usable(y, k, j, i)).count();
            let undefined_resamples = boot.iter().filter(|b| b[i].is_none()).count();
            let nan = [f64::NAN; 2];
            let (s1, st, s1_ci, st_ci) = match point[i] {
                Some((s1, st)) if undefined_resamples == 0 => (
                    s1,
                    st,
                    pct(boot.iter().filter_map(|b| b[i]).map(|x| x.0).collect()),
                    pct(boot.iter().filter_map(|b| b[i]).map(|x| x.1).collect()),
                ),
                Some((s1, st)) => (s1, st, nan, nan),
                None => (f64::NAN, f64::NAN, nan, nan),
            };
            SobolIndex {
                s1,
                s1_ci,
                st,
                st_ci,
                n_used,
                n_dropped: n - n_used,
                undefined_resamples,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Ishigami & Homma (1990) with a = 7, b = 0.1 on x ∈ [−π, π]³.
    fn ishigami(u: &[f64]) -> f64 {
        let x: Vec<f64> = u.iter().map(|v| -PI + 2.0 * PI * v).collect();
        x[0].sin() + 7.0 * x[1].sin().powi(2) + 0.1 * x[2].powi(4) * x[0].sin()
    }

    #[test]
    fn sweep_sobol_reproduces_the_ishigami_indices() {
        // Reference values: the analytic indices of the Ishigami function with a = 7, b = 0.1,
        // as tabulated by Saltelli et al. (2008) Global Sensitivity Analysis: The Primer, and
        // by SALib's test suite / UQLab's documentation: S = (0.3139, 0.4424, 0),
        // ST = (0.5576, 0.4424, 0.2437). Independently, from the closed forms here:
        // V = a²/8 + bπ⁴/5 + b²π⁸/18 + 1/2, V1 = (1 + bπ⁴/5)²/2, V2 = a²/8, VT3 = 8b²π⁸/225.
        let (a, b) = (7.0_f64, 0.1_f64);
        let v = a * a / 8.0 + b * PI.powi(4) / 5.0 + b * b * PI.powi(8) / 18.0 + 0.5;
        let s1 = 0.5 * (1.0 + b * PI.powi(4) / 5.0).powi(2) / v;
        let s2 = a * a / 8.0 / v;
        let st3 = 8.0 * b * b * PI.powi(8) / 225.0 / v;
        assert!((s1 - 0.3139).abs() < 1e-4 && (s2 - 0.4424).abs() < 1e-4);
        assert!((st3 - 0.2437).abs() < 1e-4);
        let k = 3;
        let pts = design(Method::Sobol, k, 20_000, 7, &[]);
        let y: Vec<f64> = pts.iter().map(|p| ishigami(p)).collect();
        let ix = sobol_indices(&y, k, 7);
        let want_s = [0.3139, 0.4424, 0.0];
        let want_t = [0.5576, 0.4424, 0.2437];
        for i in 0..k {
            eprintln!(
                "x{}: S1 {:.4} [{:.4}, {:.4}] ({:.4}), ST {:.4} [{:.4}, {:.4}] ({:.4})",
                i + 1,
                ix[i].s1,
                ix[i].s1_ci[0],
                ix[i].s1_ci[1],
                want_s[i],
                ix[i].st,
                ix[i].st_ci[0],
                ix[i].st_ci[1],
                want_t[i]
            );
            assert!((ix[i].s1 - want_s[i]).abs() < 0.03, "S{}", i + 1);
            assert!((ix[i].st - want_t[i]).abs() < 0.03, "ST{}", i + 1);
            // the 95 % interval covers the analytic value
            assert!(ix[i].s1_ci[0] <= want_s[i] + 0.005 && want_s[i] - 0.005 <= ix[i].s1_ci[1]);
            assert!(ix[i].st_ci[0] <= want_t[i] + 0.005 && want_t[i] - 0.005 <= ix[i].st_ci[1]);
        }
    }

    #[test]
    fn sweep_sobol_reproduces_the_sobol_g_function() {
        // Sobol' G function, g(x) = Π (|4x_i − 2| + a_i)/(1 + a_i) on [0, 1]^k. Analytic
        // (Sobol' 1993; Saltelli et al. 2010, §4): V_i = 1/(3(1 + a_i)²),
        // V = Π (1 + V_i) − 1, S_i = V_i / V, S_Ti = V_i Π_{j≠i}(1 + V_j) / V.
        let a: [f64; 5] = [0.0, 1.0, 4.5, 9.0, 99.0];
        let k = a.len();
        let vi: Vec<f64> = a
            .iter()
            .map(|ai| 1.0 / (3.0 * (1.0 + ai).powi(2)))
            .collect();
        let v = vi.iter().map(|x| 1.0 + x).product::<f64>() - 1.0;
        let g = |u: &[f64]| -> f64 {
            u.iter()
                .zip(&a)
                .map(|(x, ai)| ((4.0 * x - 2.0).abs() + ai) / (1.0 + ai))
                .product()
        };
        let pts = design(Method::Sobol, k, 20_000, 11, &[]);
        let y: Vec<f64> = pts.iter().map(|p| g(p)).collect();
        let ix = sobol_indices(&y, k, 11);
        for i in 0..k {
            let s = vi[i] / v;
            let t = vi[i]
                * (0..k)
                    .filter(|&j| j != i)
                    .map(|j| 1.0 + vi[j])
                    .product::<f64>()
                / v;
            eprintln!(
                "G x{i}: S1 {:.4} ({s:.4}), ST {:.4} ({t:.4})",
                ix[i].s1, ix[i].st
            );
            assert!((ix[i].s1 - s).abs() < 0.03, "S{i}: {} vs {s}", ix[i].s1);
            assert!((ix[i].st - t).abs() < 0.03, "ST{i}: {} vs {t}", ix[i].st);
        }
    }

    #[test]
    fn sweep_morris_ranks_and_measures_a_linear_function_exactly() {
        // y = 3u0 − 2u1 + 0·u2 + u0·u1·0: every elementary effect of a linear function equals
        // its coefficient, so μ* = |c|, μ = c, σ = 0 (Morris 1991, §2).
        let f = |u: &[f64]| 3.0 * u[0] - 2.0 * u[1];
        let pts = design(Method::Morris, 3, 10, 3, &[]);
        assert_eq!(pts.len(), 10 * 4);
        assert!(pts.iter().flatten().all(|v| (0.0..=1.0).contains(v)));
        let y: Vec<f64> = pts.iter().map(|p| f(p)).collect();
        let m = morris_indices(&pts, &y, 3);
        for (i, c) in [3.0, -2.0, 0.0].iter().enumerate() {
            assert!((m[i].mu - c).abs() < 1e-12 && (m[i].mu_star - c.abs()).abs() < 1e-12);
            assert!(m[i].sigma.abs() < 1e-12);
        }
        // on Ishigami, x3 acts only through its interaction with x1: σ₃ > 0, and x2 (sin²,
        // no interaction) has the largest μ*
        let pts = design(Method::Morris, 3, 200, 5, &[]);
        let y: Vec<f64> = pts.iter().map(|p| ishigami(p)).collect();
        let m = morris_indices(&pts, &y, 3);
        assert!(m[2].sigma > 0.0);
    }

    /// The outputs `y` of a Sobol' design (k parameters) with base row `j` removed: its
    /// f(A), f(B) and f(A_B^1…k), k + 2 consecutive values.
    fn without_row(y: &[f64], k: usize, j: usize) -> Vec<f64> {
        let mut r = y.to_vec();
        r.drain(j * (k + 2)..(j + 1) * (k + 2));
        r
    }

    #[test]
    fn sweep_sobol_leaves_out_a_failed_base_row_as_if_it_were_not_in_the_design() {
        // Reference values: the estimator applied here to the design with that base row
        // removed (computed independently by building the reduced design), and the analytic
        // Ishigami indices (a = 7, b = 0.1; Saltelli et al. 2008, Global Sensitivity Analysis:
        // The Primer, §4): S = (0.3139, 0.4424, 0), ST = (0.5576, 0.4424, 0.2437).
        let k = 3;
        let n = 4000;
        let pts = design(Method::Sobol, k, n, 17, &[]);
        let y: Vec<f64> = pts.iter().map(|p| ishigami(p)).collect();
        let full = sobol_indices(&y, k, 17);
        let want_s = [0.3139, 0.4424, 0.0];
        let want_t = [0.5576, 0.4424, 0.2437];
        let j = 123;
        // (1) f(A)_j fails: row j is unusable for every parameter
        let mut ya = y.clone();
        ya[j * (k + 2)] = f64::NAN;
        let got = sobol_indices(&ya, k, 17);
        let reduced = sobol_indices(&without_row(&y, k, j), k, 17);
        for i in 0..k {
            let (g, r) = (&got[i], &reduced[i]);
            eprintln!(
                "x{}: S1 {:.4} [{:.4}, {:.4}] (reduced design {:.4}, all rows {:.4}), ST {:.4} [{:.4}, {:.4}] (reduced {:.4})",
                i + 1, g.s1, g.s1_ci[0], g.s1_ci[1], r.s1, full[i].s1, g.st, g.st_ci[0], g.st_ci[1], r.st
            );
            // the same rows in the same order: the same arithmetic, bit for bit
            assert_eq!((g.s1, g.st), (r.s1, r.st), "x{}", i + 1);
            assert_eq!(
                (g.n_used, g.n_dropped, g.undefined_resamples),
                (n - 1, 1, 0)
            );
            assert_eq!((r.n_used, r.n_dropped), (n - 1, 0));
            for (v, ci) in [(g.s1, g.s1_ci), (g.st, g.st_ci)] {
                assert!(ci[0].is_finite() && ci[1].is_finite(), "x{}: {ci:?}", i + 1);
                assert!(ci[0] <= v && v <= ci[1], "x{}: {v} not in {ci:?}", i + 1);
            }
            assert!((g.s1 - want_s[i]).abs() < 0.05 && (g.st - want_t[i]).abs() < 0.05);
        }
        // (2) only f(A_B^2)_j fails: parameter 2 loses row j, parameters 1 and 3 keep every row
        let mut yab = y.clone();
        yab[j * (k + 2) + 2 + 1] = f64::NAN;
        let got = sobol_indices(&yab, k, 17);
        assert_eq!((got[1].s1, got[1].st), (reduced[1].s1, reduced[1].st));
        assert_eq!((got[1].n_used, got[1].n_dropped), (n - 1, 1));
        let ci = got[1].s1_ci;
        assert!(ci[0].is_finite() && ci[0] <= got[1].s1 && got[1].s1 <= ci[1]);
        for i in [0, 2] {
            // untouched: the whole design's estimate and interval
            assert_eq!(got[i], full[i], "x{}", i + 1);
            assert_eq!((got[i].n_used, got[i].n_dropped), (n, 0));
        }
    }

    #[test]
    fn sweep_sobol_gives_no_index_or_interval_from_too_few_usable_rows() {
        // Ishigami again (its values are the inputs here, not a reference); rows fail by hand
        let k = 3;
        let pts = design(Method::Sobol, k, 4, 5, &[]);
        let y: Vec<f64> = pts.iter().map(|p| ishigami(p)).collect();
        // two of four base rows fail in f(B): two usable rows give an estimate, but a resample
        // of four rows often draws fewer than two of them, so no interval is given
        let mut y2 = y.clone();
        for j in [0, 2] {
            y2[j * (k + 2) + 1] = f64::NAN;
        }
        for ix in sobol_indices(&y2, k, 5) {
            assert_eq!((ix.n_used, ix.n_dropped), (2, 2));
            assert!(ix.s1.is_finite() && ix.st.is_finite());
            assert!(ix.undefined_resamples > 0);
            assert!(ix.s1_ci.iter().chain(&ix.st_ci).all(|v| v.is_nan()));
        }
        // three of four fail: one usable row, below SOBOL_MIN_ROWS: NaN, no interval
        y2[3 * (k + 2)] = f64::NAN;
        for ix in sobol_indices(&y2, k, 5) {
            assert_eq!((ix.n_used, ix.n_dropped), (1, 3));
            assert!(ix.s1.is_nan() && ix.st.is_nan());
            assert!(ix.s1_ci.iter().chain(&ix.st_ci).all(|v| v.is_nan()));
        }
        // every value NaN (a metric undefined in every run)
        for ix in sobol_indices(&vec![f64::NAN; y.len()], k, 5) {
            assert_eq!((ix.n_used, ix.n_dropped), (0, 4));
            assert!(ix.s1.is_nan() && ix.st.is_nan() && ix.s1_ci[0].is_nan());
        }
    }

    #[test]
    fn sweep_morris_leaves_out_the_elementary_effects_of_a_failed_run() {
        // y = 3u0 − 2u1 + 0.5u2: every elementary effect of a linear function is its
        // coefficient (Morris 1991, §2), so μ* = |c_i| and μ = c_i from any subset of them
        let c = [3.0, -2.0, 0.5];
        let f = |u: &[f64]| c.iter().zip(u).map(|(c, x)| c * x).sum::<f64>();
        let (k, r) = (3, 10);
        let pts = design(Method::Morris, k, r, 3, &[]);
        let mut y: Vec<f64> = pts.iter().map(|p| f(p)).collect();
        // the first run of trajectory 4 fails: only the effect of its first step is lost,
        // which belongs to the parameter that step moves
        let t = 4;
        let first = t * (k + 1);
        let moved = (0..k)
            .find(|&i| pts[first][i] != pts[first + 1][i])
            .unwrap();
        y[first] = f64::NAN;
        let m = morris_indices(&pts, &y, k);
        for i in 0..k {
            assert!(
                (m[i].mu_star - c[i].abs()).abs() < 1e-12,
                "x{i}: {}",
                m[i].mu_star
            );
            assert!((m[i].mu - c[i]).abs() < 1e-12 && m[i].sigma.abs() < 1e-12);
            let lost = usize::from(i == moved);
            assert_eq!((m[i].n_used, m[i].n_dropped), (r - lost, lost), "x{i}");
        }
        // a run in the middle of a trajectory takes the effects of both its steps
        y[first] = f(&pts[first]);
        y[first + 1] = f64::NAN;
        let m = morris_indices(&pts, &y, k);
        let second = (0..k)
            .find(|&i| pts[first + 1][i] != pts[first + 2][i])
            .unwrap();
        for i in 0..k {
            let lost = usize::from(i == moved) + usize::from(i == second);
            assert_eq!((m[i].n_used, m[i].n_dropped), (r - lost, lost), "x{i}");
            assert!((m[i].mu_star - c[i].abs()).abs() < 1e-12);
        }
        // no finite value: NaN, none used
        let m = morris_indices(&pts, &vec![f64::NAN; y.len()], k);
        assert!(m
            .iter()
            .all(|x| x.mu_star.is_nan() && x.mu.is_nan() && x.sigma.is_nan()));
        assert!(m.iter().all(|x| (x.n_used, x.n_dropped) == (0, r)));
    }

    #[test]
    fn sweep_oat_normalised_sensitivity_of_a_power_law_is_its_exponent() {
        // m = x²: (Δm/Δx)·(x/m) between x = 1 and 3 about x = 2 is (9 − 1)/2 · 2/4 = 2
        let lv = [(1.0, 1.0), (2.0, 4.0), (3.0, 9.0)];
        let o = oat_index(&lv, 2.0, 4.0);
        assert_eq!((o.min, o.max), (1.0, 9.0));
        assert!((o.normalised - 2.0).abs() < 1e-12);
        // a failed level is left out of the range; no finite level: NaN, not ±inf
        let o = oat_index(&[(1.0, 1.0), (2.0, f64::NAN), (3.0, 9.0)], 2.0, 4.0);
        assert_eq!((o.min, o.max), (1.0, 9.0));
        let o = oat_index(&[(1.0, f64::NAN), (3.0, f64::NAN)], 2.0, 4.0);
        assert!(o.min.is_nan() && o.max.is_nan() && o.normalised.is_nan());
        let pts = design(Method::Oat, 2, 5, 0, &[0.3, 0.6]);
        assert_eq!(pts.len(), 11);
        assert_eq!(pts[3], vec![0.5, 0.6]);
    }
}
