//! The one map of Locus, shared by the simulator, the replay and the UI:
//! walls as line segments ([`SegmentMap`]) or an occupancy grid ([`Grid`]),
//! behind one [`Map`].
//!
//! - Ray casting ([`Map::cast`]) gives a [`Hit`]: range, point, surface
//!   normal and incidence. Exact for segments; for grids, an exact cell
//!   traversal to the first occupied cell with a normal fitted to the
//!   occupied neighbourhood. Casting allocates nothing.
//! - [`planar_range`]: the range to a locally planar surface and its
//!   derivatives with respect to the beam's origin and angle, for a scalar
//!   range update.
//! - Files: walls as plain text ([`text`]) or TOML ([`walls_toml`]); grids in
//!   ROS map_server's YAML and PGM ([`ros`]). [`Map::load`] and
//!   [`Map::save`] choose by extension.
//! - [`GridBuilder`]: occupancy mapping with known poses (log-odds).
//!
//! Units: metres and radians, world frame; angles counter-clockwise from +x.
//! docs/maps.md describes the formats and methods.

mod bits;
mod builder;
mod cast;
mod error;
mod geometry;
mod grid;
mod hit;
mod index;
mod normal;
mod plane;
mod reference;
pub mod ros;
mod segments;
pub mod text;
mod traverse;
pub mod walls_toml;

use std::path::Path;

pub use builder::{Beam, BuilderConfig, GridBuilder, Reading};
pub use error::MapError;
pub use geometry::GridGeometry;
pub use grid::{Grid, Occupancy, Thresholds};
pub use hit::{Hit, HitSource};
pub use normal::RADIUS as NORMAL_RADIUS;
pub use plane::{MIN_COSINE, PlanarRange, planar_range};
pub use segments::{Segment, SegmentMap};

/// A map: walls or an occupancy grid.
#[derive(Debug, Clone)]
pub enum Map {
    /// Line segments.
    Segments(SegmentMap),
    /// An occupancy grid.
    Grid(Grid),
}

impl Map {
    /// The first thing the ray from `origin` (m) at `angle` (rad, world
    /// frame) meets within `max_range` (m, may be infinite):
    /// [`SegmentMap::cast`] or [`Grid::cast`], whose docs give the degenerate
    /// cases. Allocates nothing.
    #[inline]
    pub fn cast(&self, origin: [f64; 2], angle: f64, max_range: f64) -> Option<Hit> {
        match self {
            Self::Segments(m) => m.cast(origin, angle, max_range),
            Self::Grid(g) => g.cast(origin, angle, max_range),
        }
    }

    /// Reads a map file, by its extension: `.yaml` or `.yml`, a ROS
    /// map_server map ([`ros::load`]); `.toml`, walls in TOML
    /// ([`walls_toml::load`]); anything else, walls as plain text
    /// ([`text::load`]).
    ///
    /// # Errors
    /// Those of the reader.
    pub fn load(path: &Path) -> Result<Self, MapError> {
        match extension(path).as_str() {
            "yaml" | "yml" => ros::load(path).map(Self::Grid),
            "toml" => walls_toml::load(path).map(Self::Segments),
            _ => text::load(path).map(Self::Segments),
        }
    }

    /// Writes the map: a grid as ROS map_server YAML beside a P5 PGM of the
    /// same stem ([`ros::save`], trinary); walls as TOML if the extension is
    /// `.toml`, else as plain text.
    ///
    /// # Errors
    /// Those of the writer.
    pub fn save(&self, path: &Path) -> Result<(), MapError> {
        match self {
            Self::Grid(g) => ros::save(g, path, ros::Mode::Trinary),
            Self::Segments(m) if extension(path) == "toml" => walls_toml::save(m.segments(), path),
            Self::Segments(m) => text::save(m.segments(), path),
        }
    }
}

impl From<SegmentMap> for Map {
    fn from(m: SegmentMap) -> Self {
        Self::Segments(m)
    }
}

impl From<Grid> for Map {
    fn from(g: Grid) -> Self {
        Self::Grid(g)
    }
}

fn extension(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}
