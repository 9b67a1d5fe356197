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

/// A 10 m / 10 min schedule TOML with a 1-min stop at 3 m (left at 12.7 min); `{STOP_MIN}` is
/// the stop table's only stop time (1.0 agrees with the legs).
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
end_depth_m = 3.0
duration_s = 42.0
gas = "air"

[[legs]]
kind = "stop"
start_depth_m = 3.0
end_depth_m = 3.0
duration_s = 60.0
gas = "air"

[[legs]]
kind = "ascent"
start_depth_m = 3.0
end_depth_m = 0.0
duration_s = 18.0
gas = "air"

[[stops]]
depth_m = 3.0
stop_min = {STOP_MIN}
runtime_min = 12.7
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
    assert_refused(&o, &["<command line>", "--repeat-after"]);
    // the same through `evaluate`, which named the schedule file as the place of the option
    let o = run(&[
        "evaluate".as_ref(),
        "--schedule".as_ref(),
        sched.as_os_str(),
        "--criteria".as_ref(),
        criteria().as_os_str(),
        "--repeat-after".as_ref(),
        "0".as_ref(),
        "--out".as_ref(),
        dir.join("ev").as_os_str(),
    ]);
    assert_refused(&o, &["<command line>: field '--repeat-after'"]);
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
        assert_eq!(e.line, Some(41), "{e}"); // the [[stops]] table
    }
    // depth 1e17 m in a schedule
    let e = decophantom::algorithm::Schedule::from_toml_str(
        &schedule("1e17", "1.0"),
        Path::new("s.toml"),
    )
    .unwrap_err();
    assert!(e.field.as_deref().unwrap().contains("depth_m"), "{e}");
    // a table given as a number: its key and "a table", not the Rust type `RawStop` (session 29)
    let text = schedule("10.0", "1.0").replace("[[stops]]", "[x]");
    let text = text.replacen("[[legs]]", "stops = [1]\n\n[[legs]]", 1);
    let e =
        decophantom::algorithm::Schedule::from_toml_str(&text, Path::new("s.toml")).unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(6), Some("stops")),
        "{e}"
    );
    assert!(e.to_string().ends_with("expected a table"), "{e}");
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

/// The phantom of the fit cases: the module's small phantom ([`phantom`], a 2 mm cube: the
/// largest sphere it holds has r = 1 mm) with every face open, a hyperelastic gel, one bubble of
/// 60 µm and nuclei down to 20 µm.
fn fit_phantom() -> String {
    phantom(
        "0.07",
        "law = \"hyperelastic\"\nshear_modulus = 40.0",
        "2.5e-9",
        "[1e-3, 1e-3, 1e-3]",
        "60e-6",
    )
    .replace(
        "grid_step_m = 2e-4\n",
        "grid_step_m = 2e-4\nopen_faces = [\"x-\", \"x+\", \"y-\", \"y+\", \"top\", \"bottom\"]\n",
    ) + "[nuclei]\nmin_radius_m = 20e-6\n"
}

/// A fit lab in `dir`: the phantom above, 60 psi gauge → 0 in 10 s then 50 s at the surface,
/// and `experiments.toml` naming one experiment `name`. Returns the experiments file.
fn fit_lab(dir: &Path, name: &str) -> PathBuf {
    write(dir, "phantom.toml", &fit_phantom());
    write(
        dir,
        "profile.toml",
        "time_unit = \"s\"\npressure_unit = \"psi-gauge\"\ngas = \"air\"\npoints = [[0, 60], [10, 0], [60, 0]]\n",
    );
    let name = toml::Value::String(name.to_string()).to_string();
    write(
        dir,
        "experiments.toml",
        &format!("[[experiment]]\nname = {name}\nprofile = \"profile.toml\"\nphantom = \"phantom.toml\"\n"),
    )
}

/// Measured radii of bubble 0 of experiment `e1` (µm-scale growth after the decompression),
/// the first `n` of seven rows, sd 2 µm.
fn fit_rows(n: usize) -> String {
    let rows = [
        (0, 6.17e-5),
        (10, 1.11e-4),
        (20, 1.29e-4),
        (30, 1.46e-4),
        (40, 1.57e-4),
        (50, 1.66e-4),
        (60, 1.75e-4),
    ];
    let mut s = String::from("experiment,bubble,time_s,radius_m,sd_m\n");
    for (t, r) in &rows[..n] {
        s.push_str(&format!("e1,0,{t},{r:e},2e-6\n"));
    }
    s
}

fn fit_cmd(measured: &Path, experiments: &Path, params: &[&str], out: &Path) -> Output {
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "fit".as_ref(),
        "--measured".as_ref(),
        measured.as_os_str(),
        "--experiments".as_ref(),
        experiments.as_os_str(),
    ];
    for p in params {
        args.push("--param".as_ref());
        args.push(p.as_ref());
    }
    args.push("--out".as_ref());
    args.push(out.as_os_str());
    run(&args)
}

/// Every number in a TOML document is finite.
fn all_finite(v: &toml::Value, at: &str) {
    match v {
        toml::Value::Float(x) => assert!(x.is_finite(), "{at} = {x}"),
        toml::Value::Array(a) => a.iter().for_each(|x| all_finite(x, at)),
        toml::Value::Table(t) => t
            .iter()
            .for_each(|(k, x)| all_finite(x, &format!("{at}.{k}"))),
        _ => {}
    }
}

/// D2. A fit needs two residual degrees of freedom (n ≥ p + 2): 1 and 2 observations for one
/// parameter are refused before any simulation (exit 2, the measurements file and its last
/// line named, no output and no journal). At n = p + 2 = 3 the fit runs; AICc, whose K = p + 1
/// needs n > p + 2, is not written but given with its reason, and no number written in
/// fit.toml or report.md is NaN or infinite.
#[test]
fn fit_needs_two_residual_degrees_of_freedom_and_writes_no_non_finite_number() {
    let dir = tempdir("hard-fit-dof");
    let e = fit_lab(&dir, "e1");
    let out = dir.join("out");
    for n in [1, 2] {
        let m = write(&dir, "m.csv", &fit_rows(n));
        let o = fit_cmd(&m, &e, &["gases.n2.diffusivity"], &out);
        assert_refused(&o, &[&format!("m.csv:{}:", n + 1), "at least p + 2 = 3"]);
        assert!(!out.exists() && !dir.join("out.partial").exists());
    }
    let m = write(&dir, "m.csv", &fit_rows(3));
    let o = fit_cmd(&m, &e, &["gases.n2.diffusivity"], &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let fit: toml::Table = std::fs::read_to_string(out.join("fit.toml"))
        .unwrap()
        .parse()
        .unwrap();
    all_finite(&toml::Value::Table(fit.clone()), "fit");
    assert!(!fit.contains_key("aicc"), "{fit:?}");
    let why = fit["absent"]["aicc"].as_str().unwrap();
    assert!(why.contains("n > p + 2"), "{why}");
    assert!(fit.contains_key("residual_variance"), "{fit:?}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for word in report.split(|c: char| !c.is_alphanumeric()) {
        assert!(word != "NaN" && word != "inf" && word != "nan", "{report}");
    }
    assert!(report.contains("needs n > p + 2"), "{report}");
}

/// D3. Bounds are checked against the field's accepted range by the phantom reader (D in
/// 1e-14 ..= 1e-6 m²/s, γ in 0 ..= 1 N/m) before any simulation, naming `<command line>` and
/// `--param`; an accepted range gives intervals inside the bounds, and an interval that was
/// clipped to them says so in fit.toml and in report.md.
#[test]
fn fit_bounds_must_lie_in_the_fields_range_and_intervals_inside_the_bounds() {
    let dir = tempdir("hard-fit-bounds");
    let e = fit_lab(&dir, "e1");
    let m = write(&dir, "m.csv", &fit_rows(7));
    let out = dir.join("out");
    for (bad, which) in [
        ("gases.n2.diffusivity=-1..1", "lower bound"),
        ("gases.n2.diffusivity=1e-9..1e-3", "upper bound"),
        ("material.surface_tension=0..2", "upper bound"),
        ("scale:gases.*.diffusivity=0..2", "lower bound"),
    ] {
        let o = fit_cmd(&m, &e, &[bad], &out);
        assert_refused(&o, &["<command line>", "field '--param'", which]);
        // the error is the command line's, not a line of the phantom
        assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: <command line>:"));
        assert!(!out.exists() && !dir.join("out.partial").exists());
    }
    let o = fit_cmd(&m, &e, &["material.surface_tension=0..1"], &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let fit: toml::Table = std::fs::read_to_string(out.join("fit.toml"))
        .unwrap()
        .parse()
        .unwrap();
    all_finite(&toml::Value::Table(fit.clone()), "fit");
    let p = &fit["parameter"].as_array().unwrap()[0];
    let ci: Vec<f64> = p["ci95"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_float().unwrap())
        .collect();
    assert!(0.0 <= ci[0] && ci[0] <= ci[1] && ci[1] <= 1.0, "{ci:?}");
    let bounds: Vec<f64> = p["bounds"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_float().unwrap())
        .collect();
    assert_eq!(bounds, vec![0.0, 1.0]);
    if p["ci95_clipped_to_bounds"].as_bool().unwrap() {
        let report = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(report.contains("clipped to the bounds"), "{report}");
    }
}

/// D4. A measured radius larger than the experiment's phantom can hold (a 2 mm cube holds a
/// sphere of at most r = 1 mm) is refused naming the file, its line and `radius_m`; 0.9 mm is
/// accepted by the same check.
#[test]
fn a_radius_larger_than_the_phantom_is_refused() {
    use decophantom::fit::data::{check_against, parse_measurements, read_experiments};
    let dir = tempdir("hard-fit-radius");
    let ex = read_experiments(&fit_lab(&dir, "e1")).unwrap();
    let m = |r: &str| {
        parse_measurements(
            &format!("experiment,bubble,time_s,radius_m\ne1,0,0,6e-5\ne1,0,30,{r}\n"),
            Path::new("m.csv"),
        )
        .unwrap()
    };
    check_against(&m("9e-4"), &ex).unwrap();
    let e = check_against(&m("1.5e-3"), &ex).unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref(), e.file.as_deref()),
        (Some(3), Some("radius_m"), Some(Path::new("m.csv"))),
        "{e}"
    );
}

fn synth_cmd(experiments: &Path, extra: &[&str], out: &Path) -> Output {
    let mut args: Vec<&std::ffi::OsStr> = vec![
        "synth".as_ref(),
        "--experiments".as_ref(),
        experiments.as_os_str(),
        "--noise-sd".as_ref(),
        "1e-6".as_ref(),
    ];
    args.extend(extra.iter().map(|a| -> &std::ffi::OsStr { a.as_ref() }));
    args.push("--out".as_ref());
    args.push(out.as_os_str());
    run(&args)
}

/// D7, D14. An experiment name with a comma, quotes and a leading `#` goes through `synth`'s
/// CSV and back through `fit`'s reader unchanged (the csv crate's quoting), and `fit` runs on
/// it; a name the measurements cannot hold (leading space) is refused in the experiments file.
/// `synth --out` never replaces a file it did not write (a user's file) or one edited since it
/// wrote it; its own unchanged file is replaced.
#[test]
fn synth_names_round_trip_and_existing_files_are_kept() {
    use decophantom::fit::data::read_measurements;
    let dir = tempdir("hard-synth-names");
    let name = "#e \"1\", x";
    let e = fit_lab(&dir, name);
    let out = dir.join("m.csv");
    let o = synth_cmd(&e, &["--every", "10"], &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let m = read_measurements(&out).unwrap();
    assert_eq!(m.series.len(), 1);
    assert_eq!(m.series[0].experiment, name);
    assert_eq!(m.len(), 7, "0, 10, …, 60 s");
    let o = fit_cmd(&out, &e, &["gases.n2.diffusivity"], &dir.join("fit"));
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    // its own file, unchanged: replaced
    let o = synth_cmd(&e, &["--every", "20"], &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(read_measurements(&out).unwrap().len(), 4, "0, 20, 40, 60 s");
    // edited since: kept
    let edited = std::fs::read_to_string(&out)
        .unwrap()
        .replacen(",20,", ",21,", 1);
    std::fs::write(&out, &edited).unwrap();
    let o = synth_cmd(&e, &["--every", "10"], &out);
    assert_refused(&o, &["field '--out'", "changed since"]);
    assert_eq!(std::fs::read_to_string(&out).unwrap(), edited);
    // a user's file: kept
    let mine = write(&dir, "mine.csv", "user data\n");
    let o = synth_cmd(&e, &["--every", "10"], &mine);
    assert_refused(&o, &["field '--out'", "not written by decophantom synth"]);
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "user data\n");
    // a name the measurements cannot hold
    let e2 = fit_lab(&dir, " e1");
    let o = synth_cmd(&e2, &[], &dir.join("x.csv"));
    assert_refused(&o, &["experiments.toml:2:", "field 'name'"]);
    assert!(!dir.join("x.csv").exists());
}

/// D17, D20. `synth --every` is limited to 10⁶ rows before any simulation (1e-9 s over a 60 s
/// profile would be 6·10¹⁰); `--noise-sd` to the sd range of measurements.csv; a value an
/// effect sets is checked by the phantom reader and refused naming `<command line>` and
/// `--effect` (never a phantom file's line); the same effect twice is refused as such.
#[test]
fn synth_limits_rows_and_names_effects_on_the_command_line() {
    let dir = tempdir("hard-synth-limits");
    let e = fit_lab(&dir, "e1");
    let out = dir.join("m.csv");
    let t = std::time::Instant::now();
    let o = synth_cmd(&e, &["--every", "1e-9"], &out);
    assert_refused(&o, &["field '--every'", "1000000"]);
    assert!(t.elapsed().as_secs_f64() < 10.0, "{:?}", t.elapsed());
    // 60 s every 6e-5 s is 10⁶ + 1 rows: one too many
    let o = synth_cmd(&e, &["--every", "6e-5"], &out);
    assert_refused(&o, &["field '--every'"]);
    let o = run(&[
        "synth".as_ref(),
        "--experiments".as_ref(),
        e.as_os_str(),
        "--noise-sd".as_ref(),
        "1".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_refused(&o, &["field '--noise-sd'"]);
    for effect in ["perfusion=-1", "gases.n2.diffusivity=1"] {
        let o = synth_cmd(&e, &["--effect", effect], &out);
        assert_refused(&o, &["<command line>", "field '--effect'", effect]);
        // the error is the command line's, not a line of the phantom
        assert!(String::from_utf8_lossy(&o.stderr).starts_with("error: <command line>:"));
    }
    let o = synth_cmd(
        &e,
        &["--effect", "perfusion=1e-3", "--effect", "perfusion=2e-3"],
        &out,
    );
    assert_refused(&o, &["field '--effect'", "given twice"]);
    let o = synth_cmd(
        &e,
        &[
            "--effect",
            "perfusion=1e-3",
            "--effect",
            "perfusion.rate_per_s=2e-3",
        ],
        &out,
    );
    assert_refused(&o, &["field '--effect'", "both set perfusion.rate_per_s"]);
    assert!(!out.exists());
}

// ---- bad-input review 2: schedule and criteria readers, output places ----

/// D5. A schedule TOML's pressures are in Pa, in the ranges an algorithm file's conventions
/// accept: `pa_per_m` 9 500–10 600 Pa/m (fresh to sea water), `surface_pressure_pa` 500–1 100
/// hPa, `water_vapour_pa` 0–20 kPa. A value in other units is refused at its own field and line
/// (before, `pa_per_m = 1` ran a 30 m dive at the surface and passed; 101.325 kPa was blamed on
/// the water vapour), and the limits themselves are read. The `[summary]` is read, so its
/// numbers are checked too (`cns_percent = nan` was accepted).
#[test]
fn schedule_pressures_are_pascals_of_water_and_air() {
    use decophantom::algorithm::Schedule;
    let base = schedule("10.0", "1.0");
    let read = |text: &str| Schedule::from_toml_str(text, Path::new("s.toml"));
    let with = |key: &str, v: &str| {
        base.lines()
            .map(|l| {
                if l.starts_with(&format!("{key} =")) {
                    format!("{key} = {v}")
                } else {
                    l.to_string()
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
    };
    for (key, v, line) in [
        ("pa_per_m", "1", 3),
        ("pa_per_m", "9.985", 3),
        ("pa_per_m", "0.09985", 3),
        ("pa_per_m", "3043", 3),
        ("pa_per_m", "12160", 3),
        ("surface_pressure_pa", "101.325", 2),
        ("surface_pressure_pa", "1.01325", 2),
        ("surface_pressure_pa", "1013.25", 2),
        ("water_vapour_pa", "62700", 4),
        ("water_vapour_pa", "-1", 4),
    ] {
        let e = read(&with(key, v)).unwrap_err();
        assert_eq!(
            (e.field.as_deref(), e.line),
            (Some(key), Some(line)),
            "{key} = {v}: {e}"
        );
    }
    let kpa = with("surface_pressure_pa", "101.325")
        .replace("pa_per_m = 9985.0", "pa_per_m = 9.985")
        .replace("water_vapour_pa = 6270.0", "water_vapour_pa = 6.27");
    let e = read(&kpa).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("surface_pressure_pa"), "{e}");
    for (key, v) in [
        ("pa_per_m", "9500"),
        ("pa_per_m", "10600"),
        ("pa_per_m", "9806.65"),
        ("surface_pressure_pa", "50000"),
        ("surface_pressure_pa", "110000"),
        ("water_vapour_pa", "0"),
        ("water_vapour_pa", "20000"),
    ] {
        let s = read(&with(key, v)).unwrap_or_else(|e| panic!("{key} = {v}: {e}"));
        let got = match key {
            "pa_per_m" => s.pa_per_m,
            "surface_pressure_pa" => s.surface_pressure_pa,
            _ => s.water_vapour_pa,
        };
        assert_eq!(got, v.parse::<f64>().unwrap());
    }
    let lines = base.lines().count();
    for (key, v) in [
        ("cns_percent", "nan"),
        ("otu", "-1"),
        ("runtime_min", "inf"),
        ("runtime_min", "43201"),
    ] {
        let e = read(&format!("{base}[summary]\n{key} = {v}\n")).unwrap_err();
        assert_eq!(
            (e.field.clone(), e.line),
            (Some(format!("summary.{key}")), Some(lines + 2)),
            "{e}"
        );
    }
    assert!(read(&format!("{base}[summary]\ncns_percent = 2.5\notu = 7\n")).is_ok());
    // through the command: exit 2 naming the file, line and field, nothing run
    let dir = tempdir("hard-sched-units");
    let s = write(&dir, "s.toml", &with("pa_per_m", "1"));
    let o = run(&[
        "check".as_ref(),
        "--schedule".as_ref(),
        s.as_os_str(),
        "--criteria".as_ref(),
        criteria().as_os_str(),
    ]);
    assert_refused(&o, &["s.toml:3:", "field 'pa_per_m'"]);
    assert!(o.stdout.is_empty());
}

/// D6, D20. The criteria protocol watches the surface at least a minute (with 0 the
/// after-surfacing window was empty and its criterion a silent pass of 0, or a failed plot,
/// exit 3), and a phantom must record at least two frames in that window; an unknown word in
/// a criterion's setting names its key, not the word.
#[test]
fn criteria_watch_the_surface_and_name_the_key_of_a_bad_word() {
    use decophantom::app::evaluate::breathed_gas_params;
    use decophantom::phantom::params::PhantomParams;
    use decophantom::risk::config::parse_criteria;
    let parse = |t: &str| parse_criteria(t, Path::new("c.toml"));
    let crit = "[[criterion]]\nkind = \"peak-area-growth-rate\"\nlimit = 80\nwindow = \"after-surfacing\"\n";
    for m in ["0", "0.5", "10081", "nan"] {
        let e = parse(&format!(
            "[protocol]\nobserve_after_surfacing_min = {m}\n{crit}"
        ))
        .unwrap_err();
        assert_eq!(
            (e.field.as_deref(), e.line),
            (Some("protocol.observe_after_surfacing_min"), Some(2)),
            "{m}: {e}"
        );
    }
    for m in ["1", "10080"] {
        let c = parse(&format!(
            "[protocol]\nobserve_after_surfacing_min = {m}\n{crit}"
        ))
        .unwrap();
        assert_eq!(
            c.protocol.observe_after_surfacing_s,
            m.parse::<f64>().unwrap() * 60.0
        );
    }
    for (kind, key, word) in [
        ("peak-supersaturation", "at", "moon"),
        ("peak-total-volume", "measure", "grow"),
        ("peak-area-growth-rate", "window", "sometimes"),
    ] {
        let e = parse(&format!(
            "[[criterion]]\nkind = \"{kind}\"\nlimit = 1\n{key} = \"{word}\"\n"
        ))
        .unwrap_err();
        assert_eq!(
            (e.field.clone(), e.line),
            (Some(format!("criterion.{key}")), Some(4)),
            "{e}"
        );
        assert!(e.message.contains(word), "{e}");
    }
    // the phantom's frames: at least two in the window (every ≤ window / 2)
    let c = parse(&format!(
        "[protocol]\nobserve_after_surfacing_min = 10\n{crit}"
    ))
    .unwrap();
    let mut p = PhantomParams::box_phantom([2e-3; 3], 2e-4);
    p.numerics.record_interval = 300.0;
    assert!(breathed_gas_params(&p, &c.protocol).is_ok());
    p.numerics.record_interval = 301.0;
    let e = breathed_gas_params(&p, &c.protocol).unwrap_err();
    assert_eq!(
        e.field.as_deref(),
        Some("numerics.record_interval_s"),
        "{e}"
    );
    // through check: the phantom file and line named, nothing simulated
    let dir = tempdir("hard-watch");
    let ph = write(
        &dir,
        "ph.toml",
        &format!("{}[numerics]\nrecord_interval_s = 86400\n", good_phantom()),
    );
    let line = good_phantom().lines().count() + 2;
    let s = write(&dir, "s.toml", &schedule("10.0", "1.0"));
    let out = dir.join("out");
    let o = run(&[
        "check".as_ref(),
        "--schedule".as_ref(),
        s.as_os_str(),
        "--criteria".as_ref(),
        criteria().as_os_str(),
        "--phantom".as_ref(),
        ph.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_refused(
        &o,
        &[
            &format!("ph.toml:{line}:"),
            "field 'numerics.record_interval_s'",
        ],
    );
    assert!(!out.exists());
}

/// D10. A waypoint CSV naming a column twice is refused at the header (it was read silently
/// from the first: `time_min,depth_m,depth_m` with 10 and 20 ran at 10 m).
#[test]
fn waypoint_csv_with_a_column_twice_is_refused() {
    use decophantom::algorithm::conventions::DECOTENGU;
    use decophantom::algorithm::waypoints::parse_waypoints_csv;
    let read = |t: &str| {
        parse_waypoints_csv(
            t,
            Path::new("w.csv"),
            &DECOTENGU,
            decophantom::gas::GasMix::AIR,
        )
    };
    for (text, field) in [
        (
            "time_min,depth_m,depth_m\n0,0,0\n1,10,20\n3,10,20\n4,0,0\n",
            "depth_m",
        ),
        (
            "# c\ntime_min,TIME_MIN,depth_m\n0,0,0\n1,1,10\n2,2,0\n",
            "time_min",
        ),
        (
            "time_min,depth_m,gas,Gas\n0,0,air,32\n1,10,air,32\n2,0,,\n",
            "gas",
        ),
    ] {
        let e = read(text).unwrap_err();
        let header = if text.starts_with('#') { 2 } else { 1 };
        assert_eq!(
            (e.field.as_deref(), e.line),
            (Some(field), Some(header)),
            "{e}"
        );
        assert!(e.message.contains("twice"), "{e}");
    }
    assert!(read("time_min,depth_m,gas\n0,0,air\n1,10,air\n2,0,\n").is_ok());
}

/// D19. The place of an output folder is checked before the run, naming `--out` and the
/// user's path (exit 2): a folder under a file is refused, and one this user cannot write in
/// (checked where the test does not run with privileges that bypass permissions); missing
/// folders above it are created. Before, the run was done, then exit 3 named an internal
/// staging path with the OS error twice.
#[test]
fn output_places_are_checked_before_the_run() {
    let dir = tempdir("hard-places");
    let ph = write(&dir, "ph.toml", &good_phantom());
    let prof = write(&dir, "p.toml", SHORT_PROFILE);
    let file = write(&dir, "afile", "mine");
    let o = simulate_into(&dir, &prof, &ph, &file.join("sub"));
    assert_refused(&o, &["afile/sub", "field '--out'", "is a file"]);
    assert!(o.stdout.is_empty());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !err.contains(".staging-") && !err.contains(".tmp-"),
        "{err}"
    );
    assert_eq!(std::fs::read_to_string(&file).unwrap(), "mine");
    let deep = dir.join("new").join("deeper").join("out");
    let o = simulate_into(&dir, &prof, &ph, &deep);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(deep.join("bubbles.csv").is_file());
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let ro = dir.join("ro");
        std::fs::create_dir(&ro).unwrap();
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
        // privileged (root): permissions do not stop it, so there is nothing to refuse
        let privileged = std::fs::write(ro.join("probe"), "x").is_ok();
        if !privileged {
            let o = simulate_into(&dir, &prof, &ph, &ro.join("x"));
            assert_refused(&o, &["ro/x", "field '--out'", "cannot create files"]);
            assert!(o.stdout.is_empty());
        }
        std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    // no probe or staging debris beside the outputs
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(!names.iter().any(|n| n.starts_with('.')), "{names:?}");
}

/// D21. A schedule without stops has 0 min of stops, never −0.0 (the sum of an empty list of
/// f64), in `check --json` and the reports.
#[test]
fn a_schedule_without_stops_has_zero_stop_time() {
    use decophantom::algorithm::Schedule;
    // the legs up to the bottom, then straight up: no stop leg and no [[stops]]
    let text = schedule("10.0", "1.0");
    let cut = text.find("[[legs]]\nkind = \"ascent\"").unwrap();
    let text = format!(
        "{}[[legs]]\nkind = \"ascent\"\nstart_depth_m = 10.0\nend_depth_m = 0.0\nduration_s = 60.0\ngas = \"air\"\n",
        &text[..cut]
    );
    let s = Schedule::from_toml_str(&text, Path::new("s.toml")).unwrap();
    assert!(s.stops.is_empty());
    assert!(s.stop_time_min() == 0.0 && s.stop_time_min().is_sign_positive());
    let json = serde_json::to_string(&decophantom::app::json::ScheduleJson::from(&s)).unwrap();
    assert!(json.contains("\"stop_time_min\":0.0"), "{json}");
}

/// serde's type and length errors in a phantom name the key's dotted path, an unknown key in a
/// table is named with its table, and a list of three numbers with a fourth is refused.
#[test]
fn phantom_type_and_length_errors_name_the_key_path() {
    let good = good_phantom();
    for (from, to, field) in [
        (
            "grid_step_m = 2e-4",
            "grid_step_m = \"2e-4\"",
            "geometry.grid_step_m",
        ),
        ("[2e-3, 2e-3, 2e-3]", "[2e-3, 2e-3]", "geometry.size_m"),
        (
            "[2e-3, 2e-3, 2e-3]",
            "[2e-3, 2e-3, 2e-3, 5]",
            "geometry.size_m",
        ),
        (
            "[1e-3, 1e-3, 1e-3]",
            "[1e-3, 1e-3, 1e-3, 0]",
            "bubbles.position_m",
        ),
        (
            "surface_tension = 0.07",
            "bogus_key = 1",
            "material.bogus_key",
        ),
    ] {
        phantom_refused(&good.replace(from, to), field);
    }
}

/// Bubbles that overlap at t = 0 (their volume would count twice) are refused naming both
/// tables' lines; so is a population spacing that lets them overlap. A phantom without
/// bubbles is refused with a line.
#[test]
fn overlapping_bubbles_and_bubble_free_phantoms_are_refused_with_lines() {
    let two = |z: &str| {
        format!(
            "{}[[bubbles]]\nposition_m = [1e-3, 1e-3, {z}]\ninitial_radius_m = 5e-5\n",
            good_phantom()
        )
    };
    // [[bubbles]] on lines 15 and 18; R0 + R0 = 1e-4 m
    for z in ["1e-3", "1.05e-3"] {
        let e = parse_phantom(&two(z), Path::new("p.toml")).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(18), Some("bubbles")),
            "{e}"
        );
        assert!(e.message.contains("line 15"), "{e}");
    }
    assert!(parse_phantom(&two("1.2e-3"), Path::new("p.toml")).is_ok());
    let population = |spacing: &str| {
        let text = good_phantom();
        let bare = &text[..text.find("[[bubbles]]").unwrap()];
        format!("{bare}[population]\ncount = 2\ninitial_radius_m = 5e-5\nmin_spacing_m = {spacing}\nseed = 1\n")
    };
    phantom_refused(&population("1e-4"), "population.min_spacing_m");
    assert!(parse_phantom(&population("3e-4"), Path::new("p.toml")).is_ok());

    let dir = tempdir("hard-nobubble-line");
    let text = good_phantom();
    let bare = write(
        &dir,
        "bare.toml",
        &text[..text.find("[[bubbles]]").unwrap()],
    );
    let ph = decophantom::phantom::config::load_phantom(&bare).unwrap();
    let e = decophantom::phantom::config::require_bubbles(&ph.params, &bare).unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(14), Some("bubbles")),
        "{e}"
    );
}

/// Command-line values are blamed on the command line: `--vapour-pa` out of range (not the
/// profile's line), `--checkpoint-every` without a unit; a folder as `--profile` is named as a
/// folder, not as a legacy file without `--units`; a near-vacuum profile (1e-10 Pa, below the
/// 1 kPa floor) is refused on its line instead of running for ever.
#[test]
fn command_line_values_folders_and_vacuum_are_refused_up_front() {
    let dir = tempdir("hard-cmdline");
    let ph = write(&dir, "ph.toml", &good_phantom());
    let prof = write(&dir, "p.toml", SHORT_PROFILE);
    let legacy = write(&dir, "l.txt", "0 0\n1 10\n2 0\n");
    let vacuum = write(
        &dir,
        "vac.toml",
        "time_unit = \"s\"\npressure_unit = \"pa\"\npoints = [[0, 101325],\n [10, 1e-10], [60, 1e-10]]\n",
    );
    let sim = |profile: &Path, extra: &[&str]| {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "simulate".as_ref(),
            "--profile".as_ref(),
            profile.as_os_str(),
            "--phantom".as_ref(),
            ph.as_os_str(),
            "--out".as_ref(),
        ];
        let out = dir.join("out");
        args.push(out.as_os_str());
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        run(&args)
    };
    let o = sim(&legacy, &["--units", "min,psi-gauge", "--vapour-pa", "1e6"]);
    assert_refused(&o, &["<command line>", "--vapour-pa"]);
    assert!(
        !String::from_utf8_lossy(&o.stderr).contains("l.txt:"),
        "{o:?}"
    );
    assert_refused(
        &sim(&prof, &["--checkpoint-every", "5"]),
        &["<command line>", "--checkpoint-every", "unit"],
    );
    assert_refused(&sim(&dir, &[]), &["this is a folder, not a profile"]);
    assert_refused(&sim(&vacuum, &[]), &["vac.toml:4", "points", "1 kPa"]);
    assert!(!dir.join("out").exists());
}

/// Review D (defects A–E): each silently accepted input is refused through the binary with
/// exit 2, the file, line and field named, and nothing run or written.
#[test]
fn contradictory_or_impossible_inputs_are_refused_by_the_binary() {
    let dir = tempdir("hard-review-d");
    let ph = write(&dir, "ph.toml", &good_phantom());
    let seed = std::fs::read_to_string(root().join("tests/data/seeds/schedule.toml")).unwrap();
    let evaluate = |schedule: &Path| {
        run(&[
            "evaluate".as_ref(),
            "--schedule".as_ref(),
            schedule.as_os_str(),
            "--criteria".as_ref(),
            criteria().as_os_str(),
            "--phantom".as_ref(),
            ph.as_os_str(),
            "--out".as_ref(),
            dir.join("eval").as_os_str(),
        ])
    };
    // A: a 50-min stop in the table over a 5-min stop leg (the report showed 50 min)
    let s7 = write(
        &dir,
        "s7.toml",
        &seed.replace("stop_min = 5.0", "stop_min = 50.0"),
    );
    let o = evaluate(&s7);
    assert_refused(&o, &["s7.toml:43:", "field 'stops.stop_min'", "50 min"]);
    assert!(!dir.join("eval").exists());
    // B: an ascent 30 m → 3 m in no time; a kind against the direction; waypoints at 2e6 m/min
    // and starting at 20 m
    let fast = write(
        &dir,
        "fast.toml",
        &seed.replace("duration_s = 180.0", "duration_s = 0.0"),
    );
    assert_refused(
        &evaluate(&fast),
        &["fast.toml:20:", "field 'legs.duration_s'", "inf m/min"],
    );
    let kind = write(
        &dir,
        "kind.toml",
        &seed.replacen("kind = \"descent\"", "kind = \"ascent\"", 1),
    );
    assert_refused(&evaluate(&kind), &["kind.toml:6:", "field 'legs.kind'"]);
    let csv = write(
        &dir,
        "w.csv",
        "time_min,depth_m,gas\n0,0,air\n0.0001,200,\n5,200,\n7,0,\n",
    );
    assert_refused(
        &evaluate(&csv),
        &["w.csv:3:", "field 'depth_m'", "2000000 m/min"],
    );
    let deep = write(&dir, "deep.csv", "time_min,depth_m\n0,20\n5,20\n7,0\n");
    assert_refused(
        &evaluate(&deep),
        &["deep.csv:2:", "field 'depth_m'", "at 20 m"],
    );
    assert!(!dir.join("eval").exists());
    // C: plan --out with an extension no schedule reader reads by, refused before planning
    let alg = root().join("algorithms/zhl16c-gf30-85.toml");
    for name in ["sch.txt", "sch"] {
        let out = dir.join(name);
        let o = run(&[
            "plan".as_ref(),
            "--algorithm".as_ref(),
            alg.as_os_str(),
            "--depth".as_ref(),
            "30".as_ref(),
            "--time".as_ref(),
            "20".as_ref(),
            "--out".as_ref(),
            out.as_os_str(),
        ]);
        assert_refused(&o, &[name, "field '--out'", ".toml", ".csv"]);
        assert!(o.stdout.is_empty() && !out.exists());
    }
    // D: a misspelled sd column, times out of order within a bubble, a radius of 0
    let ex = fit_lab(&dir, "e1");
    for (name, text, needles) in [
        (
            "sd.csv",
            fit_rows(7).replace("sd_m", "sd"),
            ["sd.csv:1:", "field 'sd'", "unknown column 'sd'"],
        ),
        (
            "order.csv",
            fit_rows(7).replace("e1,0,20,", "e1,0,5,"),
            ["order.csv:4:", "field 'time_s'", "comes after 10 s"],
        ),
        (
            "zero.csv",
            fit_rows(7).replace("1.29e-4", "0"),
            ["zero.csv:4:", "field 'radius_m'", "1 nm"],
        ),
    ] {
        let m = write(&dir, name, &text);
        let out = dir.join("fit");
        let o = fit_cmd(&m, &ex, &["gases.n2.diffusivity"], &out);
        assert_refused(&o, &needles);
        assert!(!out.exists());
    }
    // E: a logged depth of -21.6 m mid-dive (was set to 0 m with a note)
    let log = write(
        &dir,
        "log.ssrf",
        "<divelog program='subsurface' version='3'>\n<dives>\n<dive number='1' date='2020-01-01' time='10:00:00'>\n<divecomputer>\n<sample time='0:00 min' depth='0.0 m' />\n<sample time='2:00 min' depth='20.0 m' />\n<sample time='12:34 min' depth='-21.6 m' />\n<sample time='20:00 min' depth='20.0 m' />\n<sample time='24:00 min' depth='0.0 m' />\n</divecomputer>\n</dive>\n</dives>\n</divelog>\n",
    );
    assert_refused(
        &evaluate(&log),
        &["log.ssrf:7:", "field 'sample.depth'", "-21.6 m at 754 s"],
    );
    assert!(!dir.join("eval").exists());
}

/// A phantom with two gases, three bubbles and nuclei with VPM skins, where keys of the same
/// name stand in several tables (`diffusivity`, `position_m`, `seed`), for the sweep below.
const SWEEP_PHANTOM: &str = r#"[geometry]
shape = "box"
size_m = [2e-3, 2e-3, 2e-3]
grid_step_m = 2e-4
[material]
surface_tension = 0.07
[gases.n2]
diffusivity = 2.5e-9
ostwald = 0.014
[gases.o2]
diffusivity = 2.4e-9
ostwald = 0.027
[nucleation]
model = "critical-radius"
number_density_per_m3 = 1e9
slope_per_m = 2e6
seed = 3
skin_compression = 0.257
[[bubbles]]
position_m = [0.5e-3, 1e-3, 1e-3]
initial_radius_m = 5e-5
[[bubbles]]
position_m = [1.0e-3, 1e-3, 1e-3]
initial_radius_m = 6e-5
[[bubbles]]
position_m = [1.5e-3, 1e-3, 1e-3]
initial_radius_m = 7e-5
[numerics]
max_step_s = 1.0
"#;

/// Session 31's sweep of every numeric phantom field set to -1, 1e308 and "x": each refusal
/// names the field at the line of its own key, not at a key of the same name in another table
/// (`gases.o2.diffusivity` at n2's line, bubble 2 at bubble 0's, a wrong type in `[nucleation]`
/// as `nucleation.model`, `seed = -1` as the field `nucleation.-1`), and writes an absurd number
/// as 1e308, not in 309 digits. `to` is unique in the edited text: its line is the one named.
#[test]
fn every_phantom_field_is_named_at_its_own_line() {
    assert!(parse_phantom(SWEEP_PHANTOM, Path::new("p.toml")).is_ok());
    let cases = [
        (
            "diffusivity = 2.4e-9",
            "diffusivity = -1",
            "gases.o2.diffusivity",
        ),
        ("ostwald = 0.027", "ostwald = 1e308", "gases.o2.ostwald"),
        (
            "initial_radius_m = 7e-5",
            "initial_radius_m = -1",
            "bubbles.initial_radius_m",
        ),
        (
            "initial_radius_m = 6e-5",
            "initial_radius_m = 1e308",
            "bubbles.initial_radius_m",
        ),
        (
            "[1.5e-3, 1e-3, 1e-3]",
            "[1e308, 1e-3, 1e-3]",
            "bubbles.position_m",
        ),
        (
            "[1.5e-3, 1e-3, 1e-3]",
            "[-1, 1e-3, 1e-3]",
            "bubbles.position_m",
        ),
        (
            "[1.0e-3, 1e-3, 1e-3]",
            "[nan, 1e-3, 1e-3]",
            "bubbles.position_m",
        ),
        ("seed = 3", "seed = -1", "nucleation.seed"),
        ("seed = 3", "seed = 1e308", "nucleation.seed"),
        ("seed = 3", "seed = \"x\"", "nucleation.seed"),
        (
            "slope_per_m = 2e6",
            "slope_per_m = \"x\"",
            "nucleation.slope_per_m",
        ),
        (
            "slope_per_m = 2e6",
            "slope_per_m = 1e308",
            "nucleation.slope_per_m",
        ),
        (
            "number_density_per_m3 = 1e9",
            "number_density_per_m3 = 1e308",
            "nucleation.number_density_per_m3",
        ),
        (
            "skin_compression = 0.257",
            "skin_compression = \"x\"",
            "nucleation.skin_compression",
        ),
        (
            "skin_compression = 0.257",
            "skin_compression = 1e308",
            "nucleation.skin_compression",
        ),
        (
            "max_step_s = 1.0",
            "max_pressure_change = 1e308",
            "numerics.max_pressure_change",
        ),
        (
            "max_step_s = 1.0",
            "max_content_change = 1e308",
            "numerics.max_content_change",
        ),
        (
            "surface_tension = 0.07",
            "surface_tension = -1e308",
            "material.surface_tension",
        ),
    ];
    for (from, to, field) in cases {
        let text = SWEEP_PHANTOM.replacen(from, to, 1);
        assert_eq!(text.matches(to).count(), 1, "{to}");
        let line = text.lines().position(|l| l.contains(to)).unwrap() + 1;
        let e = parse_phantom(&text, Path::new("p.toml")).unwrap_err();
        assert_eq!(
            (e.field.as_deref(), e.line),
            (Some(field), Some(line)),
            "{to}: {e}"
        );
        assert!(e.file.is_some(), "{e}");
        assert!(!e.message.contains("00000000"), "{to}: {e}");
    }
    // a population's integers given as a float: serde's message, the number written short
    let text = SWEEP_PHANTOM
        .split("[[bubbles]]")
        .next()
        .unwrap()
        .to_string()
        + "[population]\ncount = 1e308\ninitial_radius_m = 5e-5\nseed = 1\n";
    let e = parse_phantom(&text, Path::new("p.toml")).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("population.count"), "{e}");
    assert!(e.message.contains("`1e308`"), "{e}");
    // the laws' parameter tables: an unknown or missing key is named under its table (and a
    // sum's term by its index) at its own line, or the table's header when it is missing
    // (before: `material.elasticity` or `material.surface` at the table's header)
    let hyper = "[material.elasticity]\nlaw = \"hyperelastic\"\n";
    let term = "[[material.elasticity.terms]]\nlaw = \"hyperelastic\"\nshear_modulus = 40.0\n";
    for (tables, field, at) in [
        (
            format!("{hyper}shear_modulus = 40.0\nbar = 1\n"),
            "material.elasticity.bar",
            "bar = 1",
        ),
        (
            hyper.to_string(),
            "material.elasticity.shear_modulus",
            "[material.elasticity]",
        ),
        (
            "[material.surface]\nlaw = \"equal\"\nfold = 30\n".to_string(),
            "material.surface.fold",
            "fold = 30",
        ),
        (
            format!("[material.elasticity]\nlaw = \"sum\"\n{term}{term}bar = 1\n"),
            "material.elasticity.terms[1].bar",
            "bar = 1",
        ),
    ] {
        let text = SWEEP_PHANTOM.replacen(
            "surface_tension = 0.07\n",
            &format!("surface_tension = 0.07\n{tables}"),
            1,
        );
        let line = text.lines().position(|l| l == at).unwrap() + 1;
        let e = parse_phantom(&text, Path::new("p.toml")).unwrap_err();
        assert_eq!(
            (e.field.as_deref(), e.line),
            (Some(field), Some(line)),
            "{tables}: {e}"
        );
    }
}

/// VPM skins no stronger than the gel's surface tension (γc ≤ γ, Yount 1979) were refused only
/// when the simulation built its nuclei, without the phantom file or line; a skin compression of
/// the wrong type was blamed on `nucleation.model`; `[nuclei]` holds no skin compression.
#[test]
fn skin_compression_is_refused_at_its_line_in_the_phantom_file() {
    let dir = tempdir("hard-skin");
    let profile = write(&dir, "p.toml", SHORT_PROFILE);
    let line = SWEEP_PHANTOM
        .lines()
        .position(|l| l.starts_with("skin_compression"))
        .unwrap()
        + 1;
    let nuclei_line = SWEEP_PHANTOM.lines().count() + 2;
    for (text, needles) in [
        (
            SWEEP_PHANTOM.replace("skin_compression = 0.257", "skin_compression = 0.05"),
            vec![
                format!("ph.toml:{line}:"),
                "field 'nucleation.skin_compression'".into(),
                "γc = 0.05 N/m must exceed".into(),
                "γ = 0.07 N/m".into(),
            ],
        ),
        (
            SWEEP_PHANTOM.replace("skin_compression = 0.257", "skin_compression = \"x\""),
            vec![
                format!("ph.toml:{line}:"),
                "field 'nucleation.skin_compression'".into(),
                "expected f64".into(),
            ],
        ),
        (
            SWEEP_PHANTOM.replace("skin_compression = 0.257", "skin_compression = -1"),
            vec![
                format!("ph.toml:{line}:"),
                "field 'nucleation.skin_compression'".into(),
                "-1 N/m is outside the accepted range 0.001 ..= 10 N/m".into(),
            ],
        ),
        (
            format!("{SWEEP_PHANTOM}[nuclei]\nskin_compression = 0.257\n"),
            vec![
                format!("ph.toml:{nuclei_line}:"),
                "field 'nuclei.skin_compression'".into(),
                "unknown field".into(),
            ],
        ),
    ] {
        let ph = write(&dir, "ph.toml", &text);
        let out = dir.join("out");
        let o = simulate_into(&dir, &profile, &ph, &out);
        let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
        assert_refused(&o, &needles);
        assert!(!out.exists());
    }
}

/// `[protocol] oxygen_at_faces` of a criteria file given as a number or a word: the file and
/// line were named but not the field; an absurd pressure beside it was written in 309 digits.
#[test]
fn criteria_protocol_values_name_the_field() {
    let dir = tempdir("hard-oxygen");
    let s = write(&dir, "s.toml", &schedule("10.0", "1.0"));
    let base = std::fs::read_to_string(criteria()).unwrap();
    let key_line = |text: &str, key: &str| {
        text.lines()
            .position(|l| l.starts_with(&format!("{key} =")))
            .unwrap()
            + 1
    };
    for (key, value, needle) in [
        ("oxygen_at_faces", "1", "expected a boolean"),
        ("oxygen_at_faces", "\"yes\"", "expected a boolean"),
        ("water_vapour_pa", "1e308", "(got 1e308)"),
    ] {
        let text: String = base
            .lines()
            .map(|l| {
                if l.starts_with(&format!("{key} =")) {
                    format!("{key} = {value}\n")
                } else {
                    format!("{l}\n")
                }
            })
            .collect();
        let c = write(&dir, "c.toml", &text);
        let out = dir.join("out");
        let o = run(&[
            "check".as_ref(),
            "--schedule".as_ref(),
            s.as_os_str(),
            "--criteria".as_ref(),
            c.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ]);
        let line = key_line(&text, key);
        assert_refused(
            &o,
            &[
                &format!("c.toml:{line}:"),
                &format!("field 'protocol.{key}'"),
                needle,
            ],
        );
        assert!(!String::from_utf8_lossy(&o.stderr).contains("00000000"));
        assert!(!out.exists());
    }
}

/// `elasticity`: every option's bad value names the option as typed (`--p0`, not the field
/// `p0`), on the command line, with its unit and range.
#[test]
fn elasticity_options_are_named_as_typed() {
    for (flag, v, needle) in [
        (
            "--p0",
            "-1",
            "-1 Pa is outside the accepted range 1 ..= 2e7 Pa (absolute pressure)",
        ),
        ("--p0", "0", "0 Pa is outside"),
        ("--pf", "nan", "NaN Pa is outside"),
        ("--pf", "inf", "inf Pa is outside"),
        (
            "--gamma",
            "-1",
            "-1 N/m is outside the accepted range 0 ..= 1 N/m",
        ),
        ("--gamma", "nan", "NaN N/m is outside"),
        (
            "--mu",
            "-40",
            "-40 Pa is outside the accepted range 0 ..= 1e7 Pa",
        ),
        ("--m", "1e308", "1e308 Pa/m³ is outside"),
        (
            "--k",
            "1",
            "1 Pa is outside the accepted range 1000 ..= 1e12 Pa",
        ),
        (
            "--r0",
            "1e-4,-1",
            "-1 m is outside the accepted range 1e-7 ..= 0.01 m",
        ),
        ("--r0", "0", "0 m is outside"),
    ] {
        let o = run(&["elasticity".as_ref(), flag.as_ref(), v.as_ref()]);
        assert_refused(&o, &["<command line>", &format!("field '{flag}'"), needle]);
        assert!(o.stdout.is_empty());
    }
}

// ---- bad-input review 3: fit, synth, evaluate and output folders ----

/// A `fit` parameter at a path that holds no number (the elasticity law's name, the shape, the
/// box's size list, a table) is refused as such, naming the path, what it holds and the
/// phantom file, on the command line (`--param`) and in `[fit] free` (the experiments file's
/// line). Before, `--param` said the path was "not set in the phantom file (it is at its
/// default)", and with bounds that its start value was not accepted.
#[test]
fn fit_parameters_that_are_not_numbers_are_refused_as_such() {
    let dir = tempdir("hard-fit-not-a-number");
    let e = fit_lab(&dir, "e1");
    let m = write(&dir, "m.csv", &fit_rows(7));
    let out = dir.join("out");
    for (param, holds) in [
        ("material.elasticity.law", "holds a string"),
        ("material.elasticity.law=1..2", "holds a string"),
        ("geometry.shape", "holds a string"),
        ("geometry.size_m", "holds a list of numbers"),
        ("material", "holds a table"),
    ] {
        let o = fit_cmd(&m, &e, &[param], &out);
        let path = param.split('=').next().unwrap();
        assert_refused(
            &o,
            &[
                "<command line>",
                "field '--param'",
                &format!("'{path}' {holds}"),
                "phantom.toml",
                "not a number",
            ],
        );
        assert!(!String::from_utf8_lossy(&o.stderr).contains("default"));
    }
    let o = fit_cmd(&m, &e, &["geometry.size_m"], &out);
    assert_refused(&o, &["e.g. 'geometry.size_m.0'"]);
    // in [fit] free: the experiments file's line of `free`
    let text = std::fs::read_to_string(&e).unwrap();
    let e2 = write(
        &dir,
        "e2.toml",
        &format!("{text}[fit]\nfree = [\"material.elasticity.law\"]\n"),
    );
    let o = fit_cmd(&m, &e2, &[], &out);
    assert_refused(
        &o,
        &[
            "e2.toml:6:",
            "field 'fit.free'",
            "holds a string",
            "not a number",
        ],
    );
    assert!(!out.exists() && !dir.join("out.partial").exists());
}

/// A parameter given both in `[fit] free` and as `--param` is refused naming both places (the
/// experiments file and its line, and `--param`); one listed twice in `[fit] free` is refused
/// at its line (before, it was fitted as two parameters: two estimates of one value and a
/// singular Jacobian), and `--param` twice says it is the command line's.
#[test]
fn a_fit_parameter_is_given_in_one_place_once() {
    let dir = tempdir("hard-fit-twice");
    let e = fit_lab(&dir, "e1");
    let m = write(&dir, "m.csv", &fit_rows(7));
    let out = dir.join("out");
    let text = std::fs::read_to_string(&e).unwrap();
    let e2 = write(
        &dir,
        "e2.toml",
        &format!("{text}[fit]\nfree = [\"gases.n2.diffusivity\"]\n"),
    );
    for param in ["gases.n2.diffusivity", "gases.n2.diffusivity=1e-10..1e-8"] {
        let o = fit_cmd(&m, &e2, &[param], &out);
        assert_refused(
            &o,
            &[
                "<command line>",
                "field '--param'",
                "'gases.n2.diffusivity' is also in [fit] free of",
                "e2.toml (line 6)",
            ],
        );
    }
    let e3 = write(
        &dir,
        "e3.toml",
        &format!("{text}[fit]\nfree = [\"gases.n2.diffusivity\", \"gases.n2.diffusivity\"]\n"),
    );
    let o = fit_cmd(&m, &e3, &[], &out);
    assert_refused(&o, &["e3.toml:6:", "field 'fit.free'", "listed twice"]);
    let o = fit_cmd(
        &m,
        &e,
        &["gases.n2.diffusivity", "gases.n2.diffusivity=1e-10..1e-8"],
        &out,
    );
    assert_refused(&o, &["field '--param'", "given twice on the command line"]);
    assert!(!out.exists() && !dir.join("out.partial").exists());
}

/// A journal `OUT.partial/` that cannot be resumed is refused naming its file (and line 1, or
/// the line of a byte that is not UTF-8) and what to do: resume the same work, or delete the
/// folder, or give another `--out`. A folder there with a user's file but no journal, or a
/// file in its place, is refused and kept (a finished fit removes its journal folder whole).
/// Before, the refusal named only the folder and `--out`; a journal that was not UTF-8 was
/// overwritten, a user's folder filled and then removed, and a file there was exit 3.
#[test]
fn fit_journal_refusals_name_the_journal_file_and_what_to_do() {
    let dir = tempdir("hard-fit-journal");
    let e = fit_lab(&dir, "e1");
    let m = write(&dir, "m.csv", &fit_rows(7));
    let out = dir.join("out");
    let jdir = dir.join("out.partial");
    let journal = jdir.join(decophantom::fit::journal::FILE);
    let fit = || fit_cmd(&m, &e, &["gases.n2.diffusivity"], &out);
    std::fs::create_dir_all(&jdir).unwrap();
    for (bytes, needles) in [
        (
            &b"# decophantom 0.1.0 fit 00\n"[..],
            &[
                "out.partial/simulations.txt:1:",
                "journal of a different fit",
                "its first line: # decophantom 0.1.0 fit 00",
                "resume it with the same inputs",
            ][..],
        ),
        (
            &b""[..],
            &[
                "out.partial/simulations.txt:1:",
                "journal of a different fit (no header)",
            ][..],
        ),
        (
            &b"# decophantom\nab\xff\n"[..],
            &[
                "out.partial/simulations.txt:2:",
                "not UTF-8",
                "not a journal decophantom wrote",
            ][..],
        ),
    ] {
        std::fs::write(&journal, bytes).unwrap();
        let o = fit();
        assert_refused(&o, needles);
        assert_refused(&o, &["delete the folder", "out.partial", "another --out"]);
        assert_eq!(
            std::fs::read(&journal).unwrap(),
            bytes,
            "the journal was changed"
        );
    }
    std::fs::remove_file(&journal).unwrap();
    let mine = write(&jdir, "notes.txt", "mine\n");
    assert_refused(
        &fit(),
        &["out.partial:", "no journal (simulations.txt is missing)"],
    );
    assert_eq!(std::fs::read_to_string(&mine).unwrap(), "mine\n");
    std::fs::remove_dir_all(&jdir).unwrap();
    write(&dir, "out.partial", "mine\n");
    assert_refused(
        &fit(),
        &["out.partial:", "is not a folder", "another --out"],
    );
    assert_eq!(std::fs::read_to_string(&jdir).unwrap(), "mine\n");
    assert!(!out.exists());
}

/// `evaluate` refuses a `--schedule` (or `--algorithm`) given twice, however spelt (`X`,
/// `DIR/./X`, a symlink to it), naming the option: the file would be run twice and ranked
/// against itself (before: two identical rows, tied at rank 1, exit 0).
#[test]
fn evaluate_refuses_a_file_given_twice() {
    let dir = tempdir("hard-evaluate-twice");
    let ph = write(&dir, "ph.toml", &good_phantom());
    let fast = write(
        &dir,
        "fast.csv",
        "time_min,depth_m\n0,0\n1.5,10\n5,10\n6,0\n",
    );
    let respelt = dir.join(".").join("fast.csv");
    let out = dir.join("eval");
    let crit = criteria();
    let evaluate = |flag: &str, a: &Path, b: &Path, extra: &[&str]| {
        let mut args: Vec<&std::ffi::OsStr> = vec![
            "evaluate".as_ref(),
            flag.as_ref(),
            a.as_os_str(),
            flag.as_ref(),
            b.as_os_str(),
            "--criteria".as_ref(),
            crit.as_os_str(),
            "--phantom".as_ref(),
            ph.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ];
        args.extend(extra.iter().map(std::ffi::OsStr::new));
        run(&args)
    };
    for twice in [&fast, &respelt] {
        let o = evaluate("--schedule", &fast, twice, &[]);
        assert_refused(
            &o,
            &[
                "<command line>",
                "field '--schedule'",
                "is the same file as",
                "fast.csv",
            ],
        );
    }
    #[cfg(unix)]
    {
        let link = dir.join("link.csv");
        std::os::unix::fs::symlink(&fast, &link).unwrap();
        let o = evaluate("--schedule", &fast, &link, &[]);
        assert_refused(&o, &["field '--schedule'", "link.csv' is the same file as"]);
    }
    let alg = root().join("algorithms/zhl16c-gf30-85.toml");
    let again = root().join("algorithms/../algorithms/zhl16c-gf30-85.toml");
    let o = evaluate(
        "--algorithm",
        &alg,
        &again,
        &["--depth", "10", "--time", "5"],
    );
    assert_refused(&o, &["field '--algorithm'", "is the same file as"]);
    assert!(!out.exists() && !dir.join("eval.partial").exists());
}

/// `synth --every` longer than an experiment gives each of its bubbles one sample, at t = 0
/// (the starting radius, which no parameter changes): refused before any simulation, naming
/// `--every`, the experiment and its duration (before: 1 row per bubble, exit 0, and `fit`
/// then ran on them). An interval equal to the duration gives 2 samples and is accepted.
#[test]
fn synth_every_must_sample_each_bubble_twice() {
    let dir = tempdir("hard-synth-every");
    let e = fit_lab(&dir, "e1");
    let out = dir.join("m.csv");
    for every in ["1e9", "60.5"] {
        let o = synth_cmd(&e, &["--every", every], &out);
        assert_refused(
            &o,
            &[
                "<command line>",
                "field '--every'",
                "experiment 'e1' (its profile lasts 60 s)",
                "at least 2",
                "--every ≤ 60 s",
            ],
        );
        assert!(!out.exists());
    }
    let o = synth_cmd(&e, &["--every", "60"], &out);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let m = decophantom::fit::data::read_measurements(&out).unwrap();
    assert_eq!(m.len(), 2, "t = 0 and 60 s");
}

/// An output folder inside another run's output folder is refused before the run (exit 2,
/// `--out`, the outer folder named): the outer run's next run would find it outside its
/// manifest and be refused. A folder that holds another run's output folder is refused naming
/// it as such (before: "which decophantom did not write"). Nothing is replaced or removed.
#[test]
fn an_output_folder_inside_another_is_refused() {
    let dir = tempdir("hard-nested-out");
    let ph = write(&dir, "ph.toml", &good_phantom());
    let prof = write(&dir, "p.toml", SHORT_PROFILE);
    let outer = dir.join("outer");
    let ok = |o: Output| {
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        )
    };
    ok(simulate_into(&dir, &prof, &ph, &outer));
    let before = std::fs::read(outer.join("bubbles.csv")).unwrap();
    for inner in [
        outer.join("inner"),
        outer.join("a").join("..").join("inner"),
    ] {
        let o = simulate_into(&dir, &prof, &ph, &inner);
        assert_refused(
            &o,
            &[
                "field '--out'",
                "lies inside",
                "outer",
                "the output folder of another run",
            ],
        );
    }
    assert!(!outer.join("inner").exists() && !outer.join("a").exists());
    // beside it, through `..`: accepted
    ok(simulate_into(
        &dir,
        &prof,
        &ph,
        &outer.join("..").join("beside"),
    ));
    // an output folder moved into another: the outer one is refused, naming it
    std::fs::rename(dir.join("beside"), outer.join("moved")).unwrap();
    let o = simulate_into(&dir, &prof, &ph, &outer);
    assert_refused(
        &o,
        &[
            "field '--out'",
            "holds 'moved', the output folder of another run",
        ],
    );
    assert_eq!(std::fs::read(outer.join("bubbles.csv")).unwrap(), before);
    assert!(outer.join("moved").join("bubbles.csv").is_file());
}
