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
//! * **Correction.** Each landmark sighting is one [`RangeBearing`]
//!   correction (sensor at the robot's centre). Sightings of landmarks not
//!   in the map are counted and skipped; robot-to-robot sightings never
//!   reach the replay (the MRCLAM log splits them off).
//! * **Gating with recovery.** The running filter's chi-square gate
//!   ([`Config::gate`]) rejects
//!   outliers. A filter that has become over-confident would reject every
//!   later sighting; so after [`Config::recover_after`] consecutive
//!   rejections the covariance is multiplied by [`Config::inflation`] and
//!   the sighting is tried again (and again at each further rejection, so
//!   the inflation compounds until a sighting fits).
//! * **Ground truth.** Each event's estimate is compared with the ground
//!   truth interpolated at its time (events where the truth has a gap wider
//!   than [`Config::truth_max_gap`] or has ended are not compared), beside
//!   dead reckoning from the same start with the same inputs. The
//!   figures are accumulated by `locus-eval`'s [`Tally`] into its
//!   [`Summary`], so they read as `locus run`'s.
//!
//! Units: SI (m, rad, s); headings wrapped to (-pi, pi].

pub mod log;

use locus_core::nalgebra::{Matrix3, Vector2, Vector3};
use locus_core::{
    Belief, ChiSquareGate, Ekf, MotionModel, Recovery, Rules, RunningFilter, Track, Update,
    wrap_angle,
};
use locus_eval::{Sample, Summary, Tally};
use locus_logs::mrclam::{Odometry, TruthPose};
use locus_models::range_bearing::RangeBearing;
use locus_models::unicycle::{Unicycle, Velocities};

pub use log::{Landmark, Log, Sighting};

/// Cap on one sighting's NIS in [`Report::innovation_nll`]: the 99.9 %
/// point of chi-square with 2 degrees of freedom, `-2 ln 0.001`.
pub const NIS_CAP: f64 = 13.815_510_557_964_274;

/// Errors of the replay.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The log has no odometry: nothing to replay.
    #[error("the log has no odometry")]
    NoOdometry,
    /// The log gives no initial pose and has no ground truth at the first
    /// odometry time.
    #[error("no initial pose: the log has no start pose and no ground truth at {time} s")]
    NoStart {
        /// The first odometry time, s.
        time: f64,
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
    /// The filter failed (non-finite input, ...).
    #[error("filter step at {time} s")]
    Filter {
        /// The event's time, s.
        time: f64,
        /// The filter's error.
        #[source]
        source: locus_core::Error,
    },
}

/// Parameters of a replay.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config {
    /// Power spectral density of the forward-speed noise, m^2/s (white
    /// noise on `v`: a step of `dt` seconds gets variance `q_v / dt`, so the
    /// position variance grows by about `q_v` per second whatever the
    /// odometry rate).
    pub q_v: f64,
    /// Power spectral density of the turn-rate noise, rad^2/s.
    pub q_omega: f64,
    /// Range noise standard deviation, m.
    pub sigma_range: f64,
    /// Bearing noise standard deviation, rad.
    pub sigma_bearing: f64,
    /// Scale factor applied to the logged forward speed (1 = as logged).
    pub v_scale: f64,
    /// Scale factor applied to the logged turn rate (1 = as logged).
    pub omega_scale: f64,
    /// Chi-square gate confidence in (0, 1), or `None` for no gate.
    pub gate: Option<f64>,
    /// Consecutive gate rejections after which the covariance is inflated
    /// and the sighting retried (>= 1).
    pub recover_after: u32,
    /// Factor the covariance is multiplied by on recovery (> 1).
    pub inflation: f64,
    /// Initial standard deviations of x, y (m) and heading (rad).
    pub initial_std: [f64; 3],
    /// History kept for late sightings, s (> 0): a sighting up to this much
    /// older than the latest arrival is applied at its own time.
    pub horizon: f64,
    /// Widest spacing of two ground-truth samples to interpolate between,
    /// s; events in wider gaps are not compared.
    pub truth_max_gap: f64,
}

impl Default for Config {
    /// Values for MRCLAM-like logs (commanded velocities, a camera's range
    /// and bearing), picked by hand from two small grids (16 settings) on
    /// dataset 6, for the position RMSE of the five robots and its rise
    /// with 5 % corrupted sightings: `q_v` 0.01 m^2/s, `q_omega` 0.01
    /// rad^2/s, range 0.2 m, bearing 0.03 rad; a 99.9 % gate, inflation
    /// by 4 after 5 consecutive rejections; a 1 s history. Larger `q`
    /// (e.g. 0.1 and 0.5) let the covariance grow so wide during the
    /// logs' stretches without sightings (up to about 30 s) that corrupted
    /// sightings pass the gate.
    fn default() -> Self {
        Self {
            q_v: 0.01,
            q_omega: 0.01,
            sigma_range: 0.2,
            sigma_bearing: 0.03,
            v_scale: 1.0,
            omega_scale: 1.0,
            gate: Some(0.999),
            recover_after: 5,
            inflation: 4.0,
            initial_std: [0.05, 0.05, 0.05],
            horizon: 1.0,
            truth_max_gap: 0.25,
        }
    }
}

impl Config {
    /// Checks every value's range.
    ///
    /// # Errors
    /// [`Error::InvalidConfig`] naming the first bad value.
    pub fn validate(&self) -> Result<(), Error> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        let checks = [
            (positive(self.q_v), "q_v must be finite and > 0"),
            (positive(self.q_omega), "q_omega must be finite and > 0"),
            (
                positive(self.sigma_range),
                "sigma_range must be finite and > 0",
            ),
            (
                positive(self.sigma_bearing),
                "sigma_bearing must be finite and > 0",
            ),
            (positive(self.v_scale), "v_scale must be finite and > 0"),
            (
                positive(self.omega_scale),
                "omega_scale must be finite and > 0",
            ),
            (
                self.gate.is_none_or(|g| g > 0.0 && g < 1.0),
                "gate confidence must be in (0, 1)",
            ),
            (self.recover_after >= 1, "recover_after must be >= 1"),
            (
                self.inflation.is_finite() && self.inflation > 1.0,
                "inflation must be finite and > 1",
            ),
            (
                self.initial_std.iter().all(|s| positive(*s)),
                "initial standard deviations must be finite and > 0",
            ),
            (positive(self.horizon), "horizon must be finite and > 0"),
            (
                positive(self.truth_max_gap),
                "truth_max_gap must be finite and > 0",
            ),
        ];
        match checks.iter().find(|(ok, _)| !ok) {
            Some((_, what)) => Err(Error::InvalidConfig(what)),
            None => Ok(()),
        }
    }
}

/// What happened to a sighting.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SightingOutcome {
    /// Corrected the belief (NIS of the applied correction; `recovered`:
    /// applied only after the covariance was inflated).
    Applied {
        /// NIS of the correction (2 dof).
        nis: f64,
        /// Whether the covariance was inflated before it was applied.
        recovered: bool,
    },
    /// Rejected by the gate (NIS against the belief it was tried on).
    Gated {
        /// NIS (2 dof).
        nis: f64,
    },
    /// The landmark is not in the map.
    NotInMap,
    /// The model predicts no measurement (the robot on the landmark).
    NoMeasurement,
}

/// The kind of an event.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EventKind {
    /// An odometry record (the input from now on, after scaling).
    Odometry {
        /// Forward speed as logged, m/s.
        v: f64,
        /// Turn rate as logged, rad/s.
        omega: f64,
    },
    /// A landmark sighting.
    Sighting {
        /// The sighting.
        sighting: Sighting,
        /// What the filter did with it.
        outcome: SightingOutcome,
    },
}

/// One replayed event with the final estimate after it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// Index in canonical (time) order, from 0.
    pub index: usize,
    /// The event's time, s (as in the log).
    pub time: f64,
    /// Time since the first odometry record, s.
    pub elapsed: f64,
    /// The event.
    pub kind: EventKind,
    /// The belief after the event.
    pub belief: Belief<f64, 3>,
    /// Dead reckoning (odometry alone) `[x, y, theta]` at this time.
    pub dead_reckoning: [f64; 3],
    /// Ground truth interpolated at this time, if covered.
    pub truth: Option<TruthPose>,
}

impl Step {
    /// The CSV header of [`Step::csv_row`] (units in the names).
    #[must_use]
    pub fn csv_header() -> &'static str {
        "index,time_s,elapsed_s,event,landmark,range_m,bearing_rad,nis,applied,\
         x_m,y_m,theta_rad,var_x_m2,cov_xy_m2,cov_xtheta_mrad,var_y_m2,cov_ytheta_mrad,\
         var_theta_rad2,odo_x_m,odo_y_m,odo_theta_rad,true_x_m,true_y_m,true_theta_rad"
    }

    /// The step as one CSV line (empty fields where not applicable).
    #[must_use]
    pub fn csv_row(&self) -> String {
        let (event, lm, r, b, nis, applied) = match self.kind {
            EventKind::Odometry { .. } => (
                "odometry",
                String::new(),
                String::new(),
                String::new(),
                String::new(),
                String::new(),
            ),
            EventKind::Sighting { sighting, outcome } => {
                let (nis, applied) = match outcome {
                    SightingOutcome::Applied { nis, recovered } => {
                        (nis.to_string(), if recovered { "recovered" } else { "1" })
                    }
                    SightingOutcome::Gated { nis } => (nis.to_string(), "0"),
                    SightingOutcome::NotInMap => (String::new(), "not-in-map"),
                    SightingOutcome::NoMeasurement => (String::new(), "no-measurement"),
                };
                (
                    "sighting",
                    sighting.landmark.to_string(),
                    sighting.range.to_string(),
                    sighting.bearing.to_string(),
                    nis,
                    applied.to_string(),
                )
            }
        };
        let x = &self.belief.x;
        let p = &self.belief.p;
        let d = &self.dead_reckoning;
        let truth = self.truth.map_or_else(
            || ",,".to_string(),
            |t| format!("{},{},{}", t.x, t.y, t.theta),
        );
        format!(
            "{},{},{},{event},{lm},{r},{b},{nis},{applied},{},{},{},{},{},{},{},{},{},{},{},{},{truth}",
            self.index,
            self.time,
            self.elapsed,
            x[0],
            x[1],
            x[2],
            p[(0, 0)],
            p[(0, 1)],
            p[(0, 2)],
            p[(1, 1)],
            p[(1, 2)],
            p[(2, 2)],
            d[0],
            d[1],
            d[2]
        )
    }

    /// The figures `locus run` summarises and draws, if the step has a
    /// ground truth to compare with (NEES against it, 3 dof).
    #[must_use]
    pub fn sample(&self) -> Option<Sample> {
        let t = self.truth?;
        let x = &self.belief.x;
        let e = Vector3::new(t.x - x[0], t.y - x[1], wrap_angle(t.theta - x[2]));
        let nees = locus_eval::nees(&e, &self.belief.p);
        let mut covariance = [[0.0; 3]; 3];
        for (i, row) in covariance.iter_mut().enumerate() {
            for (j, c) in row.iter_mut().enumerate() {
                *c = self.belief.p[(i, j)];
            }
        }
        let d = &self.dead_reckoning;
        let (measured, correction) = match self.kind {
            EventKind::Odometry { .. } => (false, None),
            EventKind::Sighting { outcome, .. } => match outcome {
                SightingOutcome::Applied { nis, .. } => (true, Some((nis, 2, true))),
                SightingOutcome::Gated { nis } => (true, Some((nis, 2, false))),
                SightingOutcome::NotInMap | SightingOutcome::NoMeasurement => (true, None),
            },
        };
        Some(Sample {
            step: self.index,
            time: self.elapsed,
            truth: [t.x, t.y, 0.0],
            truth_heading: t.theta,
            estimate: [x[0], x[1], 0.0],
            estimate_heading: x[2],
            heading_error: e[2],
            covariance,
            var_z: 0.0,
            odometry: Some(([d[0], d[1], 0.0], wrap_angle(t.theta - d[2]))),
            nees,
            nees_dof: 3,
            correction,
            measured,
        })
    }
}

/// What a replay did, besides the per-step figures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Report {
    /// Errors against the ground truth (over the steps it covers), as for
    /// `locus run`: `readings` counts the compared sightings,
    /// `associated` those that reached the filter, `corrections` those
    /// applied.
    pub summary: Summary,
    /// Events replayed (odometry records + landmark sightings).
    pub steps: usize,
    /// Events compared with ground truth.
    pub compared: usize,
    /// Odometry records.
    pub odometry: usize,
    /// Landmark sightings in the log (all of them, compared or not).
    pub sightings: usize,
    /// Sightings applied (including after recovery).
    pub applied: usize,
    /// Sightings rejected by the gate.
    pub gated: usize,
    /// Covariance inflations (recoveries: at each, the sighting was retried).
    pub inflations: usize,
    /// Sightings applied only after an inflation.
    pub recovered: usize,
    /// Sightings of landmarks not in the map.
    pub not_in_map: usize,
    /// Sightings where the model predicts no measurement.
    pub no_measurement: usize,
    /// Robot-to-robot sightings left out by the log.
    pub robot_sightings: usize,
    /// Sightings of unknown targets left out by the log.
    pub unknown_sightings: usize,
    /// Sightings that arrived out of order and were applied at their own
    /// time by re-running the history.
    pub late: usize,
    /// Sightings older than the history (or than the first odometry),
    /// not applied.
    pub too_late: usize,
    /// Negative log-likelihood of the innovations (natural log, without
    /// the constant `ln 2 pi` per sighting): the sum over the sightings
    /// that reached the filter of `(ln det S + min(NIS, NIS_CAP)) / 2`, `S`
    /// and the NIS against the belief before the sighting. The objective
    /// `locus tune` minimises; the cap keeps gross outliers from dominating.
    pub innovation_nll: f64,
    /// The final belief.
    pub final_belief: Belief<f64, 3>,
}

impl Report {
    /// Share of the sightings that reached the filter which the gate
    /// rejected (0 if none reached it).
    #[must_use]
    #[allow(clippy::cast_precision_loss)]
    pub fn gated_share(&self) -> f64 {
        let n = self.applied + self.gated;
        if n == 0 {
            0.0
        } else {
            self.gated as f64 / n as f64
        }
    }
}

/// An event of the canonical timeline.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Event {
    Odometry(Odometry),
    Sighting(Sighting),
}

impl Event {
    fn time(&self) -> f64 {
        match self {
            Event::Odometry(o) => o.time,
            Event::Sighting(s) => s.time,
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
            (Event::Odometry(_), Event::Odometry(_)) => Ordering::Equal,
            (Event::Odometry(_), Event::Sighting(_)) => Ordering::Less,
            (Event::Sighting(_), Event::Odometry(_)) => Ordering::Greater,
            (Event::Sighting(a), Event::Sighting(b)) => a
                .landmark
                .cmp(&b.landmark)
                .then(a.range.total_cmp(&b.range))
                .then(a.bearing.total_cmp(&b.bearing)),
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

type Filter = RunningFilter<f64, 3, HISTORY, Entry, Carried>;
type State = Track<f64, 3, Carried>;

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
        let model = Unicycle::new(cfg.q_v / dt, cfg.q_omega / dt);
        let c = track.extra;
        let u = Velocities {
            v: c.v,
            omega: c.omega,
            dt,
        };
        track.predict(&rules.ekf, &model, &u)?;
        track.extra.dead = model.f(&c.dead, &u, &Vector2::zeros());
        track.time = t;
    }
    entry.inflations = 0;
    entry.nll = 0.0;
    entry.outcome = match entry.event {
        Event::Odometry(o) => {
            track.extra.v = o.v * cfg.v_scale;
            track.extra.omega = o.omega * cfg.omega_scale;
            None
        }
        Event::Sighting(z) => Some(match log.landmark(z.landmark) {
            None => SightingOutcome::NotInMap,
            Some(l) => {
                let model = RangeBearing::new(
                    Vector2::new(l.x, l.y),
                    Vector2::zeros(),
                    cfg.sigma_range,
                    cfg.sigma_bearing,
                );
                let update = track.correct(rules, &model, &Vector2::new(z.range, z.bearing))?;
                if let Some(first) = update.first_attempt() {
                    entry.nll = 0.5 * first.s.determinant().ln() + 0.5 * first.nis.min(NIS_CAP);
                }
                entry.inflations = u32::from(update.inflated());
                match update {
                    Update::Applied { correction, first } => SightingOutcome::Applied {
                        nis: correction.nis,
                        recovered: first.is_some(),
                    },
                    Update::Gated { correction, .. } => SightingOutcome::Gated {
                        nis: correction.nis,
                    },
                    Update::NoMeasurement => SightingOutcome::NoMeasurement,
                }
            }
        }),
    };
    Ok(())
}

/// The replay engine: the running filter and what the report needs.
struct Engine<'a, F: FnMut(&Step)> {
    cfg: Config,
    log: &'a Log,
    t0: f64,
    filter: Box<Filter>,
    next_index: usize,
    tally: Tally,
    report: Report,
    sink: F,
}

impl<F: FnMut(&Step)> Engine<'_, F> {
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
        let (_, evicted) = self
            .filter
            .insert(entry, |rules, track, e| apply(cfg, log, rules, track, e))
            .map_err(|source| Error::Filter {
                time: event.time(),
                source,
            })?;
        if let Some(e) = evicted {
            self.emit(&e.0, &e.1);
        }
        Ok(())
    }

    /// Makes final the events older than `limit` (s).
    fn finalise_before(&mut self, limit: f64) {
        while let Some((entry, after)) = self.filter.pop_final_before(limit) {
            self.emit(&entry, &after);
        }
    }

    fn emit(&mut self, e: &Entry, after: &State) {
        let kind = match e.event {
            Event::Odometry(o) => {
                self.report.odometry += 1;
                EventKind::Odometry {
                    v: o.v,
                    omega: o.omega,
                }
            }
            Event::Sighting(sighting) => {
                let outcome = e.outcome.unwrap_or(SightingOutcome::NoMeasurement);
                let r = &mut self.report;
                r.sightings += 1;
                match outcome {
                    SightingOutcome::Applied { recovered, .. } => {
                        r.applied += 1;
                        r.recovered += usize::from(recovered);
                    }
                    SightingOutcome::Gated { .. } => r.gated += 1,
                    SightingOutcome::NotInMap => r.not_in_map += 1,
                    SightingOutcome::NoMeasurement => r.no_measurement += 1,
                }
                EventKind::Sighting { sighting, outcome }
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
            belief: after.belief,
            dead_reckoning: [d[0], d[1], d[2]],
            truth: self.log.truth.pose_at(time, self.cfg.truth_max_gap),
        };
        self.next_index += 1;
        self.report.steps += 1;
        if let Some(sample) = step.sample() {
            self.report.compared += 1;
            self.tally.push(&sample);
        }
        (self.sink)(&step);
    }
}

/// Replays `log` with `cfg`, handing each step (in canonical time order,
/// with its final estimate) to `sink`.
///
/// # Errors
/// An invalid configuration, a log with no odometry or no initial pose,
/// sightings out of arrival order, a filter failure.
pub fn replay(log: &Log, cfg: &Config, sink: impl FnMut(&Step)) -> Result<Report, Error> {
    cfg.validate()?;
    let first = log.odometry.first().ok_or(Error::NoOdometry)?;
    let t0 = first.time;
    let start = match log.start {
        Some(p) => p,
        None => log
            .truth
            .pose_at(t0, cfg.truth_max_gap)
            .ok_or(Error::NoStart { time: t0 })?,
    };
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
    let x = Vector3::new(start.x, start.y, wrap_angle(start.theta));
    let [sx, sy, st] = cfg.initial_std;
    let belief = Belief::new(
        x,
        Matrix3::from_diagonal(&Vector3::new(sx * sx, sy * sy, st * st)),
    );
    let mut ekf = Ekf::default();
    if let Some(g) = cfg.gate {
        ekf = ekf
            .with_gate(ChiSquareGate::new(g).map_err(|_| Error::InvalidConfig("gate confidence"))?);
    }
    let recovery = Recovery::new(cfg.recover_after, cfg.inflation)
        .map_err(|_| Error::InvalidConfig("recovery"))?;
    let tally = Tally::new(3).map_err(|_| Error::InvalidConfig("NEES degrees of freedom"))?;
    let start = Track::new(
        belief,
        t0,
        Carried {
            v: 0.0,
            omega: 0.0,
            dead: x,
        },
    );
    let mut engine = Engine {
        cfg: *cfg,
        log,
        t0,
        filter: Box::new(Filter::new(Rules::new(ekf).with_recovery(recovery), start)),
        next_index: 0,
        tally,
        report: Report {
            summary: Tally::new(3)
                .map_err(|_| Error::InvalidConfig("NEES degrees of freedom"))?
                .summary(0),
            steps: 0,
            compared: 0,
            odometry: 0,
            sightings: 0,
            applied: 0,
            gated: 0,
            inflations: 0,
            recovered: 0,
            not_in_map: 0,
            no_measurement: 0,
            robot_sightings: log.robot_sightings,
            unknown_sightings: log.unknown_sightings,
            late: 0,
            too_late: 0,
            innovation_nll: 0.0,
            final_belief: belief,
        },
        sink,
    };
    let mut odometry = log.odometry.iter().peekable();
    let mut sightings = log.sightings.iter().peekable();
    loop {
        let take_odometry = match (odometry.peek(), sightings.peek()) {
            (Some(o), Some(s)) => o.time <= s.arrival,
            (Some(_), None) => true,
            (None, Some(_)) => false,
            (None, None) => break,
        };
        if take_odometry {
            if let Some(o) = odometry.next() {
                engine.finalise_before(o.time - cfg.horizon);
                engine.insert(Event::Odometry(*o))?;
            }
        } else if let Some(s) = sightings.next() {
            engine.finalise_before(s.arrival - cfg.horizon);
            // With a delay within the horizon, every finalised event is
            // older than the sighting, so the base is never re-run.
            if s.time <= engine.filter.base().time {
                engine.report.too_late += 1;
                continue;
            }
            let late = s.time < engine.filter.time();
            engine.insert(Event::Sighting(*s))?;
            engine.report.late += usize::from(late);
        }
    }
    engine.finalise_before(f64::INFINITY);
    engine.report.final_belief = engine.filter.base().belief;
    engine.report.summary = engine.tally.summary(0);
    Ok(engine.report)
}
