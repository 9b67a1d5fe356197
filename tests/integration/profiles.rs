//! Profile readers: the paper's legacy two-column files, the shipped TOML profiles, and errors.
//! Reference values are read off the files by hand (the project's own `tests/data/legacy/`,
//! and the authors' published files in `../shared/legacy-profiles/` when that folder is
//! present) or computed here from the paper's numbers (Walsh et al. 2017) with the unit
//! constants of NIST SP 811 (psi) and the US Navy msw convention (`units::MSW_PA`).

use std::path::{Path, PathBuf};

use crate::common::{data, shared};
use decophantom::gas::GasMix;
use decophantom::profile::{self, legacy, LoadOptions, PressureHistory};
use decophantom::units::{PressureUnit, TimeUnit, ATM_PA, MSW_PA, PSI_PA};

/// One of the project's own legacy files (`tests/data/legacy/`).
fn legacy_path(name: &str) -> PathBuf {
    data("legacy").join(name)
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

/// (file, time unit, pressure unit, points, duration in file units, peak in file units).
type LegacyRow = (&'static str, TimeUnit, PressureUnit, usize, f64, f64);

/// Every `.txt` file of `dir` is in `table` (a new file must get its numbers there), and
/// each reads with the numbers read off it by hand.
fn check_legacy_folder(dir: &Path, table: &[LegacyRow]) {
    let mut on_disk: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".txt"))
        .collect();
    on_disk.sort();
    let mut listed: Vec<String> = table.iter().map(|r| r.0.to_string()).collect();
    listed.sort();
    assert_eq!(on_disk, listed);

    for &(name, tu, pu, n, end, top) in table {
        let h = profile::load(&dir.join(name), &opts(tu, pu)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(h.times_s.len(), n, "{name}");
        close(h.duration_s(), end * tu.seconds(), name);
        close(peak(&h), pu.to_absolute_pa(top, ATM_PA), name);
        assert_eq!(h.label, name.trim_end_matches(".txt"));
        assert_eq!(h.gas_at(0.0), GasMix::AIR);
    }
}

/// The project's own legacy files (tests/data/legacy/README.md gives their units and quirks);
/// points, last time and peak counted off each file by hand.
#[test]
fn every_own_legacy_file_reads_with_hand_checked_numbers() {
    use PressureUnit::{Msw, PsiGauge};
    use TimeUnit::{Min, S};
    #[rustfmt::skip]
    let table: &[LegacyRow] = &[
        ("ascent-5psi-per-s.txt", S, PsiGauge, 3, 600.0, 130.0),
        ("chamber-40psi-trailing-blanks.txt", Min, PsiGauge, 5, 4.5, 40.0),
        ("dive-40m-two-stops.txt", Min, Msw, 9, 60.0, 40.0),
        ("oscillation-1min.txt", Min, PsiGauge, 8, 7.0, 8.9),
        ("oscillation-30s.txt", Min, PsiGauge, 11, 5.0, 20.0),
        ("sensitivity-30m.txt", Min, Msw, 3, 93.75, 30.0),
        ("step-10psi.txt", Min, PsiGauge, 3, 1.0, 10.0),
    ];
    check_legacy_folder(&data("legacy"), table);
}

/// The authors' published files, with the units their README gives (run only where
/// `../shared/legacy-profiles/` is present).
#[test]
fn every_published_legacy_file_reads_with_hand_checked_numbers() {
    use PressureUnit::{Msw, PsiGauge};
    use TimeUnit::{Min, S};
    let Some(dir) = shared("legacy-profiles") else {
        return;
    };
    #[rustfmt::skip]
    let table: &[LegacyRow] = &[
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
    check_legacy_folder(&dir, table);
    // The published oscillation file and the project's own agree point for point.
    let u = opts(TimeUnit::Min, PressureUnit::PsiGauge);
    let a = profile::load(&dir.join("30sec_oscill.txt"), &u).unwrap();
    let b = profile::load(&legacy_path("oscillation-30s.txt"), &u).unwrap();
    assert_eq!(a.times_s, b.times_s);
    assert_eq!(a.ambient_pa, b.ambient_pa);
}

#[test]
fn thirty_second_oscillation_values_by_hand() {
    let h = profile::load(
        &legacy_path("oscillation-30s.txt"),
        &opts(TimeUnit::Min, PressureUnit::PsiGauge),
    )
    .unwrap();
    // File line 2 is "0.5\t20 ": 0.5 min = 30 s at 20 psi gauge = 101325 + 20·6894.757 Pa.
    assert_eq!(h.times_s.len(), 11);
    close(h.times_s[1], 30.0, "t1");
    close(h.ambient_pa[1], 101_325.0 + 20.0 * 6_894.757_293_168, "p1");
    // Line 11 "5.0\t0" (no final newline): 300 s back at the surface.
    close(h.times_s[10], 300.0, "t10");
    close(h.ambient_pa[10], 101_325.0, "p10");
    // Halfway up the first ramp (15 s): 10 psi gauge.
    close(h.ambient(15.0), 101_325.0 + 10.0 * PSI_PA, "p(15 s)");
}

#[test]
fn crlf_space_separated_bom_and_trailing_blank_files_read() {
    // dive-40m-two-stops.txt: space separated with \r\n, last line "60.0\t0.0" tab separated
    // without a newline.
    let h = profile::load(
        &legacy_path("dive-40m-two-stops.txt"),
        &opts(TimeUnit::Min, PressureUnit::Msw),
    )
    .unwrap();
    // Line 2 "2.0 40.0": 120 s at 40 msw = 101325 + 40·10^4 Pa.
    close(h.times_s[1], 120.0, "t");
    close(h.ambient_pa[1], ATM_PA + 40.0 * MSW_PA, "p");
    close(h.times_s[8], 3600.0, "last line");
    // chamber-40psi-trailing-blanks.txt line 1 "0.0\t0.0 \t" (trailing space and tab),
    // line 2 "1.5 \t40.0", and an empty line at the end.
    let h = profile::load(
        &legacy_path("chamber-40psi-trailing-blanks.txt"),
        &opts(TimeUnit::Min, PressureUnit::PsiGauge),
    )
    .unwrap();
    close(h.ambient_pa[0], ATM_PA, "p0");
    close(h.times_s[1], 90.0, "t1");
    close(h.ambient_pa[1], ATM_PA + 40.0 * PSI_PA, "p1");
    // sensitivity-30m.txt starts with a UTF-8 byte-order mark: line 1 "0\t30" is 30 msw at 0 s.
    let h = profile::load(
        &legacy_path("sensitivity-30m.txt"),
        &opts(TimeUnit::Min, PressureUnit::Msw),
    )
    .unwrap();
    close(h.times_s[0], 0.0, "t0");
    close(h.ambient_pa[0], ATM_PA + 30.0 * MSW_PA, "p0 after the BOM");
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
    // The ascent matches tests/data/legacy/ascent-5psi-per-s.txt (s, psi gauge: 130 psi to 0
    // in 26 s, the ascent of the paper's legacy file ascent_only_from_sat_10psi_s.txt).
    let leg = profile::load(
        &legacy_path("ascent-5psi-per-s.txt"),
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
            "oscillation-30s.txt",
            TimeUnit::Min,
            PressureUnit::PsiGauge,
        ),
        (
            "oscillation-1min.toml",
            "oscillation-1min.txt",
            TimeUnit::Min,
            PressureUnit::PsiGauge,
        ),
        (
            "sensitivity-30m.toml",
            "sensitivity-30m.txt",
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
    let e = profile::load(&legacy_path("step-10psi.txt"), &LoadOptions::default()).unwrap_err();
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
        &legacy_path("step-10psi.txt"),
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
// Dive-log import (Subsurface XML, UDDF) over the third-party files in ../shared/dive-files
// (real logs, not redistributable, run only where that folder is present). Reference numbers:
// shared/dive-files/README.md ("What each file contains", depths in m, times in min), which
// were measured with an independent throw-away parser; rounding there is to 0.1 m and 0.1 min.
// The project's own files with the same quirks are tested in `own_divelogs` below.

mod published_divelogs {
    use super::close;
    use crate::common::shared;
    use decophantom::gas::GasMix;
    use decophantom::profile::divelog::{self, Format, ImportedDive};
    use decophantom::units::STANDARD_GRAVITY;
    use std::path::{Path, PathBuf};

    fn read(dir: &Path, name: &str) -> Vec<ImportedDive> {
        let p: PathBuf = dir.join(name);
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
        let Some(dir) = shared("dive-files") else {
            return;
        };
        let ds = read(&dir, "subsurface__test51.xml");
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
        let Some(dir) = shared("dive-files") else {
            return;
        };
        let ds = read(&dir, "subsurface__ostc.xml");
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
        let Some(dir) = shared("dive-files") else {
            return;
        };
        let ds = read(&dir, "subsurface__test40-42.xml");
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
        let Some(dir) = shared("dive-files") else {
            return;
        };
        let ds = read(&dir, "subsurface__test20.xml");
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
        let Some(dir) = shared("dive-files") else {
            return;
        };
        // UDDF 2.2.0 (Diving Log 5.0): no namespace, flat dive children, density 1030.
        let ds = read(&dir, "subsurface-history__TestDiveDiveLog5.08.uddf");
        assert_eq!(ds.len(), 1);
        check(&ds[0], 24.7, 32.0);
        assert_eq!(ds[0].samples.len(), 65);
        assert_eq!(ds[0].gases, [GasMix::AIR]);
        close(ds[0].density_kg_m3, 1030.0, "density");
        assert_eq!(ds[0].format, Format::Uddf);

        // Kenozooid logbook: no gas definitions → air.
        let ds = read(&dir, "kenozooid__logbook.uddf");
        assert_eq!(ds.len(), 2);
        check(&ds[0], 30.1, 64.5);
        check(&ds[1], 29.4, 61.8);
        assert_eq!((ds[0].samples.len(), ds[1].samples.len()), (387, 371));
        assert_eq!(ds[0].stated_max_depth_m, Some(30.3));
        assert!(ds.iter().all(|d| d.gases == [GasMix::AIR]));

        // OSTC dump: O2 in percent; dive 1 switches air → EAN32 at 20 s (13 m).
        let ds = read(&dir, "kenozooid__ostc-dump-02.uddf");
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
        let ds = read(&dir, "swift-uddf__dive31.uddf");
        assert_eq!(ds.len(), 1);
        check(&ds[0], 17.0, 37.5);
        assert_eq!(ds[0].samples.len(), 226);
        assert_eq!(ds[0].gases, [gas("ean32")]);
        close(ds[0].surface_pa, 101_325.0, "defaulted surface");
        assert!(ds[0].notes.iter().any(|n| n.contains("implausible")));
        close(ds[0].density_kg_m3, 1020.0, "density");
    }
}

// ---------------------------------------------------------------------------------------------
// Dive-log import over the project's own files, tests/data/divelogs/ (written by hand for
// these tests; tests/data/README.md lists the quirk each one carries, modelled on the real
// files described in shared/dive-files/FORMATS.md). Every reference number below is read off
// the file named in the test: depths in m, times as written (m:ss min or s).

mod own_divelogs {
    use super::close;
    use crate::common::data;
    use decophantom::gas::GasMix;
    use decophantom::profile::divelog::{self, Format, ImportedDive};
    use decophantom::units::{ATM_PA, STANDARD_GRAVITY};
    use std::path::Path;

    fn read(name: &str) -> Vec<ImportedDive> {
        divelog::read(&data("divelogs").join(name)).unwrap_or_else(|e| panic!("{e}"))
    }

    fn gas(s: &str) -> GasMix {
        GasMix::parse(s).unwrap()
    }

    /// Deepest sample (m) and last sample time (s), exactly as written in the file.
    fn check(d: &ImportedDive, max_m: f64, last_s: f64) {
        close(d.max_depth_m(), max_m, &format!("{}: max depth", d.label));
        close(d.duration_s(), last_s, &format!("{}: last sample", d.label));
        // Every open-circuit dive becomes a valid pressure history of the same span.
        let h = d.history(0.0).unwrap();
        close(h.duration_s(), last_s, &d.label);
    }

    #[test]
    fn subsurface_planned_trimix_at_altitude() {
        let ds = read("planned-trimix.xml");
        assert_eq!(ds.len(), 1);
        let d = &ds[0];
        assert!(d.planned && !d.closed_circuit && d.format == Format::Subsurface);
        // Last sample 56:40 min = 3400 s; deepest 60.0 m.
        check(d, 60.0, 3400.0);
        // 19 <sample> lines, two at 29:00 merged into one (the last, 18.0 m, kept).
        assert_eq!(d.samples.len(), 18);
        assert!(d.samples.contains(&(1740.0, 18.0)), "{:?}", d.samples);
        assert!(d.notes.iter().any(|n| n.contains("duplicate")));
        // <surface pressure='0.912 bar'/>, <water salinity='1020 g/l'/>.
        close(d.surface_pa, 0.912e5, "surface");
        close(d.density_kg_m3, 1020.0, "density");
        // Four cylinders, the second marked use='not used' but still listed.
        let mixes = ["ean50", "25/25", "18/45", "o2"].map(gas);
        assert_eq!(d.gases, mixes);
        // gaschange to cylinder 2 at 0:00 → starts on 18/45; EAN50 at 24:01, O2 at 44:21.
        assert_eq!(d.initial_gas, 2);
        assert_eq!(d.switches, [(1441.0, 0), (2661.0, 3)]);
        assert_eq!(d.gas_at(1500.0), mixes[0]);
        assert_eq!(d.gas_at(3000.0), mixes[3]);
        // At 60 m: 0.912 bar + 60 m · 1020 kg/m³ · g.
        let h = d.history(0.0).unwrap();
        let top = h.ambient_pa.iter().cloned().fold(0.0, f64::max);
        close(
            top,
            0.912e5 + 60.0 * 1020.0 * STANDARD_GRAVITY,
            "ambient at 60 m",
        );
        assert_eq!(h.gas_at(600.0), mixes[2]);
    }

    #[test]
    fn subsurface_repetitive_logged_dives() {
        let ds = read("repetitive-logged.xml");
        assert_eq!(ds.len(), 2);
        // Dive 31: deepest 21.6 m, last sample 45:00; dive 32: 17.4 m, 38:00.
        check(&ds[0], 21.6, 45.0 * 60.0);
        check(&ds[1], 17.4, 38.0 * 60.0);
        // 11 and 10 samples, each with the prepended surface point.
        assert_eq!((ds[0].samples.len(), ds[1].samples.len()), (12, 11));
        for (d, surface) in ds.iter().zip([1.012e5, 1.011e5]) {
            // EAN32 from the gaschange to cylinder 1 at 0:02 = the first sample.
            assert_eq!(d.gases[d.initial_gas], gas("ean32"));
            assert!(d.switches.is_empty());
            close(d.surface_pa, surface, "surface");
            // No salinity: the sea-water default, and a note says so.
            close(d.density_kg_m3, divelog::DEFAULT_DENSITY_KG_M3, "density");
            assert!(d.notes.iter().any(|n| n.contains("water density")));
            assert_eq!(d.samples[0], (0.0, 0.0));
            assert_eq!(d.samples[1].0, 2.0);
            assert!(d.notes.iter().any(|n| n.contains("prepended")));
        }
        close(ds[0].samples[1].1, 1.85, "first depth");
        close(ds[1].samples[1].1, 2.105, "first depth");
        assert_eq!(ds[0].start.as_deref(), Some("2019-06-14 09:12:00"));
        assert_eq!(ds[1].start.as_deref(), Some("2019-06-14 12:40:00"));
        // duration='44:00 min' while the samples run to 45:00.
        close(ds[0].stated_duration_s.unwrap(), 2640.0, "stated duration");
    }

    #[test]
    fn subsurface_trimix_with_back_and_forth_switches_and_a_rebreather_dive() {
        let ds = read("trimix-and-ccr.xml");
        assert_eq!(ds.len(), 2);
        let d = ds
            .iter()
            .find(|d| d.number.as_deref() == Some("73"))
            .unwrap();
        check(d, 50.2, 44.0 * 60.0);
        assert_eq!(d.samples.len(), 13);
        // Header says 51.5 m; the samples' maximum is 50.2 m.
        assert_eq!(d.stated_max_depth_m, Some(51.5));
        // Cylinders: EAN32, 18/45, EAN32 again, EAN50, O2. Start on cylinder 0 (event at
        // 0:00), 18/45 at 2:30, the second EAN32 at 18:00, back to 18/45 at 19:00 (an event
        // with only value = 18 + 45·65536 = 2949138, matched to the nearest cylinder), EAN50
        // at 22:00, O2 at 30:00.
        assert_eq!(d.gases, ["ean32", "18/45", "ean32", "ean50", "o2"].map(gas));
        assert_eq!(d.initial_gas, 0);
        assert_eq!(
            d.switches,
            [
                (150.0, 1),
                (1080.0, 2),
                (1140.0, 1),
                (1320.0, 3),
                (1800.0, 4)
            ]
        );
        assert_eq!(d.gas_at(1100.0), gas("ean32"));
        assert_eq!(d.gas_at(1200.0), gas("18/45"));
        assert_eq!(d.gas_at(1800.0), gas("o2"));
        close(d.surface_pa, 1.005e5, "surface");
        close(d.density_kg_m3, 1025.0, "density");
        // The CCR dive: read, flagged, refused as a history; fresh water; starts on the
        // diluent (cylinder 1, air).
        let ccr = ds.iter().find(|d| d.closed_circuit).unwrap();
        assert_eq!(ccr.number.as_deref(), Some("74"));
        close(ccr.max_depth_m(), 30.0, "ccr depth");
        close(ccr.density_kg_m3, 1000.0, "fresh water");
        assert_eq!(ccr.initial_gas, 1);
        assert_eq!(ccr.gases[1], GasMix::AIR);
        let e = ccr.history(0.0).unwrap_err();
        assert!(e.message.contains("closed-circuit"), "{e}");
    }

    #[test]
    fn subsurface_v1_value_only_gas_changes() {
        let ds = read("legacy-v1.xml");
        assert_eq!(ds.len(), 1);
        let d = &ds[0];
        // 65 m, last sample 24:30 (the dive ends at the 6 m stop, as the file does).
        check(d, 65.0, 24.5 * 60.0);
        assert_eq!(d.samples.len(), 7);
        close(d.stated_duration_s.unwrap(), 25.0 * 60.0, "duration 25:00");
        assert_eq!(d.gases, ["20/40", "10/65", "ean36"].map(gas));
        // value='10' → Tx10/65, '20' → Tx20/40, '36' → EAN36 (nearest O2, He unknown).
        assert_eq!(d.switches, [(120.0, 1), (840.0, 0), (1080.0, 2)]);
        // Neither surface pressure nor salinity: both defaulted, with notes.
        close(d.surface_pa, ATM_PA, "surface");
        close(d.density_kg_m3, divelog::DEFAULT_DENSITY_KG_M3, "density");
        assert_eq!(d.notes.len(), 2, "{:?}", d.notes);
        assert_eq!(d.start.as_deref(), Some("2012-4-1 11:20"));
    }

    #[test]
    fn uddf_2_2_divinglog_dialect() {
        // No namespace, upper-case <UDDF> root and ID/REF attributes, CRLF and LF mixed, flat
        // dive children, nested <date>/<time>, <density>1020.0</density>.
        let ds = read("divinglog-2.2.uddf");
        assert_eq!(ds.len(), 1);
        let d = &ds[0];
        assert_eq!(d.format, Format::Uddf);
        // 13 waypoints, deepest 18.29 m, last at 1860 s.
        check(d, 18.29, 1860.0);
        assert_eq!(d.samples.len(), 13);
        assert_eq!(d.gases, [GasMix::AIR]);
        close(d.density_kg_m3, 1020.0, "density");
        assert_eq!(d.stated_max_depth_m, Some(18.3));
        assert_eq!(d.number.as_deref(), Some("12"));
        assert_eq!(d.start.as_deref(), Some("2014-08-03T14:05"));
    }

    #[test]
    fn uddf_without_gas_definitions_breathes_air() {
        let ds = read("logbook-no-gas.uddf");
        assert_eq!(ds.len(), 2);
        // Dive 3: 9 waypoints, deepest 24.4 m (greatestdepth says 24.6), last at 2520 s.
        // Dive 4: 7 waypoints, 21.3 m, 2280 s.
        check(&ds[0], 24.4, 2520.0);
        check(&ds[1], 21.3, 2280.0);
        assert_eq!((ds[0].samples.len(), ds[1].samples.len()), (9, 7));
        assert_eq!(ds[0].stated_max_depth_m, Some(24.6));
        assert!(ds.iter().all(|d| d.gases == [GasMix::AIR]));
        assert!(ds[0].notes.iter().any(|n| n.contains("no gas definitions")));
        // <surfacepressure>101100</surfacepressure> on dive 3 (Pa); none on dive 4.
        close(ds[0].surface_pa, 101_100.0, "surface");
        close(ds[1].surface_pa, ATM_PA, "default surface");
        assert_eq!(ds[1].start.as_deref(), Some("2016-05-21T14:30:00"));
    }

    #[test]
    fn uddf_oxygen_in_percent_and_a_switch_at_20_s() {
        let ds = read("ostc-percent.uddf");
        assert_eq!(ds.len(), 2);
        // <o2>21</o2>, <o2>32</o2>: percent.
        assert_eq!(ds[0].gases, [GasMix::AIR, gas("ean32")]);
        check(&ds[0], 28.0, 2220.0);
        check(&ds[1], 35.0, 2100.0);
        assert_eq!(ds[0].gases[ds[0].initial_gas], GasMix::AIR);
        assert_eq!(ds[0].switches, [(20.0, 1)]);
        let at20 = ds[0].samples.iter().find(|s| s.0 == 20.0).unwrap();
        close(at20.1, 13.0, "depth at the switch");
        assert!(ds[1].switches.is_empty() && ds[1].gases[ds[1].initial_gas] == GasMix::AIR);
    }

    #[test]
    fn uddf_shearwater_quirks() {
        let ds = read("shearwater-quirks.uddf");
        assert_eq!(ds.len(), 1);
        let d = &ds[0];
        // 10 waypoints, deepest 15.3 m, last at 1860 s; EAN32 written without <he>.
        check(d, 15.3, 1860.0);
        assert_eq!(d.samples.len(), 10);
        assert_eq!(d.gases, [gas("ean32")]);
        // <surfacepressure>6950000</surfacepressure> (69.5 bar) is replaced by 1 atm, noted.
        close(d.surface_pa, ATM_PA, "defaulted surface");
        assert!(d.notes.iter().any(|n| n.contains("implausible")));
        // Density only in <tablegeneration> profile 'profile_9001', linked from the dive.
        close(d.density_kg_m3, 1020.0, "density");
        // Dangling tankpressure refs and "30 ft" in a number field are ignored.
        assert_eq!(d.start.as_deref(), Some("2023-08-19T16:02:40Z"));
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
    let dir = data("divelogs");
    // One dive: no number needed. legacy-v1.xml: 65 m, 1030 kg/m³ default, 101325 Pa default.
    let h = profile::load(&dir.join("legacy-v1.xml"), &LoadOptions::default()).unwrap();
    let top = h.ambient_pa.iter().cloned().fold(0.0, f64::max);
    close(
        top,
        ATM_PA + 65.0 * 1030.0 * decophantom::units::STANDARD_GRAVITY,
        "65 m",
    );
    // Two dives: a number is required and checked.
    let ostc = dir.join("repetitive-logged.xml");
    let e = profile::load(&ostc, &LoadOptions::default()).unwrap_err();
    assert!(e.message.contains("2 dives"), "{e}");
    let two = LoadOptions {
        dive: Some(decophantom::profile::sequence::DiveSelection::One(2)),
        ..LoadOptions::default()
    };
    let h = profile::load(&ostc, &two).unwrap();
    assert!(h.label.contains("12:40"), "{}", h.label);
    let three = LoadOptions {
        dive: Some(decophantom::profile::sequence::DiveSelection::One(3)),
        ..LoadOptions::default()
    };
    assert!(profile::load(&ostc, &three).is_err());
    assert!(profile::load(&ostc, &opts(TimeUnit::S, PressureUnit::Pa)).is_err());
    assert!(profile::load(&legacy_path("step-10psi.txt"), &two).is_err());
}

/// Subsurface XML values carry units: known ones are converted (ft, mbar, kPa), an unknown one
/// is refused naming the line and attribute; a sample out of time order is sorted with a note
/// naming its line; an empty UDDF `<depth>` is refused naming its line.
#[test]
fn dive_log_units_order_and_empty_values() {
    use decophantom::profile::divelog;
    let p = Path::new("u.xml");
    let log = |surface: &str, depth: &str, t: &str| {
        divelog::parse(
            &format!(
                "<divelog><dives><dive>\n<divecomputer>\n<surface pressure='{surface}'/>\n<sample time='0:00 min' depth='0 m'/>\n<sample time='{t}' depth='{depth}'/>\n<sample time='2:00 min' depth='0 m'/>\n</divecomputer></dive></dives></divelog>"
            ),
            p,
        )
        .map(|mut d| d.remove(0))
    };
    // 1012 mbar = 101 200 Pa; 69 ft = 69 · 0.3048 m (international foot)
    let d = log("1012 mbar", "69 ft", "1:00 min").unwrap();
    close(d.surface_pa, 101_200.0, "1012 mbar");
    close(d.samples[1].1, 69.0 * 0.3048, "69 ft");
    // 1.012 kPa is 1012 Pa, not 1.012 bar: implausible, so the default is used and noted
    let d = log("1.012 kPa", "10 m", "1:00 min").unwrap();
    assert_eq!(d.surface_pa, ATM_PA);
    assert!(
        d.notes.iter().any(|n| n.contains("1012 Pa")),
        "{:?}",
        d.notes
    );
    let e = log("1.012 bar", "21.1 furlong", "1:00 min").unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(5), Some("sample.depth")),
        "{e}"
    );
    let e = log("760 torr", "10 m", "1:00 min").unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(3), Some("surface.pressure")),
        "{e}"
    );
    // the 2:00 sample on line 6 comes after 3:00 in the file: read sorted, and said so
    let d = log("1.012 bar", "10 m", "3:00 min").unwrap();
    assert_eq!(
        d.samples.iter().map(|s| s.0).collect::<Vec<_>>(),
        vec![0.0, 120.0, 180.0]
    );
    assert!(
        d.notes
            .iter()
            .any(|n| n.contains("out of time order") && n.contains("line 6")),
        "{:?}",
        d.notes
    );
    let d = log("1.012 bar", "10 m", "1:00 min").unwrap();
    assert!(
        !d.notes.iter().any(|n| n.contains("order")),
        "{:?}",
        d.notes
    );

    let uddf = |depth: &str| {
        divelog::parse(
            &format!("<uddf><profiledata><repetitiongroup><dive><samples>\n<waypoint><depth>0</depth><divetime>0</divetime></waypoint>\n<waypoint><depth>{depth}</depth><divetime>600</divetime></waypoint>\n<waypoint><depth>0</depth><divetime>1200</divetime></waypoint>\n</samples></dive></repetitiongroup></profiledata></uddf>"),
            Path::new("u.uddf"),
        )
    };
    assert_eq!(uddf("20").unwrap()[0].samples.len(), 3);
    for bad in ["", "20 furlong"] {
        let e = uddf(bad).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(3), Some("waypoint.depth")),
            "{e}"
        );
    }
}

/// `--vapour-pa` is a command-line value: out of range, or not below the profile's lowest
/// ambient pressure, it is blamed on `<command line>`, not on the profile file. A folder given
/// as the profile is named as a folder, whatever the other options.
#[test]
fn vapour_option_and_folder_profiles_name_their_source() {
    let dir = std::env::temp_dir().join(format!("decophantom-vapour-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let txt = dir.join("low.txt");
    // 101.325 kPa down to 20 kPa absolute
    std::fs::write(&txt, "0 101.325\n10 20\n20 20\n").unwrap();
    let with = |v: f64| LoadOptions {
        vapour_pa: Some(v),
        ..opts(TimeUnit::S, PressureUnit::Kpa)
    };
    assert_eq!(
        profile::load(&txt, &with(6270.0)).unwrap().vapour_pa,
        6270.0
    );
    for v in [1e6, 5e4, 2e4] {
        let e = profile::load(&txt, &with(v)).unwrap_err();
        assert_eq!(e.file.as_deref(), Some(Path::new("<command line>")), "{e}");
        assert_eq!(e.field.as_deref(), Some("--vapour-pa"), "{e}");
    }
    for o in [
        LoadOptions::default(),
        opts(TimeUnit::Min, PressureUnit::Msw),
    ] {
        let e = profile::load(&dir, &o).unwrap_err();
        assert_eq!(e.file.as_deref(), Some(dir.as_path()), "{e}");
        assert!(e.message.contains("folder") && e.field.is_none(), "{e}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A dive log whose descent was not logged (first sample deeper than
/// [`divelog::FIRST_SAMPLE_DEPTH_M`], 3 m, at time 0, or reached from the prepended surface
/// point faster than [`divelog::MAX_LOGGED_RATE_M_MIN`], 600 m/min) or whose depth jumps between
/// two samples faster than that is refused naming the file, the dive (1-based, as `--dive`),
/// the sample's line, its time and the depth field, in both formats; before session 31 each ran
/// with exit 0 (a 30 m dive from time 0 compressed the phantom from the surface in no time).
/// A first sample deeper than 3 m reached at a diver's pace is read, with a note that the
/// descent was not logged; a change faster than the schedules' 100 m/min is read, noted (the
/// real OSTC log `kenozooid__ostc-dump-02.uddf` goes from 8 m at 10 s to 43 m at 20 s,
/// 210 m/min, in dive 2), and so is the real logs' start at 2.68 m at time 0
/// (`subsurface__test40-42.xml` dive 3, within the 3 m).
///
/// [`divelog::FIRST_SAMPLE_DEPTH_M`]: decophantom::profile::divelog::FIRST_SAMPLE_DEPTH_M
/// [`divelog::MAX_LOGGED_RATE_M_MIN`]: decophantom::profile::divelog::MAX_LOGGED_RATE_M_MIN
#[test]
fn dive_logs_without_their_descent_or_with_impossible_rates_are_refused() {
    use decophantom::profile::divelog;
    let p = Path::new("log.ssrf");
    // dive 2 of a two-dive log carries the samples (lines 7..): dive 1 is a plain 20 m dive
    let ssrf = |samples: &[(&str, &str)]| {
        let rows: String = samples
            .iter()
            .map(|(t, d)| format!("<sample time='{t}' depth='{d} m' />\n"))
            .collect();
        format!(
            "<divelog program='subsurface' version='3'>\n<dives>\n<dive number='1'><divecomputer>\n<sample time='0:00 min' depth='0 m' /><sample time='2:00 min' depth='20 m' /><sample time='20:00 min' depth='0 m' />\n</divecomputer></dive>\n<dive number='2'><divecomputer>\n{rows}</divecomputer></dive>\n</dives>\n</divelog>\n"
        )
    };
    let refused = |samples: &[(&str, &str)], line: usize, words: &[&str]| {
        let e = divelog::parse(&ssrf(samples), p).unwrap_err();
        assert_eq!(
            (e.file.as_deref(), e.line, e.field.as_deref()),
            (Some(p), Some(line), Some("sample.depth")),
            "{e}"
        );
        assert!(e.message.starts_with("dive 2: "), "{e}");
        for w in words {
            assert!(e.message.contains(w), "{w}: {e}");
        }
    };
    let tail = [("20:00 min", "30"), ("24:00 min", "0")];
    // 30 m at 0:00: no descent
    refused(
        &[("0:00 min", "30"), tail[0], tail[1]],
        7,
        &["starts at 30 m at 0 s", "descent was not logged"],
    );
    // 30 m at 0:02: 900 m/min from the surface
    refused(
        &[("0:02 min", "30"), tail[0], tail[1]],
        7,
        &["30 m at 2 s", "900 m/min", "misses the descent"],
    );
    // a glitch to the surface and back within a second, 20 m/s = 1200 m/min
    refused(
        &[
            ("0:00 min", "0"),
            ("2:00 min", "20"),
            ("10:00 min", "20"),
            ("10:01 min", "0"),
            ("10:02 min", "20"),
            ("24:00 min", "0"),
        ],
        10,
        &["from 20 m at 600 s to 0 m at 601 s", "1200 m/min"],
    );
    // the limits themselves are read: 3 m at 0:00, 600 m/min (20 m in 2 s)
    let ok = |samples: &[(&str, &str)]| {
        let mut ds = divelog::parse(&ssrf(samples), p).unwrap();
        ds.remove(1)
    };
    let d = ok(&[
        ("0:00 min", "3"),
        ("2:00 min", "20"),
        ("2:02 min", "0"),
        ("3:00 min", "0"),
    ]);
    assert!(
        d.notes.iter().any(|n| n.contains("starts at 3 m"))
            && d.notes.iter().any(|n| n.contains(
                "1 change(s) of depth faster than the 100 m/min accepted in schedules, the fastest 600 m/min (20 m at 120 s to 0 m at 122 s, line 9)"
            )),
        "{:?}",
        d.notes
    );
    // 20 m at 1:00 (20 m/min from the surface): read, the missing descent noted
    let d = ok(&[("1:00 min", "20"), tail[0], tail[1]]);
    assert_eq!(d.samples[0], (0.0, 0.0));
    assert!(
        d.notes
            .iter()
            .any(|n| n.contains("the descent was not logged") && n.contains("20 m/min")),
        "{:?}",
        d.notes
    );
    // UDDF: the waypoint's line and field
    let uddf = "<uddf><profiledata><repetitiongroup><dive><samples>\n<waypoint><depth>0</depth><divetime>0</divetime></waypoint>\n<waypoint><depth>40</depth><divetime>3</divetime></waypoint>\n<waypoint><depth>0</depth><divetime>1200</divetime></waypoint>\n</samples></dive></repetitiongroup></profiledata></uddf>";
    let e = divelog::parse(uddf, Path::new("u.uddf")).unwrap_err();
    assert_eq!(
        (e.line, e.field.as_deref()),
        (Some(3), Some("waypoint.depth")),
        "{e}"
    );
    assert!(
        e.message.starts_with("dive 1: ") && e.message.contains("800 m/min"),
        "{e}"
    );
    // a first waypoint within the 3 m start depth is read whenever it comes, as at time 0
    // (2.5 m at 0.2 s is 750 m/min from the prepended surface point; the session-31 review)
    let shallow = "<uddf><profiledata><repetitiongroup><dive><samples>\n<waypoint><depth>2.5</depth><divetime>0.2</divetime></waypoint>\n<waypoint><depth>20</depth><divetime>120</divetime></waypoint>\n<waypoint><depth>0</depth><divetime>1200</divetime></waypoint>\n</samples></dive></repetitiongroup></profiledata></uddf>";
    let ds = divelog::parse(shallow, Path::new("u.uddf")).unwrap();
    assert_eq!(ds[0].samples[..2], [(0.0, 0.0), (0.2, 2.5)]);

    // through the binary: exit 2, the file, line and field on stderr, nothing run
    let dir = crate::common::tempdir("divelog-rates");
    let f = dir.join("deep.ssrf");
    std::fs::write(&f, ssrf(&[("0:00 min", "30"), tail[0], tail[1]])).unwrap();
    let o = std::process::Command::new(crate::common::bin())
        .args(["check", "--schedule"])
        .arg(&f)
        .args(["--dive", "2", "--criteria"])
        .arg(crate::common::root().join("algorithms/criteria/default.toml"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("deep.ssrf:7: field 'sample.depth': dive 2: the dive starts at 30 m at 0 s"),
        "{err}"
    );

    // the real logs: read, the fast change noted
    if let Some(dir) = shared("dive-files") {
        let ds = divelog::read(&dir.join("kenozooid__ostc-dump-02.uddf")).unwrap();
        assert!(
            ds[1]
                .notes
                .iter()
                .any(|n| n.contains("the fastest 210 m/min (8 m at 10 s to 43 m at 20 s")),
            "{:?}",
            ds[1].notes
        );
        let ds = divelog::read(&dir.join("subsurface__test40-42.xml")).unwrap();
        assert_eq!(ds[2].samples[0], (0.0, 2.68));
    }
}

/// One refused dive in a logbook keeps the others usable: a dive the reader refuses (here
/// dive 2's glitch, 1200 m/min) is an error only where it is chosen (`--dive 2`, a range or
/// `all` that holds it), and dive 1 of the same file runs as if dive 2 were sound.
#[test]
fn a_refused_dive_fails_only_where_it_is_chosen() {
    use decophantom::profile::divelog;
    use decophantom::profile::select_dive;
    use decophantom::profile::sequence::DiveSelection;
    let p = Path::new("book.ssrf");
    let text = "<divelog program='subsurface' version='3'>\n<dives>\n<dive number='1'><divecomputer>\n<sample time='0:00 min' depth='0 m' /><sample time='2:00 min' depth='20 m' /><sample time='20:00 min' depth='0 m' />\n</divecomputer></dive>\n<dive number='2'><divecomputer>\n<sample time='0:00 min' depth='0 m' />\n<sample time='2:00 min' depth='20 m' />\n<sample time='10:00 min' depth='20 m' />\n<sample time='10:01 min' depth='0 m' />\n<sample time='24:00 min' depth='0 m' />\n</divecomputer></dive>\n</dives>\n</divelog>\n";
    let each = || divelog::parse_each(text, p).unwrap();
    let dives = each();
    assert_eq!(dives.len(), 2);
    assert!(dives[0].is_ok());
    let e = dives[1].as_ref().unwrap_err();
    assert!(
        e.message.starts_with("dive 2: ") && e.message.contains("1200 m/min"),
        "{e}"
    );
    // the whole file read at once is refused, as before
    assert_eq!(divelog::parse(text, p).unwrap_err().line, Some(10));
    // dive 1 chosen: the same samples as read from a log without dive 2
    let one = select_dive(p, each(), Some(DiveSelection::One(1))).unwrap();
    assert_eq!(one.samples, vec![(0.0, 0.0), (120.0, 20.0), (1200.0, 0.0)]);
    for sel in [
        DiveSelection::One(2),
        DiveSelection::Range(1, 2),
        DiveSelection::All,
    ] {
        let e = select_dive(p, each(), Some(sel)).unwrap_err();
        assert_eq!(
            (e.line, e.field.as_deref()),
            (Some(10), Some("sample.depth")),
            "{sel:?}: {e}"
        );
    }
}
