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
//!
//! The window is read as rows of bits (`bits.rs`): a cell is on an edge if
//! it is occupied and not all of its four neighbours are, a few bit
//! operations a row; the sums are of small integers, so exact in any order
//! (the same fit, bit for bit, as summing cell by cell: `reference.rs`).

use crate::bits::OccupiedBits;

/// Half-width (cells) of the window the normal is fitted in.
pub const RADIUS: usize = 3;

/// Below this ratio of the scatter's eigenvalue difference to their sum the
/// cells define no direction.
pub(crate) const MIN_ANISOTROPY: f64 = 0.2;

/// Rows of the window and one more on each side (for the neighbours).
const ROWS: usize = 2 * RADIUS + 3;
const _: () = assert!(ROWS == 9, "the rows are read nine cells wide");

/// For each row `dy = -RADIUS..=RADIUS` of the window, the cells of the
/// disc `dx^2 + dy^2 <= RADIUS^2 + RADIUS`, as bit `dx + RADIUS + 1` (the
/// corners of the square cut off).
const DISC: [u32; 2 * RADIUS + 1] = disc();

const fn disc() -> [u32; 2 * RADIUS + 1] {
    let r = RADIUS as i32;
    let mut out = [0; 2 * RADIUS + 1];
    let mut dy = -r;
    while dy <= r {
        let mut dx = -r;
        while dx <= r {
            if dx * dx + dy * dy <= r * r + r {
                out[(dy + r) as usize] |= 1 << (dx + r + 1);
            }
            dx += 1;
        }
        dy += 1;
    }
    out
}

/// The unit normal (grid frame) at occupied cell `(ix, iy)` of the grid
/// whose occupied cells are `bits`, entered through the face of outward
/// normal `face` (`None`: the ray started inside), by a ray of unit
/// direction `d` (grid frame). Its orientation is left to the caller.
pub(crate) fn estimate(
    bits: &OccupiedBits,
    ix: usize,
    iy: usize,
    face: Option<[f64; 2]>,
    d: [f64; 2],
) -> [f64; 2] {
    let r = RADIUS as isize;
    let (cx, cy) = (ix as isize, iy as isize);
    // rows[i]: cells (cx - r - 1 + j, cy - r - 1 + i) as bit j.
    let mut rows = [0u32; ROWS];
    for (i, row) in rows.iter_mut().enumerate() {
        *row = bits.row9(cx - r - 1, cy - r - 1 + i as isize);
    }
    let (mut n, mut sx, mut sy, mut sxx, mut sxy, mut syy) = (0i64, 0i64, 0i64, 0i64, 0i64, 0i64);
    for (i, disc) in DISC.iter().enumerate() {
        let (below, row, above) = (rows[i], rows[i + 1], rows[i + 2]);
        let interior = row & (row << 1) & (row >> 1) & below & above;
        let mut edge = row & !interior & disc;
        let dy = i as i64 - r as i64;
        while edge != 0 {
            let dx = i64::from(edge.trailing_zeros()) - r as i64 - 1;
            edge &= edge - 1;
            n += 1;
            sx += dx;
            sy += dy;
            sxx += dx * dx;
            sxy += dx * dy;
            syy += dy * dy;
        }
    }
    let fallback = face.unwrap_or([-d[0], -d[1]]);
    if n < 2 {
        return fallback;
    }
    // Small integers: exact as f64.
    let [n, sx, sy, sxx, sxy, syy] = [n, sx, sy, sxx, sxy, syy].map(|v| v as f64);
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
