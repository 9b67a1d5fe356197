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
pub enum Command {}

/// Run a parsed command; returns the process exit code.
pub fn run(cli: Cli) -> anyhow::Result<i32> {
    match cli.command {}
}
