//! Fig. 2a: final against initial radius of a bubble taken from 10⁶ to 10⁴ Pa without mass
//! transfer, for every elasticity form and Ω = 0 (§2.1.2). The gas content is fixed by the
//! Laplace balance (2.4) at P0 and R0; the final radius solves the same balance at P_f
//! ([`crate::phantom::elasticity_compare::compare`], the `elasticity` command). The caption does not pin μ
//! ("γ and μ taken from table 1", whose μ spans 0–4 MPa): shown at μ = 40 Pa (the value of the
//! Figs 4–5 captions) and at a stiffer μ.

use super::{add_verdicts, c, discrepancies, report_err, s3, Agreement, FigureOutput, Progress};
use super::{Settings, Verdict};
use crate::error::Error;
use crate::phantom::elasticity::{law_names, AllLawParams};
use crate::phantom::elasticity_compare::{compare, ElasticityRequest, ElasticityRow};
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::plot::{LinePlot, Series};

/// Initial pressure, Pa (§2.1.2).
pub const P0: f64 = 1e6;
/// Final pressure, Pa.
pub const PF: f64 = 1e4;
/// Surface tension, N/m (Table 1's upper value, the Figs 4–5 captions).
pub const GAMMA: f64 = 0.07;
/// M = K/V_aff, Pa/m³ (caption: 5 × 10⁻² Pa µm⁻³).
pub const M: f64 = 5e16;
/// Bulk modulus, Pa (caption: 2.2 GPa).
pub const K: f64 = 2.2e9;
/// The shear moduli shown, Pa: the captions' 40 Pa and a stiffer gel.
pub const MUS: [f64; 2] = [40.0, 5000.0];

/// Initial radii: 0.1 µm to 1 mm, `per_decade` points per decade.
pub fn radii(per_decade: usize) -> Vec<f64> {
    let n = 4 * per_decade;
    (0..=n)
        .map(|i| 1e-7 * 10f64.powf(i as f64 / per_decade as f64))
        .collect()
}

/// One row of fig2a.csv.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// μ, Pa.
    pub mu: f64,
    /// R0, m.
    pub r0: f64,
    /// Form.
    pub form: &'static str,
    /// Final radius, m (None: no physical root).
    pub rf: Option<f64>,
}

/// Every row, both μ.
pub fn rows(per_decade: usize) -> Result<Vec<Row>, Error> {
    let mut out = Vec::new();
    for mu in MUS {
        let req = ElasticityRequest {
            p0: P0,
            pf: PF,
            gamma: GAMMA,
            laws: AllLawParams {
                shear_modulus: mu,
                bulk_modulus_per_volume: M,
                bulk_modulus: K,
            },
            r0: radii(per_decade),
        };
        let r: Vec<ElasticityRow> = compare(&req)?;
        out.extend(r.into_iter().map(|(r0, form, rf)| Row { mu, r0, form, rf }));
    }
    Ok(out)
}

fn rf(rows: &[Row], mu: f64, r0: f64, form: &str) -> f64 {
    rows.iter()
        .find(|r| r.mu == mu && r.r0 == r0 && r.form == form)
        .and_then(|r| r.rf)
        .unwrap_or(f64::NAN)
}

/// Compute the figure.
pub fn run(settings: &Settings, progress: Progress) -> Result<FigureOutput, Error> {
    let per_decade = if settings.quick { 2 } else { 10 };
    let rows = rows(per_decade)?;
    progress("fig2a", 1, 1);
    let r0s = radii(per_decade);
    let (small, large) = (r0s[0], *r0s.last().unwrap_or(&1e-3));
    let mut files = OutputSet::new();
    let mut csv = String::from("r0_m,form,gamma,mu,m_pa_per_m3,k_pa,p0_pa,pf_pa,rf_m,rf_over_r0\n");
    for r in &rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{}\n",
            c(r.r0),
            r.form,
            c(GAMMA),
            c(r.mu),
            c(M),
            c(K),
            c(P0),
            c(PF),
            r.rf.map_or(String::new(), c),
            r.rf.map_or(String::new(), |v| c(v / r.r0)),
        ));
    }
    files.add("fig2a.csv", csv);

    let mut page = Page::new("Fig. 2a: tissue elasticity forms, no mass transfer");
    let mut verdicts = Vec::new();
    let names = law_names();
    let mut figs = Vec::new();
    for (i, mu) in MUS.iter().enumerate() {
        let mut p = LinePlot::new(
            format!("Final vs initial radius, 1e6 → 1e4 Pa, μ = {} Pa", s3(*mu)),
            "initial radius R0 (µm)",
            "final radius R_B (µm)",
        );
        p.log_x = true;
        p.log_y = true;
        p.distinct = true;
        let mut q = LinePlot::new(
            format!("Growth ratio R_B/R0, 1e6 → 1e4 Pa, μ = {} Pa", s3(*mu)),
            "initial radius R0 (µm)",
            "R_B / R0",
        );
        q.log_x = true;
        q.log_y = true;
        q.distinct = true;
        for name in &names {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.mu == *mu && r.form == *name)
                .map(|r| (r.r0 * 1e6, r.rf.map_or(f64::NAN, |v| v * 1e6)))
                .collect();
            let ratio: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.mu == *mu && r.form == *name)
                .map(|r| (r.r0 * 1e6, r.rf.map_or(f64::NAN, |v| v / r.r0)))
                .collect();
            let label = if *name == "none" { "Ω = 0" } else { name };
            p = p.with(Series::new(label, pts));
            q = q.with(Series::new(label, ratio));
        }
        let f1 = format!("fig2a-mu{}.svg", i + 1);
        let f2 = format!("fig2a-ratio-mu{}.svg", i + 1);
        figs.push((f1.clone(), p.to_svg().map_err(report_err)?, *mu, false));
        figs.push((f2.clone(), q.to_svg().map_err(report_err)?, *mu, true));
    }

    // the claims, per μ
    let mut ordering_ok = [false; 2];
    for (mi, mu) in MUS.iter().enumerate() {
        let at = |r0: f64| -> Vec<(&str, f64)> {
            names.iter().map(|n| (*n, rf(&rows, *mu, r0, n))).collect()
        };
        let spread = |r0: f64| {
            let v: Vec<f64> = at(r0)
                .iter()
                .map(|x| x.1)
                .filter(|x| x.is_finite())
                .collect();
            v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                / v.iter().cloned().fold(f64::INFINITY, f64::min)
        };
        let (sp_small, sp_large) = (spread(small), spread(large));
        verdicts.push(Verdict::new(
            format!("larger-differences-at-larger-r0:mu{}", mi + 1),
            "'larger differences occur between the expressions at larger initial bubble sizes where surface tension is less dominant' (§2.1.2)",
            format!(
                "μ = {} Pa: largest/smallest final radius over the forms {} at R0 = 0.1 µm, {} at R0 = 1 mm",
                s3(*mu),
                s3(sp_small),
                s3(sp_large)
            ),
            Agreement::of(sp_large > sp_small),
            if sp_large > sp_small { "" } else { "the shear-modulus forms do not depend on R0's scale; only 2γ/R and the Bulk Modulus term do" },
        ));
        // bulk modulus: the smallest final radius at the largest R0, and restricts large bubbles more
        let big = at(large);
        let min_form = big
            .iter()
            .filter(|x| x.1.is_finite())
            .fold(("", f64::INFINITY), |a, x| if x.1 < a.1 { *x } else { a })
            .0;
        let bm_small = rf(&rows, *mu, small, "bulk-modulus") / rf(&rows, *mu, small, "none");
        let bm_large = rf(&rows, *mu, large, "bulk-modulus") / rf(&rows, *mu, large, "none");
        let bm_ok = min_form == "bulk-modulus" && bm_large < bm_small;
        verdicts.push(Verdict::new(
            format!("bulk-modulus-restricts-large:mu{}", mi + 1),
            "'Adopting the Bulk Modulus term appears to restrict the growth of larger bubbles significantly more than the other expressions' (§2.1.2)",
            format!(
                "μ = {} Pa: at R0 = 1 mm the smallest final radius is the {}'s; R_B(bulk modulus)/R_B(Ω = 0) = {} at 0.1 µm, {} at 1 mm",
                s3(*mu),
                min_form,
                s3(bm_small),
                s3(bm_large)
            ),
            Agreement::of(bm_ok),
            if bm_ok { "" } else { "another form restricts more at this μ" },
        ));
        // continuity of displacement: the largest final radius, by how much
        let mut cod_largest = true;
        let mut worst_gain = f64::INFINITY;
        let mut no_root = 0;
        for r0 in &r0s {
            let v = at(*r0);
            let cod = rf(&rows, *mu, *r0, "continuity-of-displacement");
            if !cod.is_finite() {
                no_root += 1;
                continue;
            }
            if v.iter()
                .any(|x| x.1.is_finite() && x.1 > cod * (1.0 + 1e-12))
            {
                cod_largest = false;
            }
            worst_gain = worst_gain.min(cod / rf(&rows, *mu, *r0, "none"));
        }
        let gain_large =
            rf(&rows, *mu, large, "continuity-of-displacement") / rf(&rows, *mu, large, "none");
        let much = gain_large > 1.1;
        let agree = match (cod_largest, much) {
            (true, true) => Agreement::Yes,
            (true, false) => Agreement::Partly,
            _ => Agreement::No,
        };
        ordering_ok[mi] = bm_ok && cod_largest && much;
        verdicts.push(Verdict::new(
            format!("continuity-largest:mu{}", mi + 1),
            "'adopting the Continuity of Displacement form leads to the opposite extreme of much higher final radii due to its persistent negative sign' (§2.1.2)",
            format!(
                "μ = {} Pa: continuity of displacement gives the largest final radius at {} R0{}; its R_B is {} of Ω = 0's at R0 = 1 mm (the smallest gain over R0: {})",
                s3(*mu),
                if cod_largest { "every" } else { "not every" },
                if no_root == 0 {
                    String::new()
                } else {
                    format!(" ({no_root} R0 without an equilibrium)")
                },
                gain_pct(gain_large),
                gain_pct(worst_gain)
            ),
            agree,
            if much {
                String::new()
            } else {
                format!(
                    "at μ = {} Pa, Ω = −4μ/3 = {} Pa is small against P_f = 10⁴ Pa, so the gain is (P_f/(P_f − 4μ/3))^(1/3) − 1 = {} %: highest, but not 'much' higher",
                    s3(*mu),
                    s3(-4.0 * mu / 3.0),
                    s3(((PF / (PF - 4.0 * mu / 3.0)).cbrt() - 1.0) * 100.0)
                )
            },
        ));
    }
    let which: Vec<String> = MUS
        .iter()
        .zip(ordering_ok)
        .filter(|x| x.1)
        .map(|x| format!("{} Pa", s3(*x.0)))
        .collect();
    verdicts.push(Verdict::new(
        "ordering-mu",
        "Fig. 2a caption: 'γ and μ taken from table 1' (μ not pinned; Table 1: 0–4 × 10⁶ Pa)",
        format!(
            "the whole described ordering (Bulk Modulus restricts large bubbles most, Continuity of Displacement much the largest) holds at μ = {}",
            if which.is_empty() { "neither μ shown".to_string() } else { which.join(" and ") }
        ),
        // the caption allows any μ of Table 1's range: the claim holds if some μ shown reproduces it
        Agreement::of(!which.is_empty()),
        "the 'much higher' continuity-of-displacement radii need 4μ/3 comparable with P_f: about 1 kPa < μ < 7.5 kPa (at μ ≥ 3P_f/4 = 7.5 kPa that form has no equilibrium at 10⁴ Pa: P_B ≤ 0). The paper's figure must have used such a μ, not the 40 Pa of its later captions",
    ));

    page.text("**The paper** (§2.1.2): 'Figure 2a shows how adopting the four different forms of Ω(R_B) affects the predicted final radius (R_B) versus initial radius (R_0) of a bubble subjected to a pressure reduction from 10^6 to 10^4 Pa. … No mass transfer is assumed in these computations and hence the change in radius is determined simply by Boyle's Law (with constant temperature assumed). As one can observe, larger differences occur between the expressions at larger initial bubble sizes where surface tension is less dominant. Adopting the Bulk Modulus term appears to restrict the growth of larger bubbles significantly more than the other expressions, whereas adopting the Continuity of Displacement form leads to the opposite extreme of much higher final radii due to its persistent negative sign.' Caption: 'M = 5 × 10^-2 Pa μm^-3 [38], K = 2.2 GPa [45], γ and μ taken from table 1.'");
    add_verdicts(&mut page, &verdicts);
    page.section("Panels");
    for (f, svg, mu, ratio) in &figs {
        page.figure(
            svg,
            Some(f),
            if *ratio {
                format!("R_B/R0 against R0 at μ = {} Pa (the differences between forms, magnified). A missing point: no physical root.", s3(*mu))
            } else {
                format!("Final against initial radius at μ = {} Pa, as the paper's Fig. 2a (log axes). A missing point: no physical root.", s3(*mu))
            },
        )
        .map_err(report_err)?;
        files.add(f.clone(), svg.clone());
    }
    page.section("Equations and parameters");
    page.text(format!(
        "Laplace balance (2.4) with the ideal gas at constant temperature: (P_amb + 2γ/R + Ω(R))·(4/3)πR³ = nR_uT, the same n at P0 = {} Pa (R = R0) and P_f = {} Pa (R = R_B); R_B is its smallest root above 1 nm (safeguarded regula falsi to 1e-14, `phantom::bubble::Balance::radius_for`). Ω: none; Bulk Modulus (2.6) Ω = (4/3)πR³M, M = {} Pa/m³ (5 × 10⁻² Pa/µm³), absolute, so Ω(R0) ≠ 0; Continuity of Displacement (2.7) Ω = −4μ/3; Reference Configuration (2.8) Ω = 4μ[(1 − P0/3K)R/R0 − (1 − P_amb/3K)], K = {} Pa; Hyperelastic (2.9) Ω = (μ/2)[5 − 4(R0/R) − (R0/R)⁴]. γ = {} N/m; μ = {} Pa. R0 from 0.1 µm to 1 mm, {} points per decade. Data: `fig2a.csv` (columns r0_m, form, gamma, mu, m_pa_per_m3, k_pa, p0_pa, pf_pa, rf_m, rf_over_r0; an empty rf_m means no root). The same numbers come from `decophantom elasticity --p0 1e6 --pf 1e4 --gamma 0.07 --mu 40 --m 5e16 --k 2.2e9 --r0 ...`.",
        c(P0),
        c(PF),
        c(M),
        c(K),
        c(GAMMA),
        MUS.iter().map(|m| c(*m)).collect::<Vec<_>>().join(" and "),
        per_decade
    ));
    page.section("Where the paper disagrees with itself");
    page.text(format!("- **μ is not pinned.** The caption takes μ 'from table 1', which gives a range (0–4 MPa), not a value; the later captions use 40 Pa. See the verdicts for which μ reproduces the described ordering.\n- **Bulk Modulus: absolute or relative.** Eq. (2.6) as printed is absolute (Ω(R0) = (4/3)πR0³M ≠ 0, so a 1 mm bubble starts at Ω = 2.1e8 Pa); decophantom uses it as printed.\n{}", discrepancies(&["eq25"])));
    Ok(FigureOutput {
        files,
        page,
        verdicts,
    })
}

/// A ratio as the gain it is, in %: 1.00178 → "+0.178 %" (a ratio rounded to 1.00 hides it).
fn gain_pct(ratio: f64) -> String {
    let p = (ratio - 1.0) * 100.0;
    format!("{}{} %", if p >= 0.0 { "+" } else { "" }, s3(p))
}
