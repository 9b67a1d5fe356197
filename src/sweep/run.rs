//! Running a design: in parallel over runs (rayon), with a journal `DIR.partial/` beside the
//! output folder that every finished run is appended to (a restarted study with the same
//! settings skips the runs already there), shards (`--shard I/N`: runs
//! ⌊I·n/N⌋ … ⌊(I+1)·n/N⌋ − 1 of the n) and the merge of shard folders.

use super::{num, report, StudySpec};
use crate::error::{Error, InputError};
use crate::fit::data::build_params;
use crate::fit::journal::fnv1a_128;
use crate::fit::model::run_one;
use crate::fit::paths;
use crate::profile::PressureHistory;
use crate::report::journal::Journal;
use crate::report::output::OutputSet;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// Points kept of each run's radius time course (for the report's plots).
const COURSE_POINTS: usize = 200;

/// A study: its design, the phantom document and the profile.
#[derive(Debug, Clone)]
pub struct Study {
    /// What fixes the design.
    pub spec: StudySpec,
    /// The phantom as a TOML document.
    pub doc: toml::Table,
    /// The phantom file (for messages).
    pub phantom_path: PathBuf,
    /// The pressure profile.
    pub profile: PressureHistory,
}

/// What a run's result depends on besides the design ([`StudySpec::fingerprint`]): the phantom
/// and the profile, each as a 128-bit FNV-1a hash ([`crate::fit::journal::fnv1a_128`], the hash
/// `fit`'s journal keys its simulations with) of its canonical text, and the program's version.
/// A journal and the shards of a merge must agree on all of them.
///
/// - The phantom: the document as parsed (`toml::to_string` of the table, as `fit` hashes it):
///   its comments, layout and number spelling (`4e-4` or `0.0004`) do not count, every value
///   does, the grid step (`geometry.grid_step_m`) among them: `sensitivity` has no override
///   of its own. The swept parameters are overwritten in every run, but their phantom values are
///   the base values, part of the design anyway.
/// - The profile: the pressure history as read and validated, in the text a checkpoint
///   identifies it by (`phantom::checkpoint::profile_text`: breakpoint times, absolute
///   pressures, the gas of each segment, water vapour, saturation, f64 in round-trip notation),
///   so the same history in other units or another file format is the same profile; its label
///   (the file's name) is left out, as no run reads it.
/// - The version: another build of the solver may give other numbers (`fit`'s journal keys on it
///   too).
///
/// The thread count is not part of it: a run's numbers do not depend on it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct InputsId {
    /// Hash of the phantom document (32 hexadecimal digits).
    pub phantom: String,
    /// Hash of the pressure history (32 hexadecimal digits).
    pub profile: String,
    /// The decophantom version that ran it.
    pub version: String,
}

impl InputsId {
    /// The identity of a study's inputs.
    pub fn of(doc: &toml::Table, profile: &PressureHistory) -> InputsId {
        let phantom = toml::to_string(doc).unwrap_or_else(|_| format!("{doc:?}"));
        // the history as a checkpoint identifies it (its label left out)
        let history = crate::phantom::checkpoint::profile_text(profile);
        InputsId {
            phantom: format!("{:032x}", fnv1a_128(phantom.as_bytes())),
            profile: format!("{:032x}", fnv1a_128(history.as_bytes())),
            version: env!("CARGO_PKG_VERSION").to_string(),
        }
    }

    /// Read back from design.toml's entries (`None` when one is missing).
    fn from_table(t: &toml::Table) -> Option<InputsId> {
        let get = |k: &str| t.get(k).and_then(|v| v.as_str()).map(str::to_string);
        Some(InputsId {
            phantom: get(PHANTOM_KEY)?,
            profile: get(PROFILE_KEY)?,
            version: get(VERSION_KEY)?,
        })
    }

    /// design.toml's entries.
    fn to_table(&self, t: &mut toml::Table) {
        t.insert(PHANTOM_KEY.into(), self.phantom.clone().into());
        t.insert(PROFILE_KEY.into(), self.profile.clone().into());
        t.insert(VERSION_KEY.into(), self.version.clone().into());
    }
}

/// design.toml's entry (and the journal header's field) of the phantom's hash.
const PHANTOM_KEY: &str = "phantom_hash";
/// … of the profile's hash.
const PROFILE_KEY: &str = "profile_hash";
/// … of the version.
const VERSION_KEY: &str = "decophantom";

/// Everything that fixes a study's runs: the design and the inputs.
#[derive(Debug, Clone, PartialEq, Eq)]
struct Identity {
    design: String,
    inputs: InputsId,
}

/// What differs between two studies' identities (`theirs` of a journal or a shard folder,
/// `ours` of this run or the first folder), in words; empty when nothing does.
fn differences(theirs: &Identity, ours: &Identity, there: &str, here: &str) -> Vec<String> {
    let mut d = Vec::new();
    if theirs.inputs.phantom != ours.inputs.phantom {
        d.push(format!(
            "the phantom (--phantom: the document as parsed; hash {} {there}, {} {here})",
            theirs.inputs.phantom, ours.inputs.phantom
        ));
    }
    if theirs.inputs.profile != ours.inputs.profile {
        d.push(format!(
            "the profile (--profile: the pressure history as read; hash {} {there}, {} {here})",
            theirs.inputs.profile, ours.inputs.profile
        ));
    }
    if theirs.design != ours.design {
        d.push(format!(
            "the design (--method, --samples, --seed, --param, --metric or a swept parameter's value in the phantom):\n  {there}: {}\n  {here}: {}",
            theirs.design, ours.design
        ));
    }
    if theirs.inputs.version != ours.inputs.version {
        d.push(format!(
            "the decophantom version ({} {there}, {} {here})",
            theirs.inputs.version, ours.inputs.version
        ));
    }
    d
}

/// The journal's first line: `# DESIGN phantom_hash=… profile_hash=… decophantom=… shard=I/N`.
fn journal_header(id: &Identity, shard: Shard) -> String {
    format!(
        "# {} {PHANTOM_KEY}={} {PROFILE_KEY}={} {VERSION_KEY}={} shard={}/{}",
        id.design,
        id.inputs.phantom,
        id.inputs.profile,
        id.inputs.version,
        shard.index,
        shard.count
    )
}

/// A journal header read back: the identity and the shard text; `None` for a header of
/// another format (an older decophantom's, without the inputs' hashes).
fn parse_journal_header(line: &str) -> Option<(Identity, String)> {
    let body = line.strip_prefix("# ")?;
    let mut it = body.rsplitn(5, ' ');
    let shard = it.next()?.strip_prefix("shard=")?.to_string();
    let version = it.next()?.strip_prefix(VERSION_KEY)?.strip_prefix('=')?;
    let profile = it.next()?.strip_prefix(PROFILE_KEY)?.strip_prefix('=')?;
    let phantom = it.next()?.strip_prefix(PHANTOM_KEY)?.strip_prefix('=')?;
    let design = it.next()?.to_string();
    Some((
        Identity {
            design,
            inputs: InputsId {
                phantom: phantom.to_string(),
                profile: profile.to_string(),
                version: version.to_string(),
            },
        },
        shard,
    ))
}

/// Refuse (exit 2, `--out`) a journal beside `out` whose first line is not `header`, naming the
/// journal's folder and what differs: the phantom, the profile, the design, the version, the
/// shard. Nothing is done without a journal; a matching one is left to [`Journal::previous`].
fn check_journal(out: &Path, header: &str, id: &Identity, shard: Shard) -> Result<(), Error> {
    let dir = journal_dir(out);
    let Ok(text) = std::fs::read_to_string(dir.join(JOURNAL_FILES[0])) else {
        return Ok(());
    };
    let head = text.lines().next().unwrap_or("");
    if head == header {
        return Ok(());
    }
    let what = match parse_journal_header(head) {
        Some((theirs, their_shard)) => {
            let mut d = differences(&theirs, id, "in the journal", "in this run");
            let ours = format!("{}/{}", shard.index, shard.count);
            if their_shard != ours {
                d.push(format!(
                    "the shard (--shard {their_shard} in the journal, {ours} in this run)"
                ));
            }
            if d.is_empty() {
                d.push(format!("its first line: {head}"));
            }
            format!("it differs in {}", d.join("; and in "))
        }
        None if head.is_empty() => "it has no header".to_string(),
        None => format!(
            "its first line is not a journal of this decophantom's (no hashes of the phantom and profile; an older version's?): {head}"
        ),
    };
    Err(InputError::new(format!(
        "'{}' holds the journal of a different study: {what}; resume with the same phantom, profile and settings, or delete that folder to start afresh",
        dir.display()
    ))
    .field("--out")
    .into())
}

/// The journal's files: the commit log (rows) and the courses.
const JOURNAL_FILES: [&str; 2] = ["sensitivity.csv", "courses.csv"];

/// The I-th of N slices of a design.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 0-based slice.
    pub index: usize,
    /// Number of slices.
    pub count: usize,
}

impl Shard {
    /// The whole design.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Parse `I/N` with 0 ≤ I < N.
    pub fn parse(text: &str) -> Result<Shard, InputError> {
        let bad = || {
            InputError::new(format!(
                "'{text}': a shard is I/N with 0 ≤ I < N, e.g. 3/64 (the 4th of 64 slices)"
            ))
            .in_file("<command line>")
            .field("--shard")
        };
        let (i, n) = text.split_once('/').ok_or_else(bad)?;
        let (i, n): (usize, usize) = (
            i.trim().parse().map_err(|_| bad())?,
            n.trim().parse().map_err(|_| bad())?,
        );
        if n == 0 || i >= n {
            return Err(bad());
        }
        Ok(Shard { index: i, count: n })
    }

    /// The runs of this slice of a design of `n` runs.
    pub fn range(&self, n: usize) -> std::ops::Range<usize> {
        (self.index * n / self.count)..((self.index + 1) * n / self.count)
    }

    /// Check the slice against a design of `n` runs: more slices than runs would leave some
    /// empty, so that is bad input naming `--shard` (with N ≤ n every slice has a run).
    pub fn check(&self, n: usize) -> Result<(), InputError> {
        if self.count > n {
            return Err(InputError::new(format!(
                "'{}/{}': the design has {n} runs, so it can be split into at most {n} shards",
                self.index, self.count
            ))
            .in_file("<command line>")
            .field("--shard"));
        }
        Ok(())
    }
}

/// A radius time course: (time s, radius m).
pub type Course = Vec<(f64, f64)>;

/// One finished run.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Run index in the design.
    pub index: usize,
    /// Parameter values.
    pub values: Vec<f64>,
    /// Metric values (NaN where undefined or the run failed).
    pub metrics: Vec<f64>,
}

/// Rows and radius courses of a design (or a shard of one).
#[derive(Debug, Clone, PartialEq)]
pub struct Results {
    /// The design.
    pub spec: StudySpec,
    /// The slice of the design these are the runs of ([`Shard::WHOLE`] for a whole or merged
    /// study).
    pub shard: Shard,
    /// Finished runs, by index.
    pub rows: Vec<Row>,
    /// Radius time course (the largest bubble) of each run, by index.
    pub courses: Vec<(usize, Vec<(f64, f64)>)>,
    /// Runs skipped because the journal already held them.
    pub resumed: usize,
    /// The phantom and profile the runs were made with (written to design.toml and checked by
    /// [`merge`]); `None` for a study run in memory ([`run_all`]: `reproduce`'s figures).
    pub inputs: Option<InputsId>,
}

impl Results {
    /// Whether the rows are every run of the design, in order (row i is run i): only then can
    /// the indices be computed ([`report::indices`]); a shard's rows are not.
    pub fn is_whole(&self) -> bool {
        self.spec.runs() == Some(self.rows.len())
            && self.rows.iter().enumerate().all(|(i, r)| {
                r.index == i
                    && r.values.len() == self.spec.params.len()
                    && r.metrics.len() == self.spec.metrics.len()
            })
    }
}

/// The `sensitivity.csv` header.
pub fn header(spec: &StudySpec) -> String {
    let mut h = vec!["index".to_string()];
    h.extend(spec.params.iter().map(|p| p.path.clone()));
    h.extend(spec.metrics.iter().map(|m| m.name()));
    h.join(",")
}

/// One `sensitivity.csv` line (shortest round-trip decimal, so reading it back gives the
/// same numbers bit for bit).
pub fn row_line(r: &Row) -> String {
    let mut s = r.index.to_string();
    for v in r.values.iter().chain(&r.metrics) {
        s.push(',');
        s.push_str(&num(*v));
    }
    s
}

fn parse_row(line: &str, k: usize, m: usize) -> Option<Row> {
    let f: Vec<&str> = line.split(',').collect();
    if f.len() != 1 + k + m {
        return None;
    }
    let nums: Option<Vec<f64>> = f[1..].iter().map(|s| s.trim().parse().ok()).collect();
    let nums = nums?;
    Some(Row {
        index: f[0].trim().parse().ok()?,
        values: nums[..k].to_vec(),
        metrics: nums[k..].to_vec(),
    })
}

/// Read `sensitivity.csv` rows (a line that does not parse — e.g. cut by a kill — is dropped).
pub fn parse_rows(text: &str, spec: &StudySpec) -> Vec<Row> {
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with("index"))
        .filter_map(|l| parse_row(l, spec.params.len(), spec.metrics.len()))
        .collect()
}

/// `courses.csv` text: index,time_s,radius_m.
pub fn courses_text(courses: &[(usize, Vec<(f64, f64)>)]) -> String {
    let mut s = String::from("index,time_s,radius_m\n");
    for (i, c) in courses {
        for (t, r) in c {
            s.push_str(&format!("{i},{},{}\n", num(*t), num(*r)));
        }
    }
    s
}

/// Read `courses.csv`, grouped by run index (ascending).
pub fn parse_courses(text: &str) -> Vec<(usize, Vec<(f64, f64)>)> {
    let mut map: std::collections::BTreeMap<usize, Vec<(f64, f64)>> = Default::default();
    for l in text.lines().skip(1) {
        let f: Vec<&str> = l.split(',').collect();
        if let (3, Some(i), Some(t), Some(r)) = (
            f.len(),
            f.first().and_then(|s| s.parse::<usize>().ok()),
            f.get(1).and_then(|s| s.parse::<f64>().ok()),
            f.get(2).and_then(|s| s.parse::<f64>().ok()),
        ) {
            map.entry(i).or_default().push((t, r));
        }
    }
    map.into_iter().collect()
}

/// The journal folder of an output folder: `DIR.partial` beside it
/// ([`crate::report::journal`]).
pub fn journal_dir(out: &Path) -> PathBuf {
    crate::report::journal::dir_of(out)
}

fn thin(points: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    if points.len() <= COURSE_POINTS {
        return points;
    }
    let step = points.len().div_ceil(COURSE_POINTS);
    let last = points.len() - 1;
    points
        .into_iter()
        .enumerate()
        .filter(|(i, _)| i % step == 0 || *i == last)
        .map(|p| p.1)
        .collect()
}

/// Check before any run that every parameter can be set at both ends of its range in the
/// phantom, and that every metric's bubble exists.
pub fn validate(study: &Study) -> Result<(), Error> {
    let base = build_params(&study.doc, &study.phantom_path)?;
    let bubbles = crate::fit::data::bubble_count(&base);
    for p in &study.spec.params {
        for v in [p.lo, p.hi] {
            let mut t = study.doc.clone();
            paths::apply(&mut t, &p.path, v).map_err(|m| {
                InputError::new(m)
                    .in_file(&study.phantom_path)
                    .field(format!("--param {}", p.path))
            })?;
            build_params(&t, &study.phantom_path).map_err(|e| {
                InputError::new(format!("{} = {v}: {}", p.path, e.message))
                    .in_file(&study.phantom_path)
                    .field(format!("--param {}", p.path))
            })?;
        }
    }
    for m in &study.spec.metrics {
        if let Some(b) = m.bubble.filter(|b| *b >= bubbles) {
            return Err(InputError::new(format!(
                "metric '{}': the phantom has {bubbles} bubble(s), 0-based, so there is no bubble {b}",
                m.name()
            ))
            .in_file("<command line>")
            .field("--metric")
            .into());
        }
    }
    Ok(())
}

/// One run of the design: its metrics and radius course (NaN metrics if the solver failed).
fn one(study: &Study, index: usize, values: &[f64]) -> (Row, Vec<(f64, f64)>) {
    let mut doc = study.doc.clone();
    let ok = study
        .spec
        .params
        .iter()
        .zip(values)
        .try_for_each(|(p, v)| paths::apply(&mut doc, &p.path, *v));
    let run = ok
        .ok()
        .and_then(|_| build_params(&doc, &study.phantom_path).ok())
        .and_then(|params| run_one(&params, &study.profile).ok());
    let nan = vec![f64::NAN; study.spec.metrics.len()];
    let (metrics, course) = match &run {
        Some(r) => (
            study.spec.metrics.iter().map(|m| m.of(r)).collect(),
            thin(super::metric::track(r, None)),
        ),
        None => (nan, Vec::new()),
    };
    (
        Row {
            index,
            values: values.to_vec(),
            metrics,
        },
        course,
    )
}

/// Run the study's shard: skip the runs the journal holds, run the rest in parallel (each
/// appended to the journal as it finishes), write `out` whole (sensitivity.csv, courses.csv,
/// design.toml; for the whole design also indices.csv and the report) and remove the journal.
/// Before any run: the design's size ([`StudySpec::check_size`]), the shard against it
/// ([`Shard::check`]) and the parameters and metrics ([`validate`]).
pub fn run_study(
    study: &Study,
    shard: Shard,
    out: &Path,
    command: &str,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Results, Error> {
    let spec = &study.spec;
    let n = spec.check_size()?;
    shard.check(n)?;
    validate(study)?;
    let values = spec.values();
    let range = shard.range(values.len());
    let id = Identity {
        design: spec.fingerprint(),
        inputs: InputsId::of(&study.doc, &study.profile),
    };
    let fp = journal_header(&id, shard);
    check_journal(out, &fp, &id, shard)?;
    let names = JOURNAL_FILES;
    let mut done: Vec<Row> = Vec::new();
    let mut courses: Vec<(usize, Vec<(f64, f64)>)> = Vec::new();
    if let Some(texts) = Journal::previous(out, &fp, &names, "study")? {
        done = parse_rows(&texts[0], spec);
        done.retain(|r| range.contains(&r.index));
        done.sort_by_key(|r| r.index);
        done.dedup_by_key(|r| r.index);
        let ids: std::collections::HashSet<usize> = done.iter().map(|r| r.index).collect();
        courses = parse_courses(&texts[1]);
        courses.retain(|c| ids.contains(&c.0));
    }
    // rewrite the journal whole (drops a line cut by a kill, and courses of unfinished runs)
    let mut text = format!("{}\n", header(spec));
    for r in &done {
        text.push_str(&row_line(r));
        text.push('\n');
    }
    let journal = Journal::start(out, &fp, &names, &[text, courses_text(&courses)])?;

    let resumed = done.len();
    let have: std::collections::HashSet<usize> = done.iter().map(|r| r.index).collect();
    let pending: Vec<usize> = range.clone().filter(|i| !have.contains(i)).collect();
    let total = range.len();
    let count = AtomicUsize::new(resumed);
    progress(resumed, total);
    let fresh: Vec<Result<(Row, Course), Error>> = pending
        .par_iter()
        .map(|&i| {
            let (row, course) = one(study, i, &values[i]);
            // the course first: a run counts as done once its row is in
            let c: String = course
                .iter()
                .map(|(t, r)| format!("{i},{},{}\n", num(*t), num(*r)))
                .collect();
            journal.append(&[format!("{}\n", row_line(&row)), c])?;
            progress(count.fetch_add(1, Ordering::Relaxed) + 1, total);
            Ok((row, course))
        })
        .collect();
    for r in fresh {
        let (row, course) = r?;
        courses.push((row.index, course));
        done.push(row);
    }
    done.sort_by_key(|r| r.index);
    courses.sort_by_key(|c| c.0);
    let results = Results {
        spec: spec.clone(),
        shard,
        rows: done,
        courses,
        resumed,
        inputs: Some(id.inputs),
    };
    let set = outputs(&results, shard, command)?;
    set.commit(out)?;
    journal.finish();
    Ok(results)
}

/// Run every run of a study in memory (no journal, no output folder), in parallel; for callers
/// that put the study's files into a larger output set (`reproduce fig3`).
pub fn run_all(study: &Study, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<Results, Error> {
    study.spec.check_size()?;
    validate(study)?;
    let values = study.spec.values();
    let total = values.len();
    let count = AtomicUsize::new(0);
    let mut out: Vec<(Row, Course)> = values
        .par_iter()
        .enumerate()
        .map(|(i, v)| {
            let r = one(study, i, v);
            progress(count.fetch_add(1, Ordering::Relaxed) + 1, total);
            r
        })
        .collect();
    out.sort_by_key(|r| r.0.index);
    let (rows, courses) = out
        .into_iter()
        .map(|(r, c)| (r.clone(), (r.index, c)))
        .unzip();
    Ok(Results {
        spec: study.spec.clone(),
        shard: Shard::WHOLE,
        rows,
        courses,
        resumed: 0,
        // reproduce's folders are figures, not shards to merge: their design.toml stays as it was
        inputs: None,
    })
}

/// The files of a finished shard (or whole study).
pub fn outputs(res: &Results, shard: Shard, command: &str) -> Result<OutputSet, Error> {
    let spec = &res.spec;
    let mut set = OutputSet::new();
    let mut csv = format!("{}\n", header(spec));
    for r in &res.rows {
        csv.push_str(&row_line(r));
        csv.push('\n');
    }
    set.add("sensitivity.csv", csv);
    set.add("courses.csv", courses_text(&res.courses));
    let mut d = toml::Table::new();
    d.insert("design".into(), spec.fingerprint().into());
    d.insert(
        "shard".into(),
        format!("{}/{}", shard.index, shard.count).into(),
    );
    d.insert("runs".into(), (spec.values().len() as i64).into());
    d.insert("command".into(), command.to_string().into());
    if let Some(i) = &res.inputs {
        i.to_table(&mut d);
    }
    set.add(
        "design.toml",
        toml::to_string(&d).map_err(|e| Error::Solver(format!("design.toml: {e}")))?,
    );
    if shard.count == 1 {
        report::add_indices_and_report(&mut set, res, command)?;
    }
    Ok(set)
}

/// Refuse an output folder inside one of the input folders (`merge DIR --out DIR/sub`), which
/// would change an input; [`crate::report::output::check_target`] covers the output being an
/// input or holding one. The nearest existing ancestor of `out` is resolved (symlinks, `..`).
fn check_out_not_inside(out: &Path, inputs: &[PathBuf]) -> Result<(), Error> {
    let Some(anc) = crate::report::output::existing_ancestor(out) else {
        return Ok(());
    };
    for d in inputs {
        if std::fs::canonicalize(d).is_ok_and(|d| anc.starts_with(d)) {
            return Err(InputError::new(format!(
                "the output folder lies inside an input of this run ({}); outputs never change inputs: choose a folder outside it",
                d.display()
            ))
            .in_file(out)
            .field("--out")
            .into());
        }
    }
    Ok(())
}

/// Merge shard folders (each with design.toml, sensitivity.csv, courses.csv) of one design
/// into a whole study, and write it with its indices and report to `out`. `out` is checked
/// before anything is read: it may not be, hold, or lie inside one of `dirs` (exit 2 naming
/// `--out`, nothing written). Every folder must hold the first folder's design and have been
/// run on the same inputs ([`InputsId`]: phantom, profile, version); a folder that differs, or
/// that does not record its inputs, is refused (exit 2 naming it and what differs).
pub fn merge(dirs: &[PathBuf], out: &Path, command: &str) -> Result<Results, Error> {
    let bad = |d: &Path, m: String| -> Error {
        InputError::new(m).in_file(d).field("design.toml").into()
    };
    // the first folder, its identity and design
    let mut spec: Option<(&Path, Identity, StudySpec)> = None;
    let mut rows: Vec<Row> = Vec::new();
    let mut courses = Vec::new();
    if dirs.is_empty() {
        return Err(InputError::new("give the shard folders to merge")
            .in_file("<command line>")
            .field("DIR")
            .into());
    }
    let inputs: Vec<&Path> = dirs.iter().map(PathBuf::as_path).collect();
    crate::report::output::check_target(out, &inputs)?;
    check_out_not_inside(out, dirs)?;
    for d in dirs {
        let dt = d.join("design.toml");
        let text = std::fs::read_to_string(&dt)
            .map_err(|e| bad(d, format!("not a sensitivity output folder: {e}")))?;
        let t: toml::Table = text
            .parse()
            .map_err(|e| bad(&dt, format!("cannot read: {e}")))?;
        let fp = t
            .get("design")
            .and_then(|v| v.as_str())
            .ok_or_else(|| bad(&dt, "no 'design' entry".into()))?
            .to_string();
        let s = StudySpec::from_fingerprint(&fp)
            .ok_or_else(|| bad(&dt, format!("cannot read the design '{fp}'")))?;
        // the design is built below: its size is checked first, as `sensitivity` does
        s.check_size().map_err(|e| bad(&dt, e.message))?;
        let recorded = InputsId::from_table(&t).ok_or_else(|| {
            bad(
                &dt,
                format!(
                    "no record of the phantom and profile '{}' was run on ({PHANTOM_KEY}, {PROFILE_KEY}, {VERSION_KEY}: written by an older decophantom?), so it cannot be checked against the other shards: run that shard again",
                    d.display()
                ),
            )
        })?;
        let id = Identity {
            design: fp,
            inputs: recorded,
        };
        if let Some((d0, id0, _)) = &spec {
            let there = format!("in '{}'", d.display());
            let here = format!("in '{}'", d0.display());
            let diff = differences(&id, id0, &there, &here);
            if !diff.is_empty() {
                return Err(bad(
                    &dt,
                    format!(
                        "'{}' is not a shard of the same study as the first folder '{}': it differs in {}; merge only the shards of one study (the same phantom, profile and settings)",
                        d.display(),
                        d0.display(),
                        diff.join("; and in ")
                    ),
                ));
            }
        }
        let s = &spec.get_or_insert((d.as_path(), id, s)).2;
        let csv = d.join("sensitivity.csv");
        rows.extend(parse_rows(
            &std::fs::read_to_string(&csv).map_err(Error::io_at(&csv))?,
            s,
        ));
        courses.extend(parse_courses(
            &std::fs::read_to_string(d.join("courses.csv")).unwrap_or_default(),
        ));
    }
    let Some((_, id, spec)) = spec else {
        unreachable!("dirs is not empty")
    };
    rows.sort_by_key(|r| r.index);
    courses.sort_by_key(|c| c.0);
    let n = spec.values().len();
    let dup = rows.windows(2).find(|w| w[0].index == w[1].index);
    if let Some(w) = dup {
        return Err(InputError::new(format!(
            "run {} is in more than one shard folder",
            w[0].index
        ))
        .in_file("<command line>")
        .field("DIR")
        .into());
    }
    if rows.len() != n {
        let have: std::collections::HashSet<usize> = rows.iter().map(|r| r.index).collect();
        let missing: Vec<String> = (0..n)
            .filter(|i| !have.contains(i))
            .take(10)
            .map(|i| i.to_string())
            .collect();
        return Err(InputError::new(format!(
            "the shards hold {} of the design's {n} runs; missing runs {}…: merge every shard's folder",
            rows.len(),
            missing.join(", ")
        ))
        .in_file("<command line>")
        .field("DIR")
        .into());
    }
    let res = Results {
        spec,
        shard: Shard::WHOLE,
        rows,
        courses,
        resumed: 0,
        inputs: Some(id.inputs),
    };
    outputs(&res, Shard::WHOLE, command)?.commit_with_inputs(out, &inputs)?;
    Ok(res)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gas::GasMix;

    const PHANTOM: &str = "[geometry]\nshape = \"box\"\nsize_m = [3.2e-3, 3.2e-3, 3.2e-3]\ngrid_step_m = 400e-6\n\n[material]\nsurface_tension = 0.07\n";

    fn history(label: &str, start_pa: f64) -> PressureHistory {
        PressureHistory::new(
            label,
            vec![0.0, 10.0, 60.0],
            vec![start_pa, 101_325.0, 101_325.0],
            vec![GasMix::AIR; 2],
            0.0,
        )
        .unwrap()
    }

    #[test]
    fn sweep_inputs_id_changes_with_the_phantom_and_profile_not_their_spelling_or_threads() {
        let doc: toml::Table = PHANTOM.parse().unwrap();
        let prof = history("prof", 2.4e5);
        let id = InputsId::of(&doc, &prof);
        assert_eq!(id.phantom.len(), 32);
        assert_eq!(id.version, env!("CARGO_PKG_VERSION"));
        // the phantom: another value changes it (the grid step too), another spelling of the
        // same document does not
        let other: toml::Table = PHANTOM
            .replace("surface_tension = 0.07", "surface_tension = 0.05")
            .parse()
            .unwrap();
        let finer: toml::Table = PHANTOM.replace("400e-6", "200e-6").parse().unwrap();
        let respelled: toml::Table = format!(
            "# the same phantom, another layout\n{}",
            PHANTOM.replace("400e-6", "0.0004").replace(" = ", "=")
        )
        .parse()
        .unwrap();
        assert_ne!(InputsId::of(&other, &prof).phantom, id.phantom);
        assert_ne!(InputsId::of(&finer, &prof).phantom, id.phantom);
        assert_eq!(InputsId::of(&respelled, &prof), id);
        // the profile: another pressure or gas changes it, its label (the file's name) does not
        assert_ne!(
            InputsId::of(&doc, &history("prof", 5.1e5)).profile,
            id.profile
        );
        let mut nitrox = prof.clone();
        nitrox.gas = vec![GasMix::new(0.32, 0.0).unwrap(); 2];
        assert_ne!(InputsId::of(&doc, &nitrox).profile, id.profile);
        assert_eq!(InputsId::of(&doc, &history("prof60", 2.4e5)), id);
        // nor the thread count the study runs on
        for threads in [1, 2] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            assert_eq!(pool.install(|| InputsId::of(&doc, &prof)), id, "{threads}");
        }
    }

    #[test]
    fn sweep_journal_header_reads_back_and_differences_name_what_differs() {
        let doc: toml::Table = PHANTOM.parse().unwrap();
        let id = Identity {
            design: "method=oat samples=3 seed=1 params=a.x=0..1 metrics=r_max base=0.5".into(),
            inputs: InputsId::of(&doc, &history("p", 2.4e5)),
        };
        let shard = Shard { index: 1, count: 3 };
        let h = journal_header(&id, shard);
        assert!(h.starts_with("# method=oat samples=3 "), "{h}");
        let (back, s) = parse_journal_header(&h).unwrap();
        assert_eq!((back, s.as_str()), (id.clone(), "1/3"));
        // an older decophantom's header (no hashes) is not read as one of these
        assert!(parse_journal_header(&format!("# {} shard=0/1", id.design)).is_none());
        assert!(differences(&id, &id, "a", "b").is_empty());
        let other = Identity {
            inputs: InputsId::of(&doc, &history("p", 5.1e5)),
            ..id.clone()
        };
        let d = differences(&other, &id, "in 'x'", "in 'y'");
        assert_eq!(d.len(), 1, "{d:?}");
        assert!(
            d[0].starts_with("the profile (--profile")
                && d[0].contains(&format!(
                    "{} in 'x', {} in 'y'",
                    other.inputs.profile, id.inputs.profile
                )),
            "{d:?}"
        );
        let seed = Identity {
            design: id.design.replace("seed=1", "seed=2"),
            ..id.clone()
        };
        let d = differences(&seed, &id, "in 'x'", "in 'y'");
        assert_eq!(d.len(), 1, "{d:?}");
        assert!(
            d[0].contains("in 'x': method=oat samples=3 seed=2"),
            "{d:?}"
        );
        assert!(
            d[0].contains("in 'y': method=oat samples=3 seed=1"),
            "{d:?}"
        );
    }
}
