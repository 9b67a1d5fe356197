//! Profile readers: the paper's legacy two-column files, the shipped TOML profiles, and errors.
//! Reference values are read off the files by hand (shared/legacy-profiles/) or computed here
//! from the paper's numbers (Walsh et al. 2017) with the unit constants of NIST SP 811 (psi)
//! and the US Navy msw convention (`units::MSW_PA`).

use std::path::{Path, PathBuf};

use decophantom::gas::GasMix;
use decophantom::profile::{self, legacy, LoadOptions, PressureHistory};
use decophantom::units::{PressureUnit, TimeUnit, ATM_PA, MSW_PA, PSI_PA};

const LEGACY_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/legacy-profiles");

fn legacy_path(name: &str) -> PathBuf {
    Path::new(LEGACY_DIR).join(name)
}

fn opts(t: TimeUnit, p: PressureUnit) -> LoadOptions {
    LoadOptions {
        time_unit: Some(t),
        pressure_unit: Some(p),
        ..LoadOptions::default()
    }
}

fn peak(h: &PressureHistory) -> f64 {
    h.ambient_pa.iter().cloned().fold(f64::MIN, f64::max)
}

fn close(a: f64, b: f64, what: &str) {
    assert!(
        (a - b).abs() <= 1e-9 * b.abs().max(1.0),
        "{what}: {a} vs {b}"
    );
}

/// Every legacy file with the units its README gives, and (points, duration in file units,
/// peak in file units) read off the file by hand.
#[test]
fn every_legacy_file_reads_with_hand_checked_numbers() {
    use PressureUnit::{Msw, PsiGauge};
    use TimeUnit::{Min, S};
    #[rustfmt::skip]
    let table: &[(&str, TimeUnit, PressureUnit, usize, f64, f64)] = &[
        ("100m_1deco_stop.txt", Min, Msw, 7, 80.0, 100.0),
        ("1hr_45m_10sec_ascent.txt", Min, Msw, 5, 222.16, 45.0),
        ("1hr_45m_2min_ascent.txt", Min, Msw, 5, 224.0, 45.0),
        ("1min_oscill.txt", Min, PsiGauge, 8, 7.0, 8.9),
        ("30sec_oscill.txt", Min, PsiGauge, 11, 5.0, 20.0),
        ("ascent_match_4hr_ex.txt", Min, PsiGauge, 3, 180.0, 79.09),
        ("ascent_only_55_in_2mins.txt", Min, Msw, 3, 60.0, 55.0),
        ("ascent_only_exp_match.txt", Min, PsiGauge, 3, 240.0, 130.0),
        ("ascent_only_from_sat_10psi_s.txt", S, PsiGauge, 3, 10800.0, 130.0),
        ("comp_50psi_1min.txt", Min, PsiGauge, 5, 3.3, 50.0),
        ("comp_50psi_2min.txt", Min, PsiGauge, 5, 4.2, 50.0),
        ("const_external_press.txt", Min, PsiGauge, 3, 1.0, 10.0),
        ("dive_test2_less_agg.txt", Min, Msw, 7, 300.0, 55.0),
        ("dive_test2_more_agg.txt", Min, Msw, 7, 80.0, 55.0),
        ("sat_30m_8m_min_ascent_sensitivity.txt", Min, Msw, 3, 93.75, 30.0),
        ("sat_30m_8m_min_ascent_sensitivity_partial.txt", Min, Msw, 2, 3.75, 30.0),
        ("slow_decr_external_press.txt", Min, PsiGauge, 3, 1.0, 30.0),
        ("slow_inc_external_press.txt", Min, PsiGauge, 3, 1.0, 30.0),
        ("test1.txt", Min, PsiGauge, 3, 1.0, 10.0),
        ("test_compression_only.txt", Min, PsiGauge, 3, 300.0, 130.0),
    ];
    // Every .txt file in the folder is in the table (a new file must get its numbers here).
    let mut on_disk: Vec<String> = std::fs::read_dir(LEGACY_DIR)
        .expect("shared/legacy-profiles beside the repository")
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".txt"))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = table.iter().map(|r| r.0.to_string()).collect();
    listed.sort();
    assert_eq!(on_disk, listed);

    for &(name, tu, pu, n, end, top) in table {
        let h = profile::load(&legacy_path(name), &opts(tu, pu)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(h.times_s.len(), n, "{name}");
        close(h.duration_s(), end * tu.seconds(), name);
        close(peak(&h), pu.to_absolute_pa(top, ATM_PA), name);
        assert_eq!(h.label, name.trim_end_matches(".txt"));
        assert_eq!(h.gas_at(0.0), GasMix::AIR);
    }
}

#[test]
fn thirty_second_oscillation_values_by_hand() {
    let h = profile::load(
        &legacy_path("30sec_oscill.txt"),
        &opts(TimeUnit::Min, PressureUnit::PsiGauge),
    )
    .unwrap();
    // File line 2 is "0.5 \t20": 0.5 min = 30 s at 20 psi gauge = 101325 + 20·6894.757 Pa.
    assert_eq!(h.times_s.len(), 11);
    close(h.times_s[1], 30.0, "t1");
    close(h.ambient_pa[1], 101_325.0 + 20.0 * 6_894.757_293_168, "p1");
    // Line 11 "5.0\t0.0": 300 s back at the surface.
    close(h.times_s[10], 300.0, "t10");
    close(h.ambient_pa[10], 101_325.0, "p10");
    // Halfway up the first ramp (15 s): 10 psi gauge.
    close(h.ambient(15.0), 101_325.0 + 10.0 * PSI_PA, "p(15 s)");
}

#[test]
fn crlf_and_space_separated_files_read() {
    // dive_test2_less_agg.txt: space separated with \r\n, last line tab separated without newline.
    let h = profile::load(
        &legacy_path("dive_test2_less_agg.txt"),
        &opts(TimeUnit::Min, PressureUnit::Msw),
    )
    .unwrap();
    // Line 2 "2.0 55.0": 120 s at 55 msw = 101325 + 55·10^4 Pa.
    close(h.times_s[1], 120.0, "t");
    close(h.ambient_pa[1], ATM_PA + 55.0 * MSW_PA, "p");
    // comp_50psi_1min.txt line 1 "0.0\t0.0 \t" (trailing space and tab), line 2 "1.0 \t50.0".
    let h = profile::load(
        &legacy_path("comp_50psi_1min.txt"),
        &opts(TimeUnit::Min, PressureUnit::PsiGauge),
    )
    .unwrap();
    close(h.ambient_pa[0], ATM_PA, "p0");
    close(h.ambient_pa[1], ATM_PA + 50.0 * PSI_PA, "p1");
}

/// The shipped TOML profiles: duration and peak from the paper's numbers.
#[test]
fn every_shipped_toml_profile_matches_the_paper() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("profiles");
    let psi = |x: f64| ATM_PA + x * PSI_PA;
    // Fig. 5: 130 psi at 1 psi/s = 130 s; 4 h; 130 psi at 5 psi/s = 26 s; 2 h.
    let fig5 = 130.0 + 4.0 * 3600.0 + 26.0 + 2.0 * 3600.0;
    // Fig. 6a: 130 psi at 6.9e4 Pa/s, 20 min, 130 psi at 8.9e4 Pa/s, 2 h.
    let fig6 = 130.0 * PSI_PA / 6.9e4 + 20.0 * 60.0 + 130.0 * PSI_PA / 8.9e4 + 2.0 * 3600.0;
    let expected: &[(&str, f64, f64)] = &[
        ("oscillation-30s.toml", 5.0 * 60.0, psi(20.0)), // §4.1: 5 cycles of 60 s
        ("oscillation-1min.toml", 7.0 * 60.0, psi(8.9)), // 1min_oscill.txt: 7 min
        ("fig5-dive.toml", fig5, psi(130.0)),
        ("fig6-dive-20min.toml", fig6, psi(130.0)),
        (
            "sensitivity-30m.toml",
            (3.75 + 90.0) * 60.0,
            ATM_PA + 30.0 * MSW_PA,
        ), // §2.3.1
    ];
    let mut found = 0;
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("toml") {
            continue;
        }
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let (_, dur, top) = expected.iter().find(|e| e.0 == name).unwrap_or_else(|| {
            panic!("profiles/{name} has no expected duration/peak in this test")
        });
        let p = profile::toml::read(&path).unwrap_or_else(|e| panic!("{e}"));
        close(p.history.duration_s(), *dur, &name);
        close(peak(&p.history), *top, &name);
        assert!(!p.description.is_empty(), "{name} needs a description");
        assert_eq!(p.history.gas_at(0.0), GasMix::AIR, "{name}");
        assert_eq!(p.history.vapour_pa, 0.0, "{name}");
        found += 1;
    }
    assert_eq!(found, expected.len());
}

#[test]
fn fig5_profile_ramps_at_the_stated_rates() {
    let h = profile::load(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("profiles/fig5-dive.toml"),
        &LoadOptions::default(),
    )
    .unwrap();
    close(h.rate(10.0), PSI_PA, "1 psi/s compression");
    close(
        h.rate(130.0 + 14400.0 + 1.0),
        -5.0 * PSI_PA,
        "5 psi/s ascent",
    );
    // The ascent matches the paper's legacy file ascent_only_from_sat_10psi_s.txt (s, psi gauge).
    let leg = profile::load(
        &legacy_path("ascent_only_from_sat_10psi_s.txt"),
        &opts(TimeUnit::S, PressureUnit::PsiGauge),
    )
    .unwrap();
    close(
        leg.rate(1.0),
        h.rate(130.0 + 14400.0 + 1.0),
        "same ascent rate",
    );
}

#[test]
fn toml_and_legacy_forms_agree() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    for (toml, txt, tu, pu) in [
        (
            "oscillation-30s.toml",
            "30sec_oscill.txt",
            TimeUnit::Min,
            PressureUnit::PsiGauge,
        ),
        (
            "oscillation-1min.toml",
            "1min_oscill.txt",
            TimeUnit::Min,
            PressureUnit::PsiGauge,
        ),
        (
            "sensitivity-30m.toml",
            "sat_30m_8m_min_ascent_sensitivity.txt",
            TimeUnit::Min,
            PressureUnit::Msw,
        ),
    ] {
        let a = profile::load(&root.join("profiles").join(toml), &LoadOptions::default()).unwrap();
        let b = profile::load(&legacy_path(txt), &opts(tu, pu)).unwrap();
        assert_eq!(a.times_s.len(), b.times_s.len(), "{toml}");
        for i in 0..a.times_s.len() {
            close(a.times_s[i], b.times_s[i], toml);
            close(a.ambient_pa[i], b.ambient_pa[i], toml);
        }
    }
}

#[test]
fn load_refuses_missing_or_superfluous_units() {
    let e = profile::load(&legacy_path("test1.txt"), &LoadOptions::default()).unwrap_err();
    assert!(e.message.contains("--units"), "{e}");
    let toml = Path::new(env!("CARGO_MANIFEST_DIR")).join("profiles/oscillation-30s.toml");
    let e = profile::load(&toml, &opts(TimeUnit::S, PressureUnit::Pa)).unwrap_err();
    assert!(e.message.contains("states its own units"), "{e}");
    let e = profile::load(
        Path::new("/nonexistent/x.txt"),
        &opts(TimeUnit::S, PressureUnit::Pa),
    )
    .unwrap_err();
    assert!(e.to_string().contains("/nonexistent/x.txt"), "{e}");
}

#[test]
fn bad_files_are_refused_with_file_and_line() {
    let dir = std::env::temp_dir().join(format!("decophantom-profiles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let txt = dir.join("backwards.txt");
    std::fs::write(&txt, "0\t0\n1\t10\n0.5\t10\n").unwrap();
    let e = profile::load(&txt, &opts(TimeUnit::Min, PressureUnit::PsiGauge)).unwrap_err();
    assert_eq!(e.line, Some(3));
    assert!(
        e.to_string().starts_with(&format!("{}:3:", txt.display())),
        "{e}"
    );

    let toml = dir.join("typo.toml");
    std::fs::write(
        &toml,
        "time_unit = \"s\"\npressure_unit = \"bar\"\npoints = [[0, 1]]\nrepaet = 2\n",
    )
    .unwrap();
    let e = profile::load(&toml, &LoadOptions::default()).unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(4), Some("repaet")),
        "{e}"
    );

    let toml = dir.join("negative.toml");
    std::fs::write(
        &toml,
        "time_unit = \"min\"\npressure_unit = \"msw\"\npoints = [\n  [0, 0],\n  [-1, 10],\n]\n",
    )
    .unwrap();
    let e = profile::load(&toml, &LoadOptions::default()).unwrap_err();
    assert_eq!(e.line, Some(5), "{e}");
    assert!(e.message.contains("negative time"), "{e}");

    // Gas and surface pressure for a legacy file come from the options.
    let h = legacy::read(
        &legacy_path("test1.txt"),
        &legacy::LegacyUnits {
            gas: GasMix::parse("ean32").unwrap(),
            surface_pa: 9.0e4,
            ..legacy::LegacyUnits::new(TimeUnit::Min, PressureUnit::PsiGauge)
        },
    )
    .unwrap();
    close(h.ambient_pa[0], 9.0e4, "altitude surface");
    std::fs::remove_dir_all(&dir).unwrap();
}

// ---------------------------------------------------------------------------------------------
// Dive-log import (Subsurface XML, UDDF). Reference numbers: shared/dive-files/README.md
// ("What each file contains", depths in m, times in min), which were measured with an
// independent throw-away parser; rounding there is to 0.1 m and 0.1 min.

mod divelogs {
    use super::close;
    use decophantom::gas::GasMix;
    use decophantom::profile::divelog::{self, Format, ImportedDive};
    use decophantom::units::STANDARD_GRAVITY;
    use std::path::{Path, PathBuf};

    const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/dive-files");

    fn read(name: &str) -> Vec<ImportedDive> {
        let p: PathBuf = Path::new(DIR).join(name);
        divelog::read(&p).unwrap_or_else(|e| panic!("{e}"))
    }

    fn gas(s: &str) -> GasMix {
        GasMix::parse(s).unwrap()
    }

    /// Max depth (m) and sample span (min) against the README, to its rounding.
    fn check(d: &ImportedDive, max_m: f64, minutes: f64) {
        assert!(
            (d.max_depth_m() - max_m).abs() <= 0.05 + 1e-9,
            "{}: max {}",
            d.label,
            d.max_depth_m()
        );
        assert!(
            (d.duration_s() / 60.0 - minutes).abs() <= 0.05 + 1e-9,
            "{}: {} min",
            d.label,
            d.duration_s() / 60.0
        );
        // Every open-circuit dive becomes a valid pressure history.
        let h = d.history(0.0).unwrap();
        close(h.duration_s(), d.duration_s(), &d.label);
    }

    #[test]
    fn subsurface_planned_trimix_test51() {
        let ds = read("subsurface__test51.xml");
        assert_eq!(ds.len(), 1);
        let d = &ds[0];
        assert!(d.planned && !d.closed_circuit && d.format == Format::Subsurface);
        check(d, 110.0, 123.5);
        // 47 samples, two of them at 94:00 merged into one.
        assert_eq!(d.samples.len(), 46);
        assert_eq!(d.samples[0], (0.0, 0.0));
        // <surface pressure='0.896 bar'/>, <water salinity='1025 g/l'/>.
        close(d.surface_pa, 0.896e5, "surface");
        close(d.density_kg_m3, 1025.0, "density");
        let mixes = ["ean55", "30/22", "31/30", "11/60", "o2"].map(gas);
        assert_eq!(d.gases, mixes);
        assert_eq!(d.initial_gas, 0);
        // Tx31/30 @10:01, Tx11/60 @14:01, Tx31/30 @36:21, EAN55 @49:21, O2 @80:21.
        let want = [
            (601.0, 2),
            (841.0, 3),
            (2181.0, 2),
            (2961.0, 0),
            (4821.0, 4),
        ];
        assert_eq!(d.switches, want);
        assert_eq!(d.gas_at(700.0), mixes[2]);
        assert_eq!(d.gas_at(5000.0), mixes[4]);
        // At 110 m: 0.896 bar + 110 m · 1025 kg/m³ · g.
        let h = d.history(0.0).unwrap();
        let top = h.ambient_pa.iter().cloned().fold(0.0, f64::max);
        close(
            top,
            0.896e5 + 110.0 * 1025.0 * STANDARD_GRAVITY,
            "ambient at 110 m",
        );
        assert_eq!(h.gas_at(900.0), mixes[3]);
    }

    #[test]
    fn subsurface_repetitive_ostc_dives() {
        let ds = read("subsurface__ostc.xml");
        assert_eq!(ds.len(), 2);
        check(&ds[0], 26.1, 76.9);
        check(&ds[1], 27.0, 70.8);
        for (d, surface) in ds.iter().zip([1.008e5, 1.009e5]) {
            // EAN32 from the gaschange at 0:02 = the first sample.
            assert_eq!(d.gases[d.initial_gas], gas("ean32"));
            assert!(d.switches.is_empty());
            close(d.surface_pa, surface, "surface");
            // No salinity: the sea-water default, and a note says so.
            close(d.density_kg_m3, divelog::DEFAULT_DENSITY_KG_M3, "density");
            assert!(d.notes.iter().any(|n| n.contains("water density")));
            // First sample 0:02 at 2.465 / 2.505 m: a surface point is prepended.
            assert_eq!(d.samples[0], (0.0, 0.0));
            assert_eq!(d.samples[1].0, 2.0);
        }
        close(ds[0].samples[1].1, 2.465, "first depth");
        assert_eq!(ds[0].start.as_deref(), Some("2017-02-03 06:58:00"));
        assert_eq!(ds[1].start.as_deref(), Some("2017-02-03 10:24:00"));
    }

    #[test]
    fn subsurface_trimix_and_rebreather_dives() {
        let ds = read("subsurface__test40-42.xml");
        assert_eq!(ds.len(), 3);
        let d = ds
            .iter()
            .find(|d| d.number.as_deref() == Some("417"))
            .unwrap();
        check(d, 79.6, 114.7);
        assert_eq!(d.samples.len(), 689);
        // Header says 81.5 m; the profile's maximum is 79.6 m.
        assert_eq!(d.stated_max_depth_m, Some(81.5));
        // 7 gaschange events: the start on 50/6 and six switches, back and forth, O2 at 72:00.
        assert_eq!(d.gases[d.initial_gas], gas("50/6"));
        assert_eq!(d.switches.len(), 6);
        assert_eq!(d.switches.last(), Some(&(72.0 * 60.0, 6)));
        assert_eq!(d.gas_at(72.0 * 60.0), gas("o2"));
        assert_eq!(d.gas_at(20.0 * 60.0), gas("16/55"));
        // The two OSTC 3 CCR dives: read, flagged, refused as histories.
        let ccr: Vec<_> = ds.iter().filter(|d| d.closed_circuit).collect();
        assert_eq!(ccr.len(), 2);
        for d in ccr {
            assert!((d.max_depth_m() - 39.0).abs() < 0.05, "{}", d.max_depth_m());
            close(d.density_kg_m3, 1000.0, "fresh water");
            let e = d.history(0.0).unwrap_err();
            assert!(e.message.contains("closed-circuit"), "{e}");
        }
    }

    #[test]
    fn subsurface_v1_value_only_gas_changes() {
        let ds = read("subsurface__test20.xml");
        assert_eq!(ds.len(), 1);
        let d = &ds[0];
        check(d, 70.0, 29.5);
        assert_eq!(d.samples.len(), 7);
        close(d.stated_duration_s.unwrap(), 30.0 * 60.0, "duration 30:00");
        assert_eq!(d.gases, ["21/30", "12/70", "ean50"].map(gas));
        // value='12' → Tx12/70, '21' → Tx21/30, '50' → EAN50 (nearest O2, He unknown).
        assert_eq!(d.switches, [(180.0, 1), (900.0, 0), (1230.0, 2)]);
    }

    #[test]
    fn uddf_dialects() {
        // UDDF 2.2.0 (Diving Log 5.0): no namespace, flat dive children, density 1030.
        let ds = read("subsurface-history__TestDiveDiveLog5.08.uddf");
        assert_eq!(ds.len(), 1);
        check(&ds[0], 24.7, 32.0);
        assert_eq!(ds[0].samples.len(), 65);
        assert_eq!(ds[0].gases, [GasMix::AIR]);
        close(ds[0].density_kg_m3, 1030.0, "density");
        assert_eq!(ds[0].format, Format::Uddf);

        // Kenozooid logbook: no gas definitions → air.
        let ds = read("kenozooid__logbook.uddf");
        assert_eq!(ds.len(), 2);
        check(&ds[0], 30.1, 64.5);
        check(&ds[1], 29.4, 61.8);
        assert_eq!((ds[0].samples.len(), ds[1].samples.len()), (387, 371));
        assert_eq!(ds[0].stated_max_depth_m, Some(30.3));
        assert!(ds.iter().all(|d| d.gases == [GasMix::AIR]));

        // OSTC dump: O2 in percent; dive 1 switches air → EAN32 at 20 s (13 m).
        let ds = read("kenozooid__ostc-dump-02.uddf");
        assert_eq!(ds.len(), 2);
        check(&ds[0], 33.0, 67.5);
        check(&ds[1], 45.0, 63.5);
        assert_eq!(ds[0].gases[ds[0].initial_gas], GasMix::AIR);
        assert_eq!(ds[0].switches.len(), 1);
        assert_eq!(ds[0].switches[0].0, 20.0);
        assert_eq!(ds[0].gases[ds[0].switches[0].1], gas("ean32"));
        let at20 = ds[0].samples.iter().find(|s| s.0 == 20.0).unwrap();
        close(at20.1, 13.0, "depth at the switch");
        assert!(ds[1].switches.is_empty() && ds[1].gases[ds[1].initial_gas] == GasMix::AIR);

        // Shearwater: EAN32, bogus 70-bar surface pressure replaced, density 1020 from
        // <tablegeneration> linked to the dive.
        let ds = read("swift-uddf__dive31.uddf");
        assert_eq!(ds.len(), 1);
        check(&ds[0], 17.0, 37.5);
        assert_eq!(ds[0].samples.len(), 226);
        assert_eq!(ds[0].gases, [gas("ean32")]);
        close(ds[0].surface_pa, 101_325.0, "defaulted surface");
        assert!(ds[0].notes.iter().any(|n| n.contains("implausible")));
        close(ds[0].density_kg_m3, 1020.0, "density");
    }

    #[test]
    fn bad_dive_logs_are_refused_with_a_line() {
        let p = Path::new("bad.uddf");
        let e = divelog::parse(
            "<uddf>\n<gasdefinitions><mix id='a'><o2>0.21</o2></mix></gasdefinitions>\n<profiledata><repetitiongroup><dive>\n<samples>\n<waypoint><depth>0</depth><divetime>0</divetime><switchmix ref='nope'/></waypoint>\n</samples></dive></repetitiongroup></profiledata></uddf>",
            p,
        )
        .unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(5), Some("switchmix")),
            "{e}"
        );
        let e = divelog::parse("<divelog>\n<dives>\n<dive>\n</dives>", p).unwrap_err();
        assert!(e.message.contains("XML"), "{e}");
        let e = divelog::parse("<divelog><dives></dives></divelog>", p).unwrap_err();
        assert!(e.message.contains("no dive"), "{e}");
        let e = divelog::parse(
            "<divelog><dives><dive><divecomputer>\n<sample time='-1:00 min' depth='3 m'/>\n</divecomputer></dive></dives></divelog>",
            p,
        )
        .unwrap_err();
        assert_eq!(e.line, Some(2), "{e}");
    }
}

#[test]
fn load_dispatches_dive_logs() {
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/dive-files"));
    // One dive: no number needed. test20: 70 m, 1030 kg/m³ default, 101325 Pa default.
    let h = profile::load(&dir.join("subsurface__test20.xml"), &LoadOptions::default()).unwrap();
    let top = h.ambient_pa.iter().cloned().fold(0.0, f64::max);
    close(
        top,
        ATM_PA + 70.0 * 1030.0 * decophantom::units::STANDARD_GRAVITY,
        "70 m",
    );
    // Two dives: a number is required and checked.
    let ostc = dir.join("subsurface__ostc.xml");
    let e = profile::load(&ostc, &LoadOptions::default()).unwrap_err();
    assert!(e.message.contains("2 dives"), "{e}");
    let two = LoadOptions {
        dive: Some(2),
        ..LoadOptions::default()
    };
    let h = profile::load(&ostc, &two).unwrap();
    assert!(h.label.contains("10:24"), "{}", h.label);
    let three = LoadOptions {
        dive: Some(3),
        ..LoadOptions::default()
    };
    assert!(profile::load(&ostc, &three).is_err());
    assert!(profile::load(&ostc, &opts(TimeUnit::S, PressureUnit::Pa)).is_err());
    assert!(profile::load(&legacy_path("test1.txt"), &two).is_err());
}
