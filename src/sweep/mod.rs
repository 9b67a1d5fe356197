//! Sensitivity studies over phantom parameters (`decophantom sensitivity`, `merge`): the
//! design ([`design`]), metrics of a run ([`metric`]), running a design in parallel with a
//! resumable journal and shards ([`run`]), and the outputs ([`report`]).
//!
//! A study is fixed by its method, samples, seed, parameters (TOML path and range) and
//! metrics: the same settings give the same design, so a restarted or sharded study runs
//! exactly the runs of the whole one.

pub mod design;
pub mod metric;
pub mod report;
pub mod run;

use crate::error::InputError;
use crate::fit::paths;

pub use design::Method;
pub use metric::Metric;

/// A swept parameter: its phantom TOML path (or `scale:` pattern), range and base value.
#[derive(Debug, Clone, PartialEq)]
pub struct Param {
    /// Path in the phantom document.
    pub path: String,
    /// Lower end of the range.
    pub lo: f64,
    /// Upper end of the range.
    pub hi: f64,
    /// Sampled log-uniformly (the range spans more than a decade and is positive).
    pub log: bool,
    /// The value in the phantom (1 for a `scale:` pattern; clamped into the range).
    pub base: f64,
}

impl Param {
    /// Parse `NAME=LO..HI` against a phantom document; the path must exist in it (or be a
    /// `scale:` pattern that matches something).
    pub fn parse(text: &str, doc: &toml::Table) -> Result<Param, InputError> {
        let bad = |m: String| {
            InputError::new(m)
                .in_file("<command line>")
                .field("--param")
        };
        let path = text.split_once('=').map_or(text, |x| x.0).trim();
        if !text.contains('=') {
            return Err(bad(format!(
                "'{text}': a swept parameter needs a range, NAME=LO..HI (e.g. gases.n2.diffusivity=1e-10..5e-9)"
            )));
        }
        let base = if path.starts_with(paths::SCALE_PREFIX) {
            Some(1.0)
        } else {
            paths::get(doc, path)
        };
        // the range is checked by the same parser as `fit`'s bounds; a base outside it is
        // allowed here (the sweep need not contain the phantom's value)
        let spec = paths::ParamSpec::parse(text, None)?;
        let (lo, hi) = (spec.lower.unwrap_or(0.0), spec.upper.unwrap_or(0.0));
        // whether the path can be set at all is checked by the caller on the phantom
        let _ = &bad;
        let log = lo > 0.0 && hi / lo > 10.0;
        let base = base.unwrap_or(if log {
            (lo * hi).sqrt()
        } else {
            0.5 * (lo + hi)
        });
        Ok(Param {
            path: path.to_string(),
            lo,
            hi,
            log,
            base: base.clamp(lo, hi),
        })
    }

    /// The value at unit-cube coordinate u ∈ [0, 1].
    pub fn value(&self, u: f64) -> f64 {
        if self.log {
            self.lo * (self.hi / self.lo).powf(u)
        } else {
            self.lo + u * (self.hi - self.lo)
        }
    }

    /// The unit-cube coordinate of value x.
    pub fn unit(&self, x: f64) -> f64 {
        if self.log {
            (x / self.lo).ln() / (self.hi / self.lo).ln()
        } else {
            (x - self.lo) / (self.hi - self.lo)
        }
    }

    /// `path=lo..hi` as given.
    pub fn label(&self) -> String {
        format!("{}={}..{}", self.path, num(self.lo), num(self.hi))
    }
}

/// What fixes a design: same settings, same runs.
#[derive(Debug, Clone, PartialEq)]
pub struct StudySpec {
    /// Method.
    pub method: Method,
    /// Levels (oat), trajectories (morris) or base rows (sobol).
    pub samples: usize,
    /// Seed of the design and the bootstrap.
    pub seed: u64,
    /// Parameters.
    pub params: Vec<Param>,
    /// Metrics.
    pub metrics: Vec<Metric>,
}

/// Most runs a study may have (the whole design, every shard together): 10⁶. The design is
/// computed whole by every shard (a run's parameters depend on its place in it), so its size is
/// bounded before it is built; 10⁶ runs of the smallest useful phantom (a few hundred cells,
/// a few thousand steps: ~0.05 s each by [`crate::run::cost::SECONDS_PER_CELL_STEP`]) are
/// already ~14 core-hours, and the largest documented designs (Sobol' with N = 10⁴ and ten
/// parameters: 1.2·10⁵ runs) stay well below it.
pub const MAX_RUNS: usize = 1_000_000;

impl StudySpec {
    /// Runs of the whole design: 1 + k·samples (oat), samples·(k + 1) (morris),
    /// samples·(k + 2) (sobol); `None` when that overflows.
    pub fn runs(&self) -> Option<usize> {
        let k = self.params.len();
        match self.method {
            Method::Oat => k.checked_mul(self.samples)?.checked_add(1),
            Method::Morris => self.samples.checked_mul(k.checked_add(1)?),
            Method::Sobol => self.samples.checked_mul(k.checked_add(2)?),
        }
    }

    /// The number of runs, checked before the design is built or any run starts: at most
    /// [`MAX_RUNS`], else bad input naming `--samples`.
    pub fn check_size(&self) -> Result<usize, InputError> {
        let k = self.params.len();
        let formula = match self.method {
            Method::Oat => "1 + parameters × samples",
            Method::Morris => "samples × (parameters + 1)",
            Method::Sobol => "samples × (parameters + 2)",
        };
        match self.runs() {
            Some(n) if n <= MAX_RUNS => Ok(n),
            runs => Err(InputError::new(format!(
                "--samples {} with {k} parameter(s) gives {} runs ({}: {formula}); a study is limited to {MAX_RUNS} runs: use fewer samples",
                self.samples,
                runs.map_or(format!("more than {}", usize::MAX), |n| n.to_string()),
                self.method.name(),
            ))
            .in_file("<command line>")
            .field("--samples")),
        }
    }

    /// The number of samples, checked before anything is read: at least 2 for every method
    /// (two levels, trajectories or rows), and at least [`design::SOBOL_MIN_SAMPLES`] base rows
    /// for Sobol' (fewer give indices and intervals that mean nothing); else bad input naming
    /// `--samples`.
    pub fn check_samples(&self) -> Result<(), InputError> {
        let bad = |m: String| {
            Err(InputError::new(m)
                .in_file("<command line>")
                .field("--samples"))
        };
        if self.samples < 2 {
            return bad(format!(
                "--samples must be at least 2 (got {})",
                self.samples
            ));
        }
        if self.method == Method::Sobol && self.samples < design::SOBOL_MIN_SAMPLES {
            return bad(format!(
                "--samples {}: Sobol' needs at least {} base rows (N(k + 2) runs); with fewer, the estimates stray outside [0, 1] and the bootstrap intervals have too few distinct resamples to mean anything",
                self.samples,
                design::SOBOL_MIN_SAMPLES
            ));
        }
        Ok(())
    }

    /// Unit-cube points of every run, in run order.
    pub fn points(&self) -> Vec<Vec<f64>> {
        let base: Vec<f64> = self.params.iter().map(|p| p.unit(p.base)).collect();
        design::design(
            self.method,
            self.params.len(),
            self.samples,
            self.seed,
            &base,
        )
    }

    /// Parameter values of every run.
    pub fn values(&self) -> Vec<Vec<f64>> {
        self.points()
            .iter()
            .map(|u| {
                u.iter()
                    .zip(&self.params)
                    .map(|(u, p)| p.value(*u))
                    .collect()
            })
            .collect()
    }

    /// One line naming the design (the journal's and the shards' identity check).
    pub fn fingerprint(&self) -> String {
        format!(
            "method={} samples={} seed={} params={} metrics={} base={}",
            self.method.name(),
            self.samples,
            self.seed,
            self.params
                .iter()
                .map(Param::label)
                .collect::<Vec<_>>()
                .join(","),
            self.metrics
                .iter()
                .map(Metric::name)
                .collect::<Vec<_>>()
                .join(","),
            self.params
                .iter()
                .map(|p| num(p.base))
                .collect::<Vec<_>>()
                .join(","),
        )
    }

    /// Parse a fingerprint back (for `merge`).
    pub fn from_fingerprint(s: &str) -> Option<StudySpec> {
        let mut kv = std::collections::HashMap::new();
        for part in s.split_whitespace() {
            let (k, v) = part.split_once('=')?;
            kv.insert(k, v);
        }
        let method = Method::parse(kv.get("method")?)?;
        let samples = kv.get("samples")?.parse().ok()?;
        let seed = kv.get("seed")?.parse().ok()?;
        let bases: Vec<f64> = kv
            .get("base")?
            .split(',')
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().ok())
            .collect::<Option<_>>()?;
        // params: path=lo..hi separated by ',' — a path holds no ',' or '='
        let text = kv.get("params")?;
        let mut params = Vec::new();
        for (i, p) in split_params(s, text).into_iter().enumerate() {
            let (path, r) = p.split_once('=')?;
            let (lo, hi) = r.split_once("..")?;
            let (lo, hi): (f64, f64) = (lo.parse().ok()?, hi.parse().ok()?);
            params.push(Param {
                path: path.to_string(),
                lo,
                hi,
                log: lo > 0.0 && hi / lo > 10.0,
                base: *bases.get(i)?,
            });
        }
        let metrics = kv
            .get("metrics")?
            .split(',')
            .map(|m| Metric::parse(m).ok())
            .collect::<Option<_>>()?;
        Some(StudySpec {
            method,
            samples,
            seed,
            params,
            metrics,
        })
    }
}

/// `params=` of a fingerprint: entries `path=lo..hi` joined by ','.
fn split_params<'a>(_whole: &str, text: &'a str) -> Vec<&'a str> {
    // the value after the first '=' of `params=` is `a=1..2,b=3..4`: split on ',' before a
    // segment that contains '='
    let mut out = Vec::new();
    let mut start = 0;
    let bytes: Vec<(usize, char)> = text.char_indices().collect();
    for &(i, c) in &bytes {
        if c == ','
            && text[i + 1..]
                .split(',')
                .next()
                .is_some_and(|s| s.contains('='))
        {
            out.push(&text[start..i]);
            start = i + 1;
        }
    }
    if start < text.len() {
        out.push(&text[start..]);
    }
    out
}

/// A number as the shortest decimal that reads back to the same `f64` (plain between 1e-3
/// and 1e7, else in exponent form: `0.014`, `60`, `2.5e-9`).
pub fn num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !v.is_finite() || (1e-3..1e7).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(method: Method, k: usize, samples: usize) -> StudySpec {
        StudySpec {
            method,
            samples,
            seed: 1,
            params: (0..k)
                .map(|i| Param {
                    path: format!("a.x{i}"),
                    lo: 0.0,
                    hi: 1.0,
                    log: false,
                    base: 0.5,
                })
                .collect(),
            metrics: vec![Metric::parse("r_max").unwrap()],
        }
    }

    #[test]
    fn sweep_run_count_is_the_designs_and_is_capped_at_a_million_naming_samples() {
        // the count against the design actually built (small cases)
        for (m, k, s) in [
            (Method::Oat, 2, 3),
            (Method::Morris, 3, 2),
            (Method::Sobol, 2, 4),
        ] {
            let sp = spec(m, k, s);
            assert_eq!(sp.runs(), Some(sp.points().len()), "{m:?}");
        }
        // at the limit: oat 1 + 1·999 999 = 10⁶, morris 500 000·(1 + 1), sobol 250 000·(2 + 2)
        for (m, k, at) in [
            (Method::Oat, 1, 999_999),
            (Method::Morris, 1, 500_000),
            (Method::Sobol, 2, 250_000),
        ] {
            assert_eq!(spec(m, k, at).check_size().unwrap(), MAX_RUNS, "{m:?}");
            let e = spec(m, k, at + 1).check_size().unwrap_err();
            assert_eq!(e.field.as_deref(), Some("--samples"), "{m:?}");
            assert!(
                e.message.contains("limited to 1000000 runs"),
                "{}",
                e.message
            );
        }
        // --samples: at least 2, and at least SOBOL_MIN_SAMPLES base rows for Sobol'
        assert!(spec(Method::Oat, 1, 2).check_samples().is_ok());
        assert!(spec(Method::Morris, 1, 2).check_samples().is_ok());
        for (m, s) in [
            (Method::Oat, 1),
            (Method::Sobol, 2),
            (Method::Sobol, design::SOBOL_MIN_SAMPLES - 1),
        ] {
            let e = spec(m, 2, s).check_samples().unwrap_err();
            assert_eq!(e.field.as_deref(), Some("--samples"), "{m:?} {s}");
        }
        assert!(spec(Method::Sobol, 2, design::SOBOL_MIN_SAMPLES)
            .check_samples()
            .is_ok());
        // an overflowing count is refused, not wrapped
        let e = spec(Method::Sobol, 3, usize::MAX).check_size().unwrap_err();
        assert_eq!(e.field.as_deref(), Some("--samples"));
        assert_eq!(spec(Method::Oat, 2, usize::MAX).runs(), None);
    }
}
