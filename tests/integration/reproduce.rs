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

    // ---- Fig. 3 Sobol': the verdict follows only the rankings the intervals resolve,
    // recomputed here from indices.csv: a parameter can be first unless another's lower ST
    // bound is above its upper bound; D alone → agrees, D out → disagrees, else unresolved
    let idx = csv_rows(&std::fs::read_to_string(out.join("fig3/sobol/indices.csv")).unwrap());
    let f = |r: &HashMap<String, String>, k: &str| r[k].parse::<f64>().unwrap_or(f64::NAN);
    let mut parts = Vec::new();
    for m in ["r_max", "t_max"] {
        let rows: Vec<_> = idx.iter().filter(|r| r["metric"] == m).collect();
        assert_eq!(rows.len(), 5);
        let can_lead: Vec<&str> = rows
            .iter()
            .filter(|p| {
                !rows
                    .iter()
                    .any(|q| q["parameter"] != p["parameter"] && f(q, "st_lo95") > f(p, "st_hi95"))
            })
            .map(|p| p["parameter"].as_str())
            .collect();
        let d = "scale:gases.*.diffusivity";
        parts.push(if can_lead == [d] {
            1
        } else if can_lead.contains(&d) {
            0
        } else {
            -1
        });
    }
    let want = if parts.iter().all(|p| *p == 1) {
        Agreement::Yes
    } else if parts.iter().all(|p| *p == 0) {
        Agreement::NotComparable
    } else if !parts.contains(&1) {
        Agreement::No
    } else {
        Agreement::Partly
    };
    assert_eq!(verdict("fig3", "sobol:most-influential"), want, "{parts:?}");
    // the bars are point estimates with error bars (plotters' three 2-px black lines each),
    // not the upper bounds drawn as bars
    let bars = std::fs::read_to_string(out.join("fig3/sobol/bars-0.svg")).unwrap();
    assert!(!bars.contains("upper 95"), "upper bounds drawn as bars");
    let error_bar_lines = bars
        .split("<line")
        .filter(|l| l.contains("stroke=\"#000000\" stroke-width=\"2\""))
        .count();
    assert!(error_bar_lines >= 3, "no error bars in bars-0.svg");
    let fig3 = std::fs::read_to_string(out.join("fig3/README.md")).unwrap();
    assert!(!fig3.contains("frames every 2 s") && !fig3.contains("D second for t_max"));

    // ---- Fig. 3's local sensitivities (review #6): every elasticity is the central
    // difference of ln m over base·(1 ± δ) recomputed from its own metrics, its step error the
    // difference from δ/2, and the sensitivity verdicts say that they judge it
    let local =
        csv_rows(&std::fs::read_to_string(out.join("fig3/local-sensitivities.csv")).unwrap());
    assert_eq!(local.len(), 2 * 5 * 2, "2 bases × 5 parameters × 2 metrics");
    for r in &local {
        let (d, lo, hi) = (
            num(r, "delta"),
            num(r, "metric_at_minus_delta"),
            num(r, "metric_at_plus_delta"),
        );
        let want = (hi.ln() - lo.ln()) / ((1.0 + d).ln() - (1.0 - d).ln());
        let e = num(r, "elasticity");
        assert!((e - want).abs() <= 1e-12 * want.abs().max(1.0), "{r:?}");
        let step = (e - num(r, "elasticity_at_half_delta")).abs();
        assert!((num(r, "step_error") - step).abs() <= 1e-12, "{r:?}");
        assert!(num(r, "numerical_error") >= 0.0);
    }
    let ours = |key: &str| -> String {
        done.iter()
            .find(|d| d.figure.name == "fig3")
            .and_then(|d| d.verdicts.iter().find(|v| v.key == key))
            .map(|v| v.ours.clone())
            .unwrap()
    };
    for base in ["modal", "mu20k"] {
        for v in ["most-sensitive-d", "mu-insensitive"] {
            let t = ours(&format!("{base}:{v}"));
            assert!(
                t.contains("Measure: the local elasticity") && t.contains("chord"),
                "{base}:{v}: {t}"
            );
        }
    }

    // ---- the panels (review #14, #22): no SVG writes one text twice at one place (the log
    // axes' doubled "10"), and every bar of Fig. 3b and 3c is drawn (or marked "0") on its
    // log axis, at least a few px tall
    let mut svgs = Vec::new();
    for sub in ["fig2a", "fig3"] {
        for e in std::fs::read_dir(out.join(sub)).unwrap() {
            let p = e.unwrap().path();
            if p.extension().is_some_and(|x| x == "svg") {
                svgs.push(p);
            }
        }
    }
    assert!(svgs.len() >= 8, "{svgs:?}");
    let texts = |svg: &str| -> Vec<(String, String, String)> {
        svg.split("<text")
            .skip(1)
            .map(|t| {
                let attr = |k: &str| {
                    t.split(&format!(" {k}=\""))
                        .nth(1)
                        .and_then(|v| v.split('"').next())
                        .unwrap_or("")
                        .to_string()
                };
                let body = t
                    .split('>')
                    .nth(1)
                    .unwrap_or("")
                    .split('<')
                    .next()
                    .unwrap_or("");
                (attr("x"), attr("y"), body.trim().to_string())
            })
            .collect()
    };
    for p in &svgs {
        let svg = std::fs::read_to_string(p).unwrap();
        let mut seen = std::collections::HashSet::new();
        for t in texts(&svg) {
            assert!(seen.insert(t.clone()), "{}: {t:?} twice", p.display());
        }
    }
    for (f, values) in [
        ("fig3c-modal.svg", 20),
        ("fig3c-mu20k.svg", 20),
        ("fig3b-rmax-modal.svg", 5),
        ("fig3b-tmax-mu20k.svg", 5),
    ] {
        let svg = std::fs::read_to_string(out.join("fig3").join(f)).unwrap();
        let heights: Vec<f64> = svg
            .split("<rect")
            .skip(1)
            .filter(|r| r.contains("stroke=\"none\"") && r.contains("opacity=\"1\""))
            .filter_map(|r| {
                let get = |k: &str| -> Option<f64> {
                    r.split(&format!(" {k}=\""))
                        .nth(1)?
                        .split('"')
                        .next()?
                        .parse()
                        .ok()
                };
                let w = get("width")?;
                (w > 20.0 && w < 150.0).then_some(get("height")?)
            })
            .collect();
        let zeros = texts(&svg).iter().filter(|t| t.2 == "0").count();
        assert_eq!(
            heights.len() + zeros,
            values,
            "{f}: {heights:?}, {zeros} zeros"
        );
        assert!(
            heights.iter().all(|h| *h >= 10.0),
            "{f}: a bar too short to see: {heights:?}"
        );
        assert!(
            svg.contains("(log)") || svg.contains(", log)"),
            "{f}: no log axis label"
        );
    }
}

/// Fig. 5 (--quick): every verdict that judges a change or a curvature does so by one rule (Fig.
/// 3's), recomputed here from the data files: a number's numerical error is twice its change
/// with every step limit halved, so a change over a series' levels (largest − smallest mean)
/// counts only above twice the change of the same difference in the halved-step means, and a
/// curvature only where the largest deviation from the least-squares line exceeds twice the
/// change of that level's deviation; within it, neither agreeing nor disagreeing.
#[test]
fn reproduce_fig5_quick_judges_every_change_by_its_numerical_error() {
    let dir = tempdir("reproduce-fig5");
    let out = dir.join("paper");
    let done = reproduce(
        &select("fig5").unwrap(),
        &Settings { quick: true },
        &out,
        "test",
        &|_, _, _| {},
    )
    .unwrap();
    let verdict = |key: &str| -> Agreement {
        done[0]
            .verdicts
            .iter()
            .find(|v| v.key == key)
            .unwrap_or_else(|| panic!("no verdict {key}"))
            .agrees
    };
    let num = |r: &HashMap<String, String>, k: &str| r[k].parse::<f64>().unwrap();
    // the run means from every bubble of every run
    let bubbles = csv_rows(&std::fs::read_to_string(out.join("fig5/fig5.csv")).unwrap());
    // ((hours, psi/s), [(plateau µm, half-life min) per bubble])
    type Run = ((f64, f64), Vec<(f64, f64)>);
    let mut runs: Vec<Run> = Vec::new();
    for b in &bubbles {
        let key = (
            num(b, "time_at_depth_h"),
            num(b, "decompression_rate_psi_s"),
        );
        let v = (num(b, "plateau_m") * 1e6, num(b, "half_life_s") / 60.0);
        match runs.iter_mut().find(|r| r.0 == key) {
            Some(r) => r.1.push(v),
            None => runs.push((key, vec![v])),
        }
    }
    let mean = |v: &[(f64, f64)]| {
        let n = v.len() as f64;
        (
            v.iter().map(|x| x.0).sum::<f64>() / n,
            v.iter().map(|x| x.1).sum::<f64>() / n,
        )
    };
    // the halved-step means, and the errors recomputed from them
    let fine =
        csv_rows(&std::fs::read_to_string(out.join("fig5/fig5-numerical-errors.csv")).unwrap());
    assert_eq!(
        fine.len(),
        runs.len(),
        "every run repeated with the steps halved"
    );
    let error = |key: (f64, f64)| -> (f64, f64) {
        let r = fine
            .iter()
            .find(|r| {
                (
                    num(r, "time_at_depth_h"),
                    num(r, "decompression_rate_psi_s"),
                ) == key
            })
            .unwrap();
        let c = mean(&runs.iter().find(|x| x.0 == key).unwrap().1);
        let e = (
            2.0 * (c.0 - num(r, "plateau_mean_halved_steps_m") * 1e6).abs(),
            2.0 * (c.1 - num(r, "half_life_mean_halved_steps_s") / 60.0).abs(),
        );
        assert!((e.0 - num(r, "plateau_error_m") * 1e6).abs() < 1e-6 * (1.0 + e.0));
        assert!((e.1 - num(r, "half_life_error_s") / 60.0).abs() < 1e-6 * (1.0 + e.1));
        e
    };
    // a series' levels (x, default mean, halved-step mean), sorted by x: hours at 5 psi/s or
    // rates after 4 h; pick 0 plateau, 1 half-life
    let levels = |by_rate: bool, pick: usize| -> Vec<(f64, f64, f64)> {
        let mut l: Vec<(f64, f64, f64)> = runs
            .iter()
            .filter(|r| {
                if by_rate {
                    r.0 .0 == 4.0
                } else {
                    r.0 .1 == 5.0
                }
            })
            .map(|r| {
                let (m, e) = (mean(&r.1), error(r.0));
                let (v, e) = if pick == 0 { (m.0, e.0) } else { (m.1, e.1) };
                // the halved-step mean from the default mean and its error's sign, read back
                // from the file
                let f = fine
                    .iter()
                    .find(|x| {
                        (
                            num(x, "time_at_depth_h"),
                            num(x, "decompression_rate_psi_s"),
                        ) == r.0
                    })
                    .unwrap();
                let vf = if pick == 0 {
                    num(f, "plateau_mean_halved_steps_m") * 1e6
                } else {
                    num(f, "half_life_mean_halved_steps_s") / 60.0
                };
                assert!((2.0 * (v - vf).abs() - e).abs() < 1e-6 * (1.0 + e));
                (if by_rate { r.0 .1 } else { r.0 .0 }, v, vf)
            })
            .collect();
        l.sort_by(|a, b| a.0.total_cmp(&b.0));
        l
    };
    // (change, its numerical error) of a series
    let series = |by_rate: bool, pick: usize| -> (f64, f64) {
        let l = levels(by_rate, pick);
        let hi = l.iter().max_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        let lo = l.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap();
        let change = hi.1 - lo.1;
        (change, 2.0 * ((hi.2 - lo.2) - change).abs())
    };
    // (largest deviation from the least-squares line, its numerical error) of a series
    let bend = |by_rate: bool, pick: usize| -> (f64, f64) {
        let l = levels(by_rate, pick);
        let dev = |y: &dyn Fn(&(f64, f64, f64)) -> f64| -> Vec<f64> {
            let n = l.len() as f64;
            let mx = l.iter().map(|p| p.0).sum::<f64>() / n;
            let my = l.iter().map(y).sum::<f64>() / n;
            let b = l.iter().map(|p| (p.0 - mx) * (y(p) - my)).sum::<f64>()
                / l.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
            l.iter().map(|p| y(p) - (my + b * (p.0 - mx))).collect()
        };
        let (d, df) = (dev(&|p| p.1), dev(&|p| p.2));
        let i = (0..d.len())
            .max_by(|a, b| d[*a].abs().total_cmp(&d[*b].abs()))
            .unwrap();
        (d[i].abs(), 2.0 * (df[i] - d[i]).abs())
    };
    let (p_h, p_r, t_h, t_r) = (
        series(false, 0),
        series(true, 0),
        series(false, 1),
        series(true, 1),
    );
    let resolved = |c: (f64, f64)| c.0 > c.1;
    let compare = |a: (f64, f64), b: (f64, f64)| -> i8 {
        if a.0 - a.1 > b.0 + b.1 {
            1
        } else if b.0 - b.1 > a.0 + a.1 {
            -1
        } else {
            0
        }
    };
    let graded = |parts: &[i8]| -> Agreement {
        if parts.iter().all(|p| *p == 1) {
            Agreement::Yes
        } else if parts.iter().all(|p| *p == 0) {
            Agreement::NotComparable
        } else if !parts.contains(&1) {
            Agreement::No
        } else {
            Agreement::Partly
        }
    };
    assert_eq!(
        verdict("time-at-depth-dominates"),
        graded(&[compare(p_h, p_r), compare(t_h, t_r)]),
        "{p_h:?} {p_r:?} {t_h:?} {t_r:?}"
    );
    // 'no trend': a resolved change is a trend (disagrees), an unresolved one counts neither way
    let no_trend = |c: (f64, f64)| if resolved(c) { -1 } else { 0 };
    assert_eq!(
        verdict("no-trend-with-rate"),
        graded(&[no_trend(p_r), no_trend(t_r), no_trend(t_h)])
    );
    let rises = {
        let at = |h: f64| mean(&runs.iter().find(|r| r.0 == (h, 5.0)).unwrap().1).0;
        at(4.0) > at(0.5)
    };
    let rise_part = match (resolved(p_h), rises) {
        (true, true) => 1,
        (true, false) => -1,
        _ => 0,
    };
    assert_eq!(
        verdict("half-life-flat-plateau-rises"),
        graded(&[no_trend(t_h), rise_part])
    );
    let (pt_bend, ht_bend) = (bend(false, 0), bend(false, 1));
    assert_eq!(
        verdict("plateau-vs-time-nonlinear"),
        if resolved(pt_bend) {
            Agreement::Yes
        } else {
            Agreement::NotComparable
        },
        "{pt_bend:?}"
    );
    assert_eq!(
        verdict("half-life-vs-time-linear"),
        match (resolved(t_h), resolved(ht_bend)) {
            (false, _) => Agreement::NotComparable,
            (true, false) => Agreement::Yes,
            (true, true) => Agreement::No,
        },
        "{t_h:?} {ht_bend:?}"
    );
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
