//! Ground-truth kinematics of the simulated robots, per-wheel true travel, and
//! wheel slip expressed as data.
//!
//! # Frames and units
//! The pose `(x, y, theta)` (m, m, rad) is in the world frame; `theta` is
//! wrapped to `(-pi, pi]`. The reference point is the midpoint of the driven
//! axle (differential drive), the body centre (skid steer) and the midpoint of
//! the rear axle (tricycle, spec section 5).
//!
//! # Integration
//! A [`DriveCommand`] is held constant over a step `dt`, so the body moves
//! with a constant speed `v` (m/s) and turn rate `w` (rad/s): the exact
//! motion is a circular arc (a straight line when `w = 0`).
//! [`Kinematics::step`] integrates that arc in closed form,
//!
//! ```text
//! x' = x + v dt sinc(w dt / 2) cos(theta + w dt / 2)
//! y' = y + v dt sinc(w dt / 2) sin(theta + w dt / 2)
//! theta' = theta + w dt
//! ```
//!
//! which is exact for any `dt` (no Euler error), unlike the filters' models.
//!
//! # Slip
//! A [`Slip`] multiplies one wheel's *measured* travel by `scale` while that
//! wheel's cumulative absolute true travel lies in `[start, end)` (m). Slip
//! and bumps make an encoder over-count (spec section 5), so `scale > 1` is
//! the usual case, but any finite scale is allowed. [`Robot`] keeps the
//! odometers and applies a [`SlipSchedule`] on every step.

use rand::RngExt;
use rand::rngs::StdRng;

/// Errors of the simulated robot.
#[derive(Debug, Clone, Copy, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum RobotError {
    /// The command's kind does not drive this kinematics (e.g. a steering
    /// command for a differential drive).
    #[error("command {command:?} does not drive a {kinematics} robot")]
    CommandMismatch {
        /// The kinematics' name.
        kinematics: &'static str,
        /// The command given.
        command: DriveCommand,
    },
    /// A command value, `dt` or the pose is not finite, or `dt < 0`.
    #[error("non-finite or invalid input: {0}")]
    InvalidInput(&'static str),
}

/// The robot's pose is Locus's one planar pose, `locus_core::Pose<f64>`:
/// `(x, y, theta)` (m, m, rad), world frame; [`Pose::new`] wraps `theta` to
/// `(-pi, pi]`, as every pose the robot moves to is.
pub use locus_core::Pose;

/// A wheel (or tread) of a robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Wheel {
    /// Left wheel or tread (rear-left on a tricycle).
    Left,
    /// Right wheel or tread (rear-right on a tricycle).
    Right,
    /// The tricycle's front (driven, steered) wheel.
    Front,
}

/// What the simulated robot's drive is told to do over one step (held
/// constant over it), in the terms of its [`Kinematics`]: wheel or tread
/// speeds for a differential drive or skid steer, front-wheel speed and
/// steering angle for a tricycle. Not a body twist (`locus_control::Twist`)
/// and not the link's packet (`locus_link::CommandPacket`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveCommand {
    /// Ground speeds of the left and right wheels or treads (m/s), for
    /// [`Kinematics::DifferentialDrive`] and [`Kinematics::SkidSteer`].
    Wheels {
        /// Left wheel/tread speed (m/s).
        left: f64,
        /// Right wheel/tread speed (m/s).
        right: f64,
    },
    /// Front wheel ground speed (m/s) and steering angle (rad, positive to
    /// the left), for [`Kinematics::Tricycle`].
    Steered {
        /// Front wheel speed along its own heading (m/s).
        speed: f64,
        /// Steering angle (rad).
        steering: f64,
    },
}

/// Ground-truth kinematics of a robot.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kinematics {
    /// Two driven wheels on one axle (seed 001).
    DifferentialDrive {
        /// Distance between the wheels' contact points, `b` (m, > 0).
        wheelbase: f64,
        /// Wheel radius (m, > 0); used by [`Kinematics::wheel_rotation`].
        wheel_radius: f64,
    },
    /// A skid-steer robot (seed 000): left and right treads.
    SkidSteer {
        /// Effective track width `D` (m, > 0), larger than the geometric one.
        effective_track: f64,
    },
    /// A tricycle (seed 004): driven, steered front wheel, passive rear wheels.
    Tricycle {
        /// Wheelbase `L`, rear axle to front wheel (m, > 0).
        wheelbase: f64,
        /// Rear track `D` (m, > 0).
        rear_track: f64,
    },
}

/// A travel (m) for each wheel of the simulated robot, keyed by [`Wheel`]:
/// a step's true or measured travel (signed: positive forwards), or the
/// odometers' cumulative absolute true travel ([`Robot::odometer`]). `front`
/// is 0 for robots without a front wheel. Not the filter's odometry input
/// (`locus_models::WheelTravel`, paper 001's `d1` right, `d2` left).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TravelByWheel {
    /// Left (rear-left) wheel or tread (m).
    pub left: f64,
    /// Right (rear-right) wheel or tread (m).
    pub right: f64,
    /// Tricycle front wheel, along its own heading (m).
    pub front: f64,
}

impl TravelByWheel {
    /// The travel of `wheel` (m).
    pub fn get(&self, wheel: Wheel) -> f64 {
        match wheel {
            Wheel::Left => self.left,
            Wheel::Right => self.right,
            Wheel::Front => self.front,
        }
    }

    /// Mutable access to the travel of `wheel` (m).
    pub fn get_mut(&mut self, wheel: Wheel) -> &mut f64 {
        match wheel {
            Wheel::Left => &mut self.left,
            Wheel::Right => &mut self.right,
            Wheel::Front => &mut self.front,
        }
    }
}

/// `sin(a) / a`, with its Taylor series near 0.
fn sinc(a: f64) -> f64 {
    if a.abs() < 1e-4 {
        1.0 - a * a / 6.0
    } else {
        a.sin() / a
    }
}

/// Exact arc: pose after moving at speed `v` (m/s) and turn rate `w` (rad/s)
/// for `dt` (s).
fn arc(pose: &Pose<f64>, v: f64, w: f64, dt: f64) -> Pose<f64> {
    let half = 0.5 * w * dt;
    let chord = v * dt * sinc(half);
    let (s, c) = (pose.theta + half).sin_cos();
    Pose::new(pose.x + chord * c, pose.y + chord * s, pose.theta + w * dt)
}

impl Kinematics {
    /// A short name for messages.
    pub fn name(&self) -> &'static str {
        match self {
            Self::DifferentialDrive { .. } => "differential-drive",
            Self::SkidSteer { .. } => "skid-steer",
            Self::Tricycle { .. } => "tricycle",
        }
    }

    /// Body speed `v` (m/s) of the reference point and turn rate `w` (rad/s)
    /// under `command`. Tricycle: `v = s cos(phi)`, `w = s sin(phi) / L`.
    pub fn body_rates(&self, command: &DriveCommand) -> Result<(f64, f64), RobotError> {
        match (*self, *command) {
            (
                Self::DifferentialDrive { wheelbase: b, .. },
                DriveCommand::Wheels { left, right },
            )
            | (Self::SkidSteer { effective_track: b }, DriveCommand::Wheels { left, right }) => {
                Ok((0.5 * (left + right), (right - left) / b))
            }
            (Self::Tricycle { wheelbase, .. }, DriveCommand::Steered { speed, steering }) => {
                let (s, c) = steering.sin_cos();
                Ok((speed * c, speed * s / wheelbase))
            }
            (_, command) => Err(RobotError::CommandMismatch {
                kinematics: self.name(),
                command,
            }),
        }
    }

    /// One step of `dt` (s, >= 0) under a constant `command`: the exact new
    /// pose and each wheel's true travel (m). Tricycle rear wheels travel
    /// `(v -+ w D/2) dt`, the front wheel `s dt`.
    pub fn step(
        &self,
        pose: &Pose<f64>,
        command: &DriveCommand,
        dt: f64,
    ) -> Result<(Pose<f64>, TravelByWheel), RobotError> {
        if !(dt.is_finite() && dt >= 0.0) {
            return Err(RobotError::InvalidInput("dt"));
        }
        if !(pose.x.is_finite() && pose.y.is_finite() && pose.theta.is_finite()) {
            return Err(RobotError::InvalidInput("pose"));
        }
        let (v, w) = self.body_rates(command)?;
        if !(v.is_finite() && w.is_finite()) {
            return Err(RobotError::InvalidInput("command"));
        }
        let travel = match (*self, *command) {
            (Self::Tricycle { rear_track, .. }, DriveCommand::Steered { speed, .. }) => {
                TravelByWheel {
                    left: (v - 0.5 * w * rear_track) * dt,
                    right: (v + 0.5 * w * rear_track) * dt,
                    front: speed * dt,
                }
            }
            (_, DriveCommand::Wheels { left, right }) => TravelByWheel {
                left: left * dt,
                right: right * dt,
                front: 0.0,
            },
            // body_rates has rejected every other pairing.
            (_, DriveCommand::Steered { .. }) => TravelByWheel::default(),
        };
        Ok((arc(pose, v, w, dt), travel))
    }

    /// The rotation (rad) of a wheel that travelled `travel` (m), for a
    /// differential drive (its `wheel_radius`); `None` for other kinematics.
    pub fn wheel_rotation(&self, travel: f64) -> Option<f64> {
        match self {
            Self::DifferentialDrive { wheel_radius, .. } => Some(travel / wheel_radius),
            _ => None,
        }
    }
}

/// One slip zone: `wheel`'s measured travel is `scale` times its true travel
/// while the wheel's cumulative absolute true travel is in `[start, end)` (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slip {
    /// The affected wheel.
    pub wheel: Wheel,
    /// Start of the zone, in the wheel's cumulative absolute travel (m).
    pub start: f64,
    /// End of the zone (m, > `start` for a non-empty zone).
    pub end: f64,
    /// Measured / true travel inside the zone (1.1: over-counts 10 %).
    pub scale: f64,
}

impl Slip {
    /// Extra measured travel (m, signed like the motion) for a step in which
    /// the wheel's odometer goes from `s0` to `s1 >= s0` and its signed true
    /// travel is `travel`.
    fn extra(&self, s0: f64, s1: f64, travel: f64) -> f64 {
        let overlap = (s1.min(self.end) - s0.max(self.start)).max(0.0);
        (self.scale - 1.0) * overlap * travel.signum()
    }
}

/// A list of slip zones (applied additively where they overlap).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SlipSchedule {
    /// The zones.
    pub zones: Vec<Slip>,
}

impl SlipSchedule {
    /// No slip.
    pub fn none() -> Self {
        Self::default()
    }

    /// `count` bumps of `length` (m) each on `wheel`, the first starting at
    /// `start` (m of the wheel's travel), successive starts `spacing` (m)
    /// apart, each scaling measured travel by `scale`. "Rear-left over-counts
    /// 10 % over three 0.3 m bumps":
    /// `SlipSchedule::bumps(Wheel::Left, 1.0, 0.3, 0.5, 3, 1.1)`.
    pub fn bumps(
        wheel: Wheel,
        start: f64,
        length: f64,
        spacing: f64,
        count: usize,
        scale: f64,
    ) -> Self {
        let zones = (0..count)
            .map(|i| {
                #[allow(clippy::cast_precision_loss)]
                let s = start + spacing * i as f64;
                Slip {
                    wheel,
                    start: s,
                    end: s + length,
                    scale,
                }
            })
            .collect();
        Self { zones }
    }

    /// `count` bumps on `wheel` at starts drawn uniformly in `[from, to)` (m
    /// of wheel travel), lengths uniform in `length` (m) and scales uniform in
    /// `scale`, from the seeded `rng`. Empty ranges take their lower bound.
    pub fn random_bumps(
        rng: &mut StdRng,
        wheel: Wheel,
        (from, to): (f64, f64),
        count: usize,
        length: (f64, f64),
        scale: (f64, f64),
    ) -> Self {
        let mut draw = |lo: f64, hi: f64| {
            if hi > lo {
                rng.random_range(lo..hi)
            } else {
                lo
            }
        };
        let mut zones: Vec<Slip> = (0..count)
            .map(|_| {
                let s = draw(from, to);
                let l = draw(length.0, length.1);
                Slip {
                    wheel,
                    start: s,
                    end: s + l,
                    scale: draw(scale.0, scale.1),
                }
            })
            .collect();
        zones.sort_by(|a, b| a.start.total_cmp(&b.start));
        Self { zones }
    }

    /// Adds a zone.
    pub fn push(&mut self, slip: Slip) {
        self.zones.push(slip);
    }

    /// The measured travel for one step (m): `travel` plus each zone's extra
    /// on its wheel, given the odometers (cumulative absolute true travel, m)
    /// before the step.
    pub fn apply(&self, odometer: &TravelByWheel, travel: &TravelByWheel) -> TravelByWheel {
        let mut measured = *travel;
        for z in &self.zones {
            let s0 = odometer.get(z.wheel);
            let t = travel.get(z.wheel);
            *measured.get_mut(z.wheel) += z.extra(s0, s0 + t.abs(), t);
        }
        measured
    }
}

/// What one [`Robot::step`] produced.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StepOutput {
    /// The true pose after the step.
    pub pose: Pose<f64>,
    /// Each wheel's true travel in the step (m).
    pub true_travel: TravelByWheel,
    /// Each wheel's travel as its encoder sees it, slip included (m).
    pub measured_travel: TravelByWheel,
}

/// A simulated robot: kinematics, true pose, slip and per-wheel odometers.
#[derive(Debug, Clone, PartialEq)]
pub struct Robot {
    /// Ground-truth kinematics.
    pub kinematics: Kinematics,
    /// True pose.
    pub pose: Pose<f64>,
    /// Slip zones.
    pub slip: SlipSchedule,
    /// Cumulative absolute true travel of each wheel (m).
    pub odometer: TravelByWheel,
}

impl Robot {
    /// A robot at `pose` with no slip and zeroed odometers.
    pub fn new(kinematics: Kinematics, pose: Pose<f64>) -> Self {
        Self {
            kinematics,
            pose,
            slip: SlipSchedule::none(),
            odometer: TravelByWheel::default(),
        }
    }

    /// The same robot with slip zones `slip`.
    #[must_use]
    pub fn with_slip(mut self, slip: SlipSchedule) -> Self {
        self.slip = slip;
        self
    }

    /// Advances the robot by `dt` (s) under `command` (exact arc), returning
    /// the new pose, true and measured wheel travel. On error the robot is
    /// unchanged.
    pub fn step(&mut self, command: &DriveCommand, dt: f64) -> Result<StepOutput, RobotError> {
        let (pose, true_travel) = self.kinematics.step(&self.pose, command, dt)?;
        let measured_travel = self.slip.apply(&self.odometer, &true_travel);
        self.odometer.left += true_travel.left.abs();
        self.odometer.right += true_travel.right.abs();
        self.odometer.front += true_travel.front.abs();
        self.pose = pose;
        Ok(StepOutput {
            pose,
            true_travel,
            measured_travel,
        })
    }

    /// Runs `n` steps of `dt` (s) under a constant `command`, `sub` exact
    /// sub-steps each (`sub >= 1`; exactness does not need them, slip zones'
    /// edges are resolved by the odometer either way); returns each step's
    /// output with travels summed over its sub-steps. Stops at the first
    /// error (the robot keeps the steps already taken).
    pub fn run(
        &mut self,
        command: &DriveCommand,
        dt: f64,
        n: usize,
        sub: usize,
    ) -> Result<Vec<StepOutput>, RobotError> {
        let sub = sub.max(1);
        #[allow(clippy::cast_precision_loss)]
        let h = dt / sub as f64;
        let mut out = Vec::with_capacity(n);
        for _ in 0..n {
            let mut acc = StepOutput {
                pose: self.pose,
                true_travel: TravelByWheel::default(),
                measured_travel: TravelByWheel::default(),
            };
            for _ in 0..sub {
                let o = self.step(command, h)?;
                acc.pose = o.pose;
                for w in [Wheel::Left, Wheel::Right, Wheel::Front] {
                    *acc.true_travel.get_mut(w) += o.true_travel.get(w);
                    *acc.measured_travel.get_mut(w) += o.measured_travel.get(w);
                }
            }
            out.push(acc);
        }
        Ok(out)
    }
}
