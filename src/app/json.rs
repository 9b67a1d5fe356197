//! `--json` output of `plan`, `check` and `evaluate`: one JSON object on stdout, numbers at
//! full precision (shortest text that reads back to the same f64), in SI-like units named in
//! the keys. The schema is documented in `docs/json.md`; each object carries
//! `"schema": "decophantom.<command>/1"`, bumped on any incompatible change.

use super::plan::PlanOutcome;
use crate::algorithm::schedule::gas_text;
use crate::algorithm::Schedule;
use crate::evaluate::rank::{ranking, ties};
use crate::evaluate::Evaluation;
use crate::risk::Score;
use serde::Serialize;

/// One criterion's score.
#[derive(Debug, Serialize)]
pub struct ScoreJson {
    /// Registry kind (`peak-radius`, ...): the stable key.
    pub kind: String,
    /// Label from the criteria file (defaults to the kind).
    pub label: String,
    /// Unit of value, limit and margin.
    pub unit: String,
    /// The value.
    pub value: f64,
    /// The limit.
    pub limit: f64,
    /// limit − value.
    pub margin: f64,
    /// value ≤ limit.
    pub pass: bool,
    /// The absolute value behind a growth score (peak volume with the nuclei, peak radius),
    /// in `unit`; null for criteria whose value is itself absolute.
    pub absolute: Option<f64>,
}

impl From<&Score> for ScoreJson {
    fn from(s: &Score) -> Self {
        ScoreJson {
            kind: s.kind.to_string(),
            label: s.label.clone(),
            unit: s.unit.to_string(),
            value: s.value,
            limit: s.limit,
            margin: s.margin,
            pass: s.pass,
            absolute: s.absolute,
        }
    }
}

/// One leg of a schedule.
#[derive(Debug, Serialize)]
pub struct LegJson {
    /// descent, bottom, ascent or stop.
    pub kind: String,
    /// m.
    pub start_depth_m: f64,
    /// m.
    pub end_depth_m: f64,
    /// s.
    pub duration_s: f64,
    /// Gas as `air`, `EAN50`, `18/45`, `O2`.
    pub gas: String,
}

/// One decompression stop.
#[derive(Debug, Serialize)]
pub struct StopJson {
    /// m.
    pub depth_m: f64,
    /// min.
    pub stop_min: f64,
    /// Runtime at the end of the stop, min.
    pub runtime_min: f64,
    /// Gas.
    pub gas: String,
}

/// A schedule.
#[derive(Debug, Serialize)]
pub struct ScheduleJson {
    /// Label.
    pub label: String,
    /// Total runtime to the surface, min.
    pub runtime_min: f64,
    /// Sum of the stops, min.
    pub stop_time_min: f64,
    /// Deepest point, m.
    pub max_depth_m: f64,
    /// Surface pressure, Pa.
    pub surface_pressure_pa: f64,
    /// Pressure per metre of depth, Pa/m.
    pub pa_per_m: f64,
    /// Stops in order.
    pub stops: Vec<StopJson>,
    /// Legs in order.
    pub legs: Vec<LegJson>,
}

impl From<&Schedule> for ScheduleJson {
    fn from(s: &Schedule) -> Self {
        ScheduleJson {
            label: s.label.clone(),
            runtime_min: s.runtime_min(),
            stop_time_min: s.stop_time_min(),
            max_depth_m: s.legs.iter().map(|l| l.end_depth_m).fold(0.0, f64::max),
            surface_pressure_pa: s.surface_pressure_pa,
            pa_per_m: s.pa_per_m,
            stops: s
                .stops
                .iter()
                .map(|x| StopJson {
                    depth_m: x.depth_m,
                    stop_min: x.stop_min,
                    runtime_min: x.runtime_min,
                    gas: gas_text(x.gas),
                })
                .collect(),
            legs: s
                .legs
                .iter()
                .map(|l| LegJson {
                    kind: format!("{:?}", l.kind).to_ascii_lowercase(),
                    start_depth_m: l.start_depth_m,
                    end_depth_m: l.end_depth_m,
                    duration_s: l.duration_s,
                    gas: gas_text(l.gas),
                })
                .collect(),
        }
    }
}

#[derive(Serialize)]
struct PlanJson<'a> {
    schema: &'static str,
    algorithm: &'a str,
    schedule: ScheduleJson,
    cns_percent: f64,
    otu: f64,
    /// No-decompression limit, min, when the dive has no stops (null otherwise, or when
    /// there is none within a day; `ndl_searched` says which).
    ndl_min: Option<f64>,
    ndl_searched: bool,
    settings: std::collections::BTreeMap<String, String>,
    warnings: &'a [String],
}

/// `plan --json`.
pub fn plan(outcome: &PlanOutcome, algorithm: &str) -> String {
    to_string(&PlanJson {
        schema: "decophantom.plan/1",
        algorithm,
        schedule: (&outcome.schedule).into(),
        cns_percent: outcome.oxygen.cns_percent,
        otu: outcome.oxygen.otu,
        ndl_min: outcome.ndl_min.flatten(),
        ndl_searched: outcome.ndl_min.is_some(),
        settings: outcome.settings.iter().cloned().collect(),
        warnings: &outcome.warnings,
    })
}

#[derive(Serialize)]
struct CandidateJson {
    label: String,
    source: String,
    import_notes: Vec<String>,
    schedule: ScheduleJson,
}

#[derive(Serialize)]
struct RunJson {
    schedule: String,
    elasticity: String,
    ending: String,
    simulated_s: f64,
    all_pass: bool,
    scores: Vec<ScoreJson>,
}

#[derive(Serialize)]
struct RankJson {
    elasticity: String,
    rank: usize,
    tied: bool,
    schedule: String,
    failures: usize,
    worst_ratio: f64,
    worst_criterion: String,
    mean_ratio: f64,
}

fn candidates(ev: &Evaluation) -> Vec<CandidateJson> {
    ev.candidates
        .iter()
        .map(|c| CandidateJson {
            label: c.label.clone(),
            source: c.source.clone(),
            import_notes: c.notes.clone(),
            schedule: (&c.schedule).into(),
        })
        .collect()
}

fn runs(ev: &Evaluation) -> Vec<RunJson> {
    ev.runs
        .iter()
        .map(|r| RunJson {
            schedule: ev.candidates[r.candidate].label.clone(),
            elasticity: r.law.to_string(),
            ending: crate::run::text::ending_text(&r.run.summary.ending),
            simulated_s: r.run.summary.end_time,
            all_pass: r.scores.iter().all(|s| s.pass),
            scores: r.scores.iter().map(ScoreJson::from).collect(),
        })
        .collect()
}

#[derive(Serialize)]
struct CheckJson {
    schema: &'static str,
    phantom: String,
    all_pass: bool,
    candidate: CandidateJson,
    run: RunJson,
}

/// `check --json`.
pub fn check(ev: &Evaluation) -> String {
    let mut c = candidates(ev);
    let mut r = runs(ev);
    to_string(&CheckJson {
        schema: "decophantom.check/1",
        phantom: ev.phantom.params.name.clone(),
        all_pass: ev.all_pass(),
        candidate: c.remove(0),
        run: r.remove(0),
    })
}

#[derive(Serialize)]
struct EvaluateJson {
    schema: &'static str,
    phantom: String,
    laws: Vec<String>,
    candidates: Vec<CandidateJson>,
    runs: Vec<RunJson>,
    ranking: Vec<RankJson>,
    ties: Vec<TieJson>,
}

#[derive(Serialize)]
struct TieJson {
    elasticity: String,
    kind: String,
    label: String,
    spread: f64,
    uncertainty: f64,
}

/// `evaluate --json`.
pub fn evaluate(ev: &Evaluation) -> String {
    to_string(&EvaluateJson {
        schema: "decophantom.evaluate/1",
        phantom: ev.phantom.params.name.clone(),
        laws: ev.laws.iter().map(|l| l.to_string()).collect(),
        candidates: candidates(ev),
        runs: runs(ev),
        ranking: ranking(ev)
            .into_iter()
            .map(|r| RankJson {
                elasticity: r.law.to_string(),
                rank: r.rank,
                tied: r.tied,
                schedule: ev.candidates[r.candidate].label.clone(),
                failures: r.failures,
                worst_ratio: r.worst.0,
                worst_criterion: r.worst.1,
                mean_ratio: r.mean_ratio,
            })
            .collect(),
        ties: ties(ev)
            .into_iter()
            .map(|t| {
                let c = &ev.criteria.criteria[t.criterion];
                TieJson {
                    elasticity: t.law.to_string(),
                    kind: c.criterion.name().to_string(),
                    label: c.label.clone(),
                    spread: t.spread,
                    uncertainty: t.uncertainty,
                }
            })
            .collect(),
    })
}

/// Pretty JSON with a final newline. Non-finite numbers (which the validation keeps out of
/// results) would become `null`.
fn to_string<T: Serialize>(v: &T) -> String {
    let mut s = serde_json::to_string_pretty(v).unwrap_or_else(|e| {
        // serialising plain structs of numbers and strings cannot fail; say so if it does
        format!("{{\"error\": \"JSON serialisation failed: {e}\"}}")
    });
    s.push('\n');
    s
}
