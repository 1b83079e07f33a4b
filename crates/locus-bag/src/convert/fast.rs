//! The fast path of [`super::to_locus`]: a topic that is only the velocity,
//! the truth, or one sighting per message, whose mapped fields are numbers
//! at fixed paths, is read through a [`Projection`] of those fields, not
//! the decoded [`crate::Value`] tree. Its first message has gone the full
//! way (every error of the mapping shows there); the figures are the same
//! to the bit, as `crates/locus/tests/bag.rs` checks against the CSV.

use locus_logs::locus_csv::LandmarkMeasurement;
use locus_logs::mrclam::{Odometry, TruthPose};

use super::{Gathered, field_error, going_back, landmark_id, log_seconds, seconds, yaw};
use crate::bag::{Channel, RawMessage};
use crate::error::BagError;
use crate::mapping::{Defaults, Mapping};
use crate::msgdef::{Definitions, Primitive};
use crate::project::Projection;
use std::path::Path;

/// What the topic gives.
enum Role {
    /// Speed and turn rate: slots 0 and 1.
    Velocity,
    /// Position x, y: slots 0, 1; the orientation's x, y, z, w: 2 to 5 if
    /// there is one.
    Truth { heading: bool },
    /// Id and range: 0, 1; bearing 2 if there is one.
    Sighting { bearing: bool },
}

/// A topic read through a projection.
pub(super) struct Fast {
    role: Role,
    projection: Projection,
    /// The slot of the stamp's `sec` (`nanosec` follows it), or none for
    /// the log time.
    stamp: Option<usize>,
    /// Scratch for the slots.
    slots: Vec<f64>,
}

/// The stamp's paths for the `stamp` the mapping gives (as
/// `Fields::time` reads it): `Ok(None)` for the log time, `Err` if the
/// fast path cannot read it.
fn stamp_path(defs: &Definitions, given: Option<&str>) -> Result<Option<String>, ()> {
    match given {
        Some("") => Ok(None),
        Some(p) => Ok(Some(p.to_string())),
        None => {
            let header = Projection::compile(defs, &["header.stamp.sec", "header.stamp.nanosec"]);
            let has_header = defs.root.field("header").is_some();
            match (header, has_header) {
                (Some(_), _) => Ok(Some("header.stamp".into())),
                (None, false) => Ok(None),
                (None, true) => Err(()),
            }
        }
    }
}

impl Fast {
    /// The fast path of `channel` under `mapping`, if it has one.
    pub(super) fn compile(channel: &Channel, mapping: &Mapping, beam: bool) -> Option<Self> {
        let defs = channel.definitions.as_ref().ok()?;
        let topic = channel.topic.as_str();
        let ty = channel.type_name.as_str();
        let velocity = mapping.velocity.topic == topic;
        let truth = mapping.truth.as_ref().filter(|t| t.topic == topic);
        let sighting = mapping.landmarks.as_ref().filter(|l| l.topic == topic);
        let roles =
            usize::from(velocity) + usize::from(truth.is_some()) + usize::from(sighting.is_some());
        if roles != 1 || beam || topic == super::TF_STATIC {
            return None;
        }
        let (role, mut paths, stamp): (Role, Vec<String>, Option<&str>) = if velocity {
            let v = &mapping.velocity;
            let usual = Defaults::velocity(ty);
            let linear = v.linear.as_deref().or(usual.map(|u| u.0))?;
            let angular = v.angular.as_deref().or(usual.map(|u| u.1))?;
            (
                Role::Velocity,
                vec![linear.into(), angular.into()],
                v.stamp.as_deref(),
            )
        } else if let Some(t) = truth {
            let usual = Defaults::pose(ty);
            let position = t.position.as_deref().or(usual.map(|u| u.0))?;
            let orientation = t.orientation.as_deref().or(usual.map(|u| u.1))?;
            let mut paths = vec![format!("{position}.x"), format!("{position}.y")];
            let heading = !orientation.is_empty();
            if heading {
                paths.extend(["x", "y", "z", "w"].map(|k| format!("{orientation}.{k}")));
            }
            (Role::Truth { heading }, paths, t.stamp.as_deref())
        } else {
            let l = sighting?;
            if l.list.is_some() {
                return None;
            }
            let mut paths = vec![l.id.clone(), l.range.clone()];
            let bearing = !l.bearing.is_empty();
            if bearing {
                paths.push(l.bearing.clone());
            }
            (Role::Sighting { bearing }, paths, l.stamp.as_deref())
        };
        let stamp = stamp_path(defs, stamp).ok()?.map(|p| {
            paths.push(format!("{p}.sec"));
            paths.push(format!("{p}.nanosec"));
            paths.len() - 2
        });
        let refs: Vec<&str> = paths.iter().map(String::as_str).collect();
        let projection = Projection::compile(defs, &refs)?;
        // A stamp is a builtin_interfaces/Time: int32 sec, uint32 nanosec.
        if let Some(s) = stamp
            && (projection.kind(s) != Some(Primitive::I32)
                || projection.kind(s + 1) != Some(Primitive::U32))
        {
            return None;
        }
        Some(Self {
            role,
            projection,
            stamp,
            slots: vec![0.0; paths.len()],
        })
    }

    /// Takes one message of the channel into `g`, as `super::take` would.
    pub(super) fn take(
        &mut self,
        file: &Path,
        channel: &Channel,
        m: &RawMessage<'_>,
        mapping: &Mapping,
        g: &mut Gathered,
    ) -> Result<(), BagError> {
        let (projection, slots) = (&self.projection, &mut self.slots);
        channel.with_definitions(file, m, |defs, data| projection.read(defs, data, slots))?;
        let s = &self.slots;
        // The stamp's integers, exact in f64, as `seconds` takes them.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let time = self.stamp.map_or_else(
            || log_seconds(m.log_time_ns),
            |i| seconds(s[i] as i64, s[i + 1] as u64),
        );
        match self.role {
            Role::Velocity => {
                if g.odometry.last().is_some_and(|o| time < o.time) {
                    let field = mapping.velocity.stamp.as_deref().unwrap_or("time");
                    return Err(field_error(
                        file,
                        channel,
                        m.record,
                        field,
                        going_back(time),
                    ));
                }
                g.odometry.push(Odometry {
                    time,
                    v: s[0],
                    omega: s[1],
                });
            }
            Role::Truth { heading } => {
                g.truth_has_heading = Some(heading);
                g.truth.push(TruthPose {
                    time,
                    x: s[0],
                    y: s[1],
                    theta: if heading {
                        yaw([s[2], s[3], s[4], s[5]])
                    } else {
                        0.0
                    },
                });
            }
            Role::Sighting { bearing } => {
                let l = mapping.landmarks.as_ref();
                let id = landmark_id(s[0]).map_err(|r| {
                    let field = l.map_or("id", |l| l.id.as_str());
                    field_error(file, channel, m.record, field, r)
                })?;
                g.measurements.push(LandmarkMeasurement {
                    time,
                    id,
                    range: s[1],
                    bearing: bearing.then(|| s[2]),
                });
            }
        }
        Ok(())
    }
}
