//! Phantom TOML files (`profiles/phantoms/*.toml`): raw serde structs that mirror the file
//! (`deny_unknown_fields`, so a typo is an error naming the field), then validation into
//! [`PhantomParams`] in SI units with defaults filled. The format is documented in
//! `profiles/phantoms/README.md`.

use super::elasticity;
use super::grid::{Face, Shape};
use super::params::{BubblePlacement, GasProperties, Numerics, PhantomParams};
use super::surface;
use crate::error::{line_of_field, line_of_key, num, toml_error_with_path, InputError};
use crate::gas::Gas;
use crate::profile::MAX_DURATION_S;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPhantom {
    name: Option<String>,
    description: Option<String>,
    geometry: RawGeometry,
    #[serde(default)]
    material: RawMaterial,
    gases: BTreeMap<String, RawGas>,
    #[serde(default)]
    nuclei: RawNuclei,
    #[serde(default)]
    bubbles: Vec<RawBubble>,
    population: Option<RawPopulation>,
    #[serde(default)]
    perfusion: RawPerfusion,
    /// `[nucleation]`: `model` (registry name) and that model's parameters, validated by the
    /// model's own raw struct (`deny_unknown_fields`, [`super::nucleation`]).
    nucleation: Option<toml::Table>,
    #[serde(default)]
    numerics: RawNumerics,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPerfusion {
    rate_per_s: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGeometry {
    shape: String,
    /// Three numbers; read as a list so that a fourth is refused, not ignored.
    size_m: Option<Vec<f64>>,
    diameter_m: Option<f64>,
    depth_m: Option<f64>,
    grid_step_m: f64,
    open_faces: Option<Vec<String>>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawMaterial {
    temperature_k: Option<f64>,
    surface_tension: Option<f64>,
    bubble_fixed_gases_pa: Option<f64>,
    elasticity: Option<toml::Table>,
    surface: Option<toml::Table>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGas {
    diffusivity: f64,
    ostwald: f64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawNuclei {
    min_radius_m: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBubble {
    /// Three numbers; read as a list so that a fourth is refused, not ignored.
    position_m: Vec<f64>,
    initial_radius_m: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawPopulation {
    count: usize,
    initial_radius_m: f64,
    min_spacing_m: Option<f64>,
    margin_m: Option<f64>,
    seed: u64,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawNumerics {
    max_step_s: Option<f64>,
    max_pressure_change: Option<f64>,
    max_step_growth: Option<f64>,
    max_content_change: Option<f64>,
    bubble_tolerance: Option<f64>,
    explicit_tolerance_factor: Option<f64>,
    field_tolerance: Option<f64>,
    loading_tolerance: Option<f64>,
    extrapolate_holds: Option<bool>,
    hold_tolerance_factor: Option<f64>,
    kernel_min_cells: Option<f64>,
    coupling_gap_cells: Option<f64>,
    record_interval_s: Option<f64>,
    record_gel: Option<bool>,
    displace_gel: Option<bool>,
    displace_min_cells: Option<f64>,
    displace_step_cells: Option<f64>,
    displace_reach: Option<f64>,
}

/// Smallest initial bubble radius accepted, m (0.1 µm: the Laplace pressure 2γ/R is then
/// already 14 bar at γ = 0.07 N/m).
pub const MIN_BUBBLE_RADIUS_M: f64 = 1e-7;
/// Most bubbles a phantom may hold.
pub const MAX_BUBBLES: usize = 10_000;

/// Accepted ranges of the numeric parameters of elasticity and surface laws (key, lo, hi, unit).
const LAW_RANGES: &[(&str, f64, f64, &str)] = &[
    ("shear_modulus", 0.0, 1e7, "Pa"),
    ("bulk_modulus", 1e3, 1e12, "Pa"),
    ("bulk_modulus_per_volume", 0.0, 1e22, "Pa/m³"),
    ("fold", 1e-3, 1e6, ""),
    ("reference_radius_m", MIN_BUBBLE_RADIUS_M, 1e-2, "m"),
    ("exponent", -10.0, 10.0, ""),
    ("layer_thickness_m", 1e-8, 1e-2, "m"),
];

/// Check the numbers of an elasticity or surface-law table (and of a `sum`'s `terms`) against
/// [`LAW_RANGES`]; the error names the full key.
fn check_law_ranges(t: &toml::Table, prefix: &str) -> Result<(), (String, String)> {
    for (k, v) in t {
        let key = format!("{prefix}.{k}");
        if let Some(terms) = v.as_array() {
            for (i, term) in terms.iter().enumerate() {
                if let Some(tt) = term.as_table() {
                    check_law_ranges(tt, &format!("{key}[{i}]"))?;
                }
            }
            continue;
        }
        let Some(&(_, lo, hi, unit)) = LAW_RANGES.iter().find(|(n, ..)| *n == k.as_str()) else {
            continue;
        };
        let x = v.as_float().or_else(|| v.as_integer().map(|i| i as f64));
        match x {
            Some(x) if x.is_finite() && x >= lo && x <= hi => {}
            Some(x) => return Err((key, crate::error::outside_range(x, lo, hi, unit))),
            None => return Err((key, format!("must be a number (got {v})"))),
        }
    }
    Ok(())
}

/// Refuse a phantom without bubbles (`bubbles` field) and without a nucleation model that can
/// make some: the commands report bubble radii, volumes and areas, and a bare gel has none.
/// The error names the line of `[population] count = 0`, else the file's last line (where
/// `[[bubbles]]` would go), read again from `source`.
pub fn require_bubbles(params: &PhantomParams, source: &Path) -> Result<(), InputError> {
    let (none, field) = match &params.bubbles {
        BubblePlacement::Explicit(list) => (list.is_empty(), "bubbles"),
        BubblePlacement::Random { count, .. } => (*count == 0, "population.count"),
    };
    if none && params.nucleation.name() == "fixed" {
        let e = InputError::new(
            "the phantom has no bubbles; add [[bubbles]] tables, a [population] with count ≥ 1, or a [nucleation] model other than \"fixed\"",
        )
        .in_file(source)
        .field(field);
        return Err(match std::fs::read_to_string(source) {
            Ok(text) if field == "bubbles" => e.at_line(crate::error::last_line(&text)),
            Ok(text) => crate::error::ensure_line(e, &text),
            Err(_) => e,
        });
    }
    Ok(())
}

/// A loaded phantom: the parameters and the description from the file.
#[derive(Debug, Clone)]
pub struct LoadedPhantom {
    /// The validated parameters.
    pub params: PhantomParams,
    /// The file's description (may be empty).
    pub description: String,
}

/// `e`, an error in a phantom's field found after the file was read (against a profile, say),
/// placed in the phantom file `path`: the file, and the line of the field when the file reads.
pub fn in_phantom_file(e: InputError, path: &Path) -> InputError {
    let e = e.in_file(path);
    match std::fs::read_to_string(path) {
        Ok(text) => crate::error::ensure_line(e, &text),
        Err(_) => e,
    }
}

/// Read and validate a phantom TOML file.
pub fn load_phantom(path: &Path) -> Result<LoadedPhantom, InputError> {
    let text = crate::error::read_text(path, "the phantom file")?;
    parse_phantom(&text, path)
}

/// Parse and validate phantom TOML text (`path` is used in messages).
pub fn parse_phantom(text: &str, path: &Path) -> Result<LoadedPhantom, InputError> {
    parse_phantom_unlined(text, path).map_err(|e| crate::error::ensure_line(e, text))
}

fn parse_phantom_unlined(text: &str, path: &Path) -> Result<LoadedPhantom, InputError> {
    let raw: RawPhantom = toml::from_str(text).map_err(|e| toml_error_with_path(path, text, &e))?;
    let err = |key: &str, msg: String| {
        let leaf = key.rsplit('.').next().unwrap_or(key);
        let mut e = InputError::new(msg).in_file(path).field(key);
        // the key's own line or its table's ([material.elasticity], [[bubbles]], [population]),
        // else a key of that name (`terms[1].shear_modulus`, which no table header spells)
        if let Some(l) = line_of_field(text, key, 0).or_else(|| line_of_key(text, leaf)) {
            e = e.at_line(l);
        }
        e
    };
    // an error about bubble i: the line of its field in the i-th [[bubbles]] table, else of
    // that table
    let at = |i: usize, e: InputError| {
        let own = e.field.as_deref().and_then(|f| line_of_field(text, f, i));
        match own.or_else(|| line_of_field(text, "bubbles", i)) {
            Some(l) => e.at_line(l),
            None => e,
        }
    };
    let positive = |key: &str, v: f64| -> Result<f64, InputError> {
        if v > 0.0 && v.is_finite() {
            Ok(v)
        } else {
            Err(err(
                key,
                format!("must be a positive number (got {})", num(v)),
            ))
        }
    };
    // a finite number in [lo, hi] (the physical ranges of `profiles/phantoms/README.md`)
    let in_range = |key: &str, v: f64, lo: f64, hi: f64, unit: &str| -> Result<f64, InputError> {
        if v.is_finite() && v >= lo && v <= hi {
            Ok(v)
        } else {
            Err(err(key, crate::error::outside_range(v, lo, hi, unit)))
        }
    };
    let g = &raw.geometry;
    let h = positive("geometry.grid_step_m", g.grid_step_m)?;
    in_range("geometry.grid_step_m", h, 1e-7, 1.0, "m")?;
    let shape = match g.shape.as_str() {
        "box" => {
            let s = g.size_m.as_deref().ok_or_else(|| {
                err(
                    "geometry.size_m",
                    "a box needs size_m = [x, y, z] in metres".into(),
                )
            })?;
            let s: [f64; 3] = s.try_into().map_err(|_| {
                err(
                    "geometry.size_m",
                    format!("expected 3 numbers [x, y, z] in metres, found {}", s.len()),
                )
            })?;
            for v in s {
                positive("geometry.size_m", v)?;
                in_range("geometry.size_m", v, 1e-6, 10.0, "m")?;
            }
            if g.diameter_m.is_some() || g.depth_m.is_some() {
                return Err(err(
                    "geometry.diameter_m",
                    "a box takes size_m, not diameter_m/depth_m".into(),
                ));
            }
            Shape::Box { size: s }
        }
        "cylinder" => {
            let d = g
                .diameter_m
                .ok_or_else(|| err("geometry.diameter_m", "a cylinder needs diameter_m".into()))?;
            let z = g
                .depth_m
                .ok_or_else(|| err("geometry.depth_m", "a cylinder needs depth_m".into()))?;
            if g.size_m.is_some() {
                return Err(err(
                    "geometry.size_m",
                    "a cylinder takes diameter_m and depth_m, not size_m".into(),
                ));
            }
            Shape::Cylinder {
                diameter: in_range(
                    "geometry.diameter_m",
                    positive("geometry.diameter_m", d)?,
                    1e-6,
                    10.0,
                    "m",
                )?,
                depth: in_range(
                    "geometry.depth_m",
                    positive("geometry.depth_m", z)?,
                    1e-6,
                    10.0,
                    "m",
                )?,
            }
        }
        other => {
            return Err(err(
                "geometry.shape",
                format!("unknown shape '{other}'; use \"box\" or \"cylinder\""),
            ))
        }
    };
    let open_faces = match &g.open_faces {
        None => shape
            .faces()
            .iter()
            .copied()
            .filter(|f| *f != Face::Bottom)
            .collect(),
        Some(list) => {
            let mut out = Vec::new();
            for name in list {
                let f = shape
                    .faces()
                    .iter()
                    .copied()
                    .find(|f| f.name() == name)
                    .ok_or_else(|| {
                        err(
                            "geometry.open_faces",
                            format!(
                                "unknown face '{name}' for a {}; faces are {}",
                                g.shape,
                                shape
                                    .faces()
                                    .iter()
                                    .map(|f| f.name())
                                    .collect::<Vec<_>>()
                                    .join(", ")
                            ),
                        )
                    })?;
                if out.contains(&f) {
                    return Err(err(
                        "geometry.open_faces",
                        format!("face '{name}' is listed twice; list each open face once"),
                    ));
                }
                out.push(f);
            }
            out
        }
    };
    let m = &raw.material;
    let temperature = positive(
        "material.temperature_k",
        m.temperature_k.unwrap_or(crate::units::BODY_TEMPERATURE_K),
    )?;
    in_range("material.temperature_k", temperature, 250.0, 400.0, "K")?;
    let surface_tension = m.surface_tension.unwrap_or(0.07);
    if !(surface_tension >= 0.0) {
        return Err(err(
            "material.surface_tension",
            format!("must be ≥ 0 N/m (got {})", num(surface_tension)),
        ));
    }
    in_range("material.surface_tension", surface_tension, 0.0, 1.0, "N/m")?;
    let bubble_fixed_gases = m.bubble_fixed_gases_pa.unwrap_or(0.0);
    if !(bubble_fixed_gases >= 0.0 && bubble_fixed_gases.is_finite()) {
        return Err(err(
            "material.bubble_fixed_gases_pa",
            format!(
                "must be a finite pressure ≥ 0 Pa (got {})",
                num(bubble_fixed_gases)
            ),
        ));
    }
    in_range(
        "material.bubble_fixed_gases_pa",
        bubble_fixed_gases,
        0.0,
        1e5,
        "Pa",
    )?;
    let perfusion_rate = raw.perfusion.rate_per_s.unwrap_or(0.0);
    if !(perfusion_rate >= 0.0 && perfusion_rate.is_finite()) {
        return Err(err(
            "perfusion.rate_per_s",
            format!(
                "must be a finite rate ≥ 0 per second (got {})",
                num(perfusion_rate)
            ),
        ));
    }
    in_range("perfusion.rate_per_s", perfusion_rate, 0.0, 10.0, "1/s")?;
    for (table, key) in [
        (&m.elasticity, "material.elasticity"),
        (&m.surface, "material.surface"),
    ] {
        if let Some(t) = table {
            check_law_ranges(t, key).map_err(|(k, msg)| err(&k, msg))?;
        }
    }
    let law_of = |t: &Option<toml::Table>, default: &str| -> (String, toml::Table) {
        let mut t = t.clone().unwrap_or_default();
        let name = t
            .remove("law")
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_else(|| default.into());
        (name, t)
    };
    let (el_name, el_params) = law_of(&m.elasticity, "none");
    // a builder's "key: message" names the key under its table
    let keyed = |table: &str, msg: String| match crate::error::split_keyed(&msg) {
        Some((k, rest)) => err(&format!("{table}.{k}"), rest.to_string()),
        None => err(table, msg),
    };
    let elasticity = elasticity::build(&el_name, toml::Value::Table(el_params))
        .map_err(|e| keyed("material.elasticity", e))?;
    let (sf_name, mut sf_params) = law_of(&m.surface, "equal");
    let layer = match sf_params.remove("layer_thickness_m") {
        Some(v) => {
            let x = v
                .as_float()
                .or(v.as_integer().map(|i| i as f64))
                .unwrap_or(f64::NAN);
            positive("material.surface.layer_thickness_m", x)?
        }
        None => super::params::DEFAULT_SURFACE_LAYER,
    };
    let surface = surface::build(&sf_name, toml::Value::Table(sf_params))
        .map_err(|e| keyed("material.surface", e))?;
    let mut gases = Vec::new();
    for (name, gp) in &raw.gases {
        let gas = Gas::parse(name).ok_or_else(|| {
            err(
                &format!("gases.{name}"),
                format!("unknown gas '{name}'; use n2, o2 or he"),
            )
        })?;
        let (dkey, lkey) = (
            format!("gases.{name}.diffusivity"),
            format!("gases.{name}.ostwald"),
        );
        gases.push(GasProperties {
            gas,
            diffusivity: in_range(&dkey, positive(&dkey, gp.diffusivity)?, 1e-14, 1e-6, "m²/s")?,
            ostwald: in_range(&lkey, positive(&lkey, gp.ostwald)?, 1e-6, 100.0, "")?,
        });
    }
    let (nu_name, nu_params) = {
        let mut t = raw.nucleation.clone().unwrap_or_default();
        let name = match t.remove("model") {
            None => "fixed".to_string(),
            Some(toml::Value::String(s)) => s,
            Some(v) => {
                return Err(err(
                    "nucleation.model",
                    format!("must be a model name in quotes (got {v})"),
                ))
            }
        };
        (name, t)
    };
    let nucleation =
        super::nucleation::build(&nu_name, nu_params).map_err(|e| err(&e.field, e.message))?;
    let min_radius = match raw.nuclei.min_radius_m {
        Some(r) if r >= 0.0 => in_range("nuclei.min_radius_m", r, 0.0, 1e-2, "m")?,
        Some(r) => {
            return Err(err(
                "nuclei.min_radius_m",
                format!("must be ≥ 0 m (got {})", num(r)),
            ))
        }
        // activated micronuclei (µm) must exchange gas to grow: no impermeable skin by default
        None if nucleation.name() != "fixed" => 0.0,
        None => h,
    };
    let bubbles = match (&raw.population, raw.bubbles.is_empty()) {
        (Some(_), false) => {
            return Err(err(
                "population",
                "give either [[bubbles]] or [population], not both".into(),
            ));
        }
        (Some(p), true) => {
            let r0 = positive("population.initial_radius_m", p.initial_radius_m)?;
            in_range(
                "population.initial_radius_m",
                r0,
                MIN_BUBBLE_RADIUS_M,
                1e-2,
                "m",
            )?;
            if p.count > MAX_BUBBLES {
                return Err(err(
                    "population.count",
                    format!("{} bubbles is too many (limit {MAX_BUBBLES})", p.count),
                ));
            }
            for (key, v) in [
                ("population.min_spacing_m", p.min_spacing_m),
                ("population.margin_m", p.margin_m),
            ] {
                if let Some(v) = v {
                    in_range(key, v, 0.0, 10.0, "m")?;
                }
            }
            // centres closer than two radii would place overlapping bubbles at t = 0
            if let Some(s) = p.min_spacing_m.filter(|&s| s <= 2.0 * r0) {
                return Err(err(
                    "population.min_spacing_m",
                    format!(
                        "{} m lets bubbles of R0 = {} m overlap at t = 0; give more than 2·R0 = {} m (default 4·R0)",
                        num(s),
                        num(r0),
                        num(2.0 * r0)
                    ),
                ));
            }
            BubblePlacement::Random {
                count: p.count,
                initial_radius: r0,
                min_spacing: p.min_spacing_m.unwrap_or(4.0 * r0),
                margin: p.margin_m.unwrap_or(2.0 * r0),
                seed: p.seed,
            }
        }
        (None, _) => {
            let mut list = Vec::new();
            if raw.bubbles.len() > MAX_BUBBLES {
                return Err(err(
                    "bubbles",
                    format!(
                        "{} bubbles is too many (limit {MAX_BUBBLES})",
                        raw.bubbles.len()
                    ),
                ));
            }
            for (i, b) in raw.bubbles.iter().enumerate() {
                let Ok(position) = <[f64; 3]>::try_from(b.position_m.as_slice()) else {
                    return Err(at(
                        i,
                        err(
                            "bubbles.position_m",
                            format!(
                                "bubble {i}: expected 3 numbers [x, y, z] in metres, found {}",
                                b.position_m.len()
                            ),
                        ),
                    ));
                };
                if let Some(v) = position.iter().find(|v| !v.is_finite()) {
                    return Err(at(
                        i,
                        err(
                            "bubbles.position_m",
                            format!("bubble {i}: position {v} m is not a finite number"),
                        ),
                    ));
                }
                let r0 = positive("bubbles.initial_radius_m", b.initial_radius_m)
                    .and_then(|r0| {
                        in_range(
                            "bubbles.initial_radius_m",
                            r0,
                            MIN_BUBBLE_RADIUS_M,
                            1e-2,
                            "m",
                        )
                    })
                    .map_err(|e| at(i, e))?;
                list.push((position, r0));
            }
            // bubbles that touch or overlap at t = 0 would count the shared volume twice and
            // coalesce on the first step (the simulation merges bubbles at a distance ≤ R1 + R2)
            for j in 0..list.len() {
                for i in 0..j {
                    let ((p, ri), (q, rj)) = (list[i], list[j]);
                    let d = (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt();
                    if d <= ri + rj {
                        let line = |k: usize| {
                            line_of_field(text, "bubbles", k)
                                .map_or(String::new(), |l| format!(" (line {l})"))
                        };
                        return Err(at(
                            j,
                            err(
                                "bubbles",
                                format!(
                                    "bubble {j}{} overlaps bubble {i}{} at t = 0: their centres are {} m apart, not more than the sum of their radii {} m; move one or make them smaller",
                                    line(j),
                                    line(i),
                                    num(d),
                                    num(ri + rj)
                                ),
                            ),
                        ));
                    }
                }
            }
            BubblePlacement::Explicit(list)
        }
    };
    let d = Numerics::default();
    let n = &raw.numerics;
    // an error tolerance: the default when not given, infinite (off), or positive up to 1
    let tolerance = |key: &str, given: Option<f64>, default: f64, unit: &str| match given {
        None => Ok(default),
        Some(x) if x == f64::INFINITY => Ok(x),
        Some(x) => in_range(key, positive(key, x)?, 1e-9, 1.0, unit),
    };
    let numerics = Numerics {
        max_step: in_range(
            "numerics.max_step_s",
            positive("numerics.max_step_s", n.max_step_s.unwrap_or(d.max_step))?,
            1e-6,
            86400.0,
            "s",
        )?,
        max_pressure_change: positive(
            "numerics.max_pressure_change",
            n.max_pressure_change.unwrap_or(d.max_pressure_change),
        )?,
        max_step_growth: in_range(
            "numerics.max_step_growth",
            positive(
                "numerics.max_step_growth",
                n.max_step_growth.unwrap_or(d.max_step_growth),
            )?,
            1.01,
            10.0,
            "(factor per step)",
        )?,
        max_content_change: positive(
            "numerics.max_content_change",
            n.max_content_change.unwrap_or(d.max_content_change),
        )?,
        bubble_tolerance: in_range(
            "numerics.bubble_tolerance",
            positive(
                "numerics.bubble_tolerance",
                n.bubble_tolerance.unwrap_or(d.bubble_tolerance),
            )?,
            1e-6,
            1.0,
            "(relative change)",
        )?,
        explicit_tolerance_factor: in_range(
            "numerics.explicit_tolerance_factor",
            positive(
                "numerics.explicit_tolerance_factor",
                n.explicit_tolerance_factor
                    .unwrap_or(d.explicit_tolerance_factor),
            )?,
            1.0,
            10.0,
            "(multiple of bubble_tolerance)",
        )?,
        field_tolerance: tolerance(
            "numerics.field_tolerance",
            n.field_tolerance,
            d.field_tolerance,
            "(fraction of the ambient pressure)",
        )?,
        loading_tolerance: tolerance(
            "numerics.loading_tolerance",
            n.loading_tolerance,
            d.loading_tolerance,
            "(fraction of the gel's content of a pure gas at the ambient pressure)",
        )?,
        kernel_min_cells: in_range(
            "numerics.kernel_min_cells",
            positive(
                "numerics.kernel_min_cells",
                n.kernel_min_cells.unwrap_or(d.kernel_min_cells),
            )?,
            1e-3,
            100.0,
            "cells",
        )?,
        coupling_gap_cells: in_range(
            "numerics.coupling_gap_cells",
            positive(
                "numerics.coupling_gap_cells",
                n.coupling_gap_cells.unwrap_or(d.coupling_gap_cells),
            )?,
            1e-3,
            100.0,
            "cells",
        )?,
        implicit_cost_ratio: d.implicit_cost_ratio,
        record_gel: n.record_gel.unwrap_or(d.record_gel),
        extrapolate_holds: n.extrapolate_holds.unwrap_or(d.extrapolate_holds),
        hold_tolerance_factor: in_range(
            "numerics.hold_tolerance_factor",
            positive(
                "numerics.hold_tolerance_factor",
                n.hold_tolerance_factor.unwrap_or(d.hold_tolerance_factor),
            )?,
            1.0,
            100.0,
            "(multiple of loading_tolerance)",
        )?,
        displace_gel: n.displace_gel.unwrap_or(d.displace_gel),
        displace_min_cells: in_range(
            "numerics.displace_min_cells",
            positive(
                "numerics.displace_min_cells",
                n.displace_min_cells.unwrap_or(d.displace_min_cells),
            )?,
            0.5,
            1000.0,
            "cells",
        )?,
        displace_step_cells: in_range(
            "numerics.displace_step_cells",
            positive(
                "numerics.displace_step_cells",
                n.displace_step_cells.unwrap_or(d.displace_step_cells),
            )?,
            1e-3,
            10.0,
            "cells",
        )?,
        displace_reach: in_range(
            "numerics.displace_reach",
            positive(
                "numerics.displace_reach",
                n.displace_reach.unwrap_or(d.displace_reach),
            )?,
            1.0,
            100.0,
            "bubble radii",
        )?,
        record_interval: match n.record_interval_s {
            // 0 (every step) or a positive interval long enough to move the clock: a tiny one
            // (1e-308 s) would never advance the next-frame time
            Some(v) if v == 0.0 || (v.is_finite() && (1e-6..=MAX_DURATION_S).contains(&v)) => v,
            Some(v) => {
                return Err(err(
                    "numerics.record_interval_s",
                    format!(
                        "must be 0 (every step) or between 1e-6 s and {MAX_DURATION_S} s (got {})",
                        num(v)
                    ),
                ))
            }
            None => d.record_interval,
        },
    };
    for (key, v) in [
        ("numerics.max_pressure_change", numerics.max_pressure_change),
        ("numerics.max_content_change", numerics.max_content_change),
    ] {
        if v > 0.5 {
            return Err(err(
                key,
                format!("{} per step is unstable for the explicit bubble coupling; use at most 0.1 (default {})", num(v), if key.ends_with("pressure_change") { d.max_pressure_change } else { d.max_content_change }),
            ));
        }
    }
    let name = raw.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "phantom".into())
    });
    let params = PhantomParams {
        name,
        shape,
        grid_step: h,
        open_faces,
        temperature,
        surface_tension,
        elasticity: Arc::from(elasticity),
        surface: Arc::from(surface),
        surface_layer_thickness: layer,
        gases,
        min_radius,
        bubbles,
        nucleation: Arc::from(nucleation),
        perfusion_rate,
        bubble_fixed_gases,
        numerics,
    };
    // geometry checks that need the grid (bubbles inside, cell count) happen here so that the
    // error points at the file
    let grid = super::grid::Grid::new(params.shape, params.grid_step, &params.open_faces)
        .map_err(|e| err("geometry.grid_step_m", e))?;
    // each placed bubble at the line of its own position
    if let BubblePlacement::Explicit(list) = &params.bubbles {
        for (i, &(p, r0)) in list.iter().enumerate() {
            if let Some(why) = super::sim::bubble_outside(&grid, p, r0) {
                return Err(at(
                    i,
                    err("bubbles.position_m", format!("bubble {i} {why}")),
                ));
            }
        }
    }
    super::sim::place_bubbles(&params, &grid).map_err(|e| match e {
        crate::error::Error::Input(ie) => {
            let key = if raw.population.is_some() {
                "population"
            } else {
                "bubbles"
            };
            err(key, ie.message)
        }
        other => err("bubbles", other.to_string()),
    })?;
    // draw the nuclei once here too, so that a population that cannot be placed (or is too
    // large), or skins no stronger than the surface tension, are an error pointing at the file
    params
        .nucleation
        .nuclei(&grid)
        .map_err(|e| err(&e.field, e.message))?;
    super::nucleation::skin_factors(surface_tension, params.nucleation.skin_compression())
        .map_err(|e| err(&e.field, e.message))?;
    Ok(LoadedPhantom {
        params,
        description: raw.description.unwrap_or_default(),
    })
}
