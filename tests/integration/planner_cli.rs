//! The planner's command line (issue 9 §3): settings that override the algorithm file, the
//! no-decompression limit, travel gas for hypoxic bottom mixes, oxygen warnings.

use crate::common::{bin, root};
use std::process::Command;

fn plan(args: &[&str]) -> (i32, String, String) {
    let o = Command::new(bin())
        .current_dir(root())
        .arg("plan")
        .args(args)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

fn plan_json(args: &[&str]) -> serde_json::Value {
    let mut a = args.to_vec();
    a.push("--json");
    let (code, out, err) = plan(&a);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

fn stops(v: &serde_json::Value) -> Vec<(f64, f64)> {
    v["schedule"]["stops"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            (
                s["depth_m"].as_f64().unwrap(),
                s["stop_min"].as_f64().unwrap(),
            )
        })
        .collect()
}

/// `--gf` and `--last-stop` on the command line, applied to one ZH-L16C file, reproduce
/// DecoTengu 0.14.1's schedules for other gradient factors and a 6 m last stop
/// (tests/oracles/decotengu_reference.csv, written by decotengu_tables.py: every ZH-L16C row).
#[test]
fn command_line_gradient_factors_and_last_stop_match_decotengu() {
    let path = root().join("tests/oracles/decotengu_reference.csv");
    let mut rdr = csv::Reader::from_path(&path).unwrap();
    let mut checked = 0;
    let mut six = 0;
    for rec in rdr.records() {
        let r = rec.unwrap();
        if &r[1] != "zh-l16c" {
            continue;
        }
        let gf = format!("{}/{}", &r[2], &r[3]);
        let mut args = vec![
            "--algorithm",
            "algorithms/zhl16c-gf30-85.toml",
            "--gf",
            &gf,
            "--depth",
            &r[4],
            "--time",
            &r[5],
            "--gas",
            &r[6],
            "--last-stop",
            &r[8],
        ];
        let decos: Vec<String> = r[7].split_whitespace().map(|s| s.to_string()).collect();
        for d in &decos {
            args.push("--deco-gas");
            args.push(d);
        }
        let v = plan_json(&args);
        let want: Vec<(f64, f64)> = r[10]
            .split_whitespace()
            .map(|s| {
                let (d, t) = s.split_once(':').unwrap();
                (d.parse().unwrap(), t.parse().unwrap())
            })
            .collect();
        assert_eq!(stops(&v), want, "DecoTengu dive {}", &r[0]);
        let runtime: f64 = r[9].parse().unwrap();
        let got = v["schedule"]["runtime_min"].as_f64().unwrap();
        assert!(
            (got - runtime).abs() < 0.05,
            "dive {}: {got} vs {runtime}",
            &r[0]
        );
        // the label follows the command line, not the file's "GF 30/85"
        assert!(
            v["schedule"]["label"]
                .as_str()
                .unwrap()
                .contains(&format!("GF {gf}")),
            "{}",
            v["schedule"]["label"]
        );
        checked += 1;
        if &r[8] == "6" {
            six += 1;
        }
    }
    assert!(
        checked >= 8 && six >= 1,
        "{checked} dives, {six} with a 6 m stop"
    );
}

/// `--altitude` gives the ICAO standard atmosphere's pressure (ISO 2533:1975 table, geometric
/// altitude: 1000 m → 898.76 hPa, 2000 m → 795.01 hPa, 3000 m → 701.21 hPa, 5000 m → 540.48 hPa), equals `--surface-pressure` with that value, and lengthens
/// the decompression; `--ascent-rate`, `--descent-rate` reach the schedule's legs; the settings
/// are echoed.
#[test]
fn altitude_surface_pressure_and_rates_reach_the_plan_and_are_echoed() {
    use decophantom::algorithm::config::isa_pressure_pa;
    for (z, p) in [
        (1000.0, 89_876.0),
        (2000.0, 79_501.0),
        (3000.0, 70_121.0),
        (5000.0, 54_048.0),
    ] {
        assert!((isa_pressure_pa(z) - p).abs() < 1.0, "{z} m");
    }
    assert_eq!(isa_pressure_pa(0.0), 101_325.0);
    let base = [
        "--algorithm",
        "algorithms/zhl16c-gf30-85.toml",
        "--depth",
        "40",
        "--time",
        "25",
    ];
    let with = |extra: &[&str]| {
        let mut a = base.to_vec();
        a.extend_from_slice(extra);
        plan_json(&a)
    };
    let sea = with(&[]);
    let alt = with(&["--altitude", "1500"]);
    let hpa = format!("{}", isa_pressure_pa(1500.0) / 100.0);
    let same = with(&["--surface-pressure", &hpa]);
    assert_eq!(stops(&alt), stops(&same));
    assert_eq!(
        alt["schedule"]["surface_pressure_pa"].as_f64().unwrap(),
        isa_pressure_pa(1500.0)
    );
    let stop_time = |v: &serde_json::Value| v["schedule"]["stop_time_min"].as_f64().unwrap();
    assert!(
        stop_time(&alt) > stop_time(&sea),
        "altitude needs more deco"
    );
    // rates: the descent leg lasts depth / rate; the ascent from the bottom to the first
    // stop at the given rate
    let slow = with(&["--descent-rate", "10", "--ascent-rate", "5"]);
    let legs = slow["schedule"]["legs"].as_array().unwrap();
    assert_eq!(legs[0]["kind"], "descent");
    assert!((legs[0]["duration_s"].as_f64().unwrap() - 40.0 / 10.0 * 60.0).abs() < 1e-9);
    let asc = legs.iter().find(|l| l["kind"] == "ascent").unwrap();
    let dz = asc["start_depth_m"].as_f64().unwrap() - asc["end_depth_m"].as_f64().unwrap();
    assert!((asc["duration_s"].as_f64().unwrap() - dz / 5.0 * 60.0).abs() < 1e-6);
    // echoed settings
    let (code, md, _) = plan(&[
        "--algorithm",
        "algorithms/zhl16c-gf30-85.toml",
        "--depth",
        "40",
        "--time",
        "25",
        "--altitude",
        "1500",
        "--ascent-rate",
        "9",
    ]);
    assert_eq!(code, 0);
    assert!(
        md.contains("surface pressure: 845.60 hPa (altitude 1500 m"),
        "{md}"
    );
    assert!(md.contains("ascent rate: 9 m/min (command line)"), "{md}");
    assert!(md.contains("descent rate: 20 m/min\n"), "{md}");
}

/// The no-decompression limit is the longest whole-minute bottom time needing no stop.
/// Checked against an independent computation in this test: Schreiner's equation for the 16
/// ZH-L16C nitrogen compartments (half-times and a, b from Bühlmann, Tauchmedizin 2002, as
/// tabulated in DecoTengu's model.py ZH_L16C_GF), DecoTengu's conventions (1.01325 bar,
/// 0.09985 bar/m, 0.0627 bar water vapour, 20 m/min down including the bottom time,
/// 10 m/min up), and Baker's GF form of the tolerated ambient pressure at GF-high
/// (p_amb = (p_t − a·gf) / (gf/b − gf + 1)), surfacing directly.
#[test]
fn no_decompression_limit_matches_an_independent_schreiner_computation() {
    const HT: [f64; 16] = [
        5.0, 8.0, 12.5, 18.5, 27.0, 38.3, 54.3, 77.0, 109.0, 146.0, 187.0, 239.0, 305.0, 390.0,
        498.0, 635.0,
    ];
    const A: [f64; 16] = [
        1.1696, 1.0, 0.8618, 0.7562, 0.62, 0.5043, 0.441, 0.4, 0.375, 0.35, 0.3295, 0.3065, 0.2835,
        0.261, 0.248, 0.2327,
    ];
    const B: [f64; 16] = [
        0.5578, 0.6514, 0.7222, 0.7825, 0.8126, 0.8434, 0.8693, 0.891, 0.9092, 0.9222, 0.9319,
        0.9403, 0.9477, 0.9544, 0.9602, 0.9653,
    ];
    let (ps, bpm, wv, fn2) = (1.01325, 0.09985, 0.0627, 0.7902);
    // Schreiner: p(t) = pi0 + R(t − 1/k) − (pi0 − p0 − R/k)·e^{−kt}
    let schreiner = |p0: f64, amb0: f64, rate_bar_min: f64, t: f64, k: f64| {
        let pi0 = fn2 * (amb0 - wv);
        let r = fn2 * rate_bar_min;
        pi0 + r * (t - 1.0 / k) - (pi0 - p0 - r / k) * (-k * t).exp()
    };
    let no_stop = |depth: f64, bottom_incl_descent: f64, gf: f64| {
        let pb = ps + depth * bpm;
        let t_down = depth / 20.0;
        let t_up = depth / 10.0;
        (0..16).all(|i| {
            let k = std::f64::consts::LN_2 / HT[i];
            let p = fn2 * (ps - wv);
            let p = schreiner(p, ps, 20.0 * bpm, t_down, k);
            let p = schreiner(p, pb, 0.0, bottom_incl_descent - t_down, k);
            let p = schreiner(p, pb, -10.0 * bpm, t_up, k);
            (p - A[i] * gf) / (gf / B[i] - gf + 1.0) <= ps
        })
    };
    for (depth, gf) in [(18.0, 0.85), (24.0, 0.85), (30.0, 0.70), (40.0, 1.0)] {
        let want = (1..600)
            .map(|t| t as f64)
            .take_while(|&t| no_stop(depth, t, gf))
            .last()
            .unwrap();
        let gfs = format!("30/{}", (gf * 100.0) as i32);
        let ds = depth.to_string();
        let v = plan_json(&[
            "--algorithm",
            "algorithms/zhl16c-gf30-85.toml",
            "--gf",
            &gfs,
            "--depth",
            &ds,
            "--time",
            "3",
        ]);
        assert!(v["ndl_searched"].as_bool().unwrap());
        let got = v["ndl_min"].as_f64().unwrap();
        assert_eq!(got, want, "{depth} m at GF-high {gf}");
        // and by definition: at the limit no stop, a minute longer a stop
        let at = plan_json(&[
            "--algorithm",
            "algorithms/zhl16c-gf30-85.toml",
            "--gf",
            &gfs,
            "--depth",
            &ds,
            "--time",
            &got.to_string(),
        ]);
        assert!(stops(&at).is_empty());
        let over = plan_json(&[
            "--algorithm",
            "algorithms/zhl16c-gf30-85.toml",
            "--gf",
            &gfs,
            "--depth",
            &ds,
            "--time",
            &(got + 1.0).to_string(),
        ]);
        assert!(!stops(&over).is_empty());
        assert!(over["ndl_min"].is_null() && !over["ndl_searched"].as_bool().unwrap());
    }
    // the Markdown says so instead of "Total stop time: -0 min"
    let (_, md, _) = plan(&[
        "--algorithm",
        "algorithms/vpmb-2-baker.toml",
        "--depth",
        "18",
        "--time",
        "20",
    ]);
    assert!(
        md.contains("No-decompression limit at 18 m on air:"),
        "{md}"
    );
    assert!(!md.contains("Total stop time"), "{md}");
    assert!(!md.contains("-0"), "{md}");
}

/// A hypoxic bottom mix below ~96 m needs a travel gas: refused without one (naming
/// `--travel-gas`), planned with one by both algorithms, and no leg of the plan ever breathes
/// a gas below 0.15 bar ppO2 or above 1.6 bar at any depth of the leg (checked from the legs).
#[test]
fn travel_gas_plans_a_hypoxic_110_m_dive_that_is_never_hypoxic_or_hyperoxic() {
    let base = [
        "--depth",
        "110",
        "--time",
        "20",
        "--gas",
        "10/70",
        "--deco-gas",
        "50",
        "--deco-gas",
        "100",
    ];
    for alg in [
        "algorithms/zhl16c-gf30-85.toml",
        "algorithms/vpmb-2-baker.toml",
    ] {
        let mut a = vec!["--algorithm", alg];
        a.extend_from_slice(&base);
        let (code, _, err) = plan(&a);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains("hypoxic") && err.contains("--travel-gas"),
            "{err}"
        );
        a.extend_from_slice(&["--travel-gas", "21/35@0..60"]);
        let v = plan_json(&a);
        let sp = v["schedule"]["surface_pressure_pa"].as_f64().unwrap();
        let ppm = v["schedule"]["pa_per_m"].as_f64().unwrap();
        let legs = v["schedule"]["legs"].as_array().unwrap();
        // down on 21/35 to 60 m, then 10/70
        assert_eq!(legs[0]["gas"], "21/35");
        assert_eq!(legs[0]["end_depth_m"].as_f64(), Some(60.0));
        assert_eq!(legs[1]["gas"], "10/70");
        let o2 = |g: &str| match g {
            "air" => 0.21,
            "O2" => 1.0,
            "EAN50" => 0.5,
            g => g.split('/').next().unwrap().parse::<f64>().unwrap() / 100.0,
        };
        for l in legs {
            let f = o2(l["gas"].as_str().unwrap());
            for key in ["start_depth_m", "end_depth_m"] {
                let d = l[key].as_f64().unwrap();
                let ppo2 = f * (sp + d * ppm) / 1e5;
                assert!(
                    (0.15 - 1e-9..=1.6 + 0.02).contains(&ppo2),
                    "{alg}: {} at {d} m has ppO2 {ppo2}",
                    l["gas"]
                );
            }
        }
        // back on the travel gas on the way up before the bottom mix turns hypoxic
        assert!(legs
            .iter()
            .skip(2)
            .any(|l| l["gas"] == "21/35" && l["start_depth_m"].as_f64().unwrap() <= 60.0));
    }
    // a travel gas beyond its MOD (21/35 at 1.6 bar: 66 m) is refused
    let mut a = vec!["--algorithm", "algorithms/zhl16c-gf30-85.toml"];
    a.extend_from_slice(&base);
    a.extend_from_slice(&["--travel-gas", "21/35@0..70"]);
    let (code, _, err) = plan(&a);
    assert_eq!(code, 2);
    assert!(err.contains("--travel-gas") && err.contains("MOD"), "{err}");
}

/// CNS above 100 % and OTU above 300 are warned, in the table, on stderr and in the JSON;
/// VPM-B files refuse `--gf`; contradictory settings name the option.
#[test]
fn oxygen_warnings_and_refused_settings() {
    let args = [
        "--algorithm",
        "algorithms/zhl16c-gf30-85.toml",
        "--depth",
        "40",
        "--time",
        "60",
        "--gas",
        "32",
        "--deco-gas",
        "100@6",
    ];
    let (code, md, err) = plan(&args);
    assert_eq!(code, 0, "{err}");
    assert!(md.contains("Warning: CNS oxygen clock"), "{md}");
    assert!(err.contains("warning: CNS oxygen clock"), "{err}");
    let v = plan_json(&args);
    let cns = v["cns_percent"].as_f64().unwrap();
    assert!(cns > 100.0);
    assert_eq!(v["warnings"].as_array().unwrap().len(), 1);
    for (extra, field) in [
        (
            vec![
                "--algorithm",
                "algorithms/vpmb-2-baker.toml",
                "--gf",
                "30/80",
            ],
            "--gf",
        ),
        (
            vec![
                "--algorithm",
                "algorithms/zhl16c-gf30-85.toml",
                "--gf",
                "90/80",
            ],
            "--gf-low",
        ),
        (
            vec![
                "--algorithm",
                "algorithms/zhl16c-gf30-85.toml",
                "--gf",
                "30-80",
            ],
            "--gf",
        ),
        (
            vec![
                "--algorithm",
                "algorithms/zhl16c-gf30-85.toml",
                "--altitude",
                "9000",
            ],
            "--altitude",
        ),
        (
            vec![
                "--algorithm",
                "algorithms/zhl16c-gf30-85.toml",
                "--ascent-rate",
                "0",
            ],
            "--ascent-rate",
        ),
        (
            vec![
                "--algorithm",
                "algorithms/zhl16c-gf30-85.toml",
                "--surface-pressure",
                "2000",
            ],
            "--surface-pressure",
        ),
    ] {
        let mut a = extra.clone();
        a.extend_from_slice(&["--depth", "30", "--time", "20"]);
        let (code, out, err) = plan(&a);
        assert_eq!(code, 2, "{extra:?}: {err}");
        assert!(out.is_empty());
        assert!(err.contains(field), "{extra:?}: {err}");
    }
}

/// `plan --plot` writes the dive-profile figure (well-formed SVG with both panels). The
/// ZH-L16C loading it draws is consistent with the plans: a GF 30/85 plan and a VPM-B plan
/// never go shallower than the GF-100 % ceiling (the M-value line), every compartment
/// on-gasses on the descent, and the slowest compartment is still below ambient at the first
/// stop while the fastest is above it.
#[test]
fn dive_profile_plot_and_the_tissue_loading_it_draws() {
    use decophantom::algorithm::load_algorithm;
    use decophantom::algorithm::loading::loading;
    let dir = crate::common::tempdir("plan-plot");
    for file in [
        "algorithms/zhl16c-gf30-85.toml",
        "algorithms/vpmb-2-baker.toml",
    ] {
        let svg_path = dir.join("p.svg");
        let svg_s = svg_path.to_str().unwrap();
        let (code, _, err) = plan(&[
            "--algorithm",
            file,
            "--depth",
            "60",
            "--time",
            "20",
            "--gas",
            "18/45",
            "--deco-gas",
            "50",
            "--deco-gas",
            "100",
            "--plot",
            svg_s,
        ]);
        assert_eq!(code, 0, "{err}");
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        let doc = roxmltree::Document::parse(&svg).expect("well-formed SVG");
        let texts: String = doc
            .descendants()
            .filter(|n| n.is_text())
            .map(|n| n.text().unwrap())
            .collect();
        assert!(texts.contains("depth, m") && texts.contains("ZH-L16C compartment"));
        let rects = doc
            .descendants()
            .filter(|n| n.tag_name().name() == "rect")
            .count();
        assert!(rects > 16 * 50, "heat map cells: {rects}");

        let alg = load_algorithm(&root().join(file)).unwrap();
        let (_, sched) = decophantom::algorithm::plan_dive(
            &alg,
            60.0,
            20.0,
            Some("18/45"),
            &["50".to_string(), "100".to_string()],
            &[],
        )
        .unwrap();
        let l = loading(&sched, &alg.conventions, 1.0, 0.25);
        for x in &l {
            assert!(
                x.depth_m >= x.ceiling_m - 1e-6,
                "{file}: at {:.2} min depth {:.2} m above the ceiling {:.2} m",
                x.time_min,
                x.depth_m,
                x.ceiling_m
            );
        }
        let descent_end = sched.legs[0].duration_s / 60.0;
        for x in l
            .iter()
            .filter(|x| x.time_min > 0.1 && x.time_min <= descent_end)
        {
            assert!(x.gradient.iter().all(|&g| g < 0.0), "{file} descent {x:?}");
        }
        let first_stop = sched.stops[0].runtime_min;
        let at = l
            .iter()
            .min_by(|a, b| {
                (a.time_min - first_stop)
                    .abs()
                    .total_cmp(&(b.time_min - first_stop).abs())
            })
            .unwrap();
        assert!(
            at.gradient[0] > 0.0 && at.gradient[15] < 0.0,
            "{file}: {at:?}"
        );
    }
}

/// Travel-gas dives against DecoTengu 0.14.1 (tests/oracles/decotengu_travel_reference.csv,
/// written by `decotengu_tables.py travel`: 110 m on 10/70 with 21/35 from the surface to
/// 60 m at GF 30/85 and 50/80, two travel gases 21/35@0..40 + 15/55@40..70, and ZH-L16B on
/// 12/65 at 100 m). Every stop, every minute and the runtime match (DecoTengu given each
/// travel gas also as a deco gas at the deep end of its range, where ours offers it again).
#[test]
fn travel_gas_dives_match_decotengu() {
    let path = root().join("tests/oracles/decotengu_travel_reference.csv");
    let mut rdr = csv::Reader::from_path(&path).unwrap();
    let mut n = 0;
    for rec in rdr.records() {
        let r = rec.unwrap();
        let file = if &r[1] == "zh-l16b" {
            "algorithms/zhl16b-gf30-85.toml"
        } else {
            "algorithms/zhl16c-gf30-85.toml"
        };
        let gf = format!("{}/{}", &r[2], &r[3]);
        let mut args = vec![
            "--algorithm",
            file,
            "--gf",
            &gf,
            "--depth",
            &r[4],
            "--time",
            &r[5],
            "--gas",
            &r[6],
        ];
        let travel: Vec<String> = r[7].split_whitespace().map(str::to_string).collect();
        let deco: Vec<String> = r[8].split_whitespace().map(str::to_string).collect();
        for t in &travel {
            args.push("--travel-gas");
            args.push(t);
        }
        for d in &deco {
            args.push("--deco-gas");
            args.push(d);
        }
        let v = plan_json(&args);
        let want: Vec<(f64, f64)> = r[10]
            .split_whitespace()
            .map(|s| {
                let (d, t) = s.split_once(':').unwrap();
                (d.parse().unwrap(), t.parse().unwrap())
            })
            .collect();
        assert_eq!(stops(&v), want, "dive {}", &r[0]);
        let runtime = v["schedule"]["legs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|l| l["duration_s"].as_f64().unwrap())
            .sum::<f64>()
            / 60.0;
        let want_rt: f64 = r[9].parse().unwrap();
        assert!(
            (runtime - want_rt).abs() < 1e-6,
            "dive {}: {runtime}",
            &r[0]
        );
        n += 1;
    }
    assert_eq!(n, 4);
}

/// The tissue loading of a travel-gas descent, against an independent computation in this
/// test: Schreiner's equation for N2 and He over each linear leg of the planned schedule
/// (21/35 from 0 to 60 m, 10/70 from 60 to 110 m, the bottom), ZH-L16C half-times and a, b
/// for both gases (Bühlmann, Tauchmedizin 2002, compartment 1b), DecoTengu's conventions.
/// Checked: each compartment's fraction of its M-value gradient at the switch depth and at
/// the end of the bottom (the `plan --plot` loading), the GF-100 % ceiling there, and that
/// the planner's first stop is where the independent GF-low ceiling puts it (the ceiling
/// after the ascent to the first stop is not below it; 3 m higher it would be).
#[test]
fn travel_gas_descent_loading_matches_an_independent_schreiner_computation() {
    use decophantom::algorithm::load_algorithm;
    use decophantom::algorithm::loading::loading;
    const HT_N2: [f64; 16] = [
        5.0, 8.0, 12.5, 18.5, 27.0, 38.3, 54.3, 77.0, 109.0, 146.0, 187.0, 239.0, 305.0, 390.0,
        498.0, 635.0,
    ];
    const A_N2: [f64; 16] = [
        1.1696, 1.0, 0.8618, 0.7562, 0.62, 0.5043, 0.441, 0.4, 0.375, 0.35, 0.3295, 0.3065, 0.2835,
        0.261, 0.248, 0.2327,
    ];
    const B_N2: [f64; 16] = [
        0.5578, 0.6514, 0.7222, 0.7825, 0.8126, 0.8434, 0.8693, 0.891, 0.9092, 0.9222, 0.9319,
        0.9403, 0.9477, 0.9544, 0.9602, 0.9653,
    ];
    const HT_HE: [f64; 16] = [
        1.88, 3.02, 4.72, 6.99, 10.21, 14.48, 20.53, 29.11, 41.2, 55.19, 70.69, 90.34, 115.29,
        147.42, 188.24, 240.03,
    ];
    const A_HE: [f64; 16] = [
        1.6189, 1.383, 1.1919, 1.0458, 0.922, 0.8205, 0.7305, 0.6502, 0.595, 0.5545, 0.5333,
        0.5189, 0.5181, 0.5176, 0.5172, 0.5119,
    ];
    const B_HE: [f64; 16] = [
        0.477, 0.5747, 0.6527, 0.7223, 0.7582, 0.7957, 0.8279, 0.8553, 0.8757, 0.8903, 0.8997,
        0.9073, 0.9122, 0.9171, 0.9217, 0.9267,
    ];
    let (ps, bpm, wv) = (1.01325, 0.09985, 0.0627);
    let alg = load_algorithm(&root().join("algorithms/zhl16c-gf30-85.toml")).unwrap();
    let fn2_surface = alg.conventions.surface_tissue_n2_fraction;
    let (_, s) = decophantom::algorithm::plan_dive(
        &alg,
        110.0,
        20.0,
        Some("10/70"),
        &["50".to_string(), "100".to_string()],
        &["21/35@0..60".to_string()],
    )
    .unwrap();
    // the legs: down on 21/35 to 60 m, on 10/70 to 110 m, the bottom
    let l = &s.legs;
    assert_eq!((l[0].start_depth_m, l[0].end_depth_m), (0.0, 60.0));
    assert!((l[0].gas.o2 - 0.21).abs() < 1e-12 && (l[0].gas.he - 0.35).abs() < 1e-12);
    assert!(
        (l[0].duration_s - 180.0).abs() < 1e-9,
        "{}",
        l[0].duration_s
    );
    assert_eq!((l[1].start_depth_m, l[1].end_depth_m), (60.0, 110.0));
    assert!((l[1].gas.o2 - 0.10).abs() < 1e-12 && (l[1].gas.he - 0.70).abs() < 1e-12);

    // Schreiner: p(t) = pi0 + R(t − 1/k) − (pi0 − p0 − R/k)·e^{−kt}, per gas
    let schreiner = |p0: f64, f: f64, amb0: f64, rate_bar_min: f64, t: f64, ht: f64| {
        let k = std::f64::consts::LN_2 / ht;
        let pi0 = f * (amb0 - wv);
        let r = f * rate_bar_min;
        pi0 + r * (t - 1.0 / k) - (pi0 - p0 - r / k) * (-k * t).exp()
    };
    let mut n2 = [fn2_surface * (ps - wv); 16];
    let mut he = [0.0; 16];
    let mut t_end = Vec::new(); // (runtime at the leg's end, tissues)
    let mut t = 0.0;
    for leg in l.iter().filter(|x| x.duration_s > 0.0) {
        let minutes = leg.duration_s / 60.0;
        let amb0 = ps + leg.start_depth_m * bpm;
        let rate = (leg.end_depth_m - leg.start_depth_m) * bpm / minutes;
        for i in 0..16 {
            n2[i] = schreiner(n2[i], leg.gas.n2(), amb0, rate, minutes, HT_N2[i]);
            he[i] = schreiner(he[i], leg.gas.he, amb0, rate, minutes, HT_HE[i]);
        }
        t += minutes;
        t_end.push((t, leg.end_depth_m, n2, he, leg.kind));
    }
    let ab = |i: usize, n2: &[f64; 16], he: &[f64; 16]| {
        let p = n2[i] + he[i];
        (
            p,
            (A_N2[i] * n2[i] + A_HE[i] * he[i]) / p,
            (B_N2[i] * n2[i] + B_HE[i] * he[i]) / p,
        )
    };
    // tolerated ambient pressure at a gradient factor (Baker's form), the largest over all
    let ceiling = |gf: f64, n2: &[f64; 16], he: &[f64; 16]| {
        (0..16)
            .map(|i| {
                let (p, a, b) = ab(i, n2, he);
                (p - a * gf) / (gf / b - gf + 1.0)
            })
            .fold(f64::NEG_INFINITY, f64::max)
    };
    let samples = loading(&s, &alg.conventions, 1.0, 0.5);
    let at = |time: f64| {
        samples
            .iter()
            .find(|x| (x.time_min - time).abs() < 1e-9)
            .unwrap()
    };
    // at the switch depth (end of the travel-gas descent) and at the end of the bottom
    let bottom_end = t_end
        .iter()
        .position(|x| x.4 == decophantom::algorithm::LegKind::Bottom)
        .unwrap();
    for k in [0, bottom_end] {
        let (time, depth, n2k, hek, _) = &t_end[k];
        let amb = ps + depth * bpm;
        let got = at(*time);
        for i in 0..16 {
            let (p, a, b) = ab(i, n2k, hek);
            let want = (p - amb) / (amb / b + a - amb);
            assert!(
                (got.gradient[i] - want).abs() < 1e-9,
                "{depth} m compartment {}: {} vs {want}",
                i + 1,
                got.gradient[i]
            );
        }
        let want_ceil = ((ceiling(1.0, n2k, hek) - ps) / bpm).max(0.0);
        assert!(
            (got.ceiling_m - want_ceil).abs() < 1e-9,
            "{} vs {want_ceil}",
            got.ceiling_m
        );
    }
    // travel gas on-gasses helium, and the bottom ceiling is real
    assert!(t_end[0].3[0] > 0.5, "{:?}", t_end[0].3);
    assert!(ceiling(1.0, &t_end[bottom_end].2, &t_end[bottom_end].3) > ps);
    // the first stop: independent GF-low (30 %) ceiling at the arrival there
    let first = t_end
        .iter()
        .position(|x| x.4 == decophantom::algorithm::LegKind::Stop)
        .unwrap();
    let (_, stop_depth, n2a, hea, _) = &t_end[first - 1];
    assert_eq!(*stop_depth, s.stops[0].depth_m);
    let c_at = ceiling(0.30, n2a, hea);
    assert!(c_at <= ps + stop_depth * bpm + 1e-9, "{c_at}");
    // 3 m higher on the same gas at 10 m/min: above the ceiling
    let gas = l[first].gas;
    let (mut n2b, mut heb) = (*n2a, *hea);
    for i in 0..16 {
        let amb0 = ps + stop_depth * bpm;
        n2b[i] = schreiner(n2b[i], gas.n2(), amb0, -10.0 * bpm, 0.3, HT_N2[i]);
        heb[i] = schreiner(heb[i], gas.he, amb0, -10.0 * bpm, 0.3, HT_HE[i]);
    }
    assert!(ceiling(0.30, &n2b, &heb) > ps + (stop_depth - 3.0) * bpm);
    println!(
        "110 m 10/70 travel 21/35@0..60: first stop {} m, runtime {:.1} min",
        s.stops[0].depth_m,
        s.runtime_min()
    );
}

/// Travel gases are checked before planning, naming the option (exit 2): hypoxic at the
/// shallow end of the range, beyond the MOD at its deep end, ranges with a gap, a range
/// reaching the bottom, the bottom mix hypoxic where it takes over; a hypoxic bottom mix
/// without a travel gas names `--gas` and suggests `--travel-gas`. `evaluate` takes
/// `--travel-gas` with the same checks.
#[test]
fn travel_gas_errors_name_the_option() {
    let base = [
        "--algorithm",
        "algorithms/vpmb-2-baker.toml",
        "--depth",
        "110",
        "--time",
        "20",
        "--gas",
        "10/70",
    ];
    for (travel, needle) in [
        (&["10/50@0..60"][..], "hypoxic at its shallow end"),
        (&["21/35@0..70"][..], "MOD"),
        (&["21/35@0..40", "15/55@45..70"][..], "without gap"),
        (&["21/35@10..60"][..], "from the surface"),
        (
            &["21/35@0..30", "15/55@30..110"][..],
            "not shallower than the dive",
        ),
        (&["21/35@0..4"][..], "bottom gas 10/70 is hypoxic"),
        (&["21/35"][..], "depth range"),
    ] {
        let mut a = base.to_vec();
        for t in travel {
            a.extend_from_slice(&["--travel-gas", t]);
        }
        let (code, out, err) = plan(&a);
        assert_eq!(code, 2, "{travel:?}: {err}");
        assert!(out.is_empty());
        assert!(
            err.contains("--travel-gas") && err.contains(needle),
            "{travel:?}: {err}"
        );
    }
    // a travel gas breathable at its shallow end that is not 0 m (second range): accepted
    let mut a = base.to_vec();
    a.extend_from_slice(&[
        "--travel-gas",
        "21/35@0..40",
        "--travel-gas",
        "14/60@40..80",
    ]);
    let (code, _, err) = plan(&a);
    assert_eq!(code, 0, "{err}");
    // evaluate: the same checks before any run
    let o = Command::new(bin())
        .current_dir(root())
        .args([
            "evaluate",
            "--algorithm",
            "algorithms/zhl16c-gf30-85.toml",
            "--depth",
            "110",
            "--time",
            "20",
            "--gas",
            "10/70",
            "--travel-gas",
            "10/50@0..60",
            "--criteria",
            "algorithms/criteria/default.toml",
            "--out",
            "/nonexistent-dir/never-written",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--travel-gas") && err.contains("hypoxic"),
        "{err}"
    );
}

/// `[gases]` in an algorithm file: `travel` and `deco` lists read like the command line,
/// used when the command line gives none (which replaces them), errors naming the file, the
/// line and `gases.travel`; unknown keys refused.
#[test]
fn travel_and_deco_gases_from_the_algorithm_file() {
    let dir = crate::common::tempdir("plan-gases");
    let base = std::fs::read_to_string(root().join("algorithms/zhl16c-gf30-85.toml")).unwrap();
    let write = |name: &str, gases: &str| {
        let p = dir.join(name);
        std::fs::write(&p, format!("{base}\n[gases]\n{gases}\n")).unwrap();
        p
    };
    let good = write(
        "good.toml",
        "travel = [\"21/35@0..60\"]\ndeco = [\"50\", \"100\"]",
    );
    let args = |alg: &std::path::Path| {
        vec![
            "--algorithm".to_string(),
            alg.display().to_string(),
            "--depth".into(),
            "110".into(),
            "--time".into(),
            "20".into(),
            "--gas".into(),
            "10/70".into(),
        ]
    };
    let a = args(&good);
    let from_file = plan_json(&a.iter().map(String::as_str).collect::<Vec<_>>());
    let mut b = a.clone();
    b.extend(
        [
            "--travel-gas",
            "21/35@0..60",
            "--deco-gas",
            "50",
            "--deco-gas",
            "100",
        ]
        .map(String::from),
    );
    let from_cli = plan_json(&b.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(stops(&from_file), stops(&from_cli));
    assert!(!stops(&from_file).is_empty());
    // the command line replaces the file's list
    let mut c = a.clone();
    c.extend(
        [
            "--travel-gas",
            "21/35@0..40",
            "--travel-gas",
            "15/55@40..70",
        ]
        .map(String::from),
    );
    let replaced = plan_json(&c.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(replaced["schedule"]["legs"][1]["gas"], "15/55");
    // errors name the file, the line and the field
    let bad = write("bad.toml", "deco = [\"50\"]\ntravel = [\"10/50@0..60\"]");
    let (code, _, err) = plan(&args(&bad).iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(code, 2, "{err}");
    let line = base.lines().count() + 4;
    assert!(
        err.contains("bad.toml")
            && err.contains("gases.travel")
            && err.contains(&format!("bad.toml:{line}:"))
            && err.contains("hypoxic"),
        "{err}"
    );
    let unknown = write("unknown.toml", "travell = [\"21/35@0..60\"]");
    let (code, _, err) = plan(
        &args(&unknown)
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("travell"), "{err}");
    let unreadable = write("unreadable.toml", "travel = [\"21/35@0..sixty\"]");
    let (code, _, err) = plan(
        &args(&unreadable)
            .iter()
            .map(String::as_str)
            .collect::<Vec<_>>(),
    );
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("gases.travel") && err.contains("end depth"),
        "{err}"
    );
}

/// The logged 110 m trimix dive of Subsurface's test file (`../shared/dive-files/
/// subsurface__test51.xml`, dives/test51.xml of subsurface/subsurface: EAN55 to 20 m, 31/30
/// to 40 m, 11/60 to 110 m, surface pressure 0.896 bar) re-planned with two travel gases in
/// Subsurface's conventions. The logged plan first stops at 51 m after 5 min at 110 m; the
/// re-plan with the same 5 min at 110 m and ZH-L16C GF 30/85 first stops there too. The log
/// spent 10 min at 20 m before going deeper (our plans descend straight), so its 123.5 min
/// runtime is not comparable and only printed. Skipped when `../shared` is absent.
#[test]
fn logged_110_m_subsurface_dive_replans_with_travel_gases() {
    let Some(log) = crate::common::shared("dive-files/subsurface__test51.xml") else {
        return;
    };
    let text = std::fs::read_to_string(log).unwrap();
    assert!(
        text.contains("<depth max='110.0 m'") && text.contains("<surface pressure='0.896 bar'")
    );
    // time at 110 m in the log: 20:00 to 25:00; our bottom time includes the descent
    // (18 m/min in Subsurface's conventions: 6.11 min to 110 m)
    let time = format!("{}", 110.0 / 18.0 + 5.0);
    let v = plan_json(&[
        "--algorithm",
        "algorithms/zhl16c-gf30-85-subsurface.toml",
        "--surface-pressure",
        "896",
        "--depth",
        "110",
        "--time",
        &time,
        "--gas",
        "11/60",
        "--travel-gas",
        "55@0..20",
        "--travel-gas",
        "31/30@20..40",
        "--deco-gas",
        "31/30@42",
        "--deco-gas",
        "55@20",
        "--deco-gas",
        "100@6",
    ]);
    let legs = v["schedule"]["legs"].as_array().unwrap();
    let gases: Vec<&str> = legs[..3]
        .iter()
        .map(|l| l["gas"].as_str().unwrap())
        .collect();
    assert_eq!(gases, ["EAN55", "31/30", "11/60"]);
    let st = stops(&v);
    assert_eq!(st[0].0, 51.0, "{st:?}");
    println!(
        "test51 re-plan: first stop {} m (log 51 m), runtime {:.1} min (log 123.5 min)",
        st[0].0,
        legs.iter()
            .map(|l| l["duration_s"].as_f64().unwrap())
            .sum::<f64>()
            / 60.0
    );
}

/// D13, D14, D19, D20 (bad-input review 2). `plan`'s outputs are checked before planning,
/// each refusal exit 2 naming the option and the user's path: `--out` and `--plot` the same
/// file (the figure replaced the schedule), `--format` with `--json` and nothing to format, a
/// folder that does not exist or is a file (before: exit 3 after the work, naming an internal
/// temporary file), the algorithm file as `--plot` (named `--plot`, not `--out`). An existing
/// file is replaced only if `plan` wrote it and it is unchanged since (its last line, a hash of
/// the lines above, as an output folder's manifest): a user's file or an edited one is kept.
#[test]
fn plan_outputs_are_checked_first_and_a_users_file_is_kept() {
    use decophantom::algorithm::Schedule;
    let dir = crate::common::tempdir("plan-outputs");
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let dive = |extra: &[&str]| {
        let mut a = vec![
            "--algorithm",
            "algorithms/zhl16c-gf30-85.toml",
            "--depth",
            "30",
            "--time",
            "10",
        ];
        a.extend_from_slice(extra);
        plan(&a)
    };
    let refused = |r: (i32, String, String), needles: &[&str]| {
        assert_eq!(r.0, 2, "{}", r.2);
        assert!(r.1.is_empty(), "{}", r.1);
        for n in needles {
            assert!(r.2.contains(n), "'{n}' not in {}", r.2);
        }
        assert!(!r.2.contains(".tmp-"), "{}", r.2);
    };
    let x = p("x.toml");
    refused(dive(&["--out", &x, "--plot", &x]), &["field '--plot'"]);
    assert!(!dir.join("x.toml").exists());
    refused(dive(&["--json", "--format", "csv"]), &["field '--format'"]);
    let missing = p("nodir/x.csv");
    refused(
        dive(&["--out", &missing]),
        &[&missing, "field '--out'", "does not exist"],
    );
    std::fs::write(dir.join("afile"), "mine").unwrap();
    let under = p("afile/x.csv");
    refused(
        dive(&["--out", &under]),
        &[&under, "field '--out'", "is a file"],
    );
    let under = p("afile/x.svg");
    refused(dive(&["--plot", &under]), &[&under, "field '--plot'"]);
    let alg = root().join("algorithms/zhl16c-gf30-85.toml");
    refused(
        dive(&["--plot", alg.to_str().unwrap()]),
        &["field '--plot'", "input"],
    );
    // a user's file: kept, for the schedule and the figure
    for (name, flag) in [("mine.csv", "--out"), ("mine.svg", "--plot")] {
        std::fs::write(dir.join(name), "user data\n").unwrap();
        refused(
            dive(&[flag, &p(name)]),
            &[&format!("field '{flag}'"), "not written"],
        );
        assert_eq!(
            std::fs::read_to_string(dir.join(name)).unwrap(),
            "user data\n"
        );
    }
    // plan's own files, unchanged: replaced (the new plan is there); edited: kept
    let s = p("s.toml");
    let svg = p("s.svg");
    assert_eq!(dive(&["--out", &s, "--plot", &svg]).0, 0);
    let (code, _, err) = plan(&[
        "--algorithm",
        "algorithms/zhl16c-gf30-85.toml",
        "--depth",
        "30",
        "--time",
        "15",
        "--out",
        &s,
        "--plot",
        &svg,
    ]);
    assert_eq!(code, 0, "{err}");
    let read = Schedule::read(&dir.join("s.toml")).unwrap();
    assert_eq!(read.legs[1].end_depth_m, 30.0);
    assert!(read.runtime_min() >= 15.0, "{}", read.runtime_min());
    roxmltree::Document::parse(&std::fs::read_to_string(dir.join("s.svg")).unwrap())
        .expect("well-formed SVG with its marker comment");
    let edited = std::fs::read_to_string(dir.join("s.toml"))
        .unwrap()
        .replacen("label = ", "label = \"mine\"\n# was ", 1);
    std::fs::write(dir.join("s.toml"), &edited).unwrap();
    refused(dive(&["--out", &s]), &["field '--out'", "changed since"]);
    assert_eq!(std::fs::read_to_string(dir.join("s.toml")).unwrap(), edited);
    // a line appended after the marker of a file plan wrote is an edit too (it was called
    // "not written by plan")
    let a = p("a.toml");
    assert_eq!(dive(&["--out", &a]).0, 0);
    let appended = format!(
        "{}# my note\n",
        std::fs::read_to_string(dir.join("a.toml")).unwrap()
    );
    std::fs::write(dir.join("a.toml"), &appended).unwrap();
    refused(dive(&["--out", &a]), &["field '--out'", "changed since"]);
    assert_eq!(
        std::fs::read_to_string(dir.join("a.toml")).unwrap(),
        appended
    );
    // the CSV, with its marker line, reads back as the same schedule
    let c = p("s.csv");
    assert_eq!(dive(&["--out", &c]).0, 0);
    let back = decophantom::algorithm::waypoints::read_schedule(
        &dir.join("s.csv"),
        &decophantom::algorithm::conventions::DECOTENGU,
        decophantom::gas::GasMix::AIR,
    )
    .unwrap();
    assert_eq!(back.runtime_min(), 13.0);
    // nothing else left in the folder (no temporary or probe files)
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        ["a.toml", "afile", "mine.csv", "mine.svg", "s.csv", "s.svg", "s.toml"]
    );
}

/// D18 (bad-input review 2). A plan lasts at most the 30 days (43 200 min) a history may:
/// travel rates below 1000 m / 43 200 min ≈ 0.0231 m/min are refused on the command line and
/// in an algorithm file, and a plan whose runtime (bottom time, travel, stops) would exceed the
/// limit is refused naming the option that made it long (before: `--ascent-rate 1e-9` planned a
/// 3·10¹⁰ min dive). The same checks cover the algorithm file's `pa_per_m` (D5).
#[test]
fn plan_rates_and_runtime_stay_within_thirty_days() {
    let dive = |extra: &[&str]| {
        let mut a = vec![
            "--algorithm",
            "algorithms/zhl16c-gf30-85.toml",
            "--depth",
            "30",
            "--time",
            "10",
        ];
        a.extend_from_slice(extra);
        plan(&a)
    };
    let min = decophantom::algorithm::conventions::MIN_TRAVEL_RATE_M_MIN;
    assert!((min * 43_200.0 - 1000.0).abs() < 1e-9);
    for (opt, v) in [
        ("--ascent-rate", "1e-9"),
        ("--descent-rate", "1e-9"),
        ("--ascent-rate", "0.023"),
    ] {
        let (code, out, err) = dive(&[opt, v]);
        assert_eq!(code, 2, "{opt} {v}: {err}");
        assert!(
            out.is_empty() && err.contains(&format!("field '{opt}'")),
            "{err}"
        );
    }
    let (code, out, err) = dive(&["--ascent-rate", "0.03"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("Total dive time"), "{out}");
    // a bottom time within 43 200 min whose stops take the dive past it
    let (code, _, err) = plan(&[
        "--algorithm",
        "algorithms/zhl16c-gf30-85.toml",
        "--depth",
        "30",
        "--time",
        "43000",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("field '--time'") && err.contains("43200"),
        "{err}"
    );
    // the algorithm file's own conventions
    let dir = crate::common::tempdir("plan-conventions");
    for (key, v) in [
        ("ascent_rate_m_min", "1e-9"),
        ("pa_per_m", "1.0"),
        ("pa_per_m", "9.985"),
        ("surface_pressure_pa", "101.325"),
    ] {
        let f = dir.join("a.toml");
        std::fs::write(
            &f,
            format!("kind = \"zhl16\"\n[conventions]\npreset = \"decotengu\"\n{key} = {v}\n[params]\nmodel = \"zh-l16c\"\ngf_low = 30\ngf_high = 85\n"),
        )
        .unwrap();
        let (code, _, err) = plan(&[
            "--algorithm",
            f.to_str().unwrap(),
            "--depth",
            "30",
            "--time",
            "10",
        ]);
        assert_eq!(code, 2, "{key} = {v}: {err}");
        assert!(
            err.contains("a.toml:4:") && err.contains(&format!("conventions.{key}")),
            "{err}"
        );
    }
}

/// Every `key = value` line of a TOML file whose value is a number, a boolean or a one-line
/// string, with that value given the wrong type (a string quoted, anything else as the string
/// `"x"` — `1` for a string): (1-based line, dotted field, the file's text with that change).
fn wrong_type_variants(text: &str) -> Vec<(usize, String, String)> {
    let lines: Vec<&str> = text.lines().collect();
    let mut table = String::new();
    let mut out = Vec::new();
    for (i, l) in lines.iter().enumerate() {
        let t = l.trim();
        if let Some(h) = t.strip_prefix('[') {
            table = h.trim_matches(|c| c == '[' || c == ']').to_string();
            continue;
        }
        let Some((key, rest)) = t.split_once(" = ") else {
            continue;
        };
        if t.starts_with('#') || rest.starts_with('[') || rest.starts_with('{') {
            continue;
        }
        let (value, tail) = match rest.strip_prefix('"') {
            Some(r) => match r.split_once('"') {
                Some((v, tail)) => (format!("\"{v}\""), tail),
                None => continue,
            },
            None => {
                let v = rest.split('#').next().unwrap().trim();
                (v.to_string(), &rest[v.len()..])
            }
        };
        let wrong = if value.starts_with('"') {
            "1".to_string()
        } else if value == "true" || value == "false" {
            "\"x\"".to_string()
        } else {
            format!("\"{value}\"")
        };
        let mut changed = lines.clone();
        let line = format!("{key} = {wrong}{tail}");
        changed[i] = &line;
        let field = if table.is_empty() {
            key.to_string()
        } else {
            format!("{table}.{key}")
        };
        out.push((i + 1, field, changed.join("\n") + "\n"));
    }
    out
}

/// Every TOML file in `folder` with the `toml` extension: it parses with `parse`, and each of
/// its [`wrong_type_variants`] is refused naming that file, the key's line and field. Returns
/// (files, variants).
fn assert_wrong_types_named<T>(
    folder: &str,
    parse: impl Fn(&str, &std::path::Path) -> Result<T, decophantom::error::InputError>,
) -> (usize, usize) {
    let (mut files, mut cases) = (0, 0);
    for entry in std::fs::read_dir(root().join(folder)).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(parse(&text, &path).is_ok(), "{}", path.display());
        files += 1;
        for (line, field, bad) in wrong_type_variants(&text) {
            let Err(e) = parse(&bad, &path) else {
                panic!("{}: line {line} accepted", path.display())
            };
            assert_eq!(
                (e.line, e.field.as_deref(), e.file.as_deref()),
                (Some(line), Some(field.as_str()), Some(path.as_path())),
                "{}: {e}",
                path.display()
            );
            cases += 1;
        }
    }
    (files, cases)
}

/// A value of the wrong type anywhere in an algorithm file names the key's own line and its
/// dotted field, for every key of every committed algorithm file (ZH-L16 and VPM-B): the
/// `[params]` table is read by the algorithm's builder once `kind` is known, and before
/// session 31 its type errors named the table (`gf.toml:10: field 'params': invalid type:
/// string "30", expected f64` for `gf_low = "30"` on line 12 of zhl16c-gf30-85.toml; VPM-B:
/// `field 'params.params'`). Through the binary for that reported case.
#[test]
fn algorithm_file_type_errors_name_the_key_and_its_line() {
    let (files, cases) = assert_wrong_types_named(
        "algorithms",
        decophantom::algorithm::config::parse_algorithm,
    );
    // 15 files; every one has kind, label, preset and two or three [params] keys
    assert_eq!(files, 15);
    assert!(cases >= 15 * 5, "{cases}");

    let dir = crate::common::tempdir("plan-type-errors");
    let text = std::fs::read_to_string(root().join("algorithms/zhl16c-gf30-85.toml")).unwrap();
    let f = dir.join("gf.toml");
    std::fs::write(&f, text.replace("gf_low = 30", "gf_low = \"30\"")).unwrap();
    let (code, out, err) = plan(&[
        "--algorithm",
        f.to_str().unwrap(),
        "--depth",
        "30",
        "--time",
        "20",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(out.is_empty(), "{out}");
    assert!(
        err.contains(
            "gf.toml:12: field 'params.gf_low': invalid type: string \"30\", expected f64"
        ),
        "{err}"
    );
}

/// The same for the committed criteria files (`algorithms/criteria/`): a wrong type in
/// `[protocol]` or in a `[[criterion]]` entry names the key's own line and field. Before
/// session 31 a criterion's own parameter (`threshold_mm3 = "0.008133"`) was blamed on
/// `criterion.kind` at the entry's `kind` line, and `[protocol]` type errors named no field.
#[test]
fn criteria_file_type_errors_name_the_key_and_its_line() {
    let (_, cases) = assert_wrong_types_named(
        "algorithms/criteria",
        decophantom::risk::config::parse_criteria,
    );
    // default.toml: description, 5 [protocol] keys, 6 criteria of 3–4 keys each
    assert!(cases >= 25, "{cases}");
}

/// Descent and ascent rates above [`MAX_TRAVEL_RATE_M_MIN`] (100 m/min, the top of the range
/// schedules accept) are refused in an algorithm file's `[conventions]`, naming file, line
/// and field (before session 31 a file's `descent_rate_m_min = 500` planned with exit 0), as
/// they are on the command line; exactly 100 m/min plans.
///
/// [`MAX_TRAVEL_RATE_M_MIN`]: decophantom::algorithm::conventions::MAX_TRAVEL_RATE_M_MIN
#[test]
fn algorithm_file_travel_rates_above_100_m_min_are_refused() {
    let dir = crate::common::tempdir("plan-fast-rates");
    let run = |key: &str, v: &str| {
        let f = dir.join("a.toml");
        std::fs::write(
            &f,
            format!("kind = \"zhl16\"\n[conventions]\npreset = \"decotengu\"\n{key} = {v}\n[params]\nmodel = \"zh-l16c\"\ngf_low = 30\ngf_high = 85\n"),
        )
        .unwrap();
        plan(&[
            "--algorithm",
            f.to_str().unwrap(),
            "--depth",
            "30",
            "--time",
            "10",
        ])
    };
    for (key, v) in [
        ("descent_rate_m_min", "500"),
        ("ascent_rate_m_min", "100.5"),
    ] {
        let (code, out, err) = run(key, v);
        assert_eq!(code, 2, "{key} = {v}: {err}");
        assert!(out.is_empty(), "{out}");
        assert!(
            err.contains(&format!("a.toml:4: field 'conventions.{key}': {v} m/min is faster than the accepted 100 m/min")),
            "{err}"
        );
    }
    for key in ["descent_rate_m_min", "ascent_rate_m_min"] {
        let (code, _, err) = run(key, "100");
        assert_eq!(code, 0, "{key} = 100: {err}");
    }
    for opt in ["--descent-rate", "--ascent-rate"] {
        let (code, _, err) = plan(&[
            "--algorithm",
            "algorithms/zhl16c-gf30-85.toml",
            "--depth",
            "30",
            "--time",
            "10",
            opt,
            "101",
        ]);
        assert_eq!(code, 2, "{err}");
        assert!(
            err.contains(&format!(
                "field '{opt}': 101 m/min is faster than the accepted 100 m/min"
            )),
            "{err}"
        );
    }
}
