//! Decompression algorithms: DecoTengu oracle, loader, plan command, schedule I/O, errors.

use crate::common::{bin, root, tempdir};
use decophantom::algorithm::buhlmann::{FirstCompartment, Variant, ZhL16Gf};
use decophantom::algorithm::conventions::DECOTENGU;
use decophantom::algorithm::{load_algorithm, DecoAlgorithm, DecoGas, DivePlan, Schedule};
use decophantom::gas::GasMix;
use std::process::Command;

/// One row of tests/oracles/decotengu_reference.csv (written by decotengu_tables.py with
/// DecoTengu 0.14.1).
struct RefDive {
    dive: String,
    variant: Variant,
    gf_low: f64,
    gf_high: f64,
    depth_m: f64,
    time_min: f64,
    gas: GasMix,
    deco: Vec<DecoGas>,
    last_stop_m: f64,
    runtime_min: f64,
    stops: Vec<(f64, f64)>,
}

fn reference_dives() -> Vec<RefDive> {
    let path = root().join("tests/oracles/decotengu_reference.csv");
    let mut rdr = csv::Reader::from_path(&path).unwrap();
    let mut out = Vec::new();
    for rec in rdr.records() {
        let r = rec.unwrap();
        let f = |i: usize| r[i].parse::<f64>().unwrap();
        let deco = r[7]
            .split_whitespace()
            .map(|s| DecoGas::parse(s, &DECOTENGU).unwrap())
            .collect();
        let stops = r[10]
            .split_whitespace()
            .map(|s| {
                let (d, t) = s.split_once(':').unwrap();
                (d.parse().unwrap(), t.parse().unwrap())
            })
            .collect();
        out.push(RefDive {
            dive: r[0].to_string(),
            variant: if &r[1] == "zh-l16b" {
                Variant::B
            } else {
                Variant::C
            },
            gf_low: f(2),
            gf_high: f(3),
            depth_m: f(4),
            time_min: f(5),
            gas: GasMix::parse(&r[6]).unwrap(),
            deco,
            last_stop_m: f(8),
            runtime_min: f(9),
            stops,
        });
    }
    out
}

#[test]
fn matches_decotengu_stop_for_stop_and_minute_for_minute() {
    let dives = reference_dives();
    assert!(dives.len() >= 8);
    let mut failures = Vec::new();
    for d in &dives {
        let mut conv = DECOTENGU.clone();
        conv.last_stop_m = d.last_stop_m;
        let alg = ZhL16Gf::new(
            "t",
            d.variant,
            d.variant.default_first_compartment(),
            d.gf_low / 100.0,
            d.gf_high / 100.0,
            conv,
        );
        let plan = DivePlan {
            depth_m: d.depth_m,
            bottom_time_min: d.time_min,
            bottom_gas: d.gas,
            deco_gases: d.deco.clone(),
            travel_gases: vec![],
        };
        let s = alg.plan(&plan).unwrap();
        let got: Vec<(f64, f64)> = s.stops.iter().map(|st| (st.depth_m, st.stop_min)).collect();
        if got != d.stops || (s.runtime_min() - d.runtime_min).abs() > 1e-6 {
            failures.push(format!(
                "dive {}: ours {:?} runtime {:.4}; DecoTengu {:?} runtime {}",
                d.dive,
                got,
                s.runtime_min(),
                d.stops,
                d.runtime_min
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn decotengu_docstring_example_through_the_shipped_file() {
    // DecoTengu 0.14.1 package docstring (decotengu/__init__.py): 35 m for 40 min on air,
    // ZH-L16B GF 30/85 → 18:1 15:1 12:4 9:6 6:10 3:22, total 44 min, last step at 87.5 min;
    // ZH-L16C GF 30/85 → total 52 min, first stop 18 m 1 min, last 3 m 26 min.
    let plan = DivePlan {
        depth_m: 35.0,
        bottom_time_min: 40.0,
        bottom_gas: GasMix::AIR,
        deco_gases: vec![],
        travel_gases: vec![],
    };
    let b = load_algorithm(&root().join("algorithms/zhl16b-gf30-85.toml")).unwrap();
    let s = b.algorithm.plan(&plan).unwrap();
    let got: Vec<(f64, f64)> = s.stops.iter().map(|st| (st.depth_m, st.stop_min)).collect();
    assert_eq!(
        got,
        vec![
            (18.0, 1.0),
            (15.0, 1.0),
            (12.0, 4.0),
            (9.0, 6.0),
            (6.0, 10.0),
            (3.0, 22.0)
        ]
    );
    assert!((s.runtime_min() - 87.5).abs() < 1e-9);
    let c = load_algorithm(&root().join("algorithms/zhl16c-gf30-85.toml")).unwrap();
    let s = c.algorithm.plan(&plan).unwrap();
    assert_eq!(s.stops.iter().map(|st| st.stop_min).sum::<f64>(), 52.0);
    assert_eq!((s.stops[0].depth_m, s.stops[0].stop_min), (18.0, 1.0));
    assert_eq!(s.stops.last().unwrap().stop_min, 26.0);
}

#[test]
fn every_shipped_zhl16_file_loads_and_plans() {
    let dir = root().join("algorithms");
    let plan = DivePlan {
        depth_m: 45.0,
        bottom_time_min: 25.0,
        bottom_gas: GasMix::AIR,
        deco_gases: vec![],
        travel_gases: vec![],
    };
    let mut n = 0;
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().and_then(|x| x.to_str()) != Some("toml") {
            continue; // e.g. the criteria/ folder
        }
        let text = std::fs::read_to_string(&p).unwrap();
        if !text.contains("kind = \"zhl16\"") {
            continue;
        }
        let a = load_algorithm(&p).unwrap_or_else(|e| panic!("{e}"));
        let s = a.algorithm.plan(&plan).unwrap();
        assert!(!s.stops.is_empty(), "{}", p.display());
        n += 1;
    }
    assert!(n >= 9, "{n} ZH-L16 files");
    // More conservative gradient factors never shorten the dive (same model, same dive).
    let rt = |f: &str| {
        load_algorithm(&root().join("algorithms").join(f))
            .unwrap()
            .algorithm
            .plan(&plan)
            .unwrap()
            .runtime_min()
    };
    assert!(rt("zhl16c-gf30-70.toml") >= rt("zhl16c-gf30-85.toml"));
    assert!(rt("zhl16c-gf30-85.toml") >= rt("zhl16c-gf100-100.toml"));
    assert!(rt("zhl16c-gf30-85.toml") >= rt("zhl16b-gf30-85.toml"));
}

#[test]
fn schedule_toml_round_trips_and_feeds_the_phantom() {
    let alg = ZhL16Gf::new(
        "ZH-L16C GF 30/70",
        Variant::C,
        FirstCompartment::One,
        0.3,
        0.7,
        DECOTENGU.clone(),
    );
    let plan = DivePlan {
        depth_m: 60.0,
        bottom_time_min: 20.0,
        bottom_gas: GasMix::parse("18/45").unwrap(),
        deco_gases: vec![
            DecoGas::parse("50", &DECOTENGU).unwrap(),
            DecoGas::parse("100@6", &DECOTENGU).unwrap(),
        ],
        travel_gases: vec![],
    };
    let s = alg.plan(&plan).unwrap();
    let dir = tempdir("schedule-roundtrip");
    let path = dir.join("s.toml");
    std::fs::write(&path, s.to_toml_string(None)).unwrap();
    let back = Schedule::read(&path).unwrap();
    assert_eq!(back, s);
    let h = back.to_pressure_history().unwrap();
    assert!((h.duration_s() / 60.0 - s.runtime_min()).abs() < 1e-9);
    // The deepest point is 60 m in DecoTengu's 0.09985 bar/m.
    let pmax = h.ambient_pa.iter().cloned().fold(0.0, f64::max);
    assert!((pmax - (101_325.0 + 60.0 * 9_985.0)).abs() < 1e-6);
    // Gas switches appear at the switch depths (EAN50's MOD 22 m → first used at 21 m stop).
    let sw = s.gas_switches();
    assert_eq!(sw.len(), 2, "{sw:?}");
    assert_eq!(sw[1].depth_m, 6.0);
}

fn plan_cmd(args: &[&str]) -> std::process::Output {
    Command::new(bin())
        .current_dir(root())
        .arg("plan")
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn plan_command_prints_table_and_writes_a_readable_schedule() {
    let dir = tempdir("plan-cmd");
    let out = dir.join("s.toml");
    let o = plan_cmd(&[
        "--algorithm",
        "algorithms/zhl16b-gf30-85.toml",
        "--depth",
        "35",
        "--time",
        "40",
        "--format",
        "csv",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8(o.stdout).unwrap();
    // DecoTengu docstring stops (see above) and total 87.5 min.
    assert!(
        text.starts_with("depth_m,stop_min,runtime_min,gas\n18,1,"),
        "{text}"
    );
    assert!(text.contains("\n3,22,"), "{text}");
    assert!(text.trim_end().ends_with("0,0,87.50,air"), "{text}");
    // --out without --format: the format follows the extension (.toml: the schedule TOML)
    let o = plan_cmd(&[
        "--algorithm",
        "algorithms/zhl16b-gf30-85.toml",
        "--depth",
        "35",
        "--time",
        "40",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let s = Schedule::read(&out).unwrap();
    assert_eq!(s.stops.len(), 6);
    let md = plan_cmd(&[
        "--algorithm",
        "algorithms/zhl16c-gf30-85.toml",
        "--depth",
        "45",
        "--time",
        "25",
        "--deco-gas",
        "50@21",
        "--deco-gas",
        "100@6",
    ]);
    assert!(md.status.success());
    let md = String::from_utf8(md.stdout).unwrap();
    assert!(
        md.contains("| depth_m | stop_min | runtime_min | gas |"),
        "{md}"
    );
    assert!(md.contains("Total dive time:") && md.contains("CNS:") && md.contains("OTU:"));
    assert!(md.contains("Gas switch to EAN50 at 21 m"), "{md}");
}

#[test]
fn bad_plans_exit_with_code_2_and_a_clear_message() {
    let dir = tempdir("plan-bad");
    let bad_gf = dir.join("gf.toml");
    std::fs::write(
        &bad_gf,
        "kind = \"zhl16\"\n[conventions]\npreset = \"decotengu\"\n[params]\nmodel = \"zh-l16c\"\ngf_low = 90\ngf_high = 80\n",
    )
    .unwrap();
    let bad_kind = dir.join("kind.toml");
    std::fs::write(&bad_kind, "kind = \"bogus\"\n").unwrap();
    let bad_rate = dir.join("rate.toml");
    std::fs::write(
        &bad_rate,
        "kind = \"zhl16\"\n[conventions]\npreset = \"decotengu\"\nascent_rate_m_min = -9.0\n[params]\nmodel = \"zh-l16c\"\ngf_low = 30\ngf_high = 80\n",
    )
    .unwrap();
    let alg = "algorithms/zhl16c-gf30-85.toml";
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec!["--algorithm", alg, "--depth", "0", "--time", "20"],
            "depth",
        ),
        (
            vec!["--algorithm", alg, "--depth", "-5", "--time", "20"],
            "depth",
        ),
        (
            vec![
                "--algorithm",
                alg,
                "--depth",
                "60",
                "--time",
                "20",
                "--gas",
                "10/70",
            ],
            "hypoxic",
        ),
        (
            vec![
                "--algorithm",
                alg,
                "--depth",
                "45",
                "--time",
                "20",
                "--deco-gas",
                "50@30",
            ],
            "beyond its MOD",
        ),
        (
            vec![
                "--algorithm",
                alg,
                "--depth",
                "45",
                "--time",
                "20",
                "--gas",
                "32",
            ],
            "beyond its MOD",
        ),
        (
            vec![
                "--algorithm",
                bad_kind.to_str().unwrap(),
                "--depth",
                "30",
                "--time",
                "20",
            ],
            "unknown algorithm kind",
        ),
        (
            vec![
                "--algorithm",
                bad_gf.to_str().unwrap(),
                "--depth",
                "30",
                "--time",
                "20",
            ],
            "GF-low",
        ),
        (
            vec![
                "--algorithm",
                bad_rate.to_str().unwrap(),
                "--depth",
                "30",
                "--time",
                "20",
            ],
            "ascent_rate_m_min",
        ),
    ];
    for (args, needle) in cases {
        let o = plan_cmd(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(needle), "{args:?}: {err}");
    }
}

#[test]
fn schedule_that_never_surfaces_is_an_error() {
    let dir = tempdir("never-surfaces");
    let p = dir.join("s.toml");
    std::fs::write(
        &p,
        "label = \"x\"\nsurface_pressure_pa = 101325.0\npa_per_m = 10000.0\nwater_vapour_pa = 6270.0\n\n\
         [[legs]]\nkind = \"descent\"\nstart_depth_m = 0.0\nend_depth_m = 30.0\nduration_s = 90.0\ngas = \"air\"\n",
    )
    .unwrap();
    let e = Schedule::read(&p).unwrap_err();
    assert!(e.message.contains("never surfaces"), "{e}");
    std::fs::write(
        &p,
        "label = \"x\"\nsurface_pressure_pa = 101325.0\npa_per_m = 10000.0\nwater_vapour_pa = 6270.0\nextra = 1\n",
    )
    .unwrap();
    let e = Schedule::read(&p).unwrap_err();
    assert_eq!(e.line, Some(5), "{e}");
}

/// Legacy two-column dive files (minutes, metres of sea water, the paper's format) read as
/// schedules: the legs follow the file's points. tests/data/legacy/dive-40m-two-stops.txt:
/// 0→40 m in 2 min, 20 min at 40 m, up to 9 m by 25 min, stops at 9 m and 6 m, surfacing at
/// 33 min, on the surface until 60 min.
#[test]
fn legacy_two_column_dive_file_reads_as_a_schedule() {
    let path = root().join("tests/data/legacy/dive-40m-two-stops.txt");
    let s =
        decophantom::algorithm::waypoints::read_schedule(&path, &DECOTENGU, GasMix::AIR).unwrap();
    assert!((s.runtime_min() - 60.0).abs() < 1e-9, "{}", s.runtime_min());
    let max_depth = s.legs.iter().map(|l| l.end_depth_m).fold(0.0, f64::max);
    assert!((max_depth - 40.0).abs() < 1e-9);
    let h = s.to_pressure_history().unwrap();
    // at 14 min the diver is still at 40 m: ambient = surface + 40 m × DecoTengu's 9 985 Pa/m
    let p = h.ambient(14.0 * 60.0);
    assert!(
        (p - (DECOTENGU.surface_pressure_pa + 40.0 * DECOTENGU.pa_per_m)).abs() < 1e-6,
        "{p}"
    );
    // at 30 min on the 6 m stop (27.3–32.3 min)
    let p = h.ambient(30.0 * 60.0);
    assert!(
        (p - (DECOTENGU.surface_pressure_pa + 6.0 * DECOTENGU.pa_per_m)).abs() < 1e-6,
        "{p}"
    );
    assert!((h.ambient(33.0 * 60.0) - DECOTENGU.surface_pressure_pa).abs() < 1e-6);
    // a garbled file names its line
    let d = tempdir("legacy-schedule");
    let bad = d.join("bad.txt");
    std::fs::write(&bad, "0 0\n2 x\n").unwrap();
    let e = decophantom::algorithm::waypoints::read_schedule(&bad, &DECOTENGU, GasMix::AIR)
        .unwrap_err();
    assert_eq!(e.line, Some(2), "{e}");
}

/// `plan --format csv --out s.csv` writes the waypoint CSV that `check` reads
/// (`time_min,depth_m,gas` below a `# conventions:` line), and reading it back gives the planned
/// schedule leg for leg; a `--format`
/// that contradicts the extension, or an `--out` naming the algorithm file, is refused with
/// exit 2 and nothing written.
#[test]
fn plan_out_follows_format_and_round_trips_through_the_csv_check_reads() {
    let dir = tempdir("plan-out-csv");
    let (csv, toml) = (dir.join("s.csv"), dir.join("s.toml"));
    let dive = [
        "--algorithm",
        "algorithms/zhl16c-gf30-85.toml",
        "--depth",
        "45",
        "--time",
        "25",
        "--deco-gas",
        "50@21",
        "--deco-gas",
        "100@6",
    ];
    let o = plan_cmd(
        &[
            &dive[..],
            &["--format", "csv", "--out", csv.to_str().unwrap()],
        ]
        .concat(),
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = plan_cmd(&[&dive[..], &["--out", toml.to_str().unwrap()]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    // the schedule's conventions above the header (DecoTengu's here: 101 325 Pa, 9 985 Pa/m,
    // 6 270 Pa), then the waypoints
    assert!(
        text.starts_with(
            "# conventions: surface_pressure_pa = 101325, pa_per_m = 9985, water_vapour_pa = 6270 "
        ),
        "{text}"
    );
    assert!(text.contains("\ntime_min,depth_m,gas\n0,0,air\n"), "{text}");
    let planned = Schedule::read(&toml).unwrap();
    let back =
        decophantom::algorithm::waypoints::read_schedule(&csv, &DECOTENGU, GasMix::AIR).unwrap();
    let legs: Vec<_> = planned.legs.iter().filter(|l| l.duration_s > 0.0).collect();
    assert_eq!(back.legs.len(), legs.len());
    for (a, b) in back.legs.iter().zip(&legs) {
        assert!(
            (a.start_depth_m - b.start_depth_m).abs() < 1e-9,
            "{a:?} {b:?}"
        );
        assert!((a.end_depth_m - b.end_depth_m).abs() < 1e-9, "{a:?} {b:?}");
        assert!((a.duration_s - b.duration_s).abs() < 1e-6, "{a:?} {b:?}");
        assert_eq!(a.gas, b.gas);
    }
    assert!((back.runtime_min() - planned.runtime_min()).abs() < 1e-9);
    assert_eq!(back.gas_switches().len(), planned.gas_switches().len());

    // --format toml with a .csv name: refused, nothing written
    let bad = dir.join("t.csv");
    let o = plan_cmd(
        &[
            &dive[..],
            &["--format", "toml", "--out", bad.to_str().unwrap()],
        ]
        .concat(),
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--out"));
    assert!(!bad.exists());
    // --out naming the algorithm file: refused, the file unchanged
    let alg = dir.join("alg.toml");
    std::fs::copy(root().join("algorithms/zhl16c-gf30-85.toml"), &alg).unwrap();
    let before = std::fs::read(&alg).unwrap();
    let o = plan_cmd(&[
        "--algorithm",
        alg.to_str().unwrap(),
        "--depth",
        "30",
        "--time",
        "20",
        "--out",
        alg.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read(&alg).unwrap(), before);
}

/// Every shipped algorithm file's plans read back through the schedule TOML reader (whose
/// stop table is checked against the legs, and whose legs' kinds and rates are checked) and
/// through the waypoint CSV reader (whose segments' rates are checked) unchanged: the checks
/// of what a file may say refuse nothing a planner writes. Dives: no-stop, air deco, nitrox,
/// trimix with two deco gases, and a hypoxic trimix with a travel gas.
#[test]
fn every_shipped_algorithms_plans_pass_the_schedule_readers_checks() {
    use decophantom::algorithm::plan_dive;
    use decophantom::algorithm::waypoints::parse_waypoints_csv;
    // (depth m, bottom time min, bottom gas, deco gases, travel gases)
    type Dive<'a> = (f64, f64, &'a str, &'a [&'a str], &'a [&'a str]);
    let dives: [Dive; 6] = [
        (18.0, 20.0, "air", &[], &[]),
        (30.0, 25.0, "air", &[], &[]),
        (40.0, 35.0, "32", &["50"], &[]),
        (45.0, 25.0, "18/45", &["50@21", "100@6"], &[]),
        (60.0, 20.0, "18/45", &["50", "100@6"], &[]),
        (100.0, 15.0, "10/70", &["50", "100@6"], &["21/35@0..60"]),
    ];
    let mut files: Vec<_> = std::fs::read_dir(root().join("algorithms"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "{files:?}");
    let mut stops = 0;
    for f in &files {
        let alg = load_algorithm(f).unwrap();
        for (depth, time, gas, deco, travel) in dives {
            let deco: Vec<String> = deco.iter().map(|s| s.to_string()).collect();
            let travel: Vec<String> = travel.iter().map(|s| s.to_string()).collect();
            let Ok((_, s)) = plan_dive(&alg, depth, time, Some(gas), &deco, &travel) else {
                continue; // a dive the algorithm refuses (e.g. past its gases' limits)
            };
            stops += s.stops.len();
            let at = format!("{} {depth} m {time} min {gas}", f.display());
            let back = Schedule::from_toml_str(&s.to_toml_string(None), f.as_path())
                .unwrap_or_else(|e| panic!("{at}: {e}"));
            assert_eq!(back, s, "{at}");
            let csv = decophantom::app::plan::waypoints_csv(&s);
            // read in DecoTengu's conventions, the CSV keeps the algorithm's own (its
            // `# conventions:` line): the reference is the planned schedule itself
            let back = parse_waypoints_csv(
                &csv,
                std::path::Path::new("w.csv"),
                &decophantom::algorithm::conventions::DECOTENGU,
                GasMix::AIR,
            )
            .unwrap_or_else(|e| panic!("{at}: {e}"));
            assert_eq!(
                (
                    back.surface_pressure_pa,
                    back.pa_per_m,
                    back.water_vapour_pa
                ),
                (s.surface_pressure_pa, s.pa_per_m, s.water_vapour_pa),
                "{at}"
            );
            assert!((back.runtime_min() - s.runtime_min()).abs() < 1e-9, "{at}");
        }
    }
    assert!(
        stops > 100,
        "{stops} stops: the dives should need decompression"
    );
}
