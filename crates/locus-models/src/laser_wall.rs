//! A laser range finder observing walls (paper 000, eq. 12-15; spec
//! `MODELS.md` section 2), in two forms: the paper's model and the exact one.
//!
//! # Frames and geometry
//! State `X = [x, y, theta]` (m, m, rad) in the world (global) frame. The
//! sensor `S_i` is mounted at `(x_si, y_si)` (m) in the robot frame, its beam at
//! `beta_i` (rad) from the robot's heading ([`LaserMount`]). In the world frame
//! the sensor sits at
//!
//! ```text
//! p_s = (x + x_si cos(theta) - y_si sin(theta),  y + x_si sin(theta) + y_si cos(theta))
//! ```
//!
//! and the beam points along `u = (cos phi, sin phi)`, `phi = theta + beta_i`.
//! It returns the range `gamma_i` (m) along the beam to the first wall it hits.
//!
//! A wall is a line in normal form (unit normal `n`, a point `p0` on it,
//! [`WallLine`]) or a segment `a -> b` of a map ([`Segment`]). The range along
//! the beam to a wall's line is
//!
//! ```text
//! gamma = n.(p0 - p_s) / (n.u)
//! ```
//!
//! which, unlike the paper's `tan(phi)` form of eq. 13, has no singularity at
//! `phi = +-90 deg`. There is **no measurement** (`h` returns `None`) when the
//! beam is parallel to the wall (`|n.u| <= parallel_tol`), when the wall is
//! behind the sensor (`gamma <= 0`), when it is out of range
//! (`gamma > max_range`, see [`BeamLimits`]), or, for a segment, when the hit
//! lies off the segment.
//!
//! # The paper's model: [`LaserWallPaper`] (eq. 12-15)
//! The measurement is the hit point `O` in the sensor frame (origin at the
//! sensor, axes parallel to the robot's), `Z = [u_i, v_i] = gamma_i [cos beta_i,
//! sin beta_i]` (eq. 12, [`LaserMount::z_from_range`]), with
//! `R = diag(s_u^2, s_v^2)`. With `(l, m) = p_s + gamma u` the predicted hit
//! point in the world frame (eq. 13, computed in the normal form; **\[fix\]** the
//! paper's text drops the robot's own `x, y`):
//!
//! ```text
//! h(X) = [ (l - x) cos(theta) + (m - y) sin(theta) - x_si ,                 (eq. 14)
//!          (m - y) cos(theta) - (l - x) sin(theta) - y_si ]
//! H    = [[-cos(theta), -sin(theta), -(l - x) sin(theta) + (m - y) cos(theta)], (eq. 15)
//!         [ sin(theta), -cos(theta), -(l - x) cos(theta) - (m - y) sin(theta)]]
//! ```
//!
//! **The paper's approximation.** `H` treats `(l, m)` as constants: it is the
//! derivative of `h` with the hit point held fixed, *not* the derivative of
//! `h(X)` (the hit point slides along the wall when the robot moves). The
//! filter then behaves as if the robot observed a fixed point on the wall and
//! gains information along the wall that a range to a wall cannot give. `h`
//! itself is exact: `h(X) = gamma(X) [cos beta_i, sin beta_i]`.
//!
//! # The exact model: [`LaserRange`]
//! The scalar range `gamma(X)` to the nearest segment of a map hit by the beam
//! (a ray cast, [`ray_cast`]), `R = s_gamma^2`, with the exact Jacobian at the
//! segment hit (normal `n`):
//!
//! ```text
//! d gamma / d(x, y) = -n / (n.u)
//! d gamma / d theta = -( n . dp_s/dtheta + gamma n.u' ) / (n.u),     u' = (-sin phi, cos phi)
//! dp_s / dtheta     = (-x_si sin(theta) - y_si cos(theta),  x_si cos(theta) - y_si sin(theta))
//! ```
//!
//! At the paper's test pose (robot at the origin, heading 0, sensor at
//! `x_si = 0.17 m`, wall `x + y = 1.17 m`) this is `H = [-1, -1, -1.17]`: a
//! range to the wall observes only `x + y + 1.17 theta`, so the exact model
//! gives no information along the wall (direction `(1, -1)/sqrt 2`).
//!
//! `h` is differentiable where the nearest hit lies strictly inside its
//! segment, the beam is not parallel to it, `0 < gamma < max_range`, and no
//! other segment's end lies on the beam in front of that hit (where the
//! nearest segment can switch).

use locus_core::nalgebra::{Matrix1, Matrix2, SMatrix, SVector, Vector1, Vector2};
use locus_core::{MeasurementModel, Scalar, cast};

/// The \[assumed\] maximum range of the laser range finder (m). The paper does
/// not give it; 8 m is the mm-resolution range of a SICK LMS200, a scanner
/// often fitted to Pioneer robots.
pub const DEFAULT_MAX_RANGE: f64 = 8.0;

/// Default parallel tolerance: the beam counts as parallel to a wall when
/// `|n.u|` (the sine of the angle between beam and wall) is at most this.
pub const DEFAULT_PARALLEL_TOL: f64 = 1e-6;

/// Mounting of a laser range finder `S_i` on the robot (paper 000, Table II).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserMount<T> {
    /// Sensor position along the robot's heading, `x_si` (m), robot frame.
    pub x_si: T,
    /// Sensor position to the left of the heading, `y_si` (m), robot frame.
    pub y_si: T,
    /// Beam angle `beta_i` from the robot's heading (rad), counter-clockwise.
    pub beta: T,
}

impl<T: Scalar> LaserMount<T> {
    /// A sensor at `(x_si, y_si)` (m, robot frame) with beam angle `beta` (rad).
    pub fn new(x_si: T, y_si: T, beta: T) -> Self {
        Self { x_si, y_si, beta }
    }

    /// The mounting of the paper's test (spec section 2): `x_si = 0.17 m`,
    /// `y_si = 0`, `beta = 0` (the beam looks straight ahead).
    pub fn paper_000() -> Self {
        Self::new(cast(0.17), T::zero(), T::zero())
    }

    /// The sensor position `p_s = (xs, ys)` in the world frame (m) at state
    /// `x = [x, y, theta]`.
    pub fn sensor_position(&self, x: &SVector<T, 3>) -> Vector2<T> {
        let (s, c) = x[2].sin_cos();
        Vector2::new(
            x[0] + self.x_si * c - self.y_si * s,
            x[1] + self.x_si * s + self.y_si * c,
        )
    }

    /// `dp_s / dtheta` (m/rad) at heading `theta` (rad).
    pub fn sensor_position_dtheta(&self, theta: T) -> Vector2<T> {
        let (s, c) = theta.sin_cos();
        Vector2::new(
            -self.x_si * s - self.y_si * c,
            self.x_si * c - self.y_si * s,
        )
    }

    /// The beam direction `u = (cos phi, sin phi)`, `phi = theta + beta`
    /// (unit vector, world frame) at robot heading `theta` (rad).
    pub fn beam_direction(&self, theta: T) -> Vector2<T> {
        let (s, c) = (theta + self.beta).sin_cos();
        Vector2::new(c, s)
    }

    /// The sensor reading as the paper's measurement (eq. 12): the hit point
    /// in the sensor frame, `Z = [u_i, v_i] = gamma [cos beta, sin beta]` (m),
    /// from the range `gamma` (m).
    pub fn z_from_range(&self, gamma: T) -> Vector2<T> {
        let (s, c) = self.beta.sin_cos();
        Vector2::new(gamma * c, gamma * s)
    }
}

/// When a beam returns a range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamLimits<T> {
    /// Largest range the sensor returns (m); hits further away give no
    /// measurement. \[assumed\] default [`DEFAULT_MAX_RANGE`] (8 m).
    pub max_range: T,
    /// The beam is parallel to a wall (no measurement) when `|n.u| <=
    /// parallel_tol` (dimensionless, the sine of the beam-wall angle).
    /// Default [`DEFAULT_PARALLEL_TOL`] (1e-6).
    pub parallel_tol: T,
}

impl<T: Scalar> Default for BeamLimits<T> {
    fn default() -> Self {
        Self {
            max_range: cast(DEFAULT_MAX_RANGE),
            parallel_tol: cast(DEFAULT_PARALLEL_TOL),
        }
    }
}

impl<T: Scalar> BeamLimits<T> {
    /// Limits with the given maximum range (m) and the default parallel
    /// tolerance.
    pub fn with_max_range(max_range: T) -> Self {
        Self {
            max_range,
            ..Self::default()
        }
    }
}

/// An infinite straight wall in normal form: the points `p` with
/// `n.(p - p0) = 0` (world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallLine<T> {
    /// Unit normal `n` (either orientation; the range does not depend on it).
    pub normal: [T; 2],
    /// A point `p0` on the wall (m, world frame).
    pub point: [T; 2],
}

impl<T: Scalar> WallLine<T> {
    /// The wall through `point` (m) with normal `normal` (any length; it is
    /// normalised). A zero normal gives a wall that is never hit.
    pub fn new(normal: [T; 2], point: [T; 2]) -> Self {
        let n = Vector2::from(normal);
        let n = n / n.norm();
        Self {
            normal: [n[0], n[1]],
            point,
        }
    }

    /// The paper's test wall (spec section 2): the line `x + y = a`, through
    /// `(a, 0)` at 45 degrees, `n = (1, 1)/sqrt 2` (`a` in m; test value 1.17).
    pub fn paper_000(a: T) -> Self {
        Self::new([T::one(), T::one()], [a, T::zero()])
    }

    /// Where a beam from `p_s` (m, world) along the unit vector `u` meets the
    /// line, within `limits`; `None` if parallel, behind or out of range.
    pub fn intersect(
        &self,
        p_s: &Vector2<T>,
        u: &Vector2<T>,
        limits: &BeamLimits<T>,
    ) -> Option<LineHit<T>> {
        intersect_line(
            &Vector2::from(self.normal),
            &Vector2::from(self.point),
            p_s,
            u,
            limits,
        )
    }
}

/// A wall segment from `a` to `b` (m, world frame), the element of a map.
/// A zero-length segment is never hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment<T> {
    /// One end (m, world frame).
    pub a: [T; 2],
    /// The other end (m, world frame).
    pub b: [T; 2],
}

impl<T> Segment<T> {
    /// The segment from `a` to `b` (m, world frame).
    pub const fn new(a: [T; 2], b: [T; 2]) -> Self {
        Self { a, b }
    }
}

impl<T: Scalar> Segment<T> {
    /// The segment's line in normal form (normal `n = rot90(b - a) / |b - a|`).
    pub fn line(&self) -> WallLine<T> {
        WallLine::new([self.a[1] - self.b[1], self.b[0] - self.a[0]], self.a)
    }

    /// Where a beam from `p_s` along the unit vector `u` hits this segment
    /// (ends included), within `limits`; `None` if parallel, behind, out of
    /// range or off the segment.
    pub fn intersect(
        &self,
        p_s: &Vector2<T>,
        u: &Vector2<T>,
        limits: &BeamLimits<T>,
    ) -> Option<LineHit<T>> {
        let a = Vector2::from(self.a);
        let d = Vector2::from(self.b) - a;
        let len2 = d.norm_squared();
        if !(len2 > T::zero() && len2.is_finite()) {
            return None;
        }
        let hit = self.line().intersect(p_s, u, limits)?;
        // Position of the hit along the segment, 0 at a, 1 at b.
        let t = (hit.point - a).dot(&d) / len2;
        (t >= T::zero() && t <= T::one()).then_some(hit)
    }
}

/// A beam's hit on a wall line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineHit<T: Scalar> {
    /// Range `gamma` along the beam (m), in `(0, max_range]`.
    pub range: T,
    /// The hit point `(l, m) = p_s + gamma u` (m, world frame).
    pub point: Vector2<T>,
    /// The wall's unit normal `n` used (world frame).
    pub normal: Vector2<T>,
    /// `n.u` (dimensionless, `|n.u| > parallel_tol`).
    pub n_dot_u: T,
}

/// The range along a beam from `p_s` (m, world) in the unit direction `u` to
/// the line `n.(p - p0) = 0` (`n` unit): `gamma = n.(p0 - p_s) / (n.u)`.
/// `None` if `|n.u| <= parallel_tol`, `gamma <= 0` or `gamma > max_range`
/// (or any of them is NaN).
pub fn intersect_line<T: Scalar>(
    n: &Vector2<T>,
    p0: &Vector2<T>,
    p_s: &Vector2<T>,
    u: &Vector2<T>,
    limits: &BeamLimits<T>,
) -> Option<LineHit<T>> {
    let n_dot_u = n.dot(u);
    // Written as positive tests so that NaN gives no measurement.
    if !(n_dot_u.abs() > limits.parallel_tol && n_dot_u.is_finite()) {
        return None;
    }
    let range = n.dot(&(p0 - p_s)) / n_dot_u;
    if !(range > T::zero() && range <= limits.max_range) {
        return None;
    }
    Some(LineHit {
        range,
        point: p_s + u * range,
        normal: *n,
        n_dot_u,
    })
}

/// The nearest hit of a ray cast on a segment map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RayHit<T: Scalar> {
    /// The hit on the nearest segment.
    pub hit: LineHit<T>,
    /// Index of that segment in the map.
    pub segment: usize,
}

/// Casts the beam from `p_s` (m, world) along the unit vector `u` on `map` and
/// returns the nearest segment hit within `limits` (the first in map order on
/// a tie), or `None` if the beam hits no segment.
pub fn ray_cast<T: Scalar>(
    p_s: &Vector2<T>,
    u: &Vector2<T>,
    map: &[Segment<T>],
    limits: &BeamLimits<T>,
) -> Option<RayHit<T>> {
    let mut best: Option<RayHit<T>> = None;
    for (segment, seg) in map.iter().enumerate() {
        if let Some(hit) = seg.intersect(p_s, u, limits) {
            if best.is_none_or(|b| hit.range < b.hit.range) {
                best = Some(RayHit { hit, segment });
            }
        }
    }
    best
}

/// The exact Jacobian `d gamma / dX` (1 x 3; m/m, m/m, m/rad) of the range
/// to a line hit `hit` by the beam of `mount` at state `x` (see the module
/// doc).
pub fn range_jacobian<T: Scalar>(
    mount: &LaserMount<T>,
    x: &SVector<T, 3>,
    hit: &LineHit<T>,
) -> SMatrix<T, 1, 3> {
    let n = hit.normal;
    let (s, c) = (x[2] + mount.beta).sin_cos();
    let du = Vector2::new(-s, c);
    let dps = mount.sensor_position_dtheta(x[2]);
    let k = -T::one() / hit.n_dot_u;
    SMatrix::<T, 1, 3>::new(
        k * n[0],
        k * n[1],
        k * (n.dot(&dps) + hit.range * n.dot(&du)),
    )
}

/// The paper-faithful laser model of seed 000 (eq. 12-15): one straight wall,
/// measurement `Z = [u_i, v_i]` (m, sensor frame), `H` with the hit point
/// `(l, m)` held fixed (the paper's approximation: see the module doc).
/// Implements [`MeasurementModel<T, 3, 2>`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserWallPaper<T: Scalar> {
    /// Sensor mounting.
    pub mount: LaserMount<T>,
    /// The wall (infinite line; the paper's is `x + y = a`).
    pub wall: WallLine<T>,
    /// Range and parallel limits of the beam.
    pub limits: BeamLimits<T>,
    /// Variance `s_u^2` of `u_i` (m^2). The paper uses a small value when the
    /// robot is at rest and a larger one when it moves.
    pub var_u: T,
    /// Variance `s_v^2` of `v_i` (m^2).
    pub var_v: T,
}

impl<T: Scalar> LaserWallPaper<T> {
    /// The model for `mount` and `wall` with `R = diag(var_u, var_v)` (m^2)
    /// and the default [`BeamLimits`].
    pub fn new(mount: LaserMount<T>, wall: WallLine<T>, var_u: T, var_v: T) -> Self {
        Self {
            mount,
            wall,
            limits: BeamLimits::default(),
            var_u,
            var_v,
        }
    }

    /// The sensor reading as this model's measurement (eq. 12): `Z = gamma
    /// [cos beta, sin beta]` (m) from the range `gamma` (m).
    pub fn z_from_range(&self, gamma: T) -> Vector2<T> {
        self.mount.z_from_range(gamma)
    }

    /// The beam's hit on the wall at state `x` (its point is the paper's
    /// `(l, m)`, eq. 13, in the normal form), or `None` if no measurement.
    pub fn hit(&self, x: &SVector<T, 3>) -> Option<LineHit<T>> {
        let p_s = self.mount.sensor_position(x);
        let u = self.mount.beam_direction(x[2]);
        self.wall.intersect(&p_s, &u, &self.limits)
    }

    /// The paper's `h` (eq. 14) for a given hit point `(l, m)` (m, world):
    /// the point in the sensor frame.
    pub fn h_at_point(&self, x: &SVector<T, 3>, lm: &Vector2<T>) -> Vector2<T> {
        let (s, c) = x[2].sin_cos();
        let (dl, dm) = (lm[0] - x[0], lm[1] - x[1]);
        Vector2::new(
            dl * c + dm * s - self.mount.x_si,
            dm * c - dl * s - self.mount.y_si,
        )
    }

    /// The paper's `H` (eq. 15): the derivative of [`Self::h_at_point`] with
    /// respect to `x` with the hit point `(l, m)` held fixed.
    pub fn jacobian_at_point(&self, x: &SVector<T, 3>, lm: &Vector2<T>) -> SMatrix<T, 2, 3> {
        let (s, c) = x[2].sin_cos();
        let (dl, dm) = (lm[0] - x[0], lm[1] - x[1]);
        SMatrix::<T, 2, 3>::new(-c, -s, -dl * s + dm * c, s, -c, -dl * c - dm * s)
    }
}

impl<T: Scalar> MeasurementModel<T, 3, 2> for LaserWallPaper<T> {
    /// `h(X)` of eq. 14 with `(l, m)` the hit at `X`; `None` if the beam is
    /// parallel to the wall, the wall is behind the sensor or out of range.
    /// `H` of eq. 15 with `(l, m)` computed at `x` and held fixed (the
    /// paper's approximation; not the derivative of `h`); one ray cast for
    /// both.
    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        jacobian: Option<&mut SMatrix<T, 2, 3>>,
    ) -> Option<SVector<T, 2>> {
        let hit = self.hit(x)?;
        if let Some(j) = jacobian {
            *j = self.jacobian_at_point(x, &hit.point);
        }
        Some(self.h_at_point(x, &hit.point))
    }

    /// `R = diag(s_u^2, s_v^2)` (m^2).
    fn noise(&self, _x: &SVector<T, 3>) -> SMatrix<T, 2, 2> {
        Matrix2::new(self.var_u, T::zero(), T::zero(), self.var_v)
    }
}

/// The exact laser model: the range `gamma(X)` (m) along the beam to the
/// nearest segment of a map, with its exact Jacobian (spec section 2).
/// Implements [`MeasurementModel<T, 3, 1>`]; the measurement is the range
/// reading `z = [gamma]` (m). Borrows the map: no allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LaserRange<'a, T: Scalar> {
    /// Sensor mounting.
    pub mount: LaserMount<T>,
    /// The map: wall segments (m, world frame).
    pub map: &'a [Segment<T>],
    /// Range and parallel limits of the beam.
    pub limits: BeamLimits<T>,
    /// Variance of the range reading `s_gamma^2` (m^2).
    pub var_range: T,
}

impl<'a, T: Scalar> LaserRange<'a, T> {
    /// The model for `mount` on `map` with `R = var_range` (m^2) and the
    /// default [`BeamLimits`].
    pub fn new(mount: LaserMount<T>, map: &'a [Segment<T>], var_range: T) -> Self {
        Self {
            mount,
            map,
            limits: BeamLimits::default(),
            var_range,
        }
    }

    /// The ray cast at state `x`: the nearest segment hit, or `None`.
    pub fn cast(&self, x: &SVector<T, 3>) -> Option<RayHit<T>> {
        let p_s = self.mount.sensor_position(x);
        let u = self.mount.beam_direction(x[2]);
        ray_cast(&p_s, &u, self.map, &self.limits)
    }

    /// The predicted range `gamma(X)` (m), or `None` if the beam hits no
    /// segment (parallel, behind, out of range or off every segment).
    pub fn range(&self, x: &SVector<T, 3>) -> Option<T> {
        self.cast(x).map(|r| r.hit.range)
    }
}

impl<T: Scalar> MeasurementModel<T, 3, 1> for LaserRange<'_, T> {
    /// `[gamma(X)]` (m), or `None` if the beam hits no segment; `d gamma /
    /// dX` at the nearest hit (exact), from the same ray cast.
    fn evaluate(
        &self,
        x: &SVector<T, 3>,
        jacobian: Option<&mut SMatrix<T, 1, 3>>,
    ) -> Option<SVector<T, 1>> {
        let r = self.cast(x)?;
        if let Some(j) = jacobian {
            *j = range_jacobian(&self.mount, x, &r.hit);
        }
        Some(Vector1::new(r.hit.range))
    }

    /// `R = s_gamma^2` (m^2).
    fn noise(&self, _x: &SVector<T, 3>) -> SMatrix<T, 1, 1> {
        Matrix1::new(self.var_range)
    }
}
