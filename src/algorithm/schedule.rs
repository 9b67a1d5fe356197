//! A planned dive and the schedule an algorithm produces for it.

use crate::gas::GasMix;
use crate::profile::PressureHistory;
use serde::{Deserialize, Serialize};

/// A decompression gas and the depth at which it is switched to.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DecoGas {
    /// The mix.
    pub mix: GasMix,
    /// Switch depth, m (default: MOD at ppO2 1.6 bar).
    pub switch_depth_m: f64,
}

/// What the diver wants to do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DivePlan {
    /// Maximum depth, m.
    pub depth_m: f64,
    /// Bottom time, min (whether it includes the descent is a convention).
    pub bottom_time_min: f64,
    /// Bottom gas.
    pub bottom_gas: GasMix,
    /// Decompression gases.
    pub deco_gases: Vec<DecoGas>,
}

/// The kind of a schedule leg.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LegKind {
    /// Descent from the surface.
    Descent,
    /// Time at the bottom.
    Bottom,
    /// Travel upwards.
    Ascent,
    /// A decompression stop (constant depth).
    Stop,
}

/// One leg of constant rate and one gas.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Leg {
    /// What this leg is.
    pub kind: LegKind,
    /// Depth at the start, m.
    pub start_depth_m: f64,
    /// Depth at the end, m.
    pub end_depth_m: f64,
    /// Duration, s.
    pub duration_s: f64,
    /// Gas breathed on the leg.
    pub gas: GasMix,
}

/// A stop as printed in a stop table.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Stop {
    /// Stop depth, m.
    pub depth_m: f64,
    /// Minutes at the stop (as the algorithm's rounding convention counts them).
    pub stop_min: f64,
    /// Runtime when leaving the stop, min.
    pub runtime_min: f64,
    /// Gas at the stop.
    pub gas: GasMix,
}

/// A dive schedule: legs from the surface back to the surface.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Schedule {
    /// Label, e.g. `ZH-L16C GF 30/85`.
    pub label: String,
    /// Surface pressure, Pa.
    pub surface_pressure_pa: f64,
    /// Pressure per metre, Pa/m.
    pub pa_per_m: f64,
    /// Alveolar water vapour, Pa (subtracted at the phantom's open faces).
    pub water_vapour_pa: f64,
    /// The legs in order.
    pub legs: Vec<Leg>,
    /// The stops (derived from the legs by the algorithm with its rounding convention).
    pub stops: Vec<Stop>,
}

impl Schedule {
    /// Total runtime, min.
    pub fn runtime_min(&self) -> f64 {
        self.legs.iter().map(|l| l.duration_s).sum::<f64>() / 60.0
    }

    /// Ambient pressure at a depth, Pa.
    pub fn pressure_at(&self, depth_m: f64) -> f64 {
        self.surface_pressure_pa + depth_m * self.pa_per_m
    }

    /// The pressure history the phantom takes: one breakpoint per leg end, the leg's gas on
    /// each segment, the schedule's water vapour subtracted at the open faces. Zero-length legs
    /// (gas switches) are merged into the next leg.
    pub fn to_pressure_history(&self) -> Result<PressureHistory, String> {
        let mut t = vec![0.0];
        let mut p = vec![self.pressure_at(self.legs.first().map_or(0.0, |l| l.start_depth_m))];
        let mut g = Vec::new();
        let mut now = 0.0;
        for leg in &self.legs {
            if leg.duration_s <= 0.0 {
                continue;
            }
            now += leg.duration_s;
            t.push(now);
            p.push(self.pressure_at(leg.end_depth_m));
            g.push(leg.gas);
        }
        if g.is_empty() {
            return Err(format!(
                "schedule '{}' has no legs of positive duration",
                self.label
            ));
        }
        PressureHistory::new(self.label.clone(), t, p, g, self.water_vapour_pa)
    }
}
