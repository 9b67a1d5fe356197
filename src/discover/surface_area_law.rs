//! `surface-area-law`: the surface layer's diffusivity depends on the bubble's size,
//! D_surf = (D_bulk/k)(R/R_0)^a — the paper's §4.1 result is k = 30, a = 2 (surface area).
//! Two parameters, the fold k and the exponent a. Null: a = 0 and k as the phantom has it
//! (1 for D_surf = D_bulk), or, on a phantom already on the area law, its own k and a.

use super::surface_permeability::{set_str, surface_law};
use super::{log_scan, CandidateEffect, EffectParam, Phantoms, Prepared};
use crate::fit::paths::{self, ParamSpec};

/// The area-law candidate.
pub struct SurfaceAreaLaw;

const FOLD: &str = "material.surface.fold";
const EXPONENT: &str = "material.surface.exponent";

impl CandidateEffect for SurfaceAreaLaw {
    fn name(&self) -> String {
        "surface-area-law".into()
    }
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String> {
        let mut null: Option<(f64, f64)> = None;
        for d in docs.iter_mut() {
            let (k, a) = match surface_law(d).as_str() {
                "equal" => (1.0, 0.0),
                "fold" => (paths::get(d, FOLD).unwrap_or(1.0), 0.0),
                "area" => (
                    paths::get(d, FOLD).unwrap_or(1.0),
                    paths::get(d, EXPONENT).unwrap_or(2.0),
                ),
                _ => return Ok(None),
            };
            set_str(d, &["material", "surface"], "law", "area");
            paths::set(d, FOLD, k)?;
            paths::set(d, EXPONENT, a)?;
            match null {
                None => null = Some((k, a)),
                Some((k1, a1)) if (k1 - k).abs() > 1e-12 * k1 || a1 != a => return Ok(None),
                _ => {}
            }
        }
        let (k0, a0) = null.unwrap_or((1.0, 0.0));
        Ok(Some(Prepared {
            params: vec![
                EffectParam {
                    spec: ParamSpec::positive(FOLD, k0),
                    null: k0,
                    scan: log_scan(k0 / 30.0, k0 * 100.0, 7),
                },
                EffectParam {
                    spec: ParamSpec {
                        path: EXPONENT.into(),
                        lower: Some(-6.0),
                        upper: Some(8.0),
                        log: false,
                        start: a0,
                    },
                    null: a0,
                    scan: vec![a0 + 1.0, a0 + 2.0, a0 + 3.0],
                },
            ],
            dof: 2,
        }))
    }
}

/// Registry entry.
pub fn build(_: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    vec![Box::new(SurfaceAreaLaw)]
}
