//! The inputs of `fit`, `discover` and `synth`: measured radii (`measurements.csv`) and the
//! experiments that produced them (`experiments.toml`).
//!
//! `measurements.csv`: header `experiment,bubble,time_s,radius_m` and optionally `sd_m` (the
//! measurement standard deviation of that row), any column order and no other column; rows of
//! different bubbles in any order, the rows of one bubble in increasing time. `bubble` is
//! the 0-based index of the bubble in the experiment's phantom (the numbering of
//! `simulate`'s `bubbles.csv`). Lines starting with `#` are comments; a file `synth` wrote
//! carries its settings in one ([`SYNTHETIC_TAG`], read into [`Measurements::provenance`]).
//!
//! `experiments.toml` (paths relative to the file):
//! ```toml
//! [[experiment]]
//! name = "osc-150"                  # the measurements' experiment column
//! profile = "osc-profile.toml"      # anything `simulate --profile` reads
//! phantom = "osc-150-phantom.toml"  # its [[bubbles]] in order are bubble 0, 1, ...
//! # units = "min,psi-gauge"         # only for the paper's two-column profiles
//! [fit]
//! free = ["gases.n2.diffusivity"]   # baseline parameters fitted in every model (default none)
//! ```

use crate::error::{line_of_key, toml_error, toml_error_with_path, Error, InputError};
use crate::phantom::config::parse_phantom;
use crate::phantom::params::{BubblePlacement, PhantomParams};
use crate::profile::{legacy, LoadOptions, PressureHistory};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// One measured radius.
#[derive(Debug, Clone, PartialEq)]
pub struct Observation {
    /// Time, s.
    pub time: f64,
    /// Radius, m.
    pub radius: f64,
    /// Measurement standard deviation, m, if given.
    pub sd: Option<f64>,
    /// 1-based line of the CSV row (for messages).
    pub line: usize,
}

/// The measured radius–time series of one bubble, in time order.
#[derive(Debug, Clone, PartialEq)]
pub struct BubbleSeries {
    /// Experiment name.
    pub experiment: String,
    /// 0-based bubble index in that experiment's phantom.
    pub bubble: usize,
    /// Observations in increasing time.
    pub points: Vec<Observation>,
}

/// All measurements, grouped by experiment and bubble (sorted by both).
#[derive(Debug, Clone, PartialEq)]
pub struct Measurements {
    /// The file read.
    pub file: PathBuf,
    /// Series in (experiment, bubble) order.
    pub series: Vec<BubbleSeries>,
    /// Where the data came from: `Some` when the file holds a [`SYNTHETIC_TAG`] comment line
    /// (written by `synth`), `None` for measured data (a file without one).
    pub provenance: Option<Provenance>,
}

/// The start of the comment line `synth` writes above the header of its CSV:
/// `# synthetic: decophantom synth --effect NAME=V[,V2] … --noise-sd SD --every S --seed N;
/// experiments fnv1a-64 HASH` (the CSV reader skips `#` lines, so the rows read the same).
pub const SYNTHETIC_TAG: &str = "# synthetic: ";

/// The settings a synthetic file was made with, read back from its [`SYNTHETIC_TAG`] line.
#[derive(Debug, Clone, PartialEq)]
pub struct SynthSettings {
    /// The effects switched on (`--effect`), in order; empty for the baseline model itself.
    pub effects: Vec<super::synth::EffectSetting>,
    /// Noise sd, m (`--noise-sd`).
    pub noise_sd: f64,
    /// Sampling interval, s (`--every`).
    pub every: f64,
    /// Seed of the noise (`--seed`).
    pub seed: u64,
    /// FNV-1a 64 of the experiments the data were made from
    /// ([`super::synth::experiments_hash`]), if recorded.
    pub experiments_hash: Option<u64>,
}

/// A file's [`SYNTHETIC_TAG`] line, as read.
#[derive(Debug, Clone, PartialEq)]
pub struct Provenance {
    /// 1-based line of the tag.
    pub line: usize,
    /// The generator's command as written after the tag (up to any `;`).
    pub command: String,
    /// The settings, or why they could not be read from the line (an edited line): the data
    /// are then still said to be synthetic, without settings or true values.
    pub settings: Result<SynthSettings, String>,
    /// Whether the file ends with `synth`'s end marker and its hash still matches the lines
    /// above it (false: edited since, or text that never went through `synth --out`).
    pub unchanged: bool,
}

/// Read the [`SYNTHETIC_TAG`] line of a measurements text, if any.
pub fn read_provenance(text: &str) -> Option<Provenance> {
    let tagged: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter_map(|(i, l)| l.strip_prefix(SYNTHETIC_TAG).map(|r| (i + 1, r.trim())))
        .collect();
    let &(line, rest) = tagged.first()?;
    let (command, tail) = match rest.split_once(';') {
        Some((c, t)) => (c.trim(), t.trim()),
        None => (rest, ""),
    };
    let settings = if tagged.len() > 1 {
        Err(format!(
            "{} '{}' lines (lines {}); a file synth writes has one",
            tagged.len(),
            SYNTHETIC_TAG.trim(),
            tagged
                .iter()
                .map(|t| t.0.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ))
    } else {
        parse_synth_settings(command, tail)
    };
    Some(Provenance {
        line,
        command: command.to_string(),
        settings,
        unchanged: crate::report::output::written_unchanged(text, "synth"),
    })
}

/// The settings in a [`SYNTHETIC_TAG`] line: `command` (`decophantom synth --effect … --seed N`)
/// and `tail` (`experiments fnv1a-64 HASH`, or empty).
fn parse_synth_settings(command: &str, tail: &str) -> Result<SynthSettings, String> {
    let mut words = command.split_whitespace();
    if (words.next(), words.next()) != (Some("decophantom"), Some("synth")) {
        return Err(format!(
            "'{command}' does not start with 'decophantom synth'"
        ));
    }
    let (mut effects, mut noise_sd, mut every, mut seed) = (Vec::new(), None, None, None);
    while let Some(flag) = words.next() {
        let value = words
            .next()
            .ok_or_else(|| format!("'{flag}' has no value"))?;
        let number = |v: &str| {
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("{flag} '{v}' is not a finite number"))
        };
        match flag {
            "--effect" => effects
                .push(super::synth::EffectSetting::parse(value).map_err(|e| e.message.clone())?),
            "--noise-sd" => noise_sd = Some(number(value)?),
            "--every" => every = Some(number(value)?),
            "--seed" => {
                seed = Some(
                    value
                        .parse::<u64>()
                        .map_err(|_| format!("--seed '{value}' is not a seed"))?,
                )
            }
            other => return Err(format!("unknown option '{other}'")),
        }
    }
    let experiments_hash = match tail.strip_prefix("experiments fnv1a-64 ") {
        Some(h) => Some(
            u64::from_str_radix(h.trim(), 16)
                .map_err(|_| format!("'{h}' is not a 64-bit hexadecimal hash"))?,
        ),
        None if tail.is_empty() => None,
        None => return Err(format!("'{tail}' is not 'experiments fnv1a-64 HASH'")),
    };
    Ok(SynthSettings {
        effects,
        noise_sd: noise_sd.ok_or("no --noise-sd")?,
        every: every.ok_or("no --every")?,
        seed: seed.ok_or("no --seed")?,
        experiments_hash,
    })
}

impl Measurements {
    /// Number of observations.
    pub fn len(&self) -> usize {
        self.series.iter().map(|s| s.points.len()).sum()
    }
    /// No observations.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Weights 1/sd² in measurement order (1 where a row has no sd: the reader accepts an
    /// `sd_m` on every row or on none, so the weights are all 1 or all 1/sd²).
    pub fn weights(&self) -> Vec<f64> {
        self.series
            .iter()
            .flat_map(|s| {
                s.points
                    .iter()
                    .map(|p| p.sd.map_or(1.0, |sd| 1.0 / (sd * sd)))
            })
            .collect()
    }
    /// Whether every row carries `sd_m`.
    pub fn has_sd(&self) -> bool {
        self.series
            .iter()
            .all(|s| s.points.iter().all(|p| p.sd.is_some()))
    }
}

/// Largest radius a measurement may give, m: 1 cm, the phantom reader's upper limit on a
/// bubble's initial radius R0 (`profiles/phantoms/README.md`). A larger number is a radius in
/// other units (mm, µm) or a diameter of a bubble the model cannot hold, never a measurement of
/// one of its bubbles.
pub const MAX_RADIUS_M: f64 = 1e-2;

/// Smallest radius a measurement may give, m: 1 nm, the floor of [`MIN_SD_M`]. Imaging
/// resolves bubble radii to ~0.1–1 µm (sub-pixel edge fits ~10 nm): a radius below 1 nm (or
/// of 0: no bubble) is not a measured radius of a bubble but a placeholder or a unit error, and
/// in a fit it would pull the model towards a bubble that has dissolved. `synth` clamps its
/// noisy radii at this floor.
pub const MIN_RADIUS_M: f64 = 1e-9;

/// Smallest measurement standard deviation, m: 1 nm. Bubble radii are measured by imaging,
/// whose resolution is ~0.1–1 µm (sub-pixel edge fits reach ~10 nm); an sd below 1 nm is not
/// an uncertainty of such a measurement, and its weight 1/sd² (above 1e18 m⁻²) would let one
/// row outweigh every other by many orders of magnitude (a 1e-20 sd made the intervals run to
/// infinity, 1e-300 made the fit fail).
pub const MIN_SD_M: f64 = 1e-9;

/// Largest measurement standard deviation, m: [`MAX_RADIUS_M`]. An uncertainty larger than any
/// radius a measurement may give says nothing about the radius.
pub const MAX_SD_M: f64 = MAX_RADIUS_M;

/// The columns `measurements.csv` reads; each may appear once.
pub const COLUMNS: [&str; 5] = ["experiment", "bubble", "time_s", "radius_m", "sd_m"];

/// Read `measurements.csv`. Refused (exit 2, file/row/field named): a missing column, a column
/// not in [`COLUMNS`] (a misspelled `sd` would otherwise leave the fit unweighted, silently) or
/// one of them named twice in the header (line 1), a value that is not a finite number, a
/// radius outside [`MIN_RADIUS_M`] ..= [`MAX_RADIUS_M`] (1 nm ..= 1 cm), an sd outside
/// [`MIN_SD_M`] ..= [`MAX_SD_M`] (1 nm ..= 1 cm), an `sd_m` column filled on some rows and
/// empty on others, a bubble index that is not a non-negative integer, and a time that does not
/// increase within a bubble (repeated, or earlier than the bubble's row above it; rows of
/// different bubbles may interleave). A radius larger than the experiment's phantom can hold is
/// refused by [`check_against`].
pub fn read_measurements(path: &Path) -> Result<Measurements, InputError> {
    let text = crate::error::read_text(path, "the measurements")?;
    parse_measurements(&text, path)
}

/// Parse measurements text (`path` for messages).
pub fn parse_measurements(text: &str, path: &Path) -> Result<Measurements, InputError> {
    let mut rdr = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(text.as_bytes());
    let headers = rdr
        .headers()
        .map_err(|e| {
            InputError::new(format!("cannot read the header: {e}"))
                .in_file(path)
                .at_line(1)
        })?
        .clone();
    let col = |name: &str| headers.iter().position(|h| h == name);
    // a column named twice would be read from its first occurrence, silently
    for name in COLUMNS {
        if headers.iter().filter(|h| *h == name).count() > 1 {
            return Err(InputError::new(format!(
                "column '{name}' appears twice in the header ({}); name each column once",
                headers.iter().collect::<Vec<_>>().join(",")
            ))
            .in_file(path)
            .at_line(1)
            .field(name));
        }
    }
    // a column the reader does not know would be ignored, silently: a misspelled `sd` would
    // leave the fit unweighted
    let unknown: Vec<&str> = headers.iter().filter(|h| !COLUMNS.contains(h)).collect();
    if let Some(first) = unknown.first() {
        return Err(InputError::new(format!(
            "unknown column{} '{}'; the columns are experiment, bubble, time_s, radius_m and optionally sd_m (the measurement standard deviation, m), any order, no others",
            if unknown.len() > 1 { "s" } else { "" },
            unknown.join("', '")
        ))
        .in_file(path)
        .at_line(1)
        .field(first.to_string()));
    }
    let mut cols = [0usize; 4];
    for (k, name) in ["experiment", "bubble", "time_s", "radius_m"]
        .iter()
        .enumerate()
    {
        cols[k] = col(name).ok_or_else(|| {
            InputError::new(format!(
                "missing column '{name}'; the header must be experiment,bubble,time_s,radius_m[,sd_m] (found: {})",
                headers.iter().collect::<Vec<_>>().join(",")
            ))
            .in_file(path)
            .at_line(1)
            .field(*name)
        })?;
    }
    let sd_col = col("sd_m");
    // the first line with an sd and the first without one: a fit weights rows with 1/sd² and
    // could give a row without one no weight of the same scale, so the column is all or none
    let (mut with_sd, mut without_sd) = (None, None);
    let mut groups: BTreeMap<(String, usize), Vec<Observation>> = BTreeMap::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| {
            let line = e.position().map(|p| p.line() as usize).unwrap_or(0);
            let mut ie = InputError::new(format!("malformed row: {e}")).in_file(path);
            if line > 0 {
                ie = ie.at_line(line);
            }
            ie
        })?;
        let line = rec.position().map(|p| p.line() as usize).unwrap_or(0);
        let err = |field: &str, m: String| {
            InputError::new(m)
                .in_file(path)
                .at_line(line)
                .field(field.to_string())
        };
        let cell = |k: usize, name: &str| -> Result<&str, InputError> {
            rec.get(k)
                .filter(|s| !s.is_empty())
                .ok_or_else(|| err(name, format!("no value for '{name}'")))
        };
        let number = |k: usize, name: &str| -> Result<f64, InputError> {
            let s = cell(k, name)?;
            s.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| err(name, format!("'{s}' is not a finite number")))
        };
        let experiment = cell(cols[0], "experiment")?.to_string();
        let b = cell(cols[1], "bubble")?;
        let bubble = b.parse::<usize>().map_err(|_| {
            err(
                "bubble",
                format!("'{b}' is not a bubble index (0, 1, 2, … as in the phantom's [[bubbles]])"),
            )
        })?;
        let time = number(cols[2], "time_s")?;
        let radius = number(cols[3], "radius_m")?;
        if !(0.0..=crate::profile::MAX_DURATION_S).contains(&time) {
            return Err(err(
                "time_s",
                format!(
                    "time {} s is outside 0 ..= {} s (30 days)",
                    crate::error::num(time),
                    crate::profile::MAX_DURATION_S
                ),
            ));
        }
        if radius < 0.0 {
            return Err(err(
                "radius_m",
                format!("a radius cannot be negative (got {radius} m)"),
            ));
        }
        if radius < MIN_RADIUS_M {
            return Err(err(
                "radius_m",
                format!(
                    "{} m is not a measured bubble radius (at least {} m, 1 nm: imaging resolves ~0.1 µm); leave out the rows where no bubble is seen",
                    crate::error::num(radius),
                    crate::error::num(MIN_RADIUS_M)
                ),
            ));
        }
        if radius > MAX_RADIUS_M {
            return Err(err(
                "radius_m",
                format!(
                    "{} m is not a bubble radius the model can hold (at most {} m, 1 cm); radii are in metres (e.g. 2.0e-4 for 0.2 mm)",
                    crate::error::num(radius),
                    MAX_RADIUS_M
                ),
            ));
        }
        let sd = match sd_col {
            Some(k) if rec.get(k).is_some_and(|s| !s.is_empty()) => {
                let v = number(k, "sd_m")?;
                if !(v > 0.0) {
                    return Err(err(
                        "sd_m",
                        format!("a standard deviation must be positive (got {v} m)"),
                    ));
                }
                if !(MIN_SD_M..=MAX_SD_M).contains(&v) {
                    return Err(err(
                        "sd_m",
                        format!(
                            "a measurement standard deviation of {} m is outside {} ..= {} m (1 nm to 1 cm); sd is in metres, like the radius (e.g. 2.0e-6 for 2 µm)",
                            crate::error::num(v),
                            crate::error::num(MIN_SD_M),
                            crate::error::num(MAX_SD_M)
                        ),
                    ));
                }
                Some(v)
            }
            _ => None,
        };
        match sd {
            Some(_) => with_sd = with_sd.or(Some(line)),
            None => without_sd = without_sd.or(Some(line)),
        }
        // the rows of one bubble in time order: a time not after the bubble's row above it is
        // a repeated or misplaced row
        if let Some(prev) = groups
            .get(&(experiment.clone(), bubble))
            .and_then(|g| g.last())
        {
            if !(time > prev.time) {
                let what = if time == prev.time {
                    format!(
                        "time {} s appears twice (lines {} and {line})",
                        prev.time, prev.line
                    )
                } else {
                    format!(
                        "time {} s comes after {} s on line {}",
                        crate::error::num(time),
                        crate::error::num(prev.time),
                        prev.line
                    )
                };
                return Err(err(
                    "time_s",
                    format!("experiment '{experiment}', bubble {bubble}: {what}; times must increase within a bubble (rows of different bubbles may interleave)"),
                ));
            }
        }
        let group = groups.entry((experiment, bubble)).or_default();
        group.push(Observation {
            time,
            radius,
            sd,
            line,
        });
    }
    if let (Some(with), Some(without)) = (with_sd, without_sd) {
        return Err(InputError::new(format!(
            "line {with} gives a standard deviation and line {without} does not: give sd_m on every row or on none (a fit weights each row by 1/sd², about 1e11 for a few µm, and a row without one would count for nothing against them)"
        ))
        .in_file(path)
        .at_line(without)
        .field("sd_m"));
    }
    let mut series = Vec::new();
    for ((experiment, bubble), mut points) in groups {
        points.sort_by(|a, b| a.time.total_cmp(&b.time));
        for w in points.windows(2) {
            if !(w[1].time > w[0].time) {
                return Err(InputError::new(format!(
                    "experiment '{experiment}', bubble {bubble}: time {} s appears twice (lines {} and {}); times must increase within a bubble",
                    w[1].time, w[0].line, w[1].line
                ))
                .in_file(path)
                .at_line(w[1].line)
                .field("time_s"));
            }
        }
        if points.first().is_some_and(|p| p.time < 0.0) {
            return Err(InputError::new(format!(
                "experiment '{experiment}', bubble {bubble}: negative time {} s (times are from the start of the profile)",
                points[0].time
            ))
            .in_file(path)
            .at_line(points[0].line)
            .field("time_s"));
        }
        series.push(BubbleSeries {
            experiment,
            bubble,
            points,
        });
    }
    if series.is_empty() {
        return Err(InputError::new("no measurements (only a header)")
            .in_file(path)
            .at_line(crate::error::last_line(text)));
    }
    Ok(Measurements {
        file: path.to_path_buf(),
        series,
        provenance: read_provenance(text),
    })
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExperiments {
    experiment: Vec<RawExperiment>,
    #[serde(default)]
    fit: RawFit,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawExperiment {
    name: String,
    profile: PathBuf,
    phantom: PathBuf,
    units: Option<String>,
    gas: Option<String>,
    vapour_pa: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFit {
    #[serde(default)]
    free: Vec<String>,
}

/// One experiment: its pressure profile and its phantom (kept as the TOML document, so any
/// parameter can be set by path).
#[derive(Debug, Clone)]
pub struct Experiment {
    /// Name (the measurements' experiment column).
    pub name: String,
    /// The pressure history.
    pub profile: PressureHistory,
    /// The phantom file.
    pub phantom_path: PathBuf,
    /// The phantom as a TOML document.
    pub phantom: toml::Table,
    /// Number of bubbles the phantom defines.
    pub bubbles: usize,
    /// Radius of the largest sphere the phantom holds, m: half its smallest extent (a box's
    /// shortest edge; a cylinder's diameter or depth). No bubble of it can be larger: a bubble
    /// that reaches a face ends the run.
    pub largest_radius_m: f64,
}

/// The experiments file.
#[derive(Debug, Clone)]
pub struct Experiments {
    /// The file read.
    pub file: PathBuf,
    /// Experiments in file order.
    pub list: Vec<Experiment>,
    /// Baseline free parameters (`[fit] free`).
    pub free: Vec<String>,
    /// 1-based line of `free =` in the file, for messages.
    pub free_line: Option<usize>,
}

impl Experiments {
    /// The largest water-vapour pressure the experiments' profiles subtract at the open faces,
    /// Pa (0 when none does): every bubble holds at least that much of gases the model does not
    /// carry ([`crate::phantom::params::PhantomParams::bubble_fixed_gases_for`]).
    pub fn vapour_pa(&self) -> f64 {
        self.list
            .iter()
            .map(|e| e.profile.vapour_pa)
            .fold(0.0, f64::max)
    }

    /// The experiment of this name.
    pub fn get(&self, name: &str) -> Option<&Experiment> {
        self.list.iter().find(|e| e.name == name)
    }
    /// Position of the experiment of this name (0 if there is none: measurements are checked
    /// against the experiments before they are used).
    pub fn index_of(&self, name: &str) -> usize {
        self.list.iter().position(|e| e.name == name).unwrap_or(0)
    }
}

/// Build validated phantom parameters from a (possibly edited) phantom document.
pub fn build_params(doc: &toml::Table, path: &Path) -> Result<PhantomParams, InputError> {
    let text = toml::to_string(doc).map_err(|e| {
        InputError::new(format!("cannot write the phantom back to TOML: {e}")).in_file(path)
    })?;
    Ok(parse_phantom(&text, path)?.params)
}

/// Radius of the largest sphere inside a phantom, m (half its smallest extent).
pub fn largest_radius(p: &PhantomParams) -> f64 {
    use crate::phantom::grid::Shape;
    match p.shape {
        Shape::Box { size } => 0.5 * size[0].min(size[1]).min(size[2]),
        Shape::Cylinder { diameter, depth } => 0.5 * diameter.min(depth),
    }
}

/// Number of bubbles a phantom defines.
pub fn bubble_count(p: &PhantomParams) -> usize {
    match &p.bubbles {
        BubblePlacement::Explicit(list) => list.len(),
        BubblePlacement::Random { count, .. } => *count,
    }
}

/// Read `experiments.toml` and everything it names.
pub fn read_experiments(path: &Path) -> Result<Experiments, Error> {
    let text = crate::error::read_text(path, "the experiments file")?;
    let raw: RawExperiments =
        toml::from_str(&text).map_err(|e| toml_error_with_path(path, &text, &e))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let err = |key: &str, m: String| {
        let mut e = InputError::new(m).in_file(path).field(key.to_string());
        if let Some(l) = line_of_key(&text, key.rsplit('.').next().unwrap_or(key)) {
            e = e.at_line(l);
        }
        crate::error::ensure_line(e, &text)
    };
    let mut list: Vec<Experiment> = Vec::new();
    if raw.experiment.is_empty() {
        return Err(err("experiment", "no [[experiment]] entries".into()).into());
    }
    for (k, e) in raw.experiment.iter().enumerate() {
        // a problem of a named file with no line of its own (missing, unreadable, or refused
        // for an option given here) is named at this experiment's entry
        let entry = |key: &str, x: InputError| -> InputError {
            if x.line.is_some() {
                return x;
            }
            let line = text
                .lines()
                .enumerate()
                .filter(|(_, l)| {
                    let t = l.trim_start();
                    t.starts_with(key) && t[key.len()..].trim_start().starts_with('=')
                })
                .nth(k)
                .map(|(i, _)| i + 1)
                .or_else(|| line_of_key(&text, key))
                .unwrap_or_else(|| crate::error::last_line(&text));
            let what = x
                .file
                .as_ref()
                .map(|f| format!("{}: ", f.display()))
                .unwrap_or_default();
            let field = x
                .field
                .as_deref()
                .map(|f| format!(" ({f})"))
                .unwrap_or_default();
            InputError::new(format!(
                "experiment '{}': {what}{}{field}",
                e.name, x.message
            ))
            .in_file(path)
            .at_line(line)
            .field(format!("experiment.{key}"))
        };
        if e.name.trim().is_empty() {
            return Err(err("name", "an experiment needs a non-empty name".into()).into());
        }
        // the measurements' cells are trimmed and read as text: a name must be written the
        // same way there (synth quotes a comma, quote or '#'); control characters and path
        // separators have no place in a name that also names the report's overlay files
        if e.name.trim() != e.name || e.name.chars().any(|c| c.is_control()) {
            return Err(err(
                "name",
                format!(
                    "experiment name {:?} has leading or trailing spaces or a control character (a line break, a tab); a measurements file cannot name it: write it without them",
                    e.name
                ),
            )
            .into());
        }
        if e.name.contains(['/', '\\']) {
            return Err(err(
                "name",
                format!(
                    "experiment name {:?} holds a path separator (/ or \\); the name also names the report's overlay files (overlay-NAME-bN.svg): write it without one",
                    e.name
                ),
            )
            .into());
        }
        if list.iter().any(|x| x.name == e.name) {
            return Err(err("name", format!("experiment '{}' is defined twice", e.name)).into());
        }
        let (time_unit, pressure_unit) = match &e.units {
            Some(u) => {
                let (t, p) = legacy::parse_units(u).map_err(|ie| err("units", ie.message))?;
                (Some(t), Some(p))
            }
            None => (None, None),
        };
        let gas = match &e.gas {
            Some(g) => Some(crate::gas::GasMix::parse(g).map_err(|m| err("gas", m))?),
            None => None,
        };
        let opts = LoadOptions {
            time_unit,
            pressure_unit,
            surface_pa: None,
            gas,
            vapour_pa: e.vapour_pa,
            dive: None,
        };
        let profile = match crate::run::load_profile_or_schedule(&dir.join(&e.profile), &opts) {
            Ok(p) => p,
            Err(Error::Input(x)) => return Err(entry("profile", x).into()),
            Err(other) => return Err(other),
        };
        let phantom_path = dir.join(&e.phantom);
        let ptext = crate::error::read_text(&phantom_path, "the phantom file")
            .map_err(|x| entry("phantom", x))?;
        // validate as a phantom file first, so errors point at its own lines
        let params = parse_phantom(&ptext, &phantom_path)
            .map_err(|x| entry("phantom", x))?
            .params;
        let phantom: toml::Table = ptext
            .parse()
            .map_err(|x: toml::de::Error| toml_error(&phantom_path, &ptext, &x))?;
        list.push(Experiment {
            name: e.name.clone(),
            profile,
            phantom_path,
            phantom,
            bubbles: bubble_count(&params),
            largest_radius_m: largest_radius(&params),
        });
    }
    let docs: Vec<toml::Table> = list.iter().map(|x| x.phantom.clone()).collect();
    let files: Vec<&Path> = list.iter().map(|x| x.phantom_path.as_path()).collect();
    for (i, f) in raw.fit.free.iter().enumerate() {
        // one parameter twice would be fitted as two, and neither determined
        if raw.fit.free[..i].contains(f) {
            return Err(err(
                "fit.free",
                format!("'{f}' is listed twice; list each parameter once"),
            )
            .into());
        }
        if let Some(m) = crate::fit::paths::not_a_number(&docs, &files, f) {
            return Err(err("fit.free", m).into());
        }
        if list
            .iter()
            .all(|x| !crate::fit::paths::holds(&x.phantom, f))
        {
            return Err(err(
                "fit.free",
                format!("'{f}' is not a number set in any experiment's phantom file"),
            )
            .into());
        }
    }
    Ok(Experiments {
        file: path.to_path_buf(),
        list,
        free: raw.fit.free,
        free_line: line_of_key(&text, "free"),
    })
}

/// Check that every measured series names an experiment and a bubble that exist, that no
/// radius is larger than its experiment's phantom can hold ([`Experiment::largest_radius_m`])
/// and that no time is after the end of its experiment's profile.
pub fn check_against(m: &Measurements, e: &Experiments) -> Result<(), InputError> {
    for s in &m.series {
        let line = s.points[0].line;
        let Some(x) = e.get(&s.experiment) else {
            return Err(InputError::new(format!(
                "experiment '{}' is not defined in {} (defined: {})",
                s.experiment,
                e.file.display(),
                e.list
                    .iter()
                    .map(|x| x.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
            .in_file(&m.file)
            .at_line(line)
            .field("experiment"));
        };
        if s.bubble >= x.bubbles {
            return Err(InputError::new(format!(
                "experiment '{}' has {} bubble(s) (0..{}) in {}; there is no bubble {}",
                x.name,
                x.bubbles,
                x.bubbles.saturating_sub(1),
                x.phantom_path.display(),
                s.bubble
            ))
            .in_file(&m.file)
            .at_line(line)
            .field("bubble"));
        }
        if let Some(p) = s.points.iter().find(|p| p.radius > x.largest_radius_m) {
            return Err(InputError::new(format!(
                "a radius of {} m is larger than the phantom of experiment '{}' can hold ({} m, half its smallest extent, in {}); radii are in metres (e.g. 2.0e-4 for 0.2 mm)",
                crate::error::num(p.radius),
                x.name,
                crate::error::num(x.largest_radius_m),
                x.phantom_path.display()
            ))
            .in_file(&m.file)
            .at_line(p.line)
            .field("radius_m"));
        }
        if let Some(p) = s
            .points
            .iter()
            .find(|p| p.time > x.profile.duration_s() + 1e-9)
        {
            return Err(InputError::new(format!(
                "time {} s is after the end of experiment '{}' ({} s)",
                p.time,
                x.name,
                x.profile.duration_s()
            ))
            .in_file(&m.file)
            .at_line(p.line)
            .field("time_s"));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plausibility limits of `radius_m` and `sd_m`, by their documented values: a radius in
    /// 1 nm ..= 1 cm and an sd in 1 nm ..= 1 cm are read, the first value past either end (and a
    /// radius of 0 or 1e-300 m) is refused naming its line and field; a column of the reader
    /// named twice is refused at line 1 naming the column.
    #[test]
    fn radius_and_sd_ranges_and_duplicate_columns() {
        let path = Path::new("m.csv");
        let row = |r: &str, sd: &str| {
            format!("experiment,bubble,time_s,radius_m,sd_m\na,0,0,1e-4,2e-6\na,0,10,{r},{sd}\n")
        };
        for (r, sd) in [
            ("1e-9", "2e-6"),
            ("1e-2", "2e-6"),
            ("1e-4", "1e-9"),
            ("1e-4", "1e-2"),
        ] {
            parse_measurements(&row(r, sd), path).unwrap_or_else(|e| panic!("{r}, {sd}: {e}"));
        }
        for (r, sd, field) in [
            ("0", "2e-6", "radius_m"),
            ("1e-300", "2e-6", "radius_m"),
            ("9.99e-10", "2e-6", "radius_m"),
            ("1.0000001e-2", "2e-6", "radius_m"),
            ("0.0617", "2e-6", "radius_m"), // 61.7 µm written in mm
            ("1e-4", "9.99e-10", "sd_m"),
            ("1e-4", "1e-20", "sd_m"),
            ("1e-4", "1e-300", "sd_m"),
            ("1e-4", "1.1e-2", "sd_m"),
        ] {
            let e = parse_measurements(&row(r, sd), path).unwrap_err();
            assert_eq!((e.line, e.field.as_deref()), (Some(3), Some(field)), "{e}");
        }
        for col in COLUMNS {
            let text = format!("experiment,bubble,time_s,radius_m,sd_m,{col}\na,0,0,1e-4,2e-6,x\n");
            let e = parse_measurements(&text, path).unwrap_err();
            assert_eq!((e.line, e.field.as_deref()), (Some(1), Some(col)), "{e}");
            assert!(e.message.contains("appears twice"), "{e}");
        }
    }

    /// Defect D: a column the reader does not read (a misspelled `sd`, a `note`) is refused at
    /// line 1 naming it and the accepted columns; the fit would otherwise run unweighted.
    #[test]
    fn unknown_columns_are_refused() {
        let path = Path::new("m.csv");
        for (header, field, named) in [
            ("experiment,bubble,time_s,radius_m,sd", "sd", "'sd'"),
            ("experiment,bubble,time_s,radius_m,note", "note", "'note'"),
            (
                "note,experiment,bubble,time_s,radius_m,note",
                "note",
                "'note', 'note'",
            ),
            (
                "experiment,bubble,Time_s,time_s,radius_m",
                "Time_s",
                "'Time_s'",
            ),
        ] {
            let n = header.split(',').count();
            let row = ["x"; 8][..n].join(",");
            let e = parse_measurements(&format!("{header}\n{row}\n"), path).unwrap_err();
            assert_eq!(
                (e.file.as_deref(), e.line, e.field.as_deref()),
                (Some(path), Some(1), Some(field)),
                "{e}"
            );
            assert!(e.message.contains(named), "{e}");
            assert!(
                e.message
                    .contains("experiment, bubble, time_s, radius_m and optionally sd_m"),
                "{e}"
            );
        }
    }

    /// Defect D: the rows of one bubble in increasing time (0, 20, 10 s is refused at the 10,
    /// naming the row above it); rows of different bubbles may interleave.
    #[test]
    fn times_increase_within_a_bubble() {
        let path = Path::new("m.csv");
        let text = "experiment,bubble,time_s,radius_m\na,0,0,1e-4\na,0,20,1e-4\na,0,10,1e-4\na,0,30,1e-4\n";
        let e = parse_measurements(text, path).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(4), Some("time_s")),
            "{e}"
        );
        assert!(
            e.message.contains("time 10 s comes after 20 s on line 3"),
            "{e}"
        );
        let twice = "experiment,bubble,time_s,radius_m\na,0,0,1e-4\na,0,10,1e-4\na,0,10,1e-4\n";
        let e = parse_measurements(twice, path).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(4), Some("time_s")),
            "{e}"
        );
        assert!(e.message.contains("appears twice (lines 3 and 4)"), "{e}");
        let interleaved = "experiment,bubble,time_s,radius_m\na,0,0,1e-4\na,1,0,1e-4\nb,0,0,1e-4\na,0,10,1e-4\na,1,5,1e-4\n";
        let m = parse_measurements(interleaved, path).unwrap();
        assert_eq!(m.len(), 5);
        assert_eq!(
            m.series[0]
                .points
                .iter()
                .map(|p| p.time)
                .collect::<Vec<_>>(),
            [0.0, 10.0]
        );
    }

    /// An `sd_m` column filled on some rows only is refused at the first row without one
    /// (weights 1/sd² ≈ 1e11 against 1 would drop those rows from a fit); a column that is empty
    /// on every row is no sd at all.
    #[test]
    fn an_sd_column_is_filled_on_every_row_or_on_none() {
        let path = Path::new("m.csv");
        let partial = "experiment,bubble,time_s,radius_m,sd_m\n\
                       a,0,0,1e-4,2e-6\na,0,10,1.1e-4,2e-6\nb,0,0,1e-4,\nb,0,10,1.1e-4,2e-6\n";
        let e = parse_measurements(partial, path).unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
        assert_eq!(e.field.as_deref(), Some("sd_m"), "{e}");
        let empty = "experiment,bubble,time_s,radius_m,sd_m\na,0,0,1e-4,\na,0,10,1.1e-4,\n";
        let m = parse_measurements(empty, path).unwrap();
        assert!(!m.has_sd());
        assert_eq!(m.weights(), vec![1.0, 1.0]);
        let full = "experiment,bubble,time_s,radius_m,sd_m\na,0,0,1e-4,2e-6\na,0,10,1.1e-4,4e-6\n";
        let m = parse_measurements(full, path).unwrap();
        assert!(m.has_sd());
        // 1/sd², computed by hand: 1/(2e-6)² = 2.5e11, 1/(4e-6)² = 6.25e10
        let w = m.weights();
        assert!((w[0] / 2.5e11 - 1.0).abs() < 1e-12 && (w[1] / 6.25e10 - 1.0).abs() < 1e-12);
    }

    /// The `# synthetic:` line: a file with it reads the same rows as without it (the CSV
    /// reader skips `#` lines) and exposes the settings written there; a file without it is
    /// measured data (`provenance` None); an unreadable line still marks the data synthetic,
    /// with the reason; the end marker of `synth` is checked (`unchanged`). Reference values:
    /// the numbers written into the line by hand.
    #[test]
    fn the_synthetic_line_is_read_and_the_rows_stay_the_same() {
        let path = Path::new("m.csv");
        let rows = "experiment,bubble,time_s,radius_m,sd_m\na,0,0,1e-4,2e-6\na,0,5,1.1e-4,2e-6\n";
        let tag = "# synthetic: decophantom synth --effect surface-area-law=30,2 --effect perfusion=2e-3 --noise-sd 2e-6 --every 5 --seed 7; experiments fnv1a-64 00000000000000ff\n";
        let plain = parse_measurements(rows, path).unwrap();
        assert_eq!(plain.provenance, None);
        let body = format!("{tag}{rows}");
        let text = format!(
            "{body}{}",
            crate::report::output::marker_line(
                "synth",
                &body,
                crate::report::output::CommentStyle::Hash
            )
        );
        let m = parse_measurements(&text, path).unwrap();
        let values = |m: &Measurements| -> Vec<(f64, f64, Option<f64>)> {
            m.series
                .iter()
                .flat_map(|s| s.points.iter().map(|p| (p.time, p.radius, p.sd)))
                .collect()
        };
        assert_eq!(values(&m), values(&plain));
        let p = m.provenance.clone().unwrap();
        assert_eq!(p.line, 1);
        assert!(p.unchanged);
        assert_eq!(
            p.command,
            "decophantom synth --effect surface-area-law=30,2 --effect perfusion=2e-3 --noise-sd 2e-6 --every 5 --seed 7"
        );
        let st = p.settings.unwrap();
        assert_eq!(st.effects.len(), 2);
        assert_eq!(
            (st.effects[0].name.as_str(), st.effects[0].values.clone()),
            ("surface-area-law", vec![30.0, 2.0])
        );
        assert_eq!(
            (st.effects[1].name.as_str(), st.effects[1].values.clone()),
            ("perfusion", vec![2e-3])
        );
        assert_eq!(
            (st.noise_sd, st.every, st.seed, st.experiments_hash),
            (2e-6, 5.0, 7, Some(0xff))
        );
        // a row edited after synth wrote the file: still read, no longer unchanged
        let edited = text.replacen("1.1e-4", "1.2e-4", 1);
        let p = parse_measurements(&edited, path)
            .unwrap()
            .provenance
            .unwrap();
        assert!(!p.unchanged && p.settings.is_ok());
        // an unreadable line: the data are synthetic, the settings are not given, and why
        let bad = format!("# synthetic: decophantom synth --noise-sd lots --seed 1\n{rows}");
        let p = parse_measurements(&bad, path).unwrap().provenance.unwrap();
        assert!(p.settings.unwrap_err().contains("--noise-sd 'lots'"));
        let twice = format!("{tag}{tag}{rows}");
        let p = parse_measurements(&twice, path)
            .unwrap()
            .provenance
            .unwrap();
        assert!(p.settings.unwrap_err().contains("lines 1, 2"));
    }
}
