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
