//! Keeping the pool's other workers awake through a lone run's serial phases (issue 13: small
//! runs are cheap).
//!
//! A time step is a parallel phase (the gel's diffusion, a few hundred µs on a small grid)
//! between serial ones (the bubbles' exchange and events, the step control, the record: tens of
//! µs). A rayon worker with no work spins for a few dozen rounds and then sleeps, and waking it
//! again at the next parallel phase costs a system call and a wake-up latency in the tens of
//! µs on this machine's virtual CPUs. On `benches/small-cube` (two threads) the other worker
//! slept and was woken at almost every step: 987 context switches in 445 steps, and the
//! parallel phases ran 1.5× faster than on one thread where the kernels alone run 2× faster.
//!
//! So a run alone on its pool ([`lone_run`]; not the batch runners' runs, which share the pool
//! with other runs that have work for it) hands each idle worker a spinner at the start of a
//! serial phase ([`KeepWarm::serial_phase`]). The spinner runs whatever work the pool has
//! meanwhile (`rayon::yield_now`: a serial phase's own parallel loops still use every
//! thread) and otherwise yields the CPU to the system and looks again (what rayon's own idle
//! loop does for a few dozen rounds before it sleeps), until the next parallel phase starts
//! ([`KeepWarm::parallel_phase`]) or [`SPIN_LIMIT`] has passed; then the worker is back in
//! rayon's own loop, where it finds the new phase's work at once. Results do not depend on it
//! (every grid loop gives the same bits on any thread count); only the wall time does.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Longest a spinner keeps its worker from sleeping. Serial phases longer than this (a frame's
/// pass over the gel, a displacement on a big grid) let the worker sleep as before; the limit
/// bounds the CPU time a long serial phase can waste on every other thread. 2 and 5 ms were
/// within 1–2 % of this on the Fig. 5 dive (docs/speed-history.md, session 20).
pub const SPIN_LIMIT: Duration = Duration::from_micros(500);

thread_local! {
    /// Whether the run on this thread is alone on its pool ([`lone_run`]).
    static LONE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Run `f` (a simulation) with its serial phases keeping the pool's workers awake when `lone`
/// (the run is the only work of its pool: a command's single run, started from outside the
/// pool). Must be called on the thread that runs the simulation.
pub fn lone_run<R>(lone: bool, f: impl FnOnce() -> R) -> R {
    struct Reset(bool);
    impl Drop for Reset {
        fn drop(&mut self) {
            LONE.set(self.0);
        }
    }
    let _reset = Reset(LONE.replace(lone));
    f()
}

/// A run's hand on its pool's idle workers ([`lone_run`]); inert unless the run is lone and
/// the pool has more than one thread.
pub struct KeepWarm {
    /// Bumped at every parallel phase (and at the end): a spinner started under another value
    /// returns.
    epoch: Arc<AtomicU64>,
    /// Spinners per serial phase: the pool's threads but this one (0: inert).
    spinners: usize,
    /// How long a spinner spins at most ([`SPIN_LIMIT`]).
    limit: Duration,
}

impl KeepWarm {
    /// For a run on the current thread.
    pub fn new() -> KeepWarm {
        let threads = rayon::current_num_threads();
        let on_pool = rayon::current_thread_index().is_some();
        KeepWarm {
            epoch: Arc::new(AtomicU64::new(0)),
            spinners: if LONE.get() && on_pool && threads > 1 {
                threads - 1
            } else {
                0
            },
            limit: SPIN_LIMIT,
        }
    }

    /// Whether this run keeps the workers awake.
    pub fn active(&self) -> bool {
        self.spinners > 0
    }

    /// A serial phase starts: give each idle worker a spinner.
    pub fn serial_phase(&self) {
        if self.spinners == 0 {
            return;
        }
        let e0 = self.epoch.load(Ordering::Acquire);
        let owner = rayon::current_thread_index();
        let limit = self.limit;
        for _ in 0..self.spinners {
            let epoch = Arc::clone(&self.epoch);
            rayon::spawn(move || {
                // popped by the run's own thread (waiting in a join of its serial phase): it
                // must not stall there
                if rayon::current_thread_index() != owner {
                    spin(&epoch, e0, limit);
                }
            });
        }
    }

    /// A parallel phase starts: the spinners return, and their workers take its work.
    pub fn parallel_phase(&self) {
        if self.spinners > 0 {
            self.epoch.fetch_add(1, Ordering::AcqRel);
        }
    }
}

/// Run the pool's pending work or spin while `epoch` is `e0`, for at most `limit`. An idle
/// round yields the CPU to the system (as rayon's own idle rounds do), so that a spinner
/// never holds a core another process wants: on the small cube as fast as a pure spin
/// (0.168–0.177 s against 0.173–0.178 s, four rounds of `perf stat -r 8`) for 1–7 % less CPU.
fn spin(epoch: &AtomicU64, e0: u64, limit: Duration) {
    let start = Instant::now();
    while epoch.load(Ordering::Acquire) == e0 && start.elapsed() < limit {
        if rayon::yield_now() != Some(rayon::Yield::Executed) {
            std::thread::yield_now();
        }
    }
}

impl Default for KeepWarm {
    fn default() -> Self {
        KeepWarm::new()
    }
}

impl Drop for KeepWarm {
    fn drop(&mut self) {
        self.parallel_phase();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(n: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
    }

    #[test]
    fn inert_unless_lone_on_a_pool_of_several_threads() {
        // off the pool, or not lone, or one thread: no spinners
        assert!(!lone_run(true, KeepWarm::new).active());
        assert!(!pool(2).install(KeepWarm::new).active());
        assert!(!pool(1).install(|| lone_run(true, KeepWarm::new)).active());
        assert!(pool(2).install(|| lone_run(true, KeepWarm::new)).active());
        // the flag is the caller's again afterwards
        assert!(!pool(2).install(|| {
            lone_run(true, || ());
            KeepWarm::new().active()
        }));
    }

    #[test]
    fn a_serial_phase_still_runs_its_parallel_loops_on_every_thread() {
        // the other worker holds a spinner that would not end before the loop does (no limit,
        // no parallel phase): the loop is still shared, because the spinner runs pool work,
        // and its result is exact
        use rayon::prelude::*;
        let p = pool(2);
        let (sum, threads) = p.install(|| {
            lone_run(true, || {
                let mut warm = KeepWarm::new();
                warm.limit = Duration::from_secs(3600);
                warm.serial_phase();
                // let the other worker take its spinner first
                std::thread::sleep(Duration::from_millis(20));
                let seen: Vec<(usize, usize)> = (0..64)
                    .into_par_iter()
                    .map(|i| {
                        std::thread::sleep(Duration::from_micros(200));
                        (i, rayon::current_thread_index().unwrap())
                    })
                    .collect();
                warm.parallel_phase();
                let sum: usize = seen.iter().map(|v| v.0).sum();
                let mut t: Vec<usize> = seen.iter().map(|v| v.1).collect();
                t.sort_unstable();
                t.dedup();
                (sum, t.len())
            })
        });
        assert_eq!(sum, 63 * 64 / 2);
        assert_eq!(threads, 2, "both workers ran the serial phase's loop");
    }

    #[test]
    fn a_spinner_ends_at_the_next_epoch_or_at_its_limit() {
        let epoch = AtomicU64::new(7);
        // the limit: no epoch change
        let t = Instant::now();
        spin(&epoch, 7, Duration::from_millis(2));
        let took = t.elapsed();
        assert!(
            took >= Duration::from_millis(2) && took < Duration::from_secs(1),
            "{took:?}"
        );
        // the epoch moved on before (or while) it spins: it returns at once
        let t = Instant::now();
        spin(&epoch, 6, Duration::from_secs(3600));
        assert!(t.elapsed() < Duration::from_secs(1));
        let epoch = Arc::new(AtomicU64::new(0));
        let e = Arc::clone(&epoch);
        let bump = std::thread::spawn(move || {
            std::thread::sleep(Duration::from_millis(5));
            e.fetch_add(1, Ordering::AcqRel);
        });
        let t = Instant::now();
        spin(&epoch, 0, Duration::from_secs(3600));
        bump.join().unwrap();
        assert!(t.elapsed() < Duration::from_secs(10));
    }
}
