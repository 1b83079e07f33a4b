//! The ray cast on an occupancy grid: the exact cell traversal (Amanatides
//! and Woo) to the first occupied cell, read a bit a cell (`bits.rs`,
//! `Traversal::first`), and the normal fitted there (`normal.rs`).

use crate::grid::Grid;
use crate::hit::{Hit, HitSource, direction, facing, valid_ray};
use crate::normal;
use crate::traverse::Traversal;

impl Grid {
    /// The first occupied cell the ray from `origin` (m) at `angle` (rad,
    /// world frame) enters within `max_range` (m, may be infinite).
    ///
    /// The range is exact to where the ray enters that cell (its boundary,
    /// not the wall inside it); the hit's normal is estimated from the
    /// occupied cells around it (`normal.rs`), so is its incidence. A ray that
    /// starts in an occupied cell hits it at range 0; `max_range` 0 hits only
    /// then. Free and unknown cells let the ray pass; a ray that leaves the
    /// grid without meeting an occupied cell, or starts outside and never
    /// enters it, returns `None`, as do a non-finite origin or angle and a NaN
    /// or negative `max_range`. Allocates nothing.
    pub fn cast(&self, origin: [f64; 2], angle: f64, max_range: f64) -> Option<Hit> {
        if !valid_ray(origin, angle, max_range) {
            return None;
        }
        let g = self.geometry();
        let d = direction(angle);
        let dg = g.rotate_in(d);
        let p = g.to_cells(origin);
        let res = g.resolution();
        let v = [dg[0] / res, dg[1] / res];
        let bits = self.occupied_bits();
        let cell = Traversal::new(p, v, max_range, g.width(), g.height()).first(|k| bits.get(k))?;
        let ng = normal::estimate(bits, cell.ix, cell.iy, cell.face, dg);
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
