//! The grid cast as first written: the cell traversal as an iterator, each
//! cell's state looked up by its coordinates, the normal fitted cell by
//! cell. [`Grid::cast`] gives the same hits, bit for bit, faster
//! (`traverse.rs`, `normal.rs`); this one stays as its oracle in the tests
//! and its peer in the benchmark (`benches/cast.rs`).

use crate::grid::Grid;
use crate::hit::{Hit, HitSource, direction, facing, valid_ray};
use crate::normal::{MIN_ANISOTROPY, RADIUS};
use crate::traverse::Traversal;

impl Grid {
    /// [`Grid::cast`], by the reference method (see the module
    /// documentation); the same contract and the same results, slower.
    #[doc(hidden)]
    pub fn cast_reference(&self, origin: [f64; 2], angle: f64, max_range: f64) -> Option<Hit> {
        if !valid_ray(origin, angle, max_range) {
            return None;
        }
        let g = self.geometry();
        let d = direction(angle);
        let dg = g.rotate_in(d);
        let p = g.to_cells(origin);
        let res = g.resolution();
        let v = [dg[0] / res, dg[1] / res];
        let cell = Traversal::new(p, v, max_range, g.width(), g.height())
            .find(|c| self.occupied(c.ix, c.iy))?;
        let ng = estimate(self, cell.ix, cell.iy, cell.face, dg);
        let (normal, incidence) = facing(g.rotate_out(ng), d);
        let t = cell.t_enter;
        Some(Hit {
            range: t,
            point: [origin[0] + t * d[0], origin[1] + t * d[1]],
            normal,
            incidence,
            source: HitSource::Cell([cell.ix, cell.iy]),
        })
    }
}

/// `normal::estimate`, cell by cell.
fn estimate(grid: &Grid, ix: usize, iy: usize, face: Option<[f64; 2]>, d: [f64; 2]) -> [f64; 2] {
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
    let theta = 0.5 * (2.0 * b).atan2(a - c);
    let (s, co) = theta.sin_cos();
    [-s, co]
}
