//! The `tricycle-slip` scenario's configuration ([`TricycleSlipConfig`])
//! with its validation, and the slip-rejection rule ([`SlipRejection`]).

use locus_odometry::Tricycle;
use locus_odometry::redundant::Selection;
use serde::{Deserialize, Serialize};

use crate::closed_loop::Error;
use crate::scenario_file::{MAX_STEPS, within};

/// The slip-rejection rule of the redundant odometry (spec section 5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SlipRejection {
    /// The paper's rule: component by component, the increment smaller in
    /// magnitude ([`Selection::ComponentMin`]).
    #[default]
    ComponentMin,
    /// The whole increment of the source with the shorter path
    /// ([`Selection::ConsistentSet`]).
    ConsistentSet,
}

impl SlipRejection {
    /// The odometry crate's selection.
    #[must_use]
    pub fn selection(self) -> Selection {
        match self {
            Self::ComponentMin => Selection::ComponentMin,
            Self::ConsistentSet => Selection::ConsistentSet,
        }
    }
}

/// Configuration of `tricycle-slip` (SI units). Defaults: the spec's
/// \[assumed\] robot and the odometry issue's slip scenario (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct TricycleSlipConfig {
    /// Odometry and filter step (s). 0.01 s (100 Hz).
    pub dt: f64,
    /// Rear-axle speed (m/s). 1 m/s.
    pub speed: f64,
    /// Length of the straight (m). 10 m.
    pub straight: f64,
    /// Radius of the left arc of the rear-axle midpoint (m). 2 m.
    pub arc_radius: f64,
    /// Angle of the arc (rad). pi/2.
    pub arc_angle: f64,
    /// Rear wheel radius (m). 0.05 m.
    pub rear_radius: f64,
    /// Front wheel radius (m). 0.06 m.
    pub front_radius: f64,
    /// Rear track `D` (m). 0.40 m.
    pub track: f64,
    /// Wheelbase `L` (m). 0.45 m.
    pub wheelbase: f64,
    /// Lines of every wheel encoder and of the steering encoder (x4
    /// decoding). 500.
    pub encoder_lines: u32,
    /// Rear-left bumps: start of the first (m of the wheel's travel). 2 m.
    pub bump_start: f64,
    /// Rear-left bumps: length of each (m of wheel travel). 0.3 m.
    pub bump_length: f64,
    /// Rear-left bumps: spacing of their starts (m). 3 m.
    pub bump_spacing: f64,
    /// Rear-left bumps: count. 3.
    pub bump_count: usize,
    /// Rear-left bumps: measured / true travel. 1.10.
    pub bump_scale: f64,
    /// Front slippery patch: start (m of the front wheel's travel). 11.025 m.
    pub patch_start: f64,
    /// Front slippery patch: length (m of front travel). 1 m.
    pub patch_length: f64,
    /// Front slippery patch: measured / true travel. 1.15.
    pub patch_scale: f64,
    /// Random error of each wheel's measured travel, `k` in
    /// `N(0, k^2 |d|)` (m per sqrt(m)). \[assumed\] 1e-3.
    pub travel_noise: f64,
    /// The slip-rejection rule. Default the paper's component-wise minimum.
    pub rejection: SlipRejection,
    /// The EKF's count noise: floor (counts^2). 1/12.
    pub count_var_floor: f64,
    /// The EKF's count noise: per count rolled (counts^2 per count). 0.1.
    pub count_var_per_count: f64,
    /// Laser beams `[x_si (m), y_si (m), beta (rad)]` on the robot (rear-axle
    /// frame). \[assumed\] 0.2 m ahead of the rear axle, looking ahead, left
    /// and right.
    pub beams: [[f64; 3]; 3],
    /// Laser range noise (m, 1 sigma), simulated and assumed. 0.01 m.
    pub laser_sigma: f64,
    /// Largest laser range (m). 8 m.
    pub laser_max_range: f64,
    /// A laser scan every this many steps (>= 1). 10 (10 Hz).
    pub laser_period: usize,
    /// The room: `[x_min, y_min, x_max, y_max]` (m). `[-1, -2, 13, 5]`.
    pub room: [f64; 4],
    /// Confidence of the chi-square gate on each beam's NIS (`None`: none).
    /// 0.9999: a bump turns the rear odometry by ~4 deg, which the count
    /// noise does not model, and a 99 % gate then rejects the laser for
    /// good (measured: 5 of seeds 0..20 ended 0.35-0.73 m off with 0.99,
    /// none above 1 cm with 0.9999 or no gate).
    pub gate_confidence: Option<f64>,
    /// Standard deviation of the initial estimate (m, m, rad); the true start
    /// is drawn from it around the origin. `[0.01, 0.01, 0.01]`.
    pub initial_std: [f64; 3],
}

impl Default for TricycleSlipConfig {
    fn default() -> Self {
        Self {
            dt: 0.01,
            speed: 1.0,
            straight: 10.0,
            arc_radius: 2.0,
            arc_angle: core::f64::consts::FRAC_PI_2,
            rear_radius: 0.05,
            front_radius: 0.06,
            track: 0.40,
            wheelbase: 0.45,
            encoder_lines: 500,
            bump_start: 2.0,
            bump_length: 0.3,
            bump_spacing: 3.0,
            bump_count: 3,
            bump_scale: 1.10,
            patch_start: 11.025,
            patch_length: 1.0,
            patch_scale: 1.15,
            travel_noise: 1e-3,
            rejection: SlipRejection::ComponentMin,
            count_var_floor: 1.0 / 12.0,
            count_var_per_count: 0.1,
            beams: [
                [0.2, 0.0, 0.0],
                [0.2, 0.0, core::f64::consts::FRAC_PI_2],
                [0.2, 0.0, -core::f64::consts::FRAC_PI_2],
            ],
            laser_sigma: 0.01,
            laser_max_range: 8.0,
            laser_period: 10,
            room: [-1.0, -2.0, 13.0, 5.0],
            gate_confidence: Some(0.9999),
            initial_std: [0.01, 0.01, 0.01],
        }
    }
}

impl TricycleSlipConfig {
    /// `Ok(())` if every value is in its domain.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first bad field.
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        // Plausible ranges (SI), and the path (straight, then the arc)
        // driven in at most 1e7 steps.
        let path = self.straight + self.arc_radius * self.arc_angle;
        let checks: [(bool, &'static str, &'static str); 20] = [
            (
                within(self.dt, 1e-4, 1.0),
                "dt",
                "must be in [1e-4, 1] s (a run is at most 1e7 steps)",
            ),
            (
                within(self.speed, 1e-3, 100.0),
                "speed",
                "must be in [0.001, 100] m/s",
            ),
            (
                within(self.straight, 0.0, 1e4),
                "straight",
                "must be in [0, 10000] m",
            ),
            (
                pos(self.arc_radius) && self.arc_radius <= 1e4,
                "arc_radius",
                "must be in (0, 10000] m",
            ),
            (
                within(self.arc_angle, 0.0, 100.0),
                "arc_angle",
                "must be in [0, 100] rad",
            ),
            (
                path / self.speed / self.dt <= MAX_STEPS,
                "dt",
                "makes more than 1e7 steps over the path ((straight + arc_radius arc_angle) / speed / dt), the most a run may have",
            ),
            (
                within(self.rear_radius, 1e-3, 1.0) && within(self.front_radius, 1e-3, 1.0),
                "rear_radius",
                "and front_radius must be in [0.001, 1] m",
            ),
            (
                within(self.track, 0.01, 10.0),
                "track",
                "must be in [0.01, 10] m",
            ),
            (
                within(self.wheelbase, 0.01, 10.0),
                "wheelbase",
                "must be in [0.01, 10] m",
            ),
            (
                (1..=1_000_000).contains(&self.encoder_lines),
                "encoder_lines",
                "must be in [1, 1000000]",
            ),
            (
                self.bump_count <= 1000,
                "bump_count",
                "must be in [0, 1000]",
            ),
            (
                within(self.bump_start, 0.0, 1e4)
                    && within(self.bump_length, 0.0, 1e4)
                    && within(self.bump_spacing, 0.0, 1e4)
                    && pos(self.bump_scale)
                    && self.bump_scale <= 10.0,
                "bump_start",
                "must be in [0, 10000] m, and bump_length, bump_spacing in [0, 10000] m and bump_scale in (0, 10]",
            ),
            (
                within(self.patch_start, 0.0, 1e4)
                    && within(self.patch_length, 0.0, 1e4)
                    && pos(self.patch_scale)
                    && self.patch_scale <= 10.0,
                "patch_start",
                "must be in [0, 10000] m, and patch_length in [0, 10000] m and patch_scale in (0, 10]",
            ),
            (
                within(self.travel_noise, 0.0, 1.0),
                "travel_noise",
                "must be in [0, 1] m",
            ),
            (
                within(self.count_var_floor, 0.0, 1e6)
                    && within(self.count_var_per_count, 0.0, 1e6),
                "count_var_floor",
                "and count_var_per_count must be in [0, 1e6] counts^2",
            ),
            (
                self.beams
                    .iter()
                    .flatten()
                    .all(|v| within(*v, -100.0, 100.0)),
                "beams",
                "must be in [-100, 100] (m, m, rad)",
            ),
            (
                pos(self.laser_sigma)
                    && self.laser_sigma <= 10.0
                    && pos(self.laser_max_range)
                    && self.laser_max_range <= 1e4,
                "laser_sigma",
                "must be in (0, 10] m and laser_max_range in (0, 10000] m",
            ),
            (
                (1..=1_000_000).contains(&self.laser_period),
                "laser_period",
                "must be in [1, 1000000]",
            ),
            (
                self.room.iter().all(|v| within(*v, -1e4, 1e4))
                    && self.room[0] < self.room[2]
                    && self.room[1] < self.room[3],
                "room",
                "must be in [-10000, 10000] m with x_min < x_max and y_min < y_max",
            ),
            (
                self.initial_std.iter().all(|v| pos(*v) && *v <= 10.0)
                    && self
                        .gate_confidence
                        .is_none_or(|c| c.is_finite() && c > 0.0 && c < 1.0),
                "initial_std",
                "must be in (0, 10] and gate_confidence in (0, 1)",
            ),
        ];
        match checks.iter().find(|(ok, _, _)| !ok) {
            Some(&(_, field, reason)) => Err(Error::Invalid { field, reason }),
            None => Ok(()),
        }
    }

    /// The odometry crate's robot of this configuration.
    pub(super) fn tricycle(&self) -> Tricycle<f64> {
        let mut t = Tricycle::<f64>::assumed();
        t.rear = locus_odometry::Wheel::new(self.encoder_lines, 1.0, self.rear_radius);
        t.front = locus_odometry::Wheel::new(self.encoder_lines, 1.0, self.front_radius);
        t.track = self.track;
        t.wheelbase = self.wheelbase;
        t.steering.lines = self.encoder_lines;
        t
    }
}
