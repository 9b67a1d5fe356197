//! Evaluating decompression schedules with the phantom: plan one dive with several
//! algorithms, run every schedule (under every requested tissue-elasticity law) through the
//! same phantom, score the runs with a criteria file, rank them, and build the decompression
//! report (`report.md`, a self-contained `report.html`, `scores.csv`, the SVG plots). The pieces
//! are public so `evaluate`, `check` and `demo` ([`crate::app`]) use the same path:
//! - [`link`]: linking a schedule to the phantom (the phantom, the pressure history, the
//!   breathed-gas convention);
//! - [`matrix`]: running every candidate under every law through the phantom, in parallel,
//!   with a journal of the finished runs;
//! - [`rank`]: the ranking of the schedules, the ties and the numerical uncertainty;
//! - [`report`] (the report's sections, plots and page) and [`tables`] (its tables, CSV files
//!   and text summaries).
//!
//! This module holds the candidates, the runs and the evaluation they make. Nothing here touches
//! the terminal; [`crate::app::evaluate`] wires the command.

pub mod link;
pub mod matrix;
pub mod rank;
pub mod report;
pub mod tables;

use crate::algorithm::config::parse_algorithm;
use crate::algorithm::plan_dive;
use crate::algorithm::{LoadedAlgorithm, Schedule};
use crate::error::InputError;
use crate::profile::PressureHistory;
use crate::risk::{CriteriaSet, Protocol, Score};
use crate::run::SimRun;
use link::{dive_history, PhantomSpec};
use std::path::{Path, PathBuf};

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

/// Refuse (exit 2, naming `<command line>` and `flag`) a file given twice to a repeatable option
/// (`--schedule`, `--algorithm`), however spelt (`X`, `./X`, a symlink to it): it would be run
/// twice and ranked against itself, two identical rows that tie.
pub fn each_file_once(files: &[PathBuf], flag: &str) -> Result<(), InputError> {
    for (i, f) in files.iter().enumerate() {
        if let Some(first) = files[..i]
            .iter()
            .find(|g| *g == f || crate::report::output::same_file(g, f))
        {
            return Err(InputError::new(format!(
                "'{}' is the same file as '{}' given before; give each file once (it would be run twice and ranked against itself)",
                f.display(),
                first.display()
            ))
            .in_file("<command line>")
            .field(flag));
        }
    }
    Ok(())
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
        let history = dive_history(&imp.schedule, protocol, repeat_after_min)
            .map_err(|e| e.or_in_file(path))?;
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

/// Load algorithms embedded as text (the demo): (text, path used in messages).
pub fn algorithms_from_text(
    list: &[(&str, &str)],
) -> Result<Vec<(LoadedAlgorithm, String)>, InputError> {
    list.iter()
        .map(|(text, path)| parse_algorithm(text, Path::new(path)).map(|a| (a, path.to_string())))
        .collect()
}
