//! Issue 20, "Replay and recorded logs": hostile input to `locus replay`
//! and `locus tune` must never freeze, corrupt the estimate or report a
//! false figure. One test per class of bad input, each named for the bug
//! it guards.

use core::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn locus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .output()
        .expect("run locus")
}

/// A fresh temporary directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("locus-hostile-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A robot driving a circular arc (0.2 m/s, 0.1 rad/s) for 10 s at 50 Hz,
/// with exact sightings of three landmarks every 0.5 s (57 in all) and,
/// with `truth`, the exact ground truth. `extra` is inserted after the
/// 13th measurement line; returns the text and the line number `extra`
/// starts on (1-based).
fn log(truth: bool, extra: &str) -> (String, usize) {
    let mut s = String::from("landmark,1,3,0\nlandmark,2,0,3\nlandmark,3,-2,-2\nstart,0,0,0,0\n");
    let (v, w) = (0.2, 0.1);
    let pose = |t: f64| (v / w * (w * t).sin(), v / w * (1.0 - (w * t).cos()), w * t);
    for i in 0..=500 {
        let t = f64::from(i) * 0.02;
        writeln!(s, "odometry,{t},{v},{w}").unwrap();
        if truth {
            let (x, y, th) = pose(t);
            writeln!(s, "truth,{t},{x},{y},{th}").unwrap();
        }
    }
    let mut extra_line = 0;
    let mut n = 0;
    for k in 1..20 {
        let t = f64::from(k) * 0.5;
        let (x, y, th) = pose(t);
        for (id, lx, ly) in [(1, 3.0, 0.0), (2, 0.0, 3.0), (3, -2.0_f64, -2.0_f64)] {
            let r = (lx - x).hypot(ly - y);
            let b = (ly - y).atan2(lx - x) - th;
            writeln!(s, "measurement,{t},{id},{r},{b}").unwrap();
            n += 1;
            if n == 13 {
                extra_line = s.lines().count() + 1;
                s.push_str(extra);
            }
        }
    }
    (s, extra_line)
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
        "ekf_position_rmse_m",
        "ekf_heading_rmse_rad",
        "ekf_max_position_error_m",
        "mean_nees",
        "nees_in_95_interval_share",
    ] {
        assert!(m[key].is_null(), "{key}: {}", m[key]);
    }
    assert_eq!(m["ir_readings"], 57);
    assert_eq!(m["corrections"], 57);
    assert_eq!(m["applied"], 57);
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
        assert_eq!(m["unusable"], 1, "{flags:?}");
        assert_eq!(m["applied"], 57, "{flags:?}: every good sighting applied");
        let rmse = m["ekf_position_rmse_m"].as_f64().expect("an RMSE");
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
    assert_eq!(m["implausible_time"], 1);
    assert_eq!(m["too_late"], 0);
    assert_eq!(m["applied"], 57, "every good sighting applied");
    assert_eq!(
        row(&stdout, "refused: unusable / implausible time")[1],
        "0 / 1",
        "{stdout}"
    );
    let _ = fs::remove_dir_all(&dir);
}

/// Bug: a 20 MB field was echoed whole in the error message.
#[test]
fn a_huge_field_is_quoted_by_a_short_prefix() {
    let dir = scratch("huge");
    let field = "1".repeat(20_000_000) + "x";
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
    assert!(stderr.contains("20000001 bytes"), "the length is stated");
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
