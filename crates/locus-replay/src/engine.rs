//! The replay engine: the forward pass over a log, one record at a time.
//!
//! [`Engine`] holds the replay's running filter and what the report needs.
//! [`Engine::advance`] takes the next record of the log (odometry or
//! sighting, whichever arrives first; odometry at its time plus
//! [`Config::odometry_delay`]) into the filter's history, and turns each
//! event the history makes final into a [`Step`] (its estimate, dead
//! reckoning, the ground truth at its time) counted into the [`Report`]
//! and the [`Tally`]. A [`Checkpoint`] is the pass's state between two
//! records: the pass is deterministic, so running on from a checkpoint
//! ([`Engine::restore`]) makes the same steps, to the bit, as the pass did
//! (the smoother's segments rest on this, `segments.rs`).
//!
//! Times in s; the estimates in the replay's state (`filter.rs`).

use locus_core::{
    Belief, ChiSquareGate, ConsistencyMonitor, Ekf, Recovery, Rules, StudentT, Track,
};
use locus_eval::Tally;
use locus_logs::mrclam::{Odometry, TruthCursor};
use locus_models::calibrated_unicycle::{
    BEARING_BIAS, OMEGA_BIAS, OMEGA_SCALE, RANGE_BIAS, V_SCALE,
};

use crate::event::{Entry, Event, ScanRef};
use crate::filter::{
    Carried, Filter, HISTORY, State, StateMatrix, StateVector, apply, calibration_of, pose_belief,
};
use crate::instants::InstantTally;
use crate::refusals::refusals_before;
use crate::start::{initial_pose, start_disagreement};
use crate::{
    Config, Error, EventKind, Log, Refusal, Report, ScanOutcome, SightingOutcome, Step, smoother,
};

/// The replay engine: the running filter and what the report needs.
pub(crate) struct Engine<'a> {
    pub(crate) cfg: Config,
    log: &'a Log,
    t0: f64,
    pub(crate) filter: Box<Filter>,
    pub(crate) next_index: usize,
    /// The filter's accuracy, one instant at a time.
    pub(crate) tally: InstantTally,
    pub(crate) report: Report,
    /// The steps made final and not yet taken by the caller.
    pub(crate) held: Vec<Step>,
    /// With [`Config::smooth`]: what the smoother needs of each held step.
    pub(crate) nodes: Vec<smoother::Node>,
    /// Ground-truth lookups in (mostly) increasing time.
    truth: TruthCursor<'a>,
    /// Steps compared with the truth after the start time.
    pub(crate) compared_after_start: usize,
    /// The next odometry record to take, an index into [`Log::odometry`].
    odometry: usize,
    /// The next sighting to take, an index into [`Log::sightings`].
    sightings: usize,
    /// The next scan to take, an index into [`Log::scans`].
    scans: usize,
}

/// The forward pass's state between two records of the log: all that
/// running it on from there needs (the running filter's base, history and
/// monitor, the step count, the places in the log and in the truth). The
/// pass is deterministic, so a run from a checkpoint makes the same steps,
/// to the bit, as the pass did; the report's counts are not part of it.
pub(crate) struct Checkpoint<'a> {
    base: State,
    /// The running filter's pending events (within [`Config::horizon`]).
    history: Vec<(Entry, State)>,
    monitor: ConsistencyMonitor<32>,
    pub(crate) next_index: usize,
    truth: TruthCursor<'a>,
    odometry: usize,
    sightings: usize,
    scans: usize,
}

impl<'a> Engine<'a> {
    /// The engine at the log's first odometry time, nothing taken yet: the
    /// configuration checked, the initial pose chosen
    /// ([`initial_pose`]), the sightings' arrival order checked, the
    /// filter and the report's start made; with [`Config::smooth`], room
    /// held for one segment of `segment` steps.
    ///
    /// # Errors
    /// An invalid configuration, a log with no odometry or no initial
    /// pose, sightings out of arrival order.
    pub(crate) fn new(log: &'a Log, cfg: &Config, segment: usize) -> Result<Self, Error> {
        cfg.validate()?;
        let first = log.odometry.first().ok_or(Error::NoOdometry)?;
        let t0 = first.time;
        let (pose, pose_covariance, started_from) = initial_pose(log, cfg, t0)?;
        let mut previous = f64::NEG_INFINITY;
        for (index, s) in log.sightings.iter().enumerate() {
            if s.arrival < previous {
                return Err(Error::ArrivalOrder {
                    index,
                    arrival: s.arrival,
                });
            }
            if s.arrival < s.time {
                return Err(Error::ArrivesBeforeTaken {
                    index,
                    time: s.time,
                    arrival: s.arrival,
                });
            }
            previous = s.arrival;
        }
        let mut x = StateVector::zeros();
        x[0] = pose[0];
        x[1] = pose[1];
        x[2] = pose[2];
        x[V_SCALE] = cfg.calibration.initial[0];
        x[OMEGA_SCALE] = cfg.calibration.initial[1];
        x[OMEGA_BIAS] = cfg.calibration.initial[2];
        x[BEARING_BIAS] = cfg.calibration.initial[3];
        let [cv, cw, cb, cz] = cfg.calibration.std;
        let cr = cfg.beams.bias.sigma;
        let mut p = StateMatrix::from_diagonal(&StateVector::from([
            0.0,
            0.0,
            0.0,
            cv * cv,
            cw * cw,
            cb * cb,
            cz * cz,
            cr * cr,
        ]));
        p.fixed_view_mut::<3, 3>(0, 0).copy_from(&pose_covariance);
        let belief = Belief::new(x, p);
        let mut ekf = Ekf::default();
        if let Some(g) = cfg.gate {
            ekf = ekf.with_gate(
                ChiSquareGate::new(g).map_err(|_| Error::InvalidConfig("gate confidence"))?,
            );
        }
        // The inflation leaves alone the calibration states the model holds
        // constant (no random walk), and the range bias, whose spread its
        // process bounds: only the pose and what drifts may grow.
        let held: Vec<usize> = (0..4)
            .filter(|&i| cfg.calibration.walk[i] == 0.0)
            .map(|i| V_SCALE + i)
            .chain([RANGE_BIAS])
            .collect();
        let recovery = Recovery::new(cfg.recover_after, cfg.inflation)
            .and_then(|r| r.holding(&held))
            .map_err(|_| Error::InvalidConfig("recovery"))?;
        let rules = Rules::new(ekf).with_recovery(recovery);
        if let Some(dof) = cfg.robust_dof {
            StudentT::new(dof).map_err(|_| Error::InvalidConfig("robust degrees of freedom"))?;
        }
        let tally = Tally::new(3).map_err(|_| Error::InvalidConfig("NEES degrees of freedom"))?;
        let start = Track::new(
            belief,
            t0,
            Carried {
                v: 0.0,
                omega: 0.0,
                dead: pose,
            },
        );
        // With the smoother: one segment, and what one record can make final.
        let events = log.odometry.len() + log.sightings.len() + log.scans.len();
        let hold = if cfg.smooth {
            segment.min(events).saturating_add(HISTORY)
        } else {
            0
        };
        Ok(Self {
            cfg: *cfg,
            log,
            t0,
            filter: Box::new(Filter::new(rules, start)),
            next_index: 0,
            tally: InstantTally::new(tally),
            report: Report {
                summary: Tally::new(3)
                    .map_err(|_| Error::InvalidConfig("NEES degrees of freedom"))?
                    .summary(0),
                smoothed: None,
                steps: 0,
                compared: 0,
                odometry: 0,
                sightings: 0,
                applied: 0,
                down_weighted: 0,
                gated: 0,
                inflations: 0,
                recovered: 0,
                not_in_map: 0,
                no_measurement: 0,
                unusable: 0,
                implausible_time: log.refused_times.len(),
                implausible_odometry: 0,
                refusals: refusals_before(log, cfg),
                robot_sightings: log.robot_sightings,
                unknown_sightings: log.unknown_sightings,
                late: 0,
                too_late: 0,
                scans: 0,
                beams: ScanOutcome::default(),
                innovation_nll: 0.0,
                final_belief: pose_belief(&belief),
                calibration: calibration_of(&belief),
                smoothed_calibration: None,
                started_from,
                start_disagreement: start_disagreement(log, cfg, &started_from),
                smoothing_held: 0,
                smoothing_checkpoints: 0,
            },
            held: Vec::with_capacity(hold),
            nodes: Vec::with_capacity(hold),
            truth: log.truth.cursor(),
            compared_after_start: 0,
            odometry: 0,
            sightings: 0,
            scans: 0,
        })
    }

    /// The state to run on from, later, with [`Engine::restore`].
    pub(crate) fn checkpoint(&self) -> Checkpoint<'a> {
        Checkpoint {
            base: *self.filter.base(),
            history: self.filter.history().copied().collect(),
            monitor: self.filter.monitor().clone(),
            next_index: self.next_index,
            truth: self.truth.clone(),
            odometry: self.odometry,
            sightings: self.sightings,
            scans: self.scans,
        }
    }

    /// Goes back to `c`, dropping the held steps.
    pub(crate) fn restore(&mut self, c: &Checkpoint<'a>) -> Result<(), Error> {
        self.filter
            .restore(&c.base, c.history.iter(), &c.monitor)
            .map_err(|source| Error::Filter {
                time: c.base.time,
                line: None,
                source,
            })?;
        self.next_index = c.next_index;
        self.truth = c.truth.clone();
        self.odometry = c.odometry;
        self.sightings = c.sightings;
        self.scans = c.scans;
        self.held.clear();
        self.nodes.clear();
        Ok(())
    }

    /// Takes the next record of the log (odometry or sighting, whichever
    /// arrives first) into the filter, the events it makes final into
    /// [`Engine::held`]; after the last record, makes every event final.
    /// Returns whether records were left.
    pub(crate) fn advance(&mut self) -> Result<bool, Error> {
        let (cfg, log) = (self.cfg, self.log);
        let (odometry, sighting) = (
            log.odometry.get(self.odometry),
            log.sightings.get(self.sightings),
        );
        let scan_time = log.scans.times().get(self.scans).copied();
        // Measurements arrive in order of arrival, sightings before scans
        // at one time; odometry goes first up to that time.
        let measurement = match (sighting, scan_time) {
            (Some(s), Some(t)) => Some((s.arrival.min(t), s.arrival <= t)),
            (Some(s), None) => Some((s.arrival, true)),
            (None, Some(t)) => Some((t, false)),
            (None, None) => None,
        };
        let take_odometry = match (odometry, measurement) {
            (Some(o), Some((arrival, _))) => o.time + cfg.odometry_delay <= arrival,
            (Some(_), None) => true,
            (None, Some(_)) => false,
            (None, None) => {
                self.finalise_before(f64::INFINITY);
                return Ok(false);
            }
        };
        if !take_odometry && let (Some(t), Some((_, false))) = (scan_time, measurement) {
            let index = self.scans;
            self.scans += 1;
            self.finalise_before(t - cfg.horizon);
            // A scan at the base's own time (the first odometry time) is
            // applied on it; an older one is too late.
            if t < self.filter.base().time {
                self.report.too_late += 1;
                return Ok(true);
            }
            let sensor = log.scans.get(index).map_or(0, |s| s.sensor);
            let scan = ScanRef {
                index,
                time: t,
                sensor,
            };
            self.insert(Event::Scan(scan, log.lines.scans.get(index).copied()))?;
            return Ok(true);
        }
        if take_odometry {
            if let Some(o) = odometry {
                let i = self.odometry;
                self.odometry += 1;
                // An implausible record is refused: the velocities before
                // it are held.
                if log.odometry_problem(i, &cfg.limits).is_some() {
                    self.report.implausible_odometry += 1;
                    return Ok(true);
                }
                let o = Odometry {
                    time: o.time + cfg.odometry_delay,
                    ..*o
                };
                self.finalise_before(o.time - cfg.horizon);
                self.insert(Event::Odometry(o, log.lines.odometry.get(i).copied()))?;
            }
        } else if let Some(s) = sighting {
            let i = self.sightings;
            self.sightings += 1;
            self.finalise_before(s.arrival - cfg.horizon);
            // With a delay within the horizon, every finalised event is
            // older than the sighting, so the base is never re-run.
            if s.time <= self.filter.base().time {
                self.report.too_late += 1;
                return Ok(true);
            }
            let late = s.time < self.filter.time();
            self.insert(Event::Sighting(*s, log.lines.measurements.get(i).copied()))?;
            self.report.late += usize::from(late);
        }
        Ok(true)
    }

    /// Inserts `event` at its place in canonical order (re-running the
    /// history after it); reports an event made final to make room.
    fn insert(&mut self, event: Event) -> Result<(), Error> {
        let entry = Entry {
            event,
            outcome: None,
            scan: ScanOutcome::default(),
            inflations: 0,
            nll: 0.0,
        };
        let (cfg, log) = (&self.cfg, self.log);
        // Matched in place: the result holds a whole history entry.
        match &self
            .filter
            .insert(entry, |rules, track, e| apply(cfg, log, rules, track, e))
        {
            Ok((_, Some((entry, after)))) => self.emit(entry, after),
            Ok((_, None)) => {}
            Err(source) => {
                return Err(Error::Filter {
                    time: event.time(),
                    line: event.line(),
                    source: *source,
                });
            }
        }
        Ok(())
    }

    /// Makes final the events older than `limit` (s).
    fn finalise_before(&mut self, limit: f64) {
        while let Some((entry, after)) = &self.filter.pop_final_before(limit) {
            self.emit(entry, after);
        }
    }

    fn emit(&mut self, e: &Entry, after: &State) {
        let kind = match e.event {
            Event::Odometry(o, _) => {
                self.report.odometry += 1;
                EventKind::Odometry {
                    v: o.v,
                    omega: o.omega,
                }
            }
            Event::Sighting(sighting, line) => {
                let outcome = e.outcome.unwrap_or(SightingOutcome::NoMeasurement);
                let r = &mut self.report;
                r.sightings += 1;
                match outcome {
                    SightingOutcome::Applied {
                        recovered, weight, ..
                    } => {
                        r.applied += 1;
                        r.recovered += usize::from(recovered);
                        r.down_weighted += usize::from(weight < 1.0);
                    }
                    SightingOutcome::Gated { .. } => r.gated += 1,
                    SightingOutcome::NotInMap => r.not_in_map += 1,
                    SightingOutcome::NoMeasurement => r.no_measurement += 1,
                    SightingOutcome::Unusable(why) => {
                        r.unusable += 1;
                        r.refusals.push(Refusal::Sighting {
                            line,
                            sighting,
                            why,
                        });
                    }
                }
                EventKind::Sighting {
                    sighting,
                    outcome,
                    line,
                }
            }
            Event::Scan(scan, line) => {
                let o = e.scan;
                let r = &mut self.report;
                r.scans += 1;
                let b = &mut r.beams;
                b.beams += o.beams;
                b.chosen += o.chosen;
                b.no_return += o.no_return;
                b.no_surface += o.no_surface;
                b.short += o.short;
                b.applied += o.applied;
                b.down_weighted += o.down_weighted;
                b.gated += o.gated;
                b.unusable += o.unusable;
                b.aligned += o.aligned;
                b.nis += o.nis;
                EventKind::Scan {
                    index: scan.index,
                    sensor: scan.sensor,
                    outcome: o,
                    line,
                }
            }
        };
        self.report.inflations += e.inflations as usize;
        self.report.innovation_nll += e.nll;
        let time = e.event.time();
        let d = after.extra.dead;
        let step = Step {
            index: self.next_index,
            time,
            elapsed: time - self.t0,
            kind,
            belief: pose_belief(&after.belief),
            calibration: calibration_of(&after.belief).map(|c| c.0),
            smoothed: None,
            smoothed_calibration: None,
            dead_reckoning: [d[0], d[1], d[2]],
            truth: if self.cfg.evaluate {
                self.truth.pose_at(time, self.cfg.truth_max_gap)
            } else {
                None
            },
        };
        self.next_index += 1;
        self.report.steps += 1;
        if step.truth.is_some() {
            self.report.compared += 1;
            self.compared_after_start += usize::from(time > self.t0);
        }
        self.tally.add(&step, Some(&step.belief));
        self.held.push(step);
        if self.cfg.smooth {
            self.nodes.push(smoother::Node {
                posterior: after.belief,
                time,
                v: after.extra.v,
                omega: after.extra.omega,
            });
        }
    }
}

/// `s` (a tally of every step) judged for a replay: with no step compared
/// after the start (`judged` false: the only one compared is the start
/// pose, copied from the truth when the replay started from it) every
/// truth figure is NaN, never the 0 error and 100 % of a pose compared
/// with itself.
pub(crate) fn judged(s: locus_eval::Summary, judged: bool) -> locus_eval::Summary {
    if judged { s } else { s.without_truth_figures() }
}
