//! The TOML profile format that a person writes (see `profiles/README.md` for the reference).
//!
//! Two layers: [`RawProfile`] mirrors the file exactly (`deny_unknown_fields`, so a typo is an
//! error naming the field and its line); [`validate`] turns it into a [`TomlProfile`] whose
//! [`PressureHistory`] is in absolute Pa and seconds.
//!
//! A profile gives its breakpoints either as `points = [[time, pressure], ...]` (piecewise
//! linear) or as a list of `[[leg]]` tables (a change to a pressure at a rate or over a
//! duration, or a hold), optionally repeated (`repeat = n`) and with gas switches.

use std::path::Path;

use ::toml::Spanned;
use serde::Deserialize;

use super::PressureHistory;
use crate::error::{line_of_key, toml_error_with_path, InputError};
use crate::gas::GasMix;
use crate::units::{PressureUnit, TimeUnit, ATM_PA};

/// Names accepted for `pressure_unit`, for error messages.
const PRESSURE_UNITS: &str = "pa, kpa, bar, atm, psi-gauge (psig, psi), psia, msw (m), fsw (ft)";
/// Names accepted for `time_unit`, for error messages.
const TIME_UNITS: &str = "s, min, h";

/// The profile file exactly as written (first layer). Field meanings: `profiles/README.md`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawProfile {
    /// Human-readable name; defaults to the file stem.
    pub name: Option<String>,
    /// Where the profile comes from (paper section, legacy file).
    pub description: Option<String>,
    /// Unit of every time and duration in the file: `s`, `min` or `h`.
    pub time_unit: Spanned<String>,
    /// Unit of every pressure in the file (see [`PressureUnit::parse`]).
    pub pressure_unit: Spanned<String>,
    /// Zero of the gauge and depth units, absolute Pa (default 101 325).
    pub surface_pressure_pa: Option<Spanned<f64>>,
    /// Chamber or breathing gas at time 0 (see [`GasMix::parse`]); default air.
    pub gas: Option<Spanned<String>>,
    /// Water-vapour pressure subtracted at the open faces, Pa (default 0: chamber gas).
    pub water_vapour_pa: Option<Spanned<f64>>,
    /// Breakpoints `[time, pressure]`, piecewise linear (exclusive with `leg`); read as lists
    /// so that a row with a third number is refused, not cut to two.
    pub points: Option<Vec<Spanned<Vec<f64>>>>,
    /// Starting pressure for `leg` profiles, in `pressure_unit` (default: the surface).
    pub start: Option<Spanned<f64>>,
    /// Legs (exclusive with `points`).
    pub leg: Option<Vec<Spanned<RawLeg>>>,
    /// Repeat the whole cycle this many times (its first and last pressures must be equal).
    pub repeat: Option<Spanned<i64>>,
    /// Gas switches at given times.
    pub switch: Option<Vec<Spanned<RawSwitch>>>,
}

/// One `[[leg]]` table: a linear change to `to` at `rate` or over `duration`, or a hold of
/// `duration` when `to` is absent.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLeg {
    /// Pressure at the end of the leg, in `pressure_unit` (absent: hold).
    pub to: Option<f64>,
    /// Rate of pressure change, a positive magnitude, in `rate_unit`.
    pub rate: Option<f64>,
    /// Unit of `rate`, `<pressure unit>/<time unit>` such as `psi/s`, `pa/s`, `msw/min`
    /// (default: `pressure_unit/time_unit`).
    pub rate_unit: Option<String>,
    /// Duration of the leg, in `time_unit`.
    pub duration: Option<f64>,
    /// Gas switched to at the start of this leg.
    pub gas: Option<String>,
}

/// One `[[switch]]` table: from `time` on, `gas` is in force.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSwitch {
    /// Time of the switch, in `time_unit`.
    pub time: f64,
    /// The new gas (see [`GasMix::parse`]).
    pub gas: String,
}

/// A validated TOML profile.
#[derive(Debug, Clone, PartialEq)]
pub struct TomlProfile {
    /// Name (the `name` field or the file stem).
    pub name: String,
    /// The `description` field (empty if absent).
    pub description: String,
    /// The pressure history, absolute Pa and s; its label is `name`.
    pub history: PressureHistory,
}

/// Read and validate a TOML profile file.
pub fn read(path: &Path) -> Result<TomlProfile, InputError> {
    let text = crate::error::read_text(path, "the profile")?;
    parse(&text, path)
}

/// Parse and validate TOML profile text; `path` is used in error messages and for the default name.
pub fn parse(text: &str, path: &Path) -> Result<TomlProfile, InputError> {
    let raw: RawProfile =
        ::toml::from_str(text).map_err(|e| toml_error_with_path(path, text, &e))?;
    validate(raw, text, path).map_err(|e| crate::error::ensure_line(e, text))
}

/// 1-based line of a byte offset in `text`.
fn line_at(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// Error helper bound to one file.
struct Ctx<'a> {
    text: &'a str,
    path: &'a Path,
}

impl Ctx<'_> {
    fn err(&self, offset: usize, field: &str, msg: impl Into<String>) -> InputError {
        InputError::new(msg)
            .in_file(self.path)
            .at_line(line_at(self.text, offset))
            .field(field)
    }
    fn err_key(&self, key: &str, msg: impl Into<String>) -> InputError {
        let mut e = InputError::new(msg).in_file(self.path).field(key);
        if let Some(l) = line_of_key(self.text, key) {
            e = e.at_line(l);
        }
        e
    }
}

/// Scale of a pressure unit for differences (rates), Pa per unit.
fn pressure_scale(u: PressureUnit) -> f64 {
    u.to_absolute_pa(1.0, 0.0) - u.to_absolute_pa(0.0, 0.0)
}

/// Parse a rate unit `<pressure>/<time>` into Pa/s per unit.
pub fn parse_rate_unit(s: &str) -> Option<f64> {
    let (p, t) = s.split_once('/')?;
    Some(pressure_scale(PressureUnit::parse(p)?) / TimeUnit::parse(t)?.seconds())
}

/// Second layer: check the raw profile and build the history.
pub fn validate(raw: RawProfile, text: &str, path: &Path) -> Result<TomlProfile, InputError> {
    let cx = Ctx { text, path };
    let tu = TimeUnit::parse(raw.time_unit.get_ref()).ok_or_else(|| {
        cx.err(
            raw.time_unit.span().start,
            "time_unit",
            format!(
                "unknown time unit '{}'; write one of {TIME_UNITS}",
                raw.time_unit.get_ref()
            ),
        )
    })?;
    let pu = PressureUnit::parse(raw.pressure_unit.get_ref()).ok_or_else(|| {
        cx.err(
            raw.pressure_unit.span().start,
            "pressure_unit",
            format!(
                "unknown pressure unit '{}'; write one of {PRESSURE_UNITS}",
                raw.pressure_unit.get_ref()
            ),
        )
    })?;
    let surface = match &raw.surface_pressure_pa {
        Some(s) => {
            let v = *s.get_ref();
            if !(v.is_finite() && v > 0.0) {
                return Err(cx.err(
                    s.span().start,
                    "surface_pressure_pa",
                    format!("surface pressure {v} Pa must be positive (sea level is 101325)"),
                ));
            }
            if !(super::MIN_AMBIENT_PA..=super::MAX_AMBIENT_PA).contains(&v) {
                return Err(cx.err(
                    s.span().start,
                    "surface_pressure_pa",
                    format!(
                        "surface pressure {} Pa is outside the accepted {} ..= {} Pa (sea level is 101325 Pa; is it in kPa or bar?)",
                        crate::error::num(v),
                        crate::error::num(super::MIN_AMBIENT_PA),
                        crate::error::num(super::MAX_AMBIENT_PA)
                    ),
                ));
            }
            v
        }
        None => ATM_PA,
    };
    let gas0 = match &raw.gas {
        Some(g) => GasMix::parse(g.get_ref()).map_err(|e| cx.err(g.span().start, "gas", e))?,
        None => GasMix::AIR,
    };
    let vapour = match &raw.water_vapour_pa {
        Some(v) => {
            let x = *v.get_ref();
            if !(0.0..1e5).contains(&x) {
                return Err(cx.err(
                    v.span().start,
                    "water_vapour_pa",
                    format!("water-vapour pressure {x} Pa must be in 0..100000 (0 for chamber gas, about 6270 for alveolar gas at 37 °C)"),
                ));
            }
            x
        }
        None => 0.0,
    };
    let sec = tu.seconds();
    let to_pa = |v: f64| pu.to_absolute_pa(v, surface);

    // Breakpoints (s, Pa), each with the byte offset it came from, and gas changes from legs.
    let mut pts: Vec<(f64, f64, usize)> = Vec::new();
    let mut switches: Vec<(f64, GasMix, usize)> = Vec::new();
    let pts_field;
    match (&raw.points, &raw.leg) {
        (Some(_), Some(_)) => {
            return Err(cx.err_key(
                "points",
                "a profile gives either `points` or `[[leg]]` tables, not both; delete one",
            ))
        }
        (None, None) => return Err(InputError::new(
            "the profile has no breakpoints; add `points = [[0, 0], [60, 10]]` or `[[leg]]` tables",
        )
        .in_file(path)
        .field("points")),
        (Some(points), None) => {
            pts_field = "points";
            if raw.start.is_some() {
                return Err(cx.err_key(
                    "start",
                    "`start` is for `[[leg]]` profiles; with `points` the first point is the start",
                ));
            }
            if points.is_empty() {
                return Err(cx.err_key(
                    "points",
                    "`points` is empty; give at least one [time, pressure] pair",
                ));
            }
            for p in points {
                let off = p.span().start;
                let &[t, v] = p.get_ref().as_slice() else {
                    return Err(cx.err(
                        off,
                        "points",
                        format!(
                            "a point has {} number(s); expected 2 numbers [time, pressure]",
                            p.get_ref().len()
                        ),
                    ));
                };
                if !t.is_finite() || !v.is_finite() {
                    return Err(cx.err(
                        off,
                        "points",
                        format!("point [{t}, {v}] is not a finite number pair"),
                    ));
                }
                pts.push((t * sec, to_pa(v), off));
            }
        }
        (None, Some(legs)) => {
            pts_field = "leg";
            let (p0, off0) = match &raw.start {
                Some(s) => (to_pa(*s.get_ref()), s.span().start),
                None => (surface, legs.first().map(|l| l.span().start).unwrap_or(0)),
            };
            if !p0.is_finite() {
                return Err(cx.err(off0, "start", "`start` must be a finite number"));
            }
            pts.push((0.0, p0, off0));
            if legs.is_empty() {
                return Err(cx.err_key("leg", "no `[[leg]]` tables; add at least one"));
            }
            for (i, l) in legs.iter().enumerate() {
                let off = l.span().start;
                let leg = l.get_ref();
                let (t_prev, p_prev, _) = *pts.last().unwrap();
                let n = i + 1;
                if let Some(g) = &leg.gas {
                    let mix = GasMix::parse(g)
                        .map_err(|e| cx.err(off, "leg.gas", format!("leg {n}: {e}")))?;
                    switches.push((t_prev, mix, off));
                }
                let p_end = match leg.to {
                    Some(v) if v.is_finite() => to_pa(v),
                    Some(v) => {
                        return Err(cx.err(
                            off,
                            "leg.to",
                            format!("leg {n}: `to = {v}` is not finite"),
                        ))
                    }
                    None => p_prev,
                };
                let dt = match (leg.duration, leg.rate) {
                    (Some(_), Some(_)) => {
                        return Err(cx.err(
                            off,
                            "leg.rate",
                            format!("leg {n} gives both `rate` and `duration`; keep one"),
                        ))
                    }
                    (Some(d), None) => {
                        if leg.rate_unit.is_some() {
                            return Err(cx.err(
                                off,
                                "leg.rate_unit",
                                format!("leg {n}: `rate_unit` without `rate`; delete it"),
                            ));
                        }
                        if !(d.is_finite() && d > 0.0) {
                            return Err(cx.err(
                                off,
                                "leg.duration",
                                format!("leg {n}: duration {d} must be positive"),
                            ));
                        }
                        d * sec
                    }
                    (None, Some(r)) => {
                        if leg.to.is_none() {
                            return Err(cx.err(
                                off,
                                "leg.rate",
                                format!(
                                    "leg {n} has a `rate` but no `to`; a hold takes `duration`"
                                ),
                            ));
                        }
                        let scale = match &leg.rate_unit {
                            Some(u) => parse_rate_unit(u).ok_or_else(|| {
                                cx.err(
                                    off,
                                    "leg.rate_unit",
                                    format!("leg {n}: cannot read rate unit '{u}'; write <pressure unit>/<time unit>, e.g. psi/s, pa/s, msw/min"),
                                )
                            })?,
                            None => pressure_scale(pu) / sec,
                        };
                        if !(r.is_finite() && r > 0.0) {
                            return Err(cx.err(
                                off,
                                "leg.rate",
                                format!("leg {n}: rate {r} must be a positive magnitude (the direction follows from `to`)"),
                            ));
                        }
                        let dp = (p_end - p_prev).abs();
                        if dp == 0.0 {
                            return Err(cx.err(
                                off,
                                "leg.to",
                                format!("leg {n} goes nowhere (`to` equals the current pressure); use `duration` for a hold"),
                            ));
                        }
                        dp / (r * scale)
                    }
                    (None, None) => {
                        return Err(cx.err(
                            off,
                            "leg.duration",
                            format!("leg {n} needs a `rate` or a `duration`"),
                        ))
                    }
                };
                pts.push((t_prev + dt, p_end, off));
            }
        }
    }

    // Times: start at 0, never negative, strictly increasing; pressures positive.
    let pressure_field = pts_field;
    for (k, &(t, p, off)) in pts.iter().enumerate() {
        if t < 0.0 {
            return Err(cx.err(
                off,
                pts_field,
                format!(
                    "point {} has a negative time ({} {}); times start at 0",
                    k + 1,
                    t / sec,
                    raw.time_unit.get_ref()
                ),
            ));
        }
        if k == 0 && t != 0.0 {
            return Err(cx.err(
                off,
                pts_field,
                format!("the first point is at {} {}; a profile starts at time 0, add [0, pressure] first", t / sec, raw.time_unit.get_ref()),
            ));
        }
        if k > 0 && t <= pts[k - 1].0 {
            return Err(cx.err(
                off,
                pts_field,
                format!(
                    "point {} (time {} {}) is not after point {} (time {} {}); times must increase strictly: fix the order or remove the duplicate",
                    k + 1,
                    t / sec,
                    raw.time_unit.get_ref(),
                    k,
                    pts[k - 1].0 / sec,
                    raw.time_unit.get_ref()
                ),
            ));
        }
        if p <= 0.0 || p.is_nan() {
            return Err(cx.err(
                off,
                pressure_field,
                format!(
                    "point {} is {p} Pa absolute (surface {surface} Pa, unit {}); absolute pressure must be positive: check the unit or the sign",
                    k + 1,
                    raw.pressure_unit.get_ref()
                ),
            ));
        }
        if p < super::MIN_AMBIENT_PA {
            return Err(cx.err(
                off,
                pressure_field,
                format!("point {}: {}", k + 1, super::below_minimum_message(p)),
            ));
        }
    }
    // the water vapour is taken out of the ambient pressure at the faces: it must stay below
    // the lowest ambient pressure, or no gas would be left there
    if let (Some(v), Some(&(t, p, _))) = (&raw.water_vapour_pa, pts.iter().find(|q| q.1 <= vapour))
    {
        return Err(cx.err(
            v.span().start,
            "water_vapour_pa",
            super::vapour_above_ambient_message(vapour, p, t),
        ));
    }

    // One rule for every reader: at least two points, and no longer than the duration limit.
    if pts.len() < 2 {
        return Err(cx.err(
            pts[0].2,
            pts_field,
            "the profile has a single point, so nothing to simulate; give at least two points (a start and an end)",
        ));
    }
    if let Some(&(end, _, off)) = pts.last() {
        if end > super::MAX_DURATION_S {
            return Err(cx.err(off, pts_field, super::duration_message(end)));
        }
    }
    if let Some(&(_, p, off)) = pts.iter().find(|q| q.1 > super::MAX_AMBIENT_PA) {
        return Err(cx.err(
            off,
            pts_field,
            format!(
                "{p:e} Pa absolute is above the accepted {:e} Pa (200 bar, about 2 000 m of sea water)",
                super::MAX_AMBIENT_PA
            ),
        ));
    }

    // Repeat the cycle.
    if let Some(r) = &raw.repeat {
        let n = *r.get_ref();
        if n < 1 {
            return Err(cx.err(
                r.span().start,
                "repeat",
                format!("repeat = {n}; write a whole number of cycles ≥ 1"),
            ));
        }
        let (first, last) = (pts[0].1, pts[pts.len() - 1].1);
        if pts.len() < 2 {
            return Err(cx.err(
                r.span().start,
                "repeat",
                "a single point cannot be repeated; give the whole cycle",
            ));
        }
        if (first - last).abs() > 1e-9 * first.abs().max(1.0) {
            return Err(cx.err(
                r.span().start,
                "repeat",
                format!("the cycle starts at {first} Pa and ends at {last} Pa; a repeated cycle must end at the pressure it starts at"),
            ));
        }
        let period = pts[pts.len() - 1].0;
        // check the size before building anything: a billion cycles must not be materialised
        let total_s = period * n as f64;
        if total_s > super::MAX_DURATION_S {
            return Err(cx.err(
                r.span().start,
                "repeat",
                format!("repeat = {n}: {}", super::duration_message(total_s)),
            ));
        }
        let total_points = (pts.len() - 1) as f64 * n as f64 + 1.0;
        if total_points > super::MAX_BREAKPOINTS as f64 {
            return Err(cx.err(
                r.span().start,
                "repeat",
                format!(
                    "repeat = {n} gives {total_points:.3e} breakpoints; the limit is {}",
                    super::MAX_BREAKPOINTS
                ),
            ));
        }
        let cycle: Vec<_> = pts[1..].to_vec();
        for k in 1..n as usize {
            for &(t, p, off) in &cycle {
                pts.push((t + k as f64 * period, p, off));
            }
        }
    }

    // Gas switches from [[switch]] tables.
    if let Some(sw) = &raw.switch {
        for s in sw {
            let off = s.span().start;
            let mix = GasMix::parse(&s.get_ref().gas).map_err(|e| cx.err(off, "switch.gas", e))?;
            let t = s.get_ref().time;
            if !t.is_finite() || t < 0.0 {
                return Err(cx.err(off, "switch.time", format!("switch time {t} must be ≥ 0")));
            }
            switches.push((t * sec, mix, off));
        }
    }
    let end = pts[pts.len() - 1].0;
    switches.sort_by(|a, b| a.0.total_cmp(&b.0));
    for w in switches.windows(2) {
        if w[1].0 == w[0].0 {
            return Err(cx.err(
                w[1].2,
                "switch.time",
                format!("two gas switches at {} s; keep one", w[1].0),
            ));
        }
    }
    for &(t, _, off) in &switches {
        if t > 0.0 && t >= end {
            return Err(cx.err(
                off,
                "switch.time",
                format!("gas switch at {} {} is at or after the end of the profile ({} {}); move it earlier", t / sec, raw.time_unit.get_ref(), end / sec, raw.time_unit.get_ref()),
            ));
        }
    }

    // Insert a breakpoint at each switch that falls inside a segment.
    let mut times: Vec<f64> = pts.iter().map(|p| p.0).collect();
    let mut pres: Vec<f64> = pts.iter().map(|p| p.1).collect();
    for &(t, _, _) in &switches {
        let k = times.partition_point(|&x| x < t);
        if k < times.len() && (times[k] - t).abs() <= 1e-9 * end.max(1.0) {
            continue;
        }
        if k == 0 || k >= times.len() {
            continue;
        }
        let (t0, t1, p0, p1) = (times[k - 1], times[k], pres[k - 1], pres[k]);
        times.insert(k, t);
        pres.insert(k, p0 + (p1 - p0) * (t - t0) / (t1 - t0));
    }
    let nseg = (times.len().max(2)) - 1;
    let gases: Vec<GasMix> = (0..nseg)
        .map(|i| {
            let t0 = times[i];
            switches
                .iter()
                .rev()
                .find(|s| s.0 <= t0 + 1e-9 * end.max(1.0))
                .map(|s| s.1)
                .unwrap_or(gas0)
        })
        .collect();

    let name = raw.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "profile".into())
    });
    let mut history = PressureHistory::new(name.clone(), times, pres, gases, vapour)
        .map_err(|e| InputError::new(e).in_file(path).field(pts_field))?;
    // the phantom starts saturated with the file's `gas` (the gas before any switch, also one
    // at time 0 or a first leg's `gas`) at the starting pressure
    history.saturation.gas = gas0;
    Ok(TomlProfile {
        name,
        description: raw.description.unwrap_or_default(),
        history,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gas::Gas;
    use crate::units::PSI_PA;

    fn p(text: &str) -> Result<TomlProfile, InputError> {
        parse(text, Path::new("t.toml"))
    }

    #[test]
    fn points_with_repeat() {
        let r = p("time_unit = \"s\"\npressure_unit = \"psi-gauge\"\npoints = [[0, 0], [30, 20], [60, 0]]\nrepeat = 5\n").unwrap();
        let h = &r.history;
        assert_eq!(h.times_s.len(), 11);
        assert_eq!(h.duration_s(), 300.0);
        // 20 psi gauge at 30 s: 101325 + 20·PSI_PA (NIST SP 811 psi).
        assert!((h.ambient(90.0) - (ATM_PA + 20.0 * PSI_PA)).abs() < 1e-6);
        assert_eq!(r.name, "t");
    }

    #[test]
    fn legs_rates_and_switches() {
        let r = p(r#"
time_unit = "min"
pressure_unit = "msw"
[[leg]]
to = 30
rate = 10
[[leg]]
duration = 20
[[leg]]
to = 6
rate = 9
gas = "50"
[[leg]]
duration = 3
gas = "o2"
"#)
        .unwrap();
        let h = &r.history;
        // 30 m at 10 m/min = 3 min; 20 min hold; 24 m at 9 m/min = 160 s; 3 min.
        let want = [0.0, 180.0, 1380.0, 1380.0 + 160.0, 1380.0 + 160.0 + 180.0];
        assert_eq!(h.times_s.len(), want.len());
        for (a, b) in h.times_s.iter().zip(want) {
            assert!((a - b).abs() < 1e-9, "{a} {b}");
        }
        assert_eq!(h.gas_at(100.0), GasMix::AIR);
        assert!((h.gas_at(1400.0).o2 - 0.5).abs() < 1e-12);
        assert_eq!(h.gas_at(1600.0).o2, 1.0);
    }

    #[test]
    fn switch_inside_segment_inserts_breakpoint() {
        let r = p("time_unit = \"s\"\npressure_unit = \"bar\"\npoints = [[0, 1], [100, 3]]\n[[switch]]\ntime = 50\ngas = \"ean32\"\n").unwrap();
        let h = &r.history;
        assert_eq!(h.times_s, vec![0.0, 50.0, 100.0]);
        assert!((h.ambient_pa[1] - 2e5).abs() < 1e-6);
        assert_eq!(h.gas_at(10.0), GasMix::AIR);
        assert!((h.gas_at(60.0).o2 - 0.32).abs() < 1e-12);
    }

    #[test]
    fn the_phantom_starts_saturated_with_the_files_gas() {
        // a switch at time 0 (a first leg's `gas` is one) is breathed from t = 0, but the
        // phantom was in the file's `gas` before: it starts saturated with that, at `start`
        let r = p("time_unit = \"s\"\npressure_unit = \"bar\"\ngas = \"air\"\nstart = 2\n[[leg]]\nduration = 60\ngas = \"18/45\"\n").unwrap();
        let h = &r.history;
        assert!((h.gas_at(0.0).he - 0.45).abs() < 1e-12);
        assert_eq!(h.saturation.gas, GasMix::AIR);
        assert_eq!(h.saturation.ambient_pa, 2e5);
        assert!((h.saturation_partial_pressure(Gas::N2) - 0.79 * 2e5).abs() < 1e-6);
        assert_eq!(h.saturation_partial_pressure(Gas::He), 0.0);
        // He is one of the run's gases (breathed), N2 too (in the gel at the start)
        assert_eq!(h.gases(), vec![Gas::N2, Gas::O2, Gas::He]);
        // without a switch at time 0 the start is the first segment's gas, as before
        let r = p("time_unit = \"s\"\npressure_unit = \"bar\"\ngas = \"ean32\"\npoints = [[0, 1], [10, 1]]\n").unwrap();
        assert_eq!(r.history.saturation.gas, r.history.gas[0]);
    }

    #[test]
    fn rows_of_three_numbers_pressures_below_1_kpa_and_vapour_above_ambient_are_refused() {
        let head = "time_unit = \"s\"\npressure_unit = \"pa\"\n";
        let e = p(&format!(
            "{head}points = [\n [0, 1e5],\n [10, 1e5, 99],\n]\n"
        ))
        .unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(5), Some("points")),
            "{e}"
        );
        assert!(e.message.contains("expected 2 numbers"), "{e}");
        let e = p(&format!("{head}points = [[0, 1e5, 5, 7], [10, 1e5]]\n")).unwrap_err();
        assert!(e.message.contains("expected 2 numbers"), "{e}");
        // 1 kPa is accepted, anything below it refused on the point's own line
        assert!(p(&format!("{head}points = [[0, 1e5], [10, 1000]]\n")).is_ok());
        let e = p(&format!("{head}points = [[0, 1e5],\n[10, 999]]\n")).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(4), Some("points")),
            "{e}"
        );
        let e = p(&format!("{head}points = [[0, 1e5],\n[10, 1e-10]]\n")).unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
        // water vapour at or above the lowest ambient pressure leaves no gas at the faces
        let e = p(&format!(
            "{head}water_vapour_pa = 50000\npoints = [[0, 101325], [10, 20000]]\n"
        ))
        .unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(3), Some("water_vapour_pa")),
            "{e}"
        );
        assert!(p(&format!(
            "{head}water_vapour_pa = 6270\npoints = [[0, 101325], [10, 20000]]\n"
        ))
        .is_ok());
        // a surface pressure in kPa by mistake
        let e = p("time_unit = \"s\"\npressure_unit = \"bar\"\nsurface_pressure_pa = 101.325\npoints = [[0, 1], [1, 1]]\n").unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(3), Some("surface_pressure_pa")),
            "{e}"
        );
        // a serde type error names its key
        let e = p(&format!(
            "{head}points = [[0, 1e5], [1, 1e5]]\nrepeat = 2.5\n"
        ))
        .unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(4), Some("repeat")),
            "{e}"
        );
    }

    #[test]
    fn errors_name_line_and_field() {
        let e = p("time_unit = \"s\"\npressure_unit = \"psi-gauge\"\npoints = [\n [0, 0],\n [30, 20],\n [20, 0],\n]\n").unwrap_err();
        assert_eq!(e.line, Some(6), "{e}");
        assert_eq!(e.field.as_deref(), Some("points"));
        assert!(e.message.contains("increase strictly"), "{e}");

        let e =
            p("time_unit = \"s\"\npressure_unit = \"furlongs\"\npoints = [[0, 0]]\n").unwrap_err();
        assert_eq!(e.line, Some(2), "{e}");
        assert!(e.message.contains("psi-gauge"), "{e}");

        let e = p("time_unit = \"s\"\npressure_unit = \"pa\"\npoints = [[0, 1e5]]\nsurface = 3\n")
            .unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
        assert!(e.message.contains("surface"), "{e}");

        let e = p(
            "time_unit = \"s\"\npressure_unit = \"psi-gauge\"\npoints = [[0, 0],\n  [10, -20]]\n",
        )
        .unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
        assert!(
            e.message.contains("absolute pressure must be positive"),
            "{e}"
        );

        let e = p("time_unit = \"s\"\npressure_unit = \"bar\"\npoints = [[-1, 1], [0, 1]]\n")
            .unwrap_err();
        assert!(e.message.contains("negative time"), "{e}");

        let e = p("time_unit = \"fortnight\"\npressure_unit = \"bar\"\npoints = [[0, 1]]\n")
            .unwrap_err();
        assert_eq!(e.line, Some(1));
        assert_eq!(e.field.as_deref(), Some("time_unit"));
    }
}
