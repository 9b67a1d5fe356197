//! Several dives of one log run as one history: `--dive 2-3` (or `all`) joins consecutive dives
//! with the surface intervals the log's start times give, so that the gel, every bubble and
//! every nucleus carry over from one dive to the next (issue 12: repetitive dives).
//!
//! The joined dive is an ordinary [`ImportedDive`]: the samples of each dive shifted to its
//! start time, the surface interval between them at depth 0 on air, the gases merged. The
//! surface pressure and water density are the first dive's (a later dive that states other
//! values is noted). A dive that ends below the surface cannot be joined to the next.

use super::divelog::ImportedDive;
use crate::gas::GasMix;

/// Which dives of a log to run: one, a range of consecutive dives, or all of them (1-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiveSelection {
    /// Dive `n`.
    One(usize),
    /// Dives `first..=last`, joined.
    Range(usize, usize),
    /// Every dive of the log, joined.
    All,
}

impl std::str::FromStr for DiveSelection {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        let num = |t: &str| {
            t.trim()
                .parse::<usize>()
                .ok()
                .filter(|n| *n >= 1)
                .ok_or_else(|| format!("'{t}' is not a dive number (1, 2, …); use N, N-M or all"))
        };
        if s.eq_ignore_ascii_case("all") {
            return Ok(DiveSelection::All);
        }
        match s.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (num(a)?, num(b)?);
                if b < a {
                    return Err(format!("dive range {a}-{b} runs backwards"));
                }
                Ok(if a == b {
                    DiveSelection::One(a)
                } else {
                    DiveSelection::Range(a, b)
                })
            }
            None => Ok(DiveSelection::One(num(s)?)),
        }
    }
}

impl std::fmt::Display for DiveSelection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            DiveSelection::One(n) => write!(f, "{n}"),
            DiveSelection::Range(a, b) => write!(f, "{a}-{b}"),
            DiveSelection::All => write!(f, "all"),
        }
    }
}

/// Seconds since 1970-01-01 00:00 of a log's start date-time, `YYYY-MM-DD HH:MM[:SS]` or with a
/// `T` between date and time (the forms Subsurface and UDDF write); `None` if it is not one.
/// Time zones are ignored: the dives of one log share one clock.
pub fn start_seconds(s: &str) -> Option<f64> {
    let s = s.trim();
    let (date, time) = s.split_once(['T', ' '])?;
    let d: Vec<&str> = date.split('-').collect();
    if d.len() != 3 {
        return None;
    }
    let (y, m, day): (i64, i64, i64) = (d[0].parse().ok()?, d[1].parse().ok()?, d[2].parse().ok()?);
    if !(1..=12).contains(&m) || !(1..=31).contains(&day) {
        return None;
    }
    // time: HH:MM[:SS[.frac]], anything after (a zone) ignored
    let time = time.trim();
    let end = time
        .find(|c: char| !(c.is_ascii_digit() || c == ':' || c == '.'))
        .unwrap_or(time.len());
    let t: Vec<&str> = time[..end].split(':').collect();
    if t.len() < 2 || t.len() > 3 {
        return None;
    }
    let hh: f64 = t[0].parse().ok()?;
    let mm: f64 = t[1].parse().ok()?;
    let ss: f64 = if t.len() == 3 {
        t[2].parse().ok()?
    } else {
        0.0
    };
    if !(0.0..24.0).contains(&hh) || !(0.0..60.0).contains(&mm) || !(0.0..61.0).contains(&ss) {
        return None;
    }
    Some(days_from_civil(y, m, day) as f64 * 86400.0 + hh * 3600.0 + mm * 60.0 + ss)
}

/// Days from 1970-01-01 to the proleptic Gregorian date y-m-d (the era arithmetic of H. Hinnant's
/// "chrono-Compatible Low-Level Date Algorithms", written out here).
fn days_from_civil(y: i64, m: i64, d: i64) -> i64 {
    let y = if m <= 2 { y - 1 } else { y };
    let era = y.div_euclid(400);
    let yoe = y - era * 400; // [0, 399]
    let mp = (m + 9) % 12; // March = 0
    let doy = (153 * mp + 2) / 5 + d - 1; // [0, 365]
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy; // [0, 146096]
    era * 146_097 + doe - 719_468
}

/// Join consecutive dives (in log order) into one: each dive's samples start at its logged
/// start time relative to the first's, the surface intervals between are at depth 0 on air.
/// Errors name the dive (1-based number `first + k`), what is missing, and the dive's line in
/// the log.
pub fn join(dives: Vec<ImportedDive>, first: usize) -> Result<ImportedDive, (String, usize)> {
    let mut it = dives.into_iter();
    let Some(mut out) = it.next() else {
        return Err(("no dive to join".into(), 1));
    };
    let start_of = |d: &ImportedDive, n: usize| {
        d.start
            .as_deref()
            .and_then(start_seconds)
            .ok_or_else(|| {
                format!(
                    "dive {n} has no readable start date-time in the log ({}), so its surface interval is unknown; run the dives one at a time",
                    d.start.as_deref().unwrap_or("none")
                )
            })
    };
    let t0 = start_of(&out, first).map_err(|m| (m, out.line))?;
    let first_label = out.label.clone();
    let mut last_label = first_label.clone();
    let mut intervals = Vec::new();
    let air = match out.gases.iter().position(|g| *g == GasMix::AIR) {
        Some(i) => i,
        None => {
            out.gases.push(GasMix::AIR);
            out.gases.len() - 1
        }
    };
    for (k, d) in it.enumerate() {
        let n = first + k + 1;
        let end_depth = out.samples.last().map_or(0.0, |s| s.1);
        if end_depth > 0.0 {
            return Err((
                format!(
                    "dive {} ends at {end_depth} m, below the surface: it cannot be followed by dive {n}",
                    n - 1
                ),
                d.line,
            ));
        }
        let offset = start_of(&d, n).map_err(|m| (m, d.line))? - t0;
        let prev_end = out.duration_s();
        if !(offset > prev_end) {
            return Err((
                format!(
                    "dive {n} starts ({}) before dive {} ends ({:.0} s after the first dive's start)",
                    d.start.as_deref().unwrap_or(""),
                    n - 1,
                    prev_end
                ),
                d.line,
            ));
        }
        intervals.push(offset - prev_end);
        // the surface interval on air, then this dive's gases from its start
        out.switches.push((prev_end, air));
        let mut map = Vec::with_capacity(d.gases.len());
        for g in &d.gases {
            let i = match out.gases.iter().position(|x| x == g) {
                Some(i) => i,
                None => {
                    out.gases.push(*g);
                    out.gases.len() - 1
                }
            };
            map.push(i);
        }
        let mut samples = d.samples.iter().map(|&(t, z)| (t + offset, z));
        // the dive's first sample is at its start (time 0); if it is at the surface the
        // interval's end is that sample, else a surface point is put just before it
        if let Some((t, z)) = samples.next() {
            if z > 0.0 {
                out.samples
                    .push((t - 1e-3f64.min(0.5 * (offset - prev_end)), 0.0));
            }
            out.samples.push((t, z));
        }
        out.samples.extend(samples);
        out.switches.push((offset, map[d.initial_gas]));
        out.switches
            .extend(d.switches.iter().map(|&(t, i)| (t + offset, map[i])));
        if (d.surface_pa - out.surface_pa).abs() > 1.0 || d.density_kg_m3 != out.density_kg_m3 {
            out.notes.push(format!(
                "dive {n} states a surface pressure of {:.0} Pa and water density {} kg/m³; the first dive's {:.0} Pa and {} kg/m³ are used for the whole sequence",
                d.surface_pa, d.density_kg_m3, out.surface_pa, out.density_kg_m3
            ));
        }
        out.notes
            .extend(d.notes.iter().map(|m| format!("dive {n}: {m}")));
        out.closed_circuit |= d.closed_circuit;
        out.planned |= d.planned;
        last_label = d.label.clone();
    }
    out.switches.sort_by(|a, b| a.0.total_cmp(&b.0));
    let text: Vec<String> = intervals
        .iter()
        .map(|s| format!("{:.0} min", s / 60.0))
        .collect();
    out.notes.push(format!(
        "dives {first}–{} run as one history, the gel, bubbles and nuclei carried across the surface interval(s) of {} (from the logged start times), breathing air",
        first + intervals.len(),
        text.join(", ")
    ));
    out.label = format!("{first_label} … {last_label}");
    out.stated_duration_s = None;
    out.stated_max_depth_m = None;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn selections_parse_and_print() {
        assert_eq!("3".parse(), Ok(DiveSelection::One(3)));
        assert_eq!(" 2-4 ".parse(), Ok(DiveSelection::Range(2, 4)));
        assert_eq!("2-2".parse(), Ok(DiveSelection::One(2)));
        assert_eq!("ALL".parse(), Ok(DiveSelection::All));
        for bad in ["0", "-1", "4-2", "x", "1-", ""] {
            assert!(bad.parse::<DiveSelection>().is_err(), "{bad}");
        }
        assert_eq!(DiveSelection::Range(2, 4).to_string(), "2-4");
    }

    #[test]
    fn start_times_against_known_epoch_seconds() {
        // reference values: the Unix epoch, and `date -u -d '2017-02-03 06:58:00' +%s`
        // = 1486105080; 2000-03-01 (after a leap day of a year divisible by 400) = 951868800
        assert_eq!(start_seconds("1970-01-01 00:00:00"), Some(0.0));
        assert_eq!(start_seconds("2017-02-03 06:58:00"), Some(1_486_105_080.0));
        assert_eq!(start_seconds("2017-02-03T06:58"), Some(1_486_105_080.0));
        assert_eq!(start_seconds("2000-03-01T00:00:00Z"), Some(951_868_800.0));
        for bad in [
            "2017-13-01 00:00",
            "2017-02-03",
            "yesterday",
            "2017-02-03 25:00",
        ] {
            assert_eq!(start_seconds(bad), None, "{bad}");
        }
    }
}
