//! `perfusion`: every gel cell exchanges gas with blood in equilibrium with the inspired gas at
//! rate k (1/s), `[perfusion] rate_per_s` (the paper, §5). Null k = 0.

use super::{CandidateEffect, Phantoms, ZeroNullSetting};

/// Registry entry.
pub fn build(_: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(ZeroNullSetting {
        name: "perfusion",
        path: "perfusion.rate_per_s",
        start: 1e-6,
        scan: (1e-5, 1e-1),
        floor: 0.0,
        ceiling: 0.0,
    })]
}
