//! `decophantom evaluate`: plan one dive with several algorithms, run every schedule (under
//! every requested tissue-elasticity law) through the same phantom, score the runs with a
//! criteria file, rank them, and write the decompression report (`report.md`, a
//! self-contained `report.html`, `scores.csv`, the SVG plots). Wiring only: the pieces (linking
//! a schedule to the phantom, running the matrix in parallel, building the report) are in
//! [`crate::evaluate`], so `check` and `demo` use the same path.

use crate::algorithm::load_algorithm;
use crate::error::{Error, InputError};
use crate::evaluate::report::{add_report, finish_page, ReportContext};
use crate::evaluate::{schedule_candidates, Evaluation};
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::risk::load_criteria;
use std::path::{Path, PathBuf};

// Also the paths (`app::evaluate::X`) the integration tests use, from before the pieces moved
// to `crate::evaluate`.
pub use crate::evaluate::link::{breathed_gas_params, dive_history, PhantomSpec};
pub use crate::evaluate::matrix::run_matrix_journaled;
pub use crate::evaluate::plan_candidates;

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
    crate::evaluate::each_file_once(&req.algorithms, "--algorithm")?;
    crate::evaluate::each_file_once(&req.schedules, "--schedule")?;
    let planned = if req.algorithms.is_empty() {
        // the dive options only plan with an algorithm: a schedule keeps its own depths and
        // gases, so they would be dropped silently
        let unused = [
            ("--depth", req.depth_m.is_some()),
            ("--time", req.time_min.is_some()),
            ("--gas", req.gas.is_some()),
            ("--deco-gas", !req.deco_gases.is_empty()),
            ("--travel-gas", !req.travel_gases.is_empty()),
        ];
        if let Some((flag, _)) = unused.iter().find(|(_, given)| *given) {
            return Err(InputError::new(format!(
                "{flag} plans a dive with --algorithm; without one it does nothing (a --schedule is scored as it is, on its own gases): drop it or add --algorithm FILE"
            ))
            .in_file("<command line>")
            .field(*flag)
            .into());
        }
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
