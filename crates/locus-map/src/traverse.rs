//! The exact cell traversal of a ray through a grid (Amanatides and Woo, "A
//! fast voxel traversal algorithm for ray tracing", Eurographics 1987): every
//! cell the ray passes through, in order, with the ray parameter where it
//! enters and leaves each. The grid cast, the occupancy builder, the
//! rasteriser and the segment index all walk cells with it.
//!
//! Coordinates are in cell units (cell `(i, j)` is the square
//! `[i, i + 1) x [j, j + 1)`); the ray parameter `t` is in the caller's unit
//! (metres): the point at `t` is `p + t v`, with `v` the direction in cells
//! per metre.

/// One cell on the ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Visit {
    /// Column.
    pub ix: usize,
    /// Row.
    pub iy: usize,
    /// Ray parameter where the ray enters the cell (0 if it starts inside).
    pub t_enter: f64,
    /// Ray parameter where it leaves the cell or stops (the limit).
    pub t_exit: f64,
    /// Outward normal (cell frame, axis-aligned unit) of the face the ray
    /// entered through; `None` for the cell the ray starts in.
    pub face: Option<[f64; 2]>,
}

/// The cells a ray passes through, nearest first; allocates nothing.
#[derive(Debug, Clone)]
pub(crate) struct Traversal {
    ix: i64,
    iy: i64,
    step_x: i64,
    step_y: i64,
    t_max_x: f64,
    t_max_y: f64,
    t_delta_x: f64,
    t_delta_y: f64,
    t: f64,
    t_end: f64,
    face: Option<[f64; 2]>,
    width: i64,
    height: i64,
    done: bool,
}

impl Traversal {
    /// The traversal of the ray `p + t v`, `0 <= t <= limit`, through a grid
    /// of `width x height` cells. A ray that misses the grid, a non-finite
    /// input, a zero `v` that starts outside the grid or a negative limit
    /// yields nothing. A ray starting on a cell boundary starts in the cell
    /// it moves into. A zero `v` (or a zero limit) yields the start cell only.
    pub fn new(p: [f64; 2], v: [f64; 2], limit: f64, width: usize, height: usize) -> Self {
        let mut s = Self {
            ix: 0,
            iy: 0,
            step_x: 0,
            step_y: 0,
            t_max_x: f64::INFINITY,
            t_max_y: f64::INFINITY,
            t_delta_x: f64::INFINITY,
            t_delta_y: f64::INFINITY,
            t: 0.0,
            t_end: 0.0,
            face: None,
            width: width as i64,
            height: height as i64,
            done: true,
        };
        let finite = p.iter().chain(v.iter()).all(|x| x.is_finite());
        if !finite || limit.is_nan() || limit < 0.0 || width == 0 || height == 0 {
            return s;
        }
        // Clip to the grid's box [0, w] x [0, h] and to [0, limit].
        let size = [width as f64, height as f64];
        let mut t0 = 0.0_f64;
        let mut t1 = limit;
        let mut entry_axis = None;
        for k in 0..2 {
            if v[k] == 0.0 {
                if p[k] < 0.0 || p[k] >= size[k] {
                    return s;
                }
            } else {
                let a = -p[k] / v[k];
                let b = (size[k] - p[k]) / v[k];
                let (lo, hi) = if a < b { (a, b) } else { (b, a) };
                if lo > t0 {
                    t0 = lo;
                    entry_axis = Some(k);
                }
                t1 = t1.min(hi);
            }
        }
        if v == [0.0, 0.0] {
            t1 = t0;
        }
        if t0 > t1 {
            return s;
        }
        let q = [p[0] + t0 * v[0], p[1] + t0 * v[1]];
        let cell = |q: f64, v: f64, n: i64| -> i64 {
            // Half-open in the direction of travel.
            let c = if v < 0.0 { q.ceil() - 1.0 } else { q.floor() };
            (c as i64).clamp(0, n - 1)
        };
        s.ix = cell(q[0], v[0], s.width);
        s.iy = cell(q[1], v[1], s.height);
        if let Some(k) = entry_axis {
            let mut n = [0.0; 2];
            n[k] = -v[k].signum();
            s.face = Some(n);
        }
        if v[0] > 0.0 {
            s.step_x = 1;
            s.t_max_x = ((s.ix + 1) as f64 - p[0]) / v[0];
            s.t_delta_x = 1.0 / v[0];
        } else if v[0] < 0.0 {
            s.step_x = -1;
            s.t_max_x = (s.ix as f64 - p[0]) / v[0];
            s.t_delta_x = -1.0 / v[0];
        }
        if v[1] > 0.0 {
            s.step_y = 1;
            s.t_max_y = ((s.iy + 1) as f64 - p[1]) / v[1];
            s.t_delta_y = 1.0 / v[1];
        } else if v[1] < 0.0 {
            s.step_y = -1;
            s.t_max_y = (s.iy as f64 - p[1]) / v[1];
            s.t_delta_y = -1.0 / v[1];
        }
        s.t = t0;
        s.t_end = t1;
        s.done = false;
        s
    }
}

impl Traversal {
    /// The first cell, nearest first, whose row-major index
    /// (`iy * width + ix`) satisfies `hit`: the visit `self.find(..)` would
    /// return, from the same arithmetic in the same order, so the same to
    /// the bit: a loop over the index, for the grid cast. Allocates
    /// nothing.
    #[inline]
    pub fn first(self, hit: impl Fn(usize) -> bool) -> Option<Visit> {
        if self.done {
            return None;
        }
        let w = self.width;
        let mut k = self.iy * w + self.ix;
        // Steps left along each axis before the ray leaves the grid.
        let steps_left = |i: i64, step: i64, n: i64| match step {
            1 => n - 1 - i,
            -1 => i,
            _ => i64::MAX,
        };
        let mut left_x = steps_left(self.ix, self.step_x, w);
        let mut left_y = steps_left(self.iy, self.step_y, self.height);
        let (dk_x, dk_y) = (self.step_x, self.step_y * w);
        let (dt_x, dt_y) = (self.t_delta_x, self.t_delta_y);
        let (mut t_max_x, mut t_max_y, mut t) = (self.t_max_x, self.t_max_y, self.t);
        // The axis of the last step, if the ray has stepped.
        let mut last_x: Option<bool> = None;
        while !hit(k as usize) {
            // Which axis steps next is a branch (it often mispredicts along
            // a diagonal, but selects in its place lengthen the chain of
            // dependent operations each step, which costs more).
            let x = t_max_x < t_max_y;
            let t_next = if x { t_max_x } else { t_max_y };
            if t_next > self.t_end {
                return None;
            }
            t = t_next;
            if x {
                t_max_x += dt_x;
                k += dk_x;
                left_x -= 1;
            } else {
                t_max_y += dt_y;
                k += dk_y;
                left_y -= 1;
            }
            last_x = Some(x);
            if (left_x | left_y) < 0 {
                return None;
            }
        }
        let face = match last_x {
            None => self.face,
            Some(true) => Some([-(self.step_x as f64), 0.0]),
            Some(false) => Some([0.0, -(self.step_y as f64)]),
        };
        Some(Visit {
            ix: (k % w) as usize,
            iy: (k / w) as usize,
            t_enter: t,
            t_exit: t_max_x.min(t_max_y).min(self.t_end),
            face,
        })
    }
}

impl Iterator for Traversal {
    type Item = Visit;

    #[inline]
    fn next(&mut self) -> Option<Visit> {
        if self.done {
            return None;
        }
        let t_next = self.t_max_x.min(self.t_max_y);
        let visit = Visit {
            ix: self.ix as usize,
            iy: self.iy as usize,
            t_enter: self.t,
            t_exit: t_next.min(self.t_end),
            face: self.face,
        };
        if t_next > self.t_end {
            self.done = true;
            return Some(visit);
        }
        if self.t_max_x < self.t_max_y {
            self.ix += self.step_x;
            self.t = self.t_max_x;
            self.t_max_x += self.t_delta_x;
            self.face = Some([-(self.step_x as f64), 0.0]);
        } else {
            self.iy += self.step_y;
            self.t = self.t_max_y;
            self.t_max_y += self.t_delta_y;
            self.face = Some([0.0, -(self.step_y as f64)]);
        }
        if self.ix < 0 || self.iy < 0 || self.ix >= self.width || self.iy >= self.height {
            self.done = true;
        }
        Some(visit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cells(p: [f64; 2], v: [f64; 2], limit: f64, w: usize, h: usize) -> Vec<(usize, usize)> {
        Traversal::new(p, v, limit, w, h)
            .map(|c| (c.ix, c.iy))
            .collect()
    }

    #[test]
    fn axis_aligned_and_diagonal() {
        assert_eq!(
            cells([0.5, 0.5], [1.0, 0.0], 10.0, 4, 2),
            vec![(0, 0), (1, 0), (2, 0), (3, 0)]
        );
        assert_eq!(
            cells([3.5, 1.5], [-1.0, 0.0], 1.6, 4, 2),
            vec![(3, 1), (2, 1), (1, 1)]
        );
        // Entered from outside through the west face.
        let v: Vec<_> = Traversal::new([-2.0, 0.5], [1.0, 0.0], 10.0, 2, 1).collect();
        assert_eq!(v.len(), 2);
        assert_eq!(v[0].t_enter, 2.0);
        assert_eq!(v[0].face, Some([-1.0, 0.0]));
        assert_eq!(v[1].face, Some([-1.0, 0.0]));
        assert_eq!(v[1].t_exit, 4.0);
    }

    #[test]
    fn degenerate_rays() {
        assert!(cells([0.5, 0.5], [1.0, 0.0], -1.0, 4, 4).is_empty());
        assert!(cells([5.5, 0.5], [1.0, 0.0], 10.0, 4, 4).is_empty());
        assert!(cells([0.5, 0.5], [1.0, 0.0], 10.0, 0, 4).is_empty());
        assert_eq!(cells([0.5, 0.5], [1.0, 0.0], 0.0, 4, 4), vec![(0, 0)]);
        assert_eq!(cells([1.5, 2.5], [0.0, 0.0], 3.0, 4, 4), vec![(1, 2)]);
        assert!(cells([f64::NAN, 0.5], [1.0, 0.0], 1.0, 4, 4).is_empty());
    }

    #[test]
    fn first_is_find() {
        // A pseudo-random grid and rays from inside, outside and on
        // boundaries, in every direction.
        let (w, h) = (23, 17);
        let occupied = |k: usize| (k * 2_654_435_761) % 97 < 9;
        let mut n = 0;
        for i in 0..400 {
            let a = f64::from(i) * 0.1237;
            let p = [
                f64::from(i % 31) - 4.0 + f64::from(i % 3) * 0.25,
                f64::from(i % 23) - 3.0,
            ];
            let v = [a.cos() * 1.7, a.sin() * 1.7];
            for limit in [0.0, 0.7, 5.0, f64::INFINITY] {
                let t = Traversal::new(p, v, limit, w, h);
                let slow = t.clone().find(|c| occupied(c.iy * w + c.ix));
                assert_eq!(t.first(occupied), slow, "ray {i}, limit {limit}");
                n += usize::from(slow.is_some());
            }
        }
        assert!(n > 300, "{n} hits");
        for v in [[1.0, 0.0], [0.0, -1.0], [0.0, 0.0]] {
            let mut t = Traversal::new([3.5, 4.0], v, 30.0, w, h);
            assert_eq!(
                t.clone().first(occupied),
                t.find(|c| occupied(c.iy * w + c.ix))
            );
        }
    }

    #[test]
    fn starts_on_a_boundary_in_the_cell_it_moves_into() {
        assert_eq!(cells([2.0, 0.5], [-1.0, 0.0], 0.5, 4, 1), vec![(1, 0)]);
        assert_eq!(cells([2.0, 0.5], [1.0, 0.0], 0.5, 4, 1), vec![(2, 0)]);
    }
}
