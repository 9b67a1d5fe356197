//! A run in words: how it ended, its events, and the short summary the terminal and the
//! reports print.

use super::SimRun;
use crate::phantom::sim::{Ending, Event, Frame};

/// A one-line description of how a run ended.
pub fn ending_text(e: &Ending) -> String {
    match e {
        Ending::Completed => "completed".into(),
        Ending::Interrupted { time } => {
            format!("interrupted at t = {time:.1} s; everything up to then is recorded")
        }
        Ending::BubbleReachedFace { bubble, face, time } => {
            format!(
                "bubble {bubble} reached the {} face at t = {time:.1} s; the run stopped there",
                face.name()
            )
        }
    }
}

pub(super) fn event_text(e: &Event) -> String {
    match e {
        Event::Coalesced {
            time,
            into,
            absorbed,
        } => format!("t = {time:.1} s: bubble {absorbed} coalesced into {into}"),
        Event::Dissolved { time, bubble } => format!("t = {time:.1} s: bubble {bubble} dissolved"),
    }
}

/// A short human-readable summary of a run, with its wall time (for the terminal).
pub fn describe(run: &SimRun) -> String {
    let mut text = describe_results(run);
    text.pop();
    text.push_str(&format!("; wall {:.2} s\n", run.wall_seconds));
    if let Some(t) = run.resumed_at {
        text.push_str(&format!("resumed from a checkpoint at t = {t:.1} s\n"));
    }
    if let Some(c) = run.checkpoints.as_ref().filter(|c| c.written > 0) {
        text.push_str(&format!(
            "{} checkpoint(s) of {:.1} MB written in {:.2} s\n",
            c.written,
            c.bytes as f64 / 1e6,
            c.seconds
        ));
    }
    text
}

/// A short human-readable summary of a run's results, without the wall time (for reports,
/// which must not change when regenerated from the same inputs). Bubble growth is reported
/// above each bubble's starting radius R0 (a run whose bubbles only shrink says so, rather
/// than calling R0 at t = 0 its "max radius"); volumes in mm³, radii in µm.
pub fn describe_results(run: &SimRun) -> String {
    use crate::report::table::sig_text;
    let s = &run.summary;
    let notes: String = run.notes.iter().map(|n| format!("note: {n}\n")).collect();
    let growth = match peak_growth(&run.frames) {
        Some(g) if g.growth > 1e-6 * g.r0 => format!(
            "largest growth above R0: bubble {}, +{} µm (R0 {} µm → {} µm at t = {:.1} s)",
            g.id,
            sig_text(g.growth * 1e6, 4, true),
            sig_text(g.r0 * 1e6, 4, true),
            sig_text((g.r0 + g.growth) * 1e6, 4, true),
            g.time
        ),
        Some(_) => "no bubble grew above its starting radius R0".to_string(),
        None => "no bubbles".to_string(),
    };
    let start = run.frames.first().map_or(f64::NAN, |f| {
        f.bubbles.iter().map(|b| b.volume).sum::<f64>()
    });
    let volume = if s.peak_total_volume.0 > start * (1.0 + 1e-6) {
        format!(
            "peak total volume {} mm³ at t = {:.1} s (start {} mm³)",
            sig_text(s.peak_total_volume.0 * 1e9, 4, true),
            s.peak_total_volume.1,
            sig_text(start * 1e9, 4, true)
        )
    } else {
        format!(
            "total volume never above its start, {} mm³",
            sig_text(start * 1e9, 4, true)
        )
    };
    notes
        + &format!(
            "{}\n{growth}; {volume}\nsteps {} explicit + {} implicit on {} cells; gas-balance error {:.2e}\n",
            ending_text(&s.ending),
            s.steps.0,
            s.steps.1,
            s.cells,
            s.gas_balance_error,
        )
}

/// The largest growth of a bubble above its radius in the first frame it appears in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeakGrowth {
    /// Bubble id.
    pub id: usize,
    /// Its starting radius, m.
    pub r0: f64,
    /// Largest R − R0 over the run, m (≤ 0 when it never grew).
    pub growth: f64,
    /// When, s.
    pub time: f64,
}

/// The bubble that grew most above its starting radius, or `None` without bubbles.
pub fn peak_growth(frames: &[Frame]) -> Option<PeakGrowth> {
    let mut start: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
    let mut best: Option<PeakGrowth> = None;
    for f in frames {
        for b in &f.bubbles {
            let r0 = *start.entry(b.id).or_insert(b.radius);
            let g = b.radius - r0;
            if best.is_none_or(|x| g > x.growth) {
                best = Some(PeakGrowth {
                    id: b.id,
                    r0,
                    growth: g,
                    time: f.time,
                });
            }
        }
    }
    best
}
