//! Fig. 6a: plateau radius against the initial radius R0 on the Fig. 6 dive (20 min at 130 psi
//! gauge), three randomly placed bubbles per run, under the two readings of the area law
//! (R_ref = each bubble's R0; one fixed R_ref) and the constant fold of the Fig. 5 caption.
//! Fig. 6b: three equal bubbles at different distances from the open faces.

use super::fig5::{dive, growth, hydrogel, simulate, GRID_STEP, GRID_STEP_QUICK, STATS_NOTE};
use super::{add_verdicts, c, discrepancies, report_err, s3, Agreement, FigureOutput, Progress};
use super::{exceeds, grade, halve_steps, Part, Settings, Verdict};
use crate::error::{Error, InputError};
use crate::fit::paths;
use crate::fit::stats::linear_fit;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::plot::{LinePlot, Series};
use crate::report::table::{Cell, Column, Table};
use crate::run::SimRun;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Fixed reference radius of the second area-law reading, m (where §4.1 fitted the law: the
/// mean R0 of the oscillation experiment).
pub const R_REF: f64 = 0.2e-3;
/// R_min as a fraction of R0 (the preset's 80/86.5: the nuclei reopen late in the ascent).
pub const RMIN_FRACTION: f64 = 80.0 / 86.5;

/// The surface-law readings: (key, label).
pub const READINGS: [(&str, &str); 3] = [
    ("area-r0", "area law, R_ref = R0"),
    ("area-fixed", "area law, R_ref = 0.2 mm"),
    ("fold", "constant fold 30"),
];

fn with_reading(doc: &mut toml::Table, key: &str) -> Result<(), Error> {
    let bad = |m: String| Error::from(InputError::new(m).in_file(super::fig5::HYDROGEL_PATH));
    match key {
        "area-r0" => Ok(()),
        "area-fixed" => paths::set(doc, "material.surface.reference_radius_m", R_REF).map_err(bad),
        _ => {
            let mut t = toml::Table::new();
            t.insert("law".into(), "fold".into());
            t.insert("fold".into(), 30.0.into());
            let m = doc
                .get_mut("material")
                .and_then(|m| m.as_table_mut())
                .ok_or_else(|| bad("the preset has no [material]".into()))?;
            m.insert("surface".into(), toml::Value::Table(t));
            Ok(())
        }
    }
}

fn set_r0(doc: &mut toml::Table, r0: f64) -> Result<(), Error> {
    let bad = |m: String| Error::from(InputError::new(m).in_file(super::fig5::HYDROGEL_PATH));
    paths::set(doc, "population.initial_radius_m", r0).map_err(bad)?;
    paths::set(doc, "nuclei.min_radius_m", RMIN_FRACTION * r0).map_err(bad)
}

/// Mean radius of all bubbles at each frame (µm) against time since the end of the ascent (min).
fn mean_course(run: &SimRun, t_surface: f64) -> Vec<(f64, f64)> {
    run.frames
        .iter()
        .filter(|f| f.time >= t_surface - 60.0 && !f.bubbles.is_empty())
        .map(|f| {
            let m = f.bubbles.iter().map(|b| b.radius).sum::<f64>() / f.bubbles.len() as f64;
            ((f.time - t_surface) / 60.0, m * 1e6)
        })
        .collect()
}

fn course(run: &SimRun, id: usize, t_surface: f64) -> Vec<(f64, f64)> {
    run.frames
        .iter()
        .filter(|f| f.time >= t_surface - 60.0)
        .filter_map(|f| {
            f.bubbles
                .iter()
                .find(|b| b.id == id)
                .map(|b| ((f.time - t_surface) / 60.0, b.radius * 1e6))
        })
        .collect()
}

/// A bubble's growth over the first 5 min after the decompression (m) and its time to 95 % of
/// its largest radius (s), from its course (minutes after the decompression, µm).
fn early_and_late(cr: &[(f64, f64)]) -> (f64, f64) {
    let at = |t_min: f64| -> f64 { cr.iter().find(|p| p.0 >= t_min).map_or(f64::NAN, |p| p.1) };
    let g5 = (at(5.0) - at(0.0)) * 1e-6;
    let rmax = cr.iter().map(|p| p.1).fold(0.0, f64::max);
    let r_start = at(0.0);
    let t = cr
        .iter()
        .find(|p| p.0 >= 0.0 && p.1 >= r_start + 0.95 * (rmax - r_start))
        .map_or(f64::NAN, |p| p.0 * 60.0);
    (g5, t)
}

/// Mean, lowest and highest plateau radius (µm) of a run's bubbles whose growth fit
/// converged (NaN, ∞, −∞ when none did).
fn plateaus(g: &[super::fig5::BubbleGrowth]) -> (f64, f64, f64) {
    let p: Vec<f64> = g
        .iter()
        .map(|b| b.3 * 1e6)
        .filter(|x| x.is_finite())
        .collect();
    let m = if p.is_empty() {
        f64::NAN
    } else {
        p.iter().sum::<f64>() / p.len() as f64
    };
    let (lo, hi) = p.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |a, x| {
        (a.0.min(*x), a.1.max(*x))
    });
    (m, lo, hi)
}

/// How the curvature is judged, said once on the page.
pub const CURVATURE_RULE: &str = "Curvature (Fig. 6a's 'nonlinearly'): a simulation is deterministic, so whether the plateau bends is judged by the numerical error, not by a p-value. The mean plateaus are fitted by a least-squares line over R0; the series counts as curved only where the largest deviation of a mean from that line exceeds that deviation's own numerical error: twice its change when every step limit is halved (the same level's deviation from the line of the halved-step means; the Richardson estimate of a first-order scheme, the rule of Figs 3 and 5). Each step between neighbouring R0 is judged the same way: the difference of the two means against twice its own change with the steps halved. A deviation or step within its error is unresolved: the model cannot tell a line from a curve, or a rise from none, there. The F-tests are printed as a description of the shape only.";

/// Compute the figure.
pub fn run(settings: &Settings, progress: Progress) -> Result<FigureOutput, Error> {
    let h = if settings.quick {
        GRID_STEP_QUICK
    } else {
        GRID_STEP
    };
    let base = hydrogel(h)?;
    let r0s: Vec<f64> = if settings.quick {
        vec![40e-6, 86.5e-6, 160e-6]
    } else {
        vec![40e-6, 60e-6, 86.5e-6, 120e-6, 160e-6]
    };
    let profile = dive(1200.0, 6.9e4, 8.9e4)?;
    let top = crate::units::ATM_PA + 130.0 * crate::units::PSI_PA;
    let t_surface =
        (top - crate::units::ATM_PA) / 6.9e4 + 1200.0 + (top - crate::units::ATM_PA) / 8.9e4;
    // 6a cases and the 6b run
    let mut cases: Vec<(usize, f64)> = Vec::new();
    for ri in 0..READINGS.len() {
        for r in &r0s {
            cases.push((ri, *r));
        }
    }
    // every run twice: as set, and with every step limit halved (the numerical error)
    let total = 2 * (cases.len() + 1);
    let done = AtomicUsize::new(0);
    let path = std::path::Path::new(super::fig5::HYDROGEL_PATH);
    let jobs: Vec<(usize, f64, bool)> = [false, true]
        .iter()
        .flat_map(|&half| cases.iter().map(move |&(ri, r0)| (ri, r0, half)))
        .collect();
    let runs: Vec<Result<SimRun, Error>> = jobs
        .par_iter()
        .map(|&(ri, r0, half)| {
            let mut doc = base.clone();
            with_reading(&mut doc, READINGS[ri].0)?;
            set_r0(&mut doc, r0)?;
            if half {
                doc = halve_steps(&doc, path)?;
            }
            let r = simulate(&doc, &profile);
            progress("fig6", done.fetch_add(1, Ordering::Relaxed) + 1, total);
            r
        })
        .collect();
    let mut runs: Vec<SimRun> = runs.into_iter().collect::<Result<_, _>>()?;
    let runs_half = runs.split_off(cases.len());

    // 6b: three equal nuclei at mid-height-ish, from near the side wall to the axis
    let mut doc_b = base.clone();
    doc_b.remove("population");
    let z = 1.5e-3;
    let xs = [1.0e-3, 3.0e-3, 5.5e-3];
    let bubbles: Vec<toml::Value> = xs
        .iter()
        .map(|x| {
            let mut t = toml::Table::new();
            t.insert(
                "position_m".into(),
                toml::Value::Array(vec![(*x).into(), 5.5e-3.into(), z.into()]),
            );
            t.insert("initial_radius_m".into(), 86.5e-6.into());
            toml::Value::Table(t)
        })
        .collect();
    doc_b.insert("bubbles".into(), toml::Value::Array(bubbles));
    let doc_b_half = halve_steps(&doc_b, path)?;
    let (run_b, run_b_half) = rayon::join(
        || simulate(&doc_b, &profile),
        || simulate(&doc_b_half, &profile),
    );
    let (run_b, run_b_half) = (run_b?, run_b_half?);
    progress("fig6", total, total);

    let mut files = OutputSet::new();
    let mut verdicts = Vec::new();
    let mut page = Page::new("Fig. 6: initial radius and position of the bubbles");
    page.text("**The paper** (§4.2.1): 'As nucleation is a stochastic process it was not possible to experimentally vary R0 and so its effect was, therefore, investigated primarily using the computational model. The results are shown in figure 6a. As one observes, increasing R0 increased the plateau radius nonlinearly (figure 6a, inset), as expected given the larger initial surface area for gas to diffuse through and the lower surface tension.' (§4.2.2): 'Figure 6b shows the results for three simulated bubbles. As can be seen, the bubble nearest the edge of the phantom has the lowest plateau radius (bubble 1). Those closer to the centre exhibit a slower rate of growth initially (due to the lower dissolved gas concentration in their immediate neighbourhood); but continue to grow for longer, as the centre of the phantom takes longer to desaturate.' Caption (a): 'decompression profile with 20 min at a depth 9.0 × 10^5 Pa with 8.9 × 10^4 Pa s^-1 decompression rate and 6.9 × 10^4 Pa s^-1 compression rate. All other simulation parameters were the same as those in figure 5. Error bars show the range of radial values for three randomly positioned bubbles all with the same initial radius. Inset shows the relation between R0 and mean plateau radius.'");

    // ---- 6a
    let mut csv =
        String::from("reading,r0_m,bubble,x_m,y_m,z_m,plateau_m,half_life_s,max_radius_m\n");
    let mut inset = LinePlot::new(
        "Fig. 6a inset: mean plateau radius against R0",
        "initial radius R0 (µm)",
        "mean plateau radius (µm)",
    );
    let mut table = Table::new(
        "Plateau radius (fit) by R0: mean [range over the three bubbles]",
        std::iter::once(Column::new("R0", "µm"))
            .chain(READINGS.iter().map(|r| Column::new(r.1, "µm")))
            .collect(),
    );
    let mut means: Vec<Vec<f64>> = vec![Vec::new(); READINGS.len()];
    let mut means_half: Vec<Vec<f64>> = vec![Vec::new(); READINGS.len()];
    let mut rising: Vec<Part> = Vec::new();
    let mut cells: Vec<Vec<String>> = vec![Vec::new(); r0s.len()];
    let mut course_figs: Vec<(String, String, String)> = Vec::new();
    for (ri, (key, label)) in READINGS.iter().enumerate() {
        let mut pts = Vec::new();
        let mut courses = LinePlot::new(
            format!("Fig. 6a: mean radius of the three bubbles, {label}"),
            "time after the decompression (min)",
            "radius (µm)",
        );
        for (k, r0) in r0s.iter().enumerate() {
            let run = &runs[ri * r0s.len() + k];
            let g = growth(run);
            for b in &g {
                let rmax = run
                    .frames
                    .iter()
                    .flat_map(|f| f.bubbles.iter().filter(|x| x.id == b.0))
                    .map(|x| x.radius)
                    .fold(0.0, f64::max);
                csv.push_str(&format!(
                    "{key},{},{},{},{},{},{},{},{}\n",
                    c(*r0),
                    b.0,
                    c(b.2[0]),
                    c(b.2[1]),
                    c(b.2[2]),
                    c(b.3),
                    c(b.4),
                    c(rmax)
                ));
            }
            let (m, lo, hi) = plateaus(&g);
            means[ri].push(m);
            means_half[ri].push(plateaus(&growth(&runs_half[ri * r0s.len() + k])).0);
            pts.push((r0 * 1e6, m));
            cells[k].push(format!("{} [{}, {}]", s3(m), s3(lo), s3(hi)));
            courses = courses.with(Series::new(
                format!("R0 = {} µm", s3(r0 * 1e6)),
                mean_course(run, t_surface),
            ));
        }
        inset = inset.with(Series::new(*label, pts));
        let f = format!("fig6a-courses-{key}.svg");
        let svg = courses.to_svg().map_err(report_err)?;
        files.add(f.clone(), svg.clone());
        course_figs.push((f, svg, format!("Mean radius of the three bubbles against time after the decompression, one line per R0 ({label}); the paper's error bars (range over the bubbles) are in fig6a.csv.")));
        // the claim, per reading, judged above the numerical error: twice the change of each
        // mean plateau with every step limit halved
        let err: Vec<f64> = means[ri]
            .iter()
            .zip(&means_half[ri])
            .map(|(a, b)| 2.0 * (a - b).abs())
            .collect();
        // each step between neighbouring R0 against its own numerical error (Fig. 3's rule)
        let steps: Vec<Part> = (1..r0s.len())
            .map(|k| {
                let d = means[ri][k] - means[ri][k - 1];
                let e = 2.0 * ((means_half[ri][k] - means_half[ri][k - 1]) - d).abs();
                exceeds((d, e), (0.0, 0.0))
            })
            .collect();
        let inc = if steps.iter().all(|p| *p == Part::Agrees) {
            Part::Agrees
        } else if steps.contains(&Part::Disagrees) {
            Part::Disagrees
        } else {
            Part::Unresolved
        };
        rising.push(inc);
        let xs: Vec<f64> = r0s.iter().map(|r| r * 1e6).collect();
        let lf = linear_fit(&xs, &means[ri]);
        let reg = super::fig5::regress(&xs, &means[ri]);
        // the curvature, judged by the numerical error of the means (the rule of Fig. 5), not
        // by a p-value: the simulation has no noise
        let bent = super::fig5::curvature_over_levels(&xs, &means[ri], &means_half[ri]);
        let curved = if bent.resolved {
            Part::Agrees
        } else {
            Part::Unresolved
        };
        let ours = format!(
            "{label}: mean plateau {} µm for R0 = {} µm ({}; numerical error of the means {} µm); largest deviation of the means from their least-squares line {} µm against its numerical error {} µm: {}. {}",
            means[ri]
                .iter()
                .map(|m| s3(*m))
                .collect::<Vec<_>>()
                .join(" / "),
            r0s.iter()
                .map(|r| s3(r * 1e6))
                .collect::<Vec<_>>()
                .join(" / "),
            match inc {
                Part::Agrees => "increasing",
                Part::Disagrees => "not increasing",
                Part::Unresolved => "a step within the numerical error",
            },
            err.iter().map(|e| s3(*e)).collect::<Vec<_>>().join(" / "),
            s3(bent.deviation.abs()),
            s3(bent.bound),
            if bent.resolved {
                "curved beyond the numerical error"
            } else {
                "within the numerical error (a line and a curve cannot be told apart)"
            },
            match (lf, reg.curvature, reg.saturating) {
                (Some(l), Some(q), Some(a)) => format!(
                    "Fits (a description of the shape, not a test: the simulation has no noise): line R² = {}; quadratic vs line p = {}, one-phase association vs line p = {}",
                    s3(l.r2),
                    s3(q.p_value),
                    s3(a.vs_line.p_value),
                ),
                (Some(l), _, _) => format!(
                    "Fit (a description of the shape, not a test: the simulation has no noise): line R² = {}",
                    s3(l.r2)
                ),
                _ => String::new(),
            },
        );
        verdicts.push(Verdict::new(
            format!("fig6a-plateau-rises-with-r0:{key}"),
            "'increasing R0 increased the plateau radius nonlinearly (figure 6a, inset)' (§4.2.1)",
            ours,
            match (inc, curved) {
                (Part::Disagrees, _) => Agreement::No,
                (Part::Unresolved, _) => Agreement::NotComparable,
                (Part::Agrees, c) => grade(&[Part::Agrees, c]),
            },
            if inc == Part::Agrees && curved == Part::Agrees {
                String::new()
            } else if inc == Part::Unresolved {
                "a step of the mean plateau between neighbouring R0 is within the numerical error".to_string()
            } else if inc == Part::Agrees {
                format!("the plateau rises with R0, but its largest deviation from a straight line ({} µm) is within twice the numerical error of the means ({} µm): whether it curves is unresolved", s3(bent.deviation), s3(bent.bound))
            } else if *key == "area-r0" {
                "with D_surf = (D_bulk/30)(R/R0)² a small nucleus that grows to a given radius has a far more permeable skin than a large nucleus at the same radius, so smaller nuclei grow more: this reading of the area law cannot be what the paper's Fig. 6a used".into()
            } else {
                "the growth is limited by the surface layer, whose permeability here does not favour large nuclei enough".into()
            },
        ));
    }
    for (k, r0) in r0s.iter().enumerate() {
        let mut row = vec![Cell::text(s3(r0 * 1e6))];
        row.extend(cells[k].iter().map(|s| Cell::text(s.clone())));
        table.push(row).map_err(report_err)?;
    }
    let which: Vec<&str> = READINGS
        .iter()
        .enumerate()
        .filter(|(ri, _)| rising[*ri] == Part::Agrees)
        .map(|(_, r)| r.1)
        .collect();
    verdicts.push(Verdict::new(
        "fig6a-which-reading",
        "§4.1: D_surf 'was a function of R_B^2 and had a value of D_bulk/30 at t = 0, R_B = R0'; Fig. 6a caption: 'All other simulation parameters were the same as those in figure 5'",
        format!(
            "Fig. 6a's trend (larger R0, larger plateau) is reproduced by: {}",
            if which.is_empty() { "none of the readings".to_string() } else { which.join("; ") }
        ),
        if which.contains(&"area law, R_ref = R0") && which.len() == READINGS.len() {
            Agreement::Yes
        } else if which.is_empty() {
            Agreement::No
        } else {
            Agreement::Partly
        },
        "the paper's literal wording (R_ref = each bubble's own R0) reverses the trend; a law referred to one fixed radius, or no area dependence, gives the paper's trend. The paper's Fig. 6a cannot have used the per-bubble reading",
    ));
    files.add("fig6a.csv", csv);
    let inset_svg = inset.to_svg().map_err(report_err)?;
    files.add("fig6a-plateau.svg", inset_svg.clone());

    // ---- 6b
    let gb = growth(&run_b);
    let radius = 5.5e-3;
    let dist: Vec<f64> = gb
        .iter()
        .map(|b| {
            let r = ((b.2[0] - radius).powi(2) + (b.2[1] - radius).powi(2)).sqrt();
            (radius - r).min(5e-3 - b.2[2])
        })
        .collect();
    let mut csv_b = String::from("bubble,x_m,y_m,z_m,distance_to_open_face_m,plateau_m,half_life_s,growth_first_5min_m,time_to_95pct_of_max_s\n");
    let mut plot_b = LinePlot::new(
        "Fig. 6b: three bubbles at different distances from the open faces",
        "time after the decompression (min)",
        "radius (µm)",
    );
    let mut early = Vec::new();
    let mut t95 = Vec::new();
    for (b, d) in gb.iter().zip(&dist) {
        let cr = course(&run_b, b.0, t_surface);
        let (g5, t) = early_and_late(&cr);
        early.push(g5);
        t95.push(t);
        csv_b.push_str(&format!(
            "{},{},{},{},{},{},{},{},{}\n",
            b.0,
            c(b.2[0]),
            c(b.2[1]),
            c(b.2[2]),
            c(*d),
            c(b.3),
            c(b.4),
            c(g5),
            c(t)
        ));
        plot_b = plot_b.with(Series::new(
            format!("bubble {}: {} mm from an open face", b.0 + 1, s3(d * 1e3)),
            cr,
        ));
    }
    files.add("fig6b.csv", csv_b);
    let svg_b = plot_b.to_svg().map_err(report_err)?;
    files.add("fig6b.svg", svg_b.clone());
    // the numerical error of each measure: twice its change with every step limit halved
    let gb_half = growth(&run_b_half);
    let half: Vec<(f64, f64, f64)> = gb
        .iter()
        .map(|b| {
            let p = gb_half
                .iter()
                .find(|x| x.0 == b.0)
                .map_or(f64::NAN, |x| x.3);
            let (g5, t) = early_and_late(&course(&run_b_half, b.0, t_surface));
            (p, g5, t)
        })
        .collect();
    let e_plateau: Vec<f64> = gb
        .iter()
        .zip(&half)
        .map(|(b, h)| 2.0 * (b.3 - h.0).abs())
        .collect();
    let e_early: Vec<f64> = early
        .iter()
        .zip(&half)
        .map(|(a, h)| 2.0 * (a - h.1).abs())
        .collect();
    let e_t95: Vec<f64> = t95
        .iter()
        .zip(&half)
        .map(|(a, h)| 2.0 * (a - h.2).abs())
        .collect();
    let nearest = (0..gb.len())
        .min_by(|a, b| dist[*a].total_cmp(&dist[*b]))
        .unwrap_or(0);
    let lowest = (0..gb.len())
        .min_by(|a, b| gb[*a].3.total_cmp(&gb[*b].3))
        .unwrap_or(0);
    let plateau_text = gb
        .iter()
        .zip(&e_plateau)
        .map(|(b, e)| format!("{} ± {}", s3(b.3 * 1e6), s3(e * 1e6)))
        .collect::<Vec<_>>()
        .join(" / ");
    // the nearest bubble's plateau below every other's, above the errors
    let lowest_part = {
        let parts: Vec<Part> = (0..gb.len())
            .filter(|i| *i != nearest)
            .map(|i| exceeds((gb[i].3, e_plateau[i]), (gb[nearest].3, e_plateau[nearest])))
            .collect();
        if parts.iter().all(|p| *p == Part::Agrees) {
            Part::Agrees
        } else if parts.contains(&Part::Disagrees) {
            Part::Disagrees
        } else {
            Part::Unresolved
        }
    };
    let dists = dist
        .iter()
        .map(|d| s3(d * 1e3))
        .collect::<Vec<_>>()
        .join(" / ");
    verdicts.push(Verdict::new(
        "fig6b-nearest-edge-lowest",
        "'the bubble nearest the edge of the phantom has the lowest plateau radius (bubble 1)' (§4.2.2)",
        format!("distances to the nearest open face {dists} mm → plateau {plateau_text} µm (± the numerical error){}", if nearest == lowest { "" } else { "; the nearest is not the lowest" }),
        grade(&[lowest_part]),
        match lowest_part {
            Part::Agrees => "",
            Part::Unresolved => "the plateaus differ by less than their numerical error",
            Part::Disagrees => "the bubbles compete for the same gas; see the courses",
        },
    ));
    let order: Vec<usize> = {
        let mut o: Vec<usize> = (0..gb.len()).collect();
        o.sort_by(|a, b| dist[*a].total_cmp(&dist[*b]));
        o
    };
    let (near, far) = (order[0], order[order.len() - 1]);
    let slower_early = exceeds((early[near], e_early[near]), (early[far], e_early[far]));
    let longer = exceeds((t95[far], e_t95[far]), (t95[near], e_t95[near]));
    verdicts.push(Verdict::new(
        "fig6b-centre-slower-then-longer",
        "'Those closer to the centre exhibit a slower rate of growth initially … but continue to grow for longer, as the centre of the phantom takes longer to desaturate' (§4.2.2)",
        format!(
            "growth over the first 5 min after the decompression {} µm; time to 95 % of the largest radius {} min (nearest to farthest: {}; ± the numerical error)",
            order.iter().map(|i| format!("{} ± {}", s3(early[*i] * 1e6), s3(e_early[*i] * 1e6))).collect::<Vec<_>>().join(" / "),
            order.iter().map(|i| format!("{} ± {}", s3(t95[*i] / 60.0), s3(e_t95[*i] / 60.0))).collect::<Vec<_>>().join(" / "),
            order.iter().map(|i| format!("bubble {}", i + 1)).collect::<Vec<_>>().join(", ")
        ),
        grade(&[slower_early, longer]),
        if slower_early == Part::Agrees && longer == Part::Agrees {
            ""
        } else if slower_early == Part::Unresolved || longer == Part::Unresolved {
            "a part is within the numerical error (the ± figures: twice the change with every step limit halved)"
        } else if longer == Part::Agrees {
            "the central bubble does grow for longer, but not more slowly at first: all three start from the same R0 in gel that is equally supersaturated in the first minutes (diffusion has not yet reached them from the faces)"
        } else {
            "see the courses"
        },
    ));

    add_verdicts(&mut page, &verdicts);
    page.section("Fig. 6a");
    page.table(&table);
    page.text(CURVATURE_RULE);
    page.figure(&inset_svg, Some("fig6a-plateau.svg"), "Mean plateau radius (exponential growth fit) against R0 for each reading of the surface law (the paper's inset).").map_err(report_err)?;
    for (f, svg, cap) in &course_figs {
        page.figure(svg, Some(f), cap.clone()).map_err(report_err)?;
    }
    page.section("Fig. 6b");
    page.figure(&svg_b, Some("fig6b.svg"), "Radius of the three equal nuclei (R0 = 86.5 µm) against time after the decompression; the legend gives each one's distance to the nearest open face (the side wall or the top; the bottom is sealed).").map_err(report_err)?;
    page.text(STATS_NOTE);
    page.section("Equations and parameters");
    page.text(format!(
        "As Fig. 5 ([../fig5/README.md](../fig5/README.md)): the preset `profiles/phantoms/hydrogel.toml` at h = {} µm, hyperelastic μ = 40 Pa, γ = 0.07 N/m, D_bulk = 2.5e-9 m²/s, L_N2 = 0.014, L_O2 = 0.027; profile: 6.9e4 Pa/s to 130 psi gauge, 20 min, 8.9e4 Pa/s to the surface, 2 h there. Fig. 6a: three nuclei placed by the seeded population (seed 2017; the same positions for every R0 and reading, see fig6a.csv), R0 ∈ {{{}}} µm, R_min = {}·R0 (the preset's 80/86.5, so that every nucleus reopens at the same point of the ascent), under three surface laws: D_surf = (D_bulk/30)(R/R0)² (the text's wording, each bubble's own R0), (D_bulk/30)(R/0.2 mm)² (one fixed R_ref, where §4.1 fitted it), both capped at D_bulk, and D_bulk/30 (the Fig. 5 caption). Fig. 6b: three nuclei R0 = 86.5 µm at height z = {} mm (3.5 mm below the open top) and {} mm from the side wall along one radius (the last on the axis), with the preset's area law. Plateau: the exponential growth fit from the end of the decompression. Data: `fig6a.csv`, `fig6b.csv`. Bubbles are numbered from 1 in the text and panels, as in the paper's Fig. 6b; the CSV files number them from 0, as every other output of decophantom does (bubble 1 here is bubble 0 there).",
        s3(h * 1e6),
        r0s.iter().map(|r| s3(r * 1e6)).collect::<Vec<_>>().join(", "),
        s3(RMIN_FRACTION),
        s3(z * 1e3),
        xs.iter().map(|x| s3(x * 1e3)).collect::<Vec<_>>().join(", ")
    ));
    page.section("Where the paper disagrees with itself");
    page.text(format!(
        "- **Fig. 6a's pressure**: '9.0 × 10^5 Pa' for the 130 psi of the other captions, and Fig. 6c writes 8.9 × 10^5 Pa for the same 130 psi.\n{}",
        discrepancies(&["dsurf", "psi", "ln2"])
    ));
    Ok(FigureOutput {
        files,
        page,
        verdicts,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A step between neighbouring R0 is judged against its own numerical error: both
    /// means moving together with the steps halved (a common error) leave the step resolved,
    /// a step that changes by more than half itself is not. Numbers by hand.
    #[test]
    fn a_step_between_r0_levels_is_judged_against_its_own_error() {
        let judge = |m: [f64; 2], half: [f64; 2]| {
            let d = m[1] - m[0];
            exceeds((d, 2.0 * ((half[1] - half[0]) - d).abs()), (0.0, 0.0))
        };
        // +10 µm, each mean 4 µm higher with the steps halved: error 0, rises
        assert_eq!(judge([300.0, 310.0], [304.0, 314.0]), Part::Agrees);
        // +1 µm, +1.8 with the steps halved: error 1.6 > 1: unresolved
        assert_eq!(judge([300.0, 301.0], [300.0, 301.8]), Part::Unresolved);
        // −5 µm, −5.5 halved: error 1: falls
        assert_eq!(judge([300.0, 295.0], [300.0, 294.5]), Part::Disagrees);
    }
}
