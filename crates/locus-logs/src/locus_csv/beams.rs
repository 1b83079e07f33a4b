//! The version-4 records of walls and beams: `wall`, `beam_sensor` and the
//! ranges of a `scan`, and version 5's `ir_pair`, each checked with its
//! field named.

use super::*;

/// The next field as a finite number within `+-limit`.
fn within(
    f: &mut Fields<'_>,
    field: &'static str,
    limit: f64,
    expected: &'static str,
) -> Result<f64> {
    f.bounded(field, |v| v.abs() <= limit, expected)
}

/// The fields of a `wall` line after its kind.
pub(super) fn wall(f: &mut Fields<'_>) -> Result<Wall> {
    const WITHIN: &str = "within +-1e5 m";
    let w = Wall {
        x1: within(f, "x1", MAX_COORDINATE, WITHIN)?,
        y1: within(f, "y1", MAX_COORDINATE, WITHIN)?,
        x2: within(f, "x2", MAX_COORDINATE, WITHIN)?,
        y2: within(f, "y2", MAX_COORDINATE, WITHIN)?,
    };
    if w.x1 == w.x2 && w.y1 == w.y2 {
        return Err(f.field_error(
            "y2",
            FieldProblem::OutOfRange {
                value: w.y2.to_string(),
                expected: "a second end apart from the first (a wall of non-zero length)",
            },
        ));
    }
    Ok(w)
}

/// The fields of a `beam_sensor` line after its kind.
pub(super) fn beam_sensor(f: &mut Fields<'_>) -> Result<BeamSensor> {
    const OFFSET: &str = "within +-10 m of the robot's centre";
    const ANGLE: &str = "within one turn, +-2 pi rad";
    let id = f.u32("id")?;
    let mount = SensorMount {
        x: within(f, "x", MAX_MOUNT_OFFSET, OFFSET)?,
        y: within(f, "y", MAX_MOUNT_OFFSET, OFFSET)?,
        yaw: within(f, "yaw", TURN, ANGLE)?,
    };
    let min_range = f.bounded(
        "min_range",
        |v| (0.0..MAX_RANGE_LIMIT).contains(&v),
        ">= 0 and < 1e5 m",
    )?;
    let max_range = f.bounded(
        "max_range",
        |v| v > min_range && v <= MAX_RANGE_LIMIT,
        "> min_range and <= 1e5 m",
    )?;
    let angle_0 = within(f, "angle_0", TURN, ANGLE)?;
    let angle_step = within(f, "angle_step", TURN, ANGLE)?;
    let text = f.next_text("count")?;
    let count = match text.parse::<u32>() {
        Ok(n) if (1..=MAX_BEAMS).contains(&n) => n,
        Ok(n) => {
            return Err(f.field_error(
                "count",
                FieldProblem::OutOfRange {
                    value: n.to_string(),
                    expected: "1 to 100000 beams",
                },
            ));
        }
        Err(_) => {
            return Err(f.field_error("count", FieldProblem::NotAnInteger(excerpt(text))));
        }
    };
    if angle_step.abs() * f64::from(count - 1) > TURN * (1.0 + 1e-12) {
        // The column of the step, two fields back.
        return Err(f.field_error(
            "angle_step",
            FieldProblem::OutOfRange {
                value: angle_step.to_string(),
                expected: "beams within one turn: |angle_step| (count - 1) <= 2 pi rad",
            },
        ));
    }
    Ok(BeamSensor {
        id,
        mount,
        min_range,
        max_range,
        angle_0,
        angle_step,
        count,
    })
}

/// Reads the ranges of a `scan` line (after its id) into `scans`: exactly
/// `sensor.count` of them, each a number `>= 0`, `max` or `-`, stored as
/// [`BeamSensor::classify`] says.
pub(super) fn scan_ranges(
    f: &mut Fields<'_>,
    sensor: &BeamSensor,
    scans: &mut Scans,
) -> Result<()> {
    let count = |found| FieldProblem::BeamCount {
        found,
        expected: sensor.count,
        sensor: sensor.id,
    };
    for k in 0..sensor.count as usize {
        let Some(text) = f.optional_text() else {
            return Err(f.field_error("range", count(k)));
        };
        let stored = match text {
            "max" => NO_RETURN,
            "-" => MISSING,
            _ => {
                // Checked as f64 (finite, >= 0), stored as the f32 nearest
                // the text (not rounded twice).
                let v = match text.parse::<f64>() {
                    Ok(v) if v.is_finite() => v,
                    Ok(_) => {
                        return Err(f.field_error("range", FieldProblem::NotFinite(excerpt(text))));
                    }
                    Err(_) => {
                        return Err(f.field_error("range", FieldProblem::NotANumber(excerpt(text))));
                    }
                };
                if v < 0.0 {
                    return Err(f.field_error(
                        "range",
                        FieldProblem::OutOfRange {
                            value: v.to_string(),
                            expected: ">= 0, max or -",
                        },
                    ));
                }
                sensor.classify(text.parse::<f32>().unwrap_or(NO_RETURN))
            }
        };
        scans.push_range(stored);
    }
    if f.optional_text().is_some() {
        let found = sensor.count as usize + 1 + f.count_rest();
        return Err(f.field_error("range", count(found)));
    }
    Ok(())
}

/// The fields of an `ir_pair` line after its kind: two one-beam sensors
/// declared above it, neither in another pair, that can form paper 001's
/// pair ([`IrPairRecord::sensor_problem`], [`IrPairRecord::pair_problem`]),
/// and the association range.
pub(super) fn ir_pair(
    f: &mut Fields<'_>,
    sensors: &[BeamSensor],
    pairs: &[IrPairRecord],
    pair_lines: &[usize],
) -> Result<IrPairRecord> {
    let out_of_range = |f: &Fields<'_>, field, id: u32, expected| {
        f.field_error(
            field,
            FieldProblem::OutOfRange {
                value: id.to_string(),
                expected,
            },
        )
    };
    let sensor = |f: &mut Fields<'_>, field: &'static str| -> Result<BeamSensor> {
        let id = f.u32(field)?;
        if let Some(i) = pairs.iter().position(|p| p.front == id || p.rear == id) {
            return Err(f.record_error(RecordProblem::Duplicate {
                what: "IR pair sensor id",
                value: id,
                first_line: pair_lines[i],
            }));
        }
        let Some(s) = sensors.iter().find(|b| b.id == id) else {
            return Err(out_of_range(
                f,
                field,
                id,
                "the id of a beam_sensor line above this one",
            ));
        };
        match IrPairRecord::sensor_problem(s) {
            Some(problem) => Err(out_of_range(f, field, id, problem.expected())),
            None => Ok(*s),
        }
    };
    let front = sensor(f, "front")?;
    let rear = sensor(f, "rear")?;
    if let Some(problem) = IrPairRecord::pair_problem(&front, &rear) {
        return Err(out_of_range(f, "rear", rear.id, problem.expected()));
    }
    let association_range = f.bounded(
        "association_range",
        |v| v > 0.0 && v <= MAX_RANGE_LIMIT,
        "> 0 and <= 1e5 m",
    )?;
    Ok(IrPairRecord {
        front: front.id,
        rear: rear.id,
        association_range,
    })
}
