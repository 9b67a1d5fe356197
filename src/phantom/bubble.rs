//! A bubble's state is the amount of each gas it holds (mol). Its radius follows from the
//! ideal-gas law with the Young–Laplace balance, eq. (2.4):
//! (P_amb + 2γ/R + Ω(R) − p_fixed)·(4/3)πR³ = n_total·R_u·T,
//! where p_fixed is the fixed partial pressure of gases that are not simulated (water vapour,
//! CO2, unsimulated O2; 0 by default), so n_total counts the simulated gases only.
//! solved by a bracketed, safeguarded secant root find. (Eq. 2.5 is the derivative of this
//! balance; the printed 2.5 and 2.10 carry sign/term misprints and are not used.)

use super::elasticity::{ElasticState, ElasticityLaw};
use std::f64::consts::PI;

/// What happened to a bubble.
#[derive(Debug, Clone, PartialEq)]
pub enum BubbleFate {
    /// Still in the phantom.
    Active,
    /// All its gas dissolved at this time (s).
    Dissolved(f64),
    /// Merged into bubble `into` at this time (s).
    Merged {
        /// Id of the surviving bubble.
        into: usize,
        /// Time, s.
        time: f64,
    },
}

/// One bubble.
#[derive(Debug, Clone)]
pub struct Bubble {
    /// Stable id (0-based, in creation order).
    pub id: usize,
    /// Centre, m.
    pub position: [f64; 3],
    /// Initial radius R_0, m (reference radius of the elasticity and surface laws).
    pub initial_radius: f64,
    /// Ambient pressure when created, Pa (P_0 of eq. 2.8).
    pub initial_ambient: f64,
    /// Amount of each gas, mol, in the simulation's gas order.
    pub moles: Vec<f64>,
    /// Current radius, m.
    pub radius: f64,
    /// Fate.
    pub fate: BubbleFate,
}

impl Bubble {
    /// Total gas, mol.
    pub fn total_moles(&self) -> f64 {
        self.moles.iter().sum()
    }
    /// Volume, m³.
    pub fn volume(&self) -> f64 {
        4.0 / 3.0 * PI * self.radius.powi(3)
    }
    /// Surface area, m².
    pub fn area(&self) -> f64 {
        4.0 * PI * self.radius.powi(2)
    }
    /// Whether the bubble is still in the phantom.
    pub fn active(&self) -> bool {
        self.fate == BubbleFate::Active
    }
}

/// Everything the Laplace balance needs besides the radius.
#[derive(Debug, Clone, Copy)]
pub struct Balance<'a> {
    /// Ambient pressure, Pa.
    pub ambient: f64,
    /// Surface tension γ, N/m.
    pub surface_tension: f64,
    /// Tissue elasticity law.
    pub law: &'a dyn ElasticityLaw,
    /// R_0, m.
    pub initial_radius: f64,
    /// P_0, Pa.
    pub initial_ambient: f64,
    /// Fixed partial pressure of the gases that are not simulated, p_fixed, Pa (0 = none).
    pub fixed_gases: f64,
}

impl Balance<'_> {
    /// Pressure inside a bubble of radius `r`: P_amb + 2γ/R + Ω(R), Pa (eq. 2.4).
    pub fn internal_pressure(&self, r: f64) -> f64 {
        let s = ElasticState {
            radius: r,
            initial_radius: self.initial_radius,
            ambient: self.ambient,
            initial_ambient: self.initial_ambient,
        };
        self.ambient + 2.0 * self.surface_tension / r + self.law.omega(&s)
    }

    /// Partial pressure of the simulated gases in a bubble of radius `r`: P_B(R) − p_fixed, Pa.
    pub fn simulated_pressure(&self, r: f64) -> f64 {
        self.internal_pressure(r) - self.fixed_gases
    }

    /// Amount of simulated gas × R_u·T (J) that a bubble of radius `r` holds:
    /// (P_B(R) − p_fixed)·(4/3)πR³.
    pub fn pv(&self, r: f64) -> f64 {
        self.simulated_pressure(r) * 4.0 / 3.0 * PI * r.powi(3)
    }

    /// The radius at which P_B·V = `nrt` (J), searched upward from 1e-9 m to 10 m starting
    /// near `guess`. `None` if there is no root (no physical equilibrium radius) in that range.
    /// When the balance is not monotone, the smallest root above 1e-9 m is returned.
    pub fn radius_for(&self, nrt: f64, guess: f64) -> Option<f64> {
        if !(nrt > 0.0) || !nrt.is_finite() {
            return None;
        }
        let f = |r: f64| self.pv(r) - nrt;
        const LO: f64 = 1e-9;
        const HI: f64 = 10.0;
        // Bracket: try a narrow bracket around the guess first (fast path in the time loop).
        let mut bracket = None;
        if guess.is_finite() && guess > LO && guess < HI {
            let (a, b) = (guess * 0.8, (guess * 1.25).min(HI));
            if f(a) < 0.0 && f(b) >= 0.0 && self.pv(a) > 0.0 {
                bracket = Some((a, b));
            }
        }
        if bracket.is_none() {
            // scan upward geometrically from LO for the first sign change from − to +
            let mut a = LO;
            let mut fa = f(a);
            let mut r = LO;
            while r < HI {
                let b = (r * 1.25).min(HI);
                let fb = f(b);
                if fa < 0.0 && fb >= 0.0 {
                    bracket = Some((a, b));
                    break;
                }
                a = b;
                fa = fb;
                r = b;
            }
        }
        let (mut a, mut b) = bracket?;
        let (mut fa, mut fb) = (f(a), f(b));
        // Illinois-safeguarded regula falsi to relative 1e-14.
        let mut side = 0i8;
        for _ in 0..200 {
            let mut c = b - fb * (b - a) / (fb - fa);
            if !(c > a && c < b) {
                c = 0.5 * (a + b);
            }
            let fc = f(c);
            if fc == 0.0 || (b - a) < 1e-14 * c {
                return Some(c);
            }
            if (fc < 0.0) == (fa < 0.0) {
                a = c;
                fa = fc;
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            } else {
                b = c;
                fb = fc;
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            }
        }
        Some(0.5 * (a + b))
    }
}

#[cfg(test)]
mod tests {
    use super::super::elasticity::*;
    use super::*;

    use proptest::prelude::*;

    proptest! {
        /// The root find inverts the balance: for any radius, the radius found for the gas
        /// content P_B(R)·V(R) is R again (every law, wide ranges of R, P, γ, moduli, any guess).
        #[test]
        fn radius_for_inverts_the_balance(
            log_r in -7.0f64..-2.0,
            log_p in 3.0f64..7.0,
            gamma in 0.0f64..0.1,
            mu in 0.0f64..100.0,
            log_m in 10.0f64..18.0,
            law_i in 0usize..5,
            log_r0 in -7.0f64..-3.0,
            guess_factor in 0.01f64..100.0,
        ) {
            let (r, p, r0) = (10f64.powf(log_r), 10f64.powf(log_p), 10f64.powf(log_r0));
            let laws: [Box<dyn ElasticityLaw>; 5] = [
                Box::new(NoElasticity),
                Box::new(BulkModulus { bulk_modulus_per_volume: 10f64.powf(log_m) }),
                Box::new(ContinuityOfDisplacement { shear_modulus: mu }),
                Box::new(ReferenceConfiguration { shear_modulus: mu, bulk_modulus: 2.2e9 }),
                Box::new(Hyperelastic { shear_modulus: mu }),
            ];
            let b = Balance { ambient: p, surface_tension: gamma, law: laws[law_i].as_ref(), initial_radius: r0, initial_ambient: p, fixed_gases: 0.0 };
            let nrt = b.pv(r);
            // a state with non-positive internal pressure holds no gas: not a physical bubble
            prop_assume!(nrt > 0.0);
            let found = b.radius_for(nrt, r * guess_factor).expect("a root exists");
            prop_assert!((found / r - 1.0).abs() < 1e-9, "R {r} found {found}");
        }
    }

    #[test]
    fn pure_boyle_without_tension() {
        let law = NoElasticity;
        let b = Balance {
            ambient: 1e5,
            surface_tension: 0.0,
            law: &law,
            initial_radius: 1e-4,
            initial_ambient: 1e5,
            fixed_gases: 0.0,
        };
        let nrt = 1e5 * 4.0 / 3.0 * PI * 1e-12; // R = 1e-4 m at 1e5 Pa
        let r = b.radius_for(nrt, 5e-5).unwrap();
        assert!((r / 1e-4 - 1.0).abs() < 1e-12);
    }
}
