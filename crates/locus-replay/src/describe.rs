//! Plain-English descriptions of what a replay did, as every front end
//! prints them (the command line, the Python package): where the initial
//! pose came from, a start pose its sightings contradict, and the records
//! refused with their place in the log. Figures in SI units with the unit
//! named; standard deviations are 1 sigma.

use core::fmt;

use crate::refusals::Refusals;
use crate::report::{StartDisagreement, StartedFrom};

/// One line: where the initial pose came from, with the fix's figures when
/// the sightings gave it.
impl fmt::Display for StartedFrom {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Log => write!(f, "initial pose: the log's start record"),
            Self::Truth => write!(
                f,
                "initial pose: the ground truth at the first odometry time"
            ),
            Self::TruthPosition(h) => write!(
                f,
                "initial pose: the ground truth's position at the first odometry time (it has no \
                 heading); heading {:.3} +- {:.3} rad (1 sigma, assumed) from its direction of \
                 motion over its first {:.2} m ({:.1} s) against the odometry's",
                h.heading, h.std, h.travelled, h.span
            ),
            Self::Sightings(fix) => {
                let sd = |k: usize| fix.covariance[(k, k)].sqrt();
                if fix.later {
                    write!(
                        f,
                        "initial pose from {} sightings of {:.1}-{:.1} s (the earlier ones fix \
                         none; carried back by dead reckoning, its drift added)",
                        fix.sightings, fix.from, fix.span
                    )?;
                } else {
                    write!(
                        f,
                        "initial pose from the first {} sightings ({:.1} s)",
                        fix.sightings, fix.span
                    )?;
                }
                write!(
                    f,
                    "; {} of them agree ({:.0} %), on {} landmarks up to {:.2} m apart, rms \
                     {:.3} m: x {:.3} +- {:.3} m, y {:.3} +- {:.3} m, heading {:.3} +- {:.3} rad \
                     (1 sigma)",
                    fix.inliers,
                    100.0 * fix.share(),
                    fix.landmarks,
                    fix.baseline,
                    fix.rms,
                    fix.pose[0],
                    sd(0),
                    fix.pose[1],
                    sd(1),
                    fix.pose[2],
                    sd(2)
                )
            }
        }
    }
}

/// A warning: the log's start pose against where its first sightings put
/// the robot, and what to do if the start record is wrong.
impl fmt::Display for StartDisagreement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (l, s) = (self.log, self.sightings);
        write!(
            f,
            "warning: the log's start pose ({:.3} m, {:.3} m, {:.3} rad) is {:.1} sigma from \
             where its first sightings put the robot ({:.3} m, {:.3} m, {:.3} rad); if the start \
             record is wrong, replay with --start-from-sightings",
            l[0], l[1], l[2], self.sigma, s[0], s[1], s[2]
        )
    }
}

impl Refusals {
    /// The refused records of the log `name`, one line each (`name:line:
    /// what`, `name: what` where the line is not known), the first
    /// [`KEPT`](crate::refusals::KEPT) and then how many more; empty when
    /// none was refused.
    #[must_use]
    pub fn listing(&self, name: &str) -> String {
        use fmt::Write as _;
        if self.total() == 0 {
            return String::new();
        }
        let mut text = format!("refused records ({}):\n", self.total());
        for r in self.first() {
            let _ = match r.line() {
                Some(line) => writeln!(text, "  {name}:{line}: {r}"),
                None => writeln!(text, "  {name}: {r}"),
            };
        }
        let more = self.total() - self.first().len();
        if more > 0 {
            let _ = writeln!(text, "  ... and {more} more");
        }
        text
    }
}
