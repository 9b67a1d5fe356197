//! `decophantom reproduce`: wiring only; the figures are in [`crate::reproduce`].

use crate::error::Error;
use crate::reproduce::{reproduce, select, Progress, Reproduced, Settings};
use std::path::PathBuf;

/// What `reproduce` needs.
#[derive(Debug, Clone)]
pub struct ReproduceRequest {
    /// `all` or a figure name (`fig2a`, `fig2b`, `fig3`, `fig5`, `fig6`).
    pub figure: String,
    /// Output folder.
    pub out: PathBuf,
    /// Reduced grids and designs.
    pub quick: bool,
    /// The command line, for the reports.
    pub command: String,
}

/// Check the request, run the figures, write the folder.
pub fn run(req: &ReproduceRequest, progress: Progress) -> Result<Vec<Reproduced>, Error> {
    let figures = select(&req.figure)?;
    reproduce(
        &figures,
        &Settings { quick: req.quick },
        &req.out,
        &req.command,
        progress,
    )
}

/// One line per figure: its verdict counts and wall time.
pub fn summary_text(done: &[Reproduced]) -> String {
    use crate::reproduce::Agreement;
    let mut s = String::new();
    for d in done {
        let n = |a: Agreement| d.verdicts.iter().filter(|v| v.agrees == a).count();
        s.push_str(&format!(
            "{}: {} claims — {} agree, {} partly, {} disagree, {} not comparable ({:.1} s)\n",
            d.figure.name,
            d.verdicts.len(),
            n(Agreement::Yes),
            n(Agreement::Partly),
            n(Agreement::No),
            n(Agreement::NotComparable),
            d.wall_seconds
        ));
    }
    s
}
