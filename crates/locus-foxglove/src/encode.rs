//! A run as Foxglove messages: each step's [`Frame`] becomes the estimate,
//! truth and odometry poses, the robot's transform, the covariance ellipse,
//! the errors with their 3-sigma bands and the NIS; the [`Scene`] becomes
//! the map, once; the summary a log message. [`crate::McapOut`] writes them
//! to a file, [`crate::ws`] frames them for the live WebSocket.

use core::f64::consts::TAU;

use base64::Engine as _;

use crate::Error;
use crate::message::{
    Color, Errors, FrameTransform, Grid, LinePrimitive, LineType, Log, LogLevel, Nis,
    PackedElementField, Pose, PoseInFrame, Quaternion, SceneEntity, SceneUpdate, SpherePrimitive,
    TextPrimitive, Time, Vector2, Vector3,
};
use crate::topic::{ROBOT_FRAME, Topic, WORLD_FRAME};

/// Points on the covariance ellipse.
const ELLIPSE_POINTS: usize = 32;

/// A drawn point's coordinate, to the micrometre: far below what a
/// display resolves, and a third of the JSON of all 17 digits.
fn drawn(v: f64) -> f64 {
    (v * 1e6).round() * 1e-6
}

/// One step of a run: what the filter believes, and what it is judged by.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// Time (s; >= 0, the log's own clock).
    pub time: f64,
    /// Estimated `[x, y, heading]` (m, m, rad).
    pub estimate: [f64; 3],
    /// Its covariance (m^2, m rad, rad^2).
    pub covariance: [[f64; 3]; 3],
    /// The true `[x, y, heading]` if the step has one (heading NaN when the
    /// truth has none: the pose is then drawn facing +x, and the heading
    /// error is null).
    pub truth: Option<[f64; 3]>,
    /// Odometry alone `[x, y, heading]`, if the run has it.
    pub odometry: Option<[f64; 3]>,
    /// The step's correction, if any: NIS, its dof, whether applied.
    pub correction: Option<(f64, u32, bool)>,
    /// NEES against the truth and its dof, when there is a truth.
    pub nees: Option<(f64, u32)>,
}

/// What the robot moves in, drawn once.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    /// Walls `[x1, y1, x2, y2]` (m).
    pub walls: Vec<[f64; 4]>,
    /// Landmarks: id and position (m).
    pub landmarks: Vec<(u32, [f64; 2])>,
    /// An occupancy grid, if the map is one.
    pub grid: Option<GridCells>,
}

/// An occupancy grid's cells as ROS's `OccupancyGrid` holds them.
#[derive(Debug, Clone, PartialEq)]
pub struct GridCells {
    /// The corner of cell (0, 0) `[x, y, yaw]` (m, m, rad).
    pub origin: [f64; 3],
    /// Cell size (m).
    pub resolution: f64,
    /// Cells per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Row by row from the origin's: 0 free to 100 occupied, -1 unknown.
    pub cells: Vec<i8>,
}

/// One message: its topic, time (ns) and JSON payload.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Message {
    /// The topic.
    pub topic: Topic,
    /// Its time (ns since the epoch of the run's clock).
    pub time: u64,
    /// The JSON payload.
    pub payload: Vec<u8>,
}

/// `time` (s) in nanoseconds.
///
/// # Errors
/// [`Error::Time`] for a time that is negative, not finite, or past what
/// Foxglove's 32-bit seconds carry.
pub fn nanos(time: f64, what: &'static str) -> Result<u64, Error> {
    if !(0.0..4.294_967_295e9).contains(&time) {
        return Err(Error::Time { time, what });
    }
    // In range and finite: exact to the nanosecond's rounding.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    Ok((time * 1e9).round() as u64)
}

fn json(topic: Topic, time: u64, value: &impl serde::Serialize) -> Message {
    Message {
        topic,
        time,
        // Plain data with finite numbers: serialising cannot fail.
        payload: serde_json::to_vec(value).unwrap_or_default(),
    }
}

fn finite(what: &'static str, value: f64, time: f64) -> Result<f64, Error> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(Error::NotFinite { what, value, time })
    }
}

fn pose(what: &'static str, p: [f64; 3], time: f64) -> Result<[f64; 3], Error> {
    let heading = if p[2].is_nan() { 0.0 } else { p[2] };
    Ok([
        finite(what, p[0], time)?,
        finite(what, p[1], time)?,
        finite(what, heading, time)?,
    ])
}

const ESTIMATE: Color = Color {
    r: 0.12,
    g: 0.47,
    b: 0.71,
    a: 1.0,
};
const WALL: Color = Color {
    r: 0.35,
    g: 0.35,
    b: 0.35,
    a: 1.0,
};
const LANDMARK: Color = Color {
    r: 0.84,
    g: 0.15,
    b: 0.16,
    a: 1.0,
};

/// The messages of one step; the ellipse is drawn at `sigma` standard
/// deviations.
///
/// # Errors
/// A time Foxglove cannot carry, or an estimate, covariance or truth
/// position that is not finite.
pub fn frame(f: &Frame, sigma: f64) -> Result<Vec<Message>, Error> {
    let t = nanos(f.time, "a step")?;
    let stamp = Time::from_nanos(t);
    let estimate = pose("the estimate", f.estimate, f.time)?;
    let mut out = Vec::with_capacity(7);
    let in_map = |p: [f64; 3]| PoseInFrame {
        timestamp: stamp,
        frame_id: WORLD_FRAME.to_string(),
        pose: Pose::planar(p),
    };
    out.push(json(Topic::Estimate, t, &in_map(estimate)));
    out.push(json(
        Topic::Transform,
        t,
        &FrameTransform {
            timestamp: stamp,
            parent_frame_id: WORLD_FRAME.to_string(),
            child_frame_id: ROBOT_FRAME.to_string(),
            translation: Vector3::planar(estimate[0], estimate[1]),
            rotation: Quaternion::yaw(estimate[2]),
        },
    ));
    if let Some(truth) = f.truth {
        out.push(json(
            Topic::Truth,
            t,
            &in_map(pose("the truth", truth, f.time)?),
        ));
    }
    if let Some(odometry) = f.odometry {
        out.push(json(
            Topic::Odometry,
            t,
            &in_map(pose("odometry", odometry, f.time)?),
        ));
    }
    let p = &f.covariance;
    let mut sd = [0.0; 3];
    for (i, s) in sd.iter_mut().enumerate() {
        *s = finite("a variance", p[i][i], f.time)?.max(0.0).sqrt();
    }
    for row in p {
        for &v in row {
            finite("a covariance", v, f.time)?;
        }
    }
    out.push(json(
        Topic::Ellipse,
        t,
        &ellipse(stamp, estimate, p, sd[2], sigma),
    ));
    let error = |i: usize| {
        f.truth.and_then(|truth| {
            let e = if i == 2 {
                wrap(truth[2] - f.estimate[2])
            } else {
                truth[i] - f.estimate[i]
            };
            e.is_finite().then_some(e)
        })
    };
    out.push(json(
        Topic::Errors,
        t,
        &Errors {
            timestamp: stamp,
            x: error(0),
            y: error(1),
            heading: error(2),
            x_plus_3_sigma: 3.0 * sd[0],
            x_minus_3_sigma: -3.0 * sd[0],
            y_plus_3_sigma: 3.0 * sd[1],
            y_minus_3_sigma: -3.0 * sd[1],
            heading_plus_3_sigma: 3.0 * sd[2],
            heading_minus_3_sigma: -3.0 * sd[2],
            nees: f.nees.map(|(v, _)| v).filter(|v| v.is_finite()),
            nees_dof: f.nees.filter(|(v, _)| v.is_finite()).map(|(_, d)| d),
        },
    ));
    if let Some((nis, dof, applied)) = f.correction
        && nis.is_finite()
        && dof > 0
    {
        out.push(json(
            Topic::Nis,
            t,
            &Nis {
                timestamp: stamp,
                nis: nis.max(0.0),
                dof,
                applied,
            },
        ));
    }
    Ok(out)
}

/// `angle` wrapped to (-pi, pi].
fn wrap(angle: f64) -> f64 {
    let a = angle.rem_euclid(TAU);
    if a > core::f64::consts::PI {
        a - TAU
    } else {
        a
    }
}

/// The position's `sigma` ellipse (a closed line, from the eigenvectors
/// of the 2 x 2 block) and the heading's `sigma` bounds (two rays from the
/// estimate, as long as the ellipse's major axis and at least 5 cm).
fn ellipse(
    stamp: Time,
    at: [f64; 3],
    p: &[[f64; 3]; 3],
    sd_heading: f64,
    sigma: f64,
) -> SceneUpdate {
    let (a, b, c) = (p[0][0], p[0][1], p[1][1]);
    // Eigen-decomposition of [[a, b], [b, c]].
    let mean = 0.5 * (a + c);
    let radius = (0.25 * (a - c).powi(2) + b * b).sqrt();
    let (l1, l2) = ((mean + radius).max(0.0), (mean - radius).max(0.0));
    let angle = 0.5 * (2.0 * b).atan2(a - c);
    let (r1, r2) = (sigma * l1.sqrt(), sigma * l2.sqrt());
    let (s, co) = angle.sin_cos();
    let points = (0..ELLIPSE_POINTS)
        .map(|k| {
            #[allow(clippy::cast_precision_loss)]
            let u = TAU * k as f64 / ELLIPSE_POINTS as f64;
            let (eu, ev) = (r1 * u.cos(), r2 * u.sin());
            Vector3::planar(
                drawn(at[0] + co * eu - s * ev),
                drawn(at[1] + s * eu + co * ev),
            )
        })
        .collect();
    let reach = r1.max(0.05);
    let ray = |d: f64| {
        Vector3::planar(
            at[0] + reach * (at[2] + d).cos(),
            at[1] + reach * (at[2] + d).sin(),
        )
    };
    let spread = (sigma * sd_heading).min(core::f64::consts::PI);
    let line = |kind, points| LinePrimitive {
        kind,
        pose: Pose::identity(),
        thickness: 2.0,
        scale_invariant: true,
        points,
        color: ESTIMATE,
        colors: Vec::new(),
        indices: Vec::new(),
    };
    let mut entity = SceneEntity::new(stamp, WORLD_FRAME, "covariance");
    entity.lines = vec![
        line(LineType::Loop, points),
        line(
            LineType::Strip,
            vec![ray(-spread), Vector3::planar(at[0], at[1]), ray(spread)],
        ),
    ];
    entity.metadata = vec![crate::message::KeyValuePair {
        key: "sigma".to_string(),
        value: format!("{sigma}"),
    }];
    SceneUpdate {
        deletions: Vec::new(),
        entities: vec![entity],
    }
}

/// The scene's messages at `time` (s): the walls and landmarks as one
/// scene entity, and the grid when there is one.
///
/// # Errors
/// A time Foxglove cannot carry.
pub fn scene(s: &Scene, time: f64) -> Result<Vec<Message>, Error> {
    let t = nanos(time, "the map")?;
    let stamp = Time::from_nanos(t);
    let mut out = Vec::new();
    if !s.walls.is_empty() || !s.landmarks.is_empty() {
        let mut entity = SceneEntity::new(stamp, WORLD_FRAME, "map");
        if !s.walls.is_empty() {
            entity.lines.push(LinePrimitive {
                kind: LineType::List,
                pose: Pose::identity(),
                thickness: 3.0,
                scale_invariant: true,
                points: s
                    .walls
                    .iter()
                    .flat_map(|w| [Vector3::planar(w[0], w[1]), Vector3::planar(w[2], w[3])])
                    .collect(),
                color: WALL,
                colors: Vec::new(),
                indices: Vec::new(),
            });
        }
        let size = landmark_size(s);
        for &(id, [x, y]) in &s.landmarks {
            let at = Pose::planar([x, y, 0.0]);
            entity.spheres.push(SpherePrimitive {
                pose: at,
                size: Vector3 {
                    x: size,
                    y: size,
                    z: size,
                },
                color: LANDMARK,
            });
            entity.texts.push(TextPrimitive {
                pose: Pose::planar([x + size, y + size, 0.0]),
                billboard: true,
                font_size: 14.0,
                scale_invariant: true,
                color: LANDMARK,
                text: id.to_string(),
            });
        }
        out.push(json(
            Topic::Map,
            t,
            &SceneUpdate {
                deletions: Vec::new(),
                entities: vec![entity],
            },
        ));
    }
    if let Some(g) = &s.grid {
        // i8 as its two's-complement byte, as ROS stores it.
        #[allow(clippy::cast_sign_loss)]
        let bytes: Vec<u8> = g.cells.iter().map(|&c| c as u8).collect();
        out.push(json(
            Topic::Grid,
            t,
            &Grid {
                timestamp: stamp,
                frame_id: WORLD_FRAME.to_string(),
                pose: Pose::planar(g.origin),
                column_count: g.width,
                cell_size: Vector2 {
                    x: g.resolution,
                    y: g.resolution,
                },
                row_stride: g.width,
                cell_stride: 1,
                fields: vec![PackedElementField {
                    name: "occupancy".to_string(),
                    offset: 0,
                    kind: 2,
                }],
                data: base64::engine::general_purpose::STANDARD.encode(bytes),
            },
        ));
    }
    Ok(out)
}

/// A landmark's drawn diameter: 1.5 % of the scene's extent, at least 2 cm.
fn landmark_size(s: &Scene) -> f64 {
    let xs = s
        .landmarks
        .iter()
        .map(|l| l.1)
        .chain(s.walls.iter().flat_map(|w| [[w[0], w[1]], [w[2], w[3]]]));
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in xs {
        for i in 0..2 {
            lo[i] = lo[i].min(p[i]);
            hi[i] = hi[i].max(p[i]);
        }
    }
    let extent = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    if extent.is_finite() {
        (0.015 * extent).max(0.02)
    } else {
        0.1
    }
}

/// The run's summary as a log message at `time` (s), written by `name`
/// (for example `locus replay`).
///
/// # Errors
/// A time Foxglove cannot carry.
pub fn summary(text: &str, time: f64, name: &str) -> Result<Message, Error> {
    let t = nanos(time, "the summary")?;
    Ok(json(
        Topic::Summary,
        t,
        &Log {
            timestamp: Time::from_nanos(t),
            level: LogLevel::Info,
            message: text.to_string(),
            name: name.to_string(),
            file: String::new(),
            line: 0,
        },
    ))
}
