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
//!
//! Here: the search's bounds, the [`Fix`] and why a search finds none
//! ([`Weak`], [`NoFix`]); the window search in `search.rs`
//! ([`from_sightings`], [`fix_between`]), one window's fit in `fit.rs`,
//! and the heading of a ground truth of positions only in `truth.rs`
//! ([`heading_from_truth`]).

mod fit;
mod search;
mod truth;

use locus_core::nalgebra::{Matrix3, Vector3};
use locus_core::wrap_angle;

pub use search::{fix_between, from_sightings};
pub use truth::{HEADING_BASELINE, HEADING_STD, HEADING_WINDOW, TruthHeading, heading_from_truth};

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
