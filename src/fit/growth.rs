//! The paper's growth metrics (§4.2, electronic supplementary Fig. S4): a bubble's radius–time
//! curve fitted by nonlinear regression to the exponential approach to a plateau
//!
//!   R(t) = R_p − (R_p − R_0)·e^{−k(t − t₀)},
//!
//! giving the plateau radius R_p and the half-life ln 2 / k, each with a 95 % interval; and the
//! extra sum-of-squares F-test of whether two curves (measured and simulated, or two
//! conditions) share one set of parameters — the comparison of the paper's Fig. 5.

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
    })
}

/// Whether two curves share one set of growth parameters: the extra sum-of-squares F-test of
/// one curve fitted to both data sets (3 parameters) against one curve each (6 parameters).
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
    }
}
