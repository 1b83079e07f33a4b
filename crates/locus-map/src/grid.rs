//! Occupancy grids: each cell's occupancy probability (or none known) and
//! its state, occupied, free or unknown, by ROS map_server's thresholds.

use crate::MapError;
use crate::bits::OccupiedBits;
use crate::geometry::GridGeometry;
use crate::segments::Segment;
use crate::traverse::Traversal;

/// A cell's state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Occupancy {
    /// Free space: rays pass.
    Free,
    /// An obstacle: rays stop at its boundary.
    Occupied,
    /// Neither known free nor known occupied: rays pass.
    Unknown,
}

/// ROS map_server's thresholds on the occupancy probability `p`: occupied if
/// `p > occupied`, free if `p < free`, unknown otherwise (and when no
/// probability is known).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thresholds {
    /// `occupied_thresh` (0..=1).
    pub occupied: f64,
    /// `free_thresh` (0..=1, at most `occupied`).
    pub free: f64,
}

impl Default for Thresholds {
    /// map_server's usual 0.65 and 0.196 (what map_saver writes).
    fn default() -> Self {
        Self {
            occupied: 0.65,
            free: 0.196,
        }
    }
}

impl Thresholds {
    /// The state of a cell of occupancy probability `p` (`None`: unknown).
    #[inline]
    pub fn classify(&self, p: Option<f64>) -> Occupancy {
        match p {
            Some(p) if p > self.occupied => Occupancy::Occupied,
            Some(p) if p < self.free => Occupancy::Free,
            _ => Occupancy::Unknown,
        }
    }

    /// Checks `0 <= free <= occupied <= 1`.
    ///
    /// # Errors
    /// [`MapError::Invalid`] otherwise.
    pub fn check(&self) -> Result<(), MapError> {
        let ok = (0.0..=1.0).contains(&self.free)
            && (0.0..=1.0).contains(&self.occupied)
            && self.free <= self.occupied;
        if ok {
            Ok(())
        } else {
            Err(MapError::invalid(
                "thresholds",
                format!(
                    "free {} and occupied {}: need 0 <= free <= occupied <= 1",
                    self.free, self.occupied
                ),
            ))
        }
    }
}

/// An occupancy grid: a [`GridGeometry`], the [`Thresholds`] and, per cell,
/// the occupancy probability (0..=1, or none known) and the state the
/// thresholds give it.
///
/// Casting ([`Grid::cast`](crate::Grid::cast)) stops at the first occupied
/// cell; free and unknown cells let rays pass. The surface normal at a hit is
/// estimated from the occupied cells around it (see `normal.rs` and
/// docs/maps.md).
#[derive(Debug, Clone)]
pub struct Grid {
    geometry: GridGeometry,
    thresholds: Thresholds,
    /// Probability per cell (row-major, row 0 at the bottom), NaN: unknown.
    probability: Vec<f32>,
    state: Vec<Occupancy>,
    /// Whether each cell is occupied (the states, as the cast reads them).
    occupied: OccupiedBits,
}

impl PartialEq for Grid {
    /// Same geometry, thresholds, states and probabilities (an unknown
    /// probability equals an unknown one).
    fn eq(&self, other: &Self) -> bool {
        self.geometry == other.geometry
            && self.thresholds == other.thresholds
            && self.state == other.state
            && self
                .probability
                .iter()
                .zip(&other.probability)
                .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()))
    }
}

impl Grid {
    /// A grid whose cells are all unknown (no probability).
    ///
    /// # Errors
    /// [`MapError::Invalid`] if the thresholds are invalid.
    pub fn new(geometry: GridGeometry, thresholds: Thresholds) -> Result<Self, MapError> {
        thresholds.check()?;
        Ok(Self {
            geometry,
            thresholds,
            probability: vec![f32::NAN; geometry.len()],
            state: vec![Occupancy::Unknown; geometry.len()],
            occupied: OccupiedBits::new(geometry.width(), geometry.height()),
        })
    }

    /// A grid from each cell's probability (row-major, row 0 at the bottom,
    /// `None`: unknown); the states follow from the thresholds.
    ///
    /// # Errors
    /// [`MapError::Invalid`] if the thresholds are invalid, the length is not
    /// `width * height`, or a probability is outside `0..=1` (NaN included).
    pub fn from_probabilities(
        geometry: GridGeometry,
        thresholds: Thresholds,
        probabilities: &[Option<f64>],
    ) -> Result<Self, MapError> {
        let mut grid = Self::new(geometry, thresholds)?;
        if probabilities.len() != geometry.len() {
            return Err(MapError::invalid(
                "grid",
                format!(
                    "{} probabilities for {} x {} cells",
                    probabilities.len(),
                    geometry.width(),
                    geometry.height()
                ),
            ));
        }
        for (k, p) in probabilities.iter().enumerate() {
            grid.set_index(k, *p)?;
        }
        Ok(grid)
    }

    /// The cells a segment passes through (occupied, probability 1), all
    /// other cells free (probability 0): a wall map as a grid.
    ///
    /// # Errors
    /// As [`Grid::new`].
    pub fn rasterise(
        segments: &[Segment],
        geometry: GridGeometry,
        thresholds: Thresholds,
    ) -> Result<Self, MapError> {
        let mut grid =
            Self::from_probabilities(geometry, thresholds, &vec![Some(0.0); geometry.len()])?;
        for s in segments {
            let a = geometry.to_cells(s.a);
            let b = geometry.to_cells(s.b);
            let e = [b[0] - a[0], b[1] - a[1]];
            let l = e[0].hypot(e[1]);
            let v = if l > 0.0 {
                [e[0] / l, e[1] / l]
            } else {
                [0.0, 0.0]
            };
            for c in Traversal::new(a, v, l, geometry.width(), geometry.height()) {
                grid.set_index(geometry.index(c.ix, c.iy), Some(1.0))?;
            }
        }
        Ok(grid)
    }

    /// Where the grid lies.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// The thresholds that gave the states.
    pub fn thresholds(&self) -> Thresholds {
        self.thresholds
    }

    /// The state of cell `(ix, iy)`; `None` outside the grid.
    pub fn state(&self, ix: usize, iy: usize) -> Option<Occupancy> {
        self.inside(ix, iy)
            .then(|| self.state[self.geometry.index(ix, iy)])
    }

    /// The occupancy probability of cell `(ix, iy)`; `None` if unknown or
    /// outside the grid.
    pub fn probability(&self, ix: usize, iy: usize) -> Option<f64> {
        if !self.inside(ix, iy) {
            return None;
        }
        let p = self.probability[self.geometry.index(ix, iy)];
        (!p.is_nan()).then_some(f64::from(p))
    }

    /// Sets the probability of cell `(ix, iy)` (`None`: unknown) and its state
    /// by the thresholds.
    ///
    /// # Errors
    /// [`MapError::Invalid`] if the cell is outside the grid or `p` is outside
    /// `0..=1`.
    pub fn set(&mut self, ix: usize, iy: usize, p: Option<f64>) -> Result<(), MapError> {
        if !self.inside(ix, iy) {
            return Err(MapError::invalid(
                format!("cell ({ix}, {iy})"),
                format!(
                    "outside the {} x {} grid",
                    self.geometry.width(),
                    self.geometry.height()
                ),
            ));
        }
        self.set_index(self.geometry.index(ix, iy), p)
    }

    /// The number of cells in each state: `(occupied, free, unknown)`.
    pub fn counts(&self) -> (usize, usize, usize) {
        self.state.iter().fold((0, 0, 0), |(o, f, u), s| match s {
            Occupancy::Occupied => (o + 1, f, u),
            Occupancy::Free => (o, f + 1, u),
            Occupancy::Unknown => (o, f, u + 1),
        })
    }

    /// Whether cell `(ix, iy)` (in the grid) is occupied.
    #[inline]
    pub(crate) fn occupied(&self, ix: usize, iy: usize) -> bool {
        self.state[self.geometry.index(ix, iy)] == Occupancy::Occupied
    }

    /// The occupied cells, a bit each.
    #[inline]
    pub(crate) fn occupied_bits(&self) -> &OccupiedBits {
        &self.occupied
    }

    fn inside(&self, ix: usize, iy: usize) -> bool {
        ix < self.geometry.width() && iy < self.geometry.height()
    }

    pub(crate) fn set_index(&mut self, k: usize, p: Option<f64>) -> Result<(), MapError> {
        if let Some(p) = p {
            if !(0.0..=1.0).contains(&p) {
                return Err(MapError::invalid(
                    format!("cell {k}"),
                    format!("probability {p}: must be in 0..=1"),
                ));
            }
        }
        // The state is that of the stored (f32) probability, so that
        // `probability` and `state` always agree.
        let stored = p.map(|p| p as f32);
        self.probability[k] = stored.unwrap_or(f32::NAN);
        self.state[k] = self.thresholds.classify(stored.map(f64::from));
        self.occupied.set(k, self.state[k] == Occupancy::Occupied);
        Ok(())
    }
}
