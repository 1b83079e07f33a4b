//! Where the replay starts: the initial pose at the first odometry time,
//! and whether a start pose given with the log contradicts its sightings.
//!
//! As [`Config::start`] says: the log's start pose, else the ground truth
//! at the first odometry time (for a truth of positions only, its position
//! and the heading of its direction of motion,
//! [`initial::heading_from_truth`], if it moves), else the pose the first
//! sightings fix ([`initial::from_sightings`]). Poses are x, y (m) and
//! heading (rad, wrapped to (-pi, pi]); covariances in those units
//! squared.

use locus_core::nalgebra::{SMatrix, Vector3};
use locus_core::wrap_angle;
use locus_logs::mrclam::TruthPose;

use crate::{Config, Error, Log, Start, StartDisagreement, StartedFrom, initial};

/// The initial pose at `t0` (the first odometry time), its covariance and
/// where it came from, as [`Config::start`] says.
pub(crate) fn initial_pose(
    log: &Log,
    cfg: &Config,
    t0: f64,
) -> Result<(Vector3<f64>, SMatrix<f64, 3, 3>, StartedFrom), Error> {
    let given = match cfg.start {
        Start::Sightings => None,
        Start::Log => log.start.map(|p| (p, StartedFrom::Log)).or_else(|| {
            log.truth
                .pose_at(t0, cfg.truth_max_gap)
                .map(|p| (p, StartedFrom::Truth))
        }),
    };
    // A truth of positions only gives the heading by its direction of
    // motion, if it can.
    let given = match given {
        Some((p, StartedFrom::Truth)) if p.theta.is_nan() => {
            initial::heading_from_truth(log, cfg, t0).map(|h| {
                (
                    TruthPose {
                        theta: h.heading,
                        ..p
                    },
                    StartedFrom::TruthPosition(h),
                )
            })
        }
        other => other,
    };
    if let Some((p, from)) = given {
        let [sx, sy, mut st] = cfg.initial_std;
        if let StartedFrom::TruthPosition(h) = from {
            st = h.std;
        }
        return Ok((
            Vector3::new(p.x, p.y, wrap_angle(p.theta)),
            SMatrix::<f64, 3, 3>::from_diagonal(&Vector3::new(sx * sx, sy * sy, st * st)),
            from,
        ));
    }
    let fix = initial::from_sightings(log, cfg).map_err(|reason| Error::NoStart {
        time: t0,
        asked: cfg.start == Start::Sightings,
        reason,
    })?;
    Ok((fix.pose, fix.covariance, StartedFrom::Sightings(fix)))
}

/// The log's start pose against where its first sightings put the robot,
/// when the replay started from that pose and the two disagree beyond
/// [`initial::DISAGREE`]; else `None` (also when the sightings fix no
/// pose).
pub(crate) fn start_disagreement(
    log: &Log,
    cfg: &Config,
    from: &StartedFrom,
) -> Option<StartDisagreement> {
    let (StartedFrom::Log, Some(start)) = (from, log.start) else {
        return None;
    };
    let fix = initial::from_sightings(log, cfg).ok()?;
    let pose = Vector3::new(start.x, start.y, start.theta);
    let d2 = fix.distance2(&pose, cfg.initial_std);
    (d2 > initial::DISAGREE).then(|| StartDisagreement {
        log: [start.x, start.y, start.theta],
        sightings: [fix.pose[0], fix.pose[1], fix.pose[2]],
        sigma: d2.sqrt(),
    })
}
