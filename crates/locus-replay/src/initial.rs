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
//! A fix is accepted only when its consensus is strong and its geometry
//! fixes a heading: at least [`MIN_INLIERS`] sightings and [`MIN_SHARE`]
//! of the window's agree, on two landmarks or more far enough apart to
//! fix the heading to [`MAX_HEADING_STD`] (see [`Weak`]). Only sightings with a bearing are used; each places its landmark
//! in the start frame, so two landmarks at distinct positions fix the
//! pose, and landmarks on one line do too (the mirror image across the
//! line that range-only sightings would leave open puts the landmarks in
//! the wrong order along the bearings).
//!
//! **Search.** From the first usable sighting, the window grows through
//! [`WINDOWS`]; if none gives a fix, the windows start again at the first
//! sighting [`SLIDE`] s later, and so on to the end of the log or until the
//! search has spent [`MAX_WORK`]. A window with more than
//! [`MAX_SIGHTINGS`] sightings uses that many, shared evenly among its
//! landmarks and spread evenly in time, so a landmark seen often cannot
//! crowd the others out. A fix from a later window is of the pose at the
//! first odometry time all the same (its sightings carried there by dead
//! reckoning); its covariance adds the drift that dead reckoning may have
//! gathered before the window ([`Fix::later`]).

use locus_core::nalgebra::{Matrix2x3, Matrix3, Vector2, Vector3};
use locus_core::wrap_angle;

use crate::dead_reckoning::DeadReckoning;

use crate::{Config, Log, Sighting};

/// The windows tried from each start, s after its first sighting: the
/// sightings up to then are used.
pub const WINDOWS: [f64; 4] = [10.0, 20.0, 40.0, 80.0];
/// Fewest inliers a fix needs: the two sightings that propose a pose agree
/// with it by construction, so at least two others must confirm it.
pub const MIN_INLIERS: usize = 4;
/// Smallest share of a window's sightings that must agree with its fix.
/// A pose that fewer than half support is contradicted by more sightings
/// than confirm it, and a chance alignment of a few gross sightings can
/// always be found among the window's pairs (random sightings: 5 of 51);
/// on MRCLAM dataset 6 all of the first sightings agree, and with 5 % of
/// them corrupted all but the corrupted ones (docs/replay.md), so the
/// bound refuses no real start while a pose supported by a minority is
/// never taken.
pub const MIN_SHARE: f64 = 0.5;
/// Largest standard deviation of the heading a fix may have, rad. Over
/// landmarks `d` apart, sightings that place them within `e` of the map
/// fix the heading to about `e / d`: landmarks close together (or all at
/// one point, where the heading is free) fix none worth the name. At 0.5
/// rad, 3 sigma is still short of a half turn's half (1.5 rad), so the fix
/// says which way the robot faces; the real starts of MRCLAM dataset 6
/// have 0.10-0.46 rad (robot 4's two landmarks 0.18 m apart the most).
pub const MAX_HEADING_STD: f64 = 0.5;
/// Smallest residual standard deviation the covariance assumes, m.
pub const MIN_RESIDUAL: f64 = 0.05;
/// Factor on the fit's covariance (see the module documentation).
pub const INFLATION: f64 = 4.0;
/// Most sightings one window uses: the hypotheses tried grow as the square
/// of their number, each checked against all of them.
pub const MAX_SIGHTINGS: usize = 120;
/// Seconds from one window start to the next: half the longest window, so
/// any stretch of sightings that long lies wholly inside one window.
pub const SLIDE: f64 = 40.0;
/// Most checks of a sighting against a proposed pose one search makes (a
/// window of [`MAX_SIGHTINGS`] sightings of two landmarks costs about
/// 4.3e5): it bounds the fits' time (about 0.6 s on one core, optimised
/// build) however long the log. Windows whose sightings see one landmark
/// cost nothing here, so such stretches never stop the search.
pub const MAX_WORK: u64 = 100_000_000;

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
    /// Sightings in the window (at most [`MAX_SIGHTINGS`]).
    pub sightings: usize,
    /// Sightings that agree with the pose.
    pub inliers: usize,
    /// Different landmarks among them.
    pub landmarks: usize,
    /// Largest distance between the map positions of two landmarks among
    /// the inliers, m: the lever that fixes the heading.
    pub baseline: f64,
    /// From the first odometry time to the first sighting used, s.
    pub from: f64,
    /// From the first odometry time to the last sighting used, s.
    pub span: f64,
    /// Root mean square distance of the inliers' landmarks from the map's, m.
    pub rms: f64,
    /// Whether the windows from earlier starts fixed none: the pose is
    /// then carried back over the dead reckoning before the window, and
    /// the covariance includes its possible drift (the filter's own prior
    /// calibration standard deviations: speed scale times the distance
    /// travelled, turn-rate scale times the angle turned plus turn-rate
    /// bias times the time, and that heading error times the distance).
    pub later: bool,
}

impl Fix {
    /// Share of the window's sightings that agree with the pose, 0 to 1.
    #[must_use]
    pub fn share(&self) -> f64 {
        share(self.inliers, self.sightings)
    }
}

/// Why one window's sightings fix no pose.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Weak {
    /// The window's sightings, or those that agree with its best pose,
    /// see one landmark only: nothing fixes the heading.
    #[error("its sightings see one landmark only")]
    OneLandmark,
    /// Fewer than [`MIN_INLIERS`] or [`MIN_SHARE`] of the sightings agree
    /// with the best pose.
    #[error(
        "only {inliers} of {sightings} sightings agree with its best pose ({share:.0} %; a fix \
         needs at least {min} and {half:.0} %)",
        share = 100.0 * share(*inliers, *sightings),
        min = MIN_INLIERS,
        half = 100.0 * MIN_SHARE
    )]
    Consensus {
        /// Sightings that agree with the best pose.
        inliers: usize,
        /// Sightings in the window.
        sightings: usize,
    },
    /// The landmarks that agree lie too close together to fix a heading:
    /// its standard deviation in the fit's covariance exceeds
    /// [`MAX_HEADING_STD`] (infinite for landmarks all at one point, which
    /// leave the heading free).
    #[error(
        "its {inliers} agreeing sightings see {landmarks} landmarks at most {baseline:.2} m \
         apart, too close to fix a heading (standard deviation {heading_std:.2} rad, at most \
         {max} rad accepted)",
        max = MAX_HEADING_STD
    )]
    Degenerate {
        /// Sightings that agree with the best pose.
        inliers: usize,
        /// Different landmarks among them.
        landmarks: usize,
        /// Largest distance between two of them, m.
        baseline: f64,
        /// The heading's standard deviation in the fit, rad.
        heading_std: f64,
    },
}

impl Weak {
    /// The sightings that agreed with the window's best pose.
    fn support(&self) -> usize {
        match self {
            Self::OneLandmark => 0,
            Self::Consensus { inliers, .. } | Self::Degenerate { inliers, .. } => *inliers,
        }
    }
}

#[allow(clippy::cast_precision_loss)]
fn share(inliers: usize, sightings: usize) -> f64 {
    inliers as f64 / sightings.max(1) as f64
}

/// Why the sightings of a log fix no initial pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoFix {
    /// The refusal of the window whose best pose most sightings agreed with and its window's first sighting, s after
    /// the first odometry time; `None` if the log has no usable sighting
    /// (with a bearing, of a landmark in the map, within range, from the
    /// first odometry time on).
    pub best: Option<(Weak, f64)>,
    /// Windows tried.
    pub windows: usize,
    /// From the first odometry time to the last sighting searched, s.
    pub searched: f64,
    /// Whether the search stopped at [`MAX_WORK`] before the log's end.
    pub capped: bool,
}

impl core::fmt::Display for NoFix {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let Some((why, from)) = self.best else {
            return write!(
                f,
                "the log has no sighting with a bearing of a landmark in the map from the first \
                 odometry time on"
            );
        };
        write!(
            f,
            "{} window{} of sightings searched, up to {:.1} s after the first odometry time ({}); \
             in the best, from {from:.1} s, {why}",
            self.windows,
            if self.windows == 1 { "" } else { "s" },
            self.searched,
            if self.capped {
                "where the search reached its work cap"
            } else {
                "the end of the sightings"
            }
        )
    }
}

impl core::error::Error for NoFix {}

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
/// documentation). Only sightings with a bearing are used: range-only
/// sightings are skipped, so a log of range-only sightings alone gives no
/// fix.
///
/// # Errors
/// No window gives a fix that [`MIN_INLIERS`], [`MIN_SHARE`] and the
/// geometry accept: why, for the best window, and how far the search went.
pub fn from_sightings(log: &Log, cfg: &Config) -> Result<Fix, NoFix> {
    let mut no = NoFix {
        best: None,
        windows: 0,
        searched: 0.0,
        capped: false,
    };
    let Some(t0) = log.odometry.first().map(|o| o.time) else {
        return Err(no);
    };
    let usable = usable(log, cfg, t0, f64::INFINITY);
    let longest = WINDOWS[WINDOWS.len() - 1];
    let mut dead = DeadReckoning::new(log, cfg, Vector3::zeros(), t0);
    let mut work = 0_u64;
    let mut first = 0;
    while let Some(start) = usable.get(first).map(|s| s.time) {
        dead.advance(start);
        let end = first + usable[first..].partition_point(|s| s.time <= start + longest);
        let pairs = carry(log, cfg, dead.clone(), &usable[first..end]);
        let mut tried = 0;
        for w in WINDOWS {
            let n = pairs.partition_point(|p| p.time <= start + w);
            if n == tried {
                continue;
            }
            tried = n;
            let chosen = balanced(&pairs[..n]);
            let cost = hypotheses(&chosen) * chosen.len() as u64;
            if work + cost > MAX_WORK {
                no.capped = true;
                return Err(no);
            }
            work += cost;
            no.windows += 1;
            no.searched = pairs[n - 1].time - t0;
            match fit(&chosen, t0, true) {
                Ok(fix) if first == 0 => return Ok(fix),
                Ok(fix) => return Ok(with_drift(fix, &dead, cfg, start - t0)),
                Err(why) => {
                    if no.best.is_none_or(|(b, _)| why.support() > b.support()) {
                        no.best = Some((why, start - t0));
                    }
                }
            }
        }
        let next = start + SLIDE;
        first = (first + 1).max(first + usable[first..].partition_point(|s| s.time < next));
    }
    Err(no)
}

/// `fix` found from a later window, its covariance widened by the drift
/// dead reckoning `dead` (at the window's first sighting, `elapsed` s after
/// the first odometry time) may have gathered on the way ([`Fix::later`]).
fn with_drift(fix: Fix, dead: &DeadReckoning<'_>, cfg: &Config, elapsed: f64) -> Fix {
    let [s_v, s_omega, b_omega, _] = cfg.calibration.std;
    let heading = s_omega * dead.turned + b_omega * elapsed;
    let position = (s_v + heading) * dead.travelled;
    let drift = Matrix3::from_diagonal(&Vector3::new(
        position * position,
        position * position,
        heading * heading,
    ));
    Fix {
        covariance: fix.covariance + drift,
        later: true,
        ..fix
    }
}

/// The pose at time `from` (s) that the sightings taken from `from` to
/// `to` fix, as [`from_sightings`] finds the initial pose (at most
/// [`MAX_SIGHTINGS`] of them, shared among the landmarks), or `None`. The
/// fix is not judged by [`MIN_SHARE`] or its geometry: the caller judges
/// it by its covariance and [`Fix::share`].
#[must_use]
pub fn fix_between(log: &Log, cfg: &Config, from: f64, to: f64) -> Option<Fix> {
    let usable = usable(log, cfg, from, to);
    let dead = DeadReckoning::new(log, cfg, Vector3::zeros(), from);
    let pairs = carry(log, cfg, dead, &usable);
    fit(&balanced(&pairs), from, false).ok()
}

/// The usable sightings (landmark in the map, finite, in range, with a
/// bearing: a range-only sighting cannot place its landmark in the robot's
/// frame and is skipped; taken from `t0` to `to`, s) in time order.
fn usable<'a>(log: &'a Log, cfg: &Config, t0: f64, to: f64) -> Vec<&'a Sighting> {
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
    if !sightings.is_sorted_by(|a, b| a.time <= b.time) {
        sightings.sort_by(|a, b| a.time.total_cmp(&b.time));
    }
    sightings
}

/// The landmarks of `sightings` (in time order, none before `dead`'s time)
/// carried to the frame `dead` started in by dead reckoning on the logged
/// odometry (its delay and initial calibration as `cfg` sets them).
fn carry(
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
fn balanced(pairs: &[Pair]) -> Vec<Pair> {
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
fn hypotheses(pairs: &[Pair]) -> u64 {
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
fn fit(pairs: &[Pair], t0: f64, strict: bool) -> Result<Fix, Weak> {
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
