//! The localisation and control host for any robot that speaks the
//! protocol (`docs/protocol.md`).
//!
//! The filter is paper 001's [`Localiser`] on the link's 32-bit wrapping
//! encoder counts, built from a [`LocaliserConfig`] (wheelbase, encoder, IR
//! pair, `Q`, `R`, gate, initial belief); the IR pair is associated with
//! the arena walls the caller gives, and the path controller
//! ([`FollowPath::square`]) drives the laps. The host knows nothing of the
//! robot beyond the protocol: a simulator (`locus_simlink`) or a
//! real robot.
//!
//! # Loop
//! 1. Send a zero-speed command (ack [`NO_ACK`](locus_link::NO_ACK)) every `resend` until the
//!    first telemetry packet arrives.
//! 2. For each datagram from the robot's address, [`Host::receive`]:
//!    decode and classify it ([`Receiver`]). Dropped classes (duplicate,
//!    late, corrupt, malformed, suspect) only count. The first applied
//!    packet sets the reference encoder counts and robot time. Every later
//!    one is first checked against the [`Limits`](crate::plausible::Limits) (robot time advancing and
//!    covered by its packets, wheel travels the top speed can explain, IR
//!    readings in range); an implausible one is refused whole and counted,
//!    and the belief is kept. A plausible one: the count differences give
//!    the wheel travels since the last accepted packet; standing for `g + 1`
//!    packets they are split into `g + 1` equal predictions (at most
//!    `MAX_JUMP + 1`: bounded work per packet; [`Localiser::counts`]); the
//!    IR reading, if any, is associated with a wall and corrects the filter
//!    behind its gate ([`Localiser::ir`]); the clock estimator gets
//!    (robot timestamp, receive time). A filter error is counted and the
//!    belief kept. [`RESYNC_AFTER`] refused packets in a row that agree with
//!    each other (a robot whose counters were reset) become the new
//!    reference, so the host is never locked out.
//! 3. The path controller maps the estimate to a body twist, turned into
//!    wheel speeds; a command packet carrying them and acknowledging the
//!    packet is sent. When the laps are done the host
//!    stops sending (the robot's watchdog stops the wheels) and keeps
//!    receiving and counting until the robot has been quiet for `quiet`.
//!
//! Files: `config.rs` ([`HostConfig`]), this one (the per-packet core,
//! [`Host`]), `run.rs` (the loops over a [`Transport`](crate::transport::Transport):
//! [`run_host`], [`run_host_over`], [`run_host_live`]).

mod config;
mod run;

pub use config::{COUNTER_BITS, HostConfig};
use config::{control_ok, localiser_error, within_settings};
pub use run::{HostReport, LiveTick, run_host, run_host_live, run_host_over};

use locus_control::{Controller, FollowPath, Twist, wheel_speeds};
use locus_core::{Belief, Update};
use locus_link::clock::ClockFit;
use locus_link::receiver::{MAX_JUMP, RESYNC_AFTER};
use locus_link::{ClockEstimator, Counters, Receiver, Status, Telemetry};
use locus_models::{CorrectionDetail, IrCorrection, IrOutcome, Localiser, LocaliserConfig};

use crate::Error;
use crate::plausible::Implausible;

/// Buckets in the clock estimator's window.
const CLOCK_WINDOW: usize = 64;

/// The host's state after one applied telemetry packet.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostStep {
    /// Sequence of the packet.
    pub sequence: u32,
    /// Robot timestamp of the packet (s).
    pub robot_time: f64,
    /// Sequence numbers skipped before it (predicted through).
    pub skipped: u32,
    /// EKF estimate `[x, y, theta]` (m, m, rad) after the packet.
    pub estimate: [f64; 3],
    /// EKF covariance diagonal (m^2, m^2, rad^2).
    pub variance: [f64; 3],
    /// EKF covariance of `[x, y, theta]` (m^2, m rad, rad^2).
    pub covariance: [[f64; 3]; 3],
    /// IR reading `[d_s1, d_s2]` (m), if any.
    pub ir: Option<[f32; 2]>,
    /// Whether an IR correction was applied (associated and gated in).
    pub corrected: bool,
    /// NIS of the IR correction tried on this packet (applied or gated
    /// out), if a reading was associated with a wall.
    pub nis: Option<f64>,
    /// Its innovation `[m, rad]` (wall distance, wall angle).
    pub innovation: Option<[f64; 2]>,
    /// Wheel speeds sent `[right, left]` (m/s); `None` once the path is
    /// done.
    pub command: Option<[f32; 2]>,
}

/// Who chooses the wheel speeds a [`Host`] sends.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Drive {
    /// The path controller (the default).
    Path,
    /// Nobody: zero wheel speeds (the robot stays connected and localised).
    Stopped,
    /// A body twist from an operator (keyboard), clamped to the
    /// controller's `v_ref` and `w_ref`, until the host time `until` (s,
    /// the clock of [`Host::receive`]); then back to what drove before.
    Teleop {
        /// The twist (`done` is false).
        twist: Twist,
        /// Host time after which it lapses (s).
        until: f64,
    },
}

/// What one datagram did to the host.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// It did not decode (counted as corrupt or malformed).
    Undecodable,
    /// It decoded but was dropped: duplicate, late or suspect by its
    /// sequence number (the status), or refused for its content.
    Dropped(Dropped),
    /// It was applied.
    Applied(HostStep),
}

/// Why a decoded packet was dropped.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Dropped {
    /// By its sequence number: duplicate, late or suspect.
    Sequence(Status),
    /// By its content.
    Implausible(Implausible),
}

/// The last accepted telemetry packet: the reference of the next.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Reference {
    sequence: u32,
    timestamp_us: u64,
    counts: [u32; 2],
}

impl Reference {
    fn of(t: &Telemetry) -> Self {
        Self {
            sequence: t.sequence,
            timestamp_us: t.timestamp_us,
            counts: t.counts,
        }
    }
}

/// The host's per-packet logic, without a socket: receiver, limits,
/// localiser, clock estimator and path controller. [`run_host`] feeds it
/// datagrams; a test can feed it any bytes.
#[derive(Debug)]
pub struct Host {
    cfg: HostConfig,
    localiser: Localiser<f64>,
    controller: FollowPath<4>,
    receiver: Receiver,
    clock: ClockEstimator<CLOCK_WINDOW>,
    /// The last accepted packet.
    reference: Option<Reference>,
    /// The newest refused packet and how many refused packets in a row,
    /// each plausible against the one before, ended with it.
    refused: Option<(Reference, u32)>,
    /// Times the reference moved to a run of refused packets.
    resync: u64,
    laps: usize,
    done: bool,
    /// Whether the path controller is paused (zero speeds sent).
    stopped: bool,
    /// The operator's twist and the host time it lapses at.
    teleop: Option<(Twist, f64)>,
    corrections: u64,
    /// IR readings associated with a wall and tried (applied or gated out).
    tried: u64,
    /// The details of the last tried correction.
    last_correction: Option<CorrectionDetail>,
    filter_errors: u64,
    estimates: Vec<(u32, [f64; 3])>,
}

impl Host {
    /// A host for `cfg`, at the filter's initial belief.
    ///
    /// # Errors
    /// [`Error::Config`] naming the first invalid value.
    pub fn new(cfg: &HostConfig) -> Result<Self, Error> {
        cfg.validate()?;
        Ok(Self {
            cfg: *cfg,
            localiser: cfg.localiser.localiser()?,
            controller: FollowPath::square(cfg.control),
            receiver: Receiver::new(),
            clock: ClockEstimator::new(cfg.clock_bucket),
            reference: None,
            refused: None,
            resync: 0,
            laps: 0,
            done: false,
            stopped: false,
            teleop: None,
            corrections: 0,
            tried: 0,
            last_correction: None,
            filter_errors: 0,
            estimates: Vec::new(),
        })
    }

    /// The filter's belief now.
    pub fn belief(&self) -> &locus_core::Belief<f64, 3> {
        self.localiser.belief()
    }

    /// The receiver's counters; `resync` also counts the times a run of
    /// refused packets became the reference.
    pub fn counters(&self) -> Counters {
        let mut c = self.receiver.counters();
        c.resync += self.resync;
        c
    }

    /// Filter errors (the belief was kept).
    pub fn filter_errors(&self) -> u64 {
        self.filter_errors
    }

    /// Whether the laps are done (no more commands).
    pub fn done(&self) -> bool {
        self.done
    }

    /// The configuration in use (with the values of the setters below).
    pub fn config(&self) -> &HostConfig {
        &self.cfg
    }

    /// The clock estimator's fit now (`robot = offset + (1 + drift) host`),
    /// `None` before it has two buckets.
    pub fn clock(&self) -> Option<ClockFit> {
        self.clock.estimate()
    }

    /// IR corrections applied so far.
    pub fn corrections(&self) -> u64 {
        self.corrections
    }

    /// IR readings associated with a wall and tried so far (applied or
    /// gated out): [`Host::last_correction`] is the newest of them.
    pub fn corrections_tried(&self) -> u64 {
        self.tried
    }

    /// The details of the last correction tried (paper 001 eq. 14-22: the
    /// belief before the packet's prediction, its wheel travels, `x-`,
    /// `P-`, `z`, `h(x-)`, `H`, `S`, `K`, the innovation, the gate's
    /// decision, `x+`, `P+`), for a page to show step by step; `None`
    /// before the first.
    pub fn last_correction(&self) -> Option<&CorrectionDetail> {
        self.last_correction.as_ref()
    }

    /// Laps of the path completed.
    pub fn laps(&self) -> usize {
        self.laps
    }

    /// The filter's process noise `Q11` (m^2 per step), `Q22` (rad^2 per
    /// step) and the IR pair's measurement noise `R11`, `R22` (m^2), from
    /// the next packet on. The belief is kept: only the next predictions
    /// and corrections use the new values.
    ///
    /// # Errors
    /// [`Error::Config`] if a value is not finite and > 0,
    /// [`Error::OutOfRange`] if outside its range of
    /// [`locus_models::settings`]; nothing changes.
    pub fn set_noise(&mut self, q11: f64, q22: f64, r11: f64, r22: f64) -> Result<(), Error> {
        self.retune(LocaliserConfig {
            q11,
            q22,
            r11,
            r22,
            ..self.cfg.localiser
        })
    }

    /// The chi-square gate of the IR corrections: its confidence in
    /// (0, 1), or `None` for no gate; from the next packet on.
    ///
    /// # Errors
    /// [`Error::Config`] if the confidence is outside (0, 1),
    /// [`Error::OutOfRange`] if above [`locus_models::settings::GATE`];
    /// nothing changes.
    pub fn set_gate(&mut self, confidence: Option<f64>) -> Result<(), Error> {
        self.retune(LocaliserConfig {
            gate_confidence: confidence,
            ..self.cfg.localiser
        })
    }

    /// Whether the filter uses the IR readings (`false`: odometry only),
    /// from the next packet on.
    pub fn set_use_ir(&mut self, on: bool) {
        self.cfg.use_ir = on;
    }

    /// The path controller's parameters (reference speeds, gains,
    /// tolerances), from the next command on; the controller keeps its
    /// place on the path.
    ///
    /// # Errors
    /// [`Error::Config`] if a value is not finite and > 0,
    /// [`Error::OutOfRange`] if a speed or gain is outside its range of
    /// [`locus_models::settings`]; nothing changes.
    pub fn set_control(&mut self, control: locus_control::Config) -> Result<(), Error> {
        if !control_ok(&control) {
            return Err(Error::Config("control values must be finite and > 0"));
        }
        within_settings(&self.cfg.localiser, &control)?;
        self.controller.set_config(control);
        self.cfg.control = control;
        Ok(())
    }

    /// Pauses (`true`: zero wheel speeds from the next command on; the
    /// link stays up and the filter keeps running) or resumes the path
    /// controller from where the estimate is.
    pub fn set_stopped(&mut self, stopped: bool) {
        self.stopped = stopped;
    }

    /// An operator's body twist `v` (m/s), `w` (rad/s), clamped to the
    /// controller's `v_ref` and `w_ref`, sent as wheel speeds instead of
    /// the controller's until host time `until` (s, the clock of
    /// [`Host::receive`]): an operator that goes away (a lost key-up)
    /// stops steering at `until`. Repeating the call extends it.
    ///
    /// # Errors
    /// [`Error::Config`] if `v`, `w` or `until` is not finite; nothing
    /// changes.
    pub fn set_teleop(&mut self, v: f64, w: f64, until: f64) -> Result<(), Error> {
        if !(v.is_finite() && w.is_finite() && until.is_finite()) {
            return Err(Error::Config("teleoperation v, w and until must be finite"));
        }
        let c = &self.cfg.control;
        let twist = Twist {
            v: v.clamp(-c.v_ref, c.v_ref),
            w: w.clamp(-c.w_ref, c.w_ref),
            done: false,
        };
        self.teleop = Some((twist, until));
        Ok(())
    }

    /// Ends the operator's twist now: back to the controller (or zero
    /// speeds if stopped).
    pub fn clear_teleop(&mut self) {
        self.teleop = None;
    }

    /// Who chooses the next command at host time `host_time` (s).
    pub fn drive(&self, host_time: f64) -> Drive {
        match self.teleop {
            Some((twist, until)) if host_time <= until => Drive::Teleop { twist, until },
            _ if self.stopped => Drive::Stopped,
            _ => Drive::Path,
        }
    }

    /// Applies a changed localiser configuration to the running filter:
    /// its rules (gate), drive model (`Q`) and association (`R`); the
    /// belief, odometer reference and NIS monitor are kept.
    fn retune(&mut self, l: LocaliserConfig<f64>) -> Result<(), Error> {
        let fresh = l.localiser().map_err(localiser_error)?;
        within_settings(&l, &self.cfg.control)?;
        self.localiser.filter.set_rules(*fresh.filter.rules());
        self.localiser.model = fresh.model;
        self.localiser.ir = fresh.ir;
        self.cfg.localiser = l;
        Ok(())
    }

    /// One datagram from the robot, received at `host_time` (s since the
    /// run began). Work per call is bounded: at most `MAX_JUMP + 1`
    /// predictions.
    #[allow(clippy::cast_possible_truncation, clippy::cast_precision_loss)]
    pub fn receive(&mut self, bytes: &[u8], host_time: f64) -> Outcome {
        let Ok((t, status)) = self.receiver.receive_telemetry(bytes) else {
            return Outcome::Undecodable;
        };
        let before = *self.localiser.belief();
        let travel = match status {
            Status::Applied { .. } | Status::Resynchronised => {
                match self.reference.filter(|_| status != Status::Resynchronised) {
                    None => {
                        self.start_stream(&t);
                        None
                    }
                    Some(r) => match self.accept(&t, &r) {
                        Ok(u) => Some(u),
                        Err(why) => return Outcome::Dropped(Dropped::Implausible(why)),
                    },
                }
            }
            Status::Duplicate | Status::Late | Status::Suspect => {
                return Outcome::Dropped(Dropped::Sequence(status));
            }
        };
        let robot_time = t.timestamp_us as f64 * 1e-6;
        self.clock.push(robot_time, host_time);
        let (corrected, tried) = match (t.ir.filter(|_| self.cfg.use_ir), travel) {
            (Some(ir), Some(u)) => self.correct(ir, &before, u),
            _ => (false, None),
        };
        self.corrections += u64::from(corrected);
        let x = self.localiser.belief().x;
        self.estimates.push((t.sequence, [x[0], x[1], x[2]]));
        let command = self.command([x[0], x[1], x[2]], host_time);
        let p = self.localiser.belief().p;
        Outcome::Applied(HostStep {
            sequence: t.sequence,
            robot_time,
            skipped: match status {
                Status::Applied { skipped } => skipped,
                _ => 0,
            },
            estimate: [x[0], x[1], x[2]],
            variance: [p[(0, 0)], p[(1, 1)], p[(2, 2)]],
            covariance: core::array::from_fn(|i| core::array::from_fn(|j| p[(i, j)])),
            ir: t.ir,
            corrected,
            nis: tried.map(|(nis, _)| nis),
            innovation: tried.map(|(_, y)| y),
            command,
        })
    }

    /// The IR correction of readings `[ds1, ds2]` (m), after predicting
    /// from `before` with wheel travels `u` (m): whether it was applied,
    /// and the NIS and innovation tried. Keeps its details.
    fn correct(
        &mut self,
        [ds1, ds2]: [f32; 2],
        before: &Belief<f64, 3>,
        u: [f64; 2],
    ) -> (bool, Option<(f64, [f64; 2])>) {
        let prior = *self.localiser.belief();
        match self
            .localiser
            .ir(&self.cfg.walls, [f64::from(ds1), f64::from(ds2)])
        {
            Ok(IrOutcome::Associated {
                observation,
                update,
            }) => {
                let c = IrCorrection {
                    observation,
                    z: observation.z(),
                    prior,
                    update,
                };
                let gate = self.localiser.filter.rules().ekf.gate;
                if let Some(d) = c.detail(before, u, gate.map(|g| g.threshold(2))) {
                    self.tried += 1;
                    self.last_correction = Some(d);
                }
                let tried = nis_and_innovation(&update);
                (update.applied(), tried)
            }
            Ok(IrOutcome::Unassociated) => (false, None),
            Err(_) => {
                self.filter_errors += 1;
                (false, None)
            }
        }
    }

    /// The first packet of a stream (the first, or after the receiver
    /// re-anchored): it only sets the references.
    fn start_stream(&mut self, t: &Telemetry) {
        if self.reference.is_some() {
            self.clock = ClockEstimator::new(self.cfg.clock_bucket);
        }
        self.localiser.set_reference_counts(t.counts);
        self.reference = Some(Reference::of(t));
        self.refused = None;
    }

    /// Checks `t` against the reference `r` and predicts through it (its
    /// wheel travels `[d1, d2]` in m), or refuses it (recounted as
    /// implausible; the belief is kept).
    fn accept(&mut self, t: &Telemetry, r: &Reference) -> Result<[f64; 2], Implausible> {
        let packets = t.sequence.wrapping_sub(r.sequence);
        let travel = match self.check(t, r, packets) {
            Ok(travel) => travel,
            Err(why) => {
                self.receiver.refuse_applied();
                let run = match self.refused {
                    Some((prev, run))
                        if self
                            .check(t, &prev, t.sequence.wrapping_sub(prev.sequence))
                            .is_ok() =>
                    {
                        run + 1
                    }
                    _ => 1,
                };
                if run >= RESYNC_AFTER {
                    // The robot's counts or clock moved for good: follow them.
                    self.resync += 1;
                    self.start_stream(t);
                } else {
                    self.refused = Some((Reference::of(t), run));
                }
                return Err(why);
            }
        };
        self.refused = None;
        self.reference = Some(Reference::of(t));
        // Bounded work: a stream of refused packets cannot make the split
        // longer than a plausible sequence jump.
        let parts = packets.min(MAX_JUMP + 1);
        if self.localiser.counts(t.counts, parts).is_err() {
            self.filter_errors += 1;
        }
        Ok(travel)
    }

    /// `t`'s content against the reference `r`, `packets` sequence numbers
    /// before it; the wheel travels `[d1, d2]` (m) since `r` if plausible.
    #[allow(clippy::cast_precision_loss)]
    fn check(&self, t: &Telemetry, r: &Reference, packets: u32) -> Result<[f64; 2], Implausible> {
        let elapsed = if t.timestamp_us >= r.timestamp_us {
            (t.timestamp_us - r.timestamp_us) as f64 * 1e-6
        } else {
            -((r.timestamp_us - t.timestamp_us) as f64 * 1e-6)
        };
        let odometer = self.localiser.odometer();
        let travel = odometer
            .with_reference(r.counts)
            .travel_since(t.counts)
            .map_or([0.0; 2], |u| [u.d1, u.d2]);
        self.cfg
            .limits
            .check_packet(elapsed, packets, travel, odometer.wheel().quantum(), t.ir)?;
        Ok(travel)
    }

    /// The wheel speeds `[right, left]` (m/s) for the estimate at host
    /// time `host_time`: the operator's twist while it lasts, zero when
    /// stopped, else the path controller's; `None` once the laps are done.
    #[allow(clippy::cast_possible_truncation)]
    fn command(&mut self, [x, y, theta]: [f64; 3], host_time: f64) -> Option<[f32; 2]> {
        if self.done {
            return None;
        }
        let speeds = |twist: Twist, b: f64| {
            let (v1, v2) = wheel_speeds(twist, b);
            [v1 as f32, v2 as f32]
        };
        match self.drive(host_time) {
            Drive::Teleop { twist, .. } => {
                return Some(speeds(twist, self.cfg.localiser.wheelbase));
            }
            Drive::Stopped => {
                self.teleop = None;
                return Some([0.0, 0.0]);
            }
            Drive::Path => self.teleop = None,
        }
        let est = locus_control::Pose::new(x, y, theta);
        let mut twist = self.controller.command(est);
        if twist.done {
            self.laps += 1;
            if self.laps >= self.cfg.laps {
                self.done = true;
                return None;
            }
            self.controller.reset();
            twist = self.controller.command(est);
        }
        Some(speeds(twist, self.cfg.localiser.wheelbase))
    }
}

/// The NIS and innovation of the correction an update applied or, gated
/// out, refused (its last attempt).
fn nis_and_innovation(update: &Update<f64, 3, 2>) -> Option<(f64, [f64; 2])> {
    update
        .correction()
        .map(|c| (c.nis, [c.innovation[0], c.innovation[1]]))
}
