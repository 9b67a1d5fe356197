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
//! - **User files are never deleted.** The marker lists every file the commit wrote (its
//!   manifest); a folder holding any other file (a profile copied in, notes) is refused, and so
//!   is a folder that holds an input of the run ([`OutputSet::commit_with_inputs`]).
//! - **No debris.** Staging (`.<name>.staging-PID-N`), old (`.<name>.old-PID-N`) and temporary
//!   (`.<name>.tmp-PID-N`) entries left by a process that no longer runs (killed between two
//!   renames) are removed by the next commit into the same place.
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

/// Number of commits under way in this process: a second Ctrl-C waits for them (see
/// [`commit_in_progress`]) so that it never leaves a half-swapped folder.
static COMMITTING: AtomicUsize = AtomicUsize::new(0);

/// Whether a commit (or an atomic file write) is under way in this process. An interrupt
/// handler that ends the process at once should wait while this is true (a few ms).
pub fn commit_in_progress() -> bool {
    COMMITTING.load(Ordering::SeqCst) > 0
}

/// Counts a commit as under way while alive.
struct Committing;
impl Committing {
    fn start() -> Self {
        COMMITTING.fetch_add(1, Ordering::SeqCst);
        Committing
    }
}
impl Drop for Committing {
    fn drop(&mut self) {
        COMMITTING.fetch_sub(1, Ordering::SeqCst);
    }
}

/// First line of the marker file; the lines after `files:` are the manifest.
const MARKER_HEADER: &str =
    "This folder was written whole by decophantom; the next run into it replaces it.";

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
        self.commit_with_inputs(dir, &[])
    }

    /// [`commit`](Self::commit), refusing first (exit 2, nothing written) when `dir` is, or
    /// holds, one of the run's `inputs`.
    pub fn commit_with_inputs(&self, dir: impl AsRef<Path>, inputs: &[&Path]) -> Result<(), Error> {
        self.check_paths()?;
        let dir = dir.as_ref();
        let _guard = Committing::start();
        check_target(dir, inputs)?;
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
            Err(e) => return Err(Error::io(dir, e)),
        };
        std::fs::create_dir_all(&parent).map_err(|e| Error::io(&parent, e))?;
        let tag = format!(
            "{}-{}",
            std::process::id(),
            COUNTER.fetch_add(1, Ordering::Relaxed)
        );
        let staging = parent.join(format!(".{name}.staging-{tag}"));
        std::fs::create_dir(&staging).map_err(|e| Error::io(&staging, e))?;
        if let Err(e) = self.write_all(&staging) {
            let _ = std::fs::remove_dir_all(&staging);
            return Err(e);
        }
        if !exists {
            if let Err(e) = std::fs::rename(&staging, dir) {
                let _ = std::fs::remove_dir_all(&staging);
                return Err(Error::io(dir, e));
            }
            sync_dir(&parent);
            return Ok(());
        }
        let old = parent.join(format!(".{name}.old-{tag}"));
        if let Err(e) = std::fs::rename(dir, &old) {
            let _ = std::fs::remove_dir_all(&staging);
            return Err(Error::io(dir, e));
        }
        if let Err(e) = std::fs::rename(&staging, dir) {
            let _ = std::fs::rename(&old, dir);
            let _ = std::fs::remove_dir_all(&staging);
            return Err(Error::io(dir, e));
        }
        sync_dir(&parent);
        // The new folder is complete and in place; the old one is only garbage now (it may be
        // read-only: make it writable first, so that no `.old` folder is left behind).
        remove_own_dir(&old);
        Ok(())
    }

    fn write_all(&self, staging: &Path) -> Result<(), Error> {
        for (rel, bytes) in &self.files {
            let path = staging.join(rel);
            if let Some(p) = path.parent() {
                std::fs::create_dir_all(p).map_err(|e| Error::io(&path, e))?;
            }
            write_synced(&path, bytes)?;
        }
        let mut marker = format!("{MARKER_HEADER}\nfiles:\n");
        for (rel, _) in &self.files {
            marker.push_str(&rel.to_string_lossy().replace('\\', "/"));
            marker.push('\n');
        }
        write_synced(&staging.join(MARKER), marker.as_bytes())
    }
}

fn write_synced(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    use std::io::Write;
    let mut f = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    f.write_all(bytes).map_err(|e| Error::io(path, e))?;
    f.sync_all().map_err(|e| Error::io(path, e))
}

/// Flush a folder's entries (the renames) where the platform allows it; best effort.
fn sync_dir(dir: &Path) {
    if let Ok(f) = std::fs::File::open(dir) {
        let _ = f.sync_all();
    }
}

/// Check an output folder before any work is done (and again at commit): it must be a
/// folder or absent, empty or written by decophantom, hold no file the tool did not write (its
/// manifest), be neither an input of the run nor hold one, and not lie inside another output
/// folder (whose next run would refuse the files it did not write, or hold another's). Also
/// removes debris of earlier interrupted commits beside it. Errors are bad input naming `--out`
/// (exit 2).
///
/// The place is checked too (missing folders above it are created at the commit): the nearest
/// existing folder above `dir` must be a folder, not a file, and one this process can create
/// entries in (a probe file is created and removed), so that a run is never done only to fail
/// at the end.
pub fn check_target(dir: &Path, inputs: &[&Path]) -> Result<(), Error> {
    let out_err = |m: String| -> Error { InputError::new(m).in_file(dir).field("--out").into() };
    let name = dir
        .file_name()
        .ok_or_else(|| {
            out_err("the output folder has no name; give a folder such as reports/run1".into())
        })?
        .to_string_lossy()
        .into_owned();
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    clean_debris(&parent, &name);
    check_place(dir, "--out", true)?;
    // an output folder inside another: that one's next run would find these files outside its
    // manifest and be refused
    if let Some(outer) = enclosing_output(dir) {
        return Err(out_err(format!(
            "lies inside '{}', the output folder of another run (it holds {MARKER}); the next run into it, which replaces it whole, would be refused with this folder inside: choose a folder outside it",
            outer.display()
        )));
    }
    // an input is the output, or lies inside it (symlinks and `..` resolved)
    let canon = |p: &Path| std::fs::canonicalize(p).ok();
    if let Some(d) = canon(dir) {
        for input in inputs {
            if let Some(i) = canon(input) {
                if i == d || i.starts_with(&d) {
                    return Err(out_err(format!(
                        "the output folder holds an input of this run ({}); outputs never replace inputs: choose another folder or move the input out",
                        input.display()
                    )));
                }
            }
        }
    }
    match std::fs::symlink_metadata(dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => {
            return Err(out_err(
                "exists and is not a folder; choose another output folder".into(),
            ))
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(Error::io(dir, e)),
    }
    let marker = dir.join(MARKER);
    if !marker.is_file() {
        let mut it = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
        if it.next().is_none() {
            return Ok(());
        }
        return Err(out_err(format!(
            "exists and was not written by decophantom (no {MARKER} file); choose a new folder or empty this one"
        )));
    }
    let text = std::fs::read_to_string(&marker).map_err(|e| Error::io(&marker, e))?;
    let Some((_, list)) = text.split_once("\nfiles:\n") else {
        // a marker of an older version, without a manifest: replaced as before
        return Ok(());
    };
    let written: std::collections::HashSet<&str> = list.lines().collect();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).map_err(|e| Error::io(&d, e))? {
            let entry = entry.map_err(|e| Error::io(&d, e))?;
            let path = entry.path();
            let is_dir = entry.file_type().map(|t| t.is_dir()).unwrap_or(false);
            let rel = path.strip_prefix(dir).unwrap_or(&path);
            if is_dir && path.join(MARKER).is_file() {
                return Err(out_err(format!(
                    "holds '{}', the output folder of another run (it has its own {MARKER}); a replaced folder would lose it: move it out or choose another folder",
                    rel.display()
                )));
            }
            if is_dir {
                stack.push(path);
                continue;
            }
            let rel_s = rel.to_string_lossy().replace('\\', "/");
            if rel_s != MARKER && !written.contains(rel_s.as_str()) {
                return Err(out_err(format!(
                    "holds '{rel_s}', which decophantom did not write; a replaced folder would lose it: move it out or choose another folder"
                )));
            }
        }
    }
    Ok(())
}

/// The nearest folder above `dir` that is an output folder (holds [`MARKER`]), with symlinks
/// and `..` resolved in the part of the path that exists; `None` when there is none.
fn enclosing_output(dir: &Path) -> Option<PathBuf> {
    let abs = std::path::absolute(dir).ok()?;
    let above = existing_ancestor(abs.parent()?)?;
    above
        .ancestors()
        .find(|a| a.join(MARKER).is_file())
        .map(Path::to_path_buf)
}

/// The nearest existing folder at or above `path`, with symlinks and `..` resolved (`None` for
/// an empty path).
pub(crate) fn existing_ancestor(path: &Path) -> Option<PathBuf> {
    std::path::absolute(path)
        .ok()?
        .ancestors()
        .find_map(|a| std::fs::canonicalize(a).ok())
}

/// Whether process `pid` is alive; `None` where it cannot be told (no `/proc`).
fn pid_alive(pid: u32) -> Option<bool> {
    if pid == std::process::id() {
        return Some(true);
    }
    let proc_root = Path::new("/proc");
    if !proc_root.join("self").exists() {
        return None;
    }
    Some(proc_root.join(pid.to_string()).exists())
}

/// Remove `.<name>.staging-PID-N`, `.<name>.old-PID-N` and `.<name>.tmp-PID-N` entries in
/// `parent` whose process is gone (best effort, never an error).
fn clean_debris(parent: &Path, name: &str) {
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    for entry in entries.flatten() {
        let file_name = entry.file_name().to_string_lossy().into_owned();
        let Some(rest) = file_name.strip_prefix(&format!(".{name}.")) else {
            continue;
        };
        let Some(tag) = ["staging-", "old-", "tmp-"]
            .iter()
            .find_map(|k| rest.strip_prefix(k))
        else {
            continue;
        };
        let Some((pid, n)) = tag.split_once('-') else {
            continue;
        };
        let (Ok(pid), true) = (pid.parse::<u32>(), n.chars().all(|c| c.is_ascii_digit())) else {
            continue;
        };
        if pid_alive(pid) != Some(false) {
            continue;
        }
        let path = entry.path();
        if entry.file_type().map(|t| t.is_dir()).unwrap_or(false) {
            remove_own_dir(&path);
        } else {
            let _ = std::fs::remove_file(&path);
        }
    }
}

/// Remove a folder this tool made and no longer needs (a journal once its work is written):
/// first renamed beside it to `.<stem>.old-PID-N`, debris that [`check_target`] of output
/// `stem` removes once this process is gone, so that a kill part-way through the removal
/// leaves no half-emptied folder in the folder's place; then removed. Best effort.
pub(crate) fn discard_dir(dir: &Path, stem: &str) {
    let tag = format!(
        "{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    );
    let old = dir.with_file_name(format!(".{stem}.old-{tag}"));
    if std::fs::rename(dir, &old).is_ok() {
        remove_own_dir(&old);
    } else {
        remove_own_dir(dir);
    }
}

/// Remove a folder this tool wrote (an old or staging folder), making read-only folders in it
/// writable first; best effort.
fn remove_own_dir(dir: &Path) {
    if std::fs::remove_dir_all(dir).is_ok() {
        return;
    }
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        if let Ok(m) = std::fs::symlink_metadata(&d) {
            if m.is_dir() {
                let mut perm = m.permissions();
                #[allow(clippy::permissions_set_readonly_false)]
                perm.set_readonly(false);
                let _ = std::fs::set_permissions(&d, perm);
                if let Ok(rd) = std::fs::read_dir(&d) {
                    stack.extend(rd.flatten().map(|e| e.path()));
                }
            }
        }
    }
    let _ = std::fs::remove_dir_all(dir);
}

/// Write one file whole or not at all: the bytes go to a temporary file beside the target,
/// are flushed to disk, and the temporary file is renamed over the target.
pub fn write_file_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    write_file_atomic_with_inputs(path, bytes, &[])
}

/// [`write_file_atomic`], refusing first (exit 2) when `path` is one of the run's `inputs`.
pub fn write_file_atomic_with_inputs(
    path: &Path,
    bytes: &[u8],
    inputs: &[&Path],
) -> Result<(), Error> {
    use std::io::Write as _;
    let _guard = Committing::start();
    check_file_target(path, inputs)?;
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
    let tmp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let result = (|| {
        let mut f = std::fs::File::create(&tmp).map_err(|e| Error::io(&tmp, e))?;
        f.write_all(bytes).map_err(|e| Error::io(&tmp, e))?;
        f.sync_all().map_err(|e| Error::io(&tmp, e))?;
        std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

/// Check the place of an output `path` (a file or a folder) before any work, naming `flag`
/// (`--out`, `--plot`) and the user's path in every refusal (exit 2):
///
/// - the folder that will hold it must exist (`create_missing = false`: a single output file),
///   or, with `create_missing` (output folders, whose missing parents the commit creates), the
///   nearest existing folder above it is used instead;
/// - that folder must be a folder, not a file (`--out notes.txt/run1`);
/// - this process must be able to create entries in it: a probe file `.NAME.tmp-PID-N` (the
///   temporary-file pattern, so a killed process's probe is removed as debris) is created and
///   removed at once. Permissions alone cannot tell (root, ACLs, read-only mounts).
pub fn check_place(path: &Path, flag: &str, create_missing: bool) -> Result<(), Error> {
    let err = |m: String| -> Error { InputError::new(m).in_file(path).field(flag).into() };
    let parent = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    // the nearest existing entry at or above the parent, and the name to be created in it
    let mut holder = parent.clone();
    let mut child = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let meta = loop {
        match std::fs::metadata(&holder) {
            Ok(m) => break m,
            Err(e) => {
                let up = match holder.parent() {
                    Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
                    Some(_) => PathBuf::from("."),
                    None => holder.clone(),
                };
                if up == holder {
                    return Err(err(format!(
                        "no existing folder was found above '{}' ({})",
                        parent.display(),
                        e.kind()
                    )));
                }
                child = holder
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or(child);
                holder = up;
            }
        }
    };
    if !meta.is_dir() {
        return Err(err(format!(
            "'{}' is a file, not a folder; an output cannot be written under it: give a path in a folder",
            holder.display()
        )));
    }
    if !create_missing && holder != parent {
        return Err(err(format!(
            "the folder '{}' does not exist; create it first or give a path in an existing folder",
            parent.display()
        )));
    }
    let probe = holder.join(format!(
        ".{child}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    match std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
    {
        Ok(f) => {
            drop(f);
            let _ = std::fs::remove_file(&probe);
            Ok(())
        }
        Err(e) => Err(err(format!(
            "cannot create files in the folder '{}' ({}); choose a folder you can write to",
            holder.display(),
            e.kind()
        ))),
    }
}

/// How the last line of a single output file ([`marker_line`]) is written: `#` for TOML and CSV
/// (both readers skip `#` lines), an XML/HTML comment for SVG and Markdown.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommentStyle {
    /// `# …` (TOML, CSV).
    Hash,
    /// `<!-- … -->` (SVG, Markdown; the text holds no `--`).
    Xml,
}

/// The last line of a single output file that `tool` (e.g. `plan`) writes with `body` above
/// it: the 64-bit FNV-1a hash of the body, the single file's counterpart of an output folder's
/// manifest ([`MARKER`]). A later run replaces the file only while this line still matches the
/// lines above it ([`check_new_file`]).
pub fn marker_line(tool: &str, body: &str, style: CommentStyle) -> String {
    let text = format!(
        "written by decophantom {tool}; fnv1a-64 of the lines above: {:016x} (a later {tool} replaces this file only while it is unchanged)",
        crate::phantom::checkpoint::fnv1a(body.as_bytes())
    );
    match style {
        CommentStyle::Hash => format!("# {text}\n"),
        CommentStyle::Xml => format!("<!-- {text} -->\n"),
    }
}

/// Whether `text` is a file `tool` wrote, unchanged since: its last line is the
/// [`marker_line`] of the lines above it (in either comment style).
pub fn written_unchanged(text: &str, tool: &str) -> bool {
    let Some(body_end) = text.trim_end_matches('\n').rfind('\n').map(|i| i + 1) else {
        return false;
    };
    let (body, last) = text.split_at(body_end);
    [CommentStyle::Hash, CommentStyle::Xml]
        .iter()
        .any(|&st| last == marker_line(tool, body, st))
}

/// Check a single output file of `tool` (`plan --out`, `plan --plot`) before any work, naming
/// `flag` and the user's path in every refusal (exit 2): everything [`check_file_target`]
/// checks (not a folder, not an input), the place ([`check_place`]: an existing folder this
/// process can write in), and the folders' manifest rule as a single file allows it: an
/// existing file is replaced only if `tool` wrote it and it is unchanged since (its last line
/// is its [`marker_line`]); any other existing file — a user's, one `tool` wrote and someone
/// edited, one of an older version without the line — is refused and kept.
pub fn check_new_file(path: &Path, inputs: &[&Path], flag: &str, tool: &str) -> Result<(), Error> {
    let err = |m: String| -> Error { InputError::new(m).in_file(path).field(flag).into() };
    check_file_target(path, inputs).map_err(|e| match e {
        Error::Input(mut i) => {
            i.field = Some(flag.to_string());
            Error::Input(i)
        }
        other => other,
    })?;
    check_place(path, flag, false)?;
    match std::fs::symlink_metadata(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(err(format!("cannot be checked ({})", e.kind()))),
        Ok(m) if m.file_type().is_symlink() => {
            return Err(err(
                "is a symbolic link; an output never replaces one: give another file name".into(),
            ))
        }
        Ok(_) => {}
    }
    let text = std::fs::read(path)
        .ok()
        .and_then(|b| String::from_utf8(b).ok());
    match text {
        Some(t) if written_unchanged(&t, tool) => Ok(()),
        // the marker on any line: lines appended after it are an edit too
        Some(t)
            if t.lines()
                .any(|l| l.contains(&format!("written by decophantom {tool};"))) =>
        {
            Err(err(format!(
                "exists and was written by {tool} but changed since (its marker line's hash no longer matches the lines above it, or lines follow it); it is never replaced: give another file name, or remove it first"
            )))
        }
        _ => Err(err(format!(
            "exists and was not written by decophantom {tool}; an existing file is never replaced: give another file name, or remove it first"
        ))),
    }
}

/// Write a single output file of `tool` whole or not at all, `body` followed by its
/// [`marker_line`]: [`check_new_file`] first (again: the file may have appeared or been
/// edited while the run went on), then the bytes go to a temporary file beside it, are flushed,
/// and are put in place — with a hard link when nothing is there (which fails rather than
/// replace a file that appeared in between; a rename where the file system has no hard links),
/// else renamed over the unchanged file `tool` wrote.
pub fn write_new_file(
    path: &Path,
    body: &str,
    style: CommentStyle,
    inputs: &[&Path],
    flag: &str,
    tool: &str,
) -> Result<(), Error> {
    use std::io::Write as _;
    let _guard = Committing::start();
    check_new_file(path, inputs, flag, tool)?;
    let exists = std::fs::symlink_metadata(path).is_ok();
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(
        ".{name}.tmp-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    let bytes = format!("{body}{}", marker_line(tool, body, style));
    let appeared = || -> Error {
        InputError::new("a file appeared there while the run went on; it was not replaced: give another file name")
            .in_file(path)
            .field(flag)
            .into()
    };
    let result = (|| {
        let mut f = std::fs::File::create(&tmp).map_err(|e| Error::io(path, e))?;
        f.write_all(bytes.as_bytes())
            .map_err(|e| Error::io(path, e))?;
        f.sync_all().map_err(|e| Error::io(path, e))?;
        drop(f);
        if exists {
            return std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e));
        }
        match std::fs::hard_link(&tmp, path) {
            Ok(()) => Ok(()),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Err(appeared()),
            Err(_) if std::fs::symlink_metadata(path).is_ok() => Err(appeared()),
            Err(_) => std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e)),
        }
    })();
    let _ = std::fs::remove_file(&tmp);
    sync_dir(&dir);
    result
}

/// Whether two paths name the same existing file (symlinks, `.` and `..` resolved).
pub fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    }
}

/// Check an output file before any work: not a folder, not one of `inputs` (symlinks and `..`
/// resolved); removes `.NAME.tmp-PID-N` debris of dead processes beside it.
pub fn check_file_target(path: &Path, inputs: &[&Path]) -> Result<(), Error> {
    let out_err = |m: &str| -> Error { InputError::new(m).in_file(path).field("--out").into() };
    let Some(name) = path.file_name() else {
        return Err(out_err("the output path names no file"));
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    clean_debris(&dir, &name.to_string_lossy());
    if path.is_dir() {
        return Err(out_err("the output path is a folder; give a file name"));
    }
    if let Ok(o) = std::fs::canonicalize(path) {
        if inputs
            .iter()
            .any(|i| std::fs::canonicalize(i).is_ok_and(|i| i == o))
        {
            return Err(out_err(
                "the output file is an input of this run; outputs never replace inputs: give another file name",
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_single_file_is_its_tools_only_while_unchanged() {
        for style in [CommentStyle::Hash, CommentStyle::Xml] {
            let body = "time_min,depth_m,gas\n0,0,air\n";
            let text = format!("{body}{}", marker_line("plan", body, style));
            assert!(written_unchanged(&text, "plan"));
            assert!(!written_unchanged(&text, "synth"));
            assert!(!written_unchanged(&text.replace("air", "32"), "plan"));
            assert!(!written_unchanged(body, "plan"));
            // an XML comment may not hold `--` between its delimiters
            let line = marker_line("plan", body, style);
            let inner = line
                .trim_end()
                .trim_start_matches("<!--")
                .trim_end_matches("-->");
            assert!(!inner.contains("--"), "{line}");
        }
        assert!(!written_unchanged("", "plan"));
    }

    /// A journal folder is discarded by a rename first: the folder is gone whole, and what a
    /// kill during the removal would leave, `.out.old-PID-N` of a process that no longer runs,
    /// is removed by the next `check_target` of `out` (the session-31 review: a half-removed
    /// `out.partial/` without its journal blocked the next run).
    #[test]
    fn discarded_folders_leave_no_half_removed_folder() {
        let root = std::env::temp_dir().join(format!("decophantom-discard-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        let journal = root.join("out.partial");
        std::fs::create_dir_all(journal.join("runs")).unwrap();
        std::fs::write(journal.join("runs/1.csv"), "x").unwrap();
        discard_dir(&journal, "out");
        assert!(!journal.exists());
        assert_eq!(std::fs::read_dir(&root).unwrap().count(), 0);
        // the debris of a killed removal: pid u32::MAX runs no process
        let debris = root.join(format!(".out.old-{}-0", u32::MAX));
        std::fs::create_dir_all(debris.join("runs")).unwrap();
        std::fs::write(debris.join("runs/1.csv"), "x").unwrap();
        if pid_alive(u32::MAX) == Some(false) {
            check_target(&root.join("out"), &[]).unwrap();
            assert!(!debris.exists());
        }
        std::fs::remove_dir_all(&root).unwrap();
    }

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
