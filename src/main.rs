//! decophantom command line: parse with clap, call the library, map errors to exit codes
//! (0 success, 1 a check failed, 2 bad input, 3 solver or I/O failure).

mod cli;

use clap::Parser;

fn main() {
    let args = cli::Cli::parse();
    let code = match cli::run(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            match e.downcast_ref::<decophantom::error::Error>() {
                Some(decophantom::error::Error::Input(_)) => 2,
                Some(decophantom::error::Error::Interrupted(_)) => 130,
                _ if e.downcast_ref::<decophantom::error::InputError>().is_some() => 2,
                _ => 3,
            }
        }
    };
    std::process::exit(code);
}
