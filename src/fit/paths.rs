//! Parameters named by their phantom-TOML path (`gases.n2.diffusivity`,
//! `material.elasticity.shear_modulus`, `bubbles.0.initial_radius_m`, `perfusion.rate_per_s`).
//!
//! A phantom is kept as its TOML document; a parameter value is written into the document at
//! its path and the document is validated again by the same reader as a phantom file
//! ([`crate::phantom::config::parse_phantom`]), so every numeric field a phantom file can hold
//! can be fitted or swept, with the reader's own range checks. Used by `fit`, `discover`,
//! `synth` and the sweeps.

use crate::error::InputError;

/// One segment of a path: a table key or an array index.
#[derive(Debug, Clone, PartialEq, Eq)]
enum Segment {
    Key(String),
    Index(usize),
}

fn segments(path: &str) -> Result<Vec<Segment>, String> {
    if path.trim().is_empty() {
        return Err("empty parameter path".into());
    }
    path.split('.')
        .map(|s| {
            if s.is_empty() {
                Err(format!("'{path}': empty segment in the path"))
            } else if let Ok(i) = s.parse::<usize>() {
                Ok(Segment::Index(i))
            } else {
                Ok(Segment::Key(s.to_string()))
            }
        })
        .collect()
}

fn as_number(v: &toml::Value) -> Option<f64> {
    v.as_float().or(v.as_integer().map(|i| i as f64))
}

/// The value at `path` in `doc`, if the path exists.
fn value_at<'a>(doc: &'a toml::Table, path: &str) -> Option<&'a toml::Value> {
    let segs = segments(path).ok()?;
    let mut cur: &toml::Value = doc.get(match &segs[0] {
        Segment::Key(k) => k.as_str(),
        Segment::Index(_) => return None,
    })?;
    for s in &segs[1..] {
        cur = match s {
            Segment::Key(k) => cur.as_table()?.get(k)?,
            Segment::Index(i) => cur.as_array()?.get(*i)?,
        };
    }
    Some(cur)
}

/// The number at `path` in `doc`, if the path exists and holds a number.
pub fn get(doc: &toml::Table, path: &str) -> Option<f64> {
    value_at(doc, path).and_then(as_number)
}

/// Why `path` cannot be a parameter of phantom documents `docs` (read from `files`) although
/// it is there: it holds something other than a number (the elasticity law's name, a table, a
/// list) in the first document that has it, named with what it holds and, for a list, how to
/// name one of its numbers. `None` when the path holds a number or is absent (a setting at its
/// default, which bounds can give a start).
pub fn not_a_number(
    docs: &[toml::Table],
    files: &[&std::path::Path],
    path: &str,
) -> Option<String> {
    if path.starts_with(SCALE_PREFIX) {
        return None;
    }
    let (v, file) = docs
        .iter()
        .zip(files)
        .find_map(|(d, f)| value_at(d, path).map(|v| (v, f)))?;
    if as_number(v).is_some() {
        return None;
    }
    let (kind, hint) = match v {
        toml::Value::Array(a) if a.first().and_then(as_number).is_some() => (
            "a list of numbers".to_string(),
            format!(" (name one of them by its 0-based index, e.g. '{path}.0')"),
        ),
        toml::Value::Array(_) => ("a list".to_string(), String::new()),
        other => (format!("a {}", other.type_str()), String::new()),
    };
    Some(format!(
        "'{path}' holds {kind} in {}, not a number: only a numeric field of the phantom can be fitted{hint}",
        file.display()
    ))
}

/// Write `value` at `path`, creating missing tables on the way (a setting left at its default
/// in the file is added). An existing non-table on the way, an array index out of range or a
/// non-numeric leaf is an error naming the path.
pub fn set(doc: &mut toml::Table, path: &str, value: f64) -> Result<(), String> {
    let segs = segments(path)?;
    let not_table = |at: &str| format!("'{path}': '{at}' is not a table in the phantom file");
    let mut cur: &mut toml::Value = {
        let Segment::Key(k) = &segs[0] else {
            return Err(format!("'{path}' must start with a table name"));
        };
        if segs.len() == 1 {
            return set_leaf(doc.entry(k.clone()), path, value);
        }
        doc.entry(k.clone())
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
    };
    for (n, s) in segs[1..].iter().enumerate() {
        let last = n + 2 == segs.len();
        match s {
            Segment::Key(k) => {
                let t = cur.as_table_mut().ok_or_else(|| not_table(k))?;
                if last {
                    return set_leaf(t.entry(k.clone()), path, value);
                }
                cur = t
                    .entry(k.clone())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            }
            Segment::Index(i) => {
                let a = cur
                    .as_array_mut()
                    .ok_or_else(|| format!("'{path}': index {i} into something not a list"))?;
                let len = a.len();
                let item = a.get_mut(*i).ok_or_else(|| {
                    format!("'{path}': index {i} is out of range (the list has {len} entries)")
                })?;
                if last {
                    return match item {
                        toml::Value::Float(_) | toml::Value::Integer(_) => {
                            *item = toml::Value::Float(value);
                            Ok(())
                        }
                        _ => Err(format!("'{path}' is not a number")),
                    };
                }
                cur = item;
            }
        }
    }
    unreachable_path(path)
}

fn unreachable_path(path: &str) -> Result<(), String> {
    Err(format!("'{path}': not a settable number"))
}

fn set_leaf(entry: toml::map::Entry<'_>, path: &str, value: f64) -> Result<(), String> {
    match entry {
        toml::map::Entry::Vacant(v) => {
            v.insert(toml::Value::Float(value));
            Ok(())
        }
        toml::map::Entry::Occupied(mut o) => match o.get() {
            toml::Value::Float(_) | toml::Value::Integer(_) => {
                o.insert(toml::Value::Float(value));
                Ok(())
            }
            _ => Err(format!(
                "'{path}' holds a {} in the phantom file, not a number",
                o.get().type_str()
            )),
        },
    }
}

/// Expand a path whose key segments may be `*` (every key of that table) into the concrete
/// paths that hold a number in `doc`, e.g. `gases.*.diffusivity` → `gases.n2.diffusivity`, ….
pub fn expand(doc: &toml::Table, pattern: &str) -> Vec<String> {
    fn walk(v: &toml::Value, rest: &[&str], prefix: String, out: &mut Vec<String>) {
        let Some((head, tail)) = rest.split_first() else {
            if as_number(v).is_some() {
                out.push(prefix);
            }
            return;
        };
        let join = |k: &str| {
            if prefix.is_empty() {
                k.to_string()
            } else {
                format!("{prefix}.{k}")
            }
        };
        match v {
            toml::Value::Table(t) if *head == "*" => {
                for (k, x) in t {
                    walk(x, tail, join(k), out);
                }
            }
            toml::Value::Table(t) => {
                if let Some(x) = t.get(*head) {
                    walk(x, tail, join(head), out);
                }
            }
            toml::Value::Array(a) => {
                if let Ok(i) = head.parse::<usize>() {
                    if let Some(x) = a.get(i) {
                        walk(x, tail, join(head), out);
                    }
                }
            }
            _ => {}
        }
    }
    let segs: Vec<&str> = pattern.split('.').collect();
    let mut out = Vec::new();
    walk(
        &toml::Value::Table(doc.clone()),
        &segs,
        String::new(),
        &mut out,
    );
    out
}

/// Prefix of a parameter that scales, rather than sets, the numbers at a path pattern:
/// `scale:gases.*.diffusivity` = 1.5 multiplies every gas's diffusivity by 1.5.
pub const SCALE_PREFIX: &str = "scale:";

/// The symbol and unit of an elasticity law's modulus field (the paper's eqs. 2.6–2.9).
fn elastic_field(field: &str) -> Option<(&'static str, &'static str)> {
    match field {
        "shear_modulus" => Some(("μ", "Pa")),
        "bulk_modulus" => Some(("K", "Pa")),
        "bulk_modulus_per_volume" => Some(("M", "Pa/m³")),
        _ => None,
    }
}

/// "second", "third"… for the `k`-th (k ≥ 2) added term; "4th" and on in digits.
fn ordinal(k: usize) -> String {
    match k {
        1 => "first".into(),
        2 => "second".into(),
        3 => "third".into(),
        _ => format!("{k}th"),
    }
}

/// A parameter path in a reader's words: its symbol (the paper's where it has one) and its
/// unit (`None`: dimensionless), e.g. `material.surface_tension` → ("γ", Some("N/m")),
/// `scale:gases.*.diffusivity` → ("D factor", None); a path it does not know is its own name.
/// A term of an elasticity `sum` law, `material.elasticity.terms.N.FIELD`, is the field's
/// symbol of that term, numbered as in the file from 0: `material.elasticity.terms.1.shear_modulus`
/// → ("μ of elasticity term 1", Some("Pa")). [`describe_in`] names terms a search added.
pub fn describe(path: &str) -> (String, Option<&'static str>) {
    describe_in(path, None)
}

/// [`describe`] in a model whose elasticity terms from index `own_terms` on were added to the
/// phantom's own (`discover`'s `elasticity:<law>` candidates append a term to the phantom's
/// law, which becomes term 0 of a sum, or to the terms of a `sum` it already has): the first
/// added term is "the added elasticity term", later ones "the second added elasticity term"…;
/// a term below `own_terms` is "the phantom's elasticity term N". `None`: [`describe`]'s
/// numbering.
pub fn describe_in(path: &str, own_terms: Option<usize>) -> (String, Option<&'static str>) {
    let gas = |g: &str| g.to_uppercase();
    let segs: Vec<&str> = path.split('.').collect();
    match segs.as_slice() {
        ["material", "elasticity", field] => {
            if let Some((sym, unit)) = elastic_field(field) {
                return (sym.into(), Some(unit));
            }
        }
        ["material", "elasticity", "terms", i, field] => {
            if let (Ok(i), Some((sym, unit))) = (i.parse::<usize>(), elastic_field(field)) {
                let term = match own_terms {
                    None => format!("elasticity term {i}"),
                    Some(own) if i < own => format!("the phantom's elasticity term {i}"),
                    Some(own) if i == own => "the added elasticity term".to_string(),
                    Some(own) => format!("the {} added elasticity term", ordinal(i - own + 1)),
                };
                return (format!("{sym} of {term}"), Some(unit));
            }
        }
        _ => {}
    }
    match (path, segs.as_slice()) {
        ("material.surface_tension", _) => ("γ".into(), Some("N/m")),
        ("material.surface.fold", _) => ("k (surface fold)".into(), None),
        ("material.surface.exponent", _) => ("a (surface exponent)".into(), None),
        ("material.temperature_k", _) => ("T".into(), Some("K")),
        ("material.bubble_fixed_gases_pa", _) => ("p_fixed".into(), Some("Pa")),
        ("perfusion.rate_per_s", _) => ("perfusion rate".into(), Some("1/s")),
        ("scale:gases.*.diffusivity", _) => ("D factor".into(), None),
        ("scale:gases.*.ostwald", _) => ("L factor".into(), None),
        (_, ["gases", g, "ostwald"]) => (format!("L_{}", gas(g)), None),
        (_, ["gases", g, "diffusivity"]) => (format!("D_{}", gas(g)), Some("m²/s")),
        _ => (path.to_string(), None),
    }
}

/// [`describe`] as an axis or category label: `γ (N/m)`, `L_N2`.
pub fn label(path: &str) -> String {
    label_in(path, None)
}

/// [`describe_in`] as a label: `μ of the added elasticity term (Pa)`.
pub fn label_in(path: &str, own_terms: Option<usize>) -> String {
    match describe_in(path, own_terms) {
        (sym, Some(unit)) => format!("{sym} ({unit})"),
        (sym, None) => sym,
    }
}

/// [`describe`] with a value, for a legend: `γ = 0.07 N/m`, `L_N2 = 0.014`.
pub fn with_value(path: &str, value: &str) -> String {
    with_value_in(path, value, None)
}

/// [`describe_in`] with a value: `μ of the added elasticity term = 21923 Pa`.
pub fn with_value_in(path: &str, value: &str, own_terms: Option<usize>) -> String {
    match describe_in(path, own_terms) {
        (sym, Some(unit)) => format!("{sym} = {value} {unit}"),
        (sym, None) => format!("{sym} = {value}"),
    }
}

/// The number of elasticity terms a phantom document has of its own: the length of `terms` of
/// a `sum` law, else 1 (its one law, or the default). The index of the first term `discover`
/// adds, for [`describe_in`].
pub fn own_elasticity_terms(doc: &toml::Table) -> usize {
    let el = doc
        .get("material")
        .and_then(|m| m.get("elasticity"))
        .and_then(|e| e.as_table());
    match el {
        Some(t) if t.get("law").and_then(|l| l.as_str()) == Some("sum") => t
            .get("terms")
            .and_then(|x| x.as_array())
            .map_or(0, |a| a.len()),
        _ => 1,
    }
}

/// Apply a parameter to a document: a plain path is set; a `scale:` pattern multiplies every
/// number it matches (an error if it matches none).
pub fn apply(doc: &mut toml::Table, path: &str, value: f64) -> Result<(), String> {
    match path.strip_prefix(SCALE_PREFIX) {
        Some(pattern) => {
            let hits = expand(doc, pattern);
            if hits.is_empty() {
                return Err(format!("'{pattern}' matches no number in the phantom"));
            }
            for h in hits {
                let v = get(doc, &h).unwrap_or(0.0);
                set(doc, &h, v * value)?;
            }
            Ok(())
        }
        None => set(doc, path, value),
    }
}

/// Whether a document holds the parameter (a `scale:` pattern: whether it matches anything).
pub fn holds(doc: &toml::Table, path: &str) -> bool {
    match path.strip_prefix(SCALE_PREFIX) {
        Some(pattern) => !expand(doc, pattern).is_empty(),
        None => get(doc, path).is_some(),
    }
}

/// A parameter to fit or sweep: its path, optional bounds, and whether it is fitted in log
/// space (positive parameters are).
#[derive(Debug, Clone, PartialEq)]
pub struct ParamSpec {
    /// TOML path in the phantom, e.g. `gases.n2.diffusivity`.
    pub path: String,
    /// Lower bound (in the parameter's own unit), if any.
    pub lower: Option<f64>,
    /// Upper bound, if any.
    pub upper: Option<f64>,
    /// Fitted in log space (the parameter is positive).
    pub log: bool,
    /// Starting value.
    pub start: f64,
}

/// Whether phantom documents `docs` (read from `files`) refuse `value` at `path`, written where a
/// fit writes it ([`crate::fit::model::set_shared`]: in every document that holds the path, or in
/// all when none does) and each document read again by the phantom reader, so the field's own
/// accepted range applies (a negative diffusivity, a surface tension above 1 N/m, a bubble
/// outside the gel): the first refusing document's index and the reader's reason.
pub fn refused_value(
    docs: &[toml::Table],
    files: &[&std::path::Path],
    path: &str,
    value: f64,
) -> Option<(usize, String)> {
    let any = docs.iter().any(|d| holds(d, path));
    docs.iter()
        .zip(files)
        .enumerate()
        .filter(|(_, (doc, _))| !any || holds(doc, path))
        .find_map(|(i, (doc, file))| {
            let mut t = doc.clone();
            let reason = match apply(&mut t, path, value) {
                Err(m) => Some(m),
                Ok(()) => crate::fit::data::build_params(&t, file)
                    .err()
                    .map(|e| match e.field {
                        Some(f) => format!("field '{f}': {}", e.message),
                        None => e.message,
                    }),
            };
            reason.map(|r| (i, r))
        })
}

impl ParamSpec {
    /// Parse `NAME` or `NAME=LO..HI` (the command-line form). The start is the value in the
    /// phantom (`base`), else the geometric (log) or arithmetic mean of the bounds.
    pub fn parse(text: &str, base: Option<f64>) -> Result<ParamSpec, InputError> {
        let bad = |m: String| {
            InputError::new(m)
                .in_file("<command line>")
                .field("--param")
        };
        let (path, range) = match text.split_once('=') {
            Some((p, r)) => (p.trim(), Some(r.trim())),
            None => (text.trim(), None),
        };
        segments(path.strip_prefix(SCALE_PREFIX).unwrap_or(path)).map_err(bad)?;
        let (lower, upper) = match range {
            None => (None, None),
            Some(r) => {
                let (lo, hi) = r.split_once("..").ok_or_else(|| {
                    bad(format!(
                        "'{text}': bounds are written NAME=LO..HI, e.g. gases.n2.diffusivity=1e-10..5e-9"
                    ))
                })?;
                let num = |s: &str| -> Result<f64, InputError> {
                    s.trim()
                        .parse::<f64>()
                        .ok()
                        .filter(|v| v.is_finite())
                        .ok_or_else(|| bad(format!("'{text}': '{s}' is not a finite number")))
                };
                let (lo, hi) = (num(lo)?, num(hi)?);
                if !(lo < hi) {
                    return Err(bad(format!(
                        "'{text}': the lower bound must be below the upper"
                    )));
                }
                (Some(lo), Some(hi))
            }
        };
        let positive = base.is_none_or(|b| b > 0.0) && lower.is_none_or(|l| l > 0.0);
        let start = match (base, lower, upper) {
            (Some(b), _, _) => b,
            (None, Some(lo), Some(hi)) if positive => (lo * hi).sqrt(),
            (None, Some(lo), Some(hi)) => 0.5 * (lo + hi),
            _ => {
                return Err(bad(format!(
                    "'{path}' is not in the phantom files (a setting left at its default, or a misspelt path): write its starting value there, or give bounds NAME=LO..HI"
                )))
            }
        };
        if let (Some(lo), Some(hi)) = (lower, upper) {
            if !(lo..=hi).contains(&start) {
                return Err(bad(format!(
                    "'{path}': its value in the phantom, {start}, is outside the bounds {lo}..{hi}"
                )));
            }
        }
        let log = positive && start > 0.0;
        Ok(ParamSpec {
            path: path.to_string(),
            lower,
            upper,
            log,
            start,
        })
    }

    /// Check, before any simulation, that this parameter can be written into the phantom
    /// documents `docs` (read from `files`; those a fit writes it in) at its start value and at both bounds: each value
    /// is set at the path and the document read again by the phantom reader, so the field's
    /// own accepted range applies (a negative diffusivity, a surface tension above 1 N/m), as
    /// `sensitivity` checks its levels. A range is an interval, so a value between accepted
    /// bounds is accepted too. Refused (exit 2) naming `<command line>` and `--param`, the value
    /// and the phantom's reason. `given` is the parameter as written, for the message.
    pub fn check_settable(
        &self,
        given: &str,
        docs: &[toml::Table],
        files: &[&std::path::Path],
    ) -> Result<(), InputError> {
        let mut values = vec![("its start value", self.start)];
        if let Some(lo) = self.lower {
            values.push(("the lower bound", lo));
        }
        if let Some(hi) = self.upper {
            values.push(("the upper bound", hi));
        }
        for (what, v) in values {
            if let Some((i, reason)) = refused_value(docs, files, &self.path, v) {
                return Err(InputError::new(format!(
                    "'{given}': {what}, {}, is not accepted in {}: {reason}",
                    crate::error::num(v),
                    files[i].display()
                ))
                .in_file("<command line>")
                .field("--param"));
            }
        }
        Ok(())
    }

    /// A positive parameter without bounds fitted in log space.
    pub fn positive(path: impl Into<String>, start: f64) -> ParamSpec {
        ParamSpec {
            path: path.into(),
            lower: None,
            upper: None,
            log: true,
            start,
        }
    }

    /// Internal (unbounded) coordinate of value `x`.
    pub fn to_internal(&self, x: f64) -> f64 {
        let v = if self.log { x.ln() } else { x };
        match self.bounds_v() {
            Some((a, b)) => {
                let f = ((v - a) / (b - a)).clamp(1e-9, 1.0 - 1e-9);
                (f / (1.0 - f)).ln()
            }
            None => v,
        }
    }

    /// Value of internal coordinate `u`.
    pub fn from_internal(&self, u: f64) -> f64 {
        let v = self.v_of(u);
        if self.log {
            v.exp()
        } else {
            v
        }
    }

    /// The fitting-space coordinate v (ln x for log parameters, x otherwise) of internal `u`.
    pub fn v_of(&self, u: f64) -> f64 {
        match self.bounds_v() {
            Some((a, b)) => a + (b - a) / (1.0 + (-u).exp()),
            None => u,
        }
    }

    /// dv/du at internal `u` (1 without bounds).
    pub fn dv_du(&self, u: f64) -> f64 {
        match self.bounds_v() {
            Some((a, b)) => {
                let s = 1.0 / (1.0 + (-u).exp());
                (b - a) * s * (1.0 - s)
            }
            None => 1.0,
        }
    }

    /// Bounds in v space (ln for log parameters).
    fn bounds_v(&self) -> Option<(f64, f64)> {
        match (self.lower, self.upper) {
            (Some(lo), Some(hi)) if self.log => Some((lo.ln(), hi.ln())),
            (Some(lo), Some(hi)) => Some((lo, hi)),
            _ => None,
        }
    }

    /// Whether `x` sits within 0.1 % (of the v-range) of a bound.
    pub fn at_bound(&self, x: f64) -> bool {
        match self.bounds_v() {
            Some((a, b)) => {
                let v = if self.log { x.ln() } else { x };
                let f = (v - a) / (b - a);
                !(0.001..=0.999).contains(&f)
            }
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_in_a_readers_words() {
        assert_eq!(label("material.surface_tension"), "γ (N/m)");
        assert_eq!(label("gases.n2.ostwald"), "L_N2");
        assert_eq!(label("gases.o2.diffusivity"), "D_O2 (m²/s)");
        assert_eq!(label("scale:gases.*.diffusivity"), "D factor");
        assert_eq!(
            with_value("material.elasticity.shear_modulus", "1e6"),
            "μ = 1e6 Pa"
        );
        // a path it does not know stays itself
        assert_eq!(label("geometry.grid_step_m"), "geometry.grid_step_m");
    }

    /// The terms of an elasticity `sum` (`material.elasticity.terms.N.FIELD`): numbered as in
    /// the file, or, in a model that added terms after the phantom's own, "the added" one
    /// (reference: the symbols of src/phantom/elasticity.rs's fields, μ Pa, K Pa, M Pa/m³).
    #[test]
    fn elasticity_terms_in_a_readers_words() {
        let mu = "material.elasticity.terms.1.shear_modulus";
        let m = "material.elasticity.terms.1.bulk_modulus_per_volume";
        assert_eq!(label(mu), "μ of elasticity term 1 (Pa)");
        assert_eq!(label_in(mu, Some(1)), "μ of the added elasticity term (Pa)");
        assert_eq!(
            with_value_in(mu, "21923", Some(1)),
            "μ of the added elasticity term = 21923 Pa"
        );
        assert_eq!(
            label_in(m, Some(1)),
            "M of the added elasticity term (Pa/m³)"
        );
        assert_eq!(
            label_in("material.elasticity.terms.3.bulk_modulus", Some(2)),
            "K of the second added elasticity term (Pa)"
        );
        assert_eq!(
            label_in("material.elasticity.terms.0.shear_modulus", Some(1)),
            "μ of the phantom's elasticity term 0 (Pa)"
        );
        assert_eq!(
            label("material.elasticity.bulk_modulus_per_volume"),
            "M (Pa/m³)"
        );
        assert_eq!(label("material.surface.exponent"), "a (surface exponent)");
        // a field that is not a modulus, or a malformed index, stays itself
        for raw in [
            "material.elasticity.terms.1.law_weight",
            "material.elasticity.terms.x.shear_modulus",
        ] {
            assert_eq!(label_in(raw, Some(1)), raw);
        }
        // the phantom's own terms: a sum's list, or 1 for any other law or none
        let sum: toml::Table = "[material.elasticity]\nlaw = \"sum\"\nterms = [{ law = \"hyperelastic\", shear_modulus = 40.0 }, { law = \"bulk-modulus\", bulk_modulus_per_volume = 1e16 }]\n"
            .parse()
            .unwrap();
        assert_eq!(own_elasticity_terms(&sum), 2);
        let one: toml::Table =
            "[material.elasticity]\nlaw = \"hyperelastic\"\nshear_modulus = 40.0\n"
                .parse()
                .unwrap();
        assert_eq!(own_elasticity_terms(&one), 1);
        assert_eq!(own_elasticity_terms(&toml::Table::new()), 1);
    }

    fn doc() -> toml::Table {
        "[gases.n2]\ndiffusivity = 2.5e-9\nostwald = 0.014\n[[bubbles]]\nposition_m = [1.0, 2.0, 3.0]\ninitial_radius_m = 1e-4\n"
            .parse()
            .unwrap()
    }

    /// A path that holds something other than a number is named with what it holds and the
    /// file (the first document that has it); a number, an absent path (a setting at its
    /// default) and a `scale:` pattern are not refused here.
    #[test]
    fn a_path_that_holds_no_number_says_what_it_holds() {
        let d: toml::Table = "name = \"x\"\n[geometry]\nsize_m = [1e-3, 2e-3]\n[material.elasticity]\nlaw = \"none\"\n[[bubbles]]\ninitial_radius_m = 1e-4\n"
            .parse()
            .unwrap();
        let docs = [toml::Table::new(), d];
        let files = [
            std::path::Path::new("a.toml"),
            std::path::Path::new("b.toml"),
        ];
        let why = |p: &str| not_a_number(&docs, &files, p);
        for (p, holds) in [
            ("material.elasticity.law", "holds a string in b.toml"),
            ("name", "holds a string in b.toml"),
            ("geometry.size_m", "holds a list of numbers in b.toml"),
            ("bubbles", "holds a list in b.toml"),
            ("material", "holds a table in b.toml"),
        ] {
            let m = why(p).unwrap_or_else(|| panic!("{p}"));
            assert!(m.contains(&format!("'{p}' {holds}, not a number")), "{m}");
        }
        assert!(why("geometry.size_m")
            .unwrap()
            .contains("'geometry.size_m.0'"));
        for ok in [
            "geometry.size_m.1",
            "bubbles.0.initial_radius_m",
            "perfusion.rate_per_s",
            "scale:gases.*.ostwald",
        ] {
            assert_eq!(why(ok), None, "{ok}");
        }
    }

    #[test]
    fn get_and_set_by_path() {
        let mut d = doc();
        assert_eq!(get(&d, "gases.n2.diffusivity"), Some(2.5e-9));
        assert_eq!(get(&d, "bubbles.0.position_m.1"), Some(2.0));
        set(&mut d, "gases.n2.diffusivity", 1e-9).unwrap();
        assert_eq!(get(&d, "gases.n2.diffusivity"), Some(1e-9));
        // a setting at its default is added, with the tables on the way
        set(&mut d, "perfusion.rate_per_s", 2e-3).unwrap();
        assert_eq!(get(&d, "perfusion.rate_per_s"), Some(2e-3));
        set(&mut d, "bubbles.0.position_m.2", 4.0).unwrap();
        assert_eq!(get(&d, "bubbles.0.position_m.2"), Some(4.0));
        assert!(set(&mut d, "bubbles.3.initial_radius_m", 1.0).is_err());
        assert!(set(&mut d, "gases.n2", 1.0).is_err());
        assert!(set(&mut d, "gases..x", 1.0).is_err());
        set(&mut d, "gases.o2.diffusivity", 2e-9).unwrap();
        set(&mut d, "gases.o2.ostwald", 0.027).unwrap();
        let mut e = expand(&d, "gases.*.diffusivity");
        e.sort();
        assert_eq!(e, vec!["gases.n2.diffusivity", "gases.o2.diffusivity"]);
        apply(&mut d, "scale:gases.*.diffusivity", 2.0).unwrap();
        assert_eq!(get(&d, "gases.n2.diffusivity"), Some(2e-9));
        assert_eq!(get(&d, "gases.o2.diffusivity"), Some(4e-9));
        assert!(apply(&mut d, "scale:gases.*.nothing", 2.0).is_err());
    }

    /// Bounds are checked by the phantom reader's own ranges (D 1e-14 ..= 1e-6 m²/s, γ 0 ..= 1
    /// N/m), at both ends, and refused naming `<command line>` and `--param`.
    #[test]
    fn bounds_outside_the_fields_range_are_refused_on_the_command_line() {
        let doc: toml::Table = "[geometry]\nshape = \"box\"\nsize_m = [2e-3, 2e-3, 2e-3]\ngrid_step_m = 2e-4\n[material]\nsurface_tension = 0.07\n[gases.n2]\ndiffusivity = 2.5e-9\nostwald = 0.014\n[gases.o2]\ndiffusivity = 2.5e-9\nostwald = 0.027\n[[bubbles]]\nposition_m = [1e-3, 1e-3, 1e-3]\ninitial_radius_m = 6e-5\n"
            .parse()
            .unwrap();
        let file = std::path::Path::new("p.toml");
        let check = |given: &str| {
            let path = given.split_once('=').map_or(given, |x| x.0);
            let base = if path.starts_with(SCALE_PREFIX) {
                Some(1.0)
            } else {
                get(&doc, path)
            };
            ParamSpec::parse(given, base)?.check_settable(
                given,
                std::slice::from_ref(&doc),
                &[file],
            )
        };
        for ok in [
            "gases.n2.diffusivity=1e-14..1e-6",
            "material.surface_tension=0..1",
            "scale:gases.*.diffusivity=0.1..10",
            "gases.n2.diffusivity",
        ] {
            check(ok).unwrap_or_else(|e| panic!("{ok}: {e}"));
        }
        for (bad, which) in [
            ("gases.n2.diffusivity=-1..1", "lower"),
            ("gases.n2.diffusivity=1e-9..1e-5", "upper"),
            ("material.surface_tension=0..2", "upper"),
            ("material.surface_tension=-0.1..0.5", "lower"),
            ("scale:gases.*.diffusivity=0..2", "lower"),
        ] {
            let e = check(bad).unwrap_err();
            assert_eq!(
                e.file.as_deref(),
                Some(std::path::Path::new("<command line>")),
                "{e}"
            );
            assert_eq!(e.field.as_deref(), Some("--param"), "{e}");
            assert!(
                e.message.contains(&format!("the {which} bound")),
                "{bad}: {e}"
            );
        }
    }

    #[test]
    fn transforms_round_trip_inside_bounds() {
        let p = ParamSpec::parse("gases.n2.diffusivity=1e-10..5e-9", Some(2.5e-9)).unwrap();
        assert!(p.log);
        for x in [1.1e-10, 2.5e-9, 4.9e-9] {
            let back = p.from_internal(p.to_internal(x));
            assert!((back / x - 1.0).abs() < 1e-9, "{x} -> {back}");
        }
        let q = ParamSpec::parse("material.surface_tension=-1..1", None).unwrap();
        assert!(!q.log);
        assert_eq!(q.start, 0.0);
        assert!(ParamSpec::parse("perfusion.rate_per_s", None).is_err());
        assert!(ParamSpec::parse("a.b=3..1", Some(2.0)).is_err());
    }
}
