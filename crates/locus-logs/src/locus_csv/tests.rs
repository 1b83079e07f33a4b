//! The Locus CSV reader and writer: round trips, every record, errors naming file, line and field.

use super::*;
use crate::Error;

fn p() -> &'static Path {
    Path::new("log.csv")
}

#[test]
fn parses_every_kind_and_round_trips() {
    let text = "# a log\n\nlandmark,6,1.5,-2\nstart,0,0,0,0.1\nodometry,0,0.1,0\n\
                odometry, 0.01 ,0.2,0.05\nmeasurement,0.02,6,2.5,0.3\n\
                measurement,0.015,6,2.4,0.31\ntruth,0,0,0,0\ntruth,0.02,0.003,0,0.001\n";
    let log = parse(text, p()).unwrap();
    assert_eq!(log.landmarks.len(), 1);
    assert_eq!(log.odometry[1].v, 0.2);
    assert_eq!(log.measurements[1].time, 0.015, "measurements may go back");
    assert_eq!(log.truth.poses().len(), 2);
    assert_eq!(log.start.unwrap().theta, 0.1);
    assert_eq!(log.sensor, None, "a version 1 log has no sensor line");
    assert_eq!(log.noise, NoiseRecords::default());
    assert_eq!(parse(&write(&log), p()).unwrap(), log);
}

#[test]
fn parses_sensor_and_noise_and_round_trips() {
    let text = "# Locus log v2\nnoise,sigma_bearing,0.03\nsensor, 0.1 ,-0.02,1.5707963267948966\n\
                landmark,6,1.5,-2\nnoise,q_v,1e-2\nodometry,0,0.1,0\nmeasurement,0.02,6,2.5,0.3\n";
    let log = parse(text, p()).unwrap();
    assert_eq!(
        log.sensor,
        Some(SensorMount {
            x: 0.1,
            y: -0.02,
            yaw: core::f64::consts::FRAC_PI_2
        })
    );
    assert_eq!(
        log.noise,
        NoiseRecords {
            q_v: Some(0.01),
            sigma_bearing: Some(0.03),
            ..NoiseRecords::default()
        }
    );
    let written = write(&log);
    assert!(written.starts_with("# Locus log v5"), "{written}");
    assert!(
        written.contains("\nsensor,0.1,-0.02,1.5707963267948966\n"),
        "{written}"
    );
    assert!(
        written.contains("\nnoise,q_v,0.01\nnoise,sigma_bearing,0.03\n"),
        "{written}"
    );
    assert_eq!(parse(&written, p()).unwrap(), log);

    // A centred sensor given explicitly is kept as given.
    let log = parse(
        "sensor,0,0,0\nnoise,q_omega,2\nnoise,sigma_range,0.2\n",
        p(),
    )
    .unwrap();
    assert_eq!(log.sensor, Some(SensorMount::default()));
    assert_eq!(parse(&write(&log), p()).unwrap(), log);
    assert!(!write(&LocusLog::default()).contains("sensor"));
}

/// The error of parsing `text`, as its message.
fn message(text: &str) -> String {
    parse(text, p()).unwrap_err().to_string()
}

#[test]
fn malformed_sensor_lines_name_the_line_and_field() {
    assert_eq!(
        message("landmark,6,1,2\nsensor,0.1,0\n"),
        "log.csv:2: field \"yaw\" (column 4): missing"
    );
    assert_eq!(
        message("sensor,0.1,inf,0\n"),
        "log.csv:1: field \"y\" (column 3): \"inf\" is not finite"
    );
    assert_eq!(
        message("sensor,NaN,0,0\n"),
        "log.csv:1: field \"x\" (column 2): \"NaN\" is not finite"
    );
    assert_eq!(
        message("sensor,0.1,0,0x1\n"),
        "log.csv:1: field \"yaw\" (column 4): \"0x1\" is not a number"
    );
    assert_eq!(
        message("sensor,0,0,0,0\n"),
        "log.csv:1: 5 fields, the format has 4"
    );
    assert_eq!(
        message("# a\nsensor,0.1,0,0\nlandmark,6,1,2\nsensor,0.1,0,0\n"),
        "log.csv:4: sensor line already appeared on line 2"
    );
    let e = parse("sensor,0,0,0\nsensor,0,0,0\n", p()).unwrap_err();
    assert!(
        matches!(
            e,
            Error::Record {
                line: 2,
                problem: RecordProblem::DuplicateRecord {
                    what: "sensor line",
                    first_line: 1
                },
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn malformed_noise_lines_name_the_line_and_field() {
    assert_eq!(
        message("noise,q_v\n"),
        "log.csv:1: field \"value\" (column 3): missing"
    );
    assert_eq!(
        message("noise\n"),
        "log.csv:1: field \"name\" (column 2): missing"
    );
    assert_eq!(
        message("\nnoise,sigma_rng,0.2\n"),
        "log.csv:2: field \"name\" (column 2): sigma_rng is out of range: \
         one of q_v, q_omega, sigma_range, sigma_bearing, sigma_beam"
    );
    assert_eq!(
        message("noise,q_omega,0\n"),
        "log.csv:1: field \"value\" (column 3): 0 is out of range: > 0"
    );
    assert_eq!(
        message("noise,sigma_range,-0.2\n"),
        "log.csv:1: field \"value\" (column 3): -0.2 is out of range: > 0"
    );
    assert_eq!(
        message("noise,sigma_bearing,inf\n"),
        "log.csv:1: field \"value\" (column 3): \"inf\" is not finite"
    );
    assert_eq!(
        message("noise,q_v,0.1,0.2\n"),
        "log.csv:1: 4 fields, the format has 3"
    );
    assert_eq!(
        message("noise,q_v,0.1\nnoise,q_omega,0.1\nnoise,q_v,0.2\n"),
        "log.csv:3: noise q_v already appeared on line 1"
    );
    assert_eq!(
        message("noise,sigma_bearing,0.1\n\nnoise,sigma_bearing,0.1\n"),
        "log.csv:3: noise sigma_bearing already appeared on line 1"
    );
}

#[test]
fn range_lines_and_truth_without_heading_read_and_round_trip() {
    let text = "# Locus log v3\nsensor,0.1,0,0\nlandmark,105,-0.02,-0.01\nodometry,0,0.1,0\n\
                range,0.13,105,2.955\nmeasurement,0.2,105,2.9,0.5\nrange,0.1,105,0\n\
                truth,0,1.65,2.22\ntruth,0.13,1.66,2.21\n";
    let (log, lines) = parse_with_lines(text, p()).unwrap();
    assert_eq!(lines.measurements, [5, 6, 7]);
    assert_eq!(
        log.measurements[0],
        LandmarkMeasurement {
            time: 0.13,
            id: 105,
            range: 2.955,
            bearing: None
        }
    );
    assert_eq!(log.measurements[1].bearing, Some(0.5));
    assert!(!log.truth.has_heading());
    assert!(log.truth.pose_at(0.05, 1.0).unwrap().theta.is_nan());
    assert!((log.truth.pose_at(0.13, 1.0).unwrap().x - 1.66).abs() < 1e-12);
    let written = write(&log);
    assert!(written.contains("\nrange,0.13,105,2.955\n"), "{written}");
    assert!(written.contains("\ntruth,0.13,1.66,2.21\n"), "{written}");
    assert_eq!(parse(&written, p()).unwrap(), log);
    // Truth with a heading stays so.
    let log = parse("truth,0,1,2,0.5\n", p()).unwrap();
    assert!(log.truth.has_heading());
    assert_eq!(log.truth.pose_at(0.0, 1.0).unwrap().theta, 0.5);
}

#[test]
fn malformed_range_and_truth_lines_name_the_line_and_field() {
    assert_eq!(
        message("range,1,105\n"),
        "log.csv:1: field \"range\" (column 4): missing"
    );
    assert_eq!(
        message("range,1,105,-0.5\n"),
        "log.csv:1: field \"range\" (column 4): -0.5 is out of range: >= 0"
    );
    assert_eq!(
        message("range,1,b105,0.5\n"),
        "log.csv:1: field \"id\" (column 3): \"b105\" is not a non-negative integer"
    );
    assert_eq!(
        message("range,1,105,0.5,0.1\n"),
        "log.csv:1: 5 fields, the format has 4"
    );
    assert_eq!(
        message("truth,0,1\n"),
        "log.csv:1: field \"y\" (column 4): missing"
    );
    assert_eq!(
        message("truth,0,1,2,x\n"),
        "log.csv:1: field \"theta\" (column 5): \"x\" is not a number"
    );
    assert_eq!(
        message("truth,0,1,2\n\ntruth,1,1,2,0.3\n"),
        "log.csv:3: truth lines give a heading or none, all alike: this one differs from line 1"
    );
    assert_eq!(
        message("truth,0,1,2,0\ntruth,1,1,2\n"),
        "log.csv:2: truth lines give a heading or none, all alike: this one differs from line 1"
    );
}

#[test]
fn a_second_start_line_names_the_first() {
    assert_eq!(
        message("start,0,0,0,0\nstart,1,0,0,0\n"),
        "log.csv:2: start line already appeared on line 1"
    );
}

#[test]
fn malformed_lines_name_the_line_and_field() {
    let e = parse("landmark,6,1,2\nodometry,0,0.1\n", p()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "log.csv:2: field \"omega\" (column 4): missing"
    );
    let e = parse("odometry,1,0,0\nodometry,0.5,0,0\n", p()).unwrap_err();
    assert!(e.to_string().starts_with("log.csv:2: time 0.5 s"), "{e}");
    let e = parse("\nwheel,1,2\n", p()).unwrap_err();
    assert!(
        e.to_string().starts_with("log.csv:2: field \"kind\""),
        "{e}"
    );
    let e = parse("measurement,1,6,-2,0\n", p()).unwrap_err();
    assert!(e.to_string().contains("\"range\" (column 4)"), "{e}");
    let e = parse("measurement,1,6,,0\n", p()).unwrap_err();
    assert!(e.to_string().contains("\"range\""), "{e}");
    let e = parse("landmark,6,1,2\nlandmark,6,3,4\n", p()).unwrap_err();
    assert!(e.to_string().contains("already appeared on line 1"), "{e}");
    let e = parse("truth,0,1,2,3,4\n", p()).unwrap_err();
    assert!(e.to_string().contains("6 fields, the format has 5"), "{e}");
}

/// A version 4 log: a map, two beam sensors (a lidar and an IR
/// sensor) and their scans.
const V4: &str = "# Locus log v4\nwall,0,-1,4,-1\nwall, 4 ,-1,4,3\nmap,maps/arena.yaml\n\
                  beam_sensor,0,0.1,0,0,0.05,8,-1.5707963267948966,0.7853981633974483,5\n\
                  beam_sensor,7,0,0.05,1.5707963267948966,0.1,0.8,0,0,1\n\
                  noise,sigma_beam,0.02\nodometry,0,0.1,0\n\
                  scan,0.1,0,1.5,max,-,2.25,8\nscan,0.1,7,0.5\nscan,0.2,7,0.01\n\
                  scan,0.3,0,9,0.04,1e-1,3.0000003,7.99\n";

#[test]
fn version_4_records_read_and_round_trip() {
    let (log, lines) = parse_with_lines(V4, p()).unwrap();
    assert_eq!(
        log.walls,
        [
            Wall {
                x1: 0.0,
                y1: -1.0,
                x2: 4.0,
                y2: -1.0
            },
            Wall {
                x1: 4.0,
                y1: -1.0,
                x2: 4.0,
                y2: 3.0
            }
        ]
    );
    assert_eq!(log.map.as_ref().unwrap().as_str(), "maps/arena.yaml");
    assert_eq!(lines.walls, [2, 3]);
    assert_eq!(lines.map, Some(4));
    assert_eq!(lines.beam_sensors, [5, 6]);
    assert_eq!(lines.scans, [9, 10, 11, 12]);
    assert_eq!(lines.noise[4], Some(7));
    assert_eq!(log.noise.sigma_beam, Some(0.02));
    let lidar = log.beam_sensor(0).unwrap();
    assert_eq!(lidar.count, 5);
    assert_eq!(lidar.mount.x, 0.1);
    assert!((lidar.angle(4) - core::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert_eq!(
        log.beam_sensor(7).unwrap().mount.yaw,
        core::f64::consts::FRAC_PI_2
    );
    assert!(log.beam_sensor(1).is_none());
    assert_eq!(log.scans.len(), 4);
    let first = log.scans.get(0).unwrap();
    assert_eq!((first.time, first.sensor), (0.1, 0));
    assert_eq!(first.ranges[0], 1.5);
    assert_eq!(first.ranges[1], NO_RETURN);
    assert!(first.ranges[2].is_nan());
    assert_eq!(
        first.ranges[4], NO_RETURN,
        "a reading at max_range is no return"
    );
    assert!(
        log.scans.get(2).unwrap().ranges[0].is_nan(),
        "a reading below min_range is missing"
    );
    let last = log.scans.get(3).unwrap();
    assert_eq!(last.ranges[0], NO_RETURN, "beyond max_range");
    assert!(last.ranges[1].is_nan(), "below min_range");
    assert_eq!(last.ranges[2], 0.1);
    assert_eq!(last.ranges[3], 3.000_000_3_f32);
    assert_eq!(last.ranges[4], 7.99_f32);
    let written = write(&log);
    assert!(written.contains("\nwall,4,-1,4,3\n"), "{written}");
    assert!(written.contains("\nmap,maps/arena.yaml\n"), "{written}");
    assert!(
        written.contains("\nbeam_sensor,7,0,0.05,1.5707963267948966,0.1,0.8,0,0,1\n"),
        "{written}"
    );
    assert!(
        written.contains("\nscan,0.1,0,1.5,max,-,2.25,max\n"),
        "{written}"
    );
    assert!(
        written.contains("\nscan,0.3,0,max,-,0.1,3.0000002,7.99\n"),
        "{written}"
    );
    assert!(written.contains("\nnoise,sigma_beam,0.02\n"), "{written}");
    assert_eq!(parse(&written, p()).unwrap(), log);
    assert_eq!(write(&parse(&written, p()).unwrap()), written);
}

#[test]
fn malformed_version_4_lines_name_the_line_and_field() {
    let sensor = "beam_sensor,0,0,0,0,0.1,4,0,0.1,3\n";
    let with = |line: &str| message(&format!("{sensor}{line}"));
    assert_eq!(
        with("scan,1,0,1,2\n"),
        "log.csv:2: field \"range\" (column 6): 2 ranges, beam sensor 0 has 3 beams"
    );
    assert_eq!(
        with("scan,1,0,1,2,3,4,5\n"),
        "log.csv:2: field \"range\" (column 7): 5 ranges, beam sensor 0 has 3 beams"
    );
    assert_eq!(
        with("scan,1,0,1,-2,3\n"),
        "log.csv:2: field \"range\" (column 5): -2 is out of range: >= 0, max or -"
    );
    assert_eq!(
        with("scan,1,0,1,inf,3\n"),
        "log.csv:2: field \"range\" (column 5): \"inf\" is not finite"
    );
    assert_eq!(
        with("scan,1,0,1,,3\n"),
        "log.csv:2: field \"range\" (column 5): \"\" is not a number"
    );
    assert_eq!(
        with("scan,1,3,1,2,3\n"),
        "log.csv:2: field \"id\" (column 3): 3 is out of range: \
         the id of a beam_sensor line above this one"
    );
    assert_eq!(
        message("scan,1,0,1,2,3\nbeam_sensor,0,0,0,0,0.1,4,0,0.1,3\n"),
        "log.csv:1: field \"id\" (column 3): 0 is out of range: \
         the id of a beam_sensor line above this one"
    );
    assert!(
        with("scan,2,0,1,2,3\nscan,1,0,1,2,3\n")
            .starts_with("log.csv:3: time 1 s is earlier than the previous record's 2 s"),
    );
    assert_eq!(
        with("beam_sensor,0,0,0,0,0,1,0,0,1\n"),
        "log.csv:2: beam sensor id 0 already appeared on line 1"
    );
    for (line, field, column, why) in [
        (
            "beam_sensor,0,11,0,0,0,1,0,0,1",
            "x",
            3,
            "11 is out of range: within +-10 m of the robot's centre",
        ),
        (
            "beam_sensor,0,0,0,7,0,1,0,0,1",
            "yaw",
            5,
            "7 is out of range: within one turn, +-2 pi rad",
        ),
        (
            "beam_sensor,0,0,0,0,-1,1,0,0,1",
            "min_range",
            6,
            "-1 is out of range: >= 0 and < 1e5 m",
        ),
        (
            "beam_sensor,0,0,0,0,2,1,0,0,1",
            "max_range",
            7,
            "1 is out of range: > min_range and <= 1e5 m",
        ),
        (
            "beam_sensor,0,0,0,0,0,1e6,0,0,1",
            "max_range",
            7,
            "1000000 is out of range: > min_range and <= 1e5 m",
        ),
        (
            "beam_sensor,0,0,0,0,0,1,0,0,0",
            "count",
            10,
            "0 is out of range: 1 to 100000 beams",
        ),
        (
            "beam_sensor,0,0,0,0,0,1,0,0,100001",
            "count",
            10,
            "100001 is out of range: 1 to 100000 beams",
        ),
        (
            "beam_sensor,0,0,0,0,0,1,0,0,-3",
            "count",
            10,
            "\"-3\" is not a non-negative integer",
        ),
        (
            "beam_sensor,0,0,0,0,0,1,0,0.1,100",
            "angle_step",
            10,
            "0.1 is out of range: beams within one turn: |angle_step| (count - 1) <= 2 pi rad",
        ),
        (
            "wall,0,0,1e6,0",
            "x2",
            4,
            "1000000 is out of range: within +-1e5 m",
        ),
        (
            "wall,1,2,1,2",
            "y2",
            5,
            "2 is out of range: a second end apart from the first (a wall of non-zero length)",
        ),
        ("map,", "path", 2, "\"\" is out of range: a non-empty path"),
        ("noise,sigma_beam,0", "value", 3, "0 is out of range: > 0"),
    ] {
        assert_eq!(
            message(&format!("{line}\n")),
            format!("log.csv:1: field \"{field}\" (column {column}): {why}"),
            "{line}"
        );
    }
    assert_eq!(
        message("map,a.yaml\nmap,b.yaml\n"),
        "log.csv:2: map line already appeared on line 1"
    );
    assert_eq!(
        message("map,a,b.yaml\n"),
        "log.csv:1: 3 fields, the format has 2"
    );
    assert_eq!(
        message("wall,0,0,1,1,2\n"),
        "log.csv:1: 6 fields, the format has 5"
    );
    assert_eq!(
        message("beam_sensor,0,0,0,0,0,1,0,0,1,9\n"),
        "log.csv:1: 11 fields, the format has 10"
    );
}

#[test]
fn a_lidar_scan_of_1081_beams_reads_within_the_line_bound() {
    let mut text = String::from(
        "beam_sensor,3,0,0,0,0.02,30,-2.356194490192345,0.004363323129985824,1081\nscan,5",
    );
    text.push_str(",3");
    for k in 0..1081 {
        text.push_str(if k % 100 == 0 { ",max" } else { ",12.345678" });
    }
    text.push('\n');
    let log = parse(&text, p()).unwrap();
    assert_eq!(log.scans.ranges_len(), 1081);
    assert!(text.len() < crate::MAX_LINE);
    assert_eq!(parse(&write(&log), p()).unwrap(), log);
}

#[test]
fn a_missing_file_is_named() {
    let e = read(Path::new("/nonexistent/robot.csv")).unwrap_err();
    assert_eq!(
        e.to_string(),
        "/nonexistent/robot.csv: not found (nor /nonexistent/robot.csv.xz)"
    );
}

/// Paper 001's two IR sensors, s1 ahead of s2, both looking right, and a
/// lidar.
const SENSORS_V5: &str = "beam_sensor,0,0.05,0,-1.5707963267948966,0.04,0.3,0,0,1\n\
                          beam_sensor,1,-0.05,0,-1.5707963267948966,0.04,0.3,0,0,1\n\
                          beam_sensor,2,0,0,0,0.1,8,-1,0.5,5\n\
                          beam_sensor,3,-0.05,0,1.5707963267948966,0.04,0.3,0,0,1\n\
                          beam_sensor,4,-0.05,0.02,-1.5707963267948966,0.04,0.3,0,0,1\n";

#[test]
fn an_ir_pair_reads_and_round_trips() {
    let text = format!("{SENSORS_V5}ir_pair,0,1,0.4\nscan,0.1,0,0.12\nscan,0.1,1,max\n");
    let (log, lines) = parse_with_lines(&text, p()).unwrap();
    assert_eq!(
        log.ir_pairs,
        [IrPairRecord {
            front: 0,
            rear: 1,
            association_range: 0.4
        }]
    );
    assert_eq!(lines.ir_pairs, [6]);
    let written = write(&log);
    assert!(written.starts_with("# Locus log v5"), "{written}");
    assert!(written.contains("\nir_pair,0,1,0.4\n"), "{written}");
    assert_eq!(parse(&written, p()).unwrap(), log);
}

#[test]
fn malformed_ir_pair_lines_name_the_line_and_field() {
    let with = |line: &str| message(&format!("{SENSORS_V5}{line}"));
    for (line, field, column, why) in [
        (
            "ir_pair,9,1,0.4",
            "front",
            2,
            "9 is out of range: the id of a beam_sensor line above this one",
        ),
        (
            "ir_pair,2,1,0.4",
            "front",
            2,
            "2 is out of range: a one-beam sensor (count 1)",
        ),
        (
            "ir_pair,0,3,0.4",
            "rear",
            3,
            "3 is out of range: a sensor looking to the robot's right (yaw -pi/2, angle_0 0), \
             as paper 001's pair",
        ),
        (
            "ir_pair,0,0,0.4",
            "rear",
            3,
            "0 is out of range: a sensor other than the front one",
        ),
        (
            "ir_pair,1,0,0.4",
            "rear",
            3,
            "0 is out of range: a sensor behind the front one (smaller x)",
        ),
        (
            "ir_pair,0,4,0.4",
            "rear",
            3,
            "4 is out of range: a sensor at the front one's lateral offset y",
        ),
        (
            "ir_pair,0,1,0",
            "association_range",
            4,
            "0 is out of range: > 0 and <= 1e5 m",
        ),
    ] {
        assert_eq!(
            with(&format!("{line}\n")),
            format!("log.csv:6: field \"{field}\" (column {column}): {why}"),
            "{line}"
        );
    }
    assert_eq!(
        with("ir_pair,0,1,0.4\nir_pair,1,4,0.4\n"),
        "log.csv:7: IR pair sensor id 1 already appeared on line 6"
    );
    assert_eq!(
        with("ir_pair,0,1,0.4,5\n"),
        "log.csv:6: 5 fields, the format has 4"
    );
}
