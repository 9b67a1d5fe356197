//! `decophantom simulate`: one pressure profile through one phantom ([`crate::run`]). Writes
//! `bubbles.csv`, `summary.toml`, `radius.svg` and `volume.svg` into the output folder,
//! whole or not at all.

use crate::error::Error;
use crate::phantom::checkpoint::{self, Checkpointer};
use crate::phantom::config::load_phantom;
use crate::phantom::sim::Ending;
use crate::profile::LoadOptions;
use crate::report::output::OutputSet;
use crate::run::files::add_run_files;
use crate::run::{load_profile_or_schedule, simulate_checkpointed, SimRun};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// What `simulate` needs.
#[derive(Debug, Clone)]
pub struct SimulateRequest {
    /// Pressure profile (TOML, legacy two-column text with units, a dive log, or a `plan --out`
    /// schedule as TOML or waypoint CSV: [`load_profile_or_schedule`]).
    pub profile: PathBuf,
    /// Units etc. for legacy files.
    pub load: LoadOptions,
    /// Phantom TOML.
    pub phantom: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// Set to true (e.g. by a Ctrl-C handler) to stop the run early; what was simulated up to
    /// then is written, and the summary says where it stopped.
    pub stop: Option<std::sync::Arc<AtomicBool>>,
    /// Save the run's state every this much wall time (`--checkpoint-every`), into
    /// [`checkpoint::default_path`] of `out`.
    pub checkpoint_every: Option<std::time::Duration>,
    /// Test hook (hidden `--checkpoint-at-step`): save the state after this step, then stop
    /// as if interrupted.
    pub checkpoint_at_step: Option<usize>,
    /// Continue from this checkpoint (`--resume`: the file, or the folder holding it).
    pub resume: Option<PathBuf>,
    /// Keep every step the loop takes and write them to `steps.csv` (`--trace-steps`).
    pub trace_steps: bool,
}

/// Run `simulate` and write its outputs; returns the run.
pub fn run(
    req: &SimulateRequest,
    progress: &mut (dyn FnMut(f64, f64) + Send),
) -> Result<SimRun, Error> {
    // the output folder is checked before anything is simulated (and again at the commit)
    let inputs = [req.profile.as_path(), req.phantom.as_path()];
    crate::report::output::check_target(&req.out, &inputs)?;
    let (profile, notes) = if crate::profile::is_dive_log(&req.profile) {
        crate::profile::load_with_notes(&req.profile, &req.load)?
    } else {
        (
            load_profile_or_schedule(&req.profile, &req.load)?,
            Vec::new(),
        )
    };
    let phantom = load_phantom(&req.phantom)?;
    crate::phantom::config::require_bubbles(&phantom.params, &req.phantom)?;
    // the phantom's gases and the bubbles' fixed gases against this profile, before anything
    // runs, placed in the phantom file
    let in_phantom = |e| crate::phantom::config::in_phantom_file(e, &req.phantom);
    phantom
        .params
        .check_gases_for(&profile)
        .map_err(in_phantom)?;
    phantom
        .params
        .bubble_fixed_gases_for(&profile)
        .map_err(in_phantom)?;
    // checkpoints: the inputs as parsed, the checkpoint to resume checked against them, and the
    // place of this run's checkpoints, all before anything is simulated
    let identity = checkpoint::Inputs::new(&phantom.params, &profile);
    let resumed_from = req.resume.as_deref().map(checkpoint::locate);
    let resume = match &resumed_from {
        Some(file) => Some(checkpoint::read(file, &identity)?),
        None => None,
    };
    let mut checkpointer = if req.checkpoint_every.is_some() || req.checkpoint_at_step.is_some() {
        let path = checkpoint::default_path(&req.out);
        checkpoint::prepare(&path)?;
        Some(Checkpointer::new(
            path,
            identity,
            inputs.iter().map(|p| p.to_path_buf()).collect(),
            req.checkpoint_every,
            req.checkpoint_at_step,
        ))
    } else {
        None
    };
    let mut run = simulate_checkpointed(
        &phantom.params,
        &profile,
        progress,
        req.stop.as_deref(),
        checkpointer.as_mut(),
        resume.zip(resumed_from.as_deref()),
        req.trace_steps,
    )?;
    // the import's notes first, then the run's own (the bubbles' fixed gases)
    run.notes = notes
        .into_iter()
        .chain(std::mem::take(&mut run.notes))
        .collect();
    let mut set = OutputSet::new();
    add_run_files(&mut set, "", &run, &profile.label, &phantom.params.name)?;
    set.commit_with_inputs(&req.out, &inputs)?;
    // a finished run no longer needs its checkpoints (an interrupted one resumes from them)
    if !matches!(run.summary.ending, Ending::Interrupted { .. }) {
        if let Some(c) = &checkpointer {
            checkpoint::remove(&c.stats.path);
        }
        if let Some(f) = &resumed_from {
            checkpoint::remove(f);
        }
    }
    Ok(run)
}
