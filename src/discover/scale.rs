//! `diffusivity-scale` and `solubility-scale`: every gas's bulk diffusivity D (eq. 2.1) or
//! Ostwald coefficient L (eq. 2.2) multiplied by one factor s. Null s = 1.

use super::{log_scan, CandidateEffect, EffectParam, Phantoms, Prepared};
use crate::fit::paths::{self, ParamSpec, SCALE_PREFIX};

/// Scale every number matching a pattern.
pub struct Scale {
    name: &'static str,
    pattern: &'static str,
}

impl CandidateEffect for Scale {
    fn name(&self) -> String {
        self.name.into()
    }
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String> {
        if docs
            .iter()
            .all(|d| paths::expand(d, self.pattern).is_empty())
        {
            return Ok(None);
        }
        Ok(Some(Prepared {
            params: vec![EffectParam {
                spec: ParamSpec::positive(format!("{SCALE_PREFIX}{}", self.pattern), 1.0),
                null: 1.0,
                scan: log_scan(0.25, 4.0, 5),
            }],
            dof: 1,
        }))
    }
}

/// Registry entry `diffusivity-scale`.
pub fn build_diffusivity(_: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(Scale {
        name: "diffusivity-scale",
        pattern: "gases.*.diffusivity",
    })]
}

/// Registry entry `solubility-scale`.
pub fn build_solubility(_: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(Scale {
        name: "solubility-scale",
        pattern: "gases.*.ostwald",
    })]
}
