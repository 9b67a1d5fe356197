//! `decophantom synth`: measured-like data from the model with effects switched on. Wiring
//! only: the work is in [`crate::fit::synth`].
//!
//! `--out` is one CSV file, written whole, and checked before any simulation by the rule of
//! every single output file ([`crate::report::output::check_new_file`]): it ends with a comment
//! line holding the hash of the lines above it (`measurements.csv` readers skip `#` lines), and
//! an existing file is replaced only if `synth` wrote it and it is unchanged since; a user's
//! file, an edited one, a folder, an input of the run or a place that cannot be written is
//! refused (exit 2, naming `--out`).

use crate::error::Error;
use crate::fit::data::read_experiments;
use crate::fit::synth::{synthesize, EffectSetting};
use crate::report::output::{check_new_file, write_new_file, CommentStyle};
use std::path::{Path, PathBuf};

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
    // never overwrite an input, a folder or a user's file: checked before any simulation
    let mut inputs: Vec<&Path> = vec![req.experiments.as_path()];
    inputs.extend(experiments.list.iter().map(|e| e.phantom_path.as_path()));
    check_new_file(&req.out, &inputs, "--out", "synth")?;
    let effects = req
        .effects
        .iter()
        .map(|e| EffectSetting::parse(e))
        .collect::<Result<Vec<_>, _>>()?;
    let text = synthesize(&experiments, &effects, req.noise_sd, req.every, req.seed)?;
    // the data rows: every line but the header and the comment lines (the settings, the marker)
    let rows = text
        .lines()
        .filter(|l| !l.starts_with('#'))
        .count()
        .saturating_sub(1);
    // checked again just before the file is put in place (it may have appeared meanwhile)
    write_new_file(
        &req.out,
        &text,
        CommentStyle::Hash,
        &inputs,
        "--out",
        "synth",
    )?;
    Ok(rows)
}
