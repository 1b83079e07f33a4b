//! `locus family` (issue 27): the simulated family replayed with no flags
//! and as an honest reference. What holds today is asserted: the
//! reference (true noise, delay and calibration) is honest on the members
//! whose errors are white, and the no-flags replay is what `locus replay
//! csv FILE` does; and the no-flags replay meets issue 27's criteria on
//! the members without correlated errors.

use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

/// Members with white sighting noise, range-bearing records (v2) and a
/// truth without a heading offset: the reference must be honest on them.
const WHITE: [&str; 5] = [
    "sonar-slow-1hz",
    "noisy-wheels-100hz",
    "one-landmark",
    "outliers-5pct",
    "commanded-lag-0.2s",
];

/// Durations scaled to half (150-300 s of simulated time each).
const SCALE: &str = "0.5";

/// Runs `locus family` on `members` into `out` with `extra` arguments and
/// returns the rows of family.csv by `(member, replay)`.
fn family(
    out: &Path,
    members: &[&str],
    extra: &[&str],
) -> HashMap<(String, String), HashMap<String, String>> {
    let mut args = vec!["family", "--scale", SCALE, "--out"];
    let dir = out.to_str().unwrap();
    args.push(dir);
    for m in members {
        args.extend(["--member", m]);
    }
    args.extend(extra);
    let output = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(&args)
        .output()
        .expect("locus runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    println!("{stdout}");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let text = std::fs::read_to_string(out.join("family.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let mut rows = HashMap::new();
    for line in lines {
        let fields: HashMap<String, String> = header
            .iter()
            .cloned()
            .zip(line.split(',').map(str::to_string))
            .collect();
        rows.insert((fields["member"].clone(), fields["replay"].clone()), fields);
    }
    assert!(out.join("family.md").is_file());
    rows
}

fn value(row: &HashMap<String, String>, column: &str) -> f64 {
    row[column]
        .parse()
        .unwrap_or_else(|_| panic!("{column}: {:?} is not a number", row[column]))
}

fn out_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("locus-family-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

#[test]
fn the_reference_is_honest_on_members_with_white_noise() {
    let dir = out_dir("reference");
    let rows = family(&dir, &WHITE, &[]);
    for m in WHITE {
        let r = &rows[&(m.to_string(), "reference".to_string())];
        assert_eq!(r["status"], "ok", "{m}");
        for axis in ["x", "y", "theta"] {
            let share = value(r, &format!("within_3sigma_{axis}"));
            assert!(
                share >= 0.9,
                "{m}: reference inside 3 sigma in {axis}: {share}"
            );
        }
        let nees = value(r, "mean_nees");
        assert!(nees <= 4.5, "{m}: reference mean NEES {nees}");
        // The reference replays with the truth.
        for name in [
            "q_v_m2_per_s",
            "q_omega_rad2_per_s",
            "sigma_range_m",
            "sigma_bearing_rad",
            "odometry_delay_s",
        ] {
            assert_eq!(
                value(r, name),
                value(r, &format!("true_{name}")),
                "{m} {name}"
            );
        }
    }
    // The no-flags replay is `locus replay csv FILE` with no flags: the
    // same figures from the kept log.
    let m = "noisy-wheels-100hz";
    let replay_out = dir.join("replay");
    let output = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["replay", "csv"])
        .arg(dir.join(format!("{m}.csv")))
        .arg("--out")
        .arg(&replay_out)
        .arg("--no-plots")
        .output()
        .unwrap();
    assert!(output.status.success());
    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(replay_out.join("metrics.json")).unwrap())
            .unwrap();
    let no_flags = &rows[&(m.to_string(), "no-flags".to_string())];
    for (csv, section, json) in [
        ("position_rmse_m", "filter", "position_rmse_m"),
        ("heading_rmse_rad", "filter", "heading_rmse_rad"),
        ("mean_nees", "filter", "mean_nees"),
        ("q_v_m2_per_s", "replay", "q_v_m2_per_s"),
        ("odometry_delay_s", "replay", "odometry_delay_s"),
    ] {
        assert_eq!(
            value(no_flags, csv),
            metrics[section][json].as_f64().unwrap(),
            "{csv}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unknown_member_is_an_error_naming_the_members() {
    let output = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["family", "--member", "no-such-robot", "--out"])
        .arg(out_dir("unknown"))
        .output()
        .unwrap();
    assert!(!output.status.success());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(stderr.contains("no member no-such-robot") && stderr.contains("laser-5hz-offset"));
}

/// Members on which the no-flags replay meets issue 27's criteria at
/// full length: every member but correlated-only-15hz, whose bearing noise
/// level the log shows is 1.38x the truth (docs/replay.md: the smoother's
/// own uncertainty, added back to the residuals' spread, is that of the
/// widened noise and so too large when the noise is this small).
const MEETING: [&str; 10] = [
    "laser-5hz-offset",
    "camera-correlated",
    "outliers-5pct",
    "sonar-slow-1hz",
    "precise-30hz",
    "noisy-wheels-100hz",
    "uwb-beacons",
    "one-landmark",
    "commanded-lag-0.2s",
    "wide-range-2hz",
];

/// Issue 27's target for `locus replay csv FILE` with no flags, judged by
/// the runner on each member: each 3-sigma share >= 90 % and mean NEES
/// <= 4.5 (about the truth's heading offset where it has one), position
/// RMSE <= 1.15 times the reference's, each noise level the log tells
/// (standard error within 15 %) within +-30 % of the truth.
#[test]
fn the_no_flags_replay_meets_issue_27() {
    let dir = out_dir("no-flags");
    let mut args = vec!["family", "--out", dir.to_str().unwrap()];
    for m in MEETING {
        args.extend(["--member", m]);
    }
    let output = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(&args)
        .output()
        .expect("locus runs");
    let stdout = String::from_utf8_lossy(&output.stdout);
    println!("{stdout}");
    assert!(output.status.success());
    for m in MEETING {
        let line = stdout
            .lines()
            .find(|l| l.trim_start().starts_with(&format!("{m} ")))
            .unwrap_or_else(|| panic!("no criteria line for {m}"));
        assert!(line.trim_end().ends_with(" met"), "{line}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
