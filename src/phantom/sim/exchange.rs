//! The bubbles' exchange with the gel: the coupling spheres' means, the fluxes, the predictor
//! ([`Simulation::exchange`]) and the corrector ([`Simulation::correct`]) through the sink kernel.

use super::*;
use std::f64::consts::PI;

/// Floor of the flux scale in the step's error estimate ([`Simulation::correct`]), as a
/// fraction of the bubble's content: a bubble whose flux passes through zero is judged by the
/// change of its content, not by a relative change of a vanishing flux.
pub(super) const FLUX_FLOOR: f64 = 0.01;

/// Sizes of coupling sphere kept by [`Simulation::prepare_sphere`] before its cache is emptied.
pub(super) const SPHERE_CACHE: usize = 16;

/// Points sampled over all bubbles in one round from which [`Simulation::all_fluxes`] runs the
/// bubbles in parallel (below, a thread's wake-up costs more than it saves: 64 points take a
/// few µs).
pub(super) const PARALLEL_SPHERE_POINTS: usize = 1024;

#[cfg(test)]
thread_local! {
    /// Tests: evaluate the bubbles' fluxes one after another, as before they ran in parallel
    /// (the reference of `parallel_fluxes_tests`).
    static SERIAL_FLUXES: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Whether the bubbles' fluxes are evaluated one by one where they interleave with the
/// corrections (tests only; always false in a build).
pub(super) fn serial_fluxes() -> bool {
    #[cfg(test)]
    {
        SERIAL_FLUXES.with(|s| s.get())
    }
    #[cfg(not(test))]
    {
        false
    }
}

/// The bubble whose exchange gave the corrector's largest error estimate over a step, with its
/// fluxes at the start and the end of the step ([`StepRecord`]).
pub(super) type WorstExchange = Option<(usize, [f64; Gas::ALL.len()], [f64; Gas::ALL.len()])>;

/// The buffers of a round of the bubbles' fluxes ([`Simulation::flux_round`]), kept between
/// steps so the time loop does not allocate them per step.
#[derive(Debug, Default)]
pub(super) struct FluxRound {
    /// The bubbles of the round.
    pub(super) which: Vec<usize>,
    /// Per bubble (all of them; only `which` filled): the gel tension and the fluxes.
    pub(super) out: Vec<(f64, [f64; Gas::ALL.len()])>,
    /// The parallel round's value of every gas at each sampled point, all bubbles' points
    /// one after the other ([`Simulation::sphere_means_of`]).
    pub(super) vals: Vec<[f64; Gas::ALL.len()]>,
    /// The parallel round's sphere means, one per bubble of `which`.
    pub(super) means: Vec<[f64; Gas::ALL.len()]>,
}

/// One bubble's exchange within a step, from the predictor ([`Simulation::exchange`]) to the
/// corrector ([`Simulation::correct`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::phantom) struct StepExchange {
    /// Content at the start of the step, mol per gas.
    pub(in crate::phantom) start: [f64; Gas::ALL.len()],
    /// Gas the grid gave before diffusion, mol per gas.
    pub(in crate::phantom) taken: [f64; Gas::ALL.len()],
    /// Fluxes J_g(t) at the start of the step, mol/s.
    pub(in crate::phantom) flux: [f64; Gas::ALL.len()],
    /// The bubble takes part in the corrector (active and not dissolved by the predictor).
    pub(in crate::phantom) open: bool,
}

/// The `n` points of the Fibonacci sphere: z_i = 1 − (2i + 1)/n, at longitude i times the
/// golden angle. `turns` holds (cos, sin) of the longitudes, which do not depend on n (grown
/// here as needed: a growing bubble asks for a slightly larger sphere at almost every step).
pub(super) fn fibonacci_sphere(n: usize, turns: &mut Vec<[f64; 2]>) -> Vec<[f64; 3]> {
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

impl Simulation<'_> {
    /// Radius of bubble `i`'s sink kernel ([`Self::kernel_radius_at`]).
    pub(super) fn kernel_radius(&self, i: usize) -> f64 {
        self.kernel_radius_at(self.bubbles[i].radius, self.displaces(i))
    }

    /// Radius of bubble `i`'s coupling sphere ρ ([`Self::coupling_radius_at`]).
    pub(super) fn coupling_radius(&self, i: usize) -> f64 {
        self.coupling_radius_at(self.bubbles[i].radius, self.displaces(i))
    }

    /// Whether bubble `i` holds cells out of the gel ([`Self::displace`]).
    pub(super) fn displaces(&self, i: usize) -> bool {
        self.displaced.get(i).is_some_and(|d| !d.cells.is_empty())
    }

    /// Sink-kernel radius of a bubble of radius `r`: max(R, kernel_min_cells·h), or, once it
    /// holds cells out of the gel (`displacing`), the shell out to R + kernel_min_cells·h.
    pub(super) fn kernel_radius_at(&self, r: f64, displacing: bool) -> f64 {
        let k = self.params.numerics.kernel_min_cells * self.grid.h;
        if displacing {
            r + k
        } else {
            r.max(k)
        }
    }

    /// Coupling radius ρ = max(kernel, R + δ) + coupling_gap_cells·h.
    pub(super) fn coupling_radius_at(&self, r: f64, displacing: bool) -> f64 {
        self.kernel_radius_at(r, displacing)
            .max(r + self.params.surface_layer_thickness)
            + self.params.numerics.coupling_gap_cells * self.grid.h
    }

    /// Average of every gas's field over the sphere of radius `rho` about `c` into `out` (one
    /// per gas; `fallback` per gas where a point has no inside cell about it). The sphere must
    /// have been prepared ([`Self::prepare_sphere_at`]). The points'
    /// corners and weights are found once for all gases ([`Grid::interpolate_many`]).
    pub(super) fn sphere_means(&self, c: [f64; 3], rho: f64, fallback: &[f64], out: &mut [f64]) {
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

    /// Every gas's field (`out.len()` of them; `fields` from [`Self::field_views`])
    /// interpolated at the point `c + rho·u` of a coupling sphere, from inside cells only
    /// (`fallback` where none is about it).
    #[inline(always)]
    pub(super) fn sphere_point(
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
    pub(super) fn sphere_size(&self, rho: f64) -> usize {
        ((16.0 * (rho / self.grid.h).powi(2)).ceil() as usize).clamp(64, 20_000)
    }

    /// Make bubble `i`'s coupling sphere ready for [`Self::sphere_means`] (built once per
    /// size; the cache is emptied when it holds more than [`SPHERE_CACHE`] sizes, before a
    /// round of fluxes). Returns its number of points.
    pub(super) fn prepare_sphere(&mut self, i: usize) -> usize {
        self.prepare_sphere_at(self.coupling_radius(i))
    }

    /// [`Self::prepare_sphere`] for a sphere of radius `rho`.
    pub(super) fn prepare_sphere_at(&mut self, rho: f64) -> usize {
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
    pub(super) fn flux_round(
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
    pub(super) fn all_fluxes(
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
    pub(super) fn inspired_concentrations(
        &self,
        profile: &PressureHistory,
    ) -> [f64; Gas::ALL.len()] {
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
    pub(super) fn sphere_means_of(
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
    pub(super) fn fluxes(
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
    pub(super) fn fluxes_from_means(
        &self,
        i: usize,
        ambient: f64,
        cbar: &[f64],
        j: &mut [f64],
    ) -> f64 {
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

    /// Phase 1: every active bubble's fluxes J_g (mol/s) and gel tension at the start of a step.
    pub(super) fn bubble_fluxes(
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

    /// Phase 3: the predictor of the gas exchange between bubbles and gel (Heun's method;
    /// [`Self::correct`] completes it after diffusion). Each bubble's content is predicted with
    /// the fluxes at the start of the step, n* = n + J(t)·dt, and that gas is taken from (or
    /// returned to) the grid now, before diffusion, through the bubble's sink kernel
    /// ([`Self::deposit`], which never overdraws a cell). A bubble that the predictor empties
    /// dissolves here, all its gas returned to the gel.
    pub(super) fn exchange(
        &mut self,
        fluxes: &[Vec<f64>],
        dt: f64,
        t1: f64,
        events: &mut Vec<Event>,
    ) {
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
    pub(super) fn take_from_grid(&mut self, i: usize, dn: &[f64]) -> [f64; Gas::ALL.len()] {
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
    pub(super) fn touch(&mut self, (clo, chi): ([usize; 3], [usize; 3])) {
        let (lo, hi) = self.touched.get_or_insert((clo, chi));
        for a in 0..3 {
            lo[a] = lo[a].min(clo[a]);
            hi[a] = hi[a].max(chi[a]);
        }
    }

    /// Whether bubble `i`'s coupling sphere (its trilinear samples reach a cell beyond ρ)
    /// may read a cell in [`Self::touched`].
    pub(super) fn reads_touched(&self, i: usize) -> bool {
        let Some((tlo, thi)) = self.touched else {
            return false;
        };
        let reach = self.coupling_radius(i) + 2.0 * self.grid.h;
        let (lo, hi) = self.grid.cell_range(self.bubbles[i].position, reach);
        (0..3).all(|a| lo[a] <= thi[a] && tlo[a] <= hi[a])
    }

    /// Bubble `i` has dissolved at `t1`: whatever round-off it still holds is dropped from it
    /// (its gas was returned to the gel by the transfer that emptied it).
    pub(super) fn dissolve(&mut self, i: usize, t1: f64, events: &mut Vec<Event>) {
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
    /// ([`Numerics::bubble_tolerance`](crate::phantom::params::Numerics::bubble_tolerance)): what stays
    /// first order after the corrector is the lag of the implicit diffusion near the bubble.
    pub(super) fn correct(
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

    /// Take `dn` mol of gas `g` from the grid through the kernel (give it back when negative) and
    /// return the amount actually moved. Gas returned to the gel goes with the kernel's weights.
    /// Gas taken never drives a cell negative: each cell gives at most what it holds — first
    /// its kernel share, then the shortfall from the cells with content left, in proportion to
    /// it. When the whole kernel holds less than `dn` it gives what it has ([`Self::exchange`]
    /// then takes the rest from the wider sphere of radius ρ the same way; if even that runs dry
    /// the bubble receives only what is there, and the next step's flux sees the emptied cells).
    pub(super) fn deposit(&mut self, g: usize, kernel: &[(usize, f64)], dn: f64) -> f64 {
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
