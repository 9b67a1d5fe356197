//! `decophantom check`: run one candidate schedule through the phantom and score it against
//! a criteria file. The schedule comes from `plan --out` (TOML), a CSV of waypoints
//! `time_min,depth_m[,gas]` (in the conventions of its `# conventions:` line, which `plan`
//! writes, else DecoTengu's: 1.01325 bar at the surface, 9 985 Pa/m, alveolar water vapour
//! 6 270 Pa; air unless a gas column says otherwise), the paper's
//! two-column `.txt`, a dive of a Subsurface or UDDF log (its own surface pressure and water
//! density; import notes printed and reported), or is written by hand. Every schedule is
//! watched at the surface after it for the criteria protocol's time.

use crate::algorithm::conventions::DECOTENGU;
use crate::algorithm::waypoints::read_schedule_with_notes;
use crate::error::Error;
use crate::evaluate::link::{dive_history, PhantomSpec};
use crate::evaluate::matrix::run_matrix;
use crate::evaluate::report::{add_report, finish_page, ReportContext};
use crate::evaluate::{Candidate, Evaluation};
use crate::gas::GasMix;
use crate::report::html::Page;
use crate::report::output::OutputSet;
use crate::report::table::sig_text;
use crate::risk::load_criteria;
use std::fmt::Write as _;
use std::path::PathBuf;

/// What `check` needs.
#[derive(Debug, Clone)]
pub struct CheckRequest {
    /// Schedule file (`.toml`, `.csv`, legacy `.txt`, or a Subsurface/UDDF dive log).
    pub schedule: PathBuf,
    /// Which dive of a dive log (1-based; required when the log holds more than one).
    pub dive: Option<crate::profile::sequence::DiveSelection>,
    /// Criteria file.
    pub criteria: PathBuf,
    /// Phantom file (built-in hydrogel-dive if absent).
    pub phantom: Option<PathBuf>,
    /// Grid step override, m.
    pub grid_step_m: Option<f64>,
    /// Repeat the dive after this surface interval, min.
    pub repeat_after_min: Option<f64>,
    /// Write the report here, if given.
    pub out: Option<PathBuf>,
}

/// The outcome: the evaluation and the text to print.
#[derive(Debug)]
pub struct CheckOutcome {
    /// The evaluation (one candidate, the phantom's own law).
    pub evaluation: Evaluation,
    /// True when every criterion passes (exit code 0; else 1).
    pub all_pass: bool,
    /// Criteria table as text.
    pub text: String,
}

/// Run `check`. Bad input → [`Error::Input`] before anything is simulated or written.
pub fn run(
    req: &CheckRequest,
    progress: &mut (dyn FnMut(f64, f64) + Send),
) -> Result<CheckOutcome, Error> {
    // the output folder is checked before anything is simulated (and again at the commit)
    let mut inputs = vec![req.schedule.as_path(), req.criteria.as_path()];
    inputs.extend(req.phantom.as_deref());
    if let Some(out) = &req.out {
        crate::report::output::check_target(out, &inputs)?;
    }
    let criteria = load_criteria(&req.criteria)?;
    let phantom = PhantomSpec::load(req.phantom.as_deref(), req.grid_step_m)?;
    let imp = read_schedule_with_notes(&req.schedule, &DECOTENGU, GasMix::AIR, req.dive)?;
    let schedule = imp.schedule;
    let history = dive_history(&schedule, &criteria.protocol, req.repeat_after_min)
        .map_err(|e| e.or_in_file(&req.schedule))?;
    let law = phantom.own_law();
    let cand = Candidate {
        label: schedule.label.clone(),
        source: req.schedule.display().to_string(),
        schedule,
        history,
        notes: imp.notes,
    };
    let ev = run_matrix(vec![cand], phantom, vec![law], criteria, progress)?;
    let all_pass = ev.all_pass();
    let mut text = String::new();
    for n in &ev.candidates[0].notes {
        let _ = writeln!(text, "note: {n}");
    }
    let _ = writeln!(
        text,
        "{} through {} ({law}):",
        ev.candidates[0].label, ev.phantom.params.name
    );
    let _ = writeln!(
        text,
        "{:<32} {:>12} {:>12} {:>12}  {:<10} {:<6} absolute",
        "criterion", "value", "limit", "margin", "unit", "result"
    );
    for s in &ev.runs[0].scores {
        let _ = writeln!(
            text,
            "{:<32} {:>12} {:>12} {:>12}  {:<10} {:<6} {}",
            s.label,
            sig_text(s.value, 4, true),
            sig_text(s.limit, 4, true),
            sig_text(s.margin, 4, true),
            s.unit,
            if s.pass { "pass" } else { "FAIL" },
            s.absolute.map(|a| sig_text(a, 4, true)).unwrap_or_default()
        );
    }
    let fails = ev.runs[0].scores.iter().filter(|s| !s.pass).count();
    let _ = writeln!(
        text,
        "{}",
        if all_pass {
            "all criteria pass".to_string()
        } else {
            format!("{fails} criterion/criteria FAIL")
        }
    );
    if let Some(out) = &req.out {
        let mut page = Page::new(format!("Schedule check: {}", ev.candidates[0].label));
        let mut set = OutputSet::new();
        let ctx = ReportContext {
            dive: format!("schedule {}", req.schedule.display()),
            criteria_source: req.criteria.display().to_string(),
            repeat_after_min: req.repeat_after_min,
            command: None,
        };
        add_report(&mut page, &mut set, "", &ev, &ctx)?;
        finish_page(&mut page, &mut set, "")?;
        set.commit_with_inputs(out, &inputs)?;
    }
    Ok(CheckOutcome {
        evaluation: ev,
        all_pass,
        text,
    })
}
