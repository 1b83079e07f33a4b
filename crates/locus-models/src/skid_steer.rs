//! Skid-steer motion from tread speeds, Euler integration (paper 000, eq. 7-10;
//! spec `MODELS.md` section 2).
//!
//! State `X = [x, y, theta]` (m, m, rad): the robot's reference point and
//! heading in the world (global) frame. `f` returns theta wrapped to
//! (-pi, pi] (a correction may leave it slightly outside; the next prediction
//! wraps it again, and every angle difference is wrapped).
//!
//! Input: the left and right tread speeds `V_L`, `V_R` (m/s, from the
//! encoders, positive forwards) and the sample time `dT` (s), see
//! [`TreadSpeeds`]. A skid-steer robot (the paper's Pioneer 3-AT) turns about
//! an *effective* track width `D` that is larger than its geometric track,
//! because the wheels skid sideways while turning (\[assumed\] default
//! [`DEFAULT_EFFECTIVE_TRACK`] = 0.50 m; configurable).
//!
//! ```text
//! v      = (V_L + V_R)/2
//! x'     = x + dT v cos(theta)                                      (eq. 7)
//! y'     = y + dT v sin(theta)
//! theta' = theta + dT (V_R - V_L)/D
//! ```
//!
//! Process noise on the tread speeds `q = e = [V_Le, V_Re]` (m/s), the
//! measured speed being the true one plus `e` (eq. 8), `Q = diag(s_VL^2,
//! s_VR^2)` (m^2/s^2). The noise enters `f` as `V_L + V_Le`, `V_R + V_Re`.
//! Jacobians at `q = 0`:
//!
//! ```text
//! A = df/dX = [[1, 0, -dT v sin(theta)],                            (eq. 9)
//!              [0, 1,  dT v cos(theta)],
//!              [0, 0,  1]]
//! W = df/de = [[dT/2 cos(theta), dT/2 cos(theta)],                  (eq. 10)
//!              [dT/2 sin(theta), dT/2 sin(theta)],
//!              [-dT/D,           dT/D          ]]
//! ```
//!
//! and the covariance prediction is `P- = A P+ A^T + W Q W^T` (eq. 11).
//! Valid everywhere for `D > 0`; `dT >= 0` is expected but not required.

use locus_core::nalgebra::{Matrix2, SMatrix, SVector, Vector3};
use locus_core::{MotionJacobians, MotionModel, Scalar, cast, wrap_angle};

/// The \[assumed\] effective track width `D` of the paper's Pioneer 3-AT (m).
/// The paper does not give it; for a skid-steer robot it is larger than the
/// geometric track because the wheels skid sideways while turning.
pub const DEFAULT_EFFECTIVE_TRACK: f64 = 0.50;

/// The input of one skid-steer step: tread speeds and sample time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TreadSpeeds<T> {
    /// Left tread speed `V_L` (m/s), positive forwards.
    pub v_l: T,
    /// Right tread speed `V_R` (m/s), positive forwards.
    pub v_r: T,
    /// Sample time `dT` (s) over which the speeds are held.
    pub dt: T,
}

impl<T: Scalar> TreadSpeeds<T> {
    /// Tread speeds `V_L`, `V_R` (m/s) held for `dT` (s).
    pub fn new(v_l: T, v_r: T, dt: T) -> Self {
        Self { v_l, v_r, dt }
    }
}

/// The skid-steer motion model of paper 000 (eq. 7-10).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SkidSteer<T: Scalar> {
    /// Effective track width `D` (m, > 0).
    pub track_width: T,
    /// Variance of the left tread-speed noise `s_VL^2` (m^2/s^2).
    pub var_vl: T,
    /// Variance of the right tread-speed noise `s_VR^2` (m^2/s^2).
    pub var_vr: T,
}

impl<T: Scalar> SkidSteer<T> {
    /// A model with effective track width `D` (m) and tread-speed noise
    /// variances `s_VL^2`, `s_VR^2` (m^2/s^2).
    pub fn new(track_width: T, var_vl: T, var_vr: T) -> Self {
        Self {
            track_width,
            var_vl,
            var_vr,
        }
    }

    /// A model with the \[assumed\] Pioneer 3-AT effective track
    /// [`DEFAULT_EFFECTIVE_TRACK`] (0.50 m) and the given noise variances
    /// (m^2/s^2).
    pub fn pioneer_3at(var_vl: T, var_vr: T) -> Self {
        Self::new(cast(DEFAULT_EFFECTIVE_TRACK), var_vl, var_vr)
    }

    /// `(v, omega)`: the forward speed `(V_L + V_R)/2` (m/s) and the turn rate
    /// `(V_R - V_L)/D` (rad/s) of an input.
    #[inline]
    pub fn speeds(&self, u: &TreadSpeeds<T>) -> (T, T) {
        (
            (u.v_l + u.v_r) * cast::<T>(0.5),
            (u.v_r - u.v_l) / self.track_width,
        )
    }
}

impl<T: Scalar> MotionModel<T, 3, 2> for SkidSteer<T> {
    type Input = TreadSpeeds<T>;

    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        u: &TreadSpeeds<T>,
        q: &SVector<T, 2>,
        jacobians: Option<&mut MotionJacobians<T, 3, 2>>,
    ) -> SVector<T, 3> {
        let noisy = TreadSpeeds::new(u.v_l + q[0], u.v_r + q[1], u.dt);
        let (v, omega) = self.speeds(&noisy);
        let (s, c) = x[2].sin_cos();
        if let Some(j) = jacobians {
            let (o, z) = (T::one(), T::zero());
            j.a = SMatrix::<T, 3, 3>::new(o, z, -u.dt * v * s, z, o, u.dt * v * c, z, z, o);
            let half_dt = u.dt * cast::<T>(0.5);
            let k = u.dt / self.track_width;
            j.w =
                SMatrix::<T, 3, 2>::new(half_dt * c, half_dt * c, half_dt * s, half_dt * s, -k, k);
        }
        Vector3::new(
            x[0] + u.dt * v * c,
            x[1] + u.dt * v * s,
            wrap_angle(x[2] + u.dt * omega),
        )
    }

    fn noise_cov(&self, _u: &TreadSpeeds<T>) -> SMatrix<T, 2, 2> {
        Matrix2::new(self.var_vl, T::zero(), T::zero(), self.var_vr)
    }

    fn input_is_finite(&self, u: &TreadSpeeds<T>) -> bool {
        u.v_l.is_finite() && u.v_r.is_finite() && u.dt.is_finite() && self.track_width.is_finite()
    }

    fn state_residual(&self, a: &SVector<T, 3>, b: &SVector<T, 3>) -> SVector<T, 3> {
        Vector3::new(a[0] - b[0], a[1] - b[1], wrap_angle(a[2] - b[2]))
    }
}
