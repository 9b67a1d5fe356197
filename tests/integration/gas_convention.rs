//! The breathed-gas convention of dive scoring (`evaluate`/`check`): the open faces hold the
//! inspired inert gas f_g·(P − P_H2O), every bubble holds the gases that are not simulated at
//! P_H2O + P_CO2 + P_vO2 (criteria `[protocol]`), the same P_H2O on both sides. At rest at the
//! surface on air a bubble then sees the physiological inherent unsaturation (the oxygen
//! window), not the 26 kPa the earlier convention built in (inert gas only in the bubble).
//! A dive starts with the gel saturated with surface air under the same convention, whatever
//! its first gas; and the step that ends on a gas switch keeps the old gas at the faces.

use decophantom::algorithm::{Leg, LegKind, Schedule};
use decophantom::app::evaluate::{breathed_gas_params, dive_history};
use decophantom::gas::{Gas, GasMix};
use decophantom::phantom::params::{BubblePlacement, GasProperties, PhantomParams};
use decophantom::phantom::sim::{Recorder, Simulation};
use decophantom::profile::PressureHistory;
use decophantom::risk::Protocol;

const P_SURFACE: f64 = 101_325.0; // Pa, 1 atm

/// Ten minutes at the surface on air, as a schedule; its planner's vapour (4 930 Pa, Baker's
/// 1.607 fsw... any value other than the protocol's) must not reach the phantom.
fn surface_schedule(minutes: f64) -> Schedule {
    Schedule {
        label: "surface".into(),
        surface_pressure_pa: P_SURFACE,
        pa_per_m: 10_000.0,
        water_vapour_pa: 4_930.0,
        legs: vec![Leg {
            kind: LegKind::Bottom,
            start_depth_m: 0.0,
            end_depth_m: 0.0,
            duration_s: minutes * 60.0,
            gas: GasMix::AIR,
        }],
        stops: vec![],
    }
}

/// The oxygen window by hand, from the physiology-text values (Guyton & Hall, *Textbook of
/// Medical Physiology*, 13th ed., ch. 40–41; West, *Respiratory Physiology*, 9th ed.):
/// breathing air at 1 atm the inspired (humidified) O2 is 0.21·(101 325 − 6 270) = 19 961.55 Pa;
/// tissue consumes it down to the venous 5 300 Pa (40 mmHg) and replaces it with CO2 at
/// 5 300 Pa (40 mmHg), so the total gas tension in tissue is below ambient by
/// 19 961.55 − 5 300 − 5 300 = 9 361.55 Pa. A bubble (no surface tension) holding H2O, CO2 and
/// venous O2 at those pressures and N2 at the rest must see exactly that N2 unsaturation.
#[test]
fn surface_unsaturation_is_the_oxygen_window() {
    let protocol = Protocol::default();
    let h = dive_history(&surface_schedule(10.0), &protocol, None).unwrap();
    let mut params = PhantomParams::box_phantom([2e-3; 3], 2e-4);
    params = breathed_gas_params(&params, &protocol).unwrap();
    // the same water vapour on both sides of the interface
    assert_eq!(h.vapour_pa, 6_270.0);
    assert_eq!(h.gases(), vec![Gas::N2]);
    let t = 60.0;
    let gel_inert: f64 = h
        .gases()
        .iter()
        .map(|g| h.inspired_partial_pressure(*g, t))
        .sum();
    let bubble_inert = h.ambient(t) - params.bubble_fixed_gases;
    let unsaturation = bubble_inert - gel_inert;
    let window = 0.21 * (P_SURFACE - 6_270.0) - 5_300.0 - 5_300.0;
    eprintln!("unsaturation {unsaturation:.2} Pa; oxygen window by hand {window:.2} Pa");
    assert!((window - 9_361.55).abs() < 1e-6);
    assert!((unsaturation - window).abs() < 1e-6, "{unsaturation}");
    // without metabolism (O2 at the faces): water vapour only, no unsaturation at all
    let inert = Protocol {
        oxygen_at_faces: true,
        co2_pa: 0.0,
        venous_o2_pa: 0.0,
        ..Protocol::default()
    };
    let h2 = dive_history(&surface_schedule(10.0), &inert, None).unwrap();
    let p2 = breathed_gas_params(&PhantomParams::box_phantom([2e-3; 3], 2e-4), &inert).unwrap();
    let gel: f64 = h2
        .gases()
        .iter()
        .map(|g| h2.inspired_partial_pressure(*g, t))
        .sum();
    assert!((h2.ambient(t) - p2.bubble_fixed_gases - gel).abs() < 1e-6);
    // a phantom with its own fixed gases is refused for a breathed gas
    let mut own = PhantomParams::box_phantom([2e-3; 3], 2e-4);
    own.bubble_fixed_gases = 1.0;
    let e = breathed_gas_params(&own, &protocol).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("material.bubble_fixed_gases_pa"));
}

/// A 100 µm bubble (γ = 0, Ω = 0, D_surf = D) in a gel at rest at the surface on air under the
/// breathed-gas convention dissolves only at the oxygen-window rate: its N2 is at
/// P − p_fixed = 84 455 Pa against the gel's 75 093.45 Pa. Reference: the independent, fully
/// resolved 1-D solution of `growth::resolved` for a pure-N2 bubble at ambient P − p_fixed
/// (with γ = Ω = 0 the fixed gases only lower the N2 pressure in the bubble) in a gel at
/// f = 75 093.45/84 455. Under the earlier convention (no fixed gases) the same bubble sees
/// 26.2 kPa of unsaturation and is gone in about 9 min.
#[test]
fn surface_bubble_dissolves_at_the_oxygen_window_rate() {
    // the default convention, without the hour of watching after the schedule
    let protocol = Protocol {
        observe_after_surfacing_s: 0.0,
        ..Protocol::default()
    };
    let minutes = 10.0;
    let h = dive_history(&surface_schedule(minutes), &protocol, None).unwrap();
    let (d, l, r0) = (2.5e-9, 0.014, 100e-6);
    let mut base = PhantomParams::box_phantom([5e-3; 3], 1e-4);
    base.surface_tension = 0.0;
    base.min_radius = 0.0;
    base.gases = vec![GasProperties {
        gas: Gas::N2,
        diffusivity: d,
        ostwald: l,
    }];
    base.bubbles = BubblePlacement::Explicit(vec![([2.5e-3; 3], r0)]);
    base.numerics.record_interval = 10.0;
    let params = breathed_gas_params(&base, &protocol).unwrap();
    let mut sim = Simulation::new(&params, &h).unwrap();
    let mut rec = Recorder::default();
    sim.run(&h, &mut rec).unwrap();
    let times = [150.0, 300.0, 600.0];
    let p_n2_bubble = P_SURFACE - 16_870.0;
    let p_n2_gel = 0.79 * (P_SURFACE - 6_270.0);
    let case = crate::growth::Case {
        p: p_n2_bubble,
        d,
        d_surf: d,
        delta: 20e-6,
        l,
        gamma: 0.0,
        mu: 0.0,
        r0,
        f: p_n2_gel / p_n2_bubble,
    };
    let (want, _) = crate::growth::resolved(&case, &times);
    // the earlier convention: pure N2 at P against the same gel
    let old = crate::growth::Case {
        p: P_SURFACE,
        f: p_n2_gel / P_SURFACE,
        ..case
    };
    let (old_r, old_t) = crate::growth::resolved(&old, &times);
    for (t, w) in times.iter().zip(&want) {
        // linear interpolation between the recorded frames around t
        let k = rec.frames.partition_point(|f| f.time < *t);
        let (a, b) = (&rec.frames[k - 1], &rec.frames[k]);
        let s = (t - a.time) / (b.time - a.time);
        let got = a.bubbles[0].radius + s * (b.bubbles[0].radius - a.bubbles[0].radius);
        eprintln!(
            "t = {t} s: model {:.2} µm, resolved 1-D {:.2} µm",
            got * 1e6,
            w * 1e6
        );
        // at default (step-converged: `bubble_steps`) steps the model is −1.1 % at 600 s: the
        // grid's share (R0 = h), as in `analytic::epstein_plesset_dissolution`
        assert!((got / w - 1.0).abs() < 0.015, "t = {t}: {got} vs {w}");
    }
    eprintln!(
        "earlier convention (resolved 1-D): R = {:.1?} µm, dissolved at {old_t:.0} s",
        old_r.iter().map(|r| r * 1e6).collect::<Vec<_>>()
    );
    assert!(old_t < 600.0 && want[2] > 0.6 * r0);
}

/// The phantom with He properties (`box_phantom` lists N2 and O2), `bubble` placed at t = 0.
fn phantom_with_helium(bubble: Option<f64>) -> PhantomParams {
    let mut p = PhantomParams::box_phantom([1e-3; 3], 1e-4);
    p.gases.push(GasProperties {
        gas: Gas::He,
        diffusivity: 8.35e-9,
        ostwald: 0.0098,
    });
    p.bubbles = BubblePlacement::Explicit(bubble.map(|r| ([5e-4; 3], r)).into_iter().collect());
    p
}

/// Every inside cell of every field against the saturation computed here, and the t = 0
/// bubble's composition: the fractions of the same partial pressures.
fn assert_saturated(sim: &Simulation, params: &PhantomParams, want_pa: &[(Gas, f64)]) {
    let rt = decophantom::units::GAS_CONSTANT * params.temperature;
    let psum: f64 = want_pa.iter().map(|w| w.1).sum();
    for (gi, g) in sim.gases().iter().enumerate() {
        let p = want_pa.iter().find(|w| w.0 == *g).map_or(0.0, |w| w.1);
        let want = params.gas(*g).unwrap().ostwald * p / rt;
        let grid = sim.grid();
        for (i, c) in sim.field(gi).iter().enumerate() {
            if grid.inside(i) {
                assert!(
                    (c - want).abs() <= 1e-12 * want.max(1e-300),
                    "{g:?} cell {i}: {c} vs {want} mol/m³"
                );
            }
        }
        if let Some(b) = sim.bubbles.first() {
            let x = b.moles[gi] / b.total_moles();
            assert!((x - p / psum).abs() < 1e-12, "{g:?} in the bubble: {x}");
        }
    }
}

/// Defect 1 of the physics review (27 Nov 2026): a dive starts with the gel (and its t = 0
/// bubbles) in equilibrium with surface air, whatever the first leg breathes — the tissues of
/// every planner here (ZH-L16 and VPM-B: f_N2,air·(P_surf − P_H2O), no He). Reference: Henry's
/// law computed in the test, C_g = L_g·f_g,air·(P_surf − P_H2O)/(R_u·T), with f_N2 = 0.79 and
/// f_O2 = 0.21 (`GasMix::AIR`), and C_He = 0. Before, an 18/45 first leg started the gel at
/// p_He = 0.45·(P − P_H2O) and p_N2 = 0.37·(P − P_H2O). Checked on the three dive paths:
/// `evaluate`/`check` (the protocol's convention, O2 left out), `simulate` of a planned
/// schedule (its own vapour, O2 at the faces) and a logged trimix dive at altitude.
#[test]
fn a_dive_starts_saturated_with_surface_air_whatever_its_first_gas() {
    let tx = GasMix::new(0.18, 0.45).unwrap();
    let leg = |kind, a: f64, b: f64, s: f64| Leg {
        kind,
        start_depth_m: a,
        end_depth_m: b,
        duration_s: s,
        gas: tx,
    };
    let schedule = Schedule {
        label: "trimix".into(),
        surface_pressure_pa: P_SURFACE,
        pa_per_m: 10_000.0,
        water_vapour_pa: 6_270.0,
        legs: vec![
            leg(LegKind::Descent, 0.0, 40.0, 240.0),
            leg(LegKind::Bottom, 40.0, 40.0, 600.0),
            leg(LegKind::Ascent, 40.0, 0.0, 400.0),
        ],
        stops: vec![],
    };
    let air = |p_surf: f64, vapour: f64, with_o2: bool| {
        let mut v = vec![(Gas::N2, 0.79 * (p_surf - vapour)), (Gas::He, 0.0)];
        if with_o2 {
            v.push((Gas::O2, 0.21 * (p_surf - vapour)));
        }
        v
    };
    // evaluate / check: the protocol's P_H2O (6 270 Pa), O2 not simulated
    let protocol = Protocol::default();
    let h = dive_history(&schedule, &protocol, None).unwrap();
    assert_eq!(h.gases(), vec![Gas::N2, Gas::He]);
    let params = breathed_gas_params(&phantom_with_helium(Some(100e-6)), &protocol).unwrap();
    let sim = Simulation::new(&params, &h).unwrap();
    assert_saturated(&sim, &params, &air(P_SURFACE, 6_270.0, false));
    // the same within the test's own numbers: N2 0.79·(101 325 − 6 270) = 75 093.45 Pa
    let rt = decophantom::units::GAS_CONSTANT * params.temperature;
    assert!((sim.field(0)[sim.grid().len() / 2] * rt / 0.014 - 75_093.45).abs() < 1e-6);
    // simulate with the planned schedule: the schedule's vapour, O2 at the faces
    let h = schedule.to_pressure_history().unwrap();
    assert_eq!(h.gases(), vec![Gas::N2, Gas::O2, Gas::He]);
    let params = phantom_with_helium(Some(100e-6));
    let sim = Simulation::new(&params, &h).unwrap();
    assert_saturated(&sim, &params, &air(P_SURFACE, 6_270.0, true));
    // a logged dive on 18/45 from its first sample, at altitude (surface 0.912 bar)
    let opts = decophantom::profile::LoadOptions {
        vapour_pa: Some(6_270.0),
        ..Default::default()
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/divelogs/planned-trimix.xml");
    let h = decophantom::profile::load(&path, &opts).unwrap();
    assert!(h.gas_at(0.0).he > 0.4, "the log starts on trimix");
    let params = phantom_with_helium(None);
    let sim = Simulation::new(&params, &h).unwrap();
    assert_saturated(&sim, &params, &air(91_200.0, 6_270.0, true));
}

/// Defect 3 of the physics review (27 Nov 2026): the step that ends on a gas switch keeps the
/// old gas at the open faces (and in the perfusion's blood) up to its end; the new gas starts
/// with the step after the breakpoint. A gel saturated with air at a constant 2 bar (no bubbles,
/// no vapour, perfusion on), switched to oxygen at 100 s: up to the switch nothing may move
/// through the open faces. References: (1) Henry's law computed here, the content of the gel
/// in equilibrium with air, n_g = L_g·f_g·P/(R_u·T)·V_gel, and (2) the same run without the
/// switch (air throughout, the same breakpoints), whose frame at 100 s must be the same bits.
/// Before the fix the last step before 100 s (up to `max_step`, 20 s) took oxygen at the faces:
/// N2 left and O2 came in for a whole step. Checked with the holds' Richardson-extrapolated
/// steps (the default) and with backward-Euler steps (`extrapolate_holds = false`).
#[test]
fn the_step_ending_on_a_gas_switch_keeps_the_old_gas_at_the_faces() {
    let (p, t_switch, end) = (2e5, 100.0, 200.0);
    let times = vec![0.0, t_switch, end];
    let switched = PressureHistory::new(
        "air then oxygen",
        times.clone(),
        vec![p; 3],
        vec![GasMix::AIR, GasMix::new(1.0, 0.0).unwrap()],
        0.0,
    )
    .unwrap();
    let air_only =
        PressureHistory::new("air", times, vec![p; 3], vec![GasMix::AIR; 2], 0.0).unwrap();
    for extrapolate in [true, false] {
        let mut params = PhantomParams::box_phantom([1e-3; 3], 1e-4);
        params.perfusion_rate = 1e-2;
        params.numerics.record_interval = 0.0;
        params.numerics.extrapolate_holds = extrapolate;
        let at_switch = |h: &PressureHistory| {
            let mut sim = Simulation::new(&params, h).unwrap();
            let mut rec = Recorder::default();
            sim.run(h, &mut rec).unwrap();
            let f = rec
                .frames
                .iter()
                .find(|f| (f.time - t_switch).abs() < 1e-6)
                .expect("a frame at the switch")
                .clone();
            let v_gel = sim.grid().n_inside as f64 * sim.grid().cell_volume();
            (f, v_gel, sim.gases().to_vec())
        };
        let (f, v_gel, gases) = at_switch(&switched);
        let (f_air, ..) = at_switch(&air_only);
        let rt = decophantom::units::GAS_CONSTANT * params.temperature;
        for (gi, g) in gases.iter().enumerate() {
            let want = params.gas(*g).unwrap().ostwald * GasMix::AIR.fraction(*g) * p / rt * v_gel;
            let got = f.grid_moles[gi];
            eprintln!(
                "extrapolate_holds {extrapolate}: {g:?} in the gel at the switch {got:.6e} mol, Henry {want:.6e} mol, without the switch {:.6e} mol",
                f_air.grid_moles[gi]
            );
            assert!((got / want - 1.0).abs() < 1e-12, "{g:?}: {got} vs {want}");
            assert_eq!(got, f_air.grid_moles[gi], "{g:?}");
        }
    }
}
