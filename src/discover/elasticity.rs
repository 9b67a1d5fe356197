//! `elasticity:<law>`: an elastic term of another of the paper's forms (eqs. 2.6–2.9) on top of
//! the phantom's own Ω, its modulus fitted: Ω = Ω_phantom + Ω_law(modulus). Null: modulus 0,
//! where every form gives Ω_law = 0 and the model is exactly the phantom's. (Adding the law
//! the phantom already has refits its modulus.)

use super::{log_scan, CandidateEffect, EffectParam, Phantoms, Prepared};
use crate::fit::paths::ParamSpec;
use crate::phantom::elasticity::law_names;

/// One law's candidate.
pub struct ExtraElasticity {
    law: &'static str,
}

impl ExtraElasticity {
    /// The modulus field of the law, its scan range and the fixed fields it needs.
    fn modulus(&self) -> (&'static str, f64, f64, Vec<(&'static str, f64)>) {
        match self.law {
            // M = K/V_aff, Pa/m³: the paper's 5e-2 Pa/µm³ = 5e16 Pa/m³
            "bulk-modulus" => ("bulk_modulus_per_volume", 1e12, 1e18, vec![]),
            // K = 2.2 GPa as the paper's Fig. 2a
            "reference-configuration" => {
                ("shear_modulus", 10.0, 1e5, vec![("bulk_modulus", 2.2e9)])
            }
            _ => ("shear_modulus", 10.0, 1e5, vec![]),
        }
    }
}

impl CandidateEffect for ExtraElasticity {
    fn name(&self) -> String {
        format!("elasticity:{}", self.law)
    }
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String> {
        let (field, lo, hi, fixed) = self.modulus();
        let mut index = None;
        for d in docs.iter_mut() {
            let material = d
                .entry("material")
                .or_insert_with(|| toml::Value::Table(toml::Table::new()))
                .as_table_mut()
                .ok_or("material is not a table")?;
            let current = material
                .remove("elasticity")
                .and_then(|v| v.as_table().cloned())
                .unwrap_or_else(|| {
                    let mut t = toml::Table::new();
                    t.insert("law".into(), "none".into());
                    t
                });
            let mut terms = if current.get("law").and_then(|l| l.as_str()) == Some("sum") {
                current
                    .get("terms")
                    .and_then(|t| t.as_array())
                    .cloned()
                    .unwrap_or_default()
            } else {
                vec![toml::Value::Table(current)]
            };
            let mut extra = toml::Table::new();
            extra.insert("law".into(), self.law.into());
            extra.insert(field.into(), toml::Value::Float(0.0));
            for (k, v) in &fixed {
                extra.insert((*k).into(), toml::Value::Float(*v));
            }
            terms.push(toml::Value::Table(extra));
            let i = terms.len() - 1;
            if index.is_some_and(|j| j != i) {
                return Ok(None);
            }
            index = Some(i);
            let mut sum = toml::Table::new();
            sum.insert("law".into(), "sum".into());
            sum.insert("terms".into(), toml::Value::Array(terms));
            material.insert("elasticity".into(), toml::Value::Table(sum));
        }
        let i = index.unwrap_or(1);
        Ok(Some(Prepared {
            params: vec![EffectParam {
                spec: ParamSpec::positive(
                    format!("material.elasticity.terms.{i}.{field}"),
                    lo * 1e-3,
                ),
                null: 0.0,
                scan: log_scan(lo, hi, 5),
            }],
            dof: 1,
        }))
    }
}

/// Registry entry: one candidate per form other than `none`.
pub fn build(_: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    law_names()
        .into_iter()
        .filter(|l| *l != "none")
        .map(|law| Box::new(ExtraElasticity { law }) as Box<dyn CandidateEffect>)
        .collect()
}
