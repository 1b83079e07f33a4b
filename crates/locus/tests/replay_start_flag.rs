//! `locus replay --start X,Y,THETA`: a user says where the robot starts,
//! over the log's start record; a malformed pose is refused with the flag
//! named.

mod common;

use std::fs;

/// The first row of `log.csv` in `out`: x, y, theta (m, m, rad).
fn first_pose(out: &std::path::Path) -> [f64; 3] {
    let text = fs::read_to_string(out.join("log.csv")).expect("log.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let row: Vec<&str> = lines.next().expect("a row").split(',').collect();
    ["x_m", "y_m", "theta_rad"].map(|name| {
        let k = header.iter().position(|h| *h == name).expect(name);
        row[k].parse().expect("a number")
    })
}

#[test]
fn the_start_flag_replaces_the_logs_start() {
    let dir = common::scratch("start-flag");
    let (text, _) = common::arc_log(true, "");
    let log = dir.join("arc.csv");
    fs::write(&log, text).unwrap();
    let s = |p: &std::path::Path| p.to_str().expect("utf-8").to_owned();
    let (log, out) = (s(&log), dir.join("out"));
    let fixed = ["--no-plots", "--no-estimate", "--out"];
    common::locus_ok(&[
        "replay",
        "csv",
        &log,
        fixed[0],
        fixed[1],
        fixed[2],
        &s(&out),
    ]);
    assert_eq!(first_pose(&out), [0.0, 0.0, 0.0]);
    common::locus_ok(&[
        "replay",
        "csv",
        &log,
        "--start",
        "0.3,-0.2,-0.1",
        "--initial-std",
        "0.5,0.5,0.2",
        fixed[0],
        fixed[1],
        fixed[2],
        &s(&out),
    ]);
    assert_eq!(first_pose(&out), [0.3, -0.2, -0.1]);
    let err = common::fails_within(&["replay", "csv", &log, "--start", "0.3,-0.2"], 30.0);
    assert!(
        err.contains("--start") && err.contains("expected three values"),
        "{err}"
    );
}
