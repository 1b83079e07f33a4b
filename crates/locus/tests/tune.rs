//! `locus tune` as a user runs it: on an MRCLAM dataset (robots 1-3 tuned
//! on, 4-5 held out) and on Locus CSV logs. By default it combines what
//! `locus replay` estimates from each tuning log alone, by the median.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

fn data() -> &'static str {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/mrclam/MRCLAM_Dataset6"
    )
}

/// The tuned column of a row of `locus tune`'s values table.
fn tuned(text: &str, label: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.starts_with('│') && l.contains(label))
        .unwrap_or_else(|| panic!("no {label} in\n{text}"));
    let cells: Vec<f64> = line
        .split(['┆', '│'])
        .filter_map(|c| c.trim().parse().ok())
        .collect();
    cells[1]
}

/// The estimates of `locus replay` (no flags) in a run's metrics.json.
fn estimated(out: &Path) -> [f64; 5] {
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("metrics.json")).unwrap()).unwrap();
    [
        "q_v_m2_per_s",
        "q_omega_rad2_per_s",
        "sigma_range_m",
        "sigma_bearing_rad",
        "odometry_delay_s",
    ]
    .map(|k| m["replay"][k].as_f64().unwrap())
}

const LABELS: [&str; 5] = [
    "q_v, forward-speed",
    "q_omega, turn-rate",
    "sigma_range",
    "sigma_bearing",
    "odometry delay",
];

#[test]
fn tune_combines_what_the_replay_estimates_from_each_log() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("tune");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let mut each = Vec::new();
    for r in ["1", "2", "3", "4"] {
        let out = dir.join(format!("replay-{r}"));
        let csv = dir.join(format!("robot{r}.csv"));
        common::locus_ok(&[
            "replay",
            "mrclam",
            data(),
            "--robot",
            r,
            "--no-plots",
            "--out",
            out.to_str().unwrap(),
            "--export",
            csv.to_str().unwrap(),
        ]);
        each.push(estimated(&out));
    }
    // MRCLAM: robots 1-3 tuned on, each value their median.
    let text = common::locus_ok(&["tune", data()]);
    assert!(
        text.contains("objective estimate,") && text.contains("held out"),
        "{text}"
    );
    for (k, label) in LABELS.iter().enumerate() {
        let mut v: Vec<f64> = each[..3].iter().map(|e| e[k]).collect();
        v.sort_by(f64::total_cmp);
        let got = tuned(&text, label);
        assert!(
            (got - v[1]).abs() <= 5e-6 * v[1].abs().max(1.0),
            "{label}: tuned {got}, median of robots 1-3 {}",
            v[1]
        );
    }
    // Locus CSV logs: one tuned on (its own estimate), one held out.
    let r1 = dir.join("robot1.csv");
    let r4 = dir.join("robot4.csv");
    let text = common::locus_ok(&[
        "tune",
        r1.to_str().unwrap(),
        "--held-out-log",
        r4.to_str().unwrap(),
    ]);
    for (k, label) in LABELS.iter().enumerate() {
        let got = tuned(&text, label);
        assert!(
            (got - each[0][k]).abs() <= 5e-6 * each[0][k].abs().max(1.0),
            "{label}: {got} against robot 1's {}",
            each[0][k]
        );
    }
    assert!(
        text.contains("robot4.csv") && text.contains("held out"),
        "{text}"
    );
    // A log tuned on cannot be held out.
    let out = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args([
            "tune",
            r1.to_str().unwrap(),
            "--held-out-log",
            r1.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("both tuned on and held out"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `locus tune` with `args`, whatever its exit status.
fn tune_run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_locus"))
        .arg("tune")
        .args(args)
        .output()
        .expect("run locus tune")
}

/// MRCLAM robot `robot` as a Locus CSV log (what `locus replay mrclam
/// --export` writes), its lines kept where `keep(kind, time)` says.
fn cut_log(robot: u32, path: &Path, keep: impl Fn(&str, f64) -> bool) {
    let dataset = locus_logs::mrclam::Dataset::open(Path::new(data())).unwrap();
    let log = locus_replay::Log::mrclam(&dataset, robot).unwrap();
    let text = locus_logs::locus_csv::write(&log.to_locus());
    let mut out = String::new();
    for line in text.lines() {
        let mut fields = line.split(',');
        let kind = fields.next().unwrap_or("");
        let time = fields.next().and_then(|t| t.parse::<f64>().ok());
        let timed = matches!(kind, "odometry" | "measurement" | "range" | "truth");
        if !timed || keep(kind, time.unwrap()) {
            out.push_str(line);
            out.push('\n');
        }
    }
    std::fs::write(path, out).unwrap();
}

/// Issue 34, fault 6: a robot's log cut to a single odometry record has no
/// estimate, yet `locus tune` put its value into the median (the tuned q_v
/// moved to another robot's), showed RMSE 0.000 for it and exited 0; tuning
/// on it alone said "q_v must be finite and > 0", naming neither log nor
/// cause. A log whose estimate cannot be computed is named with the cause
/// in a warning and left out of the median; its figures read "n/a"; with
/// no log left the run fails with that message.
#[test]
fn a_log_without_an_estimate_is_named_and_left_out_of_the_median() {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("tune-near-empty");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let (a, b, one) = (dir.join("a.csv"), dir.join("b.csv"), dir.join("one.csv"));
    // Two short logs that tell an estimate, and one cut to its first
    // odometry record.
    let first = |robot: u32| {
        let dataset = locus_logs::mrclam::Dataset::open(Path::new(data())).unwrap();
        locus_replay::Log::mrclam(&dataset, robot).unwrap().odometry[0].time
    };
    let (t1, t2, t3) = (first(1), first(2), first(3));
    cut_log(1, &a, |_, t| t < t1 + 150.0);
    cut_log(2, &b, |_, t| t < t2 + 150.0);
    cut_log(3, &one, |kind, t| kind != "odometry" || t <= t3);
    let s = |p: &Path| p.to_str().unwrap().to_owned();

    let both = tune_run(&[&s(&a), &s(&b)]);
    assert!(
        both.status.success(),
        "{}",
        String::from_utf8_lossy(&both.stderr)
    );
    let both = String::from_utf8(both.stdout).unwrap();
    let three = tune_run(&[&s(&a), &s(&b), &s(&one)]);
    let err = String::from_utf8_lossy(&three.stderr);
    assert!(three.status.success(), "{err}");
    let text = String::from_utf8(three.stdout).unwrap();
    // Named, with the cause, and left out: the values are those of the two
    // logs that have an estimate.
    assert!(
        err.contains("one.csv") && err.contains("left out") && err.contains("odometry"),
        "{err}"
    );
    for label in LABELS {
        assert_eq!(tuned(&text, label), tuned(&both, label), "{label}\n{text}");
    }
    // Its row shows no made-up RMSE.
    let row = text
        .lines()
        .find(|l| l.starts_with('│') && l.contains("one.csv"))
        .unwrap_or_else(|| panic!("no row for one.csv:\n{text}"));
    assert!(row.contains("n/a") && !row.contains("0.000"), "{row}");

    // Alone: the run fails naming the log and the cause.
    let alone = tune_run(&[&s(&one)]);
    let err = String::from_utf8_lossy(&alone.stderr);
    assert!(
        !alone.status.success(),
        "{}",
        String::from_utf8_lossy(&alone.stdout)
    );
    assert!(err.contains("one.csv") && err.contains("odometry"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
