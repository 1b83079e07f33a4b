//! The unicycle with its own calibration as states: a robot whose logged
//! velocities (commanded, or from uncalibrated encoders) are off by a scale
//! factor and whose turn rate has a bias, and whose landmark sensor reads
//! bearings with a bias.
//!
//! State `[x, y, theta, s_v, s_omega, b_omega, b_bearing]` (m, m, rad, -, -,
//! rad/s, rad). The pose moves as [`Unicycle`] with the effective
//! velocities
//!
//! `v_e = s_v v + q_v`, `omega_e = s_omega omega + b_omega + q_omega`,
//!
//! where `q_v`, `q_omega` are white noises of power spectral densities
//! `psd_v` (m^2/s) and `psd_omega` (rad^2/s) (variance `psd / dt` over a step
//! of `dt`). The four calibration states are slowly varying: each is a
//! random walk of power spectral density `walk[i]` (variance `walk[i] dt`
//! per step), so the filter can follow a drift (a battery running down, a
//! floor changing) and never becomes certain of a value for good. The
//! bearing bias does not move the robot; it is read by
//! [`CalibratedRangeBearing`](crate::calibrated_range_bearing::CalibratedRangeBearing).
//!
//! This is the classic state augmentation for sensor and odometry
//! calibration (e.g. Roumeliotis and Bekey, "3-D localization for a Mars
//! rover prototype", ICRA 1999; Martinelli et al., "Simultaneous
//! localization and odometry self calibration for mobile robot", Autonomous
//! Robots 22, 2007).

use locus_core::nalgebra::{SMatrix, SVector};
use locus_core::{MotionJacobians, MotionModel, Scalar, wrap_angle};

use crate::unicycle::{Unicycle, Velocities};

/// Index of the forward-speed scale factor in the state.
pub const V_SCALE: usize = 3;
/// Index of the turn-rate scale factor in the state.
pub const OMEGA_SCALE: usize = 4;
/// Index of the turn-rate bias (rad/s) in the state.
pub const OMEGA_BIAS: usize = 5;
/// Index of the bearing bias (rad) in the state.
pub const BEARING_BIAS: usize = 6;

/// The unicycle with scale factors and biases as states (see the module
/// documentation). Input: the logged [`Velocities`] over `dt`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibratedUnicycle<T: Scalar> {
    /// Power spectral density of the forward-speed noise, m^2/s.
    pub psd_v: T,
    /// Power spectral density of the turn-rate noise, rad^2/s.
    pub psd_omega: T,
    /// Random-walk power spectral densities of `s_v` (1/s), `s_omega`
    /// (1/s), `b_omega` (rad^2/s^3) and `b_bearing` (rad^2/s).
    pub walk: [T; 4],
}

impl<T: Scalar> CalibratedUnicycle<T> {
    /// The pose model at the effective velocities of `x`'s calibration, and
    /// those velocities.
    #[inline]
    fn effective(&self, x: &SVector<T, 7>, u: &Velocities<T>) -> Velocities<T> {
        Velocities {
            v: x[V_SCALE] * u.v,
            omega: x[OMEGA_SCALE] * u.omega + x[OMEGA_BIAS],
            dt: u.dt,
        }
    }

    fn pose(x: &SVector<T, 7>) -> SVector<T, 3> {
        SVector::<T, 3>::new(x[0], x[1], x[2])
    }
}

/// One prediction step with what it computed on the way: the smoother
/// needs the Jacobian and `A P` of the very prediction the filter made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Propagation<T: Scalar> {
    /// The predicted mean `f(x, u, 0)`.
    pub x: SVector<T, 7>,
    /// The predicted covariance `A P A^T + W Q W^T` (exactly symmetric).
    pub p: SMatrix<T, 7, 7>,
    /// The state Jacobian `A`.
    pub a: SMatrix<T, 7, 7>,
    /// The product `A P`.
    pub ap: SMatrix<T, 7, 7>,
}

impl<T: Scalar> CalibratedUnicycle<T> {
    /// [`MotionModel::propagate`] (which is this without the by-products)
    /// with `A` and `A P` as well, from one linearisation: `A` is the
    /// identity except the pose rows, which reach only heading and
    /// calibration columns; `W` maps the two velocity noises into the pose
    /// and each random walk onto its own state. About a sixth of the dense
    /// products' work.
    #[inline]
    pub fn propagate_linearized(
        &self,
        x: &SVector<T, 7>,
        u: &Velocities<T>,
        p: &SMatrix<T, 7, 7>,
    ) -> Propagation<T> {
        let (fx, a, w) = self.linearize(x, u);
        // B = A P: rows 0-2 are P's plus their off-identity terms.
        let mut b = *p;
        for r in 0..3 {
            for c in 0..7 {
                let mut v = p[(r, c)];
                for k in 2..=OMEGA_BIAS {
                    if k != r {
                        v += a[(r, k)] * p[(k, c)];
                    }
                }
                b[(r, c)] = v;
            }
        }
        // P- = B A^T: columns 0-2 likewise; then symmetric by construction
        // of the lower triangle mirrored.
        let mut out = b;
        for r in 0..7 {
            for c in 0..3 {
                let mut v = b[(r, c)];
                for k in 2..=OMEGA_BIAS {
                    if k != c {
                        v += b[(r, k)] * a[(c, k)];
                    }
                }
                out[(r, c)] = v;
            }
        }
        // W Q W^T: the velocity noises into the pose block, the walks on
        // the calibration diagonal.
        let q = self.noise_cov(u);
        for r in 0..3 {
            for c in 0..3 {
                out[(r, c)] +=
                    w[(r, 0)] * q[(0, 0)] * w[(c, 0)] + w[(r, 1)] * q[(1, 1)] * w[(c, 1)];
            }
        }
        for i in 0..4 {
            out[(V_SCALE + i, V_SCALE + i)] += q[(2 + i, 2 + i)];
        }
        // Exactly symmetric: the upper triangle from the lower.
        for r in 0..7 {
            for c in (r + 1)..7 {
                out[(r, c)] = out[(c, r)];
            }
        }
        Propagation {
            x: fx,
            p: out,
            a,
            ap: b,
        }
    }
}

/// The pose part's model: white noise only; its variances are set per step.
fn pose_model<T: Scalar>() -> Unicycle<T> {
    Unicycle::new(T::zero(), T::zero())
}

impl<T: Scalar> MotionModel<T, 7, 6> for CalibratedUnicycle<T> {
    type Input = Velocities<T>;

    /// The pose model at the effective velocities, the calibration held
    /// (plus its walk `q[2..6]`); with `A` and `W` from the pose model's one
    /// linearisation (one `sinc` and one `sin_cos`): the scales and the bias
    /// act through the effective velocities.
    fn evaluate(
        &self,
        x: &SVector<T, 7>,
        u: &Velocities<T>,
        q: &SVector<T, 6>,
        jacobians: Option<&mut MotionJacobians<T, 7, 6>>,
    ) -> SVector<T, 7> {
        let e = self.effective(x, u);
        // `g` = d pose / d(v_e, omega_e), the pose model's noise Jacobian.
        let mut pose_jacobians = MotionJacobians::<T, 3, 2>::zeros();
        let pose = pose_model::<T>().evaluate(
            &Self::pose(x),
            &e,
            &SVector::<T, 2>::new(q[0], q[1]),
            jacobians.is_some().then_some(&mut pose_jacobians),
        );
        let mut out = *x;
        out[0] = pose[0];
        out[1] = pose[1];
        out[2] = pose[2];
        for i in 0..4 {
            out[V_SCALE + i] += q[2 + i];
        }
        out[BEARING_BIAS] = wrap_angle(out[BEARING_BIAS]);
        if let Some(j) = jacobians {
            let (a3, g) = (pose_jacobians.a, pose_jacobians.w);
            j.a = SMatrix::<T, 7, 7>::identity();
            j.w = SMatrix::<T, 7, 6>::zeros();
            for r in 0..3 {
                for c in 0..3 {
                    j.a[(r, c)] = a3[(r, c)];
                }
                j.a[(r, V_SCALE)] = g[(r, 0)] * u.v;
                j.a[(r, OMEGA_SCALE)] = g[(r, 1)] * u.omega;
                j.a[(r, OMEGA_BIAS)] = g[(r, 1)];
                j.w[(r, 0)] = g[(r, 0)];
                j.w[(r, 1)] = g[(r, 1)];
            }
            for i in 0..4 {
                j.w[(V_SCALE + i, 2 + i)] = T::one();
            }
        }
        out
    }

    fn noise_cov(&self, u: &Velocities<T>) -> SMatrix<T, 6, 6> {
        let mut q = SMatrix::<T, 6, 6>::zeros();
        q[(0, 0)] = self.psd_v / u.dt;
        q[(1, 1)] = self.psd_omega / u.dt;
        for i in 0..4 {
            q[(2 + i, 2 + i)] = self.walk[i] * u.dt;
        }
        q
    }

    fn input_is_finite(&self, u: &Velocities<T>) -> bool {
        u.v.is_finite() && u.omega.is_finite() && u.dt.is_finite() && u.dt > T::zero()
    }

    /// `A P A^T + W Q W^T` with `A`'s structure (see
    /// [`CalibratedUnicycle::propagate_linearized`]).
    #[inline]
    fn propagate(
        &self,
        x: &SVector<T, 7>,
        u: &Velocities<T>,
        p: &SMatrix<T, 7, 7>,
    ) -> (SVector<T, 7>, SMatrix<T, 7, 7>) {
        let step = self.propagate_linearized(x, u, p);
        (step.x, step.p)
    }

    fn state_residual(&self, a: &SVector<T, 7>, b: &SVector<T, 7>) -> SVector<T, 7> {
        let mut d = a - b;
        d[2] = wrap_angle(d[2]);
        d[BEARING_BIAS] = wrap_angle(d[BEARING_BIAS]);
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use locus_core::jacobian_check::{check_motion_model, check_propagate};

    fn model() -> CalibratedUnicycle<f64> {
        CalibratedUnicycle {
            psd_v: 0.01,
            psd_omega: 0.02,
            walk: [1e-6, 2e-6, 3e-7, 4e-8],
        }
    }

    #[test]
    fn jacobians_match_finite_differences() {
        let m = model();
        for (x, u) in [
            (
                SVector::<f64, 7>::from([1.0, -2.0, 0.7, 1.1, 0.8, 0.02, -0.01]),
                Velocities {
                    v: 0.3,
                    omega: 0.5,
                    dt: 0.1,
                },
            ),
            (
                SVector::<f64, 7>::from([0.0, 0.0, -3.0, 0.9, 1.2, -0.05, 0.03]),
                Velocities {
                    v: -0.2,
                    omega: 1e-4,
                    dt: 0.02,
                },
            ),
            (
                SVector::<f64, 7>::from([5.0, 1.0, 2.9, 1.0, 1.0, 0.0, 0.0]),
                Velocities {
                    v: 0.0,
                    omega: -2.0,
                    dt: 0.5,
                },
            ),
        ] {
            check_motion_model(&m, &x, &u, 1e-6, 1e-6).unwrap();
            let mut p = SMatrix::<f64, 7, 7>::identity() * 0.01;
            p[(0, 2)] = 0.003;
            p[(2, 0)] = 0.003;
            check_propagate(&m, &x, &u, &p, 1e-12).unwrap();
            let step = m.propagate_linearized(&x, &u, &p);
            assert_eq!((step.x, step.p), m.propagate(&x, &u, &p));
            assert_eq!(step.a, m.jacobian_state(&x, &u));
            assert!((step.ap - step.a * p).abs().max() < 1e-15);
        }
    }

    #[test]
    fn unit_calibration_moves_as_the_plain_unicycle() {
        let m = model();
        let x = SVector::<f64, 7>::from([1.0, 2.0, 0.3, 1.0, 1.0, 0.0, 0.0]);
        let u = Velocities {
            v: 0.4,
            omega: -0.6,
            dt: 0.2,
        };
        let plain = Unicycle::new(0.0, 0.0).f(
            &SVector::<f64, 3>::new(1.0, 2.0, 0.3),
            &u,
            &SVector::zeros(),
        );
        let cal = m.f(&x, &u, &SVector::zeros());
        for i in 0..3 {
            assert_eq!(cal[i], plain[i]);
        }
    }

    #[test]
    fn scale_and_bias_change_the_motion_as_stated() {
        let m = model();
        let x = SVector::<f64, 7>::from([0.0, 0.0, 0.0, 0.5, 1.0, 0.1, 0.0]);
        let u = Velocities {
            v: 1.0,
            omega: 0.0,
            dt: 1.0,
        };
        let y = m.f(&x, &u, &SVector::zeros());
        // Half the logged speed; turned by the bias alone.
        assert!((y[2] - 0.1).abs() < 1e-15);
        assert!((y[0].hypot(y[1]) - 0.5).abs() < 1e-3);
    }
}
