//! Running the matrix of an evaluation: every candidate under every elasticity law through the
//! phantom, in parallel (rayon), scored with the criteria; with a journal beside the output
//! folder, the finished runs are kept and read back by a restart.

use super::link::{breathed_gas_params, PhantomSpec};
use super::{Candidate, Evaluation, RunOutcome};
use crate::error::Error;
use crate::phantom::params::PhantomParams;
use crate::profile::PressureHistory;
use crate::report::journal::Journal;
use crate::risk::{CriteriaSet, RunData};
use crate::run::{simulate_in_batch, SimRun};
use rayon::prelude::*;
use std::path::Path;
use std::sync::Mutex;

/// Run every candidate under every law through the phantom, in parallel (rayon), and score
/// them. `progress(done, total)` reports overall progress in runs (fractions count).
pub fn run_matrix(
    candidates: Vec<Candidate>,
    phantom: PhantomSpec,
    laws: Vec<&'static str>,
    criteria: CriteriaSet,
    progress: &mut (dyn FnMut(f64, f64) + Send),
) -> Result<Evaluation, Error> {
    run_matrix_journaled(candidates, phantom, laws, criteria, progress, None).map(|r| r.0)
}

/// The journal key of a run: the hashes of its inputs as parsed (phantom settings with the
/// law and the gas convention, pressure history), as for a checkpoint.
fn run_key(params: &PhantomParams, history: &PressureHistory) -> String {
    crate::phantom::checkpoint::Inputs::new(params, history)
        .sections
        .iter()
        .map(|s| format!("{:016x}", s.hash))
        .collect()
}

/// [`run_matrix`] with a journal beside the output folder `out` ([`crate::report::journal`],
/// `OUT.partial/`): every run is kept there as it finishes (its summary and frames in
/// `run-KEY.dcr`, then the line `KEY WALL_SECONDS` in `runs.txt`), and the runs an earlier,
/// unfinished evaluation with the same runs (the fingerprint: the keys of all runs) left there
/// are read back instead of simulated. The caller removes the journal
/// ([`crate::report::journal::Journal::finish`]) once the output is written.
pub fn run_matrix_journaled(
    candidates: Vec<Candidate>,
    phantom: PhantomSpec,
    laws: Vec<&'static str>,
    criteria: CriteriaSet,
    progress: &mut (dyn FnMut(f64, f64) + Send),
    out: Option<&Path>,
) -> Result<(Evaluation, Option<Journal>), Error> {
    let jobs: Vec<(usize, &'static str)> = (0..candidates.len())
        .flat_map(|c| laws.iter().map(move |l| (c, *l)))
        .collect();
    let total = jobs.len() as f64;
    // the phantom file, with the line of the field when the source is a readable file
    let located = |e| {
        Error::Input(crate::phantom::config::in_phantom_file(
            e,
            std::path::Path::new(&phantom.source),
        ))
    };
    let breathed = breathed_gas_params(&phantom.params, &criteria.protocol).map_err(located)?;
    // the bubbles' fixed gases against every schedule's pressures, before anything runs
    for cand in &candidates {
        breathed.check_gases_for(&cand.history).map_err(located)?;
        breathed
            .bubble_fixed_gases_for(&cand.history)
            .map_err(located)?;
    }
    let params: Vec<PhantomParams> = jobs
        .iter()
        .map(|&(_, law)| {
            breathed_gas_params(&phantom.with_law(law)?, &criteria.protocol).map_err(Error::Input)
        })
        .collect::<Result<_, _>>()?;
    let keys: Vec<String> = jobs
        .iter()
        .zip(&params)
        .map(|(&(c, _), p)| run_key(p, &candidates[c].history))
        .collect();
    // finished runs of an earlier evaluation of the same runs: key → wall seconds
    let mut kept: std::collections::HashMap<String, f64> = Default::default();
    let journal = match out {
        Some(out) => {
            let fingerprint = format!(
                "# decophantom {} evaluate runs={} {:016x}",
                env!("CARGO_PKG_VERSION"),
                keys.len(),
                crate::phantom::checkpoint::fnv1a(keys.join(",").as_bytes())
            );
            let names = ["runs.txt"];
            if let Some(texts) = Journal::previous(out, &fingerprint, &names, "evaluation")? {
                for line in texts[0].lines() {
                    if let Some((k, w)) = line.split_once(' ') {
                        if let (true, Ok(w)) = (keys.iter().any(|x| x == k), w.parse::<f64>()) {
                            kept.insert(k.to_string(), w);
                        }
                    }
                }
            }
            let text: String = kept.iter().map(|(k, w)| format!("{k} {w}\n")).collect();
            Some(Journal::start(out, &fingerprint, &names, &[text])?)
        }
        None => None,
    };
    let resumed = std::sync::atomic::AtomicUsize::new(0);
    let shared = Mutex::new((vec![0.0f64; jobs.len()], progress));
    let results: Vec<Result<RunOutcome, Error>> = jobs
        .par_iter()
        .enumerate()
        .map(|(j, &(c, law))| {
            let params = &params[j];
            let key = &keys[j];
            let file = format!("run-{key}.dcr");
            // a finished run of the journal, read back whole (else run again)
            let earlier = match (&journal, kept.get(key)) {
                (Some(jn), Some(&wall)) => jn
                    .get(&file)
                    .and_then(|b| crate::phantom::checkpoint::decode_result(&b))
                    .map(|(summary, frames)| SimRun {
                        summary,
                        frames,
                        wall_seconds: wall,
                        notes: Vec::new(),
                        checkpoints: None,
                        resumed_at: None,
                        steps: Vec::new(),
                        // not kept by the journal: a run read back took no steps here
                        phases: Default::default(),
                        gel_by_scheme: Default::default(),
                    }),
                _ => None,
            };
            let mut cb = |t: f64, end: f64| {
                if let Ok(mut g) = shared.lock() {
                    let (fr, cb) = &mut *g;
                    fr[j] = if end > 0.0 {
                        (t / end).clamp(0.0, 1.0)
                    } else {
                        1.0
                    };
                    let done: f64 = fr.iter().sum();
                    (*cb)(done, total);
                }
            };
            let run = match earlier {
                Some(run) => {
                    resumed.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    cb(1.0, 1.0);
                    run
                }
                None => {
                    let run = simulate_in_batch(params, &candidates[c].history, &mut cb).map_err(
                        |e| match e {
                            Error::Solver(m) => {
                                Error::Solver(format!("{} under {law}: {m}", candidates[c].label))
                            }
                            other => other,
                        },
                    )?;
                    if let Some(jn) = &journal {
                        jn.put(
                            &file,
                            &crate::phantom::checkpoint::encode_result(&run.summary, &run.frames),
                        )?;
                        jn.append(&[format!("{key} {}\n", run.wall_seconds)])?;
                    }
                    run
                }
            };
            let h = &candidates[c].history;
            let scores = criteria.score(&RunData {
                frames: &run.frames,
                surfaced_s: Some(h.final_arrival_s()),
            });
            crate::risk::check_finite(&scores)
                .map_err(|m| Error::Solver(format!("{} under {law}: {m}", candidates[c].label)))?;
            Ok(RunOutcome {
                candidate: c,
                law,
                run,
                scores,
            })
        })
        .collect();
    let runs = match results.into_iter().collect::<Result<Vec<_>, _>>() {
        Ok(runs) => runs,
        Err(e) => {
            // a journal that holds no finished run is no use to a restart: leave nothing
            if let Some(j) = journal {
                let finished = std::fs::read_to_string(j.dir().join("runs.txt"))
                    .map_or(0, |t| t.lines().count().saturating_sub(1));
                if finished == 0 {
                    j.finish();
                }
            }
            return Err(e);
        }
    };
    Ok((
        Evaluation {
            candidates,
            laws,
            runs,
            phantom,
            criteria,
            resumed: resumed.into_inner(),
        },
        journal,
    ))
}
