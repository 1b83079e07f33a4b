//! A bag as a Locus log ([`LocusLog`], the one every replay source becomes):
//! the mapping's velocity topic as odometry, its landmark topic as
//! sightings, its truth topic as ground truth, `/tf_static` as the
//! landmark sensor's mount, and the mapping's landmark map.
//!
//! Times: a stamp `builtin_interfaces/Time` `(sec, nanosec)` is
//! `sec + nanosec * 1e-9` s; a log time (ns) alike. Headings: the yaw of a
//! quaternion, `atan2(2 (w z + x y), 1 - 2 (y^2 + z^2))`.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use locus_logs::BeamSensor;
use locus_logs::locus_csv::{LandmarkMeasurement, LocusLog, MapLandmark};
use locus_logs::mrclam::{Groundtruth, Odometry, TruthPose};
use locus_logs::scans::Scans;
use locus_logs::se2::{Pose, compose};
use locus_logs::sensor::SensorMount;
use locus_logs::wall::{MapPath, Wall};

use crate::bag::{Channel, RawMessage, read};
use crate::error::{BagError, FieldProblem};
use crate::mapping::{Defaults, Mapping};
use crate::value::Value;

mod beams;
mod fast;

use beams::{range, scan};

/// The static transforms' topic.
pub const TF_STATIC: &str = "/tf_static";

/// A time in seconds from whole seconds and nanoseconds.
#[allow(clippy::cast_precision_loss)]
fn seconds(sec: i64, nanosec: u64) -> f64 {
    sec as f64 + nanosec as f64 * 1e-9
}

/// A log time (ns) in seconds.
#[allow(clippy::cast_possible_wrap)]
fn log_seconds(ns: u64) -> f64 {
    seconds((ns / 1_000_000_000) as i64, ns % 1_000_000_000)
}

/// The yaw of a quaternion `[x, y, z, w]`, rad.
fn yaw([x, y, z, w]: [f64; 4]) -> f64 {
    (2.0 * (w * z + x * y)).atan2(1.0 - 2.0 * (y * y + z * z))
}

/// Reads fields of one message, naming the topic, type and field on error.
struct Fields<'a> {
    file: &'a Path,
    channel: &'a Channel,
    record: u64,
    value: &'a Value,
}

/// The error of `field` of the message `record` of `channel` in `file`.
fn field_error(
    file: &Path,
    channel: &Channel,
    record: u64,
    field: &str,
    reason: impl Into<String>,
) -> BagError {
    BagError::Field {
        file: file.to_path_buf(),
        record,
        problem: Box::new(FieldProblem {
            topic: channel.topic.clone(),
            type_name: channel.type_name.clone(),
            field: field.to_string(),
            reason: reason.into(),
        }),
    }
}

impl Fields<'_> {
    fn error(&self, field: &str, reason: impl Into<String>) -> BagError {
        field_error(self.file, self.channel, self.record, field, reason)
    }

    fn at<'v>(&self, within: &'v Value, path: &str) -> Result<&'v Value, BagError> {
        within
            .get(path)
            .ok_or_else(|| self.error(path, "no such field in the message"))
    }

    fn number(&self, within: &Value, path: &str) -> Result<f64, BagError> {
        self.at(within, path)?
            .as_f64()
            .ok_or_else(|| self.error(path, "not a number"))
    }

    /// The number `key` of `within`, the value at `prefix` (which names
    /// the field in an error).
    fn number_in(&self, within: &Value, prefix: &str, key: &str) -> Result<f64, BagError> {
        within
            .get(key)
            .and_then(Value::as_f64)
            .ok_or_else(|| self.error(&format!("{prefix}.{key}"), "no such number in the message"))
    }

    /// The stamp `v` (`sec`, `nanosec`) found at `path`, in s.
    fn stamp(&self, v: &Value, path: &str) -> Result<f64, BagError> {
        let (Some(Value::Int(sec)), Some(Value::UInt(ns))) = (v.get("sec"), v.get("nanosec"))
        else {
            return Err(self.error(path, "not a builtin_interfaces/Time (sec, nanosec)"));
        };
        Ok(seconds(*sec, *ns))
    }

    /// The message's time: the stamp at `path`, its `header.stamp` when
    /// `path` is not given and it has a header, else the log time.
    fn time(&self, path: Option<&str>, log_time_ns: u64) -> Result<f64, BagError> {
        match path {
            Some("") => Ok(log_seconds(log_time_ns)),
            Some(p) => self.stamp(self.at(self.value, p)?, p),
            None => match self.value.get("header.stamp") {
                Some(v) => self.stamp(v, "header.stamp"),
                None => Ok(log_seconds(log_time_ns)),
            },
        }
    }

    /// The path given, or the type's usual one, or an error saying which
    /// key to set.
    fn path<'p>(
        &self,
        given: Option<&'p str>,
        usual: Option<&'p str>,
        key: &str,
    ) -> Result<&'p str, BagError> {
        given.or(usual).ok_or_else(|| {
            self.error(
                key,
                format!(
                    "no usual field for type {}: set `{key}` in the mapping",
                    self.channel.type_name
                ),
            )
        })
    }
}

/// What [`to_locus`] keeps of a channel once its first message is read.
struct ChannelState {
    /// Whether the mapping reads the channel.
    wanted: bool,
    /// The value its messages are decoded into (reused).
    value: Value,
    /// Its fast path, once its first message has been taken (`Some(None)`:
    /// it has none).
    fast: Option<Option<fast::Fast>>,
}

/// What the bag gives, as it is read.
#[derive(Default)]
struct Gathered {
    odometry: Vec<Odometry>,
    measurements: Vec<LandmarkMeasurement>,
    truth: Vec<TruthPose>,
    /// Static transforms by child frame: (parent, transform).
    tf: HashMap<String, (String, Pose)>,
    /// The landmark messages' frame, as they name it.
    sensor_frame: Option<String>,
    truth_has_heading: Option<bool>,
    /// Topics seen, for the error when a mapped one is missing.
    topics: Vec<String>,
    /// The beam sensors of the scan and range topics (in the mapping's
    /// order, scans first), once their first message is read, with their
    /// frame.
    beams: Vec<Option<(BeamSensor, String)>>,
    /// Their readings: time, sensor id, ranges as stored.
    readings: Vec<(f64, u32, Vec<f32>)>,
}

/// Reads the bag at `path` as a Locus log, by `mapping` (`mapping_file`
/// names it in errors).
///
/// # Errors
/// The bag cannot be read ([`read`]); a mapped topic is not in it; a
/// mapped field is not in its messages or not a number; times that go
/// back on the velocity or truth topic; the sensor's frame not reachable
/// from `base_frame` in `/tf_static`.
pub fn to_locus(path: &Path, mapping: &Mapping, mapping_file: &str) -> Result<LocusLog, BagError> {
    let beam_topics: Vec<&str> = mapping
        .scans
        .iter()
        .chain(&mapping.ranges)
        .map(|b| b.topic.as_str())
        .collect();
    let mut g = Gathered {
        beams: vec![None; beam_topics.len()],
        ..Gathered::default()
    };
    // By channel id, once its first message is read.
    let mut by_channel: Vec<Option<ChannelState>> = Vec::new();
    let mut seen: HashSet<String> = HashSet::new();
    read(path, |channel, m| {
        let slot = usize::from(channel.id);
        if by_channel.len() <= slot {
            by_channel.resize_with(slot + 1, || None);
        }
        let state = by_channel[slot].get_or_insert_with(|| {
            if seen.insert(channel.topic.clone()) {
                g.topics.push(channel.topic.clone());
            }
            let topic = channel.topic.as_str();
            let wanted = topic == mapping.velocity.topic
                || mapping.landmarks.as_ref().is_some_and(|l| l.topic == topic)
                || mapping.truth.as_ref().is_some_and(|t| t.topic == topic)
                || beam_topics.contains(&topic)
                || topic == TF_STATIC;
            ChannelState {
                wanted,
                value: Value::Bool(false),
                fast: None,
            }
        });
        let ChannelState {
            wanted,
            value,
            fast,
        } = state;
        if !*wanted {
            return Ok(());
        }
        if let Some(Some(fast)) = fast {
            return fast.take(path, channel, m, mapping, &mut g);
        }
        channel.decode_into(path, m, value)?;
        let f = Fields {
            file: path,
            channel,
            record: m.record,
            value,
        };
        take(&f, m, mapping, &mut g)?;
        // The channel's first message went the full way: its later ones
        // may take the fast path.
        if fast.is_none() {
            let beam = beam_topics.contains(&channel.topic.as_str());
            *fast = Some(fast::Fast::compile(channel, mapping, beam));
        }
        Ok(())
    })?;
    let missing = |key: &str, topic: &str| BagError::Mapping {
        file: mapping_file.to_string(),
        key: key.to_string(),
        reason: format!(
            "topic {topic} is not in the bag {} (its topics: {})",
            path.display(),
            g.topics.join(", ")
        ),
    };
    if !seen.contains(&mapping.velocity.topic) {
        return Err(missing("velocity.topic", &mapping.velocity.topic));
    }
    if let Some(l) = &mapping.landmarks
        && !seen.contains(&l.topic)
    {
        return Err(missing("landmarks.topic", &l.topic));
    }
    if let Some(t) = &mapping.truth
        && !seen.contains(&t.topic)
    {
        return Err(missing("truth.topic", &t.topic));
    }
    for (i, b) in mapping.scans.iter().chain(&mapping.ranges).enumerate() {
        let key = if i < mapping.scans.len() {
            "scan"
        } else {
            "range"
        };
        if !seen.contains(&b.topic) {
            return Err(missing(&format!("{key}.topic"), &b.topic));
        }
    }
    let no_frame = |frame: &str| BagError::Mapping {
        file: mapping_file.to_string(),
        key: "base_frame".into(),
        reason: format!(
            "the sensor's frame {frame} is not below {} in {TF_STATIC} of {}",
            mapping.base_frame,
            path.display()
        ),
    };
    let mut beam_sensors = Vec::new();
    for (sensor, frame) in g.beams.iter().flatten() {
        let mut sensor = *sensor;
        if !frame.is_empty() && *frame != mapping.base_frame {
            let p = mount(&g.tf, &mapping.base_frame, frame).ok_or_else(|| no_frame(frame))?;
            sensor.mount = SensorMount {
                x: p[0],
                y: p[1],
                yaw: p[2],
            };
        }
        beam_sensors.push(sensor);
    }
    // A log's scans come in time order; a bag's topics interleave.
    g.readings.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut scans =
        Scans::with_capacity(g.readings.len(), g.readings.iter().map(|r| r.2.len()).sum());
    for (time, sensor, ranges) in &g.readings {
        scans.push(*time, *sensor, ranges);
    }
    let frame = mapping
        .landmarks
        .as_ref()
        .and_then(|l| l.frame.clone())
        .or(g.sensor_frame.clone());
    let sensor = match frame {
        Some(frame) if frame != mapping.base_frame && !frame.is_empty() => {
            let p = mount(&g.tf, &mapping.base_frame, &frame).ok_or_else(|| no_frame(&frame))?;
            Some(SensorMount {
                x: p[0],
                y: p[1],
                yaw: p[2],
            })
        }
        _ => None,
    };
    let truth = if g.truth_has_heading == Some(false) {
        Groundtruth::positions(g.truth)
    } else {
        Groundtruth::new(g.truth)
    };
    let truth = truth.ok_or_else(|| BagError::Mapping {
        file: mapping_file.to_string(),
        key: "truth.topic".into(),
        reason: "the truth's times go back".into(),
    })?;
    Ok(LocusLog {
        sensor,
        landmarks: mapping
            .landmark_map
            .iter()
            .map(|l| MapLandmark {
                id: l.id,
                x: l.x,
                y: l.y,
            })
            .collect(),
        odometry: g.odometry,
        measurements: g.measurements,
        truth,
        map: mapping.map.as_deref().and_then(MapPath::new),
        walls: mapping
            .walls
            .iter()
            .map(|w| Wall {
                x1: w.x1,
                y1: w.y1,
                x2: w.x2,
                y2: w.y2,
            })
            .collect(),
        beam_sensors,
        scans,
        ..LocusLog::default()
    })
}

/// The pose `[x, y, yaw]` of `frame` in `base`, composed through `tf`'s
/// parents (`child` in its parent's frame, by child).
fn mount(tf: &HashMap<String, (String, Pose)>, base: &str, frame: &str) -> Option<Pose> {
    let mut at = [0.0; 3];
    let mut child = frame;
    for _ in 0..32 {
        if child == base {
            return Some(at);
        }
        let (parent, p) = tf.get(child)?;
        at = compose(*p, at);
        child = parent;
    }
    None
}

/// Takes one decoded message into `g`.
fn take(
    f: &Fields<'_>,
    m: &RawMessage<'_>,
    mapping: &Mapping,
    g: &mut Gathered,
) -> Result<(), BagError> {
    let topic = f.channel.topic.as_str();
    let ty = f.channel.type_name.as_str();
    if topic == TF_STATIC {
        let list = f.at(f.value, "transforms")?;
        for (i, t) in list.as_list().unwrap_or_default().iter().enumerate() {
            let at = |p: &str| format!("transforms[{i}].{p}");
            let text = |p: &str| -> Result<String, BagError> {
                f.at(t, p)?
                    .as_str()
                    .map(str::to_string)
                    .ok_or_else(|| f.error(&at(p), "not a string"))
            };
            let q = |k: &str| f.number(t, &format!("transform.rotation.{k}"));
            g.tf.insert(
                text("child_frame_id")?,
                (
                    text("header.frame_id")?,
                    [
                        f.number(t, "transform.translation.x")?,
                        f.number(t, "transform.translation.y")?,
                        yaw([q("x")?, q("y")?, q("z")?, q("w")?]),
                    ],
                ),
            );
        }
    }
    if topic == mapping.velocity.topic {
        let v = &mapping.velocity;
        let usual = Defaults::velocity(ty);
        let linear = f.path(v.linear.as_deref(), usual.map(|u| u.0), "velocity.linear")?;
        let angular = f.path(v.angular.as_deref(), usual.map(|u| u.1), "velocity.angular")?;
        let time = f.time(v.stamp.as_deref(), m.log_time_ns)?;
        if g.odometry.last().is_some_and(|o| time < o.time) {
            return Err(f.error(v.stamp.as_deref().unwrap_or("time"), going_back(time)));
        }
        g.odometry.push(Odometry {
            time,
            v: f.number(f.value, linear)?,
            omega: f.number(f.value, angular)?,
        });
    }
    if let Some(l) = mapping.landmarks.as_ref().filter(|l| l.topic == topic) {
        let time = f.time(l.stamp.as_deref(), m.log_time_ns)?;
        if g.sensor_frame.is_none()
            && let Some(frame) = f.value.get("header.frame_id").and_then(Value::as_str)
        {
            g.sensor_frame = Some(frame.to_string());
        }
        let sightings: &[Value] = match &l.list {
            Some(p) => f
                .at(f.value, p)?
                .as_list()
                .ok_or_else(|| f.error(p, "not a list"))?,
            None => core::slice::from_ref(f.value),
        };
        for s in sightings {
            let id = landmark_id(f.number(s, &l.id)?).map_err(|r| f.error(&l.id, r))?;
            g.measurements.push(LandmarkMeasurement {
                time,
                id,
                range: f.number(s, &l.range)?,
                bearing: if l.bearing.is_empty() {
                    None
                } else {
                    Some(f.number(s, &l.bearing)?)
                },
            });
        }
    }
    let beam_topics = mapping.scans.iter().chain(&mapping.ranges).enumerate();
    for (i, b) in beam_topics.filter(|(_, b)| b.topic == topic) {
        let id = u32::try_from(i).unwrap_or(u32::MAX);
        let time = f.time(b.stamp.as_deref(), m.log_time_ns)?;
        let is_scan = i < mapping.scans.len();
        let (sensor, ranges) = if is_scan { scan(f, id)? } else { range(f, id)? };
        let frame = b
            .frame
            .clone()
            .or_else(|| {
                f.value
                    .get("header.frame_id")
                    .and_then(Value::as_str)
                    .map(str::to_string)
            })
            .unwrap_or_default();
        match &g.beams[i] {
            None => g.beams[i] = Some((sensor, frame)),
            Some((first, _)) => {
                if (first.count, first.angle_0, first.angle_step)
                    != (sensor.count, sensor.angle_0, sensor.angle_step)
                {
                    return Err(f.error(
                        if is_scan { "ranges" } else { "range" },
                        format!(
                            "{} beams from {} rad by {} rad, where the topic's first message had {} from {} by {}",
                            sensor.count, sensor.angle_0, sensor.angle_step, first.count, first.angle_0, first.angle_step
                        ),
                    ));
                }
            }
        }
        let sensor = g.beams[i].as_ref().map_or(sensor, |(s, _)| *s);
        let stored = ranges.iter().map(|&r| sensor.reading(r)).collect();
        g.readings.push((time, id, stored));
    }
    if let Some(t) = mapping.truth.as_ref().filter(|t| t.topic == topic) {
        let usual = Defaults::pose(ty);
        let position = f.path(t.position.as_deref(), usual.map(|u| u.0), "truth.position")?;
        let orientation = f.path(
            t.orientation.as_deref(),
            usual.map(|u| u.1),
            "truth.orientation",
        )?;
        let time = f.time(t.stamp.as_deref(), m.log_time_ns)?;
        let theta = if orientation.is_empty() {
            None
        } else {
            let o = f.at(f.value, orientation)?;
            let q = |k: &str| f.number_in(o, orientation, k);
            Some(yaw([q("x")?, q("y")?, q("z")?, q("w")?]))
        };
        g.truth_has_heading = Some(theta.is_some());
        let p = f.at(f.value, position)?;
        g.truth.push(TruthPose {
            time,
            x: f.number_in(p, position, "x")?,
            y: f.number_in(p, position, "y")?,
            theta: theta.unwrap_or(0.0),
        });
    }
    Ok(())
}

/// Why a velocity at `time` (s) is refused: it goes back.
fn going_back(time: f64) -> String {
    format!("velocity at {time} s is before the one before it")
}

/// A landmark id read as a number, or why it is none.
fn landmark_id(id: f64) -> Result<u32, String> {
    if !(id >= 0.0 && id <= f64::from(u32::MAX) && id.fract() == 0.0) {
        return Err(format!("{id} is not a landmark id"));
    }
    // A whole number in range.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    Ok(id as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mount_composes_static_transforms_up_to_the_base() {
        // base_link -> arm (1 m ahead, turned 90 deg) -> camera (0.5 m
        // ahead of the arm, turned 90 deg more): the camera is at (1, 0.5),
        // turned 180 deg.
        let mut tf = HashMap::new();
        let q = |yaw: f64| [0.0, 0.0, (yaw / 2.0).sin(), (yaw / 2.0).cos()];
        let half_pi = core::f64::consts::FRAC_PI_2;
        tf.insert(
            "arm".to_string(),
            ("base_link".to_string(), [1.0, 0.0, yaw(q(half_pi))]),
        );
        tf.insert(
            "camera".to_string(),
            ("arm".to_string(), [0.5, 0.0, yaw(q(half_pi))]),
        );
        let m = mount(&tf, "base_link", "camera").unwrap();
        assert!(
            (m[0] - 1.0).abs() < 1e-15 && (m[1] - 0.5).abs() < 1e-15,
            "{m:?}"
        );
        assert!((m[2].abs() - core::f64::consts::PI).abs() < 1e-15, "{m:?}");
        assert!(mount(&tf, "odom", "camera").is_none());
        // A loop in the transforms ends.
        tf.insert("base_link".to_string(), ("camera".to_string(), tf["arm"].1));
        assert!(mount(&tf, "world", "camera").is_none());
    }

    #[test]
    fn a_stamp_round_trips_a_time_to_the_bit() {
        for t in [1_248_444_188.086, 1_248_444_175.103, 0.5, 12.000_000_001] {
            let sec = f64::floor(t);
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            let ns = ((t - sec) * 1e9).round() as u64;
            #[allow(clippy::cast_possible_truncation)]
            let back = seconds(sec as i64, ns);
            assert_eq!(back.to_bits(), t.to_bits(), "{t}");
        }
        assert_eq!(log_seconds(1_500_000_000), 1.5);
    }
}
