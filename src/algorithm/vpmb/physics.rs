//! The pieces of VPM-B as closed forms and small root finders: gas loading (Haldane and
//! Schreiner), nucleus crushing (permeable and impermeable), regeneration, the initial
//! allowable gradient, the critical-volume relaxation, Boyle's-law compensation and the
//! surface phase-volume time. Pressures in Pa, radii in m, surface tensions in N/m, time
//! in minutes, rates in Pa/min. Written from the published description of the Varying
//! Permeability Model (Yount & Hoffman 1986; Baker's VPM-B notes).

/// Nitrogen half-times of the 16 compartments, min (Bühlmann ZH-L16 with compartment 1b;
/// the set Baker's VPMDECO uses: Baker, "VPMDECO" program notes, note 1).
pub const N2_HALF_TIMES_MIN: [f64; 16] = [
    5.0, 8.0, 12.5, 18.5, 27.0, 38.3, 54.3, 77.0, 109.0, 146.0, 187.0, 239.0, 305.0, 390.0, 498.0,
    635.0,
];

/// Helium half-times of the 16 compartments, min (Bühlmann ZH-L16, compartment 1b = 1.88 min).
pub const HE_HALF_TIMES_MIN: [f64; 16] = [
    1.88, 3.02, 4.72, 6.99, 10.21, 14.48, 20.53, 29.11, 41.20, 55.19, 70.69, 90.34, 115.29, 147.42,
    188.24, 240.03,
];

/// Number of compartments.
pub const N: usize = 16;

/// Pa per fsw (1 atm = 33 fsw), the unit in which Baker states λ.
pub const PA_PER_FSW: f64 = crate::units::ATM_PA / 33.0;

/// Rate constants ln 2 / half-time, 1/min.
pub fn rate_constants(half_times: &[f64; N]) -> [f64; N] {
    let mut k = [0.0; N];
    for (ki, h) in k.iter_mut().zip(half_times) {
        *ki = std::f64::consts::LN_2 / h;
    }
    k
}

/// Haldane: tissue pressure after `t` min at constant inspired pressure `p_insp`
/// starting from `p0` (Pa), rate constant `k` (1/min).
pub fn haldane(p0: f64, p_insp: f64, k: f64, t: f64) -> f64 {
    p0 + (p_insp - p0) * (1.0 - (-k * t).exp())
}

/// Schreiner: tissue pressure after `t` min when the inspired pressure starts at `p_insp0`
/// and changes linearly at `r` Pa/min, starting from tissue pressure `p0`.
pub fn schreiner(p0: f64, p_insp0: f64, r: f64, k: f64, t: f64) -> f64 {
    p_insp0 + r * (t - 1.0 / k) - (p_insp0 - p0 - r / k) * (-k * t).exp()
}

/// Root of `a r³ − b r² − c = 0` in `[lo, hi]` by bisection (the two cubics of VPM-B have
/// this form; the caller brackets the root). Returns `None` if the bracket holds no sign change.
pub fn cubic_root(a: f64, b: f64, c: f64, lo: f64, hi: f64) -> Option<f64> {
    let f = |r: f64| ((a * r - b) * r) * r - c;
    bisect(f, lo, hi)
}

/// Bisection for a root of `f` in `[lo, hi]`; `None` without a sign change.
pub fn bisect(f: impl Fn(f64) -> f64, mut lo: f64, mut hi: f64) -> Option<f64> {
    let (mut flo, fhi) = (f(lo), f(hi));
    if flo == 0.0 {
        return Some(lo);
    }
    if fhi == 0.0 {
        return Some(hi);
    }
    if flo * fhi > 0.0 || !flo.is_finite() || !fhi.is_finite() {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        let fm = f(mid);
        if fm == 0.0 {
            return Some(mid);
        }
        if (fm < 0.0) == (flo < 0.0) {
            lo = mid;
            flo = fm;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// Surface-tension constants of a nucleus.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Skin {
    /// Surface tension γ, N/m.
    pub gamma: f64,
    /// Skin compression γc, N/m.
    pub gamma_c: f64,
}

impl Skin {
    /// 2(γc − γ), N/m: the net inward pull per unit curvature of a nucleus being crushed.
    pub fn two_net(&self) -> f64 {
        2.0 * (self.gamma_c - self.gamma)
    }

    /// Radius after a crushing pressure `crush` Pa of a nucleus of critical radius `r0` m,
    /// in the permeable regime: 1/r = Δp / (2(γc − γ)) + 1/r0.
    pub fn crushed_radius(&self, r0: f64, crush: f64) -> f64 {
        1.0 / (crush / self.two_net() + 1.0 / r0)
    }

    /// Initial allowable supersaturation gradient for a nucleus of radius `r` m, Pa:
    /// 2γ(γc − γ) / (r γc).
    pub fn initial_gradient(&self, r: f64) -> f64 {
        2.0 * self.gamma * (self.gamma_c - self.gamma) / (r * self.gamma_c)
    }

    /// Crushing pressure in the impermeable regime, Pa. The nucleus became impermeable at
    /// ambient `p_onset` with gas tension `t_onset` (Pa), radius `r_onset`; its gas now obeys
    /// Boyle's law, p_in = t_onset (r_onset/r)³, and the skin balance holds:
    /// p_amb − p_in = 2(γc − γ)(1/r − 1/r0). Solves for r at ambient `p_end` and returns
    /// the crushing pressure p_end − p_in. `None` if no radius balances.
    pub fn impermeable_crush(
        &self,
        r_onset: f64,
        p_onset: f64,
        t_onset: f64,
        p_end: f64,
    ) -> Option<f64> {
        if p_end <= p_onset {
            // Still at the onset: the nucleus has not been compressed beyond it.
            return Some(p_end - t_onset);
        }
        let b = self.two_net();
        let a = p_end - p_onset + t_onset + b / r_onset;
        let c = t_onset * r_onset.powi(3);
        let r = cubic_root(a, b, c, b / a, r_onset)?;
        Some(p_end - t_onset * (r_onset / r).powi(3))
    }

    /// Radius of a bubble grown by Boyle's law with surface tension from `r1` at ambient `p1`
    /// to ambient `p2` (< p1): (p1 + 2γ/r1) r1³ = (p2 + 2γ/r2) r2³.
    pub fn boyle_radius(&self, r1: f64, p1: f64, p2: f64) -> Option<f64> {
        let c = (p1 + 2.0 * self.gamma / r1) * r1.powi(3);
        let hi = r1 * (p1 / p2).cbrt();
        if (hi - r1).abs() <= f64::EPSILON * r1 {
            return Some(r1);
        }
        cubic_root(p2, -2.0 * self.gamma, c, r1, hi)
    }

    /// Boyle's-law compensated gradient, Pa: a bubble sized by the allowable gradient `g`
    /// (r = 2γ/g) at the first stop (ambient `p_first`) expands on the way to ambient
    /// `p_next`; the gradient it allows there is 2γ/r_next.
    pub fn boyle_gradient(&self, g: f64, p_first: f64, p_next: f64) -> Option<f64> {
        let r1 = 2.0 * self.gamma / g;
        Some(2.0 * self.gamma / self.boyle_radius(r1, p_first, p_next)?)
    }
}

/// Nuclear regeneration over a dive of `t_min` minutes with time constant `tau_min`: the
/// crushed radius relaxes back towards the critical radius `r0`. Returns (regenerated
/// radius, adjusted crushing pressure Pa). r_reg = r0 + (r_crushed − r0) e^(−t/τ); the
/// crushing pressure is scaled by r_crushed (r0 − r_reg) / (r_reg (r0 − r_crushed)), which
/// equals e^(−t/τ) r_crushed / r_reg (the form used here, exact also for zero crushing).
pub fn regenerate(skin: &Skin, r0: f64, crush: f64, t_min: f64, tau_min: f64) -> (f64, f64) {
    let r_end = skin.crushed_radius(r0, crush);
    let e = (-t_min / tau_min).exp();
    let r_reg = r0 + (r_end - r0) * e;
    (r_reg, crush * e * r_end / r_reg)
}

/// Critical-volume relaxation: the allowable gradient G solving
/// G² − (G0 + λγ/(γc t)) G + λγ² p_crush/(γc² t) = 0 (larger root), with G0 the initial
/// allowable gradient (Pa), λ in Pa·min, t the phase-volume time (min), p_crush the
/// adjusted crushing pressure (Pa).
pub fn critical_volume_gradient(
    skin: &Skin,
    g0: f64,
    lambda_pa_min: f64,
    crush: f64,
    t: f64,
) -> f64 {
    let (g, gc) = (skin.gamma, skin.gamma_c);
    let b = g0 + lambda_pa_min * g / (gc * t);
    let c = g * g * lambda_pa_min * crush / (gc * gc * t);
    0.5 * (b + (b * b - 4.0 * c).max(0.0).sqrt())
}

/// Surface phase-volume time, min: the time integral of the supersaturation after
/// surfacing (He decaying to 0, N2 to the surface inspired `n2_surf`), divided by its
/// initial value. `he`, `n2` tissue pressures (Pa) at surfacing.
pub fn surface_phase_volume_time(he: f64, n2: f64, n2_surf: f64, k_he: f64, k_n2: f64) -> f64 {
    let g0 = he + n2 - n2_surf;
    if n2 > n2_surf {
        (he / k_he + (n2 - n2_surf) / k_n2) / g0
    } else if g0 > 0.0 && he > 0.0 {
        // He decays faster than N2 recovers; the gradient reaches zero at time τ.
        let tau = ((n2_surf - n2) / he).ln() / (k_n2 - k_he);
        let integral = he / k_he * (1.0 - (-k_he * tau).exp())
            + (n2 - n2_surf) / k_n2 * (1.0 - (-k_n2 * tau).exp());
        integral / g0
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SKIN: Skin = Skin {
        gamma: 0.0179,
        gamma_c: 0.257,
    };

    #[test]
    fn initial_gradient_matches_closed_form() {
        // 2γ(γc−γ)/(r γc) with r = 0.55 µm (Baker's VPM-B N2 default): 2·0.0179·0.2391/(0.55e-6·0.257).
        let r = 0.55e-6;
        let want = 2.0 * 0.0179 * (0.257 - 0.0179) / (r * 0.257);
        assert!((SKIN.initial_gradient(r) - want).abs() < 1e-9 * want);
        // ≈ 60 560 Pa ≈ 0.598 atm: the textbook VPM N2 gradient for 0.55 µm.
        assert!((want - 60_561.0).abs() < 5.0, "{want}");
    }

    #[test]
    fn schreiner_reduces_to_haldane_and_solves_the_ode() {
        let k = std::f64::consts::LN_2 / 12.5;
        assert!((schreiner(7e4, 3e5, 0.0, k, 7.0) - haldane(7e4, 3e5, k, 7.0)).abs() < 1e-8);
        // Independent: integrate dp/dt = k (p_insp0 + r t − p) with RK4.
        let (p0, pi, r) = (7.5e4, 1.0e5, 7.9e3);
        let (mut p, mut t, h) = (p0, 0.0, 1e-3);
        let f = |t: f64, p: f64| k * (pi + r * t - p);
        while t < 3.0 - 1e-12 {
            let k1 = f(t, p);
            let k2 = f(t + h / 2.0, p + h / 2.0 * k1);
            let k3 = f(t + h / 2.0, p + h / 2.0 * k2);
            let k4 = f(t + h, p + h * k3);
            p += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
            t += h;
        }
        assert!((schreiner(p0, pi, r, k, 3.0) - p).abs() < 1e-6, "{p}");
    }

    #[test]
    fn crushing_radius_and_impermeable_branch() {
        let r0 = 0.6e-6;
        // Permeable: Laplace-type balance Δp = 2(γc−γ)(1/r − 1/r0).
        let crush = 3.0e5;
        let r = SKIN.crushed_radius(r0, crush);
        assert!((SKIN.two_net() * (1.0 / r - 1.0 / r0) - crush).abs() < 1e-6);
        // Impermeable: at onset the two branches agree (continuity).
        let g_on = 8.2 * 101_325.0;
        let r_on = SKIN.crushed_radius(r0, g_on);
        let (p_on, t_on) = (1.2e6, 1.2e6 - g_on);
        let c = SKIN.impermeable_crush(r_on, p_on, t_on, p_on).unwrap();
        assert!((c - g_on).abs() < 1e-3 * g_on, "{c}");
        // Deeper: solve the balance p_end − p_in(r) = 2(γc−γ)(1/r − 1/r0) independently by a
        // plain bisection on r (negative for tiny r, positive at r_onset) and compare.
        let p_end = 2.0e6;
        let c = SKIN.impermeable_crush(r_on, p_on, t_on, p_end).unwrap();
        let bal =
            |r: f64| p_end - t_on * (r_on / r).powi(3) - SKIN.two_net() * (1.0 / r - 1.0 / r0);
        let (mut lo, mut hi) = (1e-9, r_on);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if bal(mid) < 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let r = 0.5 * (lo + hi);
        let want = p_end - t_on * (r_on / r).powi(3);
        assert!((c - want).abs() < 1e-6 * want, "{c} vs {want}");
        // The crushing pressure is smaller than the permeable one would be (gas resists).
        assert!(c < p_end - t_on);
    }

    #[test]
    fn critical_volume_quadratic() {
        // Solve the same relation independently: bisection on
        // (G − G0)·G·t·γc²  =  λγ (γc G − γ p_crush)  ⇔  G² − bG + c = 0.
        let g0 = SKIN.initial_gradient(0.55e-6);
        let lambda = 7500.0 * PA_PER_FSW;
        let crush = 2.5e5;
        let t = 42.0;
        let g = critical_volume_gradient(&SKIN, g0, lambda, crush, t);
        let (gm, gc) = (SKIN.gamma, SKIN.gamma_c);
        let f = |x: f64| (x - g0) * x * t * gc * gc - lambda * gm * (gc * x - gm * crush);
        let root = bisect(f, g0, 1e7).unwrap();
        assert!((g - root).abs() < 1e-6 * root, "{g} vs {root}");
        assert!(g > g0, "the critical volume relaxes the gradient");
    }

    #[test]
    fn boyle_compensation_conserves_pv_with_surface_tension() {
        let g = 5.0e4;
        let (p1, p2) = (4.0e5, 1.3e5);
        let r1 = 2.0 * SKIN.gamma / g;
        let r2 = SKIN.boyle_radius(r1, p1, p2).unwrap();
        let lhs = (p1 + 2.0 * SKIN.gamma / r1) * r1.powi(3);
        let rhs = (p2 + 2.0 * SKIN.gamma / r2) * r2.powi(3);
        assert!((lhs - rhs).abs() < 1e-9 * lhs);
        let g2 = SKIN.boyle_gradient(g, p1, p2).unwrap();
        assert!(g2 < g && (g2 - 2.0 * SKIN.gamma / r2).abs() < 1e-9 * g2);
    }

    #[test]
    fn regeneration_limits() {
        let r0 = 0.55e-6;
        let crush = 4.0e5;
        // No time: nothing regenerates, the crushing pressure is kept.
        let (r, c) = regenerate(&SKIN, r0, crush, 0.0, 20160.0);
        assert!((r - SKIN.crushed_radius(r0, crush)).abs() < 1e-18 && (c - crush).abs() < 1e-6);
        // Long time: back to the critical radius, no crushing left.
        let (r, c) = regenerate(&SKIN, r0, crush, 1e7, 20160.0);
        assert!((r - r0).abs() < 1e-15 && c.abs() < 1e-3);
        // The scaling equals the defining ratio r_end (r0 − r_reg)/(r_reg (r0 − r_end)).
        let (r_reg, c) = regenerate(&SKIN, r0, crush, 500.0, 20160.0);
        let r_end = SKIN.crushed_radius(r0, crush);
        let ratio = r_end * (r0 - r_reg) / (r_reg * (r0 - r_end));
        assert!((c - crush * ratio).abs() < 1e-6 * crush);
    }

    #[test]
    fn surface_phase_volume_time_matches_numerical_integral() {
        let (k_he, k_n2) = (
            std::f64::consts::LN_2 / 14.48,
            std::f64::consts::LN_2 / 38.3,
        );
        let s = 0.79 * (101_325.0 - 4_930.0);
        for &(he, n2) in &[(3.0e4, 9.0e4), (4.0e4, 7.0e4), (0.0, 1.2e5), (1.0e3, 7.0e4)] {
            let g = |t: f64| he * (-k_he * t).exp() + s + (n2 - s) * (-k_n2 * t).exp() - s;
            let g0 = g(0.0);
            // Integrate the positive part of the gradient with the trapezoid rule.
            let (mut sum, h) = (0.0, 1e-3);
            let mut t = 0.0;
            while t < 3000.0 {
                let (a, b) = (g(t).max(0.0), g(t + h).max(0.0));
                if a == 0.0 && b == 0.0 && t > 10.0 {
                    break;
                }
                sum += 0.5 * h * (a + b);
                t += h;
            }
            let want = if g0 > 0.0 { sum / g0 } else { 0.0 };
            let got = surface_phase_volume_time(he, n2, s, k_he, k_n2);
            assert!(
                (got - want).abs() < 1e-3 * want.max(1.0),
                "{he} {n2}: {got} vs {want}"
            );
        }
    }
}
