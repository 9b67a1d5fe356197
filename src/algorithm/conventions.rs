//! The conventions in which planners differ, each a named setting (see `algorithms/*.toml`).

use serde::{Deserialize, Serialize};

/// How stop times are rounded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StopRounding {
    /// Whole minutes spent at the stop, travel to the next stop excluded (DecoTengu, Subsurface).
    WholeMinutesAtStop,
    /// Stop ends on a whole minute of runtime; the stop minutes include travel to it (Baker's VPM-B).
    WholeMinutesOfRuntime,
    /// No rounding; stops end as soon as the ceiling allows (to the second; dive-deco).
    None,
}

/// Where the gradient-factor line is anchored.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum GfLowAnchor {
    /// At the first stop (DecoTengu, Subsurface).
    FirstStop,
    /// At the deepest ceiling reached (some planners).
    DeepestCeiling,
}

/// Conventions of a planner. All SI except where the name says otherwise.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Conventions {
    /// Surface pressure, Pa (DecoTengu 101 325; Baker 101 325; dive-deco 101 325 by default).
    pub surface_pressure_pa: f64,
    /// Pressure per metre of depth, Pa/m (DecoTengu 9 985 (0.09985 bar/m); dive-deco 10 000;
    /// Baker 10 000 (10.1325 msw per atm); Subsurface from salinity 1030 g/l: 1030·9.80665 ≈ 10 100.85).
    pub pa_per_m: f64,
    /// Alveolar water-vapour pressure, Pa (DecoTengu 6 270 (0.0627 bar); Subsurface 5 670; Baker 4 930).
    pub water_vapour_pa: f64,
    /// Descent rate, m/min.
    pub descent_rate_m_min: f64,
    /// Ascent rate, m/min.
    pub ascent_rate_m_min: f64,
    /// Stop spacing, m (3).
    pub stop_spacing_m: f64,
    /// Depth of the last stop, m (3 or 6).
    pub last_stop_m: f64,
    /// Whether the bottom time includes the descent (true: bottom time is runtime at leaving the bottom).
    pub bottom_time_includes_descent: bool,
    /// Stop-time rounding.
    pub stop_rounding: StopRounding,
    /// GF-low anchor.
    pub gf_low_anchor: GfLowAnchor,
    /// Minimum stop time, min (1 for most planners; 0 allowed).
    pub min_stop_min: f64,
}
