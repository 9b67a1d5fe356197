//! The step's length and scheme: the limits of [`Simulation::choose_step`], the bubbles' and the
//! loading's error estimates, and which steps are extrapolated (README "Time stepping").

use super::*;

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

/// The loading estimate's history since the last profile breakpoint: per gas the flow
/// through the open faces over each of the last two steps, mol, and those steps' lengths, s
/// (a length 0: no such step since the breakpoint).
#[derive(Debug, Clone, Default, PartialEq)]
pub(in crate::phantom) struct LoadingHistory {
    /// The last step's flows and length.
    pub(in crate::phantom) last: Vec<f64>,
    pub(in crate::phantom) last_dt: f64,
    /// The step before it.
    pub(in crate::phantom) before: Vec<f64>,
    pub(in crate::phantom) before_dt: f64,
}

impl LoadingHistory {
    pub(super) fn new(gases: usize) -> LoadingHistory {
        LoadingHistory {
            last: vec![0.0; gases],
            last_dt: 0.0,
            before: vec![0.0; gases],
            before_dt: 0.0,
        }
    }

    /// Forget the steps (at a profile breakpoint, where the flow's rate jumps).
    pub(super) fn clear(&mut self) {
        self.last_dt = 0.0;
        self.before_dt = 0.0;
    }

    /// Take the step just done (`flow` over `dt`) into the history.
    pub(super) fn push(&mut self, flow: &[f64], dt: f64) {
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

impl Simulation<'_> {
    /// The next step the bubbles' error estimate allows after a step `dt` whose estimate was
    /// `err` (`bubble_tolerance`; the next step is 0.9·dt·tol/err). Within the explicit limit
    /// `lim` the tolerance is `explicit_tolerance_factor` times larger (forward Euler leaves no
    /// backward-Euler lag near a bubble): when that step is within the limit it is taken, when
    /// only the limit is, the limit.
    pub(super) fn bubble_step(&self, dt: f64, err: f64, lim: f64) -> f64 {
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
    pub(super) fn choose_step(
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
    pub(super) fn loading_only(&self, profile: &PressureHistory) -> bool {
        let rate = profile.rate(self.time + 1e-9);
        let num = &self.params.numerics;
        (rate > 0.0 || rate == 0.0 && num.extrapolate_holds && !num.field_tolerance.is_finite())
            && self.nuclei.is_empty()
            && self
                .bubbles
                .iter()
                .all(|b| !b.active() || b.radius <= self.params.min_radius)
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
    /// [`Numerics::loading_tolerance`]: crate::phantom::params::Numerics::loading_tolerance
    pub(super) fn loading_step(
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
