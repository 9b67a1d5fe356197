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
    /// Nitrogen fraction used for the tissues' starting load at the surface:
    /// p_N2 = fraction × (surface pressure − water vapour). DecoTengu 0.7902, Subsurface 0.781,
    /// Baker 0.79. Defaults to 0.79 when absent from a file (added after the first release of
    /// this struct; see [`default_surface_tissue_n2_fraction`]).
    #[serde(default = "default_surface_tissue_n2_fraction")]
    pub surface_tissue_n2_fraction: f64,
}

/// Default starting N2 fraction of the tissues (0.79, dry air without argon as planners lump it).
pub fn default_surface_tissue_n2_fraction() -> f64 {
    0.79
}

/// Lowest and highest surface pressure accepted in conventions and schedule files, Pa: 500 to
/// 1 100 hPa, from about 5 600 m of altitude (ICAO standard atmosphere) to above any sea-level
/// record (the range of `plan --surface-pressure`). A value in kPa (101.325) or bar (1.01325)
/// falls outside it and is refused, naming the field.
pub const SURFACE_PRESSURE_RANGE_PA: (f64, f64) = (50_000.0, 110_000.0);

/// Lowest and highest pressure per metre of depth accepted in conventions and schedule files,
/// Pa/m: ρ·g for water densities of about 969 to 1 081 kg/m³, which covers fresh water
/// (9 806.65 Pa/m at 1 000 kg/m³), DecoTengu's 9 985, the 10 000 of "1 msw = 0.1 bar",
/// Subsurface's sea water (1 030 kg/m³: 10 100.85) and brackish or saline lakes; not the
/// Dead Sea (about 1 240 kg/m³). A value in kPa/m (9.985) or bar/m (0.09985), or a
/// pressure per foot (about 3 000 Pa/ft), falls outside it and is refused.
pub const PA_PER_M_RANGE: (f64, f64) = (9_500.0, 10_600.0);

/// Highest alveolar water-vapour pressure accepted in conventions and schedule files, Pa (the
/// bound of the criteria protocol's `water_vapour_pa`): 47 mmHg = 6 270 Pa at 37 °C; saturated
/// vapour reaches 20 kPa only at about 60 °C.
pub const MAX_WATER_VAPOUR_PA: f64 = 20_000.0;

/// Slowest descent or ascent rate accepted, m/min: the rate at which the deepest accepted plan
/// ([`super::schedule::MAX_PLAN_DEPTH_M`], 1 000 m) reaches the surface in the longest history
/// accepted (30 days, [`crate::profile::MAX_DURATION_S`]): 1 000 m / 43 200 min ≈ 0.023 m/min
/// (1.4 m/h, the pace of saturation decompression, which these planners do not model). A plan's
/// whole runtime is checked against the 30 days as well
/// ([`crate::algorithm::request::plan_dive`]).
pub const MIN_TRAVEL_RATE_M_MIN: f64 =
    super::schedule::MAX_PLAN_DEPTH_M / (crate::profile::MAX_DURATION_S / 60.0);

/// Fastest descent or ascent rate accepted, m/min: the top of the range of `--descent-rate` and
/// `--ascent-rate`, and of the travel legs of a schedule (a `descent` or `ascent` leg of a
/// schedule TOML, a segment between two waypoints of a CSV): 100 m/min is several times the
/// travel rates of the usual tables (ascents at 9–18 m/min), so a faster movement is an error
/// of the file (a misplaced decimal, seconds given as minutes), not a dive.
pub const MAX_TRAVEL_RATE_M_MIN: f64 = 100.0;

/// Why a descent or ascent rate of `v` m/min is refused (not a positive number, or outside
/// [`MIN_TRAVEL_RATE_M_MIN`]..=[`MAX_TRAVEL_RATE_M_MIN`]), `None` when it is accepted: the one
/// check of an algorithm file's `descent_rate_m_min` / `ascent_rate_m_min` and of
/// `--descent-rate` / `--ascent-rate`.
pub fn travel_rate_refusal(v: f64) -> Option<String> {
    let v_text = crate::error::num(v);
    if !(v.is_finite() && v > 0.0) {
        Some(format!("must be a positive number of m/min, got {v_text}"))
    } else if v < MIN_TRAVEL_RATE_M_MIN {
        Some(format!(
            "{v_text} m/min is slower than {MIN_TRAVEL_RATE_M_MIN:.4} m/min, at which 1000 m take the whole 30 days a history may last"
        ))
    } else if v > MAX_TRAVEL_RATE_M_MIN {
        Some(format!(
            "{v_text} m/min is faster than the accepted {MAX_TRAVEL_RATE_M_MIN} m/min (the presets travel at 9–20 m/min); give the rate in m/min"
        ))
    } else {
        None
    }
}

/// Whether `v` lies in the closed range `r` (a NaN never does).
pub fn within(v: f64, r: (f64, f64)) -> bool {
    v >= r.0 && v <= r.1
}

/// Named presets reproducing reference planners, as data: `(name, conventions, source)`.
/// Every value is cited in the comment of the constant it comes from.
pub const PRESETS: &[(&str, Conventions, &str)] = &[
    (
        "decotengu",
        DECOTENGU,
        "DecoTengu 0.14.1: decotengu/const.py, engine.py, model.py",
    ),
    (
        "subsurface",
        SUBSURFACE,
        "Subsurface: core/deco.cpp, core/units.h, core/dive.cpp, core/pref.cpp",
    ),
    (
        "baker",
        BAKER,
        "Baker, VPMDECO.FOR and the issue's Baker conventions",
    ),
    (
        "dive-deco",
        DIVE_DECO,
        "dive-deco crate (MIT): 10 m/bar, per-second stops",
    ),
];

/// DecoTengu 0.14.1 (read from its installed source, used as an outside oracle only).
pub const DECOTENGU: Conventions = Conventions {
    // const.SURFACE_PRESSURE = 1.01325 bar.
    surface_pressure_pa: 101_325.0,
    // const.METER_TO_BAR = 0.09985 bar/m.
    pa_per_m: 9_985.0,
    // const.WATER_VAPOUR_PRESSURE_DEFAULT = WATER_VAPOUR_PRESSURE_Q10 = 0.0627 bar.
    water_vapour_pa: 6_270.0,
    // Engine.descent_rate = 20 m/min.
    descent_rate_m_min: 20.0,
    // Engine.ascent_rate = 10 m/min.
    ascent_rate_m_min: 10.0,
    // Stops at multiples of 3 m (Engine._p3m = 3 * METER_TO_BAR).
    stop_spacing_m: 3.0,
    // Engine.last_stop_6m = False.
    last_stop_m: 3.0,
    // Engine.calculate: bottom segment lasts `time - descent time`.
    bottom_time_includes_descent: true,
    // Engine._deco_stop: whole minutes at the stop (const.MINUTE steps), ascent excluded.
    stop_rounding: StopRounding::WholeMinutesAtStop,
    // GF-low at the first stop, GF-high at the surface (model.py docs, Engine._deco_stops).
    gf_low_anchor: GfLowAnchor::FirstStop,
    // The first check of a stop is after const.MINUTE = 1 min.
    min_stop_min: 1.0,
    // ZH_L16_GF.START_P_N2 = 0.7902.
    surface_tissue_n2_fraction: 0.7902,
};

/// Subsurface's planner (Bühlmann mode), values from its source (core/…), GPL, read only.
pub const SUBSURFACE: Conventions = Conventions {
    // core/units.h: SURFACE_PRESSURE 1013 mbar.
    surface_pressure_pa: 101_300.0,
    // core/dive.cpp calculate_depth_to_mbar: SEAWATER_SALINITY 10300 g/10 l, specific weight
    // salinity/10000 × 0.981 mbar per cm → 1.03 × 0.981 × 10 000 Pa/m = 10 104.3 Pa/m (g = 9.81).
    pa_per_m: 10_104.3,
    // core/deco.cpp: WV_PRESSURE 0.0627 bar for Bühlmann (0.0493 "Schreiner" only for VPM-B).
    water_vapour_pa: 6_270.0,
    // core/pref.cpp default descrate = 18000/60 mm/s = 18 m/min.
    descent_rate_m_min: 18.0,
    // core/pref.cpp default ascrate75 = 9000/60 mm/s = 9 m/min. Subsurface slows to 6 m/min
    // above 50 % of the depth and between stops, and to 1 m/min in the last 6 m; one rate is
    // modelled here, so schedules agree with Subsurface only approximately.
    ascent_rate_m_min: 9.0,
    // core/deco.cpp DECO_STOPS_MULTIPLIER_MM 3000.
    stop_spacing_m: 3.0,
    // core/pref.cpp last_stop = false → 3 m.
    last_stop_m: 3.0,
    // Planner waypoints are runtimes: the descent counts towards the bottom time.
    bottom_time_includes_descent: true,
    // Stops are extended in 1-minute deco timesteps.
    stop_rounding: StopRounding::WholeMinutesAtStop,
    // core/deco.cpp tissue_tolerance_calc: gf_low_pressure_this_dive = deepest GF-low ceiling.
    gf_low_anchor: GfLowAnchor::DeepestCeiling,
    min_stop_min: 1.0,
    // core/deco.cpp clear_deco: tissue N2 = (surface − WV) × N2_IN_AIR/1000, N2_IN_AIR 781 (units.h).
    surface_tissue_n2_fraction: 0.781,
};

/// Baker's conventions for VPMDECO (the list): msw at 10.1325 m/atm.
pub const BAKER: Conventions = Conventions {
    // 1 atm.
    surface_pressure_pa: 101_325.0,
    // 10.1325 msw per atm → 101 325 / 10.1325 = 10 000 Pa/m (units::MSW_PA).
    pa_per_m: 10_000.0,
    // Schreiner's alveolar water vapour, RQ 0.8: 0.0493 bar.
    water_vapour_pa: 4_930.0,
    descent_rate_m_min: 20.0,
    ascent_rate_m_min: 10.0,
    stop_spacing_m: 3.0,
    last_stop_m: 3.0,
    // Bottom time is the runtime at the end of the bottom segment.
    bottom_time_includes_descent: true,
    // Stops end on whole minutes of runtime and include the travel to them.
    stop_rounding: StopRounding::WholeMinutesOfRuntime,
    gf_low_anchor: GfLowAnchor::FirstStop,
    // Minimum_Deco_Stop_Time = 1 min.
    min_stop_min: 1.0,
    // VPMDECO starts tissues at 0.79 × (barometric − water vapour).
    surface_tissue_n2_fraction: 0.79,
};

/// dive-deco (MIT Rust crate) conventions per the issue: 10 m/bar, per-second stops, no
/// rounding. Values not stated there (rates, vapour) are the common defaults and are not
/// checked against the crate's source.
pub const DIVE_DECO: Conventions = Conventions {
    surface_pressure_pa: 101_325.0,
    // 10 m per bar.
    pa_per_m: 10_000.0,
    water_vapour_pa: 6_270.0,
    descent_rate_m_min: 20.0,
    ascent_rate_m_min: 10.0,
    stop_spacing_m: 3.0,
    last_stop_m: 3.0,
    bottom_time_includes_descent: true,
    stop_rounding: StopRounding::None,
    gf_low_anchor: GfLowAnchor::FirstStop,
    min_stop_min: 0.0,
    surface_tissue_n2_fraction: 0.79,
};

impl Conventions {
    /// A preset by name (`decotengu`, `subsurface`, `baker`, `dive-deco`).
    pub fn preset(name: &str) -> Option<Conventions> {
        PRESETS
            .iter()
            .find(|(n, _, _)| n.eq_ignore_ascii_case(name.trim()))
            .map(|(_, c, _)| c.clone())
    }

    /// Names of the presets, for error messages.
    pub fn preset_names() -> Vec<&'static str> {
        PRESETS.iter().map(|(n, _, _)| *n).collect()
    }

    /// Ambient pressure at a depth, Pa.
    pub fn pressure_at(&self, depth_m: f64) -> f64 {
        self.surface_pressure_pa + depth_m * self.pa_per_m
    }

    /// Check the values; the error names the field (without the `conventions.` prefix).
    pub fn validate(&self) -> Result<(), (String, String)> {
        let pos = |name: &str, v: f64| -> Result<(), (String, String)> {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err((
                    name.to_string(),
                    format!("must be a positive number, got {v}"),
                ))
            }
        };
        pos("surface_pressure_pa", self.surface_pressure_pa)?;
        pos("pa_per_m", self.pa_per_m)?;
        pos("stop_spacing_m", self.stop_spacing_m)?;
        pos("last_stop_m", self.last_stop_m)?;
        let (sp_lo, sp_hi) = SURFACE_PRESSURE_RANGE_PA;
        if !within(self.surface_pressure_pa, SURFACE_PRESSURE_RANGE_PA) {
            return Err((
                "surface_pressure_pa".into(),
                format!(
                    "must be between {sp_lo} and {sp_hi} Pa (500–1100 hPa), got {}; give it in Pa",
                    crate::error::num(self.surface_pressure_pa)
                ),
            ));
        }
        let (pm_lo, pm_hi) = PA_PER_M_RANGE;
        if !within(self.pa_per_m, PA_PER_M_RANGE) {
            return Err((
                "pa_per_m".into(),
                format!(
                    "must be between {pm_lo} and {pm_hi} Pa/m (fresh to sea water), got {}; give it in Pa per metre",
                    crate::error::num(self.pa_per_m)
                ),
            ));
        }
        for (name, v) in [
            ("descent_rate_m_min", self.descent_rate_m_min),
            ("ascent_rate_m_min", self.ascent_rate_m_min),
        ] {
            if let Some(why) = travel_rate_refusal(v) {
                return Err((name.into(), why));
            }
        }
        if !(self.water_vapour_pa.is_finite()
            && self.water_vapour_pa >= 0.0
            && self.water_vapour_pa <= MAX_WATER_VAPOUR_PA)
        {
            return Err((
                "water_vapour_pa".into(),
                format!(
                    "must be in 0..{MAX_WATER_VAPOUR_PA} Pa (47 mmHg = 6270 Pa at 37 °C), got {}",
                    crate::error::num(self.water_vapour_pa)
                ),
            ));
        }
        if !(self.min_stop_min.is_finite() && self.min_stop_min >= 0.0) {
            return Err((
                "min_stop_min".into(),
                format!("must be zero or positive, got {}", self.min_stop_min),
            ));
        }
        if !(self.surface_tissue_n2_fraction > 0.0 && self.surface_tissue_n2_fraction <= 1.0) {
            return Err((
                "surface_tissue_n2_fraction".into(),
                format!("must be in (0, 1], got {}", self.surface_tissue_n2_fraction),
            ));
        }
        Ok(())
    }
}
