//! Verification item 5: grid and time-step convergence on the paper's dive profile.

use decophantom::phantom::elasticity::Hyperelastic;
use decophantom::phantom::params::{BubblePlacement, PhantomParams};
use decophantom::phantom::sim::{Recorder, Simulation};
use decophantom::phantom::surface::AreaLaw;
use std::sync::Arc;

/// One centred bubble in a 2.4 mm hydrogel cube (the hydrogel's material: D = 2.5e-9 m²/s,
/// D_surf = D/30 area law, μ = 40 Pa hyperelastic, γ = 0.07 N/m); R0 and R_min fixed in metres
/// so that they do not move with h.
fn phantom(h: f64, step_scale: f64) -> PhantomParams {
    let mut p = PhantomParams::box_phantom([2.4e-3; 3], h);
    p.elasticity = Arc::new(Hyperelastic {
        shear_modulus: 40.0,
    });
    p.surface = Arc::new(AreaLaw {
        fold: 30.0,
        reference_radius_m: None,
        exponent: 2.0,
        cap_at_bulk: true,
    });
    p.min_radius = 55e-6;
    p.bubbles = BubblePlacement::Explicit(vec![([1.2e-3; 3], 60e-6)]);
    p.numerics.max_step *= step_scale;
    p.numerics.max_pressure_change *= step_scale;
    p.numerics.max_content_change *= step_scale;
    p.numerics.record_interval = 5.0;

    p
}

fn plateau(h: f64, step_scale: f64) -> f64 {
    let prof = crate::common::fig6_dive(2400.0);
    let params = phantom(h, step_scale);
    let mut sim = Simulation::new(&params, &prof).unwrap();
    let s = sim.run(&prof, &mut Recorder::default()).unwrap();
    assert_eq!(s.ending, decophantom::phantom::sim::Ending::Completed);
    s.max_radius.0
}

#[test]
fn halving_grid_and_step_changes_plateau_radius_by_less_than_two_percent() {
    let coarse = plateau(100e-6, 1.0);
    let fine = plateau(50e-6, 0.5);
    let step_only = plateau(100e-6, 0.5);

    eprintln!("plateau radius: h = 100 µm {:.2} µm; h = 50 µm, half step {:.2} µm; h = 100 µm, half step {:.2} µm", coarse * 1e6, fine * 1e6, step_only * 1e6);
    assert!(
        coarse > 2.0 * 60e-6,
        "the bubble must grow well beyond R0 for the test to mean anything: {coarse}"
    );
    assert!(
        (fine / coarse - 1.0).abs() < 0.02,
        "grid+step halving moved the plateau radius by {:+.3} %",
        100.0 * (fine / coarse - 1.0)
    );
    assert!(
        (step_only / coarse - 1.0).abs() < 0.02,
        "step halving moved the plateau radius by {:+.3} %",
        100.0 * (step_only / coarse - 1.0)
    );
}
