//! A family of simulated robots as a benchmark for the log replay
//! (`locus_replay`, issue 27 "any robot, first try"): each [`Member`] is a
//! robot unlike the others (sensor rate and noise, errors correlated in
//! time, range-only beacons, wheel or commanded odometry, scale errors and
//! a turn-rate bias, few or many landmarks in view, gross outliers, a
//! sensor mounted off-centre and off-axis, a ground truth whose heading is
//! offset), and [`generate`] writes its log in the Locus CSV format
//! (docs/log-format.md) with the [`Truth`] the log does not tell: the true
//! noise in the replay filter's terms and the true calibration.
//!
//! The robot drives piecewise arcs: constant speed and turn rate over
//! segments of 1-4 s (0.5 s while it turns back towards the centre of its
//! area), speeds in [`Member::speed`], turn rates up to
//! [`Member::max_turn_rate`], inside a disc of radius
//! [`Member::area_radius`] (it turns back towards the centre when it is
//! beyond 60 % of it). Landmarks are scattered uniformly over a disc wider
//! by the sensor's range, as densely as [`Sensor::in_view`] asks.
//!
//! What the log says and what is true:
//!
//! * **Odometry** (`odometry,t,v,omega` at [`Odometry::rate`]): the
//!   logged values are off by scale factors and a bias, `v_log = v / s_v`,
//!   `omega_log = (omega - b_omega) / s_omega`, so that the replay's
//!   calibrated unicycle (`v = s_v v_log`, `omega = s_omega omega_log +
//!   b_omega`) holds with the true `s_v`, `s_omega`, `b_omega`. From
//!   wheel speeds ([`OdometrySource::Wheels`]) each wheel's measured speed
//!   has white noise; from commanded velocities
//!   ([`OdometrySource::Commanded`]) the robot moves as commanded plus white
//!   noise, [`OdometrySource::Commanded::lag`] seconds after the command's
//!   time stamp.
//! * **Sightings** (`measurement,t,id,range,bearing`, or for range-only
//!   beacons the v3 record `range,t,id,range`): of every landmark within
//!   the sensor's range and field of view, at [`Sensor::rate`], with white
//!   noise and/or first-order Gauss-Markov noise per landmark
//!   ([`Correlated`]), and a share of gross outliers drawn uniformly over
//!   the range and field of view. The sensor sits [`Sensor::mount_x`]
//!   ahead of the centre (written truthfully in the `sensor` line) and
//!   looks [`Sensor::yaw`] off the robot's heading (the log says 0: the
//!   user does not know it; the filter's bearing bias can absorb it).
//! * **Truth** (`truth` records at [`Member::truth_rate`]): the true pose,
//!   its heading offset by [`Member::truth_heading_offset`] (a motion
//!   capture frame whose markers are not aligned with the robot).
//!
//! No `noise` records (the user does not know them) and no `start` (the
//! truth at the first odometry time gives it). Everything is drawn from one
//! `StdRng` seeded by the caller: the same member and seed give the same
//! log, byte for byte.

mod generate;
mod members;
mod motion;

pub use generate::{Generated, generate, generate_with};
pub use motion::{TruePath, arc};

/// A simulated robot of the family (all values SI: m, s, rad).
#[derive(Debug, Clone, PartialEq)]
pub struct Member {
    /// A short name (e.g. `laser-5hz-offset`).
    pub name: &'static str,
    /// What it is like, one line.
    pub about: &'static str,
    /// Length of the log (odometry span), s (> 0).
    pub duration: f64,
    /// The member's own seed (the runner's default).
    pub seed: u64,
    /// Radius of the disc the robot drives in, m (> 0).
    pub area_radius: f64,
    /// Range of the forward speed of each segment, m/s (`min <= max`).
    pub speed: (f64, f64),
    /// Largest turn rate of a segment, rad/s (>= 0).
    pub max_turn_rate: f64,
    /// The landmark sensor.
    pub sensor: Sensor,
    /// The odometry.
    pub odometry: Odometry,
    /// Rate of the `truth` records, Hz (> 0).
    pub truth_rate: f64,
    /// Added to the true heading in the `truth` records, rad (a constant
    /// frame offset of the ground truth; 0 for none).
    pub truth_heading_offset: f64,
    /// True when the log uses the v3 `range` record (range-only beacons),
    /// which the replay's reader does not read yet: such members are
    /// generated but kept out of the replay tests.
    pub needs_v3: bool,
}

/// What the landmark sensor measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensorKind {
    /// Range and bearing (`measurement` records).
    RangeBearing,
    /// Range only, to beacons (v3 `range` records).
    RangeOnly,
}

/// The landmark sensor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensor {
    /// Range and bearing, or range only.
    pub kind: SensorKind,
    /// Scans per second, Hz (> 0); each scan sights every landmark in view.
    pub rate: f64,
    /// Standard deviation of the white range noise, m (>= 0).
    pub sigma_range: f64,
    /// Standard deviation of the white bearing noise, rad (>= 0).
    pub sigma_bearing: f64,
    /// Noise correlated in time, on top of the white noise.
    pub correlated: Option<Correlated>,
    /// Share of sightings that are gross outliers, in [0, 1): range uniform
    /// in [0, `max_range`] m, bearing uniform over the field of view.
    pub outliers: f64,
    /// Mount: how far ahead of the robot's centre, m (written in the log's
    /// `sensor` line).
    pub mount_x: f64,
    /// Mount: how far the sensor's axis is turned from the robot's
    /// heading, counter-clockwise, rad (NOT written in the log: the log
    /// says 0).
    pub yaw: f64,
    /// Longest range sighted, m (> 0).
    pub max_range: f64,
    /// Half the field of view, rad, in (0, pi] (pi: all around).
    pub half_fov: f64,
    /// Landmarks in view on average (> 0): sets how densely they are
    /// scattered.
    pub in_view: f64,
}

/// First-order Gauss-Markov noise, one process per landmark and quantity:
/// `e(t + dt) = a e(t) + sqrt(1 - a^2) sigma w`, `a = exp(-dt / tau)`, `w`
/// standard normal; stationary with standard deviation `sigma` and
/// autocorrelation `exp(-|dt| / tau)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Correlated {
    /// Time constant, s (> 0).
    pub tau: f64,
    /// Marginal standard deviation of the range error, m (>= 0).
    pub sigma_range: f64,
    /// Marginal standard deviation of the bearing error, rad (>= 0).
    pub sigma_bearing: f64,
}

/// Where the odometry comes from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OdometrySource {
    /// Measured wheel speeds `r`, `l` (m/s), each with white noise:
    /// `v = (r + l) / 2`, `omega = (r - l) / track`. No lag.
    Wheels {
        /// Distance between the wheels, m (> 0).
        track: f64,
        /// Standard deviation of each wheel's speed noise per record, m/s.
        sigma_wheel: f64,
    },
    /// Commanded velocities: the robot moves `lag` seconds after each
    /// record's time stamp, at the commanded velocity plus white noise
    /// (held over the record's period).
    Commanded {
        /// Delay of the motion behind the command, s (>= 0).
        lag: f64,
        /// Standard deviation of the forward-speed noise per record, m/s.
        sigma_v: f64,
        /// Standard deviation of the turn-rate noise per record, rad/s.
        sigma_omega: f64,
    },
}

/// The odometry: its source, rate and calibration errors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Odometry {
    /// Wheel speeds or commanded velocities.
    pub source: OdometrySource,
    /// Records per second, Hz (> 0).
    pub rate: f64,
    /// True forward-speed scale `s_v` (-): the logged speed times it is the
    /// robot's.
    pub v_scale: f64,
    /// True turn-rate scale `s_omega` (-).
    pub omega_scale: f64,
    /// True turn-rate bias `b_omega`, rad/s: the robot turns at
    /// `s_omega omega_log + b_omega`.
    pub omega_bias: f64,
}

/// What the log does not say: the true noise in the replay filter's terms
/// (`locus_replay::Config`) and the true calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// Power spectral density of the forward-speed noise, m^2/s: a white
    /// per-record noise of standard deviation `sigma` at period `dt` is
    /// `sigma^2 dt` (for wheels, `sigma_wheel^2 / 2 dt`).
    pub q_v: f64,
    /// Power spectral density of the turn-rate noise, rad^2/s (for wheels,
    /// `2 sigma_wheel^2 / track^2 dt`).
    pub q_omega: f64,
    /// Marginal standard deviation of a range, m (white and correlated
    /// parts together, outliers aside).
    pub sigma_range: f64,
    /// Marginal standard deviation of a bearing, rad (NaN for range-only).
    pub sigma_bearing: f64,
    /// Time constant of the correlated part, s (0 when all white).
    pub tau: f64,
    /// How long after an odometry record the robot moves as it says, s.
    pub odometry_delay: f64,
    /// Forward-speed scale `s_v` (-).
    pub v_scale: f64,
    /// Turn-rate scale `s_omega` (-).
    pub omega_scale: f64,
    /// Turn-rate bias `b_omega`, rad/s.
    pub omega_bias: f64,
    /// The sensor's mount yaw, rad (the log says 0). In the filter's terms
    /// it is a bearing bias of `-sensor_yaw`, or a `sensor` line with this
    /// yaw.
    pub sensor_yaw: f64,
    /// The sensor's mount x, m (as the log's `sensor` line says).
    pub sensor_x: f64,
    /// The `truth` records' heading offset, rad.
    pub truth_heading_offset: f64,
    /// Share of gross outliers.
    pub outliers: f64,
}

impl Member {
    /// The true noise and calibration of this member (what [`generate`]
    /// returns beside the log).
    #[must_use]
    pub fn truth(&self) -> Truth {
        let dt = 1.0 / self.odometry.rate;
        let (q_v, q_omega, delay) = match self.odometry.source {
            OdometrySource::Wheels { track, sigma_wheel } => {
                let var = sigma_wheel * sigma_wheel;
                (var / 2.0 * dt, 2.0 * var / (track * track) * dt, 0.0)
            }
            OdometrySource::Commanded {
                lag,
                sigma_v,
                sigma_omega,
            } => (sigma_v * sigma_v * dt, sigma_omega * sigma_omega * dt, lag),
        };
        let s = &self.sensor;
        let (c_range, c_bearing, tau) = s
            .correlated
            .map_or((0.0, 0.0, 0.0), |c| (c.sigma_range, c.sigma_bearing, c.tau));
        Truth {
            q_v,
            q_omega,
            sigma_range: s.sigma_range.hypot(c_range),
            sigma_bearing: match s.kind {
                SensorKind::RangeBearing => s.sigma_bearing.hypot(c_bearing),
                SensorKind::RangeOnly => f64::NAN,
            },
            tau,
            odometry_delay: delay,
            v_scale: self.odometry.v_scale,
            omega_scale: self.odometry.omega_scale,
            omega_bias: self.odometry.omega_bias,
            sensor_yaw: s.yaw,
            sensor_x: s.mount_x,
            truth_heading_offset: self.truth_heading_offset,
            outliers: s.outliers,
        }
    }

    /// The same member shortened to `factor` of its duration (> 0).
    #[must_use]
    pub fn scaled(&self, factor: f64) -> Self {
        Self {
            duration: self.duration * factor,
            ..self.clone()
        }
    }

    /// Whether the sightings' errors are correlated in time.
    #[must_use]
    pub fn is_correlated(&self) -> bool {
        self.sensor.correlated.is_some()
    }

    /// The member of the family named `name`.
    #[must_use]
    pub fn named(name: &str) -> Option<Self> {
        Self::family().into_iter().find(|m| m.name == name)
    }
}
