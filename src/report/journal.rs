//! Journals of work made of many runs (`sensitivity`, `evaluate`; the simulations of `fit` and
//! `discover`, [`crate::fit::journal`]): a folder `OUT.partial/` beside the output folder, kept
//! until the output folder is committed.
//!
//! The journal's first file starts with the work's fingerprint line and is its commit log: a
//! run counts as done once its line is there. Whatever else the run leaves (lines in the
//! other files, a result file written whole with [`Journal::put`]) is written and flushed
//! first, so a kill between two writes leaves at most a line cut short (the reader drops it)
//! or a result without its line (run again). A restart with the same fingerprint skips the
//! runs the journal holds; a journal of other work is refused (exit 2), never mixed in; the
//! folder is removed once the output is written.

use crate::error::{Error, InputError};
use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The journal folder of an output folder: `OUT.partial` beside it.
pub fn dir_of(out: &Path) -> PathBuf {
    let name = out
        .file_name()
        .map_or("out".into(), |n| n.to_string_lossy().into_owned());
    out.with_file_name(format!("{name}.partial"))
}

/// The text of journal file `path`, `None` if it is missing. One that cannot be read as text
/// ([`crate::error::read_text`]: not a regular file, not UTF-8) is not a journal decophantom
/// wrote as it stands: refused naming it (and the line of the first invalid byte), with what to
/// do (`afresh`) in place of the reader's advice for an input.
fn read_journal_file(path: &Path, afresh: &str) -> Result<Option<String>, Error> {
    if let Err(e) = std::fs::symlink_metadata(path) {
        if e.kind() == std::io::ErrorKind::NotFound {
            return Ok(None);
        }
    }
    crate::error::read_text(path, "the journal file")
        .map(Some)
        .map_err(|e| {
            let why = e.message.split("; ").next().unwrap_or_default().to_string();
            InputError {
                message: format!("{why}: not a journal decophantom wrote as it stands; {afresh}"),
                ..e
            }
            .into()
        })
}

/// An open journal, appended to as runs finish (from several threads).
#[derive(Debug)]
pub struct Journal {
    dir: PathBuf,
    names: Vec<String>,
    files: Mutex<Vec<std::fs::File>>,
}

impl Journal {
    /// What an earlier, unfinished run of the same work left in the journal of `out`: the text
    /// of each of the files `names` (the first without its fingerprint line; a missing file is
    /// empty), or `None` without a journal. A journal whose first line is not `fingerprint`
    /// belongs to other work (`what`: "study", "evaluation", "fit", "discovery") and is refused
    /// (exit 2, naming its file and line 1), and so is a journal folder that decophantom did not
    /// make as it stands (a file in its place, a folder with other files but no journal, a
    /// journal file that is not UTF-8 text); each refusal says what to do: resume with the same
    /// work, or delete the folder to start afresh, or give another `--out`.
    pub fn previous(
        out: &Path,
        fingerprint: &str,
        names: &[&str],
        what: &str,
    ) -> Result<Option<Vec<String>>, Error> {
        let dir = dir_of(out);
        let afresh = format!(
            "delete the folder '{}' to start afresh, or give another --out",
            dir.display()
        );
        match std::fs::metadata(&dir) {
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(Error::io(&dir, e)),
            Ok(m) if !m.is_dir() => {
                return Err(InputError::new(format!(
                    "is where the journal of --out {} goes, and it is not a folder: move it away or give another --out",
                    out.display()
                ))
                .in_file(&dir)
                .into())
            }
            Ok(_) => {}
        }
        let first = dir.join(names[0]);
        let Some(text) = read_journal_file(&first, &afresh)? else {
            // a folder that holds something else than a journal is not ours to fill and remove
            let empty = std::fs::read_dir(&dir)
                .map_err(Error::io_at(&dir))?
                .next()
                .is_none();
            if empty {
                return Ok(None);
            }
            return Err(InputError::new(format!(
                "holds files but no journal ({} is missing), so decophantom did not make it as it stands: move its files away, or {afresh}",
                names[0]
            ))
            .in_file(&dir)
            .into());
        };
        let mut lines = text.splitn(2, '\n');
        let head = lines.next().unwrap_or("");
        if head != fingerprint {
            return Err(InputError::new(format!(
                "holds the journal of a different {what} ({}); resume it with the same inputs and settings, or {afresh}",
                if head.is_empty() {
                    "no header".to_string()
                } else {
                    format!("its first line: {head}")
                }
            ))
            .in_file(&first)
            .at_line(1)
            .into());
        }
        let mut texts = vec![lines.next().unwrap_or("").to_string()];
        for name in &names[1..] {
            texts.push(read_journal_file(&dir.join(name), &afresh)?.unwrap_or_default());
        }
        Ok(Some(texts))
    }

    /// Start the journal of `out` with `contents` (file `names[i]` written whole with
    /// `contents[i]`, the fingerprint line before the first's: what was kept of an earlier
    /// journal, without lines cut by a kill), then open the files for appending.
    pub fn start(
        out: &Path,
        fingerprint: &str,
        names: &[&str],
        contents: &[String],
    ) -> Result<Journal, Error> {
        let dir = dir_of(out);
        std::fs::create_dir_all(&dir).map_err(Error::io_at(&dir))?;
        let mut files = Vec::new();
        for (i, name) in names.iter().enumerate() {
            let path = dir.join(name);
            let text = if i == 0 {
                format!("{fingerprint}\n{}", contents[0])
            } else {
                contents[i].clone()
            };
            std::fs::write(&path, text).map_err(Error::io_at(&path))?;
            files.push(
                std::fs::OpenOptions::new()
                    .append(true)
                    .open(&path)
                    .map_err(Error::io_at(&path))?,
            );
        }
        Ok(Journal {
            dir,
            names: names.iter().map(|n| n.to_string()).collect(),
            files: Mutex::new(files),
        })
    }

    /// Record a finished run: `parts[i]` appended to file i, the last file first and the commit
    /// log (file 0) last, each flushed before the next.
    pub fn append(&self, parts: &[String]) -> Result<(), Error> {
        let mut files = self
            .files
            .lock()
            .map_err(|_| Error::Solver("journal lock poisoned".into()))?;
        for i in (0..parts.len().min(files.len())).rev() {
            let path = self.dir.join(&self.names[i]);
            files[i]
                .write_all(parts[i].as_bytes())
                .map_err(Error::io_at(&path))?;
            files[i].flush().map_err(Error::io_at(&path))?;
        }
        Ok(())
    }

    /// Write `bytes` whole into file `name` of the journal folder (atomically), before the
    /// run's line is appended.
    pub fn put(&self, name: &str, bytes: &[u8]) -> Result<(), Error> {
        super::output::write_file_atomic(&self.dir.join(name), bytes)
    }

    /// The bytes of file `name` of the journal folder, if it is there.
    pub fn get(&self, name: &str) -> Option<Vec<u8>> {
        std::fs::read(self.dir.join(name)).ok()
    }

    /// The journal's folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Remove the journal (its work is written); renamed away first
    /// (`report::output::discard_dir`), so that a kill during the removal leaves no
    /// journal folder without its journal, which the next run would refuse.
    pub fn finish(self) {
        drop(self.files);
        let name = self
            .dir
            .file_name()
            .map_or("out".into(), |n| n.to_string_lossy().into_owned());
        let stem = name.strip_suffix(".partial").unwrap_or(&name);
        crate::report::output::discard_dir(&self.dir, stem);
    }
}
