//! The paper's legacy two-column profiles: one `time value` pair per line.
//!
//! Tolerated (every quirk of the files the authors published, `shared/legacy-profiles/`):
//! tabs or spaces (or both) between and after the columns, Windows line ends (`\r\n`),
//! a UTF-8 byte-order mark, no final newline, and empty lines at the very end.
//! Refused, with file and line: an empty line between data lines, a line that is not exactly
//! two numbers, a time that is negative or not strictly after the previous one, a first time
//! other than 0, and an absolute pressure outside 1 kPa ..= 200 bar.
//! The file carries no units: the caller gives them ([`LegacyUnits`]).

use std::path::Path;

use super::PressureHistory;
use crate::error::InputError;
use crate::gas::GasMix;
use crate::units::{PressureUnit, TimeUnit, ATM_PA};

/// What a legacy file does not say: its units, the surface pressure and the gas.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegacyUnits {
    /// Unit of the first column.
    pub time: TimeUnit,
    /// Unit of the second column.
    pub pressure: PressureUnit,
    /// Zero of gauge and depth units, absolute Pa.
    pub surface_pa: f64,
    /// Chamber or breathing gas for the whole profile.
    pub gas: GasMix,
    /// Water-vapour pressure subtracted at the open faces, Pa.
    pub vapour_pa: f64,
}

impl LegacyUnits {
    /// Given units, sea-level surface (101 325 Pa), air, no water vapour (chamber gas).
    pub fn new(time: TimeUnit, pressure: PressureUnit) -> Self {
        LegacyUnits {
            time,
            pressure,
            surface_pa: ATM_PA,
            gas: GasMix::AIR,
            vapour_pa: 0.0,
        }
    }
}

/// Parse a command-line units string `TIME,PRESSURE` (also `TIME:PRESSURE` or `TIME/PRESSURE`),
/// e.g. `min,psi-gauge` or `s,msw`.
pub fn parse_units(s: &str) -> Result<(TimeUnit, PressureUnit), InputError> {
    let bad = || {
        InputError::new(format!(
            "cannot read units '{s}'; write TIME,PRESSURE with TIME one of s, min, h and PRESSURE one of pa, kpa, bar, atm, psi-gauge, psia, msw, fsw (e.g. min,psi-gauge)"
        ))
        .field("--units")
    };
    let (a, b) = s
        .split_once(',')
        .or_else(|| s.split_once(':'))
        .or_else(|| s.split_once('/'))
        .ok_or_else(bad)?;
    Ok((
        TimeUnit::parse(a).ok_or_else(bad)?,
        PressureUnit::parse(b).ok_or_else(bad)?,
    ))
}

/// Read a legacy file.
pub fn read(path: &Path, units: &LegacyUnits) -> Result<PressureHistory, InputError> {
    let text = crate::error::read_text(path, "the profile")?;
    parse(&text, path, units)
}

/// Parse legacy text; `path` is used in error messages and as the history's label (file stem).
pub fn parse(text: &str, path: &Path, units: &LegacyUnits) -> Result<PressureHistory, InputError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lines: Vec<&str> = text
        .split('\n')
        .map(|l| l.strip_suffix('\r').unwrap_or(l))
        .collect();
    // Trailing empty lines (including the one after a final newline) are not data.
    let last_data = lines.iter().rposition(|l| !l.trim().is_empty());
    let Some(last_data) = last_data else {
        return Err(InputError::new(
            "the file is empty; a legacy profile has one `time value` pair per line",
        )
        .in_file(path)
        .at_line(1));
    };
    let err = |line: usize, field: &str, msg: String| {
        InputError::new(msg)
            .in_file(path)
            .at_line(line)
            .field(field)
    };
    let sec = units.time.seconds();
    let mut times = Vec::new();
    let mut pres = Vec::new();
    for (i, raw) in lines[..=last_data].iter().enumerate() {
        let n = i + 1;
        let l = raw.trim();
        if l.is_empty() {
            return Err(err(
                n,
                "line",
                "empty line between data lines; delete it (every line is `time value`)".into(),
            ));
        }
        let cols: Vec<&str> = l.split_whitespace().collect();
        if cols.len() != 2 {
            return Err(err(
                n,
                "line",
                format!(
                    "expected two numbers `time value` separated by tabs or spaces, found {} field(s) in '{}'",
                    cols.len(),
                    l.escape_debug()
                ),
            ));
        }
        let num = |s: &str, field: &str| -> Result<f64, InputError> {
            match s.parse::<f64>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err(err(
                    n,
                    field,
                    format!(
                        "'{}' is not a number; write a decimal number such as 12.5",
                        s.escape_debug()
                    ),
                )),
            }
        };
        let t = num(cols[0], "time")?;
        let v = num(cols[1], "value")?;
        if t < 0.0 {
            return Err(err(
                n,
                "time",
                format!("negative time {t}; times start at 0"),
            ));
        }
        if times.is_empty() && t != 0.0 {
            return Err(err(
                n,
                "time",
                format!("the first time is {t}; a profile starts at time 0: add a line `0 <value>` first"),
            ));
        }
        let ts = t * sec;
        if let Some(&prev) = times.last() {
            if ts <= prev {
                return Err(err(
                    n,
                    "time",
                    format!(
                        "time {t} is not after the previous line's {}; times must increase strictly: fix the order or remove the duplicate line",
                        prev / sec
                    ),
                ));
            }
        }
        let p = units.pressure.to_absolute_pa(v, units.surface_pa);
        if p <= 0.0 || p.is_nan() {
            return Err(err(
                n,
                "value",
                format!(
                    "{v} in {:?} is {p} Pa absolute (surface {} Pa); absolute pressure must be positive: check the unit the file is read in (`--units` for a legacy profile; a legacy schedule holds depths in metres of sea water, so this is a depth above the surface)",
                    units.pressure, units.surface_pa
                ),
            ));
        }
        if p < super::MIN_AMBIENT_PA {
            return Err(err(
                n,
                "value",
                format!(
                    "{} in {:?}: {}",
                    crate::error::num(v),
                    units.pressure,
                    super::below_minimum_message(p)
                ),
            ));
        }
        if p > super::MAX_AMBIENT_PA {
            return Err(err(
                n,
                "value",
                format!(
                    "{} in {:?} is {} Pa absolute, above the accepted {} Pa (200 bar)",
                    crate::error::num(v),
                    units.pressure,
                    crate::error::num(p),
                    crate::error::num(super::MAX_AMBIENT_PA)
                ),
            ));
        }
        if ts > super::MAX_DURATION_S {
            return Err(err(n, "time", super::duration_message(ts)));
        }
        times.push(ts);
        pres.push(p);
    }
    let label = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "legacy".into());
    // what is left (a single point) is a problem of the last data line
    PressureHistory::with_gas(label, times, pres, units.gas, units.vapour_pa)
        .map_err(|e| InputError::new(e).in_file(path).at_line(last_data + 1))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::units::PSI_PA;

    fn u() -> LegacyUnits {
        LegacyUnits::new(TimeUnit::Min, PressureUnit::PsiGauge)
    }

    #[test]
    fn quirks_are_tolerated() {
        let h = parse(
            "\u{feff}0.0\t0.0 \t\r\n1.0 \t50.0\n2 50\n\n\n",
            Path::new("x.txt"),
            &u(),
        )
        .unwrap();
        assert_eq!(h.times_s, vec![0.0, 60.0, 120.0]);
        // 50 psi gauge = 101325 + 50·PSI_PA (NIST SP 811).
        assert!((h.ambient_pa[1] - (ATM_PA + 50.0 * PSI_PA)).abs() < 1e-6);
        assert_eq!(h.label, "x");
    }

    #[test]
    fn refusals_name_the_line() {
        let e = parse("0 0\n\n1 2\n", Path::new("x.txt"), &u()).unwrap_err();
        assert_eq!(e.line, Some(2));
        let e = parse("0 0\n1 2 3\n", Path::new("x.txt"), &u()).unwrap_err();
        assert_eq!(e.line, Some(2));
        let e = parse("0 0\n1 x\n", Path::new("x.txt"), &u()).unwrap_err();
        assert_eq!((e.line, e.field.as_deref()), (Some(2), Some("value")));
        let e = parse("0 0\n2 1\n1 1\n", Path::new("x.txt"), &u()).unwrap_err();
        assert_eq!((e.line, e.field.as_deref()), (Some(3), Some("time")));
        let e = parse("0 0\n2 1\n2 1\n", Path::new("x.txt"), &u()).unwrap_err();
        assert_eq!(e.line, Some(3));
        let e = parse("0 0\n1 -20\n", Path::new("x.txt"), &u()).unwrap_err();
        assert_eq!((e.line, e.field.as_deref()), (Some(2), Some("value")));
        assert!(parse("", Path::new("x.txt"), &u()).is_err());
        assert!(parse("1 0\n2 0\n", Path::new("x.txt"), &u()).is_err());
    }

    #[test]
    fn units_string() {
        assert_eq!(
            parse_units("min,psi-gauge").unwrap(),
            (TimeUnit::Min, PressureUnit::PsiGauge)
        );
        assert_eq!(
            parse_units("s:msw").unwrap(),
            (TimeUnit::S, PressureUnit::Msw)
        );
        assert!(parse_units("min").is_err());
        assert!(parse_units("min,furlong").is_err());
    }
}
