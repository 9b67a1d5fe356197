//! The time loop: a two-scale model. The 3-D grid carries the far field of every gas; each
//! bubble is a sub-grid object coupled to it through a quasi-steady spherical near field.
//!
//! Coupling (per bubble, per gas g), with R the radius, δ the surface-layer thickness,
//! a = max(R, kernel_min·h) the sink-kernel radius and ρ = max(a, R + δ) + gap·h the coupling radius:
//! - C̄_ρ: the 3-D field averaged over the sphere of radius ρ (trilinear samples);
//! - C_s = L_g·x_g·P_B/(R_u·T): Henry's law at the gas's partial pressure in the bubble;
//! - flux into the bubble, eq. (2.3) integrated over the quasi-steady shell R…ρ with the
//!   surface layer R…R+δ (diffusivity D_surf) in series with the gel R+δ…ρ (D_bulk):
//!   J = 4π(C̄_ρ − C_s) / [(1/R − 1/(R+δ))/D_surf + (1/(R+δ) − 1/ρ)/D_bulk].
//!   With D_surf = D_bulk this is exactly the plain Henry interface, 4πD(C̄_ρ − C_s)/(1/R − 1/ρ);
//!   the flux leaving the gel always equals the flux entering the bubble.
//! - J·dt is removed from (or returned to) the 3-D cells with a spherically symmetric kernel
//!   of radius a ≤ ρ, whose exterior field is that of a point sink (Newton's shell theorem),
//!   so the field sampled at ρ sees the bubble as the continuum does. A cell never gives more
//!   than it holds: what the kernel cannot supply comes from the sphere of radius ρ, and what
//!   that cannot supply is not taken (no gel cell goes negative). Total gas (grid + bubbles)
//!   changes only through open faces and perfusion: conserved to round-off.
//!
//! Bubbles whose radius is at or below R_min are impermeable (section 2.1.4) and follow
//! Boyle/Laplace only. Touching bubbles coalesce; a bubble reaching a face ends the run.

use super::bubble::{Balance, Bubble, BubbleFate};
use super::diffusion;
use super::displacement::{self, Displaced};
use super::fields::Fields;
use super::gel_pass::{plane_gel, same_plane_gel, PlaneGel};
use super::grid::{Face, Grid, KernelCache};
use super::nucleation::{Nucleus, NucleusPool};
use super::params::{BubblePlacement, PhantomParams};
use crate::error::Error;
use crate::gas::Gas;
use crate::profile::PressureHistory;
use crate::units::GAS_CONSTANT;
use rand::{Rng, SeedableRng};
use std::f64::consts::PI;
use std::time::Instant;

/// Largest relative gas-balance error a healthy run may show. The scheme is conservative to
/// round-off (1e-14 measured), so an error this large means something went wrong, not that the
/// grid is coarse.
const BALANCE_LIMIT: f64 = 1e-6;

/// Floor of the flux scale in the step's error estimate ([`Simulation::correct`]), as a
/// fraction of the bubble's content: a bubble whose flux passes through zero is judged by the
/// change of its content, not by a relative change of a vanishing flux.
const FLUX_FLOOR: f64 = 0.01;

/// Sizes of coupling sphere kept by [`Simulation::prepare_sphere`] before its cache is emptied.
const SPHERE_CACHE: usize = 16;

/// Largest set of fields (bytes, all gases) whose explicit steps run out of place, into a
/// second set ([`Simulation::explicit_steps_out_of_place`]), when the grid loops have more
/// than one thread; other runs step in place. Since session 21 (26 Nov 2026) a run with as
/// many gases as threads steps a thread per field in place instead
/// ([`diffusion::explicit_steps_in_place_per_field`]: the small cube −5 %, Fig. 5 −2 to −4 %,
/// docs/speed-history.md; since session 24 without its plane copy,
/// [`diffusion::explicit_steps_shifting_per_field`]), except for the steps that end at a frame with the gel's state, which stay
/// out of place here to pass the gel while its planes are in cache. Measured on the 2-core Intel machine of
/// 25 Nov 2026, alternated with in-place steps (docs/speed-history.md): the oscillation experiment
/// (8.4 MB of fields) 0.91–0.94 s against 0.99–1.04 s; the Fig. 5 dive (15 MB) 5.55–5.78 s
/// against 5.65–5.68 s, nothing for 12 MB more memory, so it stays in place; a small run on
/// one thread, as `fit` runs it, was 10–20 % slower out of place (four fields of 1.7 MB no
/// longer stay in the core's 2 MB L2).
const OUT_OF_PLACE_BYTES: usize = 12 << 20;

/// Points sampled over all bubbles in one round from which [`Simulation::all_fluxes`] runs the
/// bubbles in parallel (below, a thread's wake-up costs more than it saves: 64 points take a
/// few µs).
const PARALLEL_SPHERE_POINTS: usize = 1024;

#[cfg(test)]
thread_local! {
    /// Tests: evaluate the bubbles' fluxes one after another, as before they ran in parallel
    /// (the reference of `parallel_fluxes_tests`).
    static SERIAL_FLUXES: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether the bubbles' fluxes are evaluated one by one where they interleave with the
/// corrections (tests only; always false in a build).
fn serial_fluxes() -> bool {
    #[cfg(test)]
    {
        SERIAL_FLUXES.with(|s| s.get())
    }
    #[cfg(not(test))]
    {
        false
    }
}

/// What the observer sees of one bubble at a recorded time.
#[derive(Debug, Clone, PartialEq)]
pub struct BubbleFrame {
    /// Bubble id.
    pub id: usize,
    /// Radius, m.
    pub radius: f64,
    /// R0: the radius the bubble was created with, m (its nucleus at t = 0 or at activation;
    /// for a bubble formed by coalescence, the radius of the summed R0 volumes). Criteria
    /// measure growth above it.
    pub initial_radius: f64,
    /// Volume, m³.
    pub volume: f64,
    /// Surface area, m².
    pub area: f64,
    /// Gas amounts, mol, in the run's gas order.
    pub moles: Vec<f64>,
    /// Total gas tension of the gel at the coupling sphere, Pa: Σ_g C̄_ρ·R_u·T/L_g over the
    /// simulated gases plus the fixed partial pressure of the others (`bubble_fixed_gases`,
    /// which the tissue around the bubble holds too: the same convention on both sides).
    pub gel_tension: f64,
    /// Centre, m.
    pub position: [f64; 3],
}

/// One recorded time.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Time, s.
    pub time: f64,
    /// Ambient pressure, Pa.
    pub ambient: f64,
    /// Active bubbles.
    pub bubbles: Vec<BubbleFrame>,
    /// Largest supersaturation in the gel, Σ_g tension + p_fixed − P_amb, Pa (over all inside
    /// cells; p_fixed = `bubble_fixed_gases`, 0 for a lab gel). NaN in a frame recorded
    /// without the gel's state (`Numerics::record_gel`).
    pub max_supersaturation: f64,
    /// Gas dissolved in the grid, mol, per gas (empty without the gel's state).
    pub grid_moles: Vec<f64>,
}

/// How the gel's diffusion was stepped over one time step ([`StepRecord`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepScheme {
    /// Forward Euler within the explicit limit.
    Explicit,
    /// Locally-one-dimensional backward Euler.
    Implicit,
    /// Backward Euler Richardson-extrapolated from two half steps (descents, holds and stops
    /// with every bubble shut).
    Extrapolated,
}

impl StepScheme {
    /// Every scheme, in the order of [`Self::index`].
    pub const ALL: [StepScheme; 3] = [
        StepScheme::Explicit,
        StepScheme::Implicit,
        StepScheme::Extrapolated,
    ];

    /// Position in [`Self::ALL`].
    pub fn index(self) -> usize {
        match self {
            StepScheme::Explicit => 0,
            StepScheme::Implicit => 1,
            StepScheme::Extrapolated => 2,
        }
    }

    /// Name in `steps.csv`.
    pub fn name(self) -> &'static str {
        match self {
            StepScheme::Explicit => "explicit",
            StepScheme::Implicit => "implicit",
            StepScheme::Extrapolated => "extrapolated",
        }
    }
}

/// Which limit set a step's length ([`StepRecord`]; the last of the limits of
/// `Simulation::choose_step` to shorten it).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepLimit {
    /// `max_step`.
    MaxStep,
    /// At most `max_step_growth` times the last step.
    Growth,
    /// The bubbles' error estimate (`bubble_tolerance`).
    BubbleError,
    /// The gel field's error estimate (`field_tolerance`).
    FieldError,
    /// The loading's error estimate (`loading_tolerance`).
    LoadingError,
    /// `max_pressure_change`.
    PressureChange,
    /// A bubble's content change (`max_content_change`).
    BubbleContent,
    /// A bubble losing at most half of one gas.
    BubbleGas,
    /// A breakpoint of the profile, hit exactly.
    Breakpoint,
    /// The end of the profile.
    End,
    /// Cut to the explicit limit: between it and the implicit threshold (`implicit_cost_ratio`
    /// times [`diffusion::LimitScans::implicit_cost_unit`]) the explicit step is the cheaper and the more
    /// accurate.
    ExplicitLimit,
}

impl StepLimit {
    /// Name in `steps.csv`.
    pub fn name(self) -> &'static str {
        match self {
            StepLimit::MaxStep => "max-step",
            StepLimit::Growth => "growth",
            StepLimit::BubbleError => "bubble-error",
            StepLimit::FieldError => "field-error",
            StepLimit::LoadingError => "loading-error",
            StepLimit::PressureChange => "pressure-change",
            StepLimit::BubbleContent => "bubble-content",
            StepLimit::BubbleGas => "bubble-gas",
            StepLimit::Breakpoint => "breakpoint",
            StepLimit::End => "end",
            StepLimit::ExplicitLimit => "explicit-limit",
        }
    }
}

/// One time step as the loop took it ([`Observer::step`]; `simulate --trace-steps`
/// writes them to `steps.csv`): for studying the time stepping, not a result.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepRecord {
    /// Start of the step, s.
    pub time: f64,
    /// Its length, s.
    pub dt: f64,
    /// How the gel was stepped.
    pub scheme: StepScheme,
    /// What set the length.
    pub limit: StepLimit,
    /// The step the physics allowed before the breakpoints and the scheme's cost cut it, s.
    pub physics_dt: f64,
    /// The corrector's error estimate of the bubbles' exchange over this step (the largest
    /// over the bubbles), as a fraction of `bubble_tolerance` (0 without open bubbles).
    pub bubble_error: f64,
    /// The next step each error estimate allows, s (∞: no limit): the bubbles', the gel
    /// field's and the loading's.
    pub next_bubble_dt: f64,
    /// See `next_bubble_dt`.
    pub next_field_dt: f64,
    /// See `next_bubble_dt`.
    pub next_loading_dt: f64,
    /// The bubble whose exchange gave `bubble_error` (None without open bubbles).
    pub bubble: Option<usize>,
    /// That bubble's fluxes at the start of the step, mol/s per gas in the run's order
    /// ([`RunSummary::gases`]; 0 past its gases): what the predictor moved per second.
    pub flux_start: [f64; Gas::ALL.len()],
    /// Its fluxes at the end of the step (the corrector's, before the correction).
    pub flux_end: [f64; Gas::ALL.len()],
    /// The wall time of the step's phases (not a result: it differs from run to run).
    pub wall: StepWall,
}

/// The wall time of one step's phases, s, as the time loop took them ([`StepRecord::wall`];
/// `simulate` sums them over the run into `timing.toml`, `--trace-steps` writes them per step
/// into `steps.csv`). What a speed study needs to see where a run's time goes without a build
/// of its own (README "Speed").
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StepWall {
    /// Phases 1–3: the bubbles' fluxes at the start of the step, the step's choice and the
    /// exchange (the predictor).
    pub prepare_s: f64,
    /// Phase 4: the gel's diffusion (explicit, implicit or extrapolated), with the field's and
    /// the loading's error estimates.
    pub gel_s: f64,
    /// Phases 5–8: perfusion, the radii, the corrector, coalescence, nucleation, the
    /// displacement of the gel and the health check.
    pub events_s: f64,
    /// Of `events_s`, the corrector of the bubbles' exchange ([`Simulation::correct`]: the
    /// fluxes at the end of the step and the correction).
    pub corrector_s: f64,
    /// Of `events_s`, the gel's displacement by the bubbles (the remap, and the cells taken
    /// and given back).
    pub displacement_s: f64,
    /// The frame recorded at the end of the step, if one was due (the gel pass, the bubbles'
    /// fluxes and the observer's own work).
    pub frame_s: f64,
}

impl StepWall {
    /// The phases' names as CSV columns, in the order of [`Self::csv_fields`].
    pub const CSV_HEADER: &'static str =
        "prepare_s,gel_s,events_s,corrector_s,displacement_s,frame_s";

    /// The phases as CSV fields, to 0.1 µs ([`Self::CSV_HEADER`]).
    pub fn csv_fields(&self) -> String {
        [
            self.prepare_s,
            self.gel_s,
            self.events_s,
            self.corrector_s,
            self.displacement_s,
            self.frame_s,
        ]
        .map(|x| format!("{x:.7}"))
        .join(",")
    }

    /// Add `other` phase by phase (a run's totals).
    pub fn add(&mut self, other: &StepWall) {
        self.prepare_s += other.prepare_s;
        self.gel_s += other.gel_s;
        self.events_s += other.events_s;
        self.corrector_s += other.corrector_s;
        self.displacement_s += other.displacement_s;
        self.frame_s += other.frame_s;
    }
}

/// Seconds since `from`, and `from` moved to now (the time loop's phase clock).
fn lap(from: &mut Instant) -> f64 {
    let now = Instant::now();
    let s = (now - *from).as_secs_f64();
    *from = now;
    s
}

/// The bubble whose exchange gave the corrector's largest error estimate over a step, with its
/// fluxes at the start and the end of the step ([`StepRecord`]).
type WorstExchange = Option<(usize, [f64; Gas::ALL.len()], [f64; Gas::ALL.len()])>;

/// Receives what the simulation does (like ripgrep's `Sink`): recorders, CSV writers and
/// progress bars are observers, the time loop knows nothing of files or terminals.
pub trait Observer {
    /// A recorded frame.
    fn frame(&mut self, frame: &Frame);
    /// A step just taken. Default does nothing.
    fn step(&mut self, _step: &StepRecord) {}
    /// Progress: simulated time and end time, s. Called every step; default does nothing.
    fn progress(&mut self, _time: f64, _end: f64) {}
    /// Whether the run should stop now (e.g. the user pressed Ctrl-C). Checked every step; the
    /// run then ends as [`Ending::Interrupted`] with everything up to that moment recorded.
    fn should_stop(&self) -> bool {
        false
    }
    /// Whether to save a checkpoint now; asked after every complete step that the run goes on
    /// from (`step`: steps taken so far). Default never.
    fn checkpoint_due(&mut self, _step: usize) -> bool {
        false
    }
    /// The run's whole state after a complete step, when [`Self::checkpoint_due`] said so
    /// ([`super::checkpoint`]). An error ends the run.
    fn checkpoint(&mut self, _state: super::checkpoint::RunState) -> Result<(), Error> {
        Ok(())
    }
}

/// Keeps every frame in memory.
#[derive(Debug, Default, Clone)]
pub struct Recorder {
    /// The frames in time order.
    pub frames: Vec<Frame>,
}

impl Observer for Recorder {
    fn frame(&mut self, frame: &Frame) {
        self.frames.push(frame.clone());
    }
}

/// Why the run ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Ending {
    /// The profile ended.
    Completed,
    /// Stopped on request (the observer's `should_stop`) at this time, s.
    Interrupted {
        /// Time, s.
        time: f64,
    },
    /// A bubble reached a face of the phantom at this time; everything up to it is kept.
    BubbleReachedFace {
        /// Bubble id.
        bubble: usize,
        /// Which face.
        face: Face,
        /// Time, s.
        time: f64,
    },
}

/// A bubble event.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// Bubble `absorbed` merged into `into`.
    Coalesced {
        /// Time, s.
        time: f64,
        /// Surviving bubble.
        into: usize,
        /// Bubble that disappeared.
        absorbed: usize,
    },
    /// A bubble dissolved completely.
    Dissolved {
        /// Time, s.
        time: f64,
        /// Bubble id.
        bubble: usize,
    },
}

/// Summary of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSummary {
    /// Gases simulated, in column order.
    pub gases: Vec<Gas>,
    /// Largest radius reached by any bubble, m, its time (s) and bubble id.
    pub max_radius: (f64, f64, usize),
    /// Final radius of each bubble (0 if dissolved or merged), m.
    pub final_radii: Vec<f64>,
    /// Peak total bubble volume, m³, and its time, s.
    pub peak_total_volume: (f64, f64),
    /// |gas now − gas at start − gas in through open faces and perfusion| / gas at start, at the end.
    pub gas_balance_error: f64,
    /// Lowest concentration of any gas in any inside cell over the recorded frames, mol/m³
    /// (the sink kernel never overdraws a cell, so this is ≥ 0 up to round-off).
    pub min_concentration: f64,
    /// Steps taken (explicit, implicit).
    pub steps: (usize, usize),
    /// Simulated end time, s.
    pub end_time: f64,
    /// Why the run ended.
    pub ending: Ending,
    /// Coalescences and dissolutions.
    pub events: Vec<Event>,
    /// Cells inside the phantom.
    pub cells: usize,
}

/// What the time loop accumulates over a run.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct RunLog {
    pub(super) max_radius: (f64, f64, usize),
    pub(super) peak_volume: (f64, f64),
    pub(super) min_concentration: f64,
    pub(super) steps: (usize, usize),
    pub(super) events: Vec<Event>,
    pub(super) ending: Ending,
    pub(super) next_record: f64,
}

/// What the time loop carries from one step to the next besides the [`Simulation`]: the
/// accumulated log, the step sizes and the per-bubble buffers (a checkpoint holds it).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct LoopState {
    pub(super) log: RunLog,
    /// The step the physics allowed last, s.
    pub(super) dt_prev: f64,
    /// The step the bubbles' error estimate allows, s.
    pub(super) bubble_dt: f64,
    /// The step the gel field's error estimate allows, s ([`Simulation::diffuse`]).
    pub(super) field_dt: f64,
    /// The step the loading's error estimate allows, s ([`Simulation::loading_step`]).
    pub(super) loading_dt: f64,
    /// The loading estimate's history ([`Simulation::loading_step`]).
    pub(super) loading: LoadingHistory,
    pub(super) tensions: Vec<f64>,
    pub(super) fluxes: Vec<Vec<f64>>,
}

/// The loading estimate's history since the last profile breakpoint: per gas the flow
/// through the open faces over each of the last two steps, mol, and those steps' lengths, s
/// (a length 0: no such step since the breakpoint).
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct LoadingHistory {
    /// The last step's flows and length.
    pub(super) last: Vec<f64>,
    pub(super) last_dt: f64,
    /// The step before it.
    pub(super) before: Vec<f64>,
    pub(super) before_dt: f64,
}

impl LoadingHistory {
    fn new(gases: usize) -> LoadingHistory {
        LoadingHistory {
            last: vec![0.0; gases],
            last_dt: 0.0,
            before: vec![0.0; gases],
            before_dt: 0.0,
        }
    }

    /// Forget the steps (at a profile breakpoint, where the flow's rate jumps).
    fn clear(&mut self) {
        self.last_dt = 0.0;
        self.before_dt = 0.0;
    }

    /// Take the step just done (`flow` over `dt`) into the history.
    fn push(&mut self, flow: &[f64], dt: f64) {
        std::mem::swap(&mut self.last, &mut self.before);
        self.before_dt = self.last_dt;
        self.last.copy_from_slice(flow);
        self.last_dt = dt;
    }
}

/// Local error of a first-order step's flow through the open faces (backward or forward
/// Euler; `Numerics::loading_tolerance`): (dt²/2)·|M''| with M'' from the flows of this step and
/// the last, = dt/(dt + dt₋₁)·|F − (dt/dt₋₁)·F₋₁| (the variable-step BDF estimate).
pub(super) fn loading_error_first_order(flow: f64, dt: f64, last: f64, last_dt: f64) -> f64 {
    dt / (dt + last_dt) * (flow - dt / last_dt * last).abs()
}

/// Local error of a Richardson-extrapolated backward-Euler step's flow through the open
/// faces: (dt³/6)·|M'''| (for u' = λu the step 2·(1 − z/2)⁻² − (1 − z)⁻¹ has no z³ term,
/// against e^z's 1/6), with M''' = 6·M[t₋₂, t₋₁, t, t + dt], the third divided difference of
/// the gel's content over this step and the two before it (flows `before`, `last`, `flow`
/// over `before_dt`, `last_dt`, `dt`): dt³·|M[t₋₂, t₋₁, t, t + dt]|. Exact for a content
/// cubic in time, zero for a quadratic one.
pub(super) fn loading_error_second_order(
    (flow, dt): (f64, f64),
    (last, last_dt): (f64, f64),
    (before, before_dt): (f64, f64),
) -> f64 {
    let (s1, s2, s3) = (before / before_dt, last / last_dt, flow / dt);
    let d12 = (s2 - s1) / (before_dt + last_dt);
    let d23 = (s3 - s2) / (last_dt + dt);
    let d123 = (d23 - d12) / (before_dt + last_dt + dt);
    dt * dt * dt * d123.abs()
}

/// The buffers of a round of the bubbles' fluxes ([`Simulation::flux_round`]), kept between
/// steps so the time loop does not allocate them per step.
#[derive(Debug, Default)]
struct FluxRound {
    /// The bubbles of the round.
    which: Vec<usize>,
    /// Per bubble (all of them; only `which` filled): the gel tension and the fluxes.
    out: Vec<(f64, [f64; Gas::ALL.len()])>,
    /// The parallel round's value of every gas at each sampled point, all bubbles' points
    /// one after the other ([`Simulation::sphere_means_of`]).
    vals: Vec<[f64; Gas::ALL.len()]>,
    /// The parallel round's sphere means, one per bubble of `which`.
    means: Vec<[f64; Gas::ALL.len()]>,
}

/// One bubble's exchange within a step, from the predictor ([`Simulation::exchange`]) to the
/// corrector ([`Simulation::correct`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StepExchange {
    /// Content at the start of the step, mol per gas.
    pub(super) start: [f64; Gas::ALL.len()],
    /// Gas the grid gave before diffusion, mol per gas.
    pub(super) taken: [f64; Gas::ALL.len()],
    /// Fluxes J_g(t) at the start of the step, mol/s.
    pub(super) flux: [f64; Gas::ALL.len()],
    /// The bubble takes part in the corrector (active and not dissolved by the predictor).
    pub(super) open: bool,
}

/// The simulation state.
///
/// The fields marked `pub(super)` are the state a checkpoint saves ([`super::checkpoint`]);
/// the others follow from the inputs or are scratch space.
pub struct Simulation<'a> {
    params: &'a PhantomParams,
    pub(super) grid: Grid,
    gases: Vec<Gas>,
    diffusivity: Vec<f64>,
    ostwald: Vec<f64>,
    explicit_limit: Vec<f64>,
    /// The shortest step taken implicitly, s: `implicit_cost_ratio` ×
    /// [`diffusion::LimitScans::implicit_cost_unit`] (the smallest over the gases); a step between the
    /// explicit limit and this is cut to the limit.
    implicit_threshold: f64,
    pub(super) fields: Fields,
    /// The field before the step, for the field's error estimate (allocated when that is on).
    scratch: Vec<f64>,
    /// The explicit steps' second set of fields (one per gas) when stepped out of place
    /// ([`OUT_OF_PLACE_BYTES`]): each step writes the new values of the inside cells here and
    /// swaps it with `fields`. Its outside cells equal `fields`' since the codes `back_codes`
    /// ([`Grid::codes_id`]); it is copied again from `fields` when the codes change.
    back: Vec<Vec<f64>>,
    back_codes: u64,
    /// [`OUT_OF_PLACE_BYTES`] (a field so that a test can step in place).
    out_of_place_bytes: usize,
    /// Whether the explicit steps take a thread per field when there are as many gases as
    /// threads and no gel pass is due ([`diffusion::explicit_steps_shifting_per_field`]; a test
    /// turns it off to compare).
    per_field: bool,
    /// Explicit steps taken a thread per field (a test's check that the path is taken).
    per_field_steps: usize,
    /// The implicit step's line plan and factor table ([`diffusion::ImplicitSolver`]).
    implicit: diffusion::ImplicitSolver,
    /// Per gas, the change of every cell by diffusion in the last step (mol/m³), for the
    /// field's error estimate ([`Self::diffuse`]); empty while the estimate is off or before
    /// the first step.
    pub(super) last_change: Vec<Vec<f64>>,
    /// Length of the last step, s (0 before the first).
    pub(super) last_dt: f64,
    /// Bubbles (all ever created; check `fate`).
    pub bubbles: Vec<Bubble>,
    rt: f64,
    pub(super) time: f64,
    /// Gas that entered through open faces and by perfusion since the balance reference, mol.
    pub(super) inflow: f64,
    pub(super) initial_total: f64,
    /// Fibonacci spheres of the sizes in use, keyed by their number of points (the coupling
    /// spheres of bubbles of different radii; [`Self::sphere_means`]).
    spheres: std::collections::HashMap<usize, Vec<[f64; 3]>>,
    /// (cos, sin) of the Fibonacci spheres' longitudes ([`fibonacci_sphere`]).
    sphere_turns: Vec<[f64; 2]>,
    kernel: Vec<(usize, f64)>,
    /// Per bubble, the candidate cells of its sink kernel and of the wider one out to its
    /// coupling sphere ([`Grid::kernel_cached`]).
    kernel_caches: Vec<[KernelCache; 2]>,
    /// Per gas, its flow into the gel through the open faces in the last step, mol
    /// ([`Self::diffuse`]; the loading estimate reads it, [`Self::loading_step`]).
    step_flow: [f64; Gas::ALL.len()],
    /// A field-sized buffer for the extrapolated step ([`Self::diffuse`]; empty until used).
    extra: Vec<f64>,
    /// The cells (an index box, lowest and highest corner) that [`Self::take_from_grid`] has
    /// changed since it was last reset, or `None`: the corrector uses it to know which
    /// bubbles' fluxes, evaluated before the corrections, are still current.
    touched: Option<([usize; 3], [usize; 3])>,
    pub(super) steps_state: Vec<StepExchange>,
    /// The buffers of the bubbles' flux rounds ([`Self::flux_round`]).
    round: FluxRound,
    /// The time at which `round` holds every active bubble's fluxes and tensions, when the
    /// frame recorded at the end of a step computed them ([`Self::observe`]) and nothing has
    /// changed since: the next step starts from them ([`Self::bubble_fluxes`]) instead of
    /// computing the same round again. Cleared by every other round.
    round_at: Option<f64>,
    /// Whether [`Self::bubble_fluxes`] may take `round_at`'s round (a test turns it off).
    reuse_frame_round: bool,
    /// The gel's pass of each z-plane ([`plane_gel`]) as the last explicit step left it, when
    /// that step ended at a frame and passed its planes while they were in cache
    /// ([`diffusion::explicit_steps_into_passing_gel`]); valid while `gel_fresh`, except the
    /// planes `gel_dirty` (first, last) that the exchange, the displacement or a nucleus wrote
    /// since ([`Self::mark_gel`]), which the frame passes again ([`Self::gel_state`]).
    gel_planes: Vec<PlaneGel>,
    gel_fresh: bool,
    gel_dirty: (usize, usize),
    /// Whether the next diffusion step ends at a frame with the gel's state (set by the loop).
    pass_gel_next: bool,
    /// Whether an explicit step out of place may pass the gel for the frame (a test turns it
    /// off), and whether each frame checks those planes against a pass of its own (tests).
    fuse_gel_pass: bool,
    check_fused_gel: bool,
    /// Frames that took the step's pass of the gel (a test's check that the path is taken).
    #[cfg(test)]
    fused_frames: std::sync::atomic::AtomicUsize,
    /// Per bubble: the gel it displaces ([`displacement`]).
    pub(super) displaced: Vec<Displaced>,
    /// Change of the grid's gas by displacement since the balance reference, mol: gel pushed
    /// beyond the reach of the displacement or swallowed by a bubble ([`Self::displace`]).
    pub(super) displaced_gas: f64,
    /// Sub-grid nuclei of the nucleation model ([`Self::nucleate`]).
    pub(super) nuclei: NucleusPool,
    /// An upper bound of the gel tension anywhere in the gel so far, Pa (`None`: not known,
    /// computed from the fields when next needed): [`Self::tension_bound`].
    pub(super) tension_bound: Option<f64>,
}

/// The `n` points of the Fibonacci sphere: z_i = 1 − (2i + 1)/n, at longitude i times the
/// golden angle. `turns` holds (cos, sin) of the longitudes, which do not depend on n (grown
/// here as needed: a growing bubble asks for a slightly larger sphere at almost every step).
fn fibonacci_sphere(n: usize, turns: &mut Vec<[f64; 2]>) -> Vec<[f64; 3]> {
    let golden = PI * (3.0 - 5f64.sqrt());
    for i in turns.len()..n {
        let th = golden * i as f64;
        turns.push([th.cos(), th.sin()]);
    }
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let [c, s] = turns[i];
            [r * c, r * s, z]
        })
        .collect()
}

impl<'a> Simulation<'a> {
    /// Set up: grid, fields saturated with the profile's gas at t = 0, bubbles placed and
    /// filled at Laplace equilibrium with the composition of the gel around them.
    pub fn new(params: &'a PhantomParams, profile: &PressureHistory) -> Result<Self, Error> {
        let input = |m: String| Error::Input(crate::error::InputError::new(m));
        let grid = Grid::new(params.shape, params.grid_step, &params.open_faces).map_err(input)?;
        let gases = profile.gases();
        if gases.is_empty() {
            return Err(input(
                "the profile's gas contains no nitrogen, oxygen or helium".into(),
            ));
        }
        let mut diffusivity = Vec::new();
        let mut ostwald = Vec::new();
        for g in &gases {
            let p = params.gas(*g).ok_or_else(|| {
                input(format!(
                    "the profile uses {} but the phantom lists no properties for it; add [gases.{}] with diffusivity and ostwald",
                    g.name(),
                    g.name()
                ))
            })?;
            diffusivity.push(p.diffusivity);
            ostwald.push(p.ostwald);
        }
        let rt = GAS_CONSTANT * params.temperature;
        let scans = diffusion::LimitScans::of(&grid);
        let explicit_limit = diffusivity
            .iter()
            .map(|d| scans.explicit_limit(grid.h, *d))
            .collect();
        let implicit_threshold = params.numerics.implicit_cost_ratio
            * diffusivity
                .iter()
                .map(|d| scans.implicit_cost_unit(grid.h, *d))
                .fold(f64::INFINITY, f64::min);
        let fields: Vec<Vec<f64>> = gases
            .iter()
            .zip(&ostwald)
            .map(|(g, l)| {
                let c = l * profile.inspired_partial_pressure(*g, 0.0) / rt;
                (0..grid.len())
                    .map(|i| if grid.inside(i) { c } else { 0.0 })
                    .collect()
            })
            .collect();
        let fields = Fields::new(fields, grid.n[0] * grid.n[1]);
        let p0 = profile.ambient(0.0);
        let placements = place_bubbles(params, &grid)?;
        let partial: Vec<f64> = gases
            .iter()
            .map(|g| profile.inspired_partial_pressure(*g, 0.0))
            .collect();
        let psum: f64 = partial.iter().sum();
        if !(psum > 0.0) {
            return Err(input(
                "the inspired inert-gas pressure at t = 0 is zero (water vapour ≥ ambient?)".into(),
            ));
        }
        let mut bubbles = Vec::new();
        for (id, (pos, r0)) in placements.into_iter().enumerate() {
            let bal = Balance {
                ambient: p0,
                surface_tension: params.surface_tension,
                law: params.elasticity.as_ref(),
                initial_radius: r0,
                initial_ambient: p0,
                fixed_gases: params.bubble_fixed_gases,
            };
            let n_total = bal.pv(r0) / rt;
            if !(n_total > 0.0) {
                // name the field that pulled the bubble's pressure down: the elasticity law
                // when Ω(R0) outweighs the Laplace term, else the fixed gases
                let field = if bal.internal_pressure(r0) < p0 {
                    "material.elasticity"
                } else {
                    "material.bubble_fixed_gases_pa"
                };
                return Err(Error::Input(crate::error::InputError::new(format!(
                    "bubble {id}: no simulated gas at Laplace equilibrium with R0 = {r0} m: the pressure in the bubble, {:.0} Pa, is not above the fixed partial pressure of the other gases (material.bubble_fixed_gases_pa = {:.0} Pa)",
                    bal.internal_pressure(r0),
                    params.bubble_fixed_gases
                )).field(field)));
            }
            bubbles.push(Bubble {
                id,
                position: pos,
                initial_radius: r0,
                initial_ambient: p0,
                moles: partial.iter().map(|p| n_total * p / psum).collect(),
                radius: r0,
                fate: BubbleFate::Active,
            });
        }
        let mut sim = Simulation {
            params,
            scratch: Vec::new(),
            back: Vec::new(),
            back_codes: 0,
            out_of_place_bytes: OUT_OF_PLACE_BYTES,
            per_field: true,
            per_field_steps: 0,
            implicit: diffusion::ImplicitSolver::new(),
            last_change: Vec::new(),
            last_dt: 0.0,
            grid,
            gases,
            diffusivity,
            ostwald,
            explicit_limit,
            implicit_threshold,
            fields,
            bubbles,
            rt,
            time: 0.0,
            inflow: 0.0,
            initial_total: 0.0,
            spheres: std::collections::HashMap::new(),
            sphere_turns: Vec::new(),
            kernel: Vec::new(),
            kernel_caches: Vec::new(),
            step_flow: [0.0; Gas::ALL.len()],
            extra: Vec::new(),
            touched: None,
            round: FluxRound::default(),
            round_at: None,
            reuse_frame_round: true,
            gel_planes: Vec::new(),
            gel_fresh: false,
            gel_dirty: (usize::MAX, 0),
            pass_gel_next: false,
            fuse_gel_pass: true,
            check_fused_gel: false,
            #[cfg(test)]
            fused_frames: Default::default(),
            steps_state: Vec::new(),
            displaced: Vec::new(),
            displaced_gas: 0.0,
            nuclei: NucleusPool::default(),
            tension_bound: None,
        };
        // bubbles placed large enough take their cells out of the gel before the balance
        // reference is taken (the gel was never there)
        sim.displace(p0);
        sim.nuclei = sim.nucleus_pool()?;
        sim.rebase_balance();
        Ok(sim)
    }

    /// The grid.
    pub fn grid(&self) -> &Grid {
        &self.grid
    }

    /// Gases in column order.
    pub fn gases(&self) -> &[Gas] {
        &self.gases
    }

    /// Concentration field of gas number `g` (mol/m³).
    pub fn field(&self, g: usize) -> &[f64] {
        &self.fields[g]
    }

    /// Mutable concentration field (for tests that set an initial state). Only the cells inside
    /// the gel are part of the model: the others should stay 0 ([`Fields`]' invariant); the
    /// explicit step that moves the fields by two planes does not carry them along.
    pub fn field_mut(&mut self, g: usize) -> &mut [f64] {
        self.tension_bound = None;
        self.gel_fresh = false;
        &mut self.fields[g]
    }

    /// Reset the gas-balance reference to the current state (after editing fields).
    pub fn rebase_balance(&mut self) {
        self.inflow = 0.0;
        self.displaced_gas = 0.0;
        self.initial_total = self.total_moles();
    }

    /// Gas in the grid plus gas in active bubbles, mol.
    pub fn total_moles(&self) -> f64 {
        let grid: f64 = self.fields.iter().map(|f| self.grid.integrate(f)).sum();
        grid + self
            .bubbles
            .iter()
            .filter(|b| b.active())
            .map(|b| b.total_moles())
            .sum::<f64>()
    }

    /// Current time, s.
    pub fn time(&self) -> f64 {
        self.time
    }

    fn balance_for<'b>(&'b self, b: &Bubble, ambient: f64) -> Balance<'b> {
        Balance {
            ambient,
            surface_tension: self.params.surface_tension,
            law: self.params.elasticity.as_ref(),
            initial_radius: b.initial_radius,
            initial_ambient: b.initial_ambient,
            fixed_gases: self.params.bubble_fixed_gases,
        }
    }

    /// Change of the grid's gas by the gel's displacement since the balance reference, mol
    /// ([`Self::displace`]; part of the gas balance).
    pub fn displaced_gas(&self) -> f64 {
        self.displaced_gas
    }

    /// Radius of bubble `i`'s sink kernel ([`Self::kernel_radius_at`]).
    fn kernel_radius(&self, i: usize) -> f64 {
        self.kernel_radius_at(self.bubbles[i].radius, self.displaces(i))
    }

    /// Radius of bubble `i`'s coupling sphere ρ ([`Self::coupling_radius_at`]).
    fn coupling_radius(&self, i: usize) -> f64 {
        self.coupling_radius_at(self.bubbles[i].radius, self.displaces(i))
    }

    /// Whether bubble `i` holds cells out of the gel ([`Self::displace`]).
    fn displaces(&self, i: usize) -> bool {
        self.displaced.get(i).is_some_and(|d| !d.cells.is_empty())
    }

    /// Sink-kernel radius of a bubble of radius `r`: max(R, kernel_min_cells·h), or, once it
    /// holds cells out of the gel (`displacing`), the shell out to R + kernel_min_cells·h.
    fn kernel_radius_at(&self, r: f64, displacing: bool) -> f64 {
        let k = self.params.numerics.kernel_min_cells * self.grid.h;
        if displacing {
            r + k
        } else {
            r.max(k)
        }
    }

    /// Coupling radius ρ = max(kernel, R + δ) + coupling_gap_cells·h.
    fn coupling_radius_at(&self, r: f64, displacing: bool) -> f64 {
        self.kernel_radius_at(r, displacing)
            .max(r + self.params.surface_layer_thickness)
            + self.params.numerics.coupling_gap_cells * self.grid.h
    }

    /// Average of every gas's field over the sphere of radius `rho` about `c` into `out` (one
    /// per gas; `fallback` per gas where a point has no inside cell about it). The sphere must
    /// have been prepared ([`Self::prepare_sphere_at`]). The points'
    /// corners and weights are found once for all gases ([`Grid::interpolate_many`]).
    fn sphere_means(&self, c: [f64; 3], rho: f64, fallback: &[f64], out: &mut [f64]) {
        let sphere = &self.spheres[&self.sphere_size(rho)];
        let ng = out.len();
        let mut sum = [0.0; Gas::ALL.len()];
        let mut at = [0.0; Gas::ALL.len()];
        let fields = self.field_views();
        for &u in sphere {
            self.sphere_point(&fields, c, rho, u, fallback, &mut at[..ng]);
            for (s, a) in sum.iter_mut().zip(&at[..ng]) {
                *s += a;
            }
        }
        for (o, s) in out.iter_mut().zip(sum) {
            *o = s / sphere.len() as f64;
        }
    }

    /// Every gas's field view ([`Fields`]), the unused entries empty: taken once per sphere,
    /// not per sample (a view is an offset and a bounds check).
    fn field_views(&self) -> [&[f64]; Gas::ALL.len()] {
        let mut v: [&[f64]; Gas::ALL.len()] = [&[]; Gas::ALL.len()];
        for (v, f) in v.iter_mut().zip(self.fields.iter()) {
            *v = f;
        }
        v
    }

    /// Every gas's field (`out.len()` of them; `fields` from [`Self::field_views`])
    /// interpolated at the point `c + rho·u` of a coupling sphere, from inside cells only
    /// (`fallback` where none is about it).
    #[inline(always)]
    fn sphere_point(
        &self,
        fields: &[&[f64]; Gas::ALL.len()],
        c: [f64; 3],
        rho: f64,
        u: [f64; 3],
        fallback: &[f64],
        out: &mut [f64],
    ) {
        let grid = &self.grid;
        let p = [c[0] + rho * u[0], c[1] + rho * u[1], c[2] + rho * u[2]];
        grid.interpolate_many(p, fallback, out, |idx, v| {
            if !grid.inside(idx) {
                return false;
            }
            for (v, f) in v.iter_mut().zip(fields) {
                *v = f[idx];
            }
            true
        });
    }

    /// Points of the Fibonacci sphere [`Self::sphere_means`] samples at radius `rho`:
    /// 16·(ρ/h)², between 64 and 20 000.
    fn sphere_size(&self, rho: f64) -> usize {
        ((16.0 * (rho / self.grid.h).powi(2)).ceil() as usize).clamp(64, 20_000)
    }

    /// Make bubble `i`'s coupling sphere ready for [`Self::sphere_means`] (built once per
    /// size; the cache is emptied when it holds more than [`SPHERE_CACHE`] sizes, before a
    /// round of fluxes). Returns its number of points.
    fn prepare_sphere(&mut self, i: usize) -> usize {
        self.prepare_sphere_at(self.coupling_radius(i))
    }

    /// [`Self::prepare_sphere`] for a sphere of radius `rho`.
    fn prepare_sphere_at(&mut self, rho: f64) -> usize {
        let want = self.sphere_size(rho);
        let turns = &mut self.sphere_turns;
        self.spheres
            .entry(want)
            .or_insert_with(|| fibonacci_sphere(want, turns));
        want
    }

    /// The fluxes and gel tensions ([`Self::all_fluxes`]) at `ambient` of the bubbles `keep`
    /// selects, in the buffers of [`FluxRound`] (kept between steps: give them back with
    /// `self.round = round`).
    fn flux_round(
        &mut self,
        ambient: f64,
        profile: &PressureHistory,
        keep: impl Fn(&Self, usize) -> bool,
    ) -> FluxRound {
        self.round_at = None;
        let mut round = std::mem::take(&mut self.round);
        round.which.clear();
        round
            .which
            .extend((0..self.bubbles.len()).filter(|&i| keep(self, i)));
        round.out.clear();
        round
            .out
            .resize(self.bubbles.len(), (0.0, [0.0; Gas::ALL.len()]));
        self.all_fluxes(
            ambient,
            profile,
            &round.which,
            &mut round.out,
            (&mut round.vals, &mut round.means),
        );
        round
    }

    /// Every active bubble's fluxes and gel tension at `ambient` into `out` (by bubble index;
    /// inactive bubbles are left alone), from the grid as it is. Bubbles are independent here
    /// (each reads the grid and its own state), so when there are several and enough points
    /// to sample they run in parallel, each with the same operations as alone: the same bits.
    fn all_fluxes(
        &mut self,
        ambient: f64,
        profile: &PressureHistory,
        which: &[usize],
        out: &mut [(f64, [f64; Gas::ALL.len()])],
        (vals, means): (
            &mut Vec<[f64; Gas::ALL.len()]>,
            &mut Vec<[f64; Gas::ALL.len()]>,
        ),
    ) {
        if self.spheres.len() > SPHERE_CACHE {
            self.spheres.clear();
        }
        let points: usize = which.iter().map(|&i| self.prepare_sphere(i)).sum();
        let ng = self.gases.len();
        if points >= PARALLEL_SPHERE_POINTS && !serial_fluxes() && rayon::current_num_threads() > 1
        {
            let cb = self.inspired_concentrations(profile);
            self.sphere_means_of(which, &cb, vals, means);
            for (&i, cbar) in which.iter().zip(means.iter()) {
                let mut j = [0.0; Gas::ALL.len()];
                let t = self.fluxes_from_means(i, ambient, &cbar[..ng], &mut j[..ng]);
                out[i] = (t, j);
            }
        } else {
            for &i in which {
                let mut j = [0.0; Gas::ALL.len()];
                let t = self.fluxes(i, ambient, profile, &mut j[..ng], (vals, means));
                out[i] = (t, j);
            }
        }
    }

    /// Every gas's concentration in equilibrium with the inspired gas now, mol/m³ (the value a
    /// sampled point with no inside cell about it takes).
    fn inspired_concentrations(&self, profile: &PressureHistory) -> [f64; Gas::ALL.len()] {
        let mut cb = [0.0; Gas::ALL.len()];
        for (g, cb) in cb[..self.gases.len()].iter_mut().enumerate() {
            *cb = self.ostwald[g] * profile.inspired_partial_pressure(self.gases[g], self.time)
                / self.rt;
        }
        cb
    }

    /// [`Self::sphere_means`] of each bubble of `which` on its coupling sphere (prepared), the
    /// points of all of them sampled in one parallel pass into `vals` (balanced over the
    /// threads whatever the bubbles' sizes), then each bubble's summed in point order: the
    /// same operations on the same values, the same bits as one by one.
    fn sphere_means_of(
        &self,
        which: &[usize],
        fallback: &[f64; Gas::ALL.len()],
        vals: &mut Vec<[f64; Gas::ALL.len()]>,
        means: &mut Vec<[f64; Gas::ALL.len()]>,
    ) {
        use rayon::prelude::*;
        /// Points per parallel task.
        const CHUNK: usize = 256;
        let ng = self.gases.len();
        // per bubble: its first point in `vals`, centre, radius and sphere
        let mut segs = Vec::with_capacity(which.len());
        let mut total = 0;
        for &i in which {
            let rho = self.coupling_radius(i);
            let sphere = &self.spheres[&self.sphere_size(rho)];
            segs.push((total, self.bubbles[i].position, rho, sphere.as_slice()));
            total += sphere.len();
        }
        vals.clear();
        vals.resize(total, [0.0; Gas::ALL.len()]);
        let fields = self.field_views();
        vals.par_chunks_mut(CHUNK)
            .enumerate()
            .for_each(|(c, chunk)| {
                let first = c * CHUNK;
                let mut s = segs.partition_point(|seg| seg.0 <= first) - 1;
                for (q, v) in chunk.iter_mut().enumerate() {
                    let idx = first + q;
                    while s + 1 < segs.len() && segs[s + 1].0 <= idx {
                        s += 1;
                    }
                    let (start, c, rho, sphere) = segs[s];
                    let u = sphere[idx - start];
                    self.sphere_point(&fields, c, rho, u, &fallback[..ng], &mut v[..ng]);
                }
            });
        means.clear();
        means.extend(segs.iter().map(|&(start, _, _, sphere)| {
            let mut sum = [0.0; Gas::ALL.len()];
            for at in &vals[start..start + sphere.len()] {
                for (s, a) in sum.iter_mut().zip(&at[..ng]) {
                    *s += a;
                }
            }
            let mut mean = [0.0; Gas::ALL.len()];
            for (o, s) in mean[..ng].iter_mut().zip(sum) {
                *o = s / sphere.len() as f64;
            }
            mean
        }));
    }

    /// Gas fluxes into bubble `i` (mol/s per gas) and the gel tension at its coupling sphere.
    /// The bubble's coupling sphere must have been prepared ([`Self::prepare_sphere`]).
    fn fluxes(
        &self,
        i: usize,
        ambient: f64,
        profile: &PressureHistory,
        j: &mut [f64],
        (vals, means): (
            &mut Vec<[f64; Gas::ALL.len()]>,
            &mut Vec<[f64; Gas::ALL.len()]>,
        ),
    ) -> f64 {
        let ng = self.gases.len();
        let rho = self.coupling_radius(i);
        let mut cbar = [0.0; Gas::ALL.len()];
        let cb = self.inspired_concentrations(profile);
        if self.sphere_size(rho) >= PARALLEL_SPHERE_POINTS
            && !serial_fluxes()
            && rayon::current_num_threads() > 1
        {
            // a large sphere's points in parallel (the same bits, as in Self::all_fluxes)
            self.sphere_means_of(&[i], &cb, vals, means);
            cbar = means[0];
        } else {
            self.sphere_means(self.bubbles[i].position, rho, &cb[..ng], &mut cbar[..ng]);
        }
        self.fluxes_from_means(i, ambient, &cbar[..ng], j)
    }

    /// [`Self::fluxes`] from the means `cbar` (one per gas) over bubble `i`'s coupling sphere.
    fn fluxes_from_means(&self, i: usize, ambient: f64, cbar: &[f64], j: &mut [f64]) -> f64 {
        let (r, r0) = {
            let b = &self.bubbles[i];
            (b.radius, b.initial_radius)
        };
        let ng = self.gases.len();
        let rho = self.coupling_radius(i);
        let mut tension = self.params.bubble_fixed_gases;
        for g in 0..ng {
            tension += cbar[g] * self.rt / self.ostwald[g];
        }
        j.iter_mut().for_each(|x| *x = 0.0);
        if r <= self.params.min_radius {
            return tension;
        }
        // the gel in the shell moves with the wall where the bubble displaces it (around a
        // sub-grid bubble the grid's gel does not move, and neither does the shell's)
        let wall_speed = match self.displaced.get(i) {
            Some(d) if !d.cells.is_empty() => d.wall_speed,
            _ => 0.0,
        };
        let b = &self.bubbles[i];
        // the simulated gases' share of P_B (eq. 2.4 less the fixed partial pressure)
        let pb = self.balance_for(b, ambient).simulated_pressure(r);
        let n = b.total_moles();
        let outer = r + self.params.surface_layer_thickness;
        for g in 0..ng {
            let cs = self.ostwald[g] * (b.moles[g] / n) * pb / self.rt;
            let d = self.diffusivity[g];
            let ds = self.params.surface.d_surf(d, r, r0);
            if !(ds > 0.0) {
                continue;
            }
            let resistance = (1.0 / r - 1.0 / outer) / ds + (1.0 / outer - 1.0 / rho) / d;
            j[g] = 4.0 * PI * (cbar[g] - cs) / resistance
                * displacement::convection_factor(r * r * wall_speed * resistance);
        }
        tension
    }

    /// Run the profile to its end (or until a bubble reaches a face). Each step is the physics
    /// in order: the bubbles' fluxes at the start of the step ([`Self::bubble_fluxes`]), the step
    /// the physics allows ([`Self::choose_step`]), the gas exchange between bubbles and gel
    /// ([`Self::exchange`]), diffusion ([`Self::diffuse`]), perfusion ([`Self::perfuse`]), the
    /// radii at the new pressure ([`Self::update_radii`]), coalescence, health checks, and the
    /// record ([`Self::observe`]).
    pub fn run(
        &mut self,
        profile: &PressureHistory,
        observer: &mut dyn Observer,
    ) -> Result<RunSummary, Error> {
        self.run_from(profile, observer, None)
    }

    /// The smallest explicit limit over the gases, s.
    fn smallest_explicit_limit(&self) -> f64 {
        self.explicit_limit
            .iter()
            .cloned()
            .fold(f64::INFINITY, f64::min)
    }

    /// [`Self::run`], or its continuation from a checkpoint's loop state (`resume`: the
    /// simulation was rebuilt by [`super::checkpoint::Checkpoint::resume`]; the initial state is
    /// not recorded again). After every complete step the run goes on from, the observer may
    /// take a checkpoint ([`Observer::checkpoint_due`]).
    pub(super) fn run_from(
        &mut self,
        profile: &PressureHistory,
        observer: &mut dyn Observer,
        resume: Option<LoopState>,
    ) -> Result<RunSummary, Error> {
        let end = profile.duration_s();
        let nb = self.bubbles.len();
        let ng = self.gases.len();
        // fixed for the run
        let lim = self.smallest_explicit_limit();
        let LoopState {
            mut log,
            mut dt_prev,
            mut bubble_dt,
            mut field_dt,
            mut loading_dt,
            mut loading,
            mut tensions,
            mut fluxes,
        } = match resume {
            Some(state) => state,
            None => {
                let mut log = RunLog {
                    max_radius: (0.0, 0.0, 0),
                    peak_volume: (0.0, self.time),
                    min_concentration: f64::INFINITY,
                    steps: (0, 0),
                    events: Vec::new(),
                    ending: Ending::Completed,
                    next_record: self.time,
                };
                let mut tensions = vec![0.0; nb];
                let mut fluxes = vec![vec![0.0; ng]; nb];
                // record the initial state
                let p0 = profile.ambient(self.time);
                self.bubble_fluxes(profile, p0, &mut fluxes, &mut tensions);
                self.observe(profile, p0, &tensions, observer, &mut log, true)?;
                LoopState {
                    log,
                    dt_prev: self.params.numerics.max_step.min(lim),
                    // the step the bubbles' error estimate allows ([`Self::correct`])
                    bubble_dt: f64::INFINITY,
                    field_dt: f64::INFINITY,
                    loading_dt: f64::INFINITY,
                    loading: LoadingHistory::new(ng),
                    tensions,
                    fluxes,
                }
            }
        };
        // the pool's other workers kept awake through the serial phases of a lone run
        let warm = super::keep_warm::KeepWarm::new();
        while self.time < end - 1e-9 {
            let mut clock = Instant::now();
            let mut wall = StepWall::default();
            let t = self.time;
            let p = profile.ambient(t);
            self.bubble_fluxes(profile, p, &mut fluxes, &mut tensions);
            let estimates = [
                (bubble_dt, StepLimit::BubbleError),
                (field_dt, StepLimit::FieldError),
                (loading_dt, StepLimit::LoadingError),
            ];
            let (dt, dt_physics, limit) =
                self.choose_step(profile, &fluxes, dt_prev, estimates, lim, end);
            dt_prev = dt_physics;
            let t1 = t + dt;
            self.exchange(&fluxes, dt, t1, &mut log.events);
            // a frame with the gel's state at the end of this step (as [`Self::observe`]
            // decides; a run that ends early passes the whole gel at its last frame)
            self.pass_gel_next = self.fuse_gel_pass
                && ((self.params.numerics.record_gel && t1 >= log.next_record - 1e-9)
                    || t1 >= end - 1e-9);
            let scheme;
            wall.prepare_s = lap(&mut clock);
            warm.parallel_phase();
            (field_dt, loading_dt, scheme) =
                self.gel_step(profile, (t, dt), &mut loading, &mut log);
            warm.serial_phase();
            wall.gel_s = lap(&mut clock);
            self.perfuse(profile, t, dt);
            let (err, worst) = self.events(
                profile,
                (t, t1, dt),
                &mut tensions,
                &mut fluxes,
                &mut log,
                &mut wall,
            )?;
            wall.events_s = lap(&mut clock);
            let tol = self.params.numerics.bubble_tolerance;
            bubble_dt = self.bubble_step(dt, err, lim);
            self.observe(
                profile,
                profile.ambient(t1),
                &tensions,
                observer,
                &mut log,
                false,
            )?;
            wall.frame_s = lap(&mut clock);
            observer.step(&StepRecord {
                time: t,
                dt,
                scheme,
                limit,
                physics_dt: dt_physics,
                bubble_error: err / tol,
                next_bubble_dt: bubble_dt,
                next_field_dt: field_dt,
                next_loading_dt: loading_dt,
                bubble: worst.map(|w| w.0),
                flux_start: worst.map_or([0.0; Gas::ALL.len()], |w| w.1),
                flux_end: worst.map_or([0.0; Gas::ALL.len()], |w| w.2),
                wall,
            });
            if log.ending != Ending::Completed || self.time >= end - 1e-9 {
                break;
            }
            if observer.checkpoint_due(log.steps.0 + log.steps.1) {
                let state = LoopState {
                    log: log.clone(),
                    dt_prev,
                    bubble_dt,
                    field_dt,
                    loading_dt,
                    loading: loading.clone(),
                    tensions: tensions.clone(),
                    fluxes: fluxes.clone(),
                };
                observer.checkpoint(super::checkpoint::RunState::capture(self, state))?;
            }
        }
        let total = self.total_moles();
        let balance = ((total - self.initial_total - self.inflow - self.displaced_gas)
            / self.initial_total)
            .abs();
        if !(balance < BALANCE_LIMIT) {
            return Err(Error::Solver(format!(
                "gas balance lost: |gas now − gas at start − gas in through open faces and perfusion| is {balance:.3e} of the start; the run is not trustworthy"
            )));
        }
        Ok(RunSummary {
            gases: self.gases.clone(),
            max_radius: log.max_radius,
            final_radii: self
                .bubbles
                .iter()
                .map(|b| if b.active() { b.radius } else { 0.0 })
                .collect(),
            peak_total_volume: log.peak_volume,
            gas_balance_error: balance,
            min_concentration: log.min_concentration,
            steps: log.steps,
            end_time: self.time,
            ending: log.ending,
            events: log.events,
            cells: self.grid.n_inside,
        })
    }

    /// Phase 4 with its error estimates: the gel's diffusion over [t, t + dt] ([`Self::diffuse`],
    /// counted in the log as explicit or implicit) and the steps the field's and the loading's
    /// error estimates allow next ([`Self::loading_step`]; `loading` its history).
    fn gel_step(
        &mut self,
        profile: &PressureHistory,
        (t, dt): (f64, f64),
        loading: &mut LoadingHistory,
        log: &mut RunLog,
    ) -> (f64, f64, StepScheme) {
        // the field's tolerance, Pa: a fraction of the ambient pressure
        let p = profile.ambient(t).max(profile.ambient(t + dt));
        let field_tol = self.params.numerics.field_tolerance * p;
        let extrapolate = self.loading_only(profile);
        let (implicit, field_err) = self.diffuse(profile, t, dt, field_tol, extrapolate);
        // backward Euler's local error grows as dt²: the next step that keeps it at the
        // tolerance, with a safety factor 0.9
        let field_dt = if field_err > 0.0 {
            0.9 * dt * (field_tol / field_err).sqrt()
        } else {
            f64::INFINITY
        };
        // the second-order estimate for an extrapolated step at a steady pressure (a hold);
        // a descent's keep the first-order one ([`Self::loading_step`])
        let second = implicit && extrapolate && profile.rate(t + 1e-9) == 0.0;
        let loading_dt = self.loading_step(profile, (t, dt), second, loading);
        let scheme = if !implicit {
            log.steps.0 += 1;
            StepScheme::Explicit
        } else {
            log.steps.1 += 1;
            if extrapolate {
                StepScheme::Extrapolated
            } else {
                StepScheme::Implicit
            }
        };
        (field_dt, loading_dt, scheme)
    }

    /// Phases 6–8 of the step [t0, t1] of length dt (t1 − t0 but for its rounding) after the
    /// gel's diffusion and perfusion: the clock, the radii, the corrector of the bubbles'
    /// exchange, coalescence, nucleation, displacement and the health check. Returns the
    /// corrector's error estimate and the bubble that gave it ([`Self::correct`]), and puts the
    /// corrector's and the displacement's wall times in `wall`.
    fn events(
        &mut self,
        profile: &PressureHistory,
        (t0, t1, dt): (f64, f64, f64),
        tensions: &mut Vec<f64>,
        fluxes: &mut Vec<Vec<f64>>,
        log: &mut RunLog,
        wall: &mut StepWall,
    ) -> Result<(f64, WorstExchange), Error> {
        let end = profile.duration_s();
        let p1 = profile.ambient(t1);
        self.time = t1;
        self.update_radii(p1)?;
        let mut clock = Instant::now();
        let err = self.correct(profile, p1, dt, &mut log.events)?;
        wall.corrector_s = lap(&mut clock);
        self.coalesce(t1, p1, &mut log.events)?;
        self.nucleate(profile, t0, p1, tensions, fluxes, &mut log.events)?;
        lap(&mut clock);
        self.displace(p1);
        wall.displacement_s = lap(&mut clock);
        // a non-finite value spreads a cell per step: every 8th step is soon enough
        if (log.steps.0 + log.steps.1).is_multiple_of(8) || self.time >= end - 1e-9 {
            self.check_health()?;
        }
        Ok(err)
    }

    /// Phase 1: every active bubble's fluxes J_g (mol/s) and gel tension at the start of a step.
    fn bubble_fluxes(
        &mut self,
        profile: &PressureHistory,
        p: f64,
        fluxes: &mut [Vec<f64>],
        tensions: &mut [f64],
    ) {
        let ng = self.gases.len();
        let round = if self.reuse_frame_round && self.round_at == Some(self.time) {
            // the frame at the end of the last step computed this very round
            self.round_at = None;
            std::mem::take(&mut self.round)
        } else {
            self.flux_round(p, profile, |s, i| s.bubbles[i].active())
        };
        for i in 0..self.bubbles.len() {
            if self.bubbles[i].active() {
                tensions[i] = round.out[i].0;
                fluxes[i].copy_from_slice(&round.out[i].1[..ng]);
            } else {
                fluxes[i].iter_mut().for_each(|x| *x = 0.0);
            }
        }
        self.round = round;
    }

    /// The next step the bubbles' error estimate allows after a step `dt` whose estimate was
    /// `err` (`bubble_tolerance`; the next step is 0.9·dt·tol/err). Within the explicit limit
    /// `lim` the tolerance is `explicit_tolerance_factor` times larger (forward Euler leaves no
    /// backward-Euler lag near a bubble): when that step is within the limit it is taken, when
    /// only the limit is, the limit.
    fn bubble_step(&self, dt: f64, err: f64, lim: f64) -> f64 {
        let num = &self.params.numerics;
        let step = if err > 0.0 {
            0.9 * dt * num.bubble_tolerance / err
        } else {
            return f64::INFINITY;
        };
        let explicit = num.explicit_tolerance_factor * step;
        if explicit <= lim {
            explicit
        } else {
            step.max(lim)
        }
    }

    /// Phase 2: the step. The physics sets it — at most ×`max_step_growth` per step (×2 after
    /// an explicit step), `max_step`, the pressure-change limit, and for every bubble the
    /// content limit on the sum of each gas's own change, dt·Σ_g|J_g| ≤ max_content_change·n
    /// (not the net |Σ_g J_g|, which vanishes in counter-diffusion while each gas changes
    /// fast), and no gas losing more than half of what the bubble holds of it in one step.
    /// Then the profile's breakpoints and the scheme's cost cut it. Returns (the step, the step
    /// the physics allowed before the cuts).
    fn choose_step(
        &self,
        profile: &PressureHistory,
        fluxes: &[Vec<f64>],
        dt_prev: f64,
        estimates: [(f64, StepLimit); 3],
        lim: f64,
        end: f64,
    ) -> (f64, f64, StepLimit) {
        let num = self.params.numerics;
        let t = self.time;
        let p = profile.ambient(t);
        // every limit in turn; `limit` names the last one that shortened the step
        let mut dt = num.max_step;
        let mut limit = StepLimit::MaxStep;
        let mut lower = |dt: &mut f64, new: f64, which: StepLimit| {
            if new < *dt {
                limit = which;
            }
            *dt = new;
        };
        // ×`max_step_growth` from an implicit step while the bubbles' estimate is the tightest
        // of the error estimates (`Numerics::max_step_growth`); ×2 otherwise (forward Euler's
        // steady state does not depend on the step; the loading's and the field's estimates
        // follow their own smooth errors)
        let [(bubble_dt, _), (field_dt, _), (loading_dt, _)] = estimates;
        let bubbles_govern = bubble_dt <= field_dt.min(loading_dt).min(num.max_step);
        let growth = if dt_prev >= self.implicit_threshold && bubbles_govern {
            num.max_step_growth
        } else {
            2.0
        };
        let d = dt.min(growth * dt_prev);
        lower(&mut dt, d, StepLimit::Growth);
        for (e, which) in estimates {
            let d = dt.min(e);
            lower(&mut dt, d, which);
        }
        let rate = profile.rate(t + 1e-9).abs();
        if rate > 0.0 && !self.loading_only(profile) {
            let d = dt.min(num.max_pressure_change * p / rate);
            lower(&mut dt, d, StepLimit::PressureChange);
        }
        for (i, b) in self.bubbles.iter().enumerate() {
            if !b.active() {
                continue;
            }
            let jnet: f64 = fluxes[i].iter().sum();
            let jabs: f64 = fluxes[i].iter().map(|j| j.abs()).sum();
            let n = b.total_moles();
            // A bubble shrunk below 1 % of its initial radius may dissolve in one step
            // (otherwise the steps would shrink with R² for ever); above that every step
            // is limited by its relative change of content.
            let finishing = b.radius < 0.01 * b.initial_radius && -jnet * dt >= n;
            if finishing {
                continue;
            }
            if jabs > 0.0 {
                let d = dt.min(num.max_content_change * n / jabs).max(1e-6);
                lower(&mut dt, d, StepLimit::BubbleContent);
            }
            for (m, j) in b.moles.iter().zip(&fluxes[i]) {
                if *j < 0.0 && *m > 1e-9 * n {
                    let d = dt.min(0.5 * m / -j).max(1e-6);
                    lower(&mut dt, d, StepLimit::BubbleGas);
                }
            }
        }
        let physics = dt;
        let d = dt.min(profile.next_breakpoint(t) - t);
        lower(&mut dt, d, StepLimit::Breakpoint);
        let d = dt.min(end - t);
        lower(&mut dt, d, StepLimit::End);
        dt = dt.max(1e-9);
        // Below the implicit threshold the explicit limit itself is the cheaper and the more
        // accurate step (`Numerics::implicit_cost_ratio`).
        if dt > lim && dt < self.implicit_threshold {
            dt = lim;
            limit = StepLimit::ExplicitLimit;
        }
        (dt, physics, limit)
    }

    /// Whether the step from now only loads (or unloads) the gel through its open faces: the
    /// pressure does not fall, every bubble is dissolved, merged or shut (R ≤ R_min: no
    /// exchange; a steady or rising pressure keeps it shut, its content fixed) and there are
    /// no sub-grid nuclei. Its implicit steps are then extrapolated ([`Self::diffuse`]), the
    /// pressure-change limit does not apply and the loading's error estimate sizes the steps
    /// ([`Self::loading_step`]). Holds and deco stops with every nucleus shut are such steps
    /// as well as descents (since 27 Nov 2026; descents only before, when the holds'
    /// backward-Euler steps lagged the gel's unloading at first order: README "Time
    /// stepping"), unless `extrapolate_holds` is false or the field's error estimate is on
    /// (`field_tolerance`: it is backward Euler's, and a hold's steps then stay backward Euler).
    fn loading_only(&self, profile: &PressureHistory) -> bool {
        let rate = profile.rate(self.time + 1e-9);
        let num = &self.params.numerics;
        (rate > 0.0 || rate == 0.0 && num.extrapolate_holds && !num.field_tolerance.is_finite())
            && self.nuclei.is_empty()
            && self
                .bubbles
                .iter()
                .all(|b| !b.active() || b.radius <= self.params.min_radius)
    }

    /// Phase 3: the predictor of the gas exchange between bubbles and gel (Heun's method;
    /// [`Self::correct`] completes it after diffusion). Each bubble's content is predicted with
    /// the fluxes at the start of the step, n* = n + J(t)·dt, and that gas is taken from (or
    /// returned to) the grid now, before diffusion, through the bubble's sink kernel
    /// ([`Self::deposit`], which never overdraws a cell). A bubble that the predictor empties
    /// dissolves here, all its gas returned to the gel.
    fn exchange(&mut self, fluxes: &[Vec<f64>], dt: f64, t1: f64, events: &mut Vec<Event>) {
        let ng = self.gases.len();
        self.steps_state.clear();
        for i in 0..self.bubbles.len() {
            let mut st = StepExchange {
                start: [0.0; Gas::ALL.len()],
                taken: [0.0; Gas::ALL.len()],
                flux: [0.0; Gas::ALL.len()],
                open: false,
            };
            if !self.bubbles[i].active() {
                self.steps_state.push(st);
                continue;
            }
            st.open = true;
            st.start[..ng].copy_from_slice(&self.bubbles[i].moles[..ng]);
            st.flux[..ng].copy_from_slice(&fluxes[i][..ng]);
            if fluxes[i].iter().all(|x| *x == 0.0) {
                self.steps_state.push(st);
                continue;
            }
            let mut dn = [0.0; Gas::ALL.len()];
            for g in 0..ng {
                dn[g] = fluxes[i][g] * dt;
            }
            let n_after: f64 = self.bubbles[i].total_moles() + dn.iter().sum::<f64>();
            let dissolved = n_after <= 1e-6 * self.bubbles[i].total_moles() || n_after <= 0.0;
            for g in 0..ng {
                if dissolved || self.bubbles[i].moles[g] + dn[g] < 0.0 {
                    dn[g] = -self.bubbles[i].moles[g];
                }
            }
            if dissolved {
                let taken = self.take_from_grid(i, &dn[..ng]);
                for g in 0..ng {
                    self.bubbles[i].moles[g] += taken[g];
                }
                self.dissolve(i, t1, events);
                st.open = false;
                self.steps_state.push(st);
                continue;
            }
            let taken = self.take_from_grid(i, &dn[..ng]);
            st.taken = taken;
            // the predicted content: the fluxes of the end of the step are evaluated with it
            for g in 0..ng {
                self.bubbles[i].moles[g] = st.start[g] + dn[g];
            }
            self.steps_state.push(st);
        }
    }

    /// Move `dn[g]` mol of each gas from the grid (into it when negative) through bubble `i`'s
    /// sink kernel; what the kernel cannot supply comes from the shell out to the coupling
    /// sphere ρ ([`Self::deposit`] never overdraws a cell). Returns what was moved per gas.
    fn take_from_grid(&mut self, i: usize, dn: &[f64]) -> [f64; Gas::ALL.len()] {
        let mut out = [0.0; Gas::ALL.len()];
        let (pos, a) = (self.bubbles[i].position, self.kernel_radius(i));
        if self.kernel_caches.len() < self.bubbles.len() {
            self.kernel_caches
                .resize_with(self.bubbles.len(), Default::default);
        }
        let [mut near, mut far] = std::mem::take(&mut self.kernel_caches[i]);
        let mut kernel = std::mem::take(&mut self.kernel);
        let bounds = self.grid.kernel_cached(pos, a, &mut near, &mut kernel);
        self.touch(bounds);
        let mut wide = Vec::new();
        for (g, &want) in dn.iter().enumerate() {
            if want == 0.0 {
                continue;
            }
            let mut taken = self.deposit(g, &kernel, want);
            if want > 0.0 && taken < want {
                // the kernel ran dry: the rest comes from the shell out to the coupling
                // sphere ρ, the gel next to the bubble
                if wide.is_empty() {
                    let rho = self.coupling_radius(i);
                    let bounds = self.grid.kernel_cached(pos, rho, &mut far, &mut wide);
                    self.touch(bounds);
                }
                taken += self.deposit(g, &wide, want - taken);
            }
            out[g] = taken;
        }
        self.kernel = kernel;
        self.kernel_caches[i] = [near, far];
        out
    }

    /// Extend [`Self::touched`] by the box `(lo, hi)` (inclusive cell coordinates) of a kernel's
    /// cells ([`Grid::kernel`]).
    fn touch(&mut self, (clo, chi): ([usize; 3], [usize; 3])) {
        let (lo, hi) = self.touched.get_or_insert((clo, chi));
        for a in 0..3 {
            lo[a] = lo[a].min(clo[a]);
            hi[a] = hi[a].max(chi[a]);
        }
    }

    /// Whether bubble `i`'s coupling sphere (its trilinear samples reach a cell beyond ρ)
    /// may read a cell in [`Self::touched`].
    fn reads_touched(&self, i: usize) -> bool {
        let Some((tlo, thi)) = self.touched else {
            return false;
        };
        let reach = self.coupling_radius(i) + 2.0 * self.grid.h;
        let (lo, hi) = self.grid.cell_range(self.bubbles[i].position, reach);
        (0..3).all(|a| lo[a] <= thi[a] && tlo[a] <= hi[a])
    }

    /// Bubble `i` has dissolved at `t1`: whatever round-off it still holds is dropped from it
    /// (its gas was returned to the gel by the transfer that emptied it).
    fn dissolve(&mut self, i: usize, t1: f64, events: &mut Vec<Event>) {
        self.bubbles[i].moles.iter_mut().for_each(|m| *m = 0.0);
        self.bubbles[i].radius = 0.0;
        self.bubbles[i].fate = BubbleFate::Dissolved(t1);
        events.push(Event::Dissolved {
            time: t1,
            bubble: i,
        });
    }

    /// Phase 6b: the corrector of the bubbles' exchange (Heun's method: the trapezoidal rule on
    /// dn_g/dt = J_g). With the fluxes J_g(t + dt) of the predicted state (radius, content, and
    /// the gel after diffusion), the step moves W_g = (J_g(t) + J_g(t + dt))·dt/2 into each
    /// bubble; the grid gave the predictor's J_g(t)·dt before diffusion ([`Self::exchange`]) and
    /// gives the difference, W_g − that ≈ (J_g(t + dt) − J_g(t))·dt/2, now through the kernel:
    /// second order in dt for the bubble, gas conserved exactly, no cell overdrawn. (Splitting
    /// the predictor's gas half before and half after diffusion was tried: no more accurate on
    /// the Epstein–Plesset case, and it leaves undiffused gas in the kernel cells at every
    /// record, which the gel's peak supersaturation then reads.)
    /// Returns the largest relative change of a bubble's flux over the step,
    /// Σ_g |J_g(t + dt) − J_g(t)|·dt / (Σ_g |J̄_g|·dt + 0.01·n), which sizes the next step
    /// ([`Numerics::bubble_tolerance`](super::params::Numerics::bubble_tolerance)): what stays
    /// first order after the corrector is the lag of the implicit diffusion near the bubble.
    fn correct(
        &mut self,
        profile: &PressureHistory,
        p1: f64,
        dt: f64,
        events: &mut Vec<Event>,
    ) -> Result<(f64, WorstExchange), Error> {
        let ng = self.gases.len();
        let t1 = self.time;
        let mut worst: f64 = 0.0;
        let mut which: WorstExchange = None;
        let mut any = false;
        // every open bubble's end-of-step fluxes, from the grid before any correction; a
        // bubble whose coupling sphere reads cells that an earlier bubble's correction has
        // changed is evaluated again when its turn comes (what a serial loop would have read)
        let mut round = self.flux_round(p1, profile, |s, i| {
            s.steps_state[i].open && s.bubbles[i].active()
        });
        self.touched = None;
        for &i in &round.which {
            let st = self.steps_state[i];
            if !self.bubbles[i].active() {
                continue;
            }
            let mut j1 = round.out[i].1;
            if self.reads_touched(i) || serial_fluxes() {
                // the round's sampling buffers as scratch (its fluxes are in `out`)
                let scratch = (&mut round.vals, &mut round.means);
                self.fluxes(i, p1, profile, &mut j1[..ng], scratch);
            }
            if (0..ng).all(|g| j1[g] == 0.0 && st.flux[g] == 0.0) {
                continue;
            }
            any = true;
            let n0: f64 = st.start[..ng].iter().sum();
            let mut rest = [0.0; Gas::ALL.len()];
            let (mut change, mut moved) = (0.0, 0.0);
            for g in 0..ng {
                // never more out of the bubble than it held
                let w = (0.5 * (st.flux[g] + j1[g]) * dt).max(-st.start[g]);
                rest[g] = w - st.taken[g];
                change += (j1[g] - st.flux[g]).abs() * dt;
                moved += 0.5 * (j1[g].abs() + st.flux[g].abs()) * dt;
            }
            let scale = moved + FLUX_FLOOR * n0;
            if scale > 0.0 {
                let e = change / scale;
                worst = worst.max(e);
                if e >= worst {
                    which = Some((i, st.flux, j1));
                }
            }
            let taken = self.take_from_grid(i, &rest[..ng]);
            for g in 0..ng {
                self.bubbles[i].moles[g] = st.start[g] + st.taken[g] + taken[g];
            }
            let after = self.bubbles[i].total_moles();
            // gone: a millionth of the step's start, or below the content of R0/1000 (a bubble
            // shrinking over many steps would otherwise leave 1e-26 mol no radius solve can hold)
            let b = &self.bubbles[i];
            let n_r0 = self.balance_for(b, p1).pv(b.initial_radius) / self.rt;
            if after <= 1e-6 * n0 || after <= 1e-9 * n_r0 || after <= 0.0 {
                let back: Vec<f64> = self.bubbles[i].moles[..ng].iter().map(|m| -m).collect();
                self.take_from_grid(i, &back);
                self.dissolve(i, t1, events);
            }
        }
        self.round = round;
        if any {
            self.update_radii(p1)?;
        }
        Ok((worst, which))
    }

    /// Phase 7b: bubbles displace the gel ([`displacement`], issue 8 item 5). A bubble of
    /// radius R ≥ `displace_min_cells`·h holds the cells inside R out of the gel; whenever its
    /// radius has moved by `displace_step_cells`·h since the last displacement, the gel around
    /// it is moved radially as an incompressible medium ([`displacement::remap`], out to
    /// `displace_reach`·R + 2h), the cells it has grown over leave the gel (their gel has been
    /// carried outward by the remap) and the cells it has shrunk off come back with the gel
    /// that flowed in. A dissolved or merged bubble gives its cells back at the mean of their
    /// neighbours; a merged bubble re-takes its cells about its new centre. Every change of the
    /// grid's gas here is added to `displaced_gas`, which the gas balance carries.
    fn displace(&mut self, ambient: f64) {
        let num = self.params.numerics;
        if !num.displace_gel {
            return;
        }
        let h = self.grid.h;
        let h3 = self.grid.cell_volume();
        self.displaced
            .resize(self.bubbles.len(), Displaced::default());
        for i in 0..self.bubbles.len() {
            let b = &self.bubbles[i];
            let st = &mut self.displaced[i];
            let (r_last, t_last) = st.last;
            st.wall_speed = if self.time > t_last && b.active() && r_last > 0.0 {
                (b.radius - r_last) / (self.time - t_last)
            } else {
                0.0
            };
            st.last = (if b.active() { b.radius } else { 0.0 }, self.time);
            let st = &self.displaced[i];
            let (r_new, centre) = if b.active() && b.radius >= num.displace_min_cells * h {
                (b.radius, b.position)
            } else {
                (0.0, b.position)
            };
            let moved_centre = st.centre != centre && !st.cells.is_empty();
            if !moved_centre && (r_new - st.radius).abs() < num.displace_step_cells * h {
                continue;
            }
            if r_new == 0.0 && st.cells.is_empty() {
                self.displaced[i].radius = 0.0;
                continue;
            }
            // the gel's move (only about a fixed centre: a merge moves the centre, and its
            // rearrangement of the gel is not modelled)
            let remapped = if moved_centre || !b.active() {
                Vec::new()
            } else {
                let reach = num.displace_reach * r_new.max(st.radius) + 2.0 * h;
                // Henry's law at the wall: the gel next to the bubble
                let ps = self.balance_for(b, ambient).simulated_pressure(b.radius);
                let n = b.total_moles();
                let wall: Vec<f64> = (0..self.gases.len())
                    .map(|g| self.ostwald[g] * (b.moles[g] / n) * ps / self.rt)
                    .collect();
                displacement::remap(
                    &self.grid,
                    &self.field_views()[..self.gases.len()],
                    &wall,
                    centre,
                    st.radius,
                    r_new,
                    reach,
                )
            };
            let new_cells = if r_new > 0.0 {
                displacement::covered_cells(&self.grid, centre, r_new)
            } else {
                Vec::new()
            };
            let old_cells = std::mem::take(&mut self.displaced[i].cells);
            let mut take: Vec<usize> = Vec::new();
            let mut keep: Vec<usize> = Vec::new();
            for &idx in &new_cells {
                if old_cells.binary_search(&idx).is_ok() {
                    keep.push(idx);
                } else if !self.grid.is_excluded(idx) {
                    take.push(idx);
                }
            }
            let give: Vec<usize> = old_cells
                .iter()
                .copied()
                .filter(|idx| new_cells.binary_search(idx).is_err())
                .collect();
            self.mark_gel(take.iter().chain(&give).copied());
            self.mark_gel(remapped.iter().flatten().map(|(idx, _)| *idx));
            // cells grown over leave the gel with their gas
            for &idx in &take {
                for f in self.fields.iter_mut() {
                    self.displaced_gas -= f[idx] * h3;
                    f[idx] = 0.0;
                }
            }
            self.grid.set_excluded(&take, true);
            self.grid.set_excluded(&give, false);
            for (idx, values) in remapped.iter().flatten() {
                if !self.grid.inside(*idx) {
                    continue;
                }
                for (f, v) in self.fields.iter_mut().zip(values) {
                    self.displaced_gas += (v - f[*idx]) * h3;
                    f[*idx] = *v;
                }
            }
            if remapped.iter().all(|p| p.is_empty()) && !give.is_empty() {
                // no remap: the cells given back take the gel next to them, outer cells first
                let mut order = give.clone();
                let dist = |idx: usize| {
                    let [nx, ny, _] = self.grid.n;
                    let p = [idx % nx, (idx / nx) % ny, idx / (nx * ny)];
                    (0..3)
                        .map(|a| ((p[a] as f64 + 0.5) * h - centre[a]).powi(2))
                        .sum::<f64>()
                };
                order.sort_by(|a, b| dist(*b).total_cmp(&dist(*a)));
                for idx in order {
                    for f in self.fields.iter_mut() {
                        let v = displacement::neighbour_mean(&self.grid, f, idx, 0.0);
                        self.displaced_gas += (v - f[idx]) * h3;
                        f[idx] = v;
                    }
                }
            }
            let mut cells = keep;
            cells.extend(take);
            cells.sort_unstable();
            let st = &mut self.displaced[i];
            st.cells = cells;
            st.radius = r_new;
            st.centre = centre;
        }
    }

    /// Take `dn` mol of gas `g` from the grid through the kernel (give it back when negative) and
    /// return the amount actually moved. Gas returned to the gel goes with the kernel's weights.
    /// Gas taken never drives a cell negative: each cell gives at most what it holds — first
    /// its kernel share, then the shortfall from the cells with content left, in proportion to
    /// it. When the whole kernel holds less than `dn` it gives what it has ([`Self::exchange`]
    /// then takes the rest from the wider sphere of radius ρ the same way; if even that runs dry
    /// the bubble receives only what is there, and the next step's flux sees the emptied cells).
    fn deposit(&mut self, g: usize, kernel: &[(usize, f64)], dn: f64) -> f64 {
        self.mark_gel(kernel.iter().map(|&(idx, _)| idx));
        let h3 = self.grid.cell_volume();
        let f = &mut self.fields[g];
        let per_volume = dn / h3;
        if per_volume <= 0.0 || kernel.iter().all(|&(idx, w)| w * per_volume <= f[idx]) {
            for &(idx, w) in kernel {
                f[idx] -= w * per_volume;
            }
            return dn;
        }
        // pass 1: each cell its share, capped by its content
        let mut taken = 0.0;
        let mut left = 0.0;
        for &(idx, w) in kernel {
            let x = (w * per_volume).min(f[idx].max(0.0));
            f[idx] -= x;
            taken += x;
            left += f[idx].max(0.0);
        }
        // pass 2: the shortfall from what is left, proportionally (a fraction ≤ 1 of each)
        let short = per_volume - taken;
        if short > 0.0 && left > 0.0 {
            let frac = (short / left).min(1.0);
            for &(idx, _) in kernel {
                let x = f[idx].max(0.0) * frac;
                f[idx] -= x;
                taken += x;
            }
        }
        taken * h3
    }

    /// Phase 4: diffuse every gas (eq. 2.1), explicit when the step is within the positivity
    /// limit of every gas, LOD backward Euler otherwise; the open-face inflow goes to the
    /// balance. Returns whether the step was implicit, and the estimate of an implicit step's
    /// local error in the gel's gas tension (Pa, the largest over cells and gases; 0 after an
    /// explicit step, with the estimate off, or with no history yet).
    ///
    /// The estimate is the one of variable-step BDF codes for backward Euler: with δ_n the
    /// change of a cell by diffusion over this step (dt_n) and δ_{n−1} over the last
    /// (dt_{n−1}), the local error −(dt²/2)·∂²C/∂t² is estimated by
    /// e = dt_n/(dt_n + dt_{n−1})·(δ_n − (dt_n/dt_{n−1})·δ_{n−1}) (the corrector minus the
    /// linear extrapolation of the last change). The grid-scale components of e are stiff:
    /// backward Euler damps them, and they would otherwise hold every step near the explicit
    /// limit; so when max|e| exceeds the tolerance, e is filtered by one backward-Euler solve,
    /// (I − dt·D∇²)⁻¹e with the open faces at 0 (Shampine's filter of stiff error estimates),
    /// which leaves the smooth components and never enlarges the max norm. Converted to a gas
    /// tension by R_u·T/L_g. Forward-Euler steps (at most a few times the explicit limit, which
    /// bounds their error) keep the history going and are not measured.
    fn diffuse(
        &mut self,
        profile: &PressureHistory,
        t: f64,
        dt: f64,
        tol_pa: f64,
        extrapolate: bool,
    ) -> (bool, f64) {
        let implicit = self.explicit_limit.iter().any(|lim| dt > *lim);
        self.gel_fresh = false;
        let h3 = self.grid.cell_volume();
        let estimate = tol_pa.is_finite();
        let ng = self.gases.len();
        if estimate && self.last_change.len() != ng {
            self.last_change = vec![vec![0.0; self.grid.len()]; ng];
            self.last_dt = 0.0;
        }
        if estimate {
            self.scratch.resize(self.grid.len(), 0.0);
        }
        let mut err: f64 = 0.0;
        if !extrapolate && !self.extra.is_empty() {
            // the descent's extrapolation is over: give its field-sized buffer back
            self.extra = Vec::new();
        }
        // (the field's estimate and the extrapolated descent step gas by gas, below)
        if !(estimate || implicit && extrapolate) {
            // every gas at once, each the same bits as stepped alone: the explicit step in one
            // parallel pass, the implicit steps side by side; the open faces at their value at
            // the end of the step in both (both take the open faces' term implicitly)
            let tb = t + dt;
            let mut dc = [(0.0, 0.0); Gas::ALL.len()];
            for (g, dc) in dc[..ng].iter_mut().enumerate() {
                let cb = self.ostwald[g] * profile.inspired_partial_pressure(self.gases[g], tb)
                    / self.rt;
                *dc = (self.diffusivity[g], cb);
            }
            let mut inflow = [0.0; Gas::ALL.len()];
            let threads = rayon::current_num_threads();
            let out_of_place = self.fields_bytes() <= self.out_of_place_bytes && threads > 1;
            // as many gases as threads: a thread per field, and on one thread the fields one
            // after the other, each moved by two planes instead of copying a plane per plane
            // (`diffusion::explicit_steps_shifting_per_field`); unless the step passes the gel
            // for one of the frames that carry it (out of place, on grids up to
            // `OUT_OF_PLACE_BYTES`, two or more threads); without `record_gel` only the last
            // frame does, and a pass of its own costs less than the second set of fields
            let per_field = self.per_field && (ng > 1 && ng == threads || threads == 1);
            let pass_gel = self.pass_gel_next && self.params.numerics.record_gel;
            if !implicit && out_of_place && (pass_gel || !per_field) {
                self.explicit_steps_out_of_place(&dc[..ng], dt, &mut inflow[..ng]);
            } else if !implicit && per_field {
                // a thread per field, each moved by two planes in its store instead of copying
                // a plane per plane (`diffusion::explicit_steps_shifting_per_field`)
                self.per_field_steps += 1;
                let (mut stores, from) = self.fields.stores_for_shift();
                let to = diffusion::explicit_steps_shifting_per_field(
                    &self.grid,
                    &mut stores,
                    from,
                    &dc[..ng],
                    dt,
                    &mut inflow[..ng],
                );
                self.fields.shifted(to);
            } else {
                let mut fields = self.fields.slices_mut();
                if implicit {
                    self.implicit
                        .steps(&self.grid, &mut fields, &dc[..ng], dt, &mut inflow[..ng]);
                } else {
                    diffusion::explicit_steps_in_place(
                        &self.grid,
                        &mut fields,
                        &dc[..ng],
                        dt,
                        &mut inflow[..ng],
                    );
                }
            }
            for (g, x) in inflow[..ng].iter().enumerate() {
                self.inflow += x * h3;
                self.step_flow[g] = x * h3;
            }
            return (implicit, 0.0);
        }
        for g in 0..ng {
            let gas = self.gases[g];
            let d = self.diffusivity[g];
            // both steps are in place: keep the field before the step for the estimate
            if estimate {
                self.scratch.copy_from_slice(&self.fields[g]);
            }
            let inflow = if implicit && extrapolate {
                self.extrapolated_step(profile, g, t, dt)
            } else {
                // the open faces at their end value (both schemes take their term implicitly)
                let cb = self.ostwald[g] * profile.inspired_partial_pressure(gas, t + dt) / self.rt;
                if implicit {
                    self.implicit
                        .step(&self.grid, &mut self.fields[g], d, dt, cb)
                } else {
                    diffusion::explicit_step_in_place(&self.grid, &mut self.fields[g], d, dt, cb)
                }
            };
            if estimate {
                let ratio = if self.last_dt > 0.0 {
                    dt / self.last_dt
                } else {
                    0.0
                };
                diffusion::change_and_error(
                    &self.grid,
                    &self.fields[g],
                    &mut self.scratch,
                    &mut self.last_change[g],
                    ratio,
                );
                if implicit && self.last_dt > 0.0 {
                    let to_pa = dt / (dt + self.last_dt) * self.rt / self.ostwald[g];
                    self.clear_near_fields();
                    let mut e = diffusion::rms_inside(&self.grid, &self.scratch) * to_pa;
                    if e > tol_pa {
                        self.implicit
                            .step(&self.grid, &mut self.scratch, d, dt, 0.0);
                        e = diffusion::rms_inside(&self.grid, &self.scratch) * to_pa;
                    }
                    err = err.max(e);
                }
            }
            self.inflow += inflow * h3;
            self.step_flow[g] = inflow * h3;
        }
        if estimate {
            self.last_dt = dt;
        }
        (implicit, err)
    }

    /// The bytes of one set of fields (every gas).
    fn fields_bytes(&self) -> usize {
        self.grid.len() * self.fields.len() * std::mem::size_of::<f64>()
    }

    /// Every gas's explicit step from `fields` into `back`, then the two swapped: the same
    /// bits as [`diffusion::explicit_steps_in_place`] (test
    /// `out_of_place_explicit_steps_are_the_in_place_bits`), without that step's copy of every
    /// plane's old values. `back` is brought level with `fields` first when the grid's codes
    /// changed since it last was (a cell taken out of the gel is zeroed in `fields` only), so
    /// the cells the step does not write, those outside the gel, hold the values they would
    /// hold in place.
    fn explicit_steps_out_of_place(&mut self, dc: &[(f64, f64)], dt: f64, inflow: &mut [f64]) {
        let pass_gel = std::mem::take(&mut self.pass_gel_next);
        let k = self.gel_factors();
        let id = self.grid.codes_id();
        if self.back.len() != self.fields.len() || self.back_codes != id {
            self.back.resize_with(self.fields.len(), Vec::new);
            for (b, f) in self.back.iter_mut().zip(self.fields.iter()) {
                b.clear();
                b.extend_from_slice(f);
            }
            self.back_codes = id;
        }
        {
            let src = self.fields.slices();
            let cells = self.grid.len();
            let mut dst: Vec<&mut [f64]> = self.back.iter_mut().map(|f| &mut f[..cells]).collect();
            if pass_gel {
                self.gel_planes.resize(self.grid.n[2], PlaneGel::default());
                diffusion::explicit_steps_into_passing_gel(
                    &self.grid,
                    &src,
                    &mut dst,
                    dc,
                    dt,
                    inflow,
                    (&k, &mut self.gel_planes),
                );
            } else {
                diffusion::explicit_steps_into(&self.grid, &src, &mut dst, dc, dt, inflow);
            }
        }
        self.fields.swap_stores(&mut self.back);
        if pass_gel {
            self.gel_fresh = true;
            self.gel_dirty = (usize::MAX, 0);
        }
    }

    /// Gas `g`'s implicit step over [t, t + dt] Richardson-extrapolated, 2·u_½ − u_1 from two
    /// half steps and one whole (second order; conservative, its weights summing to 1), or the
    /// two half steps where the extrapolation would make a cell negative. Returns the inflow
    /// through the open faces per cell volume, as [`diffusion::ImplicitSolver::step`].
    fn extrapolated_step(&mut self, profile: &PressureHistory, g: usize, t: f64, dt: f64) -> f64 {
        let (gas, d) = (self.gases[g], self.diffusivity[g]);
        let cb = |s: f64| self.ostwald[g] * profile.inspired_partial_pressure(gas, s) / self.rt;
        let (cb_half, cb_end) = (cb(t + 0.5 * dt), cb(t + dt));
        use rayon::prelude::*;
        // the grid-wide passes in parallel chunks (element by element: the same bits)
        const CHUNK: usize = 1 << 14;
        // the whole step in a copy of the field's whole store (the same layout, so that the
        // stores can be swapped below)
        let mut whole = std::mem::take(&mut self.extra);
        whole.resize(self.fields.store(g).len(), 0.0);
        whole
            .par_chunks_mut(CHUNK)
            .zip(self.fields.store(g).par_chunks(CHUNK))
            .for_each(|(w, f)| w.copy_from_slice(f));
        let (a, b) = self.fields.view_range();
        let f_whole = self
            .implicit
            .step(&self.grid, &mut whole[a..b], d, dt, cb_end);
        let half = &mut self.fields[g];
        let f_half = self.implicit.step(&self.grid, half, d, 0.5 * dt, cb_half)
            + self.implicit.step(&self.grid, half, d, 0.5 * dt, cb_end);
        // the extrapolation into the whole step's buffer, in one pass with the check for a
        // negative cell; kept (the stores swapped) only if there is none
        let negative = whole[a..b]
            .par_chunks_mut(CHUNK)
            .zip(half.par_chunks(CHUNK))
            .map(|(w, h)| {
                let mut negative = false;
                for (w, h) in w.iter_mut().zip(h) {
                    *w = 2.0 * h - *w;
                    negative |= *w < 0.0;
                }
                negative
            })
            .reduce(|| false, |x, y| x || y);
        let flow = if negative {
            f_half
        } else {
            self.fields.swap_store(g, &mut whole);
            2.0 * f_half - f_whole
        };
        self.extra = whole;
        flow
    }

    /// Phase 4b: the loading's error estimate ([`Numerics::loading_tolerance`]) after the step
    /// [t, t + dt], from each gas's flow through the open faces in this step and the steps
    /// before it since the last breakpoint (`history`; updated here, and cleared when this
    /// step ends at a breakpoint of the profile, where the pressure's rate changes). After a
    /// first-order step (backward or forward Euler) the estimate is
    /// [`loading_error_first_order`] and the next step 0.9·dt·√(tol/e); after a
    /// Richardson-extrapolated step at a steady pressure (`second`: a hold or a stop with every
    /// bubble shut) with two steps of history it is [`loading_error_second_order`], the
    /// scheme's own, and the next step 0.9·dt·∛(k·tol/e), k = `hold_tolerance_factor` (with
    /// one step of history, the first-order estimate, which over-states its error). A
    /// descent's extrapolated steps keep the first-order estimate: with the second-order one
    /// the ramp of `verification::a_descent_loads_the_gel_as_duhamels_series` lagged by
    /// 0.118 % of the load (its bound 0.1 %, 0.048 % with the first-order estimate) in
    /// 85 + 17 steps. Returns the next step it allows: ∞ without history or with the estimate
    /// off, and after a breakpoint at most the explicit limit if the gel has open faces, the
    /// step the run starts with (the flow's rate jumps there, and the estimate has no history
    /// to see it: the steps then grow again from the limit by at most 2× per step until it
    /// has).
    ///
    /// [`Numerics::loading_tolerance`]: super::params::Numerics::loading_tolerance
    fn loading_step(
        &self,
        profile: &PressureHistory,
        (t, dt): (f64, f64),
        second: bool,
        history: &mut LoadingHistory,
    ) -> f64 {
        let tol = self.params.numerics.loading_tolerance;
        if !tol.is_finite() {
            return f64::INFINITY;
        }
        let ng = self.gases.len();
        let flow = &self.step_flow[..ng];
        let mut next = f64::INFINITY;
        if history.last_dt > 0.0 {
            // a pure gas at the ambient pressure in the whole gel, mol per unit of L_g
            let scale =
                self.grid.n_inside as f64 * self.grid.cell_volume() * profile.ambient(t + dt)
                    / self.rt;
            let second = second && history.before_dt > 0.0;
            let mut worst: f64 = 0.0;
            for g in 0..ng {
                let last = (history.last[g], history.last_dt);
                let e = if second {
                    let before = (history.before[g], history.before_dt);
                    loading_error_second_order((flow[g], dt), last, before)
                } else {
                    loading_error_first_order(flow[g], dt, last.0, last.1)
                };
                worst = worst.max(e / (scale * self.ostwald[g]));
            }
            if worst > 0.0 {
                next = 0.9
                    * dt
                    * if second {
                        (self.params.numerics.hold_tolerance_factor * tol / worst).cbrt()
                    } else {
                        (tol / worst).sqrt()
                    };
            }
        }
        if profile.next_breakpoint(t) <= t + dt + 1e-9 {
            history.clear();
            if self.grid.open_cells.iter().any(|c| !c.is_empty()) {
                next = next.min(self.smallest_explicit_limit());
            }
        } else {
            history.push(flow, dt);
        }
        next
    }

    /// Zero the field-error vector (in `scratch`) in every active bubble's near field: the
    /// cells within its coupling radius ρ plus two grid steps, whose change within a step is
    /// the bubble's exchange, which the bubbles' own error estimate controls
    /// (`bubble_tolerance`, [`Self::correct`]). Returns whether any cell was cleared.
    fn clear_near_fields(&mut self) -> bool {
        let [nx, ny, _] = self.grid.n;
        let h = self.grid.h;
        let mut any = false;
        for i in 0..self.bubbles.len() {
            if !self.bubbles[i].active() {
                continue;
            }
            let c = self.bubbles[i].position;
            let reach = self.coupling_radius(i) + 2.0 * h;
            let (lo, hi) = self.grid.cell_range(c, reach);
            for k in lo[2]..=hi[2] {
                for j in lo[1]..=hi[1] {
                    for ii in lo[0]..=hi[0] {
                        let x = (ii as f64 + 0.5) * h - c[0];
                        let y = (j as f64 + 0.5) * h - c[1];
                        let z = (k as f64 + 0.5) * h - c[2];
                        if x * x + y * y + z * z <= reach * reach {
                            self.scratch[ii + nx * (j + ny * k)] = 0.0;
                            any = true;
                        }
                    }
                }
            }
        }
        any
    }

    /// Phase 6: every active bubble's radius at the new ambient pressure (eq. 2.4).
    fn update_radii(&mut self, p1: f64) -> Result<(), Error> {
        let t1 = self.time;
        for i in 0..self.bubbles.len() {
            if !self.bubbles[i].active() {
                continue;
            }
            let nrt = self.bubbles[i].total_moles() * self.rt;
            let guess = self.bubbles[i].radius;
            let fixed = self.params.bubble_fixed_gases;
            let r = self.balance_for(&self.bubbles[i], p1).radius_for(nrt, guess).ok_or_else(|| {
                Error::Solver(format!(
                    "bubble {i} at t = {t1:.3} s: no radius satisfies the Laplace balance (P_amb = {p1:.0} Pa, fixed partial pressure of other gases {fixed:.0} Pa, n = {:.3e} mol); the elasticity law has no physical root here, or P_B − p_fixed ≤ 0",
                    nrt / self.rt
                ))
            })?;
            self.bubbles[i].radius = r;
        }
        Ok(())
    }

    /// Health: no non-finite concentration (sampled every 97th cell; every 8th step).
    fn check_health(&self) -> Result<(), Error> {
        for f in self.fields.iter() {
            if f.iter().step_by(97).any(|x| !x.is_finite()) {
                return Err(Error::Solver(format!(
                    "non-finite concentration at t = {:.3} s",
                    self.time
                )));
            }
        }
        Ok(())
    }

    /// Bookkeeping after a step (peaks, a bubble reaching a face, the observer's progress and
    /// stop request) and the record when a frame is due (`first`: the initial state).
    fn observe(
        &mut self,
        profile: &PressureHistory,
        p1: f64,
        tensions: &[f64],
        observer: &mut dyn Observer,
        log: &mut RunLog,
        first: bool,
    ) -> Result<(), Error> {
        let t1 = self.time;
        let end = profile.duration_s();
        let num = self.params.numerics;
        let mut vol = 0.0;
        for b in self.bubbles.iter().filter(|b| b.active()) {
            vol += b.volume();
            if b.radius > log.max_radius.0 {
                log.max_radius = (b.radius, t1, b.id);
            }
        }
        if vol > log.peak_volume.0 || first {
            log.peak_volume = (vol, t1);
        }
        if first {
            let min = self.record(profile, tensions, observer, true)?;
            log.min_concentration = log.min_concentration.min(min);
            log.next_record = self.time + num.record_interval;
            return Ok(());
        }
        for b in self.bubbles.iter().filter(|b| b.active()) {
            if let Some((face, _)) = self
                .grid
                .distance_to_faces(b.position)
                .find(|(_, d)| *d <= b.radius)
            {
                log.ending = Ending::BubbleReachedFace {
                    bubble: b.id,
                    face,
                    time: t1,
                };
                break;
            }
        }
        observer.progress(t1, end);
        if log.ending == Ending::Completed && observer.should_stop() {
            log.ending = Ending::Interrupted { time: t1 };
        }
        let done = log.ending != Ending::Completed || self.time >= end - 1e-9;
        if self.time >= log.next_record - 1e-9 || done {
            let mut fresh = tensions.to_vec();
            let round = self.flux_round(p1, profile, |s, i| s.bubbles[i].active());
            for &i in &round.which {
                fresh[i] = round.out[i].0;
            }
            self.round = round;
            self.round_at = Some(self.time);
            let min = self.record(profile, &fresh, observer, num.record_gel || done)?;
            log.min_concentration = log.min_concentration.min(min);
            let behind = (self.time + 1e-9 - log.next_record) / num.record_interval;
            if num.record_interval > 0.0
                && (behind > 1e6 || self.time + num.record_interval == self.time)
            {
                // an interval too small to step through (or to move the clock at all): jump
                log.next_record = self.time + num.record_interval;
            } else if num.record_interval > 0.0 {
                while log.next_record <= self.time + 1e-9 {
                    log.next_record += num.record_interval;
                }
            } else {
                // 0 = every step (stepping `next_record` by a tiny interval up to the
                // current time would take ~time/1e-9 iterations)
                log.next_record = self.time;
            }
        }
        Ok(())
    }

    /// Phase 5: perfusion, operator-split after diffusion: every inside cell relaxes toward the
    /// blood value C_b,g(t) = L_g·p_insp,g(t)/(R_u·T) at rate k (`perfusion_rate`), integrated
    /// exactly over the step with C_b linear in time ([`diffusion::PerfusionWeights`]). The gas
    /// perfusion adds or removes is counted with the open-face inflow in the gas balance.
    fn perfuse(&mut self, profile: &PressureHistory, t: f64, dt: f64) {
        let k = self.params.perfusion_rate;
        if !(k > 0.0) {
            return;
        }
        let w = diffusion::PerfusionWeights::new(k, dt);
        self.gel_fresh = false;
        let h3 = self.grid.cell_volume();
        for g in 0..self.gases.len() {
            let gas = self.gases[g];
            let cb0 = self.ostwald[g] * profile.inspired_partial_pressure(gas, t) / self.rt;
            let cb1 = self.ostwald[g] * profile.inspired_partial_pressure(gas, t + dt) / self.rt;
            let added = diffusion::perfusion_step(&self.grid, &mut self.fields[g], w, cb0, cb1);
            self.inflow += added * h3;
        }
    }

    fn coalesce(&mut self, t: f64, p: f64, events: &mut Vec<Event>) -> Result<(), Error> {
        loop {
            let mut pair = None;
            'outer: for i in 0..self.bubbles.len() {
                if !self.bubbles[i].active() {
                    continue;
                }
                for j in i + 1..self.bubbles.len() {
                    if !self.bubbles[j].active() {
                        continue;
                    }
                    let (a, b) = (&self.bubbles[i], &self.bubbles[j]);
                    let d2: f64 = (0..3)
                        .map(|k| (a.position[k] - b.position[k]).powi(2))
                        .sum();
                    if d2.sqrt() <= a.radius + b.radius {
                        pair = Some((i, j));
                        break 'outer;
                    }
                }
            }
            let Some((i, j)) = pair else { return Ok(()) };
            // the bubble with more gas survives; centre weighted by gas content
            let (keep, gone) = if self.bubbles[i].total_moles() >= self.bubbles[j].total_moles() {
                (i, j)
            } else {
                (j, i)
            };
            let nk = self.bubbles[keep].total_moles();
            let ng = self.bubbles[gone].total_moles();
            let mut pos = [0.0; 3];
            for (k, c) in pos.iter_mut().enumerate() {
                *c = (self.bubbles[keep].position[k] * nk + self.bubbles[gone].position[k] * ng)
                    / (nk + ng);
            }
            let gone_moles = self.bubbles[gone].moles.clone();
            let r0 = (self.bubbles[keep].initial_radius.powi(3)
                + self.bubbles[gone].initial_radius.powi(3))
            .cbrt();
            {
                let b = &mut self.bubbles[keep];
                b.position = pos;
                b.initial_radius = r0;
                for (m, x) in b.moles.iter_mut().zip(&gone_moles) {
                    *m += x;
                }
            }
            self.bubbles[gone].fate = BubbleFate::Merged {
                into: keep,
                time: t,
            };
            self.bubbles[gone].moles.iter_mut().for_each(|m| *m = 0.0);
            self.bubbles[gone].radius = 0.0;
            let nrt = self.bubbles[keep].total_moles() * self.rt;
            let guess = self.bubbles[keep].radius;
            let r = self
                .balance_for(&self.bubbles[keep], p)
                .radius_for(nrt, guess)
                .ok_or_else(|| Error::Solver(format!("merged bubble {keep}: no Laplace radius")))?;
            self.bubbles[keep].radius = r;
            events.push(Event::Coalesced {
                time: t,
                into: keep,
                absorbed: gone,
            });
        }
    }

    /// One parallel pass over the grid: the largest supersaturation Σ_g C_g·R_u·T/L_g + p_fixed − P_amb (Pa),
    /// the gas dissolved in the grid per gas (mol) and the lowest concentration of any gas
    /// (mol/m³). Plane by plane ([`plane_gel`], vectorised), the planes combined in plane
    /// order: the same bits whatever the thread count.
    fn gel_state(&self, ambient: f64) -> (f64, Vec<f64>, f64) {
        use rayon::prelude::*;
        let ng = self.fields.len();
        let k = self.gel_factors();
        let nz = self.grid.n[2];
        let views = self.field_views();
        let fields = &views[..ng];
        let pass = |kz: usize| plane_gel(&self.grid, fields, &k, kz);
        let planes: Vec<PlaneGel> = if self.gel_fresh && self.gel_planes.len() == nz {
            // the last step's pass, with the planes written since passed again
            let (lo, hi) = self.gel_dirty;
            let mut planes = self.gel_planes.clone();
            if lo <= hi {
                planes[lo..=hi]
                    .par_iter_mut()
                    .enumerate()
                    .for_each(|(m, p)| *p = pass(lo + m));
            }
            #[cfg(test)]
            self.fused_frames
                .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            if self.check_fused_gel {
                for (kz, p) in planes.iter().enumerate() {
                    assert!(
                        same_plane_gel(p, &pass(kz), ng),
                        "plane {kz} at t = {}",
                        self.time
                    );
                }
            }
            planes
        } else {
            (0..nz).into_par_iter().map(pass).collect()
        };
        let mut max_t = f64::NEG_INFINITY;
        let mut min_c = f64::INFINITY;
        let mut sums = vec![0.0; ng];
        for p in &planes {
            max_t = max_t.max(p.max_tension);
            min_c = min_c.min(p.min_c);
            for (a, b) in sums.iter_mut().zip(&p.sums) {
                *a += b;
            }
        }
        let v = self.grid.cell_volume();
        (
            max_t + self.params.bubble_fixed_gases - ambient,
            sums.into_iter().map(|x| x * v).collect(),
            min_c,
        )
    }

    /// R_u·T/L_g per gas: the factor of a concentration's gas tension ([`plane_gel`]).
    fn gel_factors(&self) -> [f64; Gas::ALL.len()] {
        let mut k = [0.0; Gas::ALL.len()];
        for (kg, l) in k.iter_mut().zip(&self.ostwald) {
            *kg = self.rt / l;
        }
        k
    }

    /// The cells `idx` are written outside the diffusion step: the z-planes they lie in are
    /// passed again at the next frame ([`Self::gel_state`]).
    fn mark_gel(&mut self, idx: impl Iterator<Item = usize>) {
        if !self.gel_fresh {
            return;
        }
        let plane = self.grid.n[0] * self.grid.n[1];
        for i in idx {
            let kz = i / plane;
            self.gel_dirty = (self.gel_dirty.0.min(kz), self.gel_dirty.1.max(kz));
        }
    }

    /// Send a frame to the observer; with the gel's state (`gel`, [`Numerics::record_gel`])
    /// it checks the gas balance on the way (the frame's grid totals come from the same pass),
    /// so a broken run stops at the first frame that shows it. Returns the lowest
    /// concentration in the gel (mol/m³; +∞ without the gel's state).
    ///
    /// [`Numerics::record_gel`]: super::params::Numerics::record_gel
    fn record(
        &self,
        profile: &PressureHistory,
        tensions: &[f64],
        observer: &mut dyn Observer,
        gel: bool,
    ) -> Result<f64, Error> {
        let p = profile.ambient(self.time);
        let (max_ss, grid_moles, min_c) = if gel {
            self.gel_state(p)
        } else {
            (f64::NAN, Vec::new(), f64::INFINITY)
        };
        if gel {
            let total = grid_moles.iter().sum::<f64>()
                + self
                    .bubbles
                    .iter()
                    .filter(|b| b.active())
                    .map(|b| b.total_moles())
                    .sum::<f64>();
            let balance = ((total - self.initial_total - self.inflow - self.displaced_gas)
                / self.initial_total)
                .abs();
            if !(balance < BALANCE_LIMIT) {
                return Err(Error::Solver(format!(
                    "gas balance lost at t = {:.3} s: |gas now − gas at start − gas in through open faces and perfusion| is {balance:.3e} of the start; the run is not trustworthy",
                    self.time
                )));
            }
        }
        let frame = Frame {
            time: self.time,
            ambient: p,
            bubbles: self
                .bubbles
                .iter()
                .filter(|b| b.active())
                .map(|b| BubbleFrame {
                    id: b.id,
                    radius: b.radius,
                    initial_radius: b.initial_radius,
                    volume: b.volume(),
                    area: b.area(),
                    moles: b.moles.clone(),
                    gel_tension: tensions[b.id],
                    position: b.position,
                })
                .collect(),
            max_supersaturation: max_ss,
            grid_moles,
        };
        observer.frame(&frame);
        Ok(min_c)
    }
}

impl Simulation<'_> {
    /// The nucleation model's nuclei in this grid, as a pool ([`Self::new`]).
    fn nucleus_pool(&self) -> Result<NucleusPool, Error> {
        let input =
            |field: &str, m: String| Error::Input(crate::error::InputError::new(m).field(field));
        let nuclei = self
            .params
            .nucleation
            .nuclei(&self.grid)
            .map_err(|e| input(&e.field, e.message))?;
        NucleusPool::new(
            &nuclei,
            &self.grid,
            self.params.surface_tension,
            self.params.nucleation.skin_compression(),
        )
        .map_err(|e| input(&e.field, e.message))
    }

    /// An upper bound of the gel tension (Σ_g C_g·R_u·T/L_g + p_fixed) anywhere in the gel up to
    /// `t1`, Pa, kept up to date over the step from `t0`: by the discrete maximum principle of
    /// both diffusion schemes (tested in `diffusion`) the gel's tension never exceeds the
    /// largest of its initial value, the open faces' and the perfusion's value (the inspired
    /// inert gas plus p_fixed, at the step's ends and the profile's breakpoints in it) and the
    /// bubbles' gas pressure (Σ n·R_u·T/V + p_fixed), the sources the exchange draws from.
    /// [`Self::nucleate`] skips the nuclei while it stays 10 % below their lowest threshold
    /// (the margin covers a bubble's pressure changing within a step).
    fn tension_bound(&mut self, profile: &PressureHistory, t0: f64, t1: f64) -> f64 {
        let fixed = self.params.bubble_fixed_gases;
        let mut b = match self.tension_bound {
            Some(b) => b,
            None => {
                let k: Vec<f64> = self.ostwald.iter().map(|l| self.rt / l).collect();
                let fields = self.field_views();
                (0..self.grid.len())
                    .filter(|&c| self.grid.inside(c))
                    .map(|c| fields.iter().zip(&k).map(|(f, kg)| f[c] * kg).sum::<f64>())
                    .fold(0.0, f64::max)
                    + fixed
            }
        };
        let inspired = |t: f64| -> f64 {
            self.gases
                .iter()
                .map(|g| profile.inspired_partial_pressure(*g, t))
                .sum::<f64>()
                + fixed
        };
        b = b.max(inspired(t0)).max(inspired(t1));
        let first = profile.times_s.partition_point(|&x| x <= t0);
        for &tb in profile.times_s[first..].iter().take_while(|&&x| x < t1) {
            b = b.max(inspired(tb));
        }
        let ng = self.gases.len();
        for bubble in self.bubbles.iter().filter(|x| x.active()) {
            let n: f64 = bubble.moles[..ng].iter().sum();
            b = b.max(n * self.rt / bubble.volume() + fixed);
        }
        self.tension_bound = Some(b);
        b
    }

    /// The nuclei of the run and their state (empty under the `fixed` model).
    pub fn nuclei(&self) -> &NucleusPool {
        &self.nuclei
    }

    /// Phase 8: nucleation ([`super::nucleation`]).
    /// 1. A nucleated bubble that has shrunk below a tenth of its nucleus radius has dissolved:
    ///    its gas returns to the gel (the step limits of [`Self::choose_step`] are sized for
    ///    bubbles of many µm; a sub-µm bubble left to shrink further would leave the range of the
    ///    radius solve).
    /// 2. Nuclei whose bubble has dissolved return to the pool (one whose bubble merged into
    ///    another is consumed: its gas is in the survivor).
    /// 3. Every nucleus in the pool whose cell's supersaturation
    ///    Σ_g C_g·R_u·T/L_g + p_fixed − P_amb exceeds its 2γ/r (eq. 2.11), and for which the
    ///    gel tension that its bubble would see (the coupling sphere of a bubble of radius r,
    ///    as in [`Self::fluxes`]) exceeds P_amb + 2γ/r too, becomes a bubble of its radius
    ///    ([`Self::add_bubble`]), unless it touches an active bubble (it would merge into it at
    ///    the next step, and its nucleus return to the pool, for ever). The cell value is the
    ///    cheap test of every nucleus; the coupling sphere is read only for those that pass it,
    ///    so that a new bubble starts growing (without it, a nucleus at a peak of the field
    ///    activates, sees a lower mean tension at its coupling sphere, dissolves, and activates
    ///    again at the next step). In a uniform gel both are the same number.
    ///
    /// `tensions` and `fluxes` (the time loop's per-bubble buffers) grow with the bubbles.
    fn nucleate(
        &mut self,
        profile: &PressureHistory,
        t0: f64,
        p1: f64,
        tensions: &mut Vec<f64>,
        fluxes: &mut Vec<Vec<f64>>,
        events: &mut Vec<Event>,
    ) -> Result<(), Error> {
        if self.nuclei.is_empty() {
            return Ok(());
        }
        let mut pool = std::mem::take(&mut self.nuclei);
        let ng = self.gases.len();
        for e in pool.entries() {
            let Some(id) = e.bubble else { continue };
            let b = &self.bubbles[id];
            if b.active() && b.radius < 0.1 * e.nucleus.radius {
                let back: Vec<f64> = b.moles[..ng].iter().map(|m| -m).collect();
                self.take_from_grid(id, &back);
                self.dissolve(id, self.time, events);
            }
        }
        pool.release(|b| matches!(self.bubbles[b].fate, BubbleFate::Dissolved(_)));
        // no nucleus can activate while even the bound of the gel tension stays below the
        // lowest threshold (bare nuclei only: with skins every step records the crushing)
        if !pool.has_skins() {
            let bound = self.tension_bound(profile, t0, p1);
            if bound - p1 < 0.9 * pool.lowest_threshold() {
                self.nuclei = pool;
                return Ok(());
            }
        }
        let k: Vec<f64> = self.ostwald.iter().map(|l| self.rt / l).collect();
        let fixed = self.params.bubble_fixed_gases;
        let ready = pool.ready(|cell| {
            let mut tension = fixed;
            for (f, kg) in self.fields.iter().zip(&k) {
                tension += f[cell] * kg;
            }
            tension - p1
        });
        // the coupling-sphere test of every candidate first, on the gel of the end of the
        // step (the gas each new bubble takes must not decide for its neighbours)
        let mut confirmed = Vec::with_capacity(ready.len());
        for index in ready {
            let e = pool.entries()[index];
            let threshold = pool.threshold(index);
            let rho = self.coupling_radius_at(pool.activation_radius(index), false);
            let ng = k.len();
            let (mut here, mut mean) = ([0.0; Gas::ALL.len()], [0.0; Gas::ALL.len()]);
            for (h, f) in here.iter_mut().zip(self.fields.iter()) {
                *h = f[e.cell];
            }
            self.prepare_sphere_at(rho);
            self.sphere_means(e.nucleus.position, rho, &here[..ng], &mut mean[..ng]);
            let mut tension = fixed;
            for (m, kg) in mean.iter().zip(&k) {
                tension += m * kg;
            }
            if tension - p1 > threshold {
                confirmed.push(index);
            }
        }
        let mut result = Ok(());
        for index in confirmed {
            let n = Nucleus {
                radius: pool.activation_radius(index),
                ..pool.entries()[index].nucleus
            };
            let engulfed = self.bubbles.iter().any(|b| {
                b.active()
                    && (0..3)
                        .map(|a| (b.position[a] - n.position[a]).powi(2))
                        .sum::<f64>()
                        < (b.radius + n.radius).powi(2)
            });
            if engulfed {
                continue;
            }
            match self.add_bubble(n.position, n.radius, p1) {
                Ok(Some(id)) => pool.activate(index, id),
                Ok(None) => {}
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        self.nuclei = pool;
        tensions.resize(self.bubbles.len(), 0.0);
        fluxes.resize(self.bubbles.len(), vec![0.0; self.gases.len()]);
        result
    }

    /// Add a bubble of radius `r` (m) centred at `position` (m) at the current time: at Laplace
    /// equilibrium (eq. 2.4) at ambient `ambient` (Pa), R0 = r and P0 = `ambient` for the
    /// elasticity and surface laws, with the composition of the gel's gas tension in its cell.
    /// Its gas is taken from the gel through its sink kernel, so the total is conserved.
    /// Returns its id, or `None` when the gel there holds no gas to give (nothing is added).
    pub fn add_bubble(
        &mut self,
        position: [f64; 3],
        r: f64,
        ambient: f64,
    ) -> Result<Option<usize>, Error> {
        let cell = super::nucleation::cell_of(&self.grid, position)
            .filter(|c| self.grid.inside(*c))
            .ok_or_else(|| {
                Error::Solver(format!(
                    "a bubble added at ({:.3e}, {:.3e}, {:.3e}) m is outside the phantom",
                    position[0], position[1], position[2]
                ))
            })?;
        let ng = self.gases.len();
        let partial: Vec<f64> = (0..ng)
            .map(|g| self.fields[g][cell].max(0.0) * self.rt / self.ostwald[g])
            .collect();
        let psum: f64 = partial.iter().sum();
        if !(psum > 0.0) {
            return Ok(None);
        }
        let id = self.bubbles.len();
        let mut bubble = Bubble {
            id,
            position,
            initial_radius: r,
            initial_ambient: ambient,
            moles: vec![0.0; ng],
            radius: r,
            fate: BubbleFate::Active,
        };
        let n_total = self.balance_for(&bubble, ambient).pv(r) / self.rt;
        if !(n_total > 0.0 && n_total.is_finite()) {
            return Err(Error::Input(
                crate::error::InputError::new(format!(
                    "a bubble of radius {r:.3e} m at P_amb = {ambient:.0} Pa holds no simulated gas at Laplace equilibrium (P_B ≤ material.bubble_fixed_gases_pa = {:.0} Pa)",
                    self.params.bubble_fixed_gases
                ))
                .field("material.bubble_fixed_gases_pa"),
            ));
        }
        self.bubbles.push(bubble.clone());
        let want: Vec<f64> = partial.iter().map(|p| n_total * p / psum).collect();
        let taken = self.take_from_grid(id, &want);
        bubble.moles.copy_from_slice(&taken[..ng]);
        let nrt = bubble.total_moles() * self.rt;
        let radius = if nrt > 0.0 {
            self.balance_for(&bubble, ambient).radius_for(nrt, r)
        } else {
            None
        };
        match radius {
            Some(radius) => {
                bubble.radius = radius;
                self.bubbles[id] = bubble;
                Ok(Some(id))
            }
            None => {
                // nothing the Laplace balance can hold: give the gas back, add nothing
                let back: Vec<f64> = taken[..ng].iter().map(|m| -m).collect();
                self.take_from_grid(id, &back);
                self.bubbles.pop();
                Ok(None)
            }
        }
    }
}

/// Place the bubbles of `params` in `grid`: explicit positions are checked; a random
/// population is drawn with ChaCha8 from the seed, rejecting centres closer than the spacing.
pub fn place_bubbles(params: &PhantomParams, grid: &Grid) -> Result<Vec<([f64; 3], f64)>, Error> {
    let input = |m: String| Error::Input(crate::error::InputError::new(m).field("bubbles"));
    match &params.bubbles {
        BubblePlacement::Explicit(list) => {
            for (i, (p, r0)) in list.iter().enumerate() {
                if !(*r0 > 0.0) {
                    return Err(input(format!(
                        "bubble {i}: initial radius must be positive (got {r0} m)"
                    )));
                }
                if let Some((face, d)) = grid.distance_to_faces(*p).find(|(_, d)| !(*d > *r0))
                // NaN positions are outside too
                {
                    let e = grid.extent();
                    return Err(input(format!(
                        "bubble {i} at ({:.3e}, {:.3e}, {:.3e}) m with R0 = {r0:.3e} m is outside the phantom or touches its {} face (distance {d:.3e} m); the modelled phantom spans {:.3e} × {:.3e} × {:.3e} m",
                        p[0], p[1], p[2], face.name(), e[0], e[1], e[2]
                    )));
                }
            }
            Ok(list.clone())
        }
        BubblePlacement::Random {
            count,
            initial_radius,
            min_spacing,
            margin,
            seed,
        } => {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(*seed);
            let e = grid.extent();
            let mut out: Vec<([f64; 3], f64)> = Vec::new();
            let mut tries = 0;
            while out.len() < *count {
                tries += 1;
                if tries > 100_000 {
                    return Err(input(format!(
                        "cannot place {count} bubbles {min_spacing} m apart and {margin} m from the faces; lower the count or the spacing"
                    )));
                }
                let p = [
                    rng.gen::<f64>() * e[0],
                    rng.gen::<f64>() * e[1],
                    rng.gen::<f64>() * e[2],
                ];
                if grid
                    .distance_to_faces(p)
                    .any(|(_, d)| d < margin.max(*initial_radius * 1.01))
                {
                    continue;
                }
                if out.iter().any(|(q, _)| {
                    (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt() < *min_spacing
                }) {
                    continue;
                }
                out.push((p, *initial_radius));
            }
            Ok(out)
        }
    }
}

#[cfg(test)]
mod field_error_tests {
    use super::*;
    use crate::gas::GasMix;
    use crate::phantom::grid::Face;
    use crate::phantom::params::{GasProperties, PhantomParams};

    /// The field's error estimate against the true local error of a backward-Euler step on the
    /// open cube with a uniform start (the Fourier-series case of
    /// `tests/integration/verification.rs`): from the same state, the step's result minus a
    /// reference (the same state advanced by 400 backward-Euler substeps, whose own error is
    /// 400× smaller), RMS over the cells, in Pa. Checked at several steps and stages of the
    /// decay, with the filtered estimate the step control uses above the tolerance: it is
    /// conservative (1.8–3.1× the true error when written) and ranks the cases as the true
    /// error does.
    #[test]
    fn field_error_estimate_tracks_the_true_local_error_on_the_open_cube() {
        let (n, h, d, l_n2) = (15usize, 1e-4, 1e-9, 0.014);
        let size = n as f64 * h;
        let mut params = PhantomParams::box_phantom([size; 3], h);
        params.gases = vec![GasProperties {
            gas: Gas::N2,
            diffusivity: d,
            ostwald: l_n2,
        }];
        params.open_faces = params.shape.faces().to_vec();
        assert!(params.open_faces.contains(&Face::Bottom));
        let pure_n2 = GasMix { o2: 0.0, he: 0.0 };
        let (p_start, p_chamber) = (2e5, 1e5);
        let t_end = 1e4;
        let profile =
            PressureHistory::with_gas("hold", vec![0.0, t_end], vec![p_chamber; 2], pure_n2, 0.0)
                .unwrap();
        let l2d = size * size / d; // diffusion time L²/D, 2250 s
        let mut pairs = Vec::new();
        // (time of the first step, its length, the length of the measured step)
        for (t0, dt1, dt2) in [
            (0.02 * l2d, 2.0, 4.0),
            (0.02 * l2d, 5.0, 5.0),
            (0.05 * l2d, 10.0, 15.0),
            (0.1 * l2d, 20.0, 20.0),
            (0.1 * l2d, 30.0, 60.0),
        ] {
            let mut sim = Simulation::new(&params, &profile).unwrap();
            let rt = sim.rt;
            let c0 = l_n2 * p_start / rt;
            sim.fields[0].iter_mut().for_each(|x| *x = c0);
            // bring the field to t0 with small steps (no estimate), then the history step
            let mut solver = diffusion::ImplicitSolver::new();
            let cb = l_n2 * p_chamber / rt;
            let sub = 200;
            for _ in 0..sub {
                solver.step(&sim.grid, &mut sim.fields[0], d, t0 / sub as f64, cb);
            }
            sim.time = t0;
            let tol = 0.0; // always filtered
            let (imp1, _) = sim.diffuse(&profile, t0, dt1, tol, false);
            assert!(imp1);
            let start = sim.fields[0].to_vec();
            let (imp2, est) = sim.diffuse(&profile, t0 + dt1, dt2, tol, false);
            assert!(imp2);
            // reference from the same start
            let mut reference = start.clone();
            let k = 400;
            for _ in 0..k {
                solver.step(&sim.grid, &mut reference, d, dt2 / k as f64, cb);
            }
            let diff: Vec<f64> = sim.fields[0]
                .iter()
                .zip(&reference)
                .map(|(a, b)| a - b)
                .collect();
            let truth = diffusion::rms_inside(&sim.grid, &diff) * rt / l_n2;
            let ratio = est / truth;
            eprintln!(
                "t0 = {t0:.0} s, steps {dt1} then {dt2} s: estimate {est:.4e} Pa, true {truth:.4e} Pa, ratio {ratio:.3}"
            );
            assert!(truth > 0.0 && (1.0..4.0).contains(&ratio), "ratio {ratio}");
            pairs.push((truth, est));
        }
        assert_eq!(pairs.len(), 5);
        // the same order by estimate as by true error
        let mut by_truth = pairs.clone();
        by_truth.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert!(by_truth.windows(2).all(|w| w[0].1 < w[1].1), "{by_truth:?}");
    }
}

/// Three bubbles in a 3 × 2 × 2 mm box open on every face, grid step `h`, a frame at every
/// step: two of them so close that their coupling spheres overlap once they grow, one far from
/// both (the bit-for-bit tests of the parallel fluxes and the out-of-place steps).
#[cfg(test)]
fn three_bubbles_in_an_open_box(h: f64) -> PhantomParams {
    let mut params = PhantomParams::box_phantom([3.0e-3, 2.0e-3, 2.0e-3], h);
    params.open_faces = params.shape.faces().to_vec();
    params.bubbles = BubblePlacement::Explicit(vec![
        ([0.9e-3, 1.0e-3, 1.0e-3], 3.0e-4),
        ([1.5e-3, 1.0e-3, 1.0e-3], 2.5e-4),
        ([2.4e-3, 0.9e-3, 1.1e-3], 3.5e-4),
    ]);
    params.numerics.record_interval = 0.0;
    params
}

/// Air at 2 bar, to 1 bar in 10 s (the bubbles of [`three_bubbles_in_an_open_box`] grow), held
/// to 40 s, to 3 bar in 5 s (they shrink and give cells back), held to `end` s.
#[cfg(test)]
fn grow_then_recompress(end: f64) -> PressureHistory {
    let air = crate::gas::GasMix { o2: 0.21, he: 0.0 };
    PressureHistory::with_gas(
        "surface",
        vec![0.0, 10.0, 40.0, 45.0, end],
        vec![2e5, 1e5, 1e5, 3e5, 3e5],
        air,
        0.0,
    )
    .unwrap()
}

/// Every frame of `a` and `b` the same bits: time, and each bubble's radius, gel tension and
/// content.
#[cfg(test)]
fn assert_same_frame_bits(a: &[Frame], b: &[Frame]) {
    assert_eq!(a.len(), b.len());
    for (a, b) in a.iter().zip(b) {
        assert_eq!(a.time.to_bits(), b.time.to_bits());
        assert_eq!(
            a.max_supersaturation.to_bits(),
            b.max_supersaturation.to_bits(),
            "t = {}",
            a.time
        );
        let bits = |m: &[f64]| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&a.grid_moles), bits(&b.grid_moles), "t = {}", a.time);
        assert_eq!(a.bubbles.len(), b.bubbles.len());
        for (x, y) in a.bubbles.iter().zip(&b.bubbles) {
            assert_eq!(x.radius.to_bits(), y.radius.to_bits(), "t = {}", a.time);
            assert_eq!(
                x.gel_tension.to_bits(),
                y.gel_tension.to_bits(),
                "t = {}",
                a.time
            );
            for (m, n) in x.moles.iter().zip(&y.moles) {
                assert_eq!(m.to_bits(), n.to_bits(), "t = {}", a.time);
            }
        }
    }
}

#[cfg(test)]
mod parallel_fluxes_tests {
    use super::*;
    use crate::gas::GasMix;

    /// The bubbles' fluxes evaluated in parallel (at the start of a step, in the corrector and
    /// at each frame) give the bits of the serial evaluation, in which each bubble's corrector
    /// reads the grid after the earlier bubbles' corrections: three growing bubbles in an open
    /// box, two of them so close that their coupling spheres overlap (the corrector evaluates
    /// the later one again) and one far from both; every frame of 60 s compared bit by bit.
    #[test]
    fn parallel_fluxes_are_the_serial_fluxes_bits() {
        let h = 1e-4;
        let params = three_bubbles_in_an_open_box(h);
        // supersaturated gel: a 2 bar air dive's gas at the surface
        let air = GasMix { o2: 0.21, he: 0.0 };
        let profile = PressureHistory::with_gas(
            "surface",
            vec![0.0, 10.0, 70.0],
            vec![2e5, 1e5, 1e5],
            air,
            0.0,
        )
        .unwrap();
        let run = |serial: bool| {
            SERIAL_FLUXES.with(|s| s.set(serial));
            let mut sim = Simulation::new(&params, &profile).unwrap();
            let mut rec = Recorder::default();
            let summary = sim.run(&profile, &mut rec).unwrap();
            SERIAL_FLUXES.with(|s| s.set(false));
            (summary, rec.frames)
        };
        let (ss, serial) = run(true);
        let (ps, parallel) = run(false);
        assert!(ss.steps.0 + ss.steps.1 > 20, "{:?}", ss.steps);
        assert_eq!(ss.steps, ps.steps);
        // the bubbles grew, and the close pair's spheres overlap (ρ ≥ R + 2h each)
        let last = serial.last().unwrap();
        assert!(last.bubbles.iter().all(|b| b.radius > b.initial_radius));
        let (r0, r1) = (last.bubbles[0].radius, last.bubbles[1].radius);
        assert!(r0 + r1 + 4.0 * h > 0.6e-3, "{r0} {r1}");
        assert_eq!(serial.len(), parallel.len());
        assert_same_frame_bits(&serial, &parallel);
    }

    /// The spheres' means sampled in one parallel pass over all bubbles' points (balanced in
    /// chunks that straddle bubbles) are each bubble's own `sphere_means`, bit for bit: three
    /// bubbles of different sizes (spheres of 64 to a few thousand points, more than
    /// `PARALLEL_SPHERE_POINTS` in all) in a gel whose two fields vary from cell to cell.
    #[test]
    fn the_spheres_sampled_together_are_each_spheres_mean() {
        let h = 1e-4;
        let params = three_bubbles_in_an_open_box(h);
        let profile = PressureHistory::with_gas(
            "flat",
            vec![0.0, 10.0],
            vec![1e5, 1e5],
            GasMix { o2: 0.21, he: 0.0 },
            0.0,
        )
        .unwrap();
        let mut sim = Simulation::new(&params, &profile).unwrap();
        for g in 0..sim.gases.len() {
            for (idx, c) in sim.field_mut(g).iter_mut().enumerate() {
                *c = 1.0 + ((idx * 7919 + 31 * g) % 997) as f64 / 997.0;
            }
        }
        for (b, r) in sim.bubbles.iter_mut().zip([3e-5, 4e-4, 9e-4]) {
            b.radius = r;
        }
        let which: Vec<usize> = (0..sim.bubbles.len()).collect();
        let points: usize = which.iter().map(|&i| sim.prepare_sphere(i)).sum();
        assert!(points > PARALLEL_SPHERE_POINTS, "{points}");
        let cb = sim.inspired_concentrations(&profile);
        let ng = sim.gases.len();
        let (mut vals, mut together) = (Vec::new(), Vec::new());
        sim.sphere_means_of(&which, &cb, &mut vals, &mut together);
        for &i in &which {
            let mut alone = [0.0; Gas::ALL.len()];
            let (c, rho) = (sim.bubbles[i].position, sim.coupling_radius(i));
            sim.sphere_means(c, rho, &cb[..ng], &mut alone[..ng]);
            for g in 0..ng {
                assert_eq!(
                    alone[g].to_bits(),
                    together[i][g].to_bits(),
                    "bubble {i} gas {g}"
                );
            }
        }
    }
}

#[cfg(test)]
mod extrapolated_step_tests {
    use super::*;
    use crate::gas::GasMix;
    use crate::phantom::params::GasProperties;

    /// An open 9³ cube of pure N2 on a rising pressure, its field set by `init`, stepped once by
    /// [`Simulation::diffuse`] with the extrapolation, and the same start stepped here with the
    /// solver directly: (the simulation's field, inflow; two half steps; one whole step).
    fn step(init: impl Fn(usize) -> f64, dt: f64) -> (Vec<f64>, f64, Vec<f64>, Vec<f64>, f64) {
        let h = 1e-4;
        let mut params = PhantomParams::box_phantom([9.0 * h; 3], h);
        params.gases = vec![GasProperties {
            gas: Gas::N2,
            diffusivity: 1e-9,
            ostwald: 0.014,
        }];
        params.open_faces = params.shape.faces().to_vec();
        let pure_n2 = GasMix { o2: 0.0, he: 0.0 };
        let profile =
            PressureHistory::with_gas("ramp", vec![0.0, 100.0], vec![1e5, 3e5], pure_n2, 0.0)
                .unwrap();
        let mut sim = Simulation::new(&params, &profile).unwrap();
        for (i, c) in sim.fields[0].iter_mut().enumerate() {
            *c = init(i);
        }
        let start = sim.fields[0].to_vec();
        let cb = |s: f64| 0.014 * profile.inspired_partial_pressure(Gas::N2, s) / sim.rt;
        let (cb_half, cb_end) = (cb(0.5 * dt), cb(dt));
        let before = sim.inflow;
        let (implicit, _) = sim.diffuse(&profile, 0.0, dt, f64::INFINITY, true);
        assert!(implicit);
        let flow = sim.inflow - before;
        let mut solver = diffusion::ImplicitSolver::new();
        let mut half = start.clone();
        solver.step(&sim.grid, &mut half, 1e-9, 0.5 * dt, cb_half);
        solver.step(&sim.grid, &mut half, 1e-9, 0.5 * dt, cb_end);
        let mut whole = start.clone();
        solver.step(&sim.grid, &mut whole, 1e-9, dt, cb_end);
        let total0: f64 = start.iter().sum::<f64>() * sim.grid.cell_volume();
        let total1: f64 = sim.fields[0].iter().sum::<f64>() * sim.grid.cell_volume();
        // conservative: what the grid gained is what came in through the faces
        assert!(
            (total1 - total0 - flow).abs() <= 1e-12 * total1.abs(),
            "{total1} {total0} {flow}"
        );
        (sim.fields[0].to_vec(), flow, half, whole, total0)
    }

    /// A smooth start: the step is 2·(two half steps) − (one whole step), cell by cell.
    #[test]
    fn the_extrapolated_step_is_two_halves_against_one_whole() {
        let (got, _, half, whole, _) = step(|i| 0.5 + 0.01 * (i % 9) as f64, 20.0);
        for ((g, h), w) in got.iter().zip(&half).zip(&whole) {
            assert!((g - (2.0 * h - w)).abs() <= 1e-12 * g.abs(), "{g} {h} {w}");
        }
    }

    /// A spike (5e4 mol/m³ in one cell of an empty gel, 50 s): near it the whole step's
    /// spread is above twice the half steps', so the extrapolation would go negative (to about
    /// −75 mol/m³); the step keeps the half steps instead,
    /// with every cell ≥ 0 and the gas conserved.
    #[test]
    fn an_extrapolation_that_would_go_negative_keeps_the_half_steps() {
        let centre = 4 + 9 * (4 + 9 * 4);
        let (got, _, half, whole, _) = step(|i| if i == centre { 5e4 } else { 0.0 }, 50.0);
        assert!(half.iter().zip(&whole).any(|(h, w)| 2.0 * h - w < 0.0));
        assert!(got.iter().all(|c| *c >= 0.0));
        for (g, h) in got.iter().zip(&half) {
            assert!((g - h).abs() <= 1e-12 * h.abs().max(1e-30), "{g} {h}");
        }
    }
}

#[cfg(test)]
mod out_of_place_tests {
    use super::*;

    /// The explicit steps out of place (into a second set of fields, swapped) and with a thread
    /// per field give the in-place steps' bits through a run in which bubbles grow over cells
    /// of the gel and give them back (the gel's displacement takes cells out, which changes the
    /// codes and zeroes those cells in one set only, then a recompression shrinks the bubbles):
    /// three bubbles in an open box, two gases on two threads; every frame's radii, contents
    /// and gel tensions, the step counts, the gas balance and the final fields compared bit by
    /// bit. With frames at every step, every step out of place passes the gel, so a thread per
    /// field is taken only in place; with frames every 0.7 s, also between those steps.
    #[test]
    fn out_of_place_and_per_field_explicit_steps_are_the_in_place_bits() {
        let profile = grow_then_recompress(90.0);
        for interval in [0.0, 0.7] {
            let mut params = three_bubbles_in_an_open_box(1e-4);
            params.numerics.record_interval = interval;
            let run = |out_of_place: bool, per_field: bool| {
                let mut sim = Simulation::new(&params, &profile).unwrap();
                assert_eq!(sim.gases.len(), 2);
                if !out_of_place {
                    sim.out_of_place_bytes = 0;
                }
                sim.per_field = per_field;
                let start_codes = sim.grid.codes_id();
                let mut rec = Recorder::default();
                // out of place and a thread per field only with more than one thread in the
                // grid loops
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(2)
                    .build()
                    .unwrap();
                let summary = pool.install(|| sim.run(&profile, &mut rec)).unwrap();
                assert_ne!(
                    sim.grid.codes_id(),
                    start_codes,
                    "no cell was taken out of the gel"
                );
                let taken = sim.per_field_steps;
                if per_field && (!out_of_place || interval > 0.0) {
                    assert!(taken > 20, "{taken} steps a thread per field");
                } else if !per_field {
                    assert_eq!(taken, 0);
                }
                assert_eq!(
                    sim.back.is_empty(),
                    !out_of_place,
                    "{out_of_place} {per_field}"
                );
                (summary, rec.frames, sim.fields.to_vecs(), sim.grid.clone())
            };
            let (ps, inplace, pf, grid) = run(false, false);
            assert!(ps.steps.0 > 20, "{:?}", ps.steps);
            for (out_of_place, per_field) in [(true, false), (false, true), (true, true)] {
                let (os, other, of, _) = run(out_of_place, per_field);
                assert_eq!(ps.steps, os.steps);
                assert_eq!(
                    ps.gas_balance_error.to_bits(),
                    os.gas_balance_error.to_bits()
                );
                assert_eq!(inplace.len(), other.len());
                assert_same_frame_bits(&inplace, &other);
                for (f, g) in pf.iter().zip(&of) {
                    for idx in 0..grid.len() {
                        if grid.inside(idx) {
                            assert_eq!(f[idx].to_bits(), g[idx].to_bits(), "cell {idx}");
                        }
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod fused_gel_tests {
    use super::*;

    /// What a run gives these tests: the summary, the frames, the frames that took the step's
    /// gel pass, the bubbles at the end and whether any cell changed hands.
    type Outcome = (RunSummary, Vec<Frame>, usize, usize, bool);

    /// `params` through `profile` on two threads (so the explicit step runs out of place), with
    /// the step's gel pass on (each such frame also checked against a pass of its own inside
    /// the run) or off.
    fn run(params: &PhantomParams, profile: &PressureHistory, fuse: bool) -> Outcome {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let mut sim = Simulation::new(params, profile).unwrap();
        sim.fuse_gel_pass = fuse;
        sim.check_fused_gel = fuse;
        let start_codes = sim.grid.codes_id();
        let mut rec = Recorder::default();
        let summary = pool.install(|| sim.run(profile, &mut rec)).unwrap();
        let fused = sim.fused_frames.load(std::sync::atomic::Ordering::Relaxed);
        let moved = sim.grid.codes_id() != start_codes;
        (summary, rec.frames, fused, sim.bubbles.len(), moved)
    }

    /// The runs with and without the step's gel pass give the same bits; with it, most frames
    /// took the step's pass (`taken`) or none did.
    fn assert_same_runs(plain: &Outcome, fused: &Outcome, taken: bool) {
        assert_eq!(plain.2, 0);
        if taken {
            assert!(
                fused.2 > fused.1.len() / 2,
                "{} of {} frames",
                fused.2,
                fused.1.len()
            );
        } else {
            assert_eq!(fused.2, 0);
        }
        assert_eq!(plain.0.steps, fused.0.steps);
        assert_eq!(
            plain.0.gas_balance_error.to_bits(),
            fused.0.gas_balance_error.to_bits()
        );
        assert_eq!(
            plain.0.min_concentration.to_bits(),
            fused.0.min_concentration.to_bits()
        );
        assert_same_frame_bits(&plain.1, &fused.1);
    }

    /// The gel's pass of a frame taken from the explicit step that wrote the planes (with the
    /// planes the corrector and the displacement wrote since passed again) gives the bits of a
    /// pass of its own: three bubbles that grow over cells and give them back, frames at every
    /// step and every 0.7 s.
    #[test]
    fn passing_the_gel_in_the_step_keeps_the_frames_bits() {
        let profile = grow_then_recompress(90.0);
        for interval in [0.0, 0.7] {
            let mut params = three_bubbles_in_an_open_box(1e-4);
            params.numerics.record_interval = interval;
            let (plain, fused) = (run(&params, &profile, false), run(&params, &profile, true));
            assert!(fused.4, "no cell changed hands");
            assert_same_runs(&plain, &fused, true);
        }
    }

    /// The same with nuclei that activate after a dive (new bubbles take their gas from the
    /// gel between the step and the frame) and with perfusion (which drops the step's pass).
    #[test]
    fn passing_the_gel_keeps_the_bits_with_nuclei_and_perfusion() {
        use crate::phantom::nucleation::critical_radius::{CriticalRadius, SizeDistribution};
        use crate::units::{ATM_PA, PSI_PA};
        let top = ATM_PA + 130.0 * PSI_PA;
        let (down, up) = ((top - ATM_PA) / 6.9e4, (top - ATM_PA) / 8.9e4);
        let profile = PressureHistory::with_gas(
            "dive",
            vec![
                0.0,
                down,
                down + 120.0,
                down + 120.0 + up,
                down + 150.0 + up,
            ],
            vec![ATM_PA, top, top, ATM_PA, ATM_PA],
            crate::gas::GasMix::AIR,
            0.0,
        )
        .unwrap();
        for perfusion in [0.0, 1e-3] {
            let mut params = PhantomParams::box_phantom([1.5e-3; 3], 100e-6);
            params.min_radius = 0.0;
            params.nucleation = std::sync::Arc::new(CriticalRadius {
                number_density: 2e10,
                distribution: SizeDistribution::Exponential { slope: 4e6 },
                margin: None,
                seed: 7,
                skin_compression: None,
            });
            params.numerics.record_interval = 0.0;
            params.numerics.max_content_change = 0.1;
            params.numerics.bubble_tolerance = 0.02;
            params.perfusion_rate = perfusion;
            let (plain, fused) = (run(&params, &profile, false), run(&params, &profile, true));
            assert!(fused.3 > 0, "the dive must nucleate bubbles");
            // perfusion writes every cell after the step: the frames pass the gel themselves
            assert_same_runs(&plain, &fused, perfusion == 0.0);
        }
    }
}

#[cfg(test)]
mod frame_round_tests {
    use super::*;

    /// A step that starts from the fluxes its previous frame computed gives the bits of one
    /// that computes them again: three growing bubbles (two with overlapping spheres), frames
    /// at every step and every 0.7 s, every frame and the summary compared bit by bit.
    #[test]
    fn reusing_the_frames_flux_round_keeps_the_bits() {
        let profile = grow_then_recompress(60.0);
        for interval in [0.0, 0.7] {
            let mut params = three_bubbles_in_an_open_box(1e-4);
            params.numerics.record_interval = interval;
            let run = |reuse: bool| {
                let mut sim = Simulation::new(&params, &profile).unwrap();
                sim.reuse_frame_round = reuse;
                let mut rec = Recorder::default();
                let summary = sim.run(&profile, &mut rec).unwrap();
                (summary, rec.frames)
            };
            let (s0, f0) = run(false);
            let (s1, f1) = run(true);
            assert!(s0.steps.0 + s0.steps.1 > 20, "{:?}", s0.steps);
            assert_eq!(s0.steps, s1.steps);
            assert_eq!(
                s0.gas_balance_error.to_bits(),
                s1.gas_balance_error.to_bits()
            );
            assert_eq!(
                s0.peak_total_volume.0.to_bits(),
                s1.peak_total_volume.0.to_bits()
            );
            assert_same_frame_bits(&f0, &f1);
        }
    }
}

#[cfg(test)]
mod step_wall_tests {
    use super::StepWall;

    /// A run's totals are the phases' sums, and the CSV fields follow the header (values worked
    /// out by hand).
    #[test]
    fn step_walls_add_phase_by_phase_and_print_in_header_order() {
        let a = StepWall {
            prepare_s: 0.001,
            gel_s: 0.010,
            events_s: 0.004,
            corrector_s: 0.002,
            displacement_s: 0.001,
            frame_s: 0.003,
        };
        let mut sum = StepWall::default();
        sum.add(&a);
        sum.add(&a);
        assert_eq!(sum.gel_s, 0.020);
        assert_eq!(sum.corrector_s, 0.004);
        assert_eq!(sum.frame_s, 0.006);
        let names: Vec<&str> = StepWall::CSV_HEADER.split(',').collect();
        let fields: Vec<f64> = a
            .csv_fields()
            .split(',')
            .map(|x| x.parse().unwrap())
            .collect();
        assert_eq!(names.len(), fields.len());
        let expect = [
            ("prepare_s", 0.001),
            ("gel_s", 0.010),
            ("events_s", 0.004),
            ("corrector_s", 0.002),
            ("displacement_s", 0.001),
            ("frame_s", 0.003),
        ];
        for ((n, x), (en, ex)) in names.iter().zip(&fields).zip(expect) {
            assert_eq!(*n, en);
            assert_eq!(*x, ex);
        }
    }
}

#[cfg(test)]
mod loading_error_tests {
    use super::{loading_error_first_order, loading_error_second_order};

    /// The flow over [t, t + dt] of a content M(t).
    fn flow(m: &impl Fn(f64) -> f64, t: f64, dt: f64) -> f64 {
        m(t + dt) - m(t)
    }

    /// Steps of unequal lengths, as the estimate sees them: the two before and this one.
    const STEPS: [(f64, f64); 3] = [(3.0, 2.0), (5.0, 3.5), (8.5, 6.0)];

    fn second(m: &impl Fn(f64) -> f64) -> f64 {
        let [(t0, d0), (t1, d1), (t2, d2)] = STEPS;
        loading_error_second_order(
            (flow(m, t2, d2), d2),
            (flow(m, t1, d1), d1),
            (flow(m, t0, d0), d0),
        )
    }

    /// Exact on polynomials (Newton's divided differences): the third divided difference of a
    /// cubic is its leading coefficient, so the estimate is dt³·|c₃|; a quadratic gives 0.
    #[test]
    fn the_second_order_estimate_is_exact_on_polynomials() {
        let dt = STEPS[2].1;
        let cubic = |t: f64| 0.7 * t * t * t - 2.0 * t * t + 5.0 * t + 1.0;
        let e = second(&cubic);
        assert!((e - 0.7 * dt * dt * dt).abs() < 1e-9 * e, "{e}");
        let quadratic = |t: f64| -2.0 * t * t + 5.0 * t + 1.0;
        assert!(second(&quadratic) < 1e-10, "{}", second(&quadratic));
        // the first-order estimate: (dt²/2)·|M''| = dt²·|c₂| on a quadratic, 0 on a line
        let [_, (t1, d1), (t2, d2)] = STEPS;
        let first = |m: &dyn Fn(f64) -> f64| {
            loading_error_first_order(m(t2 + d2) - m(t2), d2, m(t1 + d1) - m(t1), d1)
        };
        assert!((first(&quadratic) - 2.0 * d2 * d2).abs() < 1e-10);
        assert!(first(&|t: f64| 3.0 * t - 1.0) < 1e-12);
    }

    /// Each estimate against the true local error of its own scheme on u' = λu (one mode of
    /// the gel's unloading, M = u): backward Euler's step 1/(1 − z) and its Richardson
    /// extrapolation 2/(1 − z/2)² − 1/(1 − z), z = λ·dt, each from the exact u(t), against
    /// u(t + dt) = u(t)·e^z. The ratio of estimate to error tends to 1 as dt → 0, at first
    /// order (the differences reach back over the two steps before; an independent
    /// computation: the schemes' series, not the divided differences). Measured when written:
    /// 1.37 / 1.79 at dt = τ/5, 1.021 / 1.038 at τ/80, τ = 300 s.
    #[test]
    fn the_estimates_track_their_schemes_local_errors() {
        let lambda: f64 = -1.0 / 300.0;
        let u = |t: f64| (lambda * t).exp();
        let mut ratios = Vec::new();
        for dt in [60.0, 15.0, 3.75, 0.9375] {
            let z = lambda * dt;
            let t = 100.0;
            let be = u(t) / (1.0 - z);
            let ex = 2.0 * u(t) / ((1.0 - 0.5 * z) * (1.0 - 0.5 * z)) - u(t) / (1.0 - z);
            let exact = u(t + dt);
            let (f, fl, fb) = (exact - u(t), u(t) - u(t - dt), u(t - dt) - u(t - 2.0 * dt));
            let e1 = loading_error_first_order(f, dt, fl, dt);
            let e2 = loading_error_second_order((f, dt), (fl, dt), (fb, dt));
            ratios.push((e1 / (be - exact).abs(), e2 / (ex - exact).abs()));
        }
        eprintln!("estimate / true local error (first, second order): {ratios:?}");
        let (r1, r2) = ratios[3];
        assert!((r1 - 1.0).abs() < 0.01, "{ratios:?}");
        assert!((r2 - 1.0).abs() < 0.015, "{ratios:?}");
        // at first order: each 4× shorter step brings the ratios 3× nearer 1 or more
        for w in ratios.windows(2) {
            assert!(
                (w[1].0 - 1.0).abs() < (w[0].0 - 1.0).abs() / 3.0,
                "{ratios:?}"
            );
            assert!(
                (w[1].1 - 1.0).abs() < (w[0].1 - 1.0).abs() / 3.0,
                "{ratios:?}"
            );
        }
    }
}
