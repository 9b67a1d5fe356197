//! What a phantom run will cost, estimated before it starts: cells × expected steps × the time
//! of one cell-step. Used to warn about long runs and, in the binary, to refuse runs estimated
//! at hours unless `--force` is given.

use crate::error::{Error, InputError};
use crate::phantom::grid::Shape;
use crate::phantom::params::PhantomParams;
use crate::profile::PressureHistory;
use std::sync::atomic::{AtomicU64, Ordering};

/// Wall time of one cell-step, s: an upper-range value measured on the project's 2-core
/// machine (hydrogel phantom: 7e-9 for a pressure oscillation, 2e-8 for a schedule, 6.5e-8
/// for the Fig. 5 dive while bubbles grow).
pub const SECONDS_PER_CELL_STEP: f64 = 5e-8;

/// Runs estimated above this are reported on stderr when a limit is set, s (10 min).
pub const WARN_ABOVE_S: f64 = 600.0;

/// Default limit of the binary, s (6 h): longer runs need `--force`.
pub const DEFAULT_LIMIT_S: f64 = 6.0 * 3600.0;

/// The limit in force (f64 bits); infinity (no limit) unless [`set_limit`] was called.
static LIMIT_BITS: AtomicU64 = AtomicU64::new(0x7FF0_0000_0000_0000);

/// Set the longest estimated run accepted, s (`f64::INFINITY`: no limit, the library default).
/// A finite limit also turns on the warning for runs above [`WARN_ABOVE_S`].
pub fn set_limit(seconds: f64) {
    LIMIT_BITS.store(seconds.to_bits(), Ordering::Relaxed);
}

fn limit() -> f64 {
    f64::from_bits(LIMIT_BITS.load(Ordering::Relaxed))
}

/// A run's estimated cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// Cells inside the phantom.
    pub cells: f64,
    /// Expected time steps.
    pub steps: f64,
    /// Expected wall time, s.
    pub seconds: f64,
}

/// Estimate a run: inside cells from the geometry and the grid step; steps from the profile's
/// duration over `max_step_s` plus the pressure changes over `max_pressure_change`.
pub fn estimate(params: &PhantomParams, profile: &PressureHistory) -> Estimate {
    let h = params.grid_step;
    let n = |x: f64| (x / h).round().max(3.0);
    let cells = match params.shape {
        Shape::Box { size } => n(size[0]) * n(size[1]) * n(size[2]),
        Shape::Cylinder { diameter, depth } => {
            std::f64::consts::FRAC_PI_4 * n(diameter) * n(diameter) * n(depth)
        }
    };
    let num = &params.numerics;
    let mut steps = profile.duration_s() / num.max_step;
    for w in profile.ambient_pa.windows(2) {
        steps += (w[1] / w[0]).ln().abs() / num.max_pressure_change;
    }
    steps += profile.times_s.len() as f64;
    Estimate {
        cells,
        steps,
        seconds: cells * steps * SECONDS_PER_CELL_STEP,
    }
}

/// Check a run against the limit in force: above it, bad input (exit 2) naming `--force`;
/// above [`WARN_ABOVE_S`] with a limit set, a note on stderr.
pub fn check(params: &PhantomParams, profile: &PressureHistory) -> Result<Estimate, Error> {
    let e = estimate(params, profile);
    let lim = limit();
    let hours = e.seconds / 3600.0;
    if e.seconds > lim {
        return Err(InputError::new(format!(
            "run '{}' is estimated at {hours:.1} h ({:.3e} cells × {:.3e} steps); the limit is {:.1} h: use a coarser grid step or a shorter profile, or give --force to run it anyway",
            profile.label,
            e.cells,
            e.steps,
            lim / 3600.0
        ))
        .in_file("<command line>")
        .field("--force")
        .into());
    }
    if lim.is_finite() && e.seconds > WARN_ABOVE_S {
        eprintln!(
            "note: run '{}' is estimated at {:.0} min ({:.3e} cells × {:.3e} steps); Ctrl-C stops it",
            profile.label,
            e.seconds / 60.0,
            e.cells,
            e.steps
        );
    }
    Ok(e)
}
