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
//! ```

use super::conventions::{Conventions, GfLowAnchor, StopRounding};
use super::{registry, DecoAlgorithm};
use crate::error::{line_of_key, toml_error, InputError};
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

/// Read and build an algorithm file.
pub fn load_algorithm(path: &Path) -> Result<LoadedAlgorithm, InputError> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        InputError::new(format!("cannot read the algorithm file: {e}")).in_file(path)
    })?;
    parse_algorithm(&text, path)
}

/// Build an algorithm from TOML text; `path` names it in errors.
pub fn parse_algorithm(text: &str, path: &Path) -> Result<LoadedAlgorithm, InputError> {
    let raw: RawAlgorithmFile = toml::from_str(text).map_err(|e| toml_error(path, text, &e))?;
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
    Ok(LoadedAlgorithm {
        kind: raw.kind,
        label,
        conventions,
        algorithm,
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
