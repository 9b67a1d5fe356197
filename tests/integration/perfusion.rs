//! Perfusion (issue 7; the paper's §5 extension): ∂C/∂t = D∇²C − k·(C − C_b(t)) with
//! C_b = L·p_insp(t)/(R_u·T), checked against closed-form solutions written here.

use decophantom::gas::{Gas, GasMix};
use decophantom::phantom::grid::Face;
use decophantom::phantom::params::{BubblePlacement, GasProperties, PhantomParams};
use decophantom::phantom::sim::{Recorder, Simulation};
use decophantom::profile::PressureHistory;
use decophantom::units::GAS_CONSTANT;
use std::f64::consts::PI;

const D: f64 = 2e-9;
const L: f64 = 0.014;

fn n2_only(params: &mut PhantomParams) {
    params.gases = vec![GasProperties {
        gas: Gas::N2,
        diffusivity: D,
        ostwald: L,
    }];
}

/// Pure N2 at `pressures` (Pa) at `times` (s), no vapour.
fn n2_profile(times: Vec<f64>, pressures: Vec<f64>) -> PressureHistory {
    PressureHistory::with_gas("n2", times, pressures, GasMix { o2: 0.0, he: 0.0 }, 0.0).unwrap()
}

/// Blood value C_b = L·p/(R_u·T), mol/m³.
fn blood(params: &PhantomParams, p: f64) -> f64 {
    L * p / (GAS_CONSTANT * params.temperature)
}

/// A sealed, uniform gel has no gradients, so only perfusion acts:
/// dC/dt = −k·(C − C_b(t)). For constant C_b the solution is C(t) = C_b + (C0 − C_b)·e^{−kt};
/// for C_b(t) = a + s·t (a linear pressure ramp) it is
/// C(t) = C_b(t) − s/k + (C0 − a + s/k)·e^{−kt} (first-order linear ODE, integrating factor
/// e^{kt}). Checked in both schemes (explicit: small steps; implicit: steps of 10 × the explicit
/// limit with the cost switch off).
#[test]
fn uniform_sealed_gel_relaxes_exponentially_to_the_blood_value() {
    let k = 2e-3;
    for implicit in [false, true] {
        let mut params = PhantomParams::box_phantom([1e-3, 8e-4, 6e-4], 1e-4);
        n2_only(&mut params);
        params.open_faces = vec![];
        params.perfusion_rate = k;
        params.numerics.record_interval = 0.0;
        if implicit {
            params.numerics.implicit_cost_ratio = 1.0;
            params.numerics.max_step = 20.0;
        } else {
            params.numerics.max_step = 0.5;
        }
        let (p0, p1, t_ramp, t_end) = (1e5, 3e5, 600.0, 1200.0);
        let profile = n2_profile(vec![0.0, t_ramp, t_end], vec![p0, p1, p1]);
        let mut sim = Simulation::new(&params, &profile).unwrap();
        let c0 = 3.0 * blood(&params, p0);
        sim.field_mut(0).iter_mut().for_each(|c| *c = c0);
        sim.rebase_balance();
        let mut rec = Recorder::default();
        let summary = sim.run(&profile, &mut rec).unwrap();
        if implicit {
            assert!(
                summary.steps.1 > 0 && summary.steps.0 == 0,
                "{:?}",
                summary.steps
            );
        } else {
            assert!(
                summary.steps.0 > 0 && summary.steps.1 == 0,
                "{:?}",
                summary.steps
            );
        }
        let volume = summary.cells as f64 * 1e-12;
        let (a, s) = (
            blood(&params, p0),
            (blood(&params, p1) - blood(&params, p0)) / t_ramp,
        );
        let c_ramp_end = blood(&params, p1) - s / k + (c0 - a + s / k) * (-k * t_ramp).exp();
        let exact = |t: f64| {
            if t <= t_ramp {
                a + s * t - s / k + (c0 - a + s / k) * (-k * t).exp()
            } else {
                let cb = blood(&params, p1);
                cb + (c_ramp_end - cb) * (-k * (t - t_ramp)).exp()
            }
        };
        let mut worst: f64 = 0.0;
        for fr in &rec.frames {
            let mean = fr.grid_moles[0] / volume;
            worst = worst.max((mean / exact(fr.time) - 1.0).abs());
        }
        eprintln!("implicit {implicit}: worst relative error {worst:.2e}");
        assert!(worst < 1e-11, "worst relative error {worst:e}");
        assert!(summary.gas_balance_error < 1e-12);
    }
}

/// A sealed slab 0 ≤ z ≤ Lz (three cells wide in x and y and uniform across, so the problem is
/// 1-D), perfused at rate
/// k, starting from C_b + u0(z) with u0 = A for z < Lz/2 and −A above: with no-flux ends the
/// solution is the cosine series (Carslaw & Jaeger, Conduction of Heat in Solids, 2nd ed.,
/// §3.3, with the perfusion term adding −k to every mode's decay rate):
/// C − C_b = e^{−kt}·Σ_n a_n cos(nπz/Lz)·e^{−D(nπ/Lz)²t}, a_n = 4A·sin(nπ/2)/(nπ).
/// Its mean over the lower half is e^{−kt}·Σ_n a_n·(2/(nπ))·sin(nπ/2)·e^{−D(nπ/Lz)²t};
/// checked, with the whole profile, in both schemes.
#[test]
fn sealed_slab_decays_with_rate_d_lambda_plus_k() {
    let (h, nz) = (1e-4, 64usize);
    let lz = h * nz as f64;
    let k = 5e-4;
    let t_end = 1500.0;
    for implicit in [false, true] {
        let mut params = PhantomParams::box_phantom([3.0 * h, 3.0 * h, lz], h);
        n2_only(&mut params);
        params.open_faces = vec![];
        params.perfusion_rate = k;
        if implicit {
            params.numerics.implicit_cost_ratio = 1.0;
            params.numerics.max_step = 5.0; // 6 × the explicit limit h²/(6D) = 0.83 s
        } else {
            params.numerics.max_step = 0.5;
        }
        let p = 1e5;
        let profile = n2_profile(vec![0.0, t_end], vec![p, p]);
        let mut sim = Simulation::new(&params, &profile).unwrap();
        let cb = blood(&params, p);
        let amp = 0.5 * cb;
        for (idx, c) in sim.field_mut(0).iter_mut().enumerate() {
            *c = if idx / 9 < nz / 2 { cb + amp } else { cb - amp };
        }
        sim.rebase_balance();
        let summary = sim.run(&profile, &mut Recorder::default()).unwrap();
        assert_eq!(summary.cells, 9 * nz);
        assert!(summary.gas_balance_error < 1e-12);
        let series = |z: f64, t: f64| {
            let mut acc = 0.0;
            for n in (1..4000).step_by(2) {
                let nf = n as f64;
                let an = 4.0 * amp * (nf * PI / 2.0).sin() / (nf * PI);
                acc += an * (nf * PI * z / lz).cos() * (-D * (nf * PI / lz).powi(2) * t).exp();
            }
            cb + (-k * t).exp() * acc
        };
        let mut half_ref = 0.0;
        for n in (1..4000).step_by(2) {
            let nf = n as f64;
            let an = 4.0 * amp * (nf * PI / 2.0).sin() / (nf * PI);
            half_ref += an * 2.0 / (nf * PI)
                * (nf * PI / 2.0).sin()
                * (-D * (nf * PI / lz).powi(2) * t_end).exp();
        }
        half_ref *= (-k * t_end).exp();
        let f = sim.field(0);
        let half: f64 = f[..9 * nz / 2].iter().map(|c| c - cb).sum::<f64>() / (9 * nz / 2) as f64;
        let mut worst: f64 = 0.0;
        for (idx, c) in f.iter().enumerate() {
            let z = ((idx / 9) as f64 + 0.5) * h;
            worst = worst.max((c - series(z, t_end)).abs() / amp);
        }
        // without perfusion the lower-half excess would be e^{kt} = 2.1 times larger
        eprintln!(
            "implicit {implicit}: lower-half excess {half:.6e} vs series {half_ref:.6e} ({:+.2e}); worst point error {worst:.2e} of A",
            half / half_ref - 1.0
        );
        let tol = if implicit { 3e-3 } else { 1e-3 };
        assert!((half / half_ref - 1.0).abs() < tol, "{half} vs {half_ref}");
        assert!(worst < tol, "worst point error {worst}");
    }
}

/// The gas balance counts what perfusion removes or adds: with open faces, a bubble, a pressure
/// ramp and perfusion, in both schemes, the balance closes to round-off; and perfusion changes
/// the result (a perfused gel loads faster, so the bubble ends larger after compression).
#[test]
fn gas_balance_closes_with_perfusion() {
    let mut ends = Vec::new();
    for (implicit, k) in [(false, 0.0), (false, 5e-3), (true, 5e-3)] {
        let mut params = PhantomParams::box_phantom([2e-3; 3], 1e-4);
        n2_only(&mut params);
        params.open_faces = vec![Face::Top, Face::XMinus];
        params.perfusion_rate = k;
        params.bubbles = BubblePlacement::Explicit(vec![([1e-3; 3], 1.5e-4)]);
        if implicit {
            params.numerics.implicit_cost_ratio = 1.0;
        }
        let profile = n2_profile(vec![0.0, 60.0, 400.0], vec![1e5, 3e5, 3e5]);
        let mut sim = Simulation::new(&params, &profile).unwrap();
        let summary = sim.run(&profile, &mut Recorder::default()).unwrap();
        eprintln!(
            "implicit {implicit}, k {k}: balance {:.2e}, final R {:.4e} m, steps {:?}",
            summary.gas_balance_error, summary.final_radii[0], summary.steps
        );
        assert!(summary.gas_balance_error < 1e-11);
        ends.push(summary.final_radii[0]);
    }
    assert!(ends[1] > ends[0] * 1.001, "{ends:?}");
    assert!((ends[2] / ends[1] - 1.0).abs() < 0.02, "{ends:?}");
}

/// `[perfusion] rate_per_s` reaches the parameters; negative, non-numeric and unknown keys are
/// refused naming the field.
#[test]
fn perfusion_and_fixed_gases_from_toml() {
    let base = "[geometry]\nshape = \"box\"\nsize_m = [1e-3, 1e-3, 1e-3]\ngrid_step_m = 1e-4\n[gases.n2]\ndiffusivity = 2e-9\nostwald = 0.014\n";
    let path = std::path::Path::new("p.toml");
    let ok = format!(
        "{base}[perfusion]\nrate_per_s = 0.002\n[material]\nbubble_fixed_gases_pa = 16870\n"
    );
    let ph = decophantom::phantom::config::parse_phantom(&ok, path).unwrap();
    assert_eq!(ph.params.perfusion_rate, 0.002);
    assert_eq!(ph.params.bubble_fixed_gases, 16870.0);
    let def = decophantom::phantom::config::parse_phantom(base, path).unwrap();
    assert_eq!(def.params.perfusion_rate, 0.0);
    assert_eq!(def.params.bubble_fixed_gases, 0.0);
    for (bad, field) in [
        ("[perfusion]\nrate_per_s = -1.0\n", "perfusion.rate_per_s"),
        ("[perfusion]\nrate = 1.0\n", "rate"),
        (
            "[material]\nbubble_fixed_gases_pa = -5.0\n",
            "material.bubble_fixed_gases_pa",
        ),
    ] {
        let e = decophantom::phantom::config::parse_phantom(&format!("{base}{bad}"), path)
            .unwrap_err()
            .to_string();
        // "p.toml:LINE: field '...'"
        assert!(e.contains(field) && e.contains("p.toml:"), "{e}");
    }
}
