//! Model comparison and residual tests, each with its assumptions:
//! - the extra sum-of-squares F-test between nested least-squares models (the paper's test,
//!   Fig. 5; Motulsky & Christopoulos, *Fitting models to biological data*, ch. 22):
//!   F = ((SSR₀ − SSR₁)/(df₀ − df₁)) / (SSR₁/df₁), F(df₀ − df₁, df₁) under H₀ that the simpler
//!   model is true, with independent Gaussian errors of the given relative weights;
//! - AICc = n·ln(SSR/n) + 2K + 2K(K + 1)/(n − K − 1), K = parameters + 1 (the variance)
//!   (Burnham & Anderson 2002, eq. 2.5 with the least-squares likelihood);
//! - the Wald–Wolfowitz runs test on residual signs (two-sided; the exact conditional
//!   distribution of the runs given the signs' counts while the rarer sign has at most 20
//!   residuals, the normal approximation with continuity correction above; Wald & Wolfowitz
//!   1940, Bradley 1968), which detects systematic misfit along time without assuming a form
//!   for it, and the sign test in its place when every residual has one sign;
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

/// How a [`RunsTest`]'s p-value was computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunsMethod {
    /// The exact conditional distribution of the number of runs given n₊ and n₋ (Wald &
    /// Wolfowitz 1940; Swed & Eisenhart 1943), used when min(n₊, n₋) ≤
    /// [`EXACT_RUNS_MAX_MINORITY`].
    Exact,
    /// The normal approximation with a continuity correction of ½ run, used when both signs
    /// number more than [`EXACT_RUNS_MAX_MINORITY`].
    Normal,
    /// Every residual has one sign: the runs test is degenerate (one run, nothing to compare),
    /// and the two-sided sign test of n residuals all of one sign, p = min(1, 2·0.5ⁿ), stands in
    /// its place.
    SignTest,
    /// No nonzero finite residual: nothing to test (p is NaN).
    NoData,
}

impl RunsMethod {
    /// How the method is named in reports.
    pub fn name(self) -> &'static str {
        match self {
            RunsMethod::Exact => "exact",
            RunsMethod::Normal => "normal approximation",
            RunsMethod::SignTest => "sign test",
            RunsMethod::NoData => "no residual",
        }
    }
}

/// The exact distribution is used while the rarer sign has at most this many residuals (the
/// range of Swed & Eisenhart's 1943 tables; a lone or rare sign is where the normal
/// approximation fails); above it the normal approximation with continuity correction is used,
/// which agrees with the exact p to within 0.01 at n₊ = n₋ = 30 (tested).
pub const EXACT_RUNS_MAX_MINORITY: usize = 20;

/// Wald–Wolfowitz runs test on the signs of `residuals` (zeros and non-finite values dropped).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunsTest {
    /// Runs observed.
    pub runs: usize,
    /// Positive residuals, n₊.
    pub n_plus: usize,
    /// Negative residuals, n₋.
    pub n_minus: usize,
    /// Runs expected under randomness, 1 + 2n₊n₋/n.
    pub expected: f64,
    /// Standardized statistic (R − E)/sd, without continuity correction; NaN where the variance
    /// is 0 (fewer than one residual of either sign, or n₊ = n₋ = 1).
    pub z: f64,
    /// Two-sided p-value by `method`: 2·min(P(R ≤ r), P(R ≥ r)), capped at 1, for the runs
    /// test; the sign test's p when every residual has one sign; NaN without residuals.
    pub p_value: f64,
    /// How `p_value` was computed.
    pub method: RunsMethod,
}

impl RunsTest {
    /// Whether the signs cluster (fewer runs than expected under randomness, or every residual
    /// of one sign): the direction of a systematic misfit, rather than of alternating signs.
    pub fn clustered(&self) -> bool {
        match self.method {
            RunsMethod::SignTest => true,
            RunsMethod::NoData => false,
            _ => (self.runs as f64) < self.expected,
        }
    }
}

/// ln C(a, b), −∞ when b > a (no such choice).
fn ln_choose(a: usize, b: usize) -> f64 {
    use statrs::function::gamma::ln_gamma;
    if b > a {
        return f64::NEG_INFINITY;
    }
    ln_gamma(a as f64 + 1.0) - ln_gamma(b as f64 + 1.0) - ln_gamma((a - b) as f64 + 1.0)
}

/// P(R = r) for the number of runs R in a random arrangement of `n_plus` positive and
/// `n_minus` negative signs (both ≥ 1), all C(n, n₊) arrangements equally likely (Wald &
/// Wolfowitz 1940): P(R = 2k) = 2·C(n₊−1, k−1)·C(n₋−1, k−1)/C(n, n₊) and P(R = 2k+1) =
/// [C(n₊−1, k−1)·C(n₋−1, k) + C(n₊−1, k)·C(n₋−1, k−1)]/C(n, n₊), in log space (ln Γ).
pub fn runs_pmf(n_plus: usize, n_minus: usize, r: usize) -> f64 {
    if n_plus == 0 || n_minus == 0 {
        // one run, with certainty
        return if r == 1 { 1.0 } else { 0.0 };
    }
    if r < 2 {
        return 0.0;
    }
    let total = ln_choose(n_plus + n_minus, n_plus);
    let (a, b) = (n_plus - 1, n_minus - 1);
    let k = r / 2;
    let term = |x: f64| (x - total).exp();
    if r.is_multiple_of(2) {
        2.0 * term(ln_choose(a, k - 1) + ln_choose(b, k - 1))
    } else {
        term(ln_choose(a, k - 1) + ln_choose(b, k)) + term(ln_choose(a, k) + ln_choose(b, k - 1))
    }
}

/// The exact two-sided p-value of `runs` runs given n₊ and n₋ (both ≥ 1):
/// min(1, 2·min(P(R ≤ runs), P(R ≥ runs))), each tail summed from [`runs_pmf`].
pub fn runs_exact_p(n_plus: usize, n_minus: usize, runs: usize) -> f64 {
    let most = 2 * n_plus.min(n_minus) + usize::from(n_plus != n_minus);
    let lower: f64 = (1..=runs.min(most))
        .map(|r| runs_pmf(n_plus, n_minus, r))
        .sum();
    let upper: f64 = (runs.max(1)..=most)
        .map(|r| runs_pmf(n_plus, n_minus, r))
        .sum();
    (2.0 * lower.min(upper)).min(1.0)
}

/// Mean and variance of the number of runs given n₊ and n₋ (Wald & Wolfowitz 1940):
/// E = 1 + 2n₊n₋/n, Var = 2n₊n₋(2n₊n₋ − n)/(n²(n − 1)).
fn runs_moments(n_plus: usize, n_minus: usize) -> (f64, f64) {
    let (np, nm) = (n_plus as f64, n_minus as f64);
    let n = np + nm;
    let expected = 1.0 + 2.0 * np * nm / n.max(1.0);
    let var = if n > 1.0 {
        2.0 * np * nm * (2.0 * np * nm - n) / (n * n * (n - 1.0))
    } else {
        0.0
    };
    (expected, var)
}

/// The normal approximation's two-sided p-value of `runs` runs given n₊ and n₋, with a
/// continuity correction of ½ run toward the mean: 2·P(Z ≥ max(|r − E| − ½, 0)/sd).
pub fn runs_normal_p(n_plus: usize, n_minus: usize, runs: usize) -> f64 {
    let (expected, var) = runs_moments(n_plus, n_minus);
    if !(var > 0.0) {
        return f64::NAN;
    }
    let d = ((runs as f64 - expected).abs() - 0.5).max(0.0);
    (2.0 * normal_sf(d / var.sqrt())).min(1.0)
}

/// The runs test (two-sided) of the residuals' signs, zeros and non-finite values dropped: exact
/// while the rarer sign has at most [`EXACT_RUNS_MAX_MINORITY`] residuals, the normal
/// approximation above; the sign test when every residual has one sign ([`RunsMethod`]).
pub fn runs_test(residuals: &[f64]) -> RunsTest {
    let signs: Vec<bool> = residuals
        .iter()
        .filter(|r| **r != 0.0 && r.is_finite())
        .map(|r| *r > 0.0)
        .collect();
    let n_plus = signs.iter().filter(|s| **s).count();
    let n_minus = signs.len() - n_plus;
    let runs = if signs.is_empty() {
        0
    } else {
        1 + signs.windows(2).filter(|w| w[0] != w[1]).count()
    };
    let (expected, var) = runs_moments(n_plus, n_minus);
    let z = if var > 0.0 {
        (runs as f64 - expected) / var.sqrt()
    } else {
        f64::NAN
    };
    let (p_value, method) = if signs.is_empty() {
        (f64::NAN, RunsMethod::NoData)
    } else if n_plus == 0 || n_minus == 0 {
        let n = signs.len() as i32;
        ((2.0 * 0.5f64.powi(n)).min(1.0), RunsMethod::SignTest)
    } else if n_plus.min(n_minus) <= EXACT_RUNS_MAX_MINORITY {
        (runs_exact_p(n_plus, n_minus, runs), RunsMethod::Exact)
    } else {
        (runs_normal_p(n_plus, n_minus, runs), RunsMethod::Normal)
    };
    RunsTest {
        runs,
        n_plus,
        n_minus,
        expected,
        z,
        p_value,
        method,
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

/// Whether a sum of squares about the mean `ss` of `n` values with mean `m` is no spread at
/// all: a spread at the rounding level of the mean is a constant (453 equal distances leave
/// Σ(x − x̄)² ≈ 4e-32 from rounding alone).
fn flat(ss: f64, m: f64, n: usize) -> bool {
    !(ss > n as f64 * (1e-12 * m.abs()).powi(2))
}

/// Whether the values of `v` are one constant up to rounding (the test [`correlation`] applies
/// before it reports a correlation); true for no values.
pub fn is_constant(v: &[f64]) -> bool {
    let n = v.len();
    if n == 0 {
        return true;
    }
    let m = v.iter().sum::<f64>() / n as f64;
    flat(v.iter().map(|x| (x - m).powi(2)).sum(), m, n)
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
    if flat(sxx, mx, n) || flat(syy, my, n) {
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

    /// The distribution of the number of runs by brute force: every one of the C(n, n₊)
    /// arrangements of n₊ positive and n₋ negative signs (bit masks with n₊ bits set), its runs
    /// counted; returns P(R = r) for r = 0..=n. Independent of [`runs_pmf`]'s formula.
    fn enumerated_runs(n_plus: usize, n_minus: usize) -> Vec<f64> {
        let n = n_plus + n_minus;
        let mut counts = vec![0u64; n + 1];
        let mut total = 0u64;
        for mask in 0u32..(1u32 << n) {
            if mask.count_ones() as usize != n_plus {
                continue;
            }
            let bit = |i: usize| (mask >> i) & 1;
            let runs = 1 + (1..n).filter(|&i| bit(i) != bit(i - 1)).count();
            counts[runs] += 1;
            total += 1;
        }
        counts.iter().map(|&c| c as f64 / total as f64).collect()
    }

    #[test]
    fn exact_runs_distribution_sums_to_one() {
        for (a, b) in [
            (1, 1),
            (1, 7),
            (2, 2),
            (3, 5),
            (10, 10),
            (20, 45),
            (50, 3),
            (60, 60),
        ] {
            let most = 2 * a.min(b) + 1;
            let s: f64 = (0..=most).map(|r| runs_pmf(a, b, r)).sum();
            assert!((s - 1.0).abs() < 1e-12, "n₊ = {a}, n₋ = {b}: Σ P = {s}");
            // and no mass outside 2..=2·min + (1 if unequal)
            assert_eq!(runs_pmf(a, b, 1), 0.0);
            if a == b {
                assert_eq!(runs_pmf(a, b, 2 * a + 1), 0.0);
            }
        }
    }

    #[test]
    fn exact_runs_p_matches_enumeration_of_every_arrangement() {
        // n₊ = n₋ = 2 by hand: ++−−, −−++ (2 runs), +−−+, −++− (3 runs), +−+−, −+−+ (4 runs):
        // P(R = 2) = P(R = 3) = P(R = 4) = 1/3, so p(2) = 2/3 and p(3) = 1 (capped)
        for r in 2..=4 {
            assert!((runs_pmf(2, 2, r) - 1.0 / 3.0).abs() < 1e-14);
        }
        assert!((runs_exact_p(2, 2, 2) - 2.0 / 3.0).abs() < 1e-14);
        assert_eq!(runs_exact_p(2, 2, 3), 1.0);
        // every (n₊, n₋) with n ≤ 12, every attainable run count: pmf and two-sided p against
        // the distribution enumerated in this test
        for n in 2..=12 {
            for a in 1..n {
                let b = n - a;
                let dist = enumerated_runs(a, b);
                for r in 0..=n {
                    assert!(
                        (runs_pmf(a, b, r) - dist[r]).abs() < 1e-12,
                        "P(R = {r} | {a}, {b})"
                    );
                    if dist[r] == 0.0 {
                        continue;
                    }
                    let lower: f64 = dist[..=r].iter().sum();
                    let upper: f64 = dist[r..].iter().sum();
                    let want = (2.0 * lower.min(upper)).min(1.0);
                    let got = runs_exact_p(a, b, r);
                    assert!(
                        (got - want).abs() < 1e-12,
                        "p({r} | {a}, {b}) = {got}, by enumeration {want}"
                    );
                }
            }
        }
        // a lone positive among 60 negatives at an end of the series (2 runs): it sits at an end
        // in 2 of its 61 places (by hand from Wald & Wolfowitz's formula), p = 2·2/61
        let mut v = vec![-1.0; 60];
        v.push(1.0);
        let t = runs_test(&v);
        assert_eq!((t.runs, t.n_plus, t.n_minus), (2, 1, 60));
        assert_eq!(t.method, RunsMethod::Exact);
        assert!((t.p_value - 4.0 / 61.0).abs() < 1e-12, "{}", t.p_value);
        assert!(t.clustered());
    }

    #[test]
    fn normal_approximation_agrees_with_the_exact_runs_p_at_30_and_30() {
        // E = 31, sd = 3.84 (Wald & Wolfowitz 1940's moments); the exact p is the reference,
        // from [`runs_pmf`] checked against enumeration above
        for r in [20, 24, 27, 29, 31, 34, 37, 42] {
            let (e, x) = (runs_normal_p(30, 30, r), runs_exact_p(30, 30, r));
            assert!((e - x).abs() < 0.01, "R = {r}: normal {e}, exact {x}");
        }
        // the test switches to the approximation above 20 of the rarer sign
        let v: Vec<f64> = (0..60)
            .map(|i| if i % 4 < 2 { 1.0 } else { -1.0 })
            .collect();
        let t = runs_test(&v);
        assert_eq!((t.n_plus, t.n_minus, t.runs), (30, 30, 30));
        assert_eq!(t.method, RunsMethod::Normal);
        assert_eq!(t.p_value, runs_normal_p(30, 30, 30));
    }

    #[test]
    fn residuals_all_of_one_sign_get_the_sign_test() {
        // the two-sided sign test of n residuals all of one sign: p = 2·0.5ⁿ (binomial(n, ½)
        // tails, by hand), capped at 1; zeros and non-finite values are dropped first
        let t = runs_test(&[1.0, 2.0, 0.0, 3.0, 4.0, f64::NAN, 5.0]);
        assert_eq!(t.method, RunsMethod::SignTest);
        assert_eq!((t.runs, t.n_plus, t.n_minus), (1, 5, 0));
        assert!((t.p_value - 0.0625).abs() < 1e-15);
        assert!(t.clustered());
        let t = runs_test(&vec![-2e-6; 61]);
        assert_eq!(t.method, RunsMethod::SignTest);
        assert!((t.p_value - 2.0 * 0.5f64.powi(61)).abs() < 1e-30);
        assert_eq!(runs_test(&[-1.0]).p_value, 1.0);
        let t = runs_test(&[0.0, 0.0]);
        assert_eq!(t.method, RunsMethod::NoData);
        assert!(t.p_value.is_nan() && !t.clustered());
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
