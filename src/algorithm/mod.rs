//! Decompression algorithms as plug-ins. A [`DecoAlgorithm`] turns a [`DivePlan`] into a
//! [`Schedule`]; the registry maps the `kind` written in `algorithms/*.toml` to a constructor.
//! Adding an algorithm is one new file and one registry line.

pub mod buhlmann;
pub mod config;
pub mod conventions;
pub mod loading;
pub mod oxygen;
pub mod registry;
pub mod request;
pub mod schedule;
pub mod vpmb;
pub mod waypoints;

pub use config::{load_algorithm, LoadedAlgorithm};
pub use conventions::Conventions;
pub use request::plan_dive;
pub use schedule::{DecoGas, DivePlan, GasSwitch, Leg, LegKind, Schedule, Stop, TravelGas};

/// A decompression algorithm: dive plan in, schedule out.
pub trait DecoAlgorithm: Send + Sync {
    /// A short label for tables and legends, e.g. `ZH-L16C GF 30/85`.
    fn label(&self) -> String;
    /// Plan the dive. Errors are bad plans (depth ≤ 0, hypoxic gas, deco gas beyond its MOD ...).
    fn plan(&self, plan: &DivePlan) -> Result<Schedule, crate::error::InputError>;
}

/// Builds an algorithm from the `[params]` table of an algorithm TOML and the resolved
/// conventions. The error string names the offending field; the loader adds file and line.
pub type Builder = fn(
    label: &str,
    params: toml::Value,
    conventions: Conventions,
) -> Result<Box<dyn DecoAlgorithm>, String>;
