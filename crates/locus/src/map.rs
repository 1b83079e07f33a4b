//! `locus map`: an occupancy grid from a log's scans taken at known poses
//! (log-odds mapping, `locus_map::GridBuilder`), written in ROS
//! map_server's format (`map.yaml` + `map.pgm`) with a picture of the grid
//! and the path (`map.png`), so that a user maps once and localises after.
//!
//! The poses: a Locus CSV log's ground truth (with heading) interpolated at
//! each scan's time, or a CARMEN log's corrected pose of each scan. Each
//! beam starts at the sensor's mount on the robot and points at the
//! sensor's beam angle; a return marks its cell occupied and clears the
//! cells before it; a beam with no return clears up to `--clear-limit`; a
//! missing reading is left out. docs/maps.md.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail, ensure};
use clap::ArgGroup;
use locus_logs::scans::Reading as Stored;
use locus_logs::{BeamSensor, Scans};
use locus_map::{BuilderConfig, Grid, GridBuilder, GridGeometry, Reading};
use plotters::prelude::*;

use crate::font::{self, FAMILY};
use crate::plot::err;
use crate::table;

/// Most cells a grid may have (a 10 km square at 1 m, 100 m at 1 cm): a
/// larger one is refused before it is allocated.
const MAX_CELLS: usize = 100_000_000;

/// Longest side of the picture's grid area, pixels.
const PICTURE_SIDE: u32 = 900;

/// Arguments of `locus map`.
#[derive(clap::Args, Debug)]
#[command(group(ArgGroup::new("input").required(true).args(["log", "carmen"])))]
pub struct Args {
    /// A Locus CSV log (v4, docs/log-format.md; `.xz` read directly) with
    /// `beam_sensor` and `scan` records and ground truth with heading
    /// (`truth,t,x,y,theta`): each scan is placed at the truth interpolated
    /// at its time.
    pub log: Option<PathBuf>,
    /// Map from a CARMEN log instead (e.g. the Intel lab's
    /// `intel-corrected.log.gz`; plain, `.gz` or `.xz`): each scan at its
    /// corrected pose.
    #[arg(long, value_name = "FILE")]
    pub carmen: Option<PathBuf>,
    /// Cell size, m.
    #[arg(long, default_value_t = 0.05, value_parser = crate::args::positive_f64)]
    pub resolution: f64,
    /// Space around the poses and the returns' end points, m (each side).
    #[arg(long, default_value_t = 1.0, value_parser = non_negative_f64)]
    pub margin: f64,
    /// A CSV log's scan is skipped (and counted) if the truth has no pose
    /// within this time of it on both sides, s.
    #[arg(long, default_value_t = 0.1, value_parser = non_negative_f64)]
    pub max_gap: f64,
    /// How far a beam with no return clears free space, m (0: not at all;
    /// a beam with a return clears up to it, however far).
    #[arg(long, default_value_t = BuilderConfig::default().clear_limit, value_parser = non_negative_f64)]
    pub clear_limit: f64,
    /// Output directory [default: out/map-NAME, NAME the log's file name
    /// without its extensions].
    #[arg(long)]
    pub out: Option<PathBuf>,
}

/// A finite number `>= 0`.
fn non_negative_f64(text: &str) -> Result<f64, String> {
    let v = crate::args::finite_f64(text)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("must be >= 0, got {v}"))
    }
}

/// The scans to map and where each was taken.
struct Input {
    path: PathBuf,
    sensors: Vec<BeamSensor>,
    scans: Scans,
    /// The robot's pose (m, m, rad; world frame) at each scan, `None` if
    /// unknown.
    poses: Vec<Option<[f64; 3]>>,
}

impl Input {
    fn csv(path: &Path, max_gap: f64) -> Result<Self> {
        let log = locus_logs::locus_csv::read(path)
            .with_context(|| format!("reading the Locus log {}", path.display()))?;
        ensure!(
            !log.beam_sensors.is_empty() && !log.scans.is_empty(),
            "{}: no beam_sensor or no scan records, nothing to map (docs/log-format.md, \"Walls and beams\")",
            path.display()
        );
        ensure!(
            !log.truth.poses().is_empty() && log.truth.has_heading(),
            "{}: mapping needs ground truth with heading (truth,t,x,y,theta) to place the scans",
            path.display()
        );
        let mut cursor = log.truth.cursor();
        let poses = log
            .scans
            .iter()
            .map(|s| {
                cursor
                    .pose_at(s.time, max_gap)
                    .filter(|p| p.theta.is_finite())
                    .map(|p| [p.x, p.y, p.theta])
            })
            .collect();
        Ok(Self {
            path: path.to_path_buf(),
            sensors: log.beam_sensors,
            scans: log.scans,
            poses,
        })
    }

    fn carmen(path: &Path) -> Result<Self> {
        let c = locus_logs::carmen::read(path)
            .with_context(|| format!("reading the CARMEN log {}", path.display()))?;
        ensure!(
            c.scan_poses.len() == c.log.scans.len(),
            "{}: {} corrected poses for {} scans",
            path.display(),
            c.scan_poses.len(),
            c.log.scans.len()
        );
        Ok(Self {
            path: path.to_path_buf(),
            poses: c
                .scan_poses
                .iter()
                .map(|p| Some([p.x, p.y, p.theta]))
                .collect(),
            sensors: c.log.beam_sensors,
            scans: c.log.scans,
        })
    }

    fn sensor(&self, id: u32) -> Result<&BeamSensor> {
        self.sensors
            .iter()
            .find(|s| s.id == id)
            .with_context(|| format!("a scan of beam sensor {id}, which is not declared"))
    }

    /// The scans with a pose: the sensor, the sensor's pose (m, m, rad;
    /// world frame) and the scan's stored ranges.
    fn placed(&self) -> impl Iterator<Item = Result<(&BeamSensor, [f64; 3], &[f32])>> + '_ {
        self.scans
            .iter()
            .zip(&self.poses)
            .filter_map(|(scan, pose)| pose.map(|p| (scan, p)))
            .map(|(scan, p)| {
                let sensor = self.sensor(scan.sensor)?;
                Ok((sensor, sensor.mounted(p), scan.ranges))
            })
    }
}

/// The output directory's default name: `map-` and the file name without
/// its extensions.
fn default_out(path: &Path) -> PathBuf {
    let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("log");
    let stem = name
        .split('.')
        .next()
        .filter(|s| !s.is_empty())
        .unwrap_or("log");
    PathBuf::from("out").join(format!("map-{stem}"))
}

/// The box (m, world frame) of the sensor positions and the returns' end
/// points.
fn bounds(input: &Input) -> Result<([f64; 2], [f64; 2])> {
    let mut min = [f64::INFINITY; 2];
    let mut max = [f64::NEG_INFINITY; 2];
    let mut add = |p: [f64; 2]| {
        for k in 0..2 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    };
    for placed in input.placed() {
        let (sensor, pose, ranges) = placed?;
        add([pose[0], pose[1]]);
        for (k, &r) in (0u32..).zip(ranges) {
            if let Stored::Range(r) = Stored::of(r) {
                let a = pose[2] + sensor.angle(k);
                let r = f64::from(r);
                add([pose[0] + r * a.cos(), pose[1] + r * a.sin()]);
            }
        }
    }
    if !(min[0].is_finite() && min[1].is_finite() && max[0].is_finite() && max[1].is_finite()) {
        bail!("no scan has a pose: nothing to map (see --max-gap)");
    }
    Ok((min, max))
}

/// Runs `locus map`.
pub fn run(args: &Args) -> Result<()> {
    let input = match (&args.log, &args.carmen) {
        (_, Some(path)) => Input::carmen(path)?,
        (Some(path), None) => Input::csv(path, args.max_gap)?,
        (None, None) => bail!("give a Locus CSV log or --carmen FILE"),
    };
    let out = args.out.clone().unwrap_or_else(|| default_out(&input.path));
    crate::output::writable_dir(&out)?;

    let (min, max) = bounds(&input)?;
    let geometry = GridGeometry::covering(min, max, args.margin, args.resolution)
        .context("the grid's size")?;
    ensure!(
        geometry.len() <= MAX_CELLS,
        "a grid of {} x {} cells ({:.0} x {:.0} m at {} m): more than {MAX_CELLS} cells; a coarser --resolution?",
        geometry.width(),
        geometry.height(),
        geometry.width() as f64 * args.resolution,
        geometry.height() as f64 * args.resolution,
        args.resolution
    );
    let config = BuilderConfig {
        clear_limit: args.clear_limit,
        ..BuilderConfig::default()
    };
    let mut builder = GridBuilder::new(geometry, config)?;
    let used = input.poses.iter().filter(|p| p.is_some()).count();
    let bar = crate::output::progress_bar(used as u64, "{pos}/{len} scans, {elapsed} elapsed")?;
    let (mut returns, mut no_returns, mut missing) = (0usize, 0usize, 0usize);
    for placed in input.placed() {
        let (sensor, pose, ranges) = placed?;
        for (k, &r) in (0u32..).zip(ranges) {
            let reading = match Stored::of(r) {
                Stored::Range(r) => {
                    returns += 1;
                    Reading::Range(f64::from(r))
                }
                Stored::NoReturn => {
                    no_returns += 1;
                    Reading::NoReturn
                }
                Stored::Missing => {
                    missing += 1;
                    continue;
                }
            };
            builder.insert_beam([pose[0], pose[1]], pose[2] + sensor.angle(k), reading);
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let grid = builder.finish();

    let yaml = out.join("map.yaml");
    locus_map::ros::save(&grid, &yaml, locus_map::ros::Mode::Trinary)
        .with_context(|| format!("writing {}", yaml.display()))?;
    let png = out.join("map.png");
    let path: Vec<(f64, f64)> = input.poses.iter().flatten().map(|p| (p[0], p[1])).collect();
    let title = input
        .path
        .file_name()
        .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
    draw(&png, &grid, &path, &title)?;

    let skipped = input.poses.len() - used;
    let (occupied, free, unknown) = grid.counts();
    let g = grid.geometry();
    let mut t = table::with_header(["map [unit]", "value"]);
    let rows = [
        ("input".to_string(), input.path.display().to_string()),
        ("scans used [count]".to_string(), used.to_string()),
        (
            format!("scans skipped, no pose within {} s [count]", args.max_gap),
            skipped.to_string(),
        ),
        (
            "beams: returns / no return / missing [count]".to_string(),
            format!("{returns} / {no_returns} / {missing}"),
        ),
        (
            "cells occupied / free / unknown [count]".to_string(),
            format!("{occupied} / {free} / {unknown}"),
        ),
        (
            "size [m] (cells)".to_string(),
            format!(
                "{:.2} x {:.2} ({} x {} at {} m)",
                g.width() as f64 * g.resolution(),
                g.height() as f64 * g.resolution(),
                g.width(),
                g.height(),
                g.resolution()
            ),
        ),
        (
            "origin (lower-left corner) [m]".to_string(),
            format!("{:.3}, {:.3}", g.origin()[0], g.origin()[1]),
        ),
        (
            "files written".to_string(),
            [yaml, out.join("map.pgm"), png]
                .iter()
                .map(|p| p.display().to_string())
                .collect::<Vec<_>>()
                .join("\n"),
        ),
    ];
    for (name, value) in rows {
        t.add_row(vec![name, value]);
    }
    crate::output::print_out(&format!("{t}\n"))
}

/// The picture: the grid (occupied black, free white, unknown grey) under
/// the path of the poses (`path`, m), with axes in metres.
fn draw(png: &Path, grid: &Grid, path: &[(f64, f64)], title: &str) -> Result<()> {
    font::register()?;
    let g = grid.geometry();
    let (w, h) = (g.width() as f64, g.height() as f64);
    let scale = f64::from(PICTURE_SIDE) / w.max(h);
    let (pw, ph) = ((w * scale).ceil() as u32, (h * scale).ceil() as u32);
    let (left, bottom, top, right) = (80, 50, 50, 30);
    let size = (pw + left + right, ph + bottom + top);
    let root = BitMapBackend::new(png, size).into_drawing_area();
    root.fill(&WHITE).map_err(err)?;
    let origin = g.origin();
    let (x0, y0) = (origin[0], origin[1]);
    let (x1, y1) = (x0 + w * g.resolution(), y0 + h * g.resolution());
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "{title}: occupancy grid at {} m, and the path",
                g.resolution()
            ),
            (FAMILY, 20),
        )
        .margin_right(right)
        .x_label_area_size(bottom)
        .y_label_area_size(left)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(err)?;
    chart
        .configure_mesh()
        .disable_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .label_style((FAMILY, 14))
        .draw()
        .map_err(err)?;
    let area = chart.plotting_area().strip_coord_spec();
    let (aw, ah) = area.dim_in_pixel();
    let grey = RGBColor(180, 180, 180);
    for py in 0..ah {
        // Pixel rows top down, grid rows bottom up.
        let iy = (((f64::from(ah - 1 - py) + 0.5) / f64::from(ah)) * h) as usize;
        for px in 0..aw {
            let ix = (((f64::from(px) + 0.5) / f64::from(aw)) * w) as usize;
            let colour = match grid.state(ix, iy) {
                Some(locus_map::Occupancy::Occupied) => BLACK,
                Some(locus_map::Occupancy::Free) => WHITE,
                _ => grey,
            };
            area.draw_pixel((px as i32, py as i32), &colour)
                .map_err(err)?;
        }
    }
    chart
        .draw_series(LineSeries::new(path.iter().copied(), RED.stroke_width(2)))
        .map_err(err)?
        .label("scan poses")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], RED.stroke_width(2)));
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FAMILY, 14))
        .position(SeriesLabelPosition::UpperRight)
        .draw()
        .map_err(err)?;
    root.present()
        .with_context(|| format!("writing {}", png.display()))
}
