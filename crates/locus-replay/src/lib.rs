//! Replay of recorded robot logs through Locus's EKF.
//!
//! A [`Log`] (from an MRCLAM dataset or a Locus CSV log, see
//! `docs/log-format.md`) is replayed by [`replay`]:
//!
//! * **Time.** Odometry (commanded or measured `v`, `omega`, held from one
//!   record to the next) and landmark sightings are merged in time order.
//!   Each record is an *event*, kept in the history of Locus's running
//!   filter ([`locus_core::RunningFilter`]); between two events it predicts with
//!   the [`Unicycle`] model over the time between them. A sighting arrives
//!   at [`Sighting::arrival`] (after the odometry up to that time); if it is
//!   older than the filter's time, the replay goes back to the belief just
//!   before the sighting's own time in a short history
//!   ([`Config::horizon`] seconds), applies it there and re-runs the later
//!   events. The estimates are therefore those of an in-order replay (to
//!   rounding: the same operations in the same order, so in practice
//!   bit-for-bit). A sighting older than the history is counted
//!   ([`Report::too_late`]) and not applied.
//! * **Events in canonical order.** Events are kept sorted by time, then
//!   odometry before sightings, then sightings by landmark, range and
//!   bearing; odometry records at equal times keep their log order.
//! * **Correction.** Each landmark sighting is one range-bearing
//!   correction from the sensor where the log's `sensor` record mounts it
//!   ([`Log::sensor`]; the robot's centre by default), with the bearing
//!   bias state ([`CalibratedRangeBearing`]); a range-only sighting (a UWB
//!   beacon's) is a 1-D range correction from the same sensor
//!   ([`CalibratedRange`]), gated on chi-square with 1 dof; both weighted
//!   as Student-t noise
//!   ([`Config::robust_dof`]). Sightings of landmarks not in the map are
//!   counted and skipped; robot-to-robot sightings never reach the replay
//!   (the MRCLAM log splits them off).
//! * **Calibration.** The state holds the pose and the odometry and sensor
//!   calibration ([`CalibratedUnicycle`](locus_models::calibrated_unicycle::CalibratedUnicycle):
//!   scale factors of the logged speed and turn rate, turn-rate and bearing
//!   biases), estimated with it ([`Config::calibration`]).
//! * **Smoothing.** With [`Config::smooth`], the Rauch-Tung-Striebel
//!   smoother runs backwards over the final forward pass; each step then
//!   carries its smoothed pose and the report the smoother's figures. It
//!   works in segments re-made from checkpoints of the forward pass
//!   ([`replay_in_segments`]): its memory grows as the square root of the
//!   log's length.
//! * **Gating with recovery.** The running filter's chi-square gate
//!   ([`Config::gate`]) rejects
//!   outliers. A filter that has become over-confident would reject every
//!   later sighting; so after [`Config::recover_after`] consecutive
//!   rejections the covariance is multiplied by [`Config::inflation`] and
//!   the sighting is tried again (and again at each further rejection, so
//!   the inflation compounds until a sighting fits). The calibration
//!   states with no random walk are held: the inflation leaves them as
//!   they are ([`locus_core::Recovery`]).
//! * **Initial pose.** The log's start pose, else the ground truth at the
//!   first odometry time (for a truth of positions only, its position and
//!   the heading of its direction of motion, [`initial::heading_from_truth`],
//!   if it moves), else the pose the first sightings fix
//!   ([`initial`]); [`Config::start`] can ask for the last whatever the
//!   log gives. [`Report::started_from`] says which.
//! * **Ground truth.** Each event's estimate is compared with the ground
//!   truth interpolated at its time (events where the truth has a gap wider
//!   than [`Config::truth_max_gap`] or has ended are not compared), beside
//!   dead reckoning from the same start with the same inputs. The
//!   figures are accumulated by `locus-eval`'s [`Tally`] into its
//!   [`Summary`](locus_eval::Summary), so they read as `locus run`'s.
//!
//! Units: SI (m, rad, s); headings wrapped to (-pi, pi].

extern crate alloc;

mod config;
mod dead_reckoning;
pub mod drift;
pub mod fleet;
pub mod initial;
pub mod log;
pub mod noise;
pub mod policy;
pub mod refusals;
mod report;
mod smoother;
mod step;

use locus_core::nalgebra::{SMatrix, SVector, Vector2, Vector3};
use locus_core::{
    Belief, ChiSquareGate, ConsistencyMonitor, Ekf, MeasurementModel, MotionModel, Recovery, Rules,
    RunningFilter, StudentT, Track, Update, wrap_angle,
};
use locus_eval::Tally;
use locus_logs::mrclam::{Odometry, TruthCursor, TruthPose};
use locus_models::calibrated_range::CalibratedRange;
use locus_models::calibrated_range_bearing::CalibratedRangeBearing;
use locus_models::calibrated_unicycle::{BEARING_BIAS, OMEGA_BIAS, OMEGA_SCALE, V_SCALE};
use locus_models::range_bearing::RangeBearing;
use locus_models::unicycle::{Unicycle, Velocities};

pub use config::{Calibration, Config, Start};
pub use log::{Landmark, Log, RefusedRecord, RefusedTime, Sighting, TIME_TOLERANCE, TimeProblem};
pub use refusals::{Refusal, Refusals};
pub use report::{Report, StartDisagreement, StartedFrom};
pub use step::{EventKind, SightingOutcome, Step, Unusable};

/// Cap on one sighting's NIS in [`Report::innovation_nll`]: the 99.9 %
/// point of chi-square with 2 degrees of freedom, `-2 ln 0.001`.
pub const NIS_CAP: f64 = 13.815_510_557_964_274;

/// Cap on a range-only sighting's NIS in [`Report::innovation_nll`]: the
/// 99.9 % point of chi-square with 1 degree of freedom.
pub const NIS_CAP_RANGE: f64 = 10.827_566_170_662_733;

/// Errors of the replay.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The log has no odometry: nothing to replay.
    #[error("the log has no odometry")]
    NoOdometry,
    /// The log gives no initial pose, has no ground truth to start from at
    /// the first odometry time (a pose, or positions whose first motion
    /// gives a heading), or [`Config::start`] asks for the sightings' pose;
    /// and its sightings fix none ([`initial`]).
    #[error(
        "no initial pose: {}, and its sightings fix none: {reason}",
        given(*asked, *time)
    )]
    NoStart {
        /// The first odometry time, s.
        time: f64,
        /// Whether the start was asked of the sightings
        /// ([`Start::Sightings`]) rather than missing from the log.
        asked: bool,
        /// Why the sightings fix none.
        reason: initial::NoFix,
    },
    /// The sightings are not in non-decreasing arrival order.
    #[error("sighting {index}: arrival {arrival} s is earlier than the previous one's")]
    ArrivalOrder {
        /// Index of the sighting in [`Log::sightings`].
        index: usize,
        /// Its arrival time, s.
        arrival: f64,
    },
    /// A sighting arrives before it was taken.
    #[error("sighting {index}: arrival {arrival} s is before its time {time} s")]
    ArrivesBeforeTaken {
        /// Index of the sighting in [`Log::sightings`].
        index: usize,
        /// Its time, s.
        time: f64,
        /// Its arrival time, s.
        arrival: f64,
    },
    /// A configuration value is out of its valid range.
    #[error("invalid configuration: {0}")]
    InvalidConfig(&'static str),
    /// The smoother's backward pass failed (a prediction that fails or a
    /// predicted covariance that is not positive definite).
    #[error("smoother: prediction failed or not positive definite at {time} s")]
    Smoother {
        /// The event's time, s.
        time: f64,
    },
    /// The log cannot be read (file, line and field named).
    #[error(transparent)]
    Read(#[from] locus_logs::Error),
    /// A record every sighting or the start depends on is implausible
    /// (`locus_models::plausible`).
    #[error("{file}:{}{what}: {why}", line.map_or_else(String::new, |l| format!("{l}: ")))]
    Implausible {
        /// The log's name (its file's).
        file: String,
        /// The record's line, if known.
        line: Option<usize>,
        /// The record (`sensor`, `landmark`, `start`).
        what: &'static str,
        /// Why.
        why: locus_models::plausible::Implausible,
    },
    /// The filter failed (non-finite input, ...).
    #[error("filter step at {time} s{}", line.map_or_else(String::new, |l| format!(" (line {l})")))]
    Filter {
        /// The event's time, s.
        time: f64,
        /// The event's line in the log, if known.
        line: Option<usize>,
        /// The filter's error.
        #[source]
        source: locus_core::Error,
    },
}

/// An event of the canonical timeline.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Event {
    /// An odometry record and its line in the log file, if known.
    Odometry(Odometry, Option<usize>),
    /// A sighting and its line in the log file, if known (not part of the
    /// order).
    Sighting(Sighting, Option<usize>),
}

impl Event {
    fn time(&self) -> f64 {
        match self {
            Event::Odometry(o, _) => o.time,
            Event::Sighting(s, _) => s.time,
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
        match (self, other) {
            (Event::Odometry(..), Event::Odometry(..)) => Ordering::Equal,
            (Event::Odometry(..), Event::Sighting(..)) => Ordering::Less,
            (Event::Sighting(..), Event::Odometry(..)) => Ordering::Greater,
            // Range-only sightings (no bearing) before range-bearing ones.
            (Event::Sighting(a, _), Event::Sighting(b, _)) => a
                .landmark
                .cmp(&b.landmark)
                .then(a.range.total_cmp(&b.range))
                .then(match (a.bearing, b.bearing) {
                    (Some(x), Some(y)) => x.total_cmp(&y),
                    (x, y) => x.is_some().cmp(&y.is_some()),
                }),
        }
    }
}

/// What the replay carries beside the belief: the input in force (scaled)
/// and dead reckoning from the same start with the same inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Carried {
    v: f64,
    omega: f64,
    dead: Vector3<f64>,
}

/// Dimension of the replay's state: the pose and the calibration of
/// [`CalibratedUnicycle`](locus_models::calibrated_unicycle::CalibratedUnicycle).
pub const STATE: usize = 7;

/// The replay's state vector and covariance.
pub type StateVector = SVector<f64, STATE>;
/// A covariance of the replay's state.
pub type StateMatrix = SMatrix<f64, STATE, STATE>;

/// An event in the running filter's history, with what applying it did.
#[derive(Debug, Clone, Copy)]
struct Entry {
    event: Event,
    outcome: Option<SightingOutcome>,
    inflations: u32,
    /// This event's term of [`Report::innovation_nll`].
    nll: f64,
}

impl locus_core::Event for Entry {
    fn time(&self) -> f64 {
        self.event.time()
    }

    fn order(&self, other: &Self) -> core::cmp::Ordering {
        self.event.order(&other.event)
    }
}

/// Events the history holds at most. The history is cut by time
/// ([`Config::horizon`]); this bound only matters for a log with more than
/// this many events within one horizon, whose oldest events then become
/// final early.
const HISTORY: usize = 1024;

type Filter = RunningFilter<f64, STATE, HISTORY, Entry, Carried>;
type State = Track<f64, STATE, Carried>;

/// Advances `track` to `entry`'s time and applies it (the running filter's
/// `apply`; deterministic, as a re-run needs).
fn apply(
    cfg: &Config,
    log: &Log,
    rules: &Rules<f64>,
    track: &mut State,
    entry: &mut Entry,
) -> Result<(), locus_core::Error> {
    let t = entry.event.time();
    let dt = t - track.time;
    if dt > 0.0 {
        let model = cfg.motion_model();
        let c = track.extra;
        let u = Velocities {
            v: c.v,
            omega: c.omega,
            dt,
        };
        track.predict(&rules.ekf, &model, &u)?;
        track.extra.dead = Unicycle::new(0.0, 0.0).f(&c.dead, &u, &Vector2::zeros());
        track.time = t;
    }
    entry.inflations = 0;
    entry.nll = 0.0;
    entry.outcome = match entry.event {
        Event::Odometry(o, _) => {
            track.extra.v = o.v;
            track.extra.omega = o.omega;
            None
        }
        Event::Sighting(z, _) => Some(match log.landmark(z.landmark) {
            None => SightingOutcome::NotInMap,
            // Also NaN, should a log ever hold one.
            Some(_) if z.range.is_nan() || z.range > cfg.max_range => {
                SightingOutcome::Unusable(Unusable::RangeAbove { max: cfg.max_range })
            }
            Some(l) => {
                let inner = RangeBearing::new(
                    Vector2::new(l.x, l.y),
                    Vector2::new(log.sensor.x, log.sensor.y),
                    cfg.sigma_range,
                    cfg.sigma_bearing,
                );
                let outcome = match z.bearing {
                    Some(bearing) => correct(
                        cfg,
                        rules,
                        track,
                        entry,
                        &CalibratedRangeBearing {
                            inner,
                            yaw: log.sensor.yaw,
                        },
                        &Vector2::new(z.range, bearing),
                        NIS_CAP,
                        SMatrix::determinant,
                    ),
                    None => correct(
                        cfg,
                        rules,
                        track,
                        entry,
                        &CalibratedRange { inner },
                        &SVector::<f64, 1>::new(z.range),
                        NIS_CAP_RANGE,
                        |s| s[(0, 0)],
                    ),
                };
                match outcome? {
                    Some(o) => o,
                    // Refused: the track is unchanged.
                    None => return Ok(()),
                }
            }
        }),
    };
    Ok(())
}

/// Corrects `track` with one sighting `z` of `M` components (range and
/// bearing, or range alone) by `model`, Student-t weighted as `cfg` says,
/// and records its innovation log-likelihood term (its NIS capped at
/// `nis_cap`; `determinant` of the innovation covariance) in `entry`. `Ok(None)`: the correction failed on the
/// sighting, which is refused (`entry`'s outcome set, the track unchanged).
fn correct<const M: usize>(
    cfg: &Config,
    rules: &Rules<f64>,
    track: &mut State,
    entry: &mut Entry,
    model: &impl MeasurementModel<f64, STATE, M>,
    z: &SVector<f64, M>,
    nis_cap: f64,
    determinant: fn(&SMatrix<f64, M, M>) -> f64,
) -> Result<Option<SightingOutcome>, locus_core::Error> {
    let update = match cfg.robust_dof.map(StudentT::new) {
        Some(Ok(t)) => track.correct_robust(rules, &t, model, z),
        _ => track.correct(rules, model, z),
    };
    // A correction that fails on the sighting (not on the belief) refuses
    // it; the track is then unchanged.
    let update = match update {
        Ok(u) => u,
        Err(e) => match Unusable::of(e) {
            Some(why) => {
                entry.outcome = Some(SightingOutcome::Unusable(why));
                return Ok(None);
            }
            None => return Err(e),
        },
    };
    if let Some(first) = update.first_attempt() {
        entry.nll = 0.5 * determinant(&first.s).ln() + 0.5 * first.nis.min(nis_cap);
    }
    entry.inflations = u32::from(update.inflated());
    Ok(Some(match update {
        Update::Applied {
            correction,
            first,
            weight,
        } => SightingOutcome::Applied {
            nis: correction.nis,
            recovered: first.is_some(),
            weight,
        },
        Update::Gated { correction, .. } => SightingOutcome::Gated {
            nis: correction.nis,
        },
        Update::NoMeasurement => SightingOutcome::NoMeasurement,
    }))
}

/// The pose part of a belief of the replay's state.
fn pose_belief(b: &Belief<f64, STATE>) -> Belief<f64, 3> {
    Belief::new(
        b.x.fixed_rows::<3>(0).into_owned(),
        b.p.fixed_view::<3, 3>(0, 0).into_owned(),
    )
}

/// The calibration part of a belief: `(mean, standard deviation)` of `s_v`,
/// `s_omega`, `b_omega` (rad/s) and `b_bearing` (rad).
fn calibration_of(b: &Belief<f64, STATE>) -> [(f64, f64); 4] {
    [V_SCALE, OMEGA_SCALE, OMEGA_BIAS, BEARING_BIAS].map(|i| (b.x[i], b.p[(i, i)].sqrt()))
}

/// The replay engine: the running filter and what the report needs.
struct Engine<'a> {
    cfg: Config,
    log: &'a Log,
    t0: f64,
    filter: Box<Filter>,
    next_index: usize,
    tally: Tally,
    report: Report,
    /// The steps made final and not yet taken by the caller.
    held: Vec<Step>,
    /// With [`Config::smooth`]: what the smoother needs of each held step.
    nodes: Vec<smoother::Node>,
    /// Ground-truth lookups in (mostly) increasing time.
    truth: TruthCursor<'a>,
    /// Steps compared with the truth after the start time.
    compared_after_start: usize,
    /// The next odometry record to take, an index into [`Log::odometry`].
    odometry: usize,
    /// The next sighting to take, an index into [`Log::sightings`].
    sightings: usize,
}

/// The forward pass's state between two records of the log: all that
/// running it on from there needs (the running filter's base, history and
/// monitor, the step count, the places in the log and in the truth). The
/// pass is deterministic, so a run from a checkpoint makes the same steps,
/// to the bit, as the pass did; the report's counts are not part of it.
struct Checkpoint<'a> {
    base: State,
    /// The running filter's pending events (within [`Config::horizon`]).
    history: Vec<(Entry, State)>,
    monitor: ConsistencyMonitor<32>,
    next_index: usize,
    truth: TruthCursor<'a>,
    odometry: usize,
    sightings: usize,
}

impl<'a> Engine<'a> {
    /// The state to run on from, later, with [`Engine::restore`].
    fn checkpoint(&self) -> Checkpoint<'a> {
        Checkpoint {
            base: *self.filter.base(),
            history: self.filter.history().copied().collect(),
            monitor: self.filter.monitor().clone(),
            next_index: self.next_index,
            truth: self.truth.clone(),
            odometry: self.odometry,
            sightings: self.sightings,
        }
    }

    /// Goes back to `c`, dropping the held steps.
    fn restore(&mut self, c: &Checkpoint<'a>) -> Result<(), Error> {
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
        self.held.clear();
        self.nodes.clear();
        Ok(())
    }

    /// Takes the next record of the log (odometry or sighting, whichever
    /// arrives first) into the filter, the events it makes final into
    /// [`Engine::held`]; after the last record, makes every event final.
    /// Returns whether records were left.
    fn advance(&mut self) -> Result<bool, Error> {
        let (cfg, log) = (self.cfg, self.log);
        let (odometry, sighting) = (
            log.odometry.get(self.odometry),
            log.sightings.get(self.sightings),
        );
        let take_odometry = match (odometry, sighting) {
            (Some(o), Some(s)) => o.time + cfg.odometry_delay <= s.arrival,
            (Some(_), None) => true,
            (None, Some(_)) => false,
            (None, None) => {
                self.finalise_before(f64::INFINITY);
                return Ok(false);
            }
        };
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
                    line: match event {
                        Event::Odometry(_, line) | Event::Sighting(_, line) => line,
                    },
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
        step.tally_into(&mut self.tally, Some(&step.belief));
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
fn judged(s: locus_eval::Summary, judged: bool) -> locus_eval::Summary {
    if judged { s } else { s.without_truth_figures() }
}

/// What [`Error::NoStart`] says the start came from: the sightings on
/// request, or nothing else in the log.
fn given(asked: bool, time: f64) -> String {
    if asked {
        "the start was to come from the sightings".to_string()
    } else {
        format!(
            "the log has no start pose and no ground truth to start from at {time} s (a pose, or \
             positions whose first motion gives the heading)"
        )
    }
}

/// The initial pose at `t0` (the first odometry time), its covariance and
/// where it came from, as [`Config::start`] says.
fn initial_pose(
    log: &Log,
    cfg: &Config,
    t0: f64,
) -> Result<(Vector3<f64>, SMatrix<f64, 3, 3>, StartedFrom), Error> {
    let given = match cfg.start {
        Start::Sightings => None,
        Start::Log => log.start.map(|p| (p, StartedFrom::Log)).or_else(|| {
            log.truth
                .pose_at(t0, cfg.truth_max_gap)
                .map(|p| (p, StartedFrom::Truth))
        }),
    };
    // A truth of positions only gives the heading by its direction of
    // motion, if it can.
    let given = match given {
        Some((p, StartedFrom::Truth)) if p.theta.is_nan() => {
            initial::heading_from_truth(log, cfg, t0).map(|h| {
                (
                    TruthPose {
                        theta: h.heading,
                        ..p
                    },
                    StartedFrom::TruthPosition(h),
                )
            })
        }
        other => other,
    };
    if let Some((p, from)) = given {
        let [sx, sy, mut st] = cfg.initial_std;
        if let StartedFrom::TruthPosition(h) = from {
            st = h.std;
        }
        return Ok((
            Vector3::new(p.x, p.y, wrap_angle(p.theta)),
            SMatrix::<f64, 3, 3>::from_diagonal(&Vector3::new(sx * sx, sy * sy, st * st)),
            from,
        ));
    }
    let fix = initial::from_sightings(log, cfg).map_err(|reason| Error::NoStart {
        time: t0,
        asked: cfg.start == Start::Sightings,
        reason,
    })?;
    Ok((fix.pose, fix.covariance, StartedFrom::Sightings(fix)))
}

/// The records refused before the replay: implausible noise records,
/// implausible odometry records, sightings with implausible time stamps.
fn refusals_before(log: &Log, cfg: &Config) -> Refusals {
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

/// The log's start pose against where its first sightings put the robot,
/// when the replay started from that pose and the two disagree beyond
/// [`initial::DISAGREE`]; else `None` (also when the sightings fix no
/// pose).
fn start_disagreement(log: &Log, cfg: &Config, from: &StartedFrom) -> Option<StartDisagreement> {
    let (StartedFrom::Log, Some(start)) = (from, log.start) else {
        return None;
    };
    let fix = initial::from_sightings(log, cfg).ok()?;
    let pose = Vector3::new(start.x, start.y, start.theta);
    let d2 = fix.distance2(&pose, cfg.initial_std);
    (d2 > initial::DISAGREE).then(|| StartDisagreement {
        log: [start.x, start.y, start.theta],
        sightings: [fix.pose[0], fix.pose[1], fix.pose[2]],
        sigma: d2.sqrt(),
    })
}

/// Replays `log` with `cfg`, handing each step (in canonical time order,
/// with its final estimate, and with [`Config::smooth`] its smoothed one)
/// to `sink`.
///
/// The smoother works in segments of [`smoothing_segment`] steps (see
/// [`replay_in_segments`]): its memory grows as the square root of the
/// log's length, not the length.
///
/// # Errors
/// An invalid configuration, a log with no odometry or no initial pose,
/// sightings out of arrival order, a filter failure, a smoother failure.
pub fn replay(log: &Log, cfg: &Config, sink: impl FnMut(&Step)) -> Result<Report, Error> {
    let events = log.odometry.len() + log.sightings.len();
    replay_in_segments(log, cfg, smoothing_segment(events), sink)
}

/// Steps of the smoother's segments for a log of `events` events (odometry
/// records and sightings): `sqrt(1024 events)`, at least 2^17.
///
/// Checkpointing (Griewank, "Achieving logarithmic growth of temporal and
/// spatial complexity in reverse automatic differentiation", Optimization
/// Methods and Software 1(1), 1992, in its one-level form): the forward
/// pass keeps its state every `segment` steps, and the backward pass
/// re-makes each segment's steps from it. Memory is then one segment's
/// steps (0.93 KB each: the step and the 7-state belief the smoother needs)
/// and `events / segment` checkpoints (the running filter's pending
/// events, 0.6 KB each: about 40 KB on MRCLAM with its 1 s history, at
/// most 0.6 MB with the history full at 1024 events); `segment =
/// sqrt(1024 events)` balances the two in the worst case. A log of at most
/// 2^17 events is one segment, held whole (at most 122 MB) and run once,
/// as without checkpoints. For 10^7 events: segments of 2^17 steps
/// (122 MB) and 76 checkpoints.
#[must_use]
pub fn smoothing_segment(events: usize) -> usize {
    events.saturating_mul(1024).isqrt().max(1 << 17)
}

/// [`replay`] with the smoother's segments `segment` steps long (at least
/// 1): a segment's steps are held at once, and the forward pass is re-run
/// from its checkpoints twice, once for the backward pass (last segment
/// first) and once to hand the steps over in order. A log of at most
/// `segment` steps is run once, its steps all held. The steps and the
/// report are the same to the bit whatever `segment` is (the passes repeat
/// the same operations on the same values); only
/// [`Report::smoothing_held`] and [`Report::smoothing_checkpoints`]
/// differ.
///
/// # Errors
/// As [`replay`].
pub fn replay_in_segments(
    log: &Log,
    cfg: &Config,
    segment: usize,
    mut sink: impl FnMut(&Step),
) -> Result<Report, Error> {
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
    let mut p = StateMatrix::from_diagonal(&StateVector::from([
        0.0,
        0.0,
        0.0,
        cv * cv,
        cw * cw,
        cb * cb,
        cz * cz,
    ]));
    p.fixed_view_mut::<3, 3>(0, 0).copy_from(&pose_covariance);
    let belief = Belief::new(x, p);
    let mut ekf = Ekf::default();
    if let Some(g) = cfg.gate {
        ekf = ekf
            .with_gate(ChiSquareGate::new(g).map_err(|_| Error::InvalidConfig("gate confidence"))?);
    }
    // The inflation leaves alone the calibration states the model holds
    // constant (no random walk): only the pose and what drifts may grow.
    let held: Vec<usize> = (0..4)
        .filter(|&i| cfg.calibration.walk[i] == 0.0)
        .map(|i| V_SCALE + i)
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
    let events = log.odometry.len() + log.sightings.len();
    let hold = if cfg.smooth {
        segment.min(events).saturating_add(HISTORY)
    } else {
        0
    };
    let mut engine = Engine {
        cfg: *cfg,
        log,
        t0,
        filter: Box::new(Filter::new(rules, start)),
        next_index: 0,
        tally,
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
    };
    // With the smoother: a checkpoint every `segment` steps, each
    // segment's steps re-made from its checkpoint for the backward pass
    // (smoother::flush); until the second checkpoint the steps are held,
    // so a log of one segment is run once.
    let segment = segment.max(1);
    let mut checkpoints = Vec::new();
    if cfg.smooth {
        checkpoints.push(engine.checkpoint());
    }
    loop {
        if let Some(c) = checkpoints.last()
            && engine.next_index >= c.next_index.saturating_add(segment)
        {
            checkpoints.push(engine.checkpoint());
        }
        let more = engine.advance()?;
        if !cfg.smooth {
            for step in engine.held.drain(..) {
                sink(&step);
            }
        } else if checkpoints.len() > 1 {
            engine.held.clear();
            engine.nodes.clear();
        }
        engine.report.smoothing_held = engine.report.smoothing_held.max(engine.nodes.len());
        if !more {
            break;
        }
    }
    let last = engine.filter.base().belief;
    engine.report.final_belief = pose_belief(&last);
    engine.report.calibration = calibration_of(&last);
    engine.report.summary = judged(engine.tally.summary(0), engine.compared_after_start > 0);
    if cfg.smooth {
        smoother::flush(&mut engine, checkpoints, &mut sink)?;
    }
    Ok(engine.report)
}

#[cfg(test)]
mod nis_caps {
    /// The caps are the 99.9 % points of chi-square with 2 and 1 dof.
    #[test]
    fn the_caps_are_the_chi_square_points() {
        for (cap, dof) in [(super::NIS_CAP, 2), (super::NIS_CAP_RANGE, 1)] {
            let q = locus_core::chi2::quantile(0.999, dof).unwrap();
            assert!((cap - q).abs() < 1e-9 * q, "{cap} against {q} ({dof} dof)");
        }
    }
}
