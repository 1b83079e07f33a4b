//! The events of the replay's timeline and their canonical order.
//!
//! An [`Event`] is one record of the log (an odometry record or a
//! sighting, with its line in the log file if known); the running
//! filter's history keeps them sorted by time, then odometry before
//! sightings before scans, then sightings by landmark, range and bearing
//! (range-only before range-bearing) and scans by sensor and log order; odometry records at equal times keep their log
//! order. An [`Entry`] is an event in the history with what applying it
//! did. Times in s.

use locus_logs::mrclam::Odometry;

use crate::{ScanOutcome, Sighting, SightingOutcome};

/// An event of the canonical timeline.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Event {
    /// An odometry record and its line in the log file, if known.
    Odometry(Odometry, Option<usize>),
    /// A sighting and its line in the log file, if known (not part of the
    /// order).
    Sighting(Sighting, Option<usize>),
    /// A scan (its index in [`Log::scans`](crate::Log::scans), its time,
    /// its sensor) and its line in the log file, if known.
    Scan(ScanRef, Option<usize>),
}

/// A scan of the log, as the timeline orders it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ScanRef {
    pub(crate) index: usize,
    pub(crate) time: f64,
    pub(crate) sensor: u32,
}

impl Event {
    pub(crate) fn time(&self) -> f64 {
        match self {
            Event::Odometry(o, _) => o.time,
            Event::Sighting(s, _) => s.time,
            Event::Scan(s, _) => s.time,
        }
    }

    /// The event's line in the log file, if known.
    pub(crate) fn line(&self) -> Option<usize> {
        match self {
            Event::Odometry(_, line) | Event::Sighting(_, line) | Event::Scan(_, line) => *line,
        }
    }

    /// Canonical order: time, odometry before sightings, sightings by
    /// landmark, range, bearing. `Less`/`Equal` mean `self` goes first.
    fn order(&self, other: &Self) -> core::cmp::Ordering {
        use core::cmp::Ordering;
        let by_time = self.time().total_cmp(&other.time());
        if by_time != Ordering::Equal {
            return by_time;
        }
        let rank = |e: &Self| match e {
            Event::Odometry(..) => 0,
            Event::Sighting(..) => 1,
            Event::Scan(..) => 2,
        };
        match (self, other) {
            (Event::Odometry(..), Event::Odometry(..)) => Ordering::Equal,
            (Event::Scan(a, _), Event::Scan(b, _)) => {
                a.sensor.cmp(&b.sensor).then(a.index.cmp(&b.index))
            }
            (a, b) if rank(a) != rank(b) => rank(a).cmp(&rank(b)),
            // Range-only sightings (no bearing) before range-bearing ones.
            (Event::Sighting(a, _), Event::Sighting(b, _)) => a
                .landmark
                .cmp(&b.landmark)
                .then(a.range.total_cmp(&b.range))
                .then(match (a.bearing, b.bearing) {
                    (Some(x), Some(y)) => x.total_cmp(&y),
                    (x, y) => x.is_some().cmp(&y.is_some()),
                }),
            _ => Ordering::Equal,
        }
    }
}

/// An event in the running filter's history, with what applying it did.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Entry {
    pub(crate) event: Event,
    pub(crate) outcome: Option<SightingOutcome>,
    /// What a scan's beams did (zeros for other events).
    pub(crate) scan: ScanOutcome,
    pub(crate) inflations: u32,
    /// This event's term of
    /// [`Report::innovation_nll`](crate::Report::innovation_nll).
    pub(crate) nll: f64,
}

impl locus_core::Event for Entry {
    fn time(&self) -> f64 {
        self.event.time()
    }

    fn order(&self, other: &Self) -> core::cmp::Ordering {
        self.event.order(&other.event)
    }
}
