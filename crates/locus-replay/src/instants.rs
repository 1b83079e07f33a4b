//! The replay's accuracy, one instant at a time.
//!
//! A log's records can share a time: on a rail or a lidar robot the
//! odometry record and the scan stamped with it, on MRCLAM the landmarks of
//! one camera frame. The replay makes one step of each (`log.csv` writes
//! them all), but the estimate *at* that time is the one that has taken
//! every record of it: the steps before it carry a prediction the same
//! instant's measurement has not yet corrected. Compared with the truth,
//! they would count one instant twice, once with less than the filter knew
//! then. So only the last step at each time is compared with the truth
//! (position and heading errors, the 3-sigma shares, the NEES); every step
//! still counts as a step, and every measurement as a reading
//! ([`locus_eval::Tally::count`]). A baseline judged at a sensor's times
//! (the range alone, `crate::rail`) is then judged at the same instants.

use locus_core::Belief;
use locus_eval::{Sample, Summary, Tally};

use crate::Step;

/// What a step adds to the tally, kept until the next step says whether
/// it was the last at its time.
#[derive(Debug, Clone, Copy)]
struct Pending {
    time: f64,
    sample: Option<Sample>,
    elapsed: f64,
    measured: bool,
    applied: Option<bool>,
}

/// A [`Tally`] that compares only the last step at each time with the
/// truth (the module doc says why).
#[derive(Debug, Clone)]
pub(crate) struct InstantTally {
    tally: Tally,
    pending: Option<Pending>,
}

impl InstantTally {
    /// An instant tally over `tally` (empty).
    pub(crate) fn new(tally: Tally) -> Self {
        Self {
            tally,
            pending: None,
        }
    }

    /// Adds `step`, with `belief` as its estimate (none: counted only).
    pub(crate) fn add(&mut self, step: &Step, belief: Option<&Belief<f64, 3>>) {
        if let Some(p) = self.pending.take() {
            if p.time.to_bits() == step.time.to_bits() {
                self.tally.count(p.elapsed, p.measured, p.applied);
            } else {
                Self::settle(&mut self.tally, &p);
            }
        }
        let (measured, correction) = step.measurement();
        self.pending = Some(Pending {
            time: step.time,
            sample: belief.and_then(|b| step.sample_of(b)),
            elapsed: step.elapsed,
            measured,
            applied: correction.map(|(_, _, applied)| applied),
        });
    }

    /// The summary of the steps added so far (the last one as the last at
    /// its time).
    pub(crate) fn summary(&self) -> Summary {
        let mut tally = self.tally.clone();
        if let Some(p) = &self.pending {
            Self::settle(&mut tally, p);
        }
        tally.summary(0)
    }

    /// `p` added as the last step at its time.
    fn settle(tally: &mut Tally, p: &Pending) {
        match &p.sample {
            Some(sample) => tally.push(sample),
            None => tally.count(p.elapsed, p.measured, p.applied),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::EventKind;
    use locus_core::nalgebra::{Matrix3, Vector3};
    use locus_logs::mrclam::TruthPose;

    fn step(index: usize, time: f64, x: f64) -> Step {
        Step {
            index,
            time,
            elapsed: time,
            kind: EventKind::Odometry { v: 0.0, omega: 0.0 },
            belief: Belief::new(Vector3::new(x, 0.0, 0.0), Matrix3::identity() * 0.01),
            calibration: [1.0, 1.0, 0.0, 0.0],
            smoothed: None,
            smoothed_calibration: None,
            dead_reckoning: [0.0; 3],
            truth: Some(TruthPose {
                time,
                x: 0.0,
                y: 0.0,
                theta: 0.0,
            }),
        }
    }

    #[test]
    fn compares_only_the_last_step_at_each_time() {
        let mut t = InstantTally::new(Tally::new(3).unwrap());
        // At 0 s a prediction 0.3 m off, then the correction 0.1 m off; at
        // 1 s one step 0.1 m off.
        for (i, (time, x)) in [(0.0, 0.3), (0.0, 0.1), (1.0, 0.1)].into_iter().enumerate() {
            let s = step(i, time, x);
            t.add(&s, Some(&s.belief));
        }
        let s = t.summary();
        assert_eq!((s.steps, s.compared), (3, 2));
        assert!((s.position_rmse - 0.1).abs() < 1e-15, "{}", s.position_rmse);
        // Added again, the summary is unchanged by asking for it.
        assert_eq!(t.summary().compared, 2);
        let s = step(3, 2.0, 0.0);
        t.add(&s, None);
        assert_eq!((t.summary().steps, t.summary().compared), (4, 2));
    }
}
