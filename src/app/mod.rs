//! One library function per subcommand; the CLI only parses arguments and prints what these
//! return. Nothing here touches the terminal.

pub mod check;
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
