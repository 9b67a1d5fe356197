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
        match discover::find(
            &discover::Phantoms {
                docs: &docs,
                vapour_pa: experiments.vapour_pa(),
            },
            &e.name,
        ) {
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
                }
            }
            None if e.name.contains('.') && e.values.len() == 1 => {
                set_shared(&mut docs, &e.name, e.values[0]).map_err(bad)?;
                paths_set.push(e.name.clone());
            }
            None => {
                let names: Vec<String> = discover::all_candidates(&discover::Phantoms {
                    docs: &docs,
                    vapour_pa: experiments.vapour_pa(),
                })
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
    Ok(Model {
        docs,
        free: Vec::new(),
        evaluations: None,
    })
}

/// Most rows `synth` writes: 10⁶ (about 50 MB of CSV; a fit simulates every experiment for
/// each of its steps whatever the rows, but 10⁶ rows are already far more than any imaging
/// series). Checked before any simulation from each profile's duration.
pub const MAX_ROWS: usize = 1_000_000;

/// Synthesise `measurements.csv` text: every bubble of every experiment sampled at 0, `every`,
/// 2·`every`, … s while it exists, with N(0, `noise_sd`²) added (clamped at 0) and `sd_m` =
/// `noise_sd` in every row. The CSV is written by the `csv` crate (a name holding a comma, a
/// quote or `#` is quoted) and read back by `fit`'s own reader before it is returned, so what
/// `synth` writes `fit` reads as written. Refused before any simulation (exit 2, naming
/// `<command line>` and the option): a noise sd outside the range `measurements.csv` accepts
/// for `sd_m` (1 nm ..= 1 cm, [`super::data::MIN_SD_M`]), an interval `every` that is not a
/// positive number or would give more than [`MAX_ROWS`] rows.
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
    let mut w = csv::WriterBuilder::new()
        .comment(Some(b'#'))
        .from_writer(Vec::new());
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
                let y = (r + noise_sd * normal()).max(0.0);
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
