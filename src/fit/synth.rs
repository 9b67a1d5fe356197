//! `decophantom synth`: measured-like radius data from the model, with candidate effects
//! switched on at given values, sampled every `every` seconds and with Gaussian noise (seeded
//! ChaCha8; Box–Muller). For tests of `fit`/`discover` and for planning experiments ("would we
//! see this effect with our imaging noise?").

use super::data::Experiments;
use super::model::{set_shared, Model};
use crate::discover;
use crate::error::{Error, InputError};
use rand::SeedableRng;
use std::path::Path;

/// An effect to switch on: a candidate name (`perfusion`, `surface-area-law`,
/// `sealed-faces:top`, …) or a phantom path, with its parameter values.
#[derive(Debug, Clone, PartialEq)]
pub struct EffectSetting {
    /// Candidate name or TOML path.
    pub name: String,
    /// Values, in the candidate's parameter order.
    pub values: Vec<f64>,
}

impl EffectSetting {
    /// Parse `NAME=V[,V2]` or `NAME` (a discrete candidate).
    pub fn parse(s: &str) -> Result<EffectSetting, InputError> {
        let bad = |m: String| {
            InputError::new(m)
                .in_file("<command line>")
                .field("--effect")
        };
        let (name, vals) = match s.split_once('=') {
            Some((n, v)) => (n.trim(), v),
            None => (s.trim(), ""),
        };
        if name.is_empty() {
            return Err(bad(format!("'{s}': write NAME=VALUE, e.g. perfusion=2e-3")));
        }
        let mut values = Vec::new();
        for v in vals.split(',').filter(|v| !v.trim().is_empty()) {
            values.push(
                v.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| bad(format!("'{s}': '{v}' is not a finite number")))?,
            );
        }
        Ok(EffectSetting {
            name: name.to_string(),
            values,
        })
    }
}

/// The model with `effects` switched on (documents edited, no free parameters). Refused (exit
/// 2, naming `<command line>` and `--effect`, never a phantom's line): an effect given twice,
/// two effects that set the same setting, an effect that does not apply, the wrong number of
/// values, and a value the phantom reader does not accept at its setting (each effect's values
/// are written into every phantom and read back by the phantom reader, so its ranges apply).
pub fn model_with(experiments: &Experiments, effects: &[EffectSetting]) -> Result<Model, Error> {
    model_and_paths(experiments, effects).map(|(m, _)| m)
}

/// [`model_with`] and every phantom path the effects set with the value set there, in order
/// (a candidate's parameter paths, as `discover` names its estimates; a phantom-path effect's
/// own path).
pub fn model_and_paths(
    experiments: &Experiments,
    effects: &[EffectSetting],
) -> Result<(Model, Vec<(String, f64)>), Error> {
    let mut set_values: Vec<(String, f64)> = Vec::new();
    let mut docs: Vec<toml::Table> = experiments.list.iter().map(|e| e.phantom.clone()).collect();
    let bad = |m: String| {
        Error::Input(
            InputError::new(m)
                .in_file("<command line>")
                .field("--effect"),
        )
    };
    for (i, e) in effects.iter().enumerate() {
        if effects[..i].iter().any(|x| x.name == e.name) {
            return Err(bad(format!(
                "effect '{}' is given twice; give each effect once",
                e.name
            )));
        }
    }
    // the settings each effect wrote, to refuse a second effect writing one of them
    let mut set_by: Vec<(String, String)> = Vec::new();
    for e in effects {
        let mut paths_set: Vec<String> = Vec::new();
        match discover::find(&discover::Phantoms::of(experiments, &docs), &e.name) {
            Some(c) => {
                let prepared = c.prepare(&mut docs).map_err(bad)?.ok_or_else(|| {
                    bad(format!(
                        "effect '{}' does not apply to these phantoms",
                        e.name
                    ))
                })?;
                if prepared.params.len() != e.values.len() {
                    return Err(bad(format!(
                        "effect '{}' takes {} value(s) ({}); got {}",
                        e.name,
                        prepared.params.len(),
                        prepared
                            .params
                            .iter()
                            .map(|p| p.spec.path.as_str())
                            .collect::<Vec<_>>()
                            .join(", "),
                        e.values.len()
                    )));
                }
                for (p, v) in prepared.params.iter().zip(&e.values) {
                    set_shared(&mut docs, &p.spec.path, *v).map_err(bad)?;
                    paths_set.push(p.spec.path.clone());
                    set_values.push((p.spec.path.clone(), *v));
                }
            }
            None if e.name.contains('.') && e.values.len() == 1 => {
                set_shared(&mut docs, &e.name, e.values[0]).map_err(bad)?;
                paths_set.push(e.name.clone());
                set_values.push((e.name.clone(), e.values[0]));
            }
            None => {
                let names: Vec<String> =
                    discover::all_candidates(&discover::Phantoms::of(experiments, &docs))
                        .iter()
                        .map(|c| c.name())
                        .collect();
                return Err(bad(format!(
                    "unknown effect '{}'; known: {} (or a phantom path such as gases.n2.diffusivity=2e-9)",
                    e.name,
                    names.join(", ")
                )));
            }
        }
        for p in &paths_set {
            if let Some((_, other)) = set_by.iter().find(|(q, _)| q == p) {
                return Err(bad(format!(
                    "effects '{other}' and '{}' both set {p}; give one of them",
                    e.name
                )));
            }
        }
        set_by.extend(paths_set.iter().map(|p| (p.clone(), e.name.clone())));
        // the values must be ones the phantom reader accepts there: read every phantom back
        for (d, x) in docs.iter().zip(&experiments.list) {
            if let Err(pe) = super::data::build_params(d, &x.phantom_path) {
                let values: Vec<String> = e.values.iter().map(|v| crate::error::num(*v)).collect();
                return Err(bad(format!(
                    "'{}={}' is not accepted in {}: {}{}",
                    e.name,
                    values.join(","),
                    x.phantom_path.display(),
                    pe.field
                        .as_deref()
                        .map(|f| format!("field '{f}': "))
                        .unwrap_or_default(),
                    pe.message
                )));
            }
        }
    }
    Ok((
        Model {
            docs,
            free: Vec::new(),
            evaluations: None,
        },
        set_values,
    ))
}

/// FNV-1a 64 of the experiments synthetic data are made from: each experiment's name, bubble
/// count, profile and phantom document (not the paths they were read from). Recorded in the
/// [`super::data::SYNTHETIC_TAG`] line, so a report gives true values only for the
/// experiments the data were made from.
pub fn experiments_hash(experiments: &Experiments) -> u64 {
    crate::phantom::checkpoint::fnv1a(super::journal::experiments_text(experiments).as_bytes())
}

/// The [`super::data::SYNTHETIC_TAG`] line `synth` writes above its CSV's header (with its
/// line break): the command that makes the same rows from the same experiments, and the
/// experiments' [`experiments_hash`]. Every number is written in round-trip notation.
pub fn provenance_line(
    experiments: &Experiments,
    effects: &[EffectSetting],
    noise_sd: f64,
    every: f64,
    seed: u64,
) -> String {
    use crate::error::num;
    let mut s = format!("{}decophantom synth", super::data::SYNTHETIC_TAG);
    for e in effects {
        s.push_str(" --effect ");
        s.push_str(&e.name);
        if !e.values.is_empty() {
            let v: Vec<String> = e.values.iter().map(|v| num(*v)).collect();
            s.push('=');
            s.push_str(&v.join(","));
        }
    }
    s.push_str(&format!(
        " --noise-sd {} --every {} --seed {seed}; experiments fnv1a-64 {:016x}\n",
        num(noise_sd),
        num(every),
        experiments_hash(experiments)
    ));
    s
}

/// The true value of each free parameter of `model` (fitted to data `synth` made with
/// `settings` from `experiments`): `Some` for a parameter at a path the effects set (the value
/// set there), `None` for one they did not set. Given only when it is exact: the experiments
/// are those the data were made from (their [`experiments_hash`]), and the model with every
/// parameter set by the effects at its true value (every other at its value in the model's
/// phantoms) is the model `synth` ran, document for document — else the reason (an effect the
/// model lacks, a parameter of another meaning at the same path, other experiments), and no
/// value is given at all.
pub fn true_values(
    experiments: &Experiments,
    settings: &super::data::SynthSettings,
    model: &Model,
) -> Result<Vec<Option<f64>>, String> {
    match settings.experiments_hash {
        Some(h) if h == experiments_hash(experiments) => {}
        Some(_) => return Err("the experiments differ from those the data were made from".into()),
        None => return Err("the data do not record the experiments they were made from".into()),
    }
    let (synth, set) = model_and_paths(experiments, &settings.effects)
        .map_err(|e| format!("the effects cannot be set on these experiments: {e}"))?;
    let mut fitted = model.docs.clone();
    let mut truth = synth.docs;
    let mut out = Vec::with_capacity(model.free.len());
    let scale = |p: &str| p.starts_with(super::paths::SCALE_PREFIX);
    for s in &model.free {
        match set.iter().find(|(p, _)| *p == s.path) {
            Some((_, v)) => {
                set_shared(&mut fitted, &s.path, *v)?;
                // a plain path written again at its value (the same representation on both
                // sides); a scale the effects applied is already in synth's documents
                if !scale(&s.path) {
                    set_shared(&mut truth, &s.path, *v)?;
                }
                out.push(Some(*v));
            }
            None => {
                // not set by the effects: at its value in the model's phantoms on both sides
                let v = if scale(&s.path) {
                    1.0
                } else {
                    fitted
                        .iter()
                        .find_map(|d| super::paths::get(d, &s.path))
                        .ok_or_else(|| {
                            format!("{} is at its default, not in the phantoms", s.path)
                        })?
                };
                set_shared(&mut fitted, &s.path, v)?;
                set_shared(&mut truth, &s.path, v)?;
                out.push(None);
            }
        }
    }
    if fitted != truth {
        return Err(
            "with its parameters at the values synth used, the fitted model is not the model the data were made from (an effect it lacks, or a parameter of another meaning at the same path)"
                .into(),
        );
    }
    Ok(out)
}

/// Most rows `synth` writes: 10⁶ (about 50 MB of CSV; a fit simulates every experiment for
/// each of its steps whatever the rows, but 10⁶ rows are already far more than any imaging
/// series). Checked before any simulation from each profile's duration.
pub const MAX_ROWS: usize = 1_000_000;

/// Fewest samples `synth` plans for each bubble: 2, the radius at t = 0 (its starting radius,
/// which no parameter changes) and at least one later. Checked before any simulation from the
/// shortest experiment's duration (a bubble that dissolves early still gives fewer).
pub const MIN_SAMPLES_PER_BUBBLE: usize = 2;

/// Synthesise `measurements.csv` text, its first line the settings ([`provenance_line`]):
/// every bubble of every experiment sampled at 0, `every`,
/// 2·`every`, … s while it exists, with N(0, `noise_sd`²) added (clamped at the smallest
/// radius `measurements.csv` accepts, [`super::data::MIN_RADIUS_M`], 1 nm) and `sd_m` =
/// `noise_sd` in every row. The CSV is written by the `csv` crate (a name holding a comma, a
/// quote or `#` is quoted) and read back by `fit`'s own reader before it is returned, so what
/// `synth` writes `fit` reads as written. Refused before any simulation (exit 2, naming
/// `<command line>` and the option): a noise sd outside the range `measurements.csv` accepts
/// for `sd_m` (1 nm ..= 1 cm, [`super::data::MIN_SD_M`]), an interval `every` that is not a
/// positive number, would give a bubble fewer than [`MIN_SAMPLES_PER_BUBBLE`] samples (longer
/// than an experiment) or more than [`MAX_ROWS`] rows.
pub fn synthesize(
    experiments: &Experiments,
    effects: &[EffectSetting],
    noise_sd: f64,
    every: f64,
    seed: u64,
) -> Result<String, Error> {
    let bad =
        |f: &str, m: String| Error::Input(InputError::new(m).in_file("<command line>").field(f));
    use super::data::{MAX_SD_M, MIN_SD_M};
    if !(noise_sd.is_finite() && (MIN_SD_M..=MAX_SD_M).contains(&noise_sd)) {
        return Err(bad(
            "--noise-sd",
            format!(
                "must be a radius sd in m within {} ..= {} (1 nm to 1 cm, the sd_m range measurements.csv accepts; got {})",
                crate::error::num(MIN_SD_M),
                crate::error::num(MAX_SD_M),
                crate::error::num(noise_sd)
            ),
        ));
    }
    if !(every > 0.0 && every.is_finite()) {
        return Err(bad(
            "--every",
            format!("must be a positive time in s (got {every})"),
        ));
    }
    // the shortest experiment must be sampled after its start: at t = 0 alone a bubble has its
    // starting radius, which no parameter changes
    if let Some(short) = experiments
        .list
        .iter()
        .min_by(|a, b| a.profile.duration_s().total_cmp(&b.profile.duration_s()))
    {
        let duration = short.profile.duration_s();
        let samples = (duration / every + 1e-9).floor() + 1.0;
        if samples < MIN_SAMPLES_PER_BUBBLE as f64 {
            return Err(bad(
                "--every",
                format!(
                    "sampling every {} s gives each bubble of experiment '{}' (its profile lasts {} s) {} sample(s), at t = 0 only: its starting radius, which no parameter changes; a bubble needs at least {MIN_SAMPLES_PER_BUBBLE}: choose --every ≤ {} s",
                    crate::error::num(every),
                    short.name,
                    crate::error::num(duration),
                    samples,
                    crate::error::num(duration)
                ),
            ));
        }
    }
    // the most rows: every bubble sampled over its whole profile (a run that ends early, or a
    // bubble that dissolves, writes fewer)
    let bubbles: f64 = experiments.list.iter().map(|e| e.bubbles as f64).sum();
    let rows: f64 = experiments
        .list
        .iter()
        .map(|e| e.bubbles as f64 * ((e.profile.duration_s() / every + 1e-9).floor() + 1.0))
        .sum();
    if rows > MAX_ROWS as f64 {
        let bubble_seconds: f64 = experiments
            .list
            .iter()
            .map(|e| e.bubbles as f64 * e.profile.duration_s())
            .sum();
        // the least interval, rounded up to three significant digits
        let least = bubble_seconds / (MAX_ROWS as f64 - bubbles).max(1.0);
        let unit = 10f64.powf(least.log10().floor() - 2.0);
        let least = (least / unit).ceil() * unit;
        return Err(bad(
            "--every",
            format!(
                "sampling every {} s would write up to {} rows ({} bubble(s) over their profiles); at most {MAX_ROWS}: choose --every ≥ {} s",
                crate::error::num(every),
                crate::error::num(rows.round()),
                bubbles,
                crate::fit::report::sig(least, 3)
            ),
        ));
    }
    let model = model_with(experiments, effects)?;
    let runs = model.run(experiments, &[])?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut normal = move || super::stats::standard_normal(&mut rng);
    let mut w = csv::WriterBuilder::new().comment(Some(b'#')).from_writer(
        provenance_line(experiments, effects, noise_sd, every, seed)
            .as_bytes()
            .to_vec(),
    );
    let csv_err = |e: csv::Error| Error::Solver(format!("synth: writing the CSV: {e}"));
    w.write_record(["experiment", "bubble", "time_s", "radius_m", "sd_m"])
        .map_err(csv_err)?;
    let sd = format!("{noise_sd:.6e}");
    for (e, run) in experiments.list.iter().zip(&runs) {
        let end = run.summary.end_time;
        let n = (end / every + 1e-9).floor() as usize;
        for b in 0..e.bubbles {
            for k in 0..=n {
                let t = k as f64 * every;
                let r = super::model::radius_at(&run.frames, &run.summary.events, b, t);
                if !(r > 0.0) {
                    continue;
                }
                let y = (r + noise_sd * normal()).max(super::data::MIN_RADIUS_M);
                w.write_record([
                    e.name.as_str(),
                    &b.to_string(),
                    &t.to_string(),
                    &format!("{y:.9e}"),
                    &sd,
                ])
                .map_err(csv_err)?;
            }
        }
    }
    let bytes = w
        .into_inner()
        .map_err(|e| Error::Solver(format!("synth: writing the CSV: {e}")))?;
    let out = String::from_utf8(bytes)
        .map_err(|e| Error::Solver(format!("synth: the CSV is not UTF-8: {e}")))?;
    // what synth writes, fit reads as written: read back by fit's own reader
    super::data::parse_measurements(&out, Path::new("<synth output>"))
        .and_then(|m| super::data::check_against(&m, experiments))
        .map_err(|e| {
            Error::Input(
                InputError::new(format!(
                    "the data synthesised would be refused by fit, so nothing is written: {e}"
                ))
                .in_file("<command line>"),
            )
        })?;
    Ok(out)
}
