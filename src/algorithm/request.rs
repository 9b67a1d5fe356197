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
    // the runtime without stops (descent, bottom, ascent) must fit in the longest history
    // accepted before anything is planned, and the planned runtime after
    let c = &alg.conventions;
    let descent_min = depth_m / c.descent_rate_m_min;
    let ascent_min = depth_m / c.ascent_rate_m_min;
    let at_bottom_min = if c.bottom_time_includes_descent {
        time_min
    } else {
        time_min + descent_min
    };
    check_runtime(at_bottom_min + ascent_min, 0.0, descent_min, ascent_min, c)?;
    let schedule =
        alg.algorithm
            .plan(&plan)
            .map_err(|e| if e.file.is_none() { locate(e) } else { e })?;
    check_runtime(
        schedule.runtime_min(),
        schedule.stop_time_min(),
        descent_min,
        ascent_min,
        c,
    )?;
    Ok((plan, schedule))
}

/// Refuse a plan whose runtime (min) exceeds the longest history accepted (30 days,
/// [`crate::profile::MAX_DURATION_S`]: nothing could simulate or check it), naming the option
/// that made it long: the ascent or descent rate when its travel time is the larger part,
/// else the bottom time (which sets the stops too).
fn check_runtime(
    runtime_min: f64,
    stops_min: f64,
    descent_min: f64,
    ascent_min: f64,
    c: &super::Conventions,
) -> Result<(), InputError> {
    let max_min = crate::profile::MAX_DURATION_S / 60.0;
    if runtime_min.is_finite() && runtime_min <= max_min {
        return Ok(());
    }
    let field = if ascent_min >= descent_min && ascent_min >= runtime_min / 2.0 {
        "--ascent-rate"
    } else if descent_min >= runtime_min / 2.0 {
        "--descent-rate"
    } else {
        "--time"
    };
    Err(InputError::new(format!(
        "the dive would last {} min (descent {} min at {} m/min, ascent {} min at {} m/min{}), beyond the {max_min} min (30 days) a history may last; plan a shorter dive or faster travel",
        crate::error::num(runtime_min),
        crate::error::num(descent_min),
        c.descent_rate_m_min,
        crate::error::num(ascent_min),
        c.ascent_rate_m_min,
        if stops_min > 0.0 {
            format!(", stops {} min", crate::error::num(stops_min))
        } else {
            String::new()
        }
    ))
    .in_file("<command line>")
    .field(field))
}
