//! `bubble-fixed-gases`: a fixed partial pressure of gases the model does not carry (water
//! vapour, CO2, metabolic O2) inside every bubble, `[material] bubble_fixed_gases_pa`.
//! Null 0 Pa.

use super::{CandidateEffect, ZeroNullSetting};

/// Registry entry.
pub fn build(_: &[toml::Table]) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(ZeroNullSetting {
        name: "bubble-fixed-gases",
        path: "material.bubble_fixed_gases_pa",
        start: 1.0,
        scan: (1e2, 3e4),
    })]
}
