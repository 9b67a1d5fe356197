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
pub fn oat_index(levels: &[(f64, f64)], x_base: f64, m_base: f64) -> OatIndex {
    let ms = levels.iter().map(|l| l.1);
    let min = ms.clone().fold(f64::INFINITY, f64::min);
    let max = ms.fold(f64::NEG_INFINITY, f64::max);
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
/// parameter, EE in metric units per unit of the unit-cube coordinate.
#[derive(Debug, Clone, PartialEq)]
pub struct MorrisIndex {
    /// Mean of the absolute elementary effects.
    pub mu_star: f64,
    /// Mean of the elementary effects.
    pub mu: f64,
    /// Sample standard deviation of the elementary effects.
    pub sigma: f64,
}

/// Morris indices from the design's points and outputs (trajectories of k + 1 runs).
pub fn morris_indices(points: &[Vec<f64>], y: &[f64], k: usize) -> Vec<MorrisIndex> {
    let mut ee: Vec<Vec<f64>> = vec![Vec::new(); k];
    for (t, chunk) in points.chunks(k + 1).enumerate() {
        for s in 0..k {
            let (a, b) = (&chunk[s], &chunk[s + 1]);
            let Some(i) = (0..k).find(|&i| a[i] != b[i]) else {
                continue;
            };
            let (ya, yb) = (y[t * (k + 1) + s], y[t * (k + 1) + s + 1]);
            ee[i].push((yb - ya) / (b[i] - a[i]));
        }
    }
    ee.iter()
        .map(|e| {
            let n = e.len() as f64;
            let mu = e.iter().sum::<f64>() / n;
            let mu_star = e.iter().map(|v| v.abs()).sum::<f64>() / n;
            let sigma = if e.len() > 1 {
                (e.iter().map(|v| (v - mu).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
            } else {
                f64::NAN
            };
            MorrisIndex { mu_star, mu, sigma }
        })
        .collect()
}

/// Sobol' first-order and total indices of one parameter with bootstrap 95 % intervals.
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
}

fn sobol_point(rows: &[usize], y: &[f64], k: usize) -> Vec<(f64, f64)> {
    let f = |j: usize, c: usize| y[j * (k + 2) + c];
    let n = rows.len() as f64;
    // total variance from f(A) and f(B) together
    let all: Vec<f64> = rows.iter().flat_map(|&j| [f(j, 0), f(j, 1)]).collect();
    let mean = all.iter().sum::<f64>() / all.len() as f64;
    let var = all.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / all.len() as f64;
    (0..k)
        .map(|i| {
            let (mut v1, mut vt) = (0.0, 0.0);
            for &j in rows {
                let (a, b, ab) = (f(j, 0), f(j, 1), f(j, 2 + i));
                // f(B) centred on the sample mean: the same expectation, far less variance
                // when the output's mean is large against its spread
                v1 += (b - mean) * (ab - a);
                vt += (a - ab).powi(2);
            }
            (v1 / n / var, vt / (2.0 * n) / var)
        })
        .collect()
}

/// Sobol' indices from outputs in the design's order (rows of A, B, A_B^1 … A_B^k), with
/// `BOOTSTRAP` percentile resamples of the rows drawn from `seed`.
pub fn sobol_indices(y: &[f64], k: usize, seed: u64) -> Vec<SobolIndex> {
    let n = y.len() / (k + 2);
    let rows: Vec<usize> = (0..n).collect();
    let point = sobol_point(&rows, y, k);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5EED_B007);
    let mut boot: Vec<Vec<(f64, f64)>> = Vec::with_capacity(BOOTSTRAP);
    for _ in 0..BOOTSTRAP {
        let r: Vec<usize> = (0..n).map(|_| rng.gen_range(0..n)).collect();
        boot.push(sobol_point(&r, y, k));
    }
    let pct = |mut v: Vec<f64>| -> [f64; 2] {
        v.retain(|x| x.is_finite());
        if v.is_empty() {
            return [f64::NAN, f64::NAN];
        }
        v.sort_by(f64::total_cmp);
        let q = |p: f64| v[((p * (v.len() - 1) as f64).round() as usize).min(v.len() - 1)];
        [q(0.025), q(0.975)]
    };
    (0..k)
        .map(|i| SobolIndex {
            s1: point[i].0,
            s1_ci: pct(boot.iter().map(|b| b[i].0).collect()),
            st: point[i].1,
            st_ci: pct(boot.iter().map(|b| b[i].1).collect()),
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

    #[test]
    fn sweep_oat_normalised_sensitivity_of_a_power_law_is_its_exponent() {
        // m = x²: (Δm/Δx)·(x/m) between x = 1 and 3 about x = 2 is (9 − 1)/2 · 2/4 = 2
        let lv = [(1.0, 1.0), (2.0, 4.0), (3.0, 9.0)];
        let o = oat_index(&lv, 2.0, 4.0);
        assert_eq!((o.min, o.max), (1.0, 9.0));
        assert!((o.normalised - 2.0).abs() < 1e-12);
        let pts = design(Method::Oat, 2, 5, 0, &[0.3, 0.6]);
        assert_eq!(pts.len(), 11);
        assert_eq!(pts[3], vec![0.5, 0.6]);
    }
}
