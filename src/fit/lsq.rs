//! Nonlinear least squares: the `levenberg-marquardt` crate (MINPACK's trust-region LM) on
//! weighted residuals, with a forward-difference Jacobian whose columns are computed in
//! parallel (each column is one more model evaluation — for the phantom, one simulation per
//! experiment), then the usual asymptotic inference from the Jacobian at the optimum:
//! s² = SSR/(n − p), Cov(v̂) = s²(JᵀJ)⁻¹ in the fitting coordinates v (ln x for positive
//! parameters), Student-t intervals v̂ ± t₀.₉₇₅,ₙ₋ₚ·se, mapped back to x (asymmetric for log
//! parameters). Assumptions, stated in every report: independent Gaussian errors with the
//! given relative weights, a model linear enough near the optimum.

use super::paths::ParamSpec;
use crate::error::Error;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use rayon::prelude::*;

/// A model to fit: weighted residuals (√w·(y − f)) for internal parameter coordinates `u`.
pub trait ResidualModel: Sync {
    /// Weighted residuals at internal coordinates `u`.
    fn residuals(&self, u: &[f64]) -> Result<Vec<f64>, Error>;
}

impl<F: Fn(&[f64]) -> Result<Vec<f64>, Error> + Sync> ResidualModel for F {
    fn residuals(&self, u: &[f64]) -> Result<Vec<f64>, Error> {
        self(u)
    }
}

/// Settings of the least-squares solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LsqOptions {
    /// Forward-difference step in the internal coordinates (for a log parameter, a relative
    /// change). Default 1e-2: adaptive time stepping makes a simulation a slightly rough function
    /// of its parameters, and a step of 1 % stays above that roughness.
    pub fd_step: f64,
    /// Relative reduction of the SSR below which the fit has converged. Default 1e-6.
    pub ftol: f64,
    /// Relative change of the parameters below which the fit has converged. Default 1e-5.
    pub xtol: f64,
    /// Largest number of Jacobian evaluations (LM's `patience` is per parameter). Default 30.
    pub patience: usize,
}

impl Default for LsqOptions {
    fn default() -> Self {
        LsqOptions {
            fd_step: 1e-2,
            ftol: 1e-6,
            xtol: 1e-5,
            patience: 30,
        }
    }
}

/// The optimum found.
#[derive(Debug, Clone)]
pub struct LsqResult {
    /// Internal coordinates at the optimum.
    pub u: Vec<f64>,
    /// Weighted residuals there.
    pub residuals: Vec<f64>,
    /// Jacobian of the weighted residuals with respect to `u` (n × p).
    pub jacobian: DMatrix<f64>,
    /// Sum of squared weighted residuals.
    pub ssr: f64,
    /// Model evaluations used.
    pub evaluations: usize,
    /// Why LM stopped.
    pub termination: String,
    /// LM reported success (converged, orthogonal or zero residuals).
    pub converged: bool,
}

/// Penalty residual for a parameter set at which the model cannot be evaluated (a solver
/// failure): large, so LM rejects the step and shrinks its trust region.
const FAILED: f64 = 1e8;

struct Problem<'a> {
    model: &'a dyn ResidualModel,
    u: DVector<f64>,
    r: Option<DVector<f64>>,
    n: usize,
    h: f64,
    evals: std::sync::atomic::AtomicUsize,
}

impl Problem<'_> {
    fn eval(&self, u: &[f64]) -> DVector<f64> {
        self.evals
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        match self.model.residuals(u) {
            Ok(r) if r.len() == self.n && r.iter().all(|x| x.is_finite()) => DVector::from_vec(r),
            _ => DVector::from_element(self.n, FAILED),
        }
    }
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.u = x.clone();
        self.r = Some(self.eval(x.as_slice()));
    }
    fn params(&self) -> DVector<f64> {
        self.u.clone()
    }
    fn residuals(&self) -> Option<DVector<f64>> {
        self.r.clone()
    }
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        let r0 = self.r.as_ref()?;
        Some(fd_jacobian(self, r0))
    }
}

fn fd_jacobian(p: &Problem<'_>, r0: &DVector<f64>) -> DMatrix<f64> {
    let np = p.u.len();
    let cols: Vec<DVector<f64>> = (0..np)
        .into_par_iter()
        .map(|j| {
            let mut u = p.u.clone();
            u[j] += p.h;
            (p.eval(u.as_slice()) - r0) / p.h
        })
        .collect();
    DMatrix::from_columns(&cols)
}

/// Minimise the sum of squared residuals of `model` from `u0`. With no parameters the model
/// is evaluated once.
pub fn minimize(
    model: &dyn ResidualModel,
    u0: &[f64],
    opts: &LsqOptions,
) -> Result<LsqResult, Error> {
    let r0 = model.residuals(u0)?;
    let n = r0.len();
    if u0.is_empty() {
        let ssr = r0.iter().map(|x| x * x).sum();
        return Ok(LsqResult {
            u: Vec::new(),
            residuals: r0,
            jacobian: DMatrix::zeros(n, 0),
            ssr,
            evaluations: 1,
            termination: "no free parameters".into(),
            converged: true,
        });
    }
    let problem = Problem {
        model,
        u: DVector::from_column_slice(u0),
        r: Some(DVector::from_vec(r0)),
        n,
        h: opts.fd_step,
        evals: std::sync::atomic::AtomicUsize::new(1),
    };
    let lm = LevenbergMarquardt::new()
        .with_ftol(opts.ftol)
        .with_xtol(opts.xtol)
        .with_gtol(1e-10)
        .with_patience(opts.patience.max(1));
    let (problem, report) = lm.minimize(problem);
    let u = problem.u.clone();
    let r = problem.eval(u.as_slice());
    if r.iter().any(|x| *x == FAILED) {
        return Err(Error::Solver(
            "the model cannot be evaluated at the fitted parameters (every simulation failed there)"
                .into(),
        ));
    }
    let jacobian = fd_jacobian(&problem, &r);
    let evaluations = problem.evals.load(std::sync::atomic::Ordering::Relaxed);
    Ok(LsqResult {
        ssr: r.iter().map(|x| x * x).sum(),
        u: u.as_slice().to_vec(),
        residuals: r.as_slice().to_vec(),
        jacobian,
        evaluations,
        termination: format!("{:?}", report.termination),
        converged: report.termination.was_successful(),
    })
}

/// One fitted parameter with its uncertainty.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// Path (or name).
    pub name: String,
    /// Estimate.
    pub value: f64,
    /// Standard error (delta method for log parameters: x̂·se(ln x)).
    pub std_error: f64,
    /// 95 % interval.
    pub ci95: [f64; 2],
    /// Fitted in log space.
    pub log: bool,
    /// At (within 0.1 % of) a bound: the interval is not trustworthy.
    pub at_bound: bool,
    /// The interval reached past a bound `NAME=LO..HI` and was clipped to it (a bounded
    /// parameter cannot lie outside its bounds; the Student-t interval in the fitting
    /// coordinates does not know them).
    pub clipped: bool,
}

/// Asymptotic inference at an optimum.
#[derive(Debug, Clone, PartialEq)]
pub struct Inference {
    /// Parameters.
    pub estimates: Vec<Estimate>,
    /// Correlation matrix of the fitting coordinates (p × p, row-major).
    pub correlation: Vec<Vec<f64>>,
    /// Residual variance s² = SSR/(n − p) (of the weighted residuals).
    pub s2: f64,
    /// Degrees of freedom n − p.
    pub dof: usize,
    /// Whether JᵀJ was singular (a parameter the data do not determine).
    pub singular: bool,
}

/// Two-sided 97.5 % quantile of Student's t with `dof` degrees of freedom (normal for dof = 0).
pub fn t975(dof: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal, StudentsT};
    if dof == 0 {
        return Normal::new(0.0, 1.0).map_or(1.96, |n| n.inverse_cdf(0.975));
    }
    StudentsT::new(0.0, 1.0, dof as f64).map_or(1.96, |t| t.inverse_cdf(0.975))
}

/// Estimates, intervals and correlations at `fit` for parameters `specs`, with the classical
/// covariance s²(JᵀJ)⁻¹ (the weights are the inverse variances up to one common factor).
pub fn infer(fit: &LsqResult, specs: &[ParamSpec]) -> Inference {
    infer_with(fit, specs, false)
}

/// As [`infer`]; with `robust`, the heteroscedasticity-consistent sandwich covariance (HC1,
/// MacKinnon & White 1985): (JᵀJ)⁻¹ (Σ_i r_i² J_iᵀJ_i) (JᵀJ)⁻¹ · n/(n − p), valid when the
/// weights are not exactly the inverse variances (as in `discover`, whose weights include the
/// simulation's estimated numerical error, present in some data and not in others).
pub fn infer_with(fit: &LsqResult, specs: &[ParamSpec], robust: bool) -> Inference {
    let n = fit.residuals.len();
    let p = specs.len();
    let dof = n.saturating_sub(p);
    let s2 = if dof > 0 {
        fit.ssr / dof as f64
    } else {
        f64::NAN
    };
    if p == 0 {
        return Inference {
            estimates: Vec::new(),
            correlation: Vec::new(),
            s2,
            dof,
            singular: false,
        };
    }
    // Jacobian in the fitting coordinates v: ∂r/∂v = ∂r/∂u / (dv/du)
    let mut jv = fit.jacobian.clone();
    for (j, s) in specs.iter().enumerate() {
        let d = s.dv_du(fit.u[j]);
        let mut c = jv.column_mut(j);
        c /= d;
    }
    let jtj = jv.transpose() * &jv;
    let (inv, singular) = match jtj.clone().try_inverse() {
        Some(inv) if inv.iter().all(|x| x.is_finite()) => (inv, false),
        _ => (
            jtj.pseudo_inverse(1e-12)
                .unwrap_or_else(|_| DMatrix::zeros(p, p)),
            true,
        ),
    };
    let cov = if robust && dof > 0 {
        let mut meat = DMatrix::<f64>::zeros(p, p);
        for (i, r) in fit.residuals.iter().enumerate() {
            let row = jv.row(i);
            meat += row.transpose() * row * (r * r);
        }
        &inv * meat * &inv * (n as f64 / dof as f64)
    } else {
        inv * s2
    };
    let t = t975(dof);
    let estimates = specs
        .iter()
        .enumerate()
        .map(|(j, s)| {
            let v = s.v_of(fit.u[j]);
            let x = s.from_internal(fit.u[j]);
            // a variance that is not a finite number ≥ 0 (no residual degree of freedom, a
            // singular or overflowing JᵀJ) gives no standard error: NaN, never a silent 0
            let var = cov[(j, j)];
            let se_v = if var >= 0.0 { var.sqrt() } else { f64::NAN };
            let (se, mut ci) = if s.log {
                (x * se_v, [(v - t * se_v).exp(), (v + t * se_v).exp()])
            } else {
                (se_v, [v - t * se_v, v + t * se_v])
            };
            let mut clipped = false;
            if let (Some(lo), Some(hi)) = (s.lower, s.upper) {
                if ci[0] < lo {
                    ci[0] = lo;
                    clipped = true;
                }
                if ci[1] > hi {
                    ci[1] = hi;
                    clipped = true;
                }
            }
            Estimate {
                name: s.path.clone(),
                value: x,
                std_error: se,
                ci95: ci,
                log: s.log,
                at_bound: s.at_bound(x),
                clipped,
            }
        })
        .collect();
    let correlation = (0..p)
        .map(|i| {
            (0..p)
                .map(|j| {
                    let d = (cov[(i, i)] * cov[(j, j)]).sqrt();
                    if d > 0.0 {
                        cov[(i, j)] / d
                    } else {
                        f64::NAN
                    }
                })
                .collect()
        })
        .collect();
    Inference {
        estimates,
        correlation,
        s2,
        dof,
        singular,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean of four numbers as a one-parameter fit: the interval is mean ± t₀.₉₇₅,₃·s/√n
    /// (computed here by hand). With bounds 0..1 that interval reaches past both, so it is
    /// clipped to exactly [0, 1] and says so; with bounds −10..10 it is not clipped. With one
    /// observation (n = p) there is no residual variance: the standard error and interval are
    /// not finite (NaN), never a zero-width interval.
    #[test]
    fn intervals_are_clipped_to_the_bounds_and_never_zero_without_a_variance() {
        let ys = [0.1, -0.5, 0.9, 0.3];
        let model = |u: &[f64], spec: &ParamSpec| -> Vec<f64> {
            let a = spec.from_internal(u[0]);
            ys.iter().map(|y| y - a).collect()
        };
        let n = ys.len() as f64;
        let mean = ys.iter().sum::<f64>() / n;
        let s2 = ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1.0);
        let half = t975(3) * (s2 / n).sqrt();
        assert!(
            mean - half < 0.0 && mean + half > 1.0,
            "the case must reach past both bounds"
        );
        for (lo, hi, clipped) in [(0.0, 1.0, true), (-10.0, 10.0, false)] {
            let spec = ParamSpec {
                path: "a".into(),
                lower: Some(lo),
                upper: Some(hi),
                log: false,
                start: 0.5,
            };
            let sp = spec.clone();
            let m = move |u: &[f64]| -> Result<Vec<f64>, Error> { Ok(model(u, &sp)) };
            let opts = LsqOptions {
                fd_step: 1e-7,
                ftol: 1e-14,
                xtol: 1e-12,
                patience: 200,
            };
            let fit = minimize(&m, &[spec.to_internal(0.5)], &opts).unwrap();
            let e = &infer(&fit, std::slice::from_ref(&spec)).estimates[0];
            assert!((e.value - mean).abs() < 1e-6, "{e:?}");
            assert_eq!(e.clipped, clipped, "{e:?}");
            if clipped {
                assert_eq!(e.ci95, [0.0, 1.0], "{e:?}");
            } else {
                assert!((e.ci95[0] - (mean - half)).abs() < 1e-4, "{e:?}");
                assert!((e.ci95[1] - (mean + half)).abs() < 1e-4, "{e:?}");
            }
        }
        let one = |u: &[f64]| -> Result<Vec<f64>, Error> { Ok(vec![0.3 - u[0]]) };
        let spec = ParamSpec {
            path: "a".into(),
            lower: None,
            upper: None,
            log: false,
            start: 0.0,
        };
        let fit = minimize(&one, &[0.0], &LsqOptions::default()).unwrap();
        let inf = infer(&fit, &[spec]);
        assert!(
            inf.s2.is_nan() && inf.estimates[0].std_error.is_nan(),
            "{inf:?}"
        );
        assert!(inf.estimates[0].ci95.iter().all(|x| x.is_nan()), "{inf:?}");
    }

    /// Linear regression y = a + b·x: the LM optimum and its intervals must equal the closed
    /// form (normal equations; standard errors s²(XᵀX)⁻¹), computed here independently.
    #[test]
    fn linear_regression_matches_closed_form() {
        let xs: Vec<f64> = (0..20).map(|i| i as f64 * 0.5).collect();
        // deterministic "noise"
        let ys: Vec<f64> = xs
            .iter()
            .enumerate()
            .map(|(i, x)| 1.5 + 0.8 * x + 0.3 * ((i * 7919 % 13) as f64 / 13.0 - 0.5))
            .collect();
        let model = |u: &[f64]| -> Result<Vec<f64>, Error> {
            Ok(xs
                .iter()
                .zip(&ys)
                .map(|(x, y)| y - (u[0] + u[1] * x))
                .collect())
        };
        let specs = vec![
            ParamSpec {
                path: "a".into(),
                lower: None,
                upper: None,
                log: false,
                start: 0.0,
            },
            ParamSpec {
                path: "b".into(),
                lower: None,
                upper: None,
                log: false,
                start: 0.0,
            },
        ];
        let opts = LsqOptions {
            fd_step: 1e-6,
            ..Default::default()
        };
        let fit = minimize(&model, &[0.0, 0.0], &opts).unwrap();
        let inf = infer(&fit, &specs);
        // closed form
        let n = xs.len() as f64;
        let mx = xs.iter().sum::<f64>() / n;
        let my = ys.iter().sum::<f64>() / n;
        let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
        let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
        let b = sxy / sxx;
        let a = my - b * mx;
        let ssr: f64 = xs
            .iter()
            .zip(&ys)
            .map(|(x, y)| (y - a - b * x).powi(2))
            .sum();
        let s2 = ssr / (n - 2.0);
        let se_b = (s2 / sxx).sqrt();
        let se_a = (s2 * (1.0 / n + mx * mx / sxx)).sqrt();
        assert!((inf.estimates[0].value - a).abs() < 1e-6);
        assert!((inf.estimates[1].value - b).abs() < 1e-6);
        assert!((inf.estimates[0].std_error / se_a - 1.0).abs() < 1e-4);
        assert!((inf.estimates[1].std_error / se_b - 1.0).abs() < 1e-4);
        // t(18, 0.975) = 2.100922 (standard tables)
        assert!((t975(18) - 2.100922).abs() < 1e-5);
        let half = inf.estimates[1].ci95[1] - b;
        assert!((half / (2.100922 * se_b) - 1.0).abs() < 1e-4);
        // HC1 for the slope, by hand: Σ (x−x̄)² e² / (Σ (x−x̄)²)² · n/(n−2)
        let rob = infer_with(&fit, &specs, true);
        let hc: f64 = xs
            .iter()
            .zip(&ys)
            .map(|(x, y)| (x - mx).powi(2) * (y - a - b * x).powi(2))
            .sum::<f64>()
            / (sxx * sxx)
            * n
            / (n - 2.0);
        assert!((rob.estimates[1].std_error / hc.sqrt() - 1.0).abs() < 1e-4);
    }
}
