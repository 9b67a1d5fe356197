//! Verification of the phantom model (the model issue's list, items 1, 2, 4 and 6, and the
//! surface-layer coupling). Every reference value is computed independently inside the test
//! from a closed form or an analytic series, or is a published direction (item 6).

use decophantom::gas::{Gas, GasMix};
use decophantom::phantom::bubble::Balance;
use decophantom::phantom::elasticity::{law_names, AllLawParams, Hyperelastic};
use decophantom::phantom::grid::Face;
use decophantom::phantom::params::{BubblePlacement, GasProperties, PhantomParams};
use decophantom::phantom::sim::{Recorder, RunSummary, Simulation};
use decophantom::phantom::surface::{AreaLaw, EqualToBulk, Fold};
use decophantom::profile::PressureHistory;
use decophantom::units::{GAS_CONSTANT, MSW_PA, PSI_PA};
use std::f64::consts::PI;
use std::sync::Arc;

/// Pure nitrogen as chamber gas (N2 is the balance of a mix with no O2 and no He).
const PURE_N2: GasMix = GasMix { o2: 0.0, he: 0.0 };

// ---------------------------------------------------------------------------------------
// Item 1: no mass transfer (Boyle + Laplace + Ω)
// ---------------------------------------------------------------------------------------

/// The paper's Fig. 2a case (section 2.1.2): decompression from 1e6 to 1e4 Pa without mass
/// transfer; M = 5e-2 Pa/µm³ = 5e16 Pa/m³ (ref. [38] of the paper), K = 2.2 GPa (ref. [45]);
/// γ = 0.07 N/m and μ = 40 Pa as the model issue states (Table 1's upper γ).
const FIG2_P0: f64 = 1e6;
const FIG2_PF: f64 = 1e4;
const FIG2_GAMMA: f64 = 0.07;
const FIG2_MU: f64 = 40.0;
const FIG2_M: f64 = 5e16;
const FIG2_K: f64 = 2.2e9;

/// Ω(R) written out from the paper's equations, independently of the library's laws:
/// (2.6) bulk modulus (4/3)πR³M; (2.7) continuity of displacement −4μ/3; (2.8) reference
/// configuration 4μ[(1 − P0/3K)R/R0 − (1 − P_amb/3K)]; (2.9) hyperelastic
/// (μ/2)[5 − 4(R/R0)⁻¹ − (R/R0)⁻⁴]; "none" is Ω = 0.
fn omega_paper(law: &str, mu: f64, r: f64, r0: f64, p_amb: f64, p0: f64) -> f64 {
    match law {
        "none" => 0.0,
        "bulk-modulus" => 4.0 / 3.0 * PI * r.powi(3) * FIG2_M,
        "continuity-of-displacement" => -4.0 * mu / 3.0,
        "reference-configuration" => {
            4.0 * mu * ((1.0 - p0 / (3.0 * FIG2_K)) * r / r0 - (1.0 - p_amb / (3.0 * FIG2_K)))
        }
        "hyperelastic" => {
            let s = r / r0;
            mu / 2.0 * (5.0 - 4.0 / s - s.powi(-4))
        }
        other => panic!("the test does not know law '{other}'"),
    }
}

/// Independent root solve of the no-mass-transfer balance. The gas content is fixed by the
/// Laplace balance at P0 and R0: nR_uT = (P0 + 2γ/R0 + Ω(R0; P0))·V(R0). The final radius
/// is the smallest zero (crossing from − to +) of the pressure form
/// g(s) = P_f + 2γ/R + Ω(R) − nR_uT/V(R), R = eˢ, found by a scan in log R (1e-9 … 10 m,
/// 0.2 % steps) and plain bisection. `None` if g never crosses.
fn reference_final_radius(law: &str, mu: f64, r0: f64) -> Option<f64> {
    let vol = |r: f64| 4.0 / 3.0 * PI * r.powi(3);
    let nrt = (FIG2_P0 + 2.0 * FIG2_GAMMA / r0 + omega_paper(law, mu, r0, r0, FIG2_P0, FIG2_P0))
        * vol(r0);
    let g = |s: f64| {
        let r = s.exp();
        FIG2_PF + 2.0 * FIG2_GAMMA / r + omega_paper(law, mu, r, r0, FIG2_PF, FIG2_P0)
            - nrt / vol(r)
    };
    let (lo, hi) = (1e-9f64.ln(), 10f64.ln());
    let ds = 0.002;
    let mut a = lo;
    let mut ga = g(a);
    while a < hi {
        let b = (a + ds).min(hi);
        let gb = g(b);
        if ga < 0.0 && gb >= 0.0 {
            let (mut x, mut y) = (a, b);
            for _ in 0..200 {
                let m = 0.5 * (x + y);
                if g(m) < 0.0 {
                    x = m;
                } else {
                    y = m;
                }
            }
            return Some((0.5 * (x + y)).exp());
        }
        a = b;
        ga = gb;
    }
    None
}

fn fig2_balance<'a>(
    law: &'a dyn decophantom::phantom::elasticity::ElasticityLaw,
    r0: f64,
    ambient: f64,
) -> Balance<'a> {
    Balance {
        ambient,
        surface_tension: FIG2_GAMMA,
        law,
        initial_radius: r0,
        initial_ambient: FIG2_P0,
        fixed_gases: 0.0,
    }
}

/// Item 1. The registry's five laws are the "six laws (five plus Ω = 0)": the issue
/// counts Ω = 0 separately from the paper's four forms plus hyperelastic, while the registry
/// lists it as the law "none"; so these five cover all six cases (the "bulk modulus"
/// is the paper's (2.6), whose text calls the four forms plus Ω = 0 "five").
#[test]
fn no_mass_transfer_final_radius_matches_closed_form_balance() {
    let all = AllLawParams {
        shear_modulus: FIG2_MU,
        bulk_modulus_per_volume: FIG2_M,
        bulk_modulus: FIG2_K,
    };
    let names = law_names();
    assert_eq!(names.len(), 5, "expected the five registered laws");
    let r0s = [1e-6, 3e-6, 10e-6, 30e-6, 100e-6, 300e-6, 1e-3];
    let mut compared = 0;
    for name in &names {
        let law = all.build(name).unwrap();
        for &r0 in &r0s {
            let nrt = fig2_balance(law.as_ref(), r0, FIG2_P0).pv(r0);
            let got = fig2_balance(law.as_ref(), r0, FIG2_PF).radius_for(nrt, r0);
            let want = reference_final_radius(name, FIG2_MU, r0);
            match (got, want) {
                (Some(g), Some(w)) => {
                    assert!(
                        (g / w - 1.0).abs() < 1e-6,
                        "{name}, R0 = {r0:e} m: library {g:e} m vs closed form {w:e} m"
                    );
                    compared += 1;
                }
                (None, None) => {}
                (g, w) => panic!("{name}, R0 = {r0:e} m: library {g:?} vs closed form {w:?}"),
            }
        }
    }
    // With these parameters every case has a physical root (Fig. 2a plots all of them).
    assert_eq!(compared, names.len() * r0s.len());

    // A case without a physical root: continuity of displacement with 4μ/3 > P_f (μ = 1e4 Pa).
    // Then P·V = (4π/3)[(P_f − 4μ/3)R³ + 2γR²] peaks at R* = 4γ/(3(4μ/3 − P_f)) with the value
    // (4π/3)(2γ/3)R*² (set the derivative to zero), far below the gas a 100 µm bubble held at
    // 1e6 Pa: no radius balances it.
    let mu = 1e4;
    let r0 = 100e-6;
    let law = AllLawParams {
        shear_modulus: mu,
        ..all
    }
    .build("continuity-of-displacement")
    .unwrap();
    let nrt = fig2_balance(law.as_ref(), r0, FIG2_P0).pv(r0);
    let r_star = 4.0 * FIG2_GAMMA / (3.0 * (4.0 * mu / 3.0 - FIG2_PF));
    let pv_max = 4.0 / 3.0 * PI * (2.0 * FIG2_GAMMA / 3.0) * r_star * r_star;
    assert!(pv_max < nrt, "the chosen case must have no root");
    assert_eq!(
        reference_final_radius("continuity-of-displacement", mu, r0),
        None
    );
    assert_eq!(
        fig2_balance(law.as_ref(), r0, FIG2_PF).radius_for(nrt, r0),
        None,
        "the library must report no physical root"
    );
}

/// Item 1, through the time loop: an impermeable bubble (R_min above every radius reached)
/// under a pressure ramp 1e6 → 1e4 Pa ends at the closed-form no-mass-transfer radius, for
/// every law, and keeps its gas exactly.
#[test]
fn no_mass_transfer_through_the_time_loop() {
    let all = AllLawParams {
        shear_modulus: FIG2_MU,
        bulk_modulus_per_volume: FIG2_M,
        bulk_modulus: FIG2_K,
    };
    let r0 = 20e-6;
    let h = 100e-6;
    let profile = PressureHistory::with_gas(
        "fig2-ramp",
        vec![0.0, 60.0],
        vec![FIG2_P0, FIG2_PF],
        GasMix::AIR,
        0.0,
    )
    .unwrap();
    for name in law_names() {
        let mut params = PhantomParams::box_phantom([1.2e-3; 3], h);
        params.surface_tension = FIG2_GAMMA;
        params.elasticity = Arc::from(all.build(name).unwrap());
        params.min_radius = 1.0; // above every radius: no gas exchange (section 2.1.4)
        params.bubbles = BubblePlacement::Explicit(vec![([0.6e-3; 3], r0)]);
        params.numerics.record_interval = 10.0;
        let mut sim = Simulation::new(&params, &profile).unwrap();
        let n0 = sim.bubbles[0].total_moles();
        let s = sim.run(&profile, &mut Recorder::default()).unwrap();
        let want = reference_final_radius(name, FIG2_MU, r0).unwrap();
        let got = s.final_radii[0];
        assert!(
            (got / want - 1.0).abs() < 1e-6,
            "{name}: simulated {got:e} m vs closed form {want:e} m"
        );
        assert_eq!(sim.bubbles[0].total_moles(), n0, "{name}: gas changed");
        assert!(s.steps.0 + s.steps.1 > 100, "the ramp must take many steps");
    }
}

// ---------------------------------------------------------------------------------------
// Item 2: diffusion alone in an open cube
// ---------------------------------------------------------------------------------------

/// Dirichlet cube [0, L]³, uniform initial value 1, faces 0: the solution is the product of
/// three 1-D series (separation of variables; Carslaw & Jaeger, Conduction of Heat in Solids,
/// §3.3): X(ξ, τ) = Σ_n (4/π)/(2n+1)·sin((2n+1)πξ)·exp(−(2n+1)²π²τ), ξ = x/L, τ = Dt/L².
/// At the centre sin((2n+1)π/2) = (−1)ⁿ, giving the S(t).
fn slab_series(xi: f64, tau: f64) -> f64 {
    (0..400)
        .map(|n| {
            let m = (2 * n + 1) as f64;
            4.0 / PI / m * (m * PI * xi).sin() * (-m * m * PI * PI * tau).exp()
        })
        .sum()
}

const DIFF_D: f64 = 1e-9;
const DIFF_L_N2: f64 = 0.014;
const DIFF_P_START: f64 = 2e5;
const DIFF_P_CHAMBER: f64 = 1e5;

/// An open cube of `n` cells of step `h` (modelled extent L = n·h), pure N2, the field set
/// uniformly to Henry equilibrium with `DIFF_P_START` while the faces hold equilibrium with
/// `DIFF_P_CHAMBER`. Runs to each dimensionless time τ = Dt/L² in turn and returns, per τ,
/// the field relative to the initial difference, (C − C_b)/(C_0 − C_b), and the run summary.
fn open_cube(n: usize, h: f64, max_step: f64, taus: &[f64]) -> Vec<(Vec<f64>, RunSummary)> {
    open_cube_with(n, h, max_step, f64::INFINITY, taus)
}

/// A cube of side `l`, grid step `h`, open on every face, pure N2 (`DIFF_D`, `DIFF_L_N2`).
fn open_cube_params(l: f64, h: f64) -> PhantomParams {
    let mut params = PhantomParams::box_phantom([l; 3], h);
    params.gases = vec![GasProperties {
        gas: Gas::N2,
        diffusivity: DIFF_D,
        ostwald: DIFF_L_N2,
    }];
    params.open_faces = params.shape.faces().to_vec();
    params
}

/// [`open_cube`] with the field's error control at `field_tolerance` (fraction of ambient).
fn open_cube_with(
    n: usize,
    h: f64,
    max_step: f64,
    field_tolerance: f64,
    taus: &[f64],
) -> Vec<(Vec<f64>, RunSummary)> {
    let l = n as f64 * h;
    let mut params = open_cube_params(l, h);
    params.numerics.max_step = max_step;
    params.numerics.field_tolerance = field_tolerance;
    // take an implicit step whenever the step exceeds the explicit limit (no cost-based cut)
    params.numerics.implicit_cost_ratio = 1.0;
    params.numerics.record_interval = 1e9;
    let rt = GAS_CONSTANT * params.temperature;
    let c0 = DIFF_L_N2 * DIFF_P_START / rt;
    let cb = DIFF_L_N2 * DIFF_P_CHAMBER / rt;
    let flat = |t: f64| {
        PressureHistory::with_gas("step", vec![0.0, t], vec![DIFF_P_CHAMBER; 2], PURE_N2, 0.0)
            .unwrap()
    };
    let mut sim = Simulation::new(&params, &flat(1.0)).unwrap();
    assert_eq!(sim.grid().n, [n; 3]);
    for x in sim.field_mut(0).iter_mut() {
        *x = c0;
    }
    sim.rebase_balance();
    let mut out = Vec::new();
    for &tau in taus {
        let t = tau * l * l / DIFF_D;
        let s = sim.run(&flat(t), &mut Recorder::default()).unwrap();
        assert!((sim.time() - t).abs() < 1e-9 * t);
        let rel = sim.field(0).iter().map(|c| (c - cb) / (c0 - cb)).collect();
        out.push((rel, s));
    }
    out
}

/// Largest error over all cells against the 3-D product series, relative to C_0 − C_b.
fn field_error(rel: &[f64], n: usize, tau: f64) -> f64 {
    let x: Vec<f64> = (0..n)
        .map(|i| slab_series((i as f64 + 0.5) / n as f64, tau))
        .collect();
    let mut worst: f64 = 0.0;
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let e = (rel[i + n * (j + n * k)] - x[i] * x[j] * x[k]).abs();
                worst = worst.max(e);
            }
        }
    }
    worst
}

/// Item 2: the centre of an open 21³ cube against the Fourier series, within 1 % of the initial
/// difference, with the explicit scheme (steps at the positivity limit h²/(6D), as runs take
/// them; the open faces implicit) and the implicit one (steps up to L²/(1000 D), 2.6 times that
/// limit; backward Euler is first order in time, so its error grows with the step).
#[test]
fn diffusion_in_an_open_cube_matches_the_fourier_series() {
    let (n, h) = (21usize, 1e-4);
    let l = n as f64 * h;
    // six interior sides; the open faces are implicit (`diffusion::explicit_limit`)
    let explicit_limit = h * h / (6.0 * DIFF_D);
    let taus = [0.02, 0.04, 0.07, 0.1, 0.15, 0.25];
    let centre = (n / 2) + n * ((n / 2) + n * (n / 2));
    for (scheme, max_step) in [
        ("explicit", explicit_limit),
        ("implicit", l * l / (1000.0 * DIFF_D)),
    ] {
        let runs = open_cube(n, h, max_step, &taus);
        let mut steps = (0, 0);
        for (tau, (rel, s)) in taus.iter().zip(&runs) {
            let s3 = slab_series(0.5, *tau).powi(3);
            let got = rel[centre];
            eprintln!("{scheme}: τ = {tau}: centre {got:.5} vs series {s3:.5}");
            // Backward Euler carries the boundary step to the centre at once, so at the
            // earliest time (front not yet at the centre, 93 % of the difference left) the
            // implicit run is 1.2 % low with this step (0.7 % with half of it); from τ = 0.04
            // on it is within 0.4 %.
            let tol = if scheme == "implicit" && *tau < 0.03 {
                0.015
            } else {
                0.01
            };
            assert!(
                (got - s3).abs() < tol,
                "{scheme}, τ = {tau}: centre {got:.5} vs Fourier series {s3:.5}"
            );
            assert!(
                s.gas_balance_error < 1e-10,
                "{scheme}: balance {}",
                s.gas_balance_error
            );
            steps.0 += s.steps.0;
            steps.1 += s.steps.1;
        }
        // the centre has moved through most of its range
        assert!(slab_series(0.5, taus[0]).powi(3) > 0.9 && runs.last().unwrap().0[centre] < 0.2);
        match scheme {
            "explicit" => assert_eq!(steps.1, 0, "explicit run took implicit steps"),
            // (the explicit ones: the short last step before each of the six times)
            _ => assert!(
                steps.1 > 10 * steps.0.max(1),
                "implicit run mostly explicit: {steps:?}"
            ),
        }
    }
}

/// Issue 13: steps sized by the field's error estimate instead of a cap. The open cube with
/// no step cap (1 day) and `field_tolerance` 1e-3, 1e-4 and 1e-5, against the same grid run
/// with explicit steps at a quarter of the positivity limit (time error only, ~100× below the
/// controlled runs'): the largest error over the field at τ ≥ 0.1 shrinks as the tolerance
/// does (2.6× per decade when written: 0.0049, 0.0019, 0.0007 at τ ≥ 0.1; backward
/// Euler is first order and the controlled steps go as √tol: ×10 tighter is about ×3 more
/// steps and ×3 less error, but below the explicit limit h²/(6D) the steps are explicit, not
/// controlled, so the count grows less at the tightest tolerance: 63, 133, 249 steps when
/// written), and the centre stays within the fixed-step test's bounds of the Fourier series.
#[test]
fn field_error_control_sizes_the_steps_on_the_open_cube() {
    let (n, h) = (15usize, 1e-4);
    let taus = [0.02, 0.04, 0.1, 0.25];
    let centre = (n / 2) + n * ((n / 2) + n * (n / 2));
    let reference = open_cube(n, h, 0.25 * h * h / (9.0 * DIFF_D), &taus);
    let mut rows = Vec::new();
    for tol in [1e-3, 1e-4, 1e-5] {
        let runs = open_cube_with(n, h, 86400.0, tol, &taus);
        let mut worst: f64 = 0.0;
        for ((tau, (rel, _)), (want, _)) in taus.iter().zip(&runs).zip(&reference) {
            let e = rel
                .iter()
                .zip(want)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f64, f64::max);
            eprintln!("  tol {tol:e}, τ = {tau}: largest time error over the field {e:.5}");
            // the error the control governs: after the start (whose first steps, taken before
            // the estimate has a history, set the early error)
            if *tau >= 0.1 {
                worst = worst.max(e);
            }
            // as in the fixed-step test: 1.5 % before the front reaches the centre
            let bound = if *tau < 0.03 { 0.015 } else { 0.01 };
            let off = (rel[centre] - slab_series(0.5, *tau).powi(3)).abs();
            assert!(off < bound, "tol {tol}, τ = {tau}: centre off by {off:.4}");
        }
        let steps: usize = runs.iter().map(|(_, s)| s.steps.0 + s.steps.1).sum();
        eprintln!(
            "field_tolerance {tol:e}: largest time error at τ ≥ 0.1 {worst:.5}, {steps} steps"
        );
        rows.push((worst, steps));
    }
    for w in rows.windows(2) {
        assert!(w[1].0 < 0.6 * w[0].0, "error did not shrink: {rows:?}");
        assert!(2 * w[1].1 > 3 * w[0].1, "steps did not grow: {rows:?}");
    }
}

/// Item 2, grid refinement: the largest error over the whole field (explicit scheme, steps
/// ∝ h²) shrinks when h halves at fixed L; the scheme is second order, so by about 4× (3.9×
/// measured when written).
#[test]
fn diffusion_error_shrinks_with_the_grid_step() {
    let l = 1.6e-3;
    let taus = [0.03, 0.08];
    let mut errs = Vec::new();
    for n in [8usize, 16] {
        let h = l / n as f64;
        let runs = open_cube(n, h, 0.5 * h * h / (9.0 * DIFF_D), &taus);
        let e: Vec<f64> = taus
            .iter()
            .zip(&runs)
            .map(|(tau, (rel, _))| field_error(rel, n, *tau))
            .collect();
        eprintln!("n = {n}: max field errors {e:?}");
        errs.push(e);
    }
    for k in 0..taus.len() {
        assert!(
            errs[1][k] < 0.35 * errs[0][k],
            "τ = {}: error {} at h vs {} at h/2",
            taus[k],
            errs[0][k],
            errs[1][k]
        );
    }
}

// ---------------------------------------------------------------------------------------
// Item 4: conservation
// ---------------------------------------------------------------------------------------

/// A 1.5 mm cube (h = 100 µm) with five bubbles: four permeable (R0 = 150 µm > R_min = 20 µm)
/// and one nucleus (R0 = 15 µm < R_min) that opens only if Boyle growth takes it past R_min;
/// γ = 0.07 N/m, hyperelastic μ = 5 kPa, D_surf by the paper-text area law with k = 30.
fn conservation_params(open: Vec<Face>) -> PhantomParams {
    let mut p = PhantomParams::box_phantom([1.5e-3; 3], 100e-6);
    p.open_faces = open;
    p.surface_tension = 0.07;
    p.elasticity = Arc::new(Hyperelastic { shear_modulus: 5e3 });
    p.surface = Arc::new(AreaLaw {
        fold: 30.0,
        reference_radius_m: None,
        exponent: 2.0,
        cap_at_bulk: true,
    });
    p.min_radius = 20e-6;
    p.bubbles = BubblePlacement::Explicit(vec![
        ([0.45e-3, 0.45e-3, 0.45e-3], 150e-6),
        ([1.05e-3, 0.45e-3, 0.75e-3], 150e-6),
        ([0.45e-3, 1.05e-3, 1.05e-3], 150e-6),
        ([1.05e-3, 1.05e-3, 0.45e-3], 150e-6),
        ([0.75e-3, 0.75e-3, 0.75e-3], 15e-6),
    ]);
    p.numerics.record_interval = 30.0;
    p
}

/// The paper's Fig. 5 dive shape, shortened: 1 psi/s to 130 psi gauge (≈ 1.0e6 Pa absolute),
/// 10 min hold, decompression at 10 psi/s, 10 min of growth at the surface; air.
fn dive_profile() -> PressureHistory {
    let surface = 101_325.0;
    let bottom = surface + 130.0 * PSI_PA;
    PressureHistory::with_gas(
        "dive",
        vec![0.0, 130.0, 730.0, 743.0, 1343.0],
        vec![surface, bottom, bottom, surface, surface],
        GasMix::AIR,
        0.0,
    )
    .unwrap()
}

/// Item 4: sealed phantom, total gas (grid + bubbles, and the gas the bubbles' displacement
/// carried out of the modelled gel) constant to 1e-9 relative over the dive;
/// with open faces the balance error (which counts the gas that came in through the faces) is
/// below 1e-9 too.
#[test]
fn total_gas_is_conserved_over_a_dive() {
    let profile = dive_profile();
    for open in [
        vec![],
        PhantomParams::box_phantom([1e-3; 3], 1e-4).open_faces,
    ] {
        let sealed = open.is_empty();
        let params = conservation_params(open);
        let mut sim = Simulation::new(&params, &profile).unwrap();
        let total0 = sim.total_moles();
        let n0: Vec<f64> = sim.bubbles.iter().map(|b| b.total_moles()).collect();
        let mut rec = Recorder::default();
        let s = sim.run(&profile, &mut rec).unwrap();
        let total1 = sim.total_moles();
        // largest relative change of any bubble's gas content over the run
        let exchanged = rec
            .frames
            .iter()
            .flat_map(|f| f.bubbles.iter())
            .map(|b| (b.moles.iter().sum::<f64>() / n0[b.id] - 1.0).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "sealed {sealed}: {:?}, steps {:?}, final radii {:?}, events {}, exchanged {exchanged:.3}, balance {:e}, drift {:e}",
            s.ending,
            s.steps,
            s.final_radii,
            s.events.len(),
            s.gas_balance_error,
            total1 / total0 - 1.0
        );
        assert_eq!(
            s.end_time,
            profile.duration_s(),
            "the dive must run to its end"
        );
        assert!(s.steps.0 > 0 && s.steps.1 > 0, "both schemes must be used");
        // the bubbles really exchanged gas with the gel
        assert!(exchanged > 0.1, "bubbles exchanged little gas: {exchanged}");
        assert!(
            s.gas_balance_error < 1e-9,
            "balance {:e}",
            s.gas_balance_error
        );
        if sealed {
            // what the bubbles' displacement carried out of the modelled gel is counted apart
            // (src/phantom/displacement.rs); everything else is conserved to round-off
            let displaced = sim.displaced_gas();
            assert!(
                ((total1 - displaced) / total0 - 1.0).abs() < 1e-9,
                "sealed phantom: total gas drifted by {:e} (displaced {:e})",
                total1 / total0 - 1.0,
                displaced / total0
            );
        }
    }
}

// ---------------------------------------------------------------------------------------
// The surface layer (D_surf) coupling
// ---------------------------------------------------------------------------------------

/// One 100 µm pure-N2 bubble (γ = 0.07, Ω = 0) in a 1.2 mm open cube whose gel was saturated at
/// 2e5 Pa; the chamber drops to 1e5 Pa in 1 s and holds, so the bubble grows. Every step recorded.
fn surface_case(
    surface: Arc<dyn decophantom::phantom::surface::SurfacePermeability>,
) -> (PhantomParams, Vec<decophantom::phantom::sim::Frame>) {
    let mut p = PhantomParams::box_phantom([1.2e-3; 3], 100e-6);
    p.gases = vec![GasProperties {
        gas: Gas::N2,
        diffusivity: 2e-9,
        ostwald: 0.014,
    }];
    p.surface = surface;
    p.min_radius = 1e-6;
    p.bubbles = BubblePlacement::Explicit(vec![([0.6e-3; 3], 100e-6)]);
    p.numerics.record_interval = 0.0;
    let profile = PressureHistory::with_gas(
        "drop",
        vec![0.0, 1.0, 60.0],
        vec![2e5, 1e5, 1e5],
        PURE_N2,
        0.0,
    )
    .unwrap();
    let mut sim = Simulation::new(&p, &profile).unwrap();
    let mut rec = Recorder::default();
    let s = sim.run(&profile, &mut rec).unwrap();
    assert_eq!(
        rec.frames.len(),
        s.steps.0 + s.steps.1 + 1,
        "one frame per step"
    );
    (p, rec.frames)
}

/// Law "equal" and law "fold" with k = 1 give identical histories, and with D_surf = D_bulk/30
/// the bubble grows more slowly. Whether the layer's flux is right is not judged here against the
/// code's own formula but in `growth::growth_with_a_surface_layer_matches_the_resolved_reference`,
/// against an independent, fully resolved 1-D solution with the layer (D_surf = D, D/10, D/30).
#[test]
fn surface_layer_reduces_to_the_henry_interface() {
    let (_, equal) = surface_case(Arc::new(EqualToBulk));
    let (_, fold1) = surface_case(Arc::new(Fold { fold: 1.0 }));
    let (_, fold30) = surface_case(Arc::new(Fold { fold: 30.0 }));
    assert_eq!(equal, fold1, "law 'equal' and 'fold' with k = 1 differ");

    // D_surf < D_bulk: slower growth throughout.
    let r_at = |frames: &[decophantom::phantom::sim::Frame], t: f64| {
        let k = frames.partition_point(|f| f.time < t);
        frames[k.min(frames.len() - 1)].bubbles[0].radius
    };
    for t in [10.0, 30.0, 60.0] {
        let (fast, slow) = (r_at(&equal, t), r_at(&fold30, t));
        eprintln!("t = {t}: R equal {fast:e}, R fold30 {slow:e}");
        assert!(
            fast > slow && slow > 100e-6,
            "t = {t} s: D_surf = D_bulk gives {fast:e} m, D_bulk/30 gives {slow:e} m"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Item 6: the paper's sensitivity directions (section 2.3.1, Fig. 3)
// ---------------------------------------------------------------------------------------

/// Fig. 3's modal parameters (caption): γ = 0.056 N/m, L_N2 = 0.0436, L_O2 = 0.02,
/// μ = 2e6 Pa (hyperelastic), D = 1.4e-9 m²/s.
#[derive(Debug, Clone, Copy)]
struct Fig3 {
    gamma: f64,
    l_n2: f64,
    l_o2: f64,
    mu: f64,
    d: f64,
}

const FIG3_MODAL: Fig3 = Fig3 {
    gamma: 0.056,
    l_n2: 0.0436,
    l_o2: 0.02,
    mu: 2e6,
    d: 1.4e-9,
};

/// Section 2.3.1: a single bubble R0 = h = R_min = 40 µm at the centre of a 1.28 mm cube,
/// saturated with air at 30 msw, ascent to the surface in 3.75 min, then held `hold` s.
/// Default open faces (all but the bottom).
struct Fig3Result {
    /// R_max, m.
    r_max: f64,
    /// t_max, s.
    t_max: f64,
    /// Final radius, m.
    r_final: f64,
    /// Largest |n/n0 − 1| of the bubble's gas over the run.
    exchanged: f64,
    /// Largest radius over the run's first 60 s (Boyle growth opens the skin), m.
    r_early: f64,
}

fn fig3_run(c: Fig3, hold: f64) -> Fig3Result {
    let h = 40e-6;
    let mut p = PhantomParams::box_phantom([1.28e-3; 3], h);
    p.surface_tension = c.gamma;
    p.elasticity = Arc::new(Hyperelastic {
        shear_modulus: c.mu,
    });
    p.gases = vec![
        GasProperties {
            gas: Gas::N2,
            diffusivity: c.d,
            ostwald: c.l_n2,
        },
        GasProperties {
            gas: Gas::O2,
            diffusivity: c.d,
            ostwald: c.l_o2,
        },
    ];
    p.min_radius = h;
    p.bubbles = BubblePlacement::Explicit(vec![([0.64e-3; 3], h)]);
    p.numerics.record_interval = 5.0;
    let surface = 101_325.0;
    let profile = PressureHistory::with_gas(
        "fig3",
        vec![0.0, 225.0, 225.0 + hold],
        vec![surface + 30.0 * MSW_PA, surface, surface],
        GasMix::AIR,
        0.0,
    )
    .unwrap();
    let mut sim = Simulation::new(&p, &profile).unwrap();
    let n0 = sim.bubbles[0].total_moles();
    let mut rec = Recorder::default();
    let s = sim.run(&profile, &mut rec).unwrap();
    assert_eq!(s.end_time, profile.duration_s());
    let bubble = |f: &decophantom::phantom::sim::Frame| f.bubbles.first().cloned();
    Fig3Result {
        r_max: s.max_radius.0,
        t_max: s.max_radius.1,
        r_final: s.final_radii[0],
        exchanged: rec
            .frames
            .iter()
            .filter_map(bubble)
            .map(|b| (b.moles.iter().sum::<f64>() / n0 - 1.0).abs())
            .fold(0.0, f64::max),
        r_early: rec
            .frames
            .iter()
            .filter(|f| f.time <= 60.0)
            .filter_map(bubble)
            .map(|b| b.radius)
            .fold(0.0, f64::max),
    }
}

/// Runs the base case and each parameter at ×0.75 and ×1.25 (in parallel); returns, per
/// parameter, (R_max at ×0.75, R_max at ×1.25), after checking every run opened its skin by
/// Boyle growth, exchanged gas and passed its maximum before the end.
fn fig3_sweep(base: Fig3, hold: f64) -> Vec<(&'static str, f64, f64)> {
    use rayon::prelude::*;
    type Perturb = fn(Fig3, f64) -> Fig3;
    let params: [(&str, Perturb); 5] = [
        ("D", |c, f| Fig3 { d: c.d * f, ..c }),
        ("mu", |c, f| Fig3 { mu: c.mu * f, ..c }),
        ("gamma", |c, f| Fig3 {
            gamma: c.gamma * f,
            ..c
        }),
        ("L_N2", |c, f| Fig3 {
            l_n2: c.l_n2 * f,
            ..c
        }),
        ("L_O2", |c, f| Fig3 {
            l_o2: c.l_o2 * f,
            ..c
        }),
    ];
    let mut cases = vec![("base", 1.0, base)];
    for (name, perturb) in params {
        for f in [0.75, 1.25] {
            cases.push((name, f, perturb(base, f)));
        }
    }
    let results: Vec<Fig3Result> = cases.par_iter().map(|c| fig3_run(c.2, hold)).collect();
    for ((name, f, _), r) in cases.iter().zip(&results) {
        eprintln!(
            "μ0 = {:.0e}: {name} ×{f}: R_max {:.3} µm at {:.0} s, final {:.3} µm, gas exchanged {:.2}",
            base.mu,
            r.r_max * 1e6,
            r.t_max,
            r.r_final * 1e6,
            r.exchanged
        );
        assert!(
            r.r_early > 40e-6,
            "{name} ×{f}: Boyle growth did not open the skin"
        );
        assert!(
            r.exchanged > 0.05,
            "{name} ×{f}: the bubble exchanged no gas"
        );
        assert!(
            r.t_max < 225.0 + hold / 2.0 && r.r_final < r.r_max,
            "{name} ×{f}: R_max not passed"
        );
    }
    params
        .iter()
        .enumerate()
        .map(|(k, (name, _))| (*name, results[1 + 2 * k].r_max, results[2 + 2 * k].r_max))
        .collect()
}

/// Item 6, Fig. 3 (section 2.3.1): raising D, μ or γ lowers R_max; raising L_N2 or L_O2
/// raises it. Each parameter ±25 % about the base, one run each.
///
/// At the caption's modal μ = 2 MPa the hyperelastic term pins the bubble: Ω rises towards
/// 2.5μ = 5 MPa within a few per cent of strain (dΩ/dR = 4μ/R0 at R0), far above the 0.3 MPa
/// supersaturation of a 30 msw saturation, so the bubble only follows the Boyle expansion of the
/// ascent (R ≈ 1.04 R0), reaches R_max at the surface and then loses gas to the desaturating gel.
/// There D, μ and γ keep the paper's directions, but the solubilities reverse: a larger L makes
/// the exchange faster, so the bubble loses its gas faster (R_max 40.543 µm at L_N2 ×1.25 vs
/// 40.567 µm at ×0.75 when written). The paper's growth regime, in which the bubble takes up gas from the
/// supersaturated gel, needs a softer gel: at μ = 20 kPa (within Table 1's 0–4 MPa) the bubble
/// grows to ≈ 2.8 R0 by diffusion, and all five directions of Fig. 3 hold.
#[test]
fn fig3_sensitivity_directions() {
    let lowers = ["D", "mu", "gamma"];
    let raises = ["L_N2", "L_O2"];
    // the growth regime: all five directions
    for (name, lo, hi) in fig3_sweep(
        Fig3 {
            mu: 2e4,
            ..FIG3_MODAL
        },
        1800.0,
    ) {
        if lowers.contains(&name) {
            assert!(
                hi < lo,
                "μ = 20 kPa: raising {name} must lower R_max ({lo:e} → {hi:e})"
            );
        } else {
            assert!(raises.contains(&name));
            assert!(
                hi > lo,
                "μ = 20 kPa: raising {name} must raise R_max ({lo:e} → {hi:e})"
            );
        }
    }
    // the modal point of the caption: D, μ, γ directions (see above for the solubilities)
    for (name, lo, hi) in fig3_sweep(FIG3_MODAL, 1800.0) {
        if lowers.contains(&name) {
            assert!(
                hi < lo,
                "modal: raising {name} must lower R_max ({lo:e} → {hi:e})"
            );
        }
    }
}

/// The gel's loading through open faces while the pressure rises (the boundary value moves
/// with the pressure): an open 15³ cube of pure N2 (L = 1.5 mm, D = 1e-9 m²/s, L²/D = 2 250 s)
/// saturated at 1 bar, the chamber raised linearly to 5 bar in 150 s (a 40 m descent at
/// 16 m/min) and held 300 s. Reference: Duhamel's integral of the open cube's Fourier series.
/// With faces at c_b(t) = c_0 + a·t, the mean concentration is c̄(t) = c_b(t) − a·∫ S(τ) dτ over
/// τ ∈ [max(0, t − T_r), t], where S(τ) = (Σ_{n odd} 8/(n²π²)·e^{−n²π²Dτ/L²})³ is the mean of
/// the cube that starts at 1 with its faces at 0, integrated term by term (odd n up to 199).
/// With no bubble to exchange gas, the pressure-change limit does not apply on the way down:
/// the loading's error estimate (`loading_tolerance`) sizes the steps, and the implicit ones
/// are Richardson-extrapolated (two half steps against one whole, second order), on the ramp
/// and, since 27 Nov 2026, in the hold. During the ramp the default steps are within 0.1 %
/// (0.048 %) of the load c_b(T_r) − c_0 of a run at a twentieth of h²/(9D), whose difference
/// from the series (−0.76 % at the end of the ramp, then falling) is the cell-centred grid's
/// own; in the hold within 0.1 % (0.025 %, in steps the second-order estimate sizes, not the
/// cap: with a 600 s cap the same 88 + 11 steps; backward Euler's steps there lagged by up to
/// 0.098 % before, and by 0.48 % without the loading estimate), and without the loading
/// estimate (extrapolated steps straight to the 20 s cap) within 0.1 % too (0.030 %). The ramp
/// taken in 20 s steps stays within 0.25 % (0.19 %); plain backward Euler in the same steps
/// lagged by 1.6 % (session 7's measurement, before the extrapolation). Every other figure
/// here is from this test's own output.
#[test]
fn a_descent_loads_the_gel_as_duhamels_series() {
    use decophantom::phantom::sim::Frame;
    let (n, h) = (15usize, 1e-4);
    let l = n as f64 * h;
    let (p0, p1, ramp, hold) = (1e5, 5e5, 150.0, 300.0);
    let profile = PressureHistory::with_gas(
        "descent",
        vec![0.0, ramp, ramp + hold],
        vec![p0, p1, p1],
        PURE_N2,
        0.0,
    )
    .unwrap();
    let run = |max_step: f64, pressure_change: f64, loading_tolerance: f64| {
        let mut params = open_cube_params(l, h);
        params.numerics.max_step = max_step;
        params.numerics.max_pressure_change = pressure_change;
        params.numerics.loading_tolerance = loading_tolerance;
        params.numerics.record_interval = 25.0;
        let mut sim = Simulation::new(&params, &profile).unwrap();
        let mut rec = Recorder::default();
        let s = sim.run(&profile, &mut rec).unwrap();
        (s, rec.frames, GAS_CONSTANT * params.temperature)
    };
    let defaults = PhantomParams::box_phantom([l; 3], h).numerics;
    let (change, loading) = (defaults.max_pressure_change, defaults.loading_tolerance);
    let (s, frames, rt) = run(20.0, change, loading);
    let volume = l * l * l;
    let c0 = DIFF_L_N2 * p0 / rt;
    let a = DIFF_L_N2 * (p1 - p0) / ramp / rt;
    let loaded = a * ramp;
    // ∫_{τ1}^{τ2} S(τ) dτ, term by term
    let odd: Vec<f64> = (0..100).map(|i| (2 * i + 1) as f64).collect();
    let integral = |t1: f64, t2: f64| -> f64 {
        let c = 8.0 / (PI * PI);
        let mut sum = 0.0;
        for &nx in &odd {
            for &ny in &odd {
                for &nz in &odd {
                    let lam = PI * PI * DIFF_D * (nx * nx + ny * ny + nz * nz) / (l * l);
                    let w = c * c * c / (nx * nx * ny * ny * nz * nz);
                    sum += w * ((-lam * t1).exp() - (-lam * t2).exp()) / lam;
                }
            }
        }
        sum
    };
    let series = |t: f64| -> f64 {
        let cb = c0 + a * t.min(ramp);
        cb - a * integral((t - ramp).max(0.0), t)
    };
    // error of a frame against the series, as a fraction of the load
    let error = |f: &Frame| (f.grid_moles[0] / volume - series(f.time)) / loaded;
    // the same grid at a twentieth of the explicit limit (forward Euler), at the same times
    let lim = h * h / (9.0 * DIFF_D);
    let (_, fine, _) = run(lim / 20.0, change, loading);
    assert!(frames.len() > 10 && fine.len() > 10);
    let mut worst_grid: f64 = 0.0;
    for f in &fine {
        let e = error(f);
        eprintln!(
            "fine    t = {:7.2} s: {:+.3} % of the load",
            f.time,
            100.0 * e
        );
        worst_grid = worst_grid.max(e.abs());
    }
    // the grid's own error: small, and largest at the end of the ramp
    assert!(worst_grid < 0.009, "{:.3} %", 100.0 * worst_grid);
    // a frame's error beyond the grid's (the fine run's, linear between its frames)
    let beyond = |f: &Frame| -> f64 {
        let k = fine
            .partition_point(|g| g.time < f.time)
            .clamp(1, fine.len() - 1);
        let (f0, f1) = (&fine[k - 1], &fine[k]);
        let w = ((f.time - f0.time) / (f1.time - f0.time)).clamp(0.0, 1.0);
        error(f) - ((1.0 - w) * error(f0) + w * error(f1))
    };
    // the worst of it over the frames in (t0, t1]
    let lag = |frames: &[Frame], t0: f64, t1: f64| {
        frames
            .iter()
            .filter(|f| f.time > t0 && f.time <= t1 + 1e-9)
            .map(|f| beyond(f).abs())
            .fold(0.0f64, f64::max)
    };
    for f in frames.iter().filter(|f| f.time > 0.0) {
        eprintln!(
            "default t = {:7.2} s: {:+.3} % of the load beyond the grid's",
            f.time,
            100.0 * beyond(f)
        );
    }
    // the ramp: within 0.048 %; the hold: up to 0.025 % (backward Euler's steps there, before
    // 27 Nov 2026: up to −0.098 %)
    let (ramp_default, hold_default) = (lag(&frames, 0.0, ramp), lag(&frames, ramp, ramp + hold));
    assert!(
        ramp_default < 0.001,
        "ramp: {ramp_default:.5} ({:?} steps)",
        s.steps
    );
    assert!(
        hold_default < 0.001,
        "hold: {hold_default:.5} ({:?} steps)",
        s.steps
    );
    // without the loading estimate the hold's steps grow straight to the cap: extrapolated,
    // they stay within the same bound (backward Euler's lagged by 0.48 %)
    let (_, capped, _) = run(20.0, change, f64::INFINITY);
    let hold_capped = lag(&capped, ramp, ramp + hold);
    eprintln!(
        "no loading estimate: worst {:.3} % of the load in the hold",
        100.0 * hold_capped
    );
    assert!(hold_capped < 0.001, "{hold_capped} against {hold_default}");
    // the ramp in 20 s steps (no loading estimate; the pressure limit does not apply while
    // only the gel loads): the extrapolated steps stay within a quarter of a per cent (plain
    // backward Euler's were 1.6 %)
    let (sl, long, _) = run(20.0, change, f64::INFINITY);
    let ramp_long = lag(&long, 0.0, ramp);
    eprintln!(
        "20 s steps: worst {:.3} % of the load during the ramp ({:?} steps; default {:?})",
        100.0 * ramp_long,
        sl.steps,
        s.steps
    );
    assert!(ramp_long < 0.0025, "{ramp_long}");
}
