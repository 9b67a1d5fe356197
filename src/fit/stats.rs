//! Model comparison and residual tests, each with its assumptions:
//! - the extra sum-of-squares F-test between nested least-squares models (the paper's test,
//!   Fig. 5; Motulsky & Christopoulos, *Fitting models to biological data*, ch. 22):
//!   F = ((SSR₀ − SSR₁)/(df₀ − df₁)) / (SSR₁/df₁), F(df₀ − df₁, df₁) under H₀ that the simpler
//!   model is true, with independent Gaussian errors of the given relative weights;
//! - AICc = n·ln(SSR/n) + 2K + 2K(K + 1)/(n − K − 1), K = parameters + 1 (the variance)
//!   (Burnham & Anderson 2002, eq. 2.5 with the least-squares likelihood);
//! - the Wald–Wolfowitz runs test on residual signs (normal approximation; Bradley 1968),
//!   which detects systematic misfit along time without assuming a form for it;
//! - Pearson correlation with its t-test (residual against a covariate).

use statrs::distribution::{ContinuousCDF, FisherSnedecor, Normal, StudentsT};

/// The result of an extra sum-of-squares F-test.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FTest {
    /// F statistic.
    pub f: f64,
    /// Numerator degrees of freedom (extra parameters).
    pub df_num: usize,
    /// Denominator degrees of freedom (of the larger model).
    pub df_den: usize,
    /// P(F ≥ f) under H₀.
    pub p_value: f64,
}

/// Extra sum-of-squares F-test of a simpler model (SSR `ssr0`, `df0` = n − p₀) against a larger
/// one that contains it (`ssr1`, `df1` = n − p₁ < df0).
pub fn extra_ss_f_test(ssr0: f64, df0: usize, ssr1: f64, df1: usize) -> FTest {
    let dn = df0.saturating_sub(df1);
    if dn == 0 || df1 == 0 || !(ssr1 > 0.0) {
        return FTest {
            f: f64::NAN,
            df_num: dn,
            df_den: df1,
            p_value: if ssr1 == 0.0 && ssr0 > 0.0 { 0.0 } else { 1.0 },
        };
    }
    let f = ((ssr0 - ssr1) / dn as f64) / (ssr1 / df1 as f64);
    let p = if f <= 0.0 {
        1.0
    } else {
        FisherSnedecor::new(dn as f64, df1 as f64).map_or(f64::NAN, |d| d.sf(f))
    };
    FTest {
        f,
        df_num: dn,
        df_den: df1,
        p_value: p,
    }
}

/// Small-sample Akaike information criterion for a least-squares fit with `p` parameters
/// (K = p + 1 counts the error variance). Infinite when n ≤ K + 1.
pub fn aicc(ssr: f64, n: usize, p: usize) -> f64 {
    let k = (p + 1) as f64;
    let nf = n as f64;
    if nf <= k + 1.0 || !(ssr > 0.0) {
        return f64::INFINITY;
    }
    nf * (ssr / nf).ln() + 2.0 * k + 2.0 * k * (k + 1.0) / (nf - k - 1.0)
}

/// Wald–Wolfowitz runs test on the signs of `residuals` (zeros dropped).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunsTest {
    /// Runs observed.
    pub runs: usize,
    /// Runs expected under randomness, 1 + 2n₊n₋/n.
    pub expected: f64,
    /// z statistic (normal approximation).
    pub z: f64,
    /// Two-sided p-value; NaN with fewer than 2 of either sign.
    pub p_value: f64,
}

/// The runs test (two-sided).
pub fn runs_test(residuals: &[f64]) -> RunsTest {
    let signs: Vec<bool> = residuals
        .iter()
        .filter(|r| **r != 0.0 && r.is_finite())
        .map(|r| *r > 0.0)
        .collect();
    let np = signs.iter().filter(|s| **s).count() as f64;
    let nm = signs.len() as f64 - np;
    let runs = if signs.is_empty() {
        0
    } else {
        1 + signs.windows(2).filter(|w| w[0] != w[1]).count()
    };
    let n = np + nm;
    let expected = 1.0 + 2.0 * np * nm / n.max(1.0);
    if np < 2.0 || nm < 2.0 {
        return RunsTest {
            runs,
            expected,
            z: f64::NAN,
            p_value: f64::NAN,
        };
    }
    let var = 2.0 * np * nm * (2.0 * np * nm - n) / (n * n * (n - 1.0));
    let z = (runs as f64 - expected) / var.sqrt();
    RunsTest {
        runs,
        expected,
        z,
        p_value: 2.0 * normal_sf(z.abs()),
    }
}

/// One standard normal draw by Box–Muller (Box & Muller 1958, Ann. Math. Statist. 29, 610–611)
/// from two uniforms, the first on (0, 1] so that its logarithm is finite.
pub fn standard_normal<R: rand::Rng>(rng: &mut R) -> f64 {
    let u1: f64 = 1.0 - rng.gen::<f64>();
    let u2: f64 = rng.gen::<f64>();
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

fn normal_sf(z: f64) -> f64 {
    Normal::new(0.0, 1.0).map_or(f64::NAN, |n| n.sf(z))
}

/// Pearson correlation of `x` and `y` with the two-sided p-value of t = r√((n−2)/(1−r²)).
pub fn correlation(x: &[f64], y: &[f64]) -> (f64, f64) {
    let n = x.len().min(y.len());
    if n < 3 {
        return (f64::NAN, f64::NAN);
    }
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let my = y[..n].iter().sum::<f64>() / n as f64;
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (a, b) = (x[i] - mx, y[i] - my);
        sxy += a * b;
        sxx += a * a;
        syy += b * b;
    }
    // a spread at the rounding level of the mean is a constant (453 equal distances leave
    // sxx ≈ 4e-32 from rounding alone): no correlation to report
    let flat = |s: f64, m: f64| !(s > n as f64 * (1e-12 * m.abs()).powi(2));
    if flat(sxx, mx) || flat(syy, my) {
        return (f64::NAN, f64::NAN);
    }
    let r = (sxy / (sxx * syy).sqrt()).clamp(-1.0, 1.0);
    let df = (n - 2) as f64;
    if r.abs() >= 1.0 {
        return (r, 0.0);
    }
    let t = r * (df / (1.0 - r * r)).sqrt();
    let p = StudentsT::new(0.0, 1.0, df).map_or(f64::NAN, |d| 2.0 * d.sf(t.abs()));
    (r, p)
}

/// Holm's step-down adjustment of `p` (Holm 1979, Scand. J. Statist. 6, 65–70), in the given
/// order: with the m p-values sorted, p₍ᵢ₎ becomes max over j ≤ i of min(1, (m − j + 1)·p₍ⱼ₎).
/// Rejecting where the adjusted value is below α keeps the family-wise error rate at α for any
/// dependence between the tests. A p-value that is not a number counts as 1.
pub fn holm(p: &[f64]) -> Vec<f64> {
    let m = p.len();
    let clean: Vec<f64> = p
        .iter()
        .map(|&x| if x.is_nan() { 1.0 } else { x.clamp(0.0, 1.0) })
        .collect();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&a, &b| clean[a].total_cmp(&clean[b]));
    let mut out = vec![1.0; m];
    let mut running: f64 = 0.0;
    for (j, &i) in order.iter().enumerate() {
        running = running.max(((m - j) as f64 * clean[i]).min(1.0));
        out[i] = running;
    }
    out
}

/// Mean of `v` with its one-sample t-test against 0: (mean, standard error, two-sided p).
pub fn mean_test(v: &[f64]) -> (f64, f64, f64) {
    let n = v.len();
    if n == 0 {
        return (f64::NAN, f64::NAN, f64::NAN);
    }
    let m = v.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return (m, f64::NAN, f64::NAN);
    }
    let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1) as f64;
    let se = (var / n as f64).sqrt();
    if !(se > 0.0) {
        return (m, se, if m == 0.0 { 1.0 } else { 0.0 });
    }
    let t = m / se;
    let p = StudentsT::new(0.0, 1.0, (n - 1) as f64).map_or(f64::NAN, |d| 2.0 * d.sf(t.abs()));
    (m, se, p)
}

/// Ordinary least-squares straight line y = a + b·x with the inference a statistician reports:
/// Student-t 95 % intervals of intercept and slope, R², and the F-test of a zero slope
/// (the line against the mean alone; F(1, n − 2), equal to the slope's t²). Assumptions: the
/// x are fixed, the errors independent, Gaussian, of constant variance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearFit {
    /// Points.
    pub n: usize,
    /// Intercept a.
    pub intercept: f64,
    /// Its 95 % interval.
    pub intercept_ci: [f64; 2],
    /// Slope b.
    pub slope: f64,
    /// Its 95 % interval.
    pub slope_ci: [f64; 2],
    /// Coefficient of determination.
    pub r2: f64,
    /// Residual sum of squares.
    pub ssr: f64,
    /// The F-test of b = 0 (mean-only model against the line).
    pub zero_slope: FTest,
}

/// Fit a straight line (needs 3 or more points and two distinct x); `None` otherwise.
pub fn linear_fit(x: &[f64], y: &[f64]) -> Option<LinearFit> {
    let n = x.len().min(y.len());
    if n < 3 {
        return None;
    }
    let nf = n as f64;
    let mx = x[..n].iter().sum::<f64>() / nf;
    let my = y[..n].iter().sum::<f64>() / nf;
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for i in 0..n {
        let (a, b) = (x[i] - mx, y[i] - my);
        sxx += a * a;
        sxy += a * b;
        syy += b * b;
    }
    if !(sxx > 0.0) || !syy.is_finite() {
        return None;
    }
    let slope = sxy / sxx;
    let intercept = my - slope * mx;
    let ssr: f64 = (0..n)
        .map(|i| (y[i] - intercept - slope * x[i]).powi(2))
        .sum();
    let df = nf - 2.0;
    let s2 = ssr / df;
    let se_b = (s2 / sxx).sqrt();
    let se_a = (s2 * (1.0 / nf + mx * mx / sxx)).sqrt();
    let t = StudentsT::new(0.0, 1.0, df).map_or(f64::NAN, |d| d.inverse_cdf(0.975));
    Some(LinearFit {
        n,
        intercept,
        intercept_ci: [intercept - t * se_a, intercept + t * se_a],
        slope,
        slope_ci: [slope - t * se_b, slope + t * se_b],
        r2: if syy > 0.0 { 1.0 - ssr / syy } else { f64::NAN },
        ssr,
        zero_slope: extra_ss_f_test(syy, n - 1, ssr, n - 2),
    })
}

/// Residual sum of squares of the least-squares polynomial of `degree` through (x, y), by a QR
/// solve of the Vandermonde system in centred, scaled x; `None` with fewer than degree + 2 points.
pub fn polynomial_ssr(x: &[f64], y: &[f64], degree: usize) -> Option<f64> {
    let n = x.len().min(y.len());
    if n < degree + 2 {
        return None;
    }
    let mx = x[..n].iter().sum::<f64>() / n as f64;
    let sx = x[..n].iter().map(|v| (v - mx).abs()).fold(0.0, f64::max);
    if !(sx > 0.0) {
        return None;
    }
    let a = nalgebra::DMatrix::from_fn(n, degree + 1, |i, j| ((x[i] - mx) / sx).powi(j as i32));
    let b = nalgebra::DVector::from_column_slice(&y[..n]);
    let coef = a.clone().svd(true, true).solve(&b, 1e-12).ok()?;
    let r = b - a * coef;
    Some(r.norm_squared())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn holm_adjusts_as_worked_by_hand() {
        // m = 4, sorted 0.005, 0.01, 0.03, 0.04: 4·0.005 = 0.02, 3·0.01 = 0.03, 2·0.03 = 0.06,
        // 1·0.04 = 0.04 raised to the running maximum 0.06 (Holm 1979's step-down rule)
        let a = holm(&[0.01, 0.04, 0.03, 0.005]);
        for (x, y) in a.iter().zip([0.03, 0.06, 0.06, 0.02]) {
            assert!((x - y).abs() < 1e-15, "{a:?}");
        }
        // capped at 1; a NaN counts as 1; one test is not adjusted
        assert_eq!(holm(&[0.5, 0.6, f64::NAN]), vec![1.0, 1.0, 1.0]);
        assert_eq!(holm(&[0.003]), vec![0.003]);
    }

    #[test]
    fn a_constant_covariate_has_no_correlation() {
        // 453 equal values whose mean is not exactly representable leave a rounding-level
        // spread; the correlation is undefined, not r = 0, p = 1
        let x = vec![1.6e-3; 453];
        let y: Vec<f64> = (0..453).map(|i| (i as f64 * 0.7).sin()).collect();
        let (r, p) = correlation(&x, &y);
        assert!(r.is_nan() && p.is_nan(), "{r} {p}");
        // a real spread still correlates: y = 2x exactly gives r = 1
        let x: Vec<f64> = (0..10).map(|i| 1.0 + i as f64 * 1e-6).collect();
        let y: Vec<f64> = x.iter().map(|v| 2.0 * v).collect();
        assert!((correlation(&x, &y).0 - 1.0).abs() < 1e-9);
    }

    #[test]
    fn f_test_against_tables() {
        // F(1, 10) upper 5 % point is 4.9646 (standard F tables): p must be 0.05 there.
        let t = extra_ss_f_test(10.0 + 4.9646, 11, 10.0, 10);
        assert!((t.f - 4.9646).abs() < 1e-9);
        assert!((t.p_value - 0.05).abs() < 2e-5, "{}", t.p_value);
        // F(2, 20) upper 1 % point is 5.8489
        let t = extra_ss_f_test(20.0 + 2.0 * 5.8489, 22, 20.0, 20);
        assert!((t.p_value - 0.01).abs() < 2e-5, "{}", t.p_value);
        // no improvement: p = 1
        assert_eq!(extra_ss_f_test(5.0, 10, 5.0, 9).p_value, 1.0);
    }

    #[test]
    fn aicc_by_hand() {
        // n = 10, SSR = 2, p = 1 → K = 2: 10 ln 0.2 + 4 + 12/7
        let want = 10.0 * (0.2f64).ln() + 4.0 + 12.0 / 7.0;
        assert!((aicc(2.0, 10, 1) - want).abs() < 1e-12);
    }

    #[test]
    fn runs_test_by_hand() {
        // + + - - + + - - (n+ = n- = 4, 4 runs): E = 5, Var = 2·16·(32 − 8)/(64·7) = 12/7
        let r = runs_test(&[1.0, 1.0, -1.0, -1.0, 1.0, 1.0, -1.0, -1.0]);
        assert_eq!(r.runs, 4);
        assert!((r.expected - 5.0).abs() < 1e-12);
        assert!((r.z - (-1.0 / (12.0f64 / 7.0).sqrt())).abs() < 1e-12);
        // all positives then all negatives: 2 runs of 20, strongly non-random
        let mut v = vec![1.0; 20];
        v.extend(vec![-1.0; 20]);
        assert!(runs_test(&v).p_value < 1e-6);
    }

    #[test]
    fn linear_fit_by_hand() {
        // x = 1..5, y = (1, 3, 2, 5, 4): Sxx = 10, Sxy = 8, Syy = 10 → b = 0.8, a = 0.6,
        // SSR = Syy − b·Sxy = 3.6, R² = 0.64, s² = 1.2, se(b) = √0.12 = 0.34641;
        // t₀.₉₇₅,₃ = 3.182446 (t tables) → b ± 1.10242; F = t² = (0.8/0.34641)² = 5.3333 with
        // p = 0.1041 (the same test as the correlation's t above).
        let f = linear_fit(&[1.0, 2.0, 3.0, 4.0, 5.0], &[1.0, 3.0, 2.0, 5.0, 4.0]).unwrap();
        assert!((f.slope - 0.8).abs() < 1e-12 && (f.intercept - 0.6).abs() < 1e-12);
        assert!((f.r2 - 0.64).abs() < 1e-12 && (f.ssr - 3.6).abs() < 1e-12);
        assert!((f.slope_ci[1] - (0.8 + 3.182446 * 0.12f64.sqrt())).abs() < 1e-5);
        assert!((f.zero_slope.f - 16.0 / 3.0).abs() < 1e-9);
        assert!((f.zero_slope.p_value - 0.1041).abs() < 5e-4);
        // a parabola: the quadratic leaves nothing, the line leaves something
        let x = [0.0, 1.0, 2.0, 3.0, 4.0];
        let y: Vec<f64> = x.iter().map(|v| 1.0 + v * v).collect();
        assert!(polynomial_ssr(&x, &y, 2).unwrap() < 1e-20);
        assert!(
            (polynomial_ssr(&x, &y, 1).unwrap() - linear_fit(&x, &y).unwrap().ssr).abs() < 1e-9
        );
    }

    #[test]
    fn correlation_and_mean() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        let (r, p) = correlation(&x, &[2.0, 4.0, 6.0, 8.0, 10.0]);
        assert!((r - 1.0).abs() < 1e-12 && p == 0.0);
        // r = 0.8 with n = 5: t = 0.8·√(3/0.36) = 2.3094, two-sided p = 0.1041 (t tables, 3 df)
        let y = [1.0, 3.0, 2.0, 5.0, 4.0];
        let (r, p) = correlation(&x, &y);
        assert!((r - 0.8).abs() < 1e-12);
        assert!((p - 0.1041).abs() < 5e-4, "{p}");
        let (m, _, p) = mean_test(&[1.0, 1.1, 0.9, 1.05, 0.95]);
        assert!((m - 1.0).abs() < 1e-12 && p < 1e-4);
    }
}
