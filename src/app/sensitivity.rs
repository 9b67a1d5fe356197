//! `decophantom sensitivity` and `decophantom merge`: wiring only; the work is in
//! [`crate::sweep`].

use crate::error::{Error, InputError};
use crate::profile::LoadOptions;
use crate::run::load_profile_or_schedule;
use crate::sweep::run::{merge, run_study, Results, Shard, Study};
use crate::sweep::{Method, Metric, Param, StudySpec};
use std::path::PathBuf;

/// What `sensitivity` needs.
#[derive(Debug, Clone)]
pub struct SensitivityRequest {
    /// Phantom TOML.
    pub phantom: PathBuf,
    /// Pressure profile (anything `simulate --profile` reads).
    pub profile: PathBuf,
    /// `NAME=LO..HI`, each a phantom TOML path or `scale:` pattern.
    pub params: Vec<String>,
    /// Metric names (`r_max`, `r_max:0`, …).
    pub metrics: Vec<String>,
    /// `oat`, `morris` or `sobol`.
    pub method: String,
    /// Levels (oat), trajectories (morris), base rows (sobol).
    pub samples: usize,
    /// Seed of the design.
    pub seed: u64,
    /// `I/N`, or the whole design.
    pub shard: Option<String>,
    /// Output folder.
    pub out: PathBuf,
    /// The command line, for the report.
    pub command: String,
}

fn cli_err(field: &str, m: String) -> Error {
    InputError::new(m)
        .in_file("<command line>")
        .field(field)
        .into()
}

/// Read the inputs, check them all, run the (shard of the) design and write the outputs.
pub fn run(
    req: &SensitivityRequest,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Results, Error> {
    let method = Method::parse(&req.method).ok_or_else(|| {
        cli_err(
            "--method",
            format!("unknown method '{}'; use oat, morris or sobol", req.method),
        )
    })?;
    // the output folder is checked before any run
    crate::report::output::check_target(&req.out, &[req.phantom.as_path(), req.profile.as_path()])?;
    // --samples against the method (at least 2; Sobol' at least SOBOL_MIN_SAMPLES), before
    // anything is read
    StudySpec {
        method,
        samples: req.samples,
        seed: req.seed,
        params: Vec::new(),
        metrics: Vec::new(),
    }
    .check_samples()?;
    let text = crate::error::read_text(&req.phantom, "the phantom")?;
    let doc: toml::Table = text
        .parse()
        .map_err(|e| InputError::new(format!("not valid TOML: {e}")).in_file(&req.phantom))?;
    if req.params.is_empty() {
        return Err(cli_err(
            "--param",
            "give at least one --param NAME=LO..HI (a phantom TOML path)".into(),
        ));
    }
    let params = req
        .params
        .iter()
        .map(|p| Param::parse(p, &doc))
        .collect::<Result<Vec<_>, _>>()?;
    for (i, p) in params.iter().enumerate() {
        if params[..i].iter().any(|q| q.path == p.path) {
            return Err(cli_err("--param", format!("'{}' is given twice", p.path)));
        }
    }
    if req.metrics.is_empty() {
        return Err(cli_err(
            "--metric",
            "give at least one --metric (r_max, t_max, plateau, half_life, peak_volume, final_radius)".into(),
        ));
    }
    let metrics = req
        .metrics
        .iter()
        .map(|m| Metric::parse(m))
        .collect::<Result<Vec<_>, _>>()?;
    // the same metric twice (compared by canonical name: `r_max:0` and `r_max:00` are one)
    // would give its column and indices twice
    for (i, m) in metrics.iter().enumerate() {
        if metrics[..i].iter().any(|q| q.name() == m.name()) {
            return Err(cli_err(
                "--metric",
                format!("'{}' is given twice", m.name()),
            ));
        }
    }
    let shard = match &req.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::WHOLE,
    };
    let profile = load_profile_or_schedule(&req.profile, &LoadOptions::default())?;
    let study = Study {
        spec: StudySpec {
            method,
            samples: req.samples,
            seed: req.seed,
            params,
            metrics,
        },
        doc,
        phantom_path: req.phantom.clone(),
        profile,
    };
    run_study(&study, shard, &req.out, &req.command, progress)
}

/// Merge shard folders into one study with its indices and report.
pub fn run_merge(dirs: &[PathBuf], out: &std::path::Path, command: &str) -> Result<Results, Error> {
    merge(dirs, out, command)
}

/// A short text summary: the runs and the indices; for a shard (whose rows alone give no
/// indices) the runs it holds and how to get the indices. Counts (`n_used`, `n_dropped`) are
/// printed as whole numbers.
pub fn summary_text(r: &Results) -> String {
    if !r.is_whole() {
        let n = r.spec.runs().unwrap_or(0);
        let range = r.shard.range(n);
        return format!(
            "shard {}/{}: {} runs of the design's {n} (runs {}…{}; {} resumed from the journal)\nno indices from a shard: merge every shard's folder (decophantom merge DIR… --out DIR)\n",
            r.shard.index,
            r.shard.count,
            r.rows.len(),
            range.start,
            range.end.saturating_sub(1),
            r.resumed
        );
    }
    let mut s = format!(
        "{} runs ({} resumed from the journal)\n",
        r.rows.len(),
        r.resumed
    );
    let (h, rows) = crate::sweep::report::indices(r);
    for (m, p, v) in rows {
        let vals: Vec<String> = h
            .iter()
            .zip(&v)
            .map(|(n, x)| {
                if n.starts_with("n_") && x.is_finite() {
                    format!("{n} {x:.0}")
                } else {
                    format!("{n} {}", crate::fit::report::sig(*x, 3))
                }
            })
            .collect();
        // a Sobol' estimate outside [0, 1] is flagged, not printed as an index
        let out = if r.spec.method == Method::Sobol {
            crate::sweep::report::sobol_outside_unit(&v)
        } else {
            Vec::new()
        };
        let flag = if out.is_empty() {
            String::new()
        } else {
            format!(
                " ({}: {})",
                out.join(", "),
                crate::sweep::report::OUTSIDE_UNIT
            )
        };
        s.push_str(&format!("{m} / {p}: {}{flag}\n", vals.join(", ")));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sweep::run::Row;

    /// A study of one parameter `a.x` over 0..1 and the metric `r_max`.
    fn one_parameter(method: Method, samples: usize) -> StudySpec {
        StudySpec {
            method,
            samples,
            seed: 1,
            params: vec![Param {
                path: "a.x".into(),
                lo: 0.0,
                hi: 1.0,
                log: false,
                base: 0.5,
            }],
            metrics: vec![Metric::parse("r_max").unwrap()],
        }
    }

    #[test]
    fn sweep_summary_of_a_shard_has_no_indices_and_counts_print_as_integers() {
        // a Morris design of 1 parameter and 4 trajectories (8 runs), y = u: every elementary
        // effect is Δ/Δ = 1, so μ* = μ = 1, σ = 0 from 4 effects, none dropped
        let spec = one_parameter(Method::Morris, 4);
        let rows: Vec<Row> = spec
            .values()
            .into_iter()
            .enumerate()
            .map(|(index, v)| Row {
                index,
                metrics: vec![v[0]],
                values: v,
            })
            .collect();
        let whole = Results {
            spec,
            shard: Shard::WHOLE,
            rows,
            courses: Vec::new(),
            resumed: 0,
            inputs: None,
        };
        let s = summary_text(&whole);
        assert!(
            s.contains("r_max / a.x: mu_star 1.00, mu 1.00, sigma 0, n_used 4, n_dropped 0\n"),
            "{s}"
        );
        // the 2nd of 3 shards: runs ⌊8/3⌋ = 2 … ⌊16/3⌋ − 1 = 4
        let shard = Shard { index: 1, count: 3 };
        let mut part = whole.clone();
        part.shard = shard;
        part.rows.retain(|r| (2..5).contains(&r.index));
        let s = summary_text(&part);
        assert!(
            s.starts_with("shard 1/3: 3 runs of the design's 8 (runs 2…4;"),
            "{s}"
        );
        assert!(s.contains("no indices") && !s.contains("mu_star"), "{s}");
    }

    #[test]
    fn sweep_sobol_estimates_outside_the_unit_interval_are_flagged_not_printed_silently() {
        // N = 2 base rows of one parameter (rows A, B, A_B): f(A) = 0, 1; f(B) = 1, 0;
        // f(A_B) = f(B): the variance of {0, 1, 1, 0} is 1/4 and both estimators give 2
        let spec = one_parameter(Method::Sobol, 2);
        let y = [0.0, 1.0, 1.0, 1.0, 0.0, 0.0];
        let rows: Vec<Row> = spec
            .values()
            .into_iter()
            .zip(y)
            .enumerate()
            .map(|(index, (values, m))| Row {
                index,
                values,
                metrics: vec![m],
            })
            .collect();
        let res = Results {
            spec,
            shard: Shard::WHOLE,
            rows,
            courses: Vec::new(),
            resumed: 0,
            inputs: None,
        };
        let (_, idx, notes) = crate::sweep::report::indices_and_notes(&res);
        assert_eq!((idx[0].2[0], idx[0].2[3]), (2.0, 2.0), "{idx:?}");
        let s = summary_text(&res);
        assert!(
            s.contains("(S1, ST: estimate outside [0, 1]: estimator noise)"),
            "{s}"
        );
        assert!(
            notes
                .iter()
                .any(|n| n.starts_with("r_max / a.x: estimate outside [0, 1]: estimator noise: S1 and ST from 2 usable base rows")),
            "{notes:?}"
        );
        // inside [0, 1] nothing is flagged; NaN (undefined) has notes of its own
        let ok = [0.3, 0.0, 1.0, 0.5, 0.2, 0.9, 16.0, 0.0];
        assert!(crate::sweep::report::sobol_outside_unit(&ok).is_empty());
        let nan = [f64::NAN; 6];
        assert!(crate::sweep::report::sobol_outside_unit(&nan).is_empty());
        // an index near 0 whose interval straddles 0 is not flagged; an estimate below 0 is
        let near_zero = [0.01, -0.02, 0.05, 0.5, 0.2, 0.9];
        assert!(crate::sweep::report::sobol_outside_unit(&near_zero).is_empty());
        let low = [-0.01, -0.04, 0.02, 1.2, 0.7, 1.9];
        assert_eq!(crate::sweep::report::sobol_outside_unit(&low), ["S1", "ST"]);
    }
}
