//! Tricycle odometry (paper 004, eq. 1-6): the motion of a robot whose front
//! wheel drives and steers, with two passive encoder-carrying rear wheels.
//!
//! State `X = [x, y, theta]` (m, m, rad): the midpoint of the rear axle in the
//! world frame, heading from the world x axis (counter-clockwise). `f` returns
//! theta wrapped to (-pi, pi]. Both models integrate the step by Euler, as the
//! paper does: with a path increment `ds` along the heading and a heading
//! increment `dth`,
//!
//! ```text
//! x' = x + ds cos(theta)    y' = y + ds sin(theta)    theta' = theta + dth
//! A = df/dX = [[1, 0, -ds sin(theta)], [0, 1, ds cos(theta)], [0, 0, 1]]
//! ```
//!
//! The two models differ in where `(ds, dth)` come from:
//!
//! * [`TricycleRear`] (eq. 1-3), from the rear-wheel counts `n_L`, `n_R`:
//!   `ds = pi R (n_R + n_L) / N`, `dth = 2 pi R (n_R - n_L) / (N D)`;
//! * [`TricycleFront`] (eq. 4-6), from the front-wheel count `n_F` and the
//!   steering angle `phi`: `dsF = 2 pi R n_F / N`, `ds = dsF cos(phi)`,
//!   `dth = dsF sin(phi) / L` (spec **\[fix\]**: the y equation uses
//!   `cos(phi) sin(theta)`, not the text's `cos(theta) sin(phi)`).
//!
//! `N` is the number of **counts per wheel revolution** (`4 x lines x G` with
//! x4 quadrature decoding, see [`counts_per_rev`]), `R` the wheel's radius,
//! `D` the rear track, `L` the wheelbase. Counts are signed (negative when the
//! wheel turns backwards); a caller reading a wrapping 20-bit counter takes the
//! difference modulo 2^20 before handing it here.
//!
//! Process noise enters on the raw readings, not on the pose, so that `W`
//! is the exact `df/dq` and `Q` has units a user can measure:
//!
//! * rear: `q = [e_nL, e_nR]` (counts), added to `n_L`, `n_R`;
//! * front: `q = [e_nF, e_phi]` (counts, rad), added to `n_F` and to the
//!   (limited) steering angle.
//!
//! A count's variance is [`CountNoise::variance`]: a floor (quantisation,
//! 1/12 count^2 for a rounding error uniform over one count) plus a term
//! proportional to the number of counts (slip and wheel-radius error grow
//! with the distance rolled).
//!
//! **Steering limit.** The steering angle is mechanically limited to
//! `+-steering_limit` (\[assumed\] 40 deg). A reading beyond the limit is
//! **clamped** to it (the wheel cannot be past its stop, so the reading is
//! taken as the stop plus sensor error); the noise `e_phi` is added after the
//! clamp, so `f` stays smooth in `q` and `W` is exact everywhere. A caller who
//! prefers to reject such readings (for example to flag a faulty steering
//! encoder) tests [`TricycleFront::steering_in_range`] first. A non-finite
//! reading is rejected (`predict` fails with `Error::NonFinite(Control)`).
//!
//! All models are valid for any state and any finite input.

use locus_core::nalgebra::{Matrix2, SMatrix, SVector, Vector3};
use locus_core::{MotionJacobians, MotionModel, Scalar, cast, wrap_angle};

/// Counts per wheel revolution with x4 quadrature decoding: `4 x lines x G`,
/// where `lines` is the encoder's lines per encoder-shaft revolution and `G`
/// the encoder-shaft revolutions per wheel revolution (spec section 5).
/// \[assumed\] 500 lines and `G = 1` give 2000 counts per revolution.
#[inline]
pub fn counts_per_rev<T: Scalar>(lines: T, gear: T) -> T {
    cast::<T>(4.0) * lines * gear
}

/// The variance model of an encoder count over one step (counts^2):
/// `var(n) = floor + per_count * |n|`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CountNoise<T> {
    /// Variance independent of the motion, counts^2 (>= 0). Quantisation
    /// alone gives 1/12.
    pub floor: T,
    /// Variance added per count rolled, counts^2 per count (>= 0): slip,
    /// radius error and the like, growing with the distance.
    pub per_count: T,
}

impl<T: Scalar> CountNoise<T> {
    /// \[assumed\] defaults: quantisation floor 1/12 count^2 plus 0.1 count^2
    /// per count (with R = 0.05 m, N = 2000: about 4 mm standard deviation
    /// over one metre).
    pub fn assumed() -> Self {
        Self {
            floor: cast::<T>(1.0 / 12.0),
            per_count: cast::<T>(0.1),
        }
    }

    /// The variance of a reading of `n` counts, counts^2.
    #[inline]
    pub fn variance(&self, n: T) -> T {
        self.floor + self.per_count * n.abs()
    }
}

/// Counts of the two rear wheels in one step (counts, signed; may be
/// fractional if averaged or resampled).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RearCounts<T> {
    /// Left rear wheel `n_L`, counts.
    pub n_l: T,
    /// Right rear wheel `n_R`, counts.
    pub n_r: T,
}

impl<T: Scalar> RearCounts<T> {
    /// From integer counts (differences of the wrapping counters, already
    /// taken modulo 2^20).
    pub fn from_counts(n_l: i32, n_r: i32) -> Self {
        Self {
            n_l: cast::<T>(f64::from(n_l)),
            n_r: cast::<T>(f64::from(n_r)),
        }
    }
}

/// The front wheel's reading in one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontReading<T> {
    /// Front (driving) wheel count `n_F`, counts, signed.
    pub n_f: T,
    /// Steering angle `phi`, rad, positive to the left (counter-clockwise
    /// turn when driving forwards). Clamped to the model's steering limit.
    pub phi: T,
}

impl<T: Scalar> FrontReading<T> {
    /// From an integer count and a steering angle (rad).
    pub fn from_count(n_f: i32, phi: T) -> Self {
        Self {
            n_f: cast::<T>(f64::from(n_f)),
            phi,
        }
    }
}

/// The Euler step shared by both models, `(x + ds cos th, y + ds sin th,
/// th + dth)`, with `A = df/dX` written into `a` when given; returns the
/// step and `(sin th, cos th)` for the noise Jacobian.
#[inline]
fn euler_step<T: Scalar>(
    x: &SVector<T, 3>,
    ds: T,
    dth: T,
    a: Option<&mut SMatrix<T, 3, 3>>,
) -> (SVector<T, 3>, (T, T)) {
    let (s, c) = x[2].sin_cos();
    if let Some(a) = a {
        let (o, z) = (T::one(), T::zero());
        *a = SMatrix::<T, 3, 3>::new(o, z, -ds * s, z, o, ds * c, z, z, o);
    }
    (
        Vector3::new(x[0] + ds * c, x[1] + ds * s, wrap_angle(x[2] + dth)),
        (s, c),
    )
}

#[inline]
fn pose_residual<T: Scalar>(a: &SVector<T, 3>, b: &SVector<T, 3>) -> SVector<T, 3> {
    Vector3::new(a[0] - b[0], a[1] - b[1], wrap_angle(a[2] - b[2]))
}

/// Tricycle odometry from the two passive rear wheels (paper 004, eq. 1-3).
///
/// Input [`RearCounts`] (counts); noise `q = [e_nL, e_nR]` (counts) added to
/// the counts, `Q = diag(var(n_L), var(n_R))` from [`CountNoise`].
///
/// With `k = pi R / N`:
/// `ds = k (n_R + n_L)`, `dth = 2 k (n_R - n_L) / D`, and
/// `W = [[k cos(theta), k cos(theta)], [k sin(theta), k sin(theta)], [-2k/D, 2k/D]]`
/// (columns: `e_nL`, `e_nR`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TricycleRear<T: Scalar> {
    /// Rear wheel radius `R`, m (> 0). \[assumed\] 0.05 m.
    pub radius: T,
    /// Counts per rear-wheel revolution `N` (> 0), see [`counts_per_rev`].
    /// \[assumed\] 2000.
    pub counts_per_rev: T,
    /// Rear track `D` (distance between the rear wheels), m (> 0).
    /// \[assumed\] 0.40 m.
    pub track: T,
    /// Variance model of each rear count.
    pub noise: CountNoise<T>,
}

impl<T: Scalar> TricycleRear<T> {
    /// A model with wheel radius `R` (m), `N` counts per revolution, track
    /// `D` (m) and the count noise.
    pub fn new(radius: T, counts_per_rev: T, track: T, noise: CountNoise<T>) -> Self {
        Self {
            radius,
            counts_per_rev,
            track,
            noise,
        }
    }

    /// The spec's \[assumed\] values: R = 0.05 m, N = 2000 (500 lines, x4,
    /// G = 1), D = 0.40 m, [`CountNoise::assumed`].
    pub fn assumed() -> Self {
        Self::new(
            cast::<T>(0.05),
            counts_per_rev(cast::<T>(500.0), T::one()),
            cast::<T>(0.40),
            CountNoise::assumed(),
        )
    }

    /// `pi R / N` (m per count): one wheel rolls `2 pi R / N` per count, and
    /// `ds` averages the two wheels (eq. 1).
    #[inline]
    fn k(&self) -> T {
        T::pi() * self.radius / self.counts_per_rev
    }

    /// The increments `(ds, dth)` (m, rad) of a reading (eq. 1-2):
    /// `ds = pi R (n_R + n_L) / N`, `dth = 2 pi R (n_R - n_L) / (N D)`.
    /// Useful on their own for slip rejection (spec section 5).
    #[inline]
    pub fn increments(&self, u: &RearCounts<T>) -> (T, T) {
        let k = self.k();
        (k * (u.n_r + u.n_l), (k + k) * (u.n_r - u.n_l) / self.track)
    }
}

impl<T: Scalar> MotionModel<T, 3, 2> for TricycleRear<T> {
    type Input = RearCounts<T>;

    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        u: &RearCounts<T>,
        q: &SVector<T, 2>,
        jacobians: Option<&mut MotionJacobians<T, 3, 2>>,
    ) -> SVector<T, 3> {
        let noisy = RearCounts {
            n_l: u.n_l + q[0],
            n_r: u.n_r + q[1],
        };
        let (ds, dth) = self.increments(&noisy);
        let Some(j) = jacobians else {
            return euler_step(x, ds, dth, None).0;
        };
        let (next, (s, c)) = euler_step(x, ds, dth, Some(&mut j.a));
        let k = self.k();
        let kd = (k + k) / self.track;
        j.w = SMatrix::<T, 3, 2>::new(k * c, k * c, k * s, k * s, -kd, kd);
        next
    }

    fn noise_cov(&self, u: &RearCounts<T>) -> SMatrix<T, 2, 2> {
        Matrix2::new(
            self.noise.variance(u.n_l),
            T::zero(),
            T::zero(),
            self.noise.variance(u.n_r),
        )
    }

    fn input_is_finite(&self, u: &RearCounts<T>) -> bool {
        u.n_l.is_finite()
            && u.n_r.is_finite()
            && self.radius.is_finite()
            && self.counts_per_rev.is_finite()
            && self.track.is_finite()
    }

    fn state_residual(&self, a: &SVector<T, 3>, b: &SVector<T, 3>) -> SVector<T, 3> {
        pose_residual(a, b)
    }
}

/// Tricycle odometry from the driving, steering front wheel (paper 004,
/// eq. 4-6, with the spec's **\[fix\]** to the y equation).
///
/// Input [`FrontReading`] (counts, rad); noise `q = [e_nF, e_phi]` (counts,
/// rad), `Q = diag(var(n_F), var_phi)`. The steering angle used is
/// `phi_c + e_phi` with `phi_c = clamp(phi, -limit, +limit)`.
///
/// With `k = 2 pi R / N`, `dsF = k n_F`:
///
/// ```text
/// x' = x + dsF cos(phi) cos(theta)
/// y' = y + dsF cos(phi) sin(theta)
/// theta' = theta + dsF sin(phi) / L
/// W = [[k cos(phi) cos(theta), -dsF sin(phi) cos(theta)],
///      [k cos(phi) sin(theta), -dsF sin(phi) sin(theta)],
///      [k sin(phi) / L,         dsF cos(phi) / L       ]]
/// ```
///
/// The state's position is the rear-axle midpoint: the front wheel's arc
/// projected on the heading, `dsF cos(phi)`, is the rear axle's travel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TricycleFront<T: Scalar> {
    /// Front wheel radius `R`, m (> 0). \[assumed\] 0.06 m.
    pub radius: T,
    /// Counts per front-wheel revolution `N` (> 0). \[assumed\] 2000.
    pub counts_per_rev: T,
    /// Wheelbase `L` (rear axle to front wheel), m (> 0). \[assumed\] 0.45 m.
    pub wheelbase: T,
    /// Steering limit, rad (> 0): readings are clamped to `[-limit, limit]`.
    /// \[assumed\] 40 deg (paper 004).
    pub steering_limit: T,
    /// Variance model of the front count.
    pub noise: CountNoise<T>,
    /// Variance of the steering-angle error `e_phi`, rad^2 (>= 0).
    /// \[assumed\] (0.5 deg)^2.
    pub var_phi: T,
}

impl<T: Scalar> TricycleFront<T> {
    /// A model with wheel radius `R` (m), `N` counts per revolution,
    /// wheelbase `L` (m), steering limit (rad), count noise and steering
    /// variance (rad^2).
    pub fn new(
        radius: T,
        counts_per_rev: T,
        wheelbase: T,
        steering_limit: T,
        noise: CountNoise<T>,
        var_phi: T,
    ) -> Self {
        Self {
            radius,
            counts_per_rev,
            wheelbase,
            steering_limit,
            noise,
            var_phi,
        }
    }

    /// The spec's \[assumed\] values: R = 0.06 m, N = 2000, L = 0.45 m,
    /// limit 40 deg, [`CountNoise::assumed`], steering sigma 0.5 deg.
    pub fn assumed() -> Self {
        let deg = T::pi() / cast::<T>(180.0);
        let sigma_phi = cast::<T>(0.5) * deg;
        Self::new(
            cast::<T>(0.06),
            counts_per_rev(cast::<T>(500.0), T::one()),
            cast::<T>(0.45),
            cast::<T>(40.0) * deg,
            CountNoise::assumed(),
            sigma_phi * sigma_phi,
        )
    }

    /// Whether a steering reading (rad) lies within `+-steering_limit`.
    /// Readings outside are clamped by the model; test this first to reject
    /// them instead.
    #[inline]
    pub fn steering_in_range(&self, phi: T) -> bool {
        phi.abs() <= self.steering_limit
    }

    /// The steering angle the model uses: `phi` clamped to
    /// `[-steering_limit, steering_limit]` (rad).
    #[inline]
    pub fn clamped_steering(&self, phi: T) -> T {
        phi.max(-self.steering_limit).min(self.steering_limit)
    }

    #[inline]
    fn k(&self) -> T {
        T::two_pi() * self.radius / self.counts_per_rev
    }

    /// The increments `(ds, dth)` (m, rad) of a reading (eq. 4-6): the
    /// rear-axle travel along the heading `ds = dsF cos(phi)` and
    /// `dth = dsF sin(phi) / L`, with `dsF = 2 pi R n_F / N` and `phi`
    /// clamped. Useful on their own for slip rejection (spec section 5).
    #[inline]
    pub fn increments(&self, u: &FrontReading<T>) -> (T, T) {
        self.increments_noisy(u, T::zero(), T::zero())
    }

    #[inline]
    fn increments_noisy(&self, u: &FrontReading<T>, e_n: T, e_phi: T) -> (T, T) {
        let ds_f = self.k() * (u.n_f + e_n);
        let (s, c) = (self.clamped_steering(u.phi) + e_phi).sin_cos();
        (ds_f * c, ds_f * s / self.wheelbase)
    }
}

impl<T: Scalar> MotionModel<T, 3, 2> for TricycleFront<T> {
    type Input = FrontReading<T>;

    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        u: &FrontReading<T>,
        q: &SVector<T, 2>,
        jacobians: Option<&mut MotionJacobians<T, 3, 2>>,
    ) -> SVector<T, 3> {
        let (ds, dth) = self.increments_noisy(u, q[0], q[1]);
        let Some(j) = jacobians else {
            return euler_step(x, ds, dth, None).0;
        };
        let (next, (st, ct)) = euler_step(x, ds, dth, Some(&mut j.a));
        let k = self.k();
        let ds_f = k * (u.n_f + q[0]);
        let (sp, cp) = (self.clamped_steering(u.phi) + q[1]).sin_cos();
        let l = self.wheelbase;
        j.w = SMatrix::<T, 3, 2>::new(
            k * cp * ct,
            -ds_f * sp * ct,
            k * cp * st,
            -ds_f * sp * st,
            k * sp / l,
            ds_f * cp / l,
        );
        next
    }

    fn noise_cov(&self, u: &FrontReading<T>) -> SMatrix<T, 2, 2> {
        Matrix2::new(
            self.noise.variance(u.n_f),
            T::zero(),
            T::zero(),
            self.var_phi,
        )
    }

    fn input_is_finite(&self, u: &FrontReading<T>) -> bool {
        u.n_f.is_finite()
            && u.phi.is_finite()
            && self.radius.is_finite()
            && self.counts_per_rev.is_finite()
            && self.wheelbase.is_finite()
            && self.steering_limit.is_finite()
    }

    fn state_residual(&self, a: &SVector<T, 3>, b: &SVector<T, 3>) -> SVector<T, 3> {
        pose_residual(a, b)
    }
}
