//! Output folders written whole or not at all.
//!
//! An [`OutputSet`] collects files (relative path, bytes) in memory. [`OutputSet::commit`]
//! writes them into a fresh staging folder beside the target (`.<name>.staging-…`), flushes
//! them to disk, and only then swaps the staging folder into place with renames:
//!
//! - **The whole folder is replaced.** After a commit the folder holds exactly this set (plus
//!   the marker file [`MARKER`]); files of an earlier run that are not in the new set are gone,
//!   so a report never mixes two runs.
//! - **Only our own folders are replaced.** An existing target must be empty or carry the
//!   marker that an earlier commit left; any other existing folder is refused before anything
//!   is written (so `--out ~` cannot wipe a home directory).
//! - **On any error nothing half-written remains**: the staging folder is removed and the
//!   target is left exactly as it was (if the final swap fails, the old folder is renamed back).
//!
//! Between the two renames of a replacement the target name is briefly absent; a reader
//! never sees a partial folder.

use std::path::{Component, Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::error::{Error, InputError};

/// Name of the marker file that identifies a folder written by [`OutputSet::commit`].
pub const MARKER: &str = ".decophantom-output";

/// Files to be written together.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct OutputSet {
    files: Vec<(PathBuf, Vec<u8>)>,
}

/// Distinguishes staging folders of several commits in one process.
static COUNTER: AtomicUsize = AtomicUsize::new(0);

fn io_err(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl OutputSet {
    /// An empty set.
    pub fn new() -> Self {
        Self::default()
    }

    /// Add a file at `rel` (relative, `/`-separated, no `..`). Checked at [`commit`](Self::commit).
    pub fn add(&mut self, rel: impl Into<PathBuf>, bytes: impl Into<Vec<u8>>) {
        self.files.push((rel.into(), bytes.into()));
    }

    /// The relative paths, in the order added.
    pub fn paths(&self) -> Vec<&Path> {
        self.files.iter().map(|(p, _)| p.as_path()).collect()
    }

    /// Number of files.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// True if no file was added.
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// The bytes added at `rel`, if any.
    pub fn get(&self, rel: impl AsRef<Path>) -> Option<&[u8]> {
        self.files
            .iter()
            .find(|(p, _)| p == rel.as_ref())
            .map(|(_, b)| b.as_slice())
    }

    /// Add every file of `other` under the folder `prefix` (relative, `/`-separated).
    pub fn nest(&mut self, prefix: impl AsRef<Path>, other: OutputSet) {
        for (p, b) in other.files {
            self.files.push((prefix.as_ref().join(p), b));
        }
    }

    /// Check the relative paths: no absolute paths, `..`, empty names, duplicates, the marker
    /// name, or a path that is both a file and a folder of another.
    fn check_paths(&self) -> Result<(), InputError> {
        let bad = |p: &Path, why: &str| {
            InputError::new(format!("output path '{}' {why}", p.display())).field("output")
        };
        for (p, _) in &self.files {
            if p.as_os_str().is_empty() {
                return Err(bad(p, "is empty"));
            }
            if !p.components().all(|c| matches!(c, Component::Normal(_))) {
                return Err(bad(p, "must be relative, without '..', '.' or a root"));
            }
            if p == Path::new(MARKER) {
                return Err(bad(p, "is reserved for the output marker"));
            }
        }
        for (i, (a, _)) in self.files.iter().enumerate() {
            for (b, _) in &self.files[i + 1..] {
                if a == b {
                    return Err(bad(a, "is added twice"));
                }
                if b.starts_with(a) || a.starts_with(b) {
                    return Err(bad(a, "is both a file and a folder of another output"));
                }
            }
        }
        Ok(())
    }

    /// Write the set as the whole content of `dir` (see the module documentation).
    pub fn commit(&self, dir: impl AsRef<Path>) -> Result<(), Error> {
        self.check_paths()?;
        let dir = dir.as_ref();
        let name = dir
            .file_name()
            .ok_or_else(|| {
                InputError::new(format!(
                    "output folder '{}' has no name; give a folder such as reports/run1",
                    dir.display()
                ))
                .field("--out")
            })?
            .to_string_lossy()
            .into_owned();
        let parent = match dir.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let exists = match std::fs::symlink_metadata(dir) {
            Ok(m) if m.is_dir() => true,
            Ok(_) => {
                return Err(InputError::new(format!(
                    "'{}' exists and is not a folder; choose another output folder",
                    dir.display()
                ))
                .field("--out")
                .into())
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => false,
            Err(e) => return Err(io_err(dir, e)),
        };
        if exists && !is_ours_or_empty(dir)? {
            return Err(InputError::new(format!(
                "'{}' exists and was not written by decophantom (no {MARKER} file); choose a new folder or empty this one",
                dir.display()
            ))
            .field("--out")
            .into());
        }
        std::fs::create_dir_all(&parent).map_err(|e| io_err(&parent, e))?;
        let tag = format!(
            "{}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        );
        let staging = parent.join(format!(".{name}.staging-{tag}"));
        std::fs::create_dir(&staging).map_err(|e| io_err(&staging, e))?;
        if let Err(e) = self.write_all(&staging) {
            let _ = std::fs::remove_dir_all(&staging);
            return Err(e);
        }
        if !exists {
            if let Err(e) = std::fs::rename(&staging, dir) {
                let _ = std::fs::remove_dir_all(&staging);
                return Err(io_err(dir, e));
            }
            sync_dir(&parent);
            return Ok(());
        }
        let old = parent.join(format!(".{name}.old-{tag}"));
        if let Err(e) = std::fs::rename(dir, &old) {
            let _ = std::fs::remove_dir_all(&staging);
            return Err(io_err(dir, e));
        }
        if let Err(e) = std::fs::rename(&staging, dir) {
            let _ = std::fs::rename(&old, dir);
            let _ = std::fs::remove_dir_all(&staging);
            return Err(io_err(dir, e));
        }
        sync_dir(&parent);
        // The new folder is complete and in place; the old one is only garbage now.
        let _ = std::fs::remove_dir_all(&old);
        Ok(())
    }

    fn write_all(&self, staging: &Path) -> Result<(), Error> {
        for (rel, bytes) in &self.files {
            let path = staging.join(rel);
            if let Some(p) = path.parent() {
                std::fs::create_dir_all(p).map_err(|e| io_err(&path, e))?;
            }
            write_synced(&path, bytes)?;
        }
        write_synced(
            &staging.join(MARKER),
            b"This folder was written whole by decophantom; the next run into it replaces it.\n",
        )
    }
}

fn write_synced(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    use std::io::Write;
    let mut f = std::fs::File::create(path).map_err(|e| io_err(path, e))?;
    f.write_all(bytes).map_err(|e| io_err(path, e))?;
    f.sync_all().map_err(|e| io_err(path, e))
}

/// Flush a folder's entries (the renames) where the platform allows it; best effort.
fn sync_dir(dir: &Path) {
    if let Ok(f) = std::fs::File::open(dir) {
        let _ = f.sync_all();
    }
}

fn is_ours_or_empty(dir: &Path) -> Result<bool, Error> {
    if dir.join(MARKER).is_file() {
        return Ok(true);
    }
    let mut it = std::fs::read_dir(dir).map_err(|e| io_err(dir, e))?;
    Ok(it.next().is_none())
}

/// Write one file whole or not at all: the bytes go to a temporary file beside the target,
/// are flushed to disk, and the temporary file is renamed over the target.
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    use std::io::Write as _;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| {
            Error::Input(InputError::new("the output path names no file").in_file(path))
        })?
        .to_string_lossy()
        .into_owned();
    if path.is_dir() {
        return Err(Error::Input(
            InputError::new("the output path is a folder; give a file name").in_file(path),
        ));
    }
    let tmp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp).map_err(|e| io_err(&tmp, e))?;
        f.write_all(bytes).map_err(|e| io_err(&tmp, e))?;
        f.sync_all().map_err(|e| io_err(&tmp, e))?;
        std::fs::rename(&tmp, path).map_err(|e| io_err(path, e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_relative_paths_are_refused() {
        for p in ["/etc/x", "../x", "a/../b", "", MARKER] {
            let mut s = OutputSet::new();
            s.add(p, "x");
            assert!(s.check_paths().is_err(), "{p}");
        }
        let mut s = OutputSet::new();
        s.add("a", "x");
        s.add("a/b", "y");
        assert!(s.check_paths().is_err());
        let mut s = OutputSet::new();
        s.add("a/b.csv", "x");
        s.add("a/b.csv", "y");
        assert!(s.check_paths().is_err());
        let mut s = OutputSet::new();
        s.add("plots/a.svg", "x");
        s.add("plots/b.svg", "y");
        assert!(s.check_paths().is_ok());
    }
}
