//! A dive plan from the strings a user types (`--gas`, `--deco-gas`, `--travel-gas`), planned
//! with a loaded algorithm: what `plan` and `evaluate` share.

use super::schedule::parse_travel_gas;
use super::{DecoGas, DivePlan, LoadedAlgorithm, Schedule};
use crate::error::InputError;
use crate::gas::GasMix;

/// Plan a dive with a loaded algorithm from command-line strings (bottom gas, deco gases
/// `50@21` or `50`, travel gases `21/35@0..60`); errors point at the command-line option.
/// Deco or travel gases not given on the command line come from the algorithm file's
/// `[gases]` (errors about those name the file, line and `gases.deco` / `gases.travel`).
/// Used by `plan` and `evaluate`.
pub fn plan_dive(
    alg: &LoadedAlgorithm,
    depth_m: f64,
    time_min: f64,
    gas: Option<&str>,
    deco_gases: &[String],
    travel_gases: &[String],
) -> Result<(DivePlan, Schedule), InputError> {
    let cmd =
        |field: &str, msg: String| InputError::new(msg).in_file("<command line>").field(field);
    let bottom_gas = match gas {
        Some(g) => GasMix::parse(g).map_err(|m| cmd("--gas", m))?,
        None => GasMix::AIR,
    };
    let deco_from_file = deco_gases.is_empty() && !alg.gases.deco.is_empty();
    let deco_gases = if deco_from_file {
        alg.gases.deco.clone()
    } else {
        deco_gases
            .iter()
            .map(|s| DecoGas::parse(s, &alg.conventions).map_err(|m| cmd("--deco-gas", m)))
            .collect::<Result<Vec<_>, _>>()?
    };
    let travel_from_file = travel_gases.is_empty() && !alg.gases.travel.is_empty();
    let travel_gases = if travel_from_file {
        alg.gases.travel.clone()
    } else {
        travel_gases
            .iter()
            .map(|t| parse_travel_gas(t).map_err(|m| cmd("--travel-gas", m)))
            .collect::<Result<Vec<_>, _>>()?
    };
    let plan = DivePlan {
        depth_m,
        bottom_time_min: time_min,
        bottom_gas,
        deco_gases,
        travel_gases,
    };
    // where an error about a field of the plan points: the file's [gases] or the command line
    let locate = |e: InputError| -> InputError {
        let from_file = match e.field.as_deref() {
            Some("travel-gas") if travel_from_file => Some(("gases.travel", alg.gases.travel_line)),
            Some("deco-gas") if deco_from_file => Some(("gases.deco", alg.gases.deco_line)),
            _ => None,
        };
        match from_file {
            Some((field, line)) => {
                let mut e = e.in_file(&alg.gases.path);
                e.field = Some(field.to_string());
                if let Some(l) = line {
                    e = e.at_line(l);
                }
                e
            }
            None => {
                let f = e.field.clone().map(|f| format!("--{f}"));
                let mut e = e.in_file("<command line>");
                e.field = f;
                e
            }
        }
    };
    plan.validate(&alg.conventions).map_err(locate)?;
    let schedule =
        alg.algorithm
            .plan(&plan)
            .map_err(|e| if e.file.is_none() { locate(e) } else { e })?;
    Ok((plan, schedule))
}
