//! The `locus` binary as a user runs it.

use std::process::Command;

fn locus(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .output()
        .expect("run locus")
}

/// Parses the RMSE x column [cm] of a table row starting with `label`.
fn rmse_x(stdout: &str, label: &str) -> f64 {
    let row = stdout.lines().find(|l| l.contains(label)).expect("row");
    row.split('┆')
        .nth(1)
        .expect("column")
        .trim()
        .parse()
        .expect("number")
}

#[test]
fn demo_runs_and_the_ekf_beats_odometry_alone() {
    let out = locus(&["demo", "--seed", "3"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    let ekf = rmse_x(&stdout, "EKF (odometry + IR)");
    let odo = rmse_x(&stdout, "odometry alone");
    assert!(
        ekf < 0.5 * odo,
        "EKF {ekf} cm vs odometry {odo} cm\n{stdout}"
    );
    assert!(stdout.contains("NIS consistency"), "{stdout}");
    // Reproducible from its seed.
    let again = String::from_utf8(locus(&["demo", "--seed", "3"]).stdout).unwrap();
    assert_eq!(stdout, again);
}

#[test]
fn bad_arguments_are_reported_with_a_nonzero_exit() {
    let out = locus(&["demo", "--ir-sigma=-1"]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--ir-sigma"));
    let help = locus(&["demo", "--help"]);
    assert!(help.status.success());
    assert!(String::from_utf8_lossy(&help.stdout).contains("Seed"));
}

#[test]
fn run_square_prints_the_table_and_writes_a_rectangular_csv() {
    let dir = std::env::temp_dir().join(format!("locus-run-cli-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out_dir = dir.to_str().expect("utf-8 temp dir");
    // No scenario argument: `square` by default.
    let start = std::time::Instant::now();
    let out = locus(&["run", "--out", out_dir]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(start.elapsed().as_secs() < 60, "took {:?}", start.elapsed());
    let stdout = String::from_utf8(out.stdout).unwrap();
    for needle in [
        "EKF (odometry + IR)",
        "odometry alone",
        "position RMSE [cm]",
        "mean NEES",
    ] {
        assert!(stdout.contains(needle), "{needle} missing:\n{stdout}");
    }
    let ekf = rmse_x(&stdout, "EKF (odometry + IR)");
    let odo = rmse_x(&stdout, "odometry alone");
    assert!(
        ekf < 0.5 * odo,
        "EKF {ekf} cm vs odometry {odo} cm\n{stdout}"
    );

    let csv = std::fs::read_to_string(dir.join("log.csv")).expect("log.csv");
    let mut lines = csv.lines();
    let header = lines.next().expect("header");
    let columns = header.split(',').count();
    assert!(columns > 10, "{header}");
    let mut rows = 0;
    for (i, line) in lines.enumerate() {
        assert_eq!(line.split(',').count(), columns, "line {}: {line}", i + 2);
        rows += 1;
    }
    assert!(rows > 1000, "{rows} rows");
    let metrics = std::fs::read_to_string(dir.join("metrics.json")).expect("metrics.json");
    assert!(metrics.contains("\"ekf_position_rmse_m\""), "{metrics}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_with_an_unknown_scenario_names_the_supported_ones() {
    let out = locus(&["run", "no-such-scenario"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("no-such-scenario"), "{stderr}");
    assert!(stderr.contains("supported scenarios: square"), "{stderr}");
}
