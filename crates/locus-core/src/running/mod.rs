//! The running filter: one belief carried through time, the filter every
//! loop of Locus runs (simulator, robot-link host, firmware, demo, teaching
//! UI, log replay).
//!
//! [`Ekf`] is stateless; a loop needs more around it: the time of the
//! belief, the gate's recovery from over-confidence, a consistency monitor
//! of the NIS, and, for logs whose measurements arrive late, a history so
//! that a late measurement is applied at its own time. [`RunningFilter`]
//! holds exactly that, in fixed arrays (`no_std`, no allocation):
//!
//! * [`Track`]: the belief, its time (s), the count of consecutive gate
//!   rejections, and the caller's own data `X` carried beside the belief
//!   (e.g. the input in force), all restored together on a re-run.
//! * [`Track::predict`] and [`Track::correct`] are the two operations; a
//!   correction returns a typed [`Update`] (applied, with the NIS, `S` and
//!   the gain; gated; no measurement) or an error, **and on any error the
//!   track is unchanged**.
//! * Recovery ([`Recovery`]): after `after` consecutive rejections the
//!   covariance is inflated by `inflation` (leaving the states the model
//!   holds fixed as they are) and the measurement tried once more; the
//!   inflation compounds over further rejections until a
//!   measurement fits. A chi-square gate alone can lock an over-confident
//!   filter out for good.
//! * History (`H` > 0): [`RunningFilter::insert`] puts an event at its place
//!   in time order and re-runs the later ones, so the estimates equal those
//!   of an in-order run (the same operations in the same order).
//!
//! For a loop that applies its events as they come (`H = 0`), the filter's
//! own [`RunningFilter::predict`] and [`RunningFilter::correct`] act on its
//! track directly and feed the consistency monitor.
//!
//! Here: [`nees`]; the rules a track is corrected by ([`Rules`],
//! [`Recovery`]) in `rules.rs`, the [`Track`] and what a correction did
//! ([`Update`]) in `track.rs`, and the [`RunningFilter`] with its history
//! of [`Event`]s in `filter.rs`.
//!
//! [`Ekf`]: crate::Ekf

mod filter;
mod rules;
mod track;

use nalgebra::SVector;

use crate::{Scalar, cast};

pub use filter::{Event, Final, Inserted, Placement, RunningFilter};
pub use rules::{Recovery, Rules};
pub use track::{Track, Update};

/// The normalised estimation error squared `e^T P^-1 e` (dimensionless) of
/// an estimate with covariance `P` and error `e` (truth minus estimate,
/// angles wrapped), by a Cholesky solve; `None` if `P` is not positive
/// definite (the NEES is then undefined, not infinite).
pub fn nees<T: Scalar, const N: usize>(
    error: &SVector<T, N>,
    p: &nalgebra::SMatrix<T, N, N>,
) -> Option<T> {
    let c = p.cholesky()?;
    let v = error.dot(&c.solve(error));
    // A finite error and a factored P give a finite, non-negative NEES.
    (v >= cast::<T>(0.0) && v.is_finite()).then_some(v)
}
