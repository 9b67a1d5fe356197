//! How one simulation's grid loops use threads: a lone run on every thread, each of many runs
//! at once on one thread or nested, by grid size (issue 13: small runs are cheap).

use super::{simulate, SimRun};
use crate::error::Error;
use crate::phantom::params::PhantomParams;
use crate::profile::PressureHistory;

/// How one simulation's grid loops (the diffusion kernels, the per-record pass over the gel)
/// use threads (issue 13: small runs are cheap). Every mode gives the same bits (the grid
/// loops combine their parts in a fixed order, whatever the thread count); only the time
/// differs.
///
/// Runners of many simulations at once (`sweep`/`sensitivity`, `fit`, `discover`, `evaluate`,
/// `reproduce`) run them in parallel through rayon and use [`GridThreads::batch`] for each:
/// [`GridThreads::Auto`] unless the environment variable `DECOPHANTOM_GRID_THREADS` says
/// `serial`, `parallel` or `auto`. A lone `simulate` runs its grid loops on every thread.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GridThreads {
    /// [`GridThreads::Serial`] for a grid of fewer than [`SMALL_GRID_CELLS`] cells, else
    /// [`GridThreads::Parallel`].
    #[default]
    Auto,
    /// Every grid loop on one thread: the run is installed in a one-thread rayon pool, so each
    /// `par_iter` inside it runs serially, with no fork/join per step. For small runs among
    /// many running in parallel, where the parallelism is across runs.
    Serial,
    /// Grid loops on the current rayon pool (nested in a runner's parallel loop over runs).
    Parallel,
}

/// Grids of fewer cells than this run serially in a batch ([`GridThreads::Auto`]): on a tiny
/// grid the per-step fork/join of grid-level parallelism costs more than the step (a 512-cell
/// cube: ~60 % of the run was thread wake-ups). At the 216 000-cell `benches/small-cube` the
/// two are even (8 runs at once, `cargo bench --bench small_runs`, 26 Nov 2026: 1.19–1.22 s
/// nested, 1.19–1.22 s serial inside); on its 4 mm version (64 000 cells,
/// `SMALL_RUNS_SIZE_MM=4`) serial inside is the faster, 407 ms against 431 ms. (Until 26 Nov
/// 2026 serial-inside runs were serialised, [`with_grid_threads`]: 749 ms there.)
pub const SMALL_GRID_CELLS: f64 = 2.0e5;

impl GridThreads {
    /// The mode for one of many simulations run at once: `DECOPHANTOM_GRID_THREADS`
    /// (`auto`, `serial` or `parallel`; read once) or [`GridThreads::Auto`].
    pub fn batch() -> GridThreads {
        static MODE: std::sync::OnceLock<GridThreads> = std::sync::OnceLock::new();
        *MODE.get_or_init(|| {
            match std::env::var("DECOPHANTOM_GRID_THREADS")
                .unwrap_or_default()
                .trim()
                .to_ascii_lowercase()
                .as_str()
            {
                "serial" => GridThreads::Serial,
                "parallel" => GridThreads::Parallel,
                _ => GridThreads::Auto,
            }
        })
    }

    /// Whether a run of `params` keeps its grid loops on one thread in this mode.
    pub fn serial_for(self, params: &PhantomParams) -> bool {
        match self {
            GridThreads::Serial => true,
            GridThreads::Parallel => false,
            GridThreads::Auto => estimated_cells(params) < SMALL_GRID_CELLS,
        }
    }
}

/// Cells of the grid of `params` (its bounding box over the grid step cubed; no grid is built).
pub fn estimated_cells(params: &PhantomParams) -> f64 {
    let extent = match params.shape {
        crate::phantom::grid::Shape::Box { size } => size[0] * size[1] * size[2],
        crate::phantom::grid::Shape::Cylinder { diameter, depth } => diameter * diameter * depth,
    };
    extent / params.grid_step.powi(3)
}

thread_local! {
    /// This thread's one-thread pool for [`with_grid_threads`] (built on first use).
    static ONE_THREAD: Option<rayon::ThreadPool> =
        rayon::ThreadPoolBuilder::new().num_threads(1).build().ok();
}

/// Run `f` (a simulation of `params`) with its grid loops as `mode` chooses for it: inside
/// this thread's one-thread pool when serial, on the current pool otherwise.
pub fn with_grid_threads<R: Send>(
    mode: GridThreads,
    params: &PhantomParams,
    f: impl FnOnce() -> R + Send,
) -> R {
    if !mode.serial_for(params) {
        return f();
    }
    ONE_THREAD.with(|pool| match pool {
        // from a worker of another pool (a runner's loop over runs), the run is handed to a
        // plain thread that waits in `install` without taking work: a worker waiting there
        // itself would run further runs of the batch inside its wait (rayon's cross-pool
        // `install`), queueing them behind this one in the same one-thread pool
        Some(pool) if rayon::current_thread_index().is_some() => std::thread::scope(|s| {
            s.spawn(|| pool.install(f))
                .join()
                .unwrap_or_else(|e| std::panic::resume_unwind(e))
        }),
        Some(pool) => pool.install(f),
        None => f(),
    })
}

/// [`simulate`] as one of many simulations run at once ([`GridThreads::batch`]).
pub fn simulate_in_batch(
    params: &PhantomParams,
    profile: &PressureHistory,
    progress: &mut (dyn FnMut(f64, f64) + Send),
) -> Result<SimRun, Error> {
    with_grid_threads(GridThreads::batch(), params, || {
        simulate(params, profile, progress)
    })
}
