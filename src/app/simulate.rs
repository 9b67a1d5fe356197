//! `decophantom simulate`: one pressure profile through one phantom. Writes
//! `bubbles.csv`, `summary.toml`, `radius.svg` and `volume.svg` into the output folder,
//! whole or not at all.

use crate::error::Error;
use crate::gas::Gas;
use crate::phantom::checkpoint::{self, Checkpoint, Checkpointer};
use crate::phantom::config::load_phantom;
use crate::phantom::params::PhantomParams;
use crate::phantom::sim::{
    BubbleFrame, Ending, Event, Frame, Observer, Recorder, RunSummary, Simulation, StepRecord,
    StepScheme, StepWall,
};
use crate::profile::{load, LoadOptions, PressureHistory};
use crate::report::output::OutputSet;
use crate::report::plot::{LinePlot, Series};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};

/// What `simulate` needs.
#[derive(Debug, Clone)]
pub struct SimulateRequest {
    /// Pressure profile (TOML, legacy two-column text with units, or a dive log).
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
    /// Per scheme of the gel's step ([`StepScheme::ALL`] order), the steps taken and the wall
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
    let run = simulate_until(params, profile, progress, Some(&super::INTERRUPT))?;
    if let crate::phantom::sim::Ending::Interrupted { time } = run.summary.ending {
        return Err(Error::Interrupted(format!(
            "run '{}' stopped at t = {time:.1} s of {:.1} s; its results are incomplete and were not used",
            profile.label,
            profile.duration_s()
        )));
    }
    Ok(run)
}

/// [`simulate`], stopping early (as [`Ending::Interrupted`]) once `stop` becomes true.
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
    super::cost::check(params, profile)?;
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
    Ok(SimRun {
        summary,
        frames,
        wall_seconds: start.elapsed().as_secs_f64(),
        notes: Vec::new(),
        checkpoints: checkpointer.map(|c| c.stats.clone()),
        resumed_at,
        steps,
        phases,
        gel_by_scheme,
    })
}

/// How one simulation's grid loops (the diffusion kernels, the per-record pass over the gel)
/// use threads (issue 13: small runs are cheap). Every mode gives the same bits (the grid
/// loops combine their parts in a fixed order, whatever the thread count); only the time
/// differs.
///
/// Runners of many simulations at once (`sweep`/`sensitivity`, `fit`, `discover`, `evaluate`,
/// `reproduce`) run them in parallel through rayon and use [`GridThreads::batch`] for each:
/// [`GridThreads::Auto`] unless the environment variable `DECOPHANTOM_GRID_THREADS` says
/// `serial`, `parallel` or `auto`. A lone `simulate` runs its grid loops on every thread.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GridThreads {
    /// [`GridThreads::Serial`] for a grid of fewer than [`SMALL_GRID_CELLS`] cells, else
    /// [`GridThreads::Parallel`].
    #[default]
    Auto,
    /// Every grid loop on one thread: the run is installed in a one-thread rayon pool, so each
    /// `par_iter` inside it runs serially, with no fork/join per step. For small runs among
    /// many running in parallel, where the parallelism is across runs.
    Serial,
    /// Grid loops on the current rayon pool (nested in a runner's parallel loop over runs).
    Parallel,
}

/// Grids of fewer cells than this run serially in a batch ([`GridThreads::Auto`]): on a tiny
/// grid the per-step fork/join of grid-level parallelism costs more than the step (a 512-cell
/// cube: ~60 % of the run was thread wake-ups). At the 216 000-cell `benches/small-cube` the
/// two are even (8 runs at once, `cargo bench --bench small_runs`, 26 Nov 2026: 1.19–1.22 s
/// nested, 1.19–1.22 s serial inside); on its 4 mm version (64 000 cells,
/// `SMALL_RUNS_SIZE_MM=4`) serial inside is the faster, 407 ms against 431 ms. (Until 26 Nov
/// 2026 serial-inside runs were serialised, [`with_grid_threads`]: 749 ms there.)
pub const SMALL_GRID_CELLS: f64 = 2.0e5;

impl GridThreads {
    /// The mode for one of many simulations run at once: `DECOPHANTOM_GRID_THREADS`
    /// (`auto`, `serial` or `parallel`; read once) or [`GridThreads::Auto`].
    pub fn batch() -> GridThreads {
        static MODE: std::sync::OnceLock<GridThreads> = std::sync::OnceLock::new();
        *MODE.get_or_init(|| {
            match std::env::var("DECOPHANTOM_GRID_THREADS")
                .unwrap_or_default()
                .trim()
                .to_ascii_lowercase()
                .as_str()
            {
                "serial" => GridThreads::Serial,
                "parallel" => GridThreads::Parallel,
                _ => GridThreads::Auto,
            }
        })
    }

    /// Whether a run of `params` keeps its grid loops on one thread in this mode.
    pub fn serial_for(self, params: &PhantomParams) -> bool {
        match self {
            GridThreads::Serial => true,
            GridThreads::Parallel => false,
            GridThreads::Auto => estimated_cells(params) < SMALL_GRID_CELLS,
        }
    }
}

/// Cells of the grid of `params` (its bounding box over the grid step cubed; no grid is built).
pub fn estimated_cells(params: &PhantomParams) -> f64 {
    let extent = match params.shape {
        crate::phantom::grid::Shape::Box { size } => size[0] * size[1] * size[2],
        crate::phantom::grid::Shape::Cylinder { diameter, depth } => diameter * diameter * depth,
    };
    extent / params.grid_step.powi(3)
}

thread_local! {
    /// This thread's one-thread pool for [`with_grid_threads`] (built on first use).
    static ONE_THREAD: Option<rayon::ThreadPool> =
        rayon::ThreadPoolBuilder::new().num_threads(1).build().ok();
}

/// Run `f` (a simulation of `params`) with its grid loops as `mode` chooses for it: inside
/// this thread's one-thread pool when serial, on the current pool otherwise.
pub fn with_grid_threads<R: Send>(
    mode: GridThreads,
    params: &PhantomParams,
    f: impl FnOnce() -> R + Send,
) -> R {
    if !mode.serial_for(params) {
        return f();
    }
    ONE_THREAD.with(|pool| match pool {
        // from a worker of another pool (a runner's loop over runs), the run is handed to a
        // plain thread that waits in `install` without taking work: a worker waiting there
        // itself would run further runs of the batch inside its wait (rayon's cross-pool
        // `install`), queueing them behind this one in the same one-thread pool
        Some(pool) if rayon::current_thread_index().is_some() => std::thread::scope(|s| {
            s.spawn(|| pool.install(f))
                .join()
                .unwrap_or_else(|e| std::panic::resume_unwind(e))
        }),
        Some(pool) => pool.install(f),
        None => f(),
    })
}

/// [`simulate`] as one of many simulations run at once ([`GridThreads::batch`]).
pub fn simulate_in_batch(
    params: &PhantomParams,
    profile: &PressureHistory,
    progress: &mut (dyn FnMut(f64, f64) + Send),
) -> Result<SimRun, Error> {
    with_grid_threads(GridThreads::batch(), params, || {
        simulate(params, profile, progress)
    })
}

/// `bubbles.csv`: `time_s,bubble,radius_m,volume_m3,area_m2` then `n_<gas>_mol` per gas; one row per
/// active bubble per recorded frame.
pub fn bubbles_csv(frames: &[Frame], gases: &[Gas]) -> String {
    let mut s = String::from("time_s,bubble,radius_m,volume_m3,area_m2");
    for g in gases {
        s.push_str(&format!(",n_{}_mol", g.name()));
    }
    s.push('\n');
    for f in frames {
        for b in &f.bubbles {
            s.push_str(&format!(
                "{:.6},{},{:.9e},{:.9e},{:.9e}",
                f.time, b.id, b.radius, b.volume, b.area
            ));
            for n in &b.moles {
                s.push_str(&format!(",{n:.9e}"));
            }
            s.push('\n');
        }
    }
    s
}

#[derive(Serialize)]
struct SummaryFile<'a> {
    profile: &'a str,
    phantom: &'a str,
    ending: String,
    end_time_s: f64,
    max_radius_m: f64,
    max_radius_time_s: f64,
    max_radius_bubble: usize,
    final_radius_m: Vec<f64>,
    peak_total_volume_m3: f64,
    peak_total_volume_time_s: f64,
    gas_balance_error: f64,
    steps_explicit: usize,
    steps_implicit: usize,
    cells: usize,
    events: Vec<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    import_notes: Vec<String>,
}

/// A one-line description of how a run ended.
pub fn ending_text(e: &Ending) -> String {
    match e {
        Ending::Completed => "completed".into(),
        Ending::Interrupted { time } => {
            format!("interrupted at t = {time:.1} s; everything up to then is recorded")
        }
        Ending::BubbleReachedFace { bubble, face, time } => {
            format!(
                "bubble {bubble} reached the {} face at t = {time:.1} s; the run stopped there",
                face.name()
            )
        }
    }
}

fn event_text(e: &Event) -> String {
    match e {
        Event::Coalesced {
            time,
            into,
            absorbed,
        } => format!("t = {time:.1} s: bubble {absorbed} coalesced into {into}"),
        Event::Dissolved { time, bubble } => format!("t = {time:.1} s: bubble {bubble} dissolved"),
    }
}

/// `timing.toml` text: the run's wall-clock time, kept out of `summary.toml` so that the
/// summary of the same inputs is byte-identical from run to run (and a committed report does
/// not change when it is regenerated).
pub fn timing_toml(run: &SimRun) -> String {
    let p = &run.phases;
    format!(
        "# wall-clock time of this run on the machine that ran it (not a result)\n\
         wall_seconds = {}\n\n\
         # of it, the time loop's phases summed over the steps, s (src/phantom/sim/record.rs, StepWall):\n\
         # prepare: the bubbles' fluxes at the start of each step, the step's choice, the exchange;\n\
         # gel: the gel's diffusion; events: perfusion, radii, corrector, coalescence, nucleation,\n\
         # displacement (of them: corrector, displacement); frames: the frames recorded\n\
         [phases]\n\
         prepare_s = {:.6}\ngel_s = {:.6}\nevents_s = {:.6}\ncorrector_s = {:.6}\n\
         displacement_s = {:.6}\nframes_s = {:.6}\n",
        run.wall_seconds,
        p.prepare_s,
        p.gel_s,
        p.events_s,
        p.corrector_s,
        p.displacement_s,
        p.frame_s
    ) + &gel_by_scheme_toml(&run.gel_by_scheme)
}

/// `timing.toml`'s `[gel_by_scheme]`: per scheme of the gel's step, the steps taken and the
/// wall time of their diffusion (the cost of one step of each scheme is the ratio).
fn gel_by_scheme_toml(by: &[(usize, f64); 3]) -> String {
    let mut s = String::from(
        "\n# the steps of each scheme and the wall time of their diffusion (gel_s), s\n[gel_by_scheme]\n",
    );
    for (scheme, (n, t)) in StepScheme::ALL.iter().zip(by) {
        let name = scheme.name();
        s.push_str(&format!("{name}_steps = {n}\n{name}_s = {t:.6}\n"));
    }
    s
}

/// `summary.toml` text (results only: identical for identical inputs; the wall time is in
/// [`timing_toml`]).
pub fn summary_toml(run: &SimRun, profile: &str, phantom: &str) -> Result<String, Error> {
    let s = &run.summary;
    let f = SummaryFile {
        profile,
        phantom,
        ending: ending_text(&s.ending),
        end_time_s: s.end_time,
        max_radius_m: s.max_radius.0,
        max_radius_time_s: s.max_radius.1,
        max_radius_bubble: s.max_radius.2,
        final_radius_m: s.final_radii.clone(),
        peak_total_volume_m3: s.peak_total_volume.0,
        peak_total_volume_time_s: s.peak_total_volume.1,
        gas_balance_error: s.gas_balance_error,
        steps_explicit: s.steps.0,
        steps_implicit: s.steps.1,
        cells: s.cells,
        events: s.events.iter().map(event_text).collect(),
        import_notes: run.notes.clone(),
    };
    toml::to_string(&f).map_err(|e| Error::Solver(format!("summary.toml: {e}")))
}

/// Time axis in s for runs up to an hour, in min beyond.
pub fn time_axis(frames: &[Frame]) -> (f64, &'static str) {
    if frames.last().map_or(0.0, |f| f.time) > 3600.0 {
        (60.0, "time (min)")
    } else {
        (1.0, "time (s)")
    }
}

/// One series per bubble of `value(bubble)` against time (in the axis unit `tu`, s).
pub fn per_bubble_series(
    frames: &[Frame],
    tu: f64,
    value: impl Fn(&BubbleFrame) -> f64,
) -> Vec<Series> {
    let ids: std::collections::BTreeSet<usize> = frames
        .iter()
        .flat_map(|f| f.bubbles.iter().map(|b| b.id))
        .collect();
    ids.into_iter()
        .map(|id| {
            let pts = frames
                .iter()
                .filter_map(|f| {
                    f.bubbles
                        .iter()
                        .find(|b| b.id == id)
                        .map(|b| (f.time / tu, value(b)))
                })
                .collect();
            Series::new(format!("bubble {id}"), pts)
        })
        .collect()
}

/// Radius of every bubble over time, µm.
pub fn radius_plot(frames: &[Frame], title: &str) -> LinePlot {
    let (tu, tl) = time_axis(frames);
    let mut p = LinePlot::new(title, tl, "radius (µm)");
    p.series = per_bubble_series(frames, tu, |b| b.radius * 1e6);
    p
}

/// Total and per-bubble volume over time, mm³.
pub fn volume_plot(frames: &[Frame], title: &str) -> LinePlot {
    let (tu, tl) = time_axis(frames);
    let total = frames
        .iter()
        .map(|f| {
            (
                f.time / tu,
                f.bubbles.iter().map(|b| b.volume).sum::<f64>() * 1e9,
            )
        })
        .collect();
    let mut p = LinePlot::new(title, tl, "volume (mm³)").with(Series::new("total", total));
    p.series
        .extend(per_bubble_series(frames, tu, |b| b.volume * 1e9));
    p
}

fn plot_err(e: impl std::fmt::Display) -> Error {
    Error::Solver(format!("plot: {e}"))
}

/// `steps.csv`: one row per step the loop took (`--trace-steps`): its start and length, the
/// scheme, the limit that set it, the step the physics allowed, the bubbles' error estimate
/// over it as a fraction of their tolerance, the next steps the three error estimates allow
/// (`inf`: no limit), the wall time since the run started ([`TracedStep::wall_s`]: not a
/// result, it differs from run to run), and the bubble that gave the error estimate (empty
/// without one) with its flux of each gas at the start and at the end of the step (mol/s,
/// positive into the bubble; the end is the corrector's, before its correction), then the wall
/// time of the step's phases, s ([`StepWall`]: prepare, gel, events, of them the corrector and
/// the displacement, and the frame; not results either).
pub fn steps_csv(steps: &[TracedStep], gases: &[Gas]) -> String {
    let mut s = String::from(
        "time_s,dt_s,scheme,limit,physics_dt_s,bubble_error,next_bubble_dt_s,next_field_dt_s,next_loading_dt_s,wall_s,bubble",
    );
    for when in ["start", "end"] {
        for g in gases {
            s.push_str(&format!(",flux_{when}_{}_mol_s", g.name()));
        }
    }
    s.push_str(&format!(",{}\n", StepWall::CSV_HEADER));
    for t in steps {
        let r = &t.record;
        s.push_str(&format!(
            "{:.6},{:.6e},{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6},",
            r.time,
            r.dt,
            r.scheme.name(),
            r.limit.name(),
            r.physics_dt,
            r.bubble_error,
            r.next_bubble_dt,
            r.next_field_dt,
            r.next_loading_dt,
            t.wall_s
        ));
        if let Some(b) = r.bubble {
            s.push_str(&b.to_string());
        }
        for j in [&r.flux_start, &r.flux_end] {
            for x in &j[..gases.len()] {
                if r.bubble.is_some() {
                    s.push_str(&format!(",{x:.9e}"));
                } else {
                    s.push(',');
                }
            }
        }
        s.push_str(&format!(",{}\n", r.wall.csv_fields()));
    }
    s
}

/// The files of a simulation, added to `set` under `prefix`: bubbles.csv, summary.toml,
/// radius.svg, volume.svg, timing.toml (the wall time, which differs from run to run), and
/// steps.csv when the steps were traced.
pub fn add_run_files(
    set: &mut OutputSet,
    prefix: &str,
    run: &SimRun,
    profile_name: &str,
    phantom_name: &str,
) -> Result<(), Error> {
    let gases = &run.summary.gases;
    set.add(
        format!("{prefix}bubbles.csv"),
        bubbles_csv(&run.frames, gases),
    );
    set.add(
        format!("{prefix}summary.toml"),
        summary_toml(run, profile_name, phantom_name)?,
    );
    set.add(format!("{prefix}timing.toml"), timing_toml(run));
    if !run.steps.is_empty() {
        set.add(format!("{prefix}steps.csv"), steps_csv(&run.steps, gases));
    }
    let title = format!("{profile_name} — {phantom_name}");
    set.add(
        format!("{prefix}radius.svg"),
        radius_plot(&run.frames, &format!("Bubble radius: {title}"))
            .to_svg()
            .map_err(plot_err)?,
    );
    set.add(
        format!("{prefix}volume.svg"),
        volume_plot(&run.frames, &format!("Bubble volume: {title}"))
            .to_svg()
            .map_err(plot_err)?,
    );
    Ok(())
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
    run.notes = notes;
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

/// Load a pressure profile; a schedule TOML written by `plan --out` (it has `legs`) is accepted
/// too and becomes its pressure history (ambient at the gel, breathed gas with the schedule's
/// water vapour at the open faces).
pub fn load_profile_or_schedule(
    path: &std::path::Path,
    opts: &LoadOptions,
) -> Result<PressureHistory, Error> {
    let is_schedule = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"))
        && std::fs::read_to_string(path)
            .ok()
            .and_then(|t| t.parse::<toml::Table>().ok())
            .is_some_and(|t| t.contains_key("legs"));
    if is_schedule {
        let schedule = crate::algorithm::Schedule::read(path)?;
        return schedule
            .to_pressure_history()
            .map_err(|m| Error::Input(crate::error::InputError::new(m).in_file(path)));
    }
    Ok(load(path, opts)?)
}

/// A short human-readable summary of a run, with its wall time (for the terminal).
pub fn describe(run: &SimRun) -> String {
    let mut text = describe_results(run);
    text.pop();
    text.push_str(&format!("; wall {:.2} s\n", run.wall_seconds));
    if let Some(t) = run.resumed_at {
        text.push_str(&format!("resumed from a checkpoint at t = {t:.1} s\n"));
    }
    if let Some(c) = run.checkpoints.as_ref().filter(|c| c.written > 0) {
        text.push_str(&format!(
            "{} checkpoint(s) of {:.1} MB written in {:.2} s\n",
            c.written,
            c.bytes as f64 / 1e6,
            c.seconds
        ));
    }
    text
}

/// A short human-readable summary of a run's results, without the wall time (for reports,
/// which must not change when regenerated from the same inputs). Bubble growth is reported
/// above each bubble's starting radius R0 (a run whose bubbles only shrink says so, rather
/// than calling R0 at t = 0 its "max radius"); volumes in mm³, radii in µm.
pub fn describe_results(run: &SimRun) -> String {
    use crate::report::table::sig_text;
    let s = &run.summary;
    let notes: String = run.notes.iter().map(|n| format!("note: {n}\n")).collect();
    let growth = match peak_growth(&run.frames) {
        Some(g) if g.growth > 1e-6 * g.r0 => format!(
            "largest growth above R0: bubble {}, +{} µm (R0 {} µm → {} µm at t = {:.1} s)",
            g.id,
            sig_text(g.growth * 1e6, 4, true),
            sig_text(g.r0 * 1e6, 4, true),
            sig_text((g.r0 + g.growth) * 1e6, 4, true),
            g.time
        ),
        Some(_) => "no bubble grew above its starting radius R0".to_string(),
        None => "no bubbles".to_string(),
    };
    let start = run.frames.first().map_or(f64::NAN, |f| {
        f.bubbles.iter().map(|b| b.volume).sum::<f64>()
    });
    let volume = if s.peak_total_volume.0 > start * (1.0 + 1e-6) {
        format!(
            "peak total volume {} mm³ at t = {:.1} s (start {} mm³)",
            sig_text(s.peak_total_volume.0 * 1e9, 4, true),
            s.peak_total_volume.1,
            sig_text(start * 1e9, 4, true)
        )
    } else {
        format!(
            "total volume never above its start, {} mm³",
            sig_text(start * 1e9, 4, true)
        )
    };
    notes
        + &format!(
            "{}\n{growth}; {volume}\nsteps {} explicit + {} implicit on {} cells; gas-balance error {:.2e}\n",
            ending_text(&s.ending),
            s.steps.0,
            s.steps.1,
            s.cells,
            s.gas_balance_error,
        )
}

/// The largest growth of a bubble above its radius in the first frame it appears in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakGrowth {
    /// Bubble id.
    pub id: usize,
    /// Its starting radius, m.
    pub r0: f64,
    /// Largest R − R0 over the run, m (≤ 0 when it never grew).
    pub growth: f64,
    /// When, s.
    pub time: f64,
}

/// The bubble that grew most above its starting radius, or `None` without bubbles.
pub fn peak_growth(frames: &[Frame]) -> Option<PeakGrowth> {
    let mut start: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
    let mut best: Option<PeakGrowth> = None;
    for f in frames {
        for b in &f.bubbles {
            let r0 = *start.entry(b.id).or_insert(b.radius);
            let g = b.radius - r0;
            if best.is_none_or(|x| g > x.growth) {
                best = Some(PeakGrowth {
                    id: b.id,
                    r0,
                    growth: g,
                    time: f.time,
                });
            }
        }
    }
    best
}
