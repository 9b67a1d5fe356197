//! Subcommands and their arguments. No logic here: each subcommand calls one library function.

use clap::{Parser, Subcommand};

/// decophantom: decompression schedules through a 3-D bubble model of a tissue phantom.
#[derive(Parser, Debug)]
#[command(name = "decophantom", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
    /// No progress bar and no "wrote ..." lines (results, errors and --json still print).
    #[arg(long, short = 'q', global = true)]
    pub quiet: bool,
}

/// Set by --quiet: progress bars stay hidden.
static QUIET: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn quiet() -> bool {
    QUIET.load(std::sync::atomic::Ordering::Relaxed)
}

/// Write `text` to stdout. A reader that has gone away (`decophantom … | head -1`) is not an
/// error of the run: the work goes on and its output files are written, only the printing
/// stops (`print!` would panic on the broken pipe). Any other write error is said once on
/// stderr.
fn emit(text: &str) {
    use std::io::Write;
    static SAID: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);
    let mut out = std::io::stdout().lock();
    if let Err(e) = out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        if e.kind() != std::io::ErrorKind::BrokenPipe
            && !SAID.swap(true, std::sync::atomic::Ordering::Relaxed)
        {
            eprintln!("warning: could not write to stdout: {e}");
        }
    }
}

/// [`emit`] with `format!` arguments.
macro_rules! out {
    ($($t:tt)*) => { emit(&format!($($t)*)) };
}

/// [`emit`] with `format!` arguments and a newline.
macro_rules! outln {
    ($($t:tt)*) => {{
        let mut line = format!($($t)*);
        line.push('\n');
        emit(&line)
    }};
}

/// Print a "wrote ..." line unless --quiet.
fn wrote(path: &std::path::Path) {
    if !quiet() {
        outln!("wrote {}", path.display());
    }
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Plan a dive with a decompression algorithm and print its stop table.
    Plan(PlanArgs),
    /// Run one pressure profile through one phantom; writes bubbles.csv, summary.toml, radius.svg, volume.svg.
    Simulate(SimulateArgs),
    /// Final radius after a pressure change without mass transfer, for every elasticity form (CSV).
    Elasticity(ElasticityArgs),
    /// Run the built-in example and write a full report under reports/demo/.
    Demo(DemoArgs),
    /// Run a schedule through the phantom and score it: exit 0 all pass, 1 some fail, 2 bad input.
    Check(CheckArgs),
    /// Plan a dive with several algorithms, run each schedule (× elasticity law) through the phantom, rank, report.
    Evaluate(EvaluateArgs),
    /// Print a shell completion script (bash, zsh, fish, elvish, powershell) to stdout.
    Completions(CompletionsArgs),
    /// Print the man page (roff) to stdout, e.g. `decophantom man > decophantom.1`.
    Man,
    /// Fit phantom parameters (by TOML path) to measured bubble radii: estimates, intervals, report.
    Fit(FitArgs),
    /// Measured-like radius data from the model, with candidate effects switched on and noise.
    Synth(SynthArgs),
    /// Fit the baseline, diagnose the misfit, and add the candidate effects the data need.
    Discover(DiscoverArgs),
    /// Sensitivity of run metrics to phantom parameters: one-at-a-time, Morris or Sobol'; shardable.
    Sensitivity(SensitivityArgs),
    /// Merge `sensitivity --shard` output folders and compute the indices and report.
    Merge(MergeArgs),
    /// Regenerate the paper's computational figures (2a, 2b, 3, 5, 6): data, panels, claims vs ours.
    Reproduce(ReproduceArgs),
}

/// Arguments of `reproduce`.
#[derive(clap::Args, Debug)]
pub struct ReproduceArgs {
    /// fig2a, fig2b, fig3, fig5, fig6 or all.
    pub figure: String,
    /// Output folder (written whole: DIR/<figure>/..., DIR/README.md).
    #[arg(long)]
    pub out: std::path::PathBuf,
    /// Reduced grids and designs (seconds, for a first look and the tests).
    #[arg(long)]
    pub quick: bool,
}

/// Arguments of `sensitivity`.
#[derive(clap::Args, Debug)]
pub struct SensitivityArgs {
    /// Phantom TOML.
    #[arg(long)]
    pub phantom: std::path::PathBuf,
    /// Pressure profile (anything `simulate --profile` reads).
    #[arg(long)]
    pub profile: std::path::PathBuf,
    /// Swept parameter NAME=LO..HI (a phantom TOML path or scale: pattern); repeatable.
    #[arg(long = "param", allow_hyphen_values = true)]
    pub params: Vec<String>,
    /// Metric: r_max, t_max, plateau, half_life, peak_volume, final_radius, optionally :BUBBLE; repeatable.
    #[arg(long = "metric")]
    pub metrics: Vec<String>,
    /// oat, morris or sobol.
    #[arg(long, default_value = "oat")]
    pub method: String,
    /// Levels (oat), trajectories (morris) or base rows (sobol: N ≥ 16, N(k + 2) runs).
    #[arg(long, default_value_t = 5)]
    pub samples: usize,
    /// Seed of the design (same seed, same design: resumable and shardable).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Run only the I-th of N slices of the design (0-based), e.g. 3/64.
    #[arg(long)]
    pub shard: Option<String>,
    /// Output folder (written whole; the journal DIR.partial/ beside it until then).
    #[arg(long)]
    pub out: std::path::PathBuf,
}

/// Arguments of `merge`.
#[derive(clap::Args, Debug)]
pub struct MergeArgs {
    /// Shard output folders of one design.
    #[arg(required = true)]
    pub dirs: Vec<std::path::PathBuf>,
    /// Output folder.
    #[arg(long)]
    pub out: std::path::PathBuf,
}

/// Arguments of `completions`.
#[derive(clap::Args, Debug)]
pub struct CompletionsArgs {
    /// The shell.
    #[arg(value_enum)]
    pub shell: clap_complete::Shell,
}

/// Arguments of `fit`.
#[derive(clap::Args, Debug)]
pub struct FitArgs {
    /// measurements.csv: experiment,bubble,time_s,radius_m[,sd_m].
    #[arg(long)]
    pub measured: std::path::PathBuf,
    /// experiments.toml: [[experiment]] name, profile, phantom; optional [fit] free.
    #[arg(long)]
    pub experiments: std::path::PathBuf,
    /// Parameter to fit: a numeric phantom TOML path (gases.n2.diffusivity), or scale:PATTERN for one factor on every number a `*` pattern matches (scale:gases.*.ostwald); optionally with bounds NAME=LO..HI; repeatable; added to the experiments file's [fit] free (a path in both is refused).
    #[arg(long = "param")]
    pub params: Vec<String>,
    /// Output folder (replaced whole); finished simulations are kept in OUT.partial/ until then, and a restart of the same fit reads them back.
    #[arg(long)]
    pub out: std::path::PathBuf,
}

/// Arguments of `synth`.
#[derive(clap::Args, Debug)]
pub struct SynthArgs {
    /// experiments.toml.
    #[arg(long)]
    pub experiments: std::path::PathBuf,
    /// Effect switched on: NAME=VALUE[,VALUE2] (a discover candidate, e.g. perfusion=2e-3,
    /// surface-area-law=30,2, sealed-faces:top) or a phantom path PATH=VALUE; repeatable.
    #[arg(long = "effect")]
    pub effects: Vec<String>,
    /// Standard deviation of the Gaussian noise added to every radius, m.
    #[arg(long = "noise-sd", allow_hyphen_values = true)]
    pub noise_sd: f64,
    /// Sampling interval, s: every bubble is sampled at least twice, so at most the shortest experiment's duration.
    #[arg(long, default_value_t = 5.0, allow_hyphen_values = true)]
    pub every: f64,
    /// Seed of the noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Output CSV (measurements.csv format, with sd_m).
    #[arg(long)]
    pub out: std::path::PathBuf,
}

/// Arguments of `discover`.
#[derive(clap::Args, Debug)]
pub struct DiscoverArgs {
    /// measurements.csv.
    #[arg(long)]
    pub measured: std::path::PathBuf,
    /// experiments.toml.
    #[arg(long)]
    pub experiments: std::path::PathBuf,
    /// Output folder (replaced whole); finished simulations are kept in OUT.partial/ until then, and a restart of the same search reads them back.
    #[arg(long)]
    pub out: std::path::PathBuf,
    /// Family-wise significance level (Bonferroni over each round's candidates).
    #[arg(long, default_value_t = 0.01, allow_hyphen_values = true)]
    pub alpha: f64,
    /// Most effects added.
    #[arg(long = "max-effects", default_value_t = 3)]
    pub max_effects: usize,
    /// Only try candidates whose names start with these (comma-separated); default all.
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
}

/// Arguments of `check`.
#[derive(clap::Args, Debug)]
pub struct CheckArgs {
    /// Schedule: TOML from `plan --out`, CSV `time_min,depth_m[,gas]`, the paper's two-column
    /// .txt, or a Subsurface (.xml, .ssrf) / UDDF (.uddf) dive log.
    #[arg(long)]
    pub schedule: std::path::PathBuf,
    /// Which dive(s) of a dive log: N (1-based), a range N-M or `all`: consecutive dives
    /// run as one, with the surface intervals of the logged start times, the gel, bubbles
    /// and nuclei carried across. Required when the log holds more than one.
    #[arg(long)]
    pub dive: Option<decophantom::profile::sequence::DiveSelection>,
    /// Criteria TOML (algorithms/criteria/*.toml).
    #[arg(long)]
    pub criteria: std::path::PathBuf,
    /// Phantom TOML (default: the built-in profiles/phantoms/hydrogel-dive.toml).
    #[arg(long)]
    pub phantom: Option<std::path::PathBuf>,
    /// Override the phantom's grid step, m (coarser = faster; nuclei keep their radii).
    #[arg(long = "grid-step")]
    pub grid_step: Option<f64>,
    /// Repeat the dive after this surface interval, min (the phantom's state carries over).
    #[arg(long = "repeat-after", allow_hyphen_values = true)]
    pub repeat_after: Option<f64>,
    /// Write the report folder here (replaced whole).
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
    /// Print the result as JSON (schema decophantom.check/1, docs/json.md) instead of text.
    #[arg(long)]
    pub json: bool,
    /// Run even when the run is estimated to take more than 6 hours.
    #[arg(long)]
    pub force: bool,
}

/// The dive to plan (shared by `plan` and `evaluate`).
#[derive(clap::Args, Debug)]
pub struct DiveArgs {
    /// Maximum depth, m.
    #[arg(long, allow_hyphen_values = true)]
    pub depth: f64,
    /// Bottom time, min.
    #[arg(long, allow_hyphen_values = true)]
    pub time: f64,
    /// Bottom gas: air, 32 (nitrox), 18/45 (trimix O2/He).
    #[arg(long)]
    pub gas: Option<String>,
    /// Deco gas, MIX@SWITCH_DEPTH_M or MIX (switch at its MOD at 1.6 bar); repeatable.
    #[arg(long = "deco-gas")]
    pub deco_gas: Vec<String>,
    /// Travel gas MIX@FROM..TO (m), e.g. 21/35@0..60: breathed on the descent over that range,
    /// then the next travel gas or the bottom gas (for hypoxic bottom mixes); available again
    /// on the ascent from TO. Repeatable (ranges follow each other from the surface).
    #[arg(long = "travel-gas")]
    pub travel_gas: Vec<String>,
}

/// Arguments of `evaluate`.
#[derive(clap::Args, Debug)]
pub struct EvaluateArgs {
    /// Maximum depth, m (to plan with --algorithm).
    #[arg(
        long,
        allow_hyphen_values = true,
        required_unless_present = "schedule",
        requires = "algorithm"
    )]
    pub depth: Option<f64>,
    /// Bottom time, min (to plan with --algorithm).
    #[arg(
        long,
        allow_hyphen_values = true,
        required_unless_present = "schedule",
        requires = "algorithm"
    )]
    pub time: Option<f64>,
    /// Bottom gas: air, 32 (nitrox), 18/45 (trimix O2/He) (to plan with --algorithm; a
    /// --schedule keeps its own gases).
    #[arg(long, requires = "algorithm")]
    pub gas: Option<String>,
    /// Deco gas, MIX@SWITCH_DEPTH_M or MIX (switch at its MOD at 1.6 bar); repeatable (to plan
    /// with --algorithm).
    #[arg(long = "deco-gas", requires = "algorithm")]
    pub deco_gas: Vec<String>,
    /// Travel gas MIX@FROM..TO (m), e.g. 21/35@0..60, for planned hypoxic bottom mixes;
    /// repeatable (to plan with --algorithm).
    #[arg(long = "travel-gas", requires = "algorithm")]
    pub travel_gas: Vec<String>,
    /// Algorithm TOML; repeat for each algorithm to compare.
    #[arg(long, required_unless_present = "schedule")]
    pub algorithm: Vec<std::path::PathBuf>,
    /// Schedule compared as it is: plan --out TOML, CSV time_min,depth_m[,gas], the paper's
    /// two-column .txt, or a Subsurface (.xml, .ssrf) / UDDF (.uddf) dive log; repeatable.
    #[arg(long)]
    pub schedule: Vec<std::path::PathBuf>,
    /// Which dive(s) of a dive log: N (1-based), a range N-M or `all`: consecutive dives
    /// run as one, with the surface intervals of the logged start times, the gel, bubbles
    /// and nuclei carried across. Required when the log holds more than one.
    #[arg(long)]
    pub dive: Option<decophantom::profile::sequence::DiveSelection>,
    /// Elasticity laws: all, or names (comma-separated or repeated); default the phantom's own.
    #[arg(long)]
    pub elasticity: Vec<String>,
    /// Phantom TOML (default: the built-in profiles/phantoms/hydrogel-dive.toml).
    #[arg(long)]
    pub phantom: Option<std::path::PathBuf>,
    /// Override the phantom's grid step, m (coarser = faster; nuclei keep their radii).
    #[arg(long = "grid-step")]
    pub grid_step: Option<f64>,
    /// Criteria TOML (algorithms/criteria/*.toml).
    #[arg(long)]
    pub criteria: std::path::PathBuf,
    /// Repeat the dive after this surface interval, min (the phantom's state carries over).
    #[arg(long = "repeat-after", allow_hyphen_values = true)]
    pub repeat_after: Option<f64>,
    /// Output folder (replaced whole; created if missing); finished runs are kept in OUT.partial/ until then, and a restart skips them.
    #[arg(long)]
    pub out: std::path::PathBuf,
    /// Print the scores and ranking as JSON (schema decophantom.evaluate/1, docs/json.md).
    #[arg(long)]
    pub json: bool,
    /// Run even when a run is estimated to take more than 6 hours.
    #[arg(long)]
    pub force: bool,
}

/// Arguments of `simulate`.
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {
    /// Pressure profile: TOML (profiles/*.toml), a legacy two-column text file (needs --units), a dive log, or a schedule written by plan --out (.toml, or .csv of time_min,depth_m[,gas] in the conventions of its "# conventions:" line, else DecoTengu's, from air, as check reads it).
    #[arg(long)]
    pub profile: std::path::PathBuf,
    /// Phantom TOML (profiles/phantoms/*.toml).
    #[arg(long)]
    pub phantom: std::path::PathBuf,
    /// Output folder (replaced whole; created if missing).
    #[arg(long)]
    pub out: std::path::PathBuf,
    /// Units of a legacy profile as TIME,PRESSURE, e.g. min,psi-gauge or min,msw.
    #[arg(long)]
    pub units: Option<String>,
    /// Chamber or breathing gas of a legacy profile (default air).
    #[arg(long)]
    pub gas: Option<String>,
    /// Water-vapour pressure subtracted at the open faces, Pa (legacy/dive-log profiles; default 0).
    #[arg(long = "vapour-pa")]
    pub vapour_pa: Option<f64>,
    /// Which dive(s) of a dive log: N (1-based), a range N-M or `all`: consecutive dives
    /// run as one, with the surface intervals of the logged start times, the gel, bubbles
    /// and nuclei carried across. Required when the log holds more than one.
    #[arg(long)]
    pub dive: Option<decophantom::profile::sequence::DiveSelection>,
    /// Run even when the run is estimated to take more than 6 hours.
    #[arg(long)]
    pub force: bool,
    /// Save the run's whole state every INTERVAL of wall time (60s, 5min, 1h) into OUT.checkpoint/checkpoint.dcp, and once more on Ctrl-C; removed when the run completes.
    #[arg(long, value_name = "INTERVAL")]
    pub checkpoint_every: Option<String>,
    /// Continue from a checkpoint (the OUT.checkpoint folder or its file) with the same profile, phantom and options; the results are byte-identical to an uninterrupted run.
    #[arg(long, value_name = "DIR")]
    pub resume: Option<std::path::PathBuf>,
    /// Testing: save a checkpoint after step N, then stop as if interrupted.
    #[arg(long, value_name = "N", hide = true)]
    pub checkpoint_at_step: Option<usize>,
    /// Also write steps.csv: every time step the loop took, the scheme, the limit that set its length, the error estimates and the wall time (for studying the time stepping).
    #[arg(long)]
    pub trace_steps: bool,
}

/// Arguments of `elasticity`.
#[derive(clap::Args, Debug)]
pub struct ElasticityArgs {
    /// Initial ambient pressure, Pa.
    #[arg(long, default_value_t = 1e6, allow_hyphen_values = true)]
    pub p0: f64,
    /// Final ambient pressure, Pa.
    #[arg(long, default_value_t = 1e4, allow_hyphen_values = true)]
    pub pf: f64,
    /// Surface tension γ, N/m.
    #[arg(long, default_value_t = 0.07, allow_hyphen_values = true)]
    pub gamma: f64,
    /// Shear modulus μ, Pa.
    #[arg(long, default_value_t = 40.0, allow_hyphen_values = true)]
    pub mu: f64,
    /// Bulk-modulus coefficient M = K/V_aff, Pa/m³ (5e-2 Pa/µm³ = 5e16 Pa/m³).
    #[arg(long, default_value_t = 5e16, allow_hyphen_values = true)]
    pub m: f64,
    /// Bulk modulus K, Pa.
    #[arg(long, default_value_t = 2.2e9, allow_hyphen_values = true)]
    pub k: f64,
    /// Initial radii, m, comma-separated.
    #[arg(
        long,
        value_delimiter = ',',
        allow_hyphen_values = true,
        default_value = "1e-6,1e-5,1e-4,1e-3"
    )]
    pub r0: Vec<f64>,
}

/// Arguments of `demo`.
#[derive(clap::Args, Debug)]
pub struct DemoArgs {
    /// Output folder.
    #[arg(long, default_value = "reports/demo")]
    pub out: std::path::PathBuf,
}

/// Arguments of `plan`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    /// Algorithm TOML file, e.g. algorithms/zhl16c-gf30-85.toml.
    #[arg(long)]
    pub algorithm: std::path::PathBuf,
    #[command(flatten)]
    pub dive: DiveArgs,
    /// Format of the printed table and of --out: md, csv or toml (default md printed; --out
    /// by its extension: .toml the schedule TOML, .csv the waypoints `check` reads, .md the
    /// table; any other extension is refused).
    #[arg(long, value_parser = ["md", "csv", "toml"])]
    pub format: Option<String>,
    /// Write the schedule here (readable by check, simulate, evaluate --schedule); an existing
    /// file is replaced only if plan wrote it and it is unchanged since.
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
    /// Print the plan as JSON (schema decophantom.plan/1, docs/json.md) instead of the table.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub settings: PlannerSettingsArgs,
    /// Write the dive-profile figure here (SVG): depth, the ZH-L16C ceiling and a tissue
    /// heat map, as DecoTengu's dt-plot and Subsurface's planner show them; an existing file is
    /// replaced only if plan wrote it and it is unchanged since.
    #[arg(long)]
    pub plot: Option<std::path::PathBuf>,
}

/// Planner settings that replace the algorithm file's (echoed with the table).
#[derive(clap::Args, Debug)]
pub struct PlannerSettingsArgs {
    /// Gradient factors GF-LOW/GF-HIGH in %, e.g. 30/85 (ZH-L16 files).
    #[arg(long, conflicts_with_all = ["gf_low", "gf_high"])]
    pub gf: Option<String>,
    /// GF-low, %.
    #[arg(long, allow_hyphen_values = true)]
    pub gf_low: Option<f64>,
    /// GF-high, %.
    #[arg(long, allow_hyphen_values = true)]
    pub gf_high: Option<f64>,
    /// Surface pressure, hPa (mbar), e.g. 1013.25.
    #[arg(long, allow_hyphen_values = true, conflicts_with = "altitude")]
    pub surface_pressure: Option<f64>,
    /// Altitude of the dive site, m: surface pressure from the ICAO standard atmosphere.
    #[arg(long, allow_hyphen_values = true)]
    pub altitude: Option<f64>,
    /// Descent rate, m/min.
    #[arg(long, allow_hyphen_values = true)]
    pub descent_rate: Option<f64>,
    /// Ascent rate, m/min.
    #[arg(long, allow_hyphen_values = true)]
    pub ascent_rate: Option<f64>,
    /// Depth of the last stop, m (3 or 6).
    #[arg(long, allow_hyphen_values = true)]
    pub last_stop: Option<f64>,
}

impl PlannerSettingsArgs {
    /// The overrides, and the altitude they came from; bad values name the option.
    fn overrides(
        &self,
    ) -> Result<
        (decophantom::algorithm::config::Overrides, Option<f64>),
        decophantom::error::InputError,
    > {
        use decophantom::algorithm::config::{isa_pressure_pa, parse_gf, Overrides};
        let (gf_low, gf_high) = match &self.gf {
            Some(g) => {
                let (l, h) = parse_gf(g)?;
                (Some(l), Some(h))
            }
            None => (self.gf_low, self.gf_high),
        };
        let surface_pressure_pa = match self.altitude {
            Some(h) => {
                if !(h.is_finite() && (-500.0..=5_500.0).contains(&h)) {
                    return Err(decophantom::error::InputError::new(format!(
                        "altitude {h} m is outside -500..5500 m"
                    ))
                    .in_file("<command line>")
                    .field("--altitude"));
                }
                Some(isa_pressure_pa(h))
            }
            None => self.surface_pressure.map(|hpa| hpa * 100.0),
        };
        Ok((
            Overrides {
                gf_low,
                gf_high,
                surface_pressure_pa,
                descent_rate_m_min: self.descent_rate,
                ascent_rate_m_min: self.ascent_rate,
                last_stop_m: self.last_stop,
            },
            self.altitude,
        ))
    }
}

/// Run a parsed command; returns the process exit code.
pub fn run(cli: Cli) -> anyhow::Result<i32> {
    QUIET.store(cli.quiet, std::sync::atomic::Ordering::Relaxed);
    match cli.command {
        Command::Completions(a) => {
            use clap::CommandFactory;
            let mut cmd = Cli::command();
            let mut text = Vec::new();
            clap_complete::generate(a.shell, &mut cmd, "decophantom", &mut text);
            emit(&String::from_utf8_lossy(&text));
            Ok(0)
        }
        Command::Man => {
            use clap::CommandFactory;
            let mut text = Vec::new();
            clap_mangen::Man::new(Cli::command()).render(&mut text)?;
            emit(&String::from_utf8_lossy(&text));
            Ok(0)
        }
        Command::Plan(a) => {
            if a.json && a.format.is_some() && a.out.is_none() {
                return Err(decophantom::error::InputError::new(
                    "--json prints JSON, so --format has nothing to format (it sets the printed table and the --out file's format); drop one, or give --out",
                )
                .in_file("<command line>")
                .field("--format")
                .into());
            }
            let (overrides, altitude_m) = a.settings.overrides()?;
            let req = decophantom::app::plan::PlanRequest {
                algorithm: a.algorithm,
                depth_m: a.dive.depth,
                time_min: a.dive.time,
                gas: a.dive.gas,
                deco_gases: a.dive.deco_gas,
                travel_gases: a.dive.travel_gas,
                format: a
                    .format
                    .as_deref()
                    .and_then(decophantom::app::plan::PlanFormat::parse)
                    .unwrap_or_default(),
                out_format: a
                    .format
                    .as_deref()
                    .and_then(decophantom::app::plan::PlanFormat::parse),
                out: a.out,
                overrides,
                altitude_m,
                plot: a.plot,
            };
            let algorithm = req.algorithm.display().to_string();
            let outcome = decophantom::app::plan::run(&req)?;
            if a.json {
                out!("{}", decophantom::app::json::plan(&outcome, &algorithm));
            } else {
                out!("{}", outcome.text);
            }
            for w in &outcome.warnings {
                eprintln!("warning: {w}");
            }
            Ok(0)
        }
        Command::Simulate(a) => {
            long_runs(a.force);
            let (time_unit, pressure_unit) = match &a.units {
                Some(u) => {
                    let (t, p) = decophantom::profile::legacy::parse_units(u)?;
                    (Some(t), Some(p))
                }
                None => (None, None),
            };
            let gas = match &a.gas {
                Some(g) => Some(
                    decophantom::gas::GasMix::parse(g)
                        .map_err(|m| decophantom::error::InputError::new(m).field("--gas"))?,
                ),
                None => None,
            };
            let req = decophantom::app::simulate::SimulateRequest {
                profile: a.profile,
                load: decophantom::profile::LoadOptions {
                    time_unit,
                    pressure_unit,
                    surface_pa: None,
                    gas,
                    vapour_pa: a.vapour_pa,
                    dive: a.dive,
                },
                phantom: a.phantom,
                out: a.out.clone(),
                stop: Some(interrupt_flag()),
                checkpoint_every: a
                    .checkpoint_every
                    .as_deref()
                    .map(decophantom::phantom::checkpoint::parse_interval)
                    .transpose()?,
                checkpoint_at_step: a.checkpoint_at_step,
                resume: a.resume,
                trace_steps: a.trace_steps,
            };
            let mut bar = Progress::new();
            let run = decophantom::app::simulate::run(&req, &mut |t, e| bar.update(t, e));
            bar.finish();
            let run = run?;
            out!("{}", decophantom::run::text::describe(&run));
            wrote(&a.out);
            if let Some(c) = run.checkpoints.as_ref().filter(|c| c.written > 0) {
                if matches!(
                    run.summary.ending,
                    decophantom::phantom::sim::Ending::Interrupted { .. }
                ) {
                    eprintln!(
                        "checkpoint at t = {:.1} s in {}: continue with --resume {}",
                        c.time,
                        c.path.display(),
                        c.path.parent().unwrap_or(&c.path).display()
                    );
                }
            }
            // interrupted runs wrote what they had, and say so with the usual SIGINT code
            Ok(match run.summary.ending {
                decophantom::phantom::sim::Ending::Interrupted { .. } => 130,
                _ => 0,
            })
        }
        Command::Elasticity(a) => {
            let req = decophantom::phantom::elasticity_compare::ElasticityRequest {
                p0: a.p0,
                pf: a.pf,
                gamma: a.gamma,
                laws: decophantom::phantom::elasticity::AllLawParams {
                    shear_modulus: a.mu,
                    bulk_modulus_per_volume: a.m,
                    bulk_modulus: a.k,
                },
                r0: a.r0,
            };
            let rows = decophantom::phantom::elasticity_compare::compare(&req)?;
            out!(
                "{}",
                decophantom::phantom::elasticity_compare::to_csv(&rows)
            );
            Ok(0)
        }
        Command::Demo(a) => {
            let mut bar = Progress::runs();
            let text = decophantom::app::demo::run(&a.out, &mut |t, e| bar.update(t, e));
            bar.finish();
            out!("{}", text?);
            Ok(0)
        }
        Command::Check(a) => {
            interrupt_flag();
            long_runs(a.force);
            let req = decophantom::app::check::CheckRequest {
                schedule: a.schedule,
                dive: a.dive,
                criteria: a.criteria,
                phantom: a.phantom,
                grid_step_m: a.grid_step,
                repeat_after_min: a.repeat_after,
                out: a.out.clone(),
            };
            let mut bar = Progress::runs();
            let outcome = decophantom::app::check::run(&req, &mut |t, e| bar.update(t, e));
            bar.finish();
            let outcome = outcome?;
            if a.json {
                out!("{}", decophantom::app::json::check(&outcome.evaluation));
            } else {
                out!("{}", outcome.text);
                if let Some(out) = &a.out {
                    wrote(out);
                }
            }
            Ok(if outcome.all_pass { 0 } else { 1 })
        }
        Command::Evaluate(a) => {
            interrupt_flag();
            long_runs(a.force);
            let req = decophantom::app::evaluate::EvaluateRequest {
                depth_m: a.depth,
                time_min: a.time,
                gas: a.gas,
                deco_gases: a.deco_gas,
                travel_gases: a.travel_gas,
                algorithms: a.algorithm,
                schedules: a.schedule,
                dive: a.dive,
                elasticity: a.elasticity,
                phantom: a.phantom,
                grid_step_m: a.grid_step,
                criteria: a.criteria,
                repeat_after_min: a.repeat_after,
                out: a.out.clone(),
            };
            let mut bar = Progress::runs();
            let ev = decophantom::app::evaluate::run(&req, &mut |t, e| bar.update(t, e));
            bar.finish();
            let ev = ev?;
            if a.json {
                out!("{}", decophantom::app::json::evaluate(&ev));
            } else {
                out!("{}", decophantom::evaluate::tables::summary_text(&ev));
                if ev.resumed > 0 {
                    outln!(
                        "{} of {} runs read back from the journal of an unfinished evaluation",
                        ev.resumed,
                        ev.runs.len()
                    );
                }
                wrote(&a.out);
            }
            Ok(0)
        }
        Command::Fit(a) => {
            let req = decophantom::app::fit::FitRequest {
                measured: a.measured,
                experiments: a.experiments,
                params: a.params,
                out: a.out.clone(),
                command: command_line(),
            };
            let f = decophantom::app::fit::run(&req)?;
            out!("{}", decophantom::app::fit::summary_text(&f));
            outln!("wrote {}", a.out.display());
            Ok(0)
        }
        Command::Synth(a) => {
            let req = decophantom::app::synth::SynthRequest {
                experiments: a.experiments,
                effects: a.effects,
                noise_sd: a.noise_sd,
                every: a.every,
                seed: a.seed,
                out: a.out.clone(),
            };
            let rows = decophantom::app::synth::run(&req)?;
            outln!("wrote {} ({rows} rows)", a.out.display());
            Ok(0)
        }
        Command::Discover(a) => {
            let req = decophantom::app::discover::DiscoverRequest {
                measured: a.measured,
                experiments: a.experiments,
                out: a.out.clone(),
                alpha: a.alpha,
                max_effects: a.max_effects,
                only: a.only,
                command: command_line(),
            };
            let bar = std::sync::Mutex::new(Progress {
                runs: Some("candidate fits (estimated total)"),
                ..Progress::new()
            });
            let d = decophantom::app::discover::run(&req, &|done, total| {
                if let Ok(mut b) = bar.lock() {
                    b.update(done as f64, total as f64);
                }
            });
            if let Ok(b) = bar.lock() {
                b.finish();
            }
            out!("{}", decophantom::app::discover::summary_text(&d?));
            outln!("wrote {}", a.out.display());
            Ok(0)
        }
        Command::Sensitivity(a) => {
            let req = decophantom::app::sensitivity::SensitivityRequest {
                phantom: a.phantom,
                profile: a.profile,
                params: a.params,
                metrics: a.metrics,
                method: a.method,
                samples: a.samples,
                seed: a.seed,
                shard: a.shard,
                out: a.out.clone(),
                command: command_line(),
            };
            let bar = std::sync::Mutex::new(Progress::runs());
            let r = decophantom::app::sensitivity::run(&req, &|done, total| {
                if let Ok(mut b) = bar.lock() {
                    b.update(done as f64, total as f64);
                }
            });
            if let Ok(b) = bar.lock() {
                b.finish();
            }
            out!("{}", decophantom::app::sensitivity::summary_text(&r?));
            outln!("wrote {}", a.out.display());
            Ok(0)
        }
        Command::Reproduce(a) => {
            // the command as a reader would type it (not argv[0]), so that re-running it
            // leaves the committed reports/paper/ unchanged
            let command = format!(
                "decophantom reproduce {} --out {}{}",
                a.figure,
                a.out.display(),
                if a.quick { " --quick" } else { "" }
            );
            let req = decophantom::app::reproduce::ReproduceRequest {
                figure: a.figure,
                out: a.out.clone(),
                quick: a.quick,
                command,
            };
            let bar = std::sync::Mutex::new(Progress::runs());
            let r = decophantom::app::reproduce::run(&req, &|_fig, done, total| {
                if let Ok(mut b) = bar.lock() {
                    b.update(done as f64, total as f64);
                }
            });
            if let Ok(b) = bar.lock() {
                b.finish();
            }
            out!("{}", decophantom::app::reproduce::summary_text(&r?));
            wrote(&a.out);
            Ok(0)
        }
        Command::Merge(a) => {
            let r = decophantom::app::sensitivity::run_merge(&a.dirs, &a.out, &command_line())?;
            out!("{}", decophantom::app::sensitivity::summary_text(&r));
            outln!("wrote {}", a.out.display());
            Ok(0)
        }
    }
}

/// Refuse runs estimated above 6 h unless `--force` (the library itself sets no limit).
fn long_runs(force: bool) {
    decophantom::run::cost::set_limit(if force {
        f64::INFINITY
    } else {
        decophantom::run::cost::DEFAULT_LIMIT_S
    });
}

fn command_line() -> String {
    std::env::args()
        .map(|a| if a.contains(' ') { format!("'{a}'") } else { a })
        .collect::<Vec<_>>()
        .join(" ")
}

/// A progress bar on stderr that appears only for runs longer than a second.
struct Progress {
    start: std::time::Instant,
    bar: Option<indicatif::ProgressBar>,
    /// What is counted ("phantom runs", "candidate fits"); None: simulated seconds.
    runs: Option<&'static str>,
}

impl Progress {
    fn new() -> Self {
        Progress {
            start: std::time::Instant::now(),
            bar: None,
            runs: None,
        }
    }
    fn runs() -> Self {
        Progress {
            runs: Some("phantom runs"),
            ..Progress::new()
        }
    }
    fn update(&mut self, t: f64, end: f64) {
        if quiet() {
            return;
        }
        if self.bar.is_none() && self.start.elapsed().as_secs_f64() > 1.0 {
            let b = indicatif::ProgressBar::new(1000);
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{elapsed_precise} [{bar:40}] {percent}% simulated ({msg})",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
            self.bar = Some(b);
        }
        if let Some(b) = &self.bar {
            if end > 0.0 {
                b.set_position(((t / end) * 1000.0).clamp(0.0, 1000.0) as u64);
                if let Some(what) = self.runs {
                    b.set_message(format!("{t:.1} of {end:.0} {what}"));
                } else {
                    b.set_message(format!("t = {t:.0} of {end:.0} s"));
                }
            }
        }
    }
    fn finish(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
    }
}

/// A flag that Ctrl-C sets (with the library's [`decophantom::run::INTERRUPT`]): `simulate`
/// stops at its next step and writes what it has; `check` and `evaluate` stop their runs and
/// write nothing half-done. A second Ctrl-C ends the process at once, but never in the middle
/// of writing an output (it waits the few ms that takes), so no staging folder is left behind.
fn interrupt_flag() -> std::sync::Arc<std::sync::atomic::AtomicBool> {
    use std::sync::atomic::{AtomicBool, Ordering};
    let flag = std::sync::Arc::new(AtomicBool::new(false));
    let f = flag.clone();
    let _ = ctrlc::set_handler(move || {
        let again = f.swap(true, Ordering::SeqCst);
        decophantom::run::INTERRUPT.store(true, Ordering::SeqCst);
        if again {
            while decophantom::report::output::commit_in_progress() {
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
            std::process::exit(130);
        }
        eprintln!("\ninterrupted: finishing the current step; runs stop and only complete results are written (Ctrl-C again to quit now)");
    });
    flag
}
