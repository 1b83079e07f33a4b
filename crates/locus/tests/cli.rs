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
    let m: serde_json::Value = serde_json::from_str(&metrics).expect("metrics.json is JSON");
    assert!(
        m["filter"]["position_rmse_m"].as_f64().unwrap() > 0.0,
        "{metrics}"
    );
    assert_eq!(m["simulation"]["seed"], 1, "{metrics}");
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

/// A fresh, empty temporary directory for one test.
fn temp_dir(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("locus-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Issue 5: a run killed with SIGKILL leaves a readable `log.csv` prefix
/// (header, complete rectangular numeric lines, increasing time, at most a
/// partial last line).
#[test]
fn a_killed_run_leaves_a_readable_log_prefix() {
    use core::time::Duration;
    use std::time::Instant;

    let dir = temp_dir("killed-run");
    let log = dir.join("log.csv");
    let mut child = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["run", "--laps", "50", "--out"])
        .arg(&dir)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("start locus");
    let started = Instant::now();
    loop {
        let lines = std::fs::read(&log).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count());
        if lines > 500 {
            break;
        }
        if let Some(status) = child.try_wait().expect("poll locus") {
            panic!("locus ended ({status}) before the log grew: {lines} lines");
        }
        assert!(
            started.elapsed() < Duration::from_secs(60),
            "log.csv had {lines} lines after 60 s"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().expect("SIGKILL locus");
    let status = child.wait().expect("reap locus");
    assert!(!status.success(), "a 50-lap run cannot finish this fast");

    let bytes = std::fs::read(&log).expect("log.csv");
    let text = String::from_utf8_lossy(&bytes);
    let mut lines: Vec<&str> = text.split('\n').collect();
    // The text after the last newline is the partial line (empty if none):
    // only the last line may lack its newline.
    let partial = lines.pop().expect("split yields at least one piece");
    let header = lines.first().expect("header");
    let columns: Vec<&str> = header.split(',').collect();
    assert!(columns.len() > 10, "{header}");
    let time_col = columns
        .iter()
        .position(|c| c.starts_with("time"))
        .expect("time column");
    assert!(lines.len() > 500, "{} complete lines", lines.len());
    let mut last_time = f64::NEG_INFINITY;
    for (i, line) in lines.iter().enumerate().skip(1) {
        let fields: Vec<&str> = line.split(',').collect();
        assert_eq!(fields.len(), columns.len(), "line {}: {line}", i + 1);
        for (c, field) in fields.iter().enumerate() {
            assert!(
                field.is_empty() || field.parse::<f64>().is_ok_and(f64::is_finite),
                "line {}, column {}: `{field}`",
                i + 1,
                columns[c]
            );
        }
        for required in [0, time_col] {
            assert!(!fields[required].is_empty(), "line {}: {line}", i + 1);
        }
        let time: f64 = fields[time_col].parse().expect("time");
        assert!(
            time > last_time,
            "line {}: time {time} after {last_time}",
            i + 1
        );
        last_time = time;
    }
    // A partial line is a prefix of a row: never more columns than a row.
    assert!(
        partial.split(',').count() <= columns.len(),
        "partial line: {partial}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 5: `--runs 4` prints the Monte Carlo table and writes `runs.csv`
/// with one row per seed and an aggregate `metrics.json`.
#[test]
fn run_monte_carlo_prints_the_table_and_writes_runs_csv() {
    let dir = temp_dir("monte-carlo");
    let out = locus(&[
        "run",
        "--runs",
        "4",
        "--seed",
        "7",
        "--laps",
        "1",
        "--out",
        dir.to_str().expect("utf-8 temp dir"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    for needle in [
        "Monte Carlo over 4 runs",
        "mean",
        "std (n-1)",
        "EKF position RMSE [cm]",
        "odometry position RMSE [cm]",
        "EKF heading RMSE [deg]",
        "mean NEES",
        "updates accepted by the gate [%]",
    ] {
        assert!(stdout.contains(needle), "{needle} missing:\n{stdout}");
    }
    assert!(!dir.join("log.csv").exists(), "no step log with --runs > 1");
    let csv = std::fs::read_to_string(dir.join("runs.csv")).expect("runs.csv");
    let mut lines = csv.lines();
    let header = lines.next().expect("header");
    let columns = header.split(',').count();
    let rows: Vec<&str> = lines.collect();
    assert_eq!(rows.len(), 4, "{csv}");
    let mut seeds: Vec<u64> = rows
        .iter()
        .map(|r| {
            assert_eq!(r.split(',').count(), columns, "{r}");
            r.split(',').next().unwrap().parse().expect("seed")
        })
        .collect();
    seeds.sort_unstable();
    assert_eq!(seeds, [7, 8, 9, 10]);
    let metrics = std::fs::read_to_string(dir.join("metrics.json")).expect("metrics.json");
    let m: serde_json::Value = serde_json::from_str(&metrics).expect("metrics.json is JSON");
    assert_eq!(m["source"], "monte_carlo", "{metrics}");
    assert_eq!(m["monte_carlo"]["runs"], 4, "{metrics}");
    assert_eq!(m["monte_carlo"]["first_seed"], 7, "{metrics}");
    assert!(
        metrics.contains("\"position_rmse_m\": { \"mean\""),
        "{metrics}"
    );
    let rmse = &m["filter"]["position_rmse_m"];
    assert!(
        rmse["min"].as_f64().unwrap() <= rmse["mean"].as_f64().unwrap(),
        "{rmse}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `locus run | head`: a reader that goes away early is not an error and
/// never a panic.
#[test]
fn run_into_a_closed_pipe_exits_quietly() {
    let dir = temp_dir("broken-pipe");
    let mut child = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["run", "--laps", "1", "--out"])
        .arg(&dir)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start locus");
    // Close the read end before locus prints anything.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait for locus");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.status.success(), "{:?}: {stderr}", out.status);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 5: `locus run FILE.toml` runs a scenario file; `--print-config`
/// prints a template that runs the same; a bad file names line and field.
#[test]
fn run_a_scenario_file_and_print_its_template() {
    let dir = temp_dir("scenario-file");
    std::fs::create_dir_all(&dir).expect("temp dir");
    let template = locus(&["run", "--print-config", "square"]);
    assert!(template.status.success());
    let text = String::from_utf8(template.stdout).unwrap();
    assert!(text.contains("scenario = \"square\""), "{text}");
    let file = dir.join("one-lap.toml");
    std::fs::write(&file, text.replace("laps = 2", "laps = 1")).expect("write");
    let out = locus(&[
        "run",
        file.to_str().expect("utf-8"),
        "--out",
        dir.join("out").to_str().expect("utf-8"),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("locus run one-lap:"), "{stdout}");
    assert!(stdout.contains(", 1 laps)"), "{stdout}");

    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        "scenario = \"square\"\nlaps = 1\nwheelbase = \"wide\"\n",
    )
    .expect("write");
    let out = locus(&["run", bad.to_str().expect("utf-8")]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("bad.toml, line 3, column 13, field `wheelbase`"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 5: one run draws its pictures (PNG and SVG) unless `--no-plots`.
#[test]
fn run_writes_the_pictures_as_png_and_svg() {
    let dir = temp_dir("pictures");
    let out = locus(&["run", "--laps", "1", "--out", dir.to_str().expect("utf-8")]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for name in ["map", "errors", "covariance"] {
        let png = std::fs::read(dir.join(format!("{name}.png"))).expect("png");
        assert!(
            png.starts_with(b"\x89PNG\r\n\x1a\n"),
            "{name}.png signature"
        );
        assert!(png.len() > 10_000, "{name}.png: {} bytes", png.len());
        let svg = std::fs::read_to_string(dir.join(format!("{name}.svg"))).expect("svg");
        assert!(svg.contains("<svg"), "{name}.svg");
        assert!(
            svg.contains("[m]") || svg.contains("[s]"),
            "{name}.svg axis units"
        );
    }
    let svg = std::fs::read_to_string(dir.join("map.svg")).expect("svg");
    assert!(svg.contains("3-sigma ellipse"), "ellipse label");
    assert!(svg.contains("98.9 %"), "ellipse probability");

    // The ellipse level is a setting, labelled with its 2-D probability.
    let out = locus(&[
        "run",
        "--laps",
        "1",
        "--ellipse-sigma",
        "1",
        "--out",
        dir.to_str().expect("utf-8"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(dir.join("map.svg")).expect("svg");
    assert!(svg.contains("1-sigma ellipse"), "ellipse label");
    assert!(svg.contains("39.3 %"), "1-sigma ellipse probability");

    let bare = temp_dir("no-pictures");
    let out = locus(&[
        "run",
        "--laps",
        "1",
        "--no-plots",
        "--out",
        bare.to_str().expect("utf-8"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(bare.join("log.csv").exists());
    assert!(!bare.join("map.png").exists(), "--no-plots drew a map");
    let _ = std::fs::remove_dir_all(&dir);
    let _ = std::fs::remove_dir_all(&bare);
}

/// `locus guide` prints the steps a-f with a verdict each; on its default
/// seed every step passes (criteria of spec section 3, revised
/// 2026-12-01), so it exits with success. A failing step would print FAIL
/// and exit non-zero (the exit code is checked against the verdicts).
#[test]
fn guide_prints_every_step_and_exits_with_the_verdict() {
    let out = locus(&["guide", "--seed", "1"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    for step in ["a)", "b)", "c)", "d)", "e)", "f)"] {
        let row = stdout
            .lines()
            .find(|l| l.trim_start_matches('│').trim_start().starts_with(step))
            .unwrap_or_else(|| panic!("{step} missing:\n{stdout}"));
        assert!(row.contains("PASS"), "{step} does not pass:\n{stdout}");
    }
    assert_eq!(stdout.matches("FAIL").count(), 0, "{stdout}");
    // The thresholds stay visible in the table (spec: [assumed], keep them
    // in view), among them the revised a) and e); tokens without spaces,
    // which the table's wrapping keeps whole.
    for criterion in ["perm|P|", "10x", "0.9;", "c's"] {
        assert!(stdout.contains(criterion), "{criterion} missing:\n{stdout}");
    }
    assert!(!stdout.contains("note: e)"), "{stdout}");
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(!stderr.contains("failed their criterion"), "{stderr}");
}

/// Parses a column (1-based after the label) of a table row starting with
/// `label` as a number.
fn column(stdout: &str, label: &str, col: usize) -> f64 {
    let row = stdout
        .lines()
        .find(|l| l.contains(label))
        .unwrap_or_else(|| panic!("no row `{label}`:\n{stdout}"));
    row.split('┆')
        .nth(col)
        .expect("column")
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("not a number in `{row}`"))
}

#[test]
fn the_papers_other_scenarios_run_from_their_names_and_from_files() {
    for (scenario, estimator, odometry) in [
        ("wall45", "EKF (odometry + laser)", true),
        ("tricycle-slip", "EKF (rear odometry + laser)", true),
        ("hover", "6-DOF estimator (camera marks)", false),
    ] {
        let dir = temp_dir(&format!("scenario-{scenario}"));
        let out = locus(&[
            "run",
            scenario,
            "--no-plots",
            "--out",
            dir.to_str().unwrap(),
        ]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success(),
            "{scenario}: {}\n{stdout}",
            String::from_utf8_lossy(&out.stderr)
        );
        let ekf = column(&stdout, estimator, 1);
        assert!(ekf.is_finite() && ekf > 0.0, "{scenario}: {stdout}");
        if odometry {
            // Each scenario's filter beats its odometry alone on position.
            assert!(
                ekf < column(&stdout, "odometry alone", 1),
                "{scenario}: {stdout}"
            );
        } else {
            assert!(stdout.contains("n/a"), "{scenario}: {stdout}");
        }
        // The log has a header and one row per step, all of the same width.
        let log = std::fs::read_to_string(dir.join("log.csv")).unwrap();
        let mut lines = log.lines();
        let width = lines.next().unwrap().split(',').count();
        let rows: Vec<_> = lines.collect();
        assert!(rows.len() > 10, "{scenario}: {} rows", rows.len());
        assert!(rows.iter().all(|r| r.split(',').count() == width));

        // Its --print-config template is a scenario file that runs the same.
        std::fs::create_dir_all(&dir).unwrap();
        let template = locus(&["run", scenario, "--print-config"]);
        assert!(template.status.success());
        let file = dir.join(format!("{scenario}.toml"));
        std::fs::write(&file, &template.stdout).unwrap();
        let again = locus(&[
            "run",
            file.to_str().unwrap(),
            "--no-plots",
            "--out",
            dir.join("again").to_str().unwrap(),
        ]);
        assert!(
            again.status.success(),
            "{}",
            String::from_utf8_lossy(&again.stderr)
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("again").join("log.csv")).unwrap(),
            log,
            "{scenario}: the template file does not reproduce the built-in run"
        );
    }
}

#[test]
fn tricycle_slip_prints_rear_only_and_slip_rejecting_odometry() {
    let dir = temp_dir("tricycle-both");
    let out = locus(&[
        "run",
        "tricycle-slip",
        "--no-plots",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    let rear_only = column(&stdout, "odometry alone", 1);
    let line = stdout
        .lines()
        .find(|l| l.starts_with("slip-rejecting odometry alone"))
        .unwrap_or_else(|| panic!("no slip-rejecting line:\n{stdout}"));
    let slip_rejecting: f64 = line
        .split("position RMSE ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("no figure in `{line}`"));
    assert!(
        slip_rejecting < rear_only,
        "slip-rejecting {slip_rejecting} cm vs rear-only {rear_only} cm"
    );
}

#[test]
fn a_bad_value_in_a_wall45_file_names_the_line_and_field() {
    let dir = temp_dir("wall45-bad");
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("bad.toml");
    std::fs::write(&file, "scenario = \"wall45\"\ndt = 0.1\nmax_range = -3.0\n").unwrap();
    let out = locus(&["run", file.to_str().unwrap(), "--no-plots"]);
    assert!(!out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("line 3") && stderr.contains("max_range"),
        "{stderr}"
    );
}

#[test]
fn reproduce_table3_prints_the_paper_beside_both_models() {
    let out = locus(&["reproduce", "table3"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}\n{stdout}",
        String::from_utf8_lossy(&out.stderr)
    );
    for row in [
        "paper: real",
        "paper: EKF",
        "Locus: paper H",
        "Locus: exact",
        "Locus: odometry",
    ] {
        assert_eq!(
            stdout.matches(row).count(),
            6,
            "`{row}` should appear at each of the six instants:\n{stdout}"
        );
    }
}

/// `locus robot` and `locus host` talk over loopback: the host drives the
/// two laps and reports a clean link; the robot reports its watchdog stop.
#[test]
fn robot_and_host_run_the_square_over_udp() {
    // A free port for the robot (released, then bound by the robot).
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let addr = format!("127.0.0.1:{port}");
    let robot_addr = addr.clone();
    let robot = std::thread::spawn(move || {
        Command::new(env!("CARGO_BIN_EXE_locus"))
            // At 50x a default idle exit (2 s of robot time) is 40 ms of
            // wall time: a test machine busy with the other tests can
            // starve the host that long. 100 s of robot time is 2 s of wall
            // time; the run still ends on its own after the laps.
            .args([
                "robot",
                "--udp",
                &robot_addr,
                "--time-scale",
                "50",
                "--idle-exit",
                "100",
            ])
            .output()
    });
    let host = locus(&["host", "--robot", &addr]);
    let robot = robot.join().unwrap().unwrap();
    let host_out = String::from_utf8_lossy(&host.stdout);
    let robot_out = String::from_utf8_lossy(&robot.stdout);
    assert!(
        host.status.success(),
        "{}",
        String::from_utf8_lossy(&host.stderr)
    );
    assert!(
        robot.status.success(),
        "{}",
        String::from_utf8_lossy(&robot.stderr)
    );
    assert!(host_out.contains("2 laps"), "{host_out}");
    assert!(
        host_out.contains("| packets corrupt / malformed [count]"),
        "{host_out}"
    );
    assert!(robot_out.contains("watchdog stops"), "{robot_out}");
}

/// `locus replay`: MRCLAM robot 4 exported to a Locus CSV log and replayed
/// from it gives the same table; a missing file and a malformed line are
/// named.
#[test]
fn replay_mrclam_and_its_csv_export_agree_and_errors_name_the_file() {
    let data = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/mrclam/MRCLAM_Dataset6"
    );
    let dir = std::env::temp_dir().join(format!("locus-cli-replay-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("robot4.csv");
    let (csv_s, out_a, out_b) = (
        csv.to_str().unwrap(),
        dir.join("a").to_str().unwrap().to_owned(),
        dir.join("b").to_str().unwrap().to_owned(),
    );
    let a = locus(&[
        "replay",
        "mrclam",
        data,
        "--robot",
        "4",
        "--export",
        csv_s,
        "--out",
        &out_a,
        "--no-plots",
    ]);
    assert!(a.status.success(), "{}", String::from_utf8_lossy(&a.stderr));
    let a = String::from_utf8(a.stdout).unwrap();
    let ekf = rmse_x(&a, "EKF (odometry + landmarks)");
    let odo = rmse_x(&a, "odometry alone");
    assert!(ekf < odo, "{a}");
    let b = locus(&["replay", "csv", csv_s, "--out", &out_b, "--no-plots"]);
    assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr));
    let b = String::from_utf8(b.stdout).unwrap();
    assert_eq!(ekf, rmse_x(&b, "EKF (odometry + landmarks)"));
    assert!(std::path::Path::new(&out_b).join("metrics.json").is_file());

    // --smooth: the smoother's row in the table, one smoothed.csv row per
    // event; a later run without it removes the stale smoothed.csv.
    let s = locus(&[
        "replay",
        "csv",
        csv_s,
        "--out",
        &out_b,
        "--no-plots",
        "--smooth",
    ]);
    assert!(s.status.success(), "{}", String::from_utf8_lossy(&s.stderr));
    let s = String::from_utf8(s.stdout).unwrap();
    assert!(s.contains("│ smoother"), "{s}");
    let smoothed = std::path::Path::new(&out_b).join("smoothed.csv");
    let rows = std::fs::read_to_string(&smoothed).unwrap();
    let log_rows = std::fs::read_to_string(std::path::Path::new(&out_b).join("log.csv")).unwrap();
    assert!(rows.starts_with("index,time_s,x_m,y_m,theta_rad,"));
    assert_eq!(rows.lines().count(), log_rows.lines().count());
    assert!(
        locus(&["replay", "csv", csv_s, "--out", &out_b, "--no-plots"])
            .status
            .success()
    );
    assert!(!smoothed.exists(), "stale smoothed.csv left behind");

    let missing = dir.join("none.csv");
    let e = locus(&["replay", "csv", missing.to_str().unwrap()]);
    assert!(!e.status.success());
    let stderr = String::from_utf8(e.stderr).unwrap();
    assert!(stderr.contains("none.csv: not found"), "{stderr}");
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "landmark,6,1,2\nodometry,0,0.1\n").unwrap();
    let e = locus(&["replay", "csv", bad.to_str().unwrap()]);
    let stderr = String::from_utf8(e.stderr).unwrap();
    assert!(
        stderr.contains("bad.csv:2: field \"omega\" (column 4): missing"),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
