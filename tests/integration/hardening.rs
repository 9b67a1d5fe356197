//! Issue 11, "never a panic, never a lost file, never a silent wrong number": one regression
//! test per case the hostile-user run found. Each case is refused as bad input (exit 2, file,
//! line and field named) before any work, stops cleanly, or leaves the user's files alone.

use crate::common::{bin, root, tempdir};
use decophantom::phantom::config::parse_phantom;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A small valid phantom; `{MATERIAL}`, `{GAS}` and `{BUBBLE}` are replaced by the cases.
const PHANTOM: &str = r#"[geometry]
shape = "box"
size_m = [2e-3, 2e-3, 2e-3]
grid_step_m = 2e-4
[material]
surface_tension = {GAMMA}
[material.elasticity]
{ELASTICITY}
[gases.n2]
diffusivity = {D}
ostwald = 0.014
[gases.o2]
diffusivity = 2.5e-9
ostwald = 0.027
[[bubbles]]
position_m = {POS}
initial_radius_m = {R0}
"#;

fn phantom(gamma: &str, elasticity: &str, d: &str, pos: &str, r0: &str) -> String {
    PHANTOM
        .replace("{GAMMA}", gamma)
        .replace("{ELASTICITY}", elasticity)
        .replace("{D}", d)
        .replace("{POS}", pos)
        .replace("{R0}", r0)
}

fn good_phantom() -> String {
    phantom(
        "0.07",
        "law = \"none\"",
        "2.5e-9",
        "[1e-3, 1e-3, 1e-3]",
        "5e-5",
    )
}

const SHORT_PROFILE: &str =
    "time_unit = \"s\"\npressure_unit = \"psi-gauge\"\npoints = [[0, 0], [5, 5], [10, 0]]\n";

/// A 10 m / 10 min schedule TOML; `{STOP_MIN}` is the stop table's only stop time.
const SCHEDULE: &str = r#"label = "t"
surface_pressure_pa = 101325.0
pa_per_m = 9985.0
water_vapour_pa = 6270.0

[[legs]]
kind = "descent"
start_depth_m = 0.0
end_depth_m = {DEPTH}
duration_s = 60.0
gas = "air"

[[legs]]
kind = "bottom"
start_depth_m = {DEPTH}
end_depth_m = {DEPTH}
duration_s = 600.0
gas = "air"

[[legs]]
kind = "ascent"
start_depth_m = {DEPTH}
end_depth_m = 0.0
duration_s = 60.0
gas = "air"

[[stops]]
depth_m = 3.0
stop_min = {STOP_MIN}
runtime_min = 12.0
gas = "air"
"#;

fn schedule(depth: &str, stop_min: &str) -> String {
    SCHEDULE
        .replace("{DEPTH}", depth)
        .replace("{STOP_MIN}", stop_min)
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn run(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(bin())
        .arg("--quiet")
        .args(args)
        .output()
        .unwrap()
}

fn criteria() -> PathBuf {
    root().join("algorithms/criteria/default.toml")
}

/// Exit code 2 and every `needles` in stderr.
fn assert_refused(o: &Output, needles: &[&str]) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    for n in needles {
        assert!(err.contains(n), "'{n}' not in: {err}");
    }
}

/// An error of `parse_phantom` naming `field` with the file and a line.
fn phantom_refused(text: &str, field: &str) {
    let e = parse_phantom(text, Path::new("p.toml")).unwrap_err();
    assert_eq!(e.field.as_deref(), Some(field), "{e}");
    assert!(e.line.is_some() && e.file.is_some(), "{e}");
}

#[test]
fn nan_bubble_position_is_refused_not_a_panic() {
    let text = phantom(
        "0.07",
        "law = \"none\"",
        "2.5e-9",
        "[nan, 1e-3, 1e-3]",
        "5e-5",
    );
    phantom_refused(&text, "bubbles.position_m");
    // a phantom built in code reaches the placement check: NaN is outside, not inside
    let mut params = decophantom::phantom::params::PhantomParams::box_phantom([2e-3; 3], 2e-4);
    params.bubbles = decophantom::phantom::params::BubblePlacement::Explicit(vec![(
        [f64::NAN, 1e-3, 1e-3],
        5e-5,
    )]);
    let grid =
        decophantom::phantom::grid::Grid::new(params.shape, params.grid_step, &params.open_faces)
            .unwrap();
    assert!(decophantom::phantom::sim::place_bubbles(&params, &grid).is_err());
}

#[test]
fn grid_step_whose_cell_count_overflows_is_refused() {
    use decophantom::phantom::grid::{Grid, Shape};
    let shape = Shape::Cylinder {
        diameter: 11e-3,
        depth: 5e-3,
    };
    assert!(Grid::new(shape, 2.561137080192566e-12, &[]).is_err());
    assert!(Grid::new(shape, 1e-300, &[]).is_err());
    let dir = tempdir("hard-gridstep");
    let csv = write(&dir, "s.csv", "time_min,depth_m\n0,0\n1,10\n10,10\n12,0\n");
    let o = run(&[
        "check".as_ref(),
        "--schedule".as_ref(),
        csv.as_os_str(),
        "--criteria".as_ref(),
        criteria().as_os_str(),
        "--grid-step".as_ref(),
        "2.561137080192566e-12".as_ref(),
    ]);
    assert_refused(&o, &["--grid-step", "too many"]);
}

#[test]
fn tiny_record_interval_is_refused_and_never_hangs() {
    let text = format!("{}[numerics]\nrecord_interval_s = 1e-308\n", good_phantom());
    phantom_refused(&text, "numerics.record_interval_s");
    // built in code, the same interval still ends (the next-frame time is jumped, not stepped)
    let mut params = parse_phantom(&good_phantom(), Path::new("p.toml"))
        .unwrap()
        .params;
    params.numerics.record_interval = 1e-308;
    let profile = decophantom::profile::toml::parse(SHORT_PROFILE, Path::new("s.toml"))
        .unwrap()
        .history;
    let t = std::time::Instant::now();
    let r = decophantom::run::simulate(&params, &profile, &mut |_, _| {}).unwrap();
    assert!(r.frames.len() > 1 && t.elapsed().as_secs() < 20);
}

#[test]
fn a_billion_repeats_are_refused_before_anything_is_built() {
    let t = std::time::Instant::now();
    let text = "time_unit = \"s\"\npressure_unit = \"psi-gauge\"\npoints = [[0, 0], [1, 0]]\nrepeat = 1000000000\n";
    let e = decophantom::profile::toml::parse(text, Path::new("r.toml")).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("repeat"));
    assert_eq!(e.line, Some(4));
    // a short period within the duration limit but with too many breakpoints
    let text = "time_unit = \"s\"\npressure_unit = \"psi-gauge\"\npoints = [[0, 0], [0.001, 1], [0.002, 0]]\nrepeat = 100000000\n";
    let e = decophantom::profile::toml::parse(text, Path::new("r.toml")).unwrap_err();
    assert!(e.message.contains("breakpoints"), "{e}");
    assert!(t.elapsed().as_secs() < 5);
}

#[test]
fn durations_beyond_thirty_days_are_refused() {
    let p = |t: &str| decophantom::profile::toml::parse(t, Path::new("d.toml"));
    // ten years of points; a leg of 3e14 s
    let e = p("time_unit = \"h\"\npressure_unit = \"bar\"\npoints = [[0, 1], [87600, 1]]\n")
        .unwrap_err();
    assert!(e.message.contains("30 days") && e.line == Some(3), "{e}");
    assert!(p("time_unit = \"s\"\npressure_unit = \"bar\"\n[[leg]]\nduration = 3e14\n").is_err());
    // exactly 30 days is accepted
    assert!(p("time_unit = \"h\"\npressure_unit = \"bar\"\npoints = [[0, 1], [720, 1]]\n").is_ok());
    // a waypoint at 1e20 min, a schedule leg of 1e20 s
    let dir = tempdir("hard-duration");
    let csv = write(
        &dir,
        "s.csv",
        "time_min,depth_m\n0,0\n1,10\n1e20,10\n1.1e20,0\n",
    );
    let o = run(&[
        "check".as_ref(),
        "--schedule".as_ref(),
        csv.as_os_str(),
        "--criteria".as_ref(),
        criteria().as_os_str(),
    ]);
    assert_refused(&o, &["30 days"]);
    let e = decophantom::algorithm::Schedule::from_toml_str(
        &schedule("10.0", "1.0").replace("duration_s = 600.0", "duration_s = 1e20"),
        Path::new("s.toml"),
    )
    .unwrap_err();
    assert_eq!(e.field.as_deref(), Some("legs.duration_s"));
    // --repeat-after 1e6 min
    let sched = write(&dir, "s.toml", &schedule("10.0", "1.0"));
    let o = run(&[
        "check".as_ref(),
        "--schedule".as_ref(),
        sched.as_os_str(),
        "--criteria".as_ref(),
        criteria().as_os_str(),
        "--repeat-after".as_ref(),
        "1e6".as_ref(),
    ]);
    assert_refused(&o, &["--repeat-after"]);
}

#[test]
fn runs_estimated_at_hours_need_force() {
    let dir = tempdir("hard-cost");
    // steps capped at 20 s: the estimate counts duration / max_step (a month at 20 s on
    // 8 M cells is hours by SECONDS_PER_CELL_STEP)
    let big = format!(
        "{}[numerics]\nmax_step_s = 20.0\n",
        good_phantom()
            .replace("[2e-3, 2e-3, 2e-3]", "[10e-3, 10e-3, 10e-3]")
            .replace("grid_step_m = 2e-4", "grid_step_m = 5e-5")
    );
    let ph = write(&dir, "big.toml", &big);
    let month = write(
        &dir,
        "month.toml",
        "time_unit = \"h\"\npressure_unit = \"psi-gauge\"\npoints = [[0, 0], [1, 10], [720, 0]]\n",
    );
    let params = parse_phantom(&big, &ph).unwrap().params;
    let history =
        decophantom::profile::toml::parse(&std::fs::read_to_string(&month).unwrap(), &month)
            .unwrap()
            .history;
    let e = decophantom::run::cost::estimate(&params, &history);
    assert!(
        e.cells == 8e6 && e.seconds > decophantom::run::cost::DEFAULT_LIMIT_S,
        "{e:?}"
    );
    let o = run(&[
        "simulate".as_ref(),
        "--profile".as_ref(),
        month.as_os_str(),
        "--phantom".as_ref(),
        ph.as_os_str(),
        "--out".as_ref(),
        dir.join("out").as_os_str(),
    ]);
    assert_refused(&o, &["--force", "estimated"]);
    assert!(!dir.join("out").exists());
}

#[test]
fn numbers_that_would_be_written_wrong_are_refused() {
    // criteria limit 1e-308 (gave -inf in scores and report)
    let e = decophantom::risk::config::parse_criteria(
        "[[criterion]]\nkind = \"peak-radius\"\nlimit = 1e-308\n",
        Path::new("c.toml"),
    )
    .unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(3), Some("criterion.limit"))
    );
    // [[stops]] of a schedule (the report showed "21×NaN")
    for bad in ["nan", "inf", "-1.0", "1e300"] {
        let e = decophantom::algorithm::Schedule::from_toml_str(
            &schedule("10.0", bad),
            Path::new("s.toml"),
        )
        .unwrap_err();
        assert_eq!(e.field.as_deref(), Some("stops.stop_min"), "{bad}: {e}");
        assert_eq!(e.line, Some(27), "{e}"); // the [[stops]] table
    }
    // depth 1e17 m in a schedule
    let e = decophantom::algorithm::Schedule::from_toml_str(
        &schedule("1e17", "1.0"),
        Path::new("s.toml"),
    )
    .unwrap_err();
    assert!(e.field.as_deref().unwrap().contains("depth_m"), "{e}");
    // plan --time 1e308 (printed "inf min", "CNS: inf %") and VPM-B --time 1e20 ("-0 min")
    for (alg, time) in [
        ("algorithms/zhl16c-gf30-85.toml", "1e308"),
        ("algorithms/vpmb-2-baker.toml", "1e20"),
    ] {
        let a = root().join(alg);
        let o = run(&[
            "plan".as_ref(),
            "--algorithm".as_ref(),
            a.as_os_str(),
            "--depth".as_ref(),
            "30".as_ref(),
            "--time".as_ref(),
            time.as_ref(),
        ]);
        assert_refused(&o, &["--time"]);
        assert!(o.stdout.is_empty());
    }
    // a non-finite score is never written: it is an error (exit 3)
    let s = decophantom::risk::Score {
        label: "x".into(),
        kind: "peak-radius",
        unit: "µm",
        value: f64::INFINITY,
        limit: 1.0,
        pass: false,
        margin: f64::NEG_INFINITY,
        absolute: None,
    };
    assert!(decophantom::risk::check_finite(std::slice::from_ref(&s)).is_err());
    // nor a finite score whose absolute value beside it is not
    let s = decophantom::risk::Score {
        value: 1.0,
        margin: 0.0,
        absolute: Some(f64::NAN),
        ..s
    };
    assert!(decophantom::risk::check_finite(&[s]).is_err());
}

#[test]
fn physical_ranges_are_bad_input_naming_the_field() {
    let none = "law = \"none\"";
    let hyper = |mu: &str| format!("law = \"hyperelastic\"\nshear_modulus = {mu}");
    let pos = "[1e-3, 1e-3, 1e-3]";
    let cases: Vec<(String, &str)> = vec![
        (
            phantom("0.07", none, "1e3", pos, "5e-5"),
            "gases.n2.diffusivity",
        ),
        (
            phantom("0.07", none, "1e-300", pos, "5e-5"),
            "gases.n2.diffusivity",
        ),
        (
            phantom("inf", none, "2.5e-9", pos, "5e-5"),
            "material.surface_tension",
        ),
        (
            phantom("0.07", none, "2.5e-9", pos, "1e-30"),
            "bubbles.initial_radius_m",
        ),
        (
            phantom("0.07", &hyper("1e308"), "2.5e-9", pos, "5e-5"),
            "material.elasticity.shear_modulus",
        ),
        (
            phantom("0.07", &hyper("-40"), "2.5e-9", pos, "5e-5"),
            "material.elasticity.shear_modulus",
        ),
        (
            phantom("0.07", &hyper("nan"), "2.5e-9", pos, "5e-5"),
            "material.elasticity.shear_modulus",
        ),
        (
            phantom("0.07", &hyper("inf"), "2.5e-9", pos, "5e-5"),
            "material.elasticity.shear_modulus",
        ),
    ];
    for (text, field) in &cases {
        phantom_refused(text, field);
    }
    // depth 1e17 m as a profile pressure
    let e = decophantom::profile::toml::parse(
        "time_unit = \"s\"\npressure_unit = \"msw\"\npoints = [[0, 0], [60, 1e17], [120, 0]]\n",
        Path::new("p.toml"),
    )
    .unwrap_err();
    assert_eq!((e.line, e.field.as_deref()), (Some(3), Some("points")));
}

#[test]
fn phantom_without_bubbles_is_refused_up_front() {
    let dir = tempdir("hard-nobubbles");
    let text = good_phantom();
    let bare = &text[..text.find("[[bubbles]]").unwrap()];
    let ph = write(&dir, "bare.toml", bare);
    let prof = write(&dir, "p.toml", SHORT_PROFILE);
    let o = run(&[
        "simulate".as_ref(),
        "--profile".as_ref(),
        prof.as_os_str(),
        "--phantom".as_ref(),
        ph.as_os_str(),
        "--out".as_ref(),
        dir.join("out").as_os_str(),
    ]);
    assert_refused(&o, &["bare.toml", "bubbles"]);
}

#[test]
fn one_point_profiles_are_refused_by_every_reader() {
    let e = decophantom::profile::toml::parse(
        "time_unit = \"s\"\npressure_unit = \"psi-gauge\"\npoints = [[0, 0]]\n",
        Path::new("one.toml"),
    )
    .unwrap_err();
    assert_eq!((e.line, e.field.as_deref()), (Some(3), Some("points")));
    let e = decophantom::algorithm::waypoints::parse_waypoints_csv(
        "time_min,depth_m\n0,0\n",
        Path::new("one.csv"),
        &decophantom::algorithm::conventions::DECOTENGU,
        decophantom::gas::GasMix::AIR,
    );
    assert!(e.is_err());
    assert!(decophantom::profile::PressureHistory::with_gas(
        "one",
        vec![0.0],
        vec![1e5],
        decophantom::gas::GasMix::AIR,
        0.0
    )
    .is_err());
}

fn simulate_into(dir: &Path, profile: &Path, phantom: &Path, out: &Path) -> Output {
    let _ = dir;
    run(&[
        "simulate".as_ref(),
        "--profile".as_ref(),
        profile.as_os_str(),
        "--phantom".as_ref(),
        phantom.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ])
}

#[test]
fn user_files_are_never_replaced_or_deleted() {
    let dir = tempdir("hard-sacred");
    let ph = write(&dir, "ph.toml", &good_phantom());
    let prof = write(&dir, "p.toml", SHORT_PROFILE);
    let out = dir.join("out");
    let o = simulate_into(&dir, &prof, &ph, &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let marker = std::fs::read_to_string(out.join(".decophantom-output")).unwrap();
    assert!(marker.contains("\nbubbles.csv\n"), "{marker}");
    // the run's own inputs inside the old output folder
    std::fs::copy(&prof, out.join("p.toml")).unwrap();
    std::fs::copy(&ph, out.join("ph.toml")).unwrap();
    let o = simulate_into(&dir, &out.join("p.toml"), &out.join("ph.toml"), &out);
    assert_refused(&o, &["--out", "input"]);
    assert!(out.join("p.toml").exists() && out.join("ph.toml").exists());
    // a file the tool did not write
    let o = simulate_into(&dir, &prof, &ph, &out);
    assert_refused(&o, &["did not write"]);
    assert_eq!(
        std::fs::read_to_string(out.join("p.toml")).unwrap(),
        SHORT_PROFILE
    );
    std::fs::remove_file(out.join("p.toml")).unwrap();
    std::fs::remove_file(out.join("ph.toml")).unwrap();
    // --out checked before the run: a file in the way
    let file = write(&dir, "afile", "mine");
    let o = simulate_into(&dir, &prof, &ph, &file);
    assert_refused(&o, &["--out", "not a folder"]);
    assert!(o.stdout.is_empty());
    // debris of a dead process (killed between two renames) is cleaned at the next run
    let dead = {
        let mut c = Command::new("true").spawn().unwrap();
        let pid = c.id();
        c.wait().unwrap();
        pid
    };
    let staging = dir.join(format!(".out.staging-{dead}-0"));
    let old = dir.join(format!(".out.old-{dead}-3"));
    std::fs::create_dir_all(&staging).unwrap();
    std::fs::create_dir_all(old.join("sub")).unwrap();
    let o = simulate_into(&dir, &prof, &ph, &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!staging.exists() && !old.exists());
    // plan --out onto its own algorithm file
    let alg = write(
        &dir,
        "alg.toml",
        &std::fs::read_to_string(root().join("algorithms/zhl16c-gf30-85.toml")).unwrap(),
    );
    let before = std::fs::read(&alg).unwrap();
    let o = run(&[
        "plan".as_ref(),
        "--algorithm".as_ref(),
        alg.as_os_str(),
        "--depth".as_ref(),
        "30".as_ref(),
        "--time".as_ref(),
        "20".as_ref(),
        "--out".as_ref(),
        dir.join(".").join("alg.toml").as_os_str(),
    ]);
    assert_refused(&o, &["--out"]);
    assert_eq!(std::fs::read(&alg).unwrap(), before);
}

#[cfg(unix)]
#[test]
fn check_stops_on_ctrl_c_and_writes_nothing() {
    let dir = tempdir("hard-sigint");
    let sched = write(&dir, "s.toml", &schedule("30.0", "1.0"));
    let out = dir.join("out");
    let child = Command::new(bin())
        .args(["--quiet", "check", "--repeat-after", "600", "--schedule"])
        .arg(&sched)
        .arg("--criteria")
        .arg(criteria())
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(700));
    let k = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(k.success());
    let o = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert!(err.contains("interrupted"), "{err}");
    assert!(!out.exists());
    let debris = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with(".out."))
        .count();
    assert_eq!(debris, 0);
}

/// The ranges are physical, not arbitrary: every phantom and profile the project ships is
/// inside them.
#[test]
fn every_committed_phantom_and_profile_is_within_the_ranges() {
    let mut stack = vec![root().join("profiles"), root().join("tests/data")];
    let mut phantoms = 0;
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                if !p.ends_with("hostile") {
                    stack.push(p);
                }
                continue;
            }
            if p.extension().is_none_or(|x| x != "toml") {
                continue;
            }
            let text = std::fs::read_to_string(&p).unwrap();
            if text.contains("[geometry]") {
                phantoms += 1;
                if let Err(e) = parse_phantom(&text, &p) {
                    panic!("{e}");
                }
            } else if text.contains("pressure_unit") {
                if let Err(e) = decophantom::profile::toml::parse(&text, &p) {
                    panic!("{e}");
                }
            }
        }
    }
    assert!(phantoms >= 5);
}

#[test]
fn legacy_files_and_the_elasticity_command_check_their_numbers() {
    use decophantom::profile::legacy::{read, LegacyUnits};
    use decophantom::units::{PressureUnit, TimeUnit};
    let dir = tempdir("hard-legacy");
    let units = LegacyUnits::new(TimeUnit::Min, PressureUnit::Msw);
    for (text, line, field) in [
        ("0 0\n1 1e17\n2 0\n", 2, "value"),
        ("0 0\n1e20 0\n", 2, "time"),
        ("0 0\n1 nan\n2 0\n", 2, "value"),
    ] {
        let p = write(&dir, "l.txt", text);
        let e = read(&p, &units).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(line), Some(field)),
            "{e}"
        );
    }
    for (flag, v) in [
        ("--mu", "nan"),
        ("--mu", "1e308"),
        ("--r0", "1e-30"),
        ("--gamma", "inf"),
    ] {
        let o = run(&["elasticity".as_ref(), flag.as_ref(), v.as_ref()]);
        assert_refused(&o, &[flag]);
        assert!(o.stdout.is_empty());
    }
}

/// Every file of the committed corpus `tests/data/hostile/<reader>/` (the hostile-user cases of
/// issue 11 and the mutants that once failed `mutants`, one file per case) through its reader
/// with `mutants::read_checked`: no panic, within the time limit, refused (unless the name holds
/// `.ok.`) naming the file and a line, the line the file name gives as `.L<line>.`.
#[test]
fn hostile_corpus_is_refused_by_every_reader() {
    let corpus = root().join("tests/data/hostile");
    let mut count = 0;
    for folder in std::fs::read_dir(&corpus).unwrap().flatten() {
        if !folder.path().is_dir() {
            continue;
        }
        let name = folder.file_name().to_string_lossy().into_owned();
        let reader = crate::mutants::reader(&name);
        for f in std::fs::read_dir(folder.path()).unwrap().flatten() {
            let p = f.path();
            let bytes = std::fs::read(&p).unwrap();
            let fname = p.file_name().unwrap().to_string_lossy().into_owned();
            let r = crate::mutants::read_checked(reader, &p, &bytes)
                .unwrap_or_else(|m| panic!("{}: {m}", p.display()));
            let Some(e) = r else {
                assert!(fname.contains(".ok."), "{} was accepted", p.display());
                count += 1;
                continue;
            };
            assert!(!fname.contains(".ok."), "{}: refused: {e}", p.display());
            if let Some(l) = fname
                .split('.')
                .find_map(|part| part.strip_prefix('L').and_then(|n| n.parse().ok()))
            {
                assert_eq!(e.line, Some(l), "{}: {e}", p.display());
            }
            count += 1;
        }
    }
    assert!(count >= 50, "{count}");
}

/// A duration beyond the 30-day limit (or a depth beyond the accepted pressure) in a dive log,
/// a waypoint CSV, a legacy file or a measurements CSV is refused naming the file, the line of
/// the sample or row, and the field.
#[test]
fn durations_and_depths_in_logs_and_csvs_name_file_line_and_field() {
    use decophantom::algorithm::waypoints::parse_waypoints_csv;
    use decophantom::profile::divelog::parse;
    let csv = |text: &str| {
        parse_waypoints_csv(
            text,
            Path::new("w.csv"),
            &decophantom::algorithm::conventions::DECOTENGU,
            decophantom::gas::GasMix::AIR,
        )
        .unwrap_err()
    };
    let where_ = |e: &decophantom::error::InputError| {
        (
            e.file.clone().unwrap().to_string_lossy().into_owned(),
            e.line,
            e.field.clone(),
        )
    };
    // 43 201 min is one minute past 30 days; 1e20 min; 1001 m
    for (text, line, field) in [
        ("time_min,depth_m\n0,0\n1,10\n43201,0\n", 4, "time_min"),
        (
            "time_min,depth_m\n0,0\n1,10\n1e20,10\n1.1e20,0\n",
            4,
            "time_min",
        ),
        ("time_min,depth_m\n0,0\n1,1001\n2,0\n", 3, "depth_m"),
    ] {
        let e = csv(text);
        assert_eq!(
            where_(&e),
            ("w.csv".into(), Some(line), Some(field.into())),
            "{e}"
        );
    }
    assert!(csv("time_min,depth_m\n0,0\n1,10\n43201,0\n")
        .message
        .contains("30 days"));
    // exactly 30 days is accepted
    assert!(parse_waypoints_csv(
        "time_min,depth_m\n0,0\n1,10\n43200,0\n",
        Path::new("w.csv"),
        &decophantom::algorithm::conventions::DECOTENGU,
        decophantom::gas::GasMix::AIR,
    )
    .is_ok());
    let ssrf = |last: &str| {
        format!(
            "<divelog program='subsurface' version='3'><dives>\n<dive number='1'>\n<divecomputer>\n<sample time='0:00 min' depth='0 m' />\n<sample time='2:00 min' depth='20 m' />\n{last}\n</divecomputer>\n</dive>\n</dives></divelog>\n"
        )
    };
    for (last, field) in [
        ("<sample time='43201:00 min' depth='0 m' />", "sample.time"),
        ("<sample time='1e20' depth='0 m' />", "sample.time"),
        ("<sample time='3:00 min' depth='1e9 m' />", "sample.depth"),
    ] {
        let e = parse(&ssrf(last), Path::new("d.xml")).unwrap_err();
        assert_eq!(
            where_(&e),
            ("d.xml".into(), Some(6), Some(field.into())),
            "{e}"
        );
    }
    let uddf = "<uddf><profiledata><repetitiongroup><dive>\n<samples>\n<waypoint><divetime>0</divetime><depth>0</depth></waypoint>\n<waypoint><divetime>3e6</divetime><depth>0</depth></waypoint>\n</samples></dive></repetitiongroup></profiledata></uddf>\n";
    let e = parse(uddf, Path::new("d.uddf")).unwrap_err();
    assert_eq!(
        where_(&e),
        ("d.uddf".into(), Some(4), Some("waypoint.divetime".into())),
        "{e}"
    );
    // a dive that fits but whose watch time at the surface does not: the dive's line
    let e = parse(
        &ssrf("<sample time='43199:00 min' depth='0 m' />"),
        Path::new("d.xml"),
    )
    .map(|d| decophantom::profile::dive_log_history(&d[0], 0.0, 3600.0))
    .unwrap()
    .unwrap_err();
    assert!(e.message.contains("30 days") && e.line == Some(2), "{e}");
    // measurements: a time past 30 days names its row
    let e = decophantom::fit::data::parse_measurements(
        "experiment,bubble,time_s,radius_m\na,0,0,1e-4\na,0,2592001,1e-4\n",
        Path::new("m.csv"),
    )
    .unwrap_err();
    assert_eq!(
        where_(&e),
        ("m.csv".into(), Some(3), Some("time_s".into())),
        "{e}"
    );
}

/// A legacy two-column file read as a schedule (`check --schedule dive.txt`) names the file's
/// own line and column when the schedule is refused.
#[test]
fn legacy_schedules_name_the_files_own_line() {
    let dir = tempdir("hard-legacy-schedule");
    // never surfaces: the last line (3) is at 10 m
    let p = write(&dir, "d.txt", "0 0\n1 10\n20 10\n");
    let e = decophantom::algorithm::waypoints::read_legacy_schedule(
        &p,
        &decophantom::algorithm::conventions::DECOTENGU,
        decophantom::gas::GasMix::AIR,
    )
    .unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(3), Some("value")),
        "{e}"
    );
    // 1001 m on line 2
    let p = write(&dir, "e.txt", "0 0\n1 1001\n2 0\n");
    let e = decophantom::algorithm::waypoints::read_legacy_schedule(
        &p,
        &decophantom::algorithm::conventions::DECOTENGU,
        decophantom::gas::GasMix::AIR,
    )
    .unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(2), Some("value")),
        "{e}"
    );
}

/// The error tolerances of `[numerics]`: a negative, zero, NaN or above-1 value is refused with
/// its field named; `inf` switches the estimate off; a missing one takes the default.
#[test]
fn numerics_tolerances_are_checked_and_inf_is_off() {
    for key in ["field_tolerance", "loading_tolerance"] {
        for bad in ["-1e-3", "0.0", "nan", "2.0"] {
            let text = format!("{}[numerics]\n{key} = {bad}\n", good_phantom());
            phantom_refused(&text, &format!("numerics.{key}"));
        }
        let text = format!("{}[numerics]\n{key} = inf\n", good_phantom());
        let n = parse_phantom(&text, Path::new("p.toml"))
            .unwrap()
            .params
            .numerics;
        let got = if key == "field_tolerance" {
            n.field_tolerance
        } else {
            n.loading_tolerance
        };
        assert_eq!(got, f64::INFINITY, "{key}");
    }
    let n = parse_phantom(&good_phantom(), Path::new("p.toml"))
        .unwrap()
        .params
        .numerics;
    let d = decophantom::phantom::params::Numerics::default();
    assert_eq!(
        (n.field_tolerance, n.loading_tolerance),
        (d.field_tolerance, d.loading_tolerance)
    );
    assert_eq!(d.loading_tolerance, 1e-3);
}

/// `[numerics] max_step_growth`: below 1.01 (a step that could never grow), above 10, negative
/// or NaN is refused with its field named; a good value is taken as written; missing, 1.2.
#[test]
fn max_step_growth_is_checked() {
    for bad in ["1.0", "0.5", "-2.0", "nan", "11.0"] {
        let text = format!("{}[numerics]\nmax_step_growth = {bad}\n", good_phantom());
        phantom_refused(&text, "numerics.max_step_growth");
    }
    let text = format!("{}[numerics]\nmax_step_growth = 1.5\n", good_phantom());
    let n = parse_phantom(&text, Path::new("p.toml"))
        .unwrap()
        .params
        .numerics;
    assert_eq!(n.max_step_growth, 1.5);
    let n = parse_phantom(&good_phantom(), Path::new("p.toml"))
        .unwrap()
        .params
        .numerics;
    assert_eq!(n.max_step_growth, 1.2);
}

/// `[numerics] explicit_tolerance_factor`: below 1, above 10, negative or NaN is refused with
/// its field named; a good value is taken as written; missing, 2.
#[test]
fn explicit_tolerance_factor_is_checked() {
    for bad in ["0.5", "-2.0", "nan", "11.0"] {
        let text = format!(
            "{}[numerics]\nexplicit_tolerance_factor = {bad}\n",
            good_phantom()
        );
        phantom_refused(&text, "numerics.explicit_tolerance_factor");
    }
    let text = format!(
        "{}[numerics]\nexplicit_tolerance_factor = 1.0\n",
        good_phantom()
    );
    let n = parse_phantom(&text, Path::new("p.toml"))
        .unwrap()
        .params
        .numerics;
    assert_eq!(n.explicit_tolerance_factor, 1.0);
    let n = parse_phantom(&good_phantom(), Path::new("p.toml"))
        .unwrap()
        .params
        .numerics;
    assert_eq!(n.explicit_tolerance_factor, 2.0);
}
