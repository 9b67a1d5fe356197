//! `decophantom plan`: load an algorithm file, plan a dive, format the stop table.

use crate::algorithm::config::{load_algorithm_with, Overrides};
use crate::algorithm::oxygen::{self, OxygenExposure};
use crate::algorithm::plan_dive;
use crate::algorithm::schedule::{gas_text, ScheduleSummary};
use crate::algorithm::waypoints::CONVENTIONS_COMMENT;
use crate::algorithm::{DivePlan, LoadedAlgorithm, Schedule};
use crate::error::InputError;
use crate::gas::GasMix;
use crate::report::output::{same_file, write_new_file, CommentStyle};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Output format of the stop table.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlanFormat {
    /// Markdown table plus summary lines.
    #[default]
    Md,
    /// CSV `depth_m,stop_min,runtime_min,gas`; the last row (depth 0) is the arrival at the
    /// surface, its runtime the total dive time.
    Csv,
    /// The schedule TOML (as `--out` writes it).
    Toml,
}

impl PlanFormat {
    /// Parse `md`, `csv`, `toml`.
    pub fn parse(s: &str) -> Option<PlanFormat> {
        match s.trim().to_ascii_lowercase().as_str() {
            "md" | "markdown" => Some(PlanFormat::Md),
            "csv" => Some(PlanFormat::Csv),
            "toml" => Some(PlanFormat::Toml),
            _ => None,
        }
    }

    /// `md`, `csv` or `toml`.
    pub fn name(self) -> &'static str {
        match self {
            PlanFormat::Md => "md",
            PlanFormat::Csv => "csv",
            PlanFormat::Toml => "toml",
        }
    }
}

/// What the user asked for.
#[derive(Debug, Clone)]
pub struct PlanRequest {
    /// The algorithm TOML file.
    pub algorithm: PathBuf,
    /// Maximum depth, m.
    pub depth_m: f64,
    /// Bottom time, min.
    pub time_min: f64,
    /// Bottom gas (`air`, `32`, `18/45` ...); air if absent.
    pub gas: Option<String>,
    /// Deco gases, `50@21` or `50` (switch at the MOD at 1.6 bar).
    pub deco_gases: Vec<String>,
    /// Travel gases `21/35@0..60` (breathed from the surface to 60 m, then the next travel
    /// gas or the bottom gas); repeatable, ranges following each other from the surface.
    pub travel_gases: Vec<String>,
    /// Format of the printed table.
    pub format: PlanFormat,
    /// Where to write the schedule, if anywhere (whole or not at all). It ends with a comment
    /// line holding a hash of the lines above ([`crate::report::output::marker_line`]); an
    /// existing file is replaced only if `plan` wrote it and it is unchanged since.
    pub out: Option<PathBuf>,
    /// Format of `out` when given explicitly (`--format`); else from its extension
    /// (`.toml` the schedule TOML, `.csv` waypoints, `.md` the table; any other is refused,
    /// [`out_format`]).
    pub out_format: Option<PlanFormat>,
    /// Command-line settings replacing the algorithm file's (`--gf`, `--ascent-rate` ...).
    pub overrides: Overrides,
    /// The altitude the surface pressure was computed from (`--altitude`), m, for the echo.
    pub altitude_m: Option<f64>,
    /// Where to write the dive-profile figure (depth, ceiling, tissue heat map), if anywhere.
    pub plot: Option<PathBuf>,
}

/// CNS oxygen clock above which the plan is warned about, % (NOAA Diving Manual: 100 % is
/// the single-exposure limit of the CNS clock).
pub const CNS_WARN_PERCENT: f64 = 100.0;
/// Oxygen tolerance units above which a single-day plan is warned about (Hamilton's REPEX
/// single-day limit of 300 OTU for repetitive exposures; 850 for a single exceptional one).
pub const OTU_WARN: f64 = 300.0;
/// Longest bottom time searched for a no-decompression limit, min (a day).
pub const NDL_SEARCH_MAX_MIN: f64 = 1440.0;

/// The format `--out` is written in: the explicit one, else from the extension. The name must
/// end in `.toml` (the schedule TOML) or `.csv` (waypoints), the extensions `check`,
/// `simulate` and `evaluate --schedule` read those formats by, or `.md` (the stop table, for
/// people): any other name (`.txt`, which they read as the paper's two-column format, or none,
/// which they refuse) would hold a schedule no command reads back, and is refused before
/// planning. An explicit format that contradicts the extension (`--format toml --out s.csv`)
/// is refused.
pub fn out_format(
    out: &std::path::Path,
    given: Option<PlanFormat>,
) -> Result<PlanFormat, InputError> {
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let by_ext = match ext.as_deref() {
        Some("toml") => Some(PlanFormat::Toml),
        Some("csv") => Some(PlanFormat::Csv),
        Some("md" | "markdown") => Some(PlanFormat::Md),
        _ => None,
    };
    let Some(by_ext) = by_ext else {
        let found = match ext.as_deref() {
            Some("txt") => {
                "'.txt' (read as the paper's two-column minutes/metres format)".to_string()
            }
            Some(e) => format!("'.{e}'"),
            None => "no extension".to_string(),
        };
        return Err(InputError::new(format!(
            "the file name has {found}; name it .toml (the schedule TOML) or .csv (waypoints time_min,depth_m,gas), which check, simulate and evaluate --schedule read by their extension, or .md (the stop table, for reading)"
        ))
        .in_file(out)
        .field("--out"));
    };
    match given {
        Some(g) if g != by_ext => Err(InputError::new(format!(
            "--format {} contradicts the file name's extension; name the file .{} or drop --format",
            g.name(),
            g.name()
        ))
        .in_file(out)
        .field("--out")),
        _ => Ok(by_ext),
    }
}

/// The planned dive and its formatted table.
#[derive(Debug, Clone)]
pub struct PlanOutcome {
    /// The schedule.
    pub schedule: Schedule,
    /// CNS % and OTU.
    pub oxygen: OxygenExposure,
    /// The no-decompression limit when the dive has no stops, whole min at the planned depth
    /// on the planned gases (`None`: the dive has stops; `Some(None)`: no limit within
    /// [`NDL_SEARCH_MAX_MIN`]).
    pub ndl_min: Option<Option<f64>>,
    /// Settings used (algorithm, gradient factors, conventions), as echoed with the table.
    pub settings: Vec<(String, String)>,
    /// Warnings (CNS above 100 %, OTU above 300).
    pub warnings: Vec<String>,
    /// The text to print, in the requested format.
    pub text: String,
}

/// Plan the dive; write `--out` if asked. Bad input → [`InputError`] (exit code 2).
pub fn run(req: &PlanRequest) -> Result<PlanOutcome, crate::error::Error> {
    // check the outputs before planning: the format, that neither is an input nor the other
    // output, that neither replaces an existing file other than one `plan` wrote and nobody
    // changed since, and that the folders they go into exist and can be written to
    let inputs = [req.algorithm.as_path()];
    if let (Some(o), Some(p)) = (&req.out, &req.plot) {
        if same_place(o, p) {
            return Err(InputError::new(
                "--plot names the same file as --out; the figure would replace the schedule: give each its own file",
            )
            .in_file(p)
            .field("--plot")
            .into());
        }
    }
    let out = match &req.out {
        Some(o) => {
            let f = out_format(o, req.out_format)?;
            if same_file(o, &req.algorithm) {
                return Err(InputError::new(
                    "--out names the algorithm file; give another file name (outputs never replace inputs)",
                )
                .in_file(o)
                .field("--out")
                .into());
            }
            crate::report::output::check_new_file(o, &inputs, "--out", "plan")?;
            Some((o, f))
        }
        None => None,
    };
    if let Some(p) = &req.plot {
        crate::report::output::check_new_file(p, &inputs, "--plot", "plan")?;
    }
    let alg = load_algorithm_with(&req.algorithm, &req.overrides)?;
    let (plan, schedule) = plan_dive(
        &alg,
        req.depth_m,
        req.time_min,
        req.gas.as_deref(),
        &req.deco_gases,
        &req.travel_gases,
    )?;
    let oxygen = oxygen::exposure(&schedule);
    check_plan_numbers(&schedule, &oxygen)?;
    let ndl_min = if schedule.stops.is_empty() {
        Some(no_deco_limit(&alg, &plan))
    } else {
        None
    };
    let settings = settings(&alg, req, &plan);
    let mut warnings = Vec::new();
    if oxygen.cns_percent > CNS_WARN_PERCENT {
        warnings.push(format!(
            "CNS oxygen clock {:.0} % exceeds {CNS_WARN_PERCENT:.0} % (NOAA single-exposure limit)",
            oxygen.cns_percent
        ));
    }
    if oxygen.otu > OTU_WARN {
        warnings.push(format!(
            "{:.0} OTU exceeds {OTU_WARN:.0} (REPEX daily limit for repetitive exposure)",
            oxygen.otu
        ));
    }
    let summary = ScheduleSummary {
        runtime_min: Some(schedule.runtime_min()),
        cns_percent: Some(oxygen.cns_percent),
        otu: Some(oxygen.otu),
        algorithm: Some(req.algorithm.display().to_string()),
    };
    let toml_text = schedule.to_toml_string(Some(&summary));
    let extras = MdExtras {
        ndl_min,
        settings: &settings,
        warnings: &warnings,
    };
    if let Some((path, f)) = out {
        let bytes = match f {
            PlanFormat::Toml => toml_text.clone(),
            PlanFormat::Csv => waypoints_csv(&schedule),
            PlanFormat::Md => markdown(&schedule, &plan, &oxygen, &extras),
        };
        let style = match f {
            PlanFormat::Md => CommentStyle::Xml,
            PlanFormat::Toml | PlanFormat::Csv => CommentStyle::Hash,
        };
        write_new_file(path, &bytes, style, &inputs, "--out", "plan")?;
    }
    if let Some(path) = &req.plot {
        let svg = profile_figure(&schedule, &alg.conventions)
            .to_svg()
            .map_err(|e| crate::error::Error::Solver(e.to_string()))?;
        write_new_file(path, &svg, CommentStyle::Xml, &inputs, "--plot", "plan")?;
    }
    let text = match req.format {
        PlanFormat::Toml => toml_text,
        PlanFormat::Csv => csv_table(&schedule),
        PlanFormat::Md => markdown(&schedule, &plan, &oxygen, &extras),
    };
    Ok(PlanOutcome {
        schedule,
        oxygen,
        ndl_min,
        settings,
        warnings,
        text,
    })
}

/// The longest whole-minute bottom time at the plan's depth and gases that needs no stop
/// (the no-decompression limit), found by doubling and bisection over the algorithm itself —
/// the same algorithm, conventions and overrides as the plan, so it agrees with it by
/// construction. `None` when even [`NDL_SEARCH_MAX_MIN`] needs no stop. Call only for a plan
/// that has no stops.
pub fn no_deco_limit(alg: &LoadedAlgorithm, plan: &DivePlan) -> Option<f64> {
    let no_stops = |t: f64| {
        let p = DivePlan {
            bottom_time_min: t,
            ..plan.clone()
        };
        match alg.algorithm.plan(&p) {
            Ok(s) => s.stops.is_empty(),
            Err(_) => false,
        }
    };
    let mut lo = plan.bottom_time_min.floor().max(1.0);
    if !no_stops(lo) {
        // a fractional planned time that needs no stop while its floor is refused
        // (bottom time including the descent): the plan's own time is the limit found
        return Some(plan.bottom_time_min);
    }
    let mut hi = lo * 2.0;
    while no_stops(hi) {
        lo = hi;
        if hi >= NDL_SEARCH_MAX_MIN {
            return None;
        }
        hi = (hi * 2.0).min(NDL_SEARCH_MAX_MIN);
    }
    while hi - lo > 1.0 {
        let mid = ((lo + hi) / 2.0).floor();
        if no_stops(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// The settings the plan used, as `(name, value)` rows: what `dt-lint` echoes.
fn settings(alg: &LoadedAlgorithm, req: &PlanRequest, plan: &DivePlan) -> Vec<(String, String)> {
    let c = &alg.conventions;
    let o = &req.overrides;
    let mark = |set: bool| if set { " (command line)" } else { "" };
    let mut rows = vec![
        (
            "algorithm".to_string(),
            format!("{} ({}, {})", alg.label, alg.kind, req.algorithm.display()),
        ),
        (
            "surface pressure".to_string(),
            match req.altitude_m {
                Some(h) => format!(
                    "{:.2} hPa (altitude {h} m, ICAO standard atmosphere){}",
                    c.surface_pressure_pa / 100.0,
                    mark(true)
                ),
                None => format!(
                    "{:.2} hPa{}",
                    c.surface_pressure_pa / 100.0,
                    mark(o.surface_pressure_pa.is_some())
                ),
            },
        ),
        (
            "pressure per metre".to_string(),
            format!("{} hPa/m", c.pa_per_m / 100.0),
        ),
        (
            "water vapour".to_string(),
            format!("{} hPa", c.water_vapour_pa / 100.0),
        ),
        (
            "descent rate".to_string(),
            format!(
                "{} m/min{}",
                c.descent_rate_m_min,
                mark(o.descent_rate_m_min.is_some())
            ),
        ),
        (
            "ascent rate".to_string(),
            format!(
                "{} m/min{}",
                c.ascent_rate_m_min,
                mark(o.ascent_rate_m_min.is_some())
            ),
        ),
        (
            "stops".to_string(),
            format!(
                "every {} m, last at {} m{}",
                c.stop_spacing_m,
                c.last_stop_m,
                mark(o.last_stop_m.is_some())
            ),
        ),
    ];
    if !plan.travel_gases.is_empty() {
        let from = if req.travel_gases.is_empty() {
            " (algorithm file)"
        } else {
            ""
        };
        let list: Vec<String> = plan
            .travel_gases
            .iter()
            .map(|t| format!("{} {}–{} m", gas_text(t.mix), t.from_m, t.to_m))
            .collect();
        rows.push((
            "travel gases".to_string(),
            format!("{}{from}", list.join(", ")),
        ));
    }
    if req.deco_gases.is_empty() && !alg.gases.deco.is_empty() {
        let list: Vec<String> = alg
            .gases
            .deco
            .iter()
            .map(|d| format!("{} from {} m", gas_text(d.mix), d.switch_depth_m))
            .collect();
        rows.push((
            "deco gases".to_string(),
            format!("{} (algorithm file)", list.join(", ")),
        ));
    }
    if o.gf_low.is_some() || o.gf_high.is_some() {
        rows.insert(
            1,
            (
                "gradient factors".to_string(),
                "from the command line (in the label)".to_string(),
            ),
        );
    }
    rows
}

/// What the Markdown table shows beside the stops.
struct MdExtras<'a> {
    ndl_min: Option<Option<f64>>,
    settings: &'a [(String, String)],
    warnings: &'a [String],
}

/// Every number of a plan must be a real one before it is printed or written: a non-finite
/// runtime, stop or oxygen dose is a numerical failure (exit 3), never a result.
fn check_plan_numbers(
    schedule: &Schedule,
    oxygen: &OxygenExposure,
) -> Result<(), crate::error::Error> {
    let mut bad: Vec<String> = Vec::new();
    let mut check = |what: &str, v: f64| {
        if !v.is_finite() {
            bad.push(format!("{what} = {v}"));
        }
    };
    check("runtime", schedule.runtime_min());
    check("CNS", oxygen.cns_percent);
    check("OTU", oxygen.otu);
    for (i, l) in schedule.legs.iter().enumerate() {
        check(&format!("leg {} duration", i + 1), l.duration_s);
        check(&format!("leg {} depth", i + 1), l.end_depth_m);
    }
    for (i, s) in schedule.stops.iter().enumerate() {
        check(&format!("stop {} time", i + 1), s.stop_min);
        check(&format!("stop {} runtime", i + 1), s.runtime_min);
    }
    match bad.first() {
        None => Ok(()),
        Some(b) => Err(crate::error::Error::Solver(format!(
            "the planner produced a non-finite number ({b}); nothing was printed or written"
        ))),
    }
}

/// The dive-profile figure of a schedule: depth and the ZH-L16C ceiling at GF 100 % (the
/// M-value line) over the ZH-L16C tissue heat map, sampled every 0.5 min — the Bühlmann view
/// of any schedule, VPM-B's included.
pub fn profile_figure(
    schedule: &Schedule,
    conventions: &crate::algorithm::Conventions,
) -> crate::report::dive_plot::ProfileFigure {
    use crate::report::dive_plot::{ProfileFigure, ProfileSample};
    let samples = crate::algorithm::loading::loading(schedule, conventions, 1.0, 0.5)
        .into_iter()
        .map(|x| ProfileSample {
            time_min: x.time_min,
            depth_m: x.depth_m,
            ceiling_m: x.ceiling_m,
            rows: x.gradient.to_vec(),
        })
        .collect();
    ProfileFigure {
        title: format!("{}: dive profile and tissue loading", schedule.label),
        ceiling_label: "ceiling, ZH-L16C at GF 100 %".into(),
        rows_label: "ZH-L16C compartment".into(),
        samples,
    }
}

/// Whether two output paths name the same place, existing or not: the same file name in the
/// same folder (the folders compared after resolving symlinks and `..`, where they exist).
fn same_place(a: &std::path::Path, b: &std::path::Path) -> bool {
    if same_file(a, b) || a == b {
        return true;
    }
    let folder = |p: &std::path::Path| {
        let d = match p.parent() {
            Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
            _ => PathBuf::from("."),
        };
        d.canonicalize().unwrap_or(d)
    };
    a.file_name() == b.file_name() && folder(a) == folder(b)
}

/// The schedule as the waypoint CSV `check` reads: `time_min,depth_m,gas`, one row per leg
/// boundary from (0, 0) to the surface; the gas on a row is breathed from that waypoint to the
/// next (the last row's cell is empty). Full precision, so reading it back gives the same legs.
/// Above the header, a comment line ([`CONVENTIONS_COMMENT`]) carries the schedule's surface
/// pressure, pressure per metre and water vapour, which the readers take from it (a CSV
/// without one is read in DecoTengu's: 1.01325 bar, 9 985 Pa/m, 6 270 Pa water vapour).
pub fn waypoints_csv(s: &Schedule) -> String {
    let mut out = format!(
        "{CONVENTIONS_COMMENT} surface_pressure_pa = {}, pa_per_m = {}, water_vapour_pa = {} (the schedule's; decophantom reads them from here)\n",
        s.surface_pressure_pa, s.pa_per_m, s.water_vapour_pa
    );
    out.push_str("time_min,depth_m,gas\n");
    let legs: Vec<_> = s.legs.iter().filter(|l| l.duration_s > 0.0).collect();
    let mut t_s = 0.0;
    let start = legs.first().map_or(0.0, |l| l.start_depth_m);
    let mut depth = start;
    for l in &legs {
        let _ = writeln!(out, "{},{},{}", t_s / 60.0, depth, gas_text(l.gas));
        t_s += l.duration_s;
        depth = l.end_depth_m;
    }
    let _ = writeln!(out, "{},{},", t_s / 60.0, depth);
    out
}

/// Minutes for tables: whole numbers without decimals, others to 0.01.
fn fmt_min(x: f64) -> String {
    if (x - x.round()).abs() < 1e-9 {
        format!("{}", x.round())
    } else {
        format!("{x:.2}")
    }
}

fn csv_table(s: &Schedule) -> String {
    let mut out = String::from("depth_m,stop_min,runtime_min,gas\n");
    for st in &s.stops {
        let _ = writeln!(
            out,
            "{},{},{},{}",
            st.depth_m,
            fmt_min(st.stop_min),
            fmt_min(st.runtime_min),
            gas_text(st.gas)
        );
    }
    let last_gas = s.legs.last().map_or(GasMix::AIR, |l| l.gas);
    let _ = writeln!(
        out,
        "0,0,{},{}",
        fmt_min(s.runtime_min()),
        gas_text(last_gas)
    );
    out
}

fn markdown(s: &Schedule, plan: &DivePlan, o: &OxygenExposure, x: &MdExtras) -> String {
    // one precision for every time in the table: whole minutes when all are whole, else 0.1
    let whole = s
        .stops
        .iter()
        .flat_map(|st| [st.stop_min, st.runtime_min])
        .chain([s.runtime_min(), plan.bottom_time_min])
        .all(|t| (t - t.round()).abs() < 1e-9);
    let m = |t: f64| {
        if whole {
            format!("{:.0}", t)
        } else {
            format!("{:.1}", t)
        }
    };
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# {}: {} m for {} min on {}\n",
        s.label,
        plan.depth_m,
        m(plan.bottom_time_min),
        gas_text(plan.bottom_gas)
    );
    if !x.settings.is_empty() {
        out.push_str("Settings:\n\n");
        for (k, v) in x.settings {
            let _ = writeln!(out, "- {k}: {v}");
        }
        out.push('\n');
    }
    if s.stops.is_empty() {
        match x.ndl_min {
            Some(Some(ndl)) => {
                let _ = writeln!(
                    out,
                    "No decompression stops. No-decompression limit at {} m on {}: {} min.\n",
                    plan.depth_m,
                    gas_text(plan.bottom_gas),
                    m(ndl)
                );
            }
            Some(None) => {
                let _ = writeln!(
                    out,
                    "No decompression stops. No-decompression limit at {} m on {}: none within {NDL_SEARCH_MAX_MIN:.0} min.\n",
                    plan.depth_m,
                    gas_text(plan.bottom_gas)
                );
            }
            None => {
                let _ = writeln!(out, "No decompression stops.\n");
            }
        }
    } else {
        out.push_str("| depth_m | stop_min | runtime_min | gas |\n|---:|---:|---:|---|\n");
        for st in &s.stops {
            let _ = writeln!(
                out,
                "| {} | {} | {} | {} |",
                st.depth_m,
                m(st.stop_min),
                m(st.runtime_min),
                gas_text(st.gas)
            );
        }
        out.push('\n');
    }
    for g in s.gas_switches() {
        let _ = writeln!(
            out,
            "Gas switch to {} at {} m (runtime {} min).",
            gas_text(g.gas),
            g.depth_m,
            m(g.runtime_min)
        );
    }
    let _ = writeln!(out, "Total dive time: {} min", m(s.runtime_min()));
    if !s.stops.is_empty() {
        let _ = writeln!(out, "Total stop time: {} min", m(s.stop_time_min()));
    }
    let _ = writeln!(out, "CNS: {:.1} %", o.cns_percent);
    let _ = writeln!(out, "OTU: {:.1}", o.otu);
    for w in x.warnings {
        let _ = writeln!(out, "Warning: {w}");
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// Defect C: `--out` names a file the schedule readers read back by its extension (or the
    /// `.md` table); `.txt` (the paper's two-column format to them) and no extension are refused,
    /// naming the file and `--out` and listing the accepted extensions.
    #[test]
    fn out_names_an_extension_the_readers_read() {
        for (name, given, want) in [
            ("s.toml", None, PlanFormat::Toml),
            ("s.TOML", None, PlanFormat::Toml),
            ("s.csv", None, PlanFormat::Csv),
            ("s.md", None, PlanFormat::Md),
            ("s.toml", Some(PlanFormat::Toml), PlanFormat::Toml),
        ] {
            assert_eq!(out_format(Path::new(name), given).unwrap(), want, "{name}");
        }
        for (name, given, found) in [
            ("sch.txt", None, "'.txt' (read as the paper's two-column"),
            ("sch", None, "no extension"),
            ("sch", Some(PlanFormat::Toml), "no extension"),
            ("sch.json", Some(PlanFormat::Csv), "'.json'"),
        ] {
            let e = out_format(Path::new(name), given).unwrap_err();
            assert_eq!(
                (e.file.as_deref(), e.field.as_deref()),
                (Some(Path::new(name)), Some("--out")),
                "{e}"
            );
            assert!(e.message.contains(found), "{e}");
            assert!(e.message.contains("name it .toml"), "{e}");
            assert!(
                e.message.contains(".csv") && e.message.contains(".md"),
                "{e}"
            );
        }
        let e = out_format(Path::new("s.csv"), Some(PlanFormat::Toml)).unwrap_err();
        assert!(e.message.contains("contradicts"), "{e}");
    }
}
