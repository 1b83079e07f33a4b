//! Grid searches of the estimate: independent replays side by side on a
//! thread pool of their own.

use super::*;

/// Stack of each thread of [`pool`], bytes.
const STACK: usize = 64 << 20;

/// The thread pool the grids run on (built on first use; `None` if the
/// system refuses the threads: the grid then runs on the caller's
/// thread).
fn pool() -> Option<&'static rayon::ThreadPool> {
    static POOL: std::sync::OnceLock<Option<rayon::ThreadPool>> = std::sync::OnceLock::new();
    POOL.get_or_init(|| {
        rayon::ThreadPoolBuilder::new()
            .stack_size(STACK)
            .thread_name(|i| format!("locus-replay-grid-{i}"))
            .build()
            .ok()
    })
    .as_ref()
}

/// The grid point of smallest NLL, and the whole grid's `(value, NLL)` (in
/// the grid's order).
pub(super) fn grid_minimum(
    grid: &[f64],
    objective: impl Fn(f64) -> Result<f64, Error> + Sync,
) -> Result<(f64, Vec<(f64, f64)>), Error> {
    use rayon::prelude::*;
    // The grid points are independent replays: run side by side, on a pool
    // of their own whose threads have room for a replay's stack (the
    // running filter's history is a large value; a caller's 2 MiB worker
    // running these nested would overflow).
    let run = || {
        grid.par_iter()
            .map(|&g| Ok((g, objective(g)?)))
            .collect::<Result<Vec<(f64, f64)>, Error>>()
    };
    let tried = match pool() {
        Some(p) => p.install(run)?,
        None => grid
            .iter()
            .map(|&g| Ok((g, objective(g)?)))
            .collect::<Result<Vec<(f64, f64)>, Error>>()?,
    };
    let best = tried
        .iter()
        .filter(|t| t.1.is_finite())
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(grid[0], |t| t.0);
    Ok((best, tried))
}
