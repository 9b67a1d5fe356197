//! One library function per subcommand; the CLI only parses arguments and prints what these
//! return. Nothing here touches the terminal.

/// Set when the user asks the process to stop (the binary's Ctrl-C handler). Every phantom
/// run started through [`simulate::simulate`] checks it each step and ends with
/// [`crate::error::Error::Interrupted`]; commands then write nothing half-done.
pub static INTERRUPT: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

pub mod check;
pub mod cost;
pub mod demo;
pub mod discover;
pub mod elasticity;
pub mod evaluate;
pub mod fit;
pub mod json;
pub mod plan;
pub mod reproduce;
pub mod sensitivity;
pub mod simulate;
pub mod synth;
