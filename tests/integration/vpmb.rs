//! VPM-B against Baker's published outputs.
//!
//! References:
//! - the issue (#3): air 30 m / 40 min +0 and air 45 m / 25 min +2 in Baker's conventions;
//! - Baker's VPMDECO (Model: VPM-B) output files run by Baker's FORTRAN program and shipped as
//!   test data with the `bwaite/vpmb` Python port (tests/msw_test/VPMDECO.OUT, run 02-16-2010;
//!   tests/gradient_onset_of_imperm_greater/VPMDECO.OUT, run 03-01-2010). Only the printed
//!   schedules are used here, as reference values.

use decophantom::algorithm::conventions::{GfLowAnchor, StopRounding};
use decophantom::algorithm::vpmb::{self, CvaConvergence, RawVpmbParams, VpmB};
use decophantom::algorithm::{Conventions, DecoAlgorithm, DecoGas, DivePlan, Schedule, TravelGas};
use decophantom::gas::GasMix;
use decophantom::units::ATM_PA;

/// Baker's metric conventions (VPMDECO with Units='msw'): 10.1325 msw per atm, 0.493 msw
/// water vapour, whole minutes of runtime, minimum stop 1 min. Rates as given per dive.
fn baker_msw(descent: f64, ascent: f64) -> Conventions {
    Conventions {
        surface_pressure_pa: 101_325.0,
        pa_per_m: 10_000.0,
        water_vapour_pa: 4_930.0,
        descent_rate_m_min: descent,
        ascent_rate_m_min: ascent,
        stop_spacing_m: 3.0,
        last_stop_m: 3.0,
        bottom_time_includes_descent: true,
        stop_rounding: StopRounding::WholeMinutesOfRuntime,
        gf_low_anchor: GfLowAnchor::FirstStop,
        min_stop_min: 1.0,
        // Baker's VPMDECO starts the tissues at 0.79 × (surface − water vapour)
        surface_tissue_n2_fraction: 0.79,
    }
}

fn vpm(raw: RawVpmbParams, c: Conventions) -> VpmB {
    VpmB::new("VPM-B", raw.validate().unwrap(), c).unwrap()
}

fn raw(conservatism: i64) -> RawVpmbParams {
    RawVpmbParams {
        conservatism,
        ..RawVpmbParams::default()
    }
}

fn dive(depth: f64, time: f64, gas: &str, deco: &[(&str, f64)]) -> DivePlan {
    DivePlan {
        depth_m: depth,
        bottom_time_min: time,
        bottom_gas: GasMix::parse(gas).unwrap(),
        deco_gases: deco
            .iter()
            .map(|(g, d)| DecoGas {
                mix: GasMix::parse(g).unwrap(),
                switch_depth_m: *d,
            })
            .collect(),
        travel_gases: vec![],
    }
}

fn table(s: &Schedule) -> String {
    s.stops
        .iter()
        .map(|st| format!("{}:{}", st.depth_m, st.stop_min))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Stops must be the same depths, each within ±`tol` min of the reference.
fn assert_stops(s: &Schedule, want: &[(f64, f64)], tol: f64) {
    let got: Vec<(f64, f64)> = s.stops.iter().map(|x| (x.depth_m, x.stop_min)).collect();
    assert_eq!(
        got.len(),
        want.len(),
        "stops {} vs reference {want:?}",
        table(s)
    );
    for ((gd, gt), (wd, wt)) in got.iter().zip(want) {
        assert!(
            (gd - wd).abs() < 1e-6,
            "stop depth {gd} vs {wd}: {}",
            table(s)
        );
        assert!(
            (gt - wt).abs() <= tol,
            "stop {gd} m: {gt} vs {wt} min: {}",
            table(s)
        );
    }
}

#[test]
fn issue_air_30m_40min_plus0() {
    // Issue #3 reference (Baker's VPM-B, Baker conventions, +0, λ 7500): stops 12 m 2,
    // 9 m 5, 6 m 8, 3 m 14; runtime 70.3 min.
    let alg = vpm(raw(0), baker_msw(20.0, 10.0));
    let s = alg.plan(&dive(30.0, 40.0, "air", &[])).unwrap();
    println!("30/40 +0: {} rt {:.1}", table(&s), s.runtime_min());
    assert_stops(&s, &[(12.0, 2.0), (9.0, 5.0), (6.0, 8.0), (3.0, 14.0)], 1.0);
    // In fact every stop and the runtime match exactly.
    assert_stops(&s, &[(12.0, 2.0), (9.0, 5.0), (6.0, 8.0), (3.0, 14.0)], 0.0);
    assert!((s.runtime_min() - 70.3).abs() < 1e-6, "{}", s.runtime_min());
}

#[test]
fn issue_air_45m_25min_plus2() {
    // Issue #3 reference: 24 m 1, 21 m 2, 18 m 3, 15 m 3, 12 m 6, 9 m 7, 6 m 12, 3 m 22 (83.3 min).
    let alg = vpm(raw(2), baker_msw(20.0, 10.0));
    let s = alg.plan(&dive(45.0, 25.0, "air", &[])).unwrap();
    println!("45/25 +2: {} rt {:.1}", table(&s), s.runtime_min());
    assert_stops(
        &s,
        &[
            (24.0, 1.0),
            (21.0, 2.0),
            (18.0, 3.0),
            (15.0, 3.0),
            (12.0, 6.0),
            (9.0, 7.0),
            (6.0, 12.0),
            (3.0, 22.0),
        ],
        1.0,
    );
    assert!(
        (s.runtime_min() - 83.3).abs() <= 1.0 + 1e-9,
        "{}",
        s.runtime_min()
    );
}

/// Baker's sample dive: TRIMIX DIVE TO 80 MSW, 15/45, descent 23 msw/min, bottom until
/// runtime 30 min, ascent 10 msw/min, EAN36 from 33 m, O2 from 6 m, radii 0.6/0.5 µm, λ 7500.
fn baker_trimix_80m() -> (VpmB, DivePlan) {
    let r = RawVpmbParams {
        critical_radius_n2_um: 0.6,
        critical_radius_he_um: 0.5,
        ..RawVpmbParams::default()
    };
    (
        vpm(r, baker_msw(23.0, 10.0)),
        dive(80.0, 30.0, "15/45", &[("36", 33.0), ("o2", 6.0)]),
    )
}

#[test]
fn baker_vpmdeco_trimix_80m_with_deco_gases() {
    // VPMDECO.OUT (Baker's FORTRAN VPM-B, 02-16-2010), msw_test: first stop 54 m, stops
    // 54:1 51:1 48:1 45:2 42:2 39:2 36:3 33:2 30:1 27:2 24:3 21:4 18:4 15:7 12:8 9:13 6:13 3:23,
    // run time 125 min. Baker ascends at 3 msw/min on oxygen from 6 m (a per-gas rate that a
    // DivePlan does not carry); here the ascent stays 10 m/min, which only moves the last
    // two stops' travel and the final ascent (runtime tolerance 1 min for that).
    let (alg, plan) = baker_trimix_80m();
    let s = alg.plan(&plan).unwrap();
    println!("80 m trimix: {} rt {:.1}", table(&s), s.runtime_min());
    let want = [
        (54.0, 1.0),
        (51.0, 1.0),
        (48.0, 1.0),
        (45.0, 2.0),
        (42.0, 2.0),
        (39.0, 2.0),
        (36.0, 3.0),
        (33.0, 2.0),
        (30.0, 1.0),
        (27.0, 2.0),
        (24.0, 3.0),
        (21.0, 4.0),
        (18.0, 4.0),
        (15.0, 7.0),
        (12.0, 8.0),
        (9.0, 13.0),
        (6.0, 13.0),
        (3.0, 23.0),
    ];
    assert_stops(&s, &want, 1.0);
    // 16 of the 18 stops match exactly (here 15 m 6 and 12 m 9 against Baker's 7 and 8), and
    // the total stop time is Baker's 92 min.
    let exact = s
        .stops
        .iter()
        .zip(&want)
        .filter(|(a, b)| a.stop_min == b.1)
        .count();
    assert!(exact >= 16, "{exact} exact");
    assert_eq!(s.stops.iter().map(|x| x.stop_min).sum::<f64>(), 92.0);
    // Gas switches as in Baker's table: EAN36 from the 33 m stop, O2 from the 6 m stop.
    for st in &s.stops {
        let o2 = if st.depth_m <= 6.0 {
            1.0
        } else if st.depth_m <= 33.0 {
            0.36
        } else {
            0.15
        };
        assert!((st.gas.o2 - o2).abs() < 1e-12, "gas at {} m", st.depth_m);
    }
    assert!(
        (s.runtime_min() - 125.0).abs() <= 1.5,
        "{}",
        s.runtime_min()
    );
    // Baker prints "Leading compartment enters the decompression zone at 64.8 mswg"; the
    // root here is 64.73 m (an independent port, ZPlanKit's vpmb_ref.c notes, also finds
    // 64.73 against Baker's 64.8: his bisection stops early). Tolerance 0.1 m.
    let zone = alg.start_of_deco_zone_m(&plan).unwrap();
    assert!((zone - 64.8).abs() <= 0.1, "{zone}");
}

#[test]
fn baker_vpmdeco_trimix_260fsw_impermeable() {
    // VPMDECO.OUT (Baker's FORTRAN VPM-B, 03-01-2010), gradient_onset_of_imperm_greater, first
    // dive: 15/45 to 260 fsw, descent 75 fsw/min, bottom until runtime 30, ascent 30 fsw/min,
    // 10 fsw stops, last stop 20 fsw, radii 0.8/0.7 µm, onset of impermeability 5.4 atm (so
    // the impermeable crushing branch is used), λ 7500. Stops (fsw:min):
    // 190:1 180:1 170:1 160:1 150:2 140:3 130:3 120:3 110:4 100:6 90:7 80:9 70:10 60:16
    // 50:22 40:32 30:52 20:777; "enters the decompression zone at 209.7 fswg".
    // Baker's final ascent from 20 fsw is at 10 fsw/min; here 30 fsw/min (after the last stop).
    let ft = 0.3048;
    let c = Conventions {
        surface_pressure_pa: ATM_PA,
        pa_per_m: ATM_PA / 33.0 / ft,
        water_vapour_pa: 1.607 * ATM_PA / 33.0, // Baker: 1.607 fsw
        descent_rate_m_min: 75.0 * ft,
        ascent_rate_m_min: 30.0 * ft,
        stop_spacing_m: 10.0 * ft,
        last_stop_m: 20.0 * ft,
        ..baker_msw(0.0, 0.0)
    };
    let r = RawVpmbParams {
        critical_radius_n2_um: 0.8,
        critical_radius_he_um: 0.7,
        crushing_onset_atm: 5.4,
        ..RawVpmbParams::default()
    };
    let alg = vpm(r, c);
    let plan = dive(260.0 * ft, 30.0, "15/45", &[]);
    let s = alg.plan(&plan).unwrap();
    let fsw: Vec<String> = s
        .stops
        .iter()
        .map(|x| format!("{:.0}:{}", x.depth_m / ft, x.stop_min))
        .collect();
    println!("260 fsw: {} rt {:.1}", fsw.join(" "), s.runtime_min());
    let want: Vec<(f64, f64)> = [
        (190.0, 1.0),
        (180.0, 1.0),
        (170.0, 1.0),
        (160.0, 1.0),
        (150.0, 2.0),
        (140.0, 3.0),
        (130.0, 3.0),
        (120.0, 3.0),
        (110.0, 4.0),
        (100.0, 6.0),
        (90.0, 7.0),
        (80.0, 9.0),
        (70.0, 10.0),
        (60.0, 16.0),
        (50.0, 22.0),
        (40.0, 32.0),
        (30.0, 52.0),
        (20.0, 777.0),
    ]
    .iter()
    .map(|(d, t)| (d * ft, *t))
    .collect();
    assert_stops(&s, &want, 1.0);
    // In fact every stop matches exactly; the runtime differs only by the slower final ascent.
    assert_stops(&s, &want, 0.0);
    assert!(
        (s.runtime_min() - 984.0).abs() <= 1.5,
        "{}",
        s.runtime_min()
    );
    let zone = alg.start_of_deco_zone_m(&plan).unwrap() / ft;
    assert!((zone - 209.7).abs() <= 0.05 + 1e-9, "{zone}");
}

#[test]
fn more_conservatism_means_deeper_first_stop_and_longer_dive() {
    // Larger critical radii (+2: ×1.12, +4: ×1.35) give smaller allowable gradients: the first
    // stop is never shallower and the dive is longer; on deep dives the first stop moves deeper.
    let dives = [
        dive(30.0, 40.0, "air", &[]),
        dive(45.0, 25.0, "air", &[]),
        dive(60.0, 20.0, "21/35", &[("50", 21.0)]),
        dive(80.0, 30.0, "15/45", &[("36", 33.0), ("o2", 6.0)]),
    ];
    let mut strictly_deeper = 0;
    for plan in &dives {
        let s: Vec<Schedule> = [0, 2, 4]
            .iter()
            .map(|&k| vpm(raw(k), baker_msw(20.0, 10.0)).plan(plan).unwrap())
            .collect();
        for w in s.windows(2) {
            assert!(
                w[1].stops[0].depth_m >= w[0].stops[0].depth_m,
                "{} / {}",
                table(&w[0]),
                table(&w[1])
            );
            assert!(
                w[1].runtime_min() > w[0].runtime_min(),
                "{} / {}",
                table(&w[0]),
                table(&w[1])
            );
            if w[1].stops[0].depth_m > w[0].stops[0].depth_m {
                strictly_deeper += 1;
            }
        }
    }
    assert!(strictly_deeper >= 2, "{strictly_deeper}");
}

#[test]
fn smaller_lambda_gives_longer_deco() {
    // λ sets how much supersaturation volume is tolerated: a smaller λ (Subsurface 6500)
    // relaxes the gradients less than Baker's 7500, so the deco is at least as long.
    let plan = dive(45.0, 25.0, "air", &[]);
    let with = |l: f64| {
        let r = RawVpmbParams {
            critical_volume_lambda_fsw_min: l,
            ..raw(0)
        };
        vpm(r, baker_msw(20.0, 10.0)).plan(&plan).unwrap()
    };
    let (a, b) = (with(6500.0), with(7500.0));
    assert!(
        a.runtime_min() >= b.runtime_min(),
        "{} vs {}",
        table(&a),
        table(&b)
    );
    // Far apart the difference must show.
    assert!(with(3000.0).runtime_min() > with(15000.0).runtime_min());
    // Without the critical-volume algorithm (initial gradients only) the deco is longest.
    let off = RawVpmbParams {
        critical_volume: false,
        ..raw(0)
    };
    let s_off = vpm(off, baker_msw(20.0, 10.0)).plan(&plan).unwrap();
    assert!(s_off.runtime_min() > b.runtime_min());
}

#[test]
fn schedule_is_consistent_and_converts_to_a_pressure_history() {
    let (alg, plan) = baker_trimix_80m();
    let s = alg.plan(&plan).unwrap();
    // Stop runtimes are whole minutes (Baker's rounding) and the legs add up to them.
    let mut t = 0.0;
    let mut k = 0;
    for leg in &s.legs {
        t += leg.duration_s / 60.0;
        if leg.kind == decophantom::algorithm::LegKind::Stop {
            let st = &s.stops[k];
            assert!((st.runtime_min - t).abs() < 1e-9);
            assert!((st.runtime_min - st.runtime_min.round()).abs() < 1e-9);
            k += 1;
        }
    }
    assert_eq!(k, s.stops.len());
    let last = s.legs.last().unwrap();
    assert_eq!(last.end_depth_m, 0.0);
    let h = s.to_pressure_history().unwrap();
    assert!((h.times_s.last().unwrap() / 60.0 - s.runtime_min()).abs() < 1e-9);
}

#[test]
fn no_deco_dive_has_no_stops() {
    let s = vpm(raw(0), baker_msw(20.0, 10.0))
        .plan(&dive(12.0, 20.0, "air", &[]))
        .unwrap();
    assert!(s.stops.is_empty(), "{}", table(&s));
    assert!((s.runtime_min() - (20.0 + 1.2)).abs() < 1e-9);
}

#[test]
fn bad_plans_are_input_errors() {
    let alg = vpm(raw(0), baker_msw(20.0, 10.0));
    let e = alg.plan(&dive(0.0, 20.0, "air", &[])).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("depth"));
    let e = alg.plan(&dive(60.0, 20.0, "10/70", &[])).unwrap_err();
    assert_eq!(e.field.as_deref(), Some("gas"));
    let e = alg
        .plan(&dive(40.0, 20.0, "air", &[("50", 30.0)]))
        .unwrap_err();
    assert_eq!(e.field.as_deref(), Some("deco-gas"));
    assert!(e.message.contains("MOD"), "{e}");
}

#[test]
fn build_reads_params_and_rejects_unknown_keys() {
    let params = toml::Value::Table(
        "conservatism = 2\ncritical_volume_lambda_fsw_min = 6500"
            .parse()
            .unwrap(),
    );
    let alg = vpmb::build("VPM-B +2", params, baker_msw(20.0, 10.0)).unwrap();
    assert_eq!(alg.label(), "VPM-B +2");
    let bad = toml::Value::Table("conservatism = 2\nlambda = 6500".parse().unwrap());
    let e = vpmb::build("x", bad, baker_msw(20.0, 10.0)).err().unwrap();
    assert!(e.contains("lambda"), "{e}");
    let bad = toml::Value::Table("conservatism = 9".parse().unwrap());
    let e = vpmb::build("x", bad, baker_msw(20.0, 10.0)).err().unwrap();
    assert!(e.starts_with("conservatism"), "{e}");
}

#[test]
fn shipped_algorithm_files_parse() {
    // The [params] tables of algorithms/vpmb-*.toml build (the loader itself is elsewhere).
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("algorithms");
    let mut n = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().to_string();
        if !name.starts_with("vpmb-") {
            continue;
        }
        let doc: toml::Table = std::fs::read_to_string(&path).unwrap().parse().unwrap();
        assert_eq!(doc["kind"].as_str(), Some("vpm-b"), "{name}");
        let params = doc
            .get("params")
            .cloned()
            .unwrap_or(toml::Value::Table(Default::default()));
        let lambda = params["critical_volume_lambda_fsw_min"]
            .as_integer()
            .unwrap();
        let preset = doc["conventions"]["preset"].as_str().unwrap();
        assert_eq!(
            lambda,
            if preset == "baker" { 7500 } else { 6500 },
            "{name}"
        );
        vpmb::build(
            doc["label"].as_str().unwrap(),
            params,
            baker_msw(20.0, 10.0),
        )
        .unwrap();
        n += 1;
    }
    assert_eq!(n, 6);
}

#[test]
fn other_rounding_conventions_and_last_stop() {
    let plan = dive(45.0, 25.0, "air", &[]);
    let baker = vpm(raw(0), baker_msw(20.0, 10.0)).plan(&plan).unwrap();
    // Whole minutes at the stop (Subsurface, DecoTengu): every stop leg lasts whole minutes.
    let at_stop = Conventions {
        stop_rounding: StopRounding::WholeMinutesAtStop,
        ..baker_msw(20.0, 10.0)
    };
    let s = vpm(raw(0), at_stop).plan(&plan).unwrap();
    assert!(!s.stops.is_empty());
    for st in &s.stops {
        assert!(
            st.stop_min >= 1.0 && (st.stop_min - st.stop_min.round()).abs() < 1e-9,
            "{}",
            table(&s)
        );
    }
    // No rounding: stops end as soon as the ceiling allows (to the second), never longer in
    // total than whole minutes at the stop.
    let none = Conventions {
        stop_rounding: StopRounding::None,
        min_stop_min: 0.0,
        ..baker_msw(20.0, 10.0)
    };
    let s_none = vpm(raw(0), none).plan(&plan).unwrap();
    assert!(s_none.runtime_min() <= s.runtime_min() + 1e-9);
    // Last stop at 6 m: no 3 m stop, and the 6 m stop is held until the surface is allowed,
    // so it is longer than the 6 m stop with a 3 m last stop.
    let six = Conventions {
        last_stop_m: 6.0,
        ..baker_msw(20.0, 10.0)
    };
    let s6 = vpm(raw(0), six).plan(&plan).unwrap();
    let last = s6.stops.last().unwrap();
    assert_eq!(last.depth_m, 6.0, "{}", table(&s6));
    let six_baker = baker.stops.iter().find(|x| x.depth_m == 6.0).unwrap();
    assert!(
        last.stop_min > six_baker.stop_min,
        "{} / {}",
        table(&s6),
        table(&baker)
    );
}

/// One reference schedule of the cross-check grid.
struct Reference {
    /// Where the reference comes from (repository and path, or issue).
    source: &'static str,
    /// What the dive is.
    dive: &'static str,
    alg: VpmB,
    plan: DivePlan,
    /// Stops (depth m, minutes); empty when the source gives the runtime only.
    stops: Vec<(f64, f64)>,
    /// Runtime at the surface, min (the source's own, with its final-ascent rate).
    runtime_min: f64,
    /// Another published runtime of the same dive (Subsurface's "benchmark"), min.
    benchmark_min: Option<f64>,
    /// Depth unit of the table.
    unit_m: f64,
}

fn fsw_conventions(last_stop_fsw: f64) -> Conventions {
    let ft = 0.3048;
    Conventions {
        surface_pressure_pa: ATM_PA,
        pa_per_m: ATM_PA / 33.0 / ft,
        water_vapour_pa: 1.607 * ATM_PA / 33.0,
        descent_rate_m_min: 75.0 * ft,
        ascent_rate_m_min: 30.0 * ft,
        stop_spacing_m: 10.0 * ft,
        last_stop_m: last_stop_fsw * ft,
        ..baker_msw(0.0, 0.0)
    }
}

fn parse_stops(s: &str, unit_m: f64) -> Vec<(f64, f64)> {
    s.split_whitespace()
        .map(|x| {
            let (d, t) = x.split_once(':').unwrap();
            (d.parse::<f64>().unwrap() * unit_m, t.parse().unwrap())
        })
        .collect()
}

/// Subsurface's testplan conventions for its VPM-B benchmarks (tests/testplan.cpp,
/// setupPrefsVpmb and the setupPlanVpmb* plans): 1 atm, salinity 10 300 g/l, descent
/// 99 m/min (18 m/min for the 30 m dive), every ascent rate 10 m/min, last stop 3 m,
/// conservatism +0, λ 6500 (Subsurface's 199.58 bar·min).
fn subsurface_testplan(descent: f64) -> Conventions {
    Conventions {
        surface_pressure_pa: ATM_PA,
        pa_per_m: 10_300.0 * 9.806_65 / 10.0,
        descent_rate_m_min: descent,
        ascent_rate_m_min: 10.0,
        ..Conventions::preset("subsurface").unwrap()
    }
}

fn references() -> Vec<Reference> {
    let ft = 0.3048;
    let r = |n2: f64, he: f64, onset: f64, lambda: f64, k: i64| RawVpmbParams {
        conservatism: k,
        critical_radius_n2_um: n2,
        critical_radius_he_um: he,
        crushing_onset_atm: onset,
        critical_volume_lambda_fsw_min: lambda,
        ..RawVpmbParams::default()
    };
    let mut out = vec![
        Reference {
            source: "issue #3 (Baker's VPM-B, Baker conventions)",
            dive: "air 30 m / 40 min, +0, λ 7500",
            alg: vpm(raw(0), baker_msw(20.0, 10.0)),
            plan: dive(30.0, 40.0, "air", &[]),
            stops: parse_stops("12:2 9:5 6:8 3:14", 1.0),
            runtime_min: 70.3,
            benchmark_min: None,
            unit_m: 1.0,
        },
        Reference {
            source: "issue #3 (Baker's VPM-B, Baker conventions)",
            dive: "air 45 m / 25 min, +2, λ 7500",
            alg: vpm(raw(2), baker_msw(20.0, 10.0)),
            plan: dive(45.0, 25.0, "air", &[]),
            stops: parse_stops("24:1 21:2 18:3 15:3 12:6 9:7 6:12 3:22", 1.0),
            runtime_min: 83.3,
            benchmark_min: None,
            unit_m: 1.0,
        },
        Reference {
            source: "bwaite/vpmb tests/msw_test/VPMDECO.OUT (Baker's FORTRAN, 02-16-2010)",
            dive: "15/45 80 m / 30 min run, EAN36@33 O2@6, r 0.6/0.5 µm, λ 7500",
            alg: baker_trimix_80m().0,
            plan: baker_trimix_80m().1,
            stops: parse_stops(
                "54:1 51:1 48:1 45:2 42:2 39:2 36:3 33:2 30:1 27:2 24:3 21:4 18:4 15:7 12:8 9:13 6:13 3:23",
                1.0,
            ),
            // Baker ascends at 3 msw/min on O2 from 6 m (ours 10): 125 min less 1.4 min
            runtime_min: 125.0 - 1.4,
            benchmark_min: None,
            unit_m: 1.0,
        },
        Reference {
            source: "bwaite/vpmb tests/msw_simple/expected.json (the FORTRAN schedule as the port's test expects it)",
            dive: "15/45 80 m / 30 min run, no deco gas, r 0.6/0.5 µm, λ 7500",
            alg: vpm(r(0.6, 0.5, 8.2, 7500.0, 0), baker_msw(23.0, 10.0)),
            plan: dive(80.0, 30.0, "15/45", &[]),
            stops: parse_stops(
                "57:1 54:1 51:1 48:1 45:2 42:2 39:2 36:3 33:4 30:4 27:5 24:7 21:8 18:11 15:15 12:22 9:32 6:52 3:103",
                1.0,
            ),
            runtime_min: 308.3,
            benchmark_min: None,
            unit_m: 1.0,
        },
        Reference {
            source: "bwaite/vpmb tests/test1/VPMDECO.OUT (Baker's FORTRAN, 03-21-2010), first dive",
            dive: "15/45 260 fsw / 30 min run, no deco gas, r 0.8/0.7 µm, onset 8.2 atm, λ 7500",
            alg: vpm(r(0.8, 0.7, 8.2, 7500.0, 0), fsw_conventions(20.0)),
            plan: dive(260.0 * ft, 30.0, "15/45", &[]),
            stops: parse_stops(
                "190:1 180:1 170:1 160:1 150:2 140:3 130:2 120:4 110:4 100:5 90:7 80:8 70:11 60:15 50:20 40:30 30:48 20:595",
                ft,
            ),
            // Baker's final ascent from 20 fsw at 10 fsw/min (2.0 min), ours at 30 (0.7)
            runtime_min: 792.0 - 1.3,
            benchmark_min: None,
            unit_m: ft,
        },
        Reference {
            source: "bwaite/vpmb tests/gradient_onset_of_imperm_greater/VPMDECO.OUT (Baker's FORTRAN, 03-01-2010)",
            dive: "15/45 260 fsw / 30 min run, no deco gas, r 0.8/0.7 µm, onset 5.4 atm, λ 7500",
            alg: vpm(r(0.8, 0.7, 5.4, 7500.0, 0), fsw_conventions(20.0)),
            plan: dive(260.0 * ft, 30.0, "15/45", &[]),
            stops: parse_stops(
                "190:1 180:1 170:1 160:1 150:2 140:3 130:3 120:3 110:4 100:6 90:7 80:9 70:10 60:16 50:22 40:32 30:52 20:777",
                ft,
            ),
            runtime_min: 984.0,
            benchmark_min: None,
            unit_m: ft,
        },
    ];
    // Subsurface's VPM-B benchmarks (subsurface/subsurface tests/testplan.cpp): runtimes only,
    // the "known Subsurface runtime" (the reference here) and the "benchmark run time" (its
    // source is not named there; printed); bottom times include the descent.
    for (dive_s, plan, descent, known, bench) in [
        (
            "air 60 m / 30 min, +0, λ 6500",
            dive(60.0, 30.0, "air", &[]),
            99.0,
            139.0,
            141.0,
        ),
        (
            "air 60 m / 30 min, EAN50@21, +0, λ 6500",
            dive(60.0, 30.0, "air", &[("50", 21.0)]),
            99.0,
            96.0,
            95.0,
        ),
        (
            "18/45 60 m / 30 min, EAN50@21, +0, λ 6500",
            dive(60.0, 30.0, "18/45", &[("50", 21.0)]),
            99.0,
            89.0,
            89.0,
        ),
        (
            "air 30 m / 20 min, +0, λ 6500",
            dive(30.0, 20.0, "air", &[]),
            18.0,
            27.0,
            27.0,
        ),
    ] {
        out.push(Reference {
            source: "subsurface/subsurface tests/testplan.cpp (known Subsurface runtime)",
            dive: dive_s,
            alg: vpm(
                RawVpmbParams {
                    critical_volume_lambda_fsw_min: 6500.0,
                    critical_volume_convergence: CvaConvergence::DecoTime,
                    ..raw(0)
                },
                subsurface_testplan(descent),
            ),
            plan,
            stops: vec![],
            runtime_min: known + 20.0 / 60.0,
            benchmark_min: Some(bench + 20.0 / 60.0),
            unit_m: 1.0,
        });
    }
    out
}

/// The cross-check grid: every published VPM-B schedule found (Baker's VPMDECO outputs as
/// shipped with the bwaite/vpmb port, the issue's Baker schedules, Subsurface's benchmark
/// runtimes) planned here, printed as an agreement table (README "VPM-B cross-check").
/// Tolerances, from how the reference implementations agree among themselves (the port's
/// expected.json and Baker's VPMDECO.OUT of the same dive differ by 1 min on one stop;
/// Subsurface accepts 1 % + 1 min on the runtime): stop tables — the same stops, each
/// within ±1 min, the total stop time within ±2 min; runtime-only references — within
/// 1 % + 1 min, except where stated below.
#[test]
fn cross_check_grid_against_published_vpm_b_schedules() {
    println!(
        "| dive | source | first stop ref/ours | max stop diff | stop total ref/ours | runtime ref/ours |"
    );
    println!("|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    let (mut n_stops, mut n_off) = (0, 0);
    for r in references() {
        let s = r.alg.plan(&r.plan).unwrap();
        let got: Vec<(f64, f64)> = s.stops.iter().map(|x| (x.depth_m, x.stop_min)).collect();
        let u = |d: f64| format!("{:.0}", d / r.unit_m);
        let rt = s.runtime_min();
        if r.stops.is_empty() {
            let tol = 0.01 * r.runtime_min + 1.0;
            println!(
                "| {} | {} | – / {} | – | – / {:.0} | {:.1}{} / {:.1} |",
                r.dive,
                r.source,
                u(got[0].0),
                got.iter().map(|x| x.1).sum::<f64>(),
                r.runtime_min,
                r.benchmark_min
                    .map_or(String::new(), |b| format!(" (benchmark {b:.1})")),
                rt
            );
            if (rt - r.runtime_min).abs() > tol {
                failures.push(format!(
                    "{}: runtime {rt:.1} vs {:.1}",
                    r.dive, r.runtime_min
                ));
            }
            continue;
        }
        let same_depths = got.len() == r.stops.len()
            && got
                .iter()
                .zip(&r.stops)
                .all(|(a, b)| (a.0 - b.0).abs() < 1e-6);
        let max_diff = if same_depths {
            got.iter()
                .zip(&r.stops)
                .map(|(a, b)| (a.1 - b.1).abs())
                .fold(0.0, f64::max)
        } else {
            f64::INFINITY
        };
        let (tr, tg) = (
            r.stops.iter().map(|x| x.1).sum::<f64>(),
            got.iter().map(|x| x.1).sum::<f64>(),
        );
        println!(
            "| {} | {} | {} / {} | {} | {:.0} / {:.0} | {:.1} / {:.1} |",
            r.dive,
            r.source,
            u(r.stops[0].0),
            u(got[0].0),
            if same_depths {
                format!("{max_diff:.0}")
            } else {
                format!("stops differ: {}", table(&s))
            },
            tr,
            tg,
            r.runtime_min,
            rt
        );
        if same_depths {
            n_stops += got.len();
            n_off += got.iter().zip(&r.stops).filter(|(a, b)| a.1 != b.1).count();
        }
        if !(same_depths && max_diff <= 1.0 && (tr - tg).abs() <= 2.0) {
            failures.push(format!("{}: {}", r.dive, table(&s)));
        }
    }
    println!("{n_off} of {n_stops} reference stops differ (by one minute)");
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Why ours differed from Subsurface on short air dives (issue 9: "an extra deeper stop and
/// longer shallow stops"): with whole minutes at the stop (Subsurface's rounding) every pass
/// of the critical-volume loop changes the deco time by whole minutes, and Baker's test
/// (stop when any compartment's phase-volume time moved by ≤ 1 min) ends the loop one pass
/// early, on gradients relaxed from a longer schedule. Subsurface's own loop (deco time
/// falling by less than 10 s, then one pass with the updated gradients) gives its known
/// runtime; both rules agree on Baker's own outputs (the grid above uses Baker's rule for
/// them) and on the 60 m dives.
#[test]
fn subsurface_convergence_removes_the_extra_stop() {
    let plan = dive(30.0, 20.0, "air", &[]);
    let with = |conv: CvaConvergence| {
        vpm(
            RawVpmbParams {
                critical_volume_lambda_fsw_min: 6500.0,
                critical_volume_convergence: conv,
                ..raw(0)
            },
            subsurface_testplan(18.0),
        )
        .plan(&plan)
        .unwrap()
    };
    let baker = with(CvaConvergence::Baker);
    let sub = with(CvaConvergence::DecoTime);
    println!(
        "baker rule: {} / deco-time rule: {}",
        table(&baker),
        table(&sub)
    );
    assert_eq!(baker.stops[0].depth_m, 9.0, "{}", table(&baker));
    assert_stops(&sub, &[(6.0, 1.0), (3.0, 4.0)], 0.0);
    // Subsurface's known runtime 27:20 within 1 % + 1 min
    assert!((sub.runtime_min() - (27.0 + 1.0 / 3.0)).abs() <= 0.01 * 27.3 + 1.0);
    // the file key
    let params = toml::Value::Table(
        "critical_volume_convergence = \"deco-time\""
            .parse()
            .unwrap(),
    );
    assert!(vpmb::build("x", params, baker_msw(20.0, 10.0)).is_ok());
    let bad = toml::Value::Table("critical_volume_convergence = \"often\"".parse().unwrap());
    let e = vpmb::build("x", bad, baker_msw(20.0, 10.0)).err().unwrap();
    assert!(
        e.contains("critical_volume_convergence") || e.contains("often"),
        "{e}"
    );
}

/// VPM-B's tissues after a travel-gas descent, against an independent computation in this
/// test: Schreiner's equation for N2 and He on 21/35 from 0 to 60 m and 10/70 from 60 to
/// 110 m (20 m/min), Haldane at 110 m until 20 min of runtime, then the start of the
/// decompression zone (the deepest depth on a straight 10 m/min ascent where a compartment's
/// tension plus Baker's 102 mmHg of other gases reaches ambient), found here by bisection.
/// Half-times as Baker's VPMDECO (ZH-L16 with compartment 1b), Baker's msw conventions.
#[test]
fn travel_gas_descent_loading_matches_an_independent_schreiner_computation() {
    const HT_N2: [f64; 16] = [
        5.0, 8.0, 12.5, 18.5, 27.0, 38.3, 54.3, 77.0, 109.0, 146.0, 187.0, 239.0, 305.0, 390.0,
        498.0, 635.0,
    ];
    const HT_HE: [f64; 16] = [
        1.88, 3.02, 4.72, 6.99, 10.21, 14.48, 20.53, 29.11, 41.2, 55.19, 70.69, 90.34, 115.29,
        147.42, 188.24, 240.03,
    ];
    let (ps, bpm, wv) = (1.01325, 0.1, 0.0493);
    let other = 102.0 / 760.0 * ps;
    let mut plan = dive(110.0, 20.0, "10/70", &[("50", 21.0), ("o2", 6.0)]);
    plan.travel_gases = vec![TravelGas {
        mix: GasMix::parse("21/35").unwrap(),
        from_m: 0.0,
        to_m: 60.0,
    }];
    let alg = vpm(raw(2), baker_msw(20.0, 10.0));
    let s = alg.plan(&plan).unwrap();
    assert!((s.legs[0].gas.he - 0.35).abs() < 1e-12 && s.legs[0].end_depth_m == 60.0);
    assert!((s.legs[1].gas.he - 0.70).abs() < 1e-12 && s.legs[1].end_depth_m == 110.0);
    // Schreiner per gas: p(t) = pi0 + R(t − 1/k) − (pi0 − p0 − R/k)·e^{−kt}
    let sch = |p0: f64, f: f64, amb0: f64, rate: f64, t: f64, ht: f64| {
        let k = std::f64::consts::LN_2 / ht;
        let (pi0, r) = (f * (amb0 - wv), f * rate);
        pi0 + r * (t - 1.0 / k) - (pi0 - p0 - r / k) * (-k * t).exp()
    };
    let (travel, bottom) = (
        GasMix::parse("21/35").unwrap(),
        GasMix::parse("10/70").unwrap(),
    );
    let mut n2 = [0.79 * (ps - wv); 16];
    let mut he = [0.0; 16];
    let legs = [
        (0.0, 60.0, 3.0, travel),
        (60.0, 110.0, 2.5, bottom),
        (110.0, 110.0, 14.5, bottom),
    ];
    for (d0, d1, t, g) in legs {
        let rate = (d1 - d0) * bpm / t;
        for i in 0..16 {
            n2[i] = sch(n2[i], g.n2(), ps + d0 * bpm, rate, t, HT_N2[i]);
            he[i] = sch(he[i], g.he, ps + d0 * bpm, rate, t, HT_HE[i]);
        }
    }
    let pb = ps + 110.0 * bpm;
    let excess = |i: usize, t: f64| {
        sch(n2[i], bottom.n2(), pb, -bpm * 10.0, t, HT_N2[i])
            + sch(he[i], bottom.he, pb, -bpm * 10.0, t, HT_HE[i])
            + other
            - (pb - bpm * 10.0 * t)
    };
    let mut zone: f64 = 0.0;
    for i in 0..16 {
        let (mut lo, mut hi) = (0.0, 11.0);
        if excess(i, lo) >= 0.0 {
            zone = 110.0;
            continue;
        }
        if excess(i, hi) < 0.0 {
            continue;
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if excess(i, mid) < 0.0 {
                lo = mid
            } else {
                hi = mid
            }
        }
        zone = zone.max(110.0 - 10.0 * hi);
    }
    let got = alg.start_of_deco_zone_m(&plan).unwrap();
    println!(
        "start of the deco zone: {got:.4} m (independent {zone:.4} m); {}",
        table(&s)
    );
    assert!((got - zone).abs() < 1e-3, "{got} vs {zone}");
    assert!(s.stops[0].depth_m < zone);
}
