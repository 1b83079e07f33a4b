//! Process noise from how fast dead reckoning drifts between pose fixes of
//! the sightings alone (no ground truth, no filter in the loop).
//!
//! Every [`STEP`] seconds, the sightings of the next [`FIX_WINDOW`] seconds
//! fix a pose ([`crate::initial::fix_between`]); fixes whose standard
//! deviations exceed [`MAX_FIX_STD`] are left out. From each fix, dead
//! reckoning on the logged odometry (the log's delay, the calibration a
//! filter replay ends with) runs to the fix [`INTERVALS`] later. Two
//! errors are taken: the distance travelled (the chord from the first fix,
//! fix against dead reckoning: a heading error at the first fix rotates the
//! dead-reckoned path but does not lengthen it) and the heading. A white
//! velocity noise of power spectral density `q` makes such an error's
//! variance grow as `q T` over an interval `T`, plus the two fixes' own
//! errors, which do not grow with `T`, plus what a calibration error left
//! in the dead reckoning adds, which grows as `T^2`. So the variance
//! (taken robustly, 1.4826 times the median absolute deviation, squared)
//! is fitted as `a + q T + c T^2` over the intervals, by weighted least
//! squares with each interval's own sampling variance, and `q` with its
//! standard error is `q_v` (distance) or `q_omega` (heading). This is the
//! idea of the Allan-variance identification of inertial sensor noise
//! (IEEE Std 952-1997, annex C; El-Sheimy, Hou and Niu, "Analysis and
//! modeling of inertial sensors using Allan variance", IEEE Trans.
//! Instrumentation and Measurement 57(1), 2008), applied to odometry
//! between absolute fixes.
//!
//! Unlike the innovation likelihood ([`crate::noise`]), it looks at the
//! errors over the seconds-long gaps between sightings, which is where a
//! filter's covariance must grow as fast as its errors; unlike
//! expectation-maximisation over a smoother, it does not see the
//! trajectory through the filter's own process noise. Per log it is noisy
//! (a few hundred fixes, the fixes' own errors often larger than the drift
//! over a few seconds): its standard error says how much, and
//! [`crate::noise::estimate`] takes its value only where the log tells it.

use locus_core::nalgebra::Vector3;
use locus_core::wrap_angle;

use crate::dead_reckoning::DeadReckoning;
use crate::initial::{Fix, fix_between};
use crate::noise::robust_spread;
use crate::{Config, Error, Log, replay};

/// Seconds between the starts of two fixes.
pub const STEP: f64 = 1.0;
/// Seconds of sightings one fix uses.
pub const FIX_WINDOW: f64 = 2.0;
/// Largest standard deviation of a fix kept: x and y (m), heading (rad).
pub const MAX_FIX_STD: [f64; 3] = [0.5, 0.5, 0.1];
/// The intervals between fixes, s.
pub const INTERVALS: [f64; 5] = [2.0, 4.0, 8.0, 16.0, 32.0];
/// Fewest fix pairs an interval needs to count.
pub const MIN_PAIRS: usize = 10;

/// One interval's figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// The interval, s.
    pub seconds: f64,
    /// Robust variance of the error in distance travelled, m^2.
    pub along: f64,
    /// Robust variance of the heading error, rad^2.
    pub heading: f64,
    /// Fix pairs that far apart.
    pub pairs: usize,
}

/// The estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct Drift {
    /// Power spectral density of the forward-speed noise, m^2/s (the
    /// linear growth of the distance error's variance; may be negative
    /// where the log cannot tell it).
    pub q_v: f64,
    /// Power spectral density of the turn-rate noise, rad^2/s.
    pub q_omega: f64,
    /// Standard error of `q_v`, m^2/s (from the fit's weighted residual
    /// model: the module documentation).
    pub q_v_se: f64,
    /// Standard error of `q_omega`, rad^2/s.
    pub q_omega_se: f64,
    /// Fixes kept.
    pub fixes: usize,
    /// The intervals with enough pairs.
    pub intervals: Vec<Interval>,
}

/// Estimates the process noise of `log` (see the module documentation),
/// with `cfg`'s odometry delay; `q_v` and `q_omega` are NaN if fewer than
/// two intervals have [`MIN_PAIRS`] pairs.
///
/// # Errors
/// The filter replay's errors.
pub fn process_noise(log: &Log, cfg: &Config) -> Result<Drift, Error> {
    let plain = Config {
        smooth: false,
        evaluate: false,
        ..*cfg
    };
    let calibration = replay(log, &plain, |_| {})?.calibration;
    // The fixes and dead reckoning use the calibration the filter ends
    // with (scale factors and biases).
    let mut fixing = plain;
    for (k, c) in calibration.iter().enumerate() {
        fixing.calibration.initial[k] = c.0;
    }
    let (Some(first), Some(last)) = (log.odometry.first(), log.odometry.last()) else {
        return Err(Error::NoOdometry);
    };
    let mut fixes: Vec<(f64, Fix)> = Vec::new();
    let mut t = first.time;
    while t + FIX_WINDOW < last.time {
        if let Some(f) = fix_between(log, &fixing, t, t + FIX_WINDOW) {
            let ok = (0..3).all(|k| f.covariance[(k, k)].sqrt() < MAX_FIX_STD[k]);
            if ok {
                fixes.push((t, f));
            }
        }
        t += STEP;
    }
    let mut intervals = Vec::new();
    for seconds in INTERVALS {
        let (mut along, mut heading) = (Vec::new(), Vec::new());
        for (ta, a) in &fixes {
            let target = ta + seconds;
            let Some((_, b)) = fixes
                .iter()
                .find(|(tb, _)| (tb - target).abs() < 0.5 * STEP)
            else {
                continue;
            };
            let end = DeadReckoning::new(log, &fixing, a.pose, *ta).advance(target);
            // Distance travelled as the chord between the two poses: a
            // heading error at the first fix rotates the dead-reckoned
            // path but does not lengthen it.
            let chord = |p: &Vector3<f64>| (p[0] - a.pose[0]).hypot(p[1] - a.pose[1]);
            along.push(chord(&b.pose) - chord(&end));
            heading.push(wrap_angle(b.pose[2] - end[2]));
        }
        if along.len() >= MIN_PAIRS {
            intervals.push(Interval {
                seconds,
                pairs: along.len(),
                along: robust_spread(along).powi(2),
                heading: robust_spread(heading).powi(2),
            });
        }
    }
    let (q_v, q_v_se) = slope(&intervals, |i| i.along);
    let (q_omega, q_omega_se) = slope(&intervals, |i| i.heading);
    Ok(Drift {
        q_v,
        q_omega,
        q_v_se,
        q_omega_se,
        fixes: fixes.len(),
        intervals,
    })
}

/// The rate of growth of `value` with the interval, and its standard
/// error, by weighted least squares (NaN with fewer than three
/// intervals).
///
/// The variance of a drift over `T` seconds is `a + q T + c T^2`: the two
/// fixes' errors (`a`), white velocity noise (`q`), and a calibration error
/// left in the dead reckoning (a scale factor or bias a few per cent off
/// moves it by an amount proportional to `T`, so its variance grows as
/// `T^2`). `q` is the linear coefficient.
///
/// An interval's robust variance `v` has a variance of about `2 v^2 /
/// (0.37 n)`: 1.4826 MAD has 37 % of the efficiency of the standard
/// deviation, and pairs of an interval of `T` seconds overlap, so it counts
/// `n = pairs * STEP / T` independent pairs. Each interval is weighted by
/// the inverse of that variance (with `v` from the fitted curve, iterated
/// from an unweighted fit, so a small sample variance does not weigh
/// itself up).
#[allow(clippy::cast_precision_loss)]
fn slope(intervals: &[Interval], value: impl Fn(&Interval) -> f64) -> (f64, f64) {
    use locus_core::nalgebra::{Matrix3, Vector3 as V3};
    if intervals.len() < 3 {
        return (f64::NAN, f64::NAN);
    }
    let independent = |i: &Interval| (i.pairs as f64 * STEP / i.seconds).max(1.0);
    let mut weights: Vec<f64> = intervals.iter().map(|_| 1.0).collect();
    let mut fit = (f64::NAN, f64::NAN);
    let largest = intervals.iter().map(&value).fold(0.0, f64::max);
    for _ in 0..3 {
        let (mut m, mut r) = (Matrix3::<f64>::zeros(), V3::<f64>::zeros());
        for (i, w) in intervals.iter().zip(&weights) {
            let x = V3::new(1.0, i.seconds, i.seconds * i.seconds);
            m += *w * x * x.transpose();
            r += *w * value(i) * x;
        }
        let Some(inverse) = m.try_inverse() else {
            return (f64::NAN, f64::NAN);
        };
        let c = inverse * r;
        let curve = |t: f64| (c[0] + c[1] * t + c[2] * t * t).max(largest * 0.01);
        // The coefficients' covariance, each interval's variance from the
        // curve: (X^T W X)^-1 X^T W Var W X (X^T W X)^-1.
        let mut middle = Matrix3::<f64>::zeros();
        for (i, w) in intervals.iter().zip(&weights) {
            let x = V3::new(1.0, i.seconds, i.seconds * i.seconds);
            let v = curve(i.seconds);
            middle += w * w * 2.0 * v * v / (0.37 * independent(i)) * x * x.transpose();
        }
        let covariance = inverse * middle * inverse;
        fit = (c[1], covariance[(1, 1)].max(0.0).sqrt());
        for (w, i) in weights.iter_mut().zip(intervals) {
            let v = curve(i.seconds).max(f64::MIN_POSITIVE);
            *w = independent(i) / (v * v);
        }
    }
    fit
}
