//! `peak-area-growth-rate`: the fastest growth of any single bubble's surface area, µm²/s —
//! the paper's surface-area-dependent growth (its D_surf scales with area). dA/dt is the
//! forward difference between consecutive recorded frames in which the bubble exists; the
//! value is the largest over bubbles and frame pairs, 0 when no bubble ever grows.
//! `window = "after-surfacing"` looks only from the moment the dive reaches the surface, so
//! the Boyle expansion of the ascent is left out and only diffusive growth counts
//! (default `"whole-run"`).

use super::{params, series, RiskCriterion, RunData, Window};
use serde::Deserialize;

/// Peak per-bubble dA/dt, µm²/s.
#[derive(Debug, Clone, Copy, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeakAreaGrowthRate {
    /// Which frames (default the whole run).
    #[serde(default)]
    pub window: Window,
}

impl RiskCriterion for PeakAreaGrowthRate {
    fn name(&self) -> &'static str {
        "peak-area-growth-rate"
    }
    fn unit(&self) -> &'static str {
        "µm²/s"
    }
    fn evaluate(&self, run: &RunData) -> f64 {
        series::per_bubble(run.window(self.window), |b| b.area)
            .values()
            .flat_map(|pts| series::rate(pts))
            .map(|(_, r)| r)
            .fold(0.0, f64::max)
            * 1e12
    }
    fn describe(&self) -> String {
        format!(
            "peak single-bubble surface-area growth rate dA/dt (between recorded frames){}",
            match self.window {
                Window::WholeRun => "",
                Window::AfterSurfacing => ", after surfacing",
            }
        )
    }
}

/// Build from the (empty) parameter table.
pub fn build(t: toml::Table) -> Result<Box<dyn RiskCriterion>, String> {
    Ok(Box::new(params::<PeakAreaGrowthRate>(t)?))
}

#[cfg(test)]
mod tests {
    use super::super::testing::{bubble, frame};
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn fastest_growth_between_frames() {
        // bubble 0: R = 100, 110, 115 µm at t = 0, 10, 30 s; bubble 1: 50 → 70 µm over 5..15 s.
        // Rates: b0 4π(110² − 100²)/10 = 4π·210 = 2638.9 µm²/s, then 4π(115² − 110²)/20 = 4π·56.25;
        // b1 4π(70² − 50²)/10 = 4π·240 = 3015.9 µm²/s → the peak.
        let f = vec![
            frame(0.0, 1e5, 0.0, vec![bubble(0, 100e-6, 0.0)]),
            frame(5.0, 1e5, 0.0, vec![bubble(1, 50e-6, 0.0)]),
            frame(10.0, 1e5, 0.0, vec![bubble(0, 110e-6, 0.0)]),
            frame(15.0, 1e5, 0.0, vec![bubble(1, 70e-6, 0.0)]),
            frame(30.0, 1e5, 0.0, vec![bubble(0, 115e-6, 0.0)]),
        ];
        let want = 4.0 * PI * 240.0;
        let got = PeakAreaGrowthRate::default().evaluate(&RunData::new(&f));
        assert!((got - want).abs() < 1e-9 * want, "{got} vs {want}");
        // shrinking only → 0
        let g = vec![
            frame(0.0, 1e5, 0.0, vec![bubble(0, 100e-6, 0.0)]),
            frame(1.0, 1e5, 0.0, vec![bubble(0, 90e-6, 0.0)]),
        ];
        assert_eq!(
            PeakAreaGrowthRate::default().evaluate(&RunData::new(&g)),
            0.0
        );
        // Pairs need both frames in the window. Surfacing at 12 s leaves b1 at 15 s and b0 at
        // 30 s, one frame each → 0; surfacing at 8 s keeps b0's 10→30 s pair, 4π·56.25 µm²/s.
        let after = PeakAreaGrowthRate {
            window: Window::AfterSurfacing,
        };
        let at = |t| RunData {
            frames: &f,
            surfaced_s: Some(t),
        };
        assert_eq!(after.evaluate(&at(12.0)), 0.0);
        assert!((after.evaluate(&at(8.0)) - 4.0 * PI * 56.25).abs() < 1e-9);
    }
}
