//! `locus robot --serial` and `locus host --robot serial:` as a user runs
//! them, over real pseudo-terminals: each process opens the slave end of
//! its own pty pair by path, and this test joins the two master ends (the
//! cable). The host drives the two laps over the serial line and reports
//! a clean link.

extern crate alloc;

use alloc::sync::Arc;
use core::sync::atomic::{AtomicBool, Ordering};
use core::time::Duration;
use std::io::{Read, Write};
use std::process::Command;
use std::thread;

use serialport::{SerialPort, TTYPort};

/// Copies `from` to `to` until `stop` (read errors: the far end not
/// opened yet, or closed); the bytes and frame delimiters (`0x00`) it
/// carried.
fn cable(
    mut from: TTYPort,
    mut to: TTYPort,
    stop: Arc<AtomicBool>,
) -> thread::JoinHandle<(u64, u64)> {
    thread::spawn(move || {
        let mut buf = [0u8; 512];
        let (mut bytes, mut zeros) = (0u64, 0u64);
        from.set_timeout(Duration::from_millis(5)).unwrap();
        while !stop.load(Ordering::Relaxed) {
            match from.read(&mut buf) {
                Ok(n) => {
                    bytes += n as u64;
                    zeros += buf[..n].iter().filter(|&&b| b == 0).count() as u64;
                    let _ = to.write_all(&buf[..n]);
                }
                Err(_) => thread::sleep(Duration::from_millis(1)),
            }
        }
        (bytes, zeros)
    })
}

#[test]
fn robot_and_host_run_the_square_over_a_serial_line() {
    let (robot_master, robot_slave) = TTYPort::pair().expect("pty pair");
    let (host_master, host_slave) = TTYPort::pair().expect("pty pair");
    let robot_dev = robot_slave.name().expect("pty path");
    let host_dev = host_slave.name().expect("pty path");
    let stop = Arc::new(AtomicBool::new(false));
    let up = cable(
        robot_master.try_clone_native().unwrap(),
        host_master.try_clone_native().unwrap(),
        stop.clone(),
    );
    let down = cable(host_master, robot_master, stop.clone());
    // The processes open the slaves by path; ours close (an open slave
    // held here would keep exclusive access from them).
    drop((robot_slave, host_slave));
    let robot = thread::spawn(move || {
        Command::new(env!("CARGO_BIN_EXE_locus"))
            // As the UDP test: 50x, with an idle exit a busy machine
            // cannot reach before the laps end.
            .args([
                "robot",
                "--serial",
                &robot_dev,
                "--time-scale",
                "50",
                "--idle-exit",
                "100",
            ])
            .output()
            .expect("run locus robot")
    });
    let host = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args([
            "host",
            "--robot",
            &format!("serial:{host_dev}"),
            "--baud",
            "230400",
        ])
        .output()
        .expect("run locus host");
    let robot = robot.join().unwrap();
    stop.store(true, Ordering::Relaxed);
    let ((up_bytes, up_zeros), (down_bytes, _)) = (up.join().unwrap(), down.join().unwrap());
    // Each frame is 0x00, COBS (no zero), 0x00; the robot sends only
    // telemetry.
    let carried = up_zeros / 2;
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
    assert!(
        host_out.contains("serial ") && host_out.contains("2 laps"),
        "{host_out}"
    );
    // A clean line: nothing lost, corrupt, malformed or dropped.
    let row = |label: &str| {
        host_out
            .lines()
            .find(|l| l.contains(label))
            .unwrap_or_else(|| panic!("no row {label}: {host_out}"))
            .to_string()
    };
    let applied = row("packets applied / lost");
    let sent: u64 = robot_out
        .split(" telemetry packets sent")
        .next()
        .and_then(|s| s.rsplit(' ').next())
        .and_then(|s| s.parse().ok())
        .unwrap_or_else(|| panic!("{robot_out}"));
    // Every frame the cable carried was applied, none lost. Once the
    // robot's process has ended and closed its pty, a poll on the master
    // reports a hangup beside the bytes still waiting there, and
    // serialport's read then refuses to read them (a UART would send what
    // was written whatever its writer does next). So the frames the robot
    // wrote in its last milliseconds may never cross the cable: as many as
    // the cable thread lagged behind, a few on a busy machine.
    assert!(
        applied.contains(&format!("| {carried} / 0 / 0 / 0")),
        "{applied} vs {carried} frames carried, {sent} sent"
    );
    assert!(
        carried <= sent && 100 * (sent - carried) <= sent,
        "{carried} frames carried of {sent} sent"
    );
    assert!(
        row("packets corrupt / malformed").contains("| 0 / 0"),
        "{host_out}"
    );
    assert!(
        row("serial frames dropped").contains("| 0 / 0"),
        "{host_out}"
    );
    assert!(
        up_bytes > 40 * sent && down_bytes > 0,
        "{up_bytes} {down_bytes}"
    );
}
