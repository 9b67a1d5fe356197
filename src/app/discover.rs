//! `decophantom discover`: fit the baseline, diagnose it, try every candidate effect and add
//! those the data need. Wiring only: the work is in [`crate::discover`].

use crate::discover::report::discover_outputs;
use crate::discover::search::{
    check_search, discover_with, fingerprint, DiscoverOptions, Discovery,
};
use crate::error::{Error, InputError};
use crate::fit::data::{
    check_against, read_experiments, read_measurements, Experiments, Measurements,
};
use crate::fit::journal::Evaluations;
use std::path::PathBuf;
use std::sync::Arc;

/// What `discover` needs.
#[derive(Debug, Clone)]
pub struct DiscoverRequest {
    /// measurements.csv.
    pub measured: PathBuf,
    /// experiments.toml.
    pub experiments: PathBuf,
    /// Output folder.
    pub out: PathBuf,
    /// Family-wise α.
    pub alpha: f64,
    /// Most effects added.
    pub max_effects: usize,
    /// Only candidates whose names start with these.
    pub only: Vec<String>,
    /// The command line, for the report.
    pub command: String,
}

/// Run the search and write `discover.toml`, `report.md`, `report.html` and the overlays.
pub fn run(
    req: &DiscoverRequest,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Discovery, Error> {
    let (d, experiments, data) = discover_journaled(req, progress)?;
    let inputs = [req.measured.as_path(), req.experiments.as_path()];
    let base_runs = d.baseline.model.run(&experiments, &d.baseline.values)?;
    let final_runs = d.final_fit.model.run(&experiments, &d.final_fit.values)?;
    let set = discover_outputs(
        &d,
        &base_runs,
        &final_runs,
        &experiments,
        &data,
        &req.command,
    )?;
    set.commit_with_inputs(&req.out, &inputs)?;
    if let Some(ev) = &d.final_fit.model.evaluations {
        ev.finish();
    }
    Ok(d)
}

/// The search of `req`, its journal `OUT.partial/` open beside the output folder
/// ([`crate::fit::journal`]): every simulation of every fit is kept there as it finishes, and
/// those an earlier, unfinished search of the same work left there are read back instead of
/// run; a journal of other work is refused (exit 2). Nothing is written to the output folder;
/// the journal stays open (in the fitted models' `evaluations`) for the caller to finish once
/// the output is written. Also returns the experiments and measurements read.
pub fn discover_journaled(
    req: &DiscoverRequest,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<(Discovery, Experiments, Measurements), Error> {
    if !(req.alpha > 0.0 && req.alpha < 1.0) {
        return Err(
            InputError::new(format!("must be in (0, 1) (got {})", req.alpha))
                .in_file("<command line>")
                .field("--alpha")
                .into(),
        );
    }
    if req.max_effects == 0 {
        // a search that may add nothing tests no candidate: its "nothing missing" would be
        // a conclusion it never drew
        return Err(InputError::new(
            "must be at least 1 (0 would test no candidate; to fit the model as it is, use `fit`)",
        )
        .in_file("<command line>")
        .field("--max-effects")
        .into());
    }
    // the output folder is checked before any fitting (and again at the commit)
    let inputs = [req.measured.as_path(), req.experiments.as_path()];
    crate::report::output::check_target(&req.out, &inputs)?;
    let data = read_measurements(&req.measured)?;
    let experiments = read_experiments(&req.experiments)?;
    check_against(&data, &experiments)?;
    let opts = DiscoverOptions {
        alpha: req.alpha,
        max_effects: req.max_effects,
        only: req.only.clone(),
        ..DiscoverOptions::default()
    };
    // --only and the number of observations, before the journal is opened
    check_search(&experiments, &data, &opts)?;
    let fp = fingerprint(&experiments, &data, &opts);
    let evaluations = Arc::new(Evaluations::open(&req.out, &fp, "discovery")?);
    match discover_with(
        &experiments,
        &data,
        &opts,
        progress,
        Some(evaluations.clone()),
    ) {
        Ok(d) => Ok((d, experiments, data)),
        Err(e) => {
            evaluations.abandon();
            Err(e)
        }
    }
}

/// A short text summary.
pub fn summary_text(d: &Discovery) -> String {
    use crate::fit::report::sig;
    let mut s = String::new();
    if d.effects.is_empty() {
        s.push_str("no missing effect found among the candidates tried\n");
    }
    for a in &d.added {
        s.push_str(&format!(
            "added {} (F-test p {}): {}\n",
            a.effect,
            crate::discover::report::p_text(a.p_value),
            a.parameters
                .iter()
                .map(|e| {
                    // the reader's words (symbol, unit), as the report names them
                    let (symbol, unit) = crate::fit::paths::describe_in(&e.name, None);
                    let unit = unit.map_or(String::new(), |u| format!(" {u}"));
                    format!(
                        "{symbol} = {}{unit} {}",
                        sig(e.value, 4),
                        match crate::fit::report::estimate_stats(e, d.final_fit.inference.singular)
                            .1
                        {
                            Ok(c) => format!("[{}, {}]", sig(c[0], 4), sig(c[1], 4)),
                            Err(m) => format!("(interval {m})"),
                        }
                    )
                })
                .collect::<Vec<_>>()
                .join("; ")
        ));
        if !a.alternatives.is_empty() {
            s.push_str(&format!(
                "  not uniquely identified: {} fit(s) as well within the numerical error\n",
                a.alternatives
                    .iter()
                    .map(|x| x.0.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
    s.push_str(&format!(
        "RMSE {} → {} µm (numerical error {} µm)\n",
        sig(d.baseline.rmse * 1e6, 4),
        sig(d.final_fit.rmse * 1e6, 4),
        sig(d.numerical.rms * 1e6, 3)
    ));
    if let Some(ev) = &d.final_fit.model.evaluations {
        s.push_str(&ev.resumed_text("discovery"));
    }
    s
}
