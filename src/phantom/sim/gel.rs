//! The gel's diffusion step (explicit, implicit or extrapolated; [`Simulation::gel_step`]), the
//! field's error estimate and perfusion.

use super::*;

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
pub(super) const OUT_OF_PLACE_BYTES: usize = 12 << 20;

/// Largest set of fields (bytes, all gases) whose extrapolated steps run side by side, each
/// gas's whole step in a copy of its own ([`Simulation::extrapolate_side_by_side`]): 8·G B per
/// cell while the steps last, against 8 B gas by gas. 256 MiB: 16.7 M cells with two gases;
/// larger grids go gas by gas and keep one copy (as do runs on one thread, and the descents of
/// runs with the field's error estimate on, [`Simulation::diffuse`]).
pub(super) const SIDE_BY_SIDE_EXTRA_BYTES: usize = 256 << 20;

impl Simulation<'_> {
    /// Phase 4 with its error estimates: the gel's diffusion over [t, t + dt] ([`Self::diffuse`],
    /// counted in the log as explicit or implicit) and the steps the field's and the loading's
    /// error estimates allow next ([`Self::loading_step`]; `loading` its history).
    pub(super) fn gel_step(
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
    pub(super) fn diffuse(
        &mut self,
        profile: &PressureHistory,
        t: f64,
        dt: f64,
        tol_pa: f64,
        extrapolate: bool,
    ) -> (bool, f64) {
        let implicit = self.explicit_limit.iter().any(|lim| dt > *lim);
        // the open faces hold the gas of the segment the step lies in (a step ending on a gas
        // switch keeps the old gas to its end) at the ambient pressure of their time
        let seg = profile.step_segment(t, t + dt);
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
            // the extrapolated steps are over: give their copies back
            self.extra = Vec::new();
        }
        if !estimate && implicit && extrapolate && self.extrapolate_side_by_side() {
            let mut flow = [0.0; Gas::ALL.len()];
            self.extrapolated_steps(profile, 0..ng, (t, dt), &mut flow[..ng]);
            for (g, x) in flow[..ng].iter().enumerate() {
                self.inflow += x * h3;
                self.step_flow[g] = x * h3;
            }
            return (implicit, 0.0);
        }
        // (the field's estimate and the extrapolated steps of one thread, gas by gas, below)
        if !(estimate || implicit && extrapolate) {
            // every gas at once, each the same bits as stepped alone: the explicit step in one
            // parallel pass, the implicit steps side by side; the open faces at their value at
            // the end of the step in both (both take the open faces' term implicitly)
            let tb = t + dt;
            let mut dc = [(0.0, 0.0); Gas::ALL.len()];
            for (g, dc) in dc[..ng].iter_mut().enumerate() {
                let cb = self.ostwald[g]
                    * profile.inspired_partial_pressure_on(self.gases[g], seg, tb)
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
                let mut flow = [0.0];
                self.extrapolated_steps(profile, g..g + 1, (t, dt), &mut flow);
                flow[0]
            } else {
                // the open faces at their end value (both schemes take their term implicitly)
                let cb = self.ostwald[g] * profile.inspired_partial_pressure_on(gas, seg, t + dt)
                    / self.rt;
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

    /// Whether the extrapolated steps run every gas side by side
    /// ([`Self::extrapolated_steps`]): with more than one gas and more than one thread, and
    /// their whole steps' copies (a store per gas) within [`SIDE_BY_SIDE_EXTRA_BYTES`]; else
    /// gas by gas, with one copy.
    pub(super) fn extrapolate_side_by_side(&self) -> bool {
        self.fields.len() > 1
            && rayon::current_num_threads() > 1
            && self.fields_bytes() <= SIDE_BY_SIDE_EXTRA_BYTES
    }

    /// The bytes of one set of fields (every gas).
    pub(super) fn fields_bytes(&self) -> usize {
        self.grid.len() * self.fields.len() * std::mem::size_of::<f64>()
    }

    /// Every gas's explicit step from `fields` into `back`, then the two swapped: the same
    /// bits as [`diffusion::explicit_steps_in_place`] (test
    /// `out_of_place_explicit_steps_are_the_in_place_bits`), without that step's copy of every
    /// plane's old values. `back` is brought level with `fields` first when the grid's codes
    /// changed since it last was (a cell taken out of the gel is zeroed in `fields` only), so
    /// the cells the step does not write, those outside the gel, hold the values they would
    /// hold in place.
    pub(super) fn explicit_steps_out_of_place(
        &mut self,
        dc: &[(f64, f64)],
        dt: f64,
        inflow: &mut [f64],
    ) {
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

    /// The implicit steps of gases `gases` over [t, t + dt], each Richardson-extrapolated,
    /// 2·u_½ − u_1 from two half steps and one whole (second order; conservative, its weights
    /// summing to 1), or the two half steps where the extrapolation would make one of its
    /// cells negative (gas by gas). The gases are stepped side by side
    /// ([`diffusion::ImplicitSolver::steps`]: each the same bits as stepped alone), the whole
    /// steps into copies of their stores (`extra`, a store per gas, kept while the steps last).
    /// Writes the inflow through the open faces per cell volume of the i-th gas of `gases`
    /// into `flow[i]`, as [`diffusion::ImplicitSolver::step`] returns it.
    pub(super) fn extrapolated_steps(
        &mut self,
        profile: &PressureHistory,
        gases: std::ops::Range<usize>,
        (t, dt): (f64, f64),
        flow: &mut [f64],
    ) {
        let seg = profile.step_segment(t, t + dt);
        let n = gases.len();
        assert_eq!(flow.len(), n, "a flow per gas stepped");
        let mut half_dc = [(0.0, 0.0); Gas::ALL.len()];
        let mut end_dc = [(0.0, 0.0); Gas::ALL.len()];
        for (m, g) in gases.clone().enumerate() {
            let cb = |s: f64| {
                self.ostwald[g] * profile.inspired_partial_pressure_on(self.gases[g], seg, s)
                    / self.rt
            };
            half_dc[m] = (self.diffusivity[g], cb(t + 0.5 * dt));
            end_dc[m] = (self.diffusivity[g], cb(t + dt));
        }
        use rayon::prelude::*;
        // the grid-wide passes in parallel chunks (element by element: the same bits)
        const CHUNK: usize = 1 << 14;
        // the whole steps in copies of the fields' whole stores (the same layout, so that the
        // stores can be swapped below)
        let mut whole = std::mem::take(&mut self.extra);
        whole.resize_with(n, Vec::new);
        for (w, g) in whole.iter_mut().zip(gases.clone()) {
            w.resize(self.fields.store(g).len(), 0.0);
            w.par_chunks_mut(CHUNK)
                .zip(self.fields.store(g).par_chunks(CHUNK))
                .for_each(|(w, f)| w.copy_from_slice(f));
        }
        let (a, b) = self.fields.view_range();
        let mut f_whole = [0.0; Gas::ALL.len()];
        {
            let mut views: Vec<&mut [f64]> = whole.iter_mut().map(|w| &mut w[a..b]).collect();
            self.implicit
                .steps(&self.grid, &mut views, &end_dc[..n], dt, &mut f_whole[..n]);
        }
        let (mut f_first, mut f_second) = ([0.0; Gas::ALL.len()], [0.0; Gas::ALL.len()]);
        {
            let mut halves: Vec<&mut [f64]> =
                self.fields.slices_mut().drain(gases.clone()).collect();
            self.implicit.steps(
                &self.grid,
                &mut halves,
                &half_dc[..n],
                0.5 * dt,
                &mut f_first[..n],
            );
            self.implicit.steps(
                &self.grid,
                &mut halves,
                &end_dc[..n],
                0.5 * dt,
                &mut f_second[..n],
            );
        }
        for (m, g) in gases.enumerate() {
            let f_half = f_first[m] + f_second[m];
            // the extrapolation into the whole step's buffer, in one pass with the check for
            // a negative cell; kept (the stores swapped) only if there is none
            let negative = whole[m][a..b]
                .par_chunks_mut(CHUNK)
                .zip(self.fields[g].par_chunks(CHUNK))
                .map(|(w, h)| {
                    let mut negative = false;
                    for (w, h) in w.iter_mut().zip(h) {
                        *w = 2.0 * h - *w;
                        negative |= *w < 0.0;
                    }
                    negative
                })
                .reduce(|| false, |x, y| x || y);
            flow[m] = if negative {
                f_half
            } else {
                self.fields.swap_store(g, &mut whole[m]);
                2.0 * f_half - f_whole[m]
            };
        }
        self.extra = whole;
    }

    /// Zero the field-error vector (in `scratch`) in every active bubble's near field: the
    /// cells within its coupling radius ρ plus two grid steps, whose change within a step is
    /// the bubble's exchange, which the bubbles' own error estimate controls
    /// (`bubble_tolerance`, [`Self::correct`]). Returns whether any cell was cleared.
    pub(super) fn clear_near_fields(&mut self) -> bool {
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

    /// Phase 5: perfusion, operator-split after diffusion: every inside cell relaxes toward the
    /// blood value C_b,g(t) = L_g·p_insp,g(t)/(R_u·T) at rate k (`perfusion_rate`), integrated
    /// exactly over the step with C_b linear in time ([`diffusion::PerfusionWeights`]). The gas
    /// perfusion adds or removes is counted with the open-face inflow in the gas balance.
    pub(super) fn perfuse(&mut self, profile: &PressureHistory, t: f64, dt: f64) {
        let k = self.params.perfusion_rate;
        if !(k > 0.0) {
            return;
        }
        let w = diffusion::PerfusionWeights::new(k, dt);
        self.gel_fresh = false;
        let h3 = self.grid.cell_volume();
        // the blood value of the segment the step lies in, at both ends (as the open faces)
        let seg = profile.step_segment(t, t + dt);
        for g in 0..self.gases.len() {
            let gas = self.gases[g];
            let cb0 = self.ostwald[g] * profile.inspired_partial_pressure_on(gas, seg, t) / self.rt;
            let cb1 =
                self.ostwald[g] * profile.inspired_partial_pressure_on(gas, seg, t + dt) / self.rt;
            let added = diffusion::perfusion_step(&self.grid, &mut self.fields[g], w, cb0, cb1);
            self.inflow += added * h3;
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

#[cfg(test)]
mod extrapolated_step_tests {
    use super::*;
    use crate::gas::GasMix;
    use crate::phantom::params::GasProperties;

    /// An open 9³ cube (h = 100 µm) of `gases`, each (gas, D, L), breathing `mix` on a pressure
    /// rising from 1 to 3 bar over 100 s.
    fn open_cube_on_a_ramp(
        gases: &[(Gas, f64, f64)],
        mix: GasMix,
    ) -> (PhantomParams, PressureHistory) {
        let h = 1e-4;
        let mut params = PhantomParams::box_phantom([9.0 * h; 3], h);
        params.gases = gases
            .iter()
            .map(|&(gas, diffusivity, ostwald)| GasProperties {
                gas,
                diffusivity,
                ostwald,
            })
            .collect();
        params.open_faces = params.shape.faces().to_vec();
        let profile =
            PressureHistory::with_gas("ramp", vec![0.0, 100.0], vec![1e5, 3e5], mix, 0.0).unwrap();
        (params, profile)
    }

    /// The open cube of pure N2 on its ramp, its field set by `init`, stepped once by
    /// [`Simulation::diffuse`] with the extrapolation, and the same start stepped here with the
    /// solver directly: (the simulation's field, inflow; two half steps; one whole step).
    fn step(init: impl Fn(usize) -> f64, dt: f64) -> (Vec<f64>, f64, Vec<f64>, Vec<f64>, f64) {
        let pure_n2 = GasMix { o2: 0.0, he: 0.0 };
        let (params, profile) = open_cube_on_a_ramp(&[(Gas::N2, 1e-9, 0.014)], pure_n2);
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

    /// Three gases (N2, O2 and He of different D, a trimix) on a rising pressure: one explicit
    /// step (which leaves the one-thread run's fields moved by two planes in their stores),
    /// then two extrapolated steps. Side by side on two threads they give the bits of the same
    /// steps gas by gas on one thread (fields, inflow and each gas's flow), and each gas's
    /// field is, bit for bit, 2·u_½ − u_1 of the solver's own steps, or its two half steps where
    /// that goes negative: a spike in the O2 field takes O2's fallback in the first
    /// extrapolated step, as in the test below.
    #[test]
    fn side_by_side_extrapolated_steps_are_the_gas_by_gas_bits() {
        let trimix = GasMix { o2: 0.21, he: 0.35 };
        let gases = [
            (Gas::N2, 1e-9, 0.014),
            (Gas::O2, 1.7e-9, 0.027),
            (Gas::He, 2.5e-9, 0.0098),
        ];
        let (params, profile) = open_cube_on_a_ramp(&gases, trimix);
        let centre = 4 + 9 * (4 + 9 * 4);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let run = |threads: usize, spike: bool| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                let mut sim = Simulation::new(&params, &profile).unwrap();
                for g in 0..3 {
                    for (i, c) in sim.fields[g].iter_mut().enumerate() {
                        *c = 0.5 + 0.01 * ((i + 3 * g) % 9) as f64;
                    }
                }
                if spike {
                    sim.fields[1][centre] = 5e4;
                }
                let (implicit, _) = sim.diffuse(&profile, 0.0, 0.2, f64::INFINITY, false);
                assert!(!implicit);
                let offset = sim.fields.offset_planes();
                let side_by_side = sim.extrapolate_side_by_side();
                let mut fell_back = Vec::new();
                for (t, dt) in [(0.2, 50.0), (50.2, 30.0)] {
                    // each gas's steps with the solver alone, from the same start
                    let mut want = Vec::new();
                    for (g, &(gas, d, l)) in gases.iter().enumerate() {
                        let cb = |s: f64| l * profile.inspired_partial_pressure(gas, s) / sim.rt;
                        let mut solver = diffusion::ImplicitSolver::new();
                        let mut half = sim.fields[g].to_vec();
                        solver.step(&sim.grid, &mut half, d, 0.5 * dt, cb(t + 0.5 * dt));
                        solver.step(&sim.grid, &mut half, d, 0.5 * dt, cb(t + dt));
                        let mut whole = sim.fields[g].to_vec();
                        solver.step(&sim.grid, &mut whole, d, dt, cb(t + dt));
                        let extrapolated: Vec<f64> =
                            half.iter().zip(&whole).map(|(h, w)| 2.0 * h - w).collect();
                        if extrapolated.iter().any(|c| *c < 0.0) {
                            fell_back.push((t, g));
                            want.push(half);
                        } else {
                            want.push(extrapolated);
                        }
                    }
                    let (implicit, _) = sim.diffuse(&profile, t, dt, f64::INFINITY, true);
                    assert!(implicit);
                    for (g, w) in want.iter().enumerate() {
                        assert!(bits(&sim.fields[g]) == bits(w), "gas {g} at t = {t} s");
                    }
                }
                (
                    (side_by_side, offset, fell_back),
                    [0, 1, 2].map(|g| bits(&sim.fields[g])),
                    sim.inflow.to_bits(),
                    sim.step_flow.map(f64::to_bits),
                )
            })
        };
        for spike in [false, true] {
            let ((two, offset2, fell_back2), fields2, inflow2, flow2) = run(2, spike);
            let ((one, offset1, fell_back1), fields1, inflow1, flow1) = run(1, spike);
            assert!(two && !one);
            // one thread steps the fields explicitly by moving them two planes in their stores
            assert_eq!((offset2, offset1), (0, 2));
            // the spike takes O2's fallback in the first step; nothing else falls back
            let want: Vec<(f64, usize)> = if spike { vec![(0.2, 1)] } else { vec![] };
            assert_eq!((&fell_back2, &fell_back1), (&want, &want));
            assert!(fields2 == fields1, "spike {spike}");
            assert_eq!((inflow2, flow2), (inflow1, flow1), "spike {spike}");
        }
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
