//! Pressure histories: the ambient pressure at the phantom and the gas at its open
//! faces over time. A dive schedule, a laboratory TOML profile, a CSV of waypoints and
//! the paper's legacy two-column files all become a [`PressureHistory`].

use std::path::Path;

use crate::error::InputError;
use crate::gas::{Gas, GasMix};
use crate::units::{PressureUnit, TimeUnit};

pub mod divelog;
pub mod legacy;
pub mod sequence;
pub mod toml;

/// Options for [`load`]: what a legacy two-column file does not say. A TOML profile states all
/// of these itself, so every field must be `None` for a `.toml` file.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LoadOptions {
    /// Unit of the time column (required for legacy files).
    pub time_unit: Option<TimeUnit>,
    /// Unit of the pressure column (required for legacy files).
    pub pressure_unit: Option<PressureUnit>,
    /// Zero of gauge and depth units, absolute Pa (legacy default 101 325).
    pub surface_pa: Option<f64>,
    /// Chamber or breathing gas (legacy default air).
    pub gas: Option<GasMix>,
    /// Water-vapour pressure subtracted at the open faces, Pa (legacy and dive-log default 0;
    /// give the alveolar value, e.g. 6 270 Pa, when a breathed gas drives the phantom).
    pub vapour_pa: Option<f64>,
    /// Which dive(s) of a dive log (1-based; a range or `all` joins consecutive dives);
    /// required when the log holds more than one.
    pub dive: Option<sequence::DiveSelection>,
}

/// Longest history accepted, s: 30 days simulated. Longer profiles, repeated cycles, dive logs
/// and surface intervals are refused (exit 2) before any work starts.
pub const MAX_DURATION_S: f64 = 30.0 * 86400.0;

/// Highest absolute ambient pressure accepted, Pa (200 bar, about 2 000 m of sea water).
pub const MAX_AMBIENT_PA: f64 = 2e7;

/// Lowest absolute ambient pressure accepted, Pa (1 kPa). Below it the water of a gel boils
/// even at 7 °C (the vapour pressure of water is 1.0 kPa there, 6.3 kPa at 37 °C), so the
/// model of gas bubbles in a liquid gel does not hold; it is far below any altitude or
/// hypobaric chamber (19 kPa at 12 000 m, the Armstrong limit 6.3 kPa). A near-vacuum (1e-10 Pa)
/// would otherwise make the time steps, limited to a fraction of the ambient pressure, endless.
pub const MIN_AMBIENT_PA: f64 = 1e3;

/// The message for an absolute pressure below [`MIN_AMBIENT_PA`].
pub fn below_minimum_message(p: f64) -> String {
    format!(
        "{} Pa absolute is below the accepted {} Pa (1 kPa: below it the gel's water boils); check the unit or the sign",
        crate::error::num(p),
        crate::error::num(MIN_AMBIENT_PA)
    )
}

/// The message for a water-vapour pressure at or above the lowest ambient pressure of a
/// profile: the faces would hold no gas at all there.
pub fn vapour_above_ambient_message(vapour_pa: f64, ambient_pa: f64, at_s: f64) -> String {
    format!(
        "water-vapour pressure {} Pa is not below the ambient pressure {} Pa at t = {} s; the gas at the faces is (ambient − vapour), so the vapour must stay below the lowest ambient pressure of the profile",
        crate::error::num(vapour_pa),
        crate::error::num(ambient_pa),
        crate::error::num(at_s)
    )
}

/// Most breakpoints a history may have (a repeated cycle is counted whole).
pub const MAX_BREAKPOINTS: usize = 1_000_000;

/// How long a logged dive is watched at the surface after its last sample, s: the default
/// watch time of the criteria protocol (`risk::Protocol`, 60 min), so that a dive-log run
/// records the bubbles growing after surfacing and not only up to the last sample.
pub const DIVE_LOG_WATCH_S: f64 = 3600.0;

/// Whether a path names a dive log (`.xml`, `.ssrf`: Subsurface; `.uddf`).
pub fn is_dive_log(path: &Path) -> bool {
    path.extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .is_some_and(|e| matches!(e.as_str(), "xml" | "ssrf" | "uddf"))
}

/// Choose dive `dive` (1-based) of a log; required when the log holds more than one. A range
/// or `all` joins consecutive dives into one with the logged surface intervals
/// ([`sequence::join`]).
pub fn select_dive(
    path: &Path,
    mut dives: Vec<Result<divelog::ImportedDive, InputError>>,
    dive: Option<sequence::DiveSelection>,
) -> Result<divelog::ImportedDive, InputError> {
    use sequence::DiveSelection;
    let n = dives.len();
    let missing = |k: usize| {
        InputError::new(format!(
            "dive {k} does not exist: the log holds {n} dive(s), numbered from 1"
        ))
        .in_file(path)
        .field("dive")
    };
    let (first, last) = match (dive, n) {
        (None, 1) => (1, 1),
        (None, n) => {
            return Err(InputError::new(format!(
                "the log holds {n} dives; choose one with a dive number 1..={n} (or a range N-M, or all, to run them in sequence)"
            ))
            .in_file(path)
            .field("dive"))
        }
        (Some(DiveSelection::One(k)), _) => (k, k),
        (Some(DiveSelection::Range(a, b)), _) => (a, b),
        (Some(DiveSelection::All), _) => (1, n),
    };
    if first < 1 || first > n {
        return Err(missing(first));
    }
    if last > n {
        return Err(missing(last));
    }
    // a dive the reader refused is an error only when chosen
    if first == last {
        return dives.swap_remove(first - 1);
    }
    let chosen = dives
        .drain(first - 1..last)
        .collect::<Result<Vec<_>, _>>()?;
    sequence::join(chosen, first)
        .map_err(|(m, line)| InputError::new(m).in_file(path).at_line(line).field("dive"))
}

/// A logged dive as a pressure history followed by `watch_s` at the surface (on air), with
/// the import notes. A dive whose last sample is below the surface is first brought up at
/// 10 m/min (noted).
pub fn dive_log_history(
    dive: &divelog::ImportedDive,
    vapour_pa: f64,
    watch_s: f64,
) -> Result<(PressureHistory, Vec<String>), InputError> {
    let mut notes = dive.notes.clone();
    let mut h = dive.history(vapour_pa)?;
    let bad = |m: String| InputError::new(format!("dive '{}': {m}", dive.label)).at_line(dive.line);
    let last_p = *h.ambient_pa.last().unwrap_or(&dive.surface_pa);
    let last_depth =
        (last_p - dive.surface_pa) / (dive.density_kg_m3 * crate::units::STANDARD_GRAVITY);
    let gas = h.gas_at(h.duration_s());
    if last_depth > 1e-9 {
        let up_s = last_depth / 10.0 * 60.0;
        notes.push(format!(
            "the last sample is at {last_depth:.2} m; an ascent to the surface at 10 m/min ({up_s:.0} s) was added"
        ));
        let ascent = PressureHistory::with_gas(
            "ascent",
            vec![0.0, up_s],
            vec![last_p, dive.surface_pa],
            gas,
            vapour_pa,
        )
        .map_err(bad)?;
        h = h.then(&ascent).map_err(bad)?;
    }
    if watch_s > 0.0 {
        notes.push(format!(
            "watched {} min at the surface after the dive",
            watch_s / 60.0
        ));
        let surface = PressureHistory::with_gas(
            "surface",
            vec![0.0, watch_s],
            vec![dive.surface_pa, dive.surface_pa],
            GasMix::AIR,
            vapour_pa,
        )
        .map_err(bad)?;
        h = h.then(&surface).map_err(bad)?;
    }
    h.label = dive.label.clone();
    Ok((h, notes))
}

/// [`load`], and the import notes of a dive log (defaults used, repairs, the watch time at
/// the surface); empty for the other formats.
pub fn load_with_notes(
    path: &Path,
    opts: &LoadOptions,
) -> Result<(PressureHistory, Vec<String>), InputError> {
    let h = load(path, opts)?;
    let notes = if is_dive_log(path) {
        let d = select_dive(path, divelog::read_each(path)?, opts.dive)?;
        dive_log_history(&d, opts.vapour_pa.unwrap_or(0.0), DIVE_LOG_WATCH_S)
            .map_err(|e| e.in_file(path))?
            .1
    } else {
        Vec::new()
    };
    Ok((h, notes))
}

/// Load a pressure profile: `.toml` files with [`toml::read`] (their units are in the file);
/// dive logs (`.xml`, `.ssrf`: Subsurface; `.uddf`) with [`divelog::read`], choosing
/// `opts.dive`, followed by [`DIVE_LOG_WATCH_S`] at the surface; anything else as a legacy two-column file with [`legacy::read`], which needs
/// `opts.time_unit` and `opts.pressure_unit`.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<PressureHistory, InputError> {
    // what is wrong with the path comes first: a folder given without --units is a folder,
    // not a legacy file that lacks units
    match std::fs::metadata(path) {
        Err(e) => {
            return Err(
                InputError::new(format!("cannot read the profile: {e}; check the path"))
                    .in_file(path),
            )
        }
        Ok(m) if m.is_dir() => {
            return Err(InputError::new(
                "this is a folder, not a profile; give a TOML profile, a legacy two-column text file or a dive log (.xml, .ssrf, .uddf)",
            )
            .in_file(path))
        }
        Ok(_) => {}
    }
    let vapour = vapour_option(opts)?;
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if opts.dive.is_some() && !matches!(ext.as_str(), "xml" | "ssrf" | "uddf") {
        return Err(InputError::new(
            "a dive number applies only to dive logs (.xml, .ssrf, .uddf); leave it out",
        )
        .in_file(path)
        .field("dive"));
    }
    if matches!(ext.as_str(), "xml" | "ssrf" | "uddf") {
        let given = [
            (
                opts.time_unit.is_some() || opts.pressure_unit.is_some(),
                "--units",
            ),
            (opts.surface_pa.is_some(), "surface pressure"),
            (opts.gas.is_some(), "gas"),
        ];
        if let Some((_, what)) = given.iter().find(|(g, _)| *g) {
            return Err(InputError::new(format!(
                "a dive log states its own depths, gases and surface pressure; leave out the {what} option"
            ))
            .in_file(path)
            .field(*what));
        }
        let dive = select_dive(path, divelog::read_each(path)?, opts.dive)?;
        let (mut h, _) =
            dive_log_history(&dive, 0.0, DIVE_LOG_WATCH_S).map_err(|e| e.in_file(path))?;
        if let Some(v) = vapour {
            vapour_below_ambient(&h, v)?;
            h.vapour_pa = v;
        }
        return Ok(h);
    }
    if ext == "toml" {
        refuse_load_options(
            path,
            opts,
            "a TOML profile states its own units, surface pressure, gas and water vapour",
        )?;
        return toml::read(path).map(|p| p.history);
    }
    let (Some(time), Some(pressure)) = (opts.time_unit, opts.pressure_unit) else {
        return Err(InputError::new(
            "a legacy two-column profile carries no units; give them, e.g. --units min,psi-gauge (time s|min|h, pressure pa|kpa|bar|atm|psi-gauge|psia|msw|fsw)",
        )
        .in_file(path)
        .field("--units"));
    };
    let mut u = legacy::LegacyUnits::new(time, pressure);
    if let Some(s) = opts.surface_pa {
        if !(s.is_finite() && s > 0.0) {
            return Err(
                InputError::new(format!("surface pressure {s} Pa must be positive"))
                    .field("surface pressure"),
            );
        }
        u.surface_pa = s;
    }
    if let Some(g) = opts.gas {
        u.gas = g;
    }
    let mut h = legacy::read(path, &u)?;
    if let Some(v) = vapour {
        vapour_below_ambient(&h, v)?;
        h.vapour_pa = v;
    }
    Ok(h)
}

/// Refuse every option of `opts` for a file that states what they set itself (`states`, the
/// first half of the message: "a TOML profile states its own units, …"), naming the first
/// option given by its flag (and its key in a `fit` experiments file); the file's own values
/// would otherwise silently win over the command line. A dive number is refused as it is for
/// any file that is not a dive log.
pub fn refuse_load_options(
    path: &Path,
    opts: &LoadOptions,
    states: &str,
) -> Result<(), InputError> {
    if opts.dive.is_some() {
        return Err(InputError::new(
            "a dive number applies only to dive logs (.xml, .ssrf, .uddf); leave out --dive",
        )
        .in_file(path)
        .field("--dive"));
    }
    // (given, flag, what a fit experiments file calls it)
    let given = [
        (
            opts.time_unit.is_some() || opts.pressure_unit.is_some(),
            "--units",
            Some("units"),
        ),
        (opts.gas.is_some(), "--gas", Some("gas")),
        (opts.vapour_pa.is_some(), "--vapour-pa", Some("vapour_pa")),
        (opts.surface_pa.is_some(), "surface pressure", None),
    ];
    match given.iter().find(|(g, _, _)| *g) {
        None => Ok(()),
        Some((_, flag, key)) => {
            let key = key.map_or(String::new(), |k| {
                format!(" (`{k}` in a fit experiments file)")
            });
            Err(InputError::new(format!(
                "{states}; leave out the {flag} option{key}, or edit the file"
            ))
            .in_file(path)
            .field(*flag))
        }
    }
}

/// The water-vapour option (`--vapour-pa`), checked: 0 ≤ value < 100 000 Pa. It comes from
/// the command line, so a bad value names the option, not the profile file.
fn vapour_option(opts: &LoadOptions) -> Result<Option<f64>, InputError> {
    match opts.vapour_pa {
        None => Ok(None),
        Some(v) if (0.0..1e5).contains(&v) => Ok(Some(v)),
        Some(v) => Err(InputError::new(format!(
            "water-vapour pressure {} Pa is out of range 0..100000 (0 for chamber gas, about 6270 for alveolar gas at 37 °C)",
            crate::error::num(v)
        ))
        .in_file("<command line>")
        .field("--vapour-pa")),
    }
}

/// The water-vapour option against the history it is applied to: below its lowest ambient
/// pressure ([`vapour_above_ambient_message`]), else an error naming the option.
fn vapour_below_ambient(h: &PressureHistory, vapour_pa: f64) -> Result<(), InputError> {
    match h.ambient_pa.iter().position(|&p| p <= vapour_pa) {
        None => Ok(()),
        Some(i) => Err(InputError::new(vapour_above_ambient_message(
            vapour_pa,
            h.ambient_pa[i],
            h.times_s[i],
        ))
        .in_file("<command line>")
        .field("--vapour-pa")),
    }
}

/// The message for a history longer than [`MAX_DURATION_S`].
pub fn duration_message(end_s: f64) -> String {
    format!(
        "the profile lasts {} s ({} days); the longest run accepted is {} days simulated ({MAX_DURATION_S} s)",
        crate::error::num(end_s),
        crate::error::num((end_s / 86400.0 * 10.0).round() / 10.0),
        MAX_DURATION_S / 86400.0
    )
}

/// A piecewise-linear ambient-pressure history with the breathing (or chamber) gas
/// in force on each segment. Times in s, pressures absolute Pa.
#[derive(Debug, Clone, PartialEq)]
pub struct PressureHistory {
    /// Breakpoint times, s, strictly increasing, starting at 0.
    pub times_s: Vec<f64>,
    /// Absolute ambient pressure at each breakpoint, Pa ([`MIN_AMBIENT_PA`] ..= [`MAX_AMBIENT_PA`]).
    pub ambient_pa: Vec<f64>,
    /// Gas in force on segment i (from `times_s[i]` to `times_s[i+1]`); length = breakpoints − 1
    /// (a single-point history has one entry).
    pub gas: Vec<GasMix>,
    /// Water-vapour pressure subtracted from ambient before splitting it into inert-gas
    /// partial pressures at the open faces, Pa (0 for chamber gas in the laboratory; the
    /// alveolar value, e.g. 6 270 Pa, for a breathed dive gas).
    pub vapour_pa: f64,
    /// Human-readable name (profile file stem or schedule label).
    pub label: String,
    /// Open faces see only the inert gases (N2, He) of the gas in force: its O2 is left out of
    /// the phantom (for a breathed dive gas; living tissue metabolises oxygen). False (the
    /// default) for chamber gas, which reaches the gel as it is.
    pub inert_only: bool,
    /// What the phantom is saturated with at t = 0 ([`Saturation`]): for a dive (a schedule,
    /// a dive log) surface air, as every planner's tissues start; for a laboratory profile
    /// the chamber gas at the starting pressure.
    pub saturation: Saturation,
}

/// The state the phantom starts in: the gel and the t = 0 bubbles in equilibrium with `gas`
/// at the ambient pressure `ambient_pa`, under the history's conventions (its water vapour
/// subtracted, its O2 left out with [`PressureHistory::inert_only`]):
/// C_g = L_g·f_g·(ambient − P_H2O)/(R_u·T) ([`PressureHistory::saturation_partial_pressure`]).
///
/// - Dives (schedules of `plan`, `evaluate`, `check`; CSV waypoints; dive logs): surface air
///   at the surface pressure, whatever the first leg breathes — the state before the dive,
///   the one ZH-L16 and VPM-B start their tissues in, f_N2,air·(P_surf − P_H2O), no He.
/// - TOML profiles: the file's `gas` (the gas at time 0, before any switch; default air) at the
///   starting pressure. Legacy two-column files: their one gas at the starting pressure.
///   [`PressureHistory::new`] takes the first segment's gas at the first pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Saturation {
    /// The gas the phantom is saturated with.
    pub gas: GasMix,
    /// The absolute ambient pressure it is saturated at, Pa.
    pub ambient_pa: f64,
}

impl PressureHistory {
    /// Build and check a history: times strictly increasing from 0, pressures in
    /// [`MIN_AMBIENT_PA`] ..= [`MAX_AMBIENT_PA`], water vapour in 0..1e5 Pa and below every
    /// ambient pressure.
    pub fn new(
        label: impl Into<String>,
        times_s: Vec<f64>,
        ambient_pa: Vec<f64>,
        gas: Vec<GasMix>,
        vapour_pa: f64,
    ) -> Result<Self, String> {
        if times_s.len() < 2 || times_s.len() != ambient_pa.len() {
            // one rule for every reader: a single point has no duration to simulate
            return Err(format!(
                "a profile needs at least two points (a start and an end), with a pressure for every time (got {} time(s), {} pressure(s))",
                times_s.len(),
                ambient_pa.len()
            ));
        }
        if times_s.len() > MAX_BREAKPOINTS {
            return Err(format!(
                "{} breakpoints is too many (limit {MAX_BREAKPOINTS})",
                times_s.len()
            ));
        }
        if times_s[0] != 0.0 {
            return Err(format!(
                "a profile must start at time 0 (first time is {} s)",
                times_s[0]
            ));
        }
        for (i, w) in times_s.windows(2).enumerate() {
            if !(w[1] > w[0]) || !w[1].is_finite() {
                return Err(format!(
                    "times must increase strictly: point {} is at {} s after {} s",
                    i + 2,
                    w[1],
                    w[0]
                ));
            }
        }
        let end = times_s[times_s.len() - 1];
        if end > MAX_DURATION_S {
            return Err(duration_message(end));
        }
        if let Some((i, p)) = ambient_pa
            .iter()
            .enumerate()
            .find(|(_, p)| !(**p > 0.0) || !p.is_finite())
        {
            return Err(format!(
                "pressure at point {} is {p} Pa; absolute pressure must be positive",
                i + 1
            ));
        }
        if let Some((i, p)) = ambient_pa
            .iter()
            .enumerate()
            .find(|(_, p)| **p < MIN_AMBIENT_PA)
        {
            return Err(format!(
                "pressure at point {}: {}",
                i + 1,
                below_minimum_message(*p)
            ));
        }
        if let Some((i, p)) = ambient_pa
            .iter()
            .enumerate()
            .find(|(_, p)| **p > MAX_AMBIENT_PA)
        {
            return Err(format!(
                "pressure at point {} is {p:e} Pa; the accepted range ends at {MAX_AMBIENT_PA:e} Pa (200 bar, about 2 000 m of sea water)",
                i + 1
            ));
        }
        let want = (times_s.len() - 1).max(1);
        if gas.len() != want {
            return Err(format!("{} gas entries for {} segments", gas.len(), want));
        }
        if !(0.0..1e5).contains(&vapour_pa) {
            return Err(format!(
                "water-vapour pressure {vapour_pa} Pa is out of range 0..1e5"
            ));
        }
        if let Some((i, p)) = ambient_pa
            .iter()
            .enumerate()
            .find(|(_, p)| **p <= vapour_pa)
        {
            return Err(vapour_above_ambient_message(vapour_pa, *p, times_s[i]));
        }
        let saturation = Saturation {
            gas: gas[0],
            ambient_pa: ambient_pa[0],
        };
        Ok(PressureHistory {
            times_s,
            ambient_pa,
            gas,
            vapour_pa,
            label: label.into(),
            inert_only: false,
            saturation,
        })
    }

    /// A history with one gas on every segment.
    pub fn with_gas(
        label: impl Into<String>,
        times_s: Vec<f64>,
        ambient_pa: Vec<f64>,
        gas: GasMix,
        vapour_pa: f64,
    ) -> Result<Self, String> {
        let n = (times_s.len().max(2)) - 1;
        Self::new(label, times_s, ambient_pa, vec![gas; n], vapour_pa)
    }

    /// End time, s.
    pub fn duration_s(&self) -> f64 {
        *self.times_s.last().unwrap()
    }

    /// Index of the segment containing `t` (clamped to the first/last segment).
    pub fn segment(&self, t: f64) -> usize {
        if self.times_s.len() < 2 {
            return 0;
        }
        let k = self.times_s.partition_point(|&x| x <= t);
        k.saturating_sub(1).min(self.times_s.len() - 2)
    }

    /// Ambient pressure at `t`, Pa (linear between breakpoints, held beyond the ends).
    pub fn ambient(&self, t: f64) -> f64 {
        if self.times_s.len() < 2 || t <= 0.0 {
            return self.ambient_pa[0];
        }
        if t >= self.duration_s() {
            return *self.ambient_pa.last().unwrap();
        }
        let i = self.segment(t);
        let (t0, t1) = (self.times_s[i], self.times_s[i + 1]);
        let (p0, p1) = (self.ambient_pa[i], self.ambient_pa[i + 1]);
        p0 + (p1 - p0) * (t - t0) / (t1 - t0)
    }

    /// dP/dt on the segment containing `t`, Pa/s (0 beyond the ends).
    pub fn rate(&self, t: f64) -> f64 {
        if self.times_s.len() < 2 || t < 0.0 || t >= self.duration_s() {
            return 0.0;
        }
        let i = self.segment(t);
        (self.ambient_pa[i + 1] - self.ambient_pa[i]) / (self.times_s[i + 1] - self.times_s[i])
    }

    /// Gas in force at `t`.
    pub fn gas_at(&self, t: f64) -> GasMix {
        self.gas[self.segment(t).min(self.gas.len() - 1)]
    }

    /// Partial pressure of `gas` that the open faces are in equilibrium with at `t`, Pa:
    /// fraction × (ambient − water vapour).
    /// With [`PressureHistory::inert_only`], O2 gives 0.
    pub fn inspired_partial_pressure(&self, gas: Gas, t: f64) -> f64 {
        if self.inert_only && gas == Gas::O2 {
            return 0.0;
        }
        self.gas_at(t).fraction(gas) * (self.ambient(t) - self.vapour_pa).max(0.0)
    }

    /// The segment a time step [t0, t1] lies in: the one holding its midpoint. The time loop
    /// never steps across a breakpoint, so a step that ends on a gas switch belongs to the
    /// segment before it, and one that starts there to the segment after it.
    pub fn step_segment(&self, t0: f64, t1: f64) -> usize {
        self.segment(0.5 * (t0 + t1))
    }

    /// [`Self::inspired_partial_pressure`] with the gas of segment `seg` and the ambient
    /// pressure at `t`: the open faces' value at a time `t` of a step in segment `seg`
    /// ([`Self::step_segment`]), so that the step ending on a gas switch keeps the gas it was
    /// breathed with up to its end.
    pub fn inspired_partial_pressure_on(&self, gas: Gas, seg: usize, t: f64) -> f64 {
        if self.inert_only && gas == Gas::O2 {
            return 0.0;
        }
        self.gas[seg.min(self.gas.len() - 1)].fraction(gas)
            * (self.ambient(t) - self.vapour_pa).max(0.0)
    }

    /// Partial pressure of `gas` the phantom is saturated with at t = 0, Pa
    /// ([`Saturation`]): fraction × (saturation pressure − water vapour); with
    /// [`PressureHistory::inert_only`], O2 gives 0.
    pub fn saturation_partial_pressure(&self, gas: Gas) -> f64 {
        if self.inert_only && gas == Gas::O2 {
            return 0.0;
        }
        self.saturation.gas.fraction(gas) * (self.saturation.ambient_pa - self.vapour_pa).max(0.0)
    }

    /// First breakpoint strictly after `t` (or the end time).
    pub fn next_breakpoint(&self, t: f64) -> f64 {
        let k = self.times_s.partition_point(|&x| x <= t + 1e-12);
        if k < self.times_s.len() {
            self.times_s[k]
        } else {
            self.duration_s()
        }
    }

    /// When the history last arrived at its final pressure (for a dive: the time of surfacing,
    /// whatever time at the surface follows), s: the first breakpoint of the trailing run of
    /// breakpoints within 1 Pa of the last one.
    pub fn final_arrival_s(&self) -> f64 {
        let last = *self.ambient_pa.last().unwrap();
        let mut i = self.ambient_pa.len() - 1;
        while i > 0 && (self.ambient_pa[i - 1] - last).abs() <= 1.0 {
            i -= 1;
        }
        self.times_s[i]
    }

    /// Every gas that appears on any segment or in the [`Saturation`], in [`Gas::ALL`] order
    /// (without O2 when [`PressureHistory::inert_only`]).
    pub fn gases(&self) -> Vec<Gas> {
        Gas::ALL
            .into_iter()
            .filter(|g| !(self.inert_only && *g == Gas::O2))
            .filter(|g| {
                self.saturation.gas.fraction(*g) > 0.0
                    || self.gas.iter().any(|m| m.fraction(*g) > 0.0)
            })
            .collect()
    }

    /// Append another history after this one (repetitive dives, surface intervals);
    /// `other` must start at the pressure this one ends at.
    pub fn then(mut self, other: &PressureHistory) -> Result<Self, String> {
        let end = self.duration_s();
        if end + other.duration_s() > MAX_DURATION_S {
            return Err(duration_message(end + other.duration_s()));
        }
        if self.times_s.len() + other.times_s.len() > MAX_BREAKPOINTS {
            return Err(format!(
                "{} breakpoints is too many (limit {MAX_BREAKPOINTS})",
                self.times_s.len() + other.times_s.len()
            ));
        }
        if (other.ambient_pa[0] - *self.ambient_pa.last().unwrap()).abs() > 1.0 {
            return Err(
                "the appended profile must start at the pressure the first one ends at".into(),
            );
        }
        if self.times_s.len() == 1 {
            self.gas.clear();
        }
        for i in 1..other.times_s.len() {
            self.times_s.push(end + other.times_s[i]);
            self.ambient_pa.push(other.ambient_pa[i]);
            self.gas.push(other.gas[i - 1]);
        }
        if self.gas.is_empty() {
            self.gas.push(other.gas[0]);
        }
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn final_arrival_is_the_time_of_surfacing() {
        // descent, bottom, ascent to the surface at 30 s, then surface time to 90 s
        let h = PressureHistory::with_gas(
            "t",
            vec![0.0, 5.0, 20.0, 30.0, 60.0, 90.0],
            vec![1e5, 3e5, 3e5, 1e5, 1e5, 1e5],
            GasMix::AIR,
            0.0,
        )
        .unwrap();
        assert_eq!(h.final_arrival_s(), 30.0);
    }

    #[test]
    fn a_step_ending_on_a_switch_keeps_its_segments_gas() {
        // air to 100 s, oxygen after, at a constant 2 bar
        let h = PressureHistory::new(
            "t",
            vec![0.0, 100.0, 200.0],
            vec![2e5; 3],
            vec![GasMix::AIR, GasMix::new(1.0, 0.0).unwrap()],
            0.0,
        )
        .unwrap();
        // the step [80, 100] is in the air segment, [100, 120] in the oxygen one
        assert_eq!(h.step_segment(80.0, 100.0), 0);
        assert_eq!(h.step_segment(100.0, 120.0), 1);
        let seg = h.step_segment(80.0, 100.0);
        assert!((h.inspired_partial_pressure_on(Gas::N2, seg, 100.0) - 0.79 * 2e5).abs() < 1e-6);
        // what the faces took before the fix at the step's end: the next segment's gas
        assert_eq!(h.inspired_partial_pressure(Gas::N2, 100.0), 0.0);
    }

    #[test]
    fn pressures_below_1_kpa_and_vapour_at_ambient_are_refused() {
        let h = |p: f64, vapour: f64| {
            PressureHistory::with_gas("t", vec![0.0, 10.0], vec![1e5, p], GasMix::AIR, vapour)
        };
        assert!(h(MIN_AMBIENT_PA, 0.0).is_ok());
        assert!(h(999.0, 0.0).unwrap_err().contains("below the accepted"));
        assert!(h(1e-10, 0.0).is_err());
        assert!(h(2e4, 6270.0).is_ok());
        assert!(h(2e4, 2e4).unwrap_err().contains("not below the ambient"));
    }

    #[test]
    fn interpolates_and_rejects_non_monotone() {
        let h = PressureHistory::with_gas(
            "t",
            vec![0.0, 10.0, 20.0],
            vec![1e5, 2e5, 2e5],
            GasMix::AIR,
            0.0,
        )
        .unwrap();
        assert!((h.ambient(5.0) - 1.5e5).abs() < 1e-9);
        assert!((h.rate(5.0) - 1e4).abs() < 1e-9);
        assert_eq!(h.rate(15.0), 0.0);
        assert_eq!(h.next_breakpoint(0.0), 10.0);
        assert_eq!(h.next_breakpoint(10.0), 20.0);
        assert!(PressureHistory::with_gas(
            "t",
            vec![0.0, 10.0, 5.0],
            vec![1e5; 3],
            GasMix::AIR,
            0.0
        )
        .is_err());
    }
}
