//! The search for the initial pose through windows of the log's
//! sightings: from the first usable sighting the windows grow through
//! [`WINDOWS`]; if none gives a fix, they start again [`SLIDE`] s later,
//! until a window's fix is accepted, the sightings end, or the search has
//! spent [`MAX_WORK`] (see the module documentation of [`super`]). Each
//! window is fitted by [`fit`](super::fit); a fix from a later window is
//! widened by the drift dead reckoning may have gathered before it.
//! Times in s after the first odometry time unless said otherwise.

use locus_core::nalgebra::{Matrix3, Vector3};

use super::fit::{balanced, carry, fit, hypotheses};
use super::{Fix, MAX_WORK, NoFix, SLIDE, WINDOWS};
use crate::dead_reckoning::DeadReckoning;
use crate::{Config, Log, Sighting};

/// The initial pose from the sightings of `log` (see the module
/// documentation). Only sightings with a bearing are used: range-only
/// sightings are skipped, so a log of range-only sightings alone gives no
/// fix.
///
/// # Errors
/// No window gives a fix that [`MIN_INLIERS`](super::MIN_INLIERS),
/// [`MIN_SHARE`](super::MIN_SHARE) and the geometry accept: why, for the
/// best window, and how far the search went.
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
/// [`MAX_SIGHTINGS`](super::MAX_SIGHTINGS) of them, shared among the
/// landmarks), or `None`. The fix is not judged by
/// [`MIN_SHARE`](super::MIN_SHARE) or its geometry: the caller judges it by
/// its covariance and [`Fix::share`].
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
