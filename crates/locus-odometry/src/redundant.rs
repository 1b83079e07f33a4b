//! Redundant tricycle odometry with slip rejection (paper 004, section 3,
//! eq. 1-6; spec section 5).
//!
//! The robot: a front wheel that drives and steers (steering angle `phi`
//! from its own encoder, limited to +-40 deg), two passive rear wheels with
//! encoders, rear track `D`, wheelbase `L`. The pose `(x, y, theta)`
//! (m, m, rad; Locus's one [`Pose`], heading in
//! (-pi, pi]) is the **rear-axle midpoint** in the world frame, heading
//! from the world x axis, counter-clockwise; the same conventions as
//! `locus_models::tricycle`, whose `TricycleRear`/`TricycleFront`
//! `increments` these formulas are cross-checked against
//! (`tests/slip.rs`).
//!
//! # Two sources of the same motion
//!
//! With `N` = counts per wheel revolution (`4 x lines x G`,
//! [`Wheel::counts_per_rev`]) and `R` each wheel's radius, a step's motion
//! ([`Motion`]: rear-axle path length `ds`, heading change `dtheta`) is
//!
//! ```text
//! rear  (eq. 1-3):  ds = pi R (n_R + n_L) / N        dtheta = 2 pi R (n_R - n_L) / (N D)
//! front (eq. 4-6):  dsF = 2 pi R n_F / N
//!                   ds = dsF cos(phi)                dtheta = dsF sin(phi) / L
//! ```
//!
//! (spec **\[fix\]**: the front's y increment is `dsF cos(phi) sin(theta)`;
//! the text's `cos(theta) sin(phi)` is a typo). Each becomes a world-frame
//! [`Increment`] `(dx, dy, dtheta) = (ds cos(h), ds sin(h), dtheta)` with
//! the heading `h` of the chosen [`Integration`]: `theta` (Euler, the
//! paper's equations) or `theta + dtheta/2` (midpoint, exact on a straight
//! line and second-order on an arc).
//!
//! # Steering limit: clamped
//!
//! A steering reading beyond `+-limit` is **clamped** to the limit, as
//! `locus_models::TricycleFront` does: the wheel cannot be past its stop,
//! so a reading there is the stop plus sensor error (encoder backlash, a
//! count or two of index offset). A caller who would rather treat it as a
//! fault (a steering encoder that lost its index reads far beyond) checks
//! [`Steering::checked_angle`] first, which returns
//! [`Error::SteeringOutOfRange`].
//!
//! # Slip rejection
//!
//! Slip and bumps make an encoder **over-count**, never under-count. The
//! paper's rule ([`Selection::ComponentMin`]) computes the increment from
//! both sources and keeps, component by component, the one smaller in
//! magnitude. [`Selection::ConsistentSet`] keeps the whole increment of the
//! source with the smaller path length `dx^2 + dy^2`, so `dtheta` stays
//! consistent with `(dx, dy)`. Without slip, both rules take the smaller of
//! two noisy (quantised) values every step and so are biased low; the
//! component-wise minimum also mixes sources. `tests/slip.rs` measures
//! both effects. Ties go to the rear (the paper's more reliable source).
//!
//! ```
//! use locus_core::Pose;
//! use locus_odometry::cordic::Libm;
//! use locus_odometry::redundant::{Integration, Odometry, Reading, Selection, Tricycle};
//!
//! let mut odo = Odometry::new(
//!     Tricycle::<f64>::assumed(),
//!     Selection::ComponentMin,
//!     Integration::Midpoint,
//!     Libm,
//!     Pose::default(),
//! );
//! // 1 cm straight ahead: 63.66 counts on each rear wheel, 53.05 on the front.
//! let inc = odo.step(&Reading { n_l: 64, n_r: 64, n_f: 53, n_s: 0 });
//! assert!((inc.dx - 0.01).abs() < 2e-4 && inc.dtheta == 0.0);
//! assert!((odo.pose().x - 0.00999).abs() < 1e-4);
//! ```

use locus_core::{Pose, cast, wrap_angle};

use crate::cordic::SinCos;
use crate::error::Error;
use crate::wheel::{Real, Wheel};

/// The steering encoder: counts from straight ahead to the steering angle.
///
/// `phi = 2 pi n_S / (4 lines G)` rad, positive to the left
/// (counter-clockwise turn when driving forwards), then limited to
/// `+-limit` (clamped, see the [module documentation](self)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Steering<T> {
    /// Encoder lines per encoder-shaft revolution (> 0). \[assumed\] 500.
    pub lines: u32,
    /// Encoder-shaft revolutions per steering revolution (> 0).
    /// \[assumed\] 1, which with 500 lines gives 0.18 deg per count.
    pub gear: T,
    /// Mechanical steering limit, rad (> 0). \[assumed\] 40 deg (paper 004).
    pub limit: T,
}

impl<T: Real> Steering<T> {
    /// The \[assumed\] steering encoder: 500 lines x4, G = 1 (0.18 deg per
    /// count), limit 40 deg.
    pub fn assumed() -> Self {
        Self {
            lines: 500,
            gear: T::ONE,
            limit: cast(40f64.to_radians()),
        }
    }

    /// Steering angle per count, rad: `2 pi / (4 lines G)`.
    #[inline]
    pub fn quantum(&self) -> T {
        T::TWO_PI / (T::from_uint(4) * T::from_uint(self.lines) * self.gear)
    }

    /// The angle of a count `n_S` from straight ahead, rad, **not** limited.
    #[inline]
    pub fn raw_angle(&self, n_s: i32) -> T {
        T::from_int(n_s) * self.quantum()
    }

    /// The angle of a count, clamped to `[-limit, limit]`, rad. This is
    /// what the odometry uses.
    #[inline]
    pub fn angle(&self, n_s: i32) -> T {
        self.clamp(self.raw_angle(n_s))
    }

    /// The angle of a count (rad), or [`Error::SteeringOutOfRange`] if it is
    /// beyond `+-limit`: for a caller who treats such a reading as a fault
    /// instead of clamping it.
    #[inline]
    pub fn checked_angle(&self, n_s: i32) -> Result<T, Error> {
        let phi = self.raw_angle(n_s);
        if self.in_range(phi) {
            Ok(phi)
        } else {
            Err(Error::SteeringOutOfRange)
        }
    }

    /// Whether `|phi| <= limit` (rad).
    #[inline]
    pub fn in_range(&self, phi: T) -> bool {
        phi.abs() <= self.limit
    }

    /// `phi` (rad) clamped to `[-limit, limit]`.
    #[inline]
    pub fn clamp(&self, phi: T) -> T {
        if phi > self.limit {
            self.limit
        } else if phi < -self.limit {
            -self.limit
        } else {
            phi
        }
    }
}

/// The tricycle's geometry and encoders.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tricycle<T> {
    /// Each rear wheel and its encoder (both alike). \[assumed\] 500
    /// lines, G = 1, R = 0.05 m.
    pub rear: Wheel<T>,
    /// The front (driving, steering) wheel and its encoder. \[assumed\] 500
    /// lines, G = 1, R = 0.06 m.
    pub front: Wheel<T>,
    /// Rear track `D` (between the rear wheels' contact points), m (> 0).
    /// \[assumed\] 0.40 m.
    pub track: T,
    /// Wheelbase `L` (rear axle to front wheel axis), m (> 0).
    /// \[assumed\] 0.45 m.
    pub wheelbase: T,
    /// The steering encoder and limit.
    pub steering: Steering<T>,
}

impl<T: Real> Tricycle<T> {
    /// The spec's \[assumed\] robot: rear R = 0.05 m, front R = 0.06 m,
    /// both 500 lines x4 with G = 1 (N = 2000 counts per revolution),
    /// D = 0.40 m, L = 0.45 m, [`Steering::assumed`].
    pub fn assumed() -> Self {
        Self {
            rear: Wheel::assumed(),
            front: Wheel::new(500, T::ONE, cast(0.06)),
            track: cast(0.40),
            wheelbase: cast(0.45),
            steering: Steering::assumed(),
        }
    }

    /// `Ok(())` if every length, gear and line count is finite and
    /// positive; otherwise [`Error::InvalidParameter`] naming it.
    pub fn validate(&self) -> Result<(), Error> {
        self.rear.validate()?;
        self.front.validate()?;
        let positive = |v: T| v.is_finite() && v > T::ZERO;
        if !positive(self.track) {
            return Err(Error::InvalidParameter("track must be finite and > 0"));
        }
        if !positive(self.wheelbase) {
            return Err(Error::InvalidParameter("wheelbase must be finite and > 0"));
        }
        if self.steering.lines == 0 || !positive(self.steering.gear) {
            return Err(Error::InvalidParameter(
                "steering lines and gear must be > 0",
            ));
        }
        if !positive(self.steering.limit) {
            return Err(Error::InvalidParameter(
                "steering limit must be finite and > 0",
            ));
        }
        Ok(())
    }

    /// The motion from the rear counts (eq. 1-3): `ds = pi R (n_R + n_L) / N`
    /// (m), `dtheta = 2 pi R (n_R - n_L) / (N D)` (rad), counts signed.
    #[inline]
    pub fn rear_motion(&self, n_l: i32, n_r: i32) -> Motion<T> {
        // One count rolls q = dP = pi R / (2 lines G) = 2 pi R / N.
        let q = self.rear.quantum();
        let (l, r) = (T::from_int(n_l), T::from_int(n_r));
        Motion {
            ds: T::HALF * q * (r + l),
            dtheta: q * (r - l) / self.track,
        }
    }

    /// The motion from the front count `n_F` and a steering angle `phi`
    /// (rad, clamped to the limit) (eq. 4-6): `dsF = 2 pi R n_F / N`,
    /// `ds = dsF cos(phi)` (m, the rear axle's travel), `dtheta = dsF
    /// sin(phi) / L` (rad). `trig` supplies `sin`, `cos` of `phi`.
    #[inline]
    pub fn front_motion<S: SinCos<T>>(&self, n_f: i32, phi: T, trig: &S) -> Motion<T> {
        let ds_f = self.front.distance(n_f);
        let (s, c) = trig.sin_cos(self.steering.clamp(phi));
        Motion {
            ds: ds_f * c,
            dtheta: ds_f * s / self.wheelbase,
        }
    }

    /// [`Tricycle::front_motion`] with the steering angle from the steering
    /// encoder's count `n_S` (counts from straight ahead).
    #[inline]
    pub fn front_motion_counts<S: SinCos<T>>(&self, n_f: i32, n_s: i32, trig: &S) -> Motion<T> {
        self.front_motion(n_f, self.steering.raw_angle(n_s), trig)
    }
}

/// One step's motion in the body frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Motion<T> {
    /// Path length of the rear-axle midpoint, m (signed: negative
    /// backwards).
    pub ds: T,
    /// Heading change, rad (counter-clockwise positive).
    pub dtheta: T,
}

/// Which heading turns a [`Motion`] into a world-frame [`Increment`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Integration {
    /// `theta` at the start of the step: the paper's eq. 1-2 and 4-5.
    /// On an arc, each step's chord is off by `ds dtheta / 2` sideways.
    #[default]
    Euler,
    /// `theta + dtheta/2`: exact on a straight line, chord direction of an
    /// arc (position error `O(ds dtheta^2)` per step).
    Midpoint,
}

impl<T: Real> Motion<T> {
    /// The world-frame increment at heading `theta` (rad):
    /// `(ds cos h, ds sin h, dtheta)` with `h = theta` ([`Integration::Euler`])
    /// or `theta + dtheta/2` ([`Integration::Midpoint`]).
    #[inline]
    pub fn increment<S: SinCos<T>>(
        &self,
        theta: T,
        integration: Integration,
        trig: &S,
    ) -> Increment<T> {
        let h = match integration {
            Integration::Euler => theta,
            Integration::Midpoint => theta + T::HALF * self.dtheta,
        };
        let (s, c) = trig.sin_cos(h);
        Increment {
            dx: self.ds * c,
            dy: self.ds * s,
            dtheta: self.dtheta,
        }
    }
}

/// A pose increment in the world frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Increment<T> {
    /// x increment, m.
    pub dx: T,
    /// y increment, m.
    pub dy: T,
    /// Heading increment, rad.
    pub dtheta: T,
}

impl<T: Real> Increment<T> {
    /// Squared path length `dx^2 + dy^2`, m^2.
    #[inline]
    pub fn path_length_sq(&self) -> T {
        self.dx * self.dx + self.dy * self.dy
    }

    /// The pose after this increment:
    /// `(x + dx, y + dy, wrap(theta + dtheta))`.
    #[inline]
    pub fn apply(&self, pose: &Pose<T>) -> Pose<T> {
        Pose {
            x: pose.x + self.dx,
            y: pose.y + self.dy,
            theta: wrap_angle(pose.theta + self.dtheta),
        }
    }
}

/// How the increment of a step is chosen from the rear and front sources.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Selection {
    /// The rear wheels only (eq. 1-3).
    Rear,
    /// The front wheel and steering only (eq. 4-6).
    Front,
    /// The paper's rule: each of `dx`, `dy`, `dtheta` from whichever source
    /// has it smaller in magnitude (ties: rear).
    #[default]
    ComponentMin,
    /// The whole increment of the source with the smaller path length
    /// `dx^2 + dy^2` (ties: rear).
    ConsistentSet,
}

/// Chooses the increment of a step from the two sources' increments.
#[inline]
pub fn select<T: Real>(
    selection: Selection,
    rear: &Increment<T>,
    front: &Increment<T>,
) -> Increment<T> {
    let smaller = |r: T, f: T| if f.abs() < r.abs() { f } else { r };
    match selection {
        Selection::Rear => *rear,
        Selection::Front => *front,
        Selection::ComponentMin => Increment {
            dx: smaller(rear.dx, front.dx),
            dy: smaller(rear.dy, front.dy),
            dtheta: smaller(rear.dtheta, front.dtheta),
        },
        Selection::ConsistentSet => {
            if front.path_length_sq() < rear.path_length_sq() {
                *front
            } else {
                *rear
            }
        }
    }
}

/// One step's encoder readings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Reading {
    /// Left rear wheel counts in the step `n_L` (signed; the difference of
    /// two readings of the wrapping counter).
    pub n_l: i32,
    /// Right rear wheel counts in the step `n_R` (signed).
    pub n_r: i32,
    /// Front wheel counts in the step `n_F` (signed).
    pub n_f: i32,
    /// Steering encoder position `n_S`: counts from straight ahead (the
    /// steering angle at the step, not an increment).
    pub n_s: i32,
}

/// Dead reckoning with slip rejection: the geometry, the selection rule,
/// the integration, a sine/cosine source and the current pose.
/// Allocation-free; one [`Odometry::step`] per sampling period.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Odometry<T, S> {
    /// The robot.
    pub tricycle: Tricycle<T>,
    /// The slip-rejection rule.
    pub selection: Selection,
    /// Euler (paper) or midpoint heading.
    pub integration: Integration,
    /// Sine and cosine: [`Libm`](crate::cordic::Libm) or a
    /// [`Cordic`](crate::cordic::Cordic).
    pub trig: S,
    pose: Pose<T>,
}

impl<T: Real, S: SinCos<T>> Odometry<T, S> {
    /// Dead reckoning from `pose`.
    pub fn new(
        tricycle: Tricycle<T>,
        selection: Selection,
        integration: Integration,
        trig: S,
        pose: Pose<T>,
    ) -> Self {
        Self {
            tricycle,
            selection,
            integration,
            trig,
            pose,
        }
    }

    /// The current pose.
    #[inline]
    pub fn pose(&self) -> Pose<T> {
        self.pose
    }

    /// Replaces the pose (e.g. after an absolute fix); the heading is
    /// wrapped.
    #[inline]
    pub fn set_pose(&mut self, pose: Pose<T>) {
        self.pose = Pose::new(pose.x, pose.y, pose.theta);
    }

    /// Both sources' increments `(rear, front)` of a reading at the current
    /// pose, before selection.
    #[inline]
    pub fn increments(&self, reading: &Reading) -> (Increment<T>, Increment<T>) {
        let t = &self.tricycle;
        let th = self.pose.theta;
        let rear =
            t.rear_motion(reading.n_l, reading.n_r)
                .increment(th, self.integration, &self.trig);
        let front = t
            .front_motion_counts(reading.n_f, reading.n_s, &self.trig)
            .increment(th, self.integration, &self.trig);
        (rear, front)
    }

    /// One step: the selected increment, which is also applied to the pose.
    #[inline]
    pub fn step(&mut self, reading: &Reading) -> Increment<T> {
        let inc = match self.selection {
            // A single source needs only its own sines and cosines.
            Selection::Rear => self
                .tricycle
                .rear_motion(reading.n_l, reading.n_r)
                .increment(self.pose.theta, self.integration, &self.trig),
            Selection::Front => self
                .tricycle
                .front_motion_counts(reading.n_f, reading.n_s, &self.trig)
                .increment(self.pose.theta, self.integration, &self.trig),
            _ => {
                let (rear, front) = self.increments(reading);
                select(self.selection, &rear, &front)
            }
        };
        self.pose = inc.apply(&self.pose);
        inc
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cordic::Libm;

    #[test]
    fn steering_clamp_and_check() {
        let s = Steering::<f64>::assumed();
        let q = s.quantum();
        assert!((q - 0.18f64.to_radians()).abs() < 1e-15);
        // 40 deg is 222.2 counts: 222 is in range, 223 is not.
        assert!(s.checked_angle(222).is_ok());
        assert_eq!(s.checked_angle(223), Err(Error::SteeringOutOfRange));
        assert_eq!(s.checked_angle(-223), Err(Error::SteeringOutOfRange));
        assert_eq!(s.angle(223), s.limit);
        assert_eq!(s.angle(-1000), -s.limit);
        assert_eq!(s.angle(100), 100.0 * q);
        // The front motion uses the clamped angle.
        let t = Tricycle::<f64>::assumed();
        let a = t.front_motion_counts(500, 400, &Libm);
        let b = t.front_motion(500, 40f64.to_radians(), &Libm);
        assert_eq!(a, b);
    }

    #[test]
    fn selection_rules() {
        let r = Increment {
            dx: 0.010,
            dy: -0.002,
            dtheta: 0.001,
        };
        let f = Increment {
            dx: 0.009,
            dy: -0.003,
            dtheta: -0.0005,
        };
        let m = select(Selection::ComponentMin, &r, &f);
        assert_eq!((m.dx, m.dy, m.dtheta), (0.009, -0.002, -0.0005));
        // |r|^2 = 1.04e-4 > |f|^2 = 0.9e-4: the front set.
        assert_eq!(select(Selection::ConsistentSet, &r, &f), f);
        assert_eq!(select(Selection::Rear, &r, &f), r);
        assert_eq!(select(Selection::Front, &r, &f), f);
        // Ties go to the rear.
        assert_eq!(select(Selection::ConsistentSet, &r, &r), r);
    }

    #[test]
    fn rear_motion_formulas() {
        let t = Tricycle::<f64>::assumed();
        let m = t.rear_motion(1000, 3000);
        let k = core::f64::consts::PI * 0.05 / 2000.0;
        assert!((m.ds - k * 4000.0).abs() < 1e-15);
        assert!((m.dtheta - 2.0 * k * 2000.0 / 0.4).abs() < 1e-14);
        // A full circle on the spot: n_R = -n_L, one wheel rolls pi D.
        let n = (core::f64::consts::PI * 0.4 / (2.0 * k)) as i32;
        let spin = t.rear_motion(-n, n);
        assert_eq!(spin.ds, 0.0);
        assert!((spin.dtheta - 2.0 * core::f64::consts::PI).abs() < 1e-3);
    }

    #[test]
    fn pose_wraps_and_f32_works() {
        let p = Increment {
            dx: 0.0,
            dy: 0.0,
            dtheta: 0.1,
        }
        .apply(&Pose::new(0.0f32, 0.0, 3.1));
        assert!(p.theta < 0.0 && (p.theta + 2.0 * core::f32::consts::PI - 3.2).abs() < 1e-5);
        let mut odo = Odometry::new(
            Tricycle::<f32>::assumed(),
            Selection::ConsistentSet,
            Integration::Euler,
            crate::cordic::Cordic::PAPER,
            Pose::default(),
        );
        for _ in 0..100 {
            odo.step(&Reading {
                n_l: 64,
                n_r: 64,
                n_f: 53,
                n_s: 0,
            });
        }
        // 100 x min(64 rear counts, 53 front counts) of travel, front's 53
        // counts x 0.1885 mm = 9.99 mm per step: ~1 m.
        assert!((odo.pose().x - 0.999).abs() < 2e-3, "{:?}", odo.pose());
    }
}
