//! Schedules from other tools: a CSV of waypoints `time_min,depth_m[,gas]` (header required,
//! linear between waypoints; a `# conventions:` comment line above the header, as `plan --out`
//! writes it, sets the surface pressure, pressure per metre and water vapour, else the caller's
//! conventions apply). The gas on a row is breathed from that waypoint to the next;
//! rows without a `gas` column (or with an empty cell) keep the previous gas, starting from
//! `default_gas`. Constant-depth segments after the deepest point become stops. The first
//! waypoint is at the surface (0 min, 0 m), and no segment moves faster than
//! [`super::conventions::MAX_TRAVEL_RATE_M_MIN`] (100 m/min, the top of the documented rate
//! range). A segment slower than the bottom of that range
//! ([`super::conventions::MIN_TRAVEL_RATE_M_MIN`]) is accepted: waypoints carry no kind, and a
//! slow change of depth is a drift at a stop or at the bottom, not a travel at a planned rate.

use super::conventions::Conventions;
use super::schedule::{Leg, LegKind, Schedule, Stop};
use crate::error::InputError;
use crate::gas::GasMix;
use std::path::Path;

/// Read any schedule a later command may be given: `.toml` (as `plan --out` writes it) or
/// `.csv` waypoints (`time_min,depth_m[,gas]`, in `conventions`, starting on `default_gas`).
/// Dive logs: [`read_schedule_with_notes`].
pub fn read_schedule(
    path: &Path,
    conventions: &Conventions,
    default_gas: GasMix,
) -> Result<Schedule, InputError> {
    match path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .as_deref()
    {
        Some("toml") => Schedule::read(path),
        Some("csv") => read_waypoints_csv(path, conventions, default_gas),
        Some("txt") => read_legacy_schedule(path, conventions, default_gas),
        _ => Err(InputError::new(
            "unknown schedule format: use a .toml schedule (plan --out), a .csv of time_min,depth_m[,gas] \
             or the paper's two-column .txt (minutes, metres of sea water)",
        )
        .in_file(path)),
    }
}

/// A schedule read from a file, with what was assumed or repaired while reading it (import
/// notes of a dive log; empty for the other formats).
#[derive(Debug, Clone)]
pub struct ScheduleImport {
    /// The schedule.
    pub schedule: Schedule,
    /// Import notes, to print and to write into reports.
    pub notes: Vec<String>,
}

/// [`read_schedule`], and dive logs too (`.xml`, `.ssrf`: Subsurface; `.uddf`; dive `dive`,
/// 1-based, required when the log holds more than one), with their import notes.
pub fn read_schedule_with_notes(
    path: &Path,
    conventions: &Conventions,
    default_gas: GasMix,
    dive: Option<crate::profile::sequence::DiveSelection>,
) -> Result<ScheduleImport, InputError> {
    if crate::profile::is_dive_log(path) {
        return read_divelog_schedule(path, conventions, dive);
    }
    if dive.is_some() {
        return Err(InputError::new(
            "a dive number applies only to dive logs (.xml, .ssrf, .uddf); leave out --dive",
        )
        .in_file(path)
        .field("--dive"));
    }
    Ok(ScheduleImport {
        schedule: read_schedule(path, conventions, default_gas)?,
        notes: Vec::new(),
    })
}

/// One dive of a Subsurface or UDDF log as a schedule: its samples (and gas switches) become
/// the waypoints; surface pressure and water density are the log's (pressure per metre =
/// ρ·g); the water vapour is the conventions' (the gas is breathed). A dive that ends below
/// the surface is brought up at the conventions' ascent rate (noted). Closed-circuit dives
/// are refused.
pub fn read_divelog_schedule(
    path: &Path,
    conventions: &Conventions,
    dive: Option<crate::profile::sequence::DiveSelection>,
) -> Result<ScheduleImport, InputError> {
    use crate::profile::{divelog, select_dive};
    let d = select_dive(path, divelog::read_each(path)?, dive)?;
    let h = d.history(0.0).map_err(|e| e.in_file(path))?;
    let pa_per_m = d.density_kg_m3 * crate::units::STANDARD_GRAVITY;
    let mut notes = d.notes.clone();
    let mut pts: Vec<(f64, f64, GasMix, usize)> = Vec::with_capacity(h.times_s.len() + 1);
    for (i, (&t, &p)) in h.times_s.iter().zip(&h.ambient_pa).enumerate() {
        let gas = h.gas[i.min(h.gas.len() - 1)];
        let depth = ((p - d.surface_pa) / pa_per_m).max(0.0);
        pts.push((t / 60.0, depth, gas, 0));
    }
    let (t_end, d_end, gas_end, _) = *pts.last().expect("a history has points");
    if d_end > 0.0 {
        let rate = conventions.ascent_rate_m_min;
        pts.push((t_end + d_end / rate, 0.0, gas_end, 0));
        notes.push(format!(
            "the last sample is at {d_end:.2} m; an ascent to the surface at {rate} m/min was added"
        ));
    }
    notes.push(format!(
        "water vapour {} Pa at the open faces (alveolar, for a breathed gas)",
        conventions.water_vapour_pa
    ));
    let mut schedule = schedule_from_points(&pts, path, conventions);
    schedule.label = d.label.clone();
    schedule.surface_pressure_pa = d.surface_pa;
    schedule.pa_per_m = pa_per_m;
    Ok(ScheduleImport { schedule, notes })
}

/// Read one of the paper's legacy two-column dive files (`time depth`, minutes and metres of sea
/// water, e.g. `100m_1deco_stop.txt`) as a schedule. The file's quirks and format errors are
/// handled by the legacy profile reader (with file and line); the waypoints then go through the
/// same checks as a CSV schedule.
pub fn read_legacy_schedule(
    path: &Path,
    conventions: &Conventions,
    default_gas: GasMix,
) -> Result<Schedule, InputError> {
    use crate::profile::legacy::{read, LegacyUnits};
    use crate::units::{PressureUnit, TimeUnit, ATM_PA, MSW_PA};
    // read depths as msw over a reference surface of one atmosphere (any pressure the legacy
    // reader accepts, at least 1 kPa; only the depths are kept); a negative depth stays
    // negative, for the waypoint checks below to refuse at its line
    let mut units = LegacyUnits::new(TimeUnit::Min, PressureUnit::Msw);
    units.surface_pa = ATM_PA;
    let h = read(path, &units)?;
    let mut csv = String::from("time_min,depth_m\n");
    for (t, p) in h.times_s.iter().zip(&h.ambient_pa) {
        let depth = (p - ATM_PA) / MSW_PA;
        // rounding at the surface (a depth of 0 is exact; keep −0 out)
        let depth = if depth.abs() < 1e-9 { 0.0 } else { depth };
        csv.push_str(&format!("{},{}\n", t / 60.0, depth));
    }
    // the CSV's row k + 1 is the file's line k; its columns are the file's time and value
    parse_waypoints_csv(&csv, path, conventions, default_gas).map_err(|mut e| {
        e.line = e.line.map(|l| l.saturating_sub(1).max(1));
        e.field = e.field.map(|f| match f.as_str() {
            "time_min" => "time".into(),
            "depth_m" => "value".into(),
            _ => f,
        });
        e
    })
}

/// The comment line `plan --out x.csv` writes above the header ([`CONVENTIONS_COMMENT`]):
/// the schedule's surface pressure, pressure per metre and water vapour, so that a schedule
/// planned at altitude, in fresh water or with another planner's vapour reads back as planned.
pub const CONVENTIONS_COMMENT: &str = "# conventions:";

/// `base` with the surface pressure, pressure per metre and water vapour of the file's
/// [`CONVENTIONS_COMMENT`] line, if it has one before its header (`key = value` pairs separated
/// by commas, anything from a `(` on a note): a CSV without one is read in `base`. Each value is
/// checked (positive, the vapour below the surface pressure), naming the line and the key.
fn file_conventions(
    text: &str,
    path: &Path,
    base: &Conventions,
) -> Result<Conventions, InputError> {
    let mut out = base.clone();
    let mut seen: Option<usize> = None;
    for (i, line) in text.lines().enumerate() {
        let l = line.trim_start_matches('\u{feff}').trim();
        if l.is_empty() {
            continue;
        }
        if !l.starts_with('#') {
            break; // the header: comments below it are not the file's conventions
        }
        let Some(rest) = l.strip_prefix(CONVENTIONS_COMMENT) else {
            continue;
        };
        let line_no = i + 1;
        let err = |m: String, field: &str| {
            InputError::new(m)
                .in_file(path)
                .at_line(line_no)
                .field(field.to_string())
        };
        if let Some(first) = seen {
            return Err(err(
                format!("a second conventions line (the first is line {first}); keep one"),
                "conventions",
            ));
        }
        seen = Some(line_no);
        let pairs = rest.split('(').next().unwrap_or("");
        let (mut surface, mut per_m, mut vapour) = (None, None, None);
        for pair in pairs.split(',').map(str::trim).filter(|p| !p.is_empty()) {
            let Some((key, value)) = pair.split_once('=').map(|(k, v)| (k.trim(), v.trim())) else {
                return Err(err(format!("'{pair}' is not `key = value`"), "conventions"));
            };
            let slot = match key {
                "surface_pressure_pa" => &mut surface,
                "pa_per_m" => &mut per_m,
                "water_vapour_pa" => &mut vapour,
                _ => {
                    return Err(err(
                        format!(
                            "unknown key '{key}' (the keys: surface_pressure_pa, pa_per_m, water_vapour_pa)"
                        ),
                        key,
                    ))
                }
            };
            if slot.is_some() {
                return Err(err(format!("'{key}' is given twice"), key));
            }
            let v = value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(format!("'{value}' is not a number"), key))?;
            *slot = Some(v);
        }
        let surface = surface.unwrap_or(base.surface_pressure_pa);
        let per_m = per_m.unwrap_or(base.pa_per_m);
        let vapour = vapour.unwrap_or(base.water_vapour_pa);
        if !(crate::profile::MIN_AMBIENT_PA..=crate::profile::MAX_AMBIENT_PA).contains(&surface) {
            return Err(err(
                format!(
                    "surface pressure {} Pa is outside {}..{} Pa",
                    crate::error::num(surface),
                    crate::error::num(crate::profile::MIN_AMBIENT_PA),
                    crate::error::num(crate::profile::MAX_AMBIENT_PA)
                ),
                "surface_pressure_pa",
            ));
        }
        if !(per_m > 0.0) {
            return Err(err(
                format!("{} Pa/m must be positive", crate::error::num(per_m)),
                "pa_per_m",
            ));
        }
        if !(0.0..surface).contains(&vapour) {
            return Err(err(
                format!(
                    "water vapour {} Pa must be at least 0 and below the surface pressure {} Pa",
                    crate::error::num(vapour),
                    crate::error::num(surface)
                ),
                "water_vapour_pa",
            ));
        }
        out.surface_pressure_pa = surface;
        out.pa_per_m = per_m;
        out.water_vapour_pa = vapour;
    }
    Ok(out)
}

/// Read a waypoint CSV file into a schedule in the given conventions (surface pressure,
/// pressure per metre and water vapour are taken from them).
pub fn read_waypoints_csv(
    path: &Path,
    conventions: &Conventions,
    default_gas: GasMix,
) -> Result<Schedule, InputError> {
    let text = crate::error::read_text(path, "the waypoint file")?;
    parse_waypoints_csv(&text, path, conventions, default_gas)
}

/// Parse waypoint CSV text; `path` names it in errors.
pub fn parse_waypoints_csv(
    text: &str,
    path: &Path,
    conventions: &Conventions,
    default_gas: GasMix,
) -> Result<Schedule, InputError> {
    let own = file_conventions(text, path, conventions)?;
    let conventions = &own;
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let headers = rdr
        .headers()
        .map_err(|e| {
            InputError::new(format!("cannot read the CSV header: {e}"))
                .in_file(path)
                .at_line(1)
        })?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h.eq_ignore_ascii_case(name));
    let header_line = text
        .lines()
        .position(|l| !l.trim().is_empty() && !l.trim_start().starts_with('#'))
        .map_or(1, |i| i + 1);
    let need = |name: &str| {
        col(name).ok_or_else(|| {
            InputError::new(format!(
                "the header needs a '{name}' column (columns: time_min,depth_m[,gas]); found: {}",
                headers.iter().collect::<Vec<_>>().join(",")
            ))
            .in_file(path)
            .at_line(header_line)
            .field(name)
        })
    };
    // a column read by name must appear once: two `depth_m` columns would be read silently
    // from the first
    for name in ["time_min", "depth_m", "gas"] {
        if headers
            .iter()
            .filter(|h| h.eq_ignore_ascii_case(name))
            .count()
            > 1
        {
            return Err(InputError::new(format!(
                "column '{name}' appears twice in the header; keep one"
            ))
            .in_file(path)
            .at_line(header_line)
            .field(name));
        }
    }
    let (ti, di) = (need("time_min")?, need("depth_m")?);
    let gi = col("gas");
    let mut pts: Vec<(f64, f64, GasMix, usize)> = Vec::new();
    let mut gas = default_gas;
    // the schedule's time as its legs will sum it, s
    let mut now_s = 0.0;
    let mut last_line = header_line;
    for rec in rdr.records() {
        let rec = rec.map_err(|e| {
            let mut err = InputError::new(format!("bad CSV row: {e}")).in_file(path);
            if let Some(p) = e.position() {
                err = err.at_line(p.line() as usize);
            }
            err
        })?;
        let line = rec.position().map_or(0, |p| p.line() as usize);
        let num = |i: usize, name: &str| -> Result<f64, InputError> {
            let s = rec.get(i).unwrap_or("");
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    InputError::new(format!("'{s}' is not a number"))
                        .in_file(path)
                        .at_line(line)
                        .field(name)
                })
        };
        last_line = line;
        let t = num(ti, "time_min")?;
        let d = num(di, "depth_m")?;
        if d < 0.0 {
            return Err(InputError::new(format!("depth {d} m is negative"))
                .in_file(path)
                .at_line(line)
                .field("depth_m"));
        }
        if t * 60.0 > crate::profile::MAX_DURATION_S {
            return Err(InputError::new(format!(
                "time {} min: {}",
                crate::error::num(t),
                crate::profile::duration_message(t * 60.0)
            ))
            .in_file(path)
            .at_line(line)
            .field("time_min"));
        }
        let p = conventions.surface_pressure_pa + d * conventions.pa_per_m;
        if d > super::schedule::MAX_PLAN_DEPTH_M || p > crate::profile::MAX_AMBIENT_PA {
            return Err(InputError::new(format!(
                "depth {} m is beyond the accepted {} m",
                crate::error::num(d),
                super::schedule::MAX_PLAN_DEPTH_M
            ))
            .in_file(path)
            .at_line(line)
            .field("depth_m"));
        }
        if let Some(g) = gi.and_then(|i| rec.get(i)).filter(|s| !s.is_empty()) {
            gas = GasMix::parse(g)
                .map_err(|m| InputError::new(m).in_file(path).at_line(line).field("gas"))?;
        }
        if let Some(&(tp, dp, _, _)) = pts.last() {
            let dur = (t - tp) * 60.0;
            if t <= tp || now_s + dur == now_s {
                return Err(InputError::new(format!(
                    "time {t} min does not increase (previous row is at {tp} min)"
                ))
                .in_file(path)
                .at_line(line)
                .field("time_min"));
            }
            if let Some(rate) = super::schedule::too_fast(d - dp, dur) {
                return Err(InputError::new(format!(
                    "{} m at {} min after {} m at {} min is {} at {} m/min, faster than the accepted {} m/min; check this row's time and depth",
                    crate::error::num(d),
                    crate::error::num(t),
                    crate::error::num(dp),
                    crate::error::num(tp),
                    if d > dp { "a descent" } else { "an ascent" },
                    super::schedule::rate_text(rate),
                    super::conventions::MAX_TRAVEL_RATE_M_MIN
                ))
                .in_file(path)
                .at_line(line)
                .field("depth_m"));
            }
            now_s += dur;
        } else if t != 0.0 {
            return Err(InputError::new(format!(
                "the first waypoint must be at time 0, not {t} min"
            ))
            .in_file(path)
            .at_line(line)
            .field("time_min"));
        } else if d != 0.0 {
            return Err(InputError::new(format!(
                "the first waypoint is at {} m: a schedule starts at the surface (0 m at time 0), where the phantom starts saturated, and a first point below it would be an instant compression; add the surface row and the descent (a profile that starts saturated at depth is read by simulate --profile)",
                crate::error::num(d)
            ))
            .in_file(path)
            .at_line(line)
            .field("depth_m"));
        }
        pts.push((t, d, gas, line));
    }
    if pts.len() < 2 {
        return Err(InputError::new("a schedule needs at least two waypoints")
            .in_file(path)
            .at_line(last_line)
            .field("time_min"));
    }
    let (_, last_d, _, last_line) = *pts.last().unwrap();
    if last_d != 0.0 {
        return Err(InputError::new(format!(
            "the schedule never surfaces: the last waypoint is at {last_d} m; end with a row at depth 0"
        ))
        .in_file(path)
        .at_line(last_line)
        .field("depth_m"));
    }
    Ok(schedule_from_points(&pts, path, conventions))
}

/// Legs and stops through waypoints (time min, depth m, gas from this point, line), which
/// start at time 0, increase in time and end at the surface (checked by the callers).
fn schedule_from_points(
    pts: &[(f64, f64, GasMix, usize)],
    path: &Path,
    conventions: &Conventions,
) -> Schedule {
    let max_d = pts.iter().map(|p| p.1).fold(0.0, f64::max);
    let first_at_max = pts.iter().position(|p| p.1 == max_d).unwrap_or(0);
    let mut left_bottom = false;
    let mut legs = Vec::with_capacity(pts.len() - 1);
    let mut stops = Vec::new();
    for (i, w) in pts.windows(2).enumerate() {
        let ((t0, d0, g, _), (t1, d1, _, _)) = (w[0], w[1]);
        let kind = if d1 > d0 {
            LegKind::Descent
        } else if d1 < d0 {
            left_bottom = true;
            LegKind::Ascent
        } else if !left_bottom && i >= first_at_max && d0 == max_d {
            LegKind::Bottom
        } else if d0 > 0.0 && i > first_at_max {
            LegKind::Stop
        } else {
            LegKind::Bottom
        };
        if kind == LegKind::Stop {
            stops.push(Stop {
                depth_m: d0,
                stop_min: t1 - t0,
                runtime_min: t1,
                gas: g,
            });
        }
        legs.push(Leg {
            kind,
            start_depth_m: d0,
            end_depth_m: d1,
            duration_s: (t1 - t0) * 60.0,
            gas: g,
        });
    }
    Schedule {
        label: path
            .file_stem()
            .map_or_else(|| "waypoints".into(), |s| s.to_string_lossy().into_owned()),
        surface_pressure_pa: conventions.surface_pressure_pa,
        pa_per_m: conventions.pa_per_m,
        water_vapour_pa: conventions.water_vapour_pa,
        legs,
        stops,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::conventions::DECOTENGU;

    const DIVE: &str = "time_min,depth_m\n0,0\n2,20\n22,20\n26,0\n";

    fn read(text: &str) -> Result<Schedule, InputError> {
        parse_waypoints_csv(text, Path::new("w.csv"), &DECOTENGU, GasMix::AIR)
    }

    /// The `# conventions:` line above the header sets the schedule's surface pressure,
    /// pressure per metre and water vapour (a note after `(` ignored); without one, or below
    /// the header, the reader's conventions (here DecoTengu's) stand. The history's ambient pressure
    /// at 20 m is p_surf + 20·(Pa per m), by hand, and its faces' vapour the line's.
    #[test]
    fn the_conventions_line_sets_the_schedules_pressures() {
        let s = read(&format!(
            "# from a planner\n{CONVENTIONS_COMMENT} surface_pressure_pa = 79500, pa_per_m = 9800.5, water_vapour_pa = 5670 (note)\n{DIVE}"
        ))
        .unwrap();
        assert_eq!(
            (s.surface_pressure_pa, s.pa_per_m, s.water_vapour_pa),
            (79500.0, 9800.5, 5670.0)
        );
        let h = s.to_pressure_history().unwrap();
        let at_20_m = h.ambient_pa[h.times_s.iter().position(|&t| t == 120.0).unwrap()];
        assert!(
            (at_20_m - (79500.0 + 20.0 * 9800.5)).abs() < 1e-6,
            "{at_20_m}"
        );
        assert_eq!(h.vapour_pa, 5670.0);
        let plain = read(DIVE).unwrap();
        assert_eq!(
            (
                plain.surface_pressure_pa,
                plain.pa_per_m,
                plain.water_vapour_pa
            ),
            (
                DECOTENGU.surface_pressure_pa,
                DECOTENGU.pa_per_m,
                DECOTENGU.water_vapour_pa
            )
        );
        let below = read(&format!(
            "{DIVE}{CONVENTIONS_COMMENT} surface_pressure_pa = 79500\n"
        ))
        .unwrap();
        assert_eq!(below.surface_pressure_pa, DECOTENGU.surface_pressure_pa);
        // one key alone keeps the others
        let one = read(&format!("{CONVENTIONS_COMMENT} pa_per_m = 10000\n{DIVE}")).unwrap();
        assert_eq!(
            (one.surface_pressure_pa, one.pa_per_m),
            (DECOTENGU.surface_pressure_pa, 10000.0)
        );
    }

    /// A bad conventions line is refused naming its line and key, never read as defaults.
    #[test]
    fn a_bad_conventions_line_names_its_line_and_key() {
        let cases = [
            ("altitude_m = 2000", "altitude_m", "unknown key"),
            (
                "surface_pressure_pa = high",
                "surface_pressure_pa",
                "not a number",
            ),
            (
                "surface_pressure_pa = 500",
                "surface_pressure_pa",
                "outside",
            ),
            ("pa_per_m = 0", "pa_per_m", "positive"),
            (
                "water_vapour_pa = 2e5",
                "water_vapour_pa",
                "below the surface",
            ),
            ("pa_per_m = 1, pa_per_m = 2", "pa_per_m", "twice"),
            ("pa_per_m 10000", "conventions", "key = value"),
        ];
        for (pairs, field, says) in cases {
            let e = read(&format!("#\n{CONVENTIONS_COMMENT} {pairs}\n{DIVE}")).unwrap_err();
            assert_eq!(e.line, Some(2), "{pairs}: {e}");
            assert_eq!(e.field.as_deref(), Some(field), "{pairs}: {e}");
            assert!(e.message.contains(says), "{pairs}: {e}");
        }
        let twice = format!(
            "{CONVENTIONS_COMMENT} pa_per_m = 1\n{CONVENTIONS_COMMENT} pa_per_m = 2\n{DIVE}"
        );
        let e = read(&twice).unwrap_err();
        assert_eq!(e.line, Some(2), "{e}");
        assert!(e.message.contains("second conventions line"), "{e}");
    }

    #[test]
    fn reads_waypoints_with_gas_column() {
        let text = "time_min,depth_m,gas\n0,0,air\n2,30,\n20,30,\n23,6,EAN50\n26,6,O2\n27,0,\n";
        let s = parse_waypoints_csv(text, Path::new("w.csv"), &DECOTENGU, GasMix::AIR).unwrap();
        assert_eq!(s.legs.len(), 5);
        assert_eq!(s.legs[1].kind, LegKind::Bottom);
        assert_eq!(s.legs[3].kind, LegKind::Stop);
        assert_eq!(s.stops.len(), 1);
        assert_eq!(s.stops[0].depth_m, 6.0);
        assert_eq!(s.stops[0].stop_min, 3.0);
        assert_eq!(s.stops[0].gas, GasMix::new(0.5, 0.0).unwrap());
        assert!((s.runtime_min() - 27.0).abs() < 1e-12);
        assert_eq!(s.gas_switches().len(), 2);
        let h = s.to_pressure_history().unwrap();
        assert!((h.ambient(120.0) - (101_325.0 + 30.0 * 9_985.0)).abs() < 1e-6);
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse_waypoints_csv(
            "time_min,depth_m\n0,0\n2,30\n20,30\n",
            Path::new("w.csv"),
            &DECOTENGU,
            GasMix::AIR,
        )
        .unwrap_err();
        assert_eq!((e.line, e.field.as_deref()), (Some(4), Some("depth_m")));
        assert!(e.message.contains("never surfaces"));
        let e = parse_waypoints_csv(
            "time_min,depth_m\n0,0\n2,x\n3,0\n",
            Path::new("w.csv"),
            &DECOTENGU,
            GasMix::AIR,
        )
        .unwrap_err();
        assert_eq!((e.line, e.field.as_deref()), (Some(3), Some("depth_m")));
        let e = parse_waypoints_csv(
            "t,depth_m\n0,0\n",
            Path::new("w.csv"),
            &DECOTENGU,
            GasMix::AIR,
        )
        .unwrap_err();
        assert_eq!(e.field.as_deref(), Some("time_min"));
    }

    /// Defect B: a descent at 2·10⁶ m/min, and a first row below the surface (an instant
    /// compression at t = 0), are refused naming the row's line and field; exactly 100 m/min,
    /// and a slow drift at a stop, are accepted.
    #[test]
    fn impossible_movements_are_refused_at_their_row() {
        let read =
            |text: &str| parse_waypoints_csv(text, Path::new("w.csv"), &DECOTENGU, GasMix::AIR);
        let e = read("time_min,depth_m,gas\n0,0,air\n0.0001,200,\n5,200,\n7,0,\n").unwrap_err();
        assert_eq!(
            (e.file.as_deref(), e.line, e.field.as_deref()),
            (Some(Path::new("w.csv")), Some(3), Some("depth_m")),
            "{e}"
        );
        assert!(
            e.message
                .contains("a descent at 2000000 m/min, faster than the accepted 100 m/min"),
            "{e}"
        );
        let e = read("time_min,depth_m\n0,0\n2,30\n20,30\n20.01,0\n").unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(5), Some("depth_m")),
            "{e}"
        );
        assert!(e.message.contains("an ascent at 3000 m/min"), "{e}");
        let e = read("time_min,depth_m\n0,20\n5,20\n7,0\n").unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(2), Some("depth_m")),
            "{e}"
        );
        assert!(e.message.contains("the first waypoint is at 20 m"), "{e}");
        read("time_min,depth_m\n0,0\n0.3,30\n20,30\n20.3,0\n").unwrap();
        read("time_min,depth_m\n0,0\n2,30\n20,30\n23,6\n33,5.9\n34,0\n").unwrap();
        // the legacy two-column files go through the same checks, at their own line and column
        let dir = std::env::temp_dir().join(format!("decophantom-wp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = dir.join("deep-start.txt");
        std::fs::write(&f, "0 30\n3.75 0\n90 0\n").unwrap();
        let e = read_legacy_schedule(&f, &DECOTENGU, GasMix::AIR).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(1), Some("value")),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
