//! `surface-permeability`: the bubble's surface layer less permeable than the gel by a fold k,
//! D_surf = D_bulk/k (the paper's §4.1 found k = 30). On a phantom whose surface law already has
//! a fold, the candidate refits that fold. Null: k = 1 (D_surf = D_bulk), or the fold as given.

use super::{log_scan, CandidateEffect, EffectParam, Phantoms, Prepared};
use crate::fit::paths::{self, ParamSpec};

/// The surface-permeability candidate.
pub struct SurfacePermeability;

/// The surface law of a phantom document (default `equal`).
pub fn surface_law(doc: &toml::Table) -> String {
    doc.get("material")
        .and_then(|m| m.get("surface"))
        .and_then(|s| s.get("law"))
        .and_then(|l| l.as_str())
        .unwrap_or("equal")
        .to_string()
}

pub(crate) fn set_str(doc: &mut toml::Table, table: &[&str], key: &str, v: &str) {
    let mut t = doc;
    for k in table {
        t = t
            .entry(k.to_string())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .expect("phantom tables were validated");
    }
    t.insert(key.into(), toml::Value::String(v.into()));
}

const FOLD: &str = "material.surface.fold";

impl CandidateEffect for SurfacePermeability {
    fn name(&self) -> String {
        "surface-permeability".into()
    }
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String> {
        let mut null = None;
        for d in docs.iter_mut() {
            let k = match surface_law(d).as_str() {
                "equal" => {
                    set_str(d, &["material", "surface"], "law", "fold");
                    paths::set(d, FOLD, 1.0)?;
                    1.0
                }
                _ => paths::get(d, FOLD).unwrap_or(1.0),
            };
            match null {
                None => null = Some(k),
                // one shared fold: phantoms with different folds cannot share the candidate
                Some(n) if (n - k).abs() > 1e-12 * n.abs() => return Ok(None),
                _ => {}
            }
        }
        let k0 = null.unwrap_or(1.0);
        Ok(Some(Prepared {
            params: vec![EffectParam {
                spec: ParamSpec::positive(FOLD, k0),
                null: k0,
                scan: log_scan(k0 / 30.0, k0 * 100.0, 7),
            }],
            dof: 1,
        }))
    }
}

/// Registry entry.
pub fn build(_: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(SurfacePermeability)]
}
