//! Unicycle motion from commanded velocities, integrated exactly along the arc.
//!
//! Not from a seed paper: this is the motion model of recorded logs whose
//! odometry is a forward speed and a turn rate, such as the UTIAS MRCLAM
//! dataset (commanded `v`, `omega`, held constant between records).
//!
//! State `X = [x, y, theta]` (m, m, rad): the robot's centre in the world
//! frame, heading from the world x axis (counter-clockwise); `f` returns theta
//! wrapped to (-pi, pi]. Input [`Velocities`]: forward speed `v` (m/s, along
//! the robot's x axis), turn rate `omega` (rad/s, counter-clockwise positive),
//! held constant for `dt` (s, >= 0).
//!
//! Exact integration of `x_dot = v cos(theta)`, `y_dot = v sin(theta)`,
//! `theta_dot = omega` over `dt`, written in the chord form that has no
//! singularity at `omega = 0`:
//!
//! ```text
//! h = omega dt / 2        a = theta + h        d = v dt sinc(h),  sinc(h) = sin(h)/h, sinc(0) = 1
//! x' = x + d cos(a)       y' = y + d sin(a)    theta' = theta + omega dt
//! ```
//!
//! (equal to the textbook `x + v/omega (sin(theta + omega dt) - sin(theta))`,
//! `y - v/omega (cos(theta + omega dt) - cos(theta))` for `omega != 0`, and to
//! the straight line `x + v dt cos(theta)` in the limit). `sinc` and its
//! derivative are evaluated by their Taylor series for `|h| < 0.05`, where the
//! closed forms lose digits to cancellation, and by the closed forms above.
//!
//! Process noise `q = [e_v, e_omega]` (m/s, rad/s): errors of the velocities,
//! constant over the step, added to `v` and `omega`.
//! `Q = diag(var_v + rel_var_v v^2, var_omega + rel_var_omega omega^2)`.
//!
//! Jacobians, with `s = sinc(h)`, `s' = dsinc/dh`:
//!
//! ```text
//! A = [[1, 0, -d sin(a)], [0, 1, d cos(a)], [0, 0, 1]]
//! W = [[dt s cos(a), v dt^2/2 s' cos(a) - d dt/2 sin(a)],
//!      [dt s sin(a), v dt^2/2 s' sin(a) + d dt/2 cos(a)],
//!      [0,           dt                               ]]
//! ```
//!
//! Valid for any state and any finite input; `dt < 0` integrates backwards.

use locus_core::nalgebra::{Matrix2, SMatrix, SVector, Vector3};
use locus_core::{MotionJacobians, MotionModel, Scalar, cast, wrap_angle};

/// Commanded velocities held over one step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Velocities<T> {
    /// Forward speed along the robot's x axis, m/s.
    pub v: T,
    /// Turn rate, rad/s, counter-clockwise positive.
    pub omega: T,
    /// Duration of the step, s (>= 0).
    pub dt: T,
}

/// Below this `|h|` (rad), `sinc` and its derivative use their Taylor series.
const SERIES_BELOW: f64 = 0.05;

/// `sinc(h) = sin(h)/h` and its derivative `(h cos h - sin h)/h^2`.
///
/// Series below `|h| < 0.05`: the omitted terms are below 1e-16 relative
/// (`h^8/9!` and `h^9/(11 * 9!)`).
#[inline]
fn sinc_and_derivative<T: Scalar>(h: T) -> (T, T) {
    if h.abs() < cast::<T>(SERIES_BELOW) {
        let h2 = h * h;
        // sinc = 1 - h^2/6 + h^4/120 - h^6/5040
        let s = T::one()
            - h2 / cast::<T>(6.0)
                * (T::one() - h2 / cast::<T>(20.0) * (T::one() - h2 / cast::<T>(42.0)));
        // sinc' = -h/3 + h^3/30 - h^5/840 + h^7/45360
        let ds = -h / cast::<T>(3.0)
            * (T::one()
                - h2 / cast::<T>(10.0)
                    * (T::one() - h2 / cast::<T>(28.0) * (T::one() - h2 / cast::<T>(54.0))));
        (s, ds)
    } else {
        let (sn, cs) = h.sin_cos();
        (sn / h, (h * cs - sn) / (h * h))
    }
}

/// Unicycle motion from forward speed and turn rate, exact arc integration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Unicycle<T: Scalar> {
    /// Variance of the speed error independent of the speed, (m/s)^2 (>= 0).
    pub var_v: T,
    /// Variance of the turn-rate error independent of the rate, (rad/s)^2
    /// (>= 0).
    pub var_omega: T,
    /// Variance of the relative speed error (dimensionless, >= 0): adds
    /// `rel_var_v v^2` to the speed variance.
    pub rel_var_v: T,
    /// Variance of the relative turn-rate error (dimensionless, >= 0): adds
    /// `rel_var_omega omega^2` to the turn-rate variance.
    pub rel_var_omega: T,
}

impl<T: Scalar> Unicycle<T> {
    /// A model with constant velocity-error variances `var_v` ((m/s)^2) and
    /// `var_omega` ((rad/s)^2), and no speed-proportional part.
    pub fn new(var_v: T, var_omega: T) -> Self {
        Self {
            var_v,
            var_omega,
            rel_var_v: T::zero(),
            rel_var_omega: T::zero(),
        }
    }

    /// The same model with speed-proportional variances (dimensionless
    /// relative variances of `v` and `omega`).
    pub fn with_relative(mut self, rel_var_v: T, rel_var_omega: T) -> Self {
        self.rel_var_v = rel_var_v;
        self.rel_var_omega = rel_var_omega;
        self
    }

    /// The chord `(d, a)`: length `d = v dt sinc(omega dt / 2)` (m) and
    /// direction `a = theta + omega dt / 2` (rad) of the step from `theta`.
    #[inline]
    pub fn chord(&self, theta: T, u: &Velocities<T>) -> (T, T) {
        let h = u.omega * u.dt * cast::<T>(0.5);
        let (s, _) = sinc_and_derivative(h);
        (u.v * u.dt * s, theta + h)
    }
}

impl<T: Scalar> MotionModel<T, 3, 2> for Unicycle<T> {
    type Input = Velocities<T>;

    /// The exact arc with `A` and `W` beside it: one `sinc` and one
    /// `sin_cos`.
    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        u: &Velocities<T>,
        q: &SVector<T, 2>,
        jacobians: Option<&mut MotionJacobians<T, 3, 2>>,
    ) -> SVector<T, 3> {
        let (v, omega) = (u.v + q[0], u.omega + q[1]);
        let half_dt = u.dt * cast::<T>(0.5);
        let h = omega * half_dt;
        let (sc, dsc) = sinc_and_derivative(h);
        let d = v * u.dt * sc;
        let (s, c) = (x[2] + h).sin_cos();
        if let Some(j) = jacobians {
            let (o, z) = (T::one(), T::zero());
            j.a = SMatrix::<T, 3, 3>::new(o, z, -d * s, z, o, d * c, z, z, o);
            // d(d)/d(omega) = v dt sinc'(h) dt/2;  d(a)/d(omega) = dt/2.
            let dd_dw = v * u.dt * dsc * half_dt;
            j.w = SMatrix::<T, 3, 2>::new(
                u.dt * sc * c,
                dd_dw * c - d * half_dt * s,
                u.dt * sc * s,
                dd_dw * s + d * half_dt * c,
                z,
                u.dt,
            );
        }
        Vector3::new(x[0] + d * c, x[1] + d * s, wrap_angle(x[2] + omega * u.dt))
    }

    fn noise_cov(&self, u: &Velocities<T>) -> SMatrix<T, 2, 2> {
        Matrix2::new(
            self.var_v + self.rel_var_v * u.v * u.v,
            T::zero(),
            T::zero(),
            self.var_omega + self.rel_var_omega * u.omega * u.omega,
        )
    }

    fn input_is_finite(&self, u: &Velocities<T>) -> bool {
        u.v.is_finite() && u.omega.is_finite() && u.dt.is_finite()
    }

    fn state_residual(&self, a: &SVector<T, 3>, b: &SVector<T, 3>) -> SVector<T, 3> {
        Vector3::new(a[0] - b[0], a[1] - b[1], wrap_angle(a[2] - b[2]))
    }
}

#[cfg(test)]
mod tests {
    use super::sinc_and_derivative;

    #[test]
    fn series_and_closed_forms_agree_at_the_switch() {
        // Just below and above |h| = 0.05 the two branches agree to rounding.
        for h in [
            0.049_999_999f64,
            0.050_000_001,
            -0.049_999_999,
            -0.050_000_001,
        ] {
            let (s, ds) = sinc_and_derivative(h);
            let (sn, cs) = h.sin_cos();
            assert!((s - sn / h).abs() < 1e-15, "sinc at {h}");
            assert!((ds - (h * cs - sn) / (h * h)).abs() < 1e-12, "sinc' at {h}");
        }
        assert_eq!(sinc_and_derivative(0.0f64), (1.0, 0.0));
    }
}
