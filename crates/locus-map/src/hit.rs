//! What a ray cast returns.

/// Where a ray meets the map.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance from the ray's origin to the hit (m), `0 <= range <=
    /// max_range`.
    pub range: f64,
    /// The hit point (m, world frame): `origin + range * (cos angle, sin
    /// angle)`.
    pub point: [f64; 2],
    /// Unit normal of the surface at the hit (world frame), pointing back
    /// towards the ray: `normal . direction <= 0`. Exact for segments;
    /// estimated from the occupied neighbourhood for grids (see
    /// [`Grid`](crate::Grid)).
    pub normal: [f64; 2],
    /// Angle between the reversed ray and the normal (rad, `0..=pi/2`): 0
    /// head-on, pi/2 grazing.
    pub incidence: f64,
    /// What was hit.
    pub source: HitSource,
}

/// The map element a ray hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum HitSource {
    /// The segment with this index in the [`SegmentMap`](crate::SegmentMap).
    Segment(usize),
    /// The occupied cell (column, row) of the [`Grid`](crate::Grid).
    Cell([usize; 2]),
}

/// The unit direction of a ray at `angle` (rad, world frame).
#[inline]
pub(crate) fn direction(angle: f64) -> [f64; 2] {
    let (s, c) = angle.sin_cos();
    [c, s]
}

/// The normal `n` turned to face the ray `d` (`n . d <= 0`) and the incidence
/// angle between them.
#[inline]
pub(crate) fn facing(n: [f64; 2], d: [f64; 2]) -> ([f64; 2], f64) {
    let dot = n[0] * d[0] + n[1] * d[1];
    let n = if dot > 0.0 { [-n[0], -n[1]] } else { n };
    // atan2, not acos: accurate near head-on too.
    let cross = n[0] * d[1] - n[1] * d[0];
    (n, cross.abs().atan2(dot.abs()))
}

/// Whether a cast's inputs admit a hit: finite origin and angle, a
/// `max_range` that is not NaN and not negative.
#[inline]
pub(crate) fn valid_ray(origin: [f64; 2], angle: f64, max_range: f64) -> bool {
    origin[0].is_finite() && origin[1].is_finite() && angle.is_finite() && max_range >= 0.0
}
