//! The journal of `fit` and `discover` (issue 11, "Multi-run work keeps finished runs"): every
//! simulation of the model — one experiment's phantom document at one parameter vector, the
//! unit of work of a least-squares step, a Jacobian column, a candidate's scan or refit, the
//! numerical-error re-run — is kept as it finishes, as the line
//!
//! `KEY N S1 … SN`
//!
//! in `OUT.partial/simulations.txt` ([`crate::report::journal`]): KEY the 128-bit FNV-1a hash
//! of the experiment's index and of the exact TOML text the simulation reads (the document with
//! the parameter values written in, shortest round-trip decimals), S1 … SN the simulated radius
//! at that experiment's N observations as the hexadecimal bits of each f64. A line is written
//! whole and flushed; a line cut short by a kill (no newline, a wrong count, a bad number) is
//! dropped on reading.
//!
//! A fit and a search are deterministic sequences of such simulations, so a restart of the same
//! work (the journal's first line: a hash of the measurements, the experiments and the settings)
//! replays the same optimisation and reads every simulation the journal holds back instead of
//! running it: the same numbers, bit for bit, hence the same output files. A simulation that
//! failed is not kept (it is run again). Simulations whose whole frames are needed (the
//! report's overlays, the diagnostics' bubble positions) are not journaled.

use crate::error::Error;
use crate::fit::data::{Experiments, Measurements};
use crate::report::journal::Journal;
use std::collections::HashMap;
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The journal file in `OUT.partial/`.
pub const FILE: &str = "simulations.txt";

/// FNV-1a, 128 bit: a stable hash (collisions among a journal's entries are negligible).
pub fn fnv1a_128(bytes: &[u8]) -> u128 {
    let mut h: u128 = 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d;
    for &b in bytes {
        h ^= b as u128;
        h = h.wrapping_mul(0x0000_0000_0100_0000_0000_0000_0000_013b);
    }
    h
}

/// The journal's first line for `command` (`fit`, `discover`) and the texts that define its work.
pub fn fingerprint(command: &str, parts: &[String]) -> String {
    format!(
        "# decophantom {} {command} {:032x}",
        env!("CARGO_PKG_VERSION"),
        fnv1a_128(parts.join("\n\u{1f}\n").as_bytes())
    )
}

/// The text of the measurements and experiments a fit works on, exact (f64 in round-trip
/// notation), without the paths they were read from.
pub fn work_text(experiments: &Experiments, data: &Measurements) -> String {
    let mut s = experiments_text(experiments);
    s.push_str(&format!("free {:?}\n", experiments.free));
    s.push_str(&format!("measurements {:?}\n", data.series));
    s
}

/// Each experiment's name, bubble count, profile and phantom document, exact, without the paths
/// they were read from: what a fit's journal ([`work_text`]) and synthetic data's tag
/// ([`crate::fit::synth::experiments_hash`]) identify experiments by.
pub fn experiments_text(experiments: &Experiments) -> String {
    let mut s = String::new();
    for e in &experiments.list {
        s.push_str(&format!(
            "experiment {:?} bubbles {}\nprofile {:?}\nphantom {}\n",
            e.name,
            e.bubbles,
            e.profile,
            toml::to_string(&e.phantom).unwrap_or_else(|_| format!("{:?}", e.phantom))
        ));
    }
    s
}

/// The key of a simulation of experiment `experiment` (its index) on phantom document `doc`:
/// the hash of the TOML text the simulation reads; `None` when the document cannot be written
/// (the simulation then fails and is not kept).
pub fn key(experiment: usize, doc: &toml::Table) -> Option<u128> {
    let text = toml::to_string(doc).ok()?;
    Some(fnv1a_128(format!("{experiment}\n{text}").as_bytes()))
}

fn line(key: u128, samples: &[f64]) -> String {
    let mut s = format!("{key:032x} {}", samples.len());
    for v in samples {
        s.push_str(&format!(" {:016x}", v.to_bits()));
    }
    s.push('\n');
    s
}

/// A complete line of the journal (without its newline), or `None` for one cut short.
fn parse_line(l: &str) -> Option<(u128, Vec<f64>)> {
    let mut it = l.split(' ');
    let k = it.next().filter(|k| k.len() == 32)?;
    let key = u128::from_str_radix(k, 16).ok()?;
    let n: usize = it.next()?.parse().ok()?;
    let samples = it
        .map(|h| {
            if h.len() == 16 {
                u64::from_str_radix(h, 16).ok().map(f64::from_bits)
            } else {
                None
            }
        })
        .collect::<Option<Vec<f64>>>()?;
    (samples.len() == n).then_some((key, samples))
}

struct Entry {
    samples: Vec<f64>,
    /// From the journal of an earlier run, not yet read back.
    earlier: bool,
}

/// The simulations of one `fit` or `discover` into an output folder: those an earlier,
/// unfinished run of the same work left in the journal, and every one finished since.
pub struct Evaluations {
    journal: Mutex<Option<Journal>>,
    kept: Mutex<HashMap<u128, Entry>>,
    read_back: AtomicUsize,
    simulated: AtomicUsize,
}

impl std::fmt::Debug for Evaluations {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Evaluations")
            .field("read_back", &self.read_back())
            .field("simulated", &self.simulated())
            .finish()
    }
}

fn poisoned<T>(_: T) -> Error {
    Error::Solver("journal lock poisoned".into())
}

impl Evaluations {
    /// Open the journal of the output folder `out` for the work `fingerprint`: the complete
    /// lines an earlier run of the same work left are kept (the file is rewritten without a
    /// line cut short), a journal of other work is refused (exit 2 naming `--out`; `what`:
    /// "fit", "discovery").
    pub fn open(out: &Path, fingerprint: &str, what: &str) -> Result<Evaluations, Error> {
        let mut kept: HashMap<u128, Entry> = HashMap::new();
        if let Some(texts) = Journal::previous(out, fingerprint, &[FILE], what)? {
            for l in texts[0].split_inclusive('\n') {
                if let Some((k, samples)) = l.strip_suffix('\n').and_then(parse_line) {
                    kept.insert(
                        k,
                        Entry {
                            samples,
                            earlier: true,
                        },
                    );
                }
            }
        }
        let mut keys: Vec<&u128> = kept.keys().collect();
        keys.sort();
        let text: String = keys.iter().map(|k| line(**k, &kept[*k].samples)).collect();
        let journal = Journal::start(out, fingerprint, &[FILE], &[text])?;
        Ok(Evaluations {
            journal: Mutex::new(Some(journal)),
            kept: Mutex::new(kept),
            read_back: AtomicUsize::new(0),
            simulated: AtomicUsize::new(0),
        })
    }

    /// The samples kept for `key`, if they are there and `n` long.
    pub fn get(&self, key: u128, n: usize) -> Option<Vec<f64>> {
        let mut kept = self.kept.lock().ok()?;
        let e = kept.get_mut(&key).filter(|e| e.samples.len() == n)?;
        if e.earlier {
            e.earlier = false;
            self.read_back.fetch_add(1, Ordering::Relaxed);
        }
        Some(e.samples.clone())
    }

    /// Keep the samples of a finished simulation: its line appended to the journal (and
    /// flushed), then kept in memory.
    pub fn record(&self, key: u128, samples: &[f64]) -> Result<(), Error> {
        self.simulated.fetch_add(1, Ordering::Relaxed);
        if let Some(j) = self.journal.lock().map_err(poisoned)?.as_ref() {
            j.append(&[line(key, samples)])?;
        }
        self.kept.lock().map_err(poisoned)?.insert(
            key,
            Entry {
                samples: samples.to_vec(),
                earlier: false,
            },
        );
        Ok(())
    }

    /// Simulations of the earlier run read back instead of run (each counted once).
    pub fn read_back(&self) -> usize {
        self.read_back.load(Ordering::Relaxed)
    }

    /// Simulations run (and kept) by this run.
    pub fn simulated(&self) -> usize {
        self.simulated.load(Ordering::Relaxed)
    }

    /// The journal's folder (while it is open).
    pub fn dir(&self) -> Option<std::path::PathBuf> {
        let j = self.journal.lock().ok()?;
        j.as_ref().map(|j| j.dir().to_path_buf())
    }

    /// Remove the journal (the output is written). Later simulations are kept in memory only.
    pub fn finish(&self) {
        if let Ok(mut j) = self.journal.lock() {
            if let Some(j) = j.take() {
                j.finish();
            }
        }
    }

    /// After a failure: remove the journal if it holds no finished simulation (it is no use to
    /// a restart), else keep it.
    pub fn abandon(&self) {
        let empty = self.kept.lock().is_ok_and(|k| k.is_empty());
        if empty {
            self.finish();
        }
    }

    /// A line for the command's summary when simulations were read back, else nothing.
    pub fn resumed_text(&self, what: &str) -> String {
        let r = self.read_back();
        if r == 0 {
            return String::new();
        }
        format!(
            "{r} model simulations read back from the journal of an unfinished {what}, {} run\n",
            self.simulated()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_round_trip_and_cut_lines_are_dropped() {
        let s = [1.5e-4, f64::NAN, -0.0, 0.1 + 0.2, f64::MIN_POSITIVE];
        let l = line(0xabc, &s);
        let (k, back) = parse_line(l.strip_suffix('\n').unwrap()).unwrap();
        assert_eq!(k, 0xabc);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&s));
        for cut in 1..l.len() - 1 {
            assert!(parse_line(&l[..cut]).is_none(), "{}", &l[..cut]);
        }
        assert!(parse_line(&l[..l.len() - 1].replace(" 5 ", " 6 ")).is_none());
    }

    #[test]
    fn fnv128_of_the_empty_string_and_a_known_value() {
        assert_eq!(fnv1a_128(b""), 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d);
        // reference value of FNV-1a 128 for "a"
        assert_eq!(fnv1a_128(b"a"), 0xd228_cb69_6f1a_8caf_7891_2b70_4e4a_8964);
    }
}
