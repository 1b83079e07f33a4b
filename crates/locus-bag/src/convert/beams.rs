//! Scan and range messages (`sensor_msgs/msg/LaserScan`, `Range`) as
//! Locus beam sensors and their readings, checked.

use locus_logs::BeamSensor;
use locus_logs::beam_sensor::{MAX_BEAMS, MAX_RANGE_LIMIT};
use locus_logs::sensor::SensorMount;

use super::Fields;
use crate::error::BagError;

/// The limits `[min, max]` of a range sensor's message, checked.
fn limits(f: &Fields<'_>, min: &str, max: &str) -> Result<(f64, f64), BagError> {
    let (lo, hi) = (f.number(f.value, min)?, f.number(f.value, max)?);
    if !(lo >= 0.0 && hi > lo && hi <= MAX_RANGE_LIMIT) {
        return Err(f.error(
            max,
            format!("range limits [{lo}, {hi}] m: need 0 <= min < max <= {MAX_RANGE_LIMIT}"),
        ));
    }
    Ok((lo, hi))
}

/// Beam sensor `id` at the robot's centre (until its mount is known):
/// `count` beams from `angle_0` by `angle_step` (rad), ranges within
/// `limits` (m).
fn centred(id: u32, limits: (f64, f64), angle_0: f64, angle_step: f64, count: u32) -> BeamSensor {
    BeamSensor {
        id,
        mount: SensorMount {
            x: 0.0,
            y: 0.0,
            yaw: 0.0,
        },
        min_range: limits.0,
        max_range: limits.1,
        angle_0,
        angle_step,
        count,
    }
}

/// A `sensor_msgs/msg/LaserScan` as beam sensor `id` (at the robot's
/// centre until its mount is known) and its ranges.
pub(super) fn scan(f: &Fields<'_>, id: u32) -> Result<(BeamSensor, Vec<f64>), BagError> {
    let (min_range, max_range) = limits(f, "range_min", "range_max")?;
    let ranges = f
        .at(f.value, "ranges")?
        .as_list()
        .ok_or_else(|| f.error("ranges", "not a list"))?;
    let count = u32::try_from(ranges.len())
        .ok()
        .filter(|&n| (1..=MAX_BEAMS).contains(&n))
        .ok_or_else(|| {
            f.error(
                "ranges",
                format!("{} ranges: need 1 to {MAX_BEAMS}", ranges.len()),
            )
        })?;
    let sensor = centred(
        id,
        (min_range, max_range),
        f.number(f.value, "angle_min")?,
        f.number(f.value, "angle_increment")?,
        count,
    );
    let values = ranges
        .iter()
        .map(|r| r.as_f64().ok_or_else(|| f.error("ranges", "not numbers")))
        .collect::<Result<_, _>>()?;
    Ok((sensor, values))
}

/// A `sensor_msgs/msg/Range` as one-beam sensor `id` and its range.
pub(super) fn range(f: &Fields<'_>, id: u32) -> Result<(BeamSensor, Vec<f64>), BagError> {
    let (min_range, max_range) = limits(f, "min_range", "max_range")?;
    let sensor = centred(id, (min_range, max_range), 0.0, 0.0, 1);
    Ok((sensor, vec![f.number(f.value, "range")?]))
}
