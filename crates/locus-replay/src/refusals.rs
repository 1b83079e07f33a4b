//! The records a replay refused: every one counted, the first
//! [`KEPT`] kept with their line, so that a log of millions of refused
//! lines costs a bounded report (docs/log-format.md, "Every reading is
//! accounted for").

use core::fmt;

use crate::log::{RefusedRecord, RefusedTime};
use crate::step::Unusable;
use crate::{Config, Log, Sighting};

/// Refused records a [`Refusals`] keeps described.
pub const KEPT: usize = 20;

/// One record the replay refused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Refusal {
    /// A `noise` or odometry record with an implausible value: a noise
    /// level is left to the flags, the estimate or the default; an
    /// odometry record is not applied, the velocities before it held.
    Record(RefusedRecord),
    /// A sighting with an implausible time stamp, left out before the
    /// replay.
    Time(RefusedTime),
    /// A sighting the filter cannot use.
    Sighting {
        /// Its line in the file, if known.
        line: Option<usize>,
        /// The sighting as logged.
        sighting: Sighting,
        /// Why the filter cannot use it.
        why: Unusable,
    },
}

impl Refusal {
    /// The refused record's line in its file, if known (`None` for an
    /// MRCLAM log, which is read from several files).
    #[must_use]
    pub fn line(&self) -> Option<usize> {
        match self {
            Self::Record(r) => r.line,
            Self::Time(r) => r.line,
            Self::Sighting { line, .. } => *line,
        }
    }
}

/// A logged value for a message: as written if of ordinary size, else in
/// scientific notation (a range of 1e154 m is not spelt out in 155
/// digits).
struct Number(f64);

impl fmt::Display for Number {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let v = self.0;
        if v == 0.0 || (1e-4..1e12).contains(&v.abs()) {
            write!(f, "{v}")
        } else {
            write!(f, "{v:e}")
        }
    }
}

/// What was refused and why, without its place (the caller prefixes the
/// file and [`Refusal::line`]).
impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Record(r) if r.what == "odometry" => write!(
                f,
                "odometry record refused: implausible, {} (the velocities before it held)",
                r.why
            ),
            Self::Record(r) => write!(
                f,
                "{} refused: implausible, {} (the level left to the flags, the estimate or the \
                 default)",
                r.what, r.why
            ),
            Self::Time(r) => write!(
                f,
                "sighting of landmark {} at {} s refused: implausible time stamp, {}",
                r.landmark,
                Number(r.time),
                r.problem
            ),
            Self::Sighting { sighting, why, .. } => {
                write!(
                    f,
                    "sighting of landmark {} at {} s (range {} m",
                    sighting.landmark,
                    Number(sighting.time),
                    Number(sighting.range)
                )?;
                if let Some(b) = sighting.bearing {
                    write!(f, ", bearing {} rad", Number(b))?;
                }
                write!(f, ") refused: the filter cannot use it: {why}")
            }
        }
    }
}

/// Every refused record counted, the first [`KEPT`] kept in the order
/// they were refused.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Refusals {
    first: Vec<Refusal>,
    total: usize,
}

impl Refusals {
    /// Counts `r`, and keeps it if fewer than [`KEPT`] are kept.
    pub fn push(&mut self, r: Refusal) {
        if self.first.len() < KEPT {
            self.first.push(r);
        }
        self.total += 1;
    }

    /// The first refused records, at most [`KEPT`].
    #[must_use]
    pub fn first(&self) -> &[Refusal] {
        &self.first
    }

    /// How many records were refused in all.
    #[must_use]
    pub fn total(&self) -> usize {
        self.total
    }
}

/// The records refused before the replay: implausible noise records,
/// implausible odometry records, sightings with implausible time stamps.
pub(crate) fn refusals_before(log: &Log, cfg: &Config) -> Refusals {
    let mut r = Refusals::default();
    let records = log.refused_noise.iter().copied();
    for record in records.chain(log.refused_odometry(&cfg.limits)) {
        r.push(Refusal::Record(record));
    }
    for time in &log.refused_times {
        r.push(Refusal::Time(*time));
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::TimeProblem;

    fn time(line: usize) -> Refusal {
        Refusal::Time(RefusedTime {
            line: Some(line),
            time: 1e300,
            landmark: 7,
            problem: TimeProblem::AfterOdometry { last: 10.0 },
        })
    }

    #[test]
    fn every_refusal_is_counted_and_the_first_are_kept_in_order() {
        let mut r = Refusals::default();
        for line in 1..=1000 {
            r.push(time(line));
        }
        assert_eq!(r.total(), 1000);
        assert_eq!(r.first().len(), KEPT);
        let lines: Vec<_> = r.first().iter().map(Refusal::line).collect();
        assert_eq!(lines, (1..=KEPT).map(Some).collect::<Vec<_>>());
    }

    #[test]
    fn an_absurd_value_is_written_in_scientific_notation() {
        let text = time(3).to_string();
        assert!(text.contains("at 1e300 s"), "{text}");
        assert!(text.len() < 200, "{text}");
    }
}
