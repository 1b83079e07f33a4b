//! Occupancy mapping with known poses: each beam's cells, walked with the
//! same traversal as a grid cast, get a log-odds increment, a miss for the
//! cells the beam crossed and a hit for the cell its return lies in, clamped
//! (Thrun, Burgard and Fox, Probabilistic Robotics, table 9.1; the clamp as
//! OctoMap's).

use crate::MapError;
use crate::geometry::GridGeometry;
use crate::grid::{Grid, Thresholds};
use crate::hit::direction;
use crate::traverse::Traversal;

/// The inverse sensor model and its limits, as probabilities.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BuilderConfig {
    /// Occupancy after one hit from 0.5 (`0.5 < p_hit < 1`).
    pub p_hit: f64,
    /// Occupancy after one miss from 0.5 (`0 < p_miss < 0.5`).
    pub p_miss: f64,
    /// Lower clamp (`0 < p_min < 0.5`).
    pub p_min: f64,
    /// Upper clamp (`0.5 < p_max < 1`).
    pub p_max: f64,
    /// How far a beam with no return clears free space (m, `>= 0`); a beam
    /// with a return clears up to it whatever its range.
    pub clear_limit: f64,
    /// The thresholds of the grid [`GridBuilder::finish`] gives.
    pub thresholds: Thresholds,
}

impl Default for BuilderConfig {
    /// OctoMap's 0.7 / 0.4 and clamp 0.12..0.97; no-return beams clear 5 m;
    /// map_server's thresholds.
    fn default() -> Self {
        Self {
            p_hit: 0.7,
            p_miss: 0.4,
            p_min: 0.12,
            p_max: 0.97,
            clear_limit: 5.0,
            thresholds: Thresholds::default(),
        }
    }
}

/// One beam's reading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Reading {
    /// A return at this range (m).
    Range(f64),
    /// No return (max range, nothing seen): clears up to
    /// [`BuilderConfig::clear_limit`], marks nothing occupied.
    NoReturn,
}

/// One beam of a scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beam {
    /// Direction (rad) in the sensor frame.
    pub angle: f64,
    /// Range (m); at or beyond the scan's `max_range`, or not finite: no
    /// return.
    pub range: f64,
}

/// Builds an occupancy grid from beams cast from known poses.
#[derive(Debug, Clone)]
pub struct GridBuilder {
    geometry: GridGeometry,
    config: BuilderConfig,
    l_hit: f32,
    l_miss: f32,
    l_min: f32,
    l_max: f32,
    /// Log-odds per cell (row-major, row 0 at the bottom).
    log_odds: Vec<f32>,
    /// Whether a beam has touched the cell.
    seen: Vec<bool>,
}

fn logit(p: f64) -> f32 {
    (p / (1.0 - p)).ln() as f32
}

impl GridBuilder {
    /// A builder over `geometry`, every cell unknown.
    ///
    /// # Errors
    /// [`MapError::Invalid`] if a probability of `config` is out of its range,
    /// `clear_limit` is negative or NaN, or the thresholds are invalid.
    pub fn new(geometry: GridGeometry, config: BuilderConfig) -> Result<Self, MapError> {
        let c = &config;
        let bad = |what: &str, v: f64, range: &str| {
            Err(MapError::invalid(
                "mapping configuration",
                format!("{what} {v}: must be in {range}"),
            ))
        };
        if !(c.p_hit > 0.5 && c.p_hit < 1.0) {
            return bad("p_hit", c.p_hit, "(0.5, 1)");
        }
        if !(c.p_miss > 0.0 && c.p_miss < 0.5) {
            return bad("p_miss", c.p_miss, "(0, 0.5)");
        }
        if !(c.p_min > 0.0 && c.p_min < 0.5) {
            return bad("p_min", c.p_min, "(0, 0.5)");
        }
        if !(c.p_max > 0.5 && c.p_max < 1.0) {
            return bad("p_max", c.p_max, "(0.5, 1)");
        }
        if c.clear_limit.is_nan() || c.clear_limit < 0.0 {
            return bad("clear_limit", c.clear_limit, "[0, inf]");
        }
        c.thresholds.check()?;
        Ok(Self {
            geometry,
            config,
            l_hit: logit(c.p_hit),
            l_miss: logit(c.p_miss),
            l_min: logit(c.p_min),
            l_max: logit(c.p_max),
            log_odds: vec![0.0; geometry.len()],
            seen: vec![false; geometry.len()],
        })
    }

    /// Where the grid lies.
    pub fn geometry(&self) -> &GridGeometry {
        &self.geometry
    }

    /// Adds one beam from `origin` (m, world) at `angle` (rad, world). A
    /// return: every cell the beam crosses before the one its end lies in
    /// gets a miss, that one a hit (if it is in the grid; a return beyond
    /// the grid only clears). Range 0 is a hit in the origin's cell; an
    /// infinite range clears to the grid's edge. A negative or NaN range, or
    /// a non-finite origin or angle, is ignored.
    /// Allocates nothing.
    pub fn insert_beam(&mut self, origin: [f64; 2], angle: f64, reading: Reading) {
        let (limit, hit) = match reading {
            Reading::Range(r) => (r, true),
            Reading::NoReturn => (self.config.clear_limit, false),
        };
        if limit.is_nan()
            || limit < 0.0
            || !origin.iter().all(|x| x.is_finite())
            || !angle.is_finite()
        {
            return;
        }
        let g = &self.geometry;
        let d = direction(angle);
        let dg = g.rotate_in(d);
        let p = g.to_cells(origin);
        let res = g.resolution();
        let end = [p[0] + limit * dg[0] / res, p[1] + limit * dg[1] / res];
        let ends_inside = hit
            && limit.is_finite()
            && end[0] >= 0.0
            && end[1] >= 0.0
            && end[0] < g.width() as f64
            && end[1] < g.height() as f64;
        let v = [dg[0] / res, dg[1] / res];
        let (w, h) = (g.width(), g.height());
        for c in Traversal::new(p, v, limit, w, h) {
            let k = c.iy * w + c.ix;
            let last = c.t_exit >= limit;
            let l = if ends_inside && last {
                self.l_hit
            } else {
                self.l_miss
            };
            self.log_odds[k] = (self.log_odds[k] + l).clamp(self.l_min, self.l_max);
            self.seen[k] = true;
        }
    }

    /// Adds a scan taken at the sensor pose `pose` (m, m, rad; world frame):
    /// each beam at `pose[2] + angle`; a range at or beyond `max_range` (m)
    /// or not finite is a beam with no return.
    pub fn insert_scan(&mut self, pose: [f64; 3], beams: &[Beam], max_range: f64) {
        for b in beams {
            let reading = if b.range.is_finite() && b.range < max_range {
                Reading::Range(b.range)
            } else {
                Reading::NoReturn
            };
            self.insert_beam([pose[0], pose[1]], pose[2] + b.angle, reading);
        }
    }

    /// The grid: each touched cell's probability `1 - 1 / (1 + exp(l))`,
    /// untouched cells unknown, classified by the configured thresholds.
    pub fn finish(self) -> Grid {
        let probs: Vec<Option<f64>> = self
            .log_odds
            .iter()
            .zip(&self.seen)
            .map(|(&l, &seen)| seen.then(|| 1.0 - 1.0 / (1.0 + f64::from(l).exp())))
            .collect();
        Grid::from_probabilities(self.geometry, self.config.thresholds, &probs)
            .expect("probabilities in 0..=1 and checked thresholds")
    }
}
