//! One library function per subcommand; the CLI only parses arguments and prints what these
//! return. Nothing here touches the terminal. What more than one command (or a library module)
//! needs lives in the library: a phantom run in [`crate::run`], a dive planned from the
//! command line's strings in [`crate::algorithm::plan_dive`], the elasticity laws' final radii
//! in [`crate::phantom::elasticity_compare`] (the `elasticity` command calls it directly).

pub mod check;
pub mod demo;
pub mod discover;
pub mod evaluate;
pub mod fit;
pub mod json;
pub mod plan;
pub mod reproduce;
pub mod sensitivity;
pub mod simulate;
pub mod synth;
