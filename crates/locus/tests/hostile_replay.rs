//! Issue 20, "Replay and recorded logs": hostile input to `locus replay`
//! and `locus tune` must never freeze, corrupt the estimate or report a
//! false figure. One test per class of bad input, each named for the bug
//! it guards.

use core::fmt::Write as _;
use std::fs;
use std::path::Path;
use std::process::{Command, Output};

mod common;
use common::{arc_log as log, scratch};

fn locus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .output()
        .expect("run locus")
}

/// Replays `text` (written to `dir/name`) with `flags`; returns the output
/// and the parsed `metrics.json` (if it was written).
fn replay(
    dir: &Path,
    name: &str,
    text: &str,
    flags: &[&str],
) -> (Output, Option<serde_json::Value>) {
    let file = dir.join(name);
    fs::write(&file, text).expect("write log");
    let out_dir = dir.join(format!("out-{name}"));
    let mut args = vec![
        "replay",
        "csv",
        file.to_str().expect("utf-8"),
        "--no-plots",
        "--out",
        out_dir.to_str().expect("utf-8"),
    ];
    args.extend_from_slice(flags);
    let out = locus(&args);
    let metrics = fs::read_to_string(out_dir.join("metrics.json"))
        .ok()
        .map(|t| serde_json::from_str(&t).expect("metrics.json is JSON"));
    (out, metrics)
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// The value column of the table row whose label contains `label`.
fn row<'a>(stdout: &'a str, label: &str) -> Vec<&'a str> {
    let line = stdout
        .lines()
        .find(|l| l.contains(label))
        .unwrap_or_else(|| panic!("no row {label:?} in\n{stdout}"));
    line.split(['┆', '│'])
        .map(str::trim)
        .filter(|c| !c.is_empty())
        .collect()
}

/// Bug: a log with no ground truth printed an EKF RMSE of 0.00 cm, max
/// error 0.00 and NEES 0.00 (metrics.json: 0), and "landmark readings
/// 0 / 0 / 0" beside 57 sightings applied.
#[test]
fn a_log_without_ground_truth_reports_n_a_not_zero() {
    let dir = scratch("no-truth");
    let (log, _) = log(false, "");
    let (out, metrics) = replay(&dir, "no-truth.csv", &log, &[]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        row(&stdout, "EKF (odometry + landmarks)")[1..],
        ["n/a", "n/a", "n/a"],
        "{stdout}"
    );
    assert_eq!(row(&stdout, "mean NEES (3 dof")[1], "n/a", "{stdout}");
    assert_eq!(
        row(&stdout, "steps with NEES in 95 %")[1],
        "n/a",
        "{stdout}"
    );
    assert_eq!(
        row(&stdout, "landmark readings / associated / applied")[1],
        "57 / 57 / 57",
        "{stdout}"
    );
    let m = metrics.expect("metrics.json");
    for key in [
        "position_rmse_m",
        "heading_rmse_rad",
        "max_position_error_m",
        "mean_nees",
        "nees_in_95_interval_share",
    ] {
        assert!(m["filter"][key].is_null(), "{key}: {}", m["filter"][key]);
    }
    assert_eq!(m["filter"]["compared"], 0);
    assert_eq!(m["counts"]["readings"], 57);
    assert_eq!(m["counts"]["associated"], 57);
    assert_eq!(m["counts"]["applied"], 57);
    let _ = fs::remove_dir_all(&dir);
}

/// Bug: one sighting with range 1e154 (finite, so valid by
/// docs/log-format.md) aborted the whole replay with "S is not positive
/// definite" and no line number; with neither gate nor Student-t weighting
/// it was applied and threw the estimate 1e154 m away.
#[test]
fn a_sighting_the_filter_cannot_use_is_refused_with_its_line_and_the_replay_goes_on() {
    let dir = scratch("unusable");
    let (log, line) = log(true, "measurement,2.6,2,1e154,0.1\n");
    for flags in [&["--no-gate"][..], &["--no-gate", "--no-robust"], &[]] {
        let (out, metrics) = replay(&dir, "unusable.csv", &log, flags);
        let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
        assert!(out.status.success(), "{flags:?}: {stderr}");
        assert!(
            stdout.contains(&format!("unusable.csv:{line}: ")),
            "{flags:?}: the refused line is named\n{stdout}"
        );
        let m = metrics.expect("metrics.json");
        assert_eq!(m["replay"]["unusable"], 1, "{flags:?}");
        assert_eq!(
            m["counts"]["applied"], 57,
            "{flags:?}: every good sighting applied"
        );
        let rmse = m["filter"]["position_rmse_m"].as_f64().expect("an RMSE");
        assert!(
            rmse < 0.05,
            "{flags:?}: the estimate is intact, RMSE {rmse} m"
        );
        let refused = row(&stdout, "refused: unusable / implausible time");
        assert_eq!(refused[1], "1 / 0", "{flags:?}\n{stdout}");
    }
    let _ = fs::remove_dir_all(&dir);
}

/// Bug: one measurement stamped 1e6 s in the future made every later
/// sighting "too late", silently.
#[test]
fn a_time_stamp_far_in_the_future_is_refused_with_its_line_and_discards_nothing() {
    let dir = scratch("future");
    let (log, line) = log(true, "measurement,1000000,2,1,0.1\n");
    let (out, metrics) = replay(&dir, "future.csv", &log, &[]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(
        stdout.contains(&format!("future.csv:{line}: ")),
        "the refused line is named\n{stdout}"
    );
    let m = metrics.expect("metrics.json");
    assert_eq!(m["replay"]["implausible_time"], 1);
    assert_eq!(m["replay"]["too_late"], 0);
    assert_eq!(m["counts"]["applied"], 57, "every good sighting applied");
    assert_eq!(
        row(&stdout, "refused: unusable / implausible time")[1],
        "0 / 1",
        "{stdout}"
    );
    let _ = fs::remove_dir_all(&dir);
}

/// Bug: a 20 MB field was echoed whole in the error message. (A line
/// may now hold at most 1 MiB, `locus_logs::MAX_LINE`: the field is as
/// large as a line allows.)
#[test]
fn a_huge_field_is_quoted_by_a_short_prefix() {
    let dir = scratch("huge");
    let field = "1".repeat(1_000_000) + "x";
    let (log, line) = log(true, &format!("measurement,2.6,2,{field},0.1\n"));
    let (out, _) = replay(&dir, "huge.csv", &log, &[]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains(&format!(
            "huge.csv:{line}: field \"range\" (column 4): \"111"
        )),
        "{}",
        &stderr[..stderr.len().min(2000)]
    );
    assert!(stderr.contains("1000001 bytes"), "the length is stated");
    assert!(stderr.len() < 1000, "{} bytes of error", stderr.len());
    let _ = fs::remove_dir_all(&dir);
}

/// Bug: `replay csv` on a directory, a FIFO or a symlink loop said "not
/// found".
#[test]
fn replay_csv_names_what_is_wrong_with_the_path() {
    let dir = scratch("paths");
    let fifo = dir.join("fifo.csv");
    let made = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(made.success());
    let (a, b) = (dir.join("a.csv"), dir.join("b.csv"));
    std::os::unix::fs::symlink(&b, &a).unwrap();
    std::os::unix::fs::symlink(&a, &b).unwrap();
    let cases = [
        (dir.clone(), "is a directory"),
        (fifo, "is not a regular file"),
        (a, "too many levels of symbolic links"),
    ];
    for (path, what) in cases {
        let p = path.to_str().expect("utf-8");
        let out = locus(&["replay", "csv", p, "--no-plots", "--out", "/nonexistent/x"]);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{p}");
        assert!(stderr.contains(p), "{p}: the path is named: {stderr}");
        assert!(
            stderr.to_lowercase().contains(what),
            "{p}: expected {what:?}: {stderr}"
        );
        assert!(!stderr.contains("not found"), "{p}: {stderr}");
    }
    let _ = fs::remove_dir_all(&dir);
}

/// Bug: `locus tune --tune-on 1 --held-out 1` was accepted (a robot both
/// tuned on and "held out").
#[test]
fn tune_refuses_overlapping_robot_sets_before_any_work() {
    // A directory that does not exist: the sets are checked first.
    let out = locus(&[
        "tune",
        "/nonexistent/locus-dataset",
        "--tune-on",
        "1,2",
        "--held-out",
        "2,4",
    ]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("robot 2") && stderr.contains("--tune-on") && stderr.contains("--held-out"),
        "{stderr}"
    );
    assert!(
        !stderr.contains("nonexistent"),
        "checked before any work: {stderr}"
    );
    let out = locus(&["tune", "/nonexistent/locus-dataset", "--tune-on", "1,1"]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("robot 1") && stderr.contains("twice"),
        "{stderr}"
    );
}

#[test]
fn replay_noise_and_scale_flags_are_checked_before_the_log_is_read() {
    // The log does not exist: a flag checked only after reading it would
    // be reported as a missing file, not as the flag.
    for (flag, value) in [
        ("--q-v", "NaN"),
        ("--sigma-range", "-1"),
        ("--v-scale", "0"),
        ("--robust-dof", "inf"),
        ("--odometry-delay", "NaN"),
        ("--gate", "-0.5"),
    ] {
        let out = locus(&[
            "replay",
            "csv",
            "/nonexistent/log.csv",
            &format!("{flag}={value}"),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{flag} {value}: {stderr}");
        assert!(stderr.contains(flag), "{flag} {value}: {stderr}");
    }
}

/// `log(true, "")` with odometry line `time` (as written) replaced by
/// `record`; returns the text and the record's line (1-based).
fn with_odometry(time: &str, record: &str) -> (String, usize) {
    let (content, _) = log(true, "");
    let prefix = format!("odometry,{time},");
    let line = content
        .lines()
        .position(|l| l.starts_with(&prefix))
        .unwrap_or_else(|| panic!("no odometry line at {time}"));
    let replaced: Vec<&str> = content
        .lines()
        .enumerate()
        .map(|(i, l)| if i == line { record } else { l })
        .collect();
    (replaced.join("\n") + "\n", line + 1)
}

/// Issue 34, fault 1: a sensor, landmark or start at 1e308 m (finite, so a
/// valid field) was accepted; every sighting then vanished from every
/// count, exit 0 (and the start's warning spelt out 309 digits).
#[test]
fn an_absurd_sensor_landmark_or_start_is_an_error_naming_its_line() {
    let dir = scratch("absurd-static");
    let (base, _) = log(true, "");
    for (what, record) in [
        ("sensor", "sensor,1e308,0,0"),
        ("landmark", "landmark,9,1e308,0"),
        ("start", "start,0,1e308,0,0"),
    ] {
        let body = base.replace("start,0,0,0,0\n", "");
        let content = format!("{record}\n{body}");
        let (out, _) = replay(&dir, "absurd.csv", &content, &["--no-estimate"]);
        let stderr = text(&out.stderr);
        assert!(!out.status.success(), "{what}: refused");
        assert!(
            stderr.contains(&format!("absurd.csv:1: {what}: ")) && stderr.contains("1e308"),
            "{what}: the line, the record and the value are named\n{stderr}"
        );
        assert!(stderr.len() < 400, "{what}: short\n{stderr}");
    }
    let _ = fs::remove_dir_all(&dir);
}

/// Issue 34, faults 2 and 3: an odometry record of 1e308 m/s or 1e308
/// rad/s ended the whole replay ("filter step at T s: non-finite value in
/// P/Q", no line); one of 1e6 m/s put the estimate 1.4 km off, exit 0, no
/// warning; a last record stamped 1e308 s ended it too. Each is refused
/// with its line, counted, and the replay goes on intact.
#[test]
fn an_absurd_odometry_record_is_refused_with_its_line_and_the_replay_goes_on() {
    let dir = scratch("absurd-odometry");
    let mut cases = vec![
        with_odometry("5", "odometry,5,1e308,0.1"),
        with_odometry("5", "odometry,5,0.2,1e308"),
        with_odometry("5", "odometry,5,1000000,0.1"),
    ];
    let (tail, line) = log(true, "odometry,1e308,0.2,0.1\n");
    cases.push((tail, line));
    for (content, line) in cases {
        let (out, metrics) = replay(&dir, "odometry.csv", &content, &["--no-estimate"]);
        let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
        assert!(out.status.success(), "line {line}: {stderr}");
        assert!(
            stdout.contains(&format!("odometry.csv:{line}: odometry record refused")),
            "line {line} named\n{stdout}"
        );
        let m = metrics.expect("metrics.json");
        assert_eq!(m["replay"]["implausible_odometry"], 1, "line {line}");
        assert_eq!(m["counts"]["applied"], 57, "line {line}");
        let rmse = m["filter"]["position_rmse_m"].as_f64().expect("an RMSE");
        assert!(
            rmse < 0.05,
            "line {line}: the estimate is intact, RMSE {rmse} m"
        );
        assert_eq!(
            row(&stdout, "odometry records refused as implausible")[1],
            "1",
            "{stdout}"
        );
    }
    // A faster robot states its top speed: then the record is applied.
    let (content, _) = with_odometry("5", "odometry,5,12,0.1");
    let (out, metrics) = replay(
        &dir,
        "fast.csv",
        &content,
        &["--no-estimate", "--max-speed", "20"],
    );
    assert!(out.status.success());
    assert_eq!(
        metrics.expect("metrics.json")["replay"]["implausible_odometry"],
        0
    );
    let _ = fs::remove_dir_all(&dir);
}

/// Issue 34, fault 2: `noise,q_v,1e308` ended the replay with a non-finite
/// covariance and no line. It is refused with its line, and the level is
/// left to the estimate.
#[test]
fn an_absurd_noise_record_is_refused_with_its_line_and_the_replay_goes_on() {
    let dir = scratch("absurd-noise");
    let (base, _) = log(true, "");
    let content = format!("noise,q_v,1e308\n{base}");
    for flags in [&["--no-estimate"][..], &[]] {
        let (out, metrics) = replay(&dir, "noise.csv", &content, flags);
        let (stdout, stderr) = (text(&out.stdout), text(&out.stderr));
        assert!(out.status.success(), "{flags:?}: {stderr}");
        assert!(
            stdout.contains("noise.csv:1: noise q_v refused: implausible, 1e308"),
            "{flags:?}\n{stdout}"
        );
        let m = metrics.expect("metrics.json");
        let q = m["replay"]["q_v_m2_per_s"].as_f64().expect("q_v");
        assert!(q < 1.0, "{flags:?}: q_v {q}");
        assert_eq!(m["counts"]["applied"], 57, "{flags:?}");
    }
    let _ = fs::remove_dir_all(&dir);
}

/// Issue 34, fault 5: a log of one 4 GiB comment line took 5 GB of memory
/// (and blamed the xz decoder when it ran out). A line is bounded: the
/// reader stops at it and names it.
#[test]
fn a_line_longer_than_the_bound_is_refused_with_its_line() {
    let dir = scratch("long-line");
    let (base, _) = log(true, "");
    let content = format!("{base}#{}\n", "x".repeat(3 << 20));
    let line = base.lines().count() + 1;
    let (out, _) = replay(&dir, "long.csv", &content, &["--no-estimate"]);
    let stderr = text(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains(&format!("long.csv:{line}: line longer than 1048576 bytes")),
        "{stderr}"
    );
    let _ = fs::remove_dir_all(&dir);
}

/// Issue 34, fault 7: when the only step compared with the truth is the
/// start pose, copied from that truth, the summary showed RMSE 0.00, NEES
/// 0.00, 100 % inside 3 sigma and a real-time factor of 0. Nothing was
/// judged: every such figure reads n/a (null); the real-time factor is
/// over the time the log covers, which needs no truth.
#[test]
fn figures_from_the_start_pose_alone_read_n_a() {
    let dir = scratch("start-only");
    let (base, _) = log(false, "");
    let content = base.replace("start,0,0,0,0\n", "truth,0,0,0,0\n");
    let (out, metrics) = replay(&dir, "start-only.csv", &content, &["--no-estimate"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(
        row(&stdout, "EKF (odometry + landmarks)")[1..],
        ["n/a", "n/a", "n/a"],
        "{stdout}"
    );
    assert_eq!(row(&stdout, "mean NEES (3 dof")[1], "n/a", "{stdout}");
    let m = metrics.expect("metrics.json");
    for key in [
        "position_rmse_m",
        "heading_rmse_rad",
        "mean_nees",
        "nees_in_95_interval_share",
        "within_3_sigma_x_share",
    ] {
        assert!(m["filter"][key].is_null(), "{key}: {}", m["filter"][key]);
    }
    assert!(m["duration_s"].as_f64().unwrap() > 0.0, "{m}");
    assert!(
        m["timing"]["real_time_factor"].as_f64().unwrap() > 0.0,
        "{m}"
    );
    let _ = fs::remove_dir_all(&dir);
}

/// A log of a robot standing still at `pose` (x, y in m, heading in rad)
/// for `seconds` (odometry at 50 Hz), with no start and no truth, the
/// `landmarks` (id, x, y in m) and one exact sighting (range, bearing) of
/// landmark `id` at each `(t, id)` of `seen`.
fn still_log(
    pose: (f64, f64, f64),
    seconds: u32,
    landmarks: &[(u32, f64, f64)],
    seen: &[(f64, u32)],
) -> String {
    let mut s = String::new();
    for (id, x, y) in landmarks {
        writeln!(s, "landmark,{id},{x},{y}").unwrap();
    }
    for i in 0..=seconds * 50 {
        writeln!(s, "odometry,{},0,0", f64::from(i) * 0.02).unwrap();
    }
    for &(t, id) in seen {
        let &(_, lx, ly) = landmarks.iter().find(|l| l.0 == id).expect("landmark");
        let r = (lx - pose.0).hypot(ly - pose.1);
        let b = (ly - pose.1).atan2(lx - pose.0) - pose.2;
        writeln!(s, "measurement,{t},{id},{r},{b}").unwrap();
    }
    s
}

/// Bug (issue 34, 8): `--start-from-sightings` took a pose that 4 of 51
/// random sightings supported (12 m off, "+- 0.5 m", no warning), and
/// landmarks all at one point still gave a "fix". A start from the
/// sightings must say how many support it and refuse a weak consensus or
/// a geometry that fixes no heading; collinear landmarks seen with
/// bearings do fix the pose.
#[test]
fn a_start_that_few_sightings_support_or_that_one_point_cannot_fix_is_refused() {
    let dir = scratch("weak-start");
    let landmarks = [(1, 3.0, 0.0), (2, 0.0, 3.0), (3, -2.0, -2.0), (4, 4.0, 4.0)];
    // 51 sightings of random range and bearing (a fixed linear
    // congruential sequence).
    let mut state: u64 = 34;
    let mut uniform = || {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        #[allow(clippy::cast_precision_loss)]
        let u = (state >> 11) as f64 / (1_u64 << 53) as f64;
        u
    };
    let mut random = still_log((1.0, 0.5, 0.3), 12, &landmarks, &[]);
    for k in 0..51 {
        let id = 1 + k % 4;
        let (r, b) = (
            0.5 + 6.0 * uniform(),
            core::f64::consts::PI * (2.0 * uniform() - 1.0),
        );
        writeln!(random, "measurement,{},{id},{r},{b}", 0.2 * f64::from(k)).unwrap();
    }
    // A refused start: no run, and the reason named.
    let refused = |name: &str, log: &str, reason: &str| {
        let (out, metrics) = replay(&dir, name, log, &["--start-from-sightings"]);
        let stderr = text(&out.stderr);
        assert!(
            !out.status.success(),
            "{name}: a fix: {}",
            text(&out.stdout)
        );
        assert!(metrics.is_none(), "{name}");
        assert!(
            stderr.contains("sightings fix none") && stderr.contains(reason),
            "{name}: {stderr}"
        );
    };
    refused("random.csv", &random, "of 51 sightings agree");

    // Two landmarks at one point: every heading fits.
    let seen: Vec<(f64, u32)> = (0..40).map(|k| (0.25 * f64::from(k), 1 + k % 2)).collect();
    let point = still_log((1.0, 0.5, 0.3), 12, &[(1, 3.0, 0.0), (2, 3.0, 0.0)], &seen);
    refused("point.csv", &point, "apart");

    // Three landmarks on a line, seen with bearings: the pose is fixed.
    let seen: Vec<(f64, u32)> = (0..60).map(|k| (0.15 * f64::from(k), 1 + k % 3)).collect();
    let line = still_log(
        (1.0, 0.5, 0.3),
        12,
        &[(1, -2.0, 2.0), (2, 1.0, 2.0), (3, 4.0, 2.0)],
        &seen,
    );
    let (out, metrics) = replay(&dir, "line.csv", &line, &["--start-from-sightings"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let start = &metrics.expect("metrics.json")["replay"]["start"];
    let pose = &start["pose"];
    assert!(
        (pose[0].as_f64().unwrap() - 1.0).abs() < 0.05
            && (pose[1].as_f64().unwrap() - 0.5).abs() < 0.05
            && (pose[2].as_f64().unwrap() - 0.3).abs() < 0.01,
        "{start}"
    );
    // The fix states its support.
    assert_eq!(start["sightings"], 60, "{start}");
    assert_eq!(start["inliers"], 60, "{start}");
    assert_eq!(start["landmarks"], 3, "{start}");
    assert_eq!(start["inlier_share"], 1.0, "{start}");
    assert!(
        (start["baseline_m"].as_f64().unwrap_or(f64::NAN) - 6.0).abs() < 1e-9,
        "{start}"
    );
    let _ = fs::remove_dir_all(&dir);
}

/// Bug (issue 34, 9): `--start-from-sightings` looked at the first 120
/// sightings only; when those all saw one landmark it said no two
/// landmarks were seen within 80 s. A robot that sees one landmark for its
/// first 100 s (500 sightings) and then three starts from the later ones.
#[test]
fn a_start_from_sightings_searches_past_the_first_sightings() {
    let dir = scratch("late-start");
    let landmarks = [(1, 3.0, 0.0), (2, 0.0, 3.0), (3, -2.0, -2.0)];
    let mut seen: Vec<(f64, u32)> = (0..500).map(|k| (0.2 * f64::from(k), 1)).collect();
    seen.extend((0..60).map(|k| (100.0 + 0.2 * f64::from(k), 1 + k % 3)));
    let log = still_log((1.0, 0.5, 0.3), 120, &landmarks, &seen);
    let (out, metrics) = replay(&dir, "late.csv", &log, &["--start-from-sightings"]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let start = &metrics.expect("metrics.json")["replay"]["start"];
    assert_eq!(start["from"], "sightings");
    let pose = &start["pose"];
    assert!(
        (pose[0].as_f64().unwrap() - 1.0).abs() < 0.05
            && (pose[1].as_f64().unwrap() - 0.5).abs() < 0.05
            && (pose[2].as_f64().unwrap() - 0.3).abs() < 0.01,
        "{start}"
    );
    let _ = fs::remove_dir_all(&dir);
}

/// Issue 34: a replay killed midway left `log.csv` (and `smoothed.csv`)
/// under its normal name with no end marker, which a reader could not tell
/// from a complete one. They are written as `log.csv.partial` and renamed
/// only when the replay has finished: a killed replay leaves no `log.csv`.
#[test]
fn a_killed_replay_leaves_no_log_csv_under_its_normal_name() {
    use core::time::Duration;
    use std::process::Stdio;
    use std::time::Instant;

    let dir = scratch("killed-replay");
    // 5 000 s at 200 Hz (10^6 odometry records), sightings every 0.5 s:
    // long enough to be killed while it writes.
    let mut s = String::from("landmark,1,3,0\nlandmark,2,0,3\nstart,0,0,0,0\n");
    for i in 0..1_000_000u32 {
        let t = f64::from(i) * 0.005;
        writeln!(s, "odometry,{t},0,0").unwrap();
        if i % 100 == 0 && i > 0 {
            writeln!(
                s,
                "measurement,{t},1,3,0\nmeasurement,{t},2,3,1.5707963267948966"
            )
            .unwrap();
        }
    }
    let file = dir.join("long.csv");
    fs::write(&file, s).expect("write log");
    let out = dir.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["replay", "csv"])
        .arg(&file)
        .args(["--no-estimate", "--no-plots", "--out"])
        .arg(&out)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start locus");
    let lines = |name: &str| {
        fs::read(out.join(name)).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
    };
    let started = Instant::now();
    // Under either name: the old code wrote log.csv itself.
    while lines("log.csv") + lines("log.csv.partial") < 2000 {
        if let Some(status) = child.try_wait().expect("poll locus") {
            panic!("locus ended ({status}) before its log grew");
        }
        assert!(
            started.elapsed() < Duration::from_secs(120),
            "no log after 120 s"
        );
        std::thread::sleep(Duration::from_millis(2));
    }
    child.kill().expect("SIGKILL locus");
    let status = child.wait().expect("reap locus");
    assert!(!status.success(), "killed before the end");
    assert!(
        !out.join("log.csv").exists(),
        "a killed replay left log.csv under its normal name"
    );
    assert!(lines("log.csv.partial") >= 2000, "the partial log is kept");
    assert!(!out.join("metrics.json").exists());
    // A finished replay renames it; a rerun clears the earlier partial one.
    let file = dir.join("short.csv");
    fs::write(&file, log(true, "").0).expect("write log");
    let done = locus(&[
        "replay",
        "csv",
        file.to_str().expect("utf-8"),
        "--smooth",
        "--no-plots",
        "--out",
        out.to_str().expect("utf-8"),
    ]);
    assert!(done.status.success(), "{}", text(&done.stderr));
    for name in ["log.csv", "smoothed.csv"] {
        assert!(out.join(name).exists(), "{name}");
        assert!(!out.join(format!("{name}.partial")).exists(), "{name}");
    }
    let _ = fs::remove_dir_all(&dir);
}

/// A bag that is not whole (issue 30): `locus replay bag` on rosbag2's own
/// test bag cut short, on a text file named `.mcap`, and with a mapping
/// that is not TOML, each ends with an error naming the file and the
/// record (or the mapping's line), never a panic.
#[test]
fn a_damaged_bag_or_mapping_is_an_error_naming_where() {
    let bag = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/rosbag2_cdr_test/cdr_test_0.mcap");
    if !bag.is_file() {
        eprintln!("skipped: {} not found", bag.display());
        return;
    }
    let dir = scratch("hostile-bag");
    let bytes = fs::read(&bag).unwrap();
    let cut = dir.join("cut.mcap");
    fs::write(&cut, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let text = dir.join("text.mcap");
    fs::write(&text, "not,a,bag\n").unwrap();
    let mapping = dir.join("m.toml");
    fs::write(&mapping, "[velocity]\ntopic = \"/test_topic\"\n").unwrap();
    for (file, want) in [
        (&cut, "cut.mcap: record "),
        (&text, "text.mcap: record 1: "),
    ] {
        let out = locus(&["replay", "bag", file.to_str().unwrap(), "--list"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{err}");
        assert!(err.contains(want) && !err.contains("panicked"), "{err}");
    }
    // A topic whose messages have no velocity fields: the topic and field.
    let out = locus(&[
        "replay",
        "bag",
        bag.to_str().unwrap(),
        "--topics",
        mapping.to_str().unwrap(),
        "--no-plots",
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains(
            "topic /test_topic (test_msgs/msg/BasicTypes), field velocity.linear: no usual field"
        ),
        "{err}"
    );
    let bad = dir.join("bad.toml");
    fs::write(&bad, "[velocity\ntopic = 1\n").unwrap();
    let out = locus(&[
        "replay",
        "bag",
        bag.to_str().unwrap(),
        "--topics",
        bad.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.toml:1:") && !err.contains("panicked"),
        "{err}"
    );
    let _ = fs::remove_dir_all(&dir);
}
