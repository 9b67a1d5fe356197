//! `perfusion`: every gel cell exchanges gas with blood in equilibrium with the inspired gas at
//! rate k (1/s), `[perfusion] rate_per_s` (the paper, §5). Null k = 0.

use super::{log_scan, CandidateEffect, EffectParam, Prepared};
use crate::fit::paths::{self, ParamSpec};

/// The perfusion candidate.
pub struct Perfusion;

const PATH: &str = "perfusion.rate_per_s";

impl CandidateEffect for Perfusion {
    fn name(&self) -> String {
        "perfusion".into()
    }
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String> {
        // already perfused: the candidate is the rate's refit, not a new effect
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
                spec: ParamSpec::positive(PATH, 1e-6),
                null: 0.0,
                scan: log_scan(1e-5, 1e-1, 5),
            }],
            dof: 1,
        }))
    }
}

/// Registry entry.
pub fn build(_: &[toml::Table]) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(Perfusion)]
}
