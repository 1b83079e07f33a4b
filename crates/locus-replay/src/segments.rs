//! The replay's driver: the forward pass run to the end, and with the
//! smoother, in segments re-made from checkpoints.
//!
//! [`replay`] and [`replay_in_segments`] run the [`Engine`] over the whole
//! log, handing each step to the caller's sink in canonical time order.
//! Without [`Config::smooth`] each step goes to the sink as soon as it is
//! final. With it, the forward pass keeps a checkpoint every `segment`
//! steps and the smoother's backward pass re-makes each segment from its
//! checkpoint (`smoother::flush`): memory is one segment's steps and the
//! checkpoints, [`smoothing_segment`] balancing the two. The steps and
//! the report are the same to the bit whatever the segment length.

use crate::engine::{Engine, judged};
use crate::filter::{calibration_of, pose_belief};
use crate::{Config, Error, Log, Report, Step, smoother};

/// Replays `log` with `cfg`, handing each step (in canonical time order,
/// with its final estimate, and with [`Config::smooth`] its smoothed one)
/// to `sink`.
///
/// The smoother works in segments of [`smoothing_segment`] steps (see
/// [`replay_in_segments`]): its memory grows as the square root of the
/// log's length, not the length.
///
/// # Errors
/// An invalid configuration, a log with no odometry or no initial pose,
/// sightings out of arrival order, a filter failure, a smoother failure.
pub fn replay(log: &Log, cfg: &Config, sink: impl FnMut(&Step)) -> Result<Report, Error> {
    let events = log.odometry.len() + log.sightings.len() + log.scans.len();
    replay_in_segments(log, cfg, smoothing_segment(events), sink)
}

/// Steps of the smoother's segments for a log of `events` events (odometry
/// records and sightings): `sqrt(1024 events)`, at least 2^17.
///
/// Checkpointing (Griewank, "Achieving logarithmic growth of temporal and
/// spatial complexity in reverse automatic differentiation", Optimization
/// Methods and Software 1(1), 1992, in its one-level form): the forward
/// pass keeps its state every `segment` steps, and the backward pass
/// re-makes each segment's steps from it. Memory is then one segment's
/// steps (0.93 KB each: the step and the 7-state belief the smoother needs)
/// and `events / segment` checkpoints (the running filter's pending
/// events, 0.6 KB each: about 40 KB on MRCLAM with its 1 s history, at
/// most 0.6 MB with the history full at 1024 events); `segment =
/// sqrt(1024 events)` balances the two in the worst case. A log of at most
/// 2^17 events is one segment, held whole (at most 122 MB) and run once,
/// as without checkpoints. For 10^7 events: segments of 2^17 steps
/// (122 MB) and 76 checkpoints.
#[must_use]
pub fn smoothing_segment(events: usize) -> usize {
    events.saturating_mul(1024).isqrt().max(1 << 17)
}

/// [`replay`] with the smoother's segments `segment` steps long (at least
/// 1): a segment's steps are held at once, and the forward pass is re-run
/// from its checkpoints twice, once for the backward pass (last segment
/// first) and once to hand the steps over in order. A log of at most
/// `segment` steps is run once, its steps all held. The steps and the
/// report are the same to the bit whatever `segment` is (the passes repeat
/// the same operations on the same values); only
/// [`Report::smoothing_held`] and [`Report::smoothing_checkpoints`]
/// differ.
///
/// # Errors
/// As [`replay`].
pub fn replay_in_segments(
    log: &Log,
    cfg: &Config,
    segment: usize,
    sink: impl FnMut(&Step),
) -> Result<Report, Error> {
    run(log, cfg, segment, || false, sink)
}

/// [`replay`], asking `stop` before each event of the forward pass whether
/// to stop there (a user's interrupt, polled: `stop` should be cheap).
///
/// # Errors
/// As [`replay`], and [`Error::Stopped`] when `stop` said so.
pub fn replay_until(
    log: &Log,
    cfg: &Config,
    stop: impl FnMut() -> bool,
    sink: impl FnMut(&Step),
) -> Result<Report, Error> {
    let events = log.odometry.len() + log.sightings.len() + log.scans.len();
    run(log, cfg, smoothing_segment(events), stop, sink)
}

fn run(
    log: &Log,
    cfg: &Config,
    segment: usize,
    mut stop: impl FnMut() -> bool,
    mut sink: impl FnMut(&Step),
) -> Result<Report, Error> {
    let mut engine = Engine::new(log, cfg, segment)?;
    // With the smoother: a checkpoint every `segment` steps, each
    // segment's steps re-made from its checkpoint for the backward pass
    // (smoother::flush); until the second checkpoint the steps are held,
    // so a log of one segment is run once.
    let segment = segment.max(1);
    let mut checkpoints = Vec::new();
    if cfg.smooth {
        checkpoints.push(engine.checkpoint());
    }
    loop {
        if let Some(c) = checkpoints.last()
            && engine.next_index >= c.next_index.saturating_add(segment)
        {
            checkpoints.push(engine.checkpoint());
        }
        if stop() {
            return Err(Error::Stopped {
                before: engine.next_index,
            });
        }
        let more = engine.advance()?;
        if !cfg.smooth {
            for step in engine.held.drain(..) {
                sink(&step);
            }
        } else if checkpoints.len() > 1 {
            engine.held.clear();
            engine.nodes.clear();
        }
        engine.report.smoothing_held = engine.report.smoothing_held.max(engine.nodes.len());
        if !more {
            break;
        }
    }
    let last = engine.filter.base().belief;
    engine.report.final_belief = pose_belief(&last);
    engine.report.calibration = calibration_of(&last);
    engine.report.summary = judged(engine.tally.summary(), engine.compared_after_start > 0);
    if cfg.smooth {
        smoother::flush(&mut engine, checkpoints, &mut sink)?;
    }
    Ok(engine.report)
}
