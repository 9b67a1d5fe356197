//! Fixed partial pressure of non-simulated gases in every bubble (`bubble_fixed_gases_pa`):
//! the simulated gases fill the bubble at P_B − p_fixed.

use decophantom::gas::{Gas, GasMix};
use decophantom::phantom::params::{BubblePlacement, GasProperties, PhantomParams};
use decophantom::phantom::sim::{Recorder, Simulation};
use decophantom::profile::PressureHistory;
use decophantom::units::GAS_CONSTANT;
use std::f64::consts::PI;

/// A bubble is in (Laplace) equilibrium with the gel when the gel's N2 tension equals the N2
/// partial pressure inside: p_N2 = P_amb + 2γ/R0 − p_fixed (eq. 2.4 less the fixed gases).
/// The profile's water vapour sets the gel tension to P_amb − p_vap, so p_vap = p_fixed − 2γ/R0
/// makes the two equal: the bubble neither grows nor shrinks, and it holds
/// n = (P_amb + 2γ/R0 − p_fixed)·V/(R_u·T) mol. Ignoring p_fixed in Henry's law at the
/// interface would make the same bubble shrink (its C_s 20 kPa too high).
#[test]
fn bubble_with_fixed_gases_in_equilibrium_stays_put() {
    let (p, gamma, r0, p_fixed) = (1e5, 0.07, 1e-4, 2e4);
    let mut params = PhantomParams::box_phantom([2e-3; 3], 1e-4);
    params.gases = vec![GasProperties {
        gas: Gas::N2,
        diffusivity: 2e-9,
        ostwald: 0.014,
    }];
    params.surface_tension = gamma;
    params.min_radius = 0.0;
    params.bubble_fixed_gases = p_fixed;
    params.bubbles = BubblePlacement::Explicit(vec![([1e-3; 3], r0)]);
    let vapour = p_fixed - 2.0 * gamma / r0;
    let profile = PressureHistory::with_gas(
        "eq",
        vec![0.0, 300.0],
        vec![p, p],
        GasMix { o2: 0.0, he: 0.0 },
        vapour,
    )
    .unwrap();
    let mut sim = Simulation::new(&params, &profile).unwrap();
    let n_expected = (p + 2.0 * gamma / r0 - p_fixed) * 4.0 / 3.0 * PI * r0.powi(3)
        / (GAS_CONSTANT * params.temperature);
    assert!((sim.bubbles[0].total_moles() / n_expected - 1.0).abs() < 1e-12);
    let mut rec = Recorder::default();
    sim.run(&profile, &mut rec).unwrap();
    let worst = rec
        .frames
        .iter()
        .map(|f| (f.bubbles[0].radius / r0 - 1.0).abs())
        .fold(0.0, f64::max);
    eprintln!("largest relative radius change over 300 s: {worst:.2e}");
    assert!(worst < 1e-6, "{worst}");
}

/// Epstein & Plesset (1950) with fixed gases: the bubble's N2 is at P − p_fixed (γ = 0), so its
/// saturation concentration is C_s = L·(P − p_fixed)/(R_u·T) and its gas density
/// (P − p_fixed)/(R_u·T); EP's dR/dt = −D·(C_s − C_∞)/ρ_g·(1/R + 1/√(πDt)) keeps its form with
/// f = C_∞/C_s = p_∞/(P − p_fixed) (here 0.2·P/(0.8·P) = 0.25 instead of 0.2). The fixed gases
/// occupy volume without dissolving, so at the same gel tension the bubble dissolves more
/// slowly. The model's quasi-static deviation from EP (a few %, see
/// `analytic::epstein_plesset_dissolution`) is nearly the same in both runs, so the ratio of
/// the dissolution times is compared with EP's ratio (reference computed here by integrating
/// EP for both f).
#[test]
fn fixed_gases_change_epstein_plesset_f() {
    let r0 = 1e-4;
    let (d, l) = (2e-9, 0.014);
    let p_fixed = 2e4;
    let (_, t_ep0) = crate::analytic::epstein_plesset(r0, d, l, 0.2, 0.5);
    let (_, t_ep1) = crate::analytic::epstein_plesset(r0, d, l, 0.2 / 0.8, 0.5);
    let h = r0 / 2.0;
    let (_, t0) = crate::analytic::ep_case_with(r0, h, 10.0 * r0, 1.3 * t_ep0, 0.0);
    let (_, t1) = crate::analytic::ep_case_with(r0, h, 10.0 * r0, 1.3 * t_ep1, p_fixed);
    eprintln!(
        "EP: {t_ep0:.2} s → {t_ep1:.2} s (×{:.4}); model: {t0:.2} s → {t1:.2} s (×{:.4})",
        t_ep1 / t_ep0,
        t1 / t0
    );
    assert!(t1 > t0);
    assert!(((t1 / t0) / (t_ep1 / t_ep0) - 1.0).abs() < 0.01);
}
