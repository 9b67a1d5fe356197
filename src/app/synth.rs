//! `decophantom synth`: measured-like data from the model with effects switched on. Wiring
//! only: the work is in [`crate::fit::synth`].

use crate::error::Error;
use crate::fit::data::read_experiments;
use crate::fit::synth::{synthesize, EffectSetting};
use crate::report::output::write_file_atomic;
use std::path::PathBuf;

/// What `synth` needs.
#[derive(Debug, Clone)]
pub struct SynthRequest {
    /// experiments.toml.
    pub experiments: PathBuf,
    /// Effects (`NAME=VALUE[,VALUE]`).
    pub effects: Vec<String>,
    /// Noise sd, m.
    pub noise_sd: f64,
    /// Sampling interval, s.
    pub every: f64,
    /// Seed.
    pub seed: u64,
    /// Output CSV.
    pub out: PathBuf,
}

/// Write the CSV; returns the number of rows.
pub fn run(req: &SynthRequest) -> Result<usize, Error> {
    let experiments = read_experiments(&req.experiments)?;
    // never overwrite an input
    let same = |a: &std::path::Path| {
        a.canonicalize()
            .ok()
            .is_some_and(|a| req.out.canonicalize().ok().is_some_and(|b| a == b))
    };
    if same(&req.experiments) || experiments.list.iter().any(|e| same(&e.phantom_path)) {
        return Err(crate::error::InputError::new(
            "the output would overwrite an input file; choose another --out",
        )
        .in_file(&req.out)
        .field("--out")
        .into());
    }
    let effects = req
        .effects
        .iter()
        .map(|e| EffectSetting::parse(e))
        .collect::<Result<Vec<_>, _>>()?;
    let text = synthesize(&experiments, &effects, req.noise_sd, req.every, req.seed)?;
    write_file_atomic(&req.out, text.as_bytes())?;
    Ok(text.lines().count().saturating_sub(1))
}
