//! Helpers shared by the `locus` binary's integration tests (each test
//! crate uses some of them).
#![allow(dead_code)]

use core::fmt::Write as _;
use std::io::Read as _;
use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::Instant;

/// Runs `locus` with `args`, asserts it succeeds (naming the arguments,
/// with its standard output and error otherwise) and returns its standard
/// output.
pub fn locus_ok(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .output()
        .expect("run locus");
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "locus {args:?} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// Runs `locus` with `args` and asserts it fails within `secs` seconds
/// (killed there: a regression must not run for minutes, fill the disk or
/// leave a serial line waiting), returning its standard error.
pub fn fails_within(args: &[&str], secs: f64) -> String {
    let mut child = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(args)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn locus");
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed().as_secs_f64() > secs {
            let _ = child.kill();
            let _ = child.wait();
            panic!("{args:?} still running after {secs} s (the value was accepted)");
        }
        std::thread::sleep(core::time::Duration::from_millis(10));
    };
    let mut err = String::new();
    child
        .stderr
        .take()
        .expect("stderr")
        .read_to_string(&mut err)
        .expect("read stderr");
    assert!(!status.success(), "{args:?} succeeded:\n{err}");
    err
}

/// A fresh temporary directory for one test: `locus-test-NAME-PID`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("locus-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// A robot driving a circular arc (0.2 m/s, 0.1 rad/s) for 10 s at 50 Hz,
/// with exact sightings of three landmarks every 0.5 s (57 in all) and,
/// with `truth`, the exact ground truth. `extra` is inserted after the
/// 13th measurement line; returns the text and the line number `extra`
/// starts on (1-based).
pub fn arc_log(truth: bool, extra: &str) -> (String, usize) {
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
