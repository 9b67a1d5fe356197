//! `decophantom reproduce`: a reduced (`--quick`) run of Figs 2a and 3, checked against an
//! independent root solve of the no-mass-transfer balance (Fig. 2a) and against the paper's
//! qualitative claims that the README's "Reproducing the paper" section says hold.

use crate::common::{bin, tempdir};
use decophantom::reproduce::{reproduce, select, Agreement, Settings};
use std::collections::HashMap;
use std::f64::consts::PI;

/// The moduli of the Fig. 2a caption: μ (Pa), M (Pa/m³), K (Pa).
struct Moduli {
    mu: f64,
    m: f64,
    k: f64,
}

/// Ω(R) of each form written out from the paper's eqs (2.6)–(2.9) (Walsh et al. 2017, §2.1.2),
/// independently of `phantom::elasticity`.
fn omega(form: &str, r: f64, r0: f64, p: f64, p0: f64, e: &Moduli) -> f64 {
    match form {
        "none" => 0.0,
        "bulk-modulus" => 4.0 / 3.0 * PI * r.powi(3) * e.m,
        "continuity-of-displacement" => -4.0 * e.mu / 3.0,
        "reference-configuration" => {
            4.0 * e.mu * ((1.0 - p0 / (3.0 * e.k)) * r / r0 - (1.0 - p / (3.0 * e.k)))
        }
        "hyperelastic" => 0.5 * e.mu * (5.0 - 4.0 * r0 / r - (r0 / r).powi(4)),
        other => panic!("unknown form {other}"),
    }
}

/// The final radius by bisection: the gas is ideal and isothermal with no mass transfer, so
/// p_gas·R³ is constant, with p_gas = p + 2γ/R + Ω(R) (Young–Laplace with the tissue term).
/// The smallest root above 1 nm, found by a geometric scan then 200 bisections; None if the
/// balance has no root below 10 m.
fn final_radius(form: &str, r0: f64, p0: f64, pf: f64, g: f64, e: &Moduli) -> Option<f64> {
    let content = (p0 + 2.0 * g / r0 + omega(form, r0, r0, p0, p0, e)) * r0.powi(3);
    if content.is_nan() || content <= 0.0 {
        return None;
    }
    let f = |r: f64| (pf + 2.0 * g / r + omega(form, r, r0, pf, p0, e)) * r.powi(3) - content;
    let mut a = 1e-9;
    while a < 10.0 {
        let b = a * 1.01;
        if f(a) < 0.0 && f(b) >= 0.0 {
            let (mut lo, mut hi) = (a, b);
            for _ in 0..200 {
                let mid = 0.5 * (lo + hi);
                if f(mid) < 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return Some(0.5 * (lo + hi));
        }
        a = b;
    }
    None
}

fn csv_rows(text: &str) -> Vec<HashMap<String, String>> {
    let mut lines = text.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

#[test]
fn reproduce_fig2a_and_fig3_quick_against_an_independent_solve_and_the_paper() {
    let dir = tempdir("reproduce");
    let out = dir.join("paper");
    let figs: Vec<_> = ["fig2a", "fig3"]
        .iter()
        .flat_map(|n| select(n).unwrap())
        .collect();
    let done = reproduce(
        &figs,
        &Settings { quick: true },
        &out,
        "test",
        &|_, _, _| {},
    )
    .unwrap();
    let verdict = |fig: &str, key: &str| -> Agreement {
        done.iter()
            .find(|d| d.figure.name == fig)
            .and_then(|d| d.verdicts.iter().find(|v| v.key == key))
            .unwrap_or_else(|| panic!("no verdict {fig}/{key}"))
            .agrees
    };
    for f in [
        "README.md",
        "fig2a/README.md",
        "fig2a/report.html",
        "fig2a/fig2a.csv",
        "fig2a/fig2a-mu1.svg",
        "fig3/README.md",
        "fig3/fig3c-modal.svg",
        "fig3/fig3c-mu20k.svg",
        "fig3/oat-modal/sensitivity.csv",
        "fig3/oat-mu20k/indices.csv",
        "fig3/sobol/indices.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let index = std::fs::read_to_string(out.join("README.md")).unwrap();
    assert!(index.contains("L_N2, 0.014 or 0.145") && index.contains("psi gauge"));

    // ---- Fig. 2a: every row against the independent bisection
    let rows = csv_rows(&std::fs::read_to_string(out.join("fig2a/fig2a.csv")).unwrap());
    assert_eq!(
        rows.len(),
        2 * 5 * 9,
        "2 μ × 5 forms × 9 radii (2 per decade, quick)"
    );
    let num = |r: &HashMap<String, String>, k: &str| r[k].parse::<f64>().unwrap();
    let mut rf: Vec<(String, f64, f64, f64)> = Vec::new();
    for r in &rows {
        let (r0, mu) = (num(r, "r0_m"), num(r, "mu"));
        // the caption's constants, in the file and as given by the paper
        assert_eq!((num(r, "p0_pa"), num(r, "pf_pa")), (1e6, 1e4));
        assert_eq!(
            (num(r, "gamma"), num(r, "m_pa_per_m3"), num(r, "k_pa")),
            (0.07, 5e16, 2.2e9)
        );
        let moduli = Moduli {
            mu,
            m: 5e16,
            k: 2.2e9,
        };
        let want = final_radius(&r["form"], r0, 1e6, 1e4, 0.07, &moduli);
        match (r["rf_m"].as_str(), want) {
            ("", None) => {}
            (s, Some(w)) if !s.is_empty() => {
                let got: f64 = s.parse().unwrap();
                assert!((got / w - 1.0).abs() < 1e-9, "{r:?}: {got} vs {w}");
                rf.push((r["form"].clone(), mu, r0, got));
            }
            (s, w) => panic!("{r:?}: file '{s}', independent {w:?}"),
        }
    }
    let get = |form: &str, mu: f64, r0: f64| -> f64 {
        rf.iter()
            .find(|x| x.0 == form && x.1 == mu && (x.2 / r0 - 1.0).abs() < 1e-9)
            .unwrap_or_else(|| panic!("no row {form} μ = {mu} R0 = {r0}"))
            .3
    };
    for mu in [40.0, 5000.0] {
        // Ω = 0 at 1 mm is almost pure Boyle: (P0/Pf)^(1/3) = 4.6416, less the tension's 0.5 %
        assert!((get("none", mu, 1e-3) / 1e-3 / 100f64.cbrt() - 1.0).abs() < 0.01);
        // the Bulk Modulus form restricts the largest bubble most (§2.1.2)
        for f in [
            "none",
            "continuity-of-displacement",
            "reference-configuration",
            "hyperelastic",
        ] {
            assert!(
                get("bulk-modulus", mu, 1e-3) < get(f, mu, 1e-3),
                "{f} at μ = {mu}"
            );
        }
        // continuity of displacement gives the largest final radius at every R0
        for r0 in [1e-7, 1e-6, 1e-5, 1e-4, 1e-3] {
            for f in [
                "none",
                "bulk-modulus",
                "reference-configuration",
                "hyperelastic",
            ] {
                assert!(get("continuity-of-displacement", mu, r0) >= get(f, mu, r0));
            }
        }
    }
    // ... but 'much higher' only at the stiffer μ: +0.18 % at 40 Pa, +44 % at 5 kPa
    // (analytic for a large bubble: (Pf/(Pf − 4μ/3))^(1/3))
    let gain = |mu: f64| get("continuity-of-displacement", mu, 1e-3) / get("none", mu, 1e-3);
    assert!(
        gain(40.0) < 1.01 && gain(5000.0) > 1.4,
        "{} {}",
        gain(40.0),
        gain(5000.0)
    );
    assert!((gain(5000.0) - (1e4_f64 / (1e4 - 4.0 * 5000.0 / 3.0)).cbrt()).abs() < 0.01);
    assert_eq!(
        verdict("fig2a", "continuity-largest:mu1"),
        Agreement::Partly
    );
    assert_eq!(verdict("fig2a", "continuity-largest:mu2"), Agreement::Yes);
    assert_eq!(verdict("fig2a", "ordering-mu"), Agreement::Yes);

    // ---- Fig. 3, from the runs themselves (sensitivity.csv: base run, then 3 levels each)
    let levels = 3;
    let ends = |sub: &str| -> Vec<(f64, f64, f64, f64)> {
        let rows = csv_rows(
            &std::fs::read_to_string(out.join("fig3").join(sub).join("sensitivity.csv")).unwrap(),
        );
        (0..5)
            .map(|i| {
                let (lo, hi) = (&rows[1 + i * levels], &rows[i * levels + levels]);
                (
                    num(lo, "r_max"),
                    num(hi, "r_max"),
                    num(lo, "t_max"),
                    num(hi, "t_max"),
                )
            })
            .collect()
    };
    // parameters in order γ, L_N2, L_O2, μ, D. At μ = 20 kPa all five R_max directions are the
    // paper's (§2.3.1): D, μ, γ lower R_max; L_N2, L_O2 raise it.
    let e = ends("oat-mu20k");
    for (i, up) in [false, true, true, false, false].iter().enumerate() {
        assert_eq!(
            e[i].1 > e[i].0,
            *up,
            "parameter {i}: R_max {} → {}",
            e[i].0,
            e[i].1
        );
    }
    // D and μ shorten t_max; μ has the largest R_max range, D the largest t_max range (Fig. 3b)
    assert!(e[4].3 < e[4].2 && e[3].3 < e[3].2);
    let range = |j: usize| -> Vec<f64> {
        e.iter()
            .map(|x| {
                if j == 0 {
                    (x.1 - x.0).abs()
                } else {
                    (x.3 - x.2).abs()
                }
            })
            .collect()
    };
    let argmax = |v: Vec<f64>| (0..5).max_by(|a, b| v[*a].total_cmp(&v[*b])).unwrap();
    assert_eq!(argmax(range(0)), 3, "μ: largest R_max range");
    assert_eq!(argmax(range(1)), 4, "D: largest t_max range");
    // at the modal μ = 2 MPa growth is stopped: μ and D still lower R_max, but R_max stays
    // within 5 % of R0 = 40 µm for every level of γ, L_N2, L_O2 and D
    let m = ends("oat-modal");
    assert!(m[3].1 < m[3].0 && m[4].1 < m[4].0);
    for i in [0, 1, 2, 4] {
        assert!(
            m[i].0 < 42e-6 && m[i].1 < 42e-6,
            "parameter {i}: {:?}",
            m[i]
        );
    }
    assert_eq!(verdict("fig3", "mu20k:R_max-directions"), Agreement::Yes);
    assert_eq!(verdict("fig3", "modal:R_max-directions"), Agreement::Partly);
}

#[test]
fn reproduce_refuses_an_unknown_figure_with_exit_2() {
    let dir = tempdir("reproduce-bad");
    let o = std::process::Command::new(bin())
        .args(["reproduce", "fig9", "--out"])
        .arg(dir.join("x"))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("unknown figure 'fig9'") && err.contains("fig2a"),
        "{err}"
    );
    assert!(!dir.join("x").exists());
}
