//! The phantom model's parameters: one documented struct, every field with its unit and
//! default. Built from a phantom TOML by [`super::config`], or in code.

use super::elasticity::{ElasticityLaw, NoElasticity};
use super::grid::{Face, Shape};
use super::nucleation::{fixed::Fixed, NucleationModel};
use super::surface::{EqualToBulk, SurfacePermeability};
use crate::error::InputError;
use crate::gas::Gas;
use crate::profile::PressureHistory;
use std::sync::Arc;

/// Default surface-layer thickness δ, m (see [`PhantomParams::surface_layer_thickness`]).
pub const DEFAULT_SURFACE_LAYER: f64 = 20e-6;

/// Transport properties of one gas in the gel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GasProperties {
    /// Which gas.
    pub gas: Gas,
    /// Bulk diffusion coefficient D_bulk, m²/s (eq. 2.1; Table 1: 1e-10 … 2.7e-9).
    pub diffusivity: f64,
    /// Ostwald solubility coefficient L (dimensionless): C = L·p/(R_u·T) (eq. 2.2;
    /// Table 1: L_N2 = 0.014, L_O2 = 0.013–0.027).
    pub ostwald: f64,
}

/// How bubbles are placed at t = 0.
#[derive(Debug, Clone, PartialEq)]
pub enum BubblePlacement {
    /// Explicit centres (m) and initial radii R_0 (m).
    Explicit(Vec<([f64; 3], f64)>),
    /// A seeded random population.
    Random {
        /// Number of bubbles.
        count: usize,
        /// Initial radius of each, m.
        initial_radius: f64,
        /// Minimum centre-to-centre spacing, m.
        min_spacing: f64,
        /// Minimum distance from a centre to any face, m.
        margin: f64,
        /// Seed of the ChaCha8 generator.
        seed: u64,
    },
}

/// Numerical settings of the time loop. The step follows the physics: it is the smallest
/// of `max_step`, `max_step_growth` times the last step, the pressure-change limit, the
/// radius-change limit and the distance to the next profile breakpoint. Forward Euler (the
/// open faces' term implicit) is used when that step is within the explicit positivity limit,
/// locally-one-dimensional backward Euler otherwise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Numerics {
    /// Largest time step, s: a safety cap; the steps follow the error estimates of the field
    /// (`field_tolerance`) and the bubbles (`bubble_tolerance`) and the other limits. Default 600.
    pub max_step: f64,
    /// Largest change of ambient pressure per step as a fraction of ambient. Default 0.02 (0.01
    /// before 25 Nov 2026: on a 20 min 130 psi dive (`profiles/phantoms/hydrogel.toml`, every
    /// other limit ¼ of its default) 0.0025 / 0.01 / 0.02 give a peak volume of 2.932 / 2.933 /
    /// 2.933 mm³; the oscillation experiment's radii move by 0.0005 % of R). Not applied while
    /// the pressure rises and no bubble can exchange gas (every one shut, no nuclei): then only
    /// the gel loads, its implicit steps are Richardson-extrapolated and the loading's error
    /// estimate sizes them (`verification::a_descent_loads_the_gel_as_duhamels_series`); the
    /// same at a steady pressure (holds and stops: the limit has nothing to limit there).
    pub max_pressure_change: f64,
    /// Largest growth of the step after an implicit step whose bubbles' error estimate is the
    /// tightest of the error estimates (and below `max_step`), as a factor of the step the
    /// physics allowed last (before the breakpoints and the explicit limit cut it); otherwise
    /// 2. Default 1.2 (2 throughout before 26 Nov 2026). Over a long implicit step the bubbles'
    /// estimate measures mostly the change of step: the locally-one-dimensional step's
    /// quasi-steady state near a sink depends on the step (README "Time stepping"), so a step
    /// twice the last moves the coupling sphere's mean, the estimate reports 1.5–7× the
    /// tolerance, the step is cut to ⅓–½ and the cycle starts again. On the Fig. 5 dive (with
    /// `explicit_tolerance_factor` 1 and displacements every 0.1·h), the implicit steps from
    /// 5 min after surfacing: 412 with ×2, 44 % of them above the tolerance (the largest
    /// 7.5×), against 351 with ×1.2, 26 % above it (the largest 2.8×);
    /// the whole dive 780 + 446 steps against 838 + 506, peak volume 6.528 against 6.527 mm³
    /// (every step within the explicit limit: 6.522). 1.05–1.15 took 441–447 implicit steps,
    /// 1.25 / 1.35 / 1.5 461 / 472 / 495. Forward Euler's steady state does not depend on the
    /// step, and the loading's and the field's estimates follow smooth errors of their own:
    /// after those steps the factor stays 2 (the small cube takes the same steps as before).
    pub max_step_growth: f64,
    /// Largest relative change of a bubble's gas content per step. Default 0.03
    /// (≈ 1 % in radius).
    pub max_content_change: f64,
    /// Error tolerance of the bubbles' exchange per step, dimensionless: the largest relative
    /// change of a bubble's flux over one step, Σ_g |J_g(t+dt) − J_g(t)|·dt divided by
    /// Σ_g |J̄_g|·dt + 0.01·n (the content floor keeps a flux passing through zero from
    /// stalling the run). The exchange is Heun's predictor–corrector (second order), so this
    /// bounds what is left first order: the lag of the backward-Euler (LOD) diffusion steps in
    /// the near field of a bubble. The next step is 0.9·dt·tol/estimate (steps are not
    /// rejected). Default 0.004: the Epstein–Plesset case of `tests/integration/bubble_steps.rs`
    /// is then within 0.3 % of a run with every step limit 16× smaller (R at 100 s −0.14 %,
    /// dissolution time −0.26 %; at 0.007: −0.25 %, −0.38 %; Euler exchange without the
    /// control: −1.9 % and −1.2 %).
    pub bubble_tolerance: f64,
    /// The bubbles' tolerance for a step within the explicit limit, as a multiple of
    /// `bubble_tolerance`: when this × the step the bubbles' estimate allows is within the
    /// explicit limit, the step takes it (explicit); when only the limit itself is, the limit.
    /// Default 2 (1 before 26 Nov 2026). `bubble_tolerance` bounds what is left first order,
    /// the lag of the backward-Euler steps near a bubble; forward Euler within its limit leaves
    /// none. Measured with 1 and 2 (displacements every 0.1·h): the Epstein–Plesset case
    /// (`bubble_steps`) 1 488 and 1 082 steps, R(100 s) −0.125 and −0.126 % and the
    /// dissolution time −0.218 and −0.217 % from a run with every limit 16× smaller; the small cube R(300 s) 387.39 and
    /// 387.42 µm in 493 + 17 and 429 + 16 steps (every step within 0.025 s: 386.97 µm); the
    /// Fig. 5 dive 780 + 446 and 666 + 442 steps, peak volume 6.528 and 6.533 mm³, R_max 848.3
    /// and 848.5 µm (every step within the explicit limit: 6.522 mm³, 849.9 µm); the 3-D growth
    /// against Scriven +0.08 / +2.69 % and +0.61 / +2.32 % (S = 9.9 / 3; tolerances 1 / 3 %).
    /// 3 took Fig. 5 to 651 + 447 steps.
    pub explicit_tolerance_factor: f64,
    /// Error tolerance of the gel's diffusion per step, as a fraction of the ambient
    /// pressure: the estimated local error of the gas tension in any cell
    /// (`Simulation::diffuse`: the variable-step estimate of backward Euler's error from the
    /// last two steps' changes) is kept near this; the next step is 0.9·dt·√(tol/estimate)
    /// (steps are not rejected). Infinite switches the estimate off (steps then follow
    /// `max_step` and the other limits alone). Default infinite (off): on the Fig. 5 dive the
    /// error left is the bubbles' (README, "Time stepping"), and the estimate doubles the cost
    /// of an implicit step. On the open cube 1e-3 / 1e-4 / 1e-5 give a largest time error of
    /// 0.49 / 0.19 / 0.07 % of the initial difference at τ ≥ 0.1 (`tests/integration/verification.rs`).
    pub field_tolerance: f64,
    /// Error tolerance of the gel's loading per step, dimensionless: the estimated local error
    /// of each gas's flow through the open faces over one step, as a fraction of what the gel
    /// holds of a pure gas at the ambient pressure, V_gel·L_g·P_amb/(R_u·T). The estimate is
    /// variable-step BDF's for a first-order method applied to the gel's content M_g(t):
    /// e = dt_n/(dt_n + dt_{n−1})·|ΔM_n − (dt_n/dt_{n−1})·ΔM_{n−1}| (the flow of this step
    /// against the last one's extrapolated), restarted at every profile breakpoint; the next
    /// step is 0.9·dt·√(tol/e). After a Richardson-extrapolated step at a steady pressure (a
    /// hold or a stop with every bubble shut) the estimate is that scheme's own, second order,
    /// e = dt³·|M[t₋₂, t₋₁, t, t + dt]| (the third divided difference of the content over this
    /// step and the two before it), and the next step 0.9·dt·∛(tol/e) (at
    /// `hold_tolerance_factor` × this tolerance). It costs nothing (the flows are summed
    /// anyway) and keeps a hold's steps short while the gel is still loading after a descent,
    /// where backward Euler's steps would otherwise grow to `max_step` and lag the loading. Default 1e-3: on a
    /// 20 min hold at 130 psi with `profiles/phantoms/hydrogel.toml` (600 s cap) the peak
    /// volume is 2.928 mm³ against 2.928 for a run with ¼ of every limit and a 5 s cap, and
    /// 2.845 (−2.8 %) without it; the Fig. 5 dive takes 1 307 + 499 steps instead of
    /// 1 298 + 471 (README "Time stepping"). Infinite switches it off.
    pub loading_tolerance: f64,
    /// Whether a hold or a deco stop with every bubble shut takes the descents' scheme:
    /// implicit steps Richardson-extrapolated (second order) and sized by the loading's
    /// second-order estimate (`loading_tolerance`), instead of backward Euler sized by the
    /// first-order one. Default true (27 Nov 2026; false before). Backward Euler's steps lag
    /// the gel's unloading at first order: on the demo's twenty dive runs (45 m / 25 min,
    /// `hydrogel-dive.toml`), against an evaluation with every step within 0.5 s and ¼ of
    /// every limit, the scores' mean distance goes from 1.50 % to 1.00 % (peak volume), 0.70 %
    /// to 0.29 % (peak supersaturation) and 1.68 % to 0.96 % (hazard) at the default
    /// `hold_tolerance_factor`, with the preset's cap raised from 30 to 600 s (with
    /// backward-Euler stops a 600 s cap had moved the scores 3–4 %), and the demo 6–9 % faster;
    /// README "Time stepping". `hydrogel.toml` sets false: on the Fig. 5 dive's 4 h hold the
    /// extrapolated steps cost 0.2–0.4 s more and move nothing (peak volume 6.5207–6.5210
    /// against 6.5205 mm³, R_max 848.08–848.18 against 848.14 µm).
    pub extrapolate_holds: bool,
    /// The loading's tolerance for the extrapolated steps of a hold or a stop with every bubble
    /// shut (`extrapolate_holds`, their second-order estimate), as a multiple of
    /// `loading_tolerance`. Default 10. `loading_tolerance` was set for backward-Euler steps,
    /// whose local errors add up with one sign (a lag); the extrapolated steps' are an order
    /// smaller. Measured on the demo's twenty dive runs against an evaluation with every step
    /// within 0.5 s and ¼ of every limit (mean distance of the peak volume growth / peak
    /// supersaturation / hazard): 1 / 3 / 10 / 30 give 0.96 / 0.98 / 1.00 / 1.02 %, 0.22 /
    /// 0.25 / 0.29 / 0.34 % and 0.90 / 0.92 / 0.96 / 0.98 %, against 1.50 %, 0.70 % and 1.68 %
    /// with the backward-Euler stops and 30 s cap of before; the GF 30/85 dive alone, one
    /// thread, took 0.90–0.94 / 0.80–0.82 / 0.73–0.75 / 0.69–0.73 s in 90 / 77 / 67 / 62
    /// extrapolated steps (before: 0.71–0.82 s).
    pub hold_tolerance_factor: f64,
    /// Radius of the bubble's sink kernel in the 3-D grid: max(R, this × h). Default 1.0.
    pub kernel_min_cells: f64,
    /// Gap between the kernel (or the surface layer) and the coupling sphere ρ at which the
    /// near field meets the 3-D field, in grid steps. Default 1.0 (the plateau radius of the
    /// convergence test moves 1 % from h = 100 to 50 µm with 1.0/1.0, 2 % with 1.5/1.5, 3.7 %
    /// with a gap of 2.5: the quasi-steady shell should be thin).
    pub coupling_gap_cells: f64,
    /// Interval between recorded frames, s. 0 = every step. Default 1.
    pub record_interval: f64,
    /// Whether every frame carries the gel's state (the pass over every cell for the largest
    /// supersaturation and the grid's gas, which also checks the gas balance at the frame).
    /// Default true; false (what `fit` and `discover` use, which read only the radii) computes
    /// it for the first and the last frame only: the others have `max_supersaturation` NaN and
    /// no `grid_moles`, the gas balance is checked at the end, and the run's lowest
    /// concentration is over those two frames. On a 60³ grid with a frame every step the pass
    /// costs about a third of the run.
    pub record_gel: bool,
    /// Cost of an implicit step in explicit steps: a step between the explicit limit and this
    /// many times [`super::diffusion::LimitScans::implicit_cost_unit`] (the explicit limit as it was before
    /// 26 Nov 2026, when the open sides were explicit: h²/(9D) on a grid with an open corner,
    /// ⅔ of today's limit there, the same on a sealed grid) is cut to the explicit limit
    /// instead. The unit was kept so that steps are implicit from the same length as before:
    /// with today's limit as the unit, 8 moved the Epstein–Plesset case of
    /// `tests/integration/bubble_steps.rs` to −0.31 % (beyond its 0.3 %) and 6 moved the
    /// surface-layer growth of `tests/integration/growth.rs` to +3.2 % (beyond its 3 %): the
    /// bubbles' error estimate, taken from explicit steps, lets the first implicit step after
    /// them overshoot its tolerance 2–5× (and steps are not rejected). Default 8, set when the
    /// kernels' ratio was 7.7 (`cargo bench --bench kernel`: 148 against 1 133 M cell-updates/s
    /// on 128×128×32) and kept for accuracy since: the kernels' ratio is now about 2–3, but at
    /// 4 and 3 two verification figures near growing bubbles leave their tolerances, and with
    /// no bubble exchanging, 3 and 2 moved the demo's peak supersaturation away from the
    /// all-explicit reference (README, "Time stepping" and "Speed"). 1 = always implicit above
    /// the explicit limit.
    pub implicit_cost_ratio: f64,
    /// Bubbles displace the gel ([`super::displacement`], issue 8 item 5): a bubble of radius
    /// at least `displace_min_cells`·h takes the cells inside it out of the gel and pushes the
    /// gel around it outward as it grows (back as it shrinks). Default true; false gives the
    /// paper's model, where the gel inside a bubble keeps diffusing.
    pub displace_gel: bool,
    /// Smallest radius that displaces the gel, in grid steps. Default 4: below it the cells
    /// inside the bubble draw a poor sphere, and the sub-grid sink is the more accurate model
    /// (the Epstein–Plesset case at R0 = 4h, `analytic::epstein_plesset_dissolution`: radius
    /// within 0.27 % of the displaced-gel solution with 4, 1.47 % with 2); the gel volume a
    /// sub-grid bubble overlaps, below (4/3)π(4h)³, vanishes as h → 0.
    pub displace_min_cells: f64,
    /// Change of radius between two displacements of the gel, in grid steps. Default 0.2
    /// (the displacement lags the wall by at most 0.2·h; 0.1 before 26 Nov 2026). On the
    /// Fig. 5 dive 0.1 / 0.15 / 0.2 give a peak volume of 6.533 / 6.523 / 6.520 mm³ and R_max
    /// 848.5 / 848.1 / 848.1 µm (every step within the explicit limit: 6.522 mm³, 849.9 µm),
    /// 0.2 in 2.74–2.76 s against 2.87–2.89 s; the 3-D growth against Scriven
    /// (`displacement::resolved_bubble_grows_as_scriven_with_convection`) +0.36 / +2.32 % at
    /// S = 9.9 / 3 with 0.2, +0.61 / +2.32 % with 0.1.
    pub displace_step_cells: f64,
    /// Reach of the displacement: the gel is moved out to this × R + 2h from the centre.
    /// Default 3 (see [`super::displacement`]).
    pub displace_reach: f64,
}

impl Default for Numerics {
    fn default() -> Self {
        Numerics {
            max_step: 20.0,
            max_pressure_change: 0.02,
            max_step_growth: 1.2,
            max_content_change: 0.03,
            bubble_tolerance: 0.004,
            explicit_tolerance_factor: 2.0,
            field_tolerance: f64::INFINITY,
            loading_tolerance: 1e-3,
            kernel_min_cells: 1.0,
            coupling_gap_cells: 1.0,
            record_interval: 1.0,
            record_gel: true,
            extrapolate_holds: true,
            hold_tolerance_factor: 10.0,
            implicit_cost_ratio: 8.0,
            displace_gel: true,
            displace_min_cells: 4.0,
            displace_step_cells: 0.2,
            displace_reach: 3.0,
        }
    }
}

/// Every setting of the phantom model.
#[derive(Debug, Clone)]
pub struct PhantomParams {
    /// Name for tables and legends.
    pub name: String,
    /// Shape and size.
    pub shape: Shape,
    /// Grid step h, m.
    pub grid_step: f64,
    /// Faces held at Henry equilibrium with the chamber/breathing gas; the others are sealed.
    /// Default: all but the bottom.
    pub open_faces: Vec<Face>,
    /// Temperature T, K. Default 310.15 (37 °C).
    pub temperature: f64,
    /// Surface tension γ, N/m (eq. 2.4; Table 1: 0.042–0.07). Default 0.07.
    pub surface_tension: f64,
    /// Tissue elasticity Ω(R) (eqs. 2.6–2.9). Default none.
    pub elasticity: Arc<dyn ElasticityLaw>,
    /// Surface permeability D_surf law. Default equal to D_bulk.
    pub surface: Arc<dyn SurfacePermeability>,
    /// Thickness δ of the surface layer in which D_surf applies, m. Default 20 µm: the grid step
    /// at which the paper fitted D_surf = D_bulk/30 (Fig. 4 caption, h = 2e-5 m), whose code
    /// sampled the surface gradient over one grid step.
    pub surface_layer_thickness: f64,
    /// Gas properties (every gas the profile uses must be listed).
    pub gases: Vec<GasProperties>,
    /// Nucleus radius R_min, m: at or below it the skin is impermeable (section 2.1.4).
    /// Default: h; 0 when the nucleation model is not `fixed` (activated micronuclei are far
    /// below h and must exchange gas to grow).
    pub min_radius: f64,
    /// Bubbles at t = 0.
    pub bubbles: BubblePlacement,
    /// Nucleation model (TOML `[nucleation]`): which sub-grid nuclei the gel holds and so where
    /// and when new bubbles appear. Default `fixed`: none, only the bubbles at t = 0.
    pub nucleation: Arc<dyn NucleationModel>,
    /// Perfusion rate k, 1/s (TOML `[perfusion] rate_per_s`). Default 0 (a gel has no blood
    /// flow). Every gel cell exchanges gas with blood in equilibrium with the inspired gas,
    /// the paper's §5 extension: ∂C/∂t = D∇²C − k·(C − L·p_insp(t)/(R_u·T)), with p_insp the
    /// partial pressure held at the open faces.
    pub perfusion_rate: f64,
    /// Fixed partial pressure of gases that are not simulated (water vapour, CO2, O2 when it is
    /// not a simulated gas) inside every bubble, Pa (TOML `[material] bubble_fixed_gases_pa`).
    /// Default 0 (a lab gel under chamber gas). The simulated gases then fill the bubble at
    /// P_B − p_fixed: (P_amb + 2γ/R + Ω(R) − p_fixed)·V = n·R_u·T and Henry's law at the
    /// interface is C_s,g = L_g·x_g·(P_B − p_fixed)/(R_u·T). A command's run whose history
    /// subtracts water vapour at the open faces holds at least that vapour in every bubble
    /// ([`PhantomParams::bubble_fixed_gases_for`], [`crate::run::params_for`]).
    pub bubble_fixed_gases: f64,
    /// Time-loop settings.
    pub numerics: Numerics,
}

impl PhantomParams {
    /// A bare phantom: a box of the given size and step, all faces but the bottom open,
    /// air-like gas properties (Table 1: D = 2.5e-9 m²/s as fitted for the hydrogel, L_N2 0.014,
    /// L_O2 0.027), γ = 0.07, Ω = 0, D_surf = D_bulk, no bubbles.
    pub fn box_phantom(size: [f64; 3], h: f64) -> PhantomParams {
        PhantomParams {
            name: "box".into(),
            shape: Shape::Box { size },
            grid_step: h,
            open_faces: vec![
                Face::XMinus,
                Face::XPlus,
                Face::YMinus,
                Face::YPlus,
                Face::Top,
            ],
            temperature: crate::units::BODY_TEMPERATURE_K,
            surface_tension: 0.07,
            elasticity: Arc::new(NoElasticity),
            surface: Arc::new(EqualToBulk),
            surface_layer_thickness: DEFAULT_SURFACE_LAYER,
            gases: vec![
                GasProperties {
                    gas: Gas::N2,
                    diffusivity: 2.5e-9,
                    ostwald: 0.014,
                },
                GasProperties {
                    gas: Gas::O2,
                    diffusivity: 2.5e-9,
                    ostwald: 0.027,
                },
            ],
            min_radius: h,
            bubbles: BubblePlacement::Explicit(Vec::new()),
            nucleation: Arc::new(Fixed),
            perfusion_rate: 0.0,
            bubble_fixed_gases: 0.0,
            numerics: Numerics::default(),
        }
    }

    /// Properties of one gas, if listed.
    pub fn gas(&self, g: Gas) -> Option<&GasProperties> {
        self.gases.iter().find(|p| p.gas == g)
    }

    /// Every gas the profile breathes has properties in the phantom (refused naming the
    /// missing `gases.<name>` table), and the profile breathes at least one simulated gas.
    pub fn check_gases_for(&self, profile: &PressureHistory) -> Result<(), InputError> {
        let gases = profile.gases();
        if gases.is_empty() {
            return Err(InputError::new(
                "the profile's gas contains no nitrogen, oxygen or helium",
            ));
        }
        match gases.iter().find(|g| self.gas(**g).is_none()) {
            Some(g) => Err(InputError::new(format!(
                "the profile uses {} but the phantom lists no properties for it; add [gases.{}] with diffusivity and ostwald",
                g.name(),
                g.name()
            ))
            .field(format!("gases.{}", g.name()))),
            None => Ok(()),
        }
    }

    /// The fixed partial pressure every bubble holds in a command's run of `profile`
    /// ([`crate::run::params_for`]), Pa: one water-vapour convention on both sides of the
    /// interface (issue 8). The open faces hold f_g·(P_amb − P_H2O) with
    /// P_H2O = `profile.vapour_pa`, so every bubble holds that vapour too:
    /// [`PhantomParams::bubble_fixed_gases`] when it is set, else (0) the history's vapour. A
    /// value set below the vapour is refused (the interface would start P_H2O − p_fixed
    /// unsaturated), naming both settings. `evaluate`/`check` set p_fixed from the criteria's
    /// `[protocol]` (P_H2O + P_CO2 + P_vO2 ≥ the P_H2O of their faces). Refused too where
    /// they would reach the profile's lowest ambient pressure.
    pub fn bubble_fixed_gases_for(&self, profile: &PressureHistory) -> Result<f64, InputError> {
        let fixed = self.paired_fixed_gases(profile)?;
        // the fixed gases alone at or above the ambient pressure would hold a bubble open at
        // any size: no radius satisfies the Laplace balance once the pressure gets there, and
        // the run would fail mid-way (tissue's are about 17 kPa: vapour, CO2, venous O2)
        let (at, lowest) = profile.times_s.iter().zip(&profile.ambient_pa).fold(
            (f64::NAN, f64::INFINITY),
            |a, (t, p)| {
                if *p < a.1 {
                    (*t, *p)
                } else {
                    a
                }
            },
        );
        if fixed > 0.0 && fixed >= lowest {
            return Err(InputError::new(format!(
                "the bubbles' fixed gases, {} Pa, reach the profile's lowest ambient pressure, {} Pa at t = {} s: the other gases alone would then hold a bubble open at any size and no radius satisfies the Laplace balance; lower material.bubble_fixed_gases_pa (tissue's water vapour, CO2 and venous O2 are about 17 kPa)",
                crate::error::num(fixed),
                crate::error::num(lowest),
                crate::error::num(at)
            ))
            .field("material.bubble_fixed_gases_pa"));
        }
        Ok(fixed)
    }

    /// The bubbles' fixed gases paired with the profile's water vapour
    /// ([`Self::bubble_fixed_gases_for`] before its check against the ambient pressure).
    fn paired_fixed_gases(&self, profile: &PressureHistory) -> Result<f64, InputError> {
        let (fixed, vapour) = (self.bubble_fixed_gases, profile.vapour_pa);
        if !(vapour > 0.0) {
            return Ok(fixed);
        }
        if fixed == 0.0 {
            return Ok(vapour);
        }
        if fixed < vapour {
            return Err(InputError::new(format!(
                "the phantom's material.bubble_fixed_gases_pa = {} Pa is below the water vapour the profile subtracts at the open faces (water_vapour_pa = {} Pa): every bubble holds at least that vapour, or its interface starts unsaturated by the difference; set bubble_fixed_gases_pa ≥ {} Pa, or leave it out (0) to take the profile's vapour",
                crate::error::num(fixed),
                crate::error::num(vapour),
                crate::error::num(vapour)
            ))
            .field("material.bubble_fixed_gases_pa"));
        }
        Ok(fixed)
    }
}
