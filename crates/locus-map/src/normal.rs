//! The surface normal at a grid hit, estimated from the occupied
//! neighbourhood.
//!
//! The face a ray enters a cell through is axis-aligned, so it says nothing
//! of a wall's real direction: a ray grazing a diagonal wall enters its
//! cells head-on through their faces. Instead: take the occupied cells within
//! [`RADIUS`] cells of the hit cell that lie on an obstacle's edge (at least
//! one of their four neighbours is not occupied; a cell outside the grid
//! counts as not occupied), and fit a line through their centres by least
//! squares (the principal axis of their scatter); the normal is the axis of
//! least spread. This is exact for a straight wall whose rasterised edge
//! fills the window, averages a staircase over 2 * RADIUS + 1 cells, and
//! bisects a corner. When the cells do not define a direction (a lone
//! occupied cell, a blob as wide as it is long), it falls back to the entered
//! face's normal, or to the reversed ray for a ray that starts inside an
//! occupied cell. Nothing is precomputed, so a grid may change between casts;
//! nothing is allocated.

use crate::grid::Grid;

/// Half-width (cells) of the window the normal is fitted in.
pub const RADIUS: usize = 3;

/// Below this ratio of the scatter's eigenvalue difference to their sum the
/// cells define no direction.
const MIN_ANISOTROPY: f64 = 0.2;

/// The unit normal (grid frame) at occupied cell `(ix, iy)`, entered through
/// the face of outward normal `face` (`None`: the ray started inside), by a
/// ray of unit direction `d` (grid frame). Its orientation is left to the
/// caller.
pub(crate) fn estimate(
    grid: &Grid,
    ix: usize,
    iy: usize,
    face: Option<[f64; 2]>,
    d: [f64; 2],
) -> [f64; 2] {
    let g = grid.geometry();
    let (w, h) = (g.width(), g.height());
    let occupied = |x: isize, y: isize| {
        x >= 0
            && y >= 0
            && (x as usize) < w
            && (y as usize) < h
            && grid.occupied(x as usize, y as usize)
    };
    let r = RADIUS as isize;
    let r2 = (r * r + r) as f64; // a disc, corners of the square cut off
    let (cx, cy) = (ix as isize, iy as isize);
    let (mut n, mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for dy in -r..=r {
        for dx in -r..=r {
            let (x, y) = (cx + dx, cy + dy);
            if ((dx * dx + dy * dy) as f64) > r2 || !occupied(x, y) {
                continue;
            }
            let edge = !occupied(x + 1, y)
                || !occupied(x - 1, y)
                || !occupied(x, y + 1)
                || !occupied(x, y - 1);
            if !edge {
                continue;
            }
            let (fx, fy) = (dx as f64, dy as f64);
            n += 1.0;
            sx += fx;
            sy += fy;
            sxx += fx * fx;
            sxy += fx * fy;
            syy += fy * fy;
        }
    }
    let fallback = face.unwrap_or([-d[0], -d[1]]);
    if n < 2.0 {
        return fallback;
    }
    let a = sxx - sx * sx / n;
    let b = sxy - sx * sy / n;
    let c = syy - sy * sy / n;
    let diff = (a - c).hypot(2.0 * b);
    if diff <= MIN_ANISOTROPY * (a + c) {
        return fallback;
    }
    // The major axis is at 0.5 atan2(2b, a - c); the normal is across it.
    let theta = 0.5 * (2.0 * b).atan2(a - c);
    let (s, co) = theta.sin_cos();
    [-s, co]
}
