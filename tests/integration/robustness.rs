//! "Never a panic": every reader of person-written or foreign files returns a value or an
//! InputError for arbitrary input. The inputs are mutations of real, valid files (characters
//! deleted, replaced or inserted at random places, lines cut), which reach far deeper into the
//! validation than random bytes would.

use crate::common::root;
use decophantom::algorithm::conventions::DECOTENGU;
use decophantom::gas::GasMix;
use decophantom::profile::legacy::LegacyUnits;
use decophantom::units::{PressureUnit, TimeUnit};
use proptest::prelude::*;
use proptest::test_runner::FileFailurePersistence;
use std::path::Path;

fn read(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap()
}

/// Apply edits (position fraction, kind, character) to a text.
fn mutate(text: &str, edits: &[(f64, u8, char)]) -> String {
    let mut chars: Vec<char> = text.chars().collect();
    for &(pos, kind, c) in edits {
        if chars.is_empty() {
            chars.push(c);
            continue;
        }
        let i = ((pos * chars.len() as f64) as usize).min(chars.len() - 1);
        match kind % 4 {
            0 => {
                chars.remove(i);
            }
            1 => chars[i] = c,
            2 => chars.insert(i, c),
            _ => chars.truncate(i),
        }
    }
    chars.into_iter().collect()
}

fn edits() -> impl Strategy<Value = Vec<(f64, u8, char)>> {
    prop::collection::vec(
        (
            0.0f64..1.0,
            any::<u8>(),
            prop::sample::select(vec![
                '0', '9', '-', '.', 'e', '"', '=', '[', ']', ',', '\n', ' ', 'x', '#', '\t', '/',
                '@',
            ]),
        ),
        1..6,
    )
}

/// 64 cases per test. A failing case is saved to the committed file
/// `proptest-regressions/integration/robustness.txt` (re-run first on the next run; commit it
/// with the fix), never to an untracked `*.proptest-regressions` file beside this source
/// (proptest's default for a test outside `src/`). Paths are relative to the package root,
/// which is the working directory of `cargo test`.
fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 64,
        failure_persistence: Some(Box::new(FileFailurePersistence::Direct(
            "proptest-regressions/integration/robustness.txt",
        ))),
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn phantom_reader_never_panics(e in edits()) {
        let text = mutate(&read("profiles/phantoms/oscillation.toml"), &e);
        let _ = decophantom::phantom::config::parse_phantom(&text, Path::new("p.toml"));
    }

    #[test]
    fn profile_readers_never_panic(e in edits()) {
        let text = mutate(&read("profiles/fig5-dive.toml"), &e);
        let _ = decophantom::profile::toml::parse(&text, Path::new("p.toml"));
        let legacy = mutate("0.0\t0.0\n0.5 \t20\n1.0\t0.0\n1.5\t20\n", &e);
        let _ = decophantom::profile::legacy::parse(&legacy, Path::new("p.txt"), &LegacyUnits::new(TimeUnit::Min, PressureUnit::PsiGauge));
    }

    #[test]
    fn algorithm_and_criteria_readers_never_panic(e in edits()) {
        let text = mutate(&read("algorithms/zhl16c-gf30-85.toml"), &e);
        if let Ok(a) = decophantom::algorithm::config::parse_algorithm(&text, Path::new("a.toml")) {
            // a file that loads must also plan (or refuse the plan) without panicking
            let plan = decophantom::algorithm::DivePlan { depth_m: 40.0, bottom_time_min: 20.0, bottom_gas: GasMix::AIR, deco_gases: vec![] , travel_gases: vec![]};
            let _ = a.algorithm.plan(&plan);
        }
        let text = mutate(&read("algorithms/vpmb-2-baker.toml"), &e);
        let _ = decophantom::algorithm::config::parse_algorithm(&text, Path::new("v.toml"));
        let text = mutate(&read("algorithms/criteria/default.toml"), &e);
        let _ = decophantom::risk::parse_criteria(&text, Path::new("c.toml"));
    }

    #[test]
    fn schedule_and_dive_log_readers_never_panic(e in edits()) {
        let csv = mutate("time_min,depth_m,gas\n0,0,air\n2,30,\n20,30,\n25,6,50\n28,0,\n", &e);
        let _ = decophantom::algorithm::waypoints::parse_waypoints_csv(&csv, Path::new("s.csv"), &DECOTENGU, GasMix::AIR);
        let xml = mutate(&read("tests/data/divelogs/legacy-v1.xml"), &e);
        let _ = decophantom::profile::divelog::parse(&xml, Path::new("d.xml"));
    }
}

/// A reader that has gone away (`decophantom … | head -1`) is not an error: the command does
/// its work and exits 0 without a panic (Rust's `print!` panics on a broken pipe; the man page
/// went to exit 3 on "Broken pipe").
#[test]
fn a_closed_stdout_is_not_a_panic() {
    use std::process::{Command, Stdio};
    let plan = [
        "plan",
        "--algorithm",
        "algorithms/zhl16b-gf30-85.toml",
        "--depth",
        "45",
        "--time",
        "25",
    ];
    for args in [&["man"][..], &["completions", "bash"][..], &plan[..]] {
        let mut child = Command::new(crate::common::bin())
            .args(args)
            .current_dir(crate::common::root())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        // close the reading end before the command writes
        drop(child.stdout.take());
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
        assert!(
            !err.contains("panicked") && !err.contains("Broken pipe"),
            "{args:?}: {err}"
        );
    }
}
