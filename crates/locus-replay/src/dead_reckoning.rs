//! Dead reckoning on a log's odometry, for the estimates that work from
//! the sightings alone ([`crate::initial`], [`crate::drift`]): the pose
//! carried forward with the logged velocities held from one record to the
//! next, applied `cfg`'s odometry delay late and corrected by its initial
//! scale factors and turn-rate bias.

use locus_core::MotionModel;
use locus_core::nalgebra::{Vector2, Vector3};
use locus_models::unicycle::{Unicycle, Velocities};

use crate::{Config, Log};
use locus_logs::mrclam::Odometry;

/// A pose carried forward in time on the odometry.
#[derive(Clone)]
pub(crate) struct DeadReckoning<'a> {
    odometry: &'a [Odometry],
    /// The next record not yet in force.
    next: usize,
    delay: f64,
    calibration: [f64; 4],
    /// The pose at `time`.
    pub pose: Vector3<f64>,
    time: f64,
    v: f64,
    omega: f64,
    /// Distance travelled since the start, m.
    pub travelled: f64,
    /// Angle turned since the start (the turns either way added), rad.
    pub turned: f64,
}

impl<'a> DeadReckoning<'a> {
    /// `pose` at `time` (s), with the input in force then: the last record
    /// applied at or before it (none before the first: standing still).
    pub fn new(log: &'a Log, cfg: &Config, pose: Vector3<f64>, time: f64) -> Self {
        let delay = cfg.odometry_delay;
        let next = log.odometry.partition_point(|o| o.time + delay <= time);
        let mut dr = Self {
            odometry: &log.odometry,
            next,
            delay,
            calibration: cfg.calibration.initial,
            pose,
            time,
            v: 0.0,
            omega: 0.0,
            travelled: 0.0,
            turned: 0.0,
        };
        if let Some(o) = next.checked_sub(1).map(|i| log.odometry[i]) {
            dr.take(&o);
        }
        dr
    }

    fn take(&mut self, o: &Odometry) {
        let [s_v, s_omega, b_omega, _] = self.calibration;
        self.v = s_v * o.v;
        self.omega = s_omega * o.omega + b_omega;
    }

    fn go(&mut self, until: f64) {
        if until > self.time {
            self.travelled += self.v.abs() * (until - self.time);
            self.turned += self.omega.abs() * (until - self.time);
            let u = Velocities {
                v: self.v,
                omega: self.omega,
                dt: until - self.time,
            };
            self.pose = Unicycle::new(0.0, 0.0).f(&self.pose, &u, &Vector2::zeros());
            self.time = until;
        }
    }

    /// Carries the pose to `to` (s, not before the current time) and
    /// returns it.
    pub fn advance(&mut self, to: f64) -> Vector3<f64> {
        while let Some(o) = self.odometry.get(self.next).copied() {
            let at = o.time + self.delay;
            if at > to {
                break;
            }
            self.go(at);
            self.take(&o);
            self.next += 1;
        }
        self.go(to);
        self.pose
    }
}
