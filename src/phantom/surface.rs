//! Surface permeability D_surf of the bubble skin (the paper's section 4.1: D_surf was
//! found to be D_bulk/30 at R_0 and to scale with the surface area). One small trait,
//! a registry keyed by the TOML `law` name.

use serde::Deserialize;

/// A law for the diffusivity of the bubble's surface layer.
pub trait SurfacePermeability: Send + Sync + std::fmt::Debug {
    /// The name used in TOML.
    fn name(&self) -> &'static str;
    /// D_surf, m²/s, for bulk diffusivity `d_bulk` (m²/s), radius `r` and initial radius `r0` (m).
    fn d_surf(&self, d_bulk: f64, r: f64, r0: f64) -> f64;
}

/// D_surf = D_bulk (the default: the skin is no barrier).
#[derive(Debug, Clone, Copy)]
pub struct EqualToBulk;
impl SurfacePermeability for EqualToBulk {
    fn name(&self) -> &'static str {
        "equal"
    }
    fn d_surf(&self, d_bulk: f64, _: f64, _: f64) -> f64 {
        d_bulk
    }
}

/// D_surf = D_bulk/k (a constant fold; the paper found k = 30).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Fold {
    /// k, dimensionless (> 0).
    pub fold: f64,
}
impl SurfacePermeability for Fold {
    fn name(&self) -> &'static str {
        "fold"
    }
    fn d_surf(&self, d_bulk: f64, _: f64, _: f64) -> f64 {
        d_bulk / self.fold
    }
}

/// The paper-text area law (section 4.1): D_surf = (D_bulk/k)(R/R_ref)^a, a = 2 (the paper's
/// R_B² dependence; `exponent` sets another, as `discover`'s `surface-area-law` fits it), with R_ref each
/// bubble's own initial radius R_0 (the paper's wording) or, if `reference_radius_m` is given,
/// one fixed radius for every bubble — then D_surf depends on the current surface area only.
/// The paper fitted k = 30 at R_0 = 0.2 mm (the mean bubble of §4.1). With R_ref = R_0, a small
/// nucleus that grows gets a far more permeable skin than a large one at the same radius, which
/// reverses the paper's Fig. 6a trend (tests/integration/paper_findings.rs).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaLaw {
    /// k, dimensionless (> 0).
    pub fold: f64,
    /// R_ref, m (> 0); absent: each bubble's own R_0.
    #[serde(default)]
    pub reference_radius_m: Option<f64>,
    /// Exponent a of R/R_ref, dimensionless. Default 2 (surface area).
    #[serde(default = "default_area_exponent")]
    pub exponent: f64,
    /// Cap D_surf at D_bulk (TOML `cap_at_bulk`, default true): a surface layer is not more
    /// permeable than the gel it sits in. Uncapped, R0 = 86.5 µm with k = 30 gives
    /// D_surf = 3.4·D_bulk at R = 868 µm. `false` leaves the law uncapped.
    #[serde(default = "default_cap")]
    pub cap_at_bulk: bool,
}

fn default_area_exponent() -> f64 {
    2.0
}

fn default_cap() -> bool {
    true
}
impl SurfacePermeability for AreaLaw {
    fn name(&self) -> &'static str {
        "area"
    }
    fn d_surf(&self, d_bulk: f64, r: f64, r0: f64) -> f64 {
        let d =
            d_bulk / self.fold * (r / self.reference_radius_m.unwrap_or(r0)).powf(self.exponent);
        if self.cap_at_bulk {
            d.min(d_bulk)
        } else {
            d
        }
    }
}

/// The law in the authors' published code: D_surf = (D_bulk/k)(1 − R_0/R)² (zero at R = R_0;
/// clamped to zero for R < R_0).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AuthorsCodeLaw {
    /// k, dimensionless (> 0).
    pub fold: f64,
}
impl SurfacePermeability for AuthorsCodeLaw {
    fn name(&self) -> &'static str {
        "authors-code"
    }
    fn d_surf(&self, d_bulk: f64, r: f64, r0: f64) -> f64 {
        if r <= r0 {
            0.0
        } else {
            d_bulk / self.fold * (1.0 - r0 / r).powi(2)
        }
    }
}

type Build = fn(toml::Value) -> Result<Box<dyn SurfacePermeability>, String>;

fn parse<T: for<'de> Deserialize<'de> + SurfacePermeability + 'static>(
    v: toml::Value,
) -> Result<Box<dyn SurfacePermeability>, String> {
    let fold = v
        .get("fold")
        .and_then(|f| f.as_float().or(f.as_integer().map(|i| i as f64)));
    if let Some(k) = fold {
        if !(k > 0.0) {
            return Err(format!("fold: must be positive (got {k})"));
        }
    }
    let reference = v
        .get("reference_radius_m")
        .and_then(|f| f.as_float().or(f.as_integer().map(|i| i as f64)));
    if let Some(r) = reference {
        if !(r > 0.0) {
            return Err(format!("reference_radius_m: must be positive (got {r} m)"));
        }
    }
    crate::error::table_into::<T>(v).map(|x| Box::new(x) as Box<dyn SurfacePermeability>)
}

/// A law without parameters refuses any (a `fold` under `law = "equal"` would otherwise be
/// silently ignored).
fn no_params(law: &str, v: &toml::Value) -> Result<(), String> {
    match v.as_table().and_then(|t| t.keys().next()) {
        Some(k) => Err(format!(
            "{k}: unknown field `{k}`: law \"{law}\" takes no parameters (set law = \"fold\" or \"area\" to use a fold)"
        )),
        None => Ok(()),
    }
}

/// The registry: TOML name → constructor.
pub const REGISTRY: &[(&str, Build)] = &[
    ("equal", |v| {
        no_params("equal", &v)?;
        Ok(Box::new(EqualToBulk))
    }),
    ("fold", parse::<Fold>),
    ("area", parse::<AreaLaw>),
    ("authors-code", parse::<AuthorsCodeLaw>),
];

/// Build a law by name from its parameter table.
pub fn build(name: &str, params: toml::Value) -> Result<Box<dyn SurfacePermeability>, String> {
    let (_, b) = REGISTRY.iter().find(|(n, _)| *n == name).ok_or_else(|| {
        format!(
            "unknown surface law '{name}'; known: {}",
            REGISTRY
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", ")
        )
    })?;
    b(params)
}
