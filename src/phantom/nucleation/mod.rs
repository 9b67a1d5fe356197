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
//! **Skins and crushing (VPM, optional).** A model may give its nuclei the surfactant skins of
//! Yount's varying-permeability model ([`NucleationModel::skin_compression`], γc). A skin
//! lowers the supersaturation at which a nucleus of radius r grows to 2γ(γc − γ)/(γc·r), and a
//! compression of the gel by a crushing pressure ΔP = P_amb − gel tension shrinks the nucleus
//! (permeable regime) to 1/r' = 1/r + ΔP/(2(γc − γ)) (Yount 1979; Yount & Hoffman 1986).
//! Together the threshold after crushing is
//!
//! 2γ(γc − γ)/(γc·r) + (γ/γc)·ΔP_max,
//!
//! the same shift (γ/γc)·ΔP_max for every nucleus of a cell, ΔP_max the largest crushing
//! pressure its cell has seen in the run (so the pool's order within a cell holds). The
//! activated bubble, which has no skin, starts at 2γ/threshold: the radius whose Laplace
//! pressure equals the supersaturation that activated it, so it grows. Not modelled: the
//! impermeable regime of VPM (crushing above about 8.2 atm, where the skin stops passing gas
//! and a nucleus shrinks less: there the permeable formula overstates the crushing), and
//! regeneration of crushed nuclei (time constant ≈ 14 days in VPM-B, beyond any run here).
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
    /// γc, N/m: the skin compression of VPM's nuclei (Yount 1979: 0.257 N/m); `Some` gives
    /// the nuclei skins and makes compression crush them (module docs). Default: bare nuclei.
    fn skin_compression(&self) -> Option<f64> {
        None
    }
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
/// error names the field ([`crate::error::table_into_keyed`]: the key of a wrong type,
/// `unknown field `x``, `missing field `x``), else the whole `nucleation` table.
pub(crate) fn raw<T: serde::de::DeserializeOwned>(t: toml::Table) -> Result<T, NucleationError> {
    crate::error::table_into_keyed(toml::Value::Table(t)).map_err(|(key, message)| match key {
        Some(key) => NucleationError::new(&key, message),
        None => NucleationError {
            field: "nucleation".into(),
            message,
        },
    })
}

/// One nucleus in the pool.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoolEntry {
    /// The nucleus.
    pub nucleus: Nucleus,
    /// Flat index of its grid cell.
    pub cell: usize,
    /// Activation threshold before any crushing, Pa: 2γ/r (eq. 2.11), or 2γ(γc − γ)/(γc·r)
    /// with skins ([`NucleusPool::threshold`] adds the crushing).
    pub threshold: f64,
    /// The bubble it became; `None` while in the pool. A nucleus returns to the pool when its
    /// bubble dissolves; one whose bubble merged into another is consumed (its gas is in the
    /// survivor) and keeps the id of the merged bubble.
    pub bubble: Option<usize>,
}

/// The threshold factor (γc − γ)/γc and the crushing gain γ/γc of nuclei with skins of
/// compression γc (N/m) in a gel of surface tension γ (N/m); (1, 0) without skins. A skin no
/// stronger than γ holds nothing (VPM needs γc > γ): refused, naming
/// `nucleation.skin_compression`.
pub fn skin_factors(
    surface_tension: f64,
    skin_compression: Option<f64>,
) -> Result<(f64, f64), NucleationError> {
    match skin_compression {
        None => Ok((1.0, 0.0)),
        Some(gc) if gc > surface_tension => {
            Ok(((gc - surface_tension) / gc, surface_tension / gc))
        }
        Some(gc) => Err(NucleationError::new(
            "skin_compression",
            format!(
                "the skin compression γc = {gc} N/m must exceed the gel's surface tension γ = {surface_tension} N/m (material.surface_tension; VPM: a skin holds only while γc > γ)"
            ),
        )),
    }
}

/// The nuclei of a run and their state, sorted by (cell, threshold) so that a step reads one
/// tension per occupied cell and stops at the first nucleus whose threshold is not exceeded.
#[derive(Debug, Clone, Default)]
pub struct NucleusPool {
    entries: Vec<PoolEntry>,
    /// Runs of `entries` sharing a cell: (cell, start, end).
    runs: Vec<(usize, usize, usize)>,
    /// Per entry: its run.
    run_of: Vec<usize>,
    /// Per run: the largest crushing pressure P_amb − gel tension its cell has seen, Pa (≥ 0).
    crush: Vec<f64>,
    /// γ/γc: threshold rise per Pa of crushing (0 without skins).
    crush_gain: f64,
    /// γ, N/m.
    surface_tension: f64,
    /// The lowest [`PoolEntry::threshold`], Pa (∞ when empty); thresholds are fixed at set-up.
    lowest: f64,
}

impl NucleusPool {
    /// The pool of `nuclei` in `grid` with surface tension γ (N/m) and, with skins, skin
    /// compression γc (N/m, above γ). Nuclei outside the phantom's cells are an error.
    pub fn new(
        nuclei: &[Nucleus],
        grid: &Grid,
        surface_tension: f64,
        skin_compression: Option<f64>,
    ) -> Result<Self, NucleationError> {
        let err = |m: String| NucleationError {
            field: "nucleation".into(),
            message: m,
        };
        let (factor, crush_gain) = skin_factors(surface_tension, skin_compression)?;
        let mut entries = Vec::with_capacity(nuclei.len());
        for (i, n) in nuclei.iter().enumerate() {
            let cell = cell_of(grid, n.position)
                .filter(|c| grid.inside(*c))
                .ok_or_else(|| {
                    err(format!(
                        "nucleus {i} at ({:.3e}, {:.3e}, {:.3e}) m is outside the phantom",
                        n.position[0], n.position[1], n.position[2]
                    ))
                })?;
            if !(n.radius > 0.0 && n.radius.is_finite()) {
                return Err(err(format!(
                    "nucleus {i}: radius {} m is not positive",
                    n.radius
                )));
            }
            entries.push(PoolEntry {
                nucleus: *n,
                cell,
                threshold: factor * 2.0 * surface_tension / n.radius,
                bubble: None,
            });
        }
        entries.sort_by(|a, b| {
            a.cell
                .cmp(&b.cell)
                .then(a.threshold.total_cmp(&b.threshold))
        });
        let mut runs = Vec::new();
        let mut run_of = vec![0; entries.len()];
        let mut start = 0;
        for i in 1..=entries.len() {
            if i == entries.len() || entries[i].cell != entries[start].cell {
                run_of[start..i].fill(runs.len());
                runs.push((entries[start].cell, start, i));
                start = i;
            }
        }
        let lowest = entries
            .iter()
            .map(|e| e.threshold)
            .fold(f64::INFINITY, f64::min);
        Ok(NucleusPool {
            lowest,
            entries,
            crush: vec![0.0; runs.len()],
            runs,
            run_of,
            crush_gain,
            surface_tension,
        })
    }

    /// The activation threshold of nucleus `index` now, Pa: its [`PoolEntry::threshold`] plus
    /// (γ/γc)·ΔP_max of its cell with skins.
    pub fn threshold(&self, index: usize) -> f64 {
        self.entries[index].threshold + self.crush_gain * self.crush[self.run_of[index]]
    }

    /// The radius a bubble from nucleus `index` starts at, m: the nucleus's radius for bare
    /// nuclei (its Laplace pressure is the threshold), 2γ/threshold with skins.
    pub fn activation_radius(&self, index: usize) -> f64 {
        if self.crush_gain == 0.0 {
            self.entries[index].nucleus.radius
        } else {
            2.0 * self.surface_tension / self.threshold(index)
        }
    }

    /// The largest crushing pressure the cell of nucleus `index` has seen, Pa.
    pub fn crushing_pressure(&self, index: usize) -> f64 {
        self.crush[self.run_of[index]]
    }

    /// Whether the nuclei have VPM skins (then every step records the crushing pressures).
    pub fn has_skins(&self) -> bool {
        self.crush_gain > 0.0
    }

    /// The lowest activation threshold before crushing over the pool, Pa (∞ when empty).
    pub fn lowest_threshold(&self) -> f64 {
        if self.entries.is_empty() {
            f64::INFINITY
        } else {
            self.lowest
        }
    }

    /// The largest crushing pressure of each occupied cell, Pa, in the pool's cell order (the
    /// state a checkpoint keeps).
    pub fn crushing(&self) -> &[f64] {
        &self.crush
    }

    /// Restore [`Self::crushing`] from a checkpoint (same inputs, so the same cells).
    pub fn restore_crushing(&mut self, crush: &[f64]) -> Result<(), String> {
        if crush.len() != self.crush.len() || crush.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
            return Err(format!(
                "it holds {} crushing pressures of nucleus cells; this run has {} cells with nuclei",
                crush.len(),
                self.crush.len()
            ));
        }
        self.crush.copy_from_slice(crush);
        Ok(())
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
    /// occupied cell. With skins this also records each cell's crushing pressure
    /// (−supersaturation) before testing, so call it once per step.
    pub fn ready(&mut self, mut supersaturation: impl FnMut(usize) -> f64) -> Vec<usize> {
        let mut out = Vec::new();
        let skins = self.crush_gain > 0.0;
        for (run, &(cell, start, end)) in self.runs.iter().enumerate() {
            if !skins && self.entries[start..end].iter().all(|e| e.bubble.is_some()) {
                continue;
            }
            let s = supersaturation(cell);
            if skins && -s > self.crush[run] {
                self.crush[run] = -s;
            }
            let shift = self.crush_gain * self.crush[run];
            if !(s > self.entries[start].threshold + shift) {
                continue;
            }
            for (k, e) in self.entries[start..end].iter().enumerate() {
                if !(s > e.threshold + shift) {
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
        let mut pool = NucleusPool::new(&nuclei, &g, 0.07, None).unwrap();
        let radii = |pool: &mut NucleusPool, s: f64| -> Vec<f64> {
            pool.ready(|_| s)
                .into_iter()
                .map(|i| pool.entries()[i].nucleus.radius)
                .collect()
        };
        assert!(radii(&mut pool, 35_000.0).is_empty()); // equal: not exceeded
        assert_eq!(radii(&mut pool, 35_000.1), vec![4e-6]);
        assert_eq!(radii(&mut pool, 139_999.0), vec![4e-6, 2e-6]);
        assert_eq!(radii(&mut pool, 140_001.0), vec![4e-6, 2e-6, 1e-6]);
        // bare nuclei: compression does not move the thresholds
        assert!(radii(&mut pool, -500_000.0).is_empty());
        assert_eq!(radii(&mut pool, 35_000.1), vec![4e-6]);
        // an activated nucleus is not offered again until its bubble is gone
        let i = pool.ready(|_| 1e9)[0];
        pool.activate(i, 7);
        assert_eq!(pool.ready(|_| 1e9).len(), 2);
        pool.release(|b| b == 7);
        assert_eq!(pool.ready(|_| 1e9).len(), 3);
    }

    #[test]
    fn skins_lower_the_threshold_and_crushing_raises_it_as_in_vpm() {
        // Yount's VPM, computed here by the radius route (the pool adds a threshold shift):
        // a skin of compression γc gives the threshold 2γ(γc − γ)/(γc·r); crushing by ΔP in the
        // permeable regime shrinks r to 1/r' = 1/r + ΔP/(2(γc − γ)). γc = 0.257 N/m (Yount
        // 1979), γ = 0.07 N/m, r = 1 and 2 µm, ΔP = 300 kPa then 200 kPa (the largest counts).
        let (gamma, gc) = (0.07, 0.257);
        let g = grid();
        let nuclei: Vec<Nucleus> = [2e-6, 1e-6]
            .iter()
            .map(|&r| Nucleus {
                position: [0.55e-3; 3],
                radius: r,
            })
            .collect();
        let mut pool = NucleusPool::new(&nuclei, &g, gamma, Some(gc)).unwrap();
        let vpm = |r: f64, dp: f64| {
            let r_crushed = 1.0 / (1.0 / r + dp / (2.0 * (gc - gamma)));
            2.0 * gamma * (gc - gamma) / (gc * r_crushed)
        };
        let order = [2e-6, 1e-6]; // sorted by threshold
        for (i, r) in order.iter().enumerate() {
            assert!((pool.threshold(i) - vpm(*r, 0.0)).abs() < 1e-9 * vpm(*r, 0.0));
            // below 2γ/r: the skin helps the nucleus grow
            assert!(pool.threshold(i) < 2.0 * gamma / r);
        }
        assert!(pool.ready(|_| -300e3).is_empty());
        assert!(pool.ready(|_| -200e3).is_empty());
        for (i, r) in order.iter().enumerate() {
            let want = vpm(*r, 300e3);
            assert!((pool.threshold(i) - want).abs() < 1e-9 * want, "{i}");
            assert!((pool.crushing_pressure(i) - 300e3).abs() < 1e-9);
            // a bubble starts where its Laplace pressure is the threshold
            assert!((pool.activation_radius(i) - 2.0 * gamma / want).abs() < 1e-15);
        }
        let (t0, t1) = (vpm(2e-6, 300e3), vpm(1e-6, 300e3));
        assert!(pool.ready(|_| t0 * (1.0 - 1e-9)).is_empty());
        assert_eq!(pool.ready(|_| t0 * (1.0 + 1e-9)), vec![0]);
        assert_eq!(pool.ready(|_| t1 * (1.0 + 1e-9)), vec![0, 1]);
        // a skin weaker than the surface tension holds nothing: refused, naming the field
        let e = NucleusPool::new(&nuclei, &g, gamma, Some(0.05)).unwrap_err();
        assert_eq!(e.field, "nucleation.skin_compression");
    }

    #[test]
    fn a_nucleus_outside_the_phantom_is_refused() {
        let g = grid();
        let n = Nucleus {
            position: [2e-3, 0.5e-3, 0.5e-3],
            radius: 1e-6,
        };
        assert!(NucleusPool::new(&[n], &g, 0.07, None).is_err());
        assert_eq!(
            cell_of(&g, [0.05e-3, 0.15e-3, 0.95e-3]),
            Some(g.index(0, 1, 9))
        );
    }
}
