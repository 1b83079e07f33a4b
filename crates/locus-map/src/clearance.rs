//! How far each cell of a grid is from the nearest occupied cell: what lets
//! the cast jump over empty space (`Traversal::first_clear`).
//!
//! A cell's clearance is the chessboard (Chebyshev) distance, in cells, to
//! the nearest occupied cell, `max(|dx|, |dy|)`, saturated at 255: 0 on an
//! occupied cell, 1 beside one. A cell of clearance `c` has no occupied cell
//! within `c - 1` columns and `c - 1` rows of it, so a ray in it may take up
//! to `c - 1` steps along each axis without meeting one. A cell outside the
//! grid is not occupied.
//!
//! One byte a cell (a 1000 x 1000 grid in 977 KiB), built in two passes over
//! the grid (the chamfer transform with unit weights on all eight
//! neighbours, exact for the chessboard distance). A cell that becomes
//! occupied lowers the clearance around it, only as far as it changes
//! ([`Clearance::occupy`]); a cell that becomes free leaves it as it is: the
//! distance to a superset of the occupied cells, which still only
//! understates, so is still safe to skip by, and whose 0 on a free cell
//! means "look at the cell" rather than "occupied".

use crate::bits::OccupiedBits;

/// The clearance of every cell, a byte each.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Clearance {
    width: usize,
    height: usize,
    /// Row-major, row 0 first, as the grid's cells.
    cells: Vec<u8>,
}

impl Clearance {
    /// The clearance of the cells of `bits` (`width x height`); O(cells).
    pub fn of(bits: &OccupiedBits, width: usize, height: usize) -> Self {
        let mut cells = vec![u8::MAX; width * height];
        for (k, c) in cells.iter_mut().enumerate() {
            if bits.get(k) {
                *c = 0;
            }
        }
        let w = width;
        // Forward: from the left and below.
        for y in 0..height {
            let row = y * w;
            for x in 0..w {
                let mut m = cells[row + x];
                if x > 0 {
                    m = m.min(cells[row + x - 1].saturating_add(1));
                }
                if y > 0 {
                    let below = row - w;
                    let lo = x.saturating_sub(1);
                    let hi = (x + 1).min(w - 1);
                    for &b in &cells[below + lo..=below + hi] {
                        m = m.min(b.saturating_add(1));
                    }
                }
                cells[row + x] = m;
            }
        }
        // Backward: from the right and above.
        for y in (0..height).rev() {
            let row = y * w;
            for x in (0..w).rev() {
                let mut m = cells[row + x];
                if x + 1 < w {
                    m = m.min(cells[row + x + 1].saturating_add(1));
                }
                if y + 1 < height {
                    let above = row + w;
                    let lo = x.saturating_sub(1);
                    let hi = (x + 1).min(w - 1);
                    for &a in &cells[above + lo..=above + hi] {
                        m = m.min(a.saturating_add(1));
                    }
                }
                cells[row + x] = m;
            }
        }
        Self {
            width,
            height,
            cells,
        }
    }

    /// The clearance of cell `k` (row-major index, in the grid).
    #[inline]
    pub fn get(&self, k: usize) -> u8 {
        self.cells[k]
    }

    /// Cell `(ix, iy)` (in the grid) has become occupied: lowers the
    /// clearance of the cells nearer to it than to any other, ring by ring
    /// outwards, and stops at the first ring it leaves unchanged (the
    /// clearance changes by at most 1 from a cell to its neighbour, so no
    /// ring beyond would change either). Allocates nothing.
    pub fn occupy(&mut self, ix: usize, iy: usize) {
        let (w, h) = (self.width as isize, self.height as isize);
        let (cx, cy) = (ix as isize, iy as isize);
        for r in 0..=isize::from(u8::MAX) {
            let mut changed = false;
            let (y0, y1) = ((cy - r).max(0), (cy + r).min(h - 1));
            for y in y0..=y1 {
                // The whole row on the ring's bottom and top, its two ends
                // otherwise.
                let edge_row = y == cy - r || y == cy + r;
                let step = if edge_row || r == 0 {
                    1
                } else {
                    2 * r as usize
                };
                for x in (cx - r..=cx + r).step_by(step) {
                    if x < 0 || x >= w {
                        continue;
                    }
                    let c = &mut self.cells[y as usize * self.width + x as usize];
                    if isize::from(*c) > r {
                        *c = r as u8;
                        changed = true;
                    }
                }
            }
            if !changed {
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Clearance;
    use crate::bits::OccupiedBits;

    /// The clearance by its definition, cell by cell.
    fn brute(occupied: &[bool], w: usize, h: usize) -> Vec<u8> {
        (0..w * h)
            .map(|k| {
                let (x, y) = ((k % w) as isize, (k / w) as isize);
                (0..w * h)
                    .filter(|&o| occupied[o])
                    .map(|o| {
                        let (ox, oy) = ((o % w) as isize, (o / w) as isize);
                        (ox - x).abs().max((oy - y).abs())
                    })
                    .min()
                    .map_or(u8::MAX, |d| d.min(255) as u8)
            })
            .collect()
    }

    fn bits(occupied: &[bool], w: usize, h: usize) -> OccupiedBits {
        let mut b = OccupiedBits::new(w, h);
        for (k, &o) in occupied.iter().enumerate() {
            b.set(k, o);
        }
        b
    }

    #[test]
    fn is_the_chessboard_distance() {
        let mut seed = 7u64;
        for (w, h, density) in [(1, 1, 0), (9, 1, 10), (1, 7, 10), (23, 17, 3), (40, 31, 60)] {
            let occupied: Vec<bool> = (0..w * h)
                .map(|_| {
                    seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                    (seed >> 33) % 1000 < density
                })
                .collect();
            let c = Clearance::of(&bits(&occupied, w, h), w, h);
            assert_eq!(c.cells, brute(&occupied, w, h), "{w} x {h}");
        }
        // Saturated far from the only occupied cell, and on an empty grid.
        let (w, h) = (300, 2);
        let mut occupied = vec![false; w * h];
        occupied[0] = true;
        let c = Clearance::of(&bits(&occupied, w, h), w, h);
        assert_eq!(c.cells, brute(&occupied, w, h));
        assert_eq!(c.get(299), 255);
        let empty = Clearance::of(&OccupiedBits::new(5, 4), 5, 4);
        assert!(empty.cells.iter().all(|&c| c == 255));
    }

    #[test]
    fn occupy_is_a_rebuild() {
        let (w, h) = (37, 29);
        let mut occupied = vec![false; w * h];
        let mut c = Clearance::of(&bits(&occupied, w, h), w, h);
        for (i, k) in [500, 0, w * h - 1, 13, 600, 601, 1000, w - 1].into_iter().enumerate() {
            occupied[k] = true;
            c.occupy(k % w, k / w);
            assert_eq!(c.cells, brute(&occupied, w, h), "after {} cells", i + 1);
        }
    }
}
