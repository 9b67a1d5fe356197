//! A run's plots: every bubble's radius and volume against time.

use crate::phantom::sim::{BubbleFrame, Frame};
use crate::report::plot::{LinePlot, Series};

/// Time axis in s for runs up to an hour, in min beyond.
pub fn time_axis(frames: &[Frame]) -> (f64, &'static str) {
    if frames.last().map_or(0.0, |f| f.time) > 3600.0 {
        (60.0, "time (min)")
    } else {
        (1.0, "time (s)")
    }
}

/// One series per bubble of `value(bubble)` against time (in the axis unit `tu`, s).
pub fn per_bubble_series(
    frames: &[Frame],
    tu: f64,
    value: impl Fn(&BubbleFrame) -> f64,
) -> Vec<Series> {
    let ids: std::collections::BTreeSet<usize> = frames
        .iter()
        .flat_map(|f| f.bubbles.iter().map(|b| b.id))
        .collect();
    ids.into_iter()
        .map(|id| {
            let pts = frames
                .iter()
                .filter_map(|f| {
                    f.bubbles
                        .iter()
                        .find(|b| b.id == id)
                        .map(|b| (f.time / tu, value(b)))
                })
                .collect();
            Series::new(format!("bubble {id}"), pts)
        })
        .collect()
}

/// Radius of every bubble over time, µm.
pub fn radius_plot(frames: &[Frame], title: &str) -> LinePlot {
    let (tu, tl) = time_axis(frames);
    let mut p = LinePlot::new(title, tl, "radius (µm)");
    p.series = per_bubble_series(frames, tu, |b| b.radius * 1e6);
    p
}

/// Total and per-bubble volume over time, mm³.
pub fn volume_plot(frames: &[Frame], title: &str) -> LinePlot {
    let (tu, tl) = time_axis(frames);
    let total = frames
        .iter()
        .map(|f| {
            (
                f.time / tu,
                f.bubbles.iter().map(|b| b.volume).sum::<f64>() * 1e9,
            )
        })
        .collect();
    let mut p = LinePlot::new(title, tl, "volume (mm³)").with(Series::new("total", total));
    p.series
        .extend(per_bubble_series(frames, tu, |b| b.volume * 1e9));
    p
}
