//! `decophantom evaluate`: plan one dive with several algorithms, run every schedule (under
//! every requested tissue-elasticity law) through the same phantom, score the runs with a
//! criteria file, rank them, and write the decompression report (`report.md`, a
//! self-contained `report.html`, `scores.csv`, the SVG plots). The pieces (linking a
//! schedule to the phantom, running the matrix in parallel, building the report) are public
//! so `check` and `demo` use the same path.
//!
//! Linking a dive to the phantom ([`dive_history`], [`breathed_gas_params`]): the ambient
//! pressure of the schedule acts on the gel; the breathed-gas convention of the criteria
//! file's `[protocol]` ([`Protocol`]) holds on both sides of every bubble's interface — the open
//! faces are in equilibrium with the inspired inert-gas partial pressures,
//! fraction × (ambient − P_H2O), and every bubble holds the gases that are not simulated at
//! fixed partial pressures, P_H2O + P_CO2 + P_vO2 (6.27 + 5.3 + 5.3 kPa by default; the same
//! P_H2O on both sides, whatever water vapour the schedule's planner used); O2 is left out of
//! the gel unless the protocol sets `oxygen_at_faces`. The phantom starts saturated at the surface
//! with the first leg's gas; the schedule is followed by `protocol.observe_after_surfacing_min`
//! at the surface on air. A repetitive dive (`repeat_after_min`) appends a surface interval
//! on air and the same schedule again, so the gel and the bubbles carry over.

use super::plan::plan_dive;
use super::simulate::{ending_text, simulate_in_batch, SimRun};
use crate::algorithm::config::parse_algorithm;
use crate::algorithm::schedule::gas_text;
use crate::algorithm::{load_algorithm, LoadedAlgorithm, Schedule};
use crate::error::{Error, InputError};
use crate::gas::GasMix;
use crate::phantom::config::parse_phantom;
use crate::phantom::elasticity::{law_names, AllLawParams, ElasticityLaw};
use crate::phantom::params::PhantomParams;
use crate::phantom::sim::Frame;
use crate::profile::PressureHistory;
use crate::report::html::Page;
use crate::report::journal::Journal;
use crate::report::output::OutputSet;
use crate::report::plot::{BarChart, LinePlot, Series, DEFAULT_SIZE};
use crate::report::table::{Cell, Column, Table};
use crate::risk::{load_criteria, series, CriteriaSet, Protocol, RunData, Score};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

/// The built-in phantom (`profiles/phantoms/hydrogel-dive.toml`), used when none is given.
pub const HYDROGEL_PHANTOM: &str = include_str!("../../profiles/phantoms/hydrogel-dive.toml");
/// Where [`HYDROGEL_PHANTOM`] comes from.
pub const HYDROGEL_PHANTOM_PATH: &str = "profiles/phantoms/hydrogel-dive.toml";

/// Default M = K/V_aff of the Bulk-Modulus law when the phantom does not give one, Pa/m³
/// (5e-2 Pa/µm³, the paper's Fig. 2a).
pub const DEFAULT_BULK_MODULUS_PER_VOLUME: f64 = 5e16;
/// Default bulk modulus K of the Reference-Configuration law, Pa (2.2 GPa, the paper's Fig. 2a).
pub const DEFAULT_BULK_MODULUS: f64 = 2.2e9;
/// Default shear modulus μ when the phantom's own law has none, Pa (40 Pa, the hydrogel of
/// the paper's Figs. 4–5).
pub const DEFAULT_SHEAR_MODULUS: f64 = 40.0;

/// A phantom ready for evaluation: parameters, where they came from, and the parameters
/// from which the other elasticity laws are built.
#[derive(Debug, Clone)]
pub struct PhantomSpec {
    /// Validated parameters (the phantom's own elasticity law).
    pub params: PhantomParams,
    /// The file's description.
    pub description: String,
    /// The file it came from (or `built-in hydrogel`).
    pub source: String,
    /// μ from the phantom's `[material.elasticity]` (else 40 Pa), M and K from it if given
    /// (else 5e-2 Pa/µm³ and 2.2 GPa, the paper's Fig. 2a).
    pub laws: AllLawParams,
}

impl PhantomSpec {
    /// Parse phantom TOML text; `grid_step_m` overrides the grid step (the nuclei radii, R_min
    /// and the surface-layer thickness keep the file's values).
    pub fn from_text(
        text: &str,
        path: &Path,
        source: &str,
        grid_step_m: Option<f64>,
    ) -> Result<PhantomSpec, InputError> {
        let loaded = parse_phantom(text, path)?;
        let mut params = loaded.params;
        if let Some(h) = grid_step_m {
            if !(h.is_finite() && h > 0.0) {
                return Err(
                    InputError::new(format!("grid step must be positive m (got {h})"))
                        .in_file("<command line>")
                        .field("--grid-step"),
                );
            }
            params.grid_step = h;
            // the new grid must be buildable (cell count) and hold the bubbles
            let cl = |m: String| {
                InputError::new(m)
                    .in_file("<command line>")
                    .field("--grid-step")
            };
            let grid =
                crate::phantom::grid::Grid::new(params.shape, h, &params.open_faces).map_err(cl)?;
            crate::phantom::sim::place_bubbles(&params, &grid).map_err(|e| cl(e.to_string()))?;
        }
        crate::phantom::config::require_bubbles(&params, path)?;
        let table: toml::Table = toml::from_str(text).unwrap_or_default();
        let el = table
            .get("material")
            .and_then(|m| m.get("elasticity"))
            .and_then(|e| e.as_table());
        let num = |k: &str| {
            el.and_then(|e| e.get(k))
                .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
        };
        let laws = AllLawParams {
            shear_modulus: num("shear_modulus").unwrap_or(DEFAULT_SHEAR_MODULUS),
            bulk_modulus_per_volume: num("bulk_modulus_per_volume")
                .unwrap_or(DEFAULT_BULK_MODULUS_PER_VOLUME),
            bulk_modulus: num("bulk_modulus").unwrap_or(DEFAULT_BULK_MODULUS),
        };
        Ok(PhantomSpec {
            params,
            description: loaded.description,
            source: source.to_string(),
            laws,
        })
    }

    /// Read a phantom file, or the built-in hydrogel when `path` is `None`.
    pub fn load(path: Option<&Path>, grid_step_m: Option<f64>) -> Result<PhantomSpec, InputError> {
        match path {
            Some(p) => {
                let text = std::fs::read_to_string(p).map_err(|e| {
                    InputError::new(format!("cannot read phantom file: {e}")).in_file(p)
                })?;
                PhantomSpec::from_text(&text, p, &p.display().to_string(), grid_step_m)
            }
            None => PhantomSpec::from_text(
                HYDROGEL_PHANTOM,
                Path::new(HYDROGEL_PHANTOM_PATH),
                "built-in hydrogel-dive (profiles/phantoms/hydrogel-dive.toml)",
                grid_step_m,
            ),
        }
    }

    /// The phantom's own law name.
    pub fn own_law(&self) -> &'static str {
        self.params.elasticity.name()
    }

    /// The parameters with law `name`: the phantom's own law object for its own name, else
    /// built from [`PhantomSpec::laws`].
    pub fn with_law(&self, name: &str) -> Result<PhantomParams, Error> {
        let mut p = self.params.clone();
        if name != self.own_law() {
            let law: Box<dyn ElasticityLaw> = self.laws.build(name).map_err(Error::Solver)?;
            p.elasticity = Arc::from(law);
        }
        Ok(p)
    }

    /// Resolve `--elasticity` values: empty → the phantom's own law; `all` → every law;
    /// otherwise names (comma-separated allowed), each registered.
    pub fn resolve_laws(&self, requested: &[String]) -> Result<Vec<&'static str>, InputError> {
        let names = law_names();
        let mut out: Vec<&'static str> = Vec::new();
        for r in requested.iter().flat_map(|s| s.split(',')) {
            let r = r.trim();
            if r.eq_ignore_ascii_case("all") {
                // the phantom's own law first: it is the primary law of the report's plots
                let own = self.own_law();
                if !out.contains(&own) {
                    out.push(own);
                }
                for n in &names {
                    if !out.contains(n) {
                        out.push(n);
                    }
                }
                continue;
            }
            let n = names
                .iter()
                .find(|n| n.eq_ignore_ascii_case(r))
                .ok_or_else(|| {
                    InputError::new(format!(
                        "unknown elasticity law '{r}'; use all or one of {}",
                        names.join(", ")
                    ))
                    .in_file("<command line>")
                    .field("--elasticity")
                })?;
            if !out.contains(n) {
                out.push(n);
            }
        }
        if out.is_empty() {
            out.push(self.own_law());
        }
        Ok(out)
    }
}

/// A schedule to evaluate.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Label (tables, legends); unique within an evaluation.
    pub label: String,
    /// Where it came from (algorithm or schedule file).
    pub source: String,
    /// The schedule.
    pub schedule: Schedule,
    /// The pressure history that drives the phantom ([`dive_history`]).
    pub history: PressureHistory,
    /// What was assumed or repaired importing it (dive logs); printed and reported.
    pub notes: Vec<String>,
}

/// The pressure history a schedule drives the phantom with (see the module documentation);
/// `repeat_after_min` repeats the dive after that surface interval.
pub fn dive_history(
    schedule: &Schedule,
    protocol: &Protocol,
    repeat_after_min: Option<f64>,
) -> Result<PressureHistory, InputError> {
    let bad = |m: String| InputError::new(m).field("schedule");
    let last = schedule.legs.last().map_or(0.0, |l| l.end_depth_m);
    if last.abs() > 1e-9 {
        return Err(bad(format!(
            "schedule '{}' never surfaces: its last leg ends at {last} m",
            schedule.label
        )));
    }
    let mut dive = schedule.to_pressure_history().map_err(bad)?;
    // the protocol's P_H2O, the one held in the bubbles too ([`breathed_gas_params`])
    dive.vapour_pa = protocol.water_vapour_pa;
    let surface = schedule.surface_pressure_pa;
    let at_surface = |s: f64| {
        PressureHistory::with_gas(
            "surface",
            vec![0.0, s],
            vec![surface, surface],
            GasMix::AIR,
            dive.vapour_pa,
        )
        .map_err(bad)
    };
    let mut h = dive.clone();
    if let Some(si) = repeat_after_min {
        if !(si.is_finite() && si > 0.0 && si * 60.0 <= crate::profile::MAX_DURATION_S) {
            return Err(InputError::new(format!(
                "surface interval must be a positive number of minutes, at most {} (30 days) (got {})",
                crate::profile::MAX_DURATION_S / 60.0,
                crate::error::num(si)
            ))
            .in_file("<command line>")
            .field("--repeat-after"));
        }
        h = h
            .then(&at_surface(si * 60.0)?)
            .and_then(|h| h.then(&dive))
            .map_err(bad)?;
    }
    if protocol.observe_after_surfacing_s > 0.0 {
        h = h
            .then(&at_surface(protocol.observe_after_surfacing_s)?)
            .map_err(bad)?;
    }
    h.inert_only = !protocol.oxygen_at_faces;
    h.label = schedule.label.clone();
    if h.gases().is_empty() {
        return Err(bad(
            "no inert gas (N2 or He) is ever breathed; nothing reaches the phantom".into(),
        ));
    }
    Ok(h)
}

/// The phantom's parameters for a breathed-gas run under `protocol`: every bubble holds the
/// gases that are not simulated at p_fixed = P_H2O + P_CO2 + P_vO2
/// ([`Protocol::bubble_fixed_gases_pa`]), the counterpart of the faces of [`dive_history`].
/// A phantom file that sets its own `material.bubble_fixed_gases_pa` is refused: for a
/// breathed gas the criteria protocol sets it.
pub fn breathed_gas_params(
    params: &PhantomParams,
    protocol: &Protocol,
) -> Result<PhantomParams, InputError> {
    if params.bubble_fixed_gases != 0.0 {
        return Err(InputError::new(format!(
            "the phantom sets bubble_fixed_gases_pa = {} Pa; for a breathed gas the criteria file's [protocol] sets the bubble's fixed gases (water_vapour_pa + co2_pa + venous_o2_pa = {} Pa): remove it from the phantom",
            params.bubble_fixed_gases,
            protocol.bubble_fixed_gases_pa()
        ))
        .field("material.bubble_fixed_gases_pa"));
    }
    let mut p = params.clone();
    p.bubble_fixed_gases = protocol.bubble_fixed_gases_pa();
    Ok(p)
}

/// One run of the matrix: a candidate under one elasticity law.
#[derive(Debug, Clone)]
pub struct RunOutcome {
    /// Index into [`Evaluation::candidates`].
    pub candidate: usize,
    /// Elasticity law name.
    pub law: &'static str,
    /// The simulation.
    pub run: SimRun,
    /// Scores, in criteria-file order.
    pub scores: Vec<Score>,
}

/// A finished evaluation.
#[derive(Debug)]
pub struct Evaluation {
    /// The schedules.
    pub candidates: Vec<Candidate>,
    /// The laws, in request order; the first is the "primary" one of the per-schedule plots.
    pub laws: Vec<&'static str>,
    /// Every run, candidate-major (candidate 0 under every law, then candidate 1 ...).
    pub runs: Vec<RunOutcome>,
    /// The phantom.
    pub phantom: PhantomSpec,
    /// The criteria.
    pub criteria: CriteriaSet,
    /// Runs taken from the journal of an earlier, unfinished evaluation into the same folder.
    pub resumed: usize,
}

impl Evaluation {
    /// The run of candidate `c` under `law`.
    pub fn run(&self, c: usize, law: &str) -> Option<&RunOutcome> {
        self.runs.iter().find(|r| r.candidate == c && r.law == law)
    }

    /// The name of a run in tables and legends: the schedule label, with the law when
    /// several laws were run.
    pub fn run_name(&self, r: &RunOutcome) -> String {
        if self.laws.len() > 1 {
            format!("{} · {}", self.candidates[r.candidate].label, r.law)
        } else {
            self.candidates[r.candidate].label.clone()
        }
    }

    /// True when every criterion passes on every run.
    pub fn all_pass(&self) -> bool {
        self.runs.iter().all(|r| r.scores.iter().all(|s| s.pass))
    }
}

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
    breathed_gas_params(&phantom.params, &criteria.protocol)
        .map_err(|e| Error::Input(e.in_file(&phantom.source)))?;
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

/// What `evaluate` needs.
#[derive(Debug, Clone)]
pub struct EvaluateRequest {
    /// Maximum depth, m (required with algorithms).
    pub depth_m: Option<f64>,
    /// Bottom time, min (required with algorithms).
    pub time_min: Option<f64>,
    /// Bottom gas (air if absent).
    pub gas: Option<String>,
    /// Deco gases (`50@21`, `O2`).
    pub deco_gases: Vec<String>,
    /// Travel gases (`21/35@0..60`), repeatable.
    pub travel_gases: Vec<String>,
    /// Algorithm files (at least one algorithm or schedule).
    pub algorithms: Vec<PathBuf>,
    /// Schedule files compared as they are (TOML, CSV, legacy .txt, dive logs).
    pub schedules: Vec<PathBuf>,
    /// Which dive of a dive log given as a schedule (1-based).
    pub dive: Option<crate::profile::sequence::DiveSelection>,
    /// Elasticity laws (`all`, names; empty → the phantom's own).
    pub elasticity: Vec<String>,
    /// Phantom file (built-in hydrogel-dive if absent).
    pub phantom: Option<PathBuf>,
    /// Grid step override, m.
    pub grid_step_m: Option<f64>,
    /// Criteria file.
    pub criteria: PathBuf,
    /// Repeat the dive after this surface interval, min.
    pub repeat_after_min: Option<f64>,
    /// Output folder.
    pub out: PathBuf,
}

/// Plan with each algorithm: the candidates (labels made unique with the file stem).
#[allow(clippy::too_many_arguments)] // the dive's fields, as on the command line
pub fn plan_candidates(
    algorithms: &[(LoadedAlgorithm, String)],
    depth_m: f64,
    time_min: f64,
    gas: Option<&str>,
    deco_gases: &[String],
    travel_gases: &[String],
    protocol: &Protocol,
    repeat_after_min: Option<f64>,
) -> Result<Vec<Candidate>, InputError> {
    let mut out: Vec<Candidate> = Vec::new();
    for (alg, source) in algorithms {
        let (_, schedule) = plan_dive(alg, depth_m, time_min, gas, deco_gases, travel_gases)?;
        let mut label = alg.label.clone();
        if out.iter().any(|c| c.label == label) {
            let stem = Path::new(source)
                .file_stem()
                .map_or_else(|| source.clone(), |s| s.to_string_lossy().into_owned());
            label = format!("{label} ({stem})");
        }
        let history = dive_history(&schedule, protocol, repeat_after_min)?;
        out.push(Candidate {
            label,
            source: source.clone(),
            schedule,
            history,
            notes: Vec::new(),
        });
    }
    Ok(out)
}

/// Candidates from schedule files (plan --out TOML, waypoint CSV, legacy .txt, or a dive of a
/// Subsurface/UDDF log, `dive` 1-based), in DecoTengu conventions where the file states none;
/// each watched after surfacing as the protocol says. Labels are made unique with the file
/// stem.
pub fn schedule_candidates(
    files: &[PathBuf],
    dive: Option<crate::profile::sequence::DiveSelection>,
    protocol: &Protocol,
    repeat_after_min: Option<f64>,
    taken: &[Candidate],
) -> Result<Vec<Candidate>, InputError> {
    use crate::algorithm::conventions::DECOTENGU;
    use crate::algorithm::waypoints::read_schedule_with_notes;
    use crate::profile::is_dive_log;
    if dive.is_some() && !files.iter().any(|f| is_dive_log(f)) {
        return Err(InputError::new(
            "--dive applies to a dive log (.xml, .ssrf, .uddf) given with --schedule; there is none",
        )
        .in_file("<command line>")
        .field("--dive"));
    }
    let mut out: Vec<Candidate> = Vec::new();
    for path in files {
        // the dive number is for the logs among the schedules
        let d = if is_dive_log(path) { dive } else { None };
        let imp = read_schedule_with_notes(path, &DECOTENGU, crate::gas::GasMix::AIR, d)?;
        let history =
            dive_history(&imp.schedule, protocol, repeat_after_min).map_err(|e| e.in_file(path))?;
        let mut label = imp.schedule.label.clone();
        if taken.iter().chain(&out).any(|c| c.label == label) {
            label = format!("{label} ({})", path.display());
        }
        out.push(Candidate {
            label,
            source: path.display().to_string(),
            schedule: imp.schedule,
            history,
            notes: imp.notes,
        });
    }
    Ok(out)
}

/// Run `evaluate`: plan, simulate, score, write the report. Returns the evaluation.
pub fn run(
    req: &EvaluateRequest,
    progress: &mut (dyn FnMut(f64, f64) + Send),
) -> Result<Evaluation, Error> {
    if req.algorithms.is_empty() && req.schedules.is_empty() {
        return Err(
            InputError::new("give at least one --algorithm FILE or --schedule FILE")
                .in_file("<command line>")
                .field("--algorithm")
                .into(),
        );
    }
    let planned = if req.algorithms.is_empty() {
        None
    } else {
        let need = |v: Option<f64>, flag: &str| {
            v.ok_or_else(|| {
                InputError::new(format!("planning with --algorithm needs {flag}"))
                    .in_file("<command line>")
                    .field(flag)
            })
        };
        Some((need(req.depth_m, "--depth")?, need(req.time_min, "--time")?))
    };
    // the output folder is checked before anything is simulated (and again at the commit)
    let mut inputs: Vec<&Path> = vec![req.criteria.as_path()];
    inputs.extend(req.algorithms.iter().map(|p| p.as_path()));
    inputs.extend(req.schedules.iter().map(|p| p.as_path()));
    inputs.extend(req.phantom.as_deref());
    crate::report::output::check_target(&req.out, &inputs)?;
    let criteria = load_criteria(&req.criteria)?;
    let phantom = PhantomSpec::load(req.phantom.as_deref(), req.grid_step_m)?;
    let laws = phantom.resolve_laws(&req.elasticity)?;
    let algs = req
        .algorithms
        .iter()
        .map(|p| load_algorithm(p).map(|a| (a, p.display().to_string())))
        .collect::<Result<Vec<_>, _>>()?;
    let mut candidates = match planned {
        Some((depth_m, time_min)) => plan_candidates(
            &algs,
            depth_m,
            time_min,
            req.gas.as_deref(),
            &req.deco_gases,
            &req.travel_gases,
            &criteria.protocol,
            req.repeat_after_min,
        )?,
        None => Vec::new(),
    };
    let from_files = schedule_candidates(
        &req.schedules,
        req.dive,
        &criteria.protocol,
        req.repeat_after_min,
        &candidates,
    )?;
    candidates.extend(from_files);
    let (ev, journal) = run_matrix_journaled(
        candidates,
        phantom,
        laws,
        criteria,
        progress,
        Some(&req.out),
    )?;
    let mut parts: Vec<String> = Vec::new();
    if let Some((depth_m, time_min)) = planned {
        parts.push(format!(
            "{} m for {} min on {}{}{}",
            depth_m,
            time_min,
            req.gas.as_deref().unwrap_or("air"),
            if req.deco_gases.is_empty() {
                String::new()
            } else {
                format!(", deco gases {}", req.deco_gases.join(", "))
            },
            if req.travel_gases.is_empty() {
                String::new()
            } else {
                format!(", travel gases {}", req.travel_gases.join(", "))
            }
        ));
    }
    for f in &req.schedules {
        parts.push(format!("schedule {}", f.display()));
    }
    let dive = parts.join("; ");
    let mut page = Page::new(format!("Decompression report: {dive}"));
    let mut set = OutputSet::new();
    let ctx = ReportContext {
        dive,
        criteria_source: req.criteria.display().to_string(),
        repeat_after_min: req.repeat_after_min,
        command: None,
    };
    add_report(&mut page, &mut set, "", &ev, &ctx)?;
    finish_page(&mut page, &mut set, "")?;
    set.commit_with_inputs(&req.out, &inputs)?;
    if let Some(j) = journal {
        j.finish();
    }
    Ok(ev)
}

/// What the report says about where its inputs came from.
#[derive(Debug, Clone, Default)]
pub struct ReportContext {
    /// The dive in words.
    pub dive: String,
    /// The criteria file.
    pub criteria_source: String,
    /// Surface interval of a repetitive dive, min.
    pub repeat_after_min: Option<f64>,
    /// The command that produced the report, if it should be quoted.
    pub command: Option<String>,
}

fn plot_err(e: impl std::fmt::Display) -> Error {
    Error::Solver(format!("plot: {e}"))
}

fn fmt_min(x: f64) -> String {
    if (x - x.round()).abs() < 1e-9 {
        format!("{}", x.round())
    } else {
        format!("{x:.1}")
    }
}

/// The schedule table: stops, gases, runtime.
pub fn schedule_table(ev: &Evaluation) -> Result<Table, Error> {
    let mut t = Table::new(
        "Schedules",
        vec![
            Column::plain("schedule"),
            Column::plain("source"),
            Column::plain("stops (depth m × min)"),
            Column::plain("gases"),
            Column::new("stop_time", "min"),
            Column::new("runtime", "min"),
        ],
    );
    for c in &ev.candidates {
        let s = &c.schedule;
        let stops = if s.stops.is_empty() {
            "none".to_string()
        } else {
            s.stops
                .iter()
                .map(|st| format!("{}×{}", fmt_min(st.depth_m), fmt_min(st.stop_min)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut gases: Vec<String> = Vec::new();
        for l in &s.legs {
            let g = gas_text(l.gas);
            if !gases.contains(&g) {
                gases.push(g);
            }
        }
        t.push(vec![
            Cell::text(&c.label),
            Cell::text(&c.source),
            Cell::text(stops),
            Cell::text(gases.join(", ")),
            Cell::fixed(s.stops.iter().map(|st| st.stop_min).sum::<f64>(), 1),
            Cell::fixed(s.runtime_min(), 1),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(t)
}

/// `scores.csv`: one row per run and criterion, keyed by the criterion's registry `kind`
/// (stable) with the criteria file's `label` in its own column, numbers at full precision
/// (the shortest text that reads back to the same f64): `schedule,elasticity,kind,label,unit,
/// value,limit,margin,value_over_limit,result,absolute_value` (`absolute_value`: the absolute
/// value behind a growth score, e.g. the peak volume with the nuclei; empty for the others).
pub fn scores_csv(ev: &Evaluation) -> Result<String, Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| Error::Solver(format!("scores.csv: {e}"));
    w.write_record([
        "schedule",
        "elasticity",
        "kind",
        "label",
        "unit",
        "value",
        "limit",
        "margin",
        "value_over_limit",
        "result",
        "absolute_value",
    ])
    .map_err(csv_err)?;
    for r in &ev.runs {
        for s in &r.scores {
            w.write_record([
                ev.candidates[r.candidate].label.as_str(),
                r.law,
                s.kind,
                s.label.as_str(),
                s.unit,
                &s.value.to_string(),
                &s.limit.to_string(),
                &s.margin.to_string(),
                &s.ratio().to_string(),
                if s.pass { "pass" } else { "FAIL" },
                &s.absolute.map(|a| a.to_string()).unwrap_or_default(),
            ])
            .map_err(csv_err)?;
        }
    }
    let bytes = w
        .into_inner()
        .map_err(|e| Error::Solver(format!("scores.csv: {e}")))?;
    String::from_utf8(bytes).map_err(|e| Error::Solver(format!("scores.csv: {e}")))
}

/// The scores, one row per run and criterion, rounded for reading (the report's table;
/// `scores.csv` has them at full precision, [`scores_csv`]).
pub fn scores_table(ev: &Evaluation) -> Result<Table, Error> {
    let mut t = Table::new(
        "Criteria per schedule",
        vec![
            Column::plain("schedule"),
            Column::plain("elasticity"),
            Column::plain("criterion"),
            Column::plain("unit"),
            Column::plain("value"),
            Column::plain("limit"),
            Column::plain("margin"),
            Column::plain("value/limit"),
            Column::plain("result"),
            Column::plain("absolute"),
        ],
    );
    for r in &ev.runs {
        for s in &r.scores {
            t.push(vec![
                Cell::text(&ev.candidates[r.candidate].label),
                Cell::text(r.law),
                Cell::text(&s.label),
                Cell::text(s.unit),
                Cell::sig(s.value, 4),
                Cell::sig(s.limit, 4),
                Cell::sig(s.margin, 4),
                Cell::fixed(s.ratio(), 3),
                Cell::text(if s.pass { "pass" } else { "FAIL" }),
                match s.absolute {
                    Some(a) => Cell::sig(a, 4),
                    None => Cell::text(""),
                },
            ])
            .map_err(Error::Solver)?;
        }
    }
    Ok(t)
}

/// Relative floor of the numerical uncertainty of a criterion's value, as a fraction of the
/// larger of the largest |value| and the limit: the round-off and solver-tolerance noise of
/// runs that should give the same number (nuclei that never grow give dA/dt of 10⁻¹⁰ µm²/s
/// and volume·time of 10⁻¹² mm³·min, zero up to that noise). The discretisation error (grid
/// step; the step tolerance, ≈ 0.3 % on a radius at the default `bubble_tolerance`) is not in
/// it: it shifts the values of every schedule run on the same grid alike.
pub const TIE_RELATIVE_UNCERTAINTY: f64 = 1e-6;

/// The numerical uncertainty of one criterion across runs with `values` and `limit`
/// ([`TIE_RELATIVE_UNCERTAINTY`]).
pub fn criterion_uncertainty(values: &[f64], limit: f64) -> f64 {
    let big = values.iter().fold(limit.abs(), |m, v| m.max(v.abs()));
    TIE_RELATIVE_UNCERTAINTY * big
}

/// A criterion on which every schedule under one law scores the same within the numerical
/// uncertainty: it does not rank them.
#[derive(Debug, Clone, PartialEq)]
pub struct Tie {
    /// Elasticity law.
    pub law: &'static str,
    /// Index of the criterion (criteria-file order).
    pub criterion: usize,
    /// Largest minus smallest value over the schedules, in the criterion's unit.
    pub spread: f64,
    /// The numerical uncertainty ([`criterion_uncertainty`]), in the criterion's unit.
    pub uncertainty: f64,
}

/// The criteria on which the schedules are tied, per law (only with two or more schedules).
pub fn ties(ev: &Evaluation) -> Vec<Tie> {
    let mut out = Vec::new();
    for law in &ev.laws {
        let runs: Vec<&RunOutcome> = ev.runs.iter().filter(|r| r.law == *law).collect();
        if runs.len() < 2 {
            continue;
        }
        for (k, c) in ev.criteria.criteria.iter().enumerate() {
            let v: Vec<f64> = runs.iter().map(|r| r.scores[k].value).collect();
            let (lo, hi) = v
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
                    (a.min(*x), b.max(*x))
                });
            let u = criterion_uncertainty(&v, c.limit);
            if hi - lo <= u {
                out.push(Tie {
                    law,
                    criterion: k,
                    spread: hi - lo,
                    uncertainty: u,
                });
            }
        }
    }
    out
}

/// One ranked run.
#[derive(Debug, Clone, PartialEq)]
pub struct Ranked {
    /// Elasticity law.
    pub law: &'static str,
    /// 1-based rank within the law; tied schedules share a rank (1, 1, 3).
    pub rank: usize,
    /// True when another schedule shares this rank.
    pub tied: bool,
    /// Candidate index.
    pub candidate: usize,
    /// Failed criteria.
    pub failures: usize,
    /// Largest value/limit and its criterion label, over the criteria that separate the
    /// schedules (all criteria when none does).
    pub worst: (f64, String),
    /// Mean value/limit over the same criteria.
    pub mean_ratio: f64,
}

/// Rank the schedules under each law: fewest failed criteria first, then the smallest
/// worst value/limit, then the smallest mean value/limit, both over the criteria that
/// separate the schedules ([`ties`] leaves out the others). Two schedules share a rank when
/// they fail as many criteria and their worst and mean value/limit differ by no more than the
/// numerical uncertainty ([`criterion_uncertainty`] over the limit).
pub fn ranking(ev: &Evaluation) -> Vec<Ranked> {
    let ties = ties(ev);
    let mut out = Vec::new();
    for law in &ev.laws {
        let runs: Vec<&RunOutcome> = ev.runs.iter().filter(|r| r.law == *law).collect();
        let nk = ev.criteria.criteria.len();
        let mut used: Vec<usize> = (0..nk)
            .filter(|k| !ties.iter().any(|t| t.law == *law && t.criterion == *k))
            .collect();
        if used.is_empty() {
            used = (0..nk).collect();
        }
        // uncertainty of each used criterion's value/limit
        let u_ratio: Vec<f64> = used
            .iter()
            .map(|&k| {
                let v: Vec<f64> = runs.iter().map(|r| r.scores[k].value).collect();
                let limit = ev.criteria.criteria[k].limit;
                criterion_uncertainty(&v, limit) / limit
            })
            .collect();
        let u_worst = u_ratio.iter().copied().fold(0.0, f64::max);
        let u_mean = u_ratio.iter().sum::<f64>() / u_ratio.len().max(1) as f64;
        let mut rows: Vec<Ranked> = runs
            .iter()
            .map(|r| {
                let worst = used
                    .iter()
                    .map(|&k| (r.scores[k].ratio(), r.scores[k].label.clone()))
                    .fold((f64::NEG_INFINITY, String::new()), |a, b| {
                        if b.0 > a.0 {
                            b
                        } else {
                            a
                        }
                    });
                let n = used.len().max(1) as f64;
                Ranked {
                    law,
                    rank: 0,
                    tied: false,
                    candidate: r.candidate,
                    failures: r.scores.iter().filter(|s| !s.pass).count(),
                    worst,
                    mean_ratio: used.iter().map(|&k| r.scores[k].ratio()).sum::<f64>() / n,
                }
            })
            .collect();
        rows.sort_by(|a, b| {
            a.failures
                .cmp(&b.failures)
                .then(a.worst.0.total_cmp(&b.worst.0))
                .then(a.mean_ratio.total_cmp(&b.mean_ratio))
        });
        for i in 0..rows.len() {
            let same = i > 0 && {
                let (p, q) = (&rows[i - 1], &rows[i]);
                p.failures == q.failures
                    && (p.worst.0 - q.worst.0).abs() <= u_worst
                    && (p.mean_ratio - q.mean_ratio).abs() <= u_mean
            };
            if same {
                rows[i].rank = rows[i - 1].rank;
                rows[i].tied = true;
                rows[i - 1].tied = true;
            } else {
                rows[i].rank = i + 1;
            }
        }
        out.extend(rows);
    }
    out
}

fn ranking_table(ev: &Evaluation) -> Result<Table, Error> {
    let mut t = Table::new(
        "Ranking (per elasticity law: fewest failures, then smallest worst value/limit, then smallest mean, over the criteria that separate the schedules; equal ranks are ties)",
        vec![
            Column::plain("elasticity"),
            Column::plain("rank"),
            Column::plain("schedule"),
            Column::plain("failures"),
            Column::plain("worst criterion"),
            Column::plain("worst value/limit"),
            Column::plain("mean value/limit"),
        ],
    );
    for r in ranking(ev) {
        t.push(vec![
            Cell::text(r.law),
            Cell::text(if r.tied {
                format!("{} (tied)", r.rank)
            } else {
                r.rank.to_string()
            }),
            Cell::text(&ev.candidates[r.candidate].label),
            Cell::text(r.failures.to_string()),
            Cell::text(&r.worst.1),
            Cell::fixed(r.worst.0, 3),
            Cell::fixed(r.mean_ratio, 3),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(t)
}

/// The ties ([`ties`]) as a table, or `None` without any.
fn ties_table(ev: &Evaluation) -> Result<Option<Table>, Error> {
    let ties = ties(ev);
    if ties.is_empty() {
        return Ok(None);
    }
    let mut t = Table::new(
        "Ties: criteria on which the schedules score the same within the numerical uncertainty",
        vec![
            Column::plain("elasticity"),
            Column::plain("criterion"),
            Column::plain("unit"),
            Column::plain("spread between schedules"),
            Column::plain("numerical uncertainty"),
        ],
    );
    for tie in &ties {
        let s = &ev
            .runs
            .iter()
            .find(|r| r.law == tie.law)
            .map(|r| &r.scores[tie.criterion]);
        let Some(s) = s else { continue };
        t.push(vec![
            Cell::text(tie.law),
            Cell::text(&s.label),
            Cell::text(s.unit),
            Cell::sig(tie.spread, 2),
            Cell::sig(tie.uncertainty, 2),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(Some(t))
}

/// One sentence per law with ties: which criteria tie and that they are left out of the
/// ranking; empty without ties.
pub fn ties_text(ev: &Evaluation) -> String {
    let ties = ties(ev);
    let mut s = String::new();
    for law in &ev.laws {
        let names: Vec<String> = ties
            .iter()
            .filter(|t| t.law == *law)
            .map(|t| ev.criteria.criteria[t.criterion].label.clone())
            .collect();
        if names.is_empty() {
            continue;
        }
        let all = names.len() == ev.criteria.criteria.len();
        s.push_str(&format!(
            "Under {law} the schedules are tied on {}: their values differ by less than the numerical uncertainty, so {}.\n",
            names.join(", "),
            if all {
                "no criterion ranks them and they share rank 1"
            } else {
                "these criteria do not rank them (left out of the worst and mean value/limit of the ranking)"
            }
        ));
    }
    s
}

fn runs_table(ev: &Evaluation) -> Result<Table, Error> {
    let mut t = Table::new(
        "Phantom runs",
        vec![
            Column::plain("schedule"),
            Column::plain("elasticity"),
            Column::plain("ending"),
            Column::new("simulated", "min"),
            Column::plain("steps (explicit + implicit)"),
            Column::plain("gas-balance error"),
        ],
    );
    for r in &ev.runs {
        let s = &r.run.summary;
        t.push(vec![
            Cell::text(&ev.candidates[r.candidate].label),
            Cell::text(r.law),
            Cell::text(ending_text(&s.ending)),
            Cell::fixed(s.end_time / 60.0, 1),
            Cell::text(format!("{} + {}", s.steps.0, s.steps.1)),
            Cell::sig(s.gas_balance_error, 2),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(t)
}

/// What the `peak-area-growth-rate` criterion with `window = "after-surfacing"` takes the
/// peak of: from `surfaced_s` on, at the midpoint of each pair of recorded frames, the largest
/// dA/dt of a single bubble, (time s, m²/s).
pub fn area_rate_after_surfacing(frames: &[Frame], surfaced_s: f64) -> Vec<(f64, f64)> {
    let data = RunData {
        frames,
        surfaced_s: Some(surfaced_s),
    };
    let mut all: Vec<(f64, f64)> =
        series::per_bubble(data.window(crate::risk::Window::AfterSurfacing), |b| b.area)
            .values()
            .flat_map(|pts| series::rate(pts))
            .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (t, r) in all {
        match out.last_mut() {
            Some(last) if last.0 == t => last.1 = last.1.max(r),
            _ => out.push((t, r)),
        }
    }
    out
}

fn minutes(points: Vec<(f64, f64)>, scale: f64) -> Vec<(f64, f64)> {
    points
        .into_iter()
        .map(|(t, v)| (t / 60.0, v * scale))
        .collect()
}

/// Add the evaluation's sections to `page` and its files to `set` under `prefix` (e.g. `""`
/// or `"dive/"`). Writes `<prefix>scores.csv` and the SVGs.
pub fn add_report(
    page: &mut Page,
    set: &mut OutputSet,
    prefix: &str,
    ev: &Evaluation,
    ctx: &ReportContext,
) -> Result<(), Error> {
    let ph = &ev.phantom;
    let p = &ph.params;
    let cells = ev.runs.first().map_or(0, |r| r.run.summary.cells);
    let proto = &ev.criteria.protocol;
    let primary = ev.laws[0];
    let add_svg = |page: &mut Page,
                   set: &mut OutputSet,
                   name: &str,
                   svg: String,
                   caption: &str|
     -> Result<(), Error> {
        let file = format!("{prefix}{name}");
        page.figure(&svg, Some(&file), caption)
            .map_err(Error::Solver)?;
        set.add(file, svg);
        Ok(())
    };

    page.section("Inputs");
    let vapour = format!(
        "{} Pa for every schedule; every bubble holds the gases not simulated at {} Pa (water vapour {} + CO2 {} + venous O2 {} Pa, criteria `[protocol]`)",
        proto.water_vapour_pa,
        proto.bubble_fixed_gases_pa(),
        proto.water_vapour_pa,
        proto.co2_pa,
        proto.venous_o2_pa
    );
    let mut inputs = format!(
        "- Dive: **{}**{}\n- Phantom: **{}** from {} — grid step {:.1} µm, {} cells inside; {}\n- Criteria: `{}`{}\n- Linking: ambient pressure of the schedule at the gel; open faces in equilibrium with the inspired {} partial pressures, fraction × (ambient − water vapour), water vapour {}; saturated at the surface at t = 0; watched {} min at the surface on air after the schedule ends.\n- Elasticity laws: {} (μ = {} Pa; M = {} Pa/µm³ and K = {} GPa where the phantom gives none: the paper's Fig. 2a values 5 × 10⁻² Pa/µm³ and 2.2 GPa).",
        ctx.dive,
        ctx.repeat_after_min
            .map(|s| format!(", repeated after a {s} min surface interval"))
            .unwrap_or_default(),
        p.name,
        ph.source,
        p.grid_step * 1e6,
        cells,
        ph.description.replace('\n', " "),
        ctx.criteria_source,
        if ev.criteria.description.is_empty() {
            String::new()
        } else {
            format!(" — {}", ev.criteria.description.replace('\n', " "))
        },
        if proto.oxygen_at_faces {
            "gas (O2 included)"
        } else {
            "inert-gas (N2, He; O2 left out)"
        },
        vapour,
        fmt_min(proto.observe_after_surfacing_s / 60.0),
        ev.laws.join(", "),
        ph.laws.shear_modulus,
        crate::report::plot::fmt_tick(ph.laws.bulk_modulus_per_volume * 1e-18),
        crate::report::plot::fmt_tick(ph.laws.bulk_modulus * 1e-9),
    );
    if let Some(cmd) = &ctx.command {
        inputs.push_str(&format!("\n- Produced by: `{cmd}`"));
    }
    for c in ev.candidates.iter().filter(|c| !c.notes.is_empty()) {
        inputs.push_str(&format!("\n- Import notes for {}:", c.label));
        for n in &c.notes {
            inputs.push_str(&format!("\n    - {n}"));
        }
    }
    page.text(inputs);

    page.section("Schedules");
    page.table(&schedule_table(ev)?);
    let mut prof = LinePlot::new(
        "Dive profiles as applied to the phantom",
        "time (min)",
        "depth (m)",
    );
    prof.y_down = true;
    let mut press = LinePlot::new(
        "Ambient pressure at the gel",
        "time (min)",
        "ambient pressure (kPa, absolute)",
    );
    for c in &ev.candidates {
        let h = &c.history;
        let pts = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
            h.times_s
                .iter()
                .zip(&h.ambient_pa)
                .map(|(t, pa)| (t / 60.0, f(*pa)))
                .collect()
        };
        let s = &c.schedule;
        prof = prof.with(Series::new(
            &c.label,
            pts(&|pa| (pa - s.surface_pressure_pa) / s.pa_per_m),
        ));
        press = press.with(Series::new(&c.label, pts(&|pa| pa * 1e-3)));
    }
    add_svg(
        page,
        set,
        "profiles.svg",
        prof.to_svg().map_err(plot_err)?,
        "Depth against time for each schedule, including the time watched at the surface.",
    )?;
    add_svg(
        page,
        set,
        "pressure.svg",
        press.to_svg().map_err(plot_err)?,
        "The ambient pressure that acts on the gel.",
    )?;

    page.section("Scores");
    let scores = scores_table(ev)?;
    set.add(format!("{prefix}scores.csv"), scores_csv(ev)?);
    let mut crit = String::from(
        "Criteria (value ≤ limit passes; margin = limit − value). Peak volume and peak radius \
         score the growth the schedule causes, above each bubble's initial radius R0 (`measure = \
         \"growth\"`, the default); the table's *absolute* column gives the absolute peak beside \
         them, nuclei included:\n",
    );
    for c in &ev.criteria.criteria {
        crit.push_str(&format!(
            "\n- **{}** (`{}`, {}): {}; limit {}",
            c.label,
            c.criterion.name(),
            if c.criterion.unit().is_empty() {
                "dimensionless"
            } else {
                c.criterion.unit()
            },
            c.criterion.describe(),
            c.limit
        ));
    }
    page.text(crit);
    page.table(&ranking_table(ev)?);
    if let Some(t) = ties_table(ev)? {
        page.text(format!(
            "{}The numerical uncertainty of a criterion is {} × the larger of its largest |value| and its limit: the round-off and solver-tolerance noise of runs that should agree. The discretisation error (grid step; the step tolerance, about 0.3 % on a radius) is not in it, as it shifts every schedule on the same grid alike; differences between schedules smaller than that are nonetheless within the model's accuracy.",
            ties_text(ev),
            crate::report::table::sig_text(TIE_RELATIVE_UNCERTAINTY, 1, true)
        ));
        page.table(&t);
    }
    page.table(&scores);
    // one group per schedule under the primary law (the phantom's own): a legend of every
    // schedule × law would bury the bars; the other laws are in the tables above
    let primary_runs: Vec<&RunOutcome> = ev.runs.iter().filter(|r| r.law == ev.laws[0]).collect();
    let groups: Vec<String> = primary_runs
        .iter()
        .map(|r| ev.candidates[r.candidate].label.clone())
        .collect();
    let bars = BarChart {
        title: format!(
            "Each criterion as a fraction of its limit ({} elasticity)",
            ev.laws[0]
        ),
        x_label: "criterion".into(),
        y_label: "value / limit (1 = limit)".into(),
        categories: ev
            .criteria
            .criteria
            .iter()
            .map(|c| c.label.clone())
            .collect(),
        groups,
        values: (0..ev.criteria.criteria.len())
            .map(|k| primary_runs.iter().map(|r| r.scores[k].ratio()).collect())
            .collect(),
        reference: Some((1.0, "limit".into())),
        size: DEFAULT_SIZE,
    };
    add_svg(
        page,
        set,
        "criteria.svg",
        bars.to_svg().map_err(plot_err)?,
        "value/limit of every criterion for every schedule under the primary elasticity law; bars above the limit line fail.",
    )?;

    page.section(format!("Bubbles ({primary} elasticity)"));
    let mut vol = LinePlot::new(
        format!("Total bubble volume ({primary})"),
        "time (min)",
        "total bubble volume (mm³)",
    );
    let mut area = LinePlot::new(
        format!("Total bubble surface area ({primary})"),
        "time (min)",
        "total surface area (mm²)",
    );
    let mut rate = LinePlot::new(
        format!("Fastest single-bubble dA/dt after surfacing ({primary})"),
        "time after surfacing (min)",
        "largest dA/dt of one bubble (µm²/s)",
    );
    let mut ss = LinePlot::new(
        format!("Gel supersaturation, largest over all gel cells ({primary})"),
        "time (min)",
        "Σ tension + p_fixed − ambient (kPa)",
    );
    for (c, cand) in ev.candidates.iter().enumerate() {
        let Some(r) = ev.run(c, primary) else {
            continue;
        };
        let f = &r.run.frames;
        vol = vol.with(Series::new(
            &cand.label,
            minutes(series::total_volume(f), 1e9),
        ));
        let surfaced = cand.history.final_arrival_s();
        rate = rate.with(Series::new(
            &cand.label,
            area_rate_after_surfacing(f, surfaced)
                .into_iter()
                .map(|(t, v)| ((t - surfaced) / 60.0, v * 1e12))
                .collect(),
        ));
        area = area.with(Series::new(
            &cand.label,
            minutes(series::total_area(f), 1e6),
        ));
        ss = ss.with(Series::new(
            &cand.label,
            f.iter()
                .map(|fr| (fr.time / 60.0, fr.max_supersaturation * 1e-3))
                .collect(),
        ));
    }
    add_svg(
        page,
        set,
        "volume.svg",
        vol.to_svg().map_err(plot_err)?,
        "Total volume of all bubbles in the phantom for each schedule.",
    )?;
    for (c, cand) in ev.candidates.iter().enumerate() {
        let Some(r) = ev.run(c, primary) else {
            continue;
        };
        let mut rad = LinePlot::new(
            format!("Bubble radius: {} ({primary})", cand.label),
            "time (min)",
            "radius (µm)",
        );
        for (id, pts) in series::per_bubble(&r.run.frames, |b| b.radius) {
            rad = rad.with(Series::new(format!("bubble {id}"), minutes(pts, 1e6)));
        }
        add_svg(
            page,
            set,
            &format!("radius-{}.svg", c + 1),
            rad.to_svg().map_err(plot_err)?,
            &format!("Radius of each bubble under {}.", cand.label),
        )?;
    }
    add_svg(
        page,
        set,
        "area.svg",
        area.to_svg().map_err(plot_err)?,
        "Total surface area of all bubbles.",
    )?;
    add_svg(
        page,
        set,
        "area-rate.svg",
        rate.to_svg().map_err(plot_err)?,
        "From the moment each schedule surfaces (time 0 here): at each interval between recorded frames, the largest surface-area growth rate dA/dt of a single bubble. The `peak-area-growth-rate` criterion with `window = \"after-surfacing\"` scores the peak of this curve; the Boyle expansion of the ascent, before surfacing, is left out as it is by the criterion.",
    )?;
    add_svg(
        page,
        set,
        "supersaturation.svg",
        ss.to_svg().map_err(plot_err)?,
        "The largest supersaturation of any gel cell at each recorded frame: dissolved inert-gas tension plus the bubbles' fixed gases (water vapour, CO2, venous O2) minus ambient pressure. The `peak-supersaturation` criterion with `at = \"gel\"` (the default) scores the peak of this curve.",
    )?;

    if ev.laws.len() > 1 {
        page.section("Elasticity laws compared");
        page.text("The same schedules through the same phantom under each tissue-elasticity law (the paper's eqs. 2.6–2.9; `none` is Ω = 0).");
        for (c, cand) in ev.candidates.iter().enumerate() {
            let mut el = LinePlot::new(
                format!("Total bubble volume under each law: {}", cand.label),
                "time (min)",
                "total bubble volume (mm³)",
            );
            // the laws' curves lie on top of each other: dashes and markers tell them apart
            el.distinct = true;
            for law in &ev.laws {
                if let Some(r) = ev.run(c, law) {
                    el = el.with(Series::new(
                        *law,
                        minutes(series::total_volume(&r.run.frames), 1e9),
                    ));
                }
            }
            add_svg(
                page,
                set,
                &format!("elasticity-{}.svg", c + 1),
                el.to_svg().map_err(plot_err)?,
                &format!(
                    "Total bubble volume of {} under each elasticity law.",
                    cand.label
                ),
            )?;
        }
    }

    page.section("Phantom runs");
    page.table(&runs_table(ev)?);
    page.text("Wall-clock times of the runs are in `timing.csv` (they change from run to run, so the report leaves them out).");
    set.add(format!("{prefix}timing.csv"), timing_csv(ev));
    Ok(())
}

/// `timing.csv`: the wall time of every phantom run (schedule, elasticity, wall_s).
fn timing_csv(ev: &Evaluation) -> String {
    let mut out = String::from("schedule,elasticity,wall_s\n");
    for r in &ev.runs {
        let label = ev.candidates[r.candidate].label.replace('"', "\"\"");
        out.push_str(&format!("\"{label}\",{},{}\n", r.law, r.run.wall_seconds));
    }
    out
}

/// Close a page: the caveat on the hazard and model, then `report.html` and `report.md`
/// under `prefix`.
pub fn finish_page(page: &mut Page, set: &mut OutputSet, prefix: &str) -> Result<(), Error> {
    page.section("Reading this report");
    page.text("The phantom is a gel, not a diver: its bubbles rank schedules by how much gas they leave to come out of solution, under explicit and adjustable assumptions. The `hazard` criterion has the form of the BVM(3) family, P = 1 − exp(−∫ g·max(0, V − V_thr) dt), but its gain g and threshold V_thr are user parameters that this tool has **not** calibrated to human (or any) decompression-sickness data: it is a monotone score, not a probability of DCS.");
    set.add(
        format!("{prefix}report.html"),
        page.to_html().map_err(Error::Solver)?,
    );
    set.add(
        format!("{prefix}report.md"),
        page.to_markdown().map_err(Error::Solver)?,
    );
    Ok(())
}

/// A short text summary: the ranking under each law with failures and worst criterion.
pub fn summary_text(ev: &Evaluation) -> String {
    let mut s = String::new();
    for c in &ev.candidates {
        for n in &c.notes {
            s.push_str(&format!("note ({}): {n}\n", c.label));
        }
    }
    for r in ranking(ev) {
        s.push_str(&format!(
            "{:<26} {:>2}.{} {:<28} failures {}  worst {} ({:.3} of limit)\n",
            r.law,
            r.rank,
            if r.tied { " (tied)" } else { "" },
            ev.candidates[r.candidate].label,
            r.failures,
            r.worst.1,
            r.worst.0
        ));
    }
    s.push_str(&ties_text(ev));
    s
}

/// Load algorithms embedded as text (the demo): (text, path used in messages).
pub fn algorithms_from_text(
    list: &[(&str, &str)],
) -> Result<Vec<(LoadedAlgorithm, String)>, InputError> {
    list.iter()
        .map(|(text, path)| parse_algorithm(text, Path::new(path)).map(|a| (a, path.to_string())))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::{Leg, LegKind};
    use crate::gas::Gas;

    fn schedule(vapour: f64) -> Schedule {
        let leg = |kind, a: f64, b: f64, s: f64, gas| Leg {
            kind,
            start_depth_m: a,
            end_depth_m: b,
            duration_s: s,
            gas,
        };
        let tx = GasMix::new(0.18, 0.45).unwrap();
        Schedule {
            label: "t".into(),
            surface_pressure_pa: 101_325.0,
            pa_per_m: 10_000.0,
            water_vapour_pa: vapour,
            legs: vec![
                leg(LegKind::Descent, 0.0, 40.0, 200.0, tx),
                leg(LegKind::Bottom, 40.0, 40.0, 600.0, tx),
                leg(LegKind::Ascent, 40.0, 0.0, 400.0, tx),
            ],
            stops: vec![],
        }
    }

    #[test]
    fn uncertainty_floor_ties_numerical_zeros_not_real_differences() {
        // the demo under the Bulk-Modulus law: dA/dt of nuclei that never grow, 4.69e-10 and
        // 8.88e-11 µm²/s against a limit of 80: u = 1e-6 · 80 = 8e-5 µm²/s ≫ the spread
        let u = criterion_uncertainty(&[4.694e-10, 8.876e-11], 80.0);
        assert!((u - 8e-5).abs() < 1e-18);
        assert!(4.694e-10 - 8.876e-11 <= u);
        // peak radii 107.8 and 102.9 µm (limit 118): u = 1e-6 · 118 µm, far below 4.9 µm
        let u = criterion_uncertainty(&[107.8, 102.9], 118.0);
        assert!((u - 1.18e-4).abs() < 1e-15 && 107.8 - 102.9 > u);
        // a value above the limit sets the scale: 1e-6 · 131.6
        assert!((criterion_uncertainty(&[131.6, 102.9], 118.0) - 1.316e-4).abs() < 1e-15);
    }

    #[test]
    fn area_rate_plot_is_the_scored_window_per_bubble() {
        use crate::risk::testing::{bubble, frame};
        use std::f64::consts::PI;
        // two bubbles, frames at 0, 10, 20, 30 s, surfacing at 10 s. Before it bubble 0 shrinks
        // fast (the descent spike the plot must leave out); from it: b0 100 → 110 → 115 µm,
        // b1 50 → 70 → 71 µm. Rates 4π(R₂² − R₁²)/Δt: at 15 s b0 4π·2100/10 = 2638.9, b1
        // 4π·2400/10 = 3015.9 µm²/s (the larger); at 25 s b0 4π·1125/10 = 1413.7, b1
        // 4π·141/10 = 177.2 µm²/s.
        let f = vec![
            frame(
                0.0,
                3e5,
                0.0,
                vec![bubble(0, 300e-6, 0.0), bubble(1, 50e-6, 0.0)],
            ),
            frame(
                10.0,
                1e5,
                0.0,
                vec![bubble(0, 100e-6, 0.0), bubble(1, 50e-6, 0.0)],
            ),
            frame(
                20.0,
                1e5,
                0.0,
                vec![bubble(0, 110e-6, 0.0), bubble(1, 70e-6, 0.0)],
            ),
            frame(
                30.0,
                1e5,
                0.0,
                vec![bubble(0, 115e-6, 0.0), bubble(1, 71e-6, 0.0)],
            ),
        ];
        let got = area_rate_after_surfacing(&f, 10.0);
        let want = [(15.0, 4.0 * PI * 240.0), (25.0, 4.0 * PI * 112.5)];
        assert_eq!(got.len(), 2, "{got:?}");
        for ((t, r), (wt, wr)) in got.iter().zip(want) {
            assert_eq!(*t, wt);
            assert!((r * 1e12 - wr).abs() < 1e-9 * wr, "{r} vs {wr}");
        }
    }

    #[test]
    fn linking_subtracts_vapour_keeps_helium_and_drops_oxygen() {
        let p = Protocol {
            observe_after_surfacing_s: 600.0,
            ..Default::default()
        };
        // the protocol's vapour (6270 Pa) replaces the schedule's own (4930 Pa)
        let h = dive_history(&schedule(4930.0), &p, None).unwrap();
        // at the bottom (t = 500 s): ambient 101325 + 40·10000 = 501325 Pa; He 0.45 and N2 0.37
        // of (501325 − 6270) = 495055 Pa → 222774.75 and 183170.35 Pa; O2 left out.
        assert!((h.ambient(500.0) - 501_325.0).abs() < 1e-6);
        assert!((h.inspired_partial_pressure(Gas::He, 500.0) - 222_774.75).abs() < 1e-6);
        assert!((h.inspired_partial_pressure(Gas::N2, 500.0) - 183_170.35).abs() < 1e-6);
        assert_eq!(h.inspired_partial_pressure(Gas::O2, 500.0), 0.0);
        assert_eq!(h.gases(), vec![Gas::N2, Gas::He]);
        // observation at the surface on air: N2 0.79·(101325 − 6270) = 75093.45 Pa
        assert!((h.duration_s() - 1800.0).abs() < 1e-9);
        assert!((h.inspired_partial_pressure(Gas::N2, 1700.0) - 75_093.45).abs() < 1e-6);
        // the protocol's vapour replaces the schedule's; O2 kept when asked
        let p2 = Protocol {
            water_vapour_pa: 0.0,
            oxygen_at_faces: true,
            ..p
        };
        let h2 = dive_history(&schedule(6270.0), &p2, Some(30.0)).unwrap();
        assert!((h2.inspired_partial_pressure(Gas::O2, 500.0) - 0.18 * 501_325.0).abs() < 1e-6);
        // repetitive: dive (1200 s) + 30 min + dive + 10 min
        assert!((h2.duration_s() - (1200.0 + 1800.0 + 1200.0 + 600.0)).abs() < 1e-9);
        assert!((h2.ambient(1200.0 + 1800.0 + 500.0) - 501_325.0).abs() < 1e-6);
    }
}
