//! One window's fit: its sightings' landmarks carried into the start
//! frame by dead reckoning ([`Pair`]), the hypotheses from pairs of
//! sightings of two landmarks scored by their inliers, the least-squares
//! pose over the best one's inliers, and its covariance (see the module
//! documentation of [`super`] for the method and its references). Poses
//! are x, y (m) and heading (rad) of the start frame in the map.

use locus_core::nalgebra::{Matrix2x3, Matrix3, Vector2, Vector3};
use locus_core::wrap_angle;

use super::{
    Fix, INFLATION, MAX_HEADING_STD, MAX_SIGHTINGS, MIN_INLIERS, MIN_RESIDUAL, MIN_SHARE, Weak,
    inlier_tolerance, share,
};
use crate::dead_reckoning::DeadReckoning;
use crate::{Config, Log, Sighting};

/// A sighting's landmark in the start frame, and the landmark in the map.
#[derive(Debug, Clone, Copy)]
pub(super) struct Pair {
    seen: Vector2<f64>,
    map: Vector2<f64>,
    landmark: u32,
    tolerance: f64,
    pub(super) time: f64,
}

/// The landmarks of `sightings` (in time order, none before `dead`'s time)
/// carried to the frame `dead` started in by dead reckoning on the logged
/// odometry (its delay and initial calibration as `cfg` sets them).
pub(super) fn carry(
    log: &Log,
    cfg: &Config,
    mut dead: DeadReckoning<'_>,
    sightings: &[&Sighting],
) -> Vec<Pair> {
    let b_bearing = cfg.calibration.initial[3];
    let mount = log.sensor;
    let mut out = Vec::with_capacity(sightings.len());
    for s in sightings {
        let pose = dead.advance(s.time);
        let (Some(l), Some(bearing)) = (log.landmark(s.landmark), s.bearing) else {
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

/// At most [`MAX_SIGHTINGS`] of `pairs` (in time order): all if no more,
/// else an equal share for each landmark (a landmark with fewer gives its
/// rest to the others), each landmark's earliest.
pub(super) fn balanced(pairs: &[Pair]) -> Vec<Pair> {
    if pairs.len() <= MAX_SIGHTINGS {
        return pairs.to_vec();
    }
    let mut ids: Vec<u32> = pairs.iter().map(|p| p.landmark).collect();
    ids.sort_unstable();
    let mut counts: Vec<(u32, usize)> = Vec::new();
    for id in ids {
        match counts.last_mut() {
            Some((last, n)) if *last == id => *n += 1,
            _ => counts.push((id, 1)),
        }
    }
    // Equal shares, smallest landmarks first so what they leave goes on.
    counts.sort_by_key(|&(_, n)| n);
    let mut quota = Vec::with_capacity(counts.len());
    let mut left = MAX_SIGHTINGS;
    for (k, &(id, n)) in counts.iter().enumerate() {
        let q = n.min(left / (counts.len() - k));
        quota.push((id, q));
        left -= q;
    }
    quota.sort_unstable_by_key(|&(id, _)| id);
    let mut seen = vec![0_usize; quota.len()];
    let mut out = Vec::with_capacity(MAX_SIGHTINGS);
    for p in pairs {
        let k = quota
            .binary_search_by_key(&p.landmark, |&(id, _)| id)
            .unwrap_or_default();
        let q = quota[k].1;
        // A landmark's first q sightings: dead reckoning has drifted least.
        if seen[k] < q {
            out.push(*p);
        }
        seen[k] += 1;
    }
    out
}

/// The hypotheses [`fit`] tries for `pairs` at most: the pairs of
/// sightings of two different landmarks.
pub(super) fn hypotheses(pairs: &[Pair]) -> u64 {
    let mut ids: Vec<u32> = pairs.iter().map(|p| p.landmark).collect();
    ids.sort_unstable();
    let n = ids.len() as u64;
    let same: u64 = ids
        .chunk_by(|a, b| a == b)
        .map(|c| (c.len() as u64) * (c.len() as u64))
        .sum();
    (n * n - same) / 2
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

/// The best pose for `pairs` (see the module documentation), or why
/// there is none; with `strict`, judged by [`MIN_SHARE`] and its geometry
/// too.
pub(super) fn fit(pairs: &[Pair], t0: f64, strict: bool) -> Result<Fix, Weak> {
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
    let weak = |agree: usize| Weak::Consensus {
        inliers: agree,
        sightings: pairs.len(),
    };
    let Some((_, _, mut pose)) = best else {
        return Err(Weak::OneLandmark);
    };
    for _ in 0..2 {
        let (agree, _) = inliers(&pose, pairs);
        if agree.len() < 2 {
            return Err(weak(agree.len()));
        }
        pose = least_squares(&agree);
    }
    let (agree, cost) = inliers(&pose, pairs);
    if distinct_landmarks(&agree) < 2 {
        return Err(Weak::OneLandmark);
    }
    if agree.len() < MIN_INLIERS || (strict && share(agree.len(), pairs.len()) < MIN_SHARE) {
        return Err(weak(agree.len()));
    }
    let mut ids: Vec<u32> = agree.iter().map(|p| p.landmark).collect();
    ids.sort_unstable();
    ids.dedup();
    let positions: Vec<Vector2<f64>> = ids
        .iter()
        .filter_map(|id| agree.iter().find(|p| p.landmark == *id).map(|p| p.map))
        .collect();
    let baseline = positions
        .iter()
        .enumerate()
        .flat_map(|(i, a)| positions[i + 1..].iter().map(move |b| (a - b).norm()))
        .fold(0.0, f64::max);
    let degenerate = |heading_std| Weak::Degenerate {
        inliers: agree.len(),
        landmarks: ids.len(),
        baseline,
        heading_std,
    };
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
    let a_inv = a.try_inverse().ok_or(degenerate(f64::INFINITY))?;
    let covariance = a_inv * b * a_inv * (sigma2 * INFLATION);
    let heading_std = covariance[(2, 2)].sqrt();
    if strict && (heading_std.is_nan() || heading_std > MAX_HEADING_STD) {
        return Err(degenerate(heading_std));
    }
    #[allow(clippy::cast_precision_loss)]
    let rms = (cost / agree.len() as f64).sqrt();
    Ok(Fix {
        pose: Vector3::new(pose[0], pose[1], wrap_angle(pose[2])),
        covariance,
        sightings: pairs.len(),
        inliers: agree.len(),
        landmarks: ids.len(),
        baseline,
        from: pairs.first().map_or(0.0, |p| p.time - t0),
        span: pairs.last().map_or(0.0, |p| p.time - t0),
        rms,
        later: false,
    })
}
