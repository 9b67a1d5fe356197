//! What every fuzz target checks, the properties of `tests/integration/mutants.rs`: a reader
//! never panics (libFuzzer reports a panic as a crash), returns within libFuzzer's
//! `-timeout`, and when it refuses its input names the file and a line.

use decophantom::error::InputError;
use std::path::Path;

/// The name the input is given in messages.
pub fn path(ext: &str) -> std::path::PathBuf {
    std::path::PathBuf::from(format!("fuzz.{ext}"))
}

/// Assert that a refusal names `path` and a line; `unlined` are message fragments of known
/// refusals without one (the criteria reader's empty list).
pub fn check<T>(r: Result<T, InputError>, path: &Path, unlined: &[&str]) {
    if let Err(e) = r {
        assert_eq!(
            e.file.as_deref(),
            Some(path),
            "refused without the file: {e}"
        );
        assert!(
            e.line.is_some() || unlined.iter().any(|m| e.message.contains(m)),
            "refused without a line: {e}"
        );
    }
}

/// A schedule's pressure history, its refusal named in `path`.
pub fn history(
    s: Result<decophantom::algorithm::Schedule, InputError>,
    path: &Path,
) -> Result<(), InputError> {
    s?.to_pressure_history()
        .map(|_| ())
        .map_err(|m| InputError::new(m).in_file(path))
}
