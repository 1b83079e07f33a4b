//! The Locus CSV writer (version 5).

use super::*;

/// Writes a log in this format (the inverse of [`parse`]; numbers as
/// Rust's `Display` writes them, the shortest form that reads back to the
/// same value, so `parse(write(log)) == log`). Scan ranges are written as
/// the shortest text that reads back to the same `f32`, `max` for
/// [`NO_RETURN`] and `-` for any other non-finite value; the round trip
/// holds for a log whose scans name its beam sensors, with as many ranges
/// as beams, each [`NO_RETURN`], [`MISSING`] or within the sensor's limits
/// (what [`parse`] gives), and whose map path a [`MapPath`] accepted.
#[must_use]
pub fn write(log: &LocusLog) -> String {
    use core::fmt::Write as _;
    let lines = 1 + log.landmarks.len() + log.truth.poses().len() + log.odometry.len();
    let mut s = String::with_capacity(64 * (lines + log.measurements.len()));
    s.reserve(12 * log.scans.ranges_len() + 48 * log.scans.len());
    s.push_str("# Locus log v5 (docs/log-format.md); SI units\n");
    if let Some(m) = log.sensor {
        record(&mut s, "sensor", &[m.x, m.y, m.yaw]);
    }
    for (name, value) in log.noise.iter() {
        s.push_str("noise,");
        s.push_str(name);
        record(&mut s, "", &[value]);
    }
    for l in &log.landmarks {
        let _ = write!(s, "landmark,{}", l.id);
        record(&mut s, "", &[l.x, l.y]);
    }
    for w in &log.walls {
        record(&mut s, "wall", &[w.x1, w.y1, w.x2, w.y2]);
    }
    if let Some(m) = &log.map {
        s.push_str("map,");
        s.push_str(m.as_str());
        s.push('\n');
    }
    for b in &log.beam_sensors {
        let _ = write!(s, "beam_sensor,{}", b.id);
        let m = b.mount;
        let values = [
            m.x,
            m.y,
            m.yaw,
            b.min_range,
            b.max_range,
            b.angle_0,
            b.angle_step,
        ];
        for v in values {
            s.push(',');
            push_f64(&mut s, v);
        }
        let _ = writeln!(s, ",{}", b.count);
    }
    for p in &log.ir_pairs {
        let _ = write!(s, "ir_pair,{},{}", p.front, p.rear);
        record(&mut s, "", &[p.association_range]);
    }
    if let Some(p) = log.start {
        record(&mut s, "start", &[p.time, p.x, p.y, p.theta]);
    }
    let heading = log.truth.has_heading();
    for p in log.truth.poses() {
        if heading {
            record(&mut s, "truth", &[p.time, p.x, p.y, p.theta]);
        } else {
            record(&mut s, "truth", &[p.time, p.x, p.y]);
        }
    }
    for o in &log.odometry {
        record(&mut s, "odometry", &[o.time, o.v, o.omega]);
    }
    for m in &log.measurements {
        s.push_str(if m.bearing.is_some() {
            "measurement,"
        } else {
            "range,"
        });
        push_f64(&mut s, m.time);
        let _ = write!(s, ",{}", m.id);
        match m.bearing {
            Some(b) => record(&mut s, "", &[m.range, b]),
            None => record(&mut s, "", &[m.range]),
        }
    }
    let mut buffer = ryu::Buffer::new();
    for scan in log.scans.iter() {
        s.push_str("scan,");
        push_f64(&mut s, scan.time);
        let _ = write!(s, ",{}", scan.sensor);
        for r in scan.ranges {
            s.push(',');
            if *r == NO_RETURN {
                s.push_str("max");
            } else if r.is_finite() {
                let text = buffer.format_finite(*r);
                s.push_str(text.strip_suffix(".0").unwrap_or(text));
            } else {
                s.push('-');
            }
        }
        s.push('\n');
    }
    s
}

/// Appends `head`, then `,value` for each value, then a line end.
fn record(s: &mut String, head: &str, values: &[f64]) {
    s.push_str(head);
    for v in values {
        s.push(',');
        push_f64(s, *v);
    }
    s.push('\n');
}
