//! One phantom run, as every command runs it: a pressure profile through a phantom, every
//! frame recorded, with its progress, stop flag, checkpoints and the wall time of its phases
//! ([`simulate`] and its variants). `simulate`, `fit`, `discover`, `sweep`, `evaluate`,
//! `reproduce` and `demo` all run phantoms through here; the files of a run are in [`files`],
//! its plots in [`plots`], its texts for the terminal and reports in [`text`], the estimate of
//! its cost before it starts in [`cost`], and how many threads its grid loops take in
//! [`threads`].

pub mod cost;
pub mod files;
pub mod plots;
pub mod text;
pub mod threads;

pub use threads::{simulate_in_batch, with_grid_threads, GridThreads};

use crate::error::Error;
use crate::phantom::checkpoint::{self, Checkpoint, Checkpointer};
use crate::phantom::params::PhantomParams;
use crate::phantom::sim::{
    BubbleFrame, Frame, Observer, Recorder, RunSummary, Simulation, StepRecord, StepWall,
};
use crate::profile::{load, LoadOptions, PressureHistory};
use std::sync::atomic::{AtomicBool, Ordering};

/// Set when the user asks the process to stop (the binary's Ctrl-C handler). Every phantom
/// run started through [`simulate`] checks it each step and ends with
/// [`crate::error::Error::Interrupted`]; commands then write nothing half-done.
pub static INTERRUPT: AtomicBool = AtomicBool::new(false);

/// A finished run: its summary, frames and wall time.
#[derive(Debug, Clone)]
pub struct SimRun {
    /// The summary.
    pub summary: RunSummary,
    /// Recorded frames.
    pub frames: Vec<Frame>,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// Import notes of the profile (dive logs: defaults used, repairs, watch time).
    pub notes: Vec<String>,
    /// Checkpoints written (a checkpointed run), and the simulated time it resumed from.
    pub checkpoints: Option<checkpoint::Stats>,
    /// Simulated time the run was resumed from, s (`--resume`).
    pub resumed_at: Option<f64>,
    /// Every step the loop took (only when asked: `--trace-steps`; of a resumed run, the
    /// steps after the checkpoint).
    pub steps: Vec<TracedStep>,
    /// The wall time of the time loop's phases summed over the run's steps (of a resumed run,
    /// the steps after the checkpoint): `timing.toml`.
    pub phases: StepWall,
    /// Per scheme of the gel's step ([`StepScheme::ALL`](crate::phantom::sim::StepScheme::ALL) order), the steps taken and the wall
    /// time of their diffusion phase (`StepWall::gel_s`), s: `timing.toml`.
    pub gel_by_scheme: [(usize, f64); 3],
}

/// A step as `--trace-steps` keeps it: the loop's record and the wall time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TracedStep {
    /// What the loop reported.
    pub record: StepRecord,
    /// Wall time since the run (or its continuation) started when the step was done with its
    /// frame, s: the difference between two steps is the later step's cost.
    pub wall_s: f64,
}

struct WithProgress<'a> {
    rec: Recorder,
    /// The steps taken, when they are traced.
    steps: Option<Vec<TracedStep>>,
    /// The steps' phase times, summed.
    phases: StepWall,
    /// Per scheme, the steps and their diffusion's wall time ([`SimRun::gel_by_scheme`]).
    gel_by_scheme: [(usize, f64); 3],
    /// When the run started (the steps' wall times count from it).
    start: std::time::Instant,
    progress: &'a mut (dyn FnMut(f64, f64) + Send),
    stop: Option<&'a AtomicBool>,
    checkpointer: Option<&'a mut Checkpointer>,
}

impl WithProgress<'_> {
    fn stop_requested(&self) -> bool {
        self.stop.is_some_and(|s| s.load(Ordering::Relaxed))
    }
}

impl Observer for WithProgress<'_> {
    fn frame(&mut self, frame: &Frame) {
        self.rec.frame(frame);
    }
    fn step(&mut self, step: &StepRecord) {
        self.phases.add(&step.wall);
        let (n, s) = &mut self.gel_by_scheme[step.scheme.index()];
        *n += 1;
        *s += step.wall.gel_s;
        if let Some(steps) = &mut self.steps {
            steps.push(TracedStep {
                record: *step,
                wall_s: self.start.elapsed().as_secs_f64(),
            });
        }
    }
    fn progress(&mut self, time: f64, end: f64) {
        (self.progress)(time, end);
    }
    fn should_stop(&self) -> bool {
        let asked = self.stop_requested();
        match &self.checkpointer {
            Some(c) => c.let_stop(asked),
            None => asked,
        }
    }
    fn checkpoint_due(&mut self, step: usize) -> bool {
        let asked = self.stop_requested();
        self.checkpointer
            .as_mut()
            .is_some_and(|c| c.due(step, asked))
    }
    fn checkpoint(&mut self, state: checkpoint::RunState) -> Result<(), Error> {
        match self.checkpointer.as_mut() {
            Some(c) => c.write(&state, &self.rec.frames),
            None => Ok(()),
        }
    }
}

/// Run a profile through a phantom, recording every frame.
pub fn simulate(
    params: &PhantomParams,
    profile: &PressureHistory,
    progress: &mut (dyn FnMut(f64, f64) + Send),
) -> Result<SimRun, Error> {
    let run = simulate_until(params, profile, progress, Some(&INTERRUPT))?;
    if let crate::phantom::sim::Ending::Interrupted { time } = run.summary.ending {
        return Err(Error::Interrupted(format!(
            "run '{}' stopped at t = {time:.1} s of {:.1} s; its results are incomplete and were not used",
            profile.label,
            profile.duration_s()
        )));
    }
    Ok(run)
}

/// [`simulate`], stopping early (as [`Ending::Interrupted`](crate::phantom::sim::Ending::Interrupted)) once `stop` becomes true.
pub fn simulate_until(
    params: &PhantomParams,
    profile: &PressureHistory,
    progress: &mut (dyn FnMut(f64, f64) + Send),
    stop: Option<&AtomicBool>,
) -> Result<SimRun, Error> {
    simulate_checkpointed(params, profile, progress, stop, None, None, false)
}

/// [`simulate_until`] with checkpoints (`checkpointer`) and/or continued from a checkpoint
/// (`resume`: the checkpoint and its file, already checked against these inputs by
/// [`checkpoint::read`]); `trace`: keep every step ([`SimRun::steps`]).
///
/// The run itself executes on a thread of the current rayon pool (`rayon::scope`; inline when
/// called from one, as the batch runners do). Called from another thread, such as the
/// command line's main thread, its grid loops would otherwise start every parallel region
/// from outside the pool, which hands each one to a worker and back: on the small cube
/// (`benches/small-cube/`, one thread) 0.55–0.57 s against 0.45–0.48 s wall (session 11).
pub fn simulate_checkpointed(
    params: &PhantomParams,
    profile: &PressureHistory,
    progress: &mut (dyn FnMut(f64, f64) + Send),
    stop: Option<&AtomicBool>,
    mut checkpointer: Option<&mut Checkpointer>,
    resume: Option<(Checkpoint, &std::path::Path)>,
    trace: bool,
) -> Result<SimRun, Error> {
    let start = std::time::Instant::now();
    cost::check(params, profile)?;
    // every bubble holds at least the water vapour the open faces subtract
    let paired = params_for(params, profile)?;
    let params: &PhantomParams = &paired;
    let mut obs = WithProgress {
        rec: Recorder::default(),
        steps: trace.then(Vec::new),
        phases: StepWall::default(),
        gel_by_scheme: Default::default(),
        start,
        progress,
        stop,
        checkpointer: checkpointer.as_deref_mut(),
    };
    // a run started from outside the pool is its only work: it keeps the pool's workers awake
    // through its serial phases (`phantom::keep_warm`)
    let lone = rayon::current_thread_index().is_none();
    let (summary, resumed_at) = rayon::scope(|_| -> Result<_, Error> {
        crate::phantom::keep_warm::lone_run(lone, || {
            Ok(match resume {
                None => (
                    Simulation::new(params, profile)?.run(profile, &mut obs)?,
                    None,
                ),
                Some((mut cp, file)) => {
                    let at = cp.state.time();
                    obs.rec.frames = std::mem::take(&mut cp.frames);
                    (cp.resume(params, profile, &mut obs, file)?, Some(at))
                }
            })
        })
    })?;
    let frames = obs.rec.frames;
    let steps = obs.steps.unwrap_or_default();
    let (phases, gel_by_scheme) = (obs.phases, obs.gel_by_scheme);
    let mut notes = Vec::new();
    if let std::borrow::Cow::Owned(p) = &paired {
        notes.push(format!(
            "every bubble holds the {} Pa of water vapour the profile subtracts at the open faces (the phantom sets no material.bubble_fixed_gases_pa): one convention on both sides of the interface",
            crate::error::num(p.bubble_fixed_gases)
        ));
    }
    notes.extend(shut_throughout(&frames, params.min_radius));
    Ok(SimRun {
        summary,
        frames,
        wall_seconds: start.elapsed().as_secs_f64(),
        notes,
        checkpoints: checkpointer.map(|c| c.stats.clone()),
        resumed_at,
        steps,
        phases,
        gel_by_scheme,
    })
}

/// A note naming the bubbles that never exchanged gas because they stayed at or below R_min,
/// where the skin is impermeable (§2.1.4), in every recorded frame with their gas unchanged: a
/// result the reader must not take for "this dive forms no bubbles" (R_min defaults to the grid
/// step h, so a coarse grid shuts sub-grid bubbles for good). `None` if every bubble opened.
pub fn shut_throughout(frames: &[Frame], min_radius: f64) -> Option<String> {
    let first = frames.first()?;
    let shut: Vec<&BubbleFrame> = first
        .bubbles
        .iter()
        .filter(|b0| {
            frames.iter().all(|f| {
                f.bubbles
                    .iter()
                    .find(|b| b.id == b0.id)
                    .is_none_or(|b| b.radius <= min_radius && b.moles == b0.moles)
            })
        })
        .collect();
    if shut.is_empty() {
        return None;
    }
    let which = if shut.len() == first.bubbles.len() {
        "no bubble exchanged gas".to_string()
    } else {
        format!(
            "bubble{} {} never exchanged gas",
            if shut.len() > 1 { "s" } else { "" },
            shut.iter()
                .map(|b| b.id.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let r0 = shut
        .iter()
        .map(|b| b.initial_radius)
        .fold(f64::INFINITY, f64::min);
    Some(format!(
        "{which}: {} stayed at or below R_min = {} µm throughout, where a nucleus is impermeable (§2.1.4; nuclei.min_radius_m, whose default is the grid step h). To let a bubble of R0 = {} µm exchange gas, set nuclei.min_radius_m below it",
        if shut.len() > 1 { "they" } else { "it" },
        crate::report::table::sig_text(min_radius * 1e6, 4, true),
        crate::report::table::sig_text(r0 * 1e6, 4, true),
    ))
}

/// The phantom's parameters for a run of `profile`, as every command runs it: the bubbles'
/// fixed gases paired with the water vapour the history subtracts at the open faces
/// ([`PhantomParams::bubble_fixed_gases_for`]: the phantom's value when it holds that vapour,
/// the vapour itself when the phantom sets none, refused when it sets less). Borrowed when
/// nothing changes (no vapour, or the phantom's value kept); `evaluate` and `check` have set
/// theirs from the criteria's `[protocol]` already, which holds the faces' vapour.
/// [`Simulation::new`] itself takes its parameters as given (the analytic tests lower the
/// gel's tension with a "vapour" against a bubble of pure gas).
pub fn params_for<'p>(
    params: &'p PhantomParams,
    profile: &PressureHistory,
) -> Result<std::borrow::Cow<'p, PhantomParams>, Error> {
    let fixed = params.bubble_fixed_gases_for(profile)?;
    if fixed == params.bubble_fixed_gases {
        return Ok(std::borrow::Cow::Borrowed(params));
    }
    let mut p = params.clone();
    p.bubble_fixed_gases = fixed;
    Ok(std::borrow::Cow::Owned(p))
}

/// Load a pressure profile; a schedule written by `plan --out` is accepted too: a TOML with
/// `legs` (in its own conventions), or a CSV of waypoints `time_min,depth_m[,gas]` (in
/// the conventions of its `# conventions:` line, which `plan` writes, else DecoTengu's, starting
/// on air, as `check` and `evaluate` read it; a .csv goes to the legacy reader only with
/// `--units` and a header without those columns). Options that a schedule states itself
/// (`--units`, gas, surface pressure, water vapour, dive) are refused for it. A schedule becomes its
/// pressure history (ambient at the gel, breathed gas with the schedule's
/// water vapour at the open faces, the phantom saturated with surface air at the start, and
/// every bubble holding that vapour unless the phantom sets more:
/// [`PhantomParams::bubble_fixed_gases_for`]).
pub fn load_profile_or_schedule(
    path: &std::path::Path,
    opts: &LoadOptions,
) -> Result<PressureHistory, Error> {
    let has_extension = |ext: &str| {
        path.extension()
            .is_some_and(|e| e.eq_ignore_ascii_case(ext))
    };
    let text = || crate::error::read_text(path, "the profile").ok();
    let toml_schedule = has_extension("toml")
        && text()
            .and_then(|t| t.parse::<toml::Table>().ok())
            .is_some_and(|t| t.contains_key("legs"));
    // a .csv is a waypoint schedule unless --units asks for the legacy reader and its header
    // is not a waypoint header: so a .csv that is neither gets the waypoint reader's error
    let units_given = opts.time_unit.is_some() || opts.pressure_unit.is_some();
    let csv_schedule =
        has_extension("csv") && (!units_given || text().is_some_and(|t| is_waypoint_csv(&t)));
    if !(toml_schedule || csv_schedule) {
        return Ok(load(path, opts)?);
    }
    crate::profile::refuse_load_options(
        path,
        opts,
        "a schedule states its own depths, gases, surface pressure and water vapour (a .csv in its `# conventions:` line, DecoTengu's without one)",
    )?;
    let schedule = if toml_schedule {
        crate::algorithm::Schedule::read(path)?
    } else {
        // as `check` and `evaluate` read it
        crate::algorithm::waypoints::read_waypoints_csv(
            path,
            &crate::algorithm::conventions::DECOTENGU,
            crate::gas::GasMix::AIR,
        )?
    };
    schedule
        .to_pressure_history()
        .map_err(|m| Error::Input(crate::error::InputError::new(m).in_file(path)))
}

/// Whether a CSV file's header (its first line that is neither blank nor a `#` comment) names
/// a `time_min` and a `depth_m` column: a waypoint schedule (`time_min,depth_m[,gas]`, as
/// `plan --out` writes it).
fn is_waypoint_csv(text: &str) -> bool {
    let Some(header) = text
        .lines()
        .map(|l| l.trim_start_matches('\u{feff}').trim())
        .find(|l| !l.is_empty() && !l.starts_with('#'))
    else {
        return false;
    };
    let has = |name: &str| {
        header
            .split(',')
            .any(|c| c.trim().trim_matches('"').trim().eq_ignore_ascii_case(name))
    };
    has("time_min") && has("depth_m")
}

#[cfg(test)]
mod waypoint_csv_tests {
    use super::is_waypoint_csv;

    /// The header `plan --out x.csv` writes, in any column order, quoted or not, after comments,
    /// blank lines or a byte-order mark; not a legacy two-column profile or another CSV.
    #[test]
    fn a_waypoint_header_is_recognised_and_nothing_else() {
        assert!(is_waypoint_csv("time_min,depth_m,gas\n0,0,air\n"));
        assert!(is_waypoint_csv(
            "\u{feff}# from plan\n\n Depth_M , TIME_MIN\n0,0\n"
        ));
        assert!(is_waypoint_csv("\"time_min\",\"depth_m\"\n0,0\n"));
        assert!(!is_waypoint_csv("0 0\n1 130\n"));
        assert!(!is_waypoint_csv("time_s,pressure_pa\n0,101325\n"));
        assert!(!is_waypoint_csv("time_min\n0\n"));
        assert!(!is_waypoint_csv("# only a comment\n"));
    }
}

#[cfg(test)]
mod shut_tests {
    use super::*;

    fn frame(t: f64, bubbles: &[(usize, f64, f64)]) -> Frame {
        Frame {
            time: t,
            ambient: 101_325.0,
            bubbles: bubbles
                .iter()
                .map(|&(id, radius, moles)| BubbleFrame {
                    id,
                    radius,
                    initial_radius: 60e-6,
                    volume: 0.0,
                    area: 0.0,
                    moles: vec![moles],
                    gel_tension: 0.0,
                    position: [0.0; 3],
                })
                .collect(),
            max_supersaturation: f64::NAN,
            grid_moles: Vec::new(),
        }
    }

    /// A bubble that stayed at or below R_min with its gas unchanged is named; one that grew
    /// past R_min, or whose gas changed (it exchanged between frames), is not.
    #[test]
    fn bubbles_shut_throughout_are_named() {
        let r_min = 400e-6;
        // bubble 0 shut throughout (Boyle swelling at constant content), 1 opened, 2 took gas
        let frames = [
            frame(
                0.0,
                &[(0, 60e-6, 1e-9), (1, 300e-6, 1e-9), (2, 60e-6, 1e-9)],
            ),
            frame(
                10.0,
                &[(0, 80e-6, 1e-9), (1, 450e-6, 2e-9), (2, 61e-6, 1.1e-9)],
            ),
        ];
        let n = shut_throughout(&frames, r_min).unwrap();
        assert!(n.starts_with("bubble 0 never exchanged gas"), "{n}");
        assert!(
            n.contains("R_min = 400.0 µm") && n.contains("R0 = 60.00 µm"),
            "{n}"
        );
        // every bubble shut: said as such
        let all = [
            frame(0.0, &[(0, 60e-6, 1e-9)]),
            frame(5.0, &[(0, 70e-6, 1e-9)]),
        ];
        assert!(shut_throughout(&all, r_min)
            .unwrap()
            .starts_with("no bubble exchanged gas"));
        // every bubble opened, or no bubble at all: no note
        assert!(shut_throughout(&frames, 50e-6).is_none());
        assert!(shut_throughout(&[frame(0.0, &[])], r_min).is_none());
        assert!(shut_throughout(&[], r_min).is_none());
    }
}
