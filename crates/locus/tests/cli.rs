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
