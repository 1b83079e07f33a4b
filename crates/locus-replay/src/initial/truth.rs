//! The initial heading from a ground truth of positions only (a truth
//! with no heading, e.g. a UWB or motion-capture track of a point): the
//! direction in which the truth moves, less the turn dead reckoning makes
//! over the same time. Headings in rad, wrapped to (-pi, pi]; distances in
//! m; times in s.

use locus_core::nalgebra::Vector3;
use locus_core::wrap_angle;

use crate::dead_reckoning::DeadReckoning;
use crate::{Config, Log};

/// Distance the ground truth must move from its position at the first
/// odometry time before its direction of motion gives the initial heading
/// of a truth of positions only ([`heading_from_truth`]), m.
pub const HEADING_BASELINE: f64 = 0.3;

/// Seconds after the first odometry time within which the truth must have
/// moved [`HEADING_BASELINE`] for [`heading_from_truth`].
pub const HEADING_WINDOW: f64 = 30.0;

/// Standard deviation assumed for the heading [`heading_from_truth`] finds
/// when the robot drove straight, rad; a turn adds a quarter of the angle
/// turned (the odometry's turn-rate error, assumed up to 25 %).
pub const HEADING_STD: f64 = 0.1;

/// The initial heading found from a ground truth of positions only.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TruthHeading {
    /// The heading at the first odometry time, rad.
    pub heading: f64,
    /// Its standard deviation as assumed ([`HEADING_STD`]), rad.
    pub std: f64,
    /// How far the truth moved over the baseline, m.
    pub travelled: f64,
    /// From the first odometry time to the end of the baseline, s.
    pub span: f64,
}

/// The heading at the first odometry time `t0` (s) of a log whose ground
/// truth has positions only: the direction in which the truth moves from
/// its position at `t0` to its first position at least [`HEADING_BASELINE`]
/// away (within [`HEADING_WINDOW`] s), minus the direction in which dead
/// reckoning on the logged odometry (from heading 0, its delay and initial
/// calibration as `cfg` sets them) moves over the same time. A robot that
/// turned on the way is thereby accounted for to the odometry's accuracy.
/// `None` if the truth does not cover `t0`, does not move that far in time,
/// or the odometry moves less than half as far (it disagrees with the
/// truth about whether the robot moved).
#[must_use]
pub fn heading_from_truth(log: &Log, cfg: &Config, t0: f64) -> Option<TruthHeading> {
    let start = log.truth.pose_at(t0, cfg.truth_max_gap)?;
    let end = log
        .truth
        .poses()
        .iter()
        .filter(|p| p.time > t0 && p.time <= t0 + HEADING_WINDOW)
        .find(|p| (p.x - start.x).hypot(p.y - start.y) >= HEADING_BASELINE)?;
    let (dx, dy) = (end.x - start.x, end.y - start.y);
    let dead = DeadReckoning::new(log, cfg, Vector3::zeros(), t0).advance(end.time);
    let travelled = dx.hypot(dy);
    if dead[0].hypot(dead[1]) < 0.5 * travelled {
        return None;
    }
    Some(TruthHeading {
        heading: wrap_angle(dy.atan2(dx) - dead[1].atan2(dead[0])),
        std: HEADING_STD + 0.25 * dead[2].abs(),
        travelled,
        span: end.time - t0,
    })
}
