//! The evaluation path end to end: `evaluate` and `check` through a small phantom, the
//! report files, the scores, exit codes and all-or-nothing output on bad input.

use crate::common::{bin, root, tempdir};
use std::path::{Path, PathBuf};
use std::process::Command;

/// A 3 mm gel cube open at the top only (h = 150 µm, 8 000 cells) with two nuclei of 100 µm
/// just above R_min = 86.5 µm: impermeable while compressed at depth, growing near the surface.
const PHANTOM: &str = r#"name = "test-gel"
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
[gases.he]
diffusivity = 8.35e-9
ostwald = 0.0098
[nuclei]
min_radius_m = 86.5e-6
[[bubbles]]
position_m = [1.5e-3, 1.5e-3, 1.5e-3]
initial_radius_m = 100e-6
[[bubbles]]
position_m = [1.5e-3, 1.5e-3, 2.4e-3]
initial_radius_m = 100e-6
[numerics]
max_step_s = 30.0
record_interval_s = 10.0
"#;

/// Criteria with every registered kind; `scale` multiplies every limit.
fn criteria(scale: f64) -> String {
    format!(
        r#"description = "test limits"
[protocol]
observe_after_surfacing_min = 30
water_vapour_pa = 6270
[[criterion]]
kind = "peak-total-volume"
limit = {}
[[criterion]]
kind = "peak-radius"
limit = {}
[[criterion]]
kind = "peak-area-growth-rate"
label = "dA/dt after surfacing"
window = "after-surfacing"
limit = {}
[[criterion]]
kind = "volume-time-above-threshold"
limit = {}
threshold_mm3 = 0.008378
[[criterion]]
kind = "peak-supersaturation"
limit = {}
[[criterion]]
kind = "hazard"
limit = {}
gain_per_mm3_min = 0.1
threshold_mm3 = 0.008378
"#,
        0.0145 * scale,
        107.0 * scale,
        17.0 * scale,
        0.04 * scale,
        150.0 * scale,
        0.4 * scale
    )
}

/// 30 m for 10 min on air, straight to the surface at 30 m/min.
const FAST: &str = "time_min,depth_m\n0,0\n1.5,30\n11.5,30\n12.5,0\n";
/// The same dive with an ascent at about 10 m/min and stops at 6 m (5 min) and 3 m (10 min).
const STOPS: &str = "time_min,depth_m\n0,0\n1.5,30\n11.5,30\n14,6\n19,6\n19.3,3\n29.3,3\n29.6,0\n";

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn run(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(bin()).args(args).output().unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// scores.csv as rows of text cells: schedule, elasticity, kind, label, unit, value, limit,
/// margin, value_over_limit, result, absolute_value.
fn scores(dir: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(dir.join("scores.csv")).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    assert_eq!(
        header,
        "schedule,elasticity,kind,label,unit,value,limit,margin,value_over_limit,result,absolute_value"
    );
    lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect()
}

fn value(rows: &[Vec<String>], criterion: &str) -> f64 {
    rows.iter()
        .find(|r| r[3] == criterion)
        .unwrap_or_else(|| panic!("no row for {criterion}"))[5]
        .parse()
        .unwrap()
}

#[test]
fn evaluate_writes_a_consistent_well_formed_report() {
    let d = tempdir("evaluate-report");
    let ph = write(&d, "phantom.toml", PHANTOM);
    let cr = write(&d, "criteria.toml", &criteria(1.0));
    let out = d.join("report");
    let alg = |n: &str| root().join("algorithms").join(n);
    let (code, stdout, stderr) = run(&[
        "evaluate",
        "--depth",
        "30",
        "--time",
        "10",
        "--algorithm",
        s(&alg("zhl16c-gf30-85.toml")),
        "--algorithm",
        s(&alg("zhl16c-gf100-100.toml")),
        "--elasticity",
        "hyperelastic,none",
        "--phantom",
        s(&ph),
        "--criteria",
        s(&cr),
        "--out",
        s(&out),
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    for f in [
        "report.md",
        "report.html",
        "scores.csv",
        "profiles.svg",
        "pressure.svg",
        "volume.svg",
        "radius-1.svg",
        "radius-2.svg",
        "area.svg",
        "area-rate.svg",
        "supersaturation.svg",
        "criteria.svg",
        "elasticity-1.svg",
        "elasticity-2.svg",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    // HTML and every SVG are well-formed XML; the HTML inlines its figures and has no script
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    let opt = roxmltree::ParsingOptions {
        allow_dtd: true,
        ..Default::default()
    };
    let doc = roxmltree::Document::parse_with_options(&html, opt)
        .expect("report.html is well-formed XML");
    assert!(doc.descendants().any(|n| n.has_tag_name("svg")));
    assert!(!doc.descendants().any(|n| n.has_tag_name("script")));
    for e in std::fs::read_dir(&out).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "svg") {
            let t = std::fs::read_to_string(&p).unwrap();
            roxmltree::Document::parse(&t).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
        }
    }
    // every figure the Markdown links to is in the folder
    let md_text = std::fs::read_to_string(out.join("report.md")).unwrap();
    for link in md_text.split("](").skip(1) {
        let file = link.split(')').next().unwrap();
        if file.ends_with(".svg") {
            assert!(
                out.join(file).is_file(),
                "report.md links to missing {file}"
            );
        }
    }
    // every row of scores.csv appears in report.md's criteria table, the table rounding the
    // value to 4 significant figures (within half a unit of the 4th: relative 5e-4)
    let rows = scores(&out);
    assert_eq!(rows.len(), 2 * 2 * 6, "2 schedules × 2 laws × 6 criteria");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    let md_rows: Vec<Vec<String>> = md
        .lines()
        .filter(|l| l.starts_with("| ") && l.matches(" | ").count() == 9)
        .map(|l| {
            l.trim_matches(|c| c == '|' || c == ' ')
                .split(" | ")
                .map(|c| c.replace('\\', ""))
                .collect()
        })
        .collect();
    for r in &rows {
        let m = md_rows
            .iter()
            .find(|m| m[0] == r[0] && m[1] == r[1] && m[2] == r[3] && m[3] == r[4])
            .unwrap_or_else(|| panic!("scores.csv row {r:?} not in report.md"));
        let (csv_v, md_v): (f64, f64) = (r[5].parse().unwrap(), m[4].parse().unwrap());
        assert!(
            (csv_v - md_v).abs() <= 5e-4 * csv_v.abs() + 1e-300,
            "{r:?} vs {m:?}"
        );
        assert_eq!(m[8], r[9]);
    }
    // full precision: margin = limit − value exactly as computed, value_over_limit = value/limit
    for r in &rows {
        let (v, l, m, q): (f64, f64, f64, f64) = (
            r[5].parse().unwrap(),
            r[6].parse().unwrap(),
            r[7].parse().unwrap(),
            r[8].parse().unwrap(),
        );
        assert_eq!(m, l - v, "{r:?}");
        assert_eq!(q, v / l, "{r:?}");
        assert_eq!(r[9] == "pass", v <= l, "{r:?}");
    }
}

#[test]
fn fast_ascent_scores_worse_than_stops_and_check_exit_codes() {
    let d = tempdir("evaluate-fast");
    let ph = write(&d, "phantom.toml", PHANTOM);
    let tight = write(&d, "tight.toml", &criteria(1.0));
    let loose = write(&d, "loose.toml", &criteria(1e6));
    let fast = write(&d, "fast.csv", FAST);
    let stops = write(&d, "stops.csv", STOPS);
    let mut got = Vec::new();
    for (name, sched) in [("fast", &fast), ("stops", &stops)] {
        let out = d.join(name);
        let (code, stdout, stderr) = run(&[
            "check",
            "--schedule",
            s(sched),
            "--criteria",
            s(&tight),
            "--phantom",
            s(&ph),
            "--out",
            s(&out),
        ]);
        assert!(code == 0 || code == 1, "{stdout}{stderr}");
        let rows = scores(&out);
        // exit code 1 exactly when some criterion fails
        assert_eq!(code == 1, rows.iter().any(|r| r[9] == "FAIL"), "{stdout}");
        got.push(rows);
    }
    // every criterion that measures bubble growth (and the gel supersaturation that drives it)
    for c in [
        "peak-total-volume",
        "peak-radius",
        "dA/dt after surfacing",
        "volume-time-above-threshold",
        "hazard",
        "peak-supersaturation",
    ] {
        let (f, st) = (value(&got[0], c), value(&got[1], c));
        assert!(
            f > st,
            "{c}: fast ascent {f} should exceed the schedule with stops {st}"
        );
    }
    // bubbles grew at all in the fast ascent: peak-radius scores the growth above R0 = 100 µm,
    // and its absolute value (last column) is R0 plus that growth
    assert!(value(&got[0], "peak-radius") > 0.0);
    let row = got[0].iter().find(|r| r[3] == "peak-radius").unwrap();
    let absolute: f64 = row[10].parse().unwrap();
    assert!(
        (absolute - 100.0 - value(&got[0], "peak-radius")).abs() < 1e-9,
        "{row:?}"
    );
    // the fast ascent fails the tight limits (exit 1); everything passes limits ×1e6 (exit 0)
    let (code, out1, _) = run(&[
        "check",
        "--schedule",
        s(&fast),
        "--criteria",
        s(&tight),
        "--phantom",
        s(&ph),
    ]);
    assert_eq!(code, 1, "{out1}");
    assert!(out1.contains("FAIL"));
    let (code, out0, err0) = run(&[
        "check",
        "--schedule",
        s(&stops),
        "--criteria",
        s(&loose),
        "--phantom",
        s(&ph),
    ]);
    assert_eq!(code, 0, "{out0}{err0}");
    assert!(out0.contains("all criteria pass"));
}

#[test]
fn bad_input_exits_2_and_writes_nothing() {
    let d = tempdir("evaluate-bad");
    let ph = write(&d, "phantom.toml", PHANTOM);
    let good = write(&d, "criteria.toml", &criteria(1.0));
    let fast = write(&d, "fast.csv", FAST);
    let never = write(
        &d,
        "never.csv",
        "time_min,depth_m\n0,0\n1.5,30\n11.5,30\n12.5,5\n",
    );
    let unknown = write(
        &d,
        "unknown.toml",
        "[[criterion]]\nkind = \"peak-radius\"\nlimit = 100\n[[criterion]]\nkind = \"bubble-grade\"\nlimit = 3\n",
    );
    let negative = write(
        &d,
        "negative.toml",
        "[[criterion]]\nkind = \"peak-radius\"\nlimit = -100\n",
    );
    // an earlier report in the output folder must survive a failed run untouched
    let out = d.join("out");
    let (code, o, e) = run(&[
        "check",
        "--schedule",
        s(&fast),
        "--criteria",
        s(&good),
        "--phantom",
        s(&ph),
        "--out",
        s(&out),
    ]);
    assert!(code == 0 || code == 1, "{o}{e}");
    let before = std::fs::read(out.join("scores.csv")).unwrap();
    let listing = |p: &Path| {
        let mut v: Vec<_> = std::fs::read_dir(p)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        v.sort();
        v
    };
    let files_before = listing(&out);
    let cases: [(&Path, &Path, &str, &str); 3] = [
        (&never, &good, "never surfaces", "depth_m"),
        (&fast, &unknown, "unknown criterion", "criterion.kind"),
        (&fast, &negative, "must be positive", "criterion.limit"),
    ];
    for (sched, crit, msg, field) in cases {
        let (code, _, err) = run(&[
            "check",
            "--schedule",
            s(sched),
            "--criteria",
            s(crit),
            "--phantom",
            s(&ph),
            "--out",
            s(&out),
        ]);
        assert_eq!(code, 2, "{err}");
        assert!(err.contains(msg) && err.contains(field), "{err}");
        assert_eq!(std::fs::read(out.join("scores.csv")).unwrap(), before);
        assert_eq!(listing(&out), files_before);
        // evaluate with the same bad criteria creates no folder at all
        let fresh = d.join("fresh");
        if crit != good.as_path() {
            let (code, _, err) = run(&[
                "evaluate",
                "--depth",
                "30",
                "--time",
                "10",
                "--algorithm",
                s(&root().join("algorithms/zhl16c-gf30-85.toml")),
                "--phantom",
                s(&ph),
                "--criteria",
                s(crit),
                "--out",
                s(&fresh),
            ]);
            assert_eq!(code, 2, "{err}");
            assert!(!fresh.exists());
        }
    }
    // the line of the offending field is named
    let (_, _, err) = run(&[
        "check",
        "--schedule",
        s(&fast),
        "--criteria",
        s(&unknown),
        "--phantom",
        s(&ph),
    ]);
    assert!(err.contains("unknown.toml:5:"), "{err}");
    // no staging folders left beside the output
    assert!(!listing(&d)
        .iter()
        .any(|n| n.to_string_lossy().contains("staging")));
}

/// Dive logs are schedules for `check` and `evaluate` (issue 9 §2). Reference numbers from
/// tests/data/divelogs/repetitive-logged.xml, dive 2 (read off the file): last sample 38:00
/// at 0.0 m, deepest 17.4 m, surface pressure 1.011 bar, no salinity (1030 kg/m³ assumed).
#[test]
fn dive_logs_are_checked_and_evaluated_as_schedules() {
    use decophantom::algorithm::conventions::DECOTENGU;
    use decophantom::algorithm::waypoints::read_schedule_with_notes;
    use decophantom::units::STANDARD_GRAVITY;
    let log = root().join("tests/data/divelogs/repetitive-logged.xml");
    // the schedule and its history: the log's own surface and density, then the protocol's
    // watch time at the surface (30 min in these criteria), so the run goes on after the
    // last sample
    let imp = read_schedule_with_notes(
        &log,
        &DECOTENGU,
        decophantom::gas::GasMix::AIR,
        Some(decophantom::profile::sequence::DiveSelection::One(2)),
    )
    .unwrap();
    assert!((imp.schedule.runtime_min() - 38.0).abs() < 1e-9);
    assert!(imp.notes.iter().any(|n| n.contains("water density")));
    let protocol = decophantom::risk::Protocol {
        observe_after_surfacing_s: 1800.0,
        ..Default::default()
    };
    let h = decophantom::app::evaluate::dive_history(&imp.schedule, &protocol, None).unwrap();
    assert!(
        (h.duration_s() - (2280.0 + 1800.0)).abs() < 1e-6,
        "{}",
        h.duration_s()
    );
    let top = h.ambient_pa.iter().cloned().fold(0.0, f64::max);
    let want = 1.011e5 + 17.4 * 1030.0 * STANDARD_GRAVITY;
    assert!((top - want).abs() < 1e-6, "{top} vs {want}");

    let d = tempdir("evaluate-divelog");
    let ph = write(&d, "phantom.toml", PHANTOM);
    let loose = write(&d, "loose.toml", &criteria(1e6));
    let out = d.join("check");
    let (code, stdout, stderr) = run(&[
        "check",
        "--schedule",
        s(&log),
        "--dive",
        "2",
        "--criteria",
        s(&loose),
        "--phantom",
        s(&ph),
        "--out",
        s(&out),
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    // import notes printed and in the report
    assert!(stdout.contains("note: no water density"), "{stdout}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("Import notes for repetitive-logged #2"),
        "{report}"
    );
    assert!(report.contains("no water density in the file"), "{report}");
    // simulated 38 min of dive + 30 min watched at the surface
    assert!(report.contains("| 68.0 |"), "{report}");
    // a log with two dives needs --dive; a dive number on a CSV is refused
    let (code, _, stderr) = run(&[
        "check",
        "--schedule",
        s(&log),
        "--criteria",
        s(&loose),
        "--phantom",
        s(&ph),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("2 dives"), "{stderr}");
    let stops = write(&d, "stops.csv", STOPS);
    let (code, _, stderr) = run(&[
        "check",
        "--schedule",
        s(&stops),
        "--dive",
        "1",
        "--criteria",
        s(&loose),
        "--phantom",
        s(&ph),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--dive"), "{stderr}");

    // evaluate: a logged dive next to a CSV schedule, no algorithm (so no --depth/--time)
    let out = d.join("eval");
    let (code, stdout, stderr) = run(&[
        "evaluate",
        "--schedule",
        s(&log),
        "--dive",
        "1",
        "--schedule",
        s(&stops),
        "--criteria",
        s(&loose),
        "--phantom",
        s(&ph),
        "--out",
        s(&out),
    ]);
    assert_eq!(code, 0, "{stdout}{stderr}");
    assert!(
        stdout.contains("note (repetitive-logged #1 2019-06-14 09:12:00)"),
        "{stdout}"
    );
    let rows = scores(&out);
    assert!(rows
        .iter()
        .any(|r| r[0].starts_with("repetitive-logged #1")));
    assert!(rows.iter().any(|r| r[0] == "stops"), "{rows:?}");
    // an algorithm without a dive to plan is refused with the missing option named
    let (code, _, stderr) = run(&[
        "evaluate",
        "--schedule",
        s(&stops),
        "--algorithm",
        "algorithms/zhl16c-gf30-85.toml",
        "--criteria",
        s(&loose),
        "--phantom",
        s(&ph),
        "--out",
        s(&d.join("eval2")),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("--depth"), "{stderr}");
}

/// `--json` (docs/json.md) on check, evaluate and plan; `--quiet`; completions and man page.
/// The JSON is checked against the command's own definitions, not against a previous output:
/// every score has margin = limit − value and pass = (value ≤ limit); the kinds are the
/// criteria file's, in its order; the exit code agrees with all_pass.
#[test]
fn json_output_quiet_completions_and_man() {
    let d = tempdir("evaluate-json");
    let ph = write(&d, "phantom.toml", PHANTOM);
    let tight = write(&d, "tight.toml", &criteria(1.0));
    let fast = write(&d, "fast.csv", FAST);
    let out = d.join("check");
    let (code, stdout, stderr) = run(&[
        "check",
        "--schedule",
        s(&fast),
        "--criteria",
        s(&tight),
        "--phantom",
        s(&ph),
        "--json",
        "--quiet",
        "--out",
        s(&out),
    ]);
    assert!(code == 0 || code == 1, "{stdout}{stderr}");
    assert!(!stdout.contains("wrote"), "{stdout}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("check --json is JSON");
    assert_eq!(v["schema"], "decophantom.check/1");
    assert_eq!(v["all_pass"].as_bool(), Some(code == 0));
    let kinds: Vec<&str> = v["run"]["scores"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    assert_eq!(
        kinds,
        [
            "peak-total-volume",
            "peak-radius",
            "peak-area-growth-rate",
            "volume-time-above-threshold",
            "peak-supersaturation",
            "hazard"
        ]
    );
    for sc in v["run"]["scores"].as_array().unwrap() {
        let (val, lim) = (sc["value"].as_f64().unwrap(), sc["limit"].as_f64().unwrap());
        assert_eq!(sc["margin"].as_f64().unwrap(), lim - val);
        assert_eq!(sc["pass"].as_bool().unwrap(), val <= lim);
    }
    assert_eq!(v["run"]["scores"][2]["label"], "dA/dt after surfacing");
    // the fast CSV schedule: 12.5 min to the surface, 30 m deep
    assert_eq!(
        v["candidate"]["schedule"]["runtime_min"].as_f64(),
        Some(12.5)
    );
    assert_eq!(
        v["candidate"]["schedule"]["max_depth_m"].as_f64(),
        Some(30.0)
    );

    let (code, stdout, stderr) = run(&[
        "evaluate",
        "--schedule",
        s(&fast),
        "--criteria",
        s(&tight),
        "--phantom",
        s(&ph),
        "--json",
        "--out",
        s(&d.join("eval")),
    ]);
    assert_eq!(code, 0, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("evaluate --json is JSON");
    assert_eq!(v["schema"], "decophantom.evaluate/1");
    assert_eq!(v["runs"].as_array().unwrap().len(), 1);
    assert_eq!(v["ranking"][0]["rank"].as_u64(), Some(1));

    // plan --json: the stops add up to stop_time_min, and the runtime is the last stop's
    // runtime plus the final ascent (3 m at 10 m/min = 0.3 min in DecoTengu's conventions)
    let (code, stdout, stderr) = run(&[
        "plan",
        "--algorithm",
        root()
            .join("algorithms/zhl16b-gf30-85.toml")
            .to_str()
            .unwrap(),
        "--depth",
        "35",
        "--time",
        "40",
        "--json",
    ]);
    assert_eq!(code, 0, "{stderr}");
    let v: serde_json::Value = serde_json::from_str(&stdout).expect("plan --json is JSON");
    assert_eq!(v["schema"], "decophantom.plan/1");
    let stops = v["schedule"]["stops"].as_array().unwrap();
    let sum: f64 = stops.iter().map(|s| s["stop_min"].as_f64().unwrap()).sum();
    assert!((sum - v["schedule"]["stop_time_min"].as_f64().unwrap()).abs() < 1e-9);
    let last = stops.last().unwrap();
    assert_eq!(last["depth_m"].as_f64(), Some(3.0));
    let runtime = v["schedule"]["runtime_min"].as_f64().unwrap();
    assert!((runtime - (last["runtime_min"].as_f64().unwrap() + 0.3)).abs() < 1e-9);
    assert!(v["cns_percent"].as_f64().unwrap() > 0.0);

    // completions and man page come from the clap definitions
    let (code, bash, _) = run(&["completions", "bash"]);
    assert_eq!(code, 0);
    assert!(bash.contains("_decophantom()") && bash.contains("--schedule"));
    let (code, man, _) = run(&["man"]);
    assert_eq!(code, 0);
    assert!(
        man.starts_with(".ie") || man.starts_with(".TH"),
        "{}",
        &man[..80]
    );
    assert!(man.contains("decophantom"));
}

/// Part 6 of issue 9: a spread between schedules below the numerical uncertainty is a tie, not
/// a ranking. Known ties by construction: the same schedule under two names gives the same
/// run (the simulation is deterministic), so every criterion ties; with a third, different
/// schedule (stops, which scores lower on every criterion — see
/// `fast_ascent_scores_worse_than_stops_and_check_exit_codes`), no criterion ties across all
/// three, the two copies share a rank and the stops rank first.
#[test]
fn identical_schedules_tie_instead_of_ranking_noise() {
    let d = tempdir("evaluate-ties");
    let ph = write(&d, "phantom.toml", PHANTOM);
    let tight = write(&d, "tight.toml", &criteria(1.0));
    let fast = write(&d, "fast.csv", FAST);
    let copy = write(&d, "fast-copy.csv", FAST);
    let stops = write(&d, "stops.csv", STOPS);
    let eval = |scheds: &[&PathBuf], out: &str| {
        let mut args = vec!["evaluate"];
        for sc in scheds {
            args.extend(["--schedule", s(sc)]);
        }
        let out = d.join(out);
        args.extend([
            "--criteria",
            s(&tight),
            "--phantom",
            s(&ph),
            "--json",
            "--quiet",
            "--out",
            s(&out),
        ]);
        let (code, stdout, stderr) = run(&args);
        assert_eq!(code, 0, "{stderr}");
        let v: serde_json::Value = serde_json::from_str(&stdout).expect("JSON");
        (v, std::fs::read_to_string(out.join("report.md")).unwrap())
    };

    // two copies: every criterion tied, both rank 1
    let (v, md) = eval(&[&fast, &copy], "two");
    let ties = v["ties"].as_array().unwrap();
    assert_eq!(ties.len(), 6, "{ties:?}");
    for t in ties {
        assert_eq!(t["spread"].as_f64(), Some(0.0));
        assert!(t["uncertainty"].as_f64().unwrap() > 0.0);
    }
    for r in v["ranking"].as_array().unwrap() {
        assert_eq!(r["rank"].as_u64(), Some(1), "{r}");
        assert_eq!(r["tied"].as_bool(), Some(true), "{r}");
    }
    assert!(md.contains("the schedules are tied on"), "{md}");
    assert!(md.contains("share rank 1"), "{md}");
    assert!(md.contains("| 1 (tied) |"), "{md}");

    // with the stops schedule: no tie across all three; the copies share rank 2
    let (v, md) = eval(&[&fast, &copy, &stops], "three");
    assert_eq!(v["ties"].as_array().unwrap().len(), 0, "{}", v["ties"]);
    let rank = |label: &str| {
        let r = v["ranking"]
            .as_array()
            .unwrap()
            .iter()
            .find(|r| r["schedule"] == label)
            .unwrap_or_else(|| panic!("{label} not ranked: {}", v["ranking"]));
        (r["rank"].as_u64().unwrap(), r["tied"].as_bool().unwrap())
    };
    assert_eq!(rank("stops"), (1, false));
    assert_eq!(rank("fast"), (2, true));
    assert_eq!(rank("fast-copy"), (2, true));
    assert!(!md.contains("tied on"), "{md}");
}

/// D13 (bad-input review 2). The dive options of `evaluate` plan with `--algorithm`; given with
/// schedules only they would be dropped silently (the schedule scored on its own gas), so they
/// are refused (exit 2) on the command line and by the library, and no folder is created.
#[test]
fn dive_options_without_an_algorithm_are_refused() {
    let d = tempdir("evaluate-unused");
    let ph = write(&d, "phantom.toml", PHANTOM);
    let good = write(&d, "criteria.toml", &criteria(1.0));
    let fast = write(&d, "fast.csv", FAST);
    let out = d.join("out");
    for extra in [
        ["--depth", "40"],
        ["--time", "30"],
        ["--gas", "32"],
        ["--deco-gas", "50"],
        ["--travel-gas", "21/35@0..40"],
    ] {
        let mut args = vec![
            "evaluate",
            "--schedule",
            s(&fast),
            "--criteria",
            s(&good),
            "--phantom",
            s(&ph),
            "--out",
            s(&out),
        ];
        args.extend_from_slice(&extra);
        let (code, o, e) = run(&args);
        assert_eq!(code, 2, "{extra:?}: {o}{e}");
        assert!(e.contains("--algorithm") && e.contains(extra[0]), "{e}");
        assert!(!out.exists());
    }
    let req = decophantom::app::evaluate::EvaluateRequest {
        depth_m: None,
        time_min: None,
        gas: Some("32".into()),
        deco_gases: vec![],
        travel_gases: vec![],
        algorithms: vec![],
        schedules: vec![fast.clone()],
        dive: None,
        elasticity: vec![],
        phantom: Some(ph.clone()),
        grid_step_m: None,
        criteria: good.clone(),
        repeat_after_min: None,
        out: out.clone(),
    };
    match decophantom::app::evaluate::run(&req, &mut |_, _| {}) {
        Err(decophantom::error::Error::Input(e)) => {
            assert_eq!(
                (e.file.as_deref(), e.field.as_deref()),
                (Some(Path::new("<command line>")), Some("--gas")),
                "{e}"
            )
        }
        other => panic!("{other:?}"),
    }
    assert!(!out.exists());
}
