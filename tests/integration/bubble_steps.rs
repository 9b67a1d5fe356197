//! Error-controlled bubble updates (`numerics.bubble_tolerance`, Heun's predictor–corrector
//! exchange): at default settings the Epstein–Plesset case is within 0.3 % of a run whose step
//! limits are all 16× smaller (step-converged), in the dissolution time and in R at 100 s.

use decophantom::gas::{Gas, GasMix};
use decophantom::phantom::params::{BubblePlacement, GasProperties, PhantomParams};
use decophantom::phantom::sim::{Event, Recorder, Simulation};
use decophantom::profile::PressureHistory;

/// The Epstein–Plesset set-up of `analytic::epstein_plesset_dissolution` (pure N2, γ = 0,
/// Ω = 0, D_surf = D = 2e-9 m²/s, L = 0.014, f = 0.2, R0 = 100 µm = 2h, open box of
/// half-width 1 mm) with every step limit multiplied by `scale` (the bubble tolerance too: the
/// step it allows is proportional to it). A breakpoint at 100 s lands a step there.
/// Returns (R at 100 s, dissolution time, steps).
pub(crate) fn ep_run(scale: f64) -> (f64, f64, usize) {
    let (d, l, f, p, r0, h) = (2e-9, 0.014, 0.2, 1e5, 100e-6, 50e-6);
    let mut params = PhantomParams::box_phantom([2e-3; 3], h);
    params.surface_tension = 0.0;
    params.min_radius = 0.0;
    params.gases = vec![GasProperties {
        gas: Gas::N2,
        diffusivity: d,
        ostwald: l,
    }];
    params.open_faces = params.shape.faces().to_vec();
    params.bubbles = BubblePlacement::Explicit(vec![([1e-3; 3], r0)]);
    params.numerics.record_interval = 0.0;
    let n = &mut params.numerics;
    n.max_step *= scale;
    n.max_pressure_change *= scale;
    n.max_content_change *= scale;
    n.bubble_tolerance *= scale;
    // "water vapour" (1 − f)·P: the gel and the faces at N2 tension f·P, the bubble pure N2 at P
    let profile = PressureHistory::with_gas(
        "ep",
        vec![0.0, 100.0, 300.0],
        vec![p, p, p],
        GasMix { o2: 0.0, he: 0.0 },
        (1.0 - f) * p,
    )
    .unwrap();
    let mut sim = Simulation::new(&params, &profile).unwrap();
    let mut rec = Recorder::default();
    let s = sim.run(&profile, &mut rec).unwrap();
    let r100 = rec
        .frames
        .iter()
        .find(|fr| (fr.time - 100.0).abs() < 1e-9)
        .map(|fr| fr.bubbles[0].radius)
        .expect("a step ends at the 100 s breakpoint");
    let t_end = s
        .events
        .iter()
        .find_map(|e| match e {
            Event::Dissolved { time, .. } => Some(*time),
            _ => None,
        })
        .expect("the bubble dissolves within 300 s");
    (r100, t_end, s.steps.0 + s.steps.1)
}

#[test]
fn default_steps_are_within_0_3_percent_of_16x_smaller_steps() {
    let (r, t, n) = ep_run(1.0);
    let (r16, t16, n16) = ep_run(1.0 / 16.0);
    eprintln!(
        "default: R(100 s) {:.4} µm, dissolved {t:.3} s, {n} steps; 16× smaller: {:.4} µm, {t16:.3} s, {n16} steps; ΔR {:+.3} %, Δt {:+.3} %",
        r * 1e6,
        r16 * 1e6,
        100.0 * (r / r16 - 1.0),
        100.0 * (t / t16 - 1.0)
    );
    assert!((r / r16 - 1.0).abs() < 0.003, "R(100 s) {r} vs {r16}");
    assert!((t / t16 - 1.0).abs() < 0.003, "dissolution {t} vs {t16}");
    // The independent references of the same problem: the fully resolved 1-D solution
    // (`growth::resolved`, no quasi-static assumption) and Epstein–Plesset's quasi-static ODE
    // (`analytic::epstein_plesset`). What is left against them at converged steps is the
    // grid's (R0 = 2h) and the near-field shell's error, not the step's.
    let case = crate::growth::Case {
        p: 1e5,
        d: 2e-9,
        d_surf: 2e-9,
        delta: 20e-6,
        l: 0.014,
        gamma: 0.0,
        mu: 0.0,
        r0: 100e-6,
        f: 0.2,
    };
    let (rr, tr) = crate::growth::resolved(&case, &[100.0, 400.0]);
    let (ep, t_ep) = crate::analytic::epstein_plesset(100e-6, 2e-9, 0.014, 0.2, 0.5);
    let r_ep = ep
        .iter()
        .find(|(t, _)| (*t - 100.0).abs() < 0.26)
        .unwrap()
        .1;
    eprintln!(
        "resolved 1-D: R(100 s) {:.4} µm, dissolved {tr:.3} s; EP: {:.4} µm, {t_ep:.3} s",
        rr[0] * 1e6,
        r_ep * 1e6
    );
    assert!(
        (r16 / rr[0] - 1.0).abs() < 0.015,
        "R(100 s) {r16} vs resolved {}",
        rr[0]
    );
    assert!(
        (t16 / tr - 1.0).abs() < 0.015,
        "dissolution {t16} vs resolved {tr}"
    );
}
