//! `decophantom sensitivity` and `merge`: sharding, resuming, one-at-a-time against direct
//! simulations, and bad input. Small grids (3.2 mm cube at h = 400 µm, one bubble, a 60 s
//! decompression from 60 psi gauge) so a run takes milliseconds.

use crate::common::{bin, tempdir};
use std::path::{Path, PathBuf};
use std::process::Command;

const PHANTOM: &str = r#"
[geometry]
shape = "box"
size_m = [3.2e-3, 3.2e-3, 3.2e-3]
grid_step_m = 400e-6

[material]
surface_tension = 0.07

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
min_radius_m = 20e-6

[[bubbles]]
position_m = [1.6e-3, 1.6e-3, 1.6e-3]
initial_radius_m = 60e-6
"#;

const PROFILE: &str = r#"
name = "decompression"
time_unit = "s"
pressure_unit = "psi-gauge"
gas = "air"
points = [[0, 60], [10, 0], [60, 0]]
"#;

fn lab(name: &str) -> (PathBuf, PathBuf, PathBuf) {
    let d = tempdir(name);
    std::fs::write(d.join("phantom.toml"), PHANTOM).unwrap();
    std::fs::write(d.join("profile.toml"), PROFILE).unwrap();
    (d.join("phantom.toml"), d.join("profile.toml"), d)
}

fn sensitivity(ph: &Path, pr: &Path, extra: &[&str]) -> std::process::Output {
    let mut c = Command::new(bin());
    c.arg("sensitivity")
        .arg("--phantom")
        .arg(ph)
        .arg("--profile")
        .arg(pr)
        .args(extra);
    c.output().unwrap()
}

fn ok(o: &std::process::Output) -> String {
    assert!(
        o.status.success(),
        "exit {:?}: {}",
        o.status.code(),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

const SOBOL: [&str; 14] = [
    "--param",
    "gases.n2.ostwald=0.01..0.03",
    "--param",
    "gases.n2.diffusivity=1e-10..5e-9",
    "--metric",
    "r_max",
    "--metric",
    "plateau",
    "--method",
    "sobol",
    "--samples",
    "16",
    "--seed",
    "3",
];

#[test]
fn sweep_sharded_three_ways_and_merged_gives_byte_identical_indices() {
    let (ph, pr, d) = lab("sweep-shards");
    let whole = d.join("whole");
    let t = std::time::Instant::now();
    let mut a: Vec<&str> = SOBOL.to_vec();
    let w = whole.to_str().unwrap();
    a.extend(["--out", w]);
    ok(&sensitivity(&ph, &pr, &a));
    eprintln!(
        "sobol, 16 × (2 + 2) = 64 runs: {:.2} s",
        t.elapsed().as_secs_f64()
    );
    let mut shards = Vec::new();
    for i in 0..3 {
        let s = d.join(format!("shard{i}"));
        let spec = format!("{i}/3");
        let mut a: Vec<&str> = SOBOL.to_vec();
        a.extend(["--shard", &spec, "--out", s.to_str().unwrap()]);
        ok(&sensitivity(&ph, &pr, &a));
        // a shard has its runs but no indices
        assert!(!s.join("indices.csv").exists());
        shards.push(s);
    }
    let merged = d.join("merged");
    let o = Command::new(bin())
        .arg("merge")
        .args(&shards)
        .arg("--out")
        .arg(&merged)
        .output()
        .unwrap();
    ok(&o);
    for f in ["indices.csv", "sensitivity.csv", "courses.csv"] {
        let (x, y) = (
            std::fs::read(whole.join(f)).unwrap(),
            std::fs::read(merged.join(f)).unwrap(),
        );
        assert!(x == y, "{f} differs between the whole and the merged study");
    }
    let idx = std::fs::read_to_string(whole.join("indices.csv")).unwrap();
    assert_eq!(idx.lines().count(), 1 + 2 * 2);
    assert!(idx
        .starts_with("metric,parameter,s1,s1_lo95,s1_hi95,st,st_lo95,st_hi95,n_used,n_dropped\n"));
    // 64 runs, each row index once
    let rows = std::fs::read_to_string(whole.join("sensitivity.csv")).unwrap();
    assert_eq!(rows.lines().count(), 1 + 64);
    // merging only two of the three shards is refused, naming the missing runs
    let o = Command::new(bin())
        .arg("merge")
        .args(&shards[..2])
        .arg("--out")
        .arg(d.join("bad"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing runs"));
}

/// The journal a study killed after its first `runs` runs would leave at `partial`, from the
/// folder `done` of the same study run whole: the header (the design and the inputs' hashes
/// from design.toml, the shard), those runs' rows and half a line cut by the kill.
fn killed_journal(done: &Path, partial: &Path, runs: usize) {
    let t: toml::Table = std::fs::read_to_string(done.join("design.toml"))
        .unwrap()
        .parse()
        .unwrap();
    let get = |k: &str| t.get(k).and_then(|v| v.as_str()).unwrap().to_string();
    let header = format!(
        "# {} phantom_hash={} profile_hash={} decophantom={} shard={}",
        get("design"),
        get("phantom_hash"),
        get("profile_hash"),
        get("decophantom"),
        get("shard")
    );
    let rows = std::fs::read_to_string(done.join("sensitivity.csv")).unwrap();
    let kept: Vec<&str> = rows.lines().take(1 + runs).collect();
    std::fs::create_dir_all(partial).unwrap();
    std::fs::write(
        partial.join("sensitivity.csv"),
        format!("{header}\n{}\n{runs},0.0", kept.join("\n")),
    )
    .unwrap();
}

#[test]
fn sweep_resumes_from_its_journal_and_refuses_another_studys() {
    let (ph, pr, d) = lab("sweep-resume");
    let args = [
        "--param",
        "gases.n2.ostwald=0.01..0.03",
        "--metric",
        "r_max",
        "--method",
        "oat",
        "--samples",
        "6",
    ];
    let first = d.join("first");
    let mut a = args.to_vec();
    a.extend(["--out", first.to_str().unwrap()]);
    ok(&sensitivity(&ph, &pr, &a));
    // a journal as a killed run leaves it: the first 4 runs and half a line
    let second = d.join("second");
    let j = d.join("second.partial");
    killed_journal(&first, &j, 4);
    let mut a = args.to_vec();
    a.extend(["--out", second.to_str().unwrap()]);
    let out = ok(&sensitivity(&ph, &pr, &a));
    assert!(out.contains("7 runs (4 resumed"), "{out}");
    assert_eq!(
        std::fs::read(first.join("sensitivity.csv")).unwrap(),
        std::fs::read(second.join("sensitivity.csv")).unwrap()
    );
    assert_eq!(
        std::fs::read(first.join("indices.csv")).unwrap(),
        std::fs::read(second.join("indices.csv")).unwrap()
    );
    assert!(
        !j.exists(),
        "the journal is removed once the output is written"
    );
    // a journal of another design (other seed → other header) is refused, not mixed in
    std::fs::create_dir_all(&j).unwrap();
    std::fs::write(j.join("sensitivity.csv"), "# method=oat samples=3\nindex\n").unwrap();
    let o = sensitivity(&ph, &pr, &a);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("journal of a different study"));
}

#[test]
fn sweep_oat_matches_direct_simulations_and_the_solubility_direction() {
    use decophantom::fit::data::build_params;
    use decophantom::fit::model::run_one;
    let (ph, pr, d) = lab("sweep-oat");
    let out = d.join("oat");
    ok(&sensitivity(
        &ph,
        &pr,
        &[
            "--param",
            "gases.n2.ostwald=0.01..0.03",
            "--metric",
            "r_max",
            "--metric",
            "final_radius:0",
            "--method",
            "oat",
            "--samples",
            "3",
            "--out",
            out.to_str().unwrap(),
        ],
    ));
    let rows: Vec<Vec<f64>> = std::fs::read_to_string(out.join("sensitivity.csv"))
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 4);
    // each row against a simulation run here, its peak radius read from the frames
    let profile = decophantom::run::load_profile_or_schedule(
        &pr,
        &decophantom::profile::LoadOptions::default(),
    )
    .unwrap();
    let doc: toml::Table = PHANTOM.parse().unwrap();
    for r in &rows {
        let mut t = doc.clone();
        t["gases"]["n2"]
            .as_table_mut()
            .unwrap()
            .insert("ostwald".into(), toml::Value::Float(r[1]));
        let run = run_one(&build_params(&t, &ph).unwrap(), &profile).unwrap();
        let peak = run
            .frames
            .iter()
            .flat_map(|f| f.bubbles.iter().map(|b| b.radius))
            .fold(0.0, f64::max);
        let last = run.frames.last().unwrap().bubbles[0].radius;
        assert_eq!((r[2], r[3]), (peak, last), "run {}", r[0]);
    }
    // levels 0.01, 0.02, 0.03: more dissolved N2 (Henry's law, c = L·p/(R_u T)) → larger
    // bubbles (the paper's Fig. 3: R_max increases with L_N2)
    for (r, v) in rows[1..].iter().zip([0.01, 0.02, 0.03]) {
        assert!((r[1] - v).abs() < 1e-15, "{} vs {v}", r[1]);
    }
    assert!(rows[1][2] < rows[2][2] && rows[2][2] < rows[3][2]);
    // the normalised sensitivity in indices.csv, recomputed here from the rows
    let want = (rows[3][2] - rows[1][2]) / (0.03 - 0.01) * 0.014 / rows[0][2];
    let idx = std::fs::read_to_string(out.join("indices.csv")).unwrap();
    let line = idx.lines().nth(1).unwrap();
    let got: f64 = line.rsplit(',').next().unwrap().parse().unwrap();
    assert!((got - want).abs() < 1e-12 * want.abs(), "{got} vs {want}");
    let md = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(md.contains("courses-0.svg") && md.contains("bars-0.svg"));
}

#[test]
fn sweep_morris_on_the_phantom_ranks_solubility_with_a_positive_effect() {
    let (ph, pr, d) = lab("sweep-morris");
    let out = d.join("morris");
    ok(&sensitivity(
        &ph,
        &pr,
        &[
            "--param",
            "gases.n2.ostwald=0.01..0.03",
            "--param",
            "material.surface_tension=0.03..0.1",
            "--metric",
            "r_max",
            "--method",
            "morris",
            "--samples",
            "4",
            "--out",
            out.to_str().unwrap(),
        ],
    ));
    let idx = std::fs::read_to_string(out.join("indices.csv")).unwrap();
    let ost: Vec<f64> = idx
        .lines()
        .find(|l| l.contains("ostwald"))
        .unwrap()
        .split(',')
        .skip(2)
        .map(|x| x.parse().unwrap())
        .collect();
    // every elementary effect of L_N2 on R_max is positive, so μ* = μ > 0
    assert!(ost[1] > 0.0 && (ost[0] - ost[1]).abs() < 1e-15 * ost[0].abs().max(1.0));
}

/// A profile that ends at the moment the pressure reaches the surface: no growth phase, so
/// `plateau` (a fit of the growth after the last pressure change) is undefined in every run.
const PROFILE_ENDS_AT_SURFACE: &str = r#"
name = "decompression, no time at the surface"
time_unit = "s"
pressure_unit = "psi-gauge"
gas = "air"
points = [[0, 60], [10, 0]]
"#;

#[test]
fn sweep_a_metric_undefined_in_every_run_keeps_the_other_metrics_results() {
    // `--metric plateau` where no plateau exists: before, the study wrote nothing and exited 3
    // ("no finite data to draw"); now it exits 0, r_max has its indices from every run, plateau
    // is NaN with n_used 0, and the report says so instead of drawing it
    let (ph, _, d) = lab("sweep-all-nan");
    let pr = d.join("profile-ends.toml");
    std::fs::write(&pr, PROFILE_ENDS_AT_SURFACE).unwrap();
    let t = std::time::Instant::now();
    for (method, samples, per_param) in [("sobol", "16", 16), ("morris", "3", 3)] {
        let out = d.join(method);
        ok(&sensitivity(
            &ph,
            &pr,
            &[
                "--param",
                "gases.n2.ostwald=0.01..0.03",
                "--param",
                "gases.n2.diffusivity=1e-10..5e-9",
                "--metric",
                "r_max",
                "--metric",
                "plateau",
                "--method",
                method,
                "--samples",
                samples,
                "--seed",
                "3",
                "--quiet",
                "--out",
                out.to_str().unwrap(),
            ],
        ));
        let idx = std::fs::read_to_string(out.join("indices.csv")).unwrap();
        assert_eq!(idx.lines().count(), 1 + 2 * 2, "{idx}");
        assert!(idx.lines().next().unwrap().ends_with(",n_used,n_dropped"));
        for l in idx.lines().skip(1) {
            let v: Vec<&str> = l.split(',').collect();
            let nums: Vec<f64> = v[2..].iter().map(|x| x.parse().unwrap()).collect();
            let (used, dropped) = (nums[nums.len() - 2], nums[nums.len() - 1]);
            if v[0] == "r_max" {
                assert!(nums.iter().all(|x| x.is_finite()), "{method}: {l}");
                assert_eq!((used, dropped), (per_param as f64, 0.0), "{method}: {l}");
            } else {
                assert_eq!(v[0], "plateau");
                assert!(nums[..nums.len() - 2].iter().all(|x| x.is_nan()), "{l}");
                assert_eq!((used, dropped), (0.0, per_param as f64), "{method}: {l}");
            }
        }
        let md = std::fs::read_to_string(out.join("report.md")).unwrap();
        assert!(
            md.contains("**plateau** is undefined in every run"),
            "{method}: {md}"
        );
        assert!(md.contains("No chart: no index of plateau is defined"));
        assert!(out.join("bars-0.svg").exists() && !out.join("bars-1.svg").exists());
        assert!(out.join("report.html").exists() && out.join("sensitivity.csv").exists());
    }
    eprintln!(
        "sobol 64 runs + morris 9 runs: {:.2} s",
        t.elapsed().as_secs_f64()
    );
}

#[test]
fn sweep_refuses_bad_input_with_exit_2_naming_the_field() {
    let (ph, pr, d) = lab("sweep-bad");
    let out = d.join("o");
    let o = out.to_str().unwrap();
    let cases: [(&[&str], &str); 8] = [
        // the same metric twice (before: its column and indices twice)
        (
            &[
                "--param",
                "gases.n2.ostwald=0.01..0.03",
                "--metric",
                "r_max",
                "--metric",
                "r_max",
            ],
            "--metric",
        ),
        // Sobol' below its floor of 16 base rows (before: N = 2 printed S1 = 1.27 [1.27, 2.06])
        (
            &[
                "--param",
                "gases.n2.ostwald=0.01..0.03",
                "--param",
                "gases.n2.diffusivity=1e-10..5e-9",
                "--metric",
                "r_max",
                "--method",
                "sobol",
                "--samples",
                "15",
            ],
            "--samples",
        ),
        (
            &[
                "--param",
                "gases.n2.ostwald=0.03..0.01",
                "--metric",
                "r_max",
            ],
            "--param",
        ),
        (
            &["--param", "gases.n2.ostwald", "--metric", "r_max"],
            "--param",
        ),
        (
            &["--param", "geometry.size_m.7=1..2", "--metric", "r_max"],
            "--param",
        ),
        (
            &[
                "--param",
                "gases.n2.ostwald=0.01..0.03",
                "--metric",
                "radius",
            ],
            "--metric",
        ),
        (
            &[
                "--param",
                "gases.n2.ostwald=0.01..0.03",
                "--metric",
                "r_max:3",
            ],
            "--metric",
        ),
        (
            &[
                "--param",
                "gases.n2.ostwald=0.01..0.03",
                "--metric",
                "r_max",
                "--shard",
                "3/3",
            ],
            "--shard",
        ),
    ];
    for (args, field) in cases {
        let mut a = args.to_vec();
        a.extend(["--out", o]);
        let r = sensitivity(&ph, &pr, &a);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(field), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!out.exists());
    }
}

fn merge(dirs: &[PathBuf], out: &Path) -> std::process::Output {
    Command::new(bin())
        .arg("merge")
        .args(dirs)
        .arg("--out")
        .arg(out)
        .output()
        .unwrap()
}

/// Every file under `d` with its bytes (a folder's whole state, to show it was not touched).
fn snapshot(d: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![d.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push((p.clone(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

#[test]
fn sweep_oat_and_morris_shards_run_and_merge_to_the_whole_studys_indices() {
    // before: a shard of oat or morris panicked (its summary computed indices from the whole
    // design's positions with only the shard's rows). A shard writes its rows and no indices,
    // exits 0, and the merge of all shards equals the unsharded study byte for byte.
    let (ph, pr, d) = lab("sweep-shards-oat-morris");
    // oat: 1 + 1 × 3 = 4 runs; morris: 2 trajectories × (2 + 1) = 6 runs
    let oat: &[&str] = &[
        "--param",
        "gases.n2.ostwald=0.01..0.03",
        "--metric",
        "r_max",
        "--method",
        "oat",
        "--samples",
        "3",
    ];
    let morris: &[&str] = &[
        "--param",
        "gases.n2.ostwald=0.01..0.03",
        "--param",
        "material.surface_tension=0.03..0.1",
        "--metric",
        "r_max",
        "--method",
        "morris",
        "--samples",
        "2",
        "--seed",
        "5",
    ];
    let t = std::time::Instant::now();
    for (method, args, runs) in [("oat", oat, 4usize), ("morris", morris, 6)] {
        let whole = d.join(format!("{method}-whole"));
        let mut a = args.to_vec();
        a.extend(["--out", whole.to_str().unwrap()]);
        let whole_out = ok(&sensitivity(&ph, &pr, &a));
        let mut shards = Vec::new();
        let mut shard_rows = 0;
        for i in 0..3 {
            let s = d.join(format!("{method}-shard{i}"));
            let spec = format!("{i}/3");
            let mut a = args.to_vec();
            a.extend(["--shard", &spec, "--out", s.to_str().unwrap()]);
            let out = ok(&sensitivity(&ph, &pr, &a));
            assert!(out.contains("no indices from a shard"), "{method}: {out}");
            assert!(!s.join("indices.csv").exists() && !s.join("report.md").exists());
            // shard i holds runs ⌊i·n/3⌋ … ⌊(i+1)·n/3⌋ − 1
            let rows = std::fs::read_to_string(s.join("sensitivity.csv")).unwrap();
            let idx: Vec<usize> = rows
                .lines()
                .skip(1)
                .map(|l| l.split(',').next().unwrap().parse().unwrap())
                .collect();
            let want: Vec<usize> = (i * runs / 3..(i + 1) * runs / 3).collect();
            assert_eq!(idx, want, "{method} shard {i}");
            shard_rows += idx.len();
            shards.push(s);
        }
        assert_eq!(shard_rows, runs);
        let merged = d.join(format!("{method}-merged"));
        let merged_out = ok(&merge(&shards, &merged));
        for f in ["indices.csv", "sensitivity.csv", "courses.csv"] {
            assert!(
                std::fs::read(whole.join(f)).unwrap() == std::fs::read(merged.join(f)).unwrap(),
                "{method}: {f} differs between the whole and the merged study"
            );
        }
        // the printed indices too, the counts as whole numbers: morris has one elementary
        // effect per trajectory and parameter, 2 here, none dropped
        let indices = |s: &str| -> Vec<String> {
            s.lines()
                .filter(|l| l.starts_with("r_max / "))
                .map(String::from)
                .collect()
        };
        // one line per parameter (one metric)
        let k = args.iter().filter(|a| **a == "--param").count();
        assert_eq!(indices(&whole_out).len(), k, "{whole_out}");
        assert_eq!(indices(&whole_out), indices(&merged_out));
        if method == "morris" {
            assert_eq!(
                merged_out.matches("n_used 2, n_dropped 0").count(),
                2,
                "{merged_out}"
            );
        }
    }
    eprintln!(
        "oat 4 + morris 6 runs, each twice: {:.2} s",
        t.elapsed().as_secs_f64()
    );
}

#[test]
fn sweep_refuses_more_shards_than_runs_and_a_design_over_the_run_limit() {
    let (ph, pr, d) = lab("sweep-limits");
    let out = d.join("o");
    let o = out.to_str().unwrap();
    // oat with one parameter and 2 levels: 1 + 1 × 2 = 3 runs, so 4 shards are too many (one
    // would be empty); 10⁹ samples: 10⁹ + 1 runs, sobol 5·10⁵ × (2 + 2) = 2·10⁶, both over
    // the 10⁶-run limit; refused at once, before any run, nothing written
    let base = [
        "--param",
        "gases.n2.ostwald=0.01..0.03",
        "--metric",
        "r_max",
    ];
    let cases: [(&[&str], &str); 4] = [
        (&["--samples", "2", "--shard", "0/4"], "--shard"),
        (&["--samples", "2", "--shard", "0/1000000"], "--shard"),
        (&["--samples", "1000000000"], "--samples"),
        (
            &[
                "--param",
                "gases.n2.diffusivity=1e-10..5e-9",
                "--method",
                "sobol",
                "--samples",
                "500000",
            ],
            "--samples",
        ),
    ];
    for (extra, field) in cases {
        let mut a = base.to_vec();
        a.extend(extra);
        a.extend(["--out", o]);
        let t = std::time::Instant::now();
        let r = sensitivity(&ph, &pr, &a);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{extra:?}: {err}");
        assert!(
            err.contains(&format!("field '{field}'")),
            "{extra:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
        assert!(
            t.elapsed().as_secs_f64() < 5.0,
            "{extra:?}: not refused at once"
        );
        assert!(!out.exists() && !d.join("o.partial").exists());
    }
    // as many shards as runs: every shard has one run
    for i in 0..3 {
        let s = d.join(format!("s{i}"));
        let spec = format!("{i}/3");
        let mut a = base.to_vec();
        a.extend([
            "--samples",
            "2",
            "--shard",
            &spec,
            "--out",
            s.to_str().unwrap(),
        ]);
        ok(&sensitivity(&ph, &pr, &a));
        let rows = std::fs::read_to_string(s.join("sensitivity.csv")).unwrap();
        assert_eq!(rows.lines().count(), 2, "{rows}");
    }
}

#[test]
fn sweep_merge_refuses_an_output_that_is_holds_or_lies_in_an_input() {
    // before: `merge ss0 ss1 --out ss0` exited 0 and replaced the input ss0 with the merge
    let (ph, pr, d) = lab("sweep-merge-out");
    let base = [
        "--param",
        "gases.n2.ostwald=0.01..0.03",
        "--metric",
        "r_max",
        "--samples",
        "2",
    ];
    let par = d.join("par");
    let shards = [par.join("ss0"), d.join("ss1")];
    for (i, s) in shards.iter().enumerate() {
        let spec = format!("{i}/2");
        let mut a = base.to_vec();
        a.extend(["--shard", &spec, "--out", s.to_str().unwrap()]);
        ok(&sensitivity(&ph, &pr, &a));
    }
    let before: Vec<_> = shards.iter().map(|s| snapshot(s)).collect();
    let outs = [
        shards[0].clone(),                        // an input
        par.join("../par/ss0"),                   // the same, spelled otherwise
        par.clone(),                              // holds an input
        shards[1].join("merged"),                 // inside an input
        shards[0].join("x").join("..").join("m"), // inside an input, through `..`
    ];
    for out in &outs {
        let r = merge(&shards, out);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(2), "{}: {err}", out.display());
        assert!(err.contains("field '--out'"), "{err}");
        let after: Vec<_> = shards.iter().map(|s| snapshot(s)).collect();
        assert!(before == after, "{}: an input was changed", out.display());
        assert!(!shards[1].join("merged").exists() && !shards[0].join("m").exists());
    }
    // a folder beside them is fine
    ok(&merge(&shards, &d.join("merged")));
    assert!(d.join("merged/indices.csv").exists());
}

/// A copy of the lab's phantom or profile with one text replaced, at `name` in `d`.
fn variant(d: &Path, name: &str, text: &str, from: &str, to: &str) -> PathBuf {
    assert!(text.contains(from), "{from}");
    let p = d.join(name);
    std::fs::write(&p, text.replace(from, to)).unwrap();
    p
}

#[test]
fn sweep_refuses_a_journal_of_other_inputs_naming_its_folder_and_what_differs() {
    // before: a journal made with another profile or phantom was resumed (exit 0, "N resumed
    // from the journal"), mixing the two studies' runs; its header held only the design
    let (ph, pr, d) = lab("sweep-journal-inputs");
    let pr20 = variant(&d, "profile20.toml", PROFILE, "[0, 60]", "[0, 20]");
    let ph_st = variant(
        &d,
        "phantom-st.toml",
        PHANTOM,
        "surface_tension = 0.07",
        "surface_tension = 0.05",
    );
    // the same phantom in another layout: comments, number spelling
    let ph_same = variant(
        &d,
        "phantom-respelled.toml",
        &format!("# the same phantom, respelled\n{PHANTOM}"),
        "grid_step_m = 400e-6",
        "grid_step_m = 0.0004 # 400 µm",
    );
    let args = [
        "--param",
        "gases.n2.ostwald=0.01..0.03",
        "--metric",
        "r_max",
        "--samples",
        "3",
    ];
    let first = d.join("first");
    let mut a = args.to_vec();
    a.extend(["--out", first.to_str().unwrap()]);
    ok(&sensitivity(&ph, &pr, &a));
    let out = d.join("again");
    let j = d.join("again.partial");
    let mut a = args.to_vec();
    a.extend(["--out", out.to_str().unwrap()]);
    for (phantom, profile, differs, same) in [
        (&ph, &pr20, "the profile (--profile", "the phantom"),
        (&ph_st, &pr, "the phantom (--phantom", "the profile"),
    ] {
        killed_journal(&first, &j, 2);
        let before = snapshot(&j);
        let o = sensitivity(phantom, profile, &a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(err.contains("field '--out'"), "{err}");
        assert!(
            err.contains(&format!(
                "'{}' holds the journal of a different study",
                j.display()
            )),
            "{err}"
        );
        assert!(err.contains(differs) && !err.contains(same), "{err}");
        assert!(!err.contains("the design"), "{err}");
        assert!(before == snapshot(&j), "the journal was changed");
        assert!(!out.exists());
        std::fs::remove_dir_all(&j).unwrap();
    }
    // identical inputs, the phantom only respelled: resumed, and the same outputs
    killed_journal(&first, &j, 2);
    let s = ok(&sensitivity(&ph_same, &pr, &a));
    assert!(s.contains("4 runs (2 resumed"), "{s}");
    for f in ["sensitivity.csv", "indices.csv"] {
        assert_eq!(
            std::fs::read(first.join(f)).unwrap(),
            std::fs::read(out.join(f)).unwrap(),
            "{f}"
        );
    }
    assert!(!j.exists());
}

#[test]
fn sweep_merge_refuses_shards_of_other_inputs_naming_the_folder_and_what_differs() {
    // before: shards run on another profile or phantom merged with exit 0 into wrong indices
    let (ph, pr, d) = lab("sweep-merge-inputs");
    let pr20 = variant(&d, "profile20.toml", PROFILE, "[0, 60]", "[0, 20]");
    let ph_st = variant(
        &d,
        "phantom-st.toml",
        PHANTOM,
        "surface_tension = 0.07",
        "surface_tension = 0.05",
    );
    let base = [
        "--param",
        "gases.n2.ostwald=0.01..0.03",
        "--metric",
        "r_max",
        "--samples",
        "3",
    ];
    let shard = |name: &str, phantom: &Path, profile: &Path, i: usize, extra: &[&str]| {
        let s = d.join(name);
        let spec = format!("{i}/2");
        let mut a = base.to_vec();
        a.extend(extra);
        a.extend(["--shard", &spec, "--out", s.to_str().unwrap()]);
        ok(&sensitivity(phantom, profile, &a));
        s
    };
    let sh0 = shard("sh0", &ph, &pr, 0, &[]);
    let sh1 = shard("sh1", &ph, &pr, 1, &[]);
    let sh1_profile = shard("sh1-profile", &ph, &pr20, 1, &[]);
    let sh1_phantom = shard("sh1-phantom", &ph_st, &pr, 1, &[]);
    let sh1_seed = shard(
        "sh1-seed",
        &ph,
        &pr,
        1,
        &["--method", "morris", "--seed", "2"],
    );
    for (other, differs) in [
        (&sh1_profile, "it differs in the profile (--profile"),
        (&sh1_phantom, "it differs in the phantom (--phantom"),
    ] {
        let o = merge(&[sh0.clone(), other.clone()], &d.join("m"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{err}");
        assert!(
            err.contains(&format!(
                "'{}' is not a shard of the same study as the first folder '{}'",
                other.display(),
                sh0.display()
            )),
            "{err}"
        );
        assert!(err.contains(differs), "{err}");
        assert!(!d.join("m").exists());
    }
    // another design: each folder's design is named with its folder
    let o = merge(&[sh0.clone(), sh1_seed.clone()], &d.join("m"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains(&format!("in '{}': method=morris", sh1_seed.display()))
            && err.contains(&format!("in '{}': method=oat", sh0.display())),
        "{err}"
    );
    // a shard folder that does not record its inputs (an older decophantom's) is refused
    let old = d.join("sh1-old");
    std::fs::create_dir_all(&old).unwrap();
    for f in ["sensitivity.csv", "courses.csv"] {
        std::fs::copy(sh1.join(f), old.join(f)).unwrap();
    }
    let t = std::fs::read_to_string(sh1.join("design.toml")).unwrap();
    let t: String = t
        .lines()
        .filter(|l| !l.starts_with("phantom_hash") && !l.starts_with("profile_hash"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(old.join("design.toml"), t).unwrap();
    let o = merge(&[sh0.clone(), old.clone()], &d.join("m"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("no record of the phantom and profile"),
        "{err}"
    );
    // the shards of one study still merge
    ok(&merge(&[sh0, sh1], &d.join("m")));
    assert!(d.join("m/indices.csv").exists());
}
