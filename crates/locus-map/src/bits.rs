//! Which cells of a grid are occupied, one bit a cell: what the cast reads.
//!
//! A grid's states are a byte a cell; the cast only asks "occupied?", and a
//! bit a cell keeps eight times as many cells in the cache (a 1000 x 1000
//! grid in 122 KiB). Bit `k` is cell `k` of the row-major storage
//! (`iy * width + ix`, row 0 at the bottom).

/// One bit per cell, set when the cell is occupied.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct OccupiedBits {
    width: usize,
    height: usize,
    words: Vec<u64>,
}

impl OccupiedBits {
    /// No cell occupied, `width x height` cells.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            words: vec![0; (width * height).div_ceil(64)],
        }
    }

    /// Marks cell `k` (row-major index, in the grid) occupied or not.
    #[inline]
    pub fn set(&mut self, k: usize, occupied: bool) {
        let bit = 1u64 << (k & 63);
        if occupied {
            self.words[k >> 6] |= bit;
        } else {
            self.words[k >> 6] &= !bit;
        }
    }

    /// Whether cell `k` (row-major index, in the grid) is occupied.
    #[inline]
    pub fn get(&self, k: usize) -> bool {
        (self.words[k >> 6] >> (k & 63)) & 1 == 1
    }

    /// Whether cell `(x, y)` is occupied; a cell outside the grid is not.
    #[inline]
    pub fn at(&self, x: isize, y: isize) -> bool {
        x >= 0
            && y >= 0
            && (x as usize) < self.width
            && (y as usize) < self.height
            && self.get(y as usize * self.width + x as usize)
    }

    /// The cells `(x0 + j, y)`, `j = 0..9`, as bit `j` of the result (a
    /// cell outside the grid is not occupied).
    #[inline]
    pub fn row9(&self, x0: isize, y: isize) -> u32 {
        const N: usize = 9;
        let inside =
            x0 >= 0 && y >= 0 && (y as usize) < self.height && x0 as usize + N <= self.width;
        if !inside {
            return (0..N as isize).fold(0, |acc, j| acc | (u32::from(self.at(x0 + j, y)) << j));
        }
        let start = y as usize * self.width + x0 as usize;
        let (word, offset) = (start >> 6, start & 63);
        let mut bits = self.words[word] >> offset;
        if offset + N > 64 {
            // The row continues into the next word (which exists: the
            // nine cells are in the grid).
            bits |= self.words[word + 1] << (64 - offset);
        }
        (bits & ((1 << N) - 1)) as u32
    }
}

#[cfg(test)]
mod tests {
    use super::OccupiedBits;

    #[test]
    fn rows_read_across_words_and_edges() {
        let (w, h) = (70, 3);
        let mut b = OccupiedBits::new(w, h);
        let occupied = |x: usize, y: usize| (x * 7 + y * 3) % 5 == 0;
        for y in 0..h {
            for x in 0..w {
                b.set(y * w + x, occupied(x, y));
            }
        }
        b.set(6, true);
        assert!(b.get(6));
        b.set(6, false);
        assert!(!b.get(6) && b.get(5));
        for y in -1..=h as isize {
            for x0 in -10..=w as isize {
                let want = (0..9).fold(0u32, |acc, j| {
                    let (x, y) = (x0 + j, y);
                    let inside = x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h;
                    acc | (u32::from(inside && occupied(x as usize, y as usize)) << j)
                });
                assert_eq!(b.row9(x0, y), want, "x0 {x0}, y {y}");
            }
        }
    }
}
