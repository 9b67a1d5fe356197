//! Verification against analytic solutions (the model issue's list, items 1–3).

use decophantom::gas::Gas;
use decophantom::gas::GasMix;
use decophantom::phantom::params::{BubblePlacement, GasProperties, PhantomParams};
use decophantom::phantom::sim::{Recorder, Simulation};
use decophantom::profile::PressureHistory;

/// Epstein & Plesset (1950), J. Chem. Phys. 18:1505, eq. (18) with surface tension zero:
/// dR/dt = −D·L·(1 − f)·(1/R + 1/√(πDt)), L the Ostwald coefficient (the bubble's gas density
/// over the saturation concentration) and f = C_∞/C_s. Integrated here with RK4 in s = √t,
/// where the right-hand side is smooth. Returns (t, R) pairs until R reaches zero.
pub(crate) fn epstein_plesset(
    r0: f64,
    d: f64,
    l: f64,
    f: f64,
    dt_out: f64,
) -> (Vec<(f64, f64)>, f64) {
    let k = d * l * (1.0 - f);
    let rhs =
        |s: f64, r: f64| -2.0 * k * (s / r.max(1e-30) + 1.0 / (std::f64::consts::PI * d).sqrt());
    let mut out = vec![(0.0, r0)];
    let (mut s, mut r) = (0.0f64, r0);
    let ds = 1e-3 * r0 / (k / r0).sqrt().max(1e-30) / 50.0; // fine steps in √t
    let mut next = dt_out;
    loop {
        let k1 = rhs(s, r);
        let k2 = rhs(s + ds / 2.0, r + ds / 2.0 * k1);
        let k3 = rhs(s + ds / 2.0, r + ds / 2.0 * k2);
        let k4 = rhs(s + ds, r + ds * k3);
        let rn = r + ds / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        if rn <= 0.0 || rn < 1e-3 * r0 {
            // linear extrapolation to R = 0 in s
            let s0 = s + ds * r / (r - rn);
            return (out, s0 * s0);
        }
        s += ds;
        r = rn;
        if s * s >= next {
            out.push((s * s, r));
            next += dt_out;
        }
    }
}

fn ep_case(r0: f64, h: f64, half_width: f64, duration: f64) -> (Vec<(f64, f64)>, f64) {
    ep_case_with(r0, h, half_width, duration, 0.0)
}

/// The Epstein–Plesset set-up of [`epstein_plesset_dissolution`] with `p_fixed` Pa of
/// non-simulated gases in the bubble (`bubble_fixed_gases`): the gel's N2 tension stays 0.2·P.
pub(crate) fn ep_case_with(
    r0: f64,
    h: f64,
    half_width: f64,
    duration: f64,
    p_fixed: f64,
) -> (Vec<(f64, f64)>, f64) {
    let (d, l, f, p) = (2e-9, 0.014, 0.2, 1e5);
    let mut params = PhantomParams::box_phantom([2.0 * half_width; 3], h);
    params.surface_tension = 0.0;
    params.min_radius = 0.0;
    params.gases = vec![GasProperties {
        gas: Gas::N2,
        diffusivity: d,
        ostwald: l,
    }];
    params.open_faces = params.shape.faces().to_vec();
    let e = 2.0 * half_width;
    params.bubbles = BubblePlacement::Explicit(vec![([e / 2.0; 3], r0)]);
    params.bubble_fixed_gases = p_fixed;
    params.numerics.record_interval = 0.5;
    // Pure N2 in the bubble at P; the gel (and the open faces) at f·L·P/(R_u T): the profile's
    // "water vapour" of (1 − f)·P lowers the dissolved N2 tension to f·P.
    let profile = PressureHistory::with_gas(
        "ep",
        vec![0.0, duration],
        vec![p, p],
        GasMix { o2: 0.0, he: 0.0 },
        (1.0 - f) * p,
    )
    .unwrap();
    let mut sim = Simulation::new(&params, &profile).unwrap();
    let mut rec = Recorder::default();
    let summary = sim.run(&profile, &mut rec).unwrap();
    let hist: Vec<(f64, f64)> = rec
        .frames
        .iter()
        .map(|fr| (fr.time, fr.bubbles.first().map_or(0.0, |b| b.radius)))
        .collect();
    let t_end = summary.events.iter().find_map(|e| match e {
        decophantom::phantom::sim::Event::Dissolved { time, .. } => Some(*time),
        _ => None,
    });
    (hist, t_end.unwrap_or(f64::NAN))
}

/// Item 3 of the verification list. A pure-N2 bubble (γ = 0, Ω = 0, D_surf = D_bulk) dissolving in
/// gel at 20 % of its saturation (f = 0.2), L = 0.014 (Table 1's L_N2), D = 2e-9 m²/s, R0 = 100 µm,
/// open box of half-width 10·R0, at R0 = 2h and R0 = 4h, with the default steps (within 0.3 % of
/// step-converged runs: `bubble_steps`).
///
/// The reference is the independent, fully resolved 1-D radial solution of the same problem in
/// which the gel flows in behind the shrinking bubble (`displacement::displaced_reference`: mesh
/// fixed in the gel, Henry's law at R, no quasi-static assumption; 206.39 s). The static-gel
/// solution (`growth::resolved`, 206.92 s) is printed beside it, and Epstein–Plesset's closed
/// form (1950): it is quasi-static (the field is that of a sphere of fixed radius), so when the
/// bubble shrinks it ignores the gas the bubble released earlier and dissolves it too early
/// (5.0 % here); the model is judged against the resolved solution, not against EP.
#[test]
fn epstein_plesset_dissolution() {
    let r0 = 1e-4;
    let (d, l, f) = (2e-9, 0.014, 0.2);
    let (_, t_ep) = epstein_plesset(r0, d, l, f, 0.5);
    let case = crate::growth::Case {
        p: 1e5,
        d,
        d_surf: d,
        delta: 20e-6,
        l,
        gamma: 0.0,
        mu: 0.0,
        r0,
        f,
    };
    // the gel flows in behind the shrinking bubble: the displaced-gel reference
    let displaced = crate::displacement::Case {
        r0,
        gamma: 0.0,
        s: f,
        d,
        sealed_radius: None,
    };
    let (_, t_static) = crate::growth::resolved(&case, &[2.0 * t_ep]);
    let (_, t_resolved) =
        crate::displacement::displaced_reference(&displaced, &[2.0 * t_ep], 0.005);
    let times: Vec<f64> = (1..=9).map(|k| k as f64 * 0.1 * t_resolved).collect();
    let (r_resolved, _) = crate::displacement::displaced_reference(&displaced, &times, 0.005);
    eprintln!(
        "resolved 1-D dissolution {t_resolved:.2} s (static gel: {t_static:.2} s); Epstein–Plesset {t_ep:.2} s ({:+.4})",
        t_ep / t_resolved - 1.0
    );
    assert!(
        t_resolved > t_ep,
        "the resolved solution should dissolve later than quasi-static EP"
    );
    for cells in [2.0, 4.0] {
        let h = r0 / cells;
        let (hist, t_sim) = ep_case(r0, h, 10.0 * r0, 1.3 * t_ep);
        let at = |t: f64| {
            let i = hist
                .partition_point(|x| x.0 <= t)
                .min(hist.len() - 1)
                .max(1);
            let (a, b) = (hist[i - 1], hist[i]);
            a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
        };
        // radius over 10–70 % of the life (later R → 0 and relative errors lose meaning)
        let worst = times[..7]
            .iter()
            .zip(&r_resolved)
            .map(|(t, r)| (at(*t) / r - 1.0).abs())
            .fold(0.0, f64::max);
        eprintln!(
            "R0 = {cells} h: worst radius error over 10–70 % of the life {worst:.4}; dissolution {t_sim:.2} s ({:+.4} from the resolved solution)",
            t_sim / t_resolved - 1.0
        );
        assert!(worst < 0.015, "R0 = {cells} h: radius off by {worst:.4}");
        assert!(
            (t_sim / t_resolved - 1.0).abs() < 0.015,
            "R0 = {cells} h: dissolution {t_sim} s vs resolved {t_resolved} s"
        );
    }
}
