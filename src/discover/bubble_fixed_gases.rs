//! `bubble-fixed-gases`: a fixed partial pressure of gases the model does not carry (water
//! vapour, CO2, metabolic O2) inside every bubble, `[material] bubble_fixed_gases_pa`.
//! Null 0 Pa.

use super::{CandidateEffect, Phantoms, ZeroNullSetting};

/// Registry entry. On profiles that subtract water vapour at the open faces (P_H2O), every
/// bubble already holds that vapour (the null, 0, takes it) and the phantom refuses a value
/// below it: the effect is then the fixed gases beyond the vapour, fitted from P_H2O + 1 Pa
/// within P_H2O..P_H2O + 1 bar, the scan shifted by P_H2O.
pub fn build(phantoms: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(ZeroNullSetting {
        name: "bubble-fixed-gases",
        path: "material.bubble_fixed_gases_pa",
        start: 1.0,
        scan: (1e2, 3e4),
        floor: phantoms.vapour_pa,
        ceiling: 1e5,
    })]
}
