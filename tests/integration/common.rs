//! Helpers shared by the integration test modules.
#![allow(dead_code)]

use std::path::PathBuf;

/// The repository root (where Cargo.toml is).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Path to the built `decophantom` binary.
pub fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_decophantom"))
}

/// A fresh empty temporary directory under the target dir.
pub fn tempdir(name: &str) -> PathBuf {
    let d =
        PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The paper's dive profile (§4.2, Fig. 6a): compression at 6.9e4 Pa/s to 130 psi gauge, a
/// 20 min hold, decompression at 8.9e4 Pa/s, then `after_s` of growth at the surface; air.
pub fn fig6_dive(after_s: f64) -> decophantom::profile::PressureHistory {
    use decophantom::units::{ATM_PA, PSI_PA};
    let top = ATM_PA + 130.0 * PSI_PA;
    let down = (top - ATM_PA) / 6.9e4;
    let up = (top - ATM_PA) / 8.9e4;
    let t = vec![
        0.0,
        down,
        down + 1200.0,
        down + 1200.0 + up,
        down + 1200.0 + up + after_s,
    ];
    decophantom::profile::PressureHistory::with_gas(
        "fig6a",
        t,
        vec![ATM_PA, top, top, ATM_PA, ATM_PA],
        decophantom::gas::GasMix::AIR,
        0.0,
    )
    .unwrap()
}

/// A file or folder of the project's own fixtures, `tests/data/<rel>` (written for this
/// project; see `tests/data/README.md`).
pub fn data(rel: &str) -> PathBuf {
    root().join("tests/data").join(rel)
}

/// A file or folder of the third-party fixtures beside the repository (`../shared/<rel>`,
/// present on the project's own machines, not in a clone), or `None` after printing
/// `skipped: ../shared/<rel> not present` on stderr. The note is written to the process's
/// stderr directly, past the test harness's output capture, so it shows in a passing run.
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = root().join("../shared").join(rel);
    if p.exists() {
        Some(p)
    } else {
        use std::io::Write;
        let _ = writeln!(std::io::stderr(), "skipped: ../shared/{rel} not present");
        None
    }
}
