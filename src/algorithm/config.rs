//! Loading `algorithms/*.toml`: raw serde structs mirroring the file (unknown keys are errors),
//! then validated [`Conventions`] and an algorithm built through the registry.
//!
//! ```toml
//! kind = "zhl16"                  # registry key
//! label = "ZH-L16C GF 30/85"      # optional
//! [conventions]
//! preset = "decotengu"            # decotengu | subsurface | baker | dive-deco; fields override
//! pa_per_m = 9985.0
//! [params]                        # parsed by the algorithm's own build()
//! model = "zh-l16c"
//! gf_low = 30
//! gf_high = 85
//! [gases]                         # optional; --deco-gas / --travel-gas replace these lists
//! deco = ["50@21", "100@6"]       # as --deco-gas: MIX@SWITCH_DEPTH_M or MIX (at its MOD)
//! travel = ["21/35@0..60"]        # as --travel-gas: MIX@FROM..TO (m), ranges from the surface
//! ```

use super::conventions::{Conventions, GfLowAnchor, StopRounding};
use super::{registry, DecoAlgorithm};
use crate::error::{line_of_key, toml_error_with_path, InputError};
use serde::Deserialize;
use std::path::Path;

/// The file as written.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawAlgorithmFile {
    kind: String,
    label: Option<String>,
    conventions: Option<RawConventions>,
    params: Option<toml::Value>,
    gases: Option<RawGases>,
}

/// `[gases]` as written: the same strings as `--deco-gas` and `--travel-gas`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawGases {
    #[serde(default)]
    deco: Vec<String>,
    #[serde(default)]
    travel: Vec<String>,
}

/// The gases an algorithm file sets (`[gases]`), validated; used when the command line gives
/// none of that kind.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FileGases {
    /// The algorithm file (named in errors about these gases).
    pub path: std::path::PathBuf,
    /// Deco gases (`gases.deco`).
    pub deco: Vec<super::DecoGas>,
    /// Travel gases (`gases.travel`).
    pub travel: Vec<super::TravelGas>,
    /// Line of `deco =` in the file, if any.
    pub deco_line: Option<usize>,
    /// Line of `travel =` in the file, if any.
    pub travel_line: Option<usize>,
}

/// `[conventions]` as written: a preset and/or any field of [`Conventions`].
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawConventions {
    preset: Option<String>,
    surface_pressure_pa: Option<f64>,
    pa_per_m: Option<f64>,
    water_vapour_pa: Option<f64>,
    descent_rate_m_min: Option<f64>,
    ascent_rate_m_min: Option<f64>,
    stop_spacing_m: Option<f64>,
    last_stop_m: Option<f64>,
    bottom_time_includes_descent: Option<bool>,
    stop_rounding: Option<StopRounding>,
    gf_low_anchor: Option<GfLowAnchor>,
    min_stop_min: Option<f64>,
    surface_tissue_n2_fraction: Option<f64>,
}

/// A loaded algorithm file.
pub struct LoadedAlgorithm {
    /// The registry key.
    pub kind: String,
    /// The label (from the file, or the algorithm's own).
    pub label: String,
    /// The validated conventions.
    pub conventions: Conventions,
    /// The algorithm.
    pub algorithm: Box<dyn DecoAlgorithm>,
    /// Gases set in the file's `[gases]` table (empty lists when it has none).
    pub gases: FileGases,
}

impl std::fmt::Debug for LoadedAlgorithm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LoadedAlgorithm")
            .field("kind", &self.kind)
            .field("label", &self.label)
            .field("conventions", &self.conventions)
            .finish()
    }
}

/// Settings given on the command line (`plan --gf 30/85 --altitude 1500 ...`) that replace
/// the algorithm file's. Every field is optional; `None` keeps the file's value.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Overrides {
    /// Gradient factors (low, high), % (`--gf`, `--gf-low`, `--gf-high`); ZH-L16 only.
    pub gf_low: Option<f64>,
    /// GF-high, %.
    pub gf_high: Option<f64>,
    /// Surface pressure, Pa (`--surface-pressure` in hPa, or from `--altitude`).
    pub surface_pressure_pa: Option<f64>,
    /// Descent rate, m/min (`--descent-rate`).
    pub descent_rate_m_min: Option<f64>,
    /// Ascent rate, m/min (`--ascent-rate`).
    pub ascent_rate_m_min: Option<f64>,
    /// Depth of the last stop, m (`--last-stop`).
    pub last_stop_m: Option<f64>,
}

/// Sea-level pressure of the ICAO Standard Atmosphere (ISO 2533:1975), Pa.
pub const ISA_SEA_LEVEL_PA: f64 = 101_325.0;

/// Surface pressure at a (geometric) altitude in the ICAO Standard Atmosphere troposphere
/// (ISO 2533:1975): the geopotential height H = r0·z/(r0 + z) with r0 = 6 356 766 m, then
/// p = p0·(1 − L·H/T0)^(g·M/(R·L)) with L = 0.0065 K/m, T0 = 288.15 K, g·M/(R·L) = 5.25588.
/// Pa, for z in metres (valid to 11 km).
pub fn isa_pressure_pa(altitude_m: f64) -> f64 {
    const R0: f64 = 6_356_766.0;
    let h = R0 * altitude_m / (R0 + altitude_m);
    ISA_SEA_LEVEL_PA * (1.0 - 0.0065 * h / 288.15).powf(5.255_88)
}

/// Read `--gf 30/85` (GF-low/GF-high, %).
pub fn parse_gf(s: &str) -> Result<(f64, f64), InputError> {
    let bad = || {
        InputError::new(format!(
            "cannot read gradient factors '{s}'; write GF-LOW/GF-HIGH in %, e.g. 30/85"
        ))
        .in_file("<command line>")
        .field("--gf")
    };
    let (l, h) = s.split_once('/').ok_or_else(bad)?;
    let l: f64 = l.trim().parse().map_err(|_| bad())?;
    let h: f64 = h.trim().parse().map_err(|_| bad())?;
    Ok((l, h))
}

impl Overrides {
    /// Whether nothing is overridden.
    pub fn is_empty(&self) -> bool {
        *self == Overrides::default()
    }

    /// Check the values before they reach an algorithm; the error names the option.
    pub fn validate(&self) -> Result<(), InputError> {
        let cmd = |opt: &str, msg: String| {
            Err(InputError::new(msg)
                .in_file("<command line>")
                .field(opt.to_string()))
        };
        for (opt, v) in [("--gf-low", self.gf_low), ("--gf-high", self.gf_high)] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0 && v <= 150.0) {
                    return cmd(
                        opt,
                        format!("gradient factor {v} % is out of range; use 1..100 (at most 150)"),
                    );
                }
            }
        }
        if let (Some(l), Some(h)) = (self.gf_low, self.gf_high) {
            if l > h {
                return cmd(
                    "--gf-low",
                    format!("GF-low {l} % is above GF-high {h} %; GF-low must not exceed GF-high"),
                );
            }
        }
        if let Some(p) = self.surface_pressure_pa {
            // 50 kPa ≈ 5 600 m in the standard atmosphere; 110 kPa is above any sea-level record.
            if !(p.is_finite() && (50_000.0..=110_000.0).contains(&p)) {
                return cmd(
                    "--surface-pressure",
                    format!(
                        "surface pressure {} hPa is outside 500..1100 hPa (sea level to about 5 600 m)",
                        p / 100.0
                    ),
                );
            }
        }
        for (opt, v) in [
            ("--descent-rate", self.descent_rate_m_min),
            ("--ascent-rate", self.ascent_rate_m_min),
        ] {
            if let Some(why) = v.and_then(super::conventions::travel_rate_refusal) {
                return cmd(opt, why);
            }
        }
        if let Some(v) = self.last_stop_m {
            if !(v.is_finite() && v > 0.0 && v <= 30.0) {
                return cmd(
                    "--last-stop",
                    format!("last stop {v} m is outside (0, 30] m"),
                );
            }
        }
        Ok(())
    }
}

/// Read and build an algorithm file.
pub fn load_algorithm(path: &Path) -> Result<LoadedAlgorithm, InputError> {
    load_algorithm_with(path, &Overrides::default())
}

/// Read and build an algorithm file with command-line settings replacing the file's.
pub fn load_algorithm_with(
    path: &Path,
    overrides: &Overrides,
) -> Result<LoadedAlgorithm, InputError> {
    let text = crate::error::read_text(path, "the algorithm file")?;
    parse_algorithm_with(&text, path, overrides)
}

/// Build an algorithm from TOML text; `path` names it in errors.
pub fn parse_algorithm(text: &str, path: &Path) -> Result<LoadedAlgorithm, InputError> {
    parse_algorithm_with(text, path, &Overrides::default())
}

/// Build an algorithm from TOML text with command-line settings on top. An override that the
/// algorithm does not have (`--gf` for VPM-B) is refused naming the option. When the gradient
/// factors are overridden the file's `label` (which names its own factors) is replaced by the
/// algorithm's own.
pub fn parse_algorithm_with(
    text: &str,
    path: &Path,
    overrides: &Overrides,
) -> Result<LoadedAlgorithm, InputError> {
    overrides.validate()?;
    parse_algorithm_unlined(text, path, overrides).map_err(|e| crate::error::ensure_line(e, text))
}

fn parse_algorithm_unlined(
    text: &str,
    path: &Path,
    overrides: &Overrides,
) -> Result<LoadedAlgorithm, InputError> {
    let mut raw: RawAlgorithmFile =
        toml::from_str(text).map_err(|e| toml_error_with_path(path, text, &e))?;
    if overrides.gf_low.is_some() || overrides.gf_high.is_some() {
        let has_gf = raw
            .params
            .as_ref()
            .and_then(|p| p.as_table())
            .is_some_and(|t| t.contains_key("gf_low") || t.contains_key("gf_high"));
        if !has_gf {
            let opt = if overrides.gf_low.is_some() {
                "--gf-low"
            } else {
                "--gf-high"
            };
            return Err(InputError::new(format!(
                "the algorithm in {} ({}) has no gradient factors; --gf applies to ZH-L16 files",
                path.display(),
                raw.kind
            ))
            .in_file("<command line>")
            .field(opt));
        }
        let t = raw
            .params
            .as_mut()
            .and_then(|p| p.as_table_mut())
            .expect("checked above");
        for (k, v) in [("gf_low", overrides.gf_low), ("gf_high", overrides.gf_high)] {
            if let Some(v) = v {
                t.insert(k.to_string(), toml::Value::Float(v));
            }
        }
        raw.label = None;
    }
    let conv = raw.conventions.get_or_insert_with(Default::default);
    if let Some(v) = overrides.surface_pressure_pa {
        conv.surface_pressure_pa = Some(v);
    }
    if let Some(v) = overrides.descent_rate_m_min {
        conv.descent_rate_m_min = Some(v);
    }
    if let Some(v) = overrides.ascent_rate_m_min {
        conv.ascent_rate_m_min = Some(v);
    }
    if let Some(v) = overrides.last_stop_m {
        conv.last_stop_m = Some(v);
    }
    let at = |key: &str, field: &str, msg: String| {
        let mut e = InputError::new(msg).in_file(path).field(field);
        if let Some(l) = line_of_key(text, key) {
            e = e.at_line(l);
        }
        e
    };
    let builder = registry::builder(&raw.kind).ok_or_else(|| {
        at(
            "kind",
            "kind",
            format!(
                "unknown algorithm kind '{}'; known kinds: {}",
                raw.kind,
                registry::kinds().join(", ")
            ),
        )
    })?;
    let conventions = resolve_conventions(raw.conventions.unwrap_or_default(), text, path)?;
    let params = raw
        .params
        .unwrap_or_else(|| toml::Value::Table(Default::default()));
    let label = raw.label.clone().unwrap_or_default();
    let algorithm = builder(&label, params, conventions.clone()).map_err(|msg| {
        // Builders start their message with the field name ("gf_low: ...").
        let field = msg
            .split_once(": ")
            .map(|(f, _)| f.trim())
            .filter(|f| !f.is_empty() && f.chars().all(|c| c.is_alphanumeric() || c == '_'));
        let overridden = match field {
            Some("gf_low") => overrides.gf_low.or(overrides.gf_high).map(|_| "--gf-low"),
            Some("gf_high") => overrides.gf_high.or(overrides.gf_low).map(|_| "--gf-high"),
            _ => None,
        };
        if let Some(opt) = overridden {
            let rest = msg.split_once(": ").map_or(msg.as_str(), |(_, r)| r);
            return InputError::new(format!("{rest} (with the file's other gradient factor)"))
                .in_file("<command line>")
                .field(opt);
        }
        match field {
            Some(f) => {
                let rest = msg.split_once(": ").map_or(msg.as_str(), |(_, r)| r);
                let mut e = InputError::new(rest.to_string())
                    .in_file(path)
                    .field(format!("params.{f}"));
                if let Some(l) = line_of_key(text, f).or_else(|| line_of_header(text, "[params]")) {
                    e = e.at_line(l);
                }
                e
            }
            None => {
                let mut e = InputError::new(msg.clone()).in_file(path).field("params");
                if let Some(l) = line_of_header(text, "[params]") {
                    e = e.at_line(l);
                }
                e
            }
        }
    })?;
    let label = raw.label.unwrap_or_else(|| algorithm.label());
    let gases = resolve_gases(raw.gases.unwrap_or_default(), &conventions, text, path)?;
    Ok(LoadedAlgorithm {
        kind: raw.kind,
        label,
        conventions,
        algorithm,
        gases,
    })
}

/// Parse `[gases]` with the same readers as the command line; errors name `gases.deco` or
/// `gases.travel` and the line.
fn resolve_gases(
    raw: RawGases,
    conventions: &Conventions,
    text: &str,
    path: &Path,
) -> Result<FileGases, InputError> {
    let section = line_of_header(text, "[gases]");
    let deco_line = section.and(line_of_key(text, "deco"));
    let travel_line = section.and(line_of_key(text, "travel"));
    let at = |key: &str, line: Option<usize>, msg: String| {
        let mut e = InputError::new(msg)
            .in_file(path)
            .field(format!("gases.{key}"));
        if let Some(l) = line.or(section) {
            e = e.at_line(l);
        }
        e
    };
    let deco = raw
        .deco
        .iter()
        .map(|s| super::DecoGas::parse(s, conventions).map_err(|m| at("deco", deco_line, m)))
        .collect::<Result<Vec<_>, _>>()?;
    let travel = raw
        .travel
        .iter()
        .map(|s| super::schedule::parse_travel_gas(s).map_err(|m| at("travel", travel_line, m)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(FileGases {
        path: path.to_path_buf(),
        deco,
        travel,
        deco_line,
        travel_line,
    })
}

fn line_of_header(text: &str, header: &str) -> Option<usize> {
    text.lines().position(|l| l.trim() == header).map(|i| i + 1)
}

/// Preset (if any) with the file's fields on top, then validated.
fn resolve_conventions(
    raw: RawConventions,
    text: &str,
    path: &Path,
) -> Result<Conventions, InputError> {
    let at = |key: &str, msg: String| {
        let mut e = InputError::new(msg)
            .in_file(path)
            .field(format!("conventions.{key}"));
        if let Some(l) = line_of_key(text, key).or_else(|| line_of_header(text, "[conventions]")) {
            e = e.at_line(l);
        }
        e
    };
    let base = match &raw.preset {
        Some(p) => Some(Conventions::preset(p).ok_or_else(|| {
            at(
                "preset",
                format!(
                    "unknown preset '{p}'; known presets: {}",
                    Conventions::preset_names().join(", ")
                ),
            )
        })?),
        None => None,
    };
    macro_rules! pick {
        ($f:ident) => {
            match (raw.$f, &base) {
                (Some(v), _) => v,
                (None, Some(b)) => b.$f,
                (None, None) => {
                    return Err(at(
                        stringify!($f),
                        format!(
                            "missing; give `{}` or a `preset` ({})",
                            stringify!($f),
                            Conventions::preset_names().join(", ")
                        ),
                    ))
                }
            }
        };
    }
    let c = Conventions {
        surface_pressure_pa: pick!(surface_pressure_pa),
        pa_per_m: pick!(pa_per_m),
        water_vapour_pa: pick!(water_vapour_pa),
        descent_rate_m_min: pick!(descent_rate_m_min),
        ascent_rate_m_min: pick!(ascent_rate_m_min),
        stop_spacing_m: pick!(stop_spacing_m),
        last_stop_m: pick!(last_stop_m),
        bottom_time_includes_descent: pick!(bottom_time_includes_descent),
        stop_rounding: pick!(stop_rounding),
        gf_low_anchor: pick!(gf_low_anchor),
        min_stop_min: pick!(min_stop_min),
        surface_tissue_n2_fraction: raw
            .surface_tissue_n2_fraction
            .or(base.as_ref().map(|b| b.surface_tissue_n2_fraction))
            .unwrap_or_else(super::conventions::default_surface_tissue_n2_fraction),
    };
    c.validate().map_err(|(field, msg)| at(&field, msg))?;
    Ok(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<LoadedAlgorithm, InputError> {
        parse_algorithm(text, Path::new("t.toml"))
    }

    #[test]
    fn preset_with_override() {
        let a = parse(
            "kind = \"zhl16\"\n[conventions]\npreset = \"decotengu\"\nlast_stop_m = 6.0\n\
             [params]\nmodel = \"zh-l16c\"\ngf_low = 30\ngf_high = 85\n",
        )
        .unwrap();
        assert_eq!(a.conventions.last_stop_m, 6.0);
        assert_eq!(a.conventions.pa_per_m, 9985.0);
        assert_eq!(a.label, "ZH-L16C GF 30/85");
    }

    #[test]
    fn errors_name_file_line_and_field() {
        let e = parse("kind = \"zhl16\"\n[params]\nmodel = \"zh-l16c\"\ngf_low = 90\ngf_high = 85\n[conventions]\npreset = \"decotengu\"\n")
            .unwrap_err();
        assert_eq!(e.field.as_deref(), Some("params.gf_low"));
        assert_eq!(e.line, Some(4));
        let e = parse("kind = \"bogus\"\n").unwrap_err();
        assert_eq!((e.field.as_deref(), e.line), (Some("kind"), Some(1)));
        let e = parse("kind = \"zhl16\"\n[conventions]\npreset = \"decotengu\"\nascent_rate_m_min = -10.0\n[params]\nmodel = \"zh-l16c\"\ngf_low = 30\ngf_high = 85\n").unwrap_err();
        assert_eq!(
            (e.field.as_deref(), e.line),
            (Some("conventions.ascent_rate_m_min"), Some(4))
        );
        let e =
            parse("kind = \"zhl16\"\n[conventions]\npreset = \"decotengu\"\nascent_rate = 10.0\n")
                .unwrap_err();
        assert_eq!(e.line, Some(4), "{e}");
        assert!(e.message.contains("ascent_rate"), "{e}");
        let e = parse("kind = \"zhl16\"\n[conventions]\npreset = \"decotengu\"\n[params]\nmodel = \"zh-l16c\"\ngf_low = 30\ngf_high = 85\ngf_lo = 3\n").unwrap_err();
        assert_eq!(
            (e.field.as_deref(), e.line),
            (Some("params.gf_lo"), Some(8)),
            "{e}"
        );
        let e = parse("kind = \"zhl16\"\n[conventions]\npa_per_m = 1.0\n").unwrap_err();
        assert!(
            e.field.as_deref().unwrap().starts_with("conventions."),
            "{e}"
        );
    }
}
