//! Issue 20, "Tools and files": hostile input to the command-line tools
//! must never freeze them, corrupt their outputs or report a false figure.
//! One test per class of the issue; each names the behaviour it guards.

mod common;

use core::time::Duration;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::Instant;

fn locus(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .output()
        .expect("run locus")
}

/// A fresh scratch directory for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("locus-hostile-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `dt = 1e-12` wrote 1.6 GB of log in 15 s; a 50 MB array took 2.7 GB and
/// then reported "line 0, column 0". The number of steps is bounded up
/// front, scenario files are read up to a stated size, and a parse error
/// carries the real line and column.
#[test]
fn absurd_runs_and_huge_files_are_refused_up_front_with_a_real_position() {
    let dir = scratch("absurd");
    let out = dir.join("out");
    let tiny = dir.join("tiny-dt.toml");
    std::fs::write(&tiny, "scenario = \"square\"\ndt = 1e-12\n").unwrap();
    let err = common::fails_within(&["run", s(&tiny), "--no-plots", "--out", s(&out)], 10.0);
    assert!(
        err.contains("tiny-dt.toml") && err.contains("`dt`"),
        "{err}"
    );
    assert!(err.contains("steps"), "the bound is stated: {err}");
    assert!(!out.join("log.csv").exists(), "no step was logged");
    // --laps that would make the run absurd is refused the same way.
    let err = common::fails_within(
        &[
            "run",
            "square",
            "--laps",
            "5000",
            "--no-plots",
            "--out",
            s(&out),
        ],
        10.0,
    );
    assert!(err.contains("--laps") && err.contains("steps"), "{err}");

    // A wrong-length array: the position of its key, not line 0.
    let bad = dir.join("long-array.toml");
    std::fs::write(
        &bad,
        "scenario = \"square\"\n\nstart = [1.0, 2.0, 3.0, 4.0]\n",
    )
    .unwrap();
    let err = common::fails_within(&["run", s(&bad), "--no-plots", "--out", s(&out)], 10.0);
    assert!(err.contains("line 3, column 1"), "{err}");
    assert!(err.contains("`start`"), "{err}");
    assert!(!err.contains("line 0"), "{err}");

    // A huge file is refused before it is parsed, naming the file.
    let huge = dir.join("huge.toml");
    let mut text = String::from("scenario = \"square\"\nstart = [");
    text.push_str(&"1.0, ".repeat(2_000_000));
    text.push_str("1.0]\n");
    std::fs::write(&huge, text).unwrap();
    let err = common::fails_within(&["run", s(&huge), "--no-plots", "--out", s(&out)], 10.0);
    assert!(err.contains("huge.toml") && err.contains("bytes"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `wheelbase = 1e308` failed at run time with an encoder error naming
/// neither file nor field. Every numeric field has a plausible range,
/// checked before the run, and the error names file, line and field.
#[test]
fn implausible_config_values_name_file_and_field_before_the_run() {
    let dir = scratch("ranges");
    let out = dir.join("out");
    for (kind, line, field) in [
        ("square", "wheelbase = 1e308", "wheelbase"),
        ("square", "max_time = 1e300", "max_time"),
        ("square", "q11 = 1e200", "q11"),
        ("wall45", "dt = 1e308", "dt"),
        ("wall45", "speed = 1e30", "speed"),
        ("tricycle-slip", "track = 1e9", "track"),
        ("hover", "duration = 1e12", "duration"),
    ] {
        let file = dir.join(format!("{field}.toml"));
        std::fs::write(&file, format!("scenario = \"{kind}\"\n{line}\n")).unwrap();
        let err = common::fails_within(&["run", s(&file), "--no-plots", "--out", s(&out)], 10.0);
        assert!(
            err.contains(&format!("{field}.toml, line 2"))
                && err.contains(&format!("field `{field}`")),
            "{kind} {line}: {err}"
        );
        assert!(!out.join("log.csv").exists(), "{kind} {line}: no run");
    }
    // The shipped scenario files and every built-in still pass.
    for shipped in ["square", "square-ideal"] {
        let file = Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios")
            .join(format!("{shipped}.toml"));
        let o = locus(&["run", s(&file), "--print-config"]);
        assert!(o.status.success(), "{shipped}: {}", stderr(&o));
    }
    for builtin in ["square", "square-ideal", "wall45", "tricycle-slip", "hover"] {
        let o = locus(&["run", builtin, "--print-config"]);
        assert!(o.status.success(), "{builtin}: {}", stderr(&o));
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A small DOA study (2 x 1 cells, short runs) for the doa tests.
const SMALL_DOA: &str = "[grid]\nv_g_count = 2\nalpha_count = 1\nalpha_start = 25.0\n\
                         [run]\nhorizon = 0.5\n[search]\nm_cap = 0.1\n";

/// `locus doa`: `v_g_start = nan` was blamed on `grid.v_g_step` at line 0;
/// a 1e9 x 1e9 grid spun silently; `--out` was checked after the whole
/// computation; `doa merge` accepted a NaN or negative `m_zeta` and an
/// alpha the configuration does not have.
#[test]
fn doa_blames_the_right_field_and_checks_everything_before_work() {
    let dir = scratch("doa");
    let nan = dir.join("nan.toml");
    std::fs::write(&nan, "[grid]\nv_g_start = nan\n").unwrap();
    let err = common::fails_within(&["doa", s(&nan), "--out", s(&dir.join("o"))], 10.0);
    assert!(
        err.contains("nan.toml:2") && err.contains("grid.v_g_start"),
        "{err}"
    );

    let huge = dir.join("huge.toml");
    std::fs::write(
        &huge,
        "[grid]\nv_g_count = 1000000000\nalpha_count = 1000000000\n",
    )
    .unwrap();
    let err = common::fails_within(&["doa", s(&huge), "--out", s(&dir.join("o"))], 10.0);
    assert!(err.contains("huge.toml") && err.contains("cells"), "{err}");

    // --out under a regular file: refused before any cell is computed.
    let small = dir.join("small.toml");
    std::fs::write(&small, SMALL_DOA).unwrap();
    let blocker = dir.join("blocker");
    std::fs::write(&blocker, "a file").unwrap();
    let o = locus(&[
        "doa",
        s(&small),
        "--no-plots",
        "--out",
        s(&blocker.join("out")),
    ]);
    assert!(!o.status.success());
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        !stdout.contains("computed"),
        "checked after the work:\n{stdout}"
    );
    assert!(stderr(&o).contains("blocker"), "{}", stderr(&o));

    // A good shard file, then hostile copies of it.
    let shards = dir.join("shards");
    let o = locus(&["doa", s(&small), "--no-plots", "--out", s(&shards)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let good = std::fs::read_to_string(shards.join("doa.csv")).unwrap();
    let row = good.lines().nth(2).expect("a cell").to_owned();
    let fields: Vec<&str> = row.split(',').collect();
    let with = |k: usize, v: &str| {
        let mut f = fields.clone();
        f[k] = v;
        good.replace(&row, &f.join(","))
    };
    for (name, text) in [
        ("nan-m", with(5, "NaN")),
        ("negative-m", with(5, "-0.5")),
        ("foreign-alpha", with(4, "26.5")),
    ] {
        let file = dir.join(format!("{name}.csv"));
        std::fs::write(&file, text).unwrap();
        let o = locus(&[
            "doa",
            "merge",
            s(&file),
            "--config",
            s(&small),
            "--no-plots",
            "--out",
            s(&dir.join("merged")),
        ]);
        assert!(!o.status.success(), "{name} accepted");
        let err = stderr(&o);
        assert!(err.contains(&format!("{name}.csv:3")), "{name}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--ellipse-sigma -1` was refused only after a 50-lap run (here 10 laps). Float flags
/// are parsed as positive finite numbers before any work starts.
#[test]
fn float_flags_are_checked_before_any_work() {
    let dir = scratch("flags");
    let out = dir.join("out");
    for bad in ["-1", "0", "NaN", "inf"] {
        let flag = format!("--ellipse-sigma={bad}");
        let err = common::fails_within(
            &["run", "square", "--laps", "10", &flag, "--out", s(&out)],
            5.0,
        );
        assert!(err.contains("--ellipse-sigma"), "{bad}: {err}");
        assert!(!out.exists(), "{bad}: nothing written");
    }
    for args in [
        &["hw", "--clock-mhz", "0"][..],
        &["hw", "--clock-mhz", "NaN"],
        &["demo", "--ir-sigma", "inf"],
        &["demo", "--scale-error", "NaN"],
    ] {
        let err = common::fails_within(args, 5.0);
        assert!(err.contains(args[1]), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A run killed while rewriting an existing `--out` left the old
/// metrics.json and pictures beside the new partial log. The outputs a run
/// will write are cleared before it starts, so a killed run leaves no
/// finished-looking directory.
#[test]
fn a_killed_rerun_leaves_no_stale_outputs_of_the_previous_run() {
    let dir = scratch("stale");
    let out = dir.join("out");
    let o = locus(&["run", "square", "--laps", "1", "--out", s(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in ["metrics.json", "map.png", "errors.svg", "log.csv"] {
        assert!(out.join(f).exists(), "{f} after the first run");
    }
    let first_len = std::fs::metadata(out.join("log.csv")).unwrap().len();
    let mut child = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["run", "square", "--laps", "100", "--out", s(&out)])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("spawn");
    // Wait until the second run has begun its own log, then kill it.
    let start = Instant::now();
    while std::fs::metadata(out.join("log.csv")).map_or(true, |m| m.len() >= first_len) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the rerun never started"
        );
        std::thread::sleep(Duration::from_millis(5));
    }
    child.kill().expect("kill");
    child.wait().expect("wait");
    for f in [
        "metrics.json",
        "map.png",
        "map.svg",
        "errors.png",
        "covariance.svg",
    ] {
        assert!(
            !out.join(f).exists(),
            "stale {f} beside the killed run's log"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `locus hw | head -1` and `locus doa ... | head -1` panicked on the
/// broken pipe. Every command ends quietly when its reader has gone.
#[test]
fn a_closed_pipe_ends_every_command_quietly() {
    let dir = scratch("pipe");
    let small = dir.join("small.toml");
    std::fs::write(&small, SMALL_DOA).unwrap();
    let doa_out = dir.join("doa");
    for args in [
        &["hw"][..],
        &["doa", s(&small), "--no-plots", "--out", s(&doa_out)],
        &["run", "square", "--print-config"],
    ] {
        let mut child = Command::new(env!("CARGO_BIN_EXE_locus"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("spawn");
        // The reader goes away before the command has printed anything.
        drop(child.stdout.take());
        let mut err = String::new();
        child
            .stderr
            .take()
            .expect("stderr")
            .read_to_string(&mut err)
            .unwrap();
        let status = child.wait().expect("wait");
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        assert!(status.success(), "{args:?}: {status}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 34, fault 10: `locus hw --export-vectors DIR --core-vectors
/// 10000000000` aborted on a failed allocation (exit 134) and left DIR
/// partly written. Vector counts have a stated upper bound checked before
/// any work, and the error names the flag and the bound; DIR is not
/// created.
#[test]
fn huge_vector_counts_are_refused_up_front_and_leave_no_folder() {
    let dir = scratch("hw-vectors");
    let out = dir.join("vectors");
    for (flag, count) in [
        ("--core-vectors", "10000000000"),
        ("--unit-vectors", "100000000000"),
    ] {
        let err = common::fails_within(&["hw", "--export-vectors", s(&out), flag, count], 10.0);
        assert!(
            err.contains(flag) && err.contains("at most"),
            "{flag} {count}: {err}"
        );
        assert!(!err.contains("memory allocation"), "{err}");
        assert!(!out.exists(), "{flag} {count}: a folder was written");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
