//! Issue 13 (small runs are cheap): a simulation's grid loops on one thread
//! ([`GridThreads::Serial`], as batch runners run small grids) or on the rayon pool
//! ([`GridThreads::Parallel`]) give the same bits — summary and every frame.

use crate::common::root;
use decophantom::phantom::config::load_phantom;
use decophantom::profile::{load, LoadOptions};
use decophantom::run::threads::{estimated_cells, SMALL_GRID_CELLS};
use decophantom::run::{simulate, with_grid_threads, GridThreads};
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

/// Serial runs started from two workers of a batch run at the same time, each on its own
/// thread (the first run waits, up to 20 s, until the second has started). Before 26 Nov 2026 a
/// worker waiting in its one-thread pool's `install` took the second run off its own queue
/// inside the wait and queued it behind the first in the same pool: the runs of a batch below
/// `SMALL_GRID_CELLS` went one after the other (`cargo bench --bench small_runs` with
/// `SMALL_RUNS_SIZE_MM=4`: 8 runs 749 ms serial inside against 407 ms since).
#[test]
fn small_runs_serial_runs_of_a_batch_run_side_by_side() {
    use std::sync::{Condvar, Mutex};
    use std::time::Duration;
    let dir = root().join("benches/small-cube");
    let params = load_phantom(&dir.join("phantom.toml")).unwrap().params;
    let started = (Mutex::new(0usize), Condvar::new());
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let met: Vec<bool> = pool.install(|| {
        (0..2)
            .into_par_iter()
            .with_max_len(1)
            .map(|_| {
                with_grid_threads(GridThreads::Serial, &params, || {
                    // inside the run: the grid loops' pool is a one-thread pool
                    assert_eq!(rayon::current_num_threads(), 1);
                    let (count, cv) = &started;
                    let mut n = count.lock().unwrap();
                    *n += 1;
                    cv.notify_all();
                    let (n, _) = cv
                        .wait_timeout_while(n, Duration::from_secs(20), |n| *n < 2)
                        .unwrap();
                    *n == 2
                })
            })
            .collect()
    });
    assert_eq!(met, [true, true], "the two serial runs did not overlap");
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

/// `record_gel = false` (what `fit` and `discover` ask for): the same bubbles in every frame,
/// bit for bit, and the same summary (but for the lowest concentration, taken over fewer
/// frames); the gel's state only in the first and the last frame
/// (NaN supersaturation and no grid totals between), whose values are those of the full run.
#[test]
fn frames_without_the_gel_pass_keep_the_bubbles_bits() {
    let dir = root().join("benches/small-cube");
    let history = load(&dir.join("profile.toml"), &LoadOptions::default()).unwrap();
    let mut params = load_phantom(&dir.join("phantom.toml")).unwrap().params;
    params.grid_step = 200e-6;
    assert_eq!(params.numerics.record_interval, 0.0);
    let full = simulate(&params, &history, &mut |_, _| {}).unwrap();
    params.numerics.record_gel = false;
    let light = simulate(&params, &history, &mut |_, _| {}).unwrap();
    // the lowest concentration is over the first and last frames only
    assert!(light.summary.min_concentration >= full.summary.min_concentration);
    let mut same = light.summary.clone();
    same.min_concentration = full.summary.min_concentration;
    assert_eq!(format!("{same:?}"), format!("{:?}", full.summary));
    assert_eq!(light.frames.len(), full.frames.len());
    assert!(full.frames.len() > 100);
    let last = full.frames.len() - 1;
    for (k, (a, b)) in light.frames.iter().zip(&full.frames).enumerate() {
        assert_eq!(a.time.to_bits(), b.time.to_bits());
        assert_eq!(format!("{:?}", a.bubbles), format!("{:?}", b.bubbles));
        if k == 0 || k == last {
            assert_eq!(
                a.max_supersaturation.to_bits(),
                b.max_supersaturation.to_bits()
            );
            assert_eq!(a.grid_moles, b.grid_moles);
        } else {
            assert!(a.max_supersaturation.is_nan() && a.grid_moles.is_empty());
            assert!(b.max_supersaturation.is_finite() && !b.grid_moles.is_empty());
        }
    }
}
