//! Fig. 2b: the Laplace balance (2.4) with the hyperelastic term (2.9), non-dimensionalised by
//! μ: (P_B − P_amb)/μ = 2Γ/λ + ½(5 − 4/λ − λ⁻⁴) with Γ = γ/(μR0) and λ = R/R0, for several Γ.
//! The elastic term is the library's [`Hyperelastic`] law evaluated through
//! [`Balance::internal_pressure`].

use super::{add_verdicts, c, report_err, s3, Agreement, FigureOutput, Progress, Settings};
use super::{discrepancies, Verdict};
use crate::error::Error;
use crate::phantom::bubble::Balance;
use crate::phantom::elasticity::Hyperelastic;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::plot::{LinePlot, Series};

/// The values of Γ = γ/(μR0) shown.
pub const GAMMAS: [f64; 7] = [0.01, 0.1, 0.5, 1.0, 1.5, 2.0, 10.0];

/// Stretch at which the shares of the two terms are compared.
pub const LAMBDA_CMP: f64 = 2.0;

/// (P_B − P_amb)/μ and its elastic and surface parts at stretch λ for Γ, from the library's
/// balance with μ = 1 Pa, R0 = 1 m, γ = Γ N/m.
pub fn excess(gamma_ratio: f64, lambda: f64) -> (f64, f64, f64) {
    let law = Hyperelastic { shear_modulus: 1.0 };
    let b = Balance {
        ambient: 1e5,
        surface_tension: gamma_ratio,
        law: &law,
        initial_radius: 1.0,
        initial_ambient: 1e5,
        fixed_gases: 0.0,
    };
    let total = b.internal_pressure(lambda) - 1e5;
    let surface = 2.0 * gamma_ratio / lambda;
    (total, total - surface, surface)
}

/// Compute the figure.
pub fn run(settings: &Settings, progress: Progress) -> Result<FigureOutput, Error> {
    let n = if settings.quick { 40 } else { 400 };
    let lambdas: Vec<f64> = (0..=n).map(|i| 1.0 + 4.0 * i as f64 / n as f64).collect();
    let mut csv = String::from(
        "gamma_over_mu_r0,stretch,excess_pressure_over_mu,elastic_over_mu,surface_over_mu\n",
    );
    let mut plot = LinePlot::new(
        "Laplace balance with the hyperelastic term",
        "stretch R_B / R0",
        "(P_B − P_amb) / μ",
    );
    for g in GAMMAS {
        let mut pts = Vec::new();
        for l in &lambdas {
            let (t, e, s) = excess(g, *l);
            csv.push_str(&format!("{},{},{},{},{}\n", c(g), c(*l), c(t), c(e), c(s)));
            pts.push((*l, t));
        }
        plot = plot.with(Series::new(format!("γ/(μR0) = {}", s3(g)), pts));
    }
    progress("fig2b", 1, 1);
    // log y: the curves span three decades (0.02–20 at Γ = 0.01–10); on a linear axis set by
    // Γ = 10 the others and the peak at (Γ − 1)^(−1/3) for 1 < Γ < 2 are flattened to its floor
    plot.log_y = true;
    let svg = plot.to_svg().map_err(report_err)?;
    let mut files = OutputSet::new();
    files.add("fig2b.csv", csv);
    files.add("fig2b.svg", svg.clone());

    // the claim: small Γ → elasticity dominates, large Γ → surface tension dominates
    let shares: Vec<(f64, f64)> = GAMMAS
        .iter()
        .map(|g| {
            let (t, e, _) = excess(*g, LAMBDA_CMP);
            (*g, e / t)
        })
        .collect();
    let decreasing = shares.windows(2).all(|w| w[1].1 < w[0].1);
    let first = shares[0];
    let last = shares[shares.len() - 1];
    // the crossover Γ* where both terms are equal at λ: 2Γ/λ = ½(5 − 4/λ − λ⁻⁴)
    let l = LAMBDA_CMP;
    let cross = l * 0.5 * (5.0 - 4.0 / l - l.powi(-4)) / 2.0;
    // shape: d/dλ = (2/λ²)(1 + λ⁻³ − Γ): rising for Γ ≤ 1 (largest at the end of the range,
    // tending to 2.5 as λ → ∞), a maximum at λ* = (Γ − 1)^(−1/3) for 1 < Γ < 2, falling from
    // λ = 1 for Γ ≥ 2
    let mut shape_ok = true;
    let mut shape = Vec::new();
    for g in GAMMAS {
        let v: Vec<f64> = lambdas.iter().map(|l| excess(g, *l).0).collect();
        let imax = v
            .iter()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |a, (i, x)| if *x > a.1 { (i, *x) } else { a },
            )
            .0;
        let lmax = lambdas[imax];
        let want = if g <= 1.0 {
            *lambdas.last().unwrap_or(&5.0)
        } else if g < 2.0 {
            (g - 1.0).powf(-1.0 / 3.0)
        } else {
            1.0
        };
        let step = 4.0 / n as f64;
        if (lmax - want).abs() > 1.5 * step {
            shape_ok = false;
        }
        shape.push(format!("Γ = {}: largest at λ = {}", s3(g), s3(lmax)));
    }
    let verdicts = vec![
        Verdict::new(
            "elastic-share-falls-with-gamma",
            "'For smaller values of γ/μR0, resistance to bubble growth is predominantly due to tissue elasticity, whereas for larger values the resistance is predominantly due to surface tension' (§2.1.2)",
            format!(
                "elastic share of P_B − P_amb at R = 2R0: {} % at Γ = {}, {} % at Γ = {}, falling monotonically with Γ; equal shares at Γ* = {} (analytic: λ(5 − 4/λ − λ⁻⁴)/4 at λ = 2)",
                s3(first.1 * 100.0),
                s3(first.0),
                s3(last.1 * 100.0),
                s3(last.0),
                s3(cross)
            ),
            Agreement::of(decreasing && first.1 > 0.5 && last.1 < 0.5),
            "",
        ),
        Verdict::new(
            "shape-of-the-curves",
            "(not stated in the text) the curves' shape: where the resistance to growth peaks",
            format!(
                "d/dλ[(P_B − P_amb)/μ] = (2/λ²)(1 + λ⁻³ − Γ): for Γ ≤ 1 the resistance rises with every stretch (towards 2.5μ: elasticity wins), for 1 < Γ < 2 it peaks at λ* = (Γ − 1)^(−1/3) and then falls, for Γ ≥ 2 it falls from λ = 1 (surface tension wins; a bubble that starts to grow meets less and less resistance). Computed on λ ∈ [1, 5]: {}",
                shape.join("; ")
            ),
            Agreement::of(shape_ok),
            "",
        ),
    ];
    let mut page = Page::new("Fig. 2b: the Laplace balance with the hyperelastic term");
    page.text("**The paper** (§2.1.2): 'Figure 2b shows the plot of the Laplace equation with the Hyperelastic form for different values of the dimensionless parameter γ/μR0. For smaller values of γ/μR0, resistance to bubble growth is predominantly due to tissue elasticity, whereas for larger values the resistance is predominantly due to surface tension.' Caption: '(b) The Laplace equation using the hyperelastic term for variations of the non-dimensional parameter γ/μR0.'");
    add_verdicts(&mut page, &verdicts);
    page.section("Panel");
    page.figure(&svg, Some("fig2b.svg"), "The excess pressure of the bubble over ambient, in units of μ, against the stretch R/R0, for several Γ = γ/(μR0). The paper's axes are not stated in its text; this is the balance (2.4) with (2.9) non-dimensionalised by μ, which depends on Γ alone.").map_err(report_err)?;
    page.section("Equations and parameters");
    page.text(format!(
        "P_B = P_amb + 2γ/R + Ω(R) (2.4) with Ω = (μ/2)[5 − 4(R/R0)⁻¹ − (R/R0)⁻⁴] (2.9). Divided by μ, with λ = R/R0 and Γ = γ/(μR0): (P_B − P_amb)/μ = 2Γ/λ + ½(5 − 4/λ − λ⁻⁴). Evaluated with the library's law at μ = 1 Pa, R0 = 1 m, γ = Γ N/m. Γ ∈ {{{}}}, λ from 1 to 5 in {} steps. Data: `fig2b.csv`.",
        GAMMAS.iter().map(|g| s3(*g)).collect::<Vec<_>>().join(", "),
        n
    ));
    page.section("Where the paper disagrees with itself");
    page.text(format!("- The text calls this 'the Laplace equation'; with Ω it is the Young–Laplace balance (2.4) extended by the tissue term.\n{}", discrepancies(&["eq25"])));
    Ok(FigureOutput {
        files,
        page,
        verdicts,
    })
}
