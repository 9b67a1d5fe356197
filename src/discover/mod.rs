//! Finding the effect the model is missing (issue 7's `discover`): candidate model extensions,
//! residual diagnostics, and a forward search that adds an effect only when an extra
//! sum-of-squares F-test, Bonferroni-corrected over the candidates tried, says the data need it
//! and the gain in RMSE exceeds the simulation's own numerical error.
//!
//! A candidate is a [`CandidateEffect`]: one file each, one line each in [`REGISTRY`]. It edits
//! the phantom documents so that the effect is present with its parameters at their *null*
//! values — where the model is exactly the one it was given — and names those parameters.

pub mod bubble_fixed_gases;
pub mod diagnose;
pub mod elasticity;
pub mod perfusion;
pub mod report;
pub mod scale;
pub mod sealed_faces;
pub mod search;
pub mod surface_area_law;
pub mod surface_permeability;

use crate::fit::paths::ParamSpec;

/// One parameter of a candidate effect.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectParam {
    /// How it is fitted: path (or `scale:` pattern), log space, start.
    pub spec: ParamSpec,
    /// The value at which the effect is absent.
    pub null: f64,
    /// Values tried before the local fit starts (the best of these and the null is the start):
    /// a coarse scan, so that a fit from the null can reach an effect several decades away.
    pub scan: Vec<f64>,
}

/// What a candidate did to the model.
#[derive(Debug, Clone, PartialEq)]
pub struct Prepared {
    /// Its parameters (one or two), at their null values in the edited documents.
    pub params: Vec<EffectParam>,
    /// Degrees of freedom it adds (the number of parameters; 1 for a discrete choice without one).
    pub dof: usize,
}

/// A candidate model extension.
pub trait CandidateEffect: Send + Sync {
    /// Name in reports, `discover.toml` and `synth --effect` (e.g. `perfusion`, `elasticity:bulk-modulus`).
    fn name(&self) -> String;
    /// Edit the phantom documents (one per experiment) to hold the effect at its null values
    /// and return its parameters; `None` when it does not apply to these phantoms.
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String>;
}

/// What the candidates are built for: the experiments' phantoms, one TOML document each, and
/// the largest water-vapour pressure their profiles subtract at the open faces (Pa, 0 when
/// none does: [`crate::fit::data::Experiments::vapour_pa`]).
#[derive(Debug, Clone, Copy)]
pub struct Phantoms<'a> {
    /// One phantom document per experiment.
    pub docs: &'a [toml::Table],
    /// Water vapour subtracted at the open faces, Pa (the largest over the experiments).
    pub vapour_pa: f64,
}

impl<'a> Phantoms<'a> {
    /// The candidates' setting for these phantom documents of `experiments` (their profiles'
    /// largest vapour).
    pub fn of(experiments: &crate::fit::data::Experiments, docs: &'a [toml::Table]) -> Self {
        Phantoms {
            docs,
            vapour_pa: experiments.vapour_pa(),
        }
    }
}

/// Builds the candidates of one registry entry for given phantoms (an entry may expand to
/// several variants, e.g. one per elasticity law or one per open face).
pub type Build = fn(&Phantoms) -> Vec<Box<dyn CandidateEffect>>;

/// The registry: entry name → variants.
pub const REGISTRY: &[(&str, Build)] = &[
    ("surface-permeability", surface_permeability::build),
    ("surface-area-law", surface_area_law::build),
    ("elasticity", elasticity::build),
    ("sealed-faces", sealed_faces::build),
    ("perfusion", perfusion::build),
    ("bubble-fixed-gases", bubble_fixed_gases::build),
    ("diffusivity-scale", scale::build_diffusivity),
    ("solubility-scale", scale::build_solubility),
];

/// Every candidate for these phantoms, in registry order.
pub fn all_candidates(phantoms: &Phantoms) -> Vec<Box<dyn CandidateEffect>> {
    REGISTRY.iter().flat_map(|(_, b)| b(phantoms)).collect()
}

/// The candidate of this name (a registry name or a variant such as `elasticity:hyperelastic`).
pub fn find(phantoms: &Phantoms, name: &str) -> Option<Box<dyn CandidateEffect>> {
    all_candidates(phantoms)
        .into_iter()
        .find(|c| c.name() == name)
}

/// An effect switched on by one phantom setting whose null value is 0 (perfusion, fixed gases):
/// the setting is written as 0 in every phantom, fitted in log space from `start` (≈ the null),
/// after a scan of `scan`. Does not apply where a phantom already has the setting above 0.
/// With a `floor` (the fixed gases on profiles that subtract water vapour, where 0 means that
/// vapour and a value below it is refused) the setting is fitted from `floor` + `start` within
/// `floor`..`floor` + `ceiling`, and the scan is shifted by `floor`.
pub struct ZeroNullSetting {
    /// Candidate name.
    pub name: &'static str,
    /// Phantom TOML path.
    pub path: &'static str,
    /// Start of the local fit (negligible against the effects the scan covers).
    pub start: f64,
    /// Scan range (log-spaced, 5 values).
    pub scan: (f64, f64),
    /// Least value other than the null that the phantom accepts (0: none).
    pub floor: f64,
    /// With a floor, the fit's range above it.
    pub ceiling: f64,
}

impl CandidateEffect for ZeroNullSetting {
    fn name(&self) -> String {
        self.name.into()
    }
    fn prepare(&self, docs: &mut [toml::Table]) -> Result<Option<Prepared>, String> {
        use crate::fit::paths;
        if docs
            .iter()
            .any(|d| paths::get(d, self.path).is_some_and(|k| k > 0.0))
        {
            return Ok(None);
        }
        for d in docs.iter_mut() {
            paths::set(d, self.path, 0.0)?;
        }
        let mut spec = ParamSpec::positive(self.path, self.floor + self.start);
        if self.floor > 0.0 {
            spec.lower = Some(self.floor);
            spec.upper = Some(self.floor + self.ceiling);
        }
        Ok(Some(Prepared {
            params: vec![EffectParam {
                spec,
                null: 0.0,
                scan: log_scan(self.scan.0, self.scan.1, 5)
                    .into_iter()
                    .map(|x| self.floor + x)
                    .collect(),
            }],
            dof: 1,
        }))
    }
}

/// Log-spaced values from `lo` to `hi` (n ≥ 2).
pub fn log_scan(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| lo * (hi / lo).powf(i as f64 / (n - 1).max(1) as f64))
        .collect()
}
