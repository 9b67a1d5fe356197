//! `bubble-fixed-gases`: a fixed partial pressure of gases the model does not carry (water
//! vapour, CO2, metabolic O2) inside every bubble, `[material] bubble_fixed_gases_pa`.
//! Null 0 Pa.

use super::{log_scan, CandidateEffect, EffectParam, Prepared};
use crate::fit::paths::{self, ParamSpec};

/// The fixed-gases candidate.
pub struct BubbleFixedGases;

const PATH: &str = "material.bubble_fixed_gases_pa";

impl CandidateEffect for BubbleFixedGases {
    fn name(&self) -> String {
        "bubble-fixed-gases".into()
    }
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String> {
        if docs
            .iter()
            .any(|d| paths::get(d, PATH).is_some_and(|k| k > 0.0))
        {
            return Ok(None);
        }
        for d in docs.iter_mut() {
            paths::set(d, PATH, 0.0)?;
        }
        Ok(Some(Prepared {
            params: vec![EffectParam {
                spec: ParamSpec::positive(PATH, 1.0),
                null: 0.0,
                scan: log_scan(1e2, 3e4, 5),
            }],
            dof: 1,
        }))
    }
}

/// Registry entry.
pub fn build(_: &[toml::Table]) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(BubbleFixedGases)]
}
