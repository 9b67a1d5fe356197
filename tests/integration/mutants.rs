//! Issue 11, "continuous hardening": property-based tests of every reader of person-written or
//! foreign files. Each strategy mutates a valid seed file of the reader's format (bit flips,
//! deletions, duplications, truncation, a number replaced by NaN/inf/huge/negative/1e-308/-0,
//! a key, column or attribute renamed, a line duplicated) and the mutant is written to a file
//! and read through the reader's file entry point, in process. Every case must:
//!
//! - not panic;
//! - return within [`LIMIT`] (each read runs on its own thread: a hang fails the case rather
//!   than stopping the run);
//! - when refused, name the file and a line inside it (every format here has lines).
//!
//! The committed mutants under `tests/data/hostile/<reader>/` (the cases that once failed) run
//! through the same readers in `hardening::hostile_corpus_is_refused_by_every_reader`; this
//! module's `corpus_mutants_*` test also runs them through [`check`], and a failing proptest
//! case goes there too (see `tests/data/README.md`). Case counts are modest (96 per reader):
//! the whole module runs in a few seconds. No persistence file is written
//! (`failure_persistence: None`): a failing run prints the minimal mutant, which is then added
//! to the corpus by hand with the fix.

use crate::common::{root, tempdir};
use decophantom::algorithm::conventions::DECOTENGU;
use decophantom::error::InputError;
use decophantom::gas::GasMix;
use proptest::prelude::*;
use proptest::test_runner::{Config, TestCaseError};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Longest a reader may take on one mutant (they take milliseconds; generous for a loaded
/// machine).
pub const LIMIT: Duration = Duration::from_secs(3);

/// One edit of a file's bytes. Positions are fractions of the current length; `nth` picks a
/// token modulo the number found.
#[derive(Clone, Debug)]
pub enum Mutation {
    /// Flip one bit of one byte (may make the file invalid UTF-8).
    FlipBit(f64, u8),
    /// Delete up to `len` bytes.
    Delete(f64, u8),
    /// Duplicate up to `len` bytes in place.
    Duplicate(f64, u8),
    /// Cut the file.
    Truncate(f64),
    /// Insert a short string.
    Insert(f64, &'static str),
    /// Replace the n-th number with a hostile one.
    Number(u16, &'static str),
    /// Rename the n-th word (a key, column, element or attribute name, or a bare value).
    Rename(u16, &'static str),
    /// Duplicate the n-th line.
    DupLine(u16),
    /// Swap the n-th line with the next.
    SwapLines(u16),
}

/// Hostile replacements for a number.
pub const NUMBERS: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "+inf",
    "1e308",
    "1e309",
    "-1e308",
    "1e-308",
    "4.9e-324",
    "-0",
    "-0.0",
    "0",
    "-1",
    "-40",
    "1e20",
    "3e14",
    "1e17",
    "1000000000",
    "4294967296",
    "9223372036854775807",
    "18446744073709551616",
    "-9223372036854775808",
    "2.561137080192566e-12",
    "1e-30",
    "",
    "1e",
    "0x10",
    "1_000",
    ".5",
    "5.",
    "--1",
    "100000000000000000000:00",
    "1:2:3:4",
];

/// Replacement names.
pub const NAMES: &[&str] = &[
    "x",
    "",
    "time",
    "depth",
    "name",
    "points",
    "gas",
    "repeat",
    "duration",
    "rate",
    "law",
    "legs",
    "stops",
    "bubbles",
    "dive",
    "sample",
    "waypoint",
    "divetime",
    "experiment",
    "radius_m",
    "time_s",
    "time_min",
    "depth_m",
    "kind",
    "limit",
    "ünïcödé",
    "nan",
];

/// Short strings inserted at random places.
pub const INSERTS: &[&str] = &[
    "\n",
    "\r\n",
    "\0",
    "#",
    "\"",
    "'",
    "[",
    "]",
    "[[",
    "{",
    "=",
    ",",
    ":",
    "<",
    ">",
    "</",
    "/>",
    "<a>",
    "&amp;",
    "&#0;",
    "&#x110000;",
    "&unknown;",
    "<![CDATA[",
    "\u{feff}",
    "\u{fffd}",
    " nan ",
    "\n[[leg]]\n",
    "\nrepeat = 1000000000\n",
    "\n0,0\n",
    "\n1e20 0\n",
];

fn mutation() -> impl Strategy<Value = Mutation> {
    let pos = 0.0f64..1.0;
    prop_oneof![
        1 => (pos.clone(), 0u8..8).prop_map(|(p, b)| Mutation::FlipBit(p, b)),
        1 => (pos.clone(), 1u8..40).prop_map(|(p, l)| Mutation::Delete(p, l)),
        1 => (pos.clone(), 1u8..80).prop_map(|(p, l)| Mutation::Duplicate(p, l)),
        1 => pos.clone().prop_map(Mutation::Truncate),
        1 => (pos, prop::sample::select(INSERTS)).prop_map(|(p, s)| Mutation::Insert(p, s)),
        3 => (any::<u16>(), prop::sample::select(NUMBERS)).prop_map(|(n, s)| Mutation::Number(n, s)),
        2 => (any::<u16>(), prop::sample::select(NAMES)).prop_map(|(n, s)| Mutation::Rename(n, s)),
        1 => any::<u16>().prop_map(Mutation::DupLine),
        1 => any::<u16>().prop_map(Mutation::SwapLines),
    ]
}

/// One to four mutations.
pub fn mutations() -> impl Strategy<Value = Vec<Mutation>> {
    prop::collection::vec(mutation(), 1..5)
}

fn at(p: f64, len: usize) -> usize {
    ((p * len as f64) as usize).min(len)
}

/// Spans of numbers: a digit not preceded by a letter, digit or `_`, with the digits, dots,
/// signs, exponents and colons after it, and a sign before it.
fn number_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let starts = b[i].is_ascii_digit()
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'));
        if !starts {
            i += 1;
            continue;
        }
        let s = if i > 0 && (b[i - 1] == b'-' || b[i - 1] == b'+') {
            i - 1
        } else {
            i
        };
        let mut e = i;
        while e < b.len() && (b[e].is_ascii_digit() || b".eE+-:_".contains(&b[e])) {
            e += 1;
        }
        out.push((s, e));
        i = e;
    }
    out
}

/// Spans of words: a letter or `_` followed by letters, digits and `_`, at least 2 long.
fn word_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if !(b[i].is_ascii_alphabetic() || b[i] == b'_') {
            i += 1;
            continue;
        }
        let mut e = i;
        while e < b.len() && (b[e].is_ascii_alphanumeric() || b[e] == b'_') {
            e += 1;
        }
        if e - i >= 2 {
            out.push((i, e));
        }
        i = e;
    }
    out
}

fn line_spans(b: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for (i, &c) in b.iter().enumerate() {
        if c == b'\n' {
            out.push((s, i + 1));
            s = i + 1;
        }
    }
    if s < b.len() {
        out.push((s, b.len()));
    }
    out
}

fn replace(b: &mut Vec<u8>, spans: &[(usize, usize)], n: u16, with: &[u8]) {
    if spans.is_empty() {
        return;
    }
    let (s, e) = spans[n as usize % spans.len()];
    b.splice(s..e, with.iter().copied());
}

/// Apply the mutations in order.
pub fn apply(seed: &[u8], muts: &[Mutation]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for m in muts {
        let n = b.len();
        match *m {
            Mutation::FlipBit(p, bit) => {
                if n > 0 {
                    let i = at(p, n - 1);
                    b[i] ^= 1 << (bit % 8);
                }
            }
            Mutation::Delete(p, l) => {
                let i = at(p, n);
                let e = (i + l as usize).min(n);
                b.drain(i..e);
            }
            Mutation::Duplicate(p, l) => {
                let i = at(p, n);
                let e = (i + l as usize).min(n);
                let piece = b[i..e].to_vec();
                b.splice(e..e, piece);
            }
            Mutation::Truncate(p) => b.truncate(at(p, n)),
            Mutation::Insert(p, s) => {
                let i = at(p, n);
                b.splice(i..i, s.bytes());
            }
            Mutation::Number(k, s) => {
                let spans = number_spans(&b);
                replace(&mut b, &spans, k, s.as_bytes())
            }
            Mutation::Rename(k, s) => {
                let spans = word_spans(&b);
                replace(&mut b, &spans, k, s.as_bytes())
            }
            Mutation::DupLine(k) => {
                let l = line_spans(&b);
                if !l.is_empty() {
                    let (s, e) = l[k as usize % l.len()];
                    let mut piece = b[s..e].to_vec();
                    if !piece.ends_with(b"\n") {
                        piece.insert(0, b'\n');
                    }
                    b.splice(e..e, piece);
                }
            }
            Mutation::SwapLines(k) => {
                let l = line_spans(&b);
                if l.len() >= 2 {
                    let j = k as usize % (l.len() - 1);
                    let (s0, e0) = l[j];
                    let (s1, e1) = l[j + 1];
                    let mut a = b[s0..e0].to_vec();
                    let mut c = b[s1..e1].to_vec();
                    if !c.ends_with(b"\n") {
                        c.push(b'\n');
                        a.pop();
                    }
                    let mut both = c;
                    both.extend(a);
                    b.splice(s0..e1, both);
                }
            }
        }
    }
    b
}

/// A reader of one file format, called through its file entry point as the commands call it
/// (including the step to a pressure history where a command takes one).
pub struct Reader {
    /// Name, also the folder of its corpus under `tests/data/hostile/`.
    pub name: &'static str,
    /// Extension the mutant is written with.
    pub ext: &'static str,
    /// Valid seed files, relative to the repository root.
    pub seeds: &'static [&'static str],
    /// Read a file.
    pub read: fn(&Path) -> Result<(), InputError>,
    /// Refusals known to name no line (message fragments), in a module this work may not
    /// change; listed so that a new one is still caught.
    pub unlined: &'static [&'static str],
}

fn divelog(p: &Path) -> Result<(), InputError> {
    use decophantom::profile::{dive_log_history, divelog, DIVE_LOG_WATCH_S};
    for d in divelog::read(p)? {
        dive_log_history(&d, 0.0, DIVE_LOG_WATCH_S).map_err(|e| e.in_file(p))?;
    }
    // and as a schedule (`check --schedule log.xml`, every dive)
    use decophantom::profile::sequence::DiveSelection;
    let n = divelog::read(p)?.len();
    // every dive, and all of them joined with their surface intervals (`--dive all`)
    let all = (n > 1).then_some(DiveSelection::All);
    for sel in (1..=n).map(DiveSelection::One).chain(all) {
        let s = decophantom::algorithm::waypoints::read_divelog_schedule(p, &DECOTENGU, Some(sel))?;
        s.schedule
            .to_pressure_history()
            .map_err(|m| InputError::new(m).in_file(p))?;
    }
    Ok(())
}

fn legacy(p: &Path) -> Result<(), InputError> {
    use decophantom::profile::legacy::{read, LegacyUnits};
    use decophantom::units::{PressureUnit, TimeUnit};
    let units = LegacyUnits::new(TimeUnit::Min, PressureUnit::Msw);
    let h = read(p, &units)?;
    // and as a schedule (`check --schedule dive.txt`), when it is one: a schedule starts at
    // the surface (a profile that starts saturated at depth, as sensitivity-30m.txt at 30 msw,
    // is refused as a schedule at its line 1, and is read by `simulate --profile`)
    if h.ambient_pa[0] > units.surface_pa {
        return Ok(());
    }
    let s = decophantom::algorithm::waypoints::read_legacy_schedule(p, &DECOTENGU, GasMix::AIR)?;
    s.to_pressure_history()
        .map_err(|m| InputError::new(m).in_file(p))?;
    Ok(())
}

fn waypoints(p: &Path) -> Result<(), InputError> {
    let s = decophantom::algorithm::waypoints::read_waypoints_csv(p, &DECOTENGU, GasMix::AIR)?;
    s.to_pressure_history()
        .map_err(|m| InputError::new(m).in_file(p))?;
    Ok(())
}

fn schedule(p: &Path) -> Result<(), InputError> {
    let s = decophantom::algorithm::Schedule::read(p)?;
    s.to_pressure_history()
        .map_err(|m| InputError::new(m).in_file(p))?;
    Ok(())
}

fn experiments(p: &Path) -> Result<(), InputError> {
    match decophantom::fit::data::read_experiments(p) {
        Ok(_) => Ok(()),
        Err(decophantom::error::Error::Input(e)) => Err(e),
        Err(other) => panic!("{}: not an input error: {other}", p.display()),
    }
}

/// Every reader of a file a person writes or another program exports.
pub const READERS: &[Reader] = &[
    Reader {
        name: "profile",
        ext: "toml",
        seeds: &[
            "profiles/fig5-dive.toml",
            "profiles/oscillation-30s.toml",
            "profiles/sensitivity-30m.toml",
        ],
        read: |p| decophantom::profile::toml::read(p).map(|_| ()),
        unlined: &[],
    },
    Reader {
        name: "legacy",
        ext: "txt",
        seeds: &[
            "tests/data/legacy/dive-40m-two-stops.txt",
            "tests/data/legacy/sensitivity-30m.txt",
        ],
        read: legacy,
        unlined: &[],
    },
    Reader {
        name: "waypoints",
        ext: "csv",
        seeds: &["tests/data/seeds/waypoints.csv"],
        read: waypoints,
        unlined: &[],
    },
    Reader {
        name: "schedule",
        ext: "toml",
        seeds: &["tests/data/seeds/schedule.toml"],
        read: schedule,
        unlined: &[],
    },
    Reader {
        name: "algorithm",
        ext: "toml",
        seeds: &[
            "algorithms/zhl16c-gf30-85.toml",
            "algorithms/vpmb-2-baker.toml",
        ],
        read: |p| decophantom::algorithm::load_algorithm(p).map(|_| ()),
        unlined: &[],
    },
    Reader {
        name: "criteria",
        ext: "toml",
        seeds: &["algorithms/criteria/default.toml"],
        read: |p| decophantom::risk::load_criteria(p).map(|_| ()),
        unlined: &[],
    },
    Reader {
        name: "phantom",
        ext: "toml",
        seeds: &[
            "profiles/phantoms/hydrogel.toml",
            "profiles/phantoms/fig3-modal.toml",
        ],
        read: |p| decophantom::phantom::config::load_phantom(p).map(|_| ()),
        unlined: &[],
    },
    Reader {
        name: "divelog",
        ext: "xml",
        seeds: &[
            "tests/data/divelogs/planned-trimix.xml",
            "tests/data/divelogs/repetitive-logged.xml",
            "tests/data/divelogs/legacy-v1.xml",
        ],
        read: divelog,
        unlined: &[],
    },
    Reader {
        name: "uddf",
        ext: "uddf",
        seeds: &[
            "tests/data/divelogs/ostc-percent.uddf",
            "tests/data/divelogs/shearwater-quirks.uddf",
        ],
        read: divelog,
        unlined: &[],
    },
    Reader {
        name: "measurements",
        ext: "csv",
        seeds: &["tests/data/seeds/measurements.csv"],
        read: |p| decophantom::fit::data::read_measurements(p).map(|_| ()),
        unlined: &[],
    },
    Reader {
        name: "experiments",
        ext: "toml",
        seeds: &["tests/data/seeds/experiments.toml"],
        read: experiments,
        unlined: &[],
    },
];

/// The reader of this name.
pub fn reader(name: &str) -> &'static Reader {
    READERS
        .iter()
        .find(|r| r.name == name)
        .unwrap_or_else(|| panic!("no reader '{name}'"))
}

/// Write `bytes` to `path`, read it as a file of `reader` and check the three properties;
/// `Ok(true)` when the file was accepted.
pub fn check(reader: &Reader, path: &Path, bytes: &[u8]) -> Result<bool, String> {
    std::fs::write(path, bytes).unwrap();
    read_checked(reader, path, bytes).map(|e| e.is_none())
}

/// Read the file at `path` (holding `bytes`) as a file of `reader` and check the three
/// properties; the error when it was refused.
pub fn read_checked(
    reader: &Reader,
    path: &Path,
    bytes: &[u8],
) -> Result<Option<InputError>, String> {
    // on a thread of its own, so that a hang fails the case instead of stopping the run
    let t = Instant::now();
    let (tx, rx) = std::sync::mpsc::channel();
    let (read, owned) = (reader.read, path.to_path_buf());
    std::thread::spawn(move || {
        let _ = tx.send(read(&owned));
    });
    let r = match rx.recv_timeout(LIMIT) {
        Ok(r) => r,
        Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
            return Err(format!("{}: no answer within {LIMIT:?}", reader.name))
        }
        Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => {
            return Err(format!("{}: panicked (message above)", reader.name))
        }
    };
    let took = t.elapsed();
    if took > LIMIT {
        return Err(format!("{}: took {took:?}", reader.name));
    }
    let Err(e) = r else { return Ok(None) };
    // the experiments file names other files; a refusal inside one of them names that file
    let named_sibling = reader.name == "experiments"
        && e.line.is_some()
        && e.file.as_deref().and_then(Path::parent) == path.parent();
    if e.file.as_deref() != Some(path) && !named_sibling {
        return Err(format!(
            "{}: refused without naming the file: {e}",
            reader.name
        ));
    }
    // lines of the file as read: a final line without a newline counts, and a line just past
    // the end ("expected more") is accepted
    let lines = if named_sibling {
        usize::MAX - 1
    } else {
        bytes.split(|&c| c == b'\n').count()
    };
    match e.line {
        None if reader.unlined.iter().any(|m| e.message.contains(m)) => Ok(Some(e)),
        None => Err(format!("{}: refused without a line: {e}", reader.name)),
        Some(0) => Err(format!("{}: line 0: {e}", reader.name)),
        Some(l) if l > lines + 1 => Err(format!(
            "{}: line {l} is past the end ({lines} lines): {e}",
            reader.name
        )),
        Some(_) => Ok(Some(e)),
    }
}

fn seed(rel: &str) -> Vec<u8> {
    std::fs::read(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The folder mutants are written into: the experiments reader needs the profile and phantom
/// its seed names beside it.
fn workdir(name: &str) -> PathBuf {
    let d = tempdir(&format!("mutants-{name}"));
    for f in ["profile.toml", "phantom.toml"] {
        std::fs::copy(root().join("tests/data/seeds").join(f), d.join(f)).unwrap();
    }
    d
}

fn config() -> Config {
    Config {
        cases: 96,
        // no regression file: a failing mutant is printed and goes into the corpus by hand
        failure_persistence: None,
        ..Config::default()
    }
}

fn run_reader(name: &str) {
    let r = reader(name);
    let dir = workdir(name);
    let path = dir.join(format!("mutant.{}", r.ext));
    let seeds: Vec<Vec<u8>> = r.seeds.iter().map(|s| seed(s)).collect();
    // every seed is valid as it is: the mutants start from an accepted file
    for (s, b) in r.seeds.iter().zip(&seeds) {
        assert_eq!(check(r, &path, b), Ok(true), "seed {s}");
    }
    // a fixed generator: the same mutants on every run, so CI is deterministic (the ignored
    // `survey` explores new ones)
    let mut runner = proptest::test_runner::TestRunner::new_with_rng(
        config(),
        proptest::test_runner::TestRng::deterministic_rng(
            proptest::test_runner::RngAlgorithm::ChaCha,
        ),
    );
    let result = runner.run(&(0..seeds.len(), mutations()), |(k, muts)| {
        let bytes = apply(&seeds[k], &muts);
        check(r, &path, &bytes).map(|_| ()).map_err(|m| {
            TestCaseError::fail(format!("{m}\nmutant:\n{}", String::from_utf8_lossy(&bytes)))
        })
    });
    if let Err(e) = result {
        panic!("{name}: {e}");
    }
}

macro_rules! reader_tests {
    ($($test:ident => $name:literal),* $(,)?) => {
        $(
            #[test]
            fn $test() {
                run_reader($name);
            }
        )*
    };
}

reader_tests! {
    profile_toml => "profile",
    legacy_text => "legacy",
    waypoint_csv => "waypoints",
    schedule_toml => "schedule",
    algorithm_toml => "algorithm",
    criteria_toml => "criteria",
    phantom_toml => "phantom",
    subsurface_xml => "divelog",
    uddf => "uddf",
    measurements_csv => "measurements",
    experiments_toml => "experiments",
}

/// A survey, not a test: many mutants per reader, every distinct failure printed (run with
/// `cargo test --release --test integration mutants::survey -- --ignored --nocapture`).
#[test]
#[ignore]
fn survey() {
    use proptest::strategy::ValueTree;
    let n: usize = std::env::var("SURVEY_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(2000);
    for r in READERS {
        let dir = workdir(r.name);
        let path = dir.join(format!("mutant.{}", r.ext));
        let seeds: Vec<Vec<u8>> = r.seeds.iter().map(|s| seed(s)).collect();
        // a fresh random generator on every survey: new mutants each time (the tests above
        // use a fixed one)
        let mut runner = proptest::test_runner::TestRunner::new(proptest::test_runner::Config {
            failure_persistence: None,
            ..proptest::test_runner::Config::default()
        });
        let strat = (0..seeds.len(), mutations());
        let mut seen = std::collections::BTreeMap::new();
        let mut accepted = 0;
        for _ in 0..n {
            let (k, muts) = strat.new_tree(&mut runner).unwrap().current();
            let bytes = apply(&seeds[k], &muts);
            let res =
                std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| check(r, &path, &bytes)));
            match res {
                Ok(Ok(true)) => accepted += 1,
                Ok(Ok(false)) => {}
                Ok(Err(m)) => {
                    let tail = m
                        .find("mutant.")
                        .and_then(|i| m[i..].find(": ").map(|j| &m[i + j..]))
                        .unwrap_or(&m);
                    let key: String = tail
                        .chars()
                        .filter(|c| !c.is_ascii_digit())
                        .take(70)
                        .collect();
                    seen.entry(key).or_insert((m, muts));
                }
                Err(_) => {
                    seen.entry(format!("PANIC {muts:?}"))
                        .or_insert(("panic".into(), muts.clone()));
                }
            }
        }
        println!(
            "== {}: {n} mutants, {accepted} accepted, {} distinct failures",
            r.name,
            seen.len()
        );
        for (m, muts) in seen.values() {
            println!("  {m}\n     <- {muts:?}");
        }
    }
}

/// The harness itself: a panicking reader and a hanging one are failures, not a stopped run.
#[test]
fn harness_reports_panics_and_hangs() {
    let dir = tempdir("mutants-harness");
    let p = dir.join("x.txt");
    let panics = Reader {
        name: "panics",
        ext: "txt",
        seeds: &[],
        read: |_| panic!("a reader bug (expected by this test)"),
        unlined: &[],
    };
    let e = check(&panics, &p, b"x").unwrap_err();
    assert!(e.contains("panicked"), "{e}");
    let hangs = Reader {
        name: "hangs",
        ext: "txt",
        seeds: &[],
        read: |_| {
            std::thread::sleep(LIMIT + Duration::from_millis(500));
            Ok(())
        },
        unlined: &[],
    };
    let t = Instant::now();
    let e = check(&hangs, &p, b"x").unwrap_err();
    assert!(e.contains("no answer") && t.elapsed() < LIMIT * 2, "{e}");
    let silent = Reader {
        name: "silent",
        ext: "txt",
        seeds: &[],
        read: |_| Err(InputError::new("no file, no line")),
        unlined: &[],
    };
    assert!(check(&silent, &p, b"x")
        .unwrap_err()
        .contains("without naming the file"));
}
