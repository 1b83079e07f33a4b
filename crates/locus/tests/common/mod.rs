//! Helpers shared by the `locus` binary's integration tests.

use std::io::Read as _;
use std::process::{Command, Stdio};
use std::time::Instant;

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
