//! Issue 13 (small runs are cheap): a simulation's grid loops on one thread
//! ([`GridThreads::Serial`], as batch runners run small grids) or on the rayon pool
//! ([`GridThreads::Parallel`]) give the same bits — summary and every frame.

use crate::common::root;
use decophantom::app::simulate::{
    estimated_cells, simulate, with_grid_threads, GridThreads, SMALL_GRID_CELLS,
};
use decophantom::phantom::config::load_phantom;
use decophantom::profile::{load, LoadOptions};
use rayon::prelude::*;

#[test]
fn small_runs_serial_and_parallel_grid_loops_give_the_same_bits() {
    let dir = root().join("benches/small-cube");
    let history = load(&dir.join("profile.toml"), &LoadOptions::default()).unwrap();
    let mut params = load_phantom(&dir.join("phantom.toml")).unwrap().params;
    params.grid_step = 200e-6; // 30³ cells: a second or so
    assert!(GridThreads::Auto.serial_for(&params));
    assert!(estimated_cells(&params) < SMALL_GRID_CELLS);
    let run = |mode: GridThreads| {
        let r = with_grid_threads(mode, &params, || {
            simulate(&params, &history, &mut |_, _| {}).unwrap()
        });
        // Debug prints every float's shortest round-trip form: equal text, equal bits
        format!("{:?}\n{:?}", r.summary, r.frames)
    };
    let parallel = run(GridThreads::Parallel);
    assert_eq!(run(GridThreads::Serial), parallel);
    // as a batch runner does: several at once, each serial inside
    let batch: Vec<String> = (0..3)
        .into_par_iter()
        .map(|k| {
            run(if k == 1 {
                GridThreads::Parallel
            } else {
                GridThreads::Auto
            })
        })
        .collect();
    for b in &batch {
        assert_eq!(b, &parallel);
    }
}

#[test]
fn small_runs_auto_keeps_big_grids_parallel() {
    let dir = root().join("benches/small-cube");
    let mut params = load_phantom(&dir.join("phantom.toml")).unwrap().params;
    params.grid_step = 40e-6; // 150³ = 3.4 M cells
    assert!(!GridThreads::Auto.serial_for(&params));
    assert!(GridThreads::Serial.serial_for(&params));
    assert!(!GridThreads::Parallel.serial_for(&params));
}
