//! The unicycle with its own calibration as states: a robot whose logged
//! velocities (commanded, or from uncalibrated encoders) are off by a scale
//! factor and whose turn rate has a bias, and whose landmark sensor reads
//! bearings with a bias.
//!
//! State `[x, y, theta, s_v, s_omega, b_omega, b_bearing, b_range]` (m, m,
//! rad, -, -, rad/s, rad, m). The pose moves as [`Unicycle`] with the
//! effective velocities
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
//! The range bias `b_range` is the part of a beam sensor's range error that
//! persists from reading to reading (read by
//! [`PlanarBeam`](crate::planar_beam::PlanarBeam)): a first-order
//! Gauss-Markov process of stationary standard deviation `sigma` and time
//! constant `tau` ([`GaussMarkov`]), `b_k = phi b_(k-1) + w`,
//! `phi = exp(-dt / tau)`, `var(w) = sigma^2 (1 - phi^2)`, the exact
//! discretisation (Gelb, "Applied Optimal Estimation", 1974, section
//! 3.8, the shaping filter for correlated measurement noise). With `tau`
//! infinite it is a constant: `phi = 1`, no noise.
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
/// Index of the beam sensors' range bias (m) in the state.
pub const RANGE_BIAS: usize = 7;
/// Dimension of the state.
pub const STATE: usize = 8;
/// Dimension of the process noise: the two velocity noises, the four
/// calibration walks and the range bias's driving noise.
pub const NOISE: usize = 7;

/// A first-order Gauss-Markov process: stationary standard deviation
/// `sigma` and time constant `tau` (s; infinite: a constant).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussMarkov<T: Scalar> {
    /// Stationary standard deviation (the unit of the state).
    pub sigma: T,
    /// Time constant, s (> 0; infinite for a constant).
    pub tau: T,
}

impl<T: Scalar> GaussMarkov<T> {
    /// The factor `phi = exp(-dt / tau)` over `dt` (s).
    #[inline]
    pub fn decay(&self, dt: T) -> T {
        (-dt / self.tau).exp()
    }

    /// The driving noise's variance over `dt`: `sigma^2 (1 - phi^2)`.
    #[inline]
    pub fn step_variance(&self, dt: T) -> T {
        let phi = self.decay(dt);
        self.sigma * self.sigma * (T::one() - phi * phi)
    }
}

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
    /// The range bias's process (m, s).
    pub range_bias: GaussMarkov<T>,
}

impl<T: Scalar> CalibratedUnicycle<T> {
    /// The pose model at the effective velocities of `x`'s calibration, and
    /// those velocities.
    #[inline]
    fn effective(&self, x: &SVector<T, STATE>, u: &Velocities<T>) -> Velocities<T> {
        Velocities {
            v: x[V_SCALE] * u.v,
            omega: x[OMEGA_SCALE] * u.omega + x[OMEGA_BIAS],
            dt: u.dt,
        }
    }

    fn pose(x: &SVector<T, STATE>) -> SVector<T, 3> {
        SVector::<T, 3>::new(x[0], x[1], x[2])
    }
}

/// One prediction step with what it computed on the way: the smoother
/// needs the Jacobian and `A P` of the very prediction the filter made.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Propagation<T: Scalar> {
    /// The predicted mean `f(x, u, 0)`.
    pub x: SVector<T, STATE>,
    /// The predicted covariance `A P A^T + W Q W^T` (exactly symmetric).
    pub p: SMatrix<T, STATE, STATE>,
    /// The state Jacobian `A`.
    pub a: SMatrix<T, STATE, STATE>,
    /// The product `A P`.
    pub ap: SMatrix<T, STATE, STATE>,
}

impl<T: Scalar> CalibratedUnicycle<T> {
    /// [`MotionModel::propagate`] (which is this without the by-products)
    /// with `A` and `A P` as well, from one linearisation: `A` is the
    /// identity except the pose rows, which reach only heading and
    /// calibration columns, and the range bias's decay on its diagonal;
    /// `W` maps the two velocity noises into the pose and each random walk
    /// and the bias's driving noise onto its own state. About a sixth of
    /// the dense products' work.
    #[inline]
    pub fn propagate_linearized(
        &self,
        x: &SVector<T, STATE>,
        u: &Velocities<T>,
        p: &SMatrix<T, STATE, STATE>,
    ) -> Propagation<T> {
        let (fx, a, w) = self.linearize(x, u);
        // B = A P: rows 0-2 are P's plus their off-identity terms.
        let mut b = *p;
        for r in 0..3 {
            for c in 0..STATE {
                let mut v = p[(r, c)];
                for k in 2..=OMEGA_BIAS {
                    if k != r {
                        v += a[(r, k)] * p[(k, c)];
                    }
                }
                b[(r, c)] = v;
            }
        }
        let phi = a[(RANGE_BIAS, RANGE_BIAS)];
        for c in 0..STATE {
            b[(RANGE_BIAS, c)] = phi * p[(RANGE_BIAS, c)];
        }
        // P- = B A^T: columns 0-2 likewise; then symmetric by construction
        // of the lower triangle mirrored.
        let mut out = b;
        for r in 0..STATE {
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
        // Columns 3-6 of A are the identity's; column 7 is the decay (the
        // lower triangle's only entry off it is the diagonal).
        out[(RANGE_BIAS, RANGE_BIAS)] = phi * b[(RANGE_BIAS, RANGE_BIAS)];
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
        out[(RANGE_BIAS, RANGE_BIAS)] += q[(6, 6)];
        // Exactly symmetric: the upper triangle from the lower.
        for r in 0..STATE {
            for c in (r + 1)..STATE {
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

impl<T: Scalar> MotionModel<T, STATE, NOISE> for CalibratedUnicycle<T> {
    type Input = Velocities<T>;

    /// The pose model at the effective velocities, the calibration held
    /// (plus its walk `q[2..6]`); with `A` and `W` from the pose model's one
    /// linearisation (one `sinc` and one `sin_cos`): the scales and the bias
    /// act through the effective velocities.
    fn evaluate(
        &self,
        x: &SVector<T, STATE>,
        u: &Velocities<T>,
        q: &SVector<T, NOISE>,
        jacobians: Option<&mut MotionJacobians<T, STATE, NOISE>>,
    ) -> SVector<T, STATE> {
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
        let phi = self.range_bias.decay(u.dt);
        out[RANGE_BIAS] = phi * x[RANGE_BIAS] + q[6];
        if let Some(j) = jacobians {
            let (a3, g) = (pose_jacobians.a, pose_jacobians.w);
            j.a = SMatrix::<T, STATE, STATE>::identity();
            j.w = SMatrix::<T, STATE, NOISE>::zeros();
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
            j.a[(RANGE_BIAS, RANGE_BIAS)] = phi;
            j.w[(RANGE_BIAS, 6)] = T::one();
        }
        out
    }

    fn noise_cov(&self, u: &Velocities<T>) -> SMatrix<T, NOISE, NOISE> {
        let mut q = SMatrix::<T, NOISE, NOISE>::zeros();
        q[(0, 0)] = self.psd_v / u.dt;
        q[(1, 1)] = self.psd_omega / u.dt;
        for i in 0..4 {
            q[(2 + i, 2 + i)] = self.walk[i] * u.dt;
        }
        q[(6, 6)] = self.range_bias.step_variance(u.dt);
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
        x: &SVector<T, STATE>,
        u: &Velocities<T>,
        p: &SMatrix<T, STATE, STATE>,
    ) -> (SVector<T, STATE>, SMatrix<T, STATE, STATE>) {
        let step = self.propagate_linearized(x, u, p);
        (step.x, step.p)
    }

    fn state_residual(&self, a: &SVector<T, STATE>, b: &SVector<T, STATE>) -> SVector<T, STATE> {
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
            range_bias: GaussMarkov {
                sigma: 0.02,
                tau: 3.0,
            },
        }
    }

    #[test]
    fn jacobians_match_finite_differences() {
        let m = model();
        for (x, u) in [
            (
                SVector::<f64, STATE>::from([1.0, -2.0, 0.7, 1.1, 0.8, 0.02, -0.01, 0.01]),
                Velocities {
                    v: 0.3,
                    omega: 0.5,
                    dt: 0.1,
                },
            ),
            (
                SVector::<f64, STATE>::from([0.0, 0.0, -3.0, 0.9, 1.2, -0.05, 0.03, -0.02]),
                Velocities {
                    v: -0.2,
                    omega: 1e-4,
                    dt: 0.02,
                },
            ),
            (
                SVector::<f64, STATE>::from([5.0, 1.0, 2.9, 1.0, 1.0, 0.0, 0.0, 0.0]),
                Velocities {
                    v: 0.0,
                    omega: -2.0,
                    dt: 0.5,
                },
            ),
        ] {
            check_motion_model(&m, &x, &u, 1e-6, 1e-6).unwrap();
            let mut p = SMatrix::<f64, STATE, STATE>::identity() * 0.01;
            p[(0, 2)] = 0.003;
            p[(2, 0)] = 0.003;
            check_propagate(&m, &x, &u, &p, 1e-12).unwrap();
            let step = m.propagate_linearized(&x, &u, &p);
            assert_eq!((step.x, step.p), m.propagate(&x, &u, &p));
            assert_eq!(step.a, m.jacobian_state(&x, &u));
            assert!((step.ap - step.a * p).abs().max() < 1e-15);
        }
    }

    /// The range bias decays by `exp(-dt/tau)` and its variance tends to
    /// `sigma^2`; with `tau` infinite it and its variance stay as they are.
    #[test]
    fn the_range_bias_is_a_gauss_markov_process() {
        let mut m = model();
        let u = Velocities {
            v: 0.3,
            omega: 0.1,
            dt: 0.5,
        };
        let mut x = SVector::<f64, STATE>::from([0.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 0.04]);
        let y = m.f(&x, &u, &SVector::zeros());
        assert!((y[RANGE_BIAS] - 0.04 * (-0.5f64 / 3.0).exp()).abs() < 1e-15);
        let mut p = SMatrix::<f64, STATE, STATE>::identity() * 1e-4;
        for _ in 0..200 {
            p = m.propagate_linearized(&x, &u, &p).p;
        }
        assert!((p[(RANGE_BIAS, RANGE_BIAS)] - 0.02f64.powi(2)).abs() < 1e-9);
        m.range_bias.tau = f64::INFINITY;
        x[RANGE_BIAS] = 0.04;
        let p0 = SMatrix::<f64, STATE, STATE>::identity() * 1e-4;
        let step = m.propagate_linearized(&x, &u, &p0);
        assert_eq!(step.x[RANGE_BIAS], 0.04);
        assert_eq!(step.p[(RANGE_BIAS, RANGE_BIAS)], 1e-4);
    }

    #[test]
    fn unit_calibration_moves_as_the_plain_unicycle() {
        let m = model();
        let x = SVector::<f64, STATE>::from([1.0, 2.0, 0.3, 1.0, 1.0, 0.0, 0.0, 0.0]);
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
        let x = SVector::<f64, STATE>::from([0.0, 0.0, 0.0, 0.5, 1.0, 0.1, 0.0, 0.0]);
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
