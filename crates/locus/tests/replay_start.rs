//! `locus replay` on a user's own log: no start pose and no ground truth.
//! The log is MRCLAM dataset 6's robot 3, exported to Locus CSV (with no
//! `start` line) and stripped of its `truth` lines.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn locus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .output()
        .expect("run locus")
}

fn ok(o: Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).expect("utf-8")
}

fn metrics(out: &Path) -> serde_json::Value {
    serde_json::from_str(&fs::read_to_string(out.join("metrics.json")).expect("metrics.json"))
        .expect("JSON")
}

/// The log without the lines whose kind is in `drop`.
fn without(text: &str, drop: &[&str]) -> String {
    text.lines()
        .filter(|l| !drop.iter().any(|k| l.starts_with(&format!("{k},"))))
        .map(|l| format!("{l}\n"))
        .collect()
}

#[test]
fn a_log_with_no_start_replays_from_its_sightings_and_a_wrong_start_is_named() {
    let data = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/mrclam/MRCLAM_Dataset6"
    );
    let dir = std::env::temp_dir().join(format!("locus-replay-start-{}", std::process::id()));
    fs::create_dir_all(&dir).unwrap();
    let path = |name: &str| -> PathBuf { dir.join(name) };
    let s = |p: &Path| p.to_str().expect("utf-8").to_owned();
    // Flags that keep the runs comparable and quick: the delay the log's
    // own estimate finds (docs/replay.md).
    let fixed = ["--no-plots", "--no-estimate", "--odometry-delay", "0.2"];

    let export = path("robot3.csv");
    ok(locus(&[
        "replay",
        "mrclam",
        data,
        "--robot",
        "3",
        "--export",
        &s(&export),
        "--out",
        &s(&path("export")),
        "--no-plots",
    ]));
    let full = fs::read_to_string(&export).unwrap();
    // MRCLAM gives no start pose: the replay takes the truth's.
    assert!(!full.contains("\nstart,") && full.contains("\ntruth,"));

    // No start, no truth: the first sightings fix the start, and the
    // figures that need the truth read n/a.
    let bare = path("bare.csv");
    fs::write(&bare, without(&full, &["truth"])).unwrap();
    let out = ok(locus(
        &[
            &["replay", "csv", &s(&bare), "--out", &s(&path("bare"))][..],
            &fixed,
        ]
        .concat(),
    ));
    assert!(out.contains("initial pose from the first"), "{out}");
    let m = metrics(&path("bare"));
    assert_eq!(
        m["replay"]["start"]["from"], "sightings",
        "{}",
        m["replay"]["start"]
    );
    assert!(m["replay"]["start"]["std"][0].as_f64().unwrap() > 0.0);
    assert!(m["filter"]["position_rmse_m"].is_null());

    // The same start with the truth kept (to score it) is as accurate as
    // the true start: within 5 % of its position RMSE.
    let scored = |file: &Path, out: &str, extra: &[&str]| -> serde_json::Value {
        ok(locus(
            &[
                &["replay", "csv", &s(file), "--out", &s(&path(out))][..],
                &fixed,
                extra,
            ]
            .concat(),
        ));
        metrics(&path(out))
    };
    let from_truth = scored(&export, "truth", &[]);
    let from_sightings = scored(&export, "sightings", &["--start-from-sightings"]);
    assert_eq!(from_truth["replay"]["start"]["from"], "truth");
    assert_eq!(from_sightings["replay"]["start"]["from"], "sightings");
    let (a, b) = (
        from_sightings["filter"]["position_rmse_m"]
            .as_f64()
            .unwrap(),
        from_truth["filter"]["position_rmse_m"].as_f64().unwrap(),
    );
    println!(
        "robot 3, position RMSE from the sightings' start {a:.4} m, from the true start {b:.4} m"
    );
    assert!(a <= 1.05 * b, "{a} against {b}");
    assert_eq!(
        from_sightings["replay"]["start"]["pose"], m["replay"]["start"]["pose"],
        "the same fix with or without the truth in the log"
    );

    // A start record that contradicts the first sightings is named; one
    // that agrees is not.
    let fix = &m["replay"]["start"]["pose"];
    let t0 = bare_text_first_odometry(&fs::read_to_string(&bare).unwrap());
    for (name, dx, dtheta, warned) in [("wrong", 3.0, 1.5, true), ("right", 0.0, 0.0, false)] {
        let file = path(&format!("{name}.csv"));
        let start = format!(
            "start,{t0},{},{},{}\n",
            fix[0].as_f64().unwrap() + dx,
            fix[1].as_f64().unwrap(),
            fix[2].as_f64().unwrap() + dtheta
        );
        fs::write(&file, start + &fs::read_to_string(&bare).unwrap()).unwrap();
        let out = ok(locus(
            &[
                &["replay", "csv", &s(&file), "--out", &s(&path(name))][..],
                &fixed,
            ]
            .concat(),
        ));
        assert_eq!(
            out.contains("warning: the log's start pose"),
            warned,
            "{name}: {out}"
        );
        assert_eq!(metrics(&path(name))["replay"]["start"]["from"], "log");
    }
    let _ = fs::remove_dir_all(&dir);
}

/// The time of the first odometry line, s.
fn bare_text_first_odometry(text: &str) -> f64 {
    let line = text
        .lines()
        .find(|l| l.starts_with("odometry,"))
        .expect("odometry");
    line.split(',')
        .nth(1)
        .expect("time")
        .parse()
        .expect("number")
}
