//! `decophantom synth`: measured-like radius data from the model, with candidate effects
//! switched on at given values, sampled every `every` seconds and with Gaussian noise (seeded
//! ChaCha8; Box–Muller). For tests of `fit`/`discover` and for planning experiments ("would we
//! see this effect with our imaging noise?").

use super::data::Experiments;
use super::model::{set_shared, Model};
use crate::discover;
use crate::error::{Error, InputError};
use rand::SeedableRng;

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

/// The model with `effects` switched on (documents edited, no free parameters).
pub fn model_with(experiments: &Experiments, effects: &[EffectSetting]) -> Result<Model, Error> {
    let mut docs: Vec<toml::Table> = experiments.list.iter().map(|e| e.phantom.clone()).collect();
    for e in effects {
        let bad = |m: String| {
            Error::Input(
                InputError::new(m)
                    .in_file("<command line>")
                    .field("--effect"),
            )
        };
        match discover::find(&docs, &e.name) {
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
                }
            }
            None if e.name.contains('.') && e.values.len() == 1 => {
                set_shared(&mut docs, &e.name, e.values[0]).map_err(bad)?;
            }
            None => {
                let names: Vec<String> = discover::all_candidates(&docs)
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
    }
    Ok(Model {
        docs,
        free: Vec::new(),
        evaluations: None,
    })
}

/// Synthesise `measurements.csv` text: every bubble of every experiment sampled at 0, `every`,
/// 2·`every`, … s while it exists, with N(0, `noise_sd`²) added (clamped at 0) and `sd_m` =
/// `noise_sd` in every row.
pub fn synthesize(
    experiments: &Experiments,
    effects: &[EffectSetting],
    noise_sd: f64,
    every: f64,
    seed: u64,
) -> Result<String, Error> {
    let bad =
        |f: &str, m: String| Error::Input(InputError::new(m).in_file("<command line>").field(f));
    if !(noise_sd > 0.0 && noise_sd.is_finite()) {
        return Err(bad(
            "--noise-sd",
            format!("must be a positive radius in m (got {noise_sd})"),
        ));
    }
    if !(every > 0.0 && every.is_finite()) {
        return Err(bad(
            "--every",
            format!("must be a positive time in s (got {every})"),
        ));
    }
    let model = model_with(experiments, effects)?;
    let runs = model.run(experiments, &[])?;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut normal = move || super::stats::standard_normal(&mut rng);
    let mut out = String::from("experiment,bubble,time_s,radius_m,sd_m\n");
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
                out.push_str(&format!("{},{b},{t},{y:.9e},{noise_sd:.6e}\n", e.name));
            }
        }
    }
    Ok(out)
}
