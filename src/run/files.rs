//! The files of a run: `bubbles.csv`, `summary.toml`, `timing.toml`, `steps.csv` and the two
//! plots, added to an [`OutputSet`] (written whole or not at all).

use super::plots::{radius_plot, volume_plot};
use super::text::{ending_text, event_text};
use super::{SimRun, TracedStep};
use crate::error::Error;
use crate::gas::Gas;
use crate::phantom::sim::{Frame, StepScheme, StepWall};
use crate::report::output::OutputSet;
use serde::Serialize;

/// What a run's per-bubble plots say when no bubble ever existed in it (a nucleation model
/// whose nuclei never activated, or none placed): the run is valid, its plots are empty.
pub const NO_BUBBLE: &str = "No bubble in this run: no nucleus activated and none was placed, so there is no radius or volume to draw (summary.toml and bubbles.csv say the same).";

/// `bubbles.csv`: `time_s,bubble,radius_m,volume_m3,area_m2` then `n_<gas>_mol` per gas; one row per
/// active bubble per recorded frame.
pub fn bubbles_csv(frames: &[Frame], gases: &[Gas]) -> String {
    let mut s = String::from("time_s,bubble,radius_m,volume_m3,area_m2");
    for g in gases {
        s.push_str(&format!(",n_{}_mol", g.name()));
    }
    s.push('\n');
    for f in frames {
        for b in &f.bubbles {
            s.push_str(&format!(
                "{:.6},{},{:.9e},{:.9e},{:.9e}",
                f.time, b.id, b.radius, b.volume, b.area
            ));
            for n in &b.moles {
                s.push_str(&format!(",{n:.9e}"));
            }
            s.push('\n');
        }
    }
    s
}

#[derive(Serialize)]
struct SummaryFile<'a> {
    profile: &'a str,
    phantom: &'a str,
    ending: String,
    end_time_s: f64,
    max_radius_m: f64,
    max_radius_time_s: f64,
    max_radius_bubble: usize,
    final_radius_m: Vec<f64>,
    peak_total_volume_m3: f64,
    peak_total_volume_time_s: f64,
    gas_balance_error: f64,
    steps_explicit: usize,
    steps_implicit: usize,
    cells: usize,
    events: Vec<String>,
    #[serde(skip_serializing_if = "Vec::is_empty")]
    import_notes: Vec<String>,
}

/// `timing.toml` text: the run's wall-clock time, kept out of `summary.toml` so that the
/// summary of the same inputs is byte-identical from run to run (and a committed report does
/// not change when it is regenerated).
pub fn timing_toml(run: &SimRun) -> String {
    let p = &run.phases;
    format!(
        "# wall-clock time of this run on the machine that ran it (not a result)\n\
         wall_seconds = {}\n\n\
         # of it, the time loop's phases summed over the steps, s (src/phantom/sim/record.rs, StepWall):\n\
         # prepare: the bubbles' fluxes at the start of each step, the step's choice, the exchange;\n\
         # gel: the gel's diffusion; events: perfusion, radii, corrector, coalescence, nucleation,\n\
         # displacement (of them: corrector, displacement); frames: the frames recorded\n\
         [phases]\n\
         prepare_s = {:.6}\ngel_s = {:.6}\nevents_s = {:.6}\ncorrector_s = {:.6}\n\
         displacement_s = {:.6}\nframes_s = {:.6}\n",
        run.wall_seconds,
        p.prepare_s,
        p.gel_s,
        p.events_s,
        p.corrector_s,
        p.displacement_s,
        p.frame_s
    ) + &gel_by_scheme_toml(&run.gel_by_scheme)
}

/// `timing.toml`'s `[gel_by_scheme]`: per scheme of the gel's step, the steps taken and the
/// wall time of their diffusion (the cost of one step of each scheme is the ratio).
fn gel_by_scheme_toml(by: &[(usize, f64); 3]) -> String {
    let mut s = String::from(
        "\n# the steps of each scheme and the wall time of their diffusion (gel_s), s\n[gel_by_scheme]\n",
    );
    for (scheme, (n, t)) in StepScheme::ALL.iter().zip(by) {
        let name = scheme.name();
        s.push_str(&format!("{name}_steps = {n}\n{name}_s = {t:.6}\n"));
    }
    s
}

/// `summary.toml` text (results only: identical for identical inputs; the wall time is in
/// [`timing_toml`]).
pub fn summary_toml(run: &SimRun, profile: &str, phantom: &str) -> Result<String, Error> {
    let s = &run.summary;
    let f = SummaryFile {
        profile,
        phantom,
        ending: ending_text(&s.ending),
        end_time_s: s.end_time,
        max_radius_m: s.max_radius.0,
        max_radius_time_s: s.max_radius.1,
        max_radius_bubble: s.max_radius.2,
        final_radius_m: s.final_radii.clone(),
        peak_total_volume_m3: s.peak_total_volume.0,
        peak_total_volume_time_s: s.peak_total_volume.1,
        gas_balance_error: s.gas_balance_error,
        steps_explicit: s.steps.0,
        steps_implicit: s.steps.1,
        cells: s.cells,
        events: s.events.iter().map(event_text).collect(),
        import_notes: run.notes.clone(),
    };
    toml::to_string(&f).map_err(|e| Error::Solver(format!("summary.toml: {e}")))
}

fn plot_err(e: impl std::fmt::Display) -> Error {
    Error::Solver(format!("plot: {e}"))
}

/// `steps.csv`: one row per step the loop took (`--trace-steps`): its start and length, the
/// scheme, the limit that set it, the step the physics allowed, the bubbles' error estimate
/// over it as a fraction of their tolerance, the next steps the three error estimates allow
/// (`inf`: no limit), the wall time since the run started ([`TracedStep::wall_s`]: not a
/// result, it differs from run to run), and the bubble that gave the error estimate (empty
/// without one) with its flux of each gas at the start and at the end of the step (mol/s,
/// positive into the bubble; the end is the corrector's, before its correction), then the wall
/// time of the step's phases, s ([`StepWall`]: prepare, gel, events, of them the corrector and
/// the displacement, and the frame; not results either).
pub fn steps_csv(steps: &[TracedStep], gases: &[Gas]) -> String {
    let mut s = String::from(
        "time_s,dt_s,scheme,limit,physics_dt_s,bubble_error,next_bubble_dt_s,next_field_dt_s,next_loading_dt_s,wall_s,bubble",
    );
    for when in ["start", "end"] {
        for g in gases {
            s.push_str(&format!(",flux_{when}_{}_mol_s", g.name()));
        }
    }
    s.push_str(&format!(",{}\n", StepWall::CSV_HEADER));
    for t in steps {
        let r = &t.record;
        s.push_str(&format!(
            "{:.6},{:.6e},{},{},{:.6e},{:.6e},{:.6e},{:.6e},{:.6e},{:.6},",
            r.time,
            r.dt,
            r.scheme.name(),
            r.limit.name(),
            r.physics_dt,
            r.bubble_error,
            r.next_bubble_dt,
            r.next_field_dt,
            r.next_loading_dt,
            t.wall_s
        ));
        if let Some(b) = r.bubble {
            s.push_str(&b.to_string());
        }
        for j in [&r.flux_start, &r.flux_end] {
            for x in &j[..gases.len()] {
                if r.bubble.is_some() {
                    s.push_str(&format!(",{x:.9e}"));
                } else {
                    s.push(',');
                }
            }
        }
        s.push_str(&format!(",{}\n", r.wall.csv_fields()));
    }
    s
}

/// The files of a simulation, added to `set` under `prefix`: bubbles.csv, summary.toml,
/// radius.svg, volume.svg, timing.toml (the wall time, which differs from run to run), and
/// steps.csv when the steps were traced.
pub fn add_run_files(
    set: &mut OutputSet,
    prefix: &str,
    run: &SimRun,
    profile_name: &str,
    phantom_name: &str,
) -> Result<(), Error> {
    let gases = &run.summary.gases;
    set.add(
        format!("{prefix}bubbles.csv"),
        bubbles_csv(&run.frames, gases),
    );
    set.add(
        format!("{prefix}summary.toml"),
        summary_toml(run, profile_name, phantom_name)?,
    );
    set.add(format!("{prefix}timing.toml"), timing_toml(run));
    if !run.steps.is_empty() {
        set.add(format!("{prefix}steps.csv"), steps_csv(&run.steps, gases));
    }
    let title = format!("{profile_name} — {phantom_name}");
    set.add(
        format!("{prefix}radius.svg"),
        radius_plot(&run.frames, &format!("Bubble radius: {title}"))
            .to_svg_or_message(NO_BUBBLE)
            .map_err(plot_err)?,
    );
    set.add(
        format!("{prefix}volume.svg"),
        volume_plot(&run.frames, &format!("Bubble volume: {title}"))
            .to_svg_or_message(NO_BUBBLE)
            .map_err(plot_err)?,
    );
    Ok(())
}
