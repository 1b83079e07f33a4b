//! The range of a beam to a locally planar surface and its derivatives: the
//! measurement model a scalar range update linearises.
//!
//! A beam from the sensor origin `o` (m) along `d = (cos a, sin a)` meets the
//! line through `p` (m) of unit normal `n` at
//!
//! ```text
//! r = n.(p - o) / (n.d)
//! dr/do = -n / (n.d)
//! dr/da = -r (n.d') / (n.d),   d' = (-sin a, cos a)
//! ```
//!
//! with `p` and `n` held fixed (the surface does not move with the beam).

use crate::hit::{Hit, direction};

/// The planar range and its derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarRange {
    /// `r = n.(p - o) / (n.d)` (m); negative if the surface is behind the
    /// origin.
    pub range: f64,
    /// `dr/d(origin)` (m/m), world frame.
    pub d_origin: [f64; 2],
    /// `dr/d(angle)` (m/rad).
    pub d_angle: f64,
}

/// Below this `|n.d|` the beam runs along the surface and the model has no
/// finite range.
pub const MIN_COSINE: f64 = 1e-9;

/// The range from `origin` (m) at `angle` (rad, world frame) to the line
/// through `point` (m) of unit normal `normal`, and its derivatives with
/// respect to the origin and the angle (analytic). `None` if
/// `|normal . d| < MIN_COSINE` (the beam is parallel to the surface) or an
/// input is not finite.
pub fn planar_range(
    point: [f64; 2],
    normal: [f64; 2],
    origin: [f64; 2],
    angle: f64,
) -> Option<PlanarRange> {
    let d = direction(angle);
    let nd = normal[0] * d[0] + normal[1] * d[1];
    if !nd.is_finite() || nd.abs() < MIN_COSINE {
        return None;
    }
    let range = (normal[0] * (point[0] - origin[0]) + normal[1] * (point[1] - origin[1])) / nd;
    let nd_prime = -normal[0] * d[1] + normal[1] * d[0];
    let out = PlanarRange {
        range,
        d_origin: [-normal[0] / nd, -normal[1] / nd],
        d_angle: -range * nd_prime / nd,
    };
    [out.range, out.d_origin[0], out.d_origin[1], out.d_angle]
        .iter()
        .all(|x| x.is_finite())
        .then_some(out)
}

impl Hit {
    /// [`planar_range`] on the plane of this hit (its point and normal), for
    /// a beam from `origin` at `angle`: at the ray that was cast, `range`
    /// equals the hit's range.
    pub fn planar(&self, origin: [f64; 2], angle: f64) -> Option<PlanarRange> {
        planar_range(self.point, self.normal, origin, angle)
    }
}
