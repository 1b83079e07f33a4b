//! Poses in the plane (SE(2)) and the exact dead reckoning of a unicycle:
//! what the converters need to turn recorded poses into speeds and to check
//! that the speeds give the poses back.

use crate::mrclam::Odometry;

/// A pose `[x, y, theta]` (m, m, rad).
pub type Pose = [f64; 3];

/// `sin(h) / h`, 1 at 0 (a series below 1e-9 in magnitude).
#[must_use]
pub fn sinc(h: f64) -> f64 {
    if h.abs() < 1e-9 {
        1.0 - h * h / 6.0
    } else {
        h.sin() / h
    }
}

/// `a` wrapped into `[-pi, pi)`.
#[must_use]
pub fn wrap(a: f64) -> f64 {
    (a + core::f64::consts::PI).rem_euclid(core::f64::consts::TAU) - core::f64::consts::PI
}

/// `a (+) b`: `b` (in `a`'s frame) composed onto `a`.
#[must_use]
pub fn compose(a: Pose, b: Pose) -> Pose {
    let (s, c) = a[2].sin_cos();
    [
        a[0] + c * b[0] - s * b[1],
        a[1] + s * b[0] + c * b[1],
        wrap(a[2] + b[2]),
    ]
}

/// `a^-1 (+) b`: `b` in the frame of `a` (heading difference wrapped).
#[must_use]
pub fn relative(a: Pose, b: Pose) -> Pose {
    let (s, c) = a[2].sin_cos();
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    [c * dx + s * dy, -s * dx + c * dy, wrap(b[2] - a[2])]
}

/// The pose reached from the origin by dead reckoning `odometry` from
/// `from` to `to` (s): each record's speeds held until the next record's
/// time (the last's until `to`), integrated exactly (arcs).
#[must_use]
pub fn dead_reckon(odometry: &[Odometry], from: f64, to: f64) -> Pose {
    let mut pose = [0.0; 3];
    for (i, o) in odometry.iter().enumerate() {
        let end = odometry.get(i + 1).map_or(to, |n| n.time).min(to);
        let start = o.time.max(from);
        if end <= start {
            continue;
        }
        let dt = end - start;
        let h = o.omega * dt / 2.0;
        let d = o.v * dt * sinc(h);
        pose = compose(pose, [d * h.cos(), d * h.sin(), o.omega * dt]);
    }
    pose
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_undoes_compose_and_arcs_dead_reckon_exactly() {
        let a = [1.0, -2.0, 3.0];
        let b = [0.3, 0.4, -0.5];
        let c = relative(a, compose(a, b));
        for k in 0..3 {
            assert!((c[k] - b[k]).abs() < 1e-12, "{c:?}");
        }
        assert_eq!(wrap(core::f64::consts::PI), -core::f64::consts::PI);
        assert!((wrap(7.0) - (7.0 - core::f64::consts::TAU)).abs() < 1e-15);
        // A quarter circle of radius 1 in 1 s, then a wait.
        let o = [
            Odometry {
                time: 0.0,
                v: core::f64::consts::FRAC_PI_2,
                omega: core::f64::consts::FRAC_PI_2,
            },
            Odometry {
                time: 1.0,
                v: 0.0,
                omega: 0.0,
            },
        ];
        let p = dead_reckon(&o, 0.0, 2.0);
        for (got, want) in p.iter().zip([1.0, 1.0, core::f64::consts::FRAC_PI_2]) {
            assert!((got - want).abs() < 1e-12, "{p:?}");
        }
        let half = dead_reckon(&o, 0.5, 1.0);
        assert!((half[2] - core::f64::consts::FRAC_PI_4).abs() < 1e-12);
        assert_eq!(sinc(0.0), 1.0);
    }
}
