//! `sealed-faces:<face>`: a face the phantom treats as open is in fact sealed (no exchange with
//! the chamber), e.g. a gel attached to its well's wall. A discrete alternative, one variant per
//! open face, each counted as one degree of freedom and as one candidate in the Bonferroni
//! correction. Null: the face open.

use super::{CandidateEffect, Phantoms, Prepared};
use crate::phantom::grid::{Face, Shape};

/// Seal one face.
pub struct SealFace {
    face: String,
}

fn open_faces(doc: &toml::Table) -> Option<Vec<String>> {
    let g = doc.get("geometry")?.as_table()?;
    if let Some(list) = g.get("open_faces").and_then(|v| v.as_array()) {
        return Some(
            list.iter()
                .filter_map(|v| v.as_str().map(str::to_string))
                .collect(),
        );
    }
    // the reader's default: every face but the bottom
    let shape = match g.get("shape")?.as_str()? {
        "cylinder" => Shape::Cylinder {
            diameter: 1.0,
            depth: 1.0,
        },
        _ => Shape::Box { size: [1.0; 3] },
    };
    Some(
        shape
            .faces()
            .iter()
            .filter(|f| **f != Face::Bottom)
            .map(|f| f.name().to_string())
            .collect(),
    )
}

impl CandidateEffect for SealFace {
    fn name(&self) -> String {
        format!("sealed-faces:{}", self.face)
    }
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String> {
        for d in docs.iter_mut() {
            let Some(open) = open_faces(d) else {
                return Ok(None);
            };
            if !open.contains(&self.face) {
                return Ok(None);
            }
            let rest: Vec<toml::Value> = open
                .into_iter()
                .filter(|f| *f != self.face)
                .map(toml::Value::String)
                .collect();
            d.get_mut("geometry")
                .and_then(|g| g.as_table_mut())
                .ok_or("geometry is not a table")?
                .insert("open_faces".into(), toml::Value::Array(rest));
        }
        Ok(Some(Prepared {
            params: Vec::new(),
            dof: 1,
        }))
    }
}

/// Registry entry: one variant per face open in every phantom.
pub fn build(phantoms: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    let docs = phantoms.docs;
    let Some(first) = docs.first().and_then(open_faces) else {
        return Vec::new();
    };
    first
        .into_iter()
        .filter(|f| {
            docs.iter()
                .all(|d| open_faces(d).is_some_and(|o| o.contains(f)))
        })
        .map(|face| Box::new(SealFace { face }) as Box<dyn CandidateEffect>)
        .collect()
}
