//! The paper's growth metrics (§4.2, electronic supplementary Fig. S4): a bubble's radius–time
//! curve fitted by nonlinear regression to the exponential approach to a plateau
//!
//!   R(t) = R_p − (R_p − R_0)·e^{−k(t − t₀)},
//!
//! giving the plateau radius R_p and the half-life ln 2 / k, each with a 95 % interval; and two
//! extra sum-of-squares F-tests for the comparison of the paper's Fig. 5:
//! - [`compare_to_curve`], measured radii against a simulated curve: the simulation has no
//!   noise, so its fitted curve is a fully specified hypothesis, H₀: the measured series follows
//!   it; F = ((SSR₀ − SSR₁)/3)/(SSR₁/(n − 3)) on F(3, n − 3), SSR₀ about the simulated curve,
//!   SSR₁ about the measured series' own fit;
//! - [`compare_growth`], two measured series (two conditions): one curve for both (3
//!   parameters) against one each (6), F(3, n_a + n_b − 6).
//!
//! Both assume independent Gaussian errors of constant variance (or of the given relative
//! weights), and are exact only for a model linear in its parameters; the growth curve is
//! nonlinear in k, so they are approximate (measured: at 10 points and 1 µm noise a nominal
//! 5 % test of [`compare_to_curve`] rejects at its nominal rate; see the tests).

use super::lsq::{infer, minimize, LsqOptions};
use super::paths::ParamSpec;
use super::stats::{extra_ss_f_test, FTest};
use crate::error::Error;

/// A growth fit.
#[derive(Debug, Clone, PartialEq)]
pub struct GrowthFit {
    /// Plateau radius R_p, m.
    pub plateau: f64,
    /// Its 95 % interval, m.
    pub plateau_ci: [f64; 2],
    /// Fitted starting radius R_0, m.
    pub start: f64,
    /// Rate k, 1/s.
    pub rate: f64,
    /// Half-life ln 2 / k, s.
    pub half_life: f64,
    /// Its 95 % interval, s (from k's interval).
    pub half_life_ci: [f64; 2],
    /// Residual sum of squares (weighted as given), m².
    pub ssr: f64,
    /// Points fitted.
    pub n: usize,
    /// LM converged.
    pub converged: bool,
    /// The time origin t₀ of the curve (the first point's time), s.
    pub origin: f64,
}

impl GrowthFit {
    /// The fitted curve's radius at time `t`, m.
    pub fn radius_at(&self, t: f64) -> f64 {
        self.plateau - (self.plateau - self.start) * (-self.rate * (t - self.origin)).exp()
    }
}

fn specs(r_first: f64, r_last: f64, span: f64) -> Vec<ParamSpec> {
    let free = |p: &str, s: f64| ParamSpec {
        path: p.into(),
        lower: None,
        upper: None,
        log: false,
        start: s,
    };
    vec![
        free("plateau", r_last),
        free("start", r_first),
        ParamSpec::positive("rate", 3.0 / span.max(1e-9)),
    ]
}

fn curve(u: &[f64], sp: &[ParamSpec], t: f64) -> f64 {
    let (rp, r0, k) = (
        sp[0].from_internal(u[0]),
        sp[1].from_internal(u[1]),
        sp[2].from_internal(u[2]),
    );
    rp - (rp - r0) * (-k * t).exp()
}

/// Fit the growth curve to points (t, R) with optional weights (1/sd²); times are taken from
/// the first point. Needs at least 4 points.
pub fn fit_growth(points: &[(f64, f64)], weights: Option<&[f64]>) -> Result<GrowthFit, Error> {
    if points.len() < 4 {
        return Err(Error::Solver(format!(
            "a growth fit needs at least 4 points (got {})",
            points.len()
        )));
    }
    let t0 = points[0].0;
    let span = points.last().map_or(1.0, |p| p.0) - t0;
    let sp = specs(points[0].1, points.last().map_or(0.0, |p| p.1), span);
    let w = |i: usize| weights.map_or(1.0, |w| w[i].sqrt());
    let model = |u: &[f64]| -> Result<Vec<f64>, Error> {
        Ok(points
            .iter()
            .enumerate()
            .map(|(i, (t, r))| w(i) * (r - curve(u, &sp, t - t0)))
            .collect())
    };
    let u0: Vec<f64> = sp.iter().map(|s| s.to_internal(s.start)).collect();
    let opts = LsqOptions {
        fd_step: 1e-7,
        ftol: 1e-12,
        xtol: 1e-10,
        patience: 200,
    };
    let fit = minimize(&model, &u0, &opts)?;
    let inf = infer(&fit, &sp);
    let (rp, k) = (&inf.estimates[0], &inf.estimates[2]);
    let ln2 = std::f64::consts::LN_2;
    Ok(GrowthFit {
        plateau: rp.value,
        plateau_ci: rp.ci95,
        start: inf.estimates[1].value,
        rate: k.value,
        half_life: ln2 / k.value,
        half_life_ci: [ln2 / k.ci95[1], ln2 / k.ci95[0]],
        ssr: fit.ssr,
        n: points.len(),
        converged: fit.converged,
        origin: t0,
    })
}

/// Whether the measured points (t, R) follow the simulated growth curve `simulated`: the extra
/// sum-of-squares F-test of the fixed curve (no parameter estimated from these points) against
/// the points' own fit (3 parameters), on F(3, n − 3); `weights` (1/sd², or none) weight both
/// sums alike. The module's text gives the assumptions.
pub fn compare_to_curve(
    measured: &[(f64, f64)],
    weights: Option<&[f64]>,
    simulated: &GrowthFit,
) -> Result<FTest, Error> {
    let own = fit_growth(measured, weights)?;
    let w = |i: usize| weights.map_or(1.0, |w| w[i]);
    let ssr0: f64 = measured
        .iter()
        .enumerate()
        .map(|(i, (t, r))| w(i) * (r - simulated.radius_at(*t)).powi(2))
        .sum();
    let n = measured.len();
    // the own fit can only be better; an optimiser that stopped short is not evidence against
    // the simulated curve
    Ok(extra_ss_f_test(ssr0, n, own.ssr.min(ssr0), n - 3))
}

/// Whether two measured curves share one set of growth parameters: the extra sum-of-squares
/// F-test of one curve fitted to both data sets (3 parameters) against one curve each (6
/// parameters). Both series carry noise; for a measured series against a simulated one use
/// [`compare_to_curve`] (pooling a noise-free series into the error's degrees of freedom makes
/// this test reject too often: 8.5 % at a nominal 5 % with 10 points per series).
pub fn compare_growth(a: &[(f64, f64)], b: &[(f64, f64)]) -> Result<FTest, Error> {
    let fa = fit_growth(a, None)?;
    let fb = fit_growth(b, None)?;
    // the shared fit needs a common time origin: both curves from their own first point
    let ta = a[0].0;
    let tb = b[0].0;
    let mut both: Vec<(f64, f64)> = a.iter().map(|(t, r)| (t - ta, *r)).collect();
    both.extend(b.iter().map(|(t, r)| (t - tb, *r)));
    let idx_sorted = {
        let mut v = both.clone();
        v.sort_by(|x, y| x.0.total_cmp(&y.0));
        v
    };
    // fit_growth takes t₀ from the first point: with both series starting at 0 that is 0
    let shared = fit_growth(&idx_sorted, None)?;
    let n = a.len() + b.len();
    Ok(extra_ss_f_test(shared.ssr, n - 3, fa.ssr + fb.ssr, n - 6))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_an_exact_curve() {
        // R = 300 − 200·e^{−t/120} µm: plateau 300 µm, half-life 120·ln 2 = 83.18 s
        let pts: Vec<(f64, f64)> = (0..40)
            .map(|i| {
                let t = i as f64 * 10.0;
                (t, (300.0 - 200.0 * (-t / 120.0).exp()) * 1e-6)
            })
            .collect();
        let g = fit_growth(&pts, None).unwrap();
        assert!((g.plateau / 300e-6 - 1.0).abs() < 1e-6, "{}", g.plateau);
        assert!((g.half_life / (120.0 * std::f64::consts::LN_2) - 1.0).abs() < 1e-5);
        // the same curve twice: no evidence of a difference
        let t = compare_growth(&pts, &pts).unwrap();
        assert!(t.p_value > 0.5 || t.f.is_nan(), "{t:?}");
        // the curve evaluates to the points it was fitted to
        assert!(
            (g.radius_at(250.0) / ((300.0 - 200.0 * (-250.0f64 / 120.0).exp()) * 1e-6) - 1.0).abs()
                < 1e-6
        );
    }

    /// The measured-against-simulated test holds its nominal size. Data: a known curve
    /// (R_p = 300 µm, R_0 = 100 µm, k = 1/120 s⁻¹) at 10 times, plus Gaussian noise of 1 µm
    /// (ChaCha8, seed 13); the simulated curve is that exact curve. Under H₀ the statistic is
    /// F(3, 7) up to the curve's nonlinearity, so a 5 % test rejects in 5 % of 1 000
    /// replicates: the binomial standard error is 0.69 %, and the bounds 2.5–7.5 % are 3.6 of it.
    /// The earlier pooled test (the simulated series as a second noisy one, F(3, 14)) rejects
    /// about 8.5 % (exact F probabilities, the review of 27 Nov 2026), outside the bounds.
    #[test]
    fn a_measured_series_against_its_true_curve_rejects_at_the_nominal_rate() {
        use crate::fit::stats::standard_normal;
        use rand::SeedableRng;
        let truth = GrowthFit {
            plateau: 300e-6,
            plateau_ci: [0.0; 2],
            start: 100e-6,
            rate: 1.0 / 120.0,
            half_life: 120.0 * std::f64::consts::LN_2,
            half_life_ci: [0.0; 2],
            ssr: 0.0,
            n: 10,
            converged: true,
            origin: 0.0,
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        let reps = 1000;
        let mut rejected = 0;
        let mut pooled_rejected = 0;
        for _ in 0..reps {
            let m: Vec<(f64, f64)> = (0..10)
                .map(|i| {
                    let t = i as f64 * 40.0;
                    (t, truth.radius_at(t) + 1e-6 * standard_normal(&mut rng))
                })
                .collect();
            if compare_to_curve(&m, None, &truth).unwrap().p_value < 0.05 {
                rejected += 1;
            }
            let sim: Vec<(f64, f64)> = m.iter().map(|(t, _)| (*t, truth.radius_at(*t))).collect();
            if compare_growth(&m, &sim).unwrap().p_value < 0.05 {
                pooled_rejected += 1;
            }
        }
        let rate = rejected as f64 / reps as f64;
        assert!((0.025..=0.075).contains(&rate), "size {rate}");
        // the pooled test, for the record of why it is not used against a simulation
        let pooled = pooled_rejected as f64 / reps as f64;
        eprintln!("rejected at 5 %: {rate} against the simulated curve, {pooled} pooled");
        assert!(pooled > rate, "pooled {pooled} against {rate}");
    }

    /// A measured series from another curve (plateau 10 % higher) is told apart.
    #[test]
    fn a_measured_series_off_the_simulated_curve_is_rejected() {
        let sim = fit_growth(
            &(0..10)
                .map(|i| {
                    let t = i as f64 * 40.0;
                    (t, (300.0 - 200.0 * (-t / 120.0).exp()) * 1e-6)
                })
                .collect::<Vec<_>>(),
            None,
        )
        .unwrap();
        // ±1 µm of alternating noise on a curve with R_p = 330 µm
        let m: Vec<(f64, f64)> = (0..10)
            .map(|i| {
                let t = i as f64 * 40.0;
                let e = if i % 2 == 0 { 1e-6 } else { -1e-6 };
                (t, (330.0 - 230.0 * (-t / 120.0).exp()) * 1e-6 + e)
            })
            .collect();
        let t = compare_to_curve(&m, None, &sim).unwrap();
        assert!(t.p_value < 1e-6, "{t:?}");
        assert_eq!((t.df_num, t.df_den), (3, 7));
    }
}
