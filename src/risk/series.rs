//! Time series drawn from the recorded frames, shared by the criteria and the report.

use crate::phantom::sim::Frame;
use std::collections::BTreeMap;

/// Total bubble volume at each frame: (time s, Σ V m³).
pub fn total_volume(frames: &[Frame]) -> Vec<(f64, f64)> {
    frames
        .iter()
        .map(|f| (f.time, f.bubbles.iter().map(|b| b.volume).sum()))
        .collect()
}

/// Total bubble surface area at each frame: (time s, Σ A m²).
pub fn total_area(frames: &[Frame]) -> Vec<(f64, f64)> {
    frames
        .iter()
        .map(|f| (f.time, f.bubbles.iter().map(|b| b.area).sum()))
        .collect()
}

/// One series per bubble id: (time s, value) from `get` for every frame the bubble is in.
pub fn per_bubble(
    frames: &[Frame],
    get: impl Fn(&crate::phantom::sim::BubbleFrame) -> f64,
) -> BTreeMap<usize, Vec<(f64, f64)>> {
    let mut out: BTreeMap<usize, Vec<(f64, f64)>> = BTreeMap::new();
    for f in frames {
        for b in &f.bubbles {
            out.entry(b.id).or_default().push((f.time, get(b)));
        }
    }
    out
}

/// Forward differences of a series: ((t_i + t_{i+1})/2, (y_{i+1} − y_i)/(t_{i+1} − t_i)) for
/// every pair of points with increasing time.
pub fn rate(points: &[(f64, f64)]) -> Vec<(f64, f64)> {
    points
        .windows(2)
        .filter(|w| w[1].0 > w[0].0)
        .map(|w| {
            (
                0.5 * (w[0].0 + w[1].0),
                (w[1].1 - w[0].1) / (w[1].0 - w[0].0),
            )
        })
        .collect()
}

/// ∫ max(0, y(t) − threshold) dt of the piecewise-linear interpolant of `points` (exact for
/// it: a segment that crosses the threshold contributes only its part above).
pub fn integral_above(points: &[(f64, f64)], threshold: f64) -> f64 {
    points
        .windows(2)
        .map(|w| {
            let (t0, a) = (w[0].0, w[0].1 - threshold);
            let (t1, b) = (w[1].0, w[1].1 - threshold);
            let dt = t1 - t0;
            if !(dt > 0.0) {
                0.0
            } else if a >= 0.0 && b >= 0.0 {
                0.5 * (a + b) * dt
            } else if a <= 0.0 && b <= 0.0 {
                0.0
            } else {
                // one end above: a triangle of height max(a, b) over the part above
                let hi = a.max(b);
                let frac = hi / (a - b).abs();
                0.5 * hi * frac * dt
            }
        })
        .sum()
}

/// Largest value of a series (−∞ for an empty one).
pub fn peak(points: &[(f64, f64)]) -> f64 {
    points.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max)
}

/// Supersaturation of the gel at each bubble's coupling sphere, the largest over bubbles at
/// each frame: (time s, max_b(gel tension − P_amb) Pa); frames without bubbles are skipped.
pub fn supersaturation_at_bubbles(frames: &[Frame]) -> Vec<(f64, f64)> {
    frames
        .iter()
        .filter(|f| !f.bubbles.is_empty())
        .map(|f| {
            (
                f.time,
                f.bubbles
                    .iter()
                    .map(|b| b.gel_tension - f.ambient)
                    .fold(f64::NEG_INFINITY, f64::max),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integral_above_matches_triangles_and_trapezoids() {
        // y = 2t on [0, 3] sampled at 0, 1, 2, 3 and threshold 1: the line crosses at t = 0.5;
        // ∫_{0.5}^{3} (2t − 1) dt = [t² − t]_{0.5}^{3} = 6 − (−0.25) = 6.25 (exact for a line).
        let pts: Vec<(f64, f64)> = (0..=3).map(|i| (i as f64, 2.0 * i as f64)).collect();
        assert!((integral_above(&pts, 1.0) - 6.25).abs() < 1e-12);
        // threshold above everything → 0; threshold 0 → plain trapezoid ∫ 2t dt = 9
        assert_eq!(integral_above(&pts, 10.0), 0.0);
        assert!((integral_above(&pts, 0.0) - 9.0).abs() < 1e-12);
        // a falling segment that crosses: (0, 3) → (1, −1) above 0 is a triangle of height 3
        // over 3/4 of the unit interval: 0.5·3·0.75 = 1.125
        assert!((integral_above(&[(0.0, 3.0), (1.0, -1.0)], 0.0) - 1.125).abs() < 1e-12);
    }

    #[test]
    fn rate_is_the_forward_difference() {
        let r = rate(&[(0.0, 1.0), (2.0, 5.0), (2.0, 7.0), (4.0, 5.0)]);
        assert_eq!(r, vec![(1.0, 2.0), (3.0, -1.0)]);
    }
}
