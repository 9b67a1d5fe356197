//! `fixed`: no nuclei. The only bubbles are those the phantom places at t = 0 (`[[bubbles]]` or
//! `[population]`), the paper's own choice (§2.1.4: "nucleation is not modelled explicitly;
//! instead the simulated tissue phantom is assumed to contain a defined initial population of
//! bubbles"). The default, so every preset behaves as before nucleation existed.

use super::{NucleationError, NucleationModel, Nucleus};
use crate::phantom::grid::Grid;

/// No nucleation.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fixed;

impl NucleationModel for Fixed {
    fn name(&self) -> &'static str {
        "fixed"
    }
    fn nuclei(&self, _: &Grid) -> Result<Vec<Nucleus>, NucleationError> {
        Ok(Vec::new())
    }
}

/// Build from the `[nucleation]` table (no parameters).
pub fn build(t: toml::Table) -> Result<Box<dyn NucleationModel>, NucleationError> {
    match t.keys().next() {
        Some(k) => Err(NucleationError::new(
            k,
            format!("unknown field `{k}`: model \"fixed\" takes no parameters"),
        )),
        None => Ok(Box::new(Fixed)),
    }
}
