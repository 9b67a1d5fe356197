//! Criteria files (`algorithms/criteria/*.toml`): raw serde structs mirroring the file
//! (`deny_unknown_fields`), then a validated [`CriteriaSet`].
//!
//! ```toml
//! description = "what these limits are for"
//! [protocol]
//! observe_after_surfacing_min = 60   # watch the phantom this long at the surface (default 60)
//! water_vapour_pa = 6270             # H2O at the faces and in every bubble (default 6270)
//! co2_pa = 5300                      # CO2 in every bubble (default 5300; 0 with O2 at the faces)
//! venous_o2_pa = 5300                # metabolic O2 in every bubble (default 5300; not with O2 at the faces)
//! oxygen_at_faces = false            # default false: only N2 and He reach the open faces
//! [[criterion]]
//! kind = "peak-total-volume"         # registry key (risk::REGISTRY)
//! label = "peak volume"              # optional, unique; default the kind
//! limit = 0.05                       # in the criterion's unit (> 0)
//! # further fields: the criterion's parameters (e.g. threshold_mm3 = 0.02)
//! ```

use super::{build, kinds, score, RiskCriterion, RunData, Score};
use crate::error::{line_of_key, toml_error_with_path, InputError};
use serde::Deserialize;
use std::path::Path;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawCriteriaFile {
    description: Option<String>,
    protocol: Option<RawProtocol>,
    #[serde(default)]
    criterion: Vec<toml::Table>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawProtocol {
    observe_after_surfacing_min: Option<f64>,
    water_vapour_pa: Option<f64>,
    co2_pa: Option<f64>,
    venous_o2_pa: Option<f64>,
    oxygen_at_faces: Option<bool>,
}

/// How a dive schedule drives the phantom: the breathed-gas convention.
///
/// The phantom stands for tissue breathing the schedule's gas. One convention holds on both
/// sides of every bubble's interface:
/// - **at the open faces** (and hence in the gel far from bubbles) each simulated gas is at its
///   inspired partial pressure with water vapour taken out, f_g·(P_amb − P_H2O) (the alveolar
///   inert-gas pressure of Schreiner's equation and the Bühlmann planners); O2 is not simulated
///   unless `oxygen_at_faces` (tissue consumes it);
/// - **in every bubble** the gases that are not simulated sit at fixed partial pressures —
///   water vapour P_H2O (the same value as at the faces), CO2 P_CO2 and, when O2 is not
///   simulated, the venous O2 P_vO2 — and the simulated gases hold the rest of the bubble's
///   pressure, P_B − p_fixed with p_fixed = P_H2O + P_CO2 + P_vO2
///   ([`Protocol::bubble_fixed_gases_pa`], passed to the phantom's `bubble_fixed_gases`).
///
/// A bubble in tissue at rest at the surface on air then sees the physiological inherent
/// unsaturation (the "oxygen window"): P_amb − [f_N2(P_amb − P_H2O) + P_H2O + P_CO2 + P_vO2]
/// = f_O2(P_amb − P_H2O) − P_vO2 − P_CO2 = 19.96 − 5.3 − 5.3 = 9.36 kPa with the defaults,
/// plus its own Laplace pressure. (Before this convention the bubbles held inert gas only
/// against faces with vapour and O2 taken out: 26.2 kPa of built-in unsaturation.)
/// With `oxygen_at_faces` the phantom does not metabolise: O2 is simulated like N2, the faces
/// hold every gas at f_g(P_amb − P_H2O), the bubble holds water vapour (and `co2_pa` if set),
/// and the total at the faces equals ambient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Protocol {
    /// Time the phantom is watched at the surface after the schedule ends, s (bubbles in gel
    /// grow for tens of minutes after surfacing). Default 3600.
    pub observe_after_surfacing_s: f64,
    /// Water-vapour pressure P_H2O, Pa: subtracted from ambient at the open faces for every
    /// schedule (whatever its planner assumed) and held in every bubble. Default 6 270 Pa
    /// ([`crate::units::BODY_WATER_VAPOUR_PA`], 47 mmHg at 37 °C).
    pub water_vapour_pa: f64,
    /// Partial pressure of CO2 in every bubble, P_CO2, Pa. Default 5 300 Pa
    /// ([`crate::units::TISSUE_CO2_PA`], 40 mmHg); 0 when `oxygen_at_faces`.
    pub co2_pa: f64,
    /// Partial pressure of metabolic (venous) O2 in every bubble, P_vO2, Pa, when O2 is not a
    /// simulated gas. Default 5 300 Pa ([`crate::units::VENOUS_O2_PA`], 40 mmHg); 0 (and not
    /// allowed otherwise) when `oxygen_at_faces`.
    pub venous_o2_pa: f64,
    /// Let the breathed O2 reach the open faces too (default false: the faces are in
    /// equilibrium with the inspired inert gases, N2 and He, only — living tissue
    /// metabolises oxygen).
    pub oxygen_at_faces: bool,
}

impl Default for Protocol {
    fn default() -> Self {
        Protocol {
            observe_after_surfacing_s: 3600.0,
            water_vapour_pa: crate::units::BODY_WATER_VAPOUR_PA,
            co2_pa: crate::units::TISSUE_CO2_PA,
            venous_o2_pa: crate::units::VENOUS_O2_PA,
            oxygen_at_faces: false,
        }
    }
}

impl Protocol {
    /// p_fixed = P_H2O + P_CO2 + P_vO2, Pa: the partial pressure of the gases that are not
    /// simulated, held in every bubble (the phantom's `bubble_fixed_gases`).
    pub fn bubble_fixed_gases_pa(&self) -> f64 {
        self.water_vapour_pa + self.co2_pa + self.venous_o2_pa
    }
}

/// One criterion of a file with its label and limit.
#[derive(Debug)]
pub struct ConfiguredCriterion {
    /// Unique label (tables, legends).
    pub label: String,
    /// Limit in the criterion's unit (> 0).
    pub limit: f64,
    /// The criterion.
    pub criterion: Box<dyn RiskCriterion>,
}

/// A validated criteria file.
#[derive(Debug)]
pub struct CriteriaSet {
    /// Free text from the file.
    pub description: String,
    /// The evaluation protocol.
    pub protocol: Protocol,
    /// The criteria, in file order.
    pub criteria: Vec<ConfiguredCriterion>,
}

impl CriteriaSet {
    /// Score a run on every criterion, in file order.
    pub fn score(&self, run: &RunData) -> Vec<Score> {
        self.criteria
            .iter()
            .map(|c| {
                score(
                    &c.label,
                    c.criterion.as_ref(),
                    c.criterion.evaluate(run),
                    c.limit,
                    c.criterion.absolute(run),
                )
            })
            .collect()
    }
}

/// Accepted range of `[protocol] observe_after_surfacing_min`, min: at least 1 min, so that
/// the after-surfacing window (the criteria with `window = "after-surfacing"`, the plots of the
/// surface phase) holds recorded frames — with 0 it was empty and scored 0, a silent pass — and
/// at most a week (10 080 min; bubbles in gel grow for tens of minutes to hours after
/// surfacing).
pub const OBSERVE_AFTER_SURFACING_RANGE_MIN: (f64, f64) = (1.0, 10_080.0);

/// Read and validate a criteria file.
pub fn load_criteria(path: &Path) -> Result<CriteriaSet, InputError> {
    let text = crate::error::read_text(path, "the criteria file")?;
    parse_criteria(&text, path)
}

/// 1-based line of the `n`-th (0-based) `[[criterion]]` header.
fn block_line(text: &str, n: usize) -> Option<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.trim().starts_with("[[criterion]]"))
        .nth(n)
        .map(|(i, _)| i + 1)
}

/// 1-based line of `key =` inside the `n`-th `[[criterion]]` block (else the block header).
fn line_in_block(text: &str, n: usize, key: &str) -> Option<usize> {
    let start = block_line(text, n)?;
    let found = text
        .lines()
        .enumerate()
        .skip(start)
        .take_while(|(_, l)| !l.trim_start().starts_with('['))
        .find(|(_, l)| {
            let t = l.trim_start();
            t.starts_with(key) && t[key.len()..].trim_start().starts_with('=')
        })
        .map(|(i, _)| i + 1);
    Some(found.unwrap_or(start))
}

/// Parse and validate criteria TOML text (`path` names it in errors).
pub fn parse_criteria(text: &str, path: &Path) -> Result<CriteriaSet, InputError> {
    let raw: RawCriteriaFile =
        toml::from_str(text).map_err(|e| toml_error_with_path(path, text, &e))?;
    let top = |key: &str, msg: String| {
        let leaf = key.rsplit('.').next().unwrap_or(key);
        let mut e = InputError::new(msg).in_file(path).field(key);
        if let Some(l) = line_of_key(text, leaf) {
            e = e.at_line(l);
        }
        e
    };
    let rp = raw.protocol.unwrap_or_default();
    let mut protocol = Protocol::default();
    if let Some(m) = rp.observe_after_surfacing_min {
        let (lo, hi) = OBSERVE_AFTER_SURFACING_RANGE_MIN;
        if !(m.is_finite() && (lo..=hi).contains(&m)) {
            return Err(top(
                "protocol.observe_after_surfacing_min",
                format!(
                    "must be between {lo} and {hi} min (got {}); the after-surfacing window needs at least a minute of watching",
                    crate::error::num(m)
                ),
            ));
        }
        protocol.observe_after_surfacing_s = m * 60.0;
    }
    protocol.oxygen_at_faces = rp.oxygen_at_faces.unwrap_or(false);
    if protocol.oxygen_at_faces {
        // no metabolism: O2 is simulated, neither consumed nor replaced by CO2
        protocol.co2_pa = 0.0;
        protocol.venous_o2_pa = 0.0;
        if rp.venous_o2_pa.is_some_and(|v| v != 0.0) {
            return Err(top(
                "protocol.venous_o2_pa",
                "cannot be used with oxygen_at_faces = true: O2 is then a simulated gas in the bubble; remove venous_o2_pa or set oxygen_at_faces = false".into(),
            ));
        }
    }
    for (key, value, slot, typical) in [
        (
            "protocol.water_vapour_pa",
            rp.water_vapour_pa,
            &mut protocol.water_vapour_pa,
            "at 37 °C: 6270",
        ),
        (
            "protocol.co2_pa",
            rp.co2_pa,
            &mut protocol.co2_pa,
            "alveolar/venous: 5300",
        ),
        (
            "protocol.venous_o2_pa",
            rp.venous_o2_pa,
            &mut protocol.venous_o2_pa,
            "mixed venous: 5300",
        ),
    ] {
        if let Some(v) = value {
            if !(v.is_finite() && (0.0..20_000.0).contains(&v)) {
                return Err(top(
                    key,
                    format!(
                        "must be in 0..20000 Pa ({typical}) (got {})",
                        crate::error::num(v)
                    ),
                ));
            }
            *slot = v;
        }
    }
    if raw.criterion.is_empty() {
        // named at the last line of the file, where the entries would go
        return Err(crate::error::ensure_line(
            InputError::new("no criteria: add at least one [[criterion]] with kind and limit")
                .in_file(path)
                .field("criterion"),
            text,
        ));
    }
    let mut criteria: Vec<ConfiguredCriterion> = Vec::new();
    for (n, mut t) in raw.criterion.into_iter().enumerate() {
        let err = |key: &str, msg: String| {
            let mut e = InputError::new(format!("criterion {}: {msg}", n + 1))
                .in_file(path)
                .field(format!("criterion.{key}"));
            if let Some(l) = line_in_block(text, n, key) {
                e = e.at_line(l);
            }
            e
        };
        let kind = match t.remove("kind") {
            Some(toml::Value::String(s)) => s,
            Some(_) => return Err(err("kind", "must be a string".into())),
            None => {
                return Err(err(
                    "kind",
                    format!("missing; one of {}", kinds().join(", ")),
                ))
            }
        };
        let limit = match t.remove("limit") {
            Some(toml::Value::Float(x)) => x,
            Some(toml::Value::Integer(i)) => i as f64,
            Some(_) => return Err(err("limit", "must be a number".into())),
            None => {
                return Err(err(
                    "limit",
                    "missing; give the limit in the criterion's unit".into(),
                ))
            }
        };
        let label = match t.remove("label") {
            Some(toml::Value::String(s)) => s,
            Some(_) => return Err(err("label", "must be a string".into())),
            None => kind.clone(),
        };
        let criterion = build(&kind, t).map_err(|m| {
            if m.starts_with("unknown criterion") {
                return err("kind", m);
            }
            // builders and serde (through `params`) start with the key: "threshold_mm3: ..."
            let field = m
                .split_once(": ")
                .map(|(f, _)| f)
                .filter(|f| !f.is_empty() && !f.contains(' '))
                .unwrap_or("kind")
                .to_string();
            err(&field, m)
        })?;
        // a limit so small or large that value/limit overflows is not a limit (1e-308 gave -inf
        // margins on the log scale of the report)
        if !(limit.is_finite() && (1e-9..=1e12).contains(&limit)) {
            return Err(err(
                "limit",
                format!(
                    "must be positive, between 1e-9 and 1e12 (got {}); give it in {}",
                    crate::error::num(limit),
                    if criterion.unit().is_empty() {
                        "the criterion's unit"
                    } else {
                        criterion.unit()
                    }
                ),
            ));
        }
        if criteria.iter().any(|c| c.label == label) {
            return Err(err(
                "label",
                format!("label '{label}' is used twice; give each criterion its own label"),
            ));
        }
        criteria.push(ConfiguredCriterion {
            label,
            limit,
            criterion,
        });
    }
    Ok(CriteriaSet {
        description: raw.description.unwrap_or_default(),
        protocol,
        criteria,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(t: &str) -> Result<CriteriaSet, InputError> {
        parse_criteria(t, Path::new("c.toml"))
    }

    #[test]
    fn reads_criteria_and_protocol() {
        let c = parse(
            "[protocol]\nobserve_after_surfacing_min = 30\nwater_vapour_pa = 6270\n\
             [[criterion]]\nkind = \"peak-radius\"\nlimit = 200\n\
             [[criterion]]\nkind = \"hazard\"\nlabel = \"P\"\nlimit = 5.0\ngain_per_mm3_min = 0.1\n",
        )
        .unwrap();
        assert_eq!(c.criteria.len(), 2);
        assert_eq!(c.criteria[1].label, "P");
        assert_eq!(c.criteria[0].limit, 200.0);
        assert_eq!(c.protocol.observe_after_surfacing_s, 1800.0);
        assert_eq!(c.protocol.water_vapour_pa, 6270.0);
        assert!(!c.protocol.oxygen_at_faces);
        // defaults: Guyton & Hall / West figures, 47 + 40 + 40 mmHg ≈ 6.27 + 5.3 + 5.3 kPa
        assert_eq!(c.protocol.bubble_fixed_gases_pa(), 16_870.0);
        let o = parse("[protocol]\noxygen_at_faces = true\nwater_vapour_pa = 6000\n[[criterion]]\nkind = \"peak-radius\"\nlimit = 1\n").unwrap();
        assert_eq!(o.protocol.bubble_fixed_gases_pa(), 6000.0);
        let e = parse("[protocol]\noxygen_at_faces = true\nvenous_o2_pa = 5300\n[[criterion]]\nkind = \"peak-radius\"\nlimit = 1\n").unwrap_err();
        assert_eq!(e.field.as_deref(), Some("protocol.venous_o2_pa"), "{e}");
        let e =
            parse("[protocol]\nco2_pa = -1\n[[criterion]]\nkind = \"peak-radius\"\nlimit = 1\n")
                .unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(2), Some("protocol.co2_pa")),
            "{e}"
        );
    }

    #[test]
    fn errors_name_line_and_field() {
        let e = parse("[[criterion]]\nkind = \"peak-radius\"\nlimit = 1\n[[criterion]]\nkind = \"bogus\"\nlimit = 1\n")
            .unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(5), Some("criterion.kind")),
            "{e}"
        );
        assert!(e.message.contains("peak-total-volume"), "{e}");
        let e = parse("[[criterion]]\nkind = \"peak-radius\"\nlimit = -3\n").unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(3), Some("criterion.limit")),
            "{e}"
        );
        let e = parse(
            "[[criterion]]\nkind = \"hazard\"\nlimit = 3\ngain_per_mm3_min = 1\nthreshold = 2\n",
        )
        .unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(5), Some("criterion.threshold")),
            "{e}"
        );
        let e = parse("[[criterion]]\nkind = \"hazard\"\nlimit = 3\n").unwrap_err();
        assert_eq!(
            e.field.as_deref(),
            Some("criterion.gain_per_mm3_min"),
            "{e}"
        );
        let e = parse("[protocol]\nobserve_after_surfacing_min = -1\n[[criterion]]\nkind = \"peak-radius\"\nlimit = 1\n")
            .unwrap_err();
        assert_eq!(e.line, Some(2), "{e}");
        let e = parse("[[criterion]]\nkind = \"peak-radius\"\nlimit = 1\n[[criterion]]\nkind = \"peak-radius\"\nlimit = 2\n")
            .unwrap_err();
        assert_eq!(e.field.as_deref(), Some("criterion.label"), "{e}");
        let e = parse("descripton = \"x\"\n").unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(1), Some("descripton")),
            "{e}"
        );
        assert!(parse("description = \"x\"\n").is_err());
    }
}
