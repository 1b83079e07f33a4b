//! `--mcap OUT.mcap` of `locus run` and `locus replay`: the run written
//! for Foxglove by `locus_foxglove` (docs/foxglove.md). This module turns
//! the run's steps and map into its frames and scene, and reports what was
//! written.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use locus_eval::Sample;
use locus_foxglove::{Frame, GridCells, McapOut, Scene, Written};

/// The Foxglove output of a single run.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct McapArgs {
    /// Also write the run as an MCAP file that Foxglove opens with no
    /// set-up (docs/foxglove.md): estimate, truth and odometry alone as
    /// poses in frame `map`, the covariance ellipse (at --ellipse-sigma)
    /// and the map as a scene, errors with +-3 sigma bands and NIS as
    /// plottable series, the summary as a log message. Foxglove's
    /// published JSON Schemas; zstd chunks.
    #[arg(long, value_name = "OUT.mcap")]
    pub mcap: Option<PathBuf>,
}

/// An MCAP file written step by step; the first error is kept and
/// reported by [`Recorder::finish`] (the run itself goes on).
pub struct Recorder {
    out: Option<McapOut>,
    path: PathBuf,
    sigma: f64,
    error: Option<locus_foxglove::Error>,
    first: Option<f64>,
    last: f64,
    scene: Scene,
}

impl Recorder {
    /// Starts `path`, with the map `scene` drawn at the first step and
    /// ellipses at `sigma` standard deviations.
    ///
    /// # Errors
    /// The file cannot be created.
    pub fn create(path: &Path, scene: Scene, sigma: f64) -> Result<Self> {
        let out = McapOut::create(path).with_context(|| format!("--mcap {}", path.display()))?;
        Ok(Self {
            out: Some(out),
            path: path.to_path_buf(),
            sigma,
            error: None,
            first: None,
            last: 0.0,
            scene,
        })
    }

    /// Writes one step.
    pub fn push(&mut self, f: &Frame) {
        let (Some(out), None) = (self.out.as_mut(), &self.error) else {
            return;
        };
        let mut write = || -> Result<(), locus_foxglove::Error> {
            if self.first.is_none() {
                self.first = Some(f.time);
                out.write_all(&locus_foxglove::scene(&self.scene, f.time)?)?;
            }
            out.write_all(&locus_foxglove::frame(f, self.sigma)?)?;
            self.last = self.last.max(f.time);
            Ok(())
        };
        if let Err(e) = write() {
            self.error = Some(e);
        }
    }

    /// Writes `summary` (by `name`, e.g. `locus replay`) at the last step's
    /// time and finishes the file.
    ///
    /// # Errors
    /// The first error met while writing, or the file cannot be finished.
    pub fn finish(mut self, summary: &str, name: &str) -> Result<Written> {
        let context = || format!("writing {}", self.path.display());
        if let Some(e) = self.error.take() {
            return Err(e).with_context(context);
        }
        let mut out = self
            .out
            .take()
            .context("the MCAP file was already finished")?;
        out.write(&locus_foxglove::summary(summary, self.last, name).with_context(context)?)
            .with_context(context)?;
        out.finish().with_context(context)
    }
}

/// The line naming the file and its messages per topic.
pub fn written(w: &Written) -> String {
    let counts: Vec<String> = w
        .counts
        .iter()
        .map(|(t, n)| format!("{} {n}", t.name()))
        .collect();
    format!("mcap: {} ({})\n", w.path.display(), counts.join(", "))
}

/// The frame of a simulated step (its [`Sample`]).
pub fn frame_of_sample(s: &Sample) -> Frame {
    let truth = [s.truth[0], s.truth[1], s.truth_heading];
    Frame {
        time: s.time,
        estimate: [s.estimate[0], s.estimate[1], s.estimate_heading],
        covariance: s.covariance,
        truth: Some(truth),
        odometry: s.odometry.map(|(p, heading_error)| {
            [
                p[0],
                p[1],
                locus_core::wrap_angle(s.truth_heading - heading_error),
            ]
        }),
        correction: s.correction,
        nees: Some((s.nees, s.nees_dof)),
    }
}

/// The frame of a replayed step: its estimate, the truth at it if any,
/// odometry alone, the correction it made.
pub fn frame_of_step(step: &locus_replay::Step) -> Frame {
    let b = &step.belief;
    let mut covariance = [[0.0; 3]; 3];
    for (i, row) in covariance.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = b.p[(i, j)];
        }
    }
    let sample = step.sample();
    Frame {
        time: step.time,
        estimate: [b.x[0], b.x[1], b.x[2]],
        covariance,
        truth: step.truth.map(|t| [t.x, t.y, t.theta]),
        odometry: Some(step.dead_reckoning),
        correction: step.measurement().1,
        nees: sample.map(|s| (s.nees, s.nees_dof)),
    }
}

/// The scene of walls (`[x1, y1, x2, y2]`, m), landmarks and a map.
pub fn scene(
    walls: Vec<[f64; 4]>,
    landmarks: &[locus_replay::Landmark],
    map: Option<&locus_map::Map>,
) -> Scene {
    let mut s = Scene {
        walls,
        landmarks: landmarks.iter().map(|l| (l.id, [l.x, l.y])).collect(),
        grid: None,
    };
    match map {
        Some(locus_map::Map::Segments(m)) => {
            s.walls
                .extend(m.segments().iter().map(locus_map::Segment::to_array));
        }
        Some(locus_map::Map::Grid(g)) => s.grid = Some(grid_cells(g)),
        None => {}
    }
    s
}

/// An occupancy grid as ROS's `OccupancyGrid` cells: probability x 100,
/// -1 unknown.
fn grid_cells(g: &locus_map::Grid) -> GridCells {
    let geo = g.geometry();
    let (w, h) = (geo.width(), geo.height());
    let mut cells = Vec::with_capacity(w * h);
    for iy in 0..h {
        for ix in 0..w {
            // A probability in [0, 1] times 100: fits an i8.
            #[allow(clippy::cast_possible_truncation)]
            cells.push(
                g.probability(ix, iy)
                    .map_or(-1, |p| (100.0 * p).round() as i8),
            );
        }
    }
    GridCells {
        origin: geo.origin(),
        resolution: geo.resolution(),
        width: u32::try_from(w).unwrap_or(u32::MAX),
        height: u32::try_from(h).unwrap_or(u32::MAX),
        cells,
    }
}
