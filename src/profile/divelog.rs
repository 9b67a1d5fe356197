//! Import logged or planned dives from Subsurface XML (v1–v3) and UDDF (2.x, 3.x), following
//! the research notes in `shared/dive-files/FORMATS.md`.
//!
//! Every file becomes a list of [`ImportedDive`]s (depth samples, gases, gas switches, surface
//! pressure, water density, what was defaulted and why); [`ImportedDive::history`] turns one
//! into a [`PressureHistory`]: ambient = surface pressure + depth · ρ · g (g = standard gravity,
//! [`STANDARD_GRAVITY`]), piecewise linear between samples as both formats define it.
//!
//! Rules (FORMATS.md §0 and the quirks listed there):
//! - Elements and attributes are matched by lower-cased local name (namespaces, prefixes and
//!   upper-case `UDDF` roots are ignored), children by name, never by position; unknown
//!   elements are skipped. Numbers may carry exponents or decimal commas, and units: depths
//!   `m` (or none) or `ft`; pressures `bar` (or none in Subsurface XML, Pa in UDDF), `mbar`,
//!   `hPa`, `kPa`, `Pa`, `psi`, `atm`; densities `g/l`, `kg/m3`; UDDF times `s` (or none),
//!   `min`, `h`. Any other unit, or a value that is there but not a finite
//!   number (an empty UDDF `<depth>`), is refused naming its line and field.
//! - Samples are sorted by time (samples out of time order are noted with the line of the
//!   first), duplicate times merged (the last wins, noted), negative depths down to
//!   −[`SURFACE_NOISE_DEPTH_M`] (−1 m, sensor noise at the surface) clamped to 0 (noted) and
//!   deeper negative ones refused naming the sample's line and time; a sample or waypoint without a time or a depth is skipped (noted with its line);
//!   if the first sample is not at time 0, a surface point (0 s, 0 m) is prepended (recorded in
//!   [`ImportedDive::notes`]). A dive whose first sample lies deeper than
//!   [`FIRST_SAMPLE_DEPTH_M`] (3 m) at time 0, or that changes depth between two samples
//!   (the prepended point included) faster than [`MAX_LOGGED_RATE_M_MIN`] (600 m/min), is
//!   refused naming the dive, the sample's line, time and depth; changes faster than the
//!   schedules' 100 m/min are read and noted with the fastest.
//! - Surface pressure and water density are taken from the file when present and plausible
//!   (0.5–1.1 bar, 990–1040 kg/m³), else 101 325 Pa and 1030 kg/m³ (Subsurface's sea-water
//!   default), noted. A UDDF altitude without a surface pressure gives the ISA pressure.
//! - Gas fractions above 1 are percent. A Subsurface cylinder without `o2` is air; a UDDF file
//!   without `<gasdefinitions>` breathes air (UDDF spec). N2 is the balance.
//! - Closed-circuit dives (Subsurface `dctype`, UDDF `divemode`) are read, flagged, and refused
//!   by [`ImportedDive::history`]: their inspired gas depends on the set-point.
//! - Only the first `<divecomputer>` of a Subsurface dive is used (its primary computer).

use std::path::Path;

use quick_xml::events::Event;

use super::PressureHistory;
use crate::error::InputError;
use crate::gas::GasMix;
use crate::units::{ATM_PA, BAR_PA, PSI_PA, STANDARD_GRAVITY};

/// Default water density, kg/m³ (Subsurface's sea-water default, `core/dive.cpp`, per FORMATS.md §2.6).
pub const DEFAULT_DENSITY_KG_M3: f64 = 1030.0;
/// Plausible surface pressures, Pa (FORMATS.md §0.4: 0.5–1.1 bar).
const SURFACE_RANGE: (f64, f64) = (0.5e5, 1.1e5);
/// Plausible water densities, kg/m³ (FORMATS.md §0.4).
const DENSITY_RANGE: (f64, f64) = (990.0, 1040.0);

/// The file format a dive came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Subsurface XML (`<divelog>` v2/v3 or legacy `<dives>` v1).
    Subsurface,
    /// UDDF (`<uddf>`), any version.
    Uddf,
}

/// One dive read from a log file.
#[derive(Debug, Clone, PartialEq)]
pub struct ImportedDive {
    /// `<file stem> #<n> <start>`.
    pub label: String,
    /// Format of the source file.
    pub format: Format,
    /// Start date-time as written (`2017-02-03 06:58:00`, `2009-10-22T15:32:43`), if any.
    pub start: Option<String>,
    /// Dive number from the file, if any.
    pub number: Option<String>,
    /// A planned dive (Subsurface `model='planned dive'`).
    pub planned: bool,
    /// A closed- or semi-closed-circuit dive (not supported by [`ImportedDive::history`]).
    pub closed_circuit: bool,
    /// Surface pressure, Pa.
    pub surface_pa: f64,
    /// Water density, kg/m³.
    pub density_kg_m3: f64,
    /// Breathing gases in file order (Subsurface cylinders, UDDF mixes).
    pub gases: Vec<GasMix>,
    /// Index into `gases` of the gas at the start.
    pub initial_gas: usize,
    /// Gas switches after the start: (time s, index into `gases`), increasing in time.
    pub switches: Vec<(f64, usize)>,
    /// Normalised samples (time s, depth m): from time 0, strictly increasing times.
    pub samples: Vec<(f64, f64)>,
    /// Maximum depth stated in the file's summary, m (may differ from the samples').
    pub stated_max_depth_m: Option<f64>,
    /// Duration stated in the file's summary, s (usually shorter than the samples' span).
    pub stated_duration_s: Option<f64>,
    /// What was assumed or repaired while reading (defaults, prepended surface point, …).
    pub notes: Vec<String>,
    /// 1-based line of the dive's element in the file (for errors about the dive as a whole).
    pub line: usize,
}

impl ImportedDive {
    /// Deepest sample, m.
    pub fn max_depth_m(&self) -> f64 {
        self.samples.iter().map(|s| s.1).fold(0.0, f64::max)
    }

    /// Time of the last sample, s.
    pub fn duration_s(&self) -> f64 {
        self.samples.last().map(|s| s.0).unwrap_or(0.0)
    }

    /// Ambient pressure at a depth, Pa: surface + depth · ρ · g.
    pub fn ambient_pa(&self, depth_m: f64) -> f64 {
        self.surface_pa + depth_m * self.density_kg_m3 * STANDARD_GRAVITY
    }

    /// The gas breathed at time `t` (s).
    pub fn gas_at(&self, t: f64) -> GasMix {
        let idx = self
            .switches
            .iter()
            .rev()
            .find(|s| s.0 <= t)
            .map(|s| s.1)
            .unwrap_or(self.initial_gas);
        self.gases[idx]
    }

    /// The dive as a pressure history (breakpoints at every sample and gas switch);
    /// `vapour_pa` is the water-vapour pressure subtracted at the open faces (e.g. 6 270 Pa
    /// alveolar for a breathed gas). The phantom starts saturated with air at the dive's
    /// surface pressure ([`crate::profile::Saturation`]), whatever the first gas. Closed-circuit
    /// dives are refused.
    pub fn history(&self, vapour_pa: f64) -> Result<PressureHistory, InputError> {
        if self.closed_circuit {
            let field = match self.format {
                Format::Subsurface => "divecomputer.dctype",
                Format::Uddf => "divemode",
            };
            return Err(InputError::new(format!(
                "dive '{}' is a closed-circuit (rebreather) dive: its inspired gas depends on the set-point, which decophantom does not model; choose an open-circuit dive"
            , self.label)).at_line(self.line).field(field));
        }
        let mut times: Vec<f64> = self.samples.iter().map(|s| s.0).collect();
        let mut depths: Vec<f64> = self.samples.iter().map(|s| s.1).collect();
        for &(t, _) in &self.switches {
            let k = times.partition_point(|&x| x < t);
            if k < times.len() && times[k] == t || k == 0 || k >= times.len() {
                continue;
            }
            let f = (t - times[k - 1]) / (times[k] - times[k - 1]);
            let d = depths[k - 1] + f * (depths[k] - depths[k - 1]);
            times.insert(k, t);
            depths.insert(k, d);
        }
        let nseg = times.len().max(2) - 1;
        let gas: Vec<GasMix> = (0..nseg).map(|i| self.gas_at(times[i])).collect();
        let ambient = depths.iter().map(|&d| self.ambient_pa(d)).collect();
        let mut h = PressureHistory::new(self.label.clone(), times, ambient, gas, vapour_pa)
            .map_err(|e| {
                InputError::new(format!("dive '{}': {e}", self.label)).at_line(self.line)
            })?;
        h.saturation = crate::profile::Saturation {
            gas: GasMix::AIR,
            ambient_pa: self.surface_pa,
        };
        Ok(h)
    }
}

/// Read every dive in a Subsurface XML or UDDF file; any dive the reader refuses is an error
/// ([`read_each`] keeps the others).
pub fn read(path: &Path) -> Result<Vec<ImportedDive>, InputError> {
    read_each(path)?.into_iter().collect()
}

/// Parse dive-log text; `path` names the file in errors and labels. Any dive the reader
/// refuses is an error ([`parse_each`] keeps the others).
pub fn parse(text: &str, path: &Path) -> Result<Vec<ImportedDive>, InputError> {
    parse_each(text, path)?.into_iter().collect()
}

/// Read a Subsurface XML or UDDF file, each dive on its own: the outer error is the file's
/// (unreadable, not a dive log, no dive with depth samples), an inner one that dive's (a sample
/// refused), so one bad dive in a logbook of many does not keep the others from being run.
pub fn read_each(path: &Path) -> Result<Vec<Result<ImportedDive, InputError>>, InputError> {
    let bytes = crate::error::read_input(path, "the dive log")?;
    let text = String::from_utf8_lossy(&bytes);
    parse_each(&text, path)
}

/// [`read_each`] on text; `path` names the file in errors and labels.
pub fn parse_each(
    text: &str,
    path: &Path,
) -> Result<Vec<Result<ImportedDive, InputError>>, InputError> {
    let root = parse_xml(text, path)?;
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "dive".into());
    let cx = Cx { text, path, stem };
    let dives = match root.name.as_str() {
        "divelog" | "dives" => subsurface(&root, &cx)?,
        "uddf" => uddf(&root, &cx)?,
        other => {
            return Err(InputError::new(format!(
                "root element <{other}> is neither Subsurface XML (<divelog> or <dives>) nor UDDF (<uddf>)"
            ))
            .in_file(path)
            .at_line(1))
        }
    };
    if dives.is_empty() {
        return Err(InputError::new("the file holds no dive with depth samples")
            .in_file(path)
            .at_line(line_at(text, root.offset))
            .field("dive"));
    }
    Ok(dives)
}

/// Shared context for error messages.
struct Cx<'a> {
    text: &'a str,
    path: &'a Path,
    stem: String,
}

impl Cx<'_> {
    fn err(&self, node: &Node, field: &str, msg: impl Into<String>) -> InputError {
        InputError::new(msg)
            .in_file(self.path)
            .at_line(line_at(self.text, node.offset))
            .field(field)
    }
}

fn line_at(text: &str, offset: usize) -> usize {
    let end = offset.min(text.len());
    let end = (0..=end)
        .rev()
        .find(|&i| text.is_char_boundary(i))
        .unwrap_or(0);
    text[..end].matches('\n').count() + 1
}

// ---------------------------------------------------------------------------------------------
// A minimal element tree (lower-cased local names), enough for both formats.

#[derive(Debug, Default)]
struct Node {
    name: String,
    attrs: Vec<(String, String)>,
    text: String,
    children: Vec<Node>,
    offset: usize,
}

impl Node {
    fn attr(&self, key: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }
    fn child(&self, name: &str) -> Option<&Node> {
        self.children.iter().find(|c| c.name == name)
    }
    fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Node> + 'a {
        self.children.iter().filter(move |c| c.name == name)
    }
    /// Descendants named `name` in document order, not descending into matches.
    fn find_all<'a>(&'a self, name: &str, out: &mut Vec<&'a Node>) {
        for c in &self.children {
            if c.name == name {
                out.push(c);
            } else {
                c.find_all(name, out);
            }
        }
    }
    fn text_of(&self, name: &str) -> Option<&str> {
        self.child_with_text(name).map(|c| c.text.trim())
    }
    /// The first child `name` if it holds some text.
    fn child_with_text(&self, name: &str) -> Option<&Node> {
        self.child(name).filter(|c| !c.text.trim().is_empty())
    }
}

fn local_lower(qname: &[u8]) -> String {
    let s = String::from_utf8_lossy(qname);
    s.rsplit(':').next().unwrap_or("").to_ascii_lowercase()
}

fn parse_xml(text: &str, path: &Path) -> Result<Node, InputError> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut stack: Vec<Node> = vec![Node::default()];
    let xml_err = |pos: u64, e: String| {
        InputError::new(format!("not well-formed XML: {e}"))
            .in_file(path)
            .at_line(line_at(text, pos as usize))
    };
    loop {
        let pos = reader.buffer_position();
        let ev = reader
            .read_event()
            .map_err(|e| xml_err(reader.error_position(), e.to_string()))?;
        match ev {
            Event::Start(ref e) | Event::Empty(ref e) => {
                let mut node = Node {
                    name: local_lower(e.name().as_ref()),
                    offset: pos as usize,
                    ..Node::default()
                };
                for a in e.attributes().with_checks(false).flatten() {
                    let v = a
                        .normalized_value(quick_xml::XmlVersion::Implicit1_0)
                        .map(|c| c.into_owned())
                        .unwrap_or_else(|_| String::from_utf8_lossy(&a.value).into_owned());
                    node.attrs.push((local_lower(a.key.as_ref()), v));
                }
                if matches!(ev, Event::Empty(_)) {
                    stack.last_mut().expect("root").children.push(node);
                } else {
                    stack.push(node);
                }
            }
            Event::End(_) => {
                if stack.len() < 2 {
                    return Err(xml_err(pos, "unexpected closing tag".into()));
                }
                let node = stack.pop().expect("checked");
                stack.last_mut().expect("root").children.push(node);
            }
            Event::Text(t) => {
                let s = t.decode().map_err(|e| xml_err(pos, e.to_string()))?;
                stack.last_mut().expect("root").text.push_str(&s);
            }
            Event::CData(t) => {
                let s = t.decode().map_err(|e| xml_err(pos, e.to_string()))?;
                stack.last_mut().expect("root").text.push_str(&s);
            }
            Event::GeneralRef(r) => {
                let c = if r.is_char_ref() {
                    r.resolve_char_ref().ok().flatten()
                } else {
                    match r
                        .decode()
                        .map(|s| s.into_owned())
                        .unwrap_or_default()
                        .as_str()
                    {
                        "amp" => Some('&'),
                        "lt" => Some('<'),
                        "gt" => Some('>'),
                        "quot" => Some('"'),
                        "apos" => Some('\''),
                        _ => None,
                    }
                };
                if let Some(c) = c {
                    stack.last_mut().expect("root").text.push(c);
                }
            }
            Event::Eof => break,
            // Declarations, comments, processing instructions and DOCTYPEs carry nothing we
            // use; entities declared in a DOCTYPE are never expanded.
            _ => {}
        }
    }
    if stack.len() != 1 {
        return Err(xml_err(
            text.len() as u64,
            format!(
                "<{}> is never closed",
                stack.last().map(|n| n.name.as_str()).unwrap_or("")
            ),
        ));
    }
    let doc = stack.pop().expect("root");
    doc.children.into_iter().next().ok_or_else(|| {
        InputError::new("the file holds no XML element")
            .in_file(path)
            .at_line(crate::error::last_line(text))
    })
}

// ---------------------------------------------------------------------------------------------
// Values.

/// A number from text that may carry a unit suffix, a `%`, an exponent or a decimal comma.
fn num(s: &str) -> Option<f64> {
    let tok = s.split_whitespace().next()?;
    let tok = tok.trim_end_matches('%').replace(',', ".");
    let tok = tok.trim_end_matches(|c: char| c.is_ascii_alphabetic() && c != 'e' && c != 'E');
    tok.parse::<f64>().ok().filter(|v| v.is_finite())
}

/// What a dive-log number with a unit measures ([`measure`]).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Quantity {
    /// A depth, m: `m` (or no unit), `ft`.
    Length,
    /// A pressure, Pa: `Pa`, `hPa`, `mbar`, `kPa`, `bar`, `psi`, `atm`; a bare number is in
    /// `bare_pa` Pa per unit (bar in Subsurface XML, Pa in UDDF).
    Pressure { bare_pa: f64 },
    /// A water density or Subsurface salinity, kg/m³: `g/l`, `kg/m3` (or no unit).
    Density,
    /// A UDDF time, s: `s` (or no unit), `min`, `h`.
    Time,
}

/// The units [`measure`] converts, for messages.
fn known_units(q: Quantity) -> &'static str {
    match q {
        Quantity::Length => "m or ft",
        Quantity::Pressure { .. } => "Pa, hPa, mbar, kPa, bar, psi or atm",
        Quantity::Density => "g/l or kg/m3",
        Quantity::Time => "s, min or h",
    }
}

/// A number with an optional unit (`'21.1 m'`, `'69 ft'`, `'1012 mbar'`, `'30.0m'`, `'1,5'`),
/// converted to SI (m, Pa, kg/m³, s). A unit decophantom does not know (`'21.1 furlong'`) is
/// refused rather than read as the default one; the message says what was found.
fn measure(s: &str, q: Quantity) -> Result<f64, String> {
    let t = s.trim();
    // the number: up to the last digit, decimal point or comma before the unit
    let end = t
        .char_indices()
        .take_while(|(_, c)| c.is_ascii_digit() || matches!(c, '.' | ',' | '+' | '-' | 'e' | 'E'))
        .map(|(i, c)| i + c.len_utf8())
        .last()
        .unwrap_or(0);
    // an exponent marker without digits after it belongs to the unit (none starts with e)
    let end = t[..end].trim_end_matches(['e', 'E', '+', '-']).len();
    let (number, unit) = (t[..end].replace(',', "."), t[end..].trim());
    let Some(v) = number.parse::<f64>().ok().filter(|v| v.is_finite()) else {
        return Err(format!("'{s}' is not a finite number"));
    };
    let factor = match (q, unit) {
        (Quantity::Length, "" | "m") => 1.0,
        (Quantity::Length, "ft") => 0.3048,
        (Quantity::Pressure { bare_pa }, "") => bare_pa,
        (Quantity::Pressure { .. }, "Pa" | "pa") => 1.0,
        (Quantity::Pressure { .. }, "hPa" | "hpa" | "mbar") => 100.0,
        (Quantity::Pressure { .. }, "kPa" | "kpa") => 1000.0,
        (Quantity::Pressure { .. }, "bar") => BAR_PA,
        (Quantity::Pressure { .. }, "psi") => PSI_PA,
        (Quantity::Pressure { .. }, "atm") => ATM_PA,
        (Quantity::Density, "" | "g/l" | "g/L" | "kg/m3" | "kg/m³") => 1.0,
        (Quantity::Time, "" | "s") => 1.0,
        (Quantity::Time, "min") => 60.0,
        (Quantity::Time, "h") => 3600.0,
        _ => {
            return Err(format!(
                "'{s}' has the unit '{unit}', which decophantom does not read here; write the value in {}",
                known_units(q)
            ))
        }
    };
    Ok(v * factor)
}

/// A gas fraction: `31.0%` or `31` (> 1: percent) or `0.31`.
fn fraction(s: &str) -> Option<f64> {
    let v = num(s)?;
    Some(if s.trim().ends_with('%') || v > 1.0 {
        v / 100.0
    } else {
        v
    })
}

/// A Subsurface time: `m:ss min`, `h:mm:ss`, or plain seconds.
fn time_s(s: &str) -> Option<f64> {
    let tok = s.split_whitespace().next()?;
    if tok.contains(':') {
        let parts: Vec<f64> = tok
            .split(':')
            .map(|p| p.parse::<f64>().ok())
            .collect::<Option<_>>()?;
        return match parts.as_slice() {
            [m, s] => Some(m * 60.0 + s),
            [h, m, s] => Some(h * 3600.0 + m * 60.0 + s),
            _ => None,
        }
        .filter(|v| v.is_finite());
    }
    num(tok)
}

/// Standard-atmosphere pressure at an altitude, Pa (ICAO/ISA troposphere:
/// p = 101325 (1 − 2.25577e-5 h)^5.25588).
pub fn isa_pressure_pa(altitude_m: f64) -> f64 {
    ATM_PA * (1.0 - 2.255_77e-5 * altitude_m).powf(5.255_88)
}

fn mix(o2: Option<f64>, he: Option<f64>) -> Result<GasMix, String> {
    match o2 {
        None => Ok(GasMix::AIR),
        Some(o) => GasMix::new(o, he.unwrap_or(0.0)),
    }
}

/// Check surface pressure and density, defaulting implausible or missing values with a note.
fn environment(surface: Option<f64>, density: Option<f64>, notes: &mut Vec<String>) -> (f64, f64) {
    let s = match surface {
        Some(p) if (SURFACE_RANGE.0..=SURFACE_RANGE.1).contains(&p) => p,
        Some(p) => {
            notes.push(format!(
                "surface pressure {p} Pa is implausible (outside 0.5–1.1 bar); used {ATM_PA} Pa"
            ));
            ATM_PA
        }
        None => {
            notes.push(format!("no surface pressure in the file; used {ATM_PA} Pa"));
            ATM_PA
        }
    };
    let d = match density {
        Some(r) if (DENSITY_RANGE.0..=DENSITY_RANGE.1).contains(&r) => r,
        Some(r) => {
            notes.push(format!(
                "water density {r} kg/m³ is implausible (outside 990–1040); used {DEFAULT_DENSITY_KG_M3}"
            ));
            DEFAULT_DENSITY_KG_M3
        }
        None => {
            notes.push(format!(
                "no water density in the file; used {DEFAULT_DENSITY_KG_M3} kg/m³ (sea water)"
            ));
            DEFAULT_DENSITY_KG_M3
        }
    };
    (s, d)
}

/// Most a depth may lie above the surface and still be read as the surface, m: a depth
/// sensor's noise and its zeroing against the surface pressure give a few tens of centimetres
/// either side of 0 (hence the clamp); a metre covers that with margin. A sample further above
/// the surface is not noise but an error of the log (a sign, an offset, a pressure read as a
/// depth), and setting it to 0 m mid-dive would move the results, so it is refused.
pub const SURFACE_NOISE_DEPTH_M: f64 = 1.0;

/// A sample's time within the 30-day limit and its depth within the accepted ambient
/// pressure and not above the surface by more than [`SURFACE_NOISE_DEPTH_M`], refused naming
/// the sample's line and field.
fn check_sample(
    cx: &Cx,
    node: &Node,
    (t_field, t): (&str, f64),
    (d_field, d): (&str, f64),
    surface_pa: f64,
    density: f64,
) -> Result<(), InputError> {
    if t > super::MAX_DURATION_S {
        return Err(cx.err(node, t_field, super::duration_message(t)));
    }
    if d < -SURFACE_NOISE_DEPTH_M {
        return Err(cx.err(
            node,
            d_field,
            format!(
                "depth {} m at {} s is above the surface by more than the {SURFACE_NOISE_DEPTH_M} m of sensor noise read as 0 m; correct or remove the sample (a depth is positive downwards)",
                crate::error::num(d),
                crate::error::num(t)
            ),
        ));
    }
    let p = surface_pa + d.max(0.0) * density * STANDARD_GRAVITY;
    if p > super::MAX_AMBIENT_PA {
        return Err(cx.err(
            node,
            d_field,
            format!(
                "depth {} m is {} Pa absolute, above the accepted {:e} Pa (200 bar, about 2 000 m of sea water)",
                crate::error::num(d),
                crate::error::num(p),
                super::MAX_AMBIENT_PA
            ),
        ));
    }
    Ok(())
}

/// Samples left out because they lack a time or a depth (Subsurface writes both on every
/// sample; a UDDF waypoint carries both): counted, with the line of the first, for a note.
#[derive(Debug, Default)]
struct Skipped {
    count: usize,
    first_offset: Option<usize>,
}

impl Skipped {
    fn add(&mut self, node: &Node) {
        self.count += 1;
        self.first_offset.get_or_insert(node.offset);
    }
    fn note(&self, cx: &Cx, what: &str, notes: &mut Vec<String>) {
        if let Some(off) = self.first_offset {
            notes.push(format!(
                "{} {what} skipped (the first on line {})",
                self.count,
                line_at(cx.text, off)
            ));
        }
    }
}

/// Deepest a dive's first sample may lie when it is at time 0, m. A dive computer starts a dive
/// when it passes its start depth, about 1–1.5 m, and its first sample may lie a second or two
/// of descent deeper: the first samples of the real logs in `../shared/dive-files` lie at
/// 2.335–2.68 m (Subsurface's `test40-42.xml`, `ostc.xml`). Deeper at time 0 the descent was
/// not logged, and the history would compress the phantom from the surface in no time: refused.
pub const FIRST_SAMPLE_DEPTH_M: f64 = 3.0;

/// Fastest change of depth accepted between two consecutive samples of a dive log, m/min
/// (10 m/s): faster than a diver moves, so a sensor glitch, a time in the wrong unit or a
/// missed descent, refused naming the sample. It
/// lies well above the fastest change in the real logs of `../shared/dive-files`, 210 m/min
/// (`kenozooid__ostc-dump-02.uddf` dive 2: 8 m at 10 s to 43 m at 20 s); the project's own logs
/// reach 63.15 m/min (`tests/data/divelogs/repetitive-logged.xml` dive 2, from the prepended
/// surface point). Changes faster than the schedules' [`MAX_TRAVEL_RATE_M_MIN`] but within this
/// are read, and noted.
///
/// [`MAX_TRAVEL_RATE_M_MIN`]: crate::algorithm::conventions::MAX_TRAVEL_RATE_M_MIN
pub const MAX_LOGGED_RATE_M_MIN: f64 = 600.0;

/// Sort (noting samples earlier than the one before them, with the line of the first),
/// merge duplicate times (last wins), clamp negative depths (at most
/// [`SURFACE_NOISE_DEPTH_M`] above the surface: [`check_sample`] refuses the others), prepend
/// the surface, and check the rates between samples ([`FIRST_SAMPLE_DEPTH_M`],
/// [`MAX_LOGGED_RATE_M_MIN`]). Refusals name dive `number` (1-based, as `--dive`), the sample's
/// line and `depth_field`.
fn normalise(
    mut samples: Vec<(f64, f64, usize)>,
    cx: &Cx,
    (dive, number, depth_field): (&Node, usize, &str),
    notes: &mut Vec<String>,
) -> Result<Vec<(f64, f64)>, InputError> {
    if let Some(&(t, _, off)) = samples.iter().find(|s| s.0 < 0.0) {
        return Err(InputError::new(format!(
            "sample at negative time {t} s; dive times start at 0"
        ))
        .in_file(cx.path)
        .at_line(line_at(cx.text, off))
        .field("time"));
    }
    // a sample earlier than the latest one before it in the file: the log is out of order
    let mut latest = f64::NEG_INFINITY;
    let mut unsorted = 0;
    let mut first_unsorted = None;
    for &(t, _, off) in &samples {
        if t < latest {
            unsorted += 1;
            first_unsorted.get_or_insert((t, latest, off));
        }
        latest = latest.max(t);
    }
    if let Some((t, before, off)) = first_unsorted {
        notes.push(format!(
            "{unsorted} sample(s) out of time order (the first on line {}: {} s after {} s); sorted by time",
            line_at(cx.text, off),
            crate::error::num(t),
            crate::error::num(before)
        ));
    }
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(f64, f64, usize)> = Vec::with_capacity(samples.len());
    let mut merged = 0;
    let mut clamped = 0;
    for (t, d, off) in samples {
        let d = if d < 0.0 {
            clamped += 1;
            0.0
        } else {
            d
        };
        match out.last_mut() {
            Some(last) if last.0 == t => {
                *last = (t, d, off);
                merged += 1;
            }
            _ => out.push((t, d, off)),
        }
    }
    if merged > 0 {
        notes.push(format!(
            "{merged} sample(s) with a duplicate time merged (last kept)"
        ));
    }
    if clamped > 0 {
        notes.push(format!(
            "{clamped} negative depth(s) (within {SURFACE_NOISE_DEPTH_M} m of the surface: sensor noise) set to 0 m"
        ));
    }
    let refuse = |off: usize, msg: String| {
        InputError::new(format!("dive {number}: {msg}"))
            .in_file(cx.path)
            .at_line(line_at(cx.text, off))
            .field(depth_field)
    };
    let rate_text = crate::algorithm::schedule::rate_text;
    let n = crate::error::num;
    let mut prepended = false;
    match out.first() {
        None => {
            return Err(cx.err(
                dive,
                "samples",
                "the dive has no samples with both time and depth",
            ))
        }
        Some(&(t, d, off)) if t > 0.0 => {
            let rate = d / (t / 60.0);
            // within the start depth the first sample may come at any time, as at time 0
            if d > FIRST_SAMPLE_DEPTH_M && rate > MAX_LOGGED_RATE_M_MIN * (1.0 + 1e-9) {
                return Err(refuse(off, format!(
                    "the first sample is at {} m at {} s: reaching it from the surface takes {} m/min, faster than a diver moves (at most {MAX_LOGGED_RATE_M_MIN} m/min are accepted); the log misses the descent: add its samples or choose another dive",
                    n(d), n(t), rate_text(rate)
                )));
            }
            notes.push(if d > FIRST_SAMPLE_DEPTH_M {
                format!(
                    "first sample at {} s and {} m, deeper than the {FIRST_SAMPLE_DEPTH_M} m by which dive computers start recording: the descent was not logged; a surface point (0 s, 0 m) was prepended (a descent at {} m/min)",
                    n(t), n(d), rate_text(rate)
                )
            } else {
                format!("first sample at {t} s and {d} m; a surface point (0 s, 0 m) was prepended")
            });
            out.insert(0, (0.0, 0.0, off));
            prepended = true;
        }
        Some(&(_, d, off)) if d > FIRST_SAMPLE_DEPTH_M => {
            return Err(refuse(off, format!(
                "the dive starts at {} m at 0 s, deeper than the {FIRST_SAMPLE_DEPTH_M} m by which dive computers start recording: the descent was not logged, and the phantom would be compressed from the surface in no time; add the descent's samples (from 0 m at 0 s) or choose another dive",
                n(d)
            )));
        }
        Some(&(_, d, _)) if d > 0.0 => {
            notes.push(format!("the dive starts at {d} m (first sample at time 0)"));
        }
        _ => {}
    }
    // the rate between consecutive samples (times strictly increase after the merge); a
    // relative 1e-9 for times written in minutes, as for schedules
    // ([`crate::algorithm::schedule::too_fast`])
    let max_travel = crate::algorithm::conventions::MAX_TRAVEL_RATE_M_MIN;
    let mut fast = 0;
    let mut fastest: Option<(f64, usize)> = None;
    // the prepended surface point to a first sample within the start depth is not a rate
    let from = if prepended && out[1].1 <= FIRST_SAMPLE_DEPTH_M {
        2
    } else {
        1
    };
    for k in from..out.len() {
        let ((t0, d0, _), (t1, d1, off)) = (out[k - 1], out[k]);
        let rate = (d1 - d0).abs() / ((t1 - t0) / 60.0);
        if rate > MAX_LOGGED_RATE_M_MIN * (1.0 + 1e-9) {
            return Err(refuse(off, format!(
                "the depth goes from {} m at {} s to {} m at {} s, {} m/min: faster than a diver moves (at most {MAX_LOGGED_RATE_M_MIN} m/min are accepted); a sensor glitch or a wrong time: correct or remove the sample",
                n(d0), n(t0), n(d1), n(t1), rate_text(rate)
            )));
        }
        if crate::algorithm::schedule::too_fast(d1 - d0, t1 - t0).is_some() {
            fast += 1;
            if fastest.is_none_or(|(r, _)| rate > r) {
                fastest = Some((rate, k));
            }
        }
    }
    if let Some((rate, k)) = fastest {
        let ((t0, d0, _), (t1, d1, off)) = (out[k - 1], out[k]);
        notes.push(format!(
            "{fast} change(s) of depth faster than the {max_travel} m/min accepted in schedules, the fastest {} m/min ({} m at {} s to {} m at {} s, line {}): read as logged; check the log for a sensor glitch",
            rate_text(rate), n(d0), n(t0), n(d1), n(t1), line_at(cx.text, off)
        ));
    }
    Ok(out.into_iter().map(|(t, d, _)| (t, d)).collect())
}

/// Gas switches in time order; those at or before the first real sample set the initial gas.
fn settle_switches(
    mut events: Vec<(f64, usize)>,
    first_sample_s: f64,
    default_initial: usize,
) -> (usize, Vec<(f64, usize)>) {
    events.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut initial = default_initial;
    let mut switches: Vec<(f64, usize)> = Vec::new();
    for (t, g) in events {
        if t <= first_sample_s.max(1.0) {
            initial = g;
        } else if switches.last().map(|s| s.1).unwrap_or(initial) != g {
            match switches.last_mut() {
                Some(last) if last.0 == t => last.1 = g,
                _ => switches.push((t, g)),
            }
        }
    }
    (initial, switches)
}

// ---------------------------------------------------------------------------------------------
// Subsurface XML.

fn subsurface(root: &Node, cx: &Cx) -> Result<Vec<Result<ImportedDive, InputError>>, InputError> {
    let mut dive_nodes = Vec::new();
    root.find_all("dive", &mut dive_nodes);
    // each dive on its own: a dive the reader refuses is an error only where it is chosen
    let one = |n: usize, dive: &Node| -> Result<ImportedDive, InputError> {
        let mut notes = Vec::new();
        let mut gases = Vec::new();
        let mut diluent = None;
        for c in dive.children_named("cylinder") {
            let m = mix(
                c.attr("o2").and_then(fraction),
                c.attr("he").and_then(fraction),
            )
            .map_err(|e| cx.err(c, "cylinder", e))?;
            if diluent.is_none() && c.attr("use") == Some("diluent") {
                diluent = Some(gases.len());
            }
            gases.push(m);
        }
        if gases.is_empty() {
            notes.push("no cylinders; breathing air".into());
            gases.push(GasMix::AIR);
        }
        // The primary dive computer, or the dive itself in the v1 format.
        let dc = dive.child("divecomputer");
        let src = dc.unwrap_or(dive);
        let planned = dc.and_then(|d| d.attr("model")) == Some("planned dive");
        let closed_circuit = dc
            .and_then(|d| d.attr("dctype"))
            .is_some_and(|t| matches!(t.to_ascii_uppercase().as_str(), "CCR" | "PSCR"));
        // a value with a unit is converted (a bare number is in Subsurface's own unit: bar,
        // g/l); an unknown unit or an unreadable number is refused naming its line
        let read = |found: Option<(&Node, &str, &str)>, q: Quantity| {
            found
                .map(|(n, v, field)| measure(v, q).map_err(|m| cx.err(n, field, m)))
                .transpose()
        };
        let surface = read(
            attr_of(src.child("surface"), "pressure", "surface.pressure")
                .or_else(|| attr_of(Some(dive), "airpressure", "dive.airpressure")),
            Quantity::Pressure { bare_pa: BAR_PA },
        )?;
        let density = read(
            attr_of(src.child("water"), "salinity", "water.salinity")
                .or_else(|| attr_of(Some(dive), "watersalinity", "dive.watersalinity")),
            Quantity::Density,
        )?;
        let (surface_pa, density_kg_m3) = environment(surface, density, &mut notes);

        // a sample without a time or depth (temperature only) is skipped; one whose time or
        // depth is there but not a finite number is an error naming its line
        let mut raw: Vec<(f64, f64, usize)> = Vec::new();
        let mut skipped = Skipped::default();
        for s in src.children_named("sample") {
            let (Some(t), Some(d)) = (s.attr("time"), s.attr("depth")) else {
                skipped.add(s);
                continue;
            };
            let Some(t) = time_s(t) else {
                return Err(cx.err(s, "sample.time", format!("time '{t}' is not a finite time")));
            };
            let d = measure(d, Quantity::Length)
                .map_err(|m| cx.err(s, "sample.depth", format!("depth {m}")))?;
            check_sample(
                cx,
                s,
                ("sample.time", t),
                ("sample.depth", d),
                surface_pa,
                density_kg_m3,
            )?;
            raw.push((t, d, s.offset));
        }
        skipped.note(cx, "sample(s) without a time or a depth", &mut notes);
        let first_sample = raw.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
        let samples = normalise(raw, cx, (dive, n + 1, "sample.depth"), &mut notes)?;

        let mut events = Vec::new();
        for ev in src.children_named("event") {
            if ev.attr("name") != Some("gaschange") {
                continue;
            }
            let Some(t) = ev.attr("time").and_then(time_s) else {
                return Err(cx.err(ev, "event.time", "gas change without a readable time"));
            };
            let idx = match ev.attr("cylinder").and_then(num) {
                Some(c) if c >= 0.0 && (c as usize) < gases.len() => c as usize,
                _ => {
                    let o2 = ev.attr("o2").and_then(fraction);
                    let he = ev.attr("he").and_then(fraction);
                    let (target, he_known) = match (o2, ev.attr("value").and_then(num)) {
                        (Some(o), _) => (GasMix::new(o, he.unwrap_or(0.0)), true),
                        (None, Some(v)) => {
                            let v = v as u64;
                            let (o, h) = ((v & 0xffff) as f64 / 100.0, (v >> 16) as f64 / 100.0);
                            (GasMix::new(o, h), h > 0.0)
                        }
                        (None, None) => {
                            return Err(cx.err(
                                ev,
                                "event",
                                "gas change names no cylinder and no mix",
                            ))
                        }
                    };
                    let target = target.map_err(|e| cx.err(ev, "event", e))?;
                    nearest_gas(&mut gases, target, he_known, &mut notes)
                }
            };
            events.push((t, idx));
        }
        let default_initial = if closed_circuit {
            diluent.unwrap_or(0)
        } else {
            0
        };
        let (initial_gas, switches) = settle_switches(events, first_sample, default_initial);

        let stated_max_depth_m = read(
            attr_of(src.child("depth"), "max", "depth.max")
                .or_else(|| attr_of(dive.child("depth"), "max", "depth.max")),
            Quantity::Length,
        )?;
        let start = match (dive.attr("date"), dive.attr("time")) {
            (Some(d), Some(t)) => Some(format!("{d} {t}")),
            (Some(d), None) => Some(d.to_string()),
            _ => None,
        };
        Ok(ImportedDive {
            label: label(&cx.stem, n, start.as_deref()),
            format: Format::Subsurface,
            start,
            number: dive.attr("number").map(str::to_string),
            planned,
            closed_circuit,
            surface_pa,
            density_kg_m3,
            gases,
            initial_gas,
            switches,
            samples,
            stated_max_depth_m,
            stated_duration_s: dive.attr("duration").and_then(time_s),
            notes,
            line: line_at(cx.text, dive.offset),
        })
    };
    Ok(dive_nodes
        .into_iter()
        .enumerate()
        .map(|(n, d)| one(n, d))
        .collect())
}

/// Attribute `key` of `node` with the node and the field name for messages.
fn attr_of<'a>(
    node: Option<&'a Node>,
    key: &str,
    field: &'a str,
) -> Option<(&'a Node, &'a str, &'a str)> {
    node.and_then(|n| n.attr(key).map(|v| (n, v, field)))
}

/// Index of the listed gas nearest to `target` (by O2 alone when He is unknown, as in
/// value-only gas-change events); a mix with explicit fractions that matches no listed gas
/// within 1 % is appended.
fn nearest_gas(
    gases: &mut Vec<GasMix>,
    target: GasMix,
    he_known: bool,
    notes: &mut Vec<String>,
) -> usize {
    let dist = |g: &GasMix| {
        if he_known {
            (g.o2 - target.o2).abs() + (g.he - target.he).abs()
        } else {
            (g.o2 - target.o2).abs()
        }
    };
    let (best, d) = gases
        .iter()
        .enumerate()
        .map(|(i, g)| (i, dist(g)))
        .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a });
    if d <= 0.01 || !he_known {
        return best;
    }
    notes.push(format!(
        "gas change to {} matches no cylinder; added it",
        target.label()
    ));
    gases.push(target);
    gases.len() - 1
}

fn label(stem: &str, n: usize, start: Option<&str>) -> String {
    match start {
        Some(s) => format!("{stem} #{} {s}", n + 1),
        None => format!("{stem} #{}", n + 1),
    }
}

// ---------------------------------------------------------------------------------------------
// UDDF.

fn uddf(root: &Node, cx: &Cx) -> Result<Vec<Result<ImportedDive, InputError>>, InputError> {
    // Gas definitions: id -> index.
    let mut ids: Vec<String> = Vec::new();
    let mut gases: Vec<GasMix> = Vec::new();
    let gasdefs = {
        let mut v = Vec::new();
        root.find_all("gasdefinitions", &mut v);
        v
    };
    for gd in &gasdefs {
        for m in gd.children_named("mix") {
            let id = m.attr("id").unwrap_or("").trim().to_string();
            let g = mix(
                Some(m.text_of("o2").and_then(fraction).unwrap_or(GasMix::AIR.o2)),
                m.text_of("he").and_then(fraction),
            )
            .map_err(|e| cx.err(m, "mix", format!("mix '{id}': {e}")))?;
            ids.push(id);
            gases.push(g);
        }
    }
    let no_gasdefs = gasdefs.is_empty() || gases.is_empty();
    // Water densities of tablegeneration profiles (Shearwater links a dive to one).
    let mut profile_density: Vec<(String, f64)> = Vec::new();
    let mut tg = Vec::new();
    root.find_all("tablegeneration", &mut tg);
    for t in tg {
        let mut ps = Vec::new();
        t.find_all("profile", &mut ps);
        for p in ps {
            if let (Some(id), Some(dn)) = (p.attr("id"), p.child_with_text("density")) {
                let d = measure(&dn.text, Quantity::Density)
                    .map_err(|m| cx.err(dn, "profile.density", format!("density {m}")))?;
                profile_density.push((id.trim().to_string(), d));
            }
        }
    }

    let mut pd = Vec::new();
    root.find_all("profiledata", &mut pd);
    let mut dive_nodes = Vec::new();
    for p in pd {
        p.find_all("dive", &mut dive_nodes);
    }
    // each dive on its own: a dive the reader refuses is an error only where it is chosen
    let one = |n: usize, dive: &Node| -> Result<ImportedDive, InputError> {
        let mut notes = Vec::new();
        let mut gases = gases.clone();
        if no_gasdefs {
            notes.push("no gas definitions: breathing air (UDDF rule)".into());
            gases = vec![GasMix::AIR];
        }
        let ibd = dive.child("informationbeforedive");
        let before = |name: &str| {
            ibd.and_then(|i| i.text_of(name))
                .or_else(|| dive.text_of(name))
        };
        // a number of the dive (UDDF: SI units; another known unit is converted, an unknown
        // one or an unreadable number is refused naming its line)
        let value_in = |parent: Option<&Node>, name: &str, q: Quantity| {
            parent
                .and_then(|i| i.child_with_text(name))
                .or_else(|| dive.child_with_text(name))
                .map(|n| measure(&n.text, q).map_err(|m| cx.err(n, name, format!("{name} {m}"))))
                .transpose()
        };
        let mut surface = value_in(ibd, "surfacepressure", Quantity::Pressure { bare_pa: 1.0 })?;
        if surface.is_none() {
            if let Some(alt) = value_in(ibd, "altitude", Quantity::Length)? {
                let p = isa_pressure_pa(alt);
                notes.push(format!(
                    "surface pressure from the altitude {alt} m (ISA): {p:.0} Pa"
                ));
                surface = Some(p);
            }
        }
        let linked_density = ibd.and_then(|i| {
            i.children_named("link").find_map(|l| {
                let r = l.attr("ref")?.trim();
                profile_density.iter().find(|(id, _)| id == r).map(|p| p.1)
            })
        });
        let density = value_in(ibd, "density", Quantity::Density)?.or(linked_density);
        let (surface_pa, density_kg_m3) = environment(surface, density, &mut notes);

        let mut raw = Vec::new();
        let mut events = Vec::new();
        let mut closed_circuit = false;
        let mut first_switch_on_first_wp = false;
        let mut skipped = Skipped::default();
        if let Some(samples) = dive.child("samples") {
            for (k, wp) in samples.children_named("waypoint").enumerate() {
                // an element that is there must hold a number: an empty or unreadable one is
                // refused naming its line (a waypoint without it is skipped, with a note)
                let value = |name: &str, q: Quantity, field: &str| match wp.child(name) {
                    None => Ok(None),
                    Some(n) if n.text.trim().is_empty() => Err(cx.err(
                        n,
                        field,
                        format!("<{name}> is empty; give a number or delete the waypoint"),
                    )),
                    Some(n) => measure(&n.text, q)
                        .map(Some)
                        .map_err(|m| cx.err(n, field, format!("{name} {m}"))),
                };
                let t = value("divetime", Quantity::Time, "waypoint.divetime")?;
                let d = value("depth", Quantity::Length, "waypoint.depth")?;
                if let Some(sm) = wp.child("switchmix") {
                    let r = sm.attr("ref").unwrap_or("").trim();
                    let Some(idx) = ids.iter().position(|id| id == r) else {
                        return Err(cx.err(
                            sm,
                            "switchmix",
                            format!("switch to mix '{r}', which <gasdefinitions> does not define; fix the reference"),
                        ));
                    };
                    if let Some(t) = t {
                        events.push((t, idx));
                        if k == 0 {
                            first_switch_on_first_wp = true;
                        }
                    }
                }
                if let Some(m) = wp.child("divemode").and_then(|m| m.attr("type")) {
                    if matches!(m, "closedcircuit" | "semiclosedcircuit") {
                        closed_circuit = true;
                    }
                }
                if let (Some(t), Some(d)) = (t, d) {
                    check_sample(
                        cx,
                        wp,
                        ("waypoint.divetime", t),
                        ("waypoint.depth", d),
                        surface_pa,
                        density_kg_m3,
                    )?;
                    raw.push((t, d, wp.offset));
                } else {
                    skipped.add(wp);
                }
            }
        }
        skipped.note(cx, "waypoint(s) without a divetime or a depth", &mut notes);
        let first_sample = raw.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
        let samples = normalise(raw, cx, (dive, n + 1, "waypoint.depth"), &mut notes)?;
        if !first_switch_on_first_wp && !no_gasdefs && gases.len() > 1 {
            notes.push(format!(
                "no gas switch on the first waypoint; starting on the first mix '{}'",
                ids.first().map(String::as_str).unwrap_or("")
            ));
        }
        let (initial_gas, switches) = settle_switches(events, first_sample, 0);

        let iad = dive.child("informationafterdive");
        let start = before("datetime").map(str::to_string).or_else(|| {
            let d = dive.child("date")?;
            let y = d.text_of("year")?;
            let mo = d.text_of("month")?;
            let da = d.text_of("day")?;
            let t = dive.child("time");
            let h = t.and_then(|t| t.text_of("hour")).unwrap_or("0");
            let mi = t.and_then(|t| t.text_of("minute")).unwrap_or("0");
            Some(format!("{y}-{mo:0>2}-{da:0>2}T{h:0>2}:{mi:0>2}"))
        });
        Ok(ImportedDive {
            label: label(&cx.stem, n, start.as_deref()),
            format: Format::Uddf,
            start,
            number: before("divenumber").map(str::to_string),
            planned: false,
            closed_circuit,
            surface_pa,
            density_kg_m3,
            gases,
            initial_gas,
            switches,
            samples,
            stated_max_depth_m: value_in(iad, "greatestdepth", Quantity::Length)?,
            stated_duration_s: value_in(iad, "diveduration", Quantity::Time)?,
            notes,
            line: line_at(cx.text, dive.offset),
        })
    };
    Ok(dive_nodes
        .into_iter()
        .enumerate()
        .map(|(n, d)| one(n, d))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values() {
        assert_eq!(num("30.0 m"), Some(30.0));
        assert_eq!(num("1,5"), Some(1.5));
        assert_eq!(num("1.896059E+07"), Some(1.896059e7));
        assert_eq!(num("40 ft"), Some(40.0));
        assert_eq!(fraction("31.0%"), Some(0.31));
        assert_eq!(fraction("32"), Some(0.32));
        assert_eq!(fraction("0.32"), Some(0.32));
        assert_eq!(time_s("10:01 min"), Some(601.0));
        assert_eq!(time_s("1:02:03"), Some(3723.0));
        assert_eq!(time_s("90"), Some(90.0));
        // ISA at 0 m is 1 atm; at 1000 m about 89 875 Pa (ICAO standard atmosphere table).
        assert!((isa_pressure_pa(0.0) - ATM_PA).abs() < 1e-9);
        assert!((isa_pressure_pa(1000.0) - 89_875.0).abs() < 5.0);
    }

    #[test]
    fn units_are_converted_and_unknown_ones_refused() {
        let bar = Quantity::Pressure { bare_pa: BAR_PA };
        assert_eq!(measure("21.1 m", Quantity::Length), Ok(21.1));
        assert_eq!(measure("30.0m", Quantity::Length), Ok(30.0));
        assert_eq!(measure("21.1", Quantity::Length), Ok(21.1));
        // 1 ft = 0.3048 m exactly (international foot)
        assert!((measure("100 ft", Quantity::Length).unwrap() - 30.48).abs() < 1e-12);
        assert_eq!(measure("1.012 bar", bar), Ok(101_200.0));
        assert_eq!(measure("1.012", bar), Ok(101_200.0));
        assert_eq!(measure("1012 mbar", bar), Ok(101_200.0));
        assert_eq!(measure("101.2 kPa", bar), Ok(101_200.0));
        assert_eq!(measure("101200 Pa", bar), Ok(101_200.0));
        assert_eq!(
            measure("101100", Quantity::Pressure { bare_pa: 1.0 }),
            Ok(101_100.0)
        );
        assert_eq!(measure("1,5 bar", bar), Ok(150_000.0));
        assert_eq!(measure("1025 g/l", Quantity::Density), Ok(1025.0));
        assert_eq!(measure("10 min", Quantity::Time), Ok(600.0));
        assert_eq!(measure("1e3", Quantity::Time), Ok(1000.0));
        for (bad, q) in [
            ("21.1 furlong", Quantity::Length),
            ("21.1 bar", Quantity::Length),
            ("1.012 torr", bar),
            ("1 MPa", bar),
            ("1025 lb/gal", Quantity::Density),
            ("nan m", Quantity::Length),
            ("", Quantity::Length),
        ] {
            assert!(measure(bad, q).is_err(), "{bad}");
        }
    }

    #[test]
    fn malformed_xml_names_the_line() {
        let e = parse("<uddf>\n<profiledata>\n</uddf>\n", Path::new("x.uddf")).unwrap_err();
        assert!(e.line.is_some(), "{e}");
        let e = parse("<foo/>", Path::new("x.xml")).unwrap_err();
        assert!(e.message.contains("neither"), "{e}");
    }

    /// Defect E: a depth a metre or more above the surface mid-dive is refused naming the
    /// sample's line, field and time (it was set to 0 m with a note); sensor noise within
    /// [`SURFACE_NOISE_DEPTH_M`] of the surface is still set to 0 m, noted.
    #[test]
    fn large_negative_depths_are_refused_small_ones_clamped() {
        let ssrf = |d: &str| {
            format!(
                "<divelog program='subsurface' version='3'>\n<dives>\n<dive number='1' date='2020-01-01' time='10:00:00'>\n<divecomputer>\n<sample time='0:00 min' depth='0.0 m' />\n<sample time='2:00 min' depth='20.0 m' />\n<sample time='12:34 min' depth='{d} m' />\n<sample time='20:00 min' depth='20.0 m' />\n<sample time='24:00 min' depth='0.0 m' />\n</divecomputer>\n</dive>\n</dives>\n</divelog>\n"
            )
        };
        let path = Path::new("log.ssrf");
        let e = parse(&ssrf("-21.6"), path).unwrap_err();
        assert_eq!(
            (e.file.as_deref(), e.line, e.field.as_deref()),
            (Some(path), Some(7), Some("sample.depth")),
            "{e}"
        );
        assert!(e.message.contains("depth -21.6 m at 754 s"), "{e}");
        let e = parse(&ssrf("-1.01"), path).unwrap_err();
        assert_eq!(e.line, Some(7), "{e}");
        for d in ["-0.4", "-1.0"] {
            let dives = parse(&ssrf(d), path).unwrap();
            assert_eq!(dives[0].samples[2], (754.0, 0.0), "{d}");
            assert!(
                dives[0]
                    .notes
                    .iter()
                    .any(|n| n.contains("1 negative depth(s)")),
                "{d}: {:?}",
                dives[0].notes
            );
        }
        let uddf = "<uddf version=\"3.2.0\">\n<profiledata>\n<repetitiongroup>\n<dive>\n<samples>\n<waypoint><depth>0</depth><divetime>0</divetime></waypoint>\n<waypoint><depth>-21.6</depth><divetime>600</divetime></waypoint>\n<waypoint><depth>0</depth><divetime>1200</divetime></waypoint>\n</samples>\n</dive>\n</repetitiongroup>\n</profiledata>\n</uddf>\n";
        let e = parse(uddf, Path::new("log.uddf")).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(7), Some("waypoint.depth")),
            "{e}"
        );
    }
}
