//! Subcommands and their arguments. No logic here: each subcommand calls one library function.

use clap::{Parser, Subcommand};

/// decophantom: decompression schedules through a 3-D bubble model of a tissue phantom.
#[derive(Parser, Debug)]
#[command(name = "decophantom", version, about)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Plan a dive with a decompression algorithm and print its stop table.
    Plan(PlanArgs),
}

/// Arguments of `plan`.
#[derive(clap::Args, Debug)]
pub struct PlanArgs {
    /// Algorithm TOML file, e.g. algorithms/zhl16c-gf30-85.toml.
    #[arg(long)]
    pub algorithm: std::path::PathBuf,
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
    /// Output format: md, csv or toml.
    #[arg(long, default_value = "md", value_parser = ["md", "csv", "toml"])]
    pub format: String,
    /// Write the schedule TOML here (readable by every later command).
    #[arg(long)]
    pub out: Option<std::path::PathBuf>,
}

/// Run a parsed command; returns the process exit code.
pub fn run(cli: Cli) -> anyhow::Result<i32> {
    match cli.command {
        Command::Plan(a) => {
            let req = decophantom::app::plan::PlanRequest {
                algorithm: a.algorithm,
                depth_m: a.depth,
                time_min: a.time,
                gas: a.gas,
                deco_gases: a.deco_gas,
                format: decophantom::app::plan::PlanFormat::parse(&a.format).unwrap_or_default(),
                out: a.out,
            };
            print!("{}", decophantom::app::plan::run(&req)?.text);
            Ok(0)
        }
    }
}
