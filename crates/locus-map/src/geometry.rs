//! Where a grid lies in the world: its size in cells, the cell size and the
//! pose of its lower-left corner, as ROS map_server's `resolution` and
//! `origin`.

use crate::MapError;

/// The size and placement of an occupancy grid.
///
/// Cell `(ix, iy)` is column `ix` (0 at the left) and row `iy` (0 at the
/// bottom, the lowest y in the grid frame); it covers
/// `[ix, ix + 1) x [iy, iy + 1)` times `resolution` in the grid frame. The
/// grid frame is the world frame translated to `origin[0..2]` (m) and rotated
/// by `origin[2]` (rad, counter-clockwise): `origin` is the world pose of the
/// lower-left corner of cell `(0, 0)`. (Many ROS tools ignore the yaw; Locus
/// honours it.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridGeometry {
    width: usize,
    height: usize,
    resolution: f64,
    origin: [f64; 3],
    cos_yaw: f64,
    sin_yaw: f64,
}

impl GridGeometry {
    /// A grid of `width x height` cells of `resolution` metres, its
    /// lower-left corner at the world pose `origin` (m, m, rad).
    ///
    /// # Errors
    /// [`MapError::Invalid`] if a dimension is 0 or their product overflows,
    /// `resolution` is not finite and positive, or `origin` is not finite.
    pub fn new(
        width: usize,
        height: usize,
        resolution: f64,
        origin: [f64; 3],
    ) -> Result<Self, MapError> {
        let what = "grid geometry";
        if width == 0 || height == 0 {
            return Err(MapError::invalid(
                what,
                format!("{width} x {height} cells: both must be at least 1"),
            ));
        }
        if width.checked_mul(height).is_none() || width > i64::MAX as usize / 4 {
            return Err(MapError::invalid(what, "too many cells"));
        }
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(MapError::invalid(
                what,
                format!("resolution {resolution} m: must be finite and positive"),
            ));
        }
        if !origin.iter().all(|x| x.is_finite()) {
            return Err(MapError::invalid(
                what,
                format!("origin {origin:?}: must be finite"),
            ));
        }
        Ok(Self {
            width,
            height,
            resolution,
            origin,
            cos_yaw: origin[2].cos(),
            sin_yaw: origin[2].sin(),
        })
    }

    /// The smallest yaw-0 grid of `resolution` metres covering the box from
    /// `min` to `max` (m, world frame) with `margin` metres to spare on each
    /// side.
    ///
    /// # Errors
    /// As [`GridGeometry::new`]; also if the box is not finite or `max < min`.
    pub fn covering(
        min: [f64; 2],
        max: [f64; 2],
        margin: f64,
        resolution: f64,
    ) -> Result<Self, MapError> {
        let finite = min.iter().chain(max.iter()).all(|x| x.is_finite()) && margin.is_finite();
        if !finite || max[0] < min[0] || max[1] < min[1] || margin < 0.0 {
            return Err(MapError::invalid(
                "grid geometry",
                format!("box {min:?} to {max:?}, margin {margin}: not a finite box"),
            ));
        }
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(MapError::invalid(
                "grid geometry",
                format!("resolution {resolution} m: must be finite and positive"),
            ));
        }
        let cells =
            |lo: f64, hi: f64| (((hi - lo + 2.0 * margin) / resolution).ceil() as usize).max(1);
        Self::new(
            cells(min[0], max[0]),
            cells(min[1], max[1]),
            resolution,
            [min[0] - margin, min[1] - margin, 0.0],
        )
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of rows.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Cell size (m).
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// World pose (m, m, rad) of the lower-left corner of cell `(0, 0)`.
    pub fn origin(&self) -> [f64; 3] {
        self.origin
    }

    /// Number of cells, `width * height`.
    pub fn len(&self) -> usize {
        self.width * self.height
    }

    /// Always false: a grid has at least one cell.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// The index of cell `(ix, iy)` in row-major storage, row 0 first
    /// (`iy * width + ix`); the cell must be in the grid.
    #[inline]
    pub fn index(&self, ix: usize, iy: usize) -> usize {
        debug_assert!(ix < self.width && iy < self.height);
        iy * self.width + ix
    }

    /// A world point (m) in cell units of the grid frame: `[0, width] x
    /// [0, height]` is the grid.
    #[inline]
    pub fn to_cells(&self, p: [f64; 2]) -> [f64; 2] {
        let v = self.rotate_in([p[0] - self.origin[0], p[1] - self.origin[1]]);
        [v[0] / self.resolution, v[1] / self.resolution]
    }

    /// A point in cell units of the grid frame as a world point (m).
    #[inline]
    pub fn to_world(&self, c: [f64; 2]) -> [f64; 2] {
        let v = self.rotate_out([c[0] * self.resolution, c[1] * self.resolution]);
        [v[0] + self.origin[0], v[1] + self.origin[1]]
    }

    /// The cell holding the world point `p` (m), `None` outside the grid.
    pub fn cell_of(&self, p: [f64; 2]) -> Option<[usize; 2]> {
        let c = self.to_cells(p);
        let inside =
            c[0] >= 0.0 && c[1] >= 0.0 && c[0] < self.width as f64 && c[1] < self.height as f64;
        inside.then(|| [c[0] as usize, c[1] as usize])
    }

    /// The world point (m) at the centre of cell `(ix, iy)`.
    pub fn cell_center(&self, ix: usize, iy: usize) -> [f64; 2] {
        self.to_world([ix as f64 + 0.5, iy as f64 + 0.5])
    }

    /// A world-frame vector in the grid frame.
    #[inline]
    pub(crate) fn rotate_in(&self, v: [f64; 2]) -> [f64; 2] {
        [
            self.cos_yaw * v[0] + self.sin_yaw * v[1],
            -self.sin_yaw * v[0] + self.cos_yaw * v[1],
        ]
    }

    /// A grid-frame vector in the world frame.
    #[inline]
    pub(crate) fn rotate_out(&self, v: [f64; 2]) -> [f64; 2] {
        [
            self.cos_yaw * v[0] - self.sin_yaw * v[1],
            self.sin_yaw * v[0] + self.cos_yaw * v[1],
        ]
    }
}
