//! Bubbles displace the gel (issue 8, item 5), judged against two references that share no code
//! with the library:
//! - Scriven's similarity solution for a bubble growing from zero at constant supersaturation
//!   in a medium pushed outward by it (L. E. Scriven 1959, "On the dynamics of phase growth",
//!   Chem. Eng. Sci. 10, 1–13, eq. for the spherical case with ε = 1): R = 2β√(Dt) with
//!   (C∞ − C_s)/ρ_g = 2β³ exp(β² + 2εβ²) ∫_β^∞ x⁻² exp(−x² − 2εβ³/x) dx, solved here by
//!   bisection with Simpson's rule. (Derivation, for the reader: with η = r/2√(Dt) and the
//!   gel velocity u = εR²Ṙ/r², the diffusion–convection equation becomes
//!   C'' = −C'(2η + 2/η − 2εβ³/η²), so C' ∝ η⁻² exp(−η² − 2εβ³/η); Henry at η = β and the
//!   interface balance ρ_g Ṙ = D ∂C/∂r give the relation above.)
//! - A fully resolved 1-D radial solution in which the gel is incompressible and moves with the
//!   bubble wall: its mesh is fixed in the gel's volume coordinate m = r³ − R³ (each cell holds
//!   the same gel for all time, so the displacement is exact and gas is conserved to
//!   round-off), backward Euler in the gel, Henry's law at the wall, the bubble's content from
//!   the wall flux, and its radius from P_B·V = nR_uT with P_B = P + 2γ/R. The reference is
//!   itself checked against Scriven at two supersaturations.

use decophantom::gas::{Gas, GasMix};
use decophantom::phantom::params::{BubblePlacement, GasProperties, PhantomParams};
use decophantom::phantom::sim::{Recorder, Simulation};
use decophantom::profile::PressureHistory;
use std::f64::consts::PI;

const RU: f64 = 8.314_462_618; // J/(mol K), CODATA 2018
const T: f64 = 310.15; // K
const P: f64 = 1e5; // Pa
const D: f64 = 2.5e-9; // m²/s
const L: f64 = 0.014; // Ostwald coefficient of N2 (the paper's Table 1)

/// Scriven's growth constant β for supersaturation `ja` = (C∞ − C_s)/ρ_g and convection `eps`.
pub fn scriven_beta(ja: f64, eps: f64) -> f64 {
    let phi = |b: f64| {
        // ∫_b^∞ x⁻² exp(−x² − 2εb³/x) dx by Simpson's rule on [b, b + 12]
        let n = 20_000;
        let (a, top) = (b, b + 12.0);
        let h = (top - a) / n as f64;
        let f = |x: f64| x.powi(-2) * (-x * x - 2.0 * eps * b.powi(3) / x).exp();
        let mut s = f(a) + f(top);
        for i in 1..n {
            s += f(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        2.0 * b.powi(3) * (b * b * (1.0 + 2.0 * eps)).exp() * s * h / 3.0
    };
    let (mut lo, mut hi) = (1e-4f64, 10.0f64);
    for _ in 0..80 {
        let m = (lo * hi).sqrt();
        if phi(m) < ja {
            lo = m
        } else {
            hi = m
        }
    }
    (lo * hi).sqrt()
}

/// One single-gas bubble problem for the displaced-gel reference (SI units).
#[derive(Clone, Copy)]
pub struct Case {
    /// Initial radius, m.
    pub r0: f64,
    /// Surface tension, N/m.
    pub gamma: f64,
    /// Gel tension over ambient (supersaturation ratio; below 1 the bubble dissolves).
    pub s: f64,
    /// Diffusivity, m²/s.
    pub d: f64,
    /// Radius of the sealed outer sphere (the gel's volume), m; infinite gel if `None`
    /// (far field held at C∞ at 20 mm).
    pub sealed_radius: Option<f64>,
}

impl Case {
    fn pv(&self, r: f64) -> f64 {
        (P + 2.0 * self.gamma / r) * 4.0 / 3.0 * PI * r.powi(3)
    }
    fn radius_of(&self, n: f64) -> f64 {
        let target = n * RU * T;
        let (mut a, mut b) = (1e-9f64, 1e-1f64);
        for _ in 0..200 {
            let m = (a * b).sqrt();
            if self.pv(m) < target {
                a = m
            } else {
                b = m
            }
        }
        (a * b).sqrt()
    }
}

/// The displaced-gel reference: radius at the requested times (0 once dissolved) and the
/// dissolution time (NaN if the bubble survives).
pub fn displaced_reference(case: &Case, times: &[f64], dt: f64) -> (Vec<f64>, f64) {
    let r0 = case.r0;
    let d = case.d;
    // mesh in the gel's initial radius: 0.01 µm at the wall, growing 1 % a cell (fixed in the
    // gel, the cells at the wall thicken as a bubble shrinks: the EP dissolution time moves
    // from 210.60 s at 0.25 µm/3 % to 207.48 s at 0.05 µm/1 % and 206.39 s at 0.01 µm with
    // 1 % or 0.5 %)
    let outer = case.sealed_radius.unwrap_or(20e-3);
    let mut radii = vec![r0];
    let mut w = 0.01e-6;
    while *radii.last().unwrap() < outer {
        radii.push((radii.last().unwrap() + w).min(outer));
        w *= 1.01;
    }
    let m: Vec<f64> = radii.iter().map(|r| r.powi(3) - r0.powi(3)).collect();
    let nc = m.len() - 1;
    let vol: Vec<f64> = (0..nc)
        .map(|i| 4.0 / 3.0 * PI * (m[i + 1] - m[i]))
        .collect();
    let c_inf = case.s * L * P / (RU * T);
    let mut c = vec![c_inf; nc];
    let mut n = case.pv(r0) / (RU * T);
    let mut r = r0;
    let (mut a, mut b, mut cc, mut rhs) =
        (vec![0.0; nc], vec![0.0; nc], vec![0.0; nc], vec![0.0; nc]);
    let mut t = 0.0;
    let mut out = Vec::new();
    let mut next = 0;
    while next < times.len() {
        let cs = L * (case.pv(r) / (4.0 / 3.0 * PI * r.powi(3))) / (RU * T);
        // face radii now, and cell centres (volume midpoints)
        let face: Vec<f64> = m.iter().map(|mi| (r.powi(3) + mi).cbrt()).collect();
        let centre: Vec<f64> = (0..nc)
            .map(|i| (0.5 * (face[i].powi(3) + face[i + 1].powi(3))).cbrt())
            .collect();
        for i in 0..nc {
            let g_in = if i == 0 {
                4.0 * PI * face[0].powi(2) * d / (centre[0] - face[0])
            } else {
                4.0 * PI * face[i].powi(2) * d / (centre[i] - centre[i - 1])
            };
            let g_out = if i == nc - 1 {
                if case.sealed_radius.is_some() {
                    0.0
                } else {
                    4.0 * PI * face[nc].powi(2) * d / (face[nc] - centre[nc - 1])
                }
            } else {
                4.0 * PI * face[i + 1].powi(2) * d / (centre[i + 1] - centre[i])
            };
            a[i] = if i == 0 { 0.0 } else { -dt * g_in / vol[i] };
            cc[i] = if i == nc - 1 {
                0.0
            } else {
                -dt * g_out / vol[i]
            };
            b[i] = 1.0 + dt * (g_in + g_out) / vol[i];
            rhs[i] = c[i];
            if i == 0 {
                rhs[i] += dt * g_in * cs / vol[i];
            }
            if i == nc - 1 && case.sealed_radius.is_none() {
                rhs[i] += dt * g_out * c_inf / vol[i];
            }
        }
        for i in 1..nc {
            let q = a[i] / b[i - 1];
            b[i] -= q * cc[i - 1];
            rhs[i] -= q * rhs[i - 1];
        }
        c[nc - 1] = rhs[nc - 1] / b[nc - 1];
        for i in (0..nc - 1).rev() {
            c[i] = (rhs[i] - cc[i] * c[i + 1]) / b[i];
        }
        // the bubble takes what crosses its wall (the same flux the gel lost: conservative)
        let flux = 4.0 * PI * face[0].powi(2) * d * (c[0] - cs) / (centre[0] - face[0]);
        n += flux * dt;
        t += dt;
        if n <= 0.0 {
            // dissolved within this step: the moment n crossed zero
            let gone = t - dt * (n / (flux * dt)).abs().min(1.0);
            out.resize(times.len(), 0.0);
            return (out, gone);
        }
        r = case.radius_of(n);
        while next < times.len() && t >= times[next] - 1e-9 {
            out.push(r);
            next += 1;
        }
    }
    (out, f64::NAN)
}

/// The 3-D model: one bubble of radius `r0` at the centre of a sealed cube of side `side` at
/// grid step `h`, gel at `s` × saturation, γ = `gamma`; radius at `times`.
fn three_d(
    side: f64,
    h: f64,
    r0: f64,
    gamma: f64,
    s: f64,
    displace: bool,
    times: &[f64],
) -> Vec<f64> {
    let mut p = PhantomParams::box_phantom([side; 3], h);
    p.open_faces = vec![];
    p.temperature = T;
    p.surface_tension = gamma;
    p.min_radius = 0.0;
    p.gases = vec![GasProperties {
        gas: Gas::N2,
        diffusivity: D,
        ostwald: L,
    }];
    p.bubbles = BubblePlacement::Explicit(vec![([side / 2.0; 3], r0)]);
    p.numerics.displace_gel = displace;
    let end = *times.last().unwrap();
    let prof = PressureHistory::with_gas(
        "ss",
        vec![0.0, end],
        vec![P, P],
        GasMix { o2: 0.0, he: 0.0 },
        0.0,
    )
    .unwrap();
    let mut sim = Simulation::new(&p, &prof).unwrap();
    let c = s * L * P / (RU * T);
    for idx in 0..sim.grid().len() {
        if sim.grid().inside(idx) {
            sim.field_mut(0)[idx] = c;
        }
    }
    sim.rebase_balance();
    let mut rec = Recorder::default();
    let summary = sim.run(&prof, &mut rec).unwrap();
    assert!(
        summary.gas_balance_error < 1e-9,
        "{}",
        summary.gas_balance_error
    );
    times
        .iter()
        .map(|t| {
            let f = rec.frames.iter().find(|f| f.time >= t - 1e-9).unwrap();
            f.bubbles[0].radius
        })
        .collect()
}

/// The reference against Scriven: from a 10 µm seed with γ = 0 in an unbounded gel, the late
/// growth follows R² = 4β²Dt + const; the slope of R² over 200–300 s is 4β²D within 0.5 % at
/// supersaturation ratios 9.9 and 3, while Scriven without convection (ε = 0) is 4–9 % away
/// at 9.9 — the reference resolves the displacement, not just the diffusion.
#[test]
fn displaced_reference_follows_scriven() {
    for s in [9.9, 3.0] {
        let ja = L * (s - 1.0); // (C∞ − C_s)/ρ_g with ρ_g = P/(R_u T), C_s = L·P/(R_u T)
        let beta = scriven_beta(ja, 1.0);
        let beta0 = scriven_beta(ja, 0.0);
        let case = Case {
            r0: 10e-6,
            gamma: 0.0,
            s,
            d: D,
            sealed_radius: None,
        };
        let (r, _) = displaced_reference(&case, &[200.0, 300.0], 0.01);
        let slope = (r[1].powi(2) - r[0].powi(2)) / 100.0;
        let want = 4.0 * beta * beta * D;
        let want0 = 4.0 * beta0 * beta0 * D;
        eprintln!(
            "S = {s}: β = {beta:.5} (ε = 0: {beta0:.5}); dR²/dt {slope:.4e} against 4β²D {want:.4e} ({:+.2} %), ε = 0 {:+.2} %",
            100.0 * (slope / want - 1.0),
            100.0 * (slope / want0 - 1.0)
        );
        assert!((slope / want - 1.0).abs() < 0.005);
    }
}

/// The 3-D model against Scriven at the two supersaturations: a 150 µm bubble with γ = 0 in a
/// sealed cube at h = 50 µm (6 mm at S = 9.9; 4 mm at S = 3, where it grows only to 270 µm);
/// the slope of R² over 200–300 s, fitted by least squares to the 101 frames of that stretch,
/// against Scriven's 4β²D with ε = 1.
///
/// At S = 9.9 ε = 0 (no displacement) is 8.3 % higher than ε = 1, so the test tells the two
/// apart; within 1 %. At S = 3 the two differ by only 1.6 % and the model's own discretisation
/// is larger than that (measured 26 Nov 2026, every step within the explicit limit, i.e. the
/// time step converged: +3.4 / −1.5 / +1.2 / +1.8 % from ε = 1 at h = 100 / 66.7 / 50 / 40 µm,
/// the bubble's centre falling differently on each grid), so that case checks only that the
/// growth is Scriven's within 3 %. The slope used to be taken from two frames (200 and 300 s):
/// that one passed at S = 3 (+0.24 %) by a lucky draw. A change of the last bit of the
/// bubbles' step estimate moved it to +2.0 %, with the time-converged value at +1.2 %.
#[test]
fn resolved_bubble_grows_as_scriven_with_convection() {
    // at S = 3 the bubble grows from 150 to 270 µm: h = 50 µm (4 mm cube) to resolve it
    for (s, side, h, tol) in [(9.9, 6e-3, 50e-6, 0.01), (3.0, 4e-3, 50e-6, 0.03)] {
        let ja = L * (s - 1.0);
        let beta = scriven_beta(ja, 1.0);
        let beta0 = scriven_beta(ja, 0.0);
        let times: Vec<f64> = (0..=100).map(|i| 200.0 + f64::from(i)).collect();
        let r = three_d(side, h, 150e-6, 0.0, s, true, &times);
        let r2: Vec<f64> = r.iter().map(|x| x * x).collect();
        let slope = least_squares_slope(&times, &r2);
        let (want, want0) = (4.0 * beta * beta * D, 4.0 * beta0 * beta0 * D);
        eprintln!(
            "3-D, S = {s}: dR²/dt {slope:.4e}; Scriven ε = 1 {want:.4e} ({:+.2} %), ε = 0 {want0:.4e} ({:+.2} %)",
            100.0 * (slope / want - 1.0),
            100.0 * (slope / want0 - 1.0)
        );
        assert!((slope / want - 1.0).abs() < tol);
    }
}

/// The least-squares slope of y over x.
fn least_squares_slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    sxy / sxx
}

#[test]
fn least_squares_slope_of_a_line_is_its_slope() {
    // y = 3x − 2 with symmetric residuals that cancel (an independent hand computation)
    let x = [0.0, 1.0, 2.0, 3.0, 4.0];
    let y = [-2.0 + 0.5, 1.0 - 0.5, 4.0, 7.0 - 0.5, 10.0 + 0.5];
    assert!((least_squares_slope(&x, &y) - 3.0).abs() < 1e-12);
}

/// The case: a 150 µm bubble (γ = 0.07 N/m) at supersaturation ratio 9.9, D_surf = D,
/// in a sealed 6 mm cube, against the displaced-gel reference (a sealed sphere of the cube's
/// volume: the same gas). With the displacement the radius is within 1.5 % at h = 100 µm and
/// closer than at 200 µm at 300 s; without it the model is 3.5 % high at 100 µm and moves
/// away as the grid is refined (issue 8: 569/584/592 µm at h = 173/86.5/43 µm).
#[test]
fn resolved_bubble_approaches_the_displaced_gel_solution() {
    let times = [100.0, 200.0, 300.0];
    let err = study(6e-3, &[200e-6, 100e-6], &times);
    // the first 100 s carry the quasi-steady shell's lag (−2 %)
    for (t, e) in times.iter().zip(&err[1].0) {
        let tol = if *t > 150.0 { 0.015 } else { 0.025 };
        assert!(e.abs() < tol, "h = 100 µm, t = {t} s: {:+.2} %", 100.0 * e);
    }
    assert!(err[1].0[2].abs() < err[0].0[2].abs());
    assert!(err[1].1[2] > 0.03 && err[1].1[2] > err[0].1[2]);
}

/// The same on finer grids in a 4 mm cube, h = 100, 50 and 25 µm (about 80 s on 2 cores). When
/// written, at 100/200/300 s: h = 100 µm +2.11/+0.46/−0.04 % (the bubble displaces once
/// R ≥ 4h = 400 µm), 50 µm −0.32/+0.35/−0.11 %, 25 µm +0.14/+0.16/+0.24 %; without the
/// displacement +3.50 % and +4.77 % at 300 s for h = 100 and 50 µm, moving away.
#[test]
#[ignore = "fine grids, about 80 s on 2 cores: cargo test --release -- --ignored"]
fn resolved_bubble_on_fine_grids() {
    let times = [100.0, 200.0, 300.0];
    let err = study(4e-3, &[100e-6, 50e-6, 25e-6], &times);
    for (h, (e, _)) in [100, 50, 25].iter().zip(&err).skip(1) {
        for (t, x) in times.iter().zip(e) {
            assert!(
                x.abs() < 0.005,
                "h = {h} µm, t = {t} s: {:+.2} %",
                100.0 * x
            );
        }
    }
}

/// Relative radius errors against the reference per grid step: (with, without displacement).
fn study(side: f64, steps: &[f64], times: &[f64]) -> Vec<(Vec<f64>, Vec<f64>)> {
    let case = Case {
        r0: 150e-6,
        gamma: 0.07,
        s: 9.9,
        d: D,
        sealed_radius: Some((3.0 * side.powi(3) / (4.0 * PI)).cbrt()),
    };
    let (reference, _) = displaced_reference(&case, times, 0.01);
    steps
        .iter()
        .map(|&h| {
            let mut both = (Vec::new(), Vec::new());
            for displace in [true, false] {
                if !displace && h < 50e-6 {
                    continue;
                }
                let model = three_d(side, h, case.r0, case.gamma, case.s, displace, times);
                for ((t, a), b) in times.iter().zip(&reference).zip(&model) {
                    let e = b / a - 1.0;
                    eprintln!(
                        "h = {:.0} µm, displacement {displace}: t = {t} s: reference {:.2} µm, model {:.2} µm ({:+.2} %)",
                        h * 1e6,
                        a * 1e6,
                        b * 1e6,
                        100.0 * e
                    );
                    if displace {
                        both.0.push(e)
                    } else {
                        both.1.push(e)
                    }
                }
            }
            both
        })
        .collect()
}
