//! A planned dive and the schedule an algorithm produces for it.

use super::conventions::Conventions;
use crate::error::{line_of_key, toml_error_with_path, InputError};
use crate::gas::GasMix;
use crate::profile::PressureHistory;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Highest oxygen partial pressure a gas may be breathed at, bar (1.6: NOAA Diving Manual,
/// 4th ed., table 3-3, the exceptional-exposure / deco limit; also the default deco ppO2 of
/// DecoTengu users, Subsurface and most planners).
pub const MAX_PPO2_BAR: f64 = 1.6;
/// Below this oxygen partial pressure a bottom gas is refused as hypoxic at the surface, bar.
/// 0.15 rather than the more usual 0.16 so that Baker's own VPMDECO example (trimix 15/45 from
/// the surface, ppO2 0.152 bar) plans; one limit for every algorithm.
pub const HYPOXIC_PPO2_BAR: f64 = 0.15;

/// Maximum operating depth of a mix at a ppO2 limit (bar) in these conventions, m (not rounded).
pub fn mod_m(mix: GasMix, ppo2_bar: f64, conventions: &Conventions) -> f64 {
    (ppo2_bar * 1e5 / mix.o2 - conventions.surface_pressure_pa) / conventions.pa_per_m
}

impl DecoGas {
    /// Parse `50@21` (mix and switch depth in m) or `50` (switch at the MOD at 1.6 bar rounded to
    /// the nearest metre, e.g. EAN50 → 22 m, O2 → 6 m in DecoTengu's conventions).
    pub fn parse(s: &str, conventions: &Conventions) -> Result<DecoGas, String> {
        let (mix_s, depth_s) = match s.split_once('@') {
            Some((m, d)) => (m, Some(d)),
            None => (s, None),
        };
        let mix = GasMix::parse(mix_s)?;
        if mix.o2 <= 0.0 {
            return Err(format!("deco gas '{s}' has no oxygen"));
        }
        let switch_depth_m = match depth_s {
            Some(d) => d.trim().trim_end_matches('m').parse::<f64>().map_err(|_| {
                format!("cannot read the switch depth in '{s}': write MIX@DEPTH_M, e.g. 50@21")
            })?,
            None => mod_m(mix, MAX_PPO2_BAR, conventions).round(),
        };
        Ok(DecoGas {
            mix,
            switch_depth_m,
        })
    }
}

/// Deepest dive a plan may have, m.
pub const MAX_PLAN_DEPTH_M: f64 = 1000.0;

/// How far a `[[stops]]` row's depth may lie from its stop leg's, m: half the 0.1 m a stop
/// table is printed to (`plan --out` writes full precision, so its files agree exactly).
pub const STOP_TABLE_TOLERANCE_M: f64 = 0.05;

/// How far a `[[stops]]` row's runtime and minutes may lie outside what its legs give, min:
/// half the 0.1 min (6 s) a stop table is printed to.
pub const STOP_TABLE_TOLERANCE_MIN: f64 = 0.05;

/// A rate for a message, m/min: to 4 significant digits (3000, not 2999.999999999531 from
/// times in minutes), `inf` for a change in no time.
pub(crate) fn rate_text(rate: f64) -> String {
    if !(rate.is_finite() && rate > 0.0) {
        return crate::error::num(rate);
    }
    let scale = 10f64.powi(3 - rate.log10().floor() as i32);
    crate::error::num((rate * scale).round() / scale)
}

/// The rate of a change of depth of `depth_change_m` in `duration_s`, m/min, when it is faster
/// than [`super::conventions::MAX_TRAVEL_RATE_M_MIN`] (infinite for a change in no time);
/// `None` for no change or an accepted rate. A relative 1e-9 is allowed for the rounding of
/// times written in minutes, so that a leg at exactly 100 m/min passes.
pub(crate) fn too_fast(depth_change_m: f64, duration_s: f64) -> Option<f64> {
    if depth_change_m == 0.0 {
        return None;
    }
    let rate = if duration_s > 0.0 {
        depth_change_m.abs() / (duration_s / 60.0)
    } else {
        f64::INFINITY
    };
    (rate > super::conventions::MAX_TRAVEL_RATE_M_MIN * (1.0 + 1e-9)).then_some(rate)
}

impl DivePlan {
    /// The gases available on the ascent: the deco gases, and each travel gas from the deep
    /// end of its range (where the diver left it on the way down) unless a deco gas is
    /// switched to at the same depth.
    pub fn ascent_gases(&self) -> Vec<DecoGas> {
        let mut out = self.deco_gases.clone();
        for t in &self.travel_gases {
            if !out.iter().any(|d| (d.switch_depth_m - t.to_m).abs() < 1e-9) {
                out.push(DecoGas {
                    mix: t.mix,
                    switch_depth_m: t.to_m,
                });
            }
        }
        out
    }

    /// The descent as (from m, to m, gas) segments: each travel gas over its range (shallowest
    /// first), then the bottom gas from the deepest travel gas's end to the bottom.
    pub fn descent_segments(&self) -> Vec<(f64, f64, GasMix)> {
        let mut travel = self.travel_gases.clone();
        travel.sort_by(|a, b| a.from_m.total_cmp(&b.from_m));
        let mut out: Vec<(f64, f64, GasMix)> =
            travel.iter().map(|t| (t.from_m, t.to_m, t.mix)).collect();
        let start = travel.last().map_or(0.0, |t| t.to_m);
        out.push((start, self.depth_m, self.bottom_gas));
        out
    }

    /// Check the plan: depth and time positive, bottom gas breathable at the surface (not
    /// hypoxic) and at the bottom (within its MOD), deco gases within their MOD at their switch
    /// depth, shallower than the bottom, at distinct positive depths. Errors name the
    /// command-line field (`depth`, `time`, `gas`, `deco-gas`).
    pub fn validate(&self, conventions: &Conventions) -> Result<(), InputError> {
        if !(self.depth_m.is_finite() && self.depth_m > 0.0) {
            return Err(InputError::new(format!(
                "depth {} m: the maximum depth must be a positive number of metres",
                self.depth_m
            ))
            .field("depth"));
        }
        if !(self.bottom_time_min.is_finite() && self.bottom_time_min > 0.0) {
            return Err(InputError::new(format!(
                "bottom time {} min must be a positive number of minutes",
                self.bottom_time_min
            ))
            .field("time"));
        }
        if self.depth_m > MAX_PLAN_DEPTH_M {
            return Err(InputError::new(format!(
                "depth {} m is beyond the accepted {MAX_PLAN_DEPTH_M} m",
                crate::error::num(self.depth_m)
            ))
            .field("depth"));
        }
        let max_min = crate::profile::MAX_DURATION_S / 60.0;
        if self.bottom_time_min > max_min {
            return Err(InputError::new(format!(
                "bottom time {} min is beyond the accepted {max_min} min (30 days simulated)",
                crate::error::num(self.bottom_time_min)
            ))
            .field("time"));
        }
        let descent = self.depth_m / conventions.descent_rate_m_min;
        if conventions.bottom_time_includes_descent && self.bottom_time_min < descent {
            return Err(InputError::new(format!(
                "bottom time {} min is shorter than the descent ({descent:.1} min at {} m/min) that it includes; write at least {descent:.1} min",
                self.bottom_time_min, conventions.descent_rate_m_min
            ))
            .field("time"));
        }
        let ppo2 = |mix: GasMix, d: f64| mix.o2 * conventions.pressure_at(d) / 1e5;
        let g = self.bottom_gas;
        if self.travel_gases.is_empty() {
            if ppo2(g, 0.0) < HYPOXIC_PPO2_BAR - 1e-12 {
                return Err(InputError::new(format!(
                    "bottom gas {} is hypoxic at the surface (ppO2 {:.3} bar < {HYPOXIC_PPO2_BAR} bar); \
                     it cannot be breathed on the descent — choose a mix with more oxygen, or give a \
                     travel gas (--travel-gas 21/35@0..60)",
                    g.label(),
                    ppo2(g, 0.0)
                ))
                .field("gas"));
            }
        } else {
            self.validate_travel_gases(conventions)?;
        }
        let max_depth = mod_m(g, MAX_PPO2_BAR, conventions).round();
        if self.depth_m > max_depth + 1e-9 {
            return Err(InputError::new(format!(
                "bottom gas {} at {} m has ppO2 {:.2} bar, beyond its MOD {} m (ppO2 {MAX_PPO2_BAR} bar); \
                 choose a mix with less oxygen or a shallower depth",
                g.label(),
                self.depth_m,
                ppo2(g, self.depth_m),
                max_depth
            ))
            .field("gas"));
        }
        for (i, d) in self.deco_gases.iter().enumerate() {
            let lab = d.mix.label();
            if !(d.switch_depth_m.is_finite() && d.switch_depth_m > 0.0) {
                return Err(InputError::new(format!(
                    "deco gas {lab}: switch depth {} m must be positive",
                    d.switch_depth_m
                ))
                .field("deco-gas"));
            }
            let m = mod_m(d.mix, MAX_PPO2_BAR, conventions).round();
            if d.switch_depth_m > m + 1e-9 {
                return Err(InputError::new(format!(
                    "deco gas {lab} switched at {} m is beyond its MOD {m} m (ppO2 {:.2} bar > {MAX_PPO2_BAR} bar); \
                     switch at {m} m or shallower",
                    d.switch_depth_m,
                    ppo2(d.mix, d.switch_depth_m)
                ))
                .field("deco-gas"));
            }
            if d.switch_depth_m >= self.depth_m {
                return Err(InputError::new(format!(
                    "deco gas {lab} switch depth {} m is not shallower than the dive ({} m); \
                     it would be a bottom gas — drop it or give a shallower switch depth",
                    d.switch_depth_m, self.depth_m
                ))
                .field("deco-gas"));
            }
            if self.deco_gases[..i]
                .iter()
                .any(|o| (o.switch_depth_m - d.switch_depth_m).abs() < 1e-9)
            {
                return Err(InputError::new(format!(
                    "two deco gases switch at {} m; give each its own switch depth",
                    d.switch_depth_m
                ))
                .field("deco-gas"));
            }
        }
        Ok(())
    }

    /// The travel gases: ranges contiguous from the surface, each shallower than the bottom,
    /// not hypoxic at its shallow end ([`HYPOXIC_PPO2_BAR`]), within its MOD
    /// ([`MAX_PPO2_BAR`], rounded to the metre as for deco gases) at its deep end, and the
    /// bottom gas not hypoxic where it takes over. Errors name `travel-gas`.
    fn validate_travel_gases(&self, conventions: &Conventions) -> Result<(), InputError> {
        let ppo2 = |mix: GasMix, d: f64| mix.o2 * conventions.pressure_at(d) / 1e5;
        let err = |msg: String| Err(InputError::new(msg).field("travel-gas"));
        let mut travel = self.travel_gases.clone();
        travel.sort_by(|a, b| a.from_m.total_cmp(&b.from_m));
        let mut reached = 0.0;
        for tg in &travel {
            let lab = tg.mix.label();
            let range = format!("{}@{}..{}", lab, tg.from_m, tg.to_m);
            if !(tg.from_m.is_finite() && tg.to_m.is_finite() && tg.to_m > tg.from_m) {
                return err(format!(
                    "travel gas {range}: the range must run from a shallower to a deeper depth (m)"
                ));
            }
            if (tg.from_m - reached).abs() > 1e-9 {
                return err(if reached == 0.0 {
                    format!(
                        "travel gas {range} starts at {} m; the first travel gas is breathed from the surface (write @0..DEPTH)",
                        tg.from_m
                    )
                } else {
                    format!(
                        "travel gas {range} starts at {} m but the previous travel gas ends at {reached} m; \
                         travel gas ranges must follow each other without gap or overlap",
                        tg.from_m
                    )
                });
            }
            if tg.to_m >= self.depth_m {
                return err(format!(
                    "travel gas {range} reaches {} m, not shallower than the dive ({} m); \
                     the bottom gas must take over above the bottom",
                    tg.to_m, self.depth_m
                ));
            }
            let shallow = ppo2(tg.mix, tg.from_m);
            if shallow < HYPOXIC_PPO2_BAR - 1e-12 {
                return err(format!(
                    "travel gas {range} is hypoxic at its shallow end {} m (ppO2 {shallow:.3} bar < {HYPOXIC_PPO2_BAR} bar)",
                    tg.from_m
                ));
            }
            let m = mod_m(tg.mix, MAX_PPO2_BAR, conventions).round();
            if tg.to_m > m + 1e-9 {
                return err(format!(
                    "travel gas {range} breathed to {} m is beyond its MOD {m} m (ppO2 {:.2} bar > {MAX_PPO2_BAR} bar at its deep end)",
                    tg.to_m,
                    ppo2(tg.mix, tg.to_m)
                ));
            }
            reached = tg.to_m;
        }
        let g = self.bottom_gas;
        if ppo2(g, reached) < HYPOXIC_PPO2_BAR - 1e-12 {
            return err(format!(
                "bottom gas {} is hypoxic at the travel-gas switch depth {reached} m (ppO2 {:.3} bar < {HYPOXIC_PPO2_BAR} bar); switch deeper",
                g.label(),
                ppo2(g, reached)
            ));
        }
        Ok(())
    }
}

/// A decompression gas and the depth at which it is switched to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DecoGas {
    /// The mix.
    pub mix: GasMix,
    /// Switch depth, m (default: MOD at ppO2 1.6 bar).
    pub switch_depth_m: f64,
}

/// What the diver wants to do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DivePlan {
    /// Maximum depth, m.
    pub depth_m: f64,
    /// Bottom time, min (whether it includes the descent is a convention).
    pub bottom_time_min: f64,
    /// Bottom gas.
    pub bottom_gas: GasMix,
    /// Decompression gases.
    pub deco_gases: Vec<DecoGas>,
    /// Travel gases, each breathed over its depth range on the descent (the ranges follow
    /// each other from the surface; the bottom gas takes over at the deepest range's end),
    /// needed for hypoxic bottom mixes. On the ascent each is available again from the deep
    /// end of its range, like a deco gas (as Subsurface's planner uses every gas carried).
    /// Empty: the bottom gas from the surface.
    #[serde(default)]
    pub travel_gases: Vec<TravelGas>,
}

/// A travel gas and the depth range over which it is breathed on the descent.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TravelGas {
    /// The mix.
    pub mix: GasMix,
    /// Shallow end of the range, m (0 for the first travel gas).
    pub from_m: f64,
    /// Deep end of the range, m: where the next travel gas or the bottom gas takes over.
    pub to_m: f64,
}

/// Parse a travel gas `21/35@0..60` (mix, then the depth range in m over which it is breathed
/// on the descent) or `21/35@60` (short for `@0..60`).
pub fn parse_travel_gas(s: &str) -> Result<TravelGas, String> {
    let (mix_s, range) = s.split_once('@').ok_or_else(|| {
        format!("travel gas '{s}' needs its depth range: write MIX@FROM..TO (m), e.g. 21/35@0..60")
    })?;
    let mix = GasMix::parse(mix_s)?;
    if mix.o2 <= 0.0 {
        return Err(format!("travel gas '{s}' has no oxygen"));
    }
    let num = |x: &str, what: &str| -> Result<f64, String> {
        let v: f64 = x
            .trim()
            .trim_end_matches('m')
            .trim()
            .parse()
            .map_err(|_| format!("cannot read the {what} depth in travel gas '{s}': write MIX@FROM..TO (m), e.g. 21/35@0..60"))?;
        if !(v.is_finite() && v >= 0.0) {
            return Err(format!(
                "travel gas '{s}': the {what} depth must be zero or a positive number of metres"
            ));
        }
        Ok(v)
    };
    let (from_m, to_m) = match range.split_once("..") {
        Some((from, to)) => (num(from, "start")?, num(to, "end")?),
        None => (0.0, num(range, "end")?),
    };
    Ok(TravelGas { mix, from_m, to_m })
}

/// The kind of a schedule leg.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LegKind {
    /// Descent from the surface.
    Descent,
    /// Time at the bottom.
    Bottom,
    /// Travel upwards.
    Ascent,
    /// A decompression stop (constant depth).
    Stop,
}

/// One leg of constant rate and one gas.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Leg {
    /// What this leg is.
    pub kind: LegKind,
    /// Depth at the start, m.
    pub start_depth_m: f64,
    /// Depth at the end, m.
    pub end_depth_m: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Gas breathed on the leg.
    pub gas: GasMix,
}

/// A stop as printed in a stop table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stop {
    /// Stop depth, m.
    pub depth_m: f64,
    /// Minutes at the stop (as the algorithm's rounding convention counts them).
    pub stop_min: f64,
    /// Runtime when leaving the stop, min.
    pub runtime_min: f64,
    /// Gas at the stop.
    pub gas: GasMix,
}

/// A dive schedule: legs from the surface back to the surface.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Schedule {
    /// Label, e.g. `ZH-L16C GF 30/85`.
    pub label: String,
    /// Surface pressure, Pa.
    pub surface_pressure_pa: f64,
    /// Pressure per metre, Pa/m.
    pub pa_per_m: f64,
    /// Alveolar water vapour, Pa (subtracted at the phantom's open faces).
    pub water_vapour_pa: f64,
    /// The legs in order.
    pub legs: Vec<Leg>,
    /// The stops (derived from the legs by the algorithm with its rounding convention).
    pub stops: Vec<Stop>,
}

/// A gas switch found in a schedule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GasSwitch {
    /// Runtime of the switch, min.
    pub runtime_min: f64,
    /// Depth of the switch, m.
    pub depth_m: f64,
    /// The gas switched to.
    pub gas: GasMix,
}

/// The text written for a gas in schedule files: `air`, `O2`, `EAN50`, `18/45`, with
/// percentages to 1e-9 so that reading it back gives the same fractions.
pub fn gas_text(mix: GasMix) -> String {
    let pct = |x: f64| {
        let v = (x * 100.0 * 1e9).round() / 1e9;
        format!("{v}")
    };
    if mix.he > 0.0 {
        format!("{}/{}", pct(mix.o2), pct(mix.he))
    } else if mix == GasMix::AIR {
        "air".into()
    } else if mix.o2 == 1.0 {
        "O2".into()
    } else {
        format!("EAN{}", pct(mix.o2))
    }
}

/// Informational summary written into a schedule file (ignored when read back, except that
/// unknown keys are errors).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScheduleSummary {
    /// Total runtime, min.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub runtime_min: Option<f64>,
    /// CNS oxygen toxicity, % of the NOAA limit.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub cns_percent: Option<f64>,
    /// Pulmonary oxygen toxicity units.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub otu: Option<f64>,
    /// The algorithm file the schedule came from.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub algorithm: Option<String>,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawLeg {
    kind: LegKind,
    start_depth_m: f64,
    end_depth_m: f64,
    duration_s: f64,
    gas: String,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStop {
    depth_m: f64,
    stop_min: f64,
    runtime_min: f64,
    gas: String,
}

#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSchedule {
    label: String,
    surface_pressure_pa: f64,
    pa_per_m: f64,
    water_vapour_pa: f64,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    summary: Option<ScheduleSummary>,
    legs: Vec<RawLeg>,
    #[serde(default)]
    stops: Vec<RawStop>,
}

/// 1-based line of `key =` in the table `[table]` (else the table's header line).
fn line_in_table(text: &str, table: &str, key: &str) -> Option<usize> {
    let header = format!("[{table}]");
    let start = text
        .lines()
        .position(|l| l.split('#').next().unwrap_or("").trim() == header)?;
    let found = text
        .lines()
        .enumerate()
        .skip(start + 1)
        .take_while(|(_, l)| !l.trim_start().starts_with('['))
        .find(|(_, l)| {
            let t = l.trim_start();
            t.starts_with(key) && t[key.len()..].trim_start().starts_with('=')
        })
        .map(|(i, _)| i + 1);
    Some(found.unwrap_or(start + 1))
}

/// 1-based line of the `n`-th (0-based) line equal to `header` (e.g. `[[legs]]`).
fn line_of_nth(text: &str, header: &str, n: usize) -> Option<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim() == header)
        .nth(n)
        .map(|(i, _)| i + 1)
}

/// 1-based line of `key =` in the `n`-th (0-based) table `header` (e.g. `[[stops]]`), `None`
/// if the table or the key is not found.
fn line_of_nth_key(text: &str, header: &str, n: usize, key: &str) -> Option<usize> {
    let start = line_of_nth(text, header, n)?;
    text.lines()
        .enumerate()
        .skip(start)
        .take_while(|(_, l)| !l.trim_start().starts_with('['))
        .find(|(_, l)| {
            let t = l.trim_start();
            t.starts_with(key) && t[key.len()..].trim_start().starts_with('=')
        })
        .map(|(i, _)| i + 1)
}

/// A leg's kind against its direction, and its rate: a `descent` goes down, an `ascent` up
/// (both may be a zero-length gas switch), and a change of depth takes a time within the
/// accepted rates. `Err((field, message))`.
fn check_travel(l: &RawLeg) -> Result<(), (&'static str, String)> {
    use super::conventions::{MAX_TRAVEL_RATE_M_MIN, MIN_TRAVEL_RATE_M_MIN};
    let change = l.end_depth_m - l.start_depth_m;
    let moves = change.abs() > 1e-9;
    let (from, to) = (
        crate::error::num(l.start_depth_m),
        crate::error::num(l.end_depth_m),
    );
    let wrong_way = match l.kind {
        LegKind::Descent => change < -1e-9 || (!moves && l.duration_s > 0.0),
        LegKind::Ascent => change > 1e-9 || (!moves && l.duration_s > 0.0),
        LegKind::Stop | LegKind::Bottom => false,
    };
    if wrong_way {
        let (kind, should) = match l.kind {
            LegKind::Descent => ("descent", "go down"),
            _ => ("ascent", "go up"),
        };
        let actual = if change > 1e-9 {
            "goes down".to_string()
        } else if change < -1e-9 {
            "goes up".to_string()
        } else {
            format!("stays at {from} m")
        };
        return Err((
            "kind",
            format!(
                "kind \"{kind}\" but the leg {actual} ({from} m to {to} m): a {kind} must {should}; correct the kind or the depths"
            ),
        ));
    }
    if !moves {
        return Ok(());
    }
    if let Some(rate) = too_fast(change, l.duration_s) {
        return Err((
            "duration_s",
            format!(
                "{from} m to {to} m in {} s is {} m/min, faster than the accepted {MAX_TRAVEL_RATE_M_MIN} m/min; give the time the movement takes",
                crate::error::num(l.duration_s),
                rate_text(rate)
            ),
        ));
    }
    let rate = change.abs() / (l.duration_s / 60.0);
    if rate < MIN_TRAVEL_RATE_M_MIN * (1.0 - 1e-9) {
        return Err((
            "duration_s",
            format!(
                "{from} m to {to} m in {} s is {} m/min, slower than the accepted {MIN_TRAVEL_RATE_M_MIN:.4} m/min (at which 1000 m take the whole 30 days a history may last)",
                crate::error::num(l.duration_s),
                rate_text(rate)
            ),
        ));
    }
    Ok(())
}

/// A stop as the legs give it: a run of consecutive `stop` legs at one depth.
#[derive(Debug, Clone, Copy)]
struct LegStop {
    depth_m: f64,
    /// Runtime when the stop starts and ends, s.
    start_s: f64,
    end_s: f64,
    /// The legs' total duration, s.
    duration_s: f64,
    /// The gas of its last leg.
    gas: GasMix,
    /// 0-based index of its first leg.
    first_leg: usize,
}

/// The stops of the legs, in order.
fn stops_of_legs(legs: &[Leg]) -> Vec<LegStop> {
    let mut out: Vec<LegStop> = Vec::new();
    let mut now = 0.0;
    let mut prev_stop = false;
    for (i, l) in legs.iter().enumerate() {
        let start = now;
        now += l.duration_s;
        if l.kind != LegKind::Stop {
            prev_stop = false;
            continue;
        }
        match out.last_mut() {
            Some(g) if prev_stop && (g.depth_m - l.start_depth_m).abs() <= 1e-9 => {
                g.end_s = now;
                g.duration_s += l.duration_s;
                g.gas = l.gas;
            }
            _ => out.push(LegStop {
                depth_m: l.start_depth_m,
                start_s: start,
                end_s: now,
                duration_s: l.duration_s,
                gas: l.gas,
                first_leg: i,
            }),
        }
        prev_stop = true;
    }
    out
}

/// Row `i` of a stop table against the legs' stops ([`Schedule::from_toml_str`] gives the
/// rule). `Err((field, message))`.
fn check_stop_row(
    row: &Stop,
    i: usize,
    leg_stops: &[LegStop],
) -> Result<(), (&'static str, String)> {
    use crate::error::num;
    let Some(g) = leg_stops.get(i) else {
        let depths: Vec<String> = leg_stops.iter().map(|g| num(g.depth_m)).collect();
        return Err((
            "depth_m",
            format!(
                "the stop table lists {} m, but the legs have no stop for it ({}); every row must be a run of `stop` legs",
                num(row.depth_m),
                if depths.is_empty() {
                    "they have no stop legs".to_string()
                } else {
                    format!("their stops are at {} m", depths.join(", "))
                }
            ),
        ));
    };
    let leg = g.first_leg + 1;
    if (row.depth_m - g.depth_m).abs() > STOP_TABLE_TOLERANCE_M {
        return Err((
            "depth_m",
            format!(
                "{} m, but the legs' stop {} is at {} m (leg {leg}); the table must list the legs' stops in order (within {STOP_TABLE_TOLERANCE_M} m)",
                num(row.depth_m),
                i + 1,
                num(g.depth_m)
            ),
        ));
    }
    if row.gas != g.gas {
        return Err((
            "gas",
            format!(
                "{}, but leg {leg} (the stop at {} m) breathes {}",
                gas_text(row.gas),
                num(g.depth_m),
                gas_text(g.gas)
            ),
        ));
    }
    let end_min = g.end_s / 60.0;
    if (row.runtime_min - end_min).abs() > STOP_TABLE_TOLERANCE_MIN {
        return Err((
            "runtime_min",
            format!(
                "runtime {} min, but the legs leave the stop at {} m at {} min (within {STOP_TABLE_TOLERANCE_MIN} min)",
                num(row.runtime_min),
                num(g.depth_m),
                num(end_min)
            ),
        ));
    }
    let legs_min = g.duration_s / 60.0;
    let since_min = match i {
        0 => end_min - g.start_s / 60.0,
        _ => end_min - leg_stops[i - 1].end_s / 60.0,
    };
    let (lo, hi) = (
        legs_min - STOP_TABLE_TOLERANCE_MIN,
        since_min + 1.0 + STOP_TABLE_TOLERANCE_MIN,
    );
    if !(row.stop_min >= lo && row.stop_min <= hi) {
        let since = if i == 0 {
            "arriving".to_string()
        } else {
            format!("leaving the stop at {} m", num(leg_stops[i - 1].depth_m))
        };
        return Err((
            "stop_min",
            format!(
                "{} min at {} m, but the legs stay {} min (leg {leg}), {} min after {since}: a stop's minutes lie between its legs' and that time plus one minute of rounding ({}..{} min)",
                num(row.stop_min),
                num(g.depth_m),
                num(legs_min),
                num(since_min),
                num(lo.max(0.0)),
                num(hi)
            ),
        ));
    }
    Ok(())
}

impl Schedule {
    /// Write as TOML (the `plan --out` format) with an optional summary.
    pub fn to_toml_string(&self, summary: Option<&ScheduleSummary>) -> String {
        let raw = RawSchedule {
            label: self.label.clone(),
            surface_pressure_pa: self.surface_pressure_pa,
            pa_per_m: self.pa_per_m,
            water_vapour_pa: self.water_vapour_pa,
            summary: summary.cloned(),
            legs: self
                .legs
                .iter()
                .map(|l| RawLeg {
                    kind: l.kind,
                    start_depth_m: l.start_depth_m,
                    end_depth_m: l.end_depth_m,
                    duration_s: l.duration_s,
                    gas: gas_text(l.gas),
                })
                .collect(),
            stops: self
                .stops
                .iter()
                .map(|s| RawStop {
                    depth_m: s.depth_m,
                    stop_min: s.stop_min,
                    runtime_min: s.runtime_min,
                    gas: gas_text(s.gas),
                })
                .collect(),
        };
        let body =
            toml::to_string(&raw).unwrap_or_else(|e| format!("# serialisation failed: {e}\n"));
        format!(
            "# decophantom schedule: legs from the surface back to the surface.\n\
             # Depths in m, durations in s, pressures in Pa; read back with any command.\n{body}"
        )
    }

    /// Read a schedule TOML (as written by [`Schedule::to_toml_string`]). `path` is used in
    /// error messages. Checks: at least one leg, the first starting at the surface (the phantom
    /// starts saturated there; a first leg below it would be an instant compression), legs
    /// continuous in depth, depths ≥ 0, durations ≥ 0, stops/bottoms at constant depth, a
    /// `descent` going down and an `ascent` going up, every change of depth at a rate within
    /// [`super::conventions::MIN_TRAVEL_RATE_M_MIN`] ..=
    /// [`super::conventions::MAX_TRAVEL_RATE_M_MIN`] (0.0231–100 m/min, the documented range
    /// of descent and ascent rates; a leg that changes depth in no time is refused), and the
    /// last leg ends at the surface. A leg of zero duration and no change of depth (a gas
    /// switch) is accepted whatever its kind.
    ///
    /// The `[[stops]]` table is what reports print as the stop table, so it is checked against
    /// the legs, never taken on trust: a stop of the legs is a run of consecutive `stop` legs at
    /// one depth, and the table must list each, in order, one row per stop, with its depth
    /// within [`STOP_TABLE_TOLERANCE_M`], its gas the gas of the stop's (last) leg, its
    /// runtime (when leaving) within [`STOP_TABLE_TOLERANCE_MIN`] of the legs', and its
    /// minutes no shorter than the stop's legs (less [`STOP_TABLE_TOLERANCE_MIN`]) and no
    /// longer than the time since the previous stop was left (since arriving, for the first)
    /// plus one minute and [`STOP_TABLE_TOLERANCE_MIN`]: the planners' rounding conventions
    /// count the travel from the previous stop into a stop's minutes (whole minutes of
    /// runtime) and round the first stop up to a whole minute (VPM-B), and nothing else. A
    /// mismatch is refused naming the row's line and field. A file without `[[stops]]` gets
    /// the table derived from the legs (minutes = the stop's legs, as for CSV waypoints).
    pub fn from_toml_str(text: &str, path: &Path) -> Result<Schedule, InputError> {
        Self::from_toml_str_unlined(text, path).map_err(|e| crate::error::ensure_line(e, text))
    }

    fn from_toml_str_unlined(text: &str, path: &Path) -> Result<Schedule, InputError> {
        let raw: RawSchedule =
            toml::from_str(text).map_err(|e| toml_error_with_path(path, text, &e))?;
        let at_key = |key: &str, msg: String| {
            let mut e = InputError::new(msg).in_file(path).field(key);
            if let Some(l) = line_of_key(text, key) {
                e = e.at_line(l);
            }
            e
        };
        // every pressure in Pa, within the ranges of an algorithm file's conventions: a value
        // in kPa or bar (an "odd units" export) is refused at its own field, never run
        use super::conventions::{
            within, MAX_WATER_VAPOUR_PA, PA_PER_M_RANGE, SURFACE_PRESSURE_RANGE_PA,
        };
        if !within(raw.surface_pressure_pa, SURFACE_PRESSURE_RANGE_PA) {
            return Err(at_key(
                "surface_pressure_pa",
                format!(
                    "surface pressure {} Pa is outside {}..{} Pa (500–1100 hPa, about 5600 m of altitude to sea level); give it in Pa (101325, not 101.325 kPa or 1.01325 bar)",
                    crate::error::num(raw.surface_pressure_pa),
                    SURFACE_PRESSURE_RANGE_PA.0,
                    SURFACE_PRESSURE_RANGE_PA.1
                ),
            ));
        }
        if !within(raw.pa_per_m, PA_PER_M_RANGE) {
            return Err(at_key(
                "pa_per_m",
                format!(
                    "pressure per metre {} Pa/m is outside {}..{} Pa/m (fresh to sea water); give it in Pa per metre (9985, not 9.985 kPa/m)",
                    crate::error::num(raw.pa_per_m),
                    PA_PER_M_RANGE.0,
                    PA_PER_M_RANGE.1
                ),
            ));
        }
        if !(raw.water_vapour_pa.is_finite()
            && raw.water_vapour_pa >= 0.0
            && raw.water_vapour_pa <= MAX_WATER_VAPOUR_PA)
        {
            return Err(at_key(
                "water_vapour_pa",
                format!(
                    "water vapour {} Pa is outside 0..{MAX_WATER_VAPOUR_PA} Pa (6270 Pa at 37 °C); give it in Pa",
                    crate::error::num(raw.water_vapour_pa)
                ),
            ));
        }
        if let Some(sum) = &raw.summary {
            // informational, but read: every number must be a real one in its range
            let max_min = crate::profile::MAX_DURATION_S / 60.0;
            for (key, v, hi) in [
                ("runtime_min", sum.runtime_min, max_min),
                ("cns_percent", sum.cns_percent, f64::MAX),
                ("otu", sum.otu, f64::MAX),
            ] {
                if let Some(v) = v {
                    if !(v.is_finite() && v >= 0.0 && v <= hi) {
                        let range = if hi < f64::MAX {
                            format!("a number from 0 to {hi}")
                        } else {
                            "a finite number, zero or more".into()
                        };
                        let mut e =
                            InputError::new(format!("{} must be {range}", crate::error::num(v)))
                                .in_file(path)
                                .field(format!("summary.{key}"));
                        if let Some(l) = line_in_table(text, "summary", key) {
                            e = e.at_line(l);
                        }
                        return Err(e);
                    }
                }
            }
        }
        if raw.legs.is_empty() {
            return Err(
                InputError::new("a schedule needs at least one [[legs]] entry")
                    .in_file(path)
                    .field("legs"),
            );
        }
        let mut legs = Vec::with_capacity(raw.legs.len());
        let mut total_s = 0.0;
        for (i, l) in raw.legs.iter().enumerate() {
            let err = |field: &str, msg: String| {
                let mut e = InputError::new(format!("leg {}: {msg}", i + 1))
                    .in_file(path)
                    .field(format!("legs.{field}"));
                if let Some(line) = line_of_nth(text, "[[legs]]", i) {
                    e = e.at_line(line);
                }
                e
            };
            let gas = GasMix::parse(&l.gas).map_err(|m| err("gas", m))?;
            for (f, v) in [
                ("start_depth_m", l.start_depth_m),
                ("end_depth_m", l.end_depth_m),
            ] {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(err(f, format!("depth {v} m must be zero or positive")));
                }
                if v > MAX_PLAN_DEPTH_M {
                    return Err(err(
                        f,
                        format!(
                            "depth {} m is beyond the accepted {MAX_PLAN_DEPTH_M} m",
                            crate::error::num(v)
                        ),
                    ));
                }
                let p = raw.surface_pressure_pa + v * raw.pa_per_m;
                if p > crate::profile::MAX_AMBIENT_PA {
                    return Err(err(
                        f,
                        format!(
                            "depth {v} m is {} Pa with surface_pressure_pa and pa_per_m; the accepted range ends at {:e} Pa (200 bar)",
                            crate::error::num(p),
                            crate::profile::MAX_AMBIENT_PA
                        ),
                    ));
                }
            }
            if !(l.duration_s.is_finite() && l.duration_s >= 0.0) {
                return Err(err(
                    "duration_s",
                    format!("duration {} s must be zero or positive", l.duration_s),
                ));
            }
            if l.duration_s > 0.0 && total_s + l.duration_s == total_s {
                return Err(err(
                    "duration_s",
                    format!(
                        "duration {} s is too short to count after {total_s} s; give 0 or a longer leg",
                        crate::error::num(l.duration_s)
                    ),
                ));
            }
            total_s += l.duration_s;
            if total_s > crate::profile::MAX_DURATION_S {
                return Err(err("duration_s", crate::profile::duration_message(total_s)));
            }
            if let Some(prev) = legs.last().map(|p: &Leg| p.end_depth_m) {
                if (prev - l.start_depth_m).abs() > 1e-6 {
                    return Err(err(
                        "start_depth_m",
                        format!(
                            "starts at {} m but the previous leg ends at {prev} m",
                            l.start_depth_m
                        ),
                    ));
                }
            }
            if legs.is_empty() && l.start_depth_m.abs() > 1e-9 {
                return Err(err(
                    "start_depth_m",
                    format!(
                        "the schedule starts at {} m: legs run from the surface (0 m), where the phantom starts saturated, and a first leg below it would be an instant compression; add the descent from 0 m",
                        crate::error::num(l.start_depth_m)
                    ),
                ));
            }
            let constant = matches!(l.kind, LegKind::Stop | LegKind::Bottom);
            if constant && (l.start_depth_m - l.end_depth_m).abs() > 1e-9 {
                return Err(err(
                    "end_depth_m",
                    "a stop or bottom leg must stay at one depth".into(),
                ));
            }
            check_travel(l).map_err(|(f, m)| err(f, m))?;
            legs.push(Leg {
                kind: l.kind,
                start_depth_m: l.start_depth_m,
                end_depth_m: l.end_depth_m,
                duration_s: l.duration_s,
                gas,
            });
        }
        let last = legs.last().map_or(0.0, |l| l.end_depth_m);
        if last.abs() > 1e-9 {
            return Err(InputError::new(format!(
                "the schedule never surfaces: its last leg ends at {last} m; add an ascent to 0 m"
            ))
            .in_file(path)
            .field("legs.end_depth_m")
            .at_line(
                line_of_nth(text, "[[legs]]", legs.len() - 1)
                    .unwrap_or_else(|| crate::error::last_line(text)),
            ));
        }
        let leg_stops = stops_of_legs(&legs);
        let mut stops = Vec::with_capacity(raw.stops.len());
        for (i, s) in raw.stops.iter().enumerate() {
            let stop_err = |field: &str, m: String| {
                let mut e = InputError::new(format!("stop {}: {m}", i + 1))
                    .in_file(path)
                    .field(format!("stops.{field}"));
                if let Some(line) = line_of_nth(text, "[[stops]]", i) {
                    e = e.at_line(line);
                }
                e
            };
            let gas = GasMix::parse(&s.gas).map_err(|m| stop_err("gas", m))?;
            // the stop table is printed and reported as it is: every number must be a real one
            let max_min = crate::profile::MAX_DURATION_S / 60.0;
            for (f, v, hi, unit) in [
                ("depth_m", s.depth_m, MAX_PLAN_DEPTH_M, "m"),
                ("stop_min", s.stop_min, max_min, "min"),
                ("runtime_min", s.runtime_min, max_min, "min"),
            ] {
                if !(v.is_finite() && v >= 0.0 && v <= hi) {
                    return Err(stop_err(
                        f,
                        format!(
                            "{} {unit} must be a number between 0 and {hi} {unit}",
                            crate::error::num(v)
                        ),
                    ));
                }
            }
            let row = Stop {
                depth_m: s.depth_m,
                stop_min: s.stop_min,
                runtime_min: s.runtime_min,
                gas,
            };
            check_stop_row(&row, i, &leg_stops).map_err(|(f, m)| {
                let mut e = stop_err(f, m);
                if let Some(line) = line_of_nth_key(text, "[[stops]]", i, f) {
                    e = e.at_line(line);
                }
                e
            })?;
            stops.push(row);
        }
        if raw.stops.is_empty() {
            stops = leg_stops
                .iter()
                .map(|g| Stop {
                    depth_m: g.depth_m,
                    stop_min: g.duration_s / 60.0,
                    runtime_min: g.end_s / 60.0,
                    gas: g.gas,
                })
                .collect();
        } else if let Some(g) = leg_stops.get(raw.stops.len()) {
            return Err(InputError::new(format!(
                "leg {} is a stop at {} m (runtime {} min) that the stop table does not list ({} row(s) for {} stops); add its [[stops]] row, or leave out [[stops]] to have the table derived from the legs",
                g.first_leg + 1,
                crate::error::num(g.depth_m),
                crate::error::num(g.end_s / 60.0),
                raw.stops.len(),
                leg_stops.len()
            ))
            .in_file(path)
            .field("stops")
            .at_line(
                line_of_nth(text, "[[legs]]", g.first_leg)
                    .unwrap_or_else(|| crate::error::last_line(text)),
            ));
        }
        Ok(Schedule {
            label: raw.label,
            surface_pressure_pa: raw.surface_pressure_pa,
            pa_per_m: raw.pa_per_m,
            water_vapour_pa: raw.water_vapour_pa,
            legs,
            stops,
        })
    }

    /// Read a schedule TOML file.
    pub fn read(path: &Path) -> Result<Schedule, InputError> {
        let text = crate::error::read_text(path, "the schedule")?;
        Schedule::from_toml_str(&text, path)
    }

    /// The gas switches: every change of gas between consecutive legs of positive duration.
    pub fn gas_switches(&self) -> Vec<GasSwitch> {
        let mut out = Vec::new();
        let mut now = 0.0;
        let mut prev: Option<GasMix> = None;
        for l in &self.legs {
            if let Some(p) = prev {
                if p != l.gas {
                    out.push(GasSwitch {
                        runtime_min: now / 60.0,
                        depth_m: l.start_depth_m,
                        gas: l.gas,
                    });
                }
            }
            prev = Some(l.gas);
            now += l.duration_s;
        }
        out
    }

    /// Total time at the stops, min (0 without stops: a positive zero, never the −0.0 of an
    /// empty `f64` sum).
    pub fn stop_time_min(&self) -> f64 {
        self.stops.iter().fold(0.0, |acc, s| acc + s.stop_min)
    }

    /// Total runtime, min.
    pub fn runtime_min(&self) -> f64 {
        self.legs.iter().map(|l| l.duration_s).sum::<f64>() / 60.0
    }

    /// Ambient pressure at a depth, Pa.
    pub fn pressure_at(&self, depth_m: f64) -> f64 {
        self.surface_pressure_pa + depth_m * self.pa_per_m
    }

    /// The pressure history the phantom takes: one breakpoint per leg end, the leg's gas on
    /// each segment, the schedule's water vapour subtracted at the open faces. Zero-length legs
    /// (gas switches) are merged into the next leg. The phantom starts saturated with air at
    /// the surface pressure ([`crate::profile::Saturation`]), as a diver's tissues and every
    /// planner's do, whatever the first leg breathes.
    pub fn to_pressure_history(&self) -> Result<PressureHistory, String> {
        let mut t = vec![0.0];
        let mut p = vec![self.pressure_at(self.legs.first().map_or(0.0, |l| l.start_depth_m))];
        let mut g = Vec::new();
        let mut now = 0.0;
        for leg in &self.legs {
            if leg.duration_s <= 0.0 {
                continue;
            }
            now += leg.duration_s;
            t.push(now);
            p.push(self.pressure_at(leg.end_depth_m));
            g.push(leg.gas);
        }
        if g.is_empty() {
            return Err(format!(
                "schedule '{}' has no legs of positive duration",
                self.label
            ));
        }
        let mut h = PressureHistory::new(self.label.clone(), t, p, g, self.water_vapour_pa)?;
        h.saturation = crate::profile::Saturation {
            gas: GasMix::AIR,
            ambient_pa: self.surface_pressure_pa,
        };
        Ok(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 30 m for 20 min on air, up at 9 m/min to a 5-min EAN50 stop at 3 m (left at 30.0 min),
    /// then 3 m in 20 s to the surface: the legs as lines 6–39, the stop table from line 41.
    const TEXT: &str = r#"label = "t"
surface_pressure_pa = 101325.0
pa_per_m = 9985.0
water_vapour_pa = 6270.0

[[legs]]
kind = "descent"
start_depth_m = 0.0
end_depth_m = 30.0
duration_s = 120.0
gas = "air"

[[legs]]
kind = "bottom"
start_depth_m = 30.0
end_depth_m = 30.0
duration_s = 1200.0
gas = "air"

[[legs]]
kind = "ascent"
start_depth_m = 30.0
end_depth_m = 3.0
duration_s = 180.0
gas = "air"

[[legs]]
kind = "stop"
start_depth_m = 3.0
end_depth_m = 3.0
duration_s = 300.0
gas = "EAN50"

[[legs]]
kind = "ascent"
start_depth_m = 3.0
end_depth_m = 0.0
duration_s = 20.0
gas = "EAN50"

[[stops]]
depth_m = 3.0
stop_min = 5.0
runtime_min = 30.0
gas = "EAN50"
"#;

    fn read(text: &str) -> Result<Schedule, InputError> {
        Schedule::from_toml_str(text, Path::new("s7.toml"))
    }

    /// `text` with the `n`-th (1-based) occurrence of `from` replaced by `to`.
    fn edit(text: &str, n: usize, from: &str, to: &str) -> String {
        let at = text.match_indices(from).nth(n - 1).unwrap().0;
        format!("{}{to}{}", &text[..at], &text[at + from.len()..])
    }

    fn refused(text: &str) -> (Option<usize>, String, String) {
        let e = read(text).unwrap_err();
        assert_eq!(e.file.as_deref(), Some(Path::new("s7.toml")), "{e}");
        (e.line, e.field.clone().unwrap_or_default(), e.to_string())
    }

    #[test]
    fn a_stop_table_that_agrees_with_the_legs_is_read() {
        let s = read(TEXT).unwrap();
        assert_eq!(s.stops.len(), 1);
        assert_eq!(s.stop_time_min(), 5.0);
        // minutes rounded up to the whole minute (the first stop) and a runtime printed to
        // 0.1 min pass; so does a depth printed to 0.1 m
        read(&edit(TEXT, 1, "stop_min = 5.0", "stop_min = 6.0")).unwrap();
        read(&edit(TEXT, 1, "runtime_min = 30.0", "runtime_min = 30.04")).unwrap();
        read(&edit(
            TEXT,
            1,
            "depth_m = 3.0\nstop_min",
            "depth_m = 3.04\nstop_min",
        ))
        .unwrap();
    }

    /// Defect A: a stop of 50 min over a 5-min leg was reported as it was, with the simulation
    /// on the legs.
    #[test]
    fn a_stop_table_that_contradicts_the_legs_is_refused_at_its_line_and_field() {
        let (line, field, msg) = refused(&edit(TEXT, 1, "stop_min = 5.0", "stop_min = 50.0"));
        assert_eq!(
            (line, field.as_str()),
            (Some(43), "stops.stop_min"),
            "{msg}"
        );
        assert!(
            msg.starts_with("s7.toml:43: field 'stops.stop_min': stop 1: 50 min"),
            "{msg}"
        );
        assert!(msg.contains("legs stay 5 min (leg 4)"), "{msg}");
        // shorter than the leg
        let (line, field, _) = refused(&edit(TEXT, 1, "stop_min = 5.0", "stop_min = 4.9"));
        assert_eq!((line, field.as_str()), (Some(43), "stops.stop_min"));
        let (line, field, msg) = refused(&edit(
            TEXT,
            1,
            "depth_m = 3.0\nstop_min",
            "depth_m = 6.0\nstop_min",
        ));
        assert_eq!((line, field.as_str()), (Some(42), "stops.depth_m"), "{msg}");
        let (line, field, _) = refused(&edit(TEXT, 1, "runtime_min = 30.0", "runtime_min = 30.3"));
        assert_eq!((line, field.as_str()), (Some(44), "stops.runtime_min"));
        let (line, field, msg) = refused(&edit(TEXT, 3, "gas = \"EAN50\"", "gas = \"air\""));
        assert_eq!((line, field.as_str()), (Some(45), "stops.gas"), "{msg}");
        // a row the legs have no stop for: named with the stops the legs have
        let extra = format!("{TEXT}\n[[stops]]\ndepth_m = 6.0\nstop_min = 1.0\nruntime_min = 31.0\ngas = \"EAN50\"\n");
        let (line, field, msg) = refused(&extra);
        assert_eq!((line, field.as_str()), (Some(48), "stops.depth_m"), "{msg}");
        assert!(msg.contains("their stops are at 3 m"), "{msg}");
        // a stop leg without its row: named at the leg
        let two = edit(TEXT, 1, "duration_s = 300.0", "duration_s = 240.0");
        let two = edit(
            &two,
            2,
            "[[legs]]\nkind = \"ascent\"",
            "[[legs]]\nkind = \"ascent\"\nstart_depth_m = 3.0\nend_depth_m = 2.0\nduration_s = 6.0\ngas = \"EAN50\"\n\n[[legs]]\nkind = \"stop\"\nstart_depth_m = 2.0\nend_depth_m = 2.0\nduration_s = 60.0\ngas = \"EAN50\"\n\n[[legs]]\nkind = \"ascent\"",
        )
        .replace("start_depth_m = 3.0\nend_depth_m = 0.0", "start_depth_m = 2.0\nend_depth_m = 0.0")
        .replace("stop_min = 5.0", "stop_min = 4.0")
        .replace("runtime_min = 30.0", "runtime_min = 29.0");
        let (line, field, msg) = refused(&two);
        assert_eq!((line, field.as_str()), (Some(41), "stops"), "{msg}");
        assert!(msg.contains("leg 6 is a stop at 2 m"), "{msg}");
        // with a row for it, the same legs are read; the second stop's minutes may count the
        // travel from the first (whole minutes of runtime: 2 min from 29.0 to 30.1)
        let both = format!("{two}\n[[stops]]\ndepth_m = 2.0\nstop_min = 1.1\nruntime_min = 30.1\ngas = \"EAN50\"\n");
        let s = read(&both).unwrap();
        assert_eq!(s.stops.len(), 2);
    }

    /// Without `[[stops]]` the table is the legs' stops (the report's stop time is never 0 for
    /// a schedule that stops).
    #[test]
    fn an_absent_stop_table_is_derived_from_the_legs() {
        let cut = TEXT.find("[[stops]]").unwrap();
        let s = read(&TEXT[..cut]).unwrap();
        assert_eq!(
            s.stops,
            vec![Stop {
                depth_m: 3.0,
                stop_min: 5.0,
                runtime_min: 30.0,
                gas: GasMix::new(0.5, 0.0).unwrap(),
            }]
        );
    }

    /// Defect B: legs that move in no time, faster than the accepted rates or against their
    /// kind, and a schedule that starts below the surface, are refused at the leg's line.
    #[test]
    fn impossible_movements_are_refused_at_the_legs_line() {
        let ascent = |d: &str| edit(TEXT, 1, "duration_s = 180.0", &format!("duration_s = {d}"));
        for d in ["0.0", "1e-9", "16.1"] {
            let (line, field, msg) = refused(&ascent(d));
            assert_eq!(
                (line, field.as_str()),
                (Some(20), "legs.duration_s"),
                "{msg}"
            );
            assert!(msg.contains("faster than the accepted 100 m/min"), "{msg}");
        }
        // 27 m in 16.2 s is exactly 100 m/min: accepted
        read(&ascent("16.2").replace("runtime_min = 30.0", "runtime_min = 27.27")).unwrap();
        // 27 m in 100 000 s (0.016 m/min) is slower than 0.0231 m/min
        let (line, field, msg) = refused(&ascent("100000.0"));
        assert_eq!(
            (line, field.as_str()),
            (Some(20), "legs.duration_s"),
            "{msg}"
        );
        assert!(msg.contains("slower than"), "{msg}");
        let (line, field, _) = refused(&edit(TEXT, 1, "duration_s = 120.0", "duration_s = 0.0"));
        assert_eq!((line, field.as_str()), (Some(6), "legs.duration_s"));
        // kinds against the direction
        let up = edit(TEXT, 1, "kind = \"descent\"", "kind = \"ascent\"");
        let (line, field, msg) = refused(&up);
        assert_eq!((line, field.as_str()), (Some(6), "legs.kind"), "{msg}");
        assert!(
            msg.contains("kind \"ascent\" but the leg goes down (0 m to 30 m)"),
            "{msg}"
        );
        let down = edit(TEXT, 2, "kind = \"ascent\"", "kind = \"descent\"");
        let (line, field, _) = refused(&down);
        assert_eq!((line, field.as_str()), (Some(34), "legs.kind"));
        // an ascent that stays put for a while; a zero-length one (a gas switch) is accepted
        let flat = edit(TEXT, 1, "kind = \"stop\"", "kind = \"ascent\"");
        let (line, field, _) = refused(&flat);
        assert_eq!((line, field.as_str()), (Some(27), "legs.kind"));
        let switch = edit(
            TEXT,
            1,
            "[[legs]]\nkind = \"stop\"",
            "[[legs]]\nkind = \"ascent\"\nstart_depth_m = 3.0\nend_depth_m = 3.0\nduration_s = 0.0\ngas = \"EAN50\"\n\n[[legs]]\nkind = \"stop\"",
        );
        read(&switch).unwrap();
        // the first leg below the surface: an instant compression at t = 0
        let deep = edit(TEXT, 1, "start_depth_m = 0.0", "start_depth_m = 20.0");
        let (line, field, msg) = refused(&deep);
        assert_eq!(
            (line, field.as_str()),
            (Some(6), "legs.start_depth_m"),
            "{msg}"
        );
        assert!(msg.contains("starts at 20 m"), "{msg}");
    }
}
