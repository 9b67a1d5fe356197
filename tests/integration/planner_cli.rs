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
        let (_, sched) = decophantom::app::plan::plan_dive(
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
