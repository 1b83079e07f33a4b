//! The MRCLAM readers on small hand-written files: well-formed input, every
//! kind of malformed input (the error must name file, line, column and
//! field), xz and plain files, barcode mapping.

use std::fs;
use std::path::{Path, PathBuf};

use locus_logs::mrclam::{
    self, Barcodes, Dataset, Measurement, Sightings, Target, parse_barcodes, parse_groundtruth,
    parse_landmarks, parse_measurements, parse_odometry,
};
use locus_logs::{Error, FieldProblem, RecordProblem};

const HEADER: &str = "# UTIAS Multi-Robot Cooperative Localization and Mapping Dataset\n\
# produced by someone\n\
# Measurement Data Fomat:\n\
# Time [s]    Subject #    range [m]    bearing [rad]\n";

fn src() -> &'static Path {
    Path::new("Robot9_Measurement.dat")
}

/// A fresh directory under the target's temporary directory.
fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("mrclam_format")
        .join(name);
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).unwrap();
    dir
}

fn xz(text: &str) -> Vec<u8> {
    let mut out = Vec::new();
    lzma_rs::xz_compress(&mut text.as_bytes(), &mut out).unwrap();
    out
}

/// The (line, column, field, problem) of a field error, or panics.
fn field_error(e: Error) -> (usize, usize, &'static str, FieldProblem) {
    match e {
        Error::Field {
            line,
            column,
            field,
            problem,
            ..
        } => (line, column, field, problem),
        other => panic!("expected a field error, got {other:?}"),
    }
}

fn record_error(e: Error) -> (usize, RecordProblem) {
    match e {
        Error::Record { line, problem, .. } => (line, problem),
        other => panic!("expected a record error, got {other:?}"),
    }
}

#[test]
fn well_formed_measurements_parse() {
    let text = format!(
        "{HEADER}1248444200.196 \t  16 \t  5.182 \t -0.001\n\n1248444200.196 41 3.267 0.259\r\n"
    );
    let m = parse_measurements(&text, src()).unwrap();
    assert_eq!(
        m,
        vec![
            Measurement {
                time: 1248444200.196,
                barcode: 16,
                range: 5.182,
                bearing: -0.001
            },
            Measurement {
                time: 1248444200.196,
                barcode: 41,
                range: 3.267,
                bearing: 0.259
            },
        ]
    );
}

#[test]
fn a_bad_number_names_file_line_column_and_field() {
    let text = format!("{HEADER}1.0 16 5.0 0.1\n2.0 16 3.2x1 0.1\n");
    let err = parse_measurements(&text, src()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "Robot9_Measurement.dat:6: field \"range\" (column 3): \"3.2x1\" is not a number"
    );
    assert_eq!(
        field_error(err),
        (6, 3, "range", FieldProblem::NotANumber("3.2x1".into()))
    );
}

#[test]
fn every_field_problem_is_reported() {
    let case = |line: &str| {
        field_error(parse_measurements(&format!("{HEADER}{line}\n"), src()).unwrap_err())
    };
    assert_eq!(case("1.0 16 5.0"), (5, 4, "bearing", FieldProblem::Missing));
    assert_eq!(case("1.0"), (5, 2, "barcode", FieldProblem::Missing));
    assert_eq!(
        case("1.0 16.5 5.0 0.1"),
        (5, 2, "barcode", FieldProblem::NotAnInteger("16.5".into()))
    );
    assert_eq!(
        case("1.0 -3 5.0 0.1"),
        (5, 2, "barcode", FieldProblem::NotAnInteger("-3".into()))
    );
    assert_eq!(
        case("nan 16 5.0 0.1"),
        (5, 1, "time", FieldProblem::NotFinite("nan".into()))
    );
    assert_eq!(
        case("1.0 16 5.0 inf"),
        (5, 4, "bearing", FieldProblem::NotFinite("inf".into()))
    );
    let (line, column, field, problem) = case("1.0 16 -0.5 0.1");
    assert_eq!((line, column, field), (5, 3, "range"));
    assert!(
        matches!(problem, FieldProblem::OutOfRange { .. }),
        "{problem:?}"
    );
}

#[test]
fn record_problems_are_reported() {
    let err = parse_measurements(&format!("{HEADER}1.0 16 5.0 0.1 7\n"), src()).unwrap_err();
    assert_eq!(
        record_error(err),
        (
            5,
            RecordProblem::TooManyFields {
                expected: 4,
                found: 5
            }
        )
    );
    let err = parse_odometry(
        &format!("{HEADER}2.0 0.1 0.0\n2.0 0.1 0.0\n1.5 0.1 0.0\n"),
        src(),
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "Robot9_Measurement.dat:7: time 1.5 s is earlier than the previous record's 2 s"
    );
    let err = parse_barcodes("# h\n1 5\n2 14\n3 5\n", Path::new("Barcodes.dat")).unwrap_err();
    assert_eq!(
        record_error(err),
        (
            4,
            RecordProblem::Duplicate {
                what: "barcode",
                value: 5,
                first_line: 2
            }
        )
    );
    let err = parse_landmarks(
        "6 0.5 -4.2 0.0 0.0\n6 0.6 -4.4 0.0 0.0\n",
        Path::new("L.dat"),
    )
    .unwrap_err();
    assert_eq!(
        record_error(err),
        (
            2,
            RecordProblem::Duplicate {
                what: "subject",
                value: 6,
                first_line: 1
            }
        )
    );
    let err = parse_landmarks("6 0.5 -4.2 -1e-4 0.0\n", Path::new("L.dat")).unwrap_err();
    assert_eq!(field_error(err).2, "x std");
    let err = parse_groundtruth("1.0 2.0 3.0\n", Path::new("G.dat")).unwrap_err();
    assert_eq!(field_error(err), (1, 4, "theta", FieldProblem::Missing));
}

#[test]
fn xz_files_are_read_and_their_errors_name_the_file() {
    let dir = scratch("xz");
    let path = dir.join("Robot2_Measurement.dat.xz");
    fs::write(
        &path,
        xz(&format!(
            "{HEADER}1.0 16 5.0 0.1\n1.5 16 5.0 0.1\n2.0 16 5.0 zero\n"
        )),
    )
    .unwrap();
    let err = mrclam::read_measurements(&path).unwrap_err();
    let msg = err.to_string();
    assert!(
        msg.starts_with(&format!(
            "{}:7: field \"bearing\" (column 4)",
            path.display()
        )),
        "{msg}"
    );

    // A good file, compressed, reads the same as plain.
    let text = format!("{HEADER}1.0 16 5.0 0.1\n1.5 41 3.0 -0.2\n");
    fs::write(&path, xz(&text)).unwrap();
    let plain = dir.join("Robot2_Measurement.dat");
    fs::write(&plain, &text).unwrap();
    assert_eq!(
        mrclam::read_measurements(&path).unwrap(),
        mrclam::read_measurements(&plain).unwrap()
    );
    // Detected by content too, whatever the name.
    let disguised = dir.join("disguised.dat");
    fs::write(&disguised, xz(&text)).unwrap();
    assert_eq!(mrclam::read_measurements(&disguised).unwrap().len(), 2);
}

#[test]
fn corrupt_xz_and_non_utf8_are_typed_errors() {
    let dir = scratch("corrupt");
    let path = dir.join("Robot1_Odometry.dat.xz");
    // lzma-rs's encoder writes streams without a content check, so flipping
    // a payload byte would go unnoticed here (real xz files carry CRC64, which
    // is verified: see mrclam_dataset6.rs). Break the stream header's CRC32
    // and truncate the stream instead.
    let good = xz("1.0 0.1 0.0\n");
    let mut bytes = good.clone();
    bytes[8] ^= 0xFF;
    fs::write(&path, &bytes).unwrap();
    let got = mrclam::read_odometry(&path);
    assert!(matches!(got, Err(Error::Decompress { .. })), "{got:?}");
    fs::write(&path, &good[..good.len() - 8]).unwrap();
    let got = mrclam::read_odometry(&path);
    assert!(matches!(got, Err(Error::Decompress { .. })), "{got:?}");
    fs::write(&path, b"not xz at all").unwrap();
    assert!(matches!(
        mrclam::read_odometry(&path),
        Err(Error::Decompress { .. })
    ));

    let path = dir.join("Robot1_Odometry.dat");
    fs::write(&path, b"# h\n1.0 0.1 0.0\n2.0 0.1 \xFF\n").unwrap();
    match mrclam::read_odometry(&path) {
        Err(Error::NotUtf8 { line, .. }) => assert_eq!(line, 3),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        mrclam::read_odometry(&dir.join("absent.dat")),
        Err(Error::Io { .. })
    ));
}

#[test]
fn a_dataset_directory_mixes_plain_and_xz_files() {
    let dir = scratch("dataset");
    fs::write(
        dir.join("Barcodes.dat.xz"),
        xz("# h\n1 5\n2 14\n6 63\n7 81\n"),
    )
    .unwrap();
    fs::write(
        dir.join("Landmark_Groundtruth.dat"),
        "# h\n6 0.5 -4.2 0.0001 0.0002\n7 0.6 -4.4 0.0001 0.0002\n",
    )
    .unwrap();
    fs::write(
        dir.join("Robot1_Groundtruth.dat"),
        "1.0 0.0 0.0 0.0\n1.1 0.1 0.0 0.0\n",
    )
    .unwrap();
    fs::write(
        dir.join("Robot1_Measurement.dat.xz"),
        xz("1.05 63 1.0 0.0\n1.05 14 2.0 0.1\n1.06 50 3.0 0.2\n1.07 81 1.5 -0.1\n"),
    )
    .unwrap();
    let data = Dataset::open(&dir).unwrap();
    assert_eq!(data.barcodes.subject(63), Some(6));
    assert_eq!(data.barcodes.barcode(2), Some(14));
    assert_eq!(data.landmark(7).unwrap().y, -4.4);
    let seen = data.sightings(1).unwrap();
    assert_eq!(
        seen.landmarks.iter().map(|s| s.subject).collect::<Vec<_>>(),
        vec![6, 7]
    );
    assert_eq!(seen.robots.len(), 1);
    assert_eq!((seen.robots[0].subject, seen.robots[0].range), (2, 2.0));
    assert_eq!(
        seen.unknown.iter().map(|m| m.barcode).collect::<Vec<_>>(),
        vec![50]
    );
    let p = data.groundtruth(1).unwrap().pose_at(1.05, 0.15).unwrap();
    assert!((p.x - 0.05).abs() < 1e-12);

    assert!(matches!(data.odometry(1), Err(Error::NotFound { .. })));
    let err = data.odometry(6).unwrap_err();
    assert!(
        matches!(err, Error::NoSuchRobot { robot: 6, .. }),
        "{err:?}"
    );
    assert!(matches!(
        Dataset::open(dir.join("nowhere")),
        Err(Error::NotFound { .. })
    ));
}

#[test]
fn barcodes_classify_robots_landmarks_and_unknowns() {
    let b: Barcodes = parse_barcodes("1 5\n5 23\n6 63\n20 25\n", Path::new("B")).unwrap();
    assert_eq!(b.classify(5), Target::Robot(1));
    assert_eq!(b.classify(23), Target::Robot(5));
    assert_eq!(b.classify(63), Target::Landmark(6));
    assert_eq!(b.classify(25), Target::Landmark(20));
    assert_eq!(b.classify(43), Target::Unknown);
    let m = |barcode| Measurement {
        time: 0.0,
        barcode,
        range: 1.0,
        bearing: 0.0,
    };
    let s = Sightings::split(&[m(63), m(5), m(43), m(25)], &b);
    assert_eq!(
        (s.landmarks.len(), s.robots.len(), s.unknown.len()),
        (2, 1, 1)
    );
}
