//! Tissue elasticity Ω(R): the pressure the deformed gel exerts on a bubble (the paper's
//! section 2.1.2). One small trait, one implementation per form, a registry keyed by the
//! `law` name used in TOML. Adding a law is one implementation plus one registry line.

use serde::Deserialize;

/// What an elasticity law may depend on.
#[derive(Debug, Clone, Copy)]
pub struct ElasticState {
    /// Current bubble radius R_B, m.
    pub radius: f64,
    /// The bubble's initial (reference) radius R_0, m.
    pub initial_radius: f64,
    /// Current ambient pressure P_amb, Pa.
    pub ambient: f64,
    /// Ambient pressure when the bubble was created, P_0, Pa.
    pub initial_ambient: f64,
}

/// A tissue-elasticity law Ω(R) (Pa).
pub trait ElasticityLaw: Send + Sync + std::fmt::Debug {
    /// The name used in TOML and in tables.
    fn name(&self) -> &'static str;
    /// Ω(R_B), Pa.
    fn omega(&self, s: &ElasticState) -> f64;
}

/// Ω = 0: no tissue response.
#[derive(Debug, Clone, Copy)]
pub struct NoElasticity;
impl ElasticityLaw for NoElasticity {
    fn name(&self) -> &'static str {
        "none"
    }
    fn omega(&self, _: &ElasticState) -> f64 {
        0.0
    }
}

/// Bulk Modulus form, eq. (2.6), absolute: Ω = (4/3)πR³·M with M = K/V_aff.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BulkModulus {
    /// M = K/V_aff, Pa/m³ (the paper's Fig. 2a: 5e-2 Pa/µm³ = 5e16 Pa/m³).
    pub bulk_modulus_per_volume: f64,
}
impl ElasticityLaw for BulkModulus {
    fn name(&self) -> &'static str {
        "bulk-modulus"
    }
    fn omega(&self, s: &ElasticState) -> f64 {
        4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3) * self.bulk_modulus_per_volume
    }
}

/// Continuity of Displacement form, eq. (2.7): Ω = −4μ/3 (valid for 0 < μ ≪ K).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContinuityOfDisplacement {
    /// Small shear modulus μ, Pa.
    pub shear_modulus: f64,
}
impl ElasticityLaw for ContinuityOfDisplacement {
    fn name(&self) -> &'static str {
        "continuity-of-displacement"
    }
    fn omega(&self, _: &ElasticState) -> f64 {
        -4.0 * self.shear_modulus / 3.0
    }
}

/// Reference Configuration form, eq. (2.8):
/// Ω = 4μ[(1 − P_0/3K)·R_B/R_0 − (1 − P_amb/3K)].
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceConfiguration {
    /// Small shear modulus μ, Pa.
    pub shear_modulus: f64,
    /// Bulk modulus K, Pa (the paper's Fig. 2a: 2.2 GPa).
    pub bulk_modulus: f64,
}
impl ElasticityLaw for ReferenceConfiguration {
    fn name(&self) -> &'static str {
        "reference-configuration"
    }
    fn omega(&self, s: &ElasticState) -> f64 {
        let k3 = 3.0 * self.bulk_modulus;
        4.0 * self.shear_modulus
            * ((1.0 - s.initial_ambient / k3) * s.radius / s.initial_radius
                - (1.0 - s.ambient / k3))
    }
}

/// Hyperelastic form, eq. (2.9): Ω = (μ/2)[5 − 4(R_B/R_0)⁻¹ − (R_B/R_0)⁻⁴].
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Hyperelastic {
    /// Small shear modulus μ, Pa.
    pub shear_modulus: f64,
}
impl ElasticityLaw for Hyperelastic {
    fn name(&self) -> &'static str {
        "hyperelastic"
    }
    fn omega(&self, s: &ElasticState) -> f64 {
        let x = s.initial_radius / s.radius;
        0.5 * self.shear_modulus * (5.0 - 4.0 * x - x.powi(4))
    }
}

/// The sum of several laws, Ω = Σ Ω_i: a law with an extra term on top (used by `discover`'s
/// `elasticity:<law>` candidates, whose extra term at zero modulus leaves the model exactly as
/// it was). TOML: `law = "sum"`, `terms = [{ law = "hyperelastic", shear_modulus = 40.0 }, …]`.
#[derive(Debug)]
pub struct Sum {
    /// The terms.
    pub terms: Vec<Box<dyn ElasticityLaw>>,
}
impl ElasticityLaw for Sum {
    fn name(&self) -> &'static str {
        "sum"
    }
    fn omega(&self, s: &ElasticState) -> f64 {
        self.terms.iter().map(|t| t.omega(s)).sum()
    }
}

fn parse_sum(v: toml::Value) -> Result<Box<dyn ElasticityLaw>, String> {
    let mut t = match v {
        toml::Value::Table(t) => t,
        _ => return Err("a sum law needs a table".into()),
    };
    let terms = t
        .remove("terms")
        .ok_or("law \"sum\" needs terms = [{ law = ... }, ...]")?;
    if let Some(k) = t.keys().next() {
        return Err(format!(
            "unknown field `{k}` of law \"sum\", expected `terms`"
        ));
    }
    let list = terms.as_array().ok_or("terms must be a list of tables")?;
    let mut out = Vec::new();
    for (i, item) in list.iter().enumerate() {
        let mut tt = item
            .as_table()
            .cloned()
            .ok_or_else(|| format!("terms[{i}] must be a table with a law"))?;
        let name = tt
            .remove("law")
            .and_then(|l| l.as_str().map(str::to_string))
            .ok_or_else(|| format!("terms[{i}] needs law = \"...\""))?;
        if name == "sum" {
            return Err("a sum cannot contain a sum".into());
        }
        out.push(build(&name, toml::Value::Table(tt)).map_err(
            |e| match crate::error::split_keyed(&e) {
                Some((k, rest)) => format!("terms[{i}].{k}: {rest}"),
                None => format!("terms[{i}]: {e}"),
            },
        )?);
    }
    Ok(Box::new(Sum { terms: out }))
}

type Build = fn(toml::Value) -> Result<Box<dyn ElasticityLaw>, String>;

fn parse<T: for<'de> Deserialize<'de> + ElasticityLaw + 'static>(
    v: toml::Value,
) -> Result<Box<dyn ElasticityLaw>, String> {
    crate::error::table_into::<T>(v).map(|x| Box::new(x) as Box<dyn ElasticityLaw>)
}

/// The registry: TOML name → constructor from the law's parameter table.
pub const REGISTRY: &[(&str, Build)] = &[
    ("none", |v| {
        match v.as_table().and_then(|t| t.keys().next()) {
            Some(k) => Err(format!(
                "{k}: unknown field `{k}`: law \"none\" takes no parameters"
            )),
            None => Ok(Box::new(NoElasticity)),
        }
    }),
    ("bulk-modulus", parse::<BulkModulus>),
    (
        "continuity-of-displacement",
        parse::<ContinuityOfDisplacement>,
    ),
    ("reference-configuration", parse::<ReferenceConfiguration>),
    ("hyperelastic", parse::<Hyperelastic>),
    ("sum", parse_sum),
];

/// Names of the paper's forms (every registered law but the `sum` combinator), in registry order.
pub fn law_names() -> Vec<&'static str> {
    REGISTRY
        .iter()
        .map(|(n, _)| *n)
        .filter(|n| *n != "sum")
        .collect()
}

/// Build a law by name from its parameter table (fields other than `law`).
pub fn build(name: &str, params: toml::Value) -> Result<Box<dyn ElasticityLaw>, String> {
    let (_, b) = REGISTRY.iter().find(|(n, _)| *n == name).ok_or_else(|| {
        format!(
            "unknown elasticity law '{name}'; known: {}",
            law_names().join(", ")
        )
    })?;
    b(params)
}

/// Parameters from which every law can be built (the `elasticity` subcommand and comparisons).
#[derive(Debug, Clone, Copy)]
pub struct AllLawParams {
    /// μ, Pa.
    pub shear_modulus: f64,
    /// M, Pa/m³.
    pub bulk_modulus_per_volume: f64,
    /// K, Pa.
    pub bulk_modulus: f64,
}

impl AllLawParams {
    /// Build the named law from these parameters.
    pub fn build(&self, name: &str) -> Result<Box<dyn ElasticityLaw>, String> {
        let mut t = toml::Table::new();
        match name {
            "bulk-modulus" => {
                t.insert(
                    "bulk_modulus_per_volume".into(),
                    self.bulk_modulus_per_volume.into(),
                );
            }
            "continuity-of-displacement" | "hyperelastic" => {
                t.insert("shear_modulus".into(), self.shear_modulus.into());
            }
            "reference-configuration" => {
                t.insert("shear_modulus".into(), self.shear_modulus.into());
                t.insert("bulk_modulus".into(), self.bulk_modulus.into());
            }
            _ => {}
        }
        build(name, toml::Value::Table(t))
    }
}
