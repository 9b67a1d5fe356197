//! The report's tables and texts: the schedules, the scores (rounded for reading, and
//! `scores.csv` at full precision), the ranking and the ties, the phantom runs, `timing.csv`,
//! and the short text summary.

use super::rank::{ranking, ties, TIE_RELATIVE_UNCERTAINTY};
use super::Evaluation;
use crate::algorithm::schedule::gas_text;
use crate::error::Error;
use crate::phantom::sim::StepWall;
use crate::report::table::{Cell, Column, Table};
use crate::run::text::ending_text;

pub(super) fn fmt_min(x: f64) -> String {
    if (x - x.round()).abs() < 1e-9 {
        format!("{}", x.round())
    } else {
        format!("{x:.1}")
    }
}

/// The schedule table: stops, gases, runtime.
pub fn schedule_table(ev: &Evaluation) -> Result<Table, Error> {
    let mut t = Table::new(
        "Schedules",
        vec![
            Column::plain("schedule"),
            Column::plain("source"),
            Column::plain("stops (depth m × min)"),
            Column::plain("gases"),
            Column::new("stop_time", "min"),
            Column::new("runtime", "min"),
        ],
    );
    for c in &ev.candidates {
        let s = &c.schedule;
        let stops = if s.stops.is_empty() {
            "none".to_string()
        } else {
            s.stops
                .iter()
                .map(|st| format!("{}×{}", fmt_min(st.depth_m), fmt_min(st.stop_min)))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let mut gases: Vec<String> = Vec::new();
        for l in &s.legs {
            let g = gas_text(l.gas);
            if !gases.contains(&g) {
                gases.push(g);
            }
        }
        t.push(vec![
            Cell::text(&c.label),
            Cell::text(&c.source),
            Cell::text(stops),
            Cell::text(gases.join(", ")),
            Cell::fixed(s.stop_time_min(), 1),
            Cell::fixed(s.runtime_min(), 1),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(t)
}

/// `scores.csv`: one row per run and criterion, keyed by the criterion's registry `kind`
/// (stable) with the criteria file's `label` in its own column, numbers at full precision
/// (the shortest text that reads back to the same f64): `schedule,elasticity,kind,label,unit,
/// value,limit,margin,value_over_limit,result,absolute_value` (`absolute_value`: the absolute
/// value behind a growth score, e.g. the peak volume with the nuclei; empty for the others).
pub fn scores_csv(ev: &Evaluation) -> Result<String, Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    let csv_err = |e: csv::Error| Error::Solver(format!("scores.csv: {e}"));
    w.write_record([
        "schedule",
        "elasticity",
        "kind",
        "label",
        "unit",
        "value",
        "limit",
        "margin",
        "value_over_limit",
        "result",
        "absolute_value",
    ])
    .map_err(csv_err)?;
    for r in &ev.runs {
        for s in &r.scores {
            w.write_record([
                ev.candidates[r.candidate].label.as_str(),
                r.law,
                s.kind,
                s.label.as_str(),
                s.unit,
                &s.value.to_string(),
                &s.limit.to_string(),
                &s.margin.to_string(),
                &s.ratio().to_string(),
                if s.pass { "pass" } else { "FAIL" },
                &s.absolute.map(|a| a.to_string()).unwrap_or_default(),
            ])
            .map_err(csv_err)?;
        }
    }
    let bytes = w
        .into_inner()
        .map_err(|e| Error::Solver(format!("scores.csv: {e}")))?;
    String::from_utf8(bytes).map_err(|e| Error::Solver(format!("scores.csv: {e}")))
}

/// What the report's score table prints for a value of zero up to the round-off
/// ([`TIE_RELATIVE_UNCERTAINTY`] of the limit: nuclei that never grow leave 10⁻¹⁰ µm²/s of
/// dA/dt), and the sentence under the table that says so.
pub const ROUND_OFF_ZERO: (&str, &str) = (
    "≈ 0",
    "≈ 0: zero within the runs' round-off (below 10⁻⁶ of the limit; `scores.csv` has the value).",
);

/// A value zero up to the round-off: nonzero and within [`TIE_RELATIVE_UNCERTAINTY`] of `limit`.
pub fn round_off_zero(value: f64, limit: f64) -> bool {
    value != 0.0 && value.abs() <= TIE_RELATIVE_UNCERTAINTY * limit.abs()
}

/// The scores, one row per run and criterion, rounded for reading (the report's table;
/// `scores.csv` has them at full precision, [`scores_csv`]); a value of zero up to the round-off
/// reads [`ROUND_OFF_ZERO`].
pub fn scores_table(ev: &Evaluation) -> Result<Table, Error> {
    let mut t = Table::new(
        "Criteria per schedule",
        vec![
            Column::plain("schedule"),
            Column::plain("elasticity"),
            Column::plain("criterion"),
            Column::plain("unit"),
            Column::plain("value"),
            Column::plain("limit"),
            Column::plain("margin"),
            Column::plain("value/limit"),
            Column::plain("result"),
            Column::plain("absolute"),
        ],
    );
    for r in &ev.runs {
        for s in &r.scores {
            t.push(vec![
                Cell::text(&ev.candidates[r.candidate].label),
                Cell::text(r.law),
                Cell::text(&s.label),
                Cell::text(s.unit),
                if round_off_zero(s.value, s.limit) {
                    Cell::text(ROUND_OFF_ZERO.0)
                } else {
                    Cell::sig(s.value, 4)
                },
                Cell::sig(s.limit, 4),
                Cell::sig(s.margin, 4),
                Cell::fixed(s.ratio(), 3),
                Cell::text(if s.pass { "pass" } else { "FAIL" }),
                match s.absolute {
                    Some(a) => Cell::sig(a, 4),
                    None => Cell::text(""),
                },
            ])
            .map_err(Error::Solver)?;
        }
    }
    Ok(t)
}

pub(super) fn ranking_table(ev: &Evaluation) -> Result<Table, Error> {
    let mut t = Table::new(
        "Ranking (per elasticity law: fewest failures, then smallest worst value/limit, then smallest mean, over the criteria that separate the schedules; equal ranks are ties)",
        vec![
            Column::plain("elasticity"),
            Column::plain("rank"),
            Column::plain("schedule"),
            Column::plain("failures"),
            Column::plain("worst criterion"),
            Column::plain("worst value/limit"),
            Column::plain("mean value/limit"),
        ],
    );
    for r in ranking(ev) {
        t.push(vec![
            Cell::text(r.law),
            Cell::text(if r.tied {
                format!("{} (tied)", r.rank)
            } else {
                r.rank.to_string()
            }),
            Cell::text(&ev.candidates[r.candidate].label),
            Cell::text(r.failures.to_string()),
            Cell::text(&r.worst.1),
            Cell::fixed(r.worst.0, 3),
            Cell::fixed(r.mean_ratio, 3),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(t)
}

/// The ties ([`ties`]) as a table, or `None` without any.
pub(super) fn ties_table(ev: &Evaluation) -> Result<Option<Table>, Error> {
    let ties = ties(ev);
    if ties.is_empty() {
        return Ok(None);
    }
    let mut t = Table::new(
        "Ties: criteria on which the schedules score the same within the numerical uncertainty",
        vec![
            Column::plain("elasticity"),
            Column::plain("criterion"),
            Column::plain("unit"),
            Column::plain("spread between schedules"),
            Column::plain("numerical uncertainty"),
        ],
    );
    for tie in &ties {
        let s = &ev
            .runs
            .iter()
            .find(|r| r.law == tie.law)
            .map(|r| &r.scores[tie.criterion]);
        let Some(s) = s else { continue };
        t.push(vec![
            Cell::text(tie.law),
            Cell::text(&s.label),
            Cell::text(s.unit),
            Cell::sig(tie.spread, 2),
            Cell::sig(tie.uncertainty, 2),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(Some(t))
}

/// One sentence per law with ties: which criteria tie and that they are left out of the
/// ranking; empty without ties.
pub fn ties_text(ev: &Evaluation) -> String {
    let ties = ties(ev);
    let mut s = String::new();
    for law in &ev.laws {
        let names: Vec<String> = ties
            .iter()
            .filter(|t| t.law == *law)
            .map(|t| ev.criteria.criteria[t.criterion].label.clone())
            .collect();
        if names.is_empty() {
            continue;
        }
        let all = names.len() == ev.criteria.criteria.len();
        s.push_str(&format!(
            "Under {law} the schedules are tied on {}: their values differ by less than the numerical uncertainty, so {}.\n",
            names.join(", "),
            if all {
                "no criterion ranks them and they share rank 1"
            } else {
                "these criteria do not rank them (left out of the worst and mean value/limit of the ranking)"
            }
        ));
    }
    s
}

pub(super) fn runs_table(ev: &Evaluation) -> Result<Table, Error> {
    let mut t = Table::new(
        "Phantom runs",
        vec![
            Column::plain("schedule"),
            Column::plain("elasticity"),
            Column::plain("ending"),
            Column::new("simulated", "min"),
            Column::plain("steps (explicit + implicit)"),
            Column::plain("gas-balance error"),
        ],
    );
    for r in &ev.runs {
        let s = &r.run.summary;
        t.push(vec![
            Cell::text(&ev.candidates[r.candidate].label),
            Cell::text(r.law),
            Cell::text(ending_text(&s.ending)),
            Cell::fixed(s.end_time / 60.0, 1),
            Cell::text(format!("{} + {}", s.steps.0, s.steps.1)),
            Cell::sig(s.gas_balance_error, 2),
        ])
        .map_err(Error::Solver)?;
    }
    Ok(t)
}

/// `timing.csv`: the wall time of every phantom run (schedule, elasticity, wall_s), and of it
/// the time loop's phases summed over the run's steps ([`StepWall`]; 0 for a run read back
/// from a journal).
pub(super) fn timing_csv(ev: &Evaluation) -> String {
    let mut out = format!("schedule,elasticity,wall_s,{}\n", StepWall::CSV_HEADER);
    for r in &ev.runs {
        let label = ev.candidates[r.candidate].label.replace('"', "\"\"");
        out.push_str(&format!(
            "\"{label}\",{},{},{}\n",
            r.law,
            r.run.wall_seconds,
            r.run.phases.csv_fields()
        ));
    }
    out
}

/// A short text summary: the ranking under each law with failures and worst criterion.
pub fn summary_text(ev: &Evaluation) -> String {
    let mut s = String::new();
    for c in &ev.candidates {
        for n in &c.notes {
            s.push_str(&format!("note ({}): {n}\n", c.label));
        }
    }
    for r in ranking(ev) {
        s.push_str(&format!(
            "{:<26} {:>2}.{} {:<28} failures {}  worst {} ({:.3} of limit)\n",
            r.law,
            r.rank,
            if r.tied { " (tied)" } else { "" },
            ev.candidates[r.candidate].label,
            r.failures,
            r.worst.1,
            r.worst.0
        ));
    }
    s.push_str(&ties_text(ev));
    s
}

#[cfg(test)]
mod round_off_tests {
    use super::*;

    /// The demo's bulk-modulus runs, whose nuclei never grow: dA/dt 2.752e-10 µm²/s against a
    /// limit of 80 and volume·time 1.948e-12 mm³·min against 0.5 read ≈ 0; an exact 0 stays 0,
    /// and a small real value (a peak volume growth of 1e-4 mm³ against 0.009) keeps its digits.
    #[test]
    fn round_off_reads_as_zero() {
        assert!(round_off_zero(2.752e-10, 80.0));
        assert!(round_off_zero(1.948e-12, 0.5));
        assert!(!round_off_zero(0.0, 80.0));
        assert!(!round_off_zero(1e-4, 0.009));
    }
}
