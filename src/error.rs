//! Errors for bad input. Every message names where the problem is (file, line, field)
//! and, where there is one, the fix. The binary maps [`Error::Input`] to exit code 2.

use std::path::{Path, PathBuf};

/// The library's error type.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Bad input from a person or a file: exit code 2.
    #[error(transparent)]
    Input(#[from] InputError),
    /// The solver found itself unhealthy (NaN, lost gas, unstable settings).
    #[error("solver: {0}")]
    Solver(String),
    /// Stopped on request (Ctrl-C) before the work was complete; nothing half-done was
    /// written. The binary exits 130.
    #[error("interrupted: {0}")]
    Interrupted(String),
    /// An I/O failure while writing outputs.
    #[error("{path}: {error}")]
    Io {
        /// The file or folder involved.
        path: PathBuf,
        /// The underlying error: in the message, and deliberately not chained as its source
        /// (the binary prints the chain, which would repeat the OS text).
        error: std::io::Error,
    },
}

impl Error {
    /// An [`Error::Io`] at `path`.
    pub fn io(path: &Path, error: std::io::Error) -> Error {
        Error::Io {
            path: path.to_path_buf(),
            error,
        }
    }

    /// [`Error::io`] at `path`, for `map_err`.
    pub fn io_at(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
        move |error| Error::io(path, error)
    }
}

/// A bad-input error with its location.
#[derive(Debug, Clone, PartialEq)]
pub struct InputError {
    /// The file (or `<command line>`).
    pub file: Option<PathBuf>,
    /// 1-based line, where known.
    pub line: Option<usize>,
    /// The field or column, where known.
    pub field: Option<String>,
    /// What is wrong and how to fix it.
    pub message: String,
}

impl InputError {
    /// An error with only a message.
    pub fn new(message: impl Into<String>) -> Self {
        InputError {
            file: None,
            line: None,
            field: None,
            message: message.into(),
        }
    }
    /// Attach the file.
    pub fn in_file(mut self, file: impl AsRef<Path>) -> Self {
        self.file = Some(file.as_ref().to_path_buf());
        self
    }
    /// Attach the file unless the error already names one (an option's error names
    /// `<command line>`, not the file being read when it was found).
    pub fn or_in_file(self, file: impl AsRef<Path>) -> Self {
        if self.file.is_some() {
            self
        } else {
            self.in_file(file)
        }
    }
    /// Attach the 1-based line.
    pub fn at_line(mut self, line: usize) -> Self {
        self.line = Some(line);
        self
    }
    /// Attach the field name.
    pub fn field(mut self, field: impl Into<String>) -> Self {
        self.field = Some(field.into());
        self
    }
}

impl std::fmt::Display for InputError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match (&self.file, self.line) {
            (Some(p), Some(l)) => write!(f, "{}:{}: ", p.display(), l)?,
            (Some(p), None) => write!(f, "{}: ", p.display())?,
            (None, Some(l)) => write!(f, "line {l}: ")?,
            (None, None) => {}
        }
        if let Some(field) = &self.field {
            write!(f, "field '{field}': ")?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for InputError {}

/// Convert a `toml` parse error into an [`InputError`] with file, line and field.
pub fn toml_error(path: &Path, text: &str, err: &toml::de::Error) -> InputError {
    // Count newlines before the span: `lines().count()` would be one short when the span
    // starts a line (the usual case for an unknown key).
    let line = err
        .span()
        .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
    let msg = serde_message(err.message());
    // serde names the offending key of an unknown or missing field; surface it as the field
    let field = named_key(&msg).map(str::to_string);
    let mut e = InputError::new(msg).in_file(path);
    if let Some(l) = line {
        e = e.at_line(l);
    }
    if let Some(f) = field {
        e = e.field(f);
    }
    e
}

/// A serde message as a file's reader shows it: without the code's type names
/// ([`without_type_names`]) and with an absurd number as [`num`] writes it (serde writes the
/// float 1e308 of `invalid type: floating point `1e308`` in 309 digits).
pub(crate) fn serde_message(msg: &str) -> String {
    let msg = without_type_names(msg.trim());
    let mut parts: Vec<String> = msg.split('`').map(str::to_string).collect();
    // the odd parts are the quoted ones
    for quoted in parts.iter_mut().skip(1).step_by(2) {
        if quoted.len() > 20 {
            if let Ok(v) = quoted.parse::<f64>() {
                *quoted = num(v);
            }
        }
    }
    parts.join("`")
}

/// A serde message in the words of the file, not of the code: serde names the Rust type a
/// table is read into (`invalid type: integer `1`, expected struct RawStop`), which a user never
/// wrote; every such type is a TOML table, so the message says so.
fn without_type_names(msg: &str) -> String {
    let mut out = String::with_capacity(msg.len());
    let mut rest = msg;
    while let Some(i) = rest.find("expected struct ") {
        out.push_str(&rest[..i]);
        out.push_str("expected a table");
        let after = &rest[i + "expected struct ".len()..];
        let name_len = after
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(after.len());
        rest = &after[name_len..];
    }
    out.push_str(rest);
    out
}

/// [`toml_error`] with the field named by its dotted path, for serde's type and length errors
/// (`invalid type: string "200e-6", expected f64` becomes field `geometry.grid_step_m`), an
/// unknown key in a table (`material.bogus_key`, not `bogus_key`) and a missing one
/// ([`toml_field_at`]). [`toml_error`] itself is unchanged for the readers that do not use this.
pub fn toml_error_with_path(path: &Path, text: &str, err: &toml::de::Error) -> InputError {
    let e = toml_error(path, text, err);
    match err
        .span()
        .and_then(|s| toml_field_at(text, s.start, err.message()))
    {
        Some(f) => e.field(f),
        None => e,
    }
}

/// The dotted path of the key a TOML deserialisation error at byte `offset` is about: the
/// table of the last `[table]` / `[[table]]` header at or before it, then the key the message
/// names (`unknown field `x``, `missing field `x``) or else the key of the nearest `key =`
/// before the offset within that table (the value the error points at). `None` when no key
/// can be told (e.g. an error before any key).
pub fn toml_field_at(text: &str, offset: usize, message: &str) -> Option<String> {
    let mut offset = offset.min(text.len());
    while !text.is_char_boundary(offset) {
        offset -= 1;
    }
    let line_end = text[offset..].find('\n').map_or(text.len(), |i| offset + i);
    // the table: the last header line up to the error's own line
    let mut table: Vec<String> = Vec::new();
    let mut body_start = 0;
    let mut pos = 0;
    for line in text[..line_end].split_inclusive('\n') {
        if let Some(t) = toml_header(line) {
            table = t;
            body_start = pos + line.len();
        }
        pos += line.len();
    }
    let named = named_key(message).map(|k| vec![k.to_string()]);
    // an unknown table (`[bogus]`, `[conventions.extra]`): the error is on its header, which
    // already ends in the key serde names
    let line_start = text[..offset].rfind('\n').map_or(0, |i| i + 1);
    if toml_header(&text[line_start..line_end]).is_some()
        && named.as_ref().and_then(|k| k.first()) == table.last()
    {
        return Some(table.join("."));
    }
    let key = named.or_else(|| {
        let body = &text[body_start.min(offset)..offset];
        // the nearest `key =` before the value, skipping comments
        body.lines().rev().find_map(|l| {
            let l = l.split('#').next().unwrap_or("");
            let (lhs, _) = l.rsplit_once('=')?;
            let k = lhs.rsplit(['{', ',']).next()?.trim();
            toml_key_path(k)
        })
    });
    let path: Vec<String> = table.into_iter().chain(key.unwrap_or_default()).collect();
    (!path.is_empty()).then(|| path.join("."))
}

/// The key serde names in its message (`unknown field `x`, expected ...`, `missing field `x``).
fn named_key(message: &str) -> Option<&str> {
    ["unknown field `", "missing field `"]
        .iter()
        .find_map(|p| message.trim().strip_prefix(p))
        .and_then(|r| r.split_once('`'))
        .map(|(k, _)| k)
}

/// Deserialize a table read earlier from a file (an algorithm's `[params]`, a criterion's
/// entry, kept as a `toml` value until its kind was known) into its raw struct. The error
/// starts with the key it is about, dotted within the table (`gf_low: invalid type: string
/// "30", expected f64`), as the registries' builders start theirs: serde names the key of an
/// unknown or missing field, but a value of the wrong type in a parsed table has no place, so
/// the table is written back as TOML text and read again, and the key is the one at the error's
/// span there ([`toml_field_at`]). Without a key (the value is not a table) the message is
/// serde's alone.
pub fn table_into<T: serde::de::DeserializeOwned>(table: toml::Value) -> Result<T, String> {
    table_into_keyed(table).map_err(|(key, msg)| match key {
        Some(k) => format!("{k}: {msg}"),
        None => msg,
    })
}

/// A builder's message that starts with the key it is about, `key: message` ([`table_into`]):
/// (the key, dotted within its table, with `[i]` indices; the message). `None` for a message
/// that names no key (its start holds a space or other punctuation).
pub fn split_keyed(msg: &str) -> Option<(&str, &str)> {
    let (k, rest) = msg.split_once(": ")?;
    let key_like = !k.is_empty()
        && k.chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | '[' | ']'));
    key_like.then_some((k, rest))
}

/// [`table_into`] with the key apart: (the key dotted within the table, if one can be told;
/// the message, `serde_message`'s words).
pub fn table_into_keyed<T: serde::de::DeserializeOwned>(
    table: toml::Value,
) -> Result<T, (Option<String>, String)> {
    let err = match T::deserialize(table.clone()) {
        Ok(v) => return Ok(v),
        Err(e) => e,
    };
    if let Some(k) = named_key(err.message()) {
        return Err((Some(k.to_string()), serde_message(err.message())));
    }
    // the same table as text: the same keys in the same order, hence the same first error
    let located = toml::to_string(&table).ok().and_then(|text| {
        let again = toml::from_str::<T>(&text).err()?;
        let key = toml_field_at(&text, again.span()?.start, again.message())?;
        Some((Some(key), serde_message(again.message())))
    });
    Err(located.unwrap_or((None, serde_message(err.message()))))
}

/// The table path of a `[a.b]` or `[[a]]` header line, `None` for any other line.
fn toml_header(line: &str) -> Option<Vec<String>> {
    let t = line.split('#').next().unwrap_or("").trim();
    let inner = t.strip_prefix('[')?.strip_suffix(']')?;
    let inner = inner
        .strip_prefix('[')
        .and_then(|i| i.strip_suffix(']'))
        .unwrap_or(inner);
    toml_key_path(inner.trim())
}

/// The parts of a (possibly dotted, possibly quoted) TOML key, `None` if it is not one.
fn toml_key_path(k: &str) -> Option<Vec<String>> {
    let ok = |c: char| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.' | ' ' | '"' | '\'');
    if k.is_empty() || !k.chars().all(ok) {
        return None;
    }
    let parts: Vec<String> = k
        .split('.')
        .map(|p| p.trim().trim_matches(|c| c == '"' || c == '\'').to_string())
        .collect();
    (!parts.iter().any(|p| p.is_empty() || p.contains(' '))).then_some(parts)
}

/// 1-based line of the field `path` (dotted: `gases.o2.diffusivity`) in TOML text, for errors
/// found after parsing: the line of its key in its own table — in the `nth` table (0-based) of
/// the first array of tables on the path, such as `[[bubbles]]` (0 for a plain table; a number
/// in the path, `terms.1.shear_modulus` or `terms[1].shear_modulus`, indexes an array
/// itself) — or of the table's header when the path names a table. Read with `toml_edit`'s spans, so a key of the same name in
/// another table (`[gases.n2] diffusivity` for `gases.o2.diffusivity`), in a comment or in a
/// string is never it. `None` when the text does not parse or the path is not in it.
pub fn line_of_field(text: &str, path: &str, nth: usize) -> Option<usize> {
    use toml_edit::{Item, TableLike, Value};
    let doc = toml_edit::ImDocument::parse(text).ok()?;
    let mut table: &dyn TableLike = doc.as_table();
    let mut nth = Some(nth);
    // `terms[1]` as the messages write an index: `terms.1`
    let path = path.replace('[', ".").replace(']', "");
    let mut segs = path.split('.').peekable();
    let mut at = None;
    // an index segment (`.1.`) after an array, else the first array of tables' `nth`
    let index = |segs: &mut std::iter::Peekable<std::str::Split<'_, char>>,
                 nth: &mut Option<usize>| {
        match segs.peek().and_then(|s| s.parse::<usize>().ok()) {
            Some(k) => {
                segs.next();
                k
            }
            None => nth.take().unwrap_or(0),
        }
    };
    while let Some(seg) = segs.next() {
        let key_at = table.key(seg).and_then(|k| k.span()).map(|s| s.start);
        let next: Option<&dyn TableLike> = match table.get(seg)? {
            Item::ArrayOfTables(a) => {
                let t = a.get(index(&mut segs, &mut nth))?;
                at = t.span().map(|s| s.start).or(key_at);
                Some(t)
            }
            Item::Table(t) => {
                at = t.span().map(|s| s.start).or(key_at).or(at);
                Some(t)
            }
            Item::Value(Value::InlineTable(t)) => {
                at = key_at.or(at);
                Some(t)
            }
            Item::Value(Value::Array(a)) if segs.peek().is_some() => {
                let v = a.get(index(&mut segs, &mut None))?;
                at = v.span().map(|s| s.start).or(key_at).or(at);
                v.as_inline_table().map(|t| t as &dyn TableLike)
            }
            _ => {
                at = key_at.or(at);
                None
            }
        };
        match next {
            Some(t) => table = t,
            None if segs.peek().is_some() => return None,
            None => {}
        }
    }
    let offset = at?.min(text.len());
    Some(
        text.as_bytes()[..offset]
            .iter()
            .filter(|&&b| b == b'\n')
            .count()
            + 1,
    )
}

/// 1-based line of the first occurrence of `key =` in TOML text, for errors found after parsing.
pub fn line_of_key(text: &str, key: &str) -> Option<usize> {
    text.lines()
        .position(|l| {
            let t = l.trim_start();
            t.starts_with(key) && t[key.len()..].trim_start().starts_with('=')
        })
        .map(|i| i + 1)
}

/// Largest input file read, bytes (1 GiB: far above any profile, phantom, schedule, dive log or
/// measurement file; a larger one is a mistake, such as a device or a wrong path).
pub const MAX_INPUT_BYTES: u64 = 1 << 30;

/// The bytes of an input file named `what` ("the phantom file"): refused (file named) if it is
/// not a regular file — a folder, a device such as /dev/zero, a pipe that may never end — or is
/// larger than [`MAX_INPUT_BYTES`], where reading it would exhaust the memory or hang.
pub fn read_input(path: &Path, what: &str) -> Result<Vec<u8>, InputError> {
    use std::io::Read;
    let cannot =
        |e: std::io::Error| InputError::new(format!("cannot read {what}: {e}")).in_file(path);
    let meta = std::fs::metadata(path).map_err(cannot)?;
    if !meta.is_file() {
        let kind = if meta.is_dir() {
            "a folder"
        } else {
            "not a regular file (a device, pipe or socket)"
        };
        return Err(
            InputError::new(format!("{what} is {kind}; give the path of a file")).in_file(path),
        );
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(InputError::new(format!(
            "{what} is {} bytes, more than the {} an input file may have",
            meta.len(),
            MAX_INPUT_BYTES
        ))
        .in_file(path));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_INPUT_BYTES + 1).read_to_end(&mut bytes))
        .map_err(cannot)?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(InputError::new(format!(
            "{what} grew beyond the {MAX_INPUT_BYTES} bytes an input file may have while it was read"
        ))
        .in_file(path));
    }
    Ok(bytes)
}

/// Read a text file for a reader. A file that cannot be read is named with the I/O error
/// (`cannot read <what>: ...`); one that is not UTF-8 is named with the line of its first
/// invalid byte.
pub fn read_text(path: &Path, what: &str) -> Result<String, InputError> {
    let bytes = read_input(path, what)?;
    String::from_utf8(bytes).map_err(|e| {
        let at = e.utf8_error().valid_up_to();
        let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
        InputError::new(format!(
            "{what} is not UTF-8 text (invalid byte at offset {at}); save it as UTF-8"
        ))
        .in_file(path)
        .at_line(line)
    })
}

/// Number of the last line of `text` (1 for an empty text): where something missing from a
/// file would be added.
pub fn last_line(text: &str) -> usize {
    text.lines().count().max(1)
}

/// An error found after parsing, given a line when it has none: the line of its field
/// ([`line_of_field`], trying the field's parents in turn), else of the leaf `key =` anywhere or
/// the table `[a.b]` / `[[a]]` (again trying the parents), else the last line of the file. Every
/// refusal of a file then names a line.
pub fn ensure_line(e: InputError, text: &str) -> InputError {
    // a command-line option (`--gf`) is not in the file
    if e.line.is_some() || e.field.as_deref().is_some_and(|f| f.starts_with("--")) {
        return e;
    }
    let field_line = e.field.as_deref().and_then(|f| {
        let parts: Vec<&str> = f.split('.').collect();
        let own = (0..parts.len())
            .rev()
            .find_map(|k| line_of_field(text, &parts[..=k].join("."), 0));
        own.or_else(|| {
            (0..parts.len()).rev().find_map(|k| {
                line_of_key(text, parts[k]).or_else(|| {
                    let table = parts[..=k].join(".");
                    text.lines()
                        .position(|l| {
                            let t = l.split('#').next().unwrap_or("").trim();
                            t == format!("[{table}]") || t == format!("[[{table}]]")
                        })
                        .map(|i| i + 1)
                })
            })
        })
    });
    let line = field_line.unwrap_or_else(|| last_line(text));
    e.at_line(line)
}

/// A number for a message: plain when it reads well (-40, 0.07, 2500), else in scientific
/// notation (1e-308, 2.561e-12), so that an absurd value does not print 300 digits.
pub fn num(v: f64) -> String {
    if v == 0.0 || !v.is_finite() || (1e-4..1e7).contains(&v.abs()) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// "`v` `unit` is outside the accepted range `lo` ..= `hi` `unit`" ([`num`]'s numbers; no unit,
/// no space for it).
pub fn outside_range(v: f64, lo: f64, hi: f64, unit: &str) -> String {
    let u = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    format!(
        "{}{u} is outside the accepted range {} ..= {}{u}",
        num(v),
        num(lo),
        num(hi)
    )
}

/// Result alias.
pub type Result<T, E = Error> = std::result::Result<T, E>;

#[cfg(test)]
mod tests {
    use super::*;

    /// The range message with and without a unit: one space between words either way (the
    /// unit-less `nucleation.*` ranges printed "1e308  is outside …" before).
    #[test]
    fn range_messages_have_one_space_with_or_without_a_unit() {
        assert_eq!(
            outside_range(1e308, 1e-3, 1e6, ""),
            "1e308 is outside the accepted range 0.001 ..= 1000000"
        );
        assert_eq!(
            outside_range(-1.0, 1.0, 2e7, "Pa"),
            "-1 Pa is outside the accepted range 1 ..= 2e7 Pa"
        );
    }

    /// Only regular files are read: a folder, a device that never ends (/dev/zero) and a pipe
    /// with no writer (which would block forever) are refused by name, before any read.
    #[test]
    fn only_regular_files_are_read() {
        let dir =
            std::env::temp_dir().join(format!("decophantom-read-input-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("ok.toml");
        std::fs::write(&file, "a = 1\n").unwrap();
        assert_eq!(read_text(&file, "the file").unwrap(), "a = 1\n");
        let e = read_input(&dir, "the phantom file").unwrap_err();
        assert!(e.to_string().contains("is a folder"), "{e}");
        let zero = Path::new("/dev/zero");
        if zero.exists() {
            let e = read_input(zero, "the profile").unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        let fifo = dir.join("pipe.toml");
        let made = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if made {
            let e = read_input(&fifo, "the profile").unwrap_err();
            assert!(e.to_string().contains("not a regular file"), "{e}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn toml_field_paths() {
        let text = "name = \"x\"\n[geometry]\nh = \"2e-4\"\n[[bubbles]]\nposition_m = [1, 2]\n";
        let at = |needle: &str, msg: &str| toml_field_at(text, text.find(needle).unwrap(), msg);
        assert_eq!(at("\"2e-4", "invalid type").as_deref(), Some("geometry.h"));
        assert_eq!(
            at("[1, 2]", "invalid length 2").as_deref(),
            Some("bubbles.position_m")
        );
        assert_eq!(
            at("h =", "unknown field `h`, expected `a`").as_deref(),
            Some("geometry.h")
        );
        assert_eq!(
            at("[geometry]", "missing field `shape`").as_deref(),
            Some("geometry.shape")
        );
        assert_eq!(at("\"x\"", "invalid type").as_deref(), Some("name"));
        // a multi-line array: the key whose value holds the row
        let text = "[p]\npoints = [\n  [0, 0], # t = 0\n  [1, 2, 3],\n]\n";
        let off = text.find("[1, 2, 3]").unwrap();
        assert_eq!(toml_field_at(text, off, "x").as_deref(), Some("p.points"));
        // an unknown table is named once (the session-31 review: `bogus.bogus`)
        let text = "a = 1\n[bogus]\nb = 2\n[c.extra]\n";
        let unknown = |needle: &str, k: &str| {
            toml_field_at(
                text,
                text.find(needle).unwrap(),
                &format!("unknown field `{k}`, expected `a`"),
            )
        };
        assert_eq!(unknown("[bogus]", "bogus").as_deref(), Some("bogus"));
        assert_eq!(unknown("[c.extra]", "extra").as_deref(), Some("c.extra"));
        assert_eq!(unknown("b = 2", "b").as_deref(), Some("bogus.b"));
    }

    /// A key's line in its own table (the `nth` of an array of tables), not at a key of the
    /// same name in another table or in a multi-line string.
    #[test]
    fn field_lines_are_found_in_their_own_table() {
        let text = "d = \"\"\"\ndiffusivity = 1\n\"\"\"\n[gases.n2]\ndiffusivity = 2\n[gases.o2]\n\
                    diffusivity = 3\n[[b]]\nr = 1\n[[b]]\nr = 2\n[gases]\nhe.diffusivity = 4\n";
        let at = |path: &str, nth: usize| line_of_field(text, path, nth);
        assert_eq!(at("gases.n2.diffusivity", 0), Some(5));
        assert_eq!(at("gases.o2.diffusivity", 0), Some(7));
        assert_eq!(at("gases.he.diffusivity", 0), Some(13));
        assert_eq!(at("gases.o2", 0), Some(6));
        assert_eq!(
            (at("b.r", 0), at("b.r", 1), at("b", 1)),
            (Some(9), Some(11), Some(10))
        );
        assert_eq!((at("diffusivity", 0), at("b.r", 2)), (None, None));
        // ensure_line: the field's own line, not the first key of that name
        let e = ensure_line(InputError::new("x").field("gases.o2.diffusivity"), text);
        assert_eq!(e.line, Some(7));
        // triple quotes in a comment and in one-line strings (the session-31 review: a line
        // scanner counting them lost its place and named n2's line for o2's key), an escaped
        // quote in a multi-line string, CRLF line ends, an array of tables inside a table and
        // a list indexed in the path
        let text = r#"# strings may use """ quotes
name = "it's '''"
note = """a \""" b"""
[gases.n2]
diffusivity = 2
[gases.o2]
diffusivity = 3
[[m.terms]]
mu = 1
[[m.terms]]
mu = 2
[g]
size = [1,
 2]
"#
        .replace('\n', "\r\n");
        let at = |path: &str, nth: usize| line_of_field(&text, path, nth);
        assert_eq!(at("gases.o2.diffusivity", 0), Some(7));
        assert_eq!(
            (
                at("m.terms.1.mu", 0),
                at("m.terms.mu", 1),
                at("m.terms[1].mu", 0)
            ),
            (Some(11), Some(11), Some(11))
        );
        assert_eq!((at("g.size.1", 0), at("g.size", 0)), (Some(14), Some(13)));
        assert_eq!(at("name.x", 0), None);
    }

    /// serde writes the float 1e308 in 309 digits; a reader sees it as written.
    #[test]
    fn serde_messages_write_absurd_numbers_short() {
        let big = format!("{}", 1e308);
        assert!(big.len() > 300);
        assert_eq!(
            serde_message(&format!(
                "invalid type: floating point `{big}`, expected u64"
            )),
            "invalid type: floating point `1e308`, expected u64"
        );
        assert_eq!(
            serde_message("invalid value: integer `-1`, expected u64"),
            "invalid value: integer `-1`, expected u64"
        );
    }

    /// The binary prints an error with its chain (`{:#}`): an I/O error's OS text once
    /// (twice before session 29, as the message's and again as its source's).
    #[test]
    fn an_io_error_prints_its_os_text_once() {
        let e = Error::io(Path::new("out/x.csv"), std::io::Error::other("disk full"));
        assert_eq!(
            format!("{:#}", anyhow::Error::from(e)),
            "out/x.csv: disk full"
        );
    }

    /// A table given as a number: the message names a table, not the Rust type it is read
    /// into (`RawStop` leaked into a schedule file's errors before session 29).
    #[test]
    fn type_names_do_not_reach_the_message() {
        #[derive(Debug, serde::Deserialize)]
        #[allow(dead_code)]
        struct RawInner {
            a: f64,
        }
        #[derive(Debug, serde::Deserialize)]
        #[allow(dead_code)]
        struct RawOuter {
            inner: Vec<RawInner>,
        }
        let text = "inner = [1]\n";
        let err = toml::from_str::<RawOuter>(text).unwrap_err();
        assert!(err.message().contains("RawInner"), "{}", err.message());
        let e = toml_error(Path::new("f.toml"), text, &err).to_string();
        assert_eq!(
            e, "f.toml:1: invalid type: integer `1`, expected a table",
            "{e}"
        );
        assert_eq!(
            without_type_names("expected struct A_1, or expected struct B."),
            "expected a table, or expected a table."
        );
    }

    /// serde names the key of an unknown field and of a missing one; both become the error's
    /// field, at the line of the table that lacks it or holds it.
    #[test]
    fn unknown_and_missing_fields_are_named() {
        #[derive(Debug, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct RawEntry {
            name: String,
            phantom: String,
        }
        #[derive(Debug, serde::Deserialize)]
        #[allow(dead_code)]
        struct RawList {
            entry: Vec<RawEntry>,
        }
        for (text, want) in [
            (
                "[[entry]]\nname = \"a\"\nphantom = \"p\"\n\n[[entry]]\nname = \"b\"\n",
                "f.toml:5: field 'phantom': missing field `phantom`",
            ),
            (
                "[[entry]]\nname = \"a\"\nphantom = \"p\"\nphantm = \"q\"\n",
                "f.toml:4: field 'phantm': unknown field `phantm`, expected `name` or `phantom`",
            ),
        ] {
            let err = toml::from_str::<RawList>(text).unwrap_err();
            let e = toml_error(Path::new("f.toml"), text, &err).to_string();
            assert_eq!(e, want);
        }
    }
}
