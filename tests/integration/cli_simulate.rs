//! The `simulate` and `elasticity` commands through the binary: determinism (verification
//! item 7) and bad input (exit code 2, a message naming file/line/field, no output files).

use crate::common::{bin, root, tempdir};
use std::path::Path;
use std::process::Command;

const SMALL_PHANTOM: &str = r#"
name = "small"
[geometry]
shape = "box"
size_m = [1.5e-3, 1.5e-3, 1.0e-3]
grid_step_m = 100e-6
[material]
surface_tension = 0.07
[material.elasticity]
law = "hyperelastic"
shear_modulus = 40.0
[material.surface]
law = "area"
fold = 30.0
[gases.n2]
diffusivity = 2.5e-9
ostwald = 0.014
[gases.o2]
diffusivity = 2.5e-9
ostwald = 0.027
[nuclei]
min_radius_m = 50e-6
[population]
count = 2
initial_radius_m = 60e-6
min_spacing_m = 400e-6
margin_m = 300e-6
seed = 11
[numerics]
record_interval_s = 5.0
"#;

const SHORT_DIVE: &str = r#"
name = "short dive"
time_unit = "s"
pressure_unit = "psi-gauge"
gas = "air"
points = [[0, 0], [130, 130], [1330, 130], [1356, 0], [2500, 0]]
"#;

fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn simulate(profile: &Path, phantom: &Path, out: &Path) -> std::process::Output {
    simulate_with(profile, phantom, out, &[])
}

/// [`simulate`] with further options.
fn simulate_with(
    profile: &Path,
    phantom: &Path,
    out: &Path,
    extra: &[&str],
) -> std::process::Output {
    Command::new(bin())
        .arg("simulate")
        .args(extra)
        .arg("--profile")
        .arg(profile)
        .arg("--phantom")
        .arg(phantom)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

#[test]
fn same_inputs_and_seed_give_byte_identical_outputs() {
    let d = tempdir("determinism");
    let ph = write(&d, "phantom.toml", SMALL_PHANTOM);
    let pr = write(&d, "dive.toml", SHORT_DIVE);
    let (a, b) = (d.join("a"), d.join("b"));
    for out in [&a, &b] {
        let o = simulate(&pr, &ph, out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    for f in ["bubbles.csv", "radius.svg", "volume.svg"] {
        let x = std::fs::read(a.join(f)).unwrap();
        let y = std::fs::read(b.join(f)).unwrap();
        assert!(!x.is_empty());
        assert!(x == y, "{f} differs between two identical runs");
    }
    // summary.toml: identical apart from the timing field
    let strip = |p: &Path| -> String {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with("wall_seconds"))
            .collect::<Vec<_>>()
            .join("\n")
    };
    assert_eq!(
        strip(&a.join("summary.toml")),
        strip(&b.join("summary.toml"))
    );
    // the header the issue specifies
    let csv = std::fs::read_to_string(a.join("bubbles.csv")).unwrap();
    assert_eq!(
        csv.lines().next().unwrap(),
        "time_s,bubble,radius_m,volume_m3,area_m2,n_n2_mol,n_o2_mol"
    );
    // the bubbles grew after the decompression (the run means something)
    let summary: toml::Table = std::fs::read_to_string(a.join("summary.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let rmax = summary["max_radius_m"].as_float().unwrap();
    assert!(rmax > 1.5 * 60e-6, "max radius {rmax}");
    assert!(summary["gas_balance_error"].as_float().unwrap() < 1e-9);
}

fn expect_input_error(args: &[&str], must_mention: &[&str], out: &Path) {
    let o = Command::new(bin()).args(args).output().unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "args {args:?}: stderr {err}");
    for m in must_mention {
        assert!(
            err.contains(m),
            "error for {args:?} should mention '{m}': {err}"
        );
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        !out.exists(),
        "no output folder may be left after bad input: {}",
        out.display()
    );
}

#[test]
fn bad_input_exits_2_names_the_place_and_writes_nothing() {
    let d = tempdir("badinput");
    let ph = write(&d, "phantom.toml", SMALL_PHANTOM);
    let pr = write(&d, "dive.toml", SHORT_DIVE);
    let out = d.join("out");
    let o = out.to_str().unwrap();
    let s = |p: &Path| p.to_str().unwrap().to_string();
    // unknown field in the phantom
    let typo = write(
        &d,
        "typo.toml",
        &SMALL_PHANTOM.replace("surface_tension = 0.07", "surface_tensoin = 0.07"),
    );
    expect_input_error(
        &[
            "simulate",
            "--profile",
            &s(&pr),
            "--phantom",
            &s(&typo),
            "--out",
            o,
        ],
        &["typo.toml", "surface_tensoin"],
        &out,
    );
    // an open face listed twice
    let twice = write(
        &d,
        "twice.toml",
        &SMALL_PHANTOM.replace(
            "grid_step_m = 100e-6",
            "grid_step_m = 100e-6\nopen_faces = [\"top\", \"top\"]",
        ),
    );
    expect_input_error(
        &[
            "simulate",
            "--profile",
            &s(&pr),
            "--phantom",
            &s(&twice),
            "--out",
            o,
        ],
        &["twice.toml:7:", "geometry.open_faces", "listed twice"],
        &out,
    );
    // a bubble outside the phantom
    let outside = write(
        &d,
        "outside.toml",
        &SMALL_PHANTOM.replace(
            "[population]\ncount = 2\ninitial_radius_m = 60e-6\nmin_spacing_m = 400e-6\nmargin_m = 300e-6\nseed = 11",
            "[[bubbles]]\nposition_m = [2.0e-3, 0.5e-3, 0.5e-3]\ninitial_radius_m = 60e-6",
        ),
    );
    expect_input_error(
        &[
            "simulate",
            "--profile",
            &s(&pr),
            "--phantom",
            &s(&outside),
            "--out",
            o,
        ],
        &["outside.toml", "bubbles", "outside the phantom"],
        &out,
    );
    // non-monotone profile
    let back = write(
        &d,
        "back.toml",
        &SHORT_DIVE.replace("[1356, 0]", "[1200, 0]"),
    );
    expect_input_error(
        &[
            "simulate",
            "--profile",
            &s(&back),
            "--phantom",
            &s(&ph),
            "--out",
            o,
        ],
        &["back.toml"],
        &out,
    );
    // negative time in a legacy file
    let neg = write(&d, "neg.txt", "0 0\n-1 10\n");
    expect_input_error(
        &[
            "simulate",
            "--profile",
            &s(&neg),
            "--units",
            "min,psi-gauge",
            "--phantom",
            &s(&ph),
            "--out",
            o,
        ],
        &["neg.txt"],
        &out,
    );
    // unstable settings
    let unstable = write(
        &d,
        "unstable.toml",
        &SMALL_PHANTOM.replace(
            "record_interval_s = 5.0",
            "record_interval_s = 5.0\nmax_content_change = 0.9",
        ),
    );
    expect_input_error(
        &[
            "simulate",
            "--profile",
            &s(&pr),
            "--phantom",
            &s(&unstable),
            "--out",
            o,
        ],
        &["unstable.toml", "max_content_change"],
        &out,
    );
    // a legacy file without units
    let legacy = root().join("tests/data/legacy/oscillation-30s.txt");
    expect_input_error(
        &[
            "simulate",
            "--profile",
            &s(&legacy),
            "--phantom",
            &s(&ph),
            "--out",
            o,
        ],
        &["units"],
        &out,
    );
}

#[test]
fn elasticity_command_prints_every_form() {
    let o = Command::new(bin())
        .args(["elasticity", "--r0", "1e-6,1e-4"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let text = String::from_utf8_lossy(&o.stdout);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "r0_m,form,rf_m");
    assert_eq!(lines.len(), 1 + 2 * 5);
    for form in [
        "none",
        "bulk-modulus",
        "continuity-of-displacement",
        "reference-configuration",
        "hyperelastic",
    ] {
        assert_eq!(
            lines
                .iter()
                .filter(|l| l.contains(&format!(",{form},")))
                .count(),
            2,
            "{form}"
        );
    }
    // Ω = 0 and γ = 0.07 N/m at R0 = 100 µm: Boyle with a small Laplace term. Independent check
    // by fixed-point iteration of (Pf + 2γ/R)R³ = (P0 + 2γ/R0)R0³.
    let (p0, pf, g, r0) = (1e6f64, 1e4f64, 0.07f64, 1e-4f64);
    let c = (p0 + 2.0 * g / r0) * r0.powi(3);
    let mut r = r0 * 4.0;
    for _ in 0..200 {
        r = (c / (pf + 2.0 * g / r)).cbrt();
    }
    let line = lines
        .iter()
        .find(|l| l.starts_with("1.000000e-4,none,"))
        .unwrap();
    let rf: f64 = line.rsplit(',').next().unwrap().parse().unwrap();
    assert!((rf / r - 1.0).abs() < 1e-9, "{rf} vs {r}");
    // bad input
    let o = Command::new(bin())
        .args(["elasticity", "--p0", "-5"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn simulate_takes_a_schedule_written_by_plan_as_toml_or_csv() {
    let d = tempdir("plan-then-simulate");
    let ph = write(&d, "phantom.toml", SMALL_PHANTOM);
    // `plan --out NAME` of one dive, then `simulate` of it into out-NAME: its summary
    let plan_and_simulate = |name: &str| {
        let schedule = d.join(name);
        let o = Command::new(bin())
            .args(["plan", "--algorithm"])
            .arg(root().join("algorithms/zhl16c-gf30-85.toml"))
            .args([
                "--depth",
                "30",
                "--time",
                "20",
                "--altitude",
                "2000",
                "--out",
            ])
            .arg(&schedule)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let out = d.join(format!("out-{name}"));
        let o = simulate(&schedule, &ph, &out);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let summary: toml::Table = std::fs::read_to_string(out.join("summary.toml"))
            .unwrap()
            .parse()
            .unwrap();
        (schedule, summary)
    };
    let (sched, summary) = plan_and_simulate("schedule.toml");
    // the schedule's runtime (plan prints it; here: the profile ends when the schedule does)
    let schedule: toml::Table = std::fs::read_to_string(&sched).unwrap().parse().unwrap();
    let legs = schedule["legs"].as_array().unwrap();
    let runtime: f64 = legs
        .iter()
        .map(|l| l["duration_s"].as_float().unwrap())
        .sum();
    assert!((summary["end_time_s"].as_float().unwrap() - runtime).abs() < 1e-6);

    // the same plan as a CSV of waypoints (`plan --out x.csv`, what `check` reads) runs the
    // same dive: the reference is the TOML run above (the same legs, read by the other reader;
    // the CSV's times are printed in minutes, so the two agree to rounding, not bit for bit).
    // At 2 000 m the surface is at 79.5 kPa: a CSV read at DecoTengu's 101.325 kPa, as before
    // its `# conventions:` line, grew the largest bubble by half again (measured: +0.89 against
    // +0.59 µm on this phantom), far outside these bounds
    let (csv, from_csv) = plan_and_simulate("schedule.csv");
    let rel = |key: &str| {
        let (a, b) = (
            from_csv[key].as_float().unwrap(),
            summary[key].as_float().unwrap(),
        );
        (a - b).abs() / b.abs()
    };
    assert!(rel("end_time_s") < 1e-9, "end time {}", rel("end_time_s"));
    assert!(rel("max_radius_m") < 1e-9, "R_max {}", rel("max_radius_m"));
    assert!(
        rel("peak_total_volume_m3") < 1e-9,
        "peak volume {}",
        rel("peak_total_volume_m3")
    );

    // a schedule states its own units, gas and vapour: options that would set them are
    // refused (before, a TOML schedule ignored them silently), naming the option, no output
    for (schedule, option, why) in [
        (&sched, ["--units", "min,msw"], "a schedule states its own"),
        (&csv, ["--units", "min,msw"], "a schedule states its own"),
        (&csv, ["--gas", "air"], "a schedule states its own"),
        (&sched, ["--vapour-pa", "6270"], "a schedule states its own"),
        (&csv, ["--dive", "1"], "applies only to dive logs"),
    ] {
        let refused = d.join("refused");
        let o = simulate_with(schedule, &ph, &refused, &option);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{option:?}: {err}");
        assert!(err.contains(why), "{err}");
        assert!(err.contains(&format!("field '{}'", option[0])), "{err}");
        assert!(
            err.contains(schedule.file_name().unwrap().to_str().unwrap()),
            "{err}"
        );
        assert!(!refused.exists());
    }

    // a .csv that is no waypoint schedule gets the waypoint reader's error (not the legacy
    // reader's "give --units"), and a quoted header is a waypoint header, as `check` reads it
    let other = write(&d, "other.csv", "time_s;depth\n0;0\n");
    let o = simulate(&other, &ph, &d.join("other-out"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("other.csv:1") && err.contains("the header needs a 'time_min' column"),
        "{err}"
    );
    let quoted = write(
        &d,
        "quoted.csv",
        "\"time_min\",\"depth_m\"\n0,0\n2,20\n12,20\n16,0\n",
    );
    let o = simulate(&quoted, &ph, &d.join("quoted-out"));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

/// Ctrl-C during a long run: the run stops at its next step, writes everything simulated up to
/// then (whole files, a summary that says where it stopped) and exits with 130.
#[test]
fn an_interrupted_run_keeps_what_it_simulated() {
    let d = tempdir("interrupt");
    let out = d.join("out");
    let mut child = Command::new(bin())
        .args(["simulate", "--profile"])
        .arg(root().join("profiles/fig5-dive.toml"))
        .arg("--phantom")
        .arg(root().join("profiles/phantoms/hydrogel.toml"))
        .arg("--out")
        .arg(&out)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let killed = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    let summary: toml::Table = std::fs::read_to_string(out.join("summary.toml"))
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        summary["ending"]
            .as_str()
            .unwrap()
            .starts_with("interrupted"),
        "{summary:?}"
    );
    let end = summary["end_time_s"].as_float().unwrap();
    assert!(end > 0.0 && end < 21726.0, "stopped at {end} s");
    let csv = std::fs::read_to_string(out.join("bubbles.csv")).unwrap();
    let last_t: f64 = csv
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert!(
        (last_t - end).abs() < 1e-3,
        "the last recorded frame is the moment it stopped"
    );
}

/// A logged dive is watched at the surface after its last sample (the criteria protocol's
/// default 60 min, `profile::DIVE_LOG_WATCH_S`), and its import notes reach summary.toml and
/// the terminal. tests/data/divelogs/legacy-v1.xml ends at 24:30 min on the 6 m stop: the
/// run adds an ascent at 10 m/min (36 s) and then 3600 s at the surface, so it ends at
/// 1470 + 36 + 3600 = 5106 s.
#[test]
fn a_dive_log_run_watches_the_surface_after_the_dive() {
    let d = tempdir("simulate-divelog");
    let ph = d.join("p.toml");
    // the dive is trimix: the phantom needs helium too
    let he = "[gases.he]\ndiffusivity = 8.35e-9\nostwald = 0.0098\n";
    std::fs::write(&ph, format!("{SMALL_PHANTOM}{he}")).unwrap();
    let out = d.join("out");
    let o = Command::new(bin())
        .args(["simulate", "--profile"])
        .arg(root().join("tests/data/divelogs/legacy-v1.xml"))
        .arg("--phantom")
        .arg(&ph)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(
        stdout.contains("note: watched 60 min at the surface"),
        "{stdout}"
    );
    let summary: toml::Table = std::fs::read_to_string(out.join("summary.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let end = summary["end_time_s"].as_float().unwrap();
    if summary["ending"].as_str() == Some("completed") {
        assert!((end - 5106.0).abs() < 1e-6, "{end}");
    }
    let notes = summary["import_notes"].as_array().unwrap();
    assert!(notes
        .iter()
        .any(|n| n.as_str().unwrap().contains("an ascent to the surface")));
    assert!(notes
        .iter()
        .any(|n| n.as_str().unwrap().contains("no water density")));
}

/// [`SMALL_PHANTOM`]'s gel with one nucleus in place of its population, a frame at every
/// step (the text after its `[nuclei]` table).
const ONE_BUBBLE_EVERY_STEP: &str = r#"[nuclei]
min_radius_m = 20e-6
[numerics]
record_interval_s = 0.0
[[bubbles]]
position_m = [0.75e-3, 0.75e-3, 0.5e-3]
initial_radius_m = 60e-6
"#;

#[test]
fn traced_fluxes_are_the_ones_that_moved_the_bubbles_gas() {
    // steps.csv names, per step, the bubble whose exchange sized the next step and its flux of
    // each gas at the start and end of the step. Heun's corrector moves the trapezoid of the
    // two, (J_start + J_end)·dt/2, into the bubble (README "Time stepping"; nothing else
    // changes a lone bubble's content), so the content bubbles.csv records at every step must
    // change by exactly that: an independent check that the traced fluxes are the ones used.
    let dir = tempdir("trace-fluxes");
    let gel = &SMALL_PHANTOM[..SMALL_PHANTOM.find("[nuclei]").unwrap()];
    let phantom = write(&dir, "p.toml", &format!("{gel}{ONE_BUBBLE_EVERY_STEP}"));
    let profile = write(
        &dir,
        "d.toml",
        "name = \"saturated, decompressed\"\ntime_unit = \"s\"\npressure_unit = \"psi-gauge\"\n\
         gas = \"air\"\npoints = [[0, 60], [10, 0], [60, 0]]\n",
    );
    let out = dir.join("out");
    let o = simulate_with(&profile, &phantom, &out, &["--quiet", "--trace-steps"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let table = |name: &str| -> Vec<Vec<f64>> {
        std::fs::read_to_string(out.join(name))
            .unwrap()
            .lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect()
    };
    let steps = table("steps.csv");
    // time_s,bubble,radius_m,volume_m3,area_m2,n_n2_mol,n_o2_mol: one row per frame
    let frames = table("bubbles.csv");
    assert_eq!(
        frames.len(),
        steps.len() + 1,
        "a frame at the start and after every step"
    );
    let mut checked = 0;
    for (k, s) in steps.iter().enumerate() {
        let (dt, bubble) = (s[1], s[10]);
        let (before, after) = (&frames[k], &frames[k + 1]);
        assert!(
            (after[0] - (s[0] + dt)).abs() < 1e-5,
            "frame {k} is not the step's end"
        );
        if bubble.is_nan() {
            continue;
        }
        assert_eq!(bubble, 0.0);
        for g in 0..2 {
            let moved = 0.5 * (s[11 + g] + s[13 + g]) * dt;
            let change = after[5 + g] - before[5 + g];
            let tol = 1e-5 * moved.abs() + 2e-9 * before[5 + g];
            assert!(
                (change - moved).abs() <= tol,
                "step {k} at {} s, gas {g}: the content changed by {change:e} mol, the traced \
                 fluxes move {moved:e}",
                s[0]
            );
        }
        checked += 1;
    }
    assert!(checked > 50, "only {checked} steps had a bubble");
    // the decompression makes the bubble grow: nitrogen goes in after the ramp
    let last = steps.last().unwrap();
    assert!(last[11] > 0.0 && last[13] > 0.0, "{last:?}");
}

#[test]
fn trace_steps_writes_every_step_with_its_scheme_and_limit() {
    // `--trace-steps` writes steps.csv: one row per step, which must tile the run's time, count
    // as summary.toml counts, and label its scheme as the explicit limit says. The limit is
    // worked out here from the geometry: the box is open on every face but the bottom, so a top
    // corner cell has three open sides (weight 2 each) and three interior ones: w_max = 9 and
    // the forward-Euler limit is h²/(9D) = (100 µm)²/(9 · 2.5e-9 m²/s) = 0.4444 s.
    let dir = tempdir("trace-steps");
    let phantom = write(&dir, "p.toml", SMALL_PHANTOM);
    let profile = write(&dir, "d.toml", SHORT_DIVE);
    let out = dir.join("out");
    let o = simulate_with(&profile, &phantom, &out, &["--quiet", "--trace-steps"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: toml::Table = std::fs::read_to_string(out.join("summary.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let count = |k: &str| summary[k].as_integer().unwrap() as usize;
    let csv = std::fs::read_to_string(out.join("steps.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next().unwrap(),
        "time_s,dt_s,scheme,limit,physics_dt_s,bubble_error,next_bubble_dt_s,next_field_dt_s,\
         next_loading_dt_s,wall_s,bubble,flux_start_n2_mol_s,flux_start_o2_mol_s,\
         flux_end_n2_mol_s,flux_end_o2_mol_s,prepare_s,gel_s,events_s,corrector_s,\
         displacement_s,frame_s"
    );
    let rows: Vec<Vec<String>> = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    assert_eq!(
        rows.len(),
        count("steps_explicit") + count("steps_implicit")
    );
    let num = |s: &str| -> f64 { s.parse().unwrap() };
    // six interior sides (the open faces are implicit: `diffusion::explicit_limit`)
    let lim = (100e-6f64).powi(2) / (6.0 * 2.5e-9);
    let (mut t, mut explicit, mut cut) = (0.0, 0, 0);
    // the wall time counts up from the run's start and ends within the run's own (timing.toml)
    let timing: toml::Table = std::fs::read_to_string(out.join("timing.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let mut wall = 0.0;
    // the phases' sums over the steps (timing.toml's [phases], below), and per scheme the
    // steps and their diffusion's time ([gel_by_scheme])
    let mut sums = [0.0; 6];
    let mut by_scheme: std::collections::BTreeMap<String, (i64, f64)> = Default::default();
    for r in &rows {
        let w = num(&r[9]);
        assert!(w >= wall, "the wall time went back from {wall} to {w} s");
        // a step's phases (prepare, gel, events, of them corrector and displacement, frame) are
        // timed within the interval the observer's own clock gives the step: between the
        // last step's record and this one's (both printed to 1 µs, the phases to 0.1 µs)
        let phase: Vec<f64> = r[15..21].iter().map(|x| num(x)).collect();
        assert!(phase.iter().all(|x| *x >= 0.0), "{phase:?}");
        assert!(phase[3] + phase[4] <= phase[2] + 1e-6, "{phase:?}");
        let total = phase[0] + phase[1] + phase[2] + phase[5];
        assert!(
            total <= w - wall + 3e-6,
            "phases of {total} s in a step of {} s on the wall clock",
            w - wall
        );
        for (s, x) in sums.iter_mut().zip(&phase) {
            *s += x;
        }
        let e = by_scheme.entry(r[2].clone()).or_default();
        e.0 += 1;
        e.1 += phase[1];
        wall = w;
        let (start, dt, physics) = (num(&r[0]), num(&r[1]), num(&r[4]));
        assert!(
            (start - t).abs() < 1e-5,
            "a step starts at {start}, the last ended at {t}"
        );
        t = start + dt;
        match r[2].as_str() {
            "explicit" => {
                explicit += 1;
                assert!(dt <= lim * (1.0 + 1e-5), "explicit step of {dt} s");
            }
            "implicit" | "extrapolated" => assert!(dt > lim, "implicit step of {dt} s"),
            s => panic!("scheme {s}"),
        }
        if r[3] == "explicit-limit" {
            cut += 1;
            assert!((dt / lim - 1.0).abs() < 1e-5 && physics > dt);
        }
        assert!(num(&r[5]) >= 0.0);
    }
    assert_eq!(explicit, count("steps_explicit"));
    assert!(cut > 0, "no step was cut to the explicit limit");
    assert!(wall > 0.0);
    let run_wall = timing["wall_seconds"].as_float().unwrap();
    assert!(
        wall <= run_wall,
        "{wall} s of steps in a run of {run_wall} s"
    );
    // timing.toml's phases are the steps' sums (to the 1e-6 s it prints and the 5e-8 s of
    // each row), and within the run's wall time; the diffusion took some of it
    let phases = timing["phases"].as_table().unwrap();
    let names = [
        "prepare_s",
        "gel_s",
        "events_s",
        "corrector_s",
        "displacement_s",
        "frames_s",
    ];
    for (name, sum) in names.iter().zip(sums) {
        let x = phases[*name].as_float().unwrap();
        assert!(
            (x - sum).abs() <= 1e-6 + 1e-7 * rows.len() as f64,
            "{name}: {x} s in timing.toml, {sum} s over steps.csv"
        );
    }
    assert!(sums[1] > 0.0);
    assert!(sums[0] + sums[1] + sums[2] + sums[5] <= run_wall);
    let schemes = timing["gel_by_scheme"].as_table().unwrap();
    for name in ["explicit", "implicit", "extrapolated"] {
        let (n, t) = by_scheme.get(name).copied().unwrap_or_default();
        assert_eq!(schemes[&format!("{name}_steps")].as_integer().unwrap(), n);
        let x = schemes[&format!("{name}_s")].as_float().unwrap();
        assert!(
            (x - t).abs() <= 1e-6 + 1e-7 * rows.len() as f64,
            "{name}: {x} s in timing.toml, {t} s over steps.csv"
        );
    }
    // the scheme counts are summary.toml's (extrapolated steps count as implicit there)
    let count_of = |name: &str| schemes[&format!("{name}_steps")].as_integer().unwrap() as usize;
    assert_eq!(count_of("explicit"), count("steps_explicit"));
    assert_eq!(
        count_of("implicit") + count_of("extrapolated"),
        count("steps_implicit")
    );
    assert!((t - 2500.0).abs() < 1e-3, "the steps end at {t} s");
    // without the flag there is no steps.csv
    let plain = dir.join("plain");
    assert!(simulate(&profile, &phantom, &plain).status.success());
    assert!(!plain.join("steps.csv").exists());
}

/// A valid run in which no bubble ever exists (a nucleation model whose nuclei do not activate
/// on a shallow 20 psi dive: the reviewer's case, which ended in exit 3 on "no finite data to
/// draw") completes with exit 0 and writes every promised file, the plots saying why they are
/// empty; `evaluate` (its own per-bubble and area-rate plots) too.
#[test]
fn a_run_in_which_no_bubble_forms_writes_every_file_and_says_so() {
    let dir = tempdir("no-bubble");
    let phantom = write(
        &dir,
        "nuclei.toml",
        r#"
[geometry]
shape = "box"
size_m = [3.2e-3, 3.2e-3, 3.2e-3]
grid_step_m = 400e-6
[gases.n2]
diffusivity = 2.5e-9
ostwald = 0.014
[gases.o2]
diffusivity = 2.5e-9
ostwald = 0.027
[nucleation]
model = "critical-radius"
number_density_per_m3 = 1e10
slope_per_m = 5e6
seed = 1
"#,
    );
    let profile = write(
        &dir,
        "shallow.toml",
        "time_unit = \"s\"\npressure_unit = \"psi-gauge\"\ngas = \"air\"\npoints = [[0, 20], [10, 0], [60, 0]]\n",
    );
    let out = dir.join("run");
    let o = simulate(&profile, &phantom, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let summary = std::fs::read_to_string(out.join("summary.toml")).unwrap();
    assert!(summary.contains("final_radius_m = []"), "{summary}");
    for f in ["radius.svg", "volume.svg"] {
        let svg = std::fs::read_to_string(out.join(f)).unwrap();
        assert!(svg.starts_with("<svg"), "{f}");
        if f == "radius.svg" {
            assert!(svg.contains("No bubble in this run"), "{f}");
        }
    }
    let schedule = write(
        &dir,
        "dive.csv",
        "time_min,depth_m,gas\n0,0,air\n1,20,\n5,20,\n7,0,\n",
    );
    let ev = dir.join("ev");
    let o = Command::new(bin())
        .args(["evaluate", "--quiet", "--schedule"])
        .arg(&schedule)
        .arg("--criteria")
        .arg(root().join("algorithms/criteria/default.toml"))
        .arg("--phantom")
        .arg(&phantom)
        .arg("--out")
        .arg(&ev)
        .output()
        .unwrap();
    assert!(
        o.status.code() == Some(0) || o.status.code() == Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let radius = std::fs::read_to_string(ev.join("radius-1.svg")).unwrap();
    assert!(radius.contains("No bubble in this run"));
    assert!(!dir.join("ev.partial").exists());
}

/// Refused before the run, with exit 2, the phantom's file, line and field, and nothing
/// written: fixed gases at or above the profile's lowest ambient pressure, which hold no
/// bubble in Laplace balance (the run used to fail mid-way with exit 3 and no place named),
/// and a gas the phantom has no properties for (named at the phantom's last line, where its
/// table goes; before, no file was named).
#[test]
fn a_phantom_the_profile_cannot_run_is_refused_in_the_phantom_file() {
    let dir = tempdir("phantom-against-profile");
    let out = dir.join("run");
    let run = |profile: &Path, phantom: &Path, must_mention: &[&str]| {
        let (pr, ph, o) = (
            profile.to_str().unwrap(),
            phantom.to_str().unwrap(),
            out.to_str().unwrap(),
        );
        expect_input_error(
            &["simulate", "--profile", pr, "--phantom", ph, "--out", o],
            must_mention,
            &out,
        );
    };
    let fixed = write(
        &dir,
        "fixed.toml",
        &SMALL_PHANTOM.replace("[material]\n", "[material]\nbubble_fixed_gases_pa = 1e5\n"),
    );
    let altitude = write(
        &dir,
        "altitude.toml",
        "time_unit = \"s\"\npressure_unit = \"pa\"\ngas = \"air\"\npoints = [[0, 101325], [10, 20000], [60, 20000]]\n",
    );
    run(
        &altitude,
        &fixed,
        &[
            "fixed.toml:8:",
            "material.bubble_fixed_gases_pa",
            "20000 Pa at t = 10 s",
        ],
    );
    let no_he = write(&dir, "no-he.toml", SMALL_PHANTOM);
    let trimix = write(
        &dir,
        "trimix.toml",
        "time_unit = \"s\"\npressure_unit = \"psi-gauge\"\ngas = \"18/45\"\npoints = [[0, 0], [10, 20], [60, 20]]\n",
    );
    run(
        &trimix,
        &no_he,
        &["no-he.toml:", "field 'gases.he'", "add [gases.he]"],
    );
}
