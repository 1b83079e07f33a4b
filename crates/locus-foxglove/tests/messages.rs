//! Every message Locus writes validates against its topic's JSON Schema
//! (Foxglove's published ones, and Locus's two series), and says what the
//! step holds: poses, the ellipse's axes, the errors and bands.

use locus_foxglove::{Error, Frame, GridCells, Message, Scene, Topic, frame, scene, summary, ws};
use serde_json::Value;

fn validate(m: &Message) -> Value {
    let schema: Value = serde_json::from_str(m.topic.schema().data).unwrap();
    let v: Value = serde_json::from_slice(&m.payload).unwrap();
    let validator = jsonschema::validator_for(&schema).unwrap();
    let errors: Vec<String> = validator.iter_errors(&v).map(|e| e.to_string()).collect();
    assert!(errors.is_empty(), "{} on {}: {errors:?}", m.topic.name(), v);
    v
}

fn step() -> Frame {
    Frame {
        time: 12.25,
        estimate: [1.0, 2.0, 0.5],
        // sd 0.2 m in x, 0.1 m in y, 0.05 rad, uncorrelated.
        covariance: [[0.04, 0.0, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.0025]],
        truth: Some([1.1, 1.9, 0.45]),
        odometry: Some([1.5, 2.5, 0.7]),
        correction: Some((2.5, 2, true)),
        nees: Some((1.2, 3)),
    }
}

fn by_topic(ms: &[Message], t: Topic) -> Value {
    let m = ms.iter().find(|m| m.topic == t).unwrap();
    validate(m)
}

#[test]
fn a_step_is_valid_foxglove_and_says_what_the_filter_believes() {
    let ms = frame(&step(), 3.0).unwrap();
    let topics: Vec<Topic> = ms.iter().map(|m| m.topic).collect();
    assert_eq!(
        topics,
        [
            Topic::Estimate,
            Topic::Transform,
            Topic::Truth,
            Topic::Odometry,
            Topic::Ellipse,
            Topic::Errors,
            Topic::Nis
        ]
    );
    for m in &ms {
        validate(m);
        assert_eq!(m.time, 12_250_000_000);
    }
    let est = by_topic(&ms, Topic::Estimate);
    assert_eq!(est["timestamp"]["sec"], 12);
    assert_eq!(est["timestamp"]["nsec"], 250_000_000);
    assert_eq!(est["frame_id"], "map");
    assert_eq!(est["pose"]["position"]["x"], 1.0);
    let q = &est["pose"]["orientation"];
    let yaw = 2.0 * q["z"].as_f64().unwrap().atan2(q["w"].as_f64().unwrap());
    assert!((yaw - 0.5).abs() < 1e-15);
    let tf = by_topic(&ms, Topic::Transform);
    assert_eq!(tf["child_frame_id"], "base_link");
    let e = by_topic(&ms, Topic::Errors);
    assert!((e["x"].as_f64().unwrap() - 0.1).abs() < 1e-12);
    assert!((e["heading"].as_f64().unwrap() + 0.05).abs() < 1e-12);
    assert!((e["x_plus_3_sigma"].as_f64().unwrap() - 0.6).abs() < 1e-12);
    assert!((e["y_minus_3_sigma"].as_f64().unwrap() + 0.3).abs() < 1e-12);
    assert_eq!(e["nees_dof"], 3);
    let n = by_topic(&ms, Topic::Nis);
    assert_eq!(
        (n["nis"].as_f64(), n["dof"].as_u64(), n["applied"].as_bool()),
        (Some(2.5), Some(2), Some(true))
    );
    // The 3-sigma ellipse: semi-axes 0.6 m along x and 0.3 m along y.
    let c = by_topic(&ms, Topic::Ellipse);
    let pts = c["entities"][0]["lines"][0]["points"].as_array().unwrap();
    let (mut rx, mut ry) = (0.0_f64, 0.0_f64);
    for p in pts {
        rx = rx.max((p["x"].as_f64().unwrap() - 1.0).abs());
        ry = ry.max((p["y"].as_f64().unwrap() - 2.0).abs());
    }
    assert!(
        (rx - 0.6).abs() < 1e-12 && (ry - 0.3).abs() < 1e-12,
        "{rx} {ry}"
    );
}

#[test]
fn a_rotated_covariance_gives_a_rotated_ellipse() {
    // Variance 0.09 along 45 degrees, 0.01 across: every point satisfies
    // d^T P^-1 d = 9 at 3 sigma.
    let (a, b) = (0.05, 0.04);
    let mut f = step();
    f.covariance = [[a, b, 0.0], [b, a, 0.0], [0.0, 0.0, 0.01]];
    let ms = frame(&f, 3.0).unwrap();
    let c = by_topic(&ms, Topic::Ellipse);
    let det = a * a - b * b;
    for p in c["entities"][0]["lines"][0]["points"].as_array().unwrap() {
        let (dx, dy) = (
            p["x"].as_f64().unwrap() - 1.0,
            p["y"].as_f64().unwrap() - 2.0,
        );
        let m = (a * dx * dx - 2.0 * b * dx * dy + a * dy * dy) / det;
        // A point rounded to the micrometre moves by at most 0.71 um,
        // which moves its Mahalanobis distance by at most 0.71 um over the
        // smallest standard deviation (0.1 m): 7.1e-6.
        assert!((m.sqrt() - 3.0).abs() <= 7.1e-6, "{m}");
    }
}

#[test]
fn without_truth_the_errors_are_null_and_the_bands_remain() {
    let mut f = step();
    f.truth = None;
    f.odometry = None;
    f.correction = None;
    f.nees = None;
    let ms = frame(&f, 3.0).unwrap();
    assert!(
        ms.iter()
            .all(|m| ![Topic::Truth, Topic::Odometry, Topic::Nis].contains(&m.topic))
    );
    let e = by_topic(&ms, Topic::Errors);
    assert!(e["x"].is_null() && e["heading"].is_null() && e["nees"].is_null());
    assert!((e["heading_plus_3_sigma"].as_f64().unwrap() - 0.15).abs() < 1e-12);
    // A truth without heading: faces +x, heading error null.
    f.truth = Some([1.0, 2.0, f64::NAN]);
    let ms = frame(&f, 3.0).unwrap();
    let e = by_topic(&ms, Topic::Errors);
    assert!(e["heading"].is_null() && e["x"].as_f64() == Some(0.0));
    by_topic(&ms, Topic::Truth);
}

#[test]
fn a_time_or_number_foxglove_cannot_carry_is_an_error_naming_it() {
    let mut f = step();
    f.time = -1.0;
    let e = frame(&f, 3.0).unwrap_err();
    assert!(matches!(e, Error::Time { .. }), "{e}");
    assert!(e.to_string().contains("-1 s of a step"), "{e}");
    f.time = 1.0;
    f.estimate[1] = f64::NAN;
    let e = frame(&f, 3.0).unwrap_err().to_string();
    assert!(e.contains("the estimate at 1 s is NaN"), "{e}");
    f.estimate[1] = 0.0;
    f.covariance[0][1] = f64::INFINITY;
    assert!(frame(&f, 3.0).is_err());
}

#[test]
fn the_map_and_summary_are_valid_foxglove() {
    let s = Scene {
        walls: vec![[0.0, 0.0, 2.0, 0.0], [2.0, 0.0, 2.0, 2.0]],
        landmarks: vec![(7, [1.0, 1.0])],
        grid: Some(GridCells {
            origin: [-1.0, -2.0, 0.0],
            resolution: 0.05,
            width: 3,
            height: 2,
            cells: vec![0, 100, -1, 0, 0, 100],
        }),
    };
    let ms = scene(&s, 0.0).unwrap();
    let map = by_topic(&ms, Topic::Map);
    let e = &map["entities"][0];
    assert_eq!(e["lines"][0]["points"].as_array().unwrap().len(), 4);
    assert_eq!(e["texts"][0]["text"], "7");
    let g = by_topic(&ms, Topic::Grid);
    assert_eq!(g["column_count"], 3);
    assert_eq!(g["data"], "AGT/AABk"); // [0, 100, 255, 0, 0, 100]
    let log = summary("RMSE 0.1 m", 5.0, "locus replay").unwrap();
    let v = validate(&log);
    assert_eq!(v["level"], 2);
    assert_eq!(v["message"], "RMSE 0.1 m");
}

#[test]
fn the_websocket_protocol_frames_only_what_a_client_subscribed_to() {
    let ad: Value = serde_json::from_str(&ws::advertise()).unwrap();
    let channels = ad["channels"].as_array().unwrap();
    assert_eq!(channels.len(), Topic::ALL.len());
    assert_eq!(channels[0]["topic"], "/locus/estimate");
    assert_eq!(channels[0]["schemaName"], "foxglove.PoseInFrame");
    assert_eq!(channels[0]["schemaEncoding"], "jsonschema");
    let mut subs = ws::Subscriptions::default();
    assert!(
        subs.apply(r#"{"op":"subscribe","subscriptions":[{"id":7,"channelId":1}]}"#)
            .is_none()
    );
    let ms = frame(&step(), 3.0).unwrap();
    let framed: Vec<Vec<u8>> = ms.iter().filter_map(|m| subs.frame(m)).collect();
    assert_eq!(framed.len(), 1);
    let f = &framed[0];
    assert_eq!(f[0], 1);
    assert_eq!(u32::from_le_bytes(f[1..5].try_into().unwrap()), 7);
    assert_eq!(
        u64::from_le_bytes(f[5..13].try_into().unwrap()),
        12_250_000_000
    );
    assert_eq!(&f[13..], ms[0].payload.as_slice());
    // Unknown channels, reused ids and garbage are answered with a status.
    let s = subs.apply(
        r#"{"op":"subscribe","subscriptions":[{"id":7,"channelId":2},{"id":8,"channelId":99}]}"#,
    );
    assert!(
        s.unwrap()
            .contains("refused subscriptions to channels [2, 99]")
    );
    assert!(subs.apply("{not json").unwrap().contains("\"status\""));
    subs.apply(r#"{"op":"unsubscribe","subscriptionIds":[7]}"#);
    assert!(subs.is_empty());
}
