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
    #[error("{path}: {source}")]
    Io {
        /// The file or folder involved.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
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
    let msg = err.message().trim().to_string();
    // serde names the offending key as "unknown field `x`"; surface it as the field.
    let field = msg
        .strip_prefix("unknown field `")
        .and_then(|r| r.split_once('`'))
        .map(|(f, _)| f.to_string());
    let mut e = InputError::new(msg).in_file(path);
    if let Some(l) = line {
        e = e.at_line(l);
    }
    if let Some(f) = field {
        e = e.field(f);
    }
    e
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

/// Read a text file for a reader. A file that cannot be read is named with the I/O error
/// (`cannot read <what>: ...`); one that is not UTF-8 is named with the line of its first
/// invalid byte.
pub fn read_text(path: &Path, what: &str) -> Result<String, InputError> {
    let bytes = std::fs::read(path)
        .map_err(|e| InputError::new(format!("cannot read {what}: {e}")).in_file(path))?;
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

/// An error found after parsing, given a line when it has none: the line of its field's key
/// (the leaf `key =`, else the table `[a.b]` / `[[a]]`, trying the field's parents in turn),
/// else the last line of the file. Every refusal of a file then names a line.
pub fn ensure_line(e: InputError, text: &str) -> InputError {
    // a command-line option (`--gf`) is not in the file
    if e.line.is_some() || e.field.as_deref().is_some_and(|f| f.starts_with("--")) {
        return e;
    }
    let field_line = e.field.as_deref().and_then(|f| {
        let parts: Vec<&str> = f.split('.').collect();
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

/// Result alias.
pub type Result<T, E = Error> = std::result::Result<T, E>;
