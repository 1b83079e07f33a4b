//! The Foxglove messages Locus writes, field for field as Foxglove's
//! published JSON Schemas (`schemas/foxglove/`) name them, and Locus's two
//! own series (`schemas/locus/`). Serialised with serde as JSON.

use serde::Serialize;

/// A time: whole seconds and nanoseconds (Foxglove's `time`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Time {
    /// Seconds (>= 0).
    pub sec: u32,
    /// Nanoseconds, 0 to 999 999 999.
    pub nsec: u32,
}

impl Time {
    /// The time `ns` nanoseconds after the epoch.
    #[must_use]
    pub fn from_nanos(ns: u64) -> Self {
        Self {
            sec: u32::try_from(ns / 1_000_000_000).unwrap_or(u32::MAX),
            // Below 1e9: fits.
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// `foxglove.Vector3` and `foxglove.Point3` (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Vector3 {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// z (m).
    pub z: f64,
}

impl Vector3 {
    /// The point `(x, y)` on the floor (m).
    #[must_use]
    pub const fn planar(x: f64, y: f64) -> Self {
        Self { x, y, z: 0.0 }
    }
}

/// `foxglove.Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Quaternion {
    /// The rotation by `yaw` (rad) about z.
    #[must_use]
    pub fn yaw(yaw: f64) -> Self {
        let (s, c) = (0.5 * yaw).sin_cos();
        Self {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }
}

/// `foxglove.Pose`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pose {
    /// Position (m).
    pub position: Vector3,
    /// Orientation.
    pub orientation: Quaternion,
}

impl Pose {
    /// The planar pose `(x, y, theta)` (m, m, rad).
    #[must_use]
    pub fn planar([x, y, theta]: [f64; 3]) -> Self {
        Self {
            position: Vector3::planar(x, y),
            orientation: Quaternion::yaw(theta),
        }
    }

    /// The origin, unrotated.
    #[must_use]
    pub fn identity() -> Self {
        Self::planar([0.0; 3])
    }
}

/// `foxglove.PoseInFrame`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoseInFrame {
    /// Time of the pose.
    pub timestamp: Time,
    /// Frame of the pose.
    pub frame_id: String,
    /// The pose.
    pub pose: Pose,
}

/// `foxglove.FrameTransform`: where `child_frame_id` is in `parent_frame_id`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameTransform {
    /// Time of the transform.
    pub timestamp: Time,
    /// The parent frame.
    pub parent_frame_id: String,
    /// The child frame.
    pub child_frame_id: String,
    /// The child's origin in the parent (m).
    pub translation: Vector3,
    /// The child's orientation in the parent.
    pub rotation: Quaternion,
}

/// `foxglove.Color` (each 0 to 1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Color {
    /// Red.
    pub r: f64,
    /// Green.
    pub g: f64,
    /// Blue.
    pub b: f64,
    /// Opacity.
    pub a: f64,
}

/// `foxglove.LineType`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineType {
    /// 0-1, 1-2, ..., (n-1)-n.
    Strip = 0,
    /// A closed polygon.
    Loop = 1,
    /// Separate segments: 0-1, 2-3, ...
    List = 2,
}

impl Serialize for LineType {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u8(*self as u8)
    }
}

/// `foxglove.LinePrimitive`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LinePrimitive {
    /// How the points join.
    #[serde(rename = "type")]
    pub kind: LineType,
    /// Origin of the points in the entity's frame.
    pub pose: Pose,
    /// Width: pixels when `scale_invariant`, else m.
    pub thickness: f64,
    /// Whether `thickness` is in screen pixels.
    pub scale_invariant: bool,
    /// The points (m).
    pub points: Vec<Vector3>,
    /// Colour of the whole line.
    pub color: Color,
    /// Per-point colours (none: `color`).
    pub colors: Vec<Color>,
    /// Point indices to draw (none: all, in order).
    pub indices: Vec<u32>,
}

/// `foxglove.SpherePrimitive`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SpherePrimitive {
    /// Centre.
    pub pose: Pose,
    /// Diameters along x, y, z (m).
    pub size: Vector3,
    /// Colour.
    pub color: Color,
}

/// `foxglove.TextPrimitive`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TextPrimitive {
    /// Where the text sits.
    pub pose: Pose,
    /// Whether it always faces the camera.
    pub billboard: bool,
    /// Size: pixels when `scale_invariant`, else m.
    pub font_size: f64,
    /// Whether `font_size` is in screen pixels.
    pub scale_invariant: bool,
    /// Colour.
    pub color: Color,
    /// The text.
    pub text: String,
}

/// `foxglove.KeyValuePair`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KeyValuePair {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// `foxglove.Duration`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Duration {
    /// Seconds.
    pub sec: i32,
    /// Nanoseconds, 0 to 999 999 999.
    pub nsec: u32,
}

/// `foxglove.SceneEntity`, with the primitives Locus draws (the others
/// empty).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneEntity {
    /// Time of the entity.
    pub timestamp: Time,
    /// Its frame.
    pub frame_id: String,
    /// Its id: a later entity of the same id replaces it.
    pub id: String,
    /// How long it shows (zero: until replaced or deleted).
    pub lifetime: Duration,
    /// Whether it moves with its frame.
    pub frame_locked: bool,
    /// Key-value pairs shown beside it.
    pub metadata: Vec<KeyValuePair>,
    /// Arrows (none).
    pub arrows: Vec<serde_json::Value>,
    /// Cubes (none).
    pub cubes: Vec<serde_json::Value>,
    /// Spheres.
    pub spheres: Vec<SpherePrimitive>,
    /// Cylinders (none).
    pub cylinders: Vec<serde_json::Value>,
    /// Lines.
    pub lines: Vec<LinePrimitive>,
    /// Triangle lists (none).
    pub triangles: Vec<serde_json::Value>,
    /// Texts.
    pub texts: Vec<TextPrimitive>,
    /// Models (none).
    pub models: Vec<serde_json::Value>,
}

impl SceneEntity {
    /// An entity `id` in `frame_id` at `timestamp` that shows until
    /// replaced, with nothing in it yet.
    #[must_use]
    pub fn new(timestamp: Time, frame_id: &str, id: &str) -> Self {
        Self {
            timestamp,
            frame_id: frame_id.to_string(),
            id: id.to_string(),
            lifetime: Duration { sec: 0, nsec: 0 },
            frame_locked: false,
            metadata: Vec::new(),
            arrows: Vec::new(),
            cubes: Vec::new(),
            spheres: Vec::new(),
            cylinders: Vec::new(),
            lines: Vec::new(),
            triangles: Vec::new(),
            texts: Vec::new(),
            models: Vec::new(),
        }
    }
}

/// `foxglove.SceneUpdate` (Locus deletes nothing: entities are replaced by
/// id).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneUpdate {
    /// Deletions (none).
    pub deletions: Vec<serde_json::Value>,
    /// Entities added or replaced.
    pub entities: Vec<SceneEntity>,
}

/// `foxglove.PackedElementField`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PackedElementField {
    /// Name.
    pub name: String,
    /// Byte offset in an element.
    pub offset: u32,
    /// `foxglove.NumericType` (2: INT8).
    #[serde(rename = "type")]
    pub kind: u8,
}

/// `foxglove.Grid`: an occupancy grid, one `int8` per cell as ROS's
/// `OccupancyGrid` (0 free to 100 occupied, -1 unknown).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Grid {
    /// Time of the grid.
    pub timestamp: Time,
    /// Its frame.
    pub frame_id: String,
    /// The corner of cell (0, 0) (m, rad).
    pub pose: Pose,
    /// Cells per row.
    pub column_count: u32,
    /// Cell size (m).
    pub cell_size: Vector2,
    /// Bytes per row.
    pub row_stride: u32,
    /// Bytes per cell.
    pub cell_stride: u32,
    /// What a cell holds.
    pub fields: Vec<PackedElementField>,
    /// The cells, row by row from the origin's, base64.
    pub data: String,
}

/// `foxglove.Vector2` (m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Vector2 {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
}

/// `foxglove.LogLevel`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogLevel {
    /// Information.
    Info = 2,
    /// A warning.
    Warning = 3,
}

impl Serialize for LogLevel {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u8(*self as u8)
    }
}

/// `foxglove.Log`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Log {
    /// Time of the message.
    pub timestamp: Time,
    /// Level.
    pub level: LogLevel,
    /// The text.
    pub message: String,
    /// Who wrote it (`locus replay`, `locus run`).
    pub name: String,
    /// Source file (empty).
    pub file: String,
    /// Source line (0).
    pub line: u32,
}

/// `locus.Errors` (`schemas/locus/Errors.json`): one step's errors against
/// the truth and 3-sigma bands.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[allow(missing_docs)] // Documented in the schema, field by field.
pub struct Errors {
    pub timestamp: Time,
    pub x: Option<f64>,
    pub y: Option<f64>,
    pub heading: Option<f64>,
    pub x_plus_3_sigma: f64,
    pub x_minus_3_sigma: f64,
    pub y_plus_3_sigma: f64,
    pub y_minus_3_sigma: f64,
    pub heading_plus_3_sigma: f64,
    pub heading_minus_3_sigma: f64,
    pub nees: Option<f64>,
    pub nees_dof: Option<u32>,
}

/// `locus.Nis` (`schemas/locus/Nis.json`): one correction's NIS.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Nis {
    /// Time of the correction.
    pub timestamp: Time,
    /// Normalised innovation squared.
    pub nis: f64,
    /// Its degrees of freedom.
    pub dof: u32,
    /// Whether the gate let it through.
    pub applied: bool,
}
