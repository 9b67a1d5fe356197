//! Linking a dive to the phantom ([`dive_history`], [`breathed_gas_params`]): the ambient
//! pressure of the schedule acts on the gel; the breathed-gas convention of the criteria
//! file's `[protocol]` ([`Protocol`]) holds on both sides of every bubble's interface — the open
//! faces are in equilibrium with the inspired inert-gas partial pressures,
//! fraction × (ambient − P_H2O), and every bubble holds the gases that are not simulated at
//! fixed partial pressures, P_H2O + P_CO2 + P_vO2 (6.27 + 5.3 + 5.3 kPa by default; the same
//! P_H2O on both sides, whatever water vapour the schedule's planner used); O2 is left out of
//! the gel unless the protocol sets `oxygen_at_faces`. The phantom starts saturated with surface
//! air under the same convention, f_g,air·(P_surf − P_H2O) with no He, whatever the first leg
//! breathes (a diver's tissues before the dive, where ZH-L16 and VPM-B start theirs;
//! [`crate::profile::Saturation`]); the schedule is followed by
//! `protocol.observe_after_surfacing_min` at the surface on air. A repetitive dive
//! (`repeat_after_min`) appends a surface interval on air and the same schedule again, so the
//! gel and the bubbles carry over.

use crate::algorithm::Schedule;
use crate::error::{Error, InputError};
use crate::gas::GasMix;
use crate::phantom::config::parse_phantom;
use crate::phantom::elasticity::{law_names, AllLawParams, ElasticityLaw};
use crate::phantom::params::PhantomParams;
use crate::profile::PressureHistory;
use crate::risk::Protocol;
use std::path::Path;
use std::sync::Arc;

/// The built-in phantom (`profiles/phantoms/hydrogel-dive.toml`), used when none is given.
pub const HYDROGEL_PHANTOM: &str = include_str!("../../profiles/phantoms/hydrogel-dive.toml");
/// Where [`HYDROGEL_PHANTOM`] comes from.
pub const HYDROGEL_PHANTOM_PATH: &str = "profiles/phantoms/hydrogel-dive.toml";

/// Default M = K/V_aff of the Bulk-Modulus law when the phantom does not give one, Pa/m³
/// (5e-2 Pa/µm³, the paper's Fig. 2a).
pub const DEFAULT_BULK_MODULUS_PER_VOLUME: f64 = 5e16;
/// Default bulk modulus K of the Reference-Configuration law, Pa (2.2 GPa, the paper's Fig. 2a).
pub const DEFAULT_BULK_MODULUS: f64 = 2.2e9;
/// Default shear modulus μ when the phantom's own law has none, Pa (40 Pa, the hydrogel of
/// the paper's Figs. 4–5).
pub const DEFAULT_SHEAR_MODULUS: f64 = 40.0;

/// A phantom ready for evaluation: parameters, where they came from, and the parameters
/// from which the other elasticity laws are built.
#[derive(Debug, Clone)]
pub struct PhantomSpec {
    /// Validated parameters (the phantom's own elasticity law).
    pub params: PhantomParams,
    /// The file's description.
    pub description: String,
    /// The file it came from (or `built-in hydrogel`).
    pub source: String,
    /// μ from the phantom's `[material.elasticity]` (else 40 Pa), M and K from it if given
    /// (else 5e-2 Pa/µm³ and 2.2 GPa, the paper's Fig. 2a).
    pub laws: AllLawParams,
}

impl PhantomSpec {
    /// Parse phantom TOML text; `grid_step_m` overrides the grid step (the nuclei radii, R_min
    /// and the surface-layer thickness keep the file's values).
    pub fn from_text(
        text: &str,
        path: &Path,
        source: &str,
        grid_step_m: Option<f64>,
    ) -> Result<PhantomSpec, InputError> {
        let loaded = parse_phantom(text, path)?;
        let mut params = loaded.params;
        if let Some(h) = grid_step_m {
            if !(h.is_finite() && h > 0.0) {
                return Err(
                    InputError::new(format!("grid step must be positive m (got {h})"))
                        .in_file("<command line>")
                        .field("--grid-step"),
                );
            }
            params.grid_step = h;
            // the new grid must be buildable (cell count) and hold the bubbles
            let cl = |m: String| {
                InputError::new(m)
                    .in_file("<command line>")
                    .field("--grid-step")
            };
            let grid =
                crate::phantom::grid::Grid::new(params.shape, h, &params.open_faces).map_err(cl)?;
            crate::phantom::sim::place_bubbles(&params, &grid).map_err(|e| cl(e.to_string()))?;
        }
        crate::phantom::config::require_bubbles(&params, path)?;
        let table: toml::Table = toml::from_str(text).unwrap_or_default();
        let el = table
            .get("material")
            .and_then(|m| m.get("elasticity"))
            .and_then(|e| e.as_table());
        let num = |k: &str| {
            el.and_then(|e| e.get(k))
                .and_then(|v| v.as_float().or_else(|| v.as_integer().map(|i| i as f64)))
        };
        let laws = AllLawParams {
            shear_modulus: num("shear_modulus").unwrap_or(DEFAULT_SHEAR_MODULUS),
            bulk_modulus_per_volume: num("bulk_modulus_per_volume")
                .unwrap_or(DEFAULT_BULK_MODULUS_PER_VOLUME),
            bulk_modulus: num("bulk_modulus").unwrap_or(DEFAULT_BULK_MODULUS),
        };
        Ok(PhantomSpec {
            params,
            description: loaded.description,
            source: source.to_string(),
            laws,
        })
    }

    /// Read a phantom file, or the built-in hydrogel when `path` is `None`.
    pub fn load(path: Option<&Path>, grid_step_m: Option<f64>) -> Result<PhantomSpec, InputError> {
        match path {
            Some(p) => {
                let text = crate::error::read_text(p, "the phantom file")?;
                PhantomSpec::from_text(&text, p, &p.display().to_string(), grid_step_m)
            }
            None => PhantomSpec::from_text(
                HYDROGEL_PHANTOM,
                Path::new(HYDROGEL_PHANTOM_PATH),
                "built-in hydrogel-dive (profiles/phantoms/hydrogel-dive.toml)",
                grid_step_m,
            ),
        }
    }

    /// The phantom's own law name.
    pub fn own_law(&self) -> &'static str {
        self.params.elasticity.name()
    }

    /// The parameters with law `name`: the phantom's own law object for its own name, else
    /// built from [`PhantomSpec::laws`].
    pub fn with_law(&self, name: &str) -> Result<PhantomParams, Error> {
        let mut p = self.params.clone();
        if name != self.own_law() {
            let law: Box<dyn ElasticityLaw> = self.laws.build(name).map_err(Error::Solver)?;
            p.elasticity = Arc::from(law);
        }
        Ok(p)
    }

    /// Resolve `--elasticity` values: empty → the phantom's own law; `all` → every law;
    /// otherwise names (comma-separated allowed), each registered.
    pub fn resolve_laws(&self, requested: &[String]) -> Result<Vec<&'static str>, InputError> {
        let names = law_names();
        let mut out: Vec<&'static str> = Vec::new();
        for r in requested.iter().flat_map(|s| s.split(',')) {
            let r = r.trim();
            if r.eq_ignore_ascii_case("all") {
                // the phantom's own law first: it is the primary law of the report's plots
                let own = self.own_law();
                if !out.contains(&own) {
                    out.push(own);
                }
                for n in &names {
                    if !out.contains(n) {
                        out.push(n);
                    }
                }
                continue;
            }
            let n = names
                .iter()
                .find(|n| n.eq_ignore_ascii_case(r))
                .ok_or_else(|| {
                    InputError::new(format!(
                        "unknown elasticity law '{r}'; use all or one of {}",
                        names.join(", ")
                    ))
                    .in_file("<command line>")
                    .field("--elasticity")
                })?;
            if !out.contains(n) {
                out.push(n);
            }
        }
        if out.is_empty() {
            out.push(self.own_law());
        }
        Ok(out)
    }
}

/// The pressure history a schedule drives the phantom with (see the module documentation);
/// `repeat_after_min` repeats the dive after that surface interval.
pub fn dive_history(
    schedule: &Schedule,
    protocol: &Protocol,
    repeat_after_min: Option<f64>,
) -> Result<PressureHistory, InputError> {
    let bad = |m: String| InputError::new(m).field("schedule");
    let last = schedule.legs.last().map_or(0.0, |l| l.end_depth_m);
    if last.abs() > 1e-9 {
        return Err(bad(format!(
            "schedule '{}' never surfaces: its last leg ends at {last} m",
            schedule.label
        )));
    }
    let mut dive = schedule.to_pressure_history().map_err(bad)?;
    // the protocol's P_H2O, the one held in the bubbles too ([`breathed_gas_params`])
    dive.vapour_pa = protocol.water_vapour_pa;
    let surface = schedule.surface_pressure_pa;
    let at_surface = |s: f64| {
        PressureHistory::with_gas(
            "surface",
            vec![0.0, s],
            vec![surface, surface],
            GasMix::AIR,
            dive.vapour_pa,
        )
        .map_err(bad)
    };
    let mut h = dive.clone();
    if let Some(si) = repeat_after_min {
        if !(si.is_finite() && si > 0.0 && si * 60.0 <= crate::profile::MAX_DURATION_S) {
            return Err(InputError::new(format!(
                "surface interval must be a positive number of minutes, at most {} (30 days) (got {})",
                crate::profile::MAX_DURATION_S / 60.0,
                crate::error::num(si)
            ))
            .in_file("<command line>")
            .field("--repeat-after"));
        }
        h = h
            .then(&at_surface(si * 60.0)?)
            .and_then(|h| h.then(&dive))
            .map_err(bad)?;
    }
    if protocol.observe_after_surfacing_s > 0.0 {
        h = h
            .then(&at_surface(protocol.observe_after_surfacing_s)?)
            .map_err(bad)?;
    }
    h.inert_only = !protocol.oxygen_at_faces;
    h.label = schedule.label.clone();
    if h.gases().is_empty() {
        return Err(bad(
            "no inert gas (N2 or He) is ever breathed; nothing reaches the phantom".into(),
        ));
    }
    Ok(h)
}

/// The phantom's parameters for a breathed-gas run under `protocol`: every bubble holds the
/// gases that are not simulated at p_fixed = P_H2O + P_CO2 + P_vO2
/// ([`Protocol::bubble_fixed_gases_pa`]), the counterpart of the faces of [`dive_history`].
/// A phantom file that sets its own `material.bubble_fixed_gases_pa` is refused: for a
/// breathed gas the criteria protocol sets it. So is a record interval longer than half the
/// protocol's watch at the surface (the after-surfacing window would hold fewer than two
/// frames).
pub fn breathed_gas_params(
    params: &PhantomParams,
    protocol: &Protocol,
) -> Result<PhantomParams, InputError> {
    if params.bubble_fixed_gases != 0.0 {
        return Err(InputError::new(format!(
            "the phantom sets bubble_fixed_gases_pa = {} Pa; for a breathed gas the criteria file's [protocol] sets the bubble's fixed gases (water_vapour_pa + co2_pa + venous_o2_pa = {} Pa): remove it from the phantom",
            params.bubble_fixed_gases,
            protocol.bubble_fixed_gases_pa()
        ))
        .field("material.bubble_fixed_gases_pa"));
    }
    // the surface phase the protocol watches must hold recorded frames: the criteria with
    // `window = "after-surfacing"` and the report's plots of it look only there, and with
    // fewer than two frames they scored 0 (a silent pass) or the plot failed (exit 3)
    let window = protocol.observe_after_surfacing_s;
    let every = params.numerics.record_interval;
    if window > 0.0 && every > window / 2.0 {
        return Err(InputError::new(format!(
            "the phantom records a frame every {} s, but the criteria protocol watches the surface phase for {} s: fewer than two frames would fall in it; set record_interval_s to at most {} s (default 1 s) or watch longer (observe_after_surfacing_min)",
            crate::error::num(every),
            crate::error::num(window),
            crate::error::num(window / 2.0)
        ))
        .field("numerics.record_interval_s"));
    }
    let mut p = params.clone();
    p.bubble_fixed_gases = protocol.bubble_fixed_gases_pa();
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::algorithm::{Leg, LegKind};
    use crate::gas::Gas;

    fn schedule(vapour: f64) -> Schedule {
        let leg = |kind, a: f64, b: f64, s: f64, gas| Leg {
            kind,
            start_depth_m: a,
            end_depth_m: b,
            duration_s: s,
            gas,
        };
        let tx = GasMix::new(0.18, 0.45).unwrap();
        Schedule {
            label: "t".into(),
            surface_pressure_pa: 101_325.0,
            pa_per_m: 10_000.0,
            water_vapour_pa: vapour,
            legs: vec![
                leg(LegKind::Descent, 0.0, 40.0, 200.0, tx),
                leg(LegKind::Bottom, 40.0, 40.0, 600.0, tx),
                leg(LegKind::Ascent, 40.0, 0.0, 400.0, tx),
            ],
            stops: vec![],
        }
    }

    #[test]
    fn linking_subtracts_vapour_keeps_helium_and_drops_oxygen() {
        let p = Protocol {
            observe_after_surfacing_s: 600.0,
            ..Default::default()
        };
        // the protocol's vapour (6270 Pa) replaces the schedule's own (4930 Pa)
        let h = dive_history(&schedule(4930.0), &p, None).unwrap();
        // at the bottom (t = 500 s): ambient 101325 + 40·10000 = 501325 Pa; He 0.45 and N2 0.37
        // of (501325 − 6270) = 495055 Pa → 222774.75 and 183170.35 Pa; O2 left out.
        assert!((h.ambient(500.0) - 501_325.0).abs() < 1e-6);
        assert!((h.inspired_partial_pressure(Gas::He, 500.0) - 222_774.75).abs() < 1e-6);
        assert!((h.inspired_partial_pressure(Gas::N2, 500.0) - 183_170.35).abs() < 1e-6);
        assert_eq!(h.inspired_partial_pressure(Gas::O2, 500.0), 0.0);
        assert_eq!(h.gases(), vec![Gas::N2, Gas::He]);
        // observation at the surface on air: N2 0.79·(101325 − 6270) = 75093.45 Pa
        assert!((h.duration_s() - 1800.0).abs() < 1e-9);
        assert!((h.inspired_partial_pressure(Gas::N2, 1700.0) - 75_093.45).abs() < 1e-6);
        // the protocol's vapour replaces the schedule's; O2 kept when asked
        let p2 = Protocol {
            water_vapour_pa: 0.0,
            oxygen_at_faces: true,
            ..p
        };
        let h2 = dive_history(&schedule(6270.0), &p2, Some(30.0)).unwrap();
        assert!((h2.inspired_partial_pressure(Gas::O2, 500.0) - 0.18 * 501_325.0).abs() < 1e-6);
        // repetitive: dive (1200 s) + 30 min + dive + 10 min
        assert!((h2.duration_s() - (1200.0 + 1800.0 + 1200.0 + 600.0)).abs() < 1e-9);
        assert!((h2.ambient(1200.0 + 1800.0 + 500.0) - 501_325.0).abs() < 1e-6);
    }
}
