//! One 3-state EKF step of paper 001 (differential-drive predict, then one
//! 2-D IR-wall correction), measured side by side for:
//!
//! * `locus_*`     the generic Locus API (`Ekf::predict` + `Ekf::correct`) with
//!   `locus_models::DiffDrive` / `IrPairObservation`, Joseph and Plain;
//! * `closed_*`    the same step in closed form (scalar code, hand-expanded
//!   3x3 / 2x2 algebra, plain update, same model equations): the near-limit
//!   reference;
//! * `nalgebra_*`  hand-written plain nalgebra (SMatrix ops, `try_inverse` of
//!   S, plain update), with a hand linearisation (one `sin_cos` per predict);
//! * `user_plain_*` the minimal user model (`UserDrive`, `UserIr`: the same
//!   equations written the way the traits' documentation shows first) through
//!   the Locus API, plain update; `builtin_user_*` the built-in `DiffDrive`
//!   with that user's measurement model;
//! * `nalgebra_checked_*` plain nalgebra with the user's models and the
//!   guarantees Locus gives (inputs and outputs checked finite, `P-` exactly
//!   symmetric, `S` checked positive definite): what the guarantees cost;
//! * `nalgebra_modelcalls_f64` the same, but evaluating the models through
//!   the Locus traits (`f`, `jacobian_state`, `process_noise`, `h`,
//!   `jacobian`, `noise`): separates model-evaluation cost from filter cost;
//! * `adskalman_*` adskalman 0.18: its linear predict with `F = A`,
//!   `Q = W Q W^T` evaluated at the current state (mean replaced by `f(x)`),
//!   its update with `H` and `R = V R V^T`;
//!
//! plus the correction alone (group `correct`).
//!
//! Before timing, every variant is run once on the same inputs and asserted to
//! give the same posterior (f64: 1e-9; f32: against the f64 reference).
//!
//! After criterion's own output, a table is printed from criterion's
//! `estimates.json` files of this run (mean point estimate, median alongside):
//! ns per call, ratio to the closed form and to plain nalgebra of the same
//! precision and group, and the speed-up over the seed-003 timings of one
//! correction (Table 3). The directory is `$CRITERION_HOME`, else
//! `$CARGO_TARGET_DIR/criterion`, else `<target>/criterion` next to this binary.
//!
//! Then two interleaved tables of the step variants (round robin, fastest
//! batch of each; see `print_interleaved`): independent steps (throughput)
//! and chained steps (each step starts from the previous posterior: the
//! latency a filter sees). `scripts/bench_instructions.sh` counts the
//! instructions per step of the same variants under callgrind
//! (`EKF_STEP_RUN=<variant>:<n>[:chained]` runs one variant and exits;
//! `EKF_STEP_INTERLEAVED=1` prints only the interleaved tables).
//!
//! Note: timings of generic code depend on LLVM's inlining decisions, which
//! depend on how many instances share a nalgebra operator in the binary;
//! compare variants within one run.
//!
//! Run: `cargo bench -p locus-core --bench ekf_step` (criterion arguments,
//! e.g. a filter, go after `--`).

// A std-only benchmark binary: the no_std lints of the workspace do not apply.
#![allow(clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

use std::hint::black_box;
use std::path::PathBuf;
use std::time::{Duration, SystemTime};

use adskalman::{
    CovarianceUpdateMethod, ObservationModel, StateAndCovariance, TransitionModelLinearNoControl,
};
use criterion::Criterion;
use locus_core::nalgebra::{Matrix2, Matrix2x3, Matrix3, Matrix3x2, U2, U3, Vector2, Vector3};
use locus_core::{
    Belief, CovarianceUpdate, Ekf, MeasurementModel, MotionJacobians, MotionModel, Scalar, cast,
    schedule, wrap_angle,
};
use locus_models::{AxisWall, DiffDrive, IrPair, IrPairObservation, WallAxis, WheelTravel};

// ---------------------------------------------------------------------------
// Inputs: a robot running along wall x+ of the 1 m arena (path 0.15 m from it)

/// Everything one step reads.
#[derive(Debug, Clone, Copy)]
struct Inputs<T: Scalar> {
    /// The posterior of the previous step.
    belief: Belief<T, 3>,
    motion: DiffDrive<T>,
    u: WheelTravel<T>,
    obs: IrPairObservation<T>,
    /// `obs.z()`, computed once: the measurement is an input of the step.
    z: Vector2<T>,
}

fn inputs<T: Scalar>() -> Inputs<T> {
    let c = cast::<T>;
    // Near wall x+ (x = 1), on the path x = 0.85, heading +y (pi/2), slightly
    // turned away from the wall; a correlated covariance of about 1 cm / 1 deg.
    let x = Vector3::new(c(0.852), c(-0.31), c(core::f64::consts::FRAC_PI_2 + 0.025));
    let p = Matrix3::new(
        c(1.0e-4),
        c(2.0e-5),
        c(1.0e-5),
        c(2.0e-5),
        c(2.5e-4),
        c(-3.0e-5),
        c(1.0e-5),
        c(-3.0e-5),
        c(3.0e-4),
    );
    // Lego NXT: 11.2 cm wheelbase, a 1 cm step turning slightly left.
    let motion = DiffDrive::new(c(0.112), c(1.0e-6), c(7.6e-5));
    let u = WheelTravel {
        d1: c(0.0102),
        d2: c(0.0098),
    };
    // IR pair 10 cm apart, readings ~0.15 m, sigma 2 cm (spec [assumed]).
    let obs = IrPairObservation {
        pair: IrPair::centred(c(0.10)),
        wall: AxisWall::x_plus(c(1.0)),
        ds1: c(0.1525),
        ds2: c(0.1497),
        r11: c(4.0e-4),
        r22: c(4.0e-4),
    };
    Inputs {
        belief: Belief::new(x, p),
        motion,
        u,
        obs,
        z: obs.z(),
    }
}

// ---------------------------------------------------------------------------
// a. The generic Locus API

fn locus_step<T: Scalar>(ekf: &Ekf<T>, inp: &Inputs<T>) -> Belief<T, 3> {
    let prior = ekf
        .predict(&inp.belief, &inp.motion, &inp.u)
        .expect("predict");
    ekf.correct(&prior, &inp.obs, &inp.z)
        .expect("correct")
        .belief
}

// ---------------------------------------------------------------------------
// a2. The minimal user model: what a user writes first, the way the
// traits' documentation shows (the required methods only, the dense
// defaults, no angle wrapping): the same equations as DiffDrive and
// IrPairObservation.

/// A user's differential drive (paper 001, eq. 11-13).
#[derive(Debug, Clone, Copy)]
struct UserDrive<T: Scalar> {
    wheelbase: T,
    q11: T,
    q22: T,
}

impl<T: Scalar> MotionModel<T, 3, 2> for UserDrive<T> {
    type Input = WheelTravel<T>;

    fn evaluate(
        &self,
        x: &Vector3<T>,
        u: &WheelTravel<T>,
        q: &Vector2<T>,
        jacobians: Option<&mut MotionJacobians<T, 3, 2>>,
    ) -> Vector3<T> {
        let half = cast::<T>(0.5);
        let d = (u.d1 + u.d2) * half + q[0];
        let dth = (u.d1 - u.d2) / self.wheelbase + q[1];
        let (s, c) = (x[2] + dth * half).sin_cos();
        if let Some(j) = jacobians {
            let (o, z) = (T::one(), T::zero());
            j.a = Matrix3::new(o, z, -d * s, z, o, d * c, z, z, o);
            j.w = Matrix3x2::new(c, -d * half * s, s, d * half * c, z, o);
        }
        Vector3::new(x[0] + d * c, x[1] + d * s, x[2] + dth)
    }

    fn noise_cov(&self, _u: &WheelTravel<T>) -> Matrix2<T> {
        Matrix2::new(self.q11, T::zero(), T::zero(), self.q22)
    }
}

/// A user's IR pair against wall x+ (paper 001, eq. 14-17).
#[derive(Debug, Clone, Copy)]
struct UserIr<T: Scalar>(IrPairObservation<T>);

impl<T: Scalar> MeasurementModel<T, 3, 2> for UserIr<T> {
    fn evaluate(&self, x: &Vector3<T>, jacobian: Option<&mut Matrix2x3<T>>) -> Option<Vector2<T>> {
        if let Some(j) = jacobian {
            let (o, z) = (T::one(), T::zero());
            *j = Matrix2x3::new(o, z, z, z, z, o);
        }
        Some(Vector2::new(x[0], x[2]))
    }

    fn noise(&self, _x: &Vector3<T>) -> Matrix2<T> {
        let v = self.0.v();
        v * Matrix2::new(self.0.r11, T::zero(), T::zero(), self.0.r22) * v.transpose()
    }
}

fn user_drive<T: Scalar>(m: &DiffDrive<T>) -> UserDrive<T> {
    UserDrive {
        wheelbase: m.wheelbase,
        q11: m.q11,
        q22: m.q22,
    }
}

/// The minimal user model through the Locus API.
fn user_step<T: Scalar>(ekf: &Ekf<T>, inp: &Inputs<T>) -> Belief<T, 3> {
    let prior = ekf
        .predict(&inp.belief, &user_drive(&inp.motion), &inp.u)
        .expect("predict");
    ekf.correct(&prior, &UserIr(inp.obs), &inp.z)
        .expect("correct")
        .belief
}

/// The built-in DiffDrive with the user's plain measurement model.
fn builtin_user_step<T: Scalar>(ekf: &Ekf<T>, inp: &Inputs<T>) -> Belief<T, 3> {
    let prior = ekf
        .predict(&inp.belief, &inp.motion, &inp.u)
        .expect("predict");
    ekf.correct(&prior, &UserIr(inp.obs), &inp.z)
        .expect("correct")
        .belief
}

// ---------------------------------------------------------------------------
// b. Closed form: scalar code, hand-expanded, plain update

/// `(x-, P-)` of the differential-drive predict, P- as a full symmetric array.
#[inline]
fn closed_predict<T: Scalar>(
    b: &Belief<T, 3>,
    m: &DiffDrive<T>,
    u: &WheelTravel<T>,
) -> ([T; 3], [[T; 3]; 3]) {
    let half = cast::<T>(0.5);
    let d = (u.d1 + u.d2) * half;
    let dth = (u.d1 - u.d2) / m.wheelbase;
    let th = b.x[2];
    let (s, c) = (th + dth * half).sin_cos();
    let x = [b.x[0] + d * c, b.x[1] + d * s, wrap_angle(th + dth)];
    // A = [[1, 0, a02], [0, 1, a12], [0, 0, 1]]
    let a02 = -d * s;
    let a12 = d * c;
    let p = &b.p;
    let (p00, p01, p02) = (p[(0, 0)], p[(0, 1)], p[(0, 2)]);
    let (p11, p12, p22) = (p[(1, 1)], p[(1, 2)], p[(2, 2)]);
    let t02 = p02 + a02 * p22;
    let t12 = p12 + a12 * p22;
    // W = [[c, -ws], [s, wc], [0, 1]], Q = diag(q11, q22)
    let ws = d * half * s;
    let wc = d * half * c;
    let (q11, q22) = (m.q11, m.q22);
    let m00 = p00 + a02 * (p02 + t02) + (q11 * c * c + q22 * ws * ws);
    let m01 = p01 + a02 * p12 + a12 * t02 + (q11 * c * s - q22 * ws * wc);
    let m02 = t02 - q22 * ws;
    let m11 = p11 + a12 * (p12 + t12) + (q11 * s * s + q22 * wc * wc);
    let m12 = t12 + q22 * wc;
    let m22 = p22 + q22;
    (x, [[m00, m01, m02], [m01, m11, m12], [m02, m12, m22]])
}

/// The IR correction in closed form (plain update, symmetric result).
#[inline]
fn closed_correct<T: Scalar>(
    x: &[T; 3],
    m: &[[T; 3]; 3],
    o: &IrPairObservation<T>,
    z: &Vector2<T>,
) -> Belief<T, 3> {
    let half = cast::<T>(0.5);
    // V R V^T (eq. 18-20 with the offsets), R = diag(r11, r22).
    // sin and cos of ObsAng = atan(diff / l) without the angle, as the model
    // computes them.
    let l = o.pair.spacing;
    let diff = o.ds1 - o.ds2;
    let den = l * l + diff * diff;
    let kk = l / den;
    let inv_hyp = T::one() / den.sqrt();
    let (sa, ca) = (diff * inv_hyp, l * inv_hyp);
    let a = ca * half;
    let b = -(o.ds1 + o.ds2) * half * sa * kk;
    let g = -(o.pair.lateral_offset * sa + o.pair.forward_offset * ca) * kk;
    let sgn = -o.wall.side_sign();
    let v00 = sgn * (a + b + g);
    let v01 = sgn * (a - b - g);
    let r00 = o.r11 * v00 * v00 + o.r22 * v01 * v01;
    let r01 = kk * (o.r11 * v00 - o.r22 * v01);
    let r11 = kk * kk * (o.r11 + o.r22);
    // H = [[e_k], [e_2]]: P H^T is columns k and 2 of P.
    let k = match o.wall.axis {
        WallAxis::X => 0,
        WallAxis::Y => 1,
    };
    let ph0 = [m[0][k], m[1][k], m[2][k]];
    let ph1 = [m[0][2], m[1][2], m[2][2]];
    let s00 = ph0[k] + r00;
    let s01 = ph0[2] + r01;
    let s11 = ph1[2] + r11;
    let inv_det = T::one() / (s00 * s11 - s01 * s01);
    let (i00, i01, i11) = (s11 * inv_det, -s01 * inv_det, s00 * inv_det);
    let g0 = [0, 1, 2].map(|i| ph0[i] * i00 + ph1[i] * i01);
    let g1 = [0, 1, 2].map(|i| ph0[i] * i01 + ph1[i] * i11);
    let nu0 = z[0] - x[k];
    let nu1 = wrap_angle(z[1] - x[2]);
    let xp = Vector3::new(
        x[0] + g0[0] * nu0 + g1[0] * nu1,
        x[1] + g0[1] * nu0 + g1[1] * nu1,
        x[2] + g0[2] * nu0 + g1[2] * nu1,
    );
    let e = |i: usize, j: usize| m[i][j] - (g0[i] * ph0[j] + g1[i] * ph1[j]);
    let (e00, e01, e02, e11, e12, e22) = (e(0, 0), e(0, 1), e(0, 2), e(1, 1), e(1, 2), e(2, 2));
    let p = Matrix3::new(e00, e01, e02, e01, e11, e12, e02, e12, e22);
    Belief::new(xp, p)
}

fn closed_step<T: Scalar>(inp: &Inputs<T>) -> Belief<T, 3> {
    let (x, p) = closed_predict(&inp.belief, &inp.motion, &inp.u);
    closed_correct(&x, &p, &inp.obs, &inp.z)
}

// ---------------------------------------------------------------------------
// c. Plain nalgebra (and the hand linearisation shared with adskalman)

/// `f(x, u, 0)`, `A` and `W` with one `sin_cos` (same equations as DiffDrive).
#[inline]
fn motion_lin<T: Scalar>(
    b: &Belief<T, 3>,
    m: &DiffDrive<T>,
    u: &WheelTravel<T>,
) -> (Vector3<T>, Matrix3<T>, Matrix3x2<T>) {
    let half = cast::<T>(0.5);
    let d = (u.d1 + u.d2) * half;
    let dth = (u.d1 - u.d2) / m.wheelbase;
    let (s, c) = (b.x[2] + dth * half).sin_cos();
    let x = Vector3::new(b.x[0] + d * c, b.x[1] + d * s, wrap_angle(b.x[2] + dth));
    let (o, z) = (T::one(), T::zero());
    let a = Matrix3::new(o, z, -d * s, z, o, d * c, z, z, o);
    let w = Matrix3x2::new(c, -d * half * s, s, d * half * c, z, o);
    (x, a, w)
}

/// `H`, `h(x)` and `V R V^T` of the IR pair (same equations as IrPairObservation).
#[inline]
fn ir_lin<T: Scalar>(
    o: &IrPairObservation<T>,
    x: &Vector3<T>,
) -> (Matrix2x3<T>, Vector2<T>, Matrix2<T>) {
    let (one, zero) = (T::one(), T::zero());
    let (h, zhat) = match o.wall.axis {
        WallAxis::X => (
            Matrix2x3::new(one, zero, zero, zero, zero, one),
            Vector2::new(x[0], x[2]),
        ),
        WallAxis::Y => (
            Matrix2x3::new(zero, one, zero, zero, zero, one),
            Vector2::new(x[1], x[2]),
        ),
    };
    let v = o.v();
    let r = v * Matrix2::new(o.r11, zero, zero, o.r22) * v.transpose();
    (h, zhat, r)
}

#[inline]
fn nalgebra_correct<T: Scalar>(
    x: &Vector3<T>,
    p: &Matrix3<T>,
    h: &Matrix2x3<T>,
    zhat: &Vector2<T>,
    r: &Matrix2<T>,
    z: &Vector2<T>,
) -> Belief<T, 3> {
    let pht = p * h.transpose();
    let s = h * pht + r;
    let s_inv = s.try_inverse().expect("S singular");
    let g = pht * s_inv;
    let nu = Vector2::new(z[0] - zhat[0], wrap_angle(z[1] - zhat[1]));
    let x = x + g * nu;
    let p = p - g * pht.transpose();
    Belief::new(x, p)
}

fn nalgebra_step<T: Scalar>(inp: &Inputs<T>) -> Belief<T, 3> {
    let m = &inp.motion;
    let (x, a, w) = motion_lin(&inp.belief, m, &inp.u);
    let q = Matrix2::new(m.q11, T::zero(), T::zero(), m.q22);
    let p = a * inp.belief.p * a.transpose() + w * q * w.transpose();
    let (h, zhat, r) = ir_lin(&inp.obs, &x);
    nalgebra_correct(&x, &p, &h, &zhat, &r, &inp.z)
}

/// `nalgebra_step` with the user's models through the traits and the
/// guarantees the Locus filter gives: every input and output checked
/// finite, `P-` exactly symmetric, `S` checked positive definite.
fn nalgebra_checked_step<T: Scalar>(inp: &Inputs<T>) -> Option<Belief<T, 3>> {
    let ok = |v: &[T]| v.iter().fold(T::zero(), |a, b| a + *b * T::zero()) == T::zero();
    let (m, b) = (user_drive(&inp.motion), &inp.belief);
    if !(ok(b.x.as_slice()) && ok(b.p.as_slice())) {
        return None;
    }
    let (x, a, w) = m.linearize(&b.x, &inp.u);
    let p = a * b.p * a.transpose() + w * m.noise_cov(&inp.u) * w.transpose();
    let p = (p + p.transpose()) * cast::<T>(0.5);
    if !(ok(x.as_slice()) && ok(p.as_slice())) {
        return None;
    }
    let o = UserIr(inp.obs);
    let (zhat, h) = o.linearize(&x)?;
    let r = o.noise(&x);
    let pht = p * h.transpose();
    let s = h * pht + r;
    if !(s[(0, 0)] > T::zero() && s.determinant() > T::zero()) {
        return None;
    }
    let s_inv = s.try_inverse()?;
    let nu = inp.z - zhat;
    let y = s_inv * nu;
    if !ok(&[nu.dot(&y)]) {
        return None;
    }
    let g = pht * s_inv;
    Some(Belief::new(x + pht * y, p - g * pht.transpose()))
}

/// Plain nalgebra algebra, models evaluated through the Locus traits.
fn nalgebra_modelcalls_step<T: Scalar>(inp: &Inputs<T>) -> Belief<T, 3> {
    let (m, b, u) = (&inp.motion, &inp.belief, &inp.u);
    let x = m.f(&b.x, u, &Vector2::zeros());
    let a = m.jacobian_state(&b.x, u);
    let p = a * b.p * a.transpose() + m.process_noise(&b.x, u);
    let o = &inp.obs;
    let zhat = o.h(&x).expect("h");
    nalgebra_correct(&x, &p, &o.jacobian(&x), &zhat, &o.noise(&x), &inp.z)
}

// ---------------------------------------------------------------------------
// d. adskalman

struct AdsMotion {
    f: Matrix3<f64>,
    ft: Matrix3<f64>,
    q: Matrix3<f64>,
}

impl TransitionModelLinearNoControl<f64, U3> for AdsMotion {
    fn F(&self) -> &Matrix3<f64> {
        &self.f
    }
    fn FT(&self) -> &Matrix3<f64> {
        &self.ft
    }
    fn Q(&self) -> &Matrix3<f64> {
        &self.q
    }
}

/// `h(x) = H x` is linear for the IR pair, so adskalman's default
/// `predict_observation` is the model (its innovation is not angle-wrapped:
/// harmless here, theta is far from +-pi).
struct AdsObs {
    h: Matrix2x3<f64>,
    ht: Matrix3x2<f64>,
    r: Matrix2<f64>,
}

impl ObservationModel<f64, U3, U2> for AdsObs {
    fn H(&self) -> &Matrix2x3<f64> {
        &self.h
    }
    fn HT(&self) -> &Matrix3x2<f64> {
        &self.ht
    }
    fn R(&self) -> &Matrix2<f64> {
        &self.r
    }
}

fn ads_correct(
    prior: &StateAndCovariance<f64, U3>,
    o: &IrPairObservation<f64>,
    z: &Vector2<f64>,
    method: CovarianceUpdateMethod,
) -> Belief<f64, 3> {
    let (h, _zhat, r) = ir_lin(o, prior.state());
    let obs = AdsObs {
        h,
        ht: h.transpose(),
        r,
    };
    let post = obs.update(prior, z, method).expect("adskalman update");
    Belief::new(*post.state(), *post.covariance())
}

fn adskalman_step(inp: &Inputs<f64>, method: CovarianceUpdateMethod) -> Belief<f64, 3> {
    let m = &inp.motion;
    let (x, a, w) = motion_lin(&inp.belief, m, &inp.u);
    let q = w * Matrix2::new(m.q11, 0.0, 0.0, m.q22) * w.transpose();
    let motion = AdsMotion {
        f: a,
        ft: a.transpose(),
        q,
    };
    let prev = StateAndCovariance::new(inp.belief.x, inp.belief.p);
    let mut prior = motion.predict(&prev);
    // EKF: the mean goes through f, not through F x.
    *prior.state_mut() = x;
    ads_correct(&prior, &inp.obs, &inp.z, method)
}

// ---------------------------------------------------------------------------
// Agreement check (outside the timed loops)

fn max_abs_diff<const R: usize, const C: usize, T: Scalar>(
    a: &locus_core::nalgebra::SMatrix<T, R, C>,
    b: &locus_core::nalgebra::SMatrix<f64, R, C>,
) -> f64 {
    a.iter()
        .zip(b.iter())
        .map(|(x, y)| (locus_core::nalgebra::try_convert::<T, f64>(*x).unwrap() - y).abs())
        .fold(0.0, f64::max)
}

/// Asserts `got` equals `reference`: |dx| <= tol (m, rad) and
/// |dP| <= tol * max|P| (relative to the covariance's scale).
fn assert_same<T: Scalar>(name: &str, got: &Belief<T, 3>, reference: &Belief<f64, 3>, tol: f64) {
    let dx = max_abs_diff(&got.x, &reference.x);
    let scale = reference.p.amax();
    let dp = max_abs_diff(&got.p, &reference.p) / scale;
    assert!(
        dx <= tol && dp <= tol,
        "{name}: posterior differs from the closed form: |dx| = {dx:e}, |dP|/max|P| = {dp:e} (tol {tol:e})"
    );
    println!("agree  {name:<28} |dx| = {dx:8.1e}  |dP|/max|P| = {dp:8.1e}");
}

fn check_agreement() {
    let i64_ = inputs::<f64>();
    let i32_ = inputs::<f32>();
    let joseph = Ekf::<f64>::new(CovarianceUpdate::Joseph);
    let plain = Ekf::<f64>::new(CovarianceUpdate::Plain);
    let reference = closed_step(&i64_);
    // The correction moves the estimate: the check is not vacuous.
    let prior = joseph.predict(&i64_.belief, &i64_.motion, &i64_.u).unwrap();
    assert!((reference.x - prior.x).amax() > 1e-4 && (reference.p - prior.p).amax() > 1e-6);

    let tol = 1e-9;
    assert_same(
        "step/locus_joseph_f64",
        &locus_step(&joseph, &i64_),
        &reference,
        tol,
    );
    assert_same(
        "step/locus_plain_f64",
        &locus_step(&plain, &i64_),
        &reference,
        tol,
    );
    assert_same("step/nalgebra_f64", &nalgebra_step(&i64_), &reference, tol);
    assert_same("step/user_f64", &user_step(&plain, &i64_), &reference, tol);
    assert_same(
        "step/builtin_user_f64",
        &builtin_user_step(&plain, &i64_),
        &reference,
        tol,
    );
    assert_same(
        "step/nalgebra_modelcalls_f64",
        &nalgebra_modelcalls_step(&i64_),
        &reference,
        tol,
    );
    let ads = adskalman_step(&i64_, CovarianceUpdateMethod::JosephForm);
    assert_same("step/adskalman_joseph_f64", &ads, &reference, tol);
    let ads = adskalman_step(&i64_, CovarianceUpdateMethod::OptimalKalman);
    assert_same("step/adskalman_plain_f64", &ads, &reference, tol);

    // f32 against the f64 reference (single precision: ~1e-4 relative).
    let tol32 = 1e-4;
    let j32 = Ekf::<f32>::new(CovarianceUpdate::Joseph);
    let p32 = Ekf::<f32>::new(CovarianceUpdate::Plain);
    assert_same("step/closed_f32", &closed_step(&i32_), &reference, tol32);
    assert_same(
        "step/locus_joseph_f32",
        &locus_step(&j32, &i32_),
        &reference,
        tol32,
    );
    assert_same(
        "step/locus_plain_f32",
        &locus_step(&p32, &i32_),
        &reference,
        tol32,
    );
    assert_same(
        "step/nalgebra_f32",
        &nalgebra_step(&i32_),
        &reference,
        tol32,
    );
    assert_same("step/user_f32", &user_step(&p32, &i32_), &reference, tol32);
    assert_same(
        "step/builtin_user_f32",
        &builtin_user_step(&p32, &i32_),
        &reference,
        tol32,
    );

    // The correction alone, from the generic prior.
    let (x, o, z) = (prior.x, &i64_.obs, &i64_.z);
    let refc = closed_correct(&[x[0], x[1], x[2]], &prior.p.transpose().data.0, o, z);
    assert_same("correct/closed_f64 vs step", &refc, &reference, tol);
    let seq_p = plain.correct_sequential(&prior, o, z).unwrap().belief;
    let seq_j = joseph.correct_sequential(&prior, o, z).unwrap().belief;
    assert_same(
        "correct/locus_joseph_f64",
        &joseph.correct(&prior, o, z).unwrap().belief,
        &refc,
        tol,
    );
    assert_same(
        "correct/locus_plain_f64",
        &plain.correct(&prior, o, z).unwrap().belief,
        &refc,
        tol,
    );
    assert_same("correct/locus_seq_plain_f64", &seq_p, &refc, tol);
    assert_same("correct/locus_seq_joseph_f64", &seq_j, &refc, tol);
    assert_same(
        "correct/schedule_11_f64",
        &schedule::correct_11_step(&prior, o, z).unwrap().belief(),
        &refc,
        tol,
    );
    let (h, zhat, r) = ir_lin(o, &x);
    assert_same(
        "correct/nalgebra_f64",
        &nalgebra_correct(&x, &prior.p, &h, &zhat, &r, z),
        &refc,
        tol,
    );
    let prior_ads = StateAndCovariance::new(prior.x, prior.p);
    let ads = ads_correct(&prior_ads, o, z, CovarianceUpdateMethod::JosephForm);
    assert_same("correct/adskalman_joseph_f64", &ads, &refc, tol);
}

// ---------------------------------------------------------------------------
// Benchmarks

fn bench_step(c: &mut Criterion) {
    let i64_ = inputs::<f64>();
    let i32_ = inputs::<f32>();
    let j64 = Ekf::<f64>::new(CovarianceUpdate::Joseph);
    let p64 = Ekf::<f64>::new(CovarianceUpdate::Plain);
    let j32 = Ekf::<f32>::new(CovarianceUpdate::Joseph);
    let p32 = Ekf::<f32>::new(CovarianceUpdate::Plain);

    let mut g = c.benchmark_group("step");
    g.bench_function("closed_f64", |b| b.iter(|| closed_step(black_box(&i64_))));
    g.bench_function("nalgebra_f64", |b| {
        b.iter(|| nalgebra_step(black_box(&i64_)))
    });
    g.bench_function("locus_plain_f64", |b| {
        b.iter(|| locus_step(black_box(&p64), black_box(&i64_)))
    });
    g.bench_function("locus_joseph_f64", |b| {
        b.iter(|| locus_step(black_box(&j64), black_box(&i64_)))
    });
    g.bench_function("user_plain_f64", |b| {
        b.iter(|| user_step(black_box(&p64), black_box(&i64_)))
    });
    g.bench_function("builtin_user_f64", |b| {
        b.iter(|| builtin_user_step(black_box(&p64), black_box(&i64_)))
    });
    g.bench_function("nalgebra_modelcalls_f64", |b| {
        b.iter(|| nalgebra_modelcalls_step(black_box(&i64_)))
    });
    g.bench_function("adskalman_joseph_f64", |b| {
        b.iter(|| adskalman_step(black_box(&i64_), CovarianceUpdateMethod::JosephForm))
    });
    g.bench_function("adskalman_plain_f64", |b| {
        b.iter(|| adskalman_step(black_box(&i64_), CovarianceUpdateMethod::OptimalKalman))
    });
    g.bench_function("closed_f32", |b| b.iter(|| closed_step(black_box(&i32_))));
    g.bench_function("nalgebra_f32", |b| {
        b.iter(|| nalgebra_step(black_box(&i32_)))
    });
    g.bench_function("locus_plain_f32", |b| {
        b.iter(|| locus_step(black_box(&p32), black_box(&i32_)))
    });
    g.bench_function("locus_joseph_f32", |b| {
        b.iter(|| locus_step(black_box(&j32), black_box(&i32_)))
    });
    g.bench_function("user_plain_f32", |b| {
        b.iter(|| user_step(black_box(&p32), black_box(&i32_)))
    });
    g.bench_function("builtin_user_f32", |b| {
        b.iter(|| builtin_user_step(black_box(&p32), black_box(&i32_)))
    });
    g.finish();
}

fn bench_correct(c: &mut Criterion) {
    let inp = inputs::<f64>();
    let j64 = Ekf::<f64>::new(CovarianceUpdate::Joseph);
    let p64 = Ekf::<f64>::new(CovarianceUpdate::Plain);
    let prior = j64.predict(&inp.belief, &inp.motion, &inp.u).unwrap();
    let (o, z) = (&inp.obs, &inp.z);

    let mut g = c.benchmark_group("correct");
    g.bench_function("closed_f64", |b| {
        b.iter(|| {
            let pr = black_box(&prior);
            // Column-major storage: data.0[i][j] = P[j][i] = P[i][j] (P- is symmetric).
            closed_correct(
                &[pr.x[0], pr.x[1], pr.x[2]],
                &pr.p.data.0,
                black_box(o),
                black_box(z),
            )
        })
    });
    g.bench_function("nalgebra_f64", |b| {
        b.iter(|| {
            let pr = black_box(&prior);
            let (h, zhat, r) = ir_lin(black_box(o), &pr.x);
            nalgebra_correct(&pr.x, &pr.p, &h, &zhat, &r, black_box(z))
        })
    });
    // Every variant yields the posterior belief (what a caller keeps).
    let post = |r: Result<locus_core::Correction<f64, 3, 2>, locus_core::Error>| {
        r.expect("correct").belief
    };
    g.bench_function("locus_plain_f64", |b| {
        b.iter(|| post(black_box(&p64).correct(black_box(&prior), black_box(o), black_box(z))))
    });
    g.bench_function("locus_joseph_f64", |b| {
        b.iter(|| post(black_box(&j64).correct(black_box(&prior), black_box(o), black_box(z))))
    });
    g.bench_function("locus_seq_plain_f64", |b| {
        b.iter(|| {
            post(black_box(&p64).correct_sequential(black_box(&prior), black_box(o), black_box(z)))
        })
    });
    g.bench_function("locus_seq_joseph_f64", |b| {
        b.iter(|| {
            post(black_box(&j64).correct_sequential(black_box(&prior), black_box(o), black_box(z)))
        })
    });
    g.bench_function("schedule_11_f64", |b| {
        b.iter(|| {
            schedule::correct_11_step(black_box(&prior), black_box(o), black_box(z))
                .expect("11-step")
                .belief()
        })
    });
    let prior_ads = StateAndCovariance::new(prior.x, prior.p);
    g.bench_function("adskalman_joseph_f64", |b| {
        b.iter(|| {
            ads_correct(
                black_box(&prior_ads),
                black_box(o),
                black_box(z),
                CovarianceUpdateMethod::JosephForm,
            )
        })
    });
    g.finish();
}

// ---------------------------------------------------------------------------
// Summary table from criterion's estimates.json

/// Criterion's output directory: `$CRITERION_HOME`, else
/// `$CARGO_TARGET_DIR/criterion`, else `<target>/criterion` with `<target>`
/// found from this executable's path (`<target>/<profile>/deps/ekf_step-*`).
fn criterion_dir() -> Option<PathBuf> {
    if let Some(home) = std::env::var_os("CRITERION_HOME") {
        return Some(PathBuf::from(home));
    }
    if let Some(target) = std::env::var_os("CARGO_TARGET_DIR") {
        return Some(PathBuf::from(target).join("criterion"));
    }
    let exe = std::env::current_exe().ok()?;
    Some(exe.parent()?.parent()?.parent()?.join("criterion"))
}

/// The point estimate (ns) of statistic `stat` ("mean", "median") of a
/// criterion `estimates.json`, parsed by hand
/// (`{"mean":{"confidence_interval":{...},"point_estimate":X,...},...}`).
fn point_estimate(json: &str, stat: &str) -> Option<f64> {
    let rest = &json[json.find(&format!("\"{stat}\""))?..];
    let key = "\"point_estimate\"";
    let rest = rest[rest.find(key)? + key.len()..]
        .trim_start()
        .strip_prefix(':')?
        .trim_start();
    let end = rest
        .find(|ch: char| !(ch.is_ascii_digit() || matches!(ch, '.' | '-' | '+' | 'e' | 'E')))
        .unwrap_or(rest.len());
    rest[..end].parse().ok()
}

/// Seed 003, Table 3: time of one correction (us).
const SEED_003: [(&str, f64); 3] = [
    ("Nios II 577us", 577.0),
    ("FPGA core 2.08us", 2.08),
    ("Pentium M 21us", 21.0),
];

fn print_table(started: SystemTime, groups: &[(&str, &[&str])]) {
    let Some(dir) = criterion_dir() else {
        println!("(no criterion directory found: no summary table)");
        return;
    };
    // Only estimates written by this run (a filter may have skipped some).
    // (mean, median) in ns.
    let read = |group: &str, id: &str| -> Option<(f64, f64)> {
        let path = dir.join(group).join(id).join("new").join("estimates.json");
        let fresh = std::fs::metadata(&path).and_then(|m| m.modified()).ok()? >= started;
        if !fresh {
            return None;
        }
        let json = std::fs::read_to_string(&path).ok()?;
        Some((
            point_estimate(&json, "mean")?,
            point_estimate(&json, "median")?,
        ))
    };
    println!();
    println!(
        "Summary (criterion's estimates.json under {}):",
        dir.display()
    );
    println!(
        "ns: criterion's mean point estimate; (median): its median, more robust on a busy machine;"
    );
    println!("x closed / x nalgebra: ratio of the means to the closed form / plain nalgebra");
    println!("  of the same group and precision;");
    println!("seed 003 columns: speed-up (from the mean) over one correction on that platform");
    println!(
        "  (Table 3; the step rows include the predict, the reference is the correction alone)."
    );
    let mut printed = false;
    for (group, ids) in groups {
        let times: Vec<(&str, Option<(f64, f64)>)> =
            ids.iter().map(|id| (*id, read(group, id))).collect();
        if times.iter().all(|(_, t)| t.is_none()) {
            continue;
        }
        printed = true;
        println!();
        println!(
            "{:<26} {:>8} {:>8} {:>9} {:>10}  {:>14} {:>16} {:>14}",
            format!("{group}/"),
            "ns",
            "(median)",
            "x closed",
            "x nalgebra",
            SEED_003[0].0,
            SEED_003[1].0,
            SEED_003[2].0
        );
        let lookup = |name: &str| {
            times
                .iter()
                .find(|(id, _)| *id == name)
                .and_then(|(_, t)| t.map(|t| t.0))
        };
        for (id, t) in &times {
            let Some((t, median)) = *t else { continue };
            let prec = if id.ends_with("_f32") { "f32" } else { "f64" };
            let ratio = |r: Option<f64>| r.map_or("-".to_string(), |r| format!("{:.2}", t / r));
            let speedups: Vec<String> = SEED_003
                .iter()
                .map(|(_, us)| format!("{:.0}x", us * 1000.0 / t))
                .collect();
            println!(
                "{:<26} {:>8.1} {:>8.1} {:>9} {:>10}  {:>14} {:>16} {:>14}",
                id,
                t,
                median,
                ratio(lookup(&format!("closed_{prec}"))),
                ratio(lookup(&format!("nalgebra_{prec}"))),
                speedups[0],
                speedups[1],
                speedups[2]
            );
        }
    }
    if !printed {
        println!("(no estimates written by this run)");
    }
}

const STEP_IDS: &[&str] = &[
    "closed_f64",
    "nalgebra_f64",
    "locus_plain_f64",
    "locus_joseph_f64",
    "user_plain_f64",
    "builtin_user_f64",
    "nalgebra_modelcalls_f64",
    "adskalman_joseph_f64",
    "adskalman_plain_f64",
    "closed_f32",
    "nalgebra_f32",
    "locus_plain_f32",
    "locus_joseph_f32",
    "user_plain_f32",
    "builtin_user_f32",
];

const CORRECT_IDS: &[&str] = &[
    "closed_f64",
    "nalgebra_f64",
    "locus_plain_f64",
    "locus_joseph_f64",
    "locus_seq_plain_f64",
    "locus_seq_joseph_f64",
    "schedule_11_f64",
    "adskalman_joseph_f64",
];

fn main() {
    // Instruction counting (scripts/bench_instructions.sh): run one variant
    // `n` times and exit, without criterion.
    if let Ok(spec) = std::env::var("EKF_STEP_RUN") {
        run_one(&spec);
        return;
    }
    check_agreement();
    // `EKF_STEP_INTERLEAVED=1`: only the interleaved tables (about 15 s),
    // for repeated runs.
    if std::env::var_os("EKF_STEP_INTERLEAVED").is_some() {
        print_interleaved();
        return;
    }
    // Truncate to whole seconds: some filesystems store coarse mtimes.
    let started = SystemTime::now() - Duration::from_secs(1);
    let mut c = Criterion::default()
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .configure_from_args();
    bench_step(&mut c);
    bench_correct(&mut c);
    c.final_summary();
    print_table(started, &[("step", STEP_IDS), ("correct", CORRECT_IDS)]);
    print_interleaved();
}

/// One step variant, run `n` times in one of two ways:
/// * independent steps (throughput): every step starts from the same inputs,
///   so consecutive steps may overlap in the processor;
/// * chained steps (latency): step k+1 starts from step k's posterior, as a
///   filter runs, so each step waits for the previous one.
type Batch<'a> = Box<dyn Fn(u32, bool) + 'a>;

/// A batch runner for a step function `f(&Inputs<T>) -> Belief<T, 3>`.
fn batch<'a, T: Scalar>(
    inp: &'a Inputs<T>,
    f: impl Fn(&Inputs<T>) -> Belief<T, 3> + 'a,
) -> Batch<'a> {
    Box::new(move |n, chained| {
        if chained {
            let mut i = *inp;
            for _ in 0..n {
                i.belief = f(black_box(&i));
            }
            black_box(i);
        } else {
            for _ in 0..n {
                black_box(f(black_box(inp)));
            }
        }
    })
}

/// The step variants of the interleaved tables (and of the instruction
/// counts), by name.
fn step_variants<'a>(
    i64_: &'a Inputs<f64>,
    i32_: &'a Inputs<f32>,
    ekf: &'a [Ekf<f64>; 2],
    ekf32: &'a [Ekf<f32>; 2],
) -> Vec<(&'static str, Batch<'a>)> {
    let [plain, joseph] = ekf;
    let [plain32, joseph32] = ekf32;
    vec![
        ("closed_f64", batch(i64_, closed_step)),
        ("nalgebra_f64", batch(i64_, nalgebra_step)),
        (
            "locus_plain_f64",
            batch(i64_, move |i| locus_step(black_box(plain), i)),
        ),
        (
            "locus_joseph_f64",
            batch(i64_, move |i| locus_step(black_box(joseph), i)),
        ),
        (
            "user_plain_f64",
            batch(i64_, move |i| user_step(black_box(plain), i)),
        ),
        (
            "builtin_user_f64",
            batch(i64_, move |i| builtin_user_step(black_box(plain), i)),
        ),
        (
            "nalgebra_checked_f64",
            batch(i64_, |i| nalgebra_checked_step(i).expect("step")),
        ),
        ("closed_f32", batch(i32_, closed_step)),
        ("nalgebra_f32", batch(i32_, nalgebra_step)),
        (
            "locus_plain_f32",
            batch(i32_, move |i| locus_step(black_box(plain32), i)),
        ),
        (
            "locus_joseph_f32",
            batch(i32_, move |i| locus_step(black_box(joseph32), i)),
        ),
        (
            "user_plain_f32",
            batch(i32_, move |i| user_step(black_box(plain32), i)),
        ),
        (
            "builtin_user_f32",
            batch(i32_, move |i| builtin_user_step(black_box(plain32), i)),
        ),
        (
            "nalgebra_checked_f32",
            batch(i32_, |i| nalgebra_checked_step(i).expect("step")),
        ),
    ]
}

/// `EKF_STEP_RUN=<variant>:<n>[:chained]`: runs one variant `n` times (for
/// `valgrind --tool=callgrind`; see scripts/bench_instructions.sh).
fn run_one(spec: &str) {
    let mut parts = spec.split(':');
    let name = parts.next().unwrap_or_default();
    let n: u32 = parts
        .next()
        .and_then(|n| n.parse().ok())
        .expect("EKF_STEP_RUN=<variant>:<n>[:chained]");
    let chained = parts.next() == Some("chained");
    let (i64_, i32_) = (inputs::<f64>(), inputs::<f32>());
    let ekf = [CovarianceUpdate::Plain, CovarianceUpdate::Joseph].map(Ekf::<f64>::new);
    let ekf32 = [CovarianceUpdate::Plain, CovarianceUpdate::Joseph].map(Ekf::<f32>::new);
    let variants = step_variants(&i64_, &i32_, &ekf, &ekf32);
    let Some((_, run)) = variants.iter().find(|(id, _)| *id == name) else {
        let names: Vec<&str> = variants.iter().map(|(id, _)| *id).collect();
        panic!("unknown variant {name:?}; one of {names:?}");
    };
    run(n, chained);
}

/// Ratios that survive a busy machine: the step variants timed in short
/// batches taken in turn (round robin, 400 rounds of 2000 steps), keeping
/// each variant's fastest batch. Criterion times one variant after another,
/// so load that comes and goes shifts its ratios; here every variant sees
/// the same conditions. Two tables: independent steps (throughput: every
/// step starts from the same inputs) and chained steps (latency: each step
/// starts from the previous posterior, as a filter runs).
fn print_interleaved() {
    const ROUNDS: usize = 400;
    const BATCH: u32 = 2000;
    let (i64_, i32_) = (inputs::<f64>(), inputs::<f32>());
    let ekf = [CovarianceUpdate::Plain, CovarianceUpdate::Joseph].map(Ekf::<f64>::new);
    let ekf32 = [CovarianceUpdate::Plain, CovarianceUpdate::Joseph].map(Ekf::<f32>::new);
    let variants = step_variants(&i64_, &i32_, &ekf, &ekf32);
    // best[k][0]: independent, best[k][1]: chained (ns per step).
    let mut best = vec![[f64::INFINITY; 2]; variants.len()];
    for _ in 0..ROUNDS {
        for chained in [false, true] {
            for (k, (_, run)) in variants.iter().enumerate() {
                let t = std::time::Instant::now();
                run(BATCH, chained);
                let ns = t.elapsed().as_secs_f64() * 1e9 / f64::from(BATCH);
                let b = &mut best[k][usize::from(chained)];
                *b = b.min(ns);
            }
        }
    }
    let index = |name: &str| variants.iter().position(|(id, _)| *id == name);
    println!();
    println!("Interleaved (round robin, fastest of {ROUNDS} batches of {BATCH} steps each):");
    println!("  independent: every step from the same inputs (throughput);");
    println!("  chained: each step from the previous posterior (latency, as a filter runs).");
    println!(
        "{:<20} {:>11} {:>9} {:>10}   {:>8} {:>9} {:>10}",
        "step/", "indep. ns", "x closed", "x nalgebra", "chain ns", "x closed", "x nalgebra"
    );
    for (k, (name, _)) in variants.iter().enumerate() {
        let prec = if name.ends_with("f64") { "f64" } else { "f32" };
        let closed = index(&format!("closed_{prec}"));
        let nalgebra = index(&format!("nalgebra_{prec}"));
        let ratio = |m: usize, r: Option<usize>| {
            r.map_or("-".to_string(), |r| {
                format!("{:.2}", best[k][m] / best[r][m])
            })
        };
        println!(
            "{:<20} {:>11.1} {:>9} {:>10}   {:>8.1} {:>9} {:>10}",
            name,
            best[k][0],
            ratio(0, closed),
            ratio(0, nalgebra),
            best[k][1],
            ratio(1, closed),
            ratio(1, nalgebra)
        );
    }
}
