//! Shared helpers of locus-core's integration tests: random beliefs, inputs
//! and IR observations of paper 001, and matrix comparisons.
#![allow(dead_code)]

use locus_core::nalgebra::{Matrix3, SMatrix, Vector3};
use locus_core::{Belief, Scalar, cast};
use locus_models::{AxisWall, DiffDrive, IrPair, IrPairObservation, WheelTravel};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};

pub fn rng(seed: u64) -> StdRng {
    StdRng::seed_from_u64(seed)
}

/// Log-uniform in [lo, hi].
pub fn log_uniform(r: &mut StdRng, lo: f64, hi: f64) -> f64 {
    (r.random_range(lo.ln()..=hi.ln())).exp()
}

/// A random rotation of R^3 (from a random unit quaternion).
pub fn random_rotation(r: &mut StdRng) -> Matrix3<f64> {
    let q: [f64; 4] = core::array::from_fn(|_| r.random_range(-1.0..1.0));
    let q = locus_core::nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]);
    locus_core::nalgebra::UnitQuaternion::from_quaternion(q)
        .to_rotation_matrix()
        .into_inner()
}

/// A random SPD covariance whose largest eigenvalue is `scale` and whose
/// condition number is `cond`.
pub fn random_covariance(r: &mut StdRng, scale: f64, cond: f64) -> Matrix3<f64> {
    let rot = random_rotation(r);
    let mid = log_uniform(r, scale / cond, scale);
    let d = Matrix3::from_diagonal(&Vector3::new(scale, mid, scale / cond));
    let p = rot * d * rot.transpose();
    (p + p.transpose()) * 0.5
}

/// A random belief of a robot inside the 001 arena (Lw = 1 m).
pub fn random_belief(r: &mut StdRng, cond_max: f64) -> Belief<f64, 3> {
    let x = Vector3::new(
        r.random_range(-0.9..0.9),
        r.random_range(-0.9..0.9),
        r.random_range(-core::f64::consts::PI..core::f64::consts::PI),
    );
    let cond = log_uniform(r, 1.0, cond_max);
    let scale = log_uniform(r, 1e-6, 1e-1);
    Belief::new(x, random_covariance(r, scale, cond))
}

pub fn random_model(r: &mut StdRng) -> DiffDrive<f64> {
    DiffDrive::new(
        0.12,
        log_uniform(r, 1e-10, 1e-3),
        log_uniform(r, 1e-10, 1e-2),
    )
}

pub fn random_travel(r: &mut StdRng) -> WheelTravel<f64> {
    WheelTravel {
        d1: r.random_range(-0.02..0.03),
        d2: r.random_range(-0.02..0.03),
    }
}

/// A random IR observation of one of the four walls of the 1 m arena, with
/// random mounting offsets and readings within the sensors' range.
pub fn random_ir(r: &mut StdRng) -> IrPairObservation<f64> {
    let wall = match r.random_range(0..4) {
        0 => AxisWall::x_plus(1.0),
        1 => AxisWall::x_minus(1.0),
        2 => AxisWall::y_plus(1.0),
        _ => AxisWall::y_minus(1.0),
    };
    IrPairObservation {
        pair: IrPair {
            spacing: 0.10,
            lateral_offset: r.random_range(-0.05..0.05),
            forward_offset: r.random_range(-0.05..0.05),
        },
        wall,
        ds1: r.random_range(0.04..0.30),
        ds2: r.random_range(0.04..0.30),
        r11: log_uniform(r, 1e-8, 1e-3),
        r22: log_uniform(r, 1e-8, 1e-3),
    }
}

/// Largest absolute entry.
pub fn max_abs<T: Scalar, const R: usize, const C: usize>(m: &SMatrix<T, R, C>) -> T {
    m.iter().fold(T::zero(), |acc, v| acc.max(v.abs()))
}

/// Norm-wise relative difference `max|a - b| / max(max|a|, tiny)`.
pub fn rel_diff<const R: usize, const C: usize>(
    a: &SMatrix<f64, R, C>,
    b: &SMatrix<f64, R, C>,
) -> f64 {
    max_abs(&(a - b)) / max_abs(a).max(1e-300)
}

/// `max|a - b| / scale`: the difference relative to a given magnitude. Used
/// for posterior covariances, whose rounding error is set by the magnitude of
/// the prior they are computed from (a precise measurement shrinks `P` by
/// orders of magnitude, and `P- - G H P-` cancels digits at the prior's scale).
pub fn diff_at_scale<const R: usize, const C: usize>(
    a: &SMatrix<f64, R, C>,
    b: &SMatrix<f64, R, C>,
    scale: f64,
) -> f64 {
    max_abs(&(a - b)) / scale
}

/// Converts an f64 belief into another scalar type.
pub fn cast_belief<T: Scalar>(b: &Belief<f64, 3>) -> Belief<T, 3> {
    Belief::new(b.x.map(cast::<T>), b.p.map(cast::<T>))
}
