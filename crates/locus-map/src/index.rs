//! A uniform grid of segment ids over a wall map's bounding box: a cast walks
//! the index cells along the ray (the same traversal as a grid cast) and
//! tests only the segments registered in them, stopping at the first cell
//! that holds the nearest crossing found so far.

use crate::segments::{Segment, bounds, nearest};
use crate::traverse::Traversal;

/// Index cells per segment, about.
const CELLS_PER_SEGMENT: f64 = 2.0;
/// Largest number of index cells along one axis.
const MAX_SIDE: usize = 1024;

/// The segment ids of each cell of a uniform grid (compressed rows).
#[derive(Debug, Clone)]
pub(crate) struct SegmentIndex {
    min: [f64; 2],
    cell: f64,
    width: usize,
    height: usize,
    /// `ids[start[k]..start[k + 1]]` are the segments crossing cell `k`
    /// (row-major, row 0 at the lowest y).
    start: Vec<u32>,
    ids: Vec<u32>,
}

impl SegmentIndex {
    /// The index of `segments` (at least one, all finite). A segment is
    /// registered in every cell whose box, grown by a relative 1e-9, it
    /// touches; zero-length segments are left out (never hit).
    pub fn build(segments: &[Segment]) -> Self {
        let (lo, hi) = bounds(segments).unwrap_or(([0.0, 0.0], [1.0, 1.0]));
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-9);
        let pad = 1e-6 * span;
        let min = [lo[0] - pad, lo[1] - pad];
        let size = [hi[0] - lo[0] + 2.0 * pad, hi[1] - lo[1] + 2.0 * pad];
        let target = (segments.len() as f64 * CELLS_PER_SEGMENT).max(1.0);
        let mut cell = (size[0] * size[1] / target).sqrt();
        // A long thin map: not more cells along an axis than MAX_SIDE.
        cell = cell.max(size[0].max(size[1]) / MAX_SIDE as f64);
        let width = ((size[0] / cell).ceil() as usize).clamp(1, MAX_SIDE);
        let height = ((size[1] / cell).ceil() as usize).clamp(1, MAX_SIDE);
        let mut index = Self {
            min,
            cell,
            width,
            height,
            start: Vec::new(),
            ids: Vec::new(),
        };
        // Two passes: count, then fill.
        let mut counts = vec![0u32; width * height];
        for s in segments {
            index.for_cells(s, |k| counts[k] += 1);
        }
        let mut start = Vec::with_capacity(width * height + 1);
        let mut acc = 0u32;
        for c in &counts {
            start.push(acc);
            acc += c;
        }
        start.push(acc);
        let mut ids = vec![0u32; acc as usize];
        let mut next = start.clone();
        for (i, s) in segments.iter().enumerate() {
            index.for_cells(s, |k| {
                ids[next[k] as usize] = i as u32;
                next[k] += 1;
            });
        }
        index.start = start;
        index.ids = ids;
        index
    }

    /// Calls `f` with the index of every cell segment `s` touches.
    fn for_cells(&self, s: &Segment, mut f: impl FnMut(usize)) {
        if s.length() == 0.0 {
            return;
        }
        let to = |p: [f64; 2]| {
            [
                (p[0] - self.min[0]) / self.cell,
                (p[1] - self.min[1]) / self.cell,
            ]
        };
        let (a, b) = (to(s.a), to(s.b));
        let clamp = |x: f64, n: usize| (x.floor().max(0.0) as usize).min(n - 1);
        let (x0, x1) = (
            clamp(a[0].min(b[0]), self.width),
            clamp(a[0].max(b[0]), self.width),
        );
        let (y0, y1) = (
            clamp(a[1].min(b[1]), self.height),
            clamp(a[1].max(b[1]), self.height),
        );
        let eps = 1e-9;
        for iy in y0..=y1 {
            for ix in x0..=x1 {
                let lo = [ix as f64 - eps, iy as f64 - eps];
                let hi = [ix as f64 + 1.0 + eps, iy as f64 + 1.0 + eps];
                if clips(a, b, lo, hi) {
                    f(iy * self.width + ix);
                }
            }
        }
    }

    /// The nearest crossing `(t, segment)` of the ray `origin + t d` (`d`
    /// unit), `0 <= t <= max_range`.
    pub fn cast(
        &self,
        segments: &[Segment],
        origin: [f64; 2],
        d: [f64; 2],
        max_range: f64,
    ) -> Option<(f64, usize)> {
        let p = [
            (origin[0] - self.min[0]) / self.cell,
            (origin[1] - self.min[1]) / self.cell,
        ];
        let v = [d[0] / self.cell, d[1] / self.cell];
        let mut best: Option<(f64, usize)> = None;
        for c in Traversal::new(p, v, max_range, self.width, self.height) {
            let k = c.iy * self.width + c.ix;
            let ids = &self.ids[self.start[k] as usize..self.start[k + 1] as usize];
            if let Some((t, i)) = nearest(
                segments,
                ids.iter().map(|&i| i as usize),
                origin,
                d,
                max_range,
            ) {
                if best.is_none_or(|(bt, bi)| t < bt || (t == bt && i < bi)) {
                    best = Some((t, i));
                }
            }
            if best.is_some_and(|(bt, _)| bt <= c.t_exit) {
                break;
            }
        }
        best
    }
}

/// Whether the segment from `a` to `b` meets the box `[lo, hi]` (Liang and
/// Barsky's clip).
fn clips(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> bool {
    let mut t0 = 0.0_f64;
    let mut t1 = 1.0_f64;
    for k in 0..2 {
        let d = b[k] - a[k];
        if d == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
        } else {
            let u = (lo[k] - a[k]) / d;
            let w = (hi[k] - a[k]) / d;
            let (u, w) = if u < w { (u, w) } else { (w, u) };
            t0 = t0.max(u);
            t1 = t1.min(w);
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}
