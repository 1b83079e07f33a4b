//! Which topics and fields of a bag are what the filter needs: a small
//! TOML file (docs/bags.md), for example
//!
//! ```toml
//! base_frame = "base_link"   # the robot's frame in /tf_static (the default)
//! map = "maps/lab.yaml"      # for scans and ranges: the map (or [[wall]] entries)
//!
//! [velocity]                 # required: the input
//! topic = "/cmd_vel"         # geometry_msgs/msg/Twist, TwistStamped or nav_msgs/msg/Odometry
//!
//! [landmarks]                # range-bearing sightings of point landmarks
//! topic = "/landmarks"
//! id = "id"                  # field paths in each message (these are the defaults)
//! range = "range"
//! bearing = "bearing"        # "" for range-only sightings
//!
//! [truth]                    # ground truth, e.g. motion capture
//! topic = "/mocap/pose"      # PoseStamped, PoseWithCovarianceStamped, Odometry, TransformStamped
//!
//! [[scan]]                   # sensor_msgs/msg/LaserScan: a beam sensor
//! topic = "/scan"
//! [[range]]                  # sensor_msgs/msg/Range: a one-beam sensor (IR, sonar)
//! topic = "/ir_left"
//!
//! [[landmark]]               # the landmark map
//! id = 6
//! x = 0.588
//! y = -4.283
//! ```
//!
//! A field path is dotted, with `[i]` for an element (`twist.twist.linear.x`).
//! Where a path is left out, the message type's usual one is taken
//! ([`Defaults`]); a message's time is its `header.stamp` when its type has
//! a header, else the time the bag logged it (`stamp = ""` forces the
//! latter). A sensor (the landmarks', a scan's, a range's) sits where
//! `/tf_static` puts its frame (`frame`, default the messages'
//! `header.frame_id`) relative to `base_frame`; at the robot's centre
//! without one.

use serde::Deserialize;

/// The whole mapping.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mapping {
    /// The robot's frame in `/tf_static`.
    #[serde(default = "base_link")]
    pub base_frame: String,
    /// The velocities (the filter's input).
    pub velocity: Velocity,
    /// Landmark sightings, if any.
    pub landmarks: Option<Landmarks>,
    /// Ground truth, if any.
    pub truth: Option<Truth>,
    /// The landmark map.
    #[serde(default, rename = "landmark")]
    pub landmark_map: Vec<MapEntry>,
    /// The map the scans and ranges are corrected against (a ROS
    /// map_server YAML, or walls as text or TOML: docs/maps.md), relative
    /// to the mapping file.
    pub map: Option<String>,
    /// Walls of the map (instead of a map file), m.
    #[serde(default, rename = "wall")]
    pub walls: Vec<WallEntry>,
    /// Laser scans (`sensor_msgs/msg/LaserScan`), each topic a beam sensor.
    #[serde(default, rename = "scan")]
    pub scans: Vec<BeamTopic>,
    /// Single ranges (`sensor_msgs/msg/Range`: IR, sonar, a laser
    /// rangefinder), each topic a one-beam sensor.
    #[serde(default, rename = "range")]
    pub ranges: Vec<BeamTopic>,
}

/// A topic of range readings: a `LaserScan` or a `Range`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BeamTopic {
    /// The topic.
    pub topic: String,
    /// The sensor's frame in `/tf_static`; default the messages'
    /// `header.frame_id`.
    pub frame: Option<String>,
    /// The stamp; `""` for the log time.
    pub stamp: Option<String>,
}

fn base_link() -> String {
    "base_link".into()
}

/// The velocity topic and its fields.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Velocity {
    /// The topic.
    pub topic: String,
    /// Forward speed, m/s.
    pub linear: Option<String>,
    /// Turn rate, rad/s.
    pub angular: Option<String>,
    /// The stamp (`builtin_interfaces/Time`); `""` for the log time.
    pub stamp: Option<String>,
}

/// The landmark topic and its fields.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Landmarks {
    /// The topic.
    pub topic: String,
    /// The path of a list of sightings in each message; without it, a
    /// message is one sighting.
    pub list: Option<String>,
    /// The landmark's id (an integer), in a sighting.
    #[serde(default = "id")]
    pub id: String,
    /// The range, m, in a sighting.
    #[serde(default = "range")]
    pub range: String,
    /// The bearing, rad, in a sighting; `""` for range only.
    #[serde(default = "bearing")]
    pub bearing: String,
    /// The stamp, in the message; `""` for the log time.
    pub stamp: Option<String>,
    /// The sensor's frame in `/tf_static`; default the message's
    /// `header.frame_id`.
    pub frame: Option<String>,
}

fn id() -> String {
    "id".into()
}
fn range() -> String {
    "range".into()
}
fn bearing() -> String {
    "bearing".into()
}

/// The truth topic and its fields.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Truth {
    /// The topic.
    pub topic: String,
    /// The position (a message with `x` and `y`, m).
    pub position: Option<String>,
    /// The orientation (a quaternion `x, y, z, w`); `""` for positions only.
    pub orientation: Option<String>,
    /// The stamp; `""` for the log time.
    pub stamp: Option<String>,
}

/// A landmark of the map.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MapEntry {
    /// Its id, as the sightings name it.
    pub id: u32,
    /// Position in the world frame, m.
    pub x: f64,
    /// See `x`.
    pub y: f64,
}

/// A wall segment of the map, m.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallEntry {
    /// One end.
    pub x1: f64,
    /// See `x1`.
    pub y1: f64,
    /// The other end.
    pub x2: f64,
    /// See `x2`.
    pub y2: f64,
}

/// The usual field paths of the message types a mapping's topics have.
pub struct Defaults;

impl Defaults {
    /// `(linear, angular)` of a velocity message type.
    #[must_use]
    pub fn velocity(type_name: &str) -> Option<(&'static str, &'static str)> {
        Some(match type_name {
            "geometry_msgs/msg/Twist" => ("linear.x", "angular.z"),
            "geometry_msgs/msg/TwistStamped" => ("twist.linear.x", "twist.angular.z"),
            "geometry_msgs/msg/TwistWithCovarianceStamped" => {
                ("twist.twist.linear.x", "twist.twist.angular.z")
            }
            "nav_msgs/msg/Odometry" => ("twist.twist.linear.x", "twist.twist.angular.z"),
            _ => return None,
        })
    }

    /// `(position, orientation)` of a pose message type.
    #[must_use]
    pub fn pose(type_name: &str) -> Option<(&'static str, &'static str)> {
        Some(match type_name {
            "geometry_msgs/msg/PoseStamped" => ("pose.position", "pose.orientation"),
            "geometry_msgs/msg/PoseWithCovarianceStamped" | "nav_msgs/msg/Odometry" => {
                ("pose.pose.position", "pose.pose.orientation")
            }
            "geometry_msgs/msg/TransformStamped" => ("transform.translation", "transform.rotation"),
            "geometry_msgs/msg/Pose" => ("position", "orientation"),
            _ => return None,
        })
    }
}

impl Mapping {
    /// The mapping in the TOML `text` of the file `file` (for errors).
    ///
    /// # Errors
    /// Text that does not parse or has another shape (an unknown key, a
    /// missing `velocity`), with the file, line and key.
    pub fn from_toml(text: &str, file: &str) -> Result<Self, String> {
        toml::from_str(text).map_err(|e| {
            let line = e
                .span()
                .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
            let at = line.map(|l| format!(":{l}")).unwrap_or_default();
            format!("{file}{at}: {}", e.message())
        })
    }
}
