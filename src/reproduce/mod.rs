//! `decophantom reproduce`: the paper's computational figures (Walsh et al. 2017, Figs 2a, 2b,
//! 3, 5 and 6) regenerated, each with its data (CSV), panels in the style of the paper's figure
//! (SVG) and a section that quotes the paper's claim, states our number and says whether they
//! agree. One file per figure, a registry keyed by the figure's name (`fig2a`, …).
//!
//! Output layout: `DIR/<figure>/` (README.md, report.html, CSVs, SVGs) for every figure run,
//! `DIR/README.md` indexing them with every verdict, and `DIR/timing.csv` (wall times; the only
//! file that changes between identical runs). The folder is written whole or not at all
//! ([`OutputSet`]).

pub mod fig2a;
pub mod fig2b;
pub mod fig3;
pub mod fig5;
pub mod fig6;

use crate::error::{Error, InputError};
use crate::fit::report::sig;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::table::{Cell, Column, Table};
use std::path::Path;

/// How much to compute.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Settings {
    /// Reduced grids and designs (seconds instead of minutes; for tests and a first look).
    pub quick: bool,
}

/// Whether our number agrees with the paper's claim.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Agreement {
    /// It does.
    Yes,
    /// In part (some of several directions, or the sign but not the size).
    Partly,
    /// It does not.
    No,
    /// The claim is about the experiments, or needs data we do not have.
    NotComparable,
}

impl Agreement {
    /// The word in tables.
    pub fn word(self) -> &'static str {
        match self {
            Agreement::Yes => "yes",
            Agreement::Partly => "partly",
            Agreement::No => "no",
            Agreement::NotComparable => "not comparable",
        }
    }
    /// `Yes` if `ok`, else `No`.
    pub fn of(ok: bool) -> Agreement {
        if ok {
            Agreement::Yes
        } else {
            Agreement::No
        }
    }
}

/// One claim of the paper against our number.
#[derive(Debug, Clone, PartialEq)]
pub struct Verdict {
    /// Short name of the check (stable; tests look verdicts up by it).
    pub key: String,
    /// The paper's words (quoted) with their place, e.g. `§2.1.2`.
    pub claim: String,
    /// What we find, with the number.
    pub ours: String,
    /// Agreement.
    pub agrees: Agreement,
    /// Where they differ: the most likely reason (empty when they agree).
    pub why: String,
}

impl Verdict {
    /// A verdict.
    pub fn new(
        key: impl Into<String>,
        claim: impl Into<String>,
        ours: impl Into<String>,
        agrees: Agreement,
        why: impl Into<String>,
    ) -> Verdict {
        Verdict {
            key: key.into(),
            claim: claim.into(),
            ours: ours.into(),
            agrees,
            why: why.into(),
        }
    }
}

/// What a figure produced: its files (relative to its folder), page and verdicts.
#[derive(Debug, Clone)]
pub struct FigureOutput {
    /// CSVs and SVGs.
    pub files: OutputSet,
    /// The section (README.md and report.html of the figure's folder).
    pub page: Page,
    /// Claims against our numbers.
    pub verdicts: Vec<Verdict>,
}

/// Progress: (figure, runs done, runs in all).
pub type Progress<'a> = &'a (dyn Fn(&str, usize, usize) + Sync);

/// One reproducible figure.
#[derive(Debug, Clone, Copy)]
pub struct Figure {
    /// Name on the command line and folder name.
    pub name: &'static str,
    /// One line: what the figure shows.
    pub title: &'static str,
    /// Compute it.
    pub run: fn(&Settings, Progress) -> Result<FigureOutput, Error>,
}

/// The registry, in the paper's order.
pub const REGISTRY: &[Figure] = &[
    Figure {
        name: "fig2a",
        title: "Fig. 2a: final against initial radius for every elasticity form, no mass transfer",
        run: fig2a::run,
    },
    Figure {
        name: "fig2b",
        title: "Fig. 2b: the Laplace balance with the hyperelastic term for several γ/(μR0)",
        run: fig2b::run,
    },
    Figure {
        name: "fig3",
        title: "Fig. 3: one-at-a-time sensitivity of R_max and t_max (and Sobol' indices)",
        run: fig3::run,
    },
    Figure {
        name: "fig5",
        title: "Fig. 5: plateau radius and half-life against time at depth and decompression rate",
        run: fig5::run,
    },
    Figure {
        name: "fig6",
        title:
            "Fig. 6a, b: plateau radius against R0; bubbles at different distances from the faces",
        run: fig6::run,
    },
];

/// The figures named by `name` (`all` or one of [`REGISTRY`]).
pub fn select(name: &str) -> Result<Vec<&'static Figure>, InputError> {
    let n = name.trim().to_ascii_lowercase();
    if n == "all" {
        return Ok(REGISTRY.iter().collect());
    }
    REGISTRY
        .iter()
        .find(|f| f.name == n)
        .map(|f| vec![f])
        .ok_or_else(|| {
            InputError::new(format!(
                "unknown figure '{name}'; use all or one of {}",
                REGISTRY
                    .iter()
                    .map(|f| f.name)
                    .collect::<Vec<_>>()
                    .join(", ")
            ))
            .in_file("<command line>")
            .field("FIGURE")
        })
}

/// A figure that was reproduced.
#[derive(Debug, Clone)]
pub struct Reproduced {
    /// Its registry entry.
    pub figure: Figure,
    /// Its verdicts.
    pub verdicts: Vec<Verdict>,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
}

/// Run the figures and write `out` whole (see the module documentation).
pub fn reproduce(
    figures: &[&Figure],
    settings: &Settings,
    out: &Path,
    command: &str,
    progress: Progress,
) -> Result<Vec<Reproduced>, Error> {
    let mut set = OutputSet::new();
    let mut done = Vec::new();
    for f in figures {
        let start = std::time::Instant::now();
        let mut o = (f.run)(settings, progress)?;
        let wall = start.elapsed().as_secs_f64();
        o.page.text(format!(
            "Written by `{command}`{}.",
            if settings.quick {
                " (--quick: reduced grids and designs)"
            } else {
                ""
            }
        ));
        o.files
            .add("README.md", o.page.to_markdown().map_err(Error::Solver)?);
        o.files
            .add("report.html", o.page.to_html().map_err(Error::Solver)?);
        set.nest(f.name, o.files);
        done.push(Reproduced {
            figure: **f,
            verdicts: o.verdicts,
            wall_seconds: wall,
        });
    }
    set.add("README.md", index(&done, settings, command)?);
    let mut timing = String::from("figure,wall_seconds\n");
    for d in &done {
        timing.push_str(&format!("{},{:.1}\n", d.figure.name, d.wall_seconds));
    }
    set.add("timing.csv", timing);
    set.commit(out)?;
    Ok(done)
}

/// `DIR/README.md`: every verdict, figure by figure, and where the paper disagrees with itself.
fn index(done: &[Reproduced], settings: &Settings, command: &str) -> Result<String, Error> {
    let mut s = String::from("# The paper's figures, reproduced\n\n");
    s.push_str("Walsh et al. (2017) *A combined three-dimensional in vitro–in silico approach to modelling bubble dynamics in decompression sickness*, J. R. Soc. Interface 14: 20170653. Each folder holds one figure: its data (CSV), panels (SVG), and a section (README.md, also report.html) with the paper's claim quoted, our number, whether they agree and, where they do not, the most likely reason; the equations, parameters and every setting used.\n\n");
    s.push_str(&format!(
        "Written by `{command}`{}. Wall times are in `timing.csv`, written beside this file by each run (the repository does not keep it: it changes from run to run).\n\n",
        if settings.quick {
            " with --quick (reduced grids and designs)"
        } else {
            ""
        }
    ));
    s.push_str("| figure | claims | agree | partly | disagree | not comparable |\n|---|---|---|---|---|---|\n");
    for d in done {
        let c = |a: Agreement| d.verdicts.iter().filter(|v| v.agrees == a).count();
        s.push_str(&format!(
            "| [{}]({}/README.md) | {} | {} | {} | {} | {} |\n",
            d.figure.name,
            d.figure.name,
            d.verdicts.len(),
            c(Agreement::Yes),
            c(Agreement::Partly),
            c(Agreement::No),
            c(Agreement::NotComparable)
        ));
    }
    for d in done {
        s.push_str(&format!(
            "\n## [{}]({}/README.md)\n\n",
            d.figure.title, d.figure.name
        ));
        s.push_str(
            &verdict_table(&d.verdicts)
                .to_markdown()
                .map_err(Error::Solver)?,
        );
    }
    s.push_str("\n## Where the paper disagrees with itself, and what decophantom does\n\n");
    for (_, text) in DISCREPANCIES {
        s.push_str(&format!("- {text}\n"));
    }
    Ok(s)
}

/// What one part of a claim came to, judged above the numerical error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Part {
    /// The comparison agrees with the claim, above the numerical error.
    Agrees,
    /// It disagrees, above the numerical error.
    Disagrees,
    /// The comparison is within the numerical error: the model cannot tell.
    Unresolved,
}

/// A claim of several parts, judged on its resolved parts only: yes if every part agrees, not
/// comparable if no part is resolved, no if no part agrees (and one at least disagrees), partly
/// if some agree and the others disagree or are unresolved. An unresolved part counts neither
/// way: it cannot turn a disagreement into 'partly' nor an agreement into 'no'.
pub fn grade(parts: &[Part]) -> Agreement {
    if parts.iter().all(|p| *p == Part::Agrees) {
        Agreement::Yes
    } else if parts.iter().all(|p| *p == Part::Unresolved) {
        Agreement::NotComparable
    } else if !parts.contains(&Part::Agrees) {
        Agreement::No
    } else {
        Agreement::Partly
    }
}

/// Whether `a` exceeds `b` (each with its numerical error): agrees when a − e_a > b + e_b,
/// disagrees when b − e_b > a + e_a, unresolved otherwise.
pub fn exceeds((a, ea): (f64, f64), (b, eb): (f64, f64)) -> Part {
    if a - ea > b + eb {
        Part::Agrees
    } else if b - eb > a + ea {
        Part::Disagrees
    } else {
        Part::Unresolved
    }
}

/// The document with every step limit halved ([`crate::fit::model::halve_step_limits`]): the refined
/// run of a numerical-error estimate (Fig. 5's half-life, Fig. 3's metrics); `path` names the
/// document in errors.
pub fn halve_steps(doc: &toml::Table, path: &Path) -> Result<toml::Table, Error> {
    let mut doc = doc.clone();
    crate::fit::model::halve_step_limits(&mut doc).map_err(|m| InputError::new(m).in_file(path))?;
    Ok(doc)
}

/// The verdicts as a table.
pub fn verdict_table(v: &[Verdict]) -> Table {
    let mut t = Table::new(
        "",
        vec![
            Column::plain("claim (paper)"),
            Column::plain("ours"),
            Column::plain("agrees?"),
            Column::plain("note; where not, the most likely reason"),
        ],
    );
    for x in v {
        // the columns are fixed: a push cannot fail
        let _ = t.push(vec![
            Cell::text(x.claim.clone()),
            Cell::text(x.ours.clone()),
            Cell::text(x.agrees.word()),
            Cell::text(x.why.clone()),
        ]);
    }
    t
}

/// Add the verdict table to a figure's page.
pub fn add_verdicts(page: &mut Page, v: &[Verdict]) {
    page.section("The paper's claims against ours");
    page.table(&verdict_table(v));
}

/// Places where the paper's text, captions, tables and published code disagree, keyed for the
/// figures that touch them; each says what decophantom does.
pub const DISCREPANCIES: &[(&str, &str)] = &[
    ("ln2", "**L_N2, 0.014 or 0.145.** Table 1 gives the Ostwald coefficient of N2 as 0.014; the captions of Figs 4 and 5 give LN2 = 0.145, ten times as much (and Fig. 3's modal 0.0436 lies between). decophantom uses 0.014 (`gases.n2.ostwald` in the presets) and reads the captions' 0.145 as a misprint."),
    ("dsurf", "**The D_surf law.** §4.1 says D_surf 'was a function of R_B^2 and had a value of D_bulk/30 at t = 0, R_B = R_0', i.e. D_surf = (D_bulk/30)(R/R0)²; the Fig. 5 caption says only 'D_surf = D_bulk/30'; the authors' published code uses (D_bulk/k)(1 − R0/R)², which is zero at R = R0. decophantom has all three (`material.surface.law` = `area` (the text; default R_ref = each bubble's R0, `reference_radius_m` for one fixed R_ref, capped at D_bulk), `fold`, `authors-code`); the hydrogel preset uses the text's `area`."),
    ("psi", "**The psi gauge.** The paper writes '130 psi = 9.0 × 10^5 Pa' (Fig. 5) and '8.9 × 10^5 Pa (130 psi)' (Fig. 6c): the gauge value converted (130 × 6894.76 Pa = 8.96e5 Pa). A chamber at 130 psi gauge holds 9.98e5 Pa absolute. decophantom reads psi as gauge (`psi-gauge`), so the Fig. 5/6 dives reach 101 325 + 8.96e5 = 9.98e5 Pa absolute."),
    ("units", "**Units in Table 1 and the Fig. 5 caption.** D_O2 is given in cm² s⁻¹ with the same numbers as D_N2 in m² s⁻¹; the Fig. 5 caption gives D_bulk in 'm s⁻²'; the 'specific gas constants' α = 92.07 and 80.6 kJ kg⁻¹ are R·T/M at 310 K (8.314 × 310/28 and 8.314 × 310/32), not the specific gas constants R/M. decophantom uses m² s⁻¹ for both gases and the universal gas constant with moles."),
    ("eq25", "**Eqs 2.5 and 2.10** (dR/dt) carry sign and term misprints (e.g. −2γ(1/3R + 1/R²) in the denominator of 2.5; 4γ/3R′ with + signs elsewhere in 2.10). decophantom does not integrate dR/dt: it carries the moles of each gas and solves the Laplace balance (2.4) with the ideal gas law for R each step."),
    ("gamma", "**The γ range.** Table 1 gives γ = 0.042–0.07 N m⁻¹ (modal 0.056 in the Fig. 3 caption); §2.3.1 speaks of 'the lowest and highest values of surface tension used in these simulations (γ = 0.04 and γ = 0.073 N m⁻¹)'. decophantom's Fig. 3 uses Table 1's range."),
];

/// The discrepancy texts with the given keys, as a Markdown list.
pub fn discrepancies(keys: &[&str]) -> String {
    DISCREPANCIES
        .iter()
        .filter(|(k, _)| keys.contains(k))
        .map(|(_, t)| format!("- {t}\n"))
        .collect()
}

/// A number with 3 significant digits (tables and verdicts).
pub fn s3(v: f64) -> String {
    sig(v, 3)
}

/// A CSV number: the shortest decimal that reads back to the same `f64`.
pub fn c(v: f64) -> String {
    crate::sweep::num(v)
}

/// Error for a plot or page that could not be made.
pub fn report_err(e: impl std::fmt::Display) -> Error {
    Error::Solver(format!("reproduce: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Above, below and within the errors (numbers worked by hand).
    #[test]
    fn exceeds_judges_a_difference_against_both_errors() {
        assert_eq!(exceeds((10.0, 1.0), (5.0, 1.0)), Part::Agrees);
        assert_eq!(exceeds((5.0, 1.0), (10.0, 1.0)), Part::Disagrees);
        // 10 − 3 = 7 is not above 5 + 3 = 8
        assert_eq!(exceeds((10.0, 3.0), (5.0, 3.0)), Part::Unresolved);
        assert_eq!(exceeds((10.0, 0.0), (10.0, 0.0)), Part::Unresolved);
    }
}
