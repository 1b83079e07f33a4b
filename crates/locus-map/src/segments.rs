//! Wall maps: line segments and the exact ray cast against them.

use crate::MapError;
use crate::hit::{Hit, HitSource, direction, facing, valid_ray};
use crate::index::SegmentIndex;

/// A wall from `a` to `b` (m, world frame).
///
/// The same ends as `locus_models::laser_wall::Segment<f64>` (`a`, `b`):
/// `laser_wall::Segment::new(s.a, s.b)` converts. A zero-length segment is
/// kept (files round-trip) but never hit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// One end (m).
    pub a: [f64; 2],
    /// The other end (m).
    pub b: [f64; 2],
}

impl Segment {
    /// The wall from `a` to `b` (m).
    pub const fn new(a: [f64; 2], b: [f64; 2]) -> Self {
        Self { a, b }
    }

    /// `[x1, y1, x2, y2]` (m), the order of the text format.
    pub const fn to_array(&self) -> [f64; 4] {
        [self.a[0], self.a[1], self.b[0], self.b[1]]
    }

    /// Length (m).
    pub fn length(&self) -> f64 {
        (self.b[0] - self.a[0]).hypot(self.b[1] - self.a[1])
    }

    /// Where the ray `origin + t d` (`d` a unit vector) crosses the segment
    /// (ends included) for `0 <= t <= max_range`: `t` (m), or `None` if it
    /// does not, if the ray is parallel to the segment (collinear included)
    /// or if the segment has zero length.
    #[inline]
    pub fn intersect(&self, origin: [f64; 2], d: [f64; 2], max_range: f64) -> Option<f64> {
        let e = [self.b[0] - self.a[0], self.b[1] - self.a[1]];
        let denom = d[0] * e[1] - d[1] * e[0];
        if denom == 0.0 {
            return None;
        }
        let w = [self.a[0] - origin[0], self.a[1] - origin[1]];
        let t = (w[0] * e[1] - w[1] * e[0]) / denom;
        let s = (w[0] * d[1] - w[1] * d[0]) / denom;
        ((0.0..=1.0).contains(&s) && t >= 0.0 && t <= max_range).then_some(t)
    }

    /// The unit normal `rot90(b - a) / |b - a|` (zero for a zero-length
    /// segment).
    pub fn normal(&self) -> [f64; 2] {
        let e = [self.b[0] - self.a[0], self.b[1] - self.a[1]];
        let l = e[0].hypot(e[1]);
        if l == 0.0 {
            [0.0, 0.0]
        } else {
            [-e[1] / l, e[0] / l]
        }
    }
}

impl From<[f64; 4]> for Segment {
    /// `[x1, y1, x2, y2]` (m).
    fn from(s: [f64; 4]) -> Self {
        Self::new([s[0], s[1]], [s[2], s[3]])
    }
}

impl From<Segment> for [f64; 4] {
    fn from(s: Segment) -> Self {
        s.to_array()
    }
}

/// Above this many segments a cast walks a uniform grid of segment ids;
/// at or below it, it tests every segment.
const BRUTE_FORCE_MAX: usize = 16;

/// A map of walls, with the spatial index its casts use.
#[derive(Debug, Clone)]
pub struct SegmentMap {
    segments: Vec<Segment>,
    index: Option<SegmentIndex>,
}

impl SegmentMap {
    /// The map of these walls (any number, none included: an empty map is
    /// never hit).
    ///
    /// # Errors
    /// [`MapError::Invalid`] naming the first segment with a non-finite
    /// coordinate.
    pub fn new(segments: Vec<Segment>) -> Result<Self, MapError> {
        if let Some((i, s)) = segments
            .iter()
            .enumerate()
            .find(|(_, s)| !s.to_array().iter().all(|x| x.is_finite()))
        {
            return Err(MapError::invalid(
                format!("segment {i}"),
                format!("{:?}: coordinates must be finite", s.to_array()),
            ));
        }
        let index = (segments.len() > BRUTE_FORCE_MAX).then(|| SegmentIndex::build(&segments));
        Ok(Self { segments, index })
    }

    /// The walls, in the order given.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// The bounding box `(min, max)` of the walls (m); `None` for an empty
    /// map.
    pub fn bounds(&self) -> Option<([f64; 2], [f64; 2])> {
        bounds(&self.segments)
    }

    /// The first wall the ray from `origin` (m) at `angle` (rad, world frame)
    /// meets within `max_range` (m, may be infinite): exact intersection, the
    /// lowest index on a tie. `None` if it meets none, for an empty map, for a
    /// non-finite origin or angle, or a NaN or negative `max_range`. A ray
    /// starting on a wall hits it at range 0 (so `max_range` 0 hits only
    /// then); a ray along a wall (parallel) does not hit it. Allocates
    /// nothing.
    pub fn cast(&self, origin: [f64; 2], angle: f64, max_range: f64) -> Option<Hit> {
        if !valid_ray(origin, angle, max_range) {
            return None;
        }
        let d = direction(angle);
        let (t, i) = match &self.index {
            Some(index) => index.cast(&self.segments, origin, d, max_range)?,
            None => nearest(&self.segments, 0..self.segments.len(), origin, d, max_range)?,
        };
        Some(self.hit(i, t, origin, d))
    }

    /// The hit on segment `i` at `t`.
    fn hit(&self, i: usize, t: f64, origin: [f64; 2], d: [f64; 2]) -> Hit {
        let (normal, incidence) = facing(self.segments[i].normal(), d);
        Hit {
            range: t,
            point: [origin[0] + t * d[0], origin[1] + t * d[1]],
            normal,
            incidence,
            source: HitSource::Segment(i),
        }
    }
}

/// The nearest crossing `(t, index)` among `ids` (lowest index on a tie).
#[inline]
pub(crate) fn nearest(
    segments: &[Segment],
    ids: impl IntoIterator<Item = usize>,
    origin: [f64; 2],
    d: [f64; 2],
    max_range: f64,
) -> Option<(f64, usize)> {
    let mut best: Option<(f64, usize)> = None;
    for i in ids {
        if let Some(t) = segments[i].intersect(origin, d, max_range) {
            if best.is_none_or(|(bt, bi)| t < bt || (t == bt && i < bi)) {
                best = Some((t, i));
            }
        }
    }
    best
}

/// The bounding box of the segments' ends; `None` if there are none.
pub(crate) fn bounds(segments: &[Segment]) -> Option<([f64; 2], [f64; 2])> {
    let mut it = segments.iter().flat_map(|s| [s.a, s.b]);
    let first = it.next()?;
    Some(it.fold((first, first), |(lo, hi), p| {
        (
            [lo[0].min(p[0]), lo[1].min(p[1])],
            [hi[0].max(p[0]), hi[1].max(p[1])],
        )
    }))
}
