#![doc = include_str!("../README.md")]
#![no_std]
#![forbid(unsafe_code)]

pub mod belief;
pub mod chi2;
pub mod consistency;
pub mod ekf;
pub mod error;
pub mod gate;
pub mod jacobian_check;
mod linalg;
pub mod model;
pub mod pose;
pub mod robust;
pub mod running;
pub mod schedule;

pub use belief::Belief;
pub use consistency::{Consistency, ConsistencyMonitor, Verdict};
pub use ekf::{Correction, CovarianceUpdate, Ekf, Mask};
pub use error::{Error, Input};
pub use gate::ChiSquareGate;
pub use model::{MeasurementModel, MotionJacobians, MotionModel};
pub use pose::Pose;
pub use robust::{ScaledNoise, StudentT};
pub use running::{Event, Placement, Recovery, Rules, RunningFilter, Track, Update, nees};

/// Re-export of the linear-algebra crate the core is built on, so that users
/// name exactly the same `SVector`/`SMatrix` types.
pub use nalgebra;

/// The scalar types the filter runs in: `f32` (microcontrollers) and `f64`
/// (PC). Any `nalgebra::RealField + Copy` qualifies.
pub trait Scalar: nalgebra::RealField + Copy {}
impl<T: nalgebra::RealField + Copy> Scalar for T {}

/// Converts an `f64` constant into the filter's scalar type.
#[inline(always)]
pub fn cast<T: Scalar>(v: f64) -> T {
    nalgebra::convert(v)
}

/// Wraps an angle (rad) into (-pi, pi].
///
/// Used wherever a difference of angles is formed (spec: "Angles are wrapped to
/// (-pi, pi] wherever a difference of angles is formed").
#[inline]
pub fn wrap_angle<T: Scalar>(a: T) -> T {
    let pi = T::pi();
    let two_pi = T::two_pi();
    if a > -pi && a <= pi {
        return a;
    }
    let mut r = a - two_pi * ((a + pi) / two_pi).floor();
    // r is now in [-pi, pi); move -pi to +pi.
    if r <= -pi {
        r += two_pi;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::wrap_angle;
    use core::f64::consts::PI;

    #[test]
    fn wrap_angle_range_and_identity() {
        for k in -20..=20 {
            let a = k as f64 * 0.7;
            let w = wrap_angle(a);
            assert!(w > -PI && w <= PI, "{a} -> {w}");
            let d = (a - w) / (2.0 * PI);
            assert!(
                (d - d.round()).abs() < 1e-12,
                "{a} -> {w} is not a multiple of 2 pi away"
            );
        }
        assert_eq!(wrap_angle(PI), PI);
        assert_eq!(wrap_angle(-PI), PI);
        assert_eq!(wrap_angle(3.0 * PI), PI);
        assert_eq!(wrap_angle(0.25f32), 0.25f32);
    }
}

/// The repository README's examples, compiled and run as doctests
/// (`cargo test -p locus-core --doc`).
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
pub struct ReadmeDoctests;
