//! `decophantom fit`: least squares of the phantom model to measured radii over all experiments
//! at once. Wiring only: the work is in [`crate::fit`].

use crate::error::{Error, InputError};
use crate::fit::data::{
    check_against, read_experiments, read_measurements, Experiments, Measurements,
};
use crate::fit::journal::Evaluations;
use crate::fit::lsq::LsqOptions;
use crate::fit::model::{fit, Fitted, Model};
use crate::fit::paths::{self, ParamSpec};
use crate::fit::report::fit_outputs;
use std::path::PathBuf;
use std::sync::Arc;

/// What `fit` needs.
#[derive(Debug, Clone)]
pub struct FitRequest {
    /// measurements.csv.
    pub measured: PathBuf,
    /// experiments.toml.
    pub experiments: PathBuf,
    /// `NAME` or `NAME=LO..HI`, each a phantom TOML path holding a number (added to `[fit]
    /// free`; a path given there too is refused).
    pub params: Vec<String>,
    /// Output folder.
    pub out: PathBuf,
    /// The command line, for the report.
    pub command: String,
}

/// Fit and write `fit.toml`, `report.md`, `report.html` and the overlays; the journal
/// ([`fit_journaled`]) is removed once they are written.
pub fn run(req: &FitRequest) -> Result<Fitted, Error> {
    let (fitted, experiments, data) = fit_journaled(req)?;
    let model = &fitted.model;
    let start_runs = model.run(&experiments, &model.start())?;
    let fitted_runs = model.run(&experiments, &fitted.values)?;
    let set = fit_outputs(
        &fitted,
        &start_runs,
        &fitted_runs,
        &experiments,
        &data,
        &req.command,
    )?;
    let inputs = [req.measured.as_path(), req.experiments.as_path()];
    set.commit_with_inputs(&req.out, &inputs)?;
    if let Some(ev) = &model.evaluations {
        ev.finish();
    }
    Ok(fitted)
}

/// The fit of `req`, its journal `OUT.partial/` open beside the output folder
/// ([`crate::fit::journal`]): every simulation is kept there as it finishes, and those an
/// earlier, unfinished fit of the same work left there are read back instead of run; a journal
/// of other work is refused (exit 2). Nothing is written to the output folder; the journal
/// stays open (in the fitted model's [`Model::evaluations`]) for the caller to finish once the
/// output is written. Also returns the experiments and measurements read.
pub fn fit_journaled(req: &FitRequest) -> Result<(Fitted, Experiments, Measurements), Error> {
    // the output folder is checked before any fitting (and again at the commit)
    let inputs = [req.measured.as_path(), req.experiments.as_path()];
    crate::report::output::check_target(&req.out, &inputs)?;
    let data = read_measurements(&req.measured)?;
    let experiments = read_experiments(&req.experiments)?;
    check_against(&data, &experiments)?;
    let mut model = Model::baseline(&experiments)?;
    let files: Vec<&std::path::Path> = experiments
        .list
        .iter()
        .map(|e| e.phantom_path.as_path())
        .collect();
    let refused = |m: String| -> Error {
        InputError::new(m)
            .in_file("<command line>")
            .field("--param")
            .into()
    };
    let in_file = model.free.len();
    for p in &req.params {
        let path = p.split_once('=').map_or(p.as_str(), |x| x.0).trim();
        if let Some(m) = paths::not_a_number(&model.docs, &files, path) {
            return Err(refused(m));
        }
        let base = if path.starts_with(paths::SCALE_PREFIX) {
            Some(1.0)
        } else {
            model.docs.iter().find_map(|d| paths::get(d, path))
        };
        let spec = ParamSpec::parse(p, base)?;
        if model.free[..in_file].iter().any(|s| s.path == spec.path) {
            return Err(refused(format!(
                "'{}' is also in [fit] free of {}{}; a parameter is fitted once: give it in one place (--param to give it bounds)",
                spec.path,
                experiments.file.display(),
                experiments
                    .free_line
                    .map(|l| format!(" (line {l})"))
                    .unwrap_or_default()
            )));
        }
        if model.free.iter().any(|s| s.path == spec.path) {
            return Err(refused(format!(
                "'{}' is given twice on the command line; give each --param once",
                spec.path
            )));
        }
        // the start and both bounds must be values the phantom reader accepts at this path:
        // tried on the phantoms now, before any simulation
        spec.check_settable(p.trim(), &model.docs, &files)?;
        model.free.push(spec);
    }
    if model.free.is_empty() {
        return Err(InputError::new(
            "nothing to fit: give --param NAME (a phantom TOML path such as gases.n2.diffusivity) or [fit] free in the experiments file",
        )
        .in_file("<command line>")
        .field("--param")
        .into());
    }
    crate::fit::model::enough_observations(&data, model.free.len())?;
    let weights = data.weights();
    let opts = LsqOptions::default();
    let fingerprint = crate::fit::journal::fingerprint(
        "fit",
        &[
            crate::fit::journal::work_text(&experiments, &data),
            format!("free {:?}", model.free),
            format!("{opts:?}"),
        ],
    );
    let evaluations = Arc::new(Evaluations::open(&req.out, &fingerprint, "fit")?);
    let model = model.with_evaluations(Some(evaluations.clone()));
    match fit(&model, &experiments, &data, &weights, &opts) {
        Ok(fitted) => Ok((fitted, experiments, data)),
        Err(e) => {
            evaluations.abandon();
            Err(e)
        }
    }
}

/// A short text summary of a fit.
pub fn summary_text(f: &Fitted) -> String {
    use crate::fit::report::sig;
    use crate::fit::report::{aicc_absent, estimate_stats};
    let mut s = String::new();
    for e in &f.inference.estimates {
        let interval = match estimate_stats(e, f.inference.singular).1 {
            Ok(c) => format!(
                "95 % interval {} … {}{}",
                sig(c[0], 4),
                sig(c[1], 4),
                if e.clipped {
                    ", clipped to the bounds"
                } else {
                    ""
                }
            ),
            Err(m) => format!("95 % interval {m}"),
        };
        s.push_str(&format!(
            "{} = {} ({interval}){}\n",
            e.name,
            sig(e.value, 4),
            if e.at_bound { " at a bound" } else { "" }
        ));
    }
    s.push_str(&format!(
        "n = {}, SSR = {}, RMSE = {} µm, AICc = {}; {}\n",
        f.n,
        sig(f.ssr, 4),
        sig(f.rmse * 1e6, 4),
        match aicc_absent(f.aicc, f.ssr, f.n, f.p()) {
            None => sig(f.aicc, 5),
            Some(_) => "not given (see fit.toml, [absent])".into(),
        },
        f.lsq.termination
    ));
    if let Some(ev) = &f.model.evaluations {
        s.push_str(&ev.resumed_text("fit"));
    }
    s
}
