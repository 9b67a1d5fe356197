//! What the time loop reports: the frames, the step records and the phase clock, the
//! [`Observer`] that receives them, and the gel's state of each frame.

use super::*;
use crate::phantom::gel_pass::same_plane_gel;

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
    /// Of `events_s`, the corrector of the bubbles' exchange (`Simulation::correct`: the
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
pub(super) fn lap(from: &mut Instant) -> f64 {
    let now = Instant::now();
    let s = (now - *from).as_secs_f64();
    *from = now;
    s
}

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
    /// ([`crate::phantom::checkpoint`]). An error ends the run.
    fn checkpoint(&mut self, _state: crate::phantom::checkpoint::RunState) -> Result<(), Error> {
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

impl Simulation<'_> {
    /// Bookkeeping after a step (peaks, a bubble reaching a face, the observer's progress and
    /// stop request) and the record when a frame is due (`first`: the initial state).
    pub(super) fn observe(
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

    /// One parallel pass over the grid: the largest supersaturation Σ_g C_g·R_u·T/L_g + p_fixed − P_amb (Pa),
    /// the gas dissolved in the grid per gas (mol) and the lowest concentration of any gas
    /// (mol/m³). Plane by plane ([`plane_gel`], vectorised), the planes combined in plane
    /// order: the same bits whatever the thread count.
    pub(super) fn gel_state(&self, ambient: f64) -> (f64, Vec<f64>, f64) {
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
    pub(super) fn gel_factors(&self) -> [f64; Gas::ALL.len()] {
        let mut k = [0.0; Gas::ALL.len()];
        for (kg, l) in k.iter_mut().zip(&self.ostwald) {
            *kg = self.rt / l;
        }
        k
    }

    /// The cells `idx` are written outside the diffusion step: the z-planes they lie in are
    /// passed again at the next frame ([`Self::gel_state`]).
    pub(super) fn mark_gel(&mut self, idx: impl Iterator<Item = usize>) {
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
    /// [`Numerics::record_gel`]: crate::phantom::params::Numerics::record_gel
    pub(super) fn record(
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
