//! The evaluation's report: its sections (inputs, schedules, scores, bubbles, the elasticity
//! laws compared, the phantom runs), its SVG plots, and the page (`report.html`,
//! `report.md`).

use super::rank::TIE_RELATIVE_UNCERTAINTY;
use super::tables::{
    fmt_min, ranking_table, round_off_zero, runs_table, schedule_table, scores_csv, scores_table,
    ties_table, ties_text, timing_csv, ROUND_OFF_ZERO,
};
use super::{Evaluation, RunOutcome};
use crate::error::Error;
use crate::phantom::sim::Frame;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::plot::{BarChart, LinePlot, Series, DEFAULT_SIZE};
use crate::risk::{series, RunData};

/// What the report says about where its inputs came from.
#[derive(Debug, Clone, Default)]
pub struct ReportContext {
    /// The dive in words.
    pub dive: String,
    /// The criteria file.
    pub criteria_source: String,
    /// Surface interval of a repetitive dive, min.
    pub repeat_after_min: Option<f64>,
    /// The command that produced the report, if it should be quoted.
    pub command: Option<String>,
}

fn plot_err(e: impl std::fmt::Display) -> Error {
    Error::Solver(format!("plot: {e}"))
}

/// What the all-schedule bubble plots say when no schedule's run had a bubble.
const NO_BUBBLES: &str =
    "No bubble in any run: no nucleus activated and none was placed, so there is nothing to draw.";

/// What the `peak-area-growth-rate` criterion with `window = "after-surfacing"` takes the
/// peak of: from `surfaced_s` on, at the midpoint of each pair of recorded frames, the largest
/// dA/dt of a single bubble, (time s, m²/s).
pub fn area_rate_after_surfacing(frames: &[Frame], surfaced_s: f64) -> Vec<(f64, f64)> {
    let data = RunData {
        frames,
        surfaced_s: Some(surfaced_s),
    };
    let mut all: Vec<(f64, f64)> =
        series::per_bubble(data.window(crate::risk::Window::AfterSurfacing), |b| b.area)
            .values()
            .flat_map(|pts| series::rate(pts))
            .collect();
    all.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out: Vec<(f64, f64)> = Vec::new();
    for (t, r) in all {
        match out.last_mut() {
            Some(last) if last.0 == t => last.1 = last.1.max(r),
            _ => out.push((t, r)),
        }
    }
    out
}

fn minutes(points: Vec<(f64, f64)>, scale: f64) -> Vec<(f64, f64)> {
    points
        .into_iter()
        .map(|(t, v)| (t / 60.0, v * scale))
        .collect()
}

/// Add the evaluation's sections to `page` and its files to `set` under `prefix` (e.g. `""`
/// or `"dive/"`). Writes `<prefix>scores.csv` and the SVGs.
pub fn add_report(
    page: &mut Page,
    set: &mut OutputSet,
    prefix: &str,
    ev: &Evaluation,
    ctx: &ReportContext,
) -> Result<(), Error> {
    let ph = &ev.phantom;
    let p = &ph.params;
    let cells = ev.runs.first().map_or(0, |r| r.run.summary.cells);
    let proto = &ev.criteria.protocol;
    let primary = ev.laws[0];
    let add_svg = |page: &mut Page,
                   set: &mut OutputSet,
                   name: &str,
                   svg: String,
                   caption: &str|
     -> Result<(), Error> {
        let file = format!("{prefix}{name}");
        page.figure(&svg, Some(&file), caption)
            .map_err(Error::Solver)?;
        set.add(file, svg);
        Ok(())
    };

    page.section("Inputs");
    let vapour = format!(
        "{} Pa for every schedule; every bubble holds the gases not simulated at {} Pa (water vapour {} + CO2 {} + venous O2 {} Pa, criteria `[protocol]`)",
        proto.water_vapour_pa,
        proto.bubble_fixed_gases_pa(),
        proto.water_vapour_pa,
        proto.co2_pa,
        proto.venous_o2_pa
    );
    let mut inputs = format!(
        "- Dive: **{}**{}\n- Phantom: **{}** from {} — grid step {:.1} µm, {} cells inside; {}\n- Criteria: `{}`{}\n- Linking: ambient pressure of the schedule at the gel; open faces in equilibrium with the inspired {} partial pressures, fraction × (ambient − water vapour), water vapour {}; saturated with surface air at t = 0, whatever the first gas; watched {} min at the surface on air after the schedule ends.\n- Elasticity laws: {} (μ = {} Pa; M = {} Pa/µm³ and K = {} GPa where the phantom gives none: the paper's Fig. 2a values 5 × 10⁻² Pa/µm³ and 2.2 GPa).",
        ctx.dive,
        ctx.repeat_after_min
            .map(|s| format!(", repeated after a {s} min surface interval"))
            .unwrap_or_default(),
        p.name,
        ph.source,
        p.grid_step * 1e6,
        cells,
        ph.description.replace('\n', " "),
        ctx.criteria_source,
        if ev.criteria.description.is_empty() {
            String::new()
        } else {
            format!(" — {}", ev.criteria.description.replace('\n', " "))
        },
        if proto.oxygen_at_faces {
            "gas (O2 included)"
        } else {
            "inert-gas (N2, He; O2 left out)"
        },
        vapour,
        fmt_min(proto.observe_after_surfacing_s / 60.0),
        ev.laws.join(", "),
        ph.laws.shear_modulus,
        crate::report::plot::fmt_tick(ph.laws.bulk_modulus_per_volume * 1e-18),
        crate::report::plot::fmt_tick(ph.laws.bulk_modulus * 1e-9),
    );
    if let Some(cmd) = &ctx.command {
        inputs.push_str(&format!("\n- Produced by: `{cmd}`"));
    }
    for c in ev.candidates.iter().filter(|c| !c.notes.is_empty()) {
        inputs.push_str(&format!("\n- Import notes for {}:", c.label));
        for n in &c.notes {
            inputs.push_str(&format!("\n    - {n}"));
        }
    }
    page.text(inputs);

    page.section("Schedules");
    page.table(&schedule_table(ev)?);
    let mut prof = LinePlot::new(
        "Dive profiles as applied to the phantom",
        "time (min)",
        "depth (m)",
    );
    prof.y_down = true;
    let mut press = LinePlot::new(
        "Ambient pressure at the gel",
        "time (min)",
        "ambient pressure (kPa, absolute)",
    );
    for c in &ev.candidates {
        let h = &c.history;
        let pts = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
            h.times_s
                .iter()
                .zip(&h.ambient_pa)
                .map(|(t, pa)| (t / 60.0, f(*pa)))
                .collect()
        };
        let s = &c.schedule;
        prof = prof.with(Series::new(
            &c.label,
            pts(&|pa| (pa - s.surface_pressure_pa) / s.pa_per_m),
        ));
        press = press.with(Series::new(&c.label, pts(&|pa| pa * 1e-3)));
    }
    add_svg(
        page,
        set,
        "profiles.svg",
        prof.to_svg().map_err(plot_err)?,
        "Depth against time for each schedule, including the time watched at the surface.",
    )?;
    add_svg(
        page,
        set,
        "pressure.svg",
        press.to_svg().map_err(plot_err)?,
        "The ambient pressure that acts on the gel.",
    )?;

    page.section("Scores");
    let scores = scores_table(ev)?;
    set.add(format!("{prefix}scores.csv"), scores_csv(ev)?);
    let mut crit = String::from(
        "Criteria (value ≤ limit passes; margin = limit − value). Peak volume and peak radius \
         score the growth the schedule causes, above each bubble's initial radius R0 (`measure = \
         \"growth\"`, the default); the table's *absolute* column gives the absolute peak beside \
         them, nuclei included:\n",
    );
    for c in &ev.criteria.criteria {
        crit.push_str(&format!(
            "\n- **{}** (`{}`, {}): {}; limit {}",
            c.label,
            c.criterion.name(),
            if c.criterion.unit().is_empty() {
                "dimensionless"
            } else {
                c.criterion.unit()
            },
            c.criterion.describe(),
            c.limit
        ));
    }
    page.text(crit);
    page.table(&ranking_table(ev)?);
    if let Some(t) = ties_table(ev)? {
        page.text(format!(
            "{}The numerical uncertainty of a criterion is {} × the larger of its largest |value| and its limit: the round-off and solver-tolerance noise of runs that should agree. The discretisation error (grid step; the step tolerance, about 0.3 % on a radius) is not in it, as it shifts every schedule on the same grid alike; differences between schedules smaller than that are nonetheless within the model's accuracy.",
            ties_text(ev),
            crate::report::table::sig_text(TIE_RELATIVE_UNCERTAINTY, 1, true)
        ));
        page.table(&t);
    }
    page.table(&scores);
    if ev
        .runs
        .iter()
        .flat_map(|r| &r.scores)
        .any(|s| round_off_zero(s.value, s.limit))
    {
        page.text(ROUND_OFF_ZERO.1);
    }
    // one group per schedule under the primary law (the phantom's own): a legend of every
    // schedule × law would bury the bars; the other laws are in the tables above
    let primary_runs: Vec<&RunOutcome> = ev.runs.iter().filter(|r| r.law == ev.laws[0]).collect();
    let groups: Vec<String> = primary_runs
        .iter()
        .map(|r| ev.candidates[r.candidate].label.clone())
        .collect();
    let bars = BarChart {
        title: format!(
            "Each criterion as a fraction of its limit ({} elasticity)",
            ev.laws[0]
        ),
        x_label: "criterion".into(),
        y_label: "value / limit (1 = limit)".into(),
        categories: ev
            .criteria
            .criteria
            .iter()
            .map(|c| c.label.clone())
            .collect(),
        groups,
        values: (0..ev.criteria.criteria.len())
            .map(|k| primary_runs.iter().map(|r| r.scores[k].ratio()).collect())
            .collect(),
        reference: Some((1.0, "limit".into())),
        size: DEFAULT_SIZE,
    };
    add_svg(
        page,
        set,
        "criteria.svg",
        bars.to_svg().map_err(plot_err)?,
        "value/limit of every criterion for every schedule under the primary elasticity law; bars above the limit line fail.",
    )?;

    page.section(format!("Bubbles ({primary} elasticity)"));
    let mut vol = LinePlot::new(
        format!("Total bubble volume ({primary})"),
        "time (min)",
        "total bubble volume (mm³)",
    );
    let mut area = LinePlot::new(
        format!("Total bubble surface area ({primary})"),
        "time (min)",
        "total surface area (mm²)",
    );
    let mut rate = LinePlot::new(
        format!("Fastest single-bubble dA/dt after surfacing ({primary})"),
        "time after surfacing (min)",
        "largest dA/dt of one bubble (µm²/s)",
    );
    let mut ss = LinePlot::new(
        format!("Gel supersaturation, largest over all gel cells ({primary})"),
        "time (min)",
        "Σ tension + p_fixed − ambient (kPa)",
    );
    for (c, cand) in ev.candidates.iter().enumerate() {
        let Some(r) = ev.run(c, primary) else {
            continue;
        };
        let f = &r.run.frames;
        vol = vol.with(Series::new(
            &cand.label,
            minutes(series::total_volume(f), 1e9),
        ));
        let surfaced = cand.history.final_arrival_s();
        rate = rate.with(Series::new(
            &cand.label,
            area_rate_after_surfacing(f, surfaced)
                .into_iter()
                .map(|(t, v)| ((t - surfaced) / 60.0, v * 1e12))
                .collect(),
        ));
        area = area.with(Series::new(
            &cand.label,
            minutes(series::total_area(f), 1e6),
        ));
        ss = ss.with(Series::new(
            &cand.label,
            f.iter()
                .map(|fr| (fr.time / 60.0, fr.max_supersaturation * 1e-3))
                .collect(),
        ));
    }
    add_svg(
        page,
        set,
        "volume.svg",
        vol.to_svg_or_message(NO_BUBBLES).map_err(plot_err)?,
        "Total volume of all bubbles in the phantom for each schedule.",
    )?;
    for (c, cand) in ev.candidates.iter().enumerate() {
        let Some(r) = ev.run(c, primary) else {
            continue;
        };
        let mut rad = LinePlot::new(
            format!("Bubble radius: {} ({primary})", cand.label),
            "time (min)",
            "radius (µm)",
        );
        for (id, pts) in series::per_bubble(&r.run.frames, |b| b.radius) {
            rad = rad.with(Series::new(format!("bubble {id}"), minutes(pts, 1e6)));
        }
        add_svg(
            page,
            set,
            &format!("radius-{}.svg", c + 1),
            rad.to_svg_or_message(crate::run::files::NO_BUBBLE)
                .map_err(plot_err)?,
            &format!("Radius of each bubble under {}.", cand.label),
        )?;
    }
    add_svg(
        page,
        set,
        "area.svg",
        area.to_svg_or_message(NO_BUBBLES).map_err(plot_err)?,
        "Total surface area of all bubbles.",
    )?;
    add_svg(
        page,
        set,
        "area-rate.svg",
        rate.to_svg_or_message(NO_BUBBLES).map_err(plot_err)?,
        "From the moment each schedule surfaces (time 0 here): at each interval between recorded frames, the largest surface-area growth rate dA/dt of a single bubble. The `peak-area-growth-rate` criterion with `window = \"after-surfacing\"` scores the peak of this curve; the Boyle expansion of the ascent, before surfacing, is left out as it is by the criterion.",
    )?;
    add_svg(
        page,
        set,
        "supersaturation.svg",
        ss.to_svg().map_err(plot_err)?,
        "The largest supersaturation of any gel cell at each recorded frame: dissolved inert-gas tension plus the bubbles' fixed gases (water vapour, CO2, venous O2) minus ambient pressure. The `peak-supersaturation` criterion with `at = \"gel\"` (the default) scores the peak of this curve.",
    )?;

    if ev.laws.len() > 1 {
        page.section("Elasticity laws compared");
        page.text("The same schedules through the same phantom under each tissue-elasticity law (the paper's eqs. 2.6–2.9; `none` is Ω = 0).");
        for (c, cand) in ev.candidates.iter().enumerate() {
            let mut el = LinePlot::new(
                format!("Total bubble volume under each law: {}", cand.label),
                "time (min)",
                "total bubble volume (mm³)",
            );
            // the laws' curves lie on top of each other: dashes and markers tell them apart
            el.distinct = true;
            for law in &ev.laws {
                if let Some(r) = ev.run(c, law) {
                    el = el.with(Series::new(
                        *law,
                        minutes(series::total_volume(&r.run.frames), 1e9),
                    ));
                }
            }
            add_svg(
                page,
                set,
                &format!("elasticity-{}.svg", c + 1),
                el.to_svg().map_err(plot_err)?,
                &format!(
                    "Total bubble volume of {} under each elasticity law.",
                    cand.label
                ),
            )?;
        }
    }

    page.section("Phantom runs");
    page.table(&runs_table(ev)?);
    page.text("Wall-clock times of the runs are in `timing.csv`, written beside this report by each run (they change from run to run, so the report leaves them out, and the repository's example reports do not keep the file).");
    set.add(format!("{prefix}timing.csv"), timing_csv(ev));
    Ok(())
}

/// Close a page: the caveat on the hazard and model, then `report.html` and `report.md`
/// under `prefix`.
pub fn finish_page(page: &mut Page, set: &mut OutputSet, prefix: &str) -> Result<(), Error> {
    page.section("Reading this report");
    page.text("The phantom is a gel, not a diver: its bubbles rank schedules by how much gas they leave to come out of solution, under explicit and adjustable assumptions. The `hazard` criterion has the form of the BVM(3) family, P = 1 − exp(−∫ g·max(0, V − V_thr) dt), but its gain g and threshold V_thr are user parameters that this tool has **not** calibrated to human (or any) decompression-sickness data: it is a monotone score, not a probability of DCS.");
    set.add(
        format!("{prefix}report.html"),
        page.to_html().map_err(Error::Solver)?,
    );
    set.add(
        format!("{prefix}report.md"),
        page.to_markdown().map_err(Error::Solver)?,
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn area_rate_plot_is_the_scored_window_per_bubble() {
        use crate::risk::testing::{bubble, frame};
        use std::f64::consts::PI;
        // two bubbles, frames at 0, 10, 20, 30 s, surfacing at 10 s. Before it bubble 0 shrinks
        // fast (the descent spike the plot must leave out); from it: b0 100 → 110 → 115 µm,
        // b1 50 → 70 → 71 µm. Rates 4π(R₂² − R₁²)/Δt: at 15 s b0 4π·2100/10 = 2638.9, b1
        // 4π·2400/10 = 3015.9 µm²/s (the larger); at 25 s b0 4π·1125/10 = 1413.7, b1
        // 4π·141/10 = 177.2 µm²/s.
        let f = vec![
            frame(
                0.0,
                3e5,
                0.0,
                vec![bubble(0, 300e-6, 0.0), bubble(1, 50e-6, 0.0)],
            ),
            frame(
                10.0,
                1e5,
                0.0,
                vec![bubble(0, 100e-6, 0.0), bubble(1, 50e-6, 0.0)],
            ),
            frame(
                20.0,
                1e5,
                0.0,
                vec![bubble(0, 110e-6, 0.0), bubble(1, 70e-6, 0.0)],
            ),
            frame(
                30.0,
                1e5,
                0.0,
                vec![bubble(0, 115e-6, 0.0), bubble(1, 71e-6, 0.0)],
            ),
        ];
        let got = area_rate_after_surfacing(&f, 10.0);
        let want = [(15.0, 4.0 * PI * 240.0), (25.0, 4.0 * PI * 112.5)];
        assert_eq!(got.len(), 2, "{got:?}");
        for ((t, r), (wt, wr)) in got.iter().zip(want) {
            assert_eq!(*t, wt);
            assert!((r * 1e12 - wr).abs() < 1e-9 * wr, "{r} vs {wr}");
        }
    }
}
