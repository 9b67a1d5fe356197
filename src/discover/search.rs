//! The forward search of `discover`:
//!
//! 1. fit the baseline (the experiments as configured, `[fit] free` free);
//! 2. estimate the simulation's own numerical error: the baseline re-run with the grid step and
//!    every step limit halved; the Richardson estimate of a first-order scheme, 2 × the change,
//!    and e_b = its RMS over each bubble's observations;
//! 3. fix the weights once: σ_i² = sd_i² + e_b² (sd from the file, or, without one, the
//!    measurement variance estimated from the baseline fit, less the numerical part), so grid
//!    error is never read as physics;
//! 4. each round: every candidate not yet added is prepared on the current model, its
//!    parameters started from the best of a coarse scan and the null, and the whole model
//!    refitted; the extra sum-of-squares F-test against the current model, ΔSSR and ΔAICc;
//! 5. the candidate with the smallest p is added only if p < α/m (Bonferroni over the m
//!    candidates tried in that round) AND it lowers the RMSE by more than the numerical error;
//!    repeat until none qualifies.
//!
//! The intervals of every fit here are heteroscedasticity-consistent (sandwich, HC1): the
//! weights carry the estimated numerical error, which the measurements need not contain.

use super::diagnose::{diagnose, Diagnostics};
use super::{all_candidates, Phantoms, Prepared};
use crate::error::{Error, InputError};
use crate::fit::data::{Experiments, Measurements};
use crate::fit::lsq::{Estimate, LsqOptions};
use crate::fit::model::{fit_with, observed, refine, Fitted, Model};
use crate::fit::stats::{aicc, extra_ss_f_test, FTest};
use rayon::prelude::*;

/// Settings of the search.
#[derive(Debug, Clone, PartialEq)]
pub struct DiscoverOptions {
    /// Family-wise significance level, Bonferroni-corrected over each round's candidates.
    /// Default 0.01.
    pub alpha: f64,
    /// Most effects added. Default 3.
    pub max_effects: usize,
    /// Least-squares settings of every fit.
    pub lsq: LsqOptions,
    /// Only candidates whose name starts with one of these (empty: all).
    pub only: Vec<String>,
}

impl Default for DiscoverOptions {
    fn default() -> Self {
        DiscoverOptions {
            alpha: 0.01,
            max_effects: 3,
            lsq: LsqOptions {
                fd_step: 2e-3,
                ftol: 1e-7,
                xtol: 1e-6,
                patience: 12,
            },
            only: Vec::new(),
        }
    }
}

/// One candidate's refit in one round.
#[derive(Debug, Clone)]
pub struct CandidateOutcome {
    /// Candidate name.
    pub name: String,
    /// Its parameters' estimates (empty for a discrete candidate).
    pub estimates: Vec<Estimate>,
    /// Degrees of freedom it adds.
    pub dof: usize,
    /// Weighted SSR of the refitted model.
    pub ssr: f64,
    /// Current SSR − this SSR (≥ 0 when the refit started at the null).
    pub delta_ssr: f64,
    /// The F-test against the current model.
    pub f_test: FTest,
    /// AICc of this model − AICc of the current one (negative favours the candidate).
    pub delta_aicc: f64,
    /// Unweighted RMSE, m.
    pub rmse: f64,
    /// Why it could not be fitted, if it could not.
    pub error: Option<String>,
    /// The candidate's parameters as prepared (null value, scan, bounds), one per estimate in
    /// the same order (empty when it could not be fitted): the report tells an estimate that
    /// ran to its null from a small effect by them.
    pub params: Vec<super::EffectParam>,
    /// The refitted model (kept for the accepted one).
    pub fitted: Option<Box<Fitted>>,
}

/// One round of the search.
#[derive(Debug, Clone)]
pub struct Round {
    /// Effects in the model at the start of the round.
    pub current: Vec<String>,
    /// Every candidate tried.
    pub outcomes: Vec<CandidateOutcome>,
    /// The Bonferroni threshold α/m.
    pub threshold: f64,
    /// The candidate added, if any.
    pub accepted: Option<String>,
    /// Why the best candidate was or was not added.
    pub verdict: String,
}

/// An added effect.
#[derive(Debug, Clone)]
pub struct Added {
    /// Effect name.
    pub effect: String,
    /// Its parameters (estimates and intervals in the final model).
    pub parameters: Vec<Estimate>,
    /// p-value of its F-test when it was added.
    pub p_value: f64,
    /// F statistic then.
    pub f: f64,
    /// SSR reduction then.
    pub delta_ssr: f64,
    /// ΔAICc then.
    pub delta_aicc: f64,
    /// Other candidates of that round that were significant too and fitted within the numerical
    /// error of the added one (RMSE difference below it): these data, at this numerical
    /// accuracy, cannot tell them apart from the added effect. With their estimates.
    pub alternatives: Vec<(String, Vec<Estimate>)>,
}

/// The numerical-error estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct NumericalError {
    /// Estimated error of the run at every observation, m: the Richardson factor × (refined −
    /// coarse radius).
    pub difference: Vec<f64>,
    /// Per-observation e_b (the RMS over its bubble), m.
    pub per_observation: Vec<f64>,
    /// RMS over all observations, m.
    pub rms: f64,
}

/// The outcome of `discover`.
#[derive(Debug, Clone)]
pub struct Discovery {
    /// The baseline fit with the final weights.
    pub baseline: Fitted,
    /// The final model's fit.
    pub final_fit: Fitted,
    /// Effect names added, in order.
    pub effects: Vec<String>,
    /// Details of each added effect.
    pub added: Vec<Added>,
    /// Every round.
    pub rounds: Vec<Round>,
    /// Numerical error of the baseline.
    pub numerical: NumericalError,
    /// Measurement sd used, m (per observation).
    pub measurement_sd: Vec<f64>,
    /// Whether the sd came from the file.
    pub sd_given: bool,
    /// Weights 1/σ² used in every test.
    pub weights: Vec<f64>,
    /// Diagnostics of the baseline.
    pub diagnostics_before: Diagnostics,
    /// Diagnostics of the final model.
    pub diagnostics_after: Diagnostics,
    /// Settings used.
    pub options: DiscoverOptions,
}

/// Diagnose a fit (runs it once more for the bubble positions).
pub fn diagnose_fit(
    f: &Fitted,
    experiments: &Experiments,
    data: &Measurements,
) -> Result<Diagnostics, Error> {
    let runs = f.model.run(experiments, &f.values)?;
    let first: Vec<_> = runs.iter().map(|r| r.frames.first().cloned()).collect();
    Ok(diagnose(experiments, data, &f.predicted, &first))
}

/// Richardson factor of the numerical-error estimate: the error of the run itself is
/// |f_{h/2} − f_h|·2^p/(2^p − 1) for a scheme of order p; the time stepping and the sub-grid
/// coupling are first order (p = 1), so the factor is 2.
pub const RICHARDSON_FACTOR: f64 = 2.0;

/// The numerical error of a fitted model: the Richardson estimate from the run refined in space
/// and time, RICHARDSON_FACTOR × (refined − coarse).
pub fn numerical_error(
    f: &Fitted,
    experiments: &Experiments,
    data: &Measurements,
) -> Result<NumericalError, Error> {
    let mut fine = f.model.clone();
    for d in fine.docs.iter_mut() {
        refine(d).map_err(|m| Error::Input(crate::error::InputError::new(m)))?;
    }
    let pf = fine.predict(experiments, data, &f.values)?;
    let difference: Vec<f64> = pf
        .iter()
        .zip(&f.predicted)
        .map(|(a, b)| RICHARDSON_FACTOR * (a - b))
        .collect();
    let mut per_observation = Vec::with_capacity(difference.len());
    let mut k = 0;
    for s in &data.series {
        let n = s.points.len();
        let rms =
            (difference[k..k + n].iter().map(|x| x * x).sum::<f64>() / n.max(1) as f64).sqrt();
        per_observation.extend(std::iter::repeat_n(rms, n));
        k += n;
    }
    let rms =
        (difference.iter().map(|x| x * x).sum::<f64>() / difference.len().max(1) as f64).sqrt();
    Ok(NumericalError {
        difference,
        per_observation,
        rms,
    })
}

/// `discrete`: the degrees of freedom of the current model's accepted discrete effects (a
/// sealed face), which `current.p()` (its continuous parameters) does not count.
fn try_candidate(
    cand: &dyn super::CandidateEffect,
    current: &Fitted,
    discrete: usize,
    experiments: &Experiments,
    data: &Measurements,
    weights: &[f64],
    opts: &DiscoverOptions,
) -> CandidateOutcome {
    let name = cand.name();
    let failed = |m: String| CandidateOutcome {
        name: name.clone(),
        estimates: Vec::new(),
        dof: 0,
        ssr: f64::NAN,
        delta_ssr: f64::NAN,
        f_test: FTest {
            f: f64::NAN,
            df_num: 0,
            df_den: 0,
            p_value: 1.0,
        },
        delta_aicc: f64::NAN,
        rmse: f64::NAN,
        error: Some(m),
        params: Vec::new(),
        fitted: None,
    };
    let mut docs = current.model.docs.clone();
    let prepared: Prepared = match cand.prepare(&mut docs) {
        Ok(Some(p)) => p,
        Ok(None) => return failed("does not apply to these phantoms".into()),
        Err(m) => return failed(m),
    };
    // a parameter the current model already fits (e.g. the fold, when the area law follows the
    // constant fold) passes to the candidate, starting where it is, and adds no freedom
    let mut free = current.model.free.clone();
    let mut base_values = current.values.clone();
    let mut specs: Vec<_> = prepared.params.iter().map(|p| p.spec.clone()).collect();
    let mut dof = prepared.dof;
    for s in specs.iter_mut() {
        if let Some(j) = free.iter().position(|f| f.path == s.path) {
            s.start = base_values[j];
            free.remove(j);
            base_values.remove(j);
            dof = dof.saturating_sub(1);
        }
    }
    if dof == 0 {
        return failed("adds no parameter to the current model".into());
    }
    for (s, v) in free.iter_mut().zip(&base_values) {
        s.start = *v;
    }
    let mut model = Model {
        docs,
        free,
        evaluations: current.model.evaluations.clone(),
    };
    // start: the best of the null and a scan (of the first parameter, and of the second with it)
    if let Some(first) = prepared.params.first() {
        let y = observed(data);
        let ssr_at = |vals: &[f64]| -> f64 {
            let mut values = base_values.clone();
            values.extend(vals.iter().copied());
            let mut m = model.clone();
            m.free.extend(specs.iter().cloned());
            match m.predict(experiments, data, &values) {
                Ok(f) => y
                    .iter()
                    .zip(&f)
                    .zip(weights)
                    .map(|((a, b), w)| w * (a - b).powi(2))
                    .sum(),
                Err(_) => f64::INFINITY,
            }
        };
        let starts: Vec<f64> = specs.iter().map(|s| s.start).collect();
        let mut grid: Vec<Vec<f64>> = Vec::new();
        for v in &first.scan {
            match prepared.params.get(1) {
                Some(second) => {
                    for w in second.scan.iter().chain(std::iter::once(&starts[1])) {
                        grid.push(vec![*v, *w]);
                    }
                }
                None => grid.push(vec![*v]),
            }
        }
        let scores: Vec<(Vec<f64>, f64)> = grid
            .into_par_iter()
            .map(|g| {
                let mut vals = starts.clone();
                vals[..g.len()].copy_from_slice(&g);
                let s = ssr_at(&vals);
                (vals, s)
            })
            .collect();
        if let Some((v, sc)) = scores
            .into_iter()
            .filter(|(_, s)| s.is_finite())
            .min_by(|a, b| a.1.total_cmp(&b.1))
        {
            if sc < current.ssr {
                for (s, x) in specs.iter_mut().zip(v) {
                    s.start = x;
                }
            }
        }
    }
    let n_effect = specs.len();
    model.free.extend(specs);
    let f = match fit_with(&model, experiments, data, weights, &opts.lsq, true) {
        Ok(f) => f,
        Err(e) => return failed(e.to_string()),
    };
    let p_extra = dof;
    let p0 = current.p() + discrete;
    let df0 = current.n.saturating_sub(p0);
    let df1 = current.n.saturating_sub(p0 + p_extra);
    // the F-test's SSR is capped at the current model's: a nested candidate's fit that stopped
    // above its null is the optimiser's shortfall, not evidence (F ≤ 0 gives p = 1 either way).
    // ΔAICc uses the fit's own SSR: a discrete candidate (a sealed face) has no null inside it,
    // so a worse fit is real and its ΔAICc is more than the parameter's penalty
    let ssr1 = f.ssr.min(current.ssr);
    let f_test = extra_ss_f_test(current.ssr, df0, ssr1, df1);
    let delta_aicc = aicc(f.ssr, current.n, p0 + p_extra) - aicc(current.ssr, current.n, p0);
    let k0 = f.p() - n_effect;
    CandidateOutcome {
        name,
        estimates: f.inference.estimates[k0..].to_vec(),
        dof: p_extra,
        ssr: f.ssr,
        delta_ssr: current.ssr - f.ssr,
        f_test,
        delta_aicc,
        rmse: f.rmse,
        error: None,
        params: prepared.params.clone(),
        fitted: Some(Box::new(f)),
    }
}

/// The names of the candidates for the experiments' own phantoms.
fn candidate_names(experiments: &Experiments) -> Vec<String> {
    let docs: Vec<toml::Table> = experiments.list.iter().map(|e| e.phantom.clone()).collect();
    all_candidates(&Phantoms::of(experiments, &docs))
        .iter()
        .map(|c| c.name())
        .collect()
}

/// Run the search. `progress(done, total)` is called as candidate fits finish (total is an
/// estimate: rounds × candidates).
pub fn discover(
    experiments: &Experiments,
    data: &Measurements,
    opts: &DiscoverOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Discovery, Error> {
    discover_with(experiments, data, opts, progress, None)
}

/// The first line of the journal of a search ([`crate::fit::journal`]): the measurements, the
/// experiments, the settings and the candidates.
pub fn fingerprint(
    experiments: &Experiments,
    data: &Measurements,
    opts: &DiscoverOptions,
) -> String {
    let names = candidate_names(experiments);
    crate::fit::journal::fingerprint(
        "discover",
        &[
            crate::fit::journal::work_text(experiments, data),
            format!("{opts:?}"),
            format!("candidates {names:?}"),
        ],
    )
}

/// Check `--only` against the candidates for these phantoms, before any simulation: every
/// entry must be non-empty and the start of at least one candidate's name (`elasticity`
/// selects every `elasticity:<law>`). Refused (exit 2) naming `<command line>` and `--only`,
/// with the candidates these phantoms have.
pub fn check_only(experiments: &Experiments, only: &[String]) -> Result<(), InputError> {
    let names = candidate_names(experiments);
    let bad = |m: String| InputError::new(m).in_file("<command line>").field("--only");
    for o in only {
        if o.trim().is_empty() {
            return Err(bad(format!(
                "an empty name (in '{}'); give candidate names or their starts, comma-separated; known: {}",
                only.join(","),
                names.join(", ")
            )));
        }
        if !names.iter().any(|n| n.starts_with(o.as_str())) {
            return Err(bad(format!(
                "'{o}' matches no candidate for these phantoms; known: {}",
                names.join(", ")
            )));
        }
    }
    Ok(())
}

/// The most parameters a candidate of the first round adds to the baseline (with `only`, of
/// those selected): its model must leave two residual degrees of freedom.
fn largest_candidate(experiments: &Experiments, only: &[String]) -> usize {
    let docs: Vec<toml::Table> = experiments.list.iter().map(|e| e.phantom.clone()).collect();
    all_candidates(&Phantoms::of(experiments, &docs))
        .iter()
        .filter(|c| only.is_empty() || only.iter().any(|o| c.name().starts_with(o.as_str())))
        .filter_map(|c| {
            let mut d = docs.clone();
            c.prepare(&mut d)
                .ok()
                .flatten()
                .map(|p| p.params.len().max(p.dof))
        })
        .max()
        .unwrap_or(0)
}

/// Check, before any simulation, that the data can carry the search: the baseline's `[fit]
/// free` parameters and the largest candidate's must leave
/// [`crate::fit::model::MIN_RESIDUAL_DOF`] residual degrees of freedom (the F-test and every
/// interval need them), and `--only` must select candidates ([`check_only`]). Refused (exit 2)
/// naming the measurements file (its last line, where more rows would go).
pub fn check_search(
    experiments: &Experiments,
    data: &Measurements,
    opts: &DiscoverOptions,
) -> Result<(), Error> {
    check_only(experiments, &opts.only)?;
    let p0 = Model::baseline(experiments)?.free.len();
    let q = largest_candidate(experiments, &opts.only);
    let need = p0 + q + crate::fit::model::MIN_RESIDUAL_DOF;
    let n = data.len();
    if n >= need {
        return Ok(());
    }
    let last = data
        .series
        .iter()
        .flat_map(|s| s.points.iter().map(|o| o.line))
        .max()
        .unwrap_or(1);
    Err(InputError::new(format!(
        "{n} observation(s): discover needs at least {need}, the baseline's {p0} free parameter(s) ([fit] free) plus the {q} of its largest candidate plus two residual degrees of freedom (for the F-test and the intervals); measure more radii, or choose smaller candidates with --only"
    ))
    .in_file(&data.file)
    .at_line(last)
    .into())
}

/// [`discover`] with every simulation of every fit kept in (and read back from) `evaluations`
/// ([`crate::fit::journal`]): a search is deterministic, so a restart of the same search with
/// the journal of an unfinished one replays it and runs only the simulations not yet there.
pub fn discover_with(
    experiments: &Experiments,
    data: &Measurements,
    opts: &DiscoverOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
    evaluations: Option<std::sync::Arc<crate::fit::journal::Evaluations>>,
) -> Result<Discovery, Error> {
    check_search(experiments, data, opts)?;
    let base = Model::baseline(experiments)?.with_evaluations(evaluations);
    let n = data.len();
    let sd_given = data.has_sd();
    let unit = data.weights();
    let first = fit_with(&base, experiments, data, &unit, &opts.lsq, true)?;
    let numerical = numerical_error(&first, experiments, data)?;
    // measurement sd: from the file, else from the baseline residuals less the numerical part
    let measurement_sd: Vec<f64> = if sd_given {
        data.series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.sd.unwrap_or(0.0)))
            .collect()
    } else {
        let y = observed(data);
        let ss: f64 = y
            .iter()
            .zip(&first.predicted)
            .map(|(a, b)| (a - b).powi(2))
            .sum();
        let s2 = ss / first.dof().max(1) as f64 - numerical.rms.powi(2);
        vec![s2.max(1e-30).sqrt(); n]
    };
    let weights: Vec<f64> = measurement_sd
        .iter()
        .zip(&numerical.per_observation)
        .map(|(s, e)| 1.0 / (s * s + e * e).max(1e-40))
        .collect();
    let mut base_w = base.clone();
    for (s, v) in base_w.free.iter_mut().zip(&first.values) {
        s.start = *v;
    }
    let baseline = fit_with(&base_w, experiments, data, &weights, &opts.lsq, true)?;
    let diagnostics_before = diagnose_fit(&baseline, experiments, data)?;
    let mut current = baseline.clone();
    let mut effects: Vec<String> = Vec::new();
    // degrees of freedom of accepted discrete effects (not among the fit's parameters)
    let mut discrete = 0usize;
    let mut added: Vec<(Added, Vec<String>)> = Vec::new();
    let mut rounds = Vec::new();
    let total_guess = all_candidates(&Phantoms::of(experiments, &current.model.docs)).len()
        * (opts.max_effects.min(2) + 1);
    let done = std::sync::atomic::AtomicUsize::new(0);
    while effects.len() < opts.max_effects {
        let cands: Vec<_> = all_candidates(&Phantoms::of(experiments, &current.model.docs))
            .into_iter()
            .filter(|c| {
                let name = c.name();
                !effects.contains(&name)
                    && (opts.only.is_empty() || opts.only.iter().any(|o| name.starts_with(o)))
            })
            .collect();
        let outcomes: Vec<CandidateOutcome> = cands
            .par_iter()
            .map(|c| {
                let o = try_candidate(
                    c.as_ref(),
                    &current,
                    discrete,
                    experiments,
                    data,
                    &weights,
                    opts,
                );
                let k = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
                progress(k, total_guess.max(k));
                o
            })
            .collect();
        let tried = outcomes.iter().filter(|o| o.error.is_none()).count().max(1);
        let threshold = opts.alpha / tried as f64;
        let best = outcomes
            .iter()
            .enumerate()
            .filter(|(_, o)| o.error.is_none() && o.f_test.p_value.is_finite())
            .min_by(|a, b| {
                a.1.f_test
                    .p_value
                    .total_cmp(&b.1.f_test.p_value)
                    .then(b.1.delta_ssr.total_cmp(&a.1.delta_ssr))
            })
            .map(|(i, _)| i);
        let mut round = Round {
            current: effects.clone(),
            outcomes,
            threshold,
            accepted: None,
            verdict: String::new(),
        };
        let Some(bi) = best else {
            round.verdict = "no candidate could be fitted".into();
            rounds.push(round);
            break;
        };
        let b = &round.outcomes[bi];
        let gain = current.rmse - b.rmse;
        let significant = b.f_test.p_value < threshold;
        let above_numerics = gain > numerical.rms;
        // 3 significant digits, as the report prints every statistic (p below 1e-16 as a bound)
        let sig = crate::fit::report::sig;
        round.verdict = format!(
            "best: {} (p {} {} α/m = {}; RMSE gain {} µm {} numerical error {} µm)",
            b.name,
            super::report::p_text(b.f_test.p_value),
            if significant { "<" } else { "≥" },
            sig(threshold, 3),
            sig(gain * 1e6, 3),
            if above_numerics { ">" } else { "≤" },
            sig(numerical.rms * 1e6, 3)
        );
        if significant && above_numerics {
            let fitted = b.fitted.clone().expect("a fitted candidate keeps its fit");
            let accepted_dof = b.dof;
            let name = b.name.clone();
            let claimed: Vec<String> = b.estimates.iter().map(|e| e.name.clone()).collect();
            for (_, paths) in added.iter_mut() {
                paths.retain(|p| !claimed.contains(p));
            }
            let alternatives = round
                .outcomes
                .iter()
                .enumerate()
                .filter(|(i, o)| {
                    *i != bi
                        && o.error.is_none()
                        && o.f_test.p_value < threshold
                        && o.rmse - b.rmse < numerical.rms
                })
                .map(|(_, o)| (o.name.clone(), o.estimates.clone()))
                .collect();
            added.push((
                Added {
                    effect: name.clone(),
                    parameters: Vec::new(),
                    p_value: b.f_test.p_value,
                    f: b.f_test.f,
                    delta_ssr: b.delta_ssr,
                    delta_aicc: b.delta_aicc,
                    alternatives,
                },
                claimed,
            ));
            round.accepted = Some(name.clone());
            effects.push(name);
            discrete += accepted_dof.saturating_sub(fitted.p().saturating_sub(current.p()));
            current = *fitted;
            rounds.push(round);
        } else {
            rounds.push(round);
            break;
        }
    }
    // the added effects' parameters as estimated in the final model
    // (a parameter taken over by a later effect is reported with that effect)
    let mut added_out = Vec::new();
    for (mut a, paths) in added {
        a.parameters = current
            .inference
            .estimates
            .iter()
            .filter(|e| paths.contains(&e.name))
            .cloned()
            .collect();
        added_out.push(a);
    }
    // strip the kept fits from the rounds (only the accepted ones matter, and they are in
    // `current`'s history)
    for r in rounds.iter_mut() {
        for o in r.outcomes.iter_mut() {
            o.fitted = None;
        }
    }
    let diagnostics_after = diagnose_fit(&current, experiments, data)?;
    Ok(Discovery {
        baseline,
        final_fit: current,
        effects,
        added: added_out,
        rounds,
        numerical,
        measurement_sd,
        sd_given,
        weights,
        diagnostics_before,
        diagnostics_after,
        options: opts.clone(),
    })
}
