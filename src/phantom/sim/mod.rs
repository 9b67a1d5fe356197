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
//!
//! The files follow the time loop's phases (`Simulation::run_from`): this one holds the state,
//! the set-up and the loop itself; `exchange` the bubbles' fluxes, the predictor and the
//! corrector; `step_control` the step's length and scheme; `gel` the gel's diffusion and
//! perfusion; `bubbles` displacement, coalescence and nucleation; `record` the frames, the step
//! records and the [`Observer`].

mod bubbles;
mod exchange;
mod gel;
mod record;
mod step_control;

pub use bubbles::{bubble_outside, place_bubbles};
pub(super) use exchange::StepExchange;
use exchange::{FluxRound, WorstExchange};
use gel::OUT_OF_PLACE_BYTES;
use record::lap;
pub use record::{BubbleFrame, Frame, Observer, Recorder, StepRecord, StepWall};
pub(super) use step_control::LoadingHistory;
pub use step_control::{StepLimit, StepScheme};

use super::bubble::{Balance, Bubble, BubbleFate};
use super::diffusion;
use super::displacement::{self, Displaced};
use super::fields::Fields;
use super::gel_pass::{plane_gel, PlaneGel};
use super::grid::{Face, Grid, KernelCache};
use super::nucleation::NucleusPool;
use super::params::{BubblePlacement, PhantomParams};
use crate::error::Error;
use crate::gas::Gas;
use crate::profile::PressureHistory;
use crate::units::GAS_CONSTANT;
use std::time::Instant;

/// Largest relative gas-balance error a healthy run may show. The scheme is conservative to
/// round-off (1e-14 measured), so an error this large means something went wrong, not that the
/// grid is coarse.
const BALANCE_LIMIT: f64 = 1e-6;

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
    /// The extrapolated steps' whole-step copies, one store per gas stepped at once
    /// ([`Self::extrapolated_steps`]; empty until used and after the extrapolated steps).
    extra: Vec<Vec<f64>>,
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

impl<'a> Simulation<'a> {
    /// Set up: grid, fields saturated with the profile's [`Saturation`](crate::profile::Saturation)
    /// (surface air for a dive, the chamber gas for a laboratory profile), bubbles placed and
    /// filled at Laplace equilibrium with the composition of the gel around them. The
    /// parameters are taken as given (`bubble_fixed_gases` too); the commands pair the bubbles'
    /// fixed gases with the history's water vapour first ([`crate::run::params_for`]).
    pub fn new(params: &'a PhantomParams, profile: &PressureHistory) -> Result<Self, Error> {
        let input = |m: String| Error::Input(crate::error::InputError::new(m));
        let grid = Grid::new(params.shape, params.grid_step, &params.open_faces).map_err(input)?;
        params.check_gases_for(profile).map_err(Error::Input)?;
        let gases = profile.gases();
        let mut diffusivity = Vec::new();
        let mut ostwald = Vec::new();
        for g in &gases {
            let p = params
                .gas(*g)
                .expect("every gas of the profile checked by check_gases_for");
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
                let c = l * profile.saturation_partial_pressure(*g) / rt;
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
            .map(|g| profile.saturation_partial_pressure(*g))
            .collect();
        let psum: f64 = partial.iter().sum();
        if !(psum > 0.0) {
            return Err(input(
                "the gel's starting saturation holds no simulated gas (water vapour ≥ the starting pressure?)".into(),
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
    /// (`Self::displace`; part of the gas balance).
    pub fn displaced_gas(&self) -> f64 {
        self.displaced_gas
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

    /// Run the profile to its end (or until a bubble reaches a face). Each step is the physics
    /// in order: the bubbles' fluxes at the start of the step (`Self::bubble_fluxes`), the step
    /// the physics allows (`Self::choose_step`), the gas exchange between bubbles and gel
    /// (`Self::exchange`), diffusion (`Self::diffuse`), perfusion (`Self::perfuse`), the
    /// radii at the new pressure (`Self::update_radii`), coalescence, health checks, and the
    /// record (`Self::observe`).
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
