//! One library function per subcommand; the CLI only parses arguments and prints what these
//! return. Nothing here touches the terminal.

pub mod demo;
pub mod elasticity;
pub mod plan;
pub mod simulate;
