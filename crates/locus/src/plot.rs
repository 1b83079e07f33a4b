//! Pictures of a run, from its per-step [`Sample`]s and its [`Map`] (walls
//! or landmarks), so they work for every scenario and log: `map` (walls, true / estimated / odometry
//! paths, covariance ellipses of the x-y block), `errors` (x, y, heading
//! errors with +-3 sigma bands) and `covariance` (the variances over time,
//! log scale), each as PNG and SVG; `nis` for a replay. Text uses the
//! embedded font (`crate::font`).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow};
use locus_eval::Sample;
use locus_models::laser_wall::Segment;
use plotters::coord::{CoordTranslate, Shift};
use plotters::prelude::*;

use crate::font::{self, FAMILY};

/// Picture size (pixels) of the time plots; the map is square.
const SIZE: (u32, u32) = (1000, 700);

/// Side of the square map picture (pixels).
const MAP_SIDE: u32 = 800;
/// Width of the band right of the map that holds its legend, pixels (the
/// legend never covers the data).
const MAP_LEGEND: u32 = 380;
/// Covariance ellipses drawn on the map at most (over long runs they are
/// spread out further than [`ELLIPSE_EVERY`]).
const MAX_ELLIPSES: f64 = 25.0;
/// An ellipse whose semi-major axis exceeds this share of the map's side is
/// not drawn: it would cover the map and says only "lost".
const ELLIPSE_MAX_SHARE: f64 = 0.1;

/// At most this many points per plotted series (the samples are thinned
/// evenly; the SVGs stay small).
const MAX_POINTS: usize = 2000;

/// Default level of the covariance ellipses on the map (standard
/// deviations).
pub const ELLIPSE_SIGMA: f64 = 3.0;

/// The pictures' options of `locus run` and `locus replay`.
#[derive(clap::Args, Debug)]
pub struct PictureArgs {
    /// Do not draw the pictures. By default a single run or a replay also
    /// writes `map`, `errors` and `covariance` as PNG and SVG into the
    /// output directory: the map (walls, or landmarks as crosses) with the
    /// true, estimated and odometry paths and covariance ellipses; x, y,
    /// heading errors with +-3 sigma bands; the variances over time (log
    /// scale); a replay with corrections also `nis`.
    #[arg(long)]
    pub no_plots: bool,
    /// Level of the covariance ellipses on the map, in standard deviations
    /// (positive). The legend gives the probability a 2-D Gaussian falls
    /// inside, 1 - exp(-k^2/2): 39.3 % at 1 sigma (not 68.3 %), 68.3 % at
    /// 1.515, 98.9 % at 3.
    #[arg(long, default_value_t = ELLIPSE_SIGMA, value_parser = crate::args::positive_f64)]
    pub ellipse_sigma: f64,
}

/// Half the arm of a landmark's cross on the map, m.
const CROSS_HALF: f64 = 0.15;

/// What the map shows under the paths, in the world frame (m).
#[derive(Debug, Clone, Copy)]
pub enum Map<'a> {
    /// A simulated world's walls, drawn as thick lines.
    Walls(&'a [Segment<f64>]),
    /// A log's landmarks at `[x, y]`, drawn as crosses.
    Landmarks(&'a [[f64; 2]]),
}

impl Map<'_> {
    /// The strokes that draw the map (`[a, b]` end points, m) and their
    /// legend label.
    fn strokes(self) -> (Vec<[[f64; 2]; 2]>, &'static str) {
        match self {
            Map::Walls(walls) => (walls.iter().map(|w| [w.a, w.b]).collect(), "walls"),
            Map::Landmarks(points) => (
                points
                    .iter()
                    .flat_map(|&[x, y]| {
                        [
                            [[x - CROSS_HALF, y], [x + CROSS_HALF, y]],
                            [[x, y - CROSS_HALF], [x, y + CROSS_HALF]],
                        ]
                    })
                    .collect(),
                "landmarks",
            ),
        }
    }
}

/// Simulated time between two covariance ellipses on the map (s).
const ELLIPSE_EVERY: f64 = 10.0;

/// Probability that a 2-D Gaussian falls inside its `k`-sigma ellipse:
/// `1 - exp(-k^2 / 2)` (the squared Mahalanobis distance is chi-square with
/// 2 dof). For `k = 3`: 98.9 %, not the 1-D 99.7 %.
#[must_use]
pub fn ellipse_probability(k: f64) -> f64 {
    1.0 - (-k * k / 2.0).exp()
}

/// Every `ceil(n / MAX_POINTS)`-th sample (and the last).
fn thinned(samples: &[Sample]) -> impl Iterator<Item = &Sample> {
    let step = samples.len().div_ceil(MAX_POINTS).max(1);
    samples
        .iter()
        .enumerate()
        .filter(move |(i, _)| i % step == 0 || i + 1 == samples.len())
        .map(|(_, s)| s)
}

/// The `k`-sigma ellipse of the 2x2 covariance `[[a, b], [b, c]]` around
/// `centre`, as a closed polygon (m).
fn ellipse(centre: [f64; 2], a: f64, b: f64, c: f64, k: f64) -> Vec<(f64, f64)> {
    let half = (a - c) / 2.0;
    let root = (half * half + b * b).sqrt();
    let l1 = ((a + c) / 2.0 + root).max(0.0);
    let l2 = ((a + c) / 2.0 - root).max(0.0);
    let angle = 0.5 * (2.0 * b).atan2(a - c);
    let (sa, ca) = angle.sin_cos();
    (0..=72)
        .map(|i| {
            let t = f64::from(i) * core::f64::consts::TAU / 72.0;
            let (u, v) = (k * l1.sqrt() * t.cos(), k * l2.sqrt() * t.sin());
            (centre[0] + ca * u - sa * v, centre[1] + sa * u + ca * v)
        })
        .collect()
}

/// Draws with `$draw` (a function taking the drawing area first) on a PNG
/// backend if `$ext` is `"png"`, else on an SVG one, at `$path` and `$size`.
/// A macro because the two backends are different types.
macro_rules! on_backend {
    ($ext:expr, $path:expr, $size:expr, $draw:ident($($arg:expr),* $(,)?)) => {
        if $ext == "png" {
            $draw(&BitMapBackend::new($path, $size).into_drawing_area(), $($arg),*)
        } else {
            $draw(&SVGBackend::new($path, $size).into_drawing_area(), $($arg),*)
        }
    };
}
pub(crate) use on_backend;

/// A plotters error as an anyhow error.
pub(crate) fn err<E: core::fmt::Debug>(e: E) -> anyhow::Error {
    anyhow!("drawing: {e:?}")
}

/// A legend entry: a short line in `style`.
fn legend_line(style: ShapeStyle) -> impl Fn((i32, i32)) -> PathElement<(i32, i32)> {
    move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style)
}

/// Draws the legend of `chart` at `position`: labels in `font_size` on a
/// translucent white box.
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    font_size: u32,
    position: SeriesLabelPosition,
) -> Result<()> {
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font((FAMILY, font_size))
        .position(position)
        .draw()
        .map_err(err)
}

/// The map: walls, paths and covariance ellipses.
fn draw_map<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    samples: &[Sample],
    map: Map<'_>,
    title: &str,
    sigma: f64,
) -> Result<()> {
    let (strokes, map_label) = map.strokes();
    root.fill(&WHITE).map_err(err)?;
    let (area, band) = root.split_horizontally(MAP_SIDE);
    let mut legend: Vec<(String, ShapeStyle)> = Vec::new();
    let mut xs: Vec<f64> = Vec::new();
    let mut ys: Vec<f64> = Vec::new();
    for [a, b] in &strokes {
        xs.extend([a[0], b[0]]);
        ys.extend([a[1], b[1]]);
    }
    for s in samples {
        xs.extend([s.truth[0], s.estimate[0]]);
        ys.extend([s.truth[1], s.estimate[1]]);
        if let Some((p, _)) = s.odometry {
            xs.push(p[0]);
            ys.push(p[1]);
        }
    }
    let fold = |v: &[f64]| {
        v.iter()
            .filter(|x| x.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
                (lo.min(x), hi.max(x))
            })
    };
    let ((x0, x1), (y0, y1)) = (fold(&xs), fold(&ys));
    if !(x0.is_finite() && y0.is_finite()) {
        return Err(anyhow!("nothing to draw on the map"));
    }
    // Equal scales on both axes, 10 % margin.
    let side = (x1 - x0).max(y1 - y0).max(0.1) * 1.1;
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let mut chart = ChartBuilder::on(&area)
        .caption(title, (FAMILY, 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (cx - side / 2.0)..(cx + side / 2.0),
            (cy - side / 2.0)..(cy + side / 2.0),
        )
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("x [m]")
        .y_desc("y [m]")
        .label_style((FAMILY, 14))
        .draw()
        .map_err(err)?;

    let wall_style = ShapeStyle::from(&BLACK).stroke_width(4);
    for (i, [a, b]) in strokes.iter().enumerate() {
        let series = LineSeries::new([(a[0], a[1]), (b[0], b[1])], wall_style);
        chart.draw_series(series).map_err(err)?;
        if i == 0 {
            legend.push((map_label.to_string(), wall_style));
        }
    }
    let truth = RGBColor(0, 150, 0);
    let est = RGBColor(0, 80, 220);
    let odo = RGBColor(220, 60, 0);
    let ellipse_color = RGBColor(160, 0, 160);
    chart
        .draw_series(LineSeries::new(
            thinned(samples).map(|s| (s.truth[0], s.truth[1])),
            truth.stroke_width(2),
        ))
        .map_err(err)?;
    legend.push(("true path".to_string(), truth.stroke_width(2)));
    chart
        .draw_series(LineSeries::new(
            thinned(samples).map(|s| (s.estimate[0], s.estimate[1])),
            est.stroke_width(1),
        ))
        .map_err(err)?;
    legend.push(("EKF estimate".to_string(), est.stroke_width(2)));
    if samples.iter().any(|s| s.odometry.is_some()) {
        chart
            .draw_series(LineSeries::new(
                thinned(samples).filter_map(|s| s.odometry.map(|(p, _)| (p[0], p[1]))),
                odo.stroke_width(1),
            ))
            .map_err(err)?;
        legend.push(("odometry alone".to_string(), odo.stroke_width(2)));
    }
    let span = match (samples.first(), samples.last()) {
        (Some(a), Some(b)) => b.time - a.time,
        _ => 0.0,
    };
    let every = ELLIPSE_EVERY.max(span / MAX_ELLIPSES);
    let widest = ELLIPSE_MAX_SHARE * side;
    let mut next = 0.0;
    let mut ellipses = Vec::new();
    let mut too_wide = 0usize;
    for s in samples {
        if s.time + 1e-9 >= next {
            next = s.time + every;
            let p = &s.covariance;
            // Semi-major axis of the k-sigma ellipse: k sqrt(largest eigenvalue).
            let half = (p[0][0] - p[1][1]) / 2.0;
            let largest = (p[0][0] + p[1][1]) / 2.0 + half.hypot(p[0][1]);
            if sigma * largest.max(0.0).sqrt() > widest {
                too_wide += 1;
                continue;
            }
            ellipses.push(ellipse(
                [s.estimate[0], s.estimate[1]],
                p[0][0],
                p[0][1],
                p[1][1],
                sigma,
            ));
        }
    }
    chart
        .draw_series(
            ellipses
                .into_iter()
                .map(|e| PathElement::new(e, ellipse_color.stroke_width(1))),
        )
        .map_err(err)?;
    legend.push((
        format!(
            "{sigma}-sigma ellipses of x-y ({:.1} %),",
            100.0 * ellipse_probability(sigma)
        ),
        ellipse_color.stroke_width(2),
    ));
    legend.push((
        format!("  every {every:.0} s, true scale;"),
        ShapeStyle::from(&WHITE),
    ));
    legend.push((
        format!("  {too_wide} wider than {widest:.2} m not drawn"),
        ShapeStyle::from(&WHITE),
    ));
    draw_side_legend(&band, &legend)?;
    root.present().map_err(err)?;
    Ok(())
}

/// A legend in its own area (beside a chart, off its data): a short line
/// in each entry's style and its label.
fn draw_side_legend<DB: DrawingBackend>(
    band: &DrawingArea<DB, Shift>,
    entries: &[(String, ShapeStyle)],
) -> Result<()> {
    for (i, (label, style)) in entries.iter().enumerate() {
        #[allow(clippy::cast_possible_truncation, clippy::cast_possible_wrap)]
        let y = 70 + 26 * i as i32;
        band.draw(&PathElement::new(vec![(10, y), (45, y)], *style))
            .map_err(err)?;
        band.draw(&Text::new(label.as_str(), (55, y - 8), (FAMILY, 15)))
            .map_err(err)?;
    }
    Ok(())
}

/// One panel of the error plot: `error(s)` and `+-3 sigma(s)` over time,
/// in display units (`scale`).
fn error_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    samples: &[Sample],
    name: &str,
    unit: &str,
    scale: f64,
    error: impl Fn(&Sample) -> f64,
    variance: impl Fn(&Sample) -> f64,
) -> Result<()> {
    let t1 = samples.last().map_or(1.0, |s| s.time).max(1e-3);
    let band = |s: &Sample| scale * 3.0 * variance(s).max(0.0).sqrt();
    let hi = thinned(samples)
        .map(|s| (scale * error(s)).abs().max(band(s)))
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max)
        .max(1e-9)
        * 1.1;
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(0.0..t1, -hi..hi)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time [s]")
        .y_desc(format!("{name} error [{unit}]"))
        .label_style((FAMILY, 13))
        .draw()
        .map_err(err)?;
    let band_color = RGBColor(150, 150, 150);
    // The band as one polygon: +3 sigma forwards, -3 sigma backwards.
    let upper: Vec<(f64, f64)> = thinned(samples).map(|s| (s.time, band(s))).collect();
    let polygon: Vec<(f64, f64)> = upper
        .iter()
        .copied()
        .chain(upper.iter().rev().map(|&(t, b)| (t, -b)))
        .collect();
    chart
        .draw_series(core::iter::once(Polygon::new(
            polygon,
            band_color.mix(0.35).filled(),
        )))
        .map_err(err)?
        .label("+-3 sigma (EKF covariance)")
        .legend(move |(x, y)| {
            Rectangle::new([(x, y - 5), (x + 20, y + 5)], band_color.mix(0.5).filled())
        });
    let line = RGBColor(0, 80, 220);
    chart
        .draw_series(LineSeries::new(
            thinned(samples).map(|s| (s.time, scale * error(s))),
            line.stroke_width(1),
        ))
        .map_err(err)?
        .label(format!("{name} error (truth - EKF)"))
        .legend(legend_line(line.stroke_width(2)));
    draw_legend(&mut chart, 13, SeriesLabelPosition::UpperRight)?;
    Ok(())
}

/// x, y and heading errors with their +-3 sigma bands.
fn draw_errors<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    samples: &[Sample],
    title: &str,
) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let root = root.titled(title, (FAMILY, 20)).map_err(err)?;
    let panels = root.split_evenly((3, 1));
    error_panel(
        &panels[0],
        samples,
        "x",
        "cm",
        100.0,
        |s| s.truth[0] - s.estimate[0],
        |s| s.covariance[0][0],
    )?;
    error_panel(
        &panels[1],
        samples,
        "y",
        "cm",
        100.0,
        |s| s.truth[1] - s.estimate[1],
        |s| s.covariance[1][1],
    )?;
    error_panel(
        &panels[2],
        samples,
        "heading",
        "deg",
        180.0 / core::f64::consts::PI,
        |s| s.heading_error,
        |s| s.covariance[2][2],
    )?;
    root.present().map_err(err)?;
    Ok(())
}

/// The variances `P_x`, `P_y` (m^2) and `P_theta` (rad^2) over time, log
/// scale.
fn draw_covariance<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    samples: &[Sample],
    title: &str,
) -> Result<()> {
    root.fill(&WHITE).map_err(err)?;
    let t1 = samples.last().map_or(1.0, |s| s.time).max(1e-3);
    let (lo, hi) = samples
        .iter()
        .flat_map(|s| (0..3).map(|i| s.covariance[i][i]))
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if !lo.is_finite() {
        return Err(anyhow!("no positive variance to draw"));
    }
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FAMILY, 20))
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d(0.0..t1, (lo / 2.0..hi * 2.0).log_scale())
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time [s]")
        .y_desc("variance [m^2 (x, y); rad^2 (theta)]")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .label_style((FAMILY, 14))
        .draw()
        .map_err(err)?;
    let series = [
        ("P_x [m^2]", 0, RGBColor(0, 80, 220)),
        ("P_y [m^2]", 1, RGBColor(0, 150, 0)),
        ("P_theta [rad^2]", 2, RGBColor(220, 60, 0)),
    ];
    for (name, i, color) in series {
        chart
            .draw_series(LineSeries::new(
                thinned(samples)
                    .filter(|s| s.covariance[i][i] > 0.0)
                    .map(|s| (s.time, s.covariance[i][i])),
                color.stroke_width(2),
            ))
            .map_err(err)?
            .label(name)
            .legend(legend_line(color.stroke_width(2)));
    }
    draw_legend(&mut chart, 14, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(err)?;
    Ok(())
}

/// Writes `map` (the [`Map`] `map`, the paths, ellipses at
/// `ellipse_sigma` standard deviations),
/// `errors` and `covariance` as `.png` and `.svg` into `dir`; returns the
/// paths written.
///
/// # Errors
/// No samples, or a picture that cannot be drawn or written.
pub fn write_all(
    dir: &Path,
    samples: &[Sample],
    map: Map<'_>,
    title: &str,
    ellipse_sigma: f64,
) -> Result<Vec<PathBuf>> {
    if samples.is_empty() {
        return Err(anyhow!("no steps to plot"));
    }
    if !(ellipse_sigma.is_finite() && ellipse_sigma > 0.0) {
        return Err(anyhow!("the ellipse level must be finite and > 0 sigma"));
    }
    font::register()?;
    let mut written = Vec::new();
    for ext in ["png", "svg"] {
        let map_file = dir.join(format!("map.{ext}"));
        let errors = dir.join(format!("errors.{ext}"));
        let cov = dir.join(format!("covariance.{ext}"));
        let map_title = format!("{title}: paths and covariance");
        let err_title = format!("{title}: EKF errors and +-3 sigma");
        let cov_title = format!("{title}: EKF variances");
        let side = (MAP_SIDE + MAP_LEGEND, MAP_SIDE);
        on_backend!(
            ext,
            &map_file,
            side,
            draw_map(samples, map, &map_title, ellipse_sigma)
        )
        .with_context(|| format!("writing {}", map_file.display()))?;
        on_backend!(ext, &errors, SIZE, draw_errors(samples, &err_title))
            .with_context(|| format!("writing {}", errors.display()))?;
        on_backend!(ext, &cov, SIZE, draw_covariance(samples, &cov_title))
            .with_context(|| format!("writing {}", cov.display()))?;
        written.extend([map_file, errors, cov]);
    }
    Ok(written)
}

/// One correction on the NIS picture: time (s), NIS, window mean, lower
/// and upper bound of the mean's interval.
type NisRow = (f64, f64, f64, f64, f64);

/// A line of the NIS picture: label (empty: none), colour, value of a row.
type NisLine = (&'static str, RGBColor, fn(&NisRow) -> f64);

/// Corrections in the NIS monitor's window on the `nis` picture.
pub const NIS_WINDOW: usize = 50;

/// Writes `nis.png` and `nis.svg` into `dir`: the NIS of every correction
/// against time (capped at the top of the plot), the mean NIS over the last
/// [`NIS_WINDOW`] corrections from [`locus_core::ConsistencyMonitor`] and its
/// two-sided 95 % acceptance interval; returns the paths written.
///
/// # Errors
/// No corrections, or a picture that cannot be drawn or written.
pub fn write_nis(dir: &Path, samples: &[Sample], title: &str) -> Result<Vec<PathBuf>> {
    use locus_core::ConsistencyMonitor;
    let mut monitor = ConsistencyMonitor::<NIS_WINDOW>::new(0.95).map_err(err)?;
    // (time, NIS, window mean, lower, upper) per correction.
    let mut rows: Vec<NisRow> = Vec::new();
    for s in samples {
        if let Some((nis, dof, _)) = s.correction {
            monitor.push(nis, dof);
            let c = monitor.assess();
            rows.push((s.time, nis, c.mean_nis, c.lower, c.upper));
        }
    }
    if rows.is_empty() {
        return Err(anyhow!("no corrections to plot"));
    }
    font::register()?;
    let mut written = Vec::new();
    for ext in ["png", "svg"] {
        let path = dir.join(format!("nis.{ext}"));
        let t = format!("{title}: NIS and its {NIS_WINDOW}-correction mean");
        on_backend!(ext, &path, SIZE, draw_nis(&rows, &t))
            .with_context(|| format!("writing {}", path.display()))?;
        written.push(path);
    }
    Ok(written)
}

fn draw_nis<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    rows: &[NisRow],
    title: &str,
) -> Result<()> {
    const TOP: f64 = 20.0;
    root.fill(&WHITE).map_err(err)?;
    let t1 = rows.last().map_or(1.0, |r| r.0).max(1e-3);
    let mut chart = ChartBuilder::on(root)
        .caption(title, (FAMILY, 20))
        .margin(10)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..t1, 0.0..TOP)
        .map_err(err)?;
    chart
        .configure_mesh()
        .x_desc("time [s]")
        .y_desc("NIS [-]")
        .label_style((FAMILY, 13))
        .draw()
        .map_err(err)?;
    let step = rows.len().div_ceil(MAX_POINTS * 2).max(1);
    let dots = RGBColor(120, 120, 120);
    chart
        .draw_series(
            rows.iter()
                .step_by(step)
                .map(|r| Circle::new((r.0, r.1.min(TOP)), 1, dots.filled())),
        )
        .map_err(err)?
        .label(format!("NIS of a correction (capped at {TOP})"))
        .legend(move |(x, y)| Circle::new((x + 10, y), 3, dots.filled()));
    let series: [NisLine; 3] = [
        ("window mean NIS", RGBColor(0, 80, 220), |r| r.2),
        ("95 % interval of the mean", RGBColor(200, 40, 40), |r| r.3),
        ("", RGBColor(200, 40, 40), |r| r.4),
    ];
    for (label, color, f) in series {
        let s = chart
            .draw_series(LineSeries::new(
                rows.iter()
                    .step_by(step)
                    .filter(|r| f(r).is_finite())
                    .map(|r| (r.0, f(r).min(TOP))),
                color.stroke_width(2),
            ))
            .map_err(err)?;
        if !label.is_empty() {
            s.label(label).legend(legend_line(color.stroke_width(2)));
        }
    }
    draw_legend(&mut chart, 13, SeriesLabelPosition::UpperRight)?;
    root.present().map_err(err)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ellipse_probabilities_are_those_of_a_2d_gaussian() {
        assert!((ellipse_probability(1.0) - 0.393_469).abs() < 1e-6);
        assert!((ellipse_probability(3.0) - 0.988_891).abs() < 1e-6);
    }

    #[test]
    fn an_ellipse_has_the_covariances_axes() {
        // P = diag(4, 1), rotated by 90 deg: x variance 1, y variance 4.
        let e = ellipse([1.0, 2.0], 1.0, 0.0, 4.0, 3.0);
        let max_x = e.iter().map(|p| (p.0 - 1.0).abs()).fold(0.0, f64::max);
        let max_y = e.iter().map(|p| (p.1 - 2.0).abs()).fold(0.0, f64::max);
        assert!((max_x - 3.0).abs() < 1e-9, "{max_x}");
        assert!((max_y - 6.0).abs() < 1e-9, "{max_y}");
    }
}
