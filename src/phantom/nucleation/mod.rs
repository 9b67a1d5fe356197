//! Nucleation: where and when new bubbles appear (the paper's §2.1.4, §4.2.1 and §6: "a model of
//! nucleation is one of the most crucial research avenues"). One small trait, one file per
//! model, a registry keyed by the `model` name of the phantom TOML's `[nucleation]` table.
//!
//! A model only says which sub-grid gas nuclei the gel holds ([`NucleationModel::nuclei`]);
//! the shared [`NucleusPool`] decides when one activates. A nucleus of radius r activates into a
//! bubble when the supersaturation of the gel in its cell exceeds the Laplace pressure of the
//! nucleus, eq. (2.11) read for a given r:
//!
//! Σ_g C_g·R_u·T/L_g + p_fixed − P_amb > 2γ/r,
//!
//! with p_fixed = `material.bubble_fixed_gases_pa` (the same convention as the gel tension of
//! the bubbles' coupling). The bubble starts at radius r with the Laplace content and the
//! composition of the gel in its cell, its gas taken from the gel
//! ([`Simulation::add_bubble`](super::sim::Simulation::add_bubble)). When that bubble dissolves
//! its nucleus returns to the pool (when it merges into another, the nucleus is consumed). Nuclei cost nothing until they activate:
//! each one's cell and threshold are computed once, the pool is sorted by cell and threshold,
//! and each step reads one tension per occupied cell.
//!
//! Models: `fixed` (no nuclei: only the bubbles placed at t = 0, the paper's own choice and
//! the default) and `critical-radius` (a seeded population after Yount's varying-permeability
//! model, [`critical_radius`]).

pub mod critical_radius;
pub mod fixed;

use super::grid::Grid;

/// One sub-grid gas nucleus.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Nucleus {
    /// Centre, m.
    pub position: [f64; 3],
    /// Radius r, m.
    pub radius: f64,
}

/// A nucleation model: the population of gas nuclei a phantom holds.
pub trait NucleationModel: Send + Sync + std::fmt::Debug {
    /// The name used in TOML (`[nucleation] model`) and in tables.
    fn name(&self) -> &'static str;
    /// The nuclei in `grid`, drawn once when the simulation is set up (the same inputs give
    /// the same nuclei). An error names the TOML field at fault.
    fn nuclei(&self, grid: &Grid) -> Result<Vec<Nucleus>, NucleationError>;
}

/// A nucleation error: the TOML field (under `nucleation.`) and the message.
#[derive(Debug, Clone, PartialEq)]
pub struct NucleationError {
    /// Full TOML key, e.g. `nucleation.number_density_per_m3`.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl NucleationError {
    /// An error on `nucleation.<key>`.
    pub fn new(key: &str, message: impl Into<String>) -> Self {
        NucleationError {
            field: format!("nucleation.{key}"),
            message: message.into(),
        }
    }
}

impl std::fmt::Display for NucleationError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

/// A model's constructor from its parameter table (the `[nucleation]` table less `model`).
pub type Build = fn(toml::Table) -> Result<Box<dyn NucleationModel>, NucleationError>;

/// The registry: TOML name → constructor.
pub const REGISTRY: &[(&str, Build)] = &[
    ("fixed", fixed::build),
    ("critical-radius", critical_radius::build),
];

/// The registered model names, in registry order.
pub fn model_names() -> Vec<&'static str> {
    REGISTRY.iter().map(|(n, _)| *n).collect()
}

/// Build a model by name from its parameter table (every field but `model`).
pub fn build(name: &str, params: toml::Table) -> Result<Box<dyn NucleationModel>, NucleationError> {
    let (_, b) = REGISTRY.iter().find(|(n, _)| *n == name).ok_or_else(|| {
        NucleationError::new(
            "model",
            format!(
                "unknown nucleation model '{name}'; known: {}",
                model_names().join(", ")
            ),
        )
    })?;
    b(params)
}

/// Deserialize a model's parameter table into its raw struct (`deny_unknown_fields`); the
/// error names the field when serde does.
pub(crate) fn raw<T: serde::de::DeserializeOwned>(t: toml::Table) -> Result<T, NucleationError> {
    T::deserialize(toml::Value::Table(t)).map_err(|e| {
        let msg = e.message().trim().to_string();
        // serde's "unknown field `x`" / "missing field `x`": point at x
        let key = msg
            .split('`')
            .nth(1)
            .map(str::to_string)
            .unwrap_or_else(|| "model".into());
        NucleationError::new(&key, msg)
    })
}

/// One nucleus in the pool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoolEntry {
    /// The nucleus.
    pub nucleus: Nucleus,
    /// Flat index of its grid cell.
    pub cell: usize,
    /// Activation threshold 2γ/r, Pa (eq. 2.11).
    pub threshold: f64,
    /// The bubble it became; `None` while in the pool. A nucleus returns to the pool when its
    /// bubble dissolves; one whose bubble merged into another is consumed (its gas is in the
    /// survivor) and keeps the id of the merged bubble.
    pub bubble: Option<usize>,
}

/// The nuclei of a run and their state, sorted by (cell, threshold) so that a step reads one
/// tension per occupied cell and stops at the first nucleus whose threshold is not exceeded.
#[derive(Debug, Clone, Default)]
pub struct NucleusPool {
    entries: Vec<PoolEntry>,
    /// Runs of `entries` sharing a cell: (cell, start, end).
    runs: Vec<(usize, usize, usize)>,
}

impl NucleusPool {
    /// The pool of `nuclei` in `grid` with surface tension γ (N/m). Nuclei outside the
    /// phantom's cells are an error.
    pub fn new(nuclei: &[Nucleus], grid: &Grid, surface_tension: f64) -> Result<Self, String> {
        let mut entries = Vec::with_capacity(nuclei.len());
        for (i, n) in nuclei.iter().enumerate() {
            let cell = cell_of(grid, n.position)
                .filter(|c| grid.inside(*c))
                .ok_or_else(|| {
                    format!(
                        "nucleus {i} at ({:.3e}, {:.3e}, {:.3e}) m is outside the phantom",
                        n.position[0], n.position[1], n.position[2]
                    )
                })?;
            if !(n.radius > 0.0 && n.radius.is_finite()) {
                return Err(format!(
                    "nucleus {i}: radius {} m is not positive",
                    n.radius
                ));
            }
            entries.push(PoolEntry {
                nucleus: *n,
                cell,
                threshold: 2.0 * surface_tension / n.radius,
                bubble: None,
            });
        }
        entries.sort_by(|a, b| {
            a.cell
                .cmp(&b.cell)
                .then(a.threshold.total_cmp(&b.threshold))
        });
        let mut runs = Vec::new();
        let mut start = 0;
        for i in 1..=entries.len() {
            if i == entries.len() || entries[i].cell != entries[start].cell {
                runs.push((entries[start].cell, start, i));
                start = i;
            }
        }
        Ok(NucleusPool { entries, runs })
    }

    /// Every nucleus with its cell, threshold and state (sorted by cell, then threshold).
    pub fn entries(&self) -> &[PoolEntry] {
        &self.entries
    }

    /// Whether the pool holds no nuclei (the `fixed` model).
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// Return to the pool every nucleus whose bubble has dissolved (`dissolved(id)`).
    pub fn release(&mut self, dissolved: impl Fn(usize) -> bool) {
        for e in &mut self.entries {
            if let Some(b) = e.bubble {
                if dissolved(b) {
                    e.bubble = None;
                }
            }
        }
    }

    /// Indices (into [`Self::entries`]) of the nuclei in the pool whose threshold the
    /// supersaturation of their cell exceeds; `supersaturation(cell)` in Pa is called once per
    /// occupied cell.
    pub fn ready(&self, mut supersaturation: impl FnMut(usize) -> f64) -> Vec<usize> {
        let mut out = Vec::new();
        for &(cell, start, end) in &self.runs {
            if self.entries[start..end].iter().all(|e| e.bubble.is_some()) {
                continue;
            }
            let s = supersaturation(cell);
            if !(s > self.entries[start].threshold) {
                continue;
            }
            for (k, e) in self.entries[start..end].iter().enumerate() {
                if !(s > e.threshold) {
                    break;
                }
                if e.bubble.is_none() {
                    out.push(start + k);
                }
            }
        }
        out
    }

    /// Record that nucleus `index` became bubble `bubble`.
    pub fn activate(&mut self, index: usize, bubble: usize) {
        self.entries[index].bubble = Some(bubble);
    }
}

/// Flat index of the grid cell holding point `p` (`None` outside the grid's box).
pub fn cell_of(grid: &Grid, p: [f64; 3]) -> Option<usize> {
    let mut ijk = [0usize; 3];
    for a in 0..3 {
        let f = p[a] / grid.h;
        if !(f >= 0.0 && f < grid.n[a] as f64) {
            return None;
        }
        ijk[a] = f.floor() as usize;
    }
    Some(grid.index(ijk[0], ijk[1], ijk[2]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::phantom::grid::Shape;

    fn grid() -> Grid {
        Grid::new(Shape::Box { size: [1e-3; 3] }, 1e-4, &[]).unwrap()
    }

    #[test]
    fn ready_takes_exactly_the_nuclei_whose_threshold_is_exceeded() {
        let g = grid();
        let p = [0.55e-3; 3];
        // γ = 0.07 N/m: thresholds 2γ/r = 140 000, 70 000, 35 000 Pa for r = 1, 2, 4 µm
        let nuclei: Vec<Nucleus> = [1e-6, 4e-6, 2e-6]
            .iter()
            .map(|&r| Nucleus {
                position: p,
                radius: r,
            })
            .collect();
        let mut pool = NucleusPool::new(&nuclei, &g, 0.07).unwrap();
        let radii = |pool: &NucleusPool, s: f64| -> Vec<f64> {
            pool.ready(|_| s)
                .into_iter()
                .map(|i| pool.entries()[i].nucleus.radius)
                .collect()
        };
        assert!(radii(&pool, 35_000.0).is_empty()); // equal: not exceeded
        assert_eq!(radii(&pool, 35_000.1), vec![4e-6]);
        assert_eq!(radii(&pool, 139_999.0), vec![4e-6, 2e-6]);
        assert_eq!(radii(&pool, 140_001.0), vec![4e-6, 2e-6, 1e-6]);
        // an activated nucleus is not offered again until its bubble is gone
        let i = pool.ready(|_| 1e9)[0];
        pool.activate(i, 7);
        assert_eq!(pool.ready(|_| 1e9).len(), 2);
        pool.release(|b| b == 7);
        assert_eq!(pool.ready(|_| 1e9).len(), 3);
    }

    #[test]
    fn a_nucleus_outside_the_phantom_is_refused() {
        let g = grid();
        let n = Nucleus {
            position: [2e-3, 0.5e-3, 0.5e-3],
            radius: 1e-6,
        };
        assert!(NucleusPool::new(&[n], &g, 0.07).is_err());
        assert_eq!(
            cell_of(&g, [0.05e-3, 0.15e-3, 0.95e-3]),
            Some(g.index(0, 1, 9))
        );
    }
}
