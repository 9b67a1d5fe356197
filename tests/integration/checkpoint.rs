//! `simulate --checkpoint-every` / `--resume` (issue 11, "Long work survives interruption"):
//! a run stopped at a random step (the hidden `--checkpoint-at-step` hook, a SIGKILL, a
//! Ctrl-C) and resumed writes the same bytes as an uninterrupted run; checkpoints of other
//! inputs, of another format version, truncated or corrupt are refused with exit 2 naming the
//! file and what is wrong, never a panic.

use crate::common::{bin, tempdir};
use decophantom::phantom::checkpoint::{self, DecodeError};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A 2 mm cube at h = 100 µm with two bubbles that displace the gel (from R ≥ 1 h), grow and
/// coalesce during the ascent: every part of the state takes part.
const PHANTOM: &str = r#"
name = "checkpoint test"
[geometry]
shape = "box"
size_m = [2.0e-3, 2.0e-3, 2.0e-3]
grid_step_m = 100e-6
[material]
surface_tension = 0.07
[material.elasticity]
law = "none"
[gases.n2]
diffusivity = 2.5e-9
ostwald = 0.014
[gases.o2]
diffusivity = 2.5e-9
ostwald = 0.027
[nuclei]
min_radius_m = 50e-6
[[bubbles]]
position_m = [0.8e-3, 1.0e-3, 1.0e-3]
initial_radius_m = 150e-6
[[bubbles]]
position_m = [1.25e-3, 1.0e-3, 1.0e-3]
initial_radius_m = 120e-6
[numerics]
record_interval_s = 1.0
displace_min_cells = 1.0
"#;

/// 1 min to 130 psi, 140 s there, 10 s up, 90 s at the surface (5 min simulated).
const DIVE: &str = r#"
name = "short dive"
time_unit = "s"
pressure_unit = "psi-gauge"
gas = "air"
points = [[0, 0], [60, 130], [200, 130], [210, 0], [300, 0]]
"#;

const OUTPUTS: [&str; 4] = ["bubbles.csv", "summary.toml", "radius.svg", "volume.svg"];

struct Case {
    dir: PathBuf,
    profile: PathBuf,
    phantom: PathBuf,
}

impl Case {
    fn new(name: &str) -> Case {
        Case::with_phantom(name, PHANTOM)
    }

    fn with_phantom(name: &str, phantom_text: &str) -> Case {
        let dir = tempdir(name);
        let profile = dir.join("dive.toml");
        let phantom = dir.join("phantom.toml");
        std::fs::write(&profile, DIVE).unwrap();
        std::fs::write(&phantom, phantom_text).unwrap();
        Case {
            dir,
            profile,
            phantom,
        }
    }

    fn command(&self, out: &str, extra: &[&str]) -> Command {
        let mut c = Command::new(bin());
        c.args(["--quiet", "simulate", "--profile"])
            .arg(&self.profile)
            .arg("--phantom")
            .arg(&self.phantom)
            .arg("--out")
            .arg(self.dir.join(out))
            .args(extra);
        c
    }

    fn run(&self, out: &str, extra: &[&str]) -> Output {
        self.command(out, extra).output().unwrap()
    }

    fn checkpoint_dir(&self, out: &str) -> PathBuf {
        self.dir.join(format!("{out}.checkpoint"))
    }
}

fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

fn summary_value(dir: &Path, key: &str) -> String {
    let t = std::fs::read_to_string(dir.join("summary.toml")).unwrap();
    let v: toml::Table = t.parse().unwrap();
    v[key].to_string()
}

/// The outputs of `a` and `b` are the same bytes.
fn assert_same_outputs(a: &Path, b: &Path, what: &str) {
    for f in OUTPUTS {
        let x = std::fs::read(a.join(f)).unwrap();
        let y = std::fs::read(b.join(f)).unwrap();
        assert!(x.len() > 100, "{f} is nearly empty");
        assert!(x == y, "{what}: {f} differs from the uninterrupted run's");
    }
}

#[test]
fn a_run_resumed_from_a_random_step_is_byte_identical() {
    let c = Case::new("checkpoint-resume");
    let o = c.run("whole", &[]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let whole = c.dir.join("whole");
    // the case exercises what a checkpoint must carry: both bubbles grow, displace the gel
    // and coalesce; hundreds of steps, some implicit
    assert_eq!(summary_value(&whole, "ending"), "\"completed\"");
    assert!(summary_value(&whole, "events").contains("coalesced"));
    let steps: usize = summary_value(&whole, "steps_explicit")
        .parse::<usize>()
        .unwrap()
        + summary_value(&whole, "steps_implicit")
            .parse::<usize>()
            .unwrap();
    assert!(steps > 400, "{steps} steps");
    let rows = std::fs::read_to_string(whole.join("bubbles.csv"))
        .unwrap()
        .lines()
        .count();
    assert!(rows > 300, "{rows} rows");

    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20261123);
    for round in 0..3 {
        let n = rng.gen_range(1..steps);
        let out = format!("stopped{round}");
        let o = c.run(&out, &["--checkpoint-at-step", &n.to_string()]);
        // stopped as an interrupted run: exit 130, the partial run written, the checkpoint kept
        assert_eq!(o.status.code(), Some(130), "{}", text(&o.stderr));
        let err = text(&o.stderr);
        let ck = c.checkpoint_dir(&out);
        assert!(
            err.contains("--resume") && err.contains(&ck.display().to_string()),
            "{err}"
        );
        let file = ck.join(checkpoint::FILE_NAME);
        let cp = checkpoint::decode(&std::fs::read(&file).unwrap()).unwrap();
        let (e, i) = cp.state.steps();
        assert_eq!(e + i, n, "the checkpoint is taken after step {n}");
        assert!(cp.state.time() > 0.0 && cp.state.time() < 300.0);
        assert!(!cp.frames.is_empty());
        // resume into another folder: the same bytes as the uninterrupted run
        let resumed = format!("resumed{round}");
        let o = c.run(&resumed, &["--resume", ck.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert!(
            text(&o.stdout).contains(&format!(
                "resumed from a checkpoint at t = {:.1} s",
                cp.state.time()
            )),
            "{}",
            text(&o.stdout)
        );
        assert_same_outputs(&whole, &c.dir.join(&resumed), &format!("step {n}"));
        // a completed run removes the checkpoint it resumed from, and its folder
        assert!(!file.exists() && !ck.exists());
    }
}

/// The gel of [`SKIN_PHANTOM`] (open at the top), with one bubble that the compression shuts
/// (R_min = 90 µm): the 140 s at 130 psi is a hold with every bubble shut, taken in
/// Richardson-extrapolated steps sized by the loading's second-order estimate, whose two
/// steps of history the checkpoint carries (format 4).
fn hold_phantom() -> String {
    // SKIN_PHANTOM's gel, without its nucleation
    let gel = SKIN_PHANTOM.split("[nucleation]").next().unwrap();
    format!(
        "{}[nuclei]\nmin_radius_m = 90e-6\n[[bubbles]]\nposition_m = [1.0e-3, 1.0e-3, 0.8e-3]\n\
         initial_radius_m = 100e-6\n[numerics]\nrecord_interval_s = 1.0\n",
        gel.replace("nucleating", "extrapolated hold")
    )
}

#[test]
fn a_run_resumed_within_an_extrapolated_hold_is_byte_identical() {
    let c = Case::with_phantom("checkpoint-hold", &hold_phantom());
    let o = c.run("whole", &["--trace-steps"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let whole = c.dir.join("whole");
    // the steps of the hold at 130 psi (60–200 s) that are extrapolated, by their number
    let steps = std::fs::read_to_string(whole.join("steps.csv")).unwrap();
    let held: Vec<usize> = steps
        .lines()
        .skip(1)
        .enumerate()
        .filter(|(_, l)| {
            let f: Vec<&str> = l.split(',').collect();
            let t: f64 = f[0].parse().unwrap();
            f[2] == "extrapolated" && t > 60.0 && t < 200.0
        })
        .map(|(i, _)| i + 1)
        .collect();
    assert!(
        held.len() >= 5,
        "{} extrapolated steps in the hold",
        held.len()
    );
    // stop after the hold's third extrapolated step (two steps of history behind the next)
    // and after its second-to-last
    stop_and_resume(&c, &whole, &[held[2], held[held.len() - 2]]);
}

/// Stop `c`'s run after each of `steps` and resume it: the same bytes as `whole`.
fn stop_and_resume(c: &Case, whole: &Path, steps: &[usize]) {
    for (k, n) in steps.iter().enumerate() {
        let out = format!("stopped{k}");
        let o = c.run(&out, &["--checkpoint-at-step", &n.to_string()]);
        assert_eq!(o.status.code(), Some(130), "{}", text(&o.stderr));
        let ck = c.checkpoint_dir(&out);
        let resumed = format!("resumed{k}");
        let o = c.run(&resumed, &["--resume", ck.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert_same_outputs(whole, &c.dir.join(&resumed), &format!("step {n}"));
    }
}

/// The gel of [`PHANTOM`] open at the top, without placed bubbles, holding 20 micronuclei with
/// VPM skins (γc = 0.257 N/m): the compression crushes them (each cell keeps the largest crushing
/// pressure it has seen, part of the state) and the ascent activates some.
const SKIN_PHANTOM: &str = r#"
name = "checkpoint test, nucleating"
[geometry]
shape = "box"
size_m = [2.0e-3, 2.0e-3, 2.0e-3]
grid_step_m = 100e-6
open_faces = ["top"]
[material]
surface_tension = 0.07
[material.elasticity]
law = "none"
[gases.n2]
diffusivity = 2.5e-9
ostwald = 0.014
[gases.o2]
diffusivity = 2.5e-9
ostwald = 0.027
[nucleation]
model = "critical-radius"
number_density_per_m3 = 2.5e9
slope_per_m = 5e5
skin_compression = 0.257
seed = 3
[numerics]
record_interval_s = 1.0
"#;

#[test]
fn a_nucleating_run_with_crushed_skins_resumes_to_the_same_bytes() {
    let c = Case::with_phantom("checkpoint-skins", SKIN_PHANTOM);
    let o = c.run("whole", &[]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let whole = c.dir.join("whole");
    // nuclei activated (no bubble was placed, so every row of bubbles.csv is a nucleated one)
    let rows = std::fs::read_to_string(whole.join("bubbles.csv"))
        .unwrap()
        .lines()
        .count();
    assert!(rows > 10, "{rows} rows: nothing nucleated");
    let steps: usize = summary_value(&whole, "steps_explicit")
        .parse::<usize>()
        .unwrap()
        + summary_value(&whole, "steps_implicit")
            .parse::<usize>()
            .unwrap();
    // stop at the bottom (after the crushing, before the activations) and near the end
    stop_and_resume(&c, &whole, &[steps / 4, 3 * steps / 4]);
}

#[test]
fn a_run_killed_while_checkpointing_resumes_to_the_same_bytes() {
    let c = Case::new("checkpoint-kill");
    let o = c.run("whole", &[]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // a checkpoint every 20 ms, SIGKILL as soon as a checkpoint exists plus a seeded delay
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let delay = std::time::Duration::from_millis(rng.gen_range(0..60));
    let file = c.checkpoint_dir("killed").join(checkpoint::FILE_NAME);
    let mut child = c
        .command("killed", &["--checkpoint-every", "0.02s"])
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !file.exists() {
        if let Some(status) = child.try_wait().unwrap() {
            // finished (and removed its checkpoint) between two looks: nothing to resume
            assert!(status.success());
            return;
        }
        assert!(start.elapsed().as_secs() < 20, "no checkpoint appeared");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    std::thread::sleep(delay);
    let _ = child.kill();
    let status = child.wait().unwrap();
    if status.success() {
        // the machine was fast enough to finish first: nothing left to resume
        return;
    }
    assert!(
        !c.dir.join("killed").exists(),
        "a killed run writes no output"
    );
    let o = c.run(
        "resumed",
        &["--resume", c.checkpoint_dir("killed").to_str().unwrap()],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_same_outputs(
        &c.dir.join("whole"),
        &c.dir.join("resumed"),
        "after SIGKILL",
    );
    // the killed writer's temporary file, if any, went with the checkpoint
    assert!(!c.checkpoint_dir("killed").exists());
}

#[test]
fn ctrl_c_saves_a_checkpoint_that_resumes_to_the_same_bytes() {
    let c = Case::new("checkpoint-sigint");
    let o = c.run("whole", &[]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // the signal goes once the run is under way (its first checkpoint, after 50 ms, tells
    // when: the Ctrl-C handler is in place by then)
    let file = c.checkpoint_dir("stopped").join(checkpoint::FILE_NAME);
    let mut child = c
        .command("stopped", &["--checkpoint-every", "0.05s"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while !file.exists() && child.try_wait().unwrap().is_none() {
        assert!(start.elapsed().as_secs() < 20, "no checkpoint appeared");
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
    let _ = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    let o = child.wait_with_output().unwrap();
    if o.status.success() {
        return; // finished before the signal
    }
    assert_eq!(o.status.code(), Some(130), "{}", text(&o.stderr));
    // Ctrl-C: one more step, the checkpoint of the step before the stop, the partial run
    let cp = checkpoint::decode(&std::fs::read(&file).unwrap()).unwrap();
    let stopped = c.dir.join("stopped");
    let steps: usize = summary_value(&stopped, "steps_explicit")
        .parse::<usize>()
        .unwrap()
        + summary_value(&stopped, "steps_implicit")
            .parse::<usize>()
            .unwrap();
    let (e, i) = cp.state.steps();
    assert_eq!(e + i + 1, steps, "{}", text(&o.stderr));
    let end: f64 = summary_value(&stopped, "end_time_s").parse().unwrap();
    assert!(cp.state.time() < end && end < 300.0);
    let o = c.run("resumed", &["--resume", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_same_outputs(&c.dir.join("whole"), &c.dir.join("resumed"), "after Ctrl-C");
}

/// A checkpoint of the test case after step 40, its file.
fn checkpoint_of(c: &Case) -> PathBuf {
    let o = c.run("stopped", &["--checkpoint-at-step", "40"]);
    assert_eq!(o.status.code(), Some(130), "{}", text(&o.stderr));
    c.checkpoint_dir("stopped").join(checkpoint::FILE_NAME)
}

/// Resume `c` from `file` into `out`: exit 2 with a message naming the file, nothing written.
fn refused(c: &Case, file: &Path, out: &str) -> String {
    let o = c.run(out, &["--resume", file.to_str().unwrap()]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains(&file.display().to_string()), "{err}");
    assert!(err.contains("--resume"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(!c.dir.join(out).exists(), "a refused resume writes nothing");
    err
}

#[test]
fn a_checkpoint_of_other_inputs_is_refused_naming_what_differs() {
    let c = Case::new("checkpoint-inputs");
    let file = checkpoint_of(&c);
    // the same inputs under another file name resume (paths play no part) …
    let renamed = c.dir.join("same-dive-renamed.toml");
    std::fs::copy(&c.profile, &renamed).unwrap();
    // … but another surface tension does not
    std::fs::write(&c.phantom, PHANTOM.replace("0.07", "0.05")).unwrap();
    let err = refused(&c, &file, "other-phantom");
    assert!(err.contains("other inputs"), "{err}");
    assert!(
        err.contains("the phantom differs: surface_tension: `surface_tension: 0.05` here, `surface_tension: 0.07` in the checkpoint"),
        "{err}"
    );
    // a deeper field: its path
    std::fs::write(
        &c.phantom,
        PHANTOM.replace("ostwald = 0.027", "ostwald = 0.026"),
    )
    .unwrap();
    let err = refused(&c, &file, "other-gas");
    assert!(
        err.contains("gases.ostwald: `ostwald: 0.026` here, `ostwald: 0.027`"),
        "{err}"
    );
    // another profile: the first breakpoint that differs
    std::fs::write(&c.phantom, PHANTOM).unwrap();
    std::fs::write(&c.profile, DIVE.replace("[200, 130]", "[190, 130]")).unwrap();
    let err = refused(&c, &file, "other-profile");
    assert!(
        err.contains("the profile differs: breakpoints.2: `2: t 190.0 s"),
        "{err}"
    );
    // the original inputs, the profile under its new name: accepted, same bytes as afresh
    std::fs::write(&c.profile, DIVE).unwrap();
    let o = Command::new(bin())
        .args(["--quiet", "simulate", "--profile"])
        .arg(&renamed)
        .arg("--phantom")
        .arg(&c.phantom)
        .arg("--out")
        .arg(c.dir.join("resumed"))
        .arg("--resume")
        .arg(&file)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = c.run("whole", &[]);
    assert!(o.status.success());
    let a = std::fs::read(c.dir.join("whole/bubbles.csv")).unwrap();
    let b = std::fs::read(c.dir.join("resumed/bubbles.csv")).unwrap();
    assert!(a == b);
}

#[test]
fn checkpoints_of_another_version_truncated_or_corrupt_are_refused() {
    let c = Case::new("checkpoint-corrupt");
    let file = checkpoint_of(&c);
    let good = std::fs::read(&file).unwrap();
    assert_eq!(&good[..8], checkpoint::MAGIC);
    let put = |name: &str, bytes: &[u8]| -> PathBuf {
        let p = c.dir.join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    };
    // another format version
    let other = checkpoint::FORMAT_VERSION + 1;
    let mut v2 = good.clone();
    v2[8..12].copy_from_slice(&other.to_le_bytes());
    let err = refused(&c, &put("v2.dcp", &v2), "out-v2");
    assert!(
        err.contains(&format!("format version {other}"))
            && err.contains(&format!("reads version {}", checkpoint::FORMAT_VERSION)),
        "{err}"
    );
    // another decophantom version (the checksum made right: only the version differs)
    let version = env!("CARGO_PKG_VERSION");
    let at = good
        .windows(version.len())
        .position(|w| w == version.as_bytes())
        .unwrap();
    let mut other = good.clone();
    other[at] = b'9';
    let n = other.len() - 8;
    let sum = checkpoint::fnv1a(&other[..n]);
    other[n..].copy_from_slice(&sum.to_le_bytes());
    let err = refused(&c, &put("other.dcp", &other), "out-other");
    assert!(err.contains("written by decophantom 9"), "{err}");
    // truncated (a half-copied file)
    let err = refused(&c, &put("half.dcp", &good[..good.len() / 2]), "out-half");
    assert!(err.contains("truncated"), "{err}");
    // one byte changed in the middle of the gas fields
    let mut flipped = good.clone();
    flipped[good.len() / 2] ^= 0x10;
    let err = refused(&c, &put("flipped.dcp", &flipped), "out-flipped");
    assert!(err.contains("checksum"), "{err}");
    // not a checkpoint at all, and an empty file
    let err = refused(&c, &c.profile.clone(), "out-toml");
    assert!(err.contains("not a decophantom checkpoint"), "{err}");
    let err = refused(&c, &put("empty.dcp", b""), "out-empty");
    assert!(err.contains("not a decophantom checkpoint"), "{err}");
    // a missing file
    let err = refused(&c, &c.dir.join("nowhere.dcp"), "out-missing");
    assert!(err.contains("cannot read"), "{err}");
    // the original still resumes
    let o = c.run("resumed", &["--resume", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
}

#[test]
fn decoding_mutated_checkpoints_never_panics() {
    let c = Case::new("checkpoint-mutants");
    let good = std::fs::read(checkpoint_of(&c)).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let fix = |b: &mut Vec<u8>| {
        let payload = (b.len() - 28) as u64;
        b[12..20].copy_from_slice(&payload.to_le_bytes());
        let n = b.len() - 8;
        let sum = checkpoint::fnv1a(&b[..n]);
        b[n..].copy_from_slice(&sum.to_le_bytes());
    };
    // per kind of mutation (word replaced, cut, bytes appended): (refused, read)
    let mut counts = [(0, 0); 3];
    for i in 0..400 {
        let mut b = good.clone();
        match i % 4 {
            // a random 8-byte word (a length, a count, a tag, a number) replaced, checksum fixed
            0 | 1 => {
                let at = rng.gen_range(20..b.len() - 16);
                let v: u64 = if rng.gen_bool(0.5) {
                    rng.gen()
                } else {
                    rng.gen_range(0..64)
                };
                b[at..at + 8].copy_from_slice(&v.to_le_bytes());
                fix(&mut b);
            }
            // cut anywhere, header length and checksum made consistent
            2 => {
                let n = rng.gen_range(28..b.len());
                b.truncate(n);
                fix(&mut b);
            }
            // bytes appended
            _ => {
                b.extend((0..rng.gen_range(1..64)).map(|_| rng.gen::<u8>()));
                fix(&mut b);
            }
        }
        let kind = (i % 4usize).saturating_sub(1).min(2);
        match checkpoint::decode(&b) {
            Ok(_) => counts[kind].1 += 1,
            Err(DecodeError::Corrupt(m)) => {
                assert!(!m.is_empty());
                counts[kind].0 += 1
            }
            Err(e) => panic!("unexpected {e:?}"),
        }
    }
    // a cut or appended bytes are always found (the structure no longer ends where the
    // frame says); a replaced word mostly lands in the gas fields' numbers and still reads
    assert_eq!(counts[1], (100, 0), "cuts: (refused, read)");
    assert_eq!(counts[2], (100, 0), "appended: (refused, read)");
    assert!(counts[0].1 > 0, "words replaced: {:?}", counts[0]);
    // a structural word replaced is found: the count of input sections (the first word after
    // the 20-byte header) made huge or one too many
    for v in [u64::MAX / 3, 1 << 40, 4] {
        let mut b = good.clone();
        b[20..28].copy_from_slice(&v.to_le_bytes());
        fix(&mut b);
        assert!(
            matches!(checkpoint::decode(&b), Err(DecodeError::Corrupt(_))),
            "sections count {v} read"
        );
    }
}

/// The evaluation of the `evaluate` tests' kind: two schedules × two laws in a 3 mm cube.
const EVAL_PHANTOM: &str = r#"name = "journal-gel"
[geometry]
shape = "box"
size_m = [3e-3, 3e-3, 3e-3]
grid_step_m = 150e-6
open_faces = ["top"]
[material.elasticity]
law = "hyperelastic"
shear_modulus = 40.0
[gases.n2]
diffusivity = 2.5e-9
ostwald = 0.014
[gases.o2]
diffusivity = 2.5e-9
ostwald = 0.027
[nuclei]
min_radius_m = 86.5e-6
[[bubbles]]
position_m = [1.5e-3, 1.5e-3, 1.5e-3]
initial_radius_m = 100e-6
[numerics]
max_step_s = 30.0
record_interval_s = 10.0
"#;

const EVAL_CRITERIA: &str = r#"description = "journal test"
[protocol]
observe_after_surfacing_min = 30
water_vapour_pa = 6270
[[criterion]]
kind = "peak-total-volume"
limit = 1.0
[[criterion]]
kind = "peak-radius"
limit = 1e-3
"#;

#[test]
fn evaluate_keeps_finished_runs_and_skips_them_on_restart() {
    use decophantom::app::evaluate::{plan_candidates, run_matrix_journaled, PhantomSpec};
    let d = tempdir("evaluate-journal");
    let ph = d.join("phantom.toml");
    let cr = d.join("criteria.toml");
    std::fs::write(&ph, EVAL_PHANTOM).unwrap();
    std::fs::write(&cr, EVAL_CRITERIA).unwrap();
    let algs: Vec<PathBuf> = ["zhl16c-gf30-85.toml", "zhl16c-gf100-100.toml"]
        .iter()
        .map(|n| crate::common::root().join("algorithms").join(n))
        .collect();
    let evaluate = |out: &Path| -> Output {
        let mut c = Command::new(bin());
        c.args(["evaluate", "--depth", "30", "--time", "10"]);
        for a in &algs {
            c.arg("--algorithm").arg(a);
        }
        c.args(["--elasticity", "hyperelastic,none", "--phantom"])
            .arg(&ph)
            .arg("--criteria")
            .arg(&cr)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap()
    };
    let whole = d.join("whole");
    let o = evaluate(&whole);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(!text(&o.stdout).contains("read back"));
    // an evaluation into `second` that did all four runs but never wrote its folder (as a
    // killed one would leave it): the library's journaled matrix, the journal not finished
    let second = d.join("second");
    let criteria = decophantom::risk::load_criteria(&cr).unwrap();
    let phantom = PhantomSpec::load(Some(&ph), None).unwrap();
    let laws = phantom
        .resolve_laws(&["hyperelastic".into(), "none".into()])
        .unwrap();
    let loaded: Vec<_> = algs
        .iter()
        .map(|p| {
            (
                decophantom::algorithm::load_algorithm(p).unwrap(),
                p.display().to_string(),
            )
        })
        .collect();
    let cands = plan_candidates(
        &loaded,
        30.0,
        10.0,
        None,
        &[],
        &[],
        &criteria.protocol,
        None,
    )
    .unwrap();
    let (ev, journal) = run_matrix_journaled(
        cands,
        phantom,
        laws,
        criteria,
        &mut |_, _| {},
        Some(&second),
    )
    .unwrap();
    assert_eq!((ev.runs.len(), ev.resumed), (4, 0));
    let jdir = journal.unwrap().dir().to_path_buf();
    assert_eq!(jdir, d.join("second.partial"));
    let runs = std::fs::read_to_string(jdir.join("runs.txt")).unwrap();
    let lines: Vec<&str> = runs.lines().collect();
    assert_eq!(lines.len(), 5, "{runs}");
    assert!(lines[0].starts_with("# decophantom "));
    // killed after three runs, one result file lost, the last line cut
    let key = |l: &str| l.split(' ').next().unwrap().to_string();
    std::fs::remove_file(jdir.join(format!("run-{}.dcr", key(lines[2])))).unwrap();
    std::fs::write(
        jdir.join("runs.txt"),
        format!(
            "{}\n{}\n{}\n{}\n{}",
            lines[0],
            lines[1],
            lines[2],
            lines[3],
            &lines[4][..7]
        ),
    )
    .unwrap();
    let o = evaluate(&second);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("2 of 4 runs read back from the journal"),
        "{}",
        text(&o.stdout)
    );
    // the same report as the uninterrupted evaluation (the wall times aside), journal gone
    let mut compared = 0;
    for e in std::fs::read_dir(&whole).unwrap() {
        let name = e.unwrap().file_name();
        if name == "timing.csv" {
            continue;
        }
        let a = std::fs::read(whole.join(&name)).unwrap();
        let b = std::fs::read(second.join(&name)).unwrap();
        assert!(a == b, "{name:?} differs after the restart");
        compared += 1;
    }
    assert!(compared >= 10, "{compared} files");
    assert!(!jdir.exists());
    // a journal of another evaluation is refused, not mixed in
    std::fs::create_dir_all(&jdir).unwrap();
    std::fs::write(
        jdir.join("runs.txt"),
        "# decophantom 0.1.0 evaluate runs=9 0\n",
    )
    .unwrap();
    let o = evaluate(&second);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("journal of a different evaluation"));
}

#[test]
fn a_file_that_is_not_a_checkpoint_is_never_overwritten() {
    let c = Case::new("checkpoint-user-file");
    let ck = c.checkpoint_dir("out");
    std::fs::create_dir_all(&ck).unwrap();
    let mine = ck.join(checkpoint::FILE_NAME);
    std::fs::write(&mine, "my notes\n").unwrap();
    let o = c.run("out", &["--checkpoint-every", "0.01s"]);
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("--checkpoint-every") && err.contains("not a decophantom checkpoint"));
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "my notes\n");
    assert!(!c.dir.join("out").exists());
    // a bad interval is refused before anything is simulated or created
    let o = c.run("other", &["--checkpoint-every", "0min"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(!c.checkpoint_dir("other").exists() && !c.dir.join("other").exists());
}
