//! The initial pose found from the log's own sightings, for a log that
//! gives no start pose and has no ground truth (a user's own robot).
//!
//! Dead reckoning from the first odometry time puts the landmark of each
//! sighting of the first seconds in the frame of the robot at that time
//! (the *start frame*). The robot's initial pose is the 2D rigid
//! transform that carries those points onto the landmarks' map positions:
//!
//! * **Hypotheses** from every pair of sightings of two different
//!   landmarks whose distance apart agrees with the map's (RANSAC with an
//!   exhaustive draw: Fischler and Bolles, "Random sample consensus",
//!   Comm. ACM 24(6), 1981), each scored by the sightings it places within
//!   [`inlier_tolerance`] of their landmark, so a relabelled or gross
//!   sighting (1-4 % of MRCLAM's) cannot set the pose.
//! * **Least squares** over the best hypothesis's inliers, in closed form
//!   (the 2D case of Umeyama, "Least-squares estimation of transformation
//!   parameters between two point patterns", IEEE PAMI 13(4), 1991),
//!   twice (the inliers taken again against the refined pose).
//! * **Covariance** of that estimate when each landmark's sightings share
//!   one error (a camera's range to a landmark errs the same way for
//!   seconds, docs/replay.md): `sigma^2 A^-1 B A^-1` with `A = sum J_i^T
//!   J_i` over the sightings and `B = sum S_l^T S_l`, `S_l` the sum of
//!   landmark `l`'s Jacobians; `sigma^2` the inliers' residual variance
//!   (at least [`MIN_RESIDUAL`] squared); times
//!   [`INFLATION`]: the filter applies these same sightings again, and the
//!   dead reckoning that carried them to the start frame drifts in ways
//!   the residuals only partly show.
//!
//! The window grows through [`WINDOWS`] until a fix has
//! [`MIN_INLIERS`] inliers on at least two landmarks.

use locus_core::nalgebra::{Matrix2x3, Matrix3, Vector2, Vector3};
use locus_core::wrap_angle;

use crate::dead_reckoning::DeadReckoning;

use crate::{Config, Log};

/// The windows tried, s after the first usable sighting: sightings up to
/// then are used.
pub const WINDOWS: [f64; 4] = [10.0, 20.0, 40.0, 80.0];
/// Fewest inliers a fix needs.
pub const MIN_INLIERS: usize = 4;
/// Smallest residual standard deviation the covariance assumes, m.
pub const MIN_RESIDUAL: f64 = 0.05;
/// Factor on the fit's covariance (see the module documentation).
pub const INFLATION: f64 = 4.0;
/// Most sightings one window uses (the first ones): the pairs tried grow
/// as its square.
pub const MAX_SIGHTINGS: usize = 120;

/// How far a sighting at `range` may place its landmark from the map's
/// position and still agree with a pose, m: dead reckoning's drift over
/// the window and a range error of a tenth.
#[must_use]
pub fn inlier_tolerance(range: f64) -> f64 {
    0.3 + 0.1 * range
}

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

/// An initial pose found from sightings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fix {
    /// The pose at the first odometry time: x, y (m), heading (rad).
    pub pose: Vector3<f64>,
    /// Its covariance (m^2, m^2 rad, rad^2).
    pub covariance: Matrix3<f64>,
    /// Sightings in the window.
    pub sightings: usize,
    /// Sightings that agree with the pose.
    pub inliers: usize,
    /// Different landmarks among them.
    pub landmarks: usize,
    /// From the first odometry time to the last sighting used, s.
    pub span: f64,
    /// Root mean square distance of the inliers' landmarks from the map's, m.
    pub rms: f64,
}

/// A sighting's landmark in the start frame, and the landmark in the map.
#[derive(Debug, Clone, Copy)]
struct Pair {
    seen: Vector2<f64>,
    map: Vector2<f64>,
    landmark: u32,
    tolerance: f64,
    time: f64,
}

/// The initial pose from the sightings of `log` (see the module
/// documentation), or `None` if no window gives a fix. Only sightings with
/// a bearing are used: range-only sightings are skipped, so a log of
/// range-only sightings alone gives `None`.
#[must_use]
pub fn from_sightings(log: &Log, cfg: &Config) -> Option<Fix> {
    let t0 = log.odometry.first()?.time;
    let pairs = pairs(log, cfg, t0, f64::INFINITY);
    let first = pairs.first()?.time;
    WINDOWS.iter().find_map(|w| {
        let n = pairs
            .iter()
            .take(MAX_SIGHTINGS)
            .take_while(|p| p.time <= first + w)
            .count();
        fit(&pairs[..n], t0)
    })
}

/// The pose at time `from` (s) that the sightings taken from `from` to
/// `to` fix, as [`from_sightings`] finds the initial pose (at most
/// [`MAX_SIGHTINGS`] of them), or `None`.
#[must_use]
pub fn fix_between(log: &Log, cfg: &Config, from: f64, to: f64) -> Option<Fix> {
    let pairs = pairs(log, cfg, from, to);
    fit(&pairs[..pairs.len().min(MAX_SIGHTINGS)], from)
}

/// The usable sightings (landmark in the map, finite, in range, with a
/// bearing: a range-only sighting cannot place its landmark in the robot's
/// frame and is skipped; from the first odometry time on) in time order, with their landmarks carried to
/// the start frame by dead reckoning on the logged odometry (its delay and
/// initial calibration as `cfg` sets them).
fn pairs(log: &Log, cfg: &Config, t0: f64, to: f64) -> Vec<Pair> {
    let mut sightings: Vec<_> = log
        .sightings
        .iter()
        .filter(|s| {
            s.time >= t0
                && s.time <= to
                && s.range.is_finite()
                && s.bearing.is_some_and(f64::is_finite)
                && s.range <= cfg.max_range
                && log.landmark(s.landmark).is_some()
        })
        .collect();
    sightings.sort_by(|a, b| a.time.total_cmp(&b.time));
    let b_bearing = cfg.calibration.initial[3];
    let mut dead = DeadReckoning::new(log, cfg, Vector3::zeros(), t0);
    let mount = log.sensor;
    let mut out = Vec::with_capacity(sightings.len());
    for s in sightings {
        let pose = dead.advance(s.time);
        let Some(l) = log.landmark(s.landmark) else {
            continue;
        };
        let Some(bearing) = s.bearing else {
            continue;
        };
        let a = mount.yaw + bearing - b_bearing;
        let in_robot = Vector2::new(mount.x + s.range * a.cos(), mount.y + s.range * a.sin());
        out.push(Pair {
            seen: Vector2::new(pose[0], pose[1]) + rotate(pose[2], in_robot),
            map: Vector2::new(l.x, l.y),
            landmark: s.landmark,
            tolerance: inlier_tolerance(s.range),
            time: s.time,
        });
    }
    out
}

fn rotate(theta: f64, p: Vector2<f64>) -> Vector2<f64> {
    let (s, c) = theta.sin_cos();
    Vector2::new(c * p.x - s * p.y, s * p.x + c * p.y)
}

/// Where `pose` (the start frame's pose in the map) puts `p`'s landmark,
/// minus the map's position.
fn residual(pose: &Vector3<f64>, p: &Pair) -> Vector2<f64> {
    Vector2::new(pose[0], pose[1]) + rotate(pose[2], p.seen) - p.map
}

/// The pairs that agree with `pose`, and the sum of their squared residuals.
fn inliers<'a>(pose: &Vector3<f64>, pairs: &'a [Pair]) -> (Vec<&'a Pair>, f64) {
    let mut cost = 0.0;
    let agree = pairs
        .iter()
        .filter(|p| {
            let r = residual(pose, p).norm();
            let inside = r <= p.tolerance;
            if inside {
                cost += r * r;
            }
            inside
        })
        .collect();
    (agree, cost)
}

/// The rigid transform carrying the `seen` points onto the `map` points in
/// least squares (closed form), as a pose `[x, y, theta]`.
fn least_squares(pairs: &[&Pair]) -> Vector3<f64> {
    #[allow(clippy::cast_precision_loss)]
    let n = pairs.len() as f64;
    let seen = pairs.iter().map(|p| p.seen).sum::<Vector2<f64>>() / n;
    let map = pairs.iter().map(|p| p.map).sum::<Vector2<f64>>() / n;
    let (mut cross, mut dot) = (0.0, 0.0);
    for p in pairs {
        let (a, b) = (p.seen - seen, p.map - map);
        cross += a.x * b.y - a.y * b.x;
        dot += a.dot(&b);
    }
    let theta = cross.atan2(dot);
    let t = map - rotate(theta, seen);
    Vector3::new(t.x, t.y, theta)
}

fn distinct_landmarks(pairs: &[&Pair]) -> usize {
    let mut ids: Vec<u32> = pairs.iter().map(|p| p.landmark).collect();
    ids.sort_unstable();
    ids.dedup();
    ids.len()
}

/// The best pose for `pairs` (see the module documentation), or `None`.
fn fit(pairs: &[Pair], t0: f64) -> Option<Fix> {
    let mut best: Option<(usize, f64, Vector3<f64>)> = None;
    for (i, a) in pairs.iter().enumerate() {
        for b in &pairs[i + 1..] {
            let (seen, map) = (b.seen - a.seen, b.map - a.map);
            if a.landmark == b.landmark
                || (seen.norm() - map.norm()).abs() > a.tolerance + b.tolerance
            {
                continue;
            }
            let theta = map.y.atan2(map.x) - seen.y.atan2(seen.x);
            let t = a.map - rotate(theta, a.seen);
            let pose = Vector3::new(t.x, t.y, theta);
            let (agree, cost) = inliers(&pose, pairs);
            let better =
                best.is_none_or(|(n, c, _)| agree.len() > n || (agree.len() == n && cost < c));
            if better {
                best = Some((agree.len(), cost, pose));
            }
        }
    }
    let (_, _, mut pose) = best?;
    for _ in 0..2 {
        let (agree, _) = inliers(&pose, pairs);
        if agree.len() < 2 {
            return None;
        }
        pose = least_squares(&agree);
    }
    let (agree, cost) = inliers(&pose, pairs);
    if agree.len() < MIN_INLIERS || distinct_landmarks(&agree) < 2 {
        return None;
    }
    // Information of the fit: residual r = t + R(theta) seen - map, so
    // dr/dt = I and dr/dtheta = R(theta) seen turned by +90 degrees.
    // The least-squares estimate's covariance when each landmark's
    // sightings share one error (the sandwich A^-1 B A^-1): residual
    // r = t + R(theta) seen - map, so dr/dt = I and dr/dtheta = R(theta)
    // seen turned by +90 degrees.
    let jacobian = |p: &Pair| {
        let q = rotate(pose[2], p.seen);
        Matrix2x3::new(1.0, 0.0, -q.y, 0.0, 1.0, q.x)
    };
    let a: Matrix3<f64> = agree
        .iter()
        .map(|p| jacobian(p).transpose() * jacobian(p))
        .sum();
    let mut ids: Vec<u32> = agree.iter().map(|p| p.landmark).collect();
    ids.sort_unstable();
    ids.dedup();
    let b: Matrix3<f64> = ids
        .iter()
        .map(|id| {
            let s: Matrix2x3<f64> = agree
                .iter()
                .filter(|p| p.landmark == *id)
                .map(|p| jacobian(p))
                .sum();
            s.transpose() * s
        })
        .sum();
    #[allow(clippy::cast_precision_loss)]
    let dof = (2 * agree.len() - 3) as f64;
    let sigma2 = (cost / dof).max(MIN_RESIDUAL * MIN_RESIDUAL);
    let a_inv = a.try_inverse()?;
    let covariance = a_inv * b * a_inv * (sigma2 * INFLATION);
    #[allow(clippy::cast_precision_loss)]
    let rms = (cost / agree.len() as f64).sqrt();
    Some(Fix {
        pose: Vector3::new(pose[0], pose[1], wrap_angle(pose[2])),
        covariance,
        sightings: pairs.len(),
        inliers: agree.len(),
        landmarks: ids.len(),
        span: pairs.last().map_or(0.0, |p| p.time - t0),
        rms,
    })
}

impl Fix {
    /// How far `pose` (x, y in m, heading in rad; with standard deviations
    /// `std`) lies from this fix: the squared Mahalanobis distance under
    /// both covariances, the heading difference wrapped. Above the
    /// chi-square(3) quantile [`DISAGREE`], a start pose given with the log
    /// contradicts its own first sightings.
    #[must_use]
    pub fn distance2(&self, pose: &Vector3<f64>, std: [f64; 3]) -> f64 {
        let d = Vector3::new(
            pose[0] - self.pose[0],
            pose[1] - self.pose[1],
            wrap_angle(pose[2] - self.pose[2]),
        );
        let c = self.covariance
            + Matrix3::from_diagonal(&Vector3::new(
                std[0] * std[0],
                std[1] * std[1],
                std[2] * std[2],
            ));
        c.try_inverse()
            .map_or(f64::INFINITY, |inv| (d.transpose() * inv * d)[0])
    }
}

/// The 99.9 % quantile of chi-square with 3 degrees of freedom: a
/// [`Fix::distance2`] above it is a disagreement.
pub const DISAGREE: f64 = 16.266_236_196_238_134;
