//! `locus robot` refuses timing and limit flags that would switch off its
//! safety (a NaN watchdog never fires, a negative one never lets the wheels
//! move) before it binds a socket or waits for a host.

mod common;

use std::process::Command;

#[test]
fn robot_flags_that_would_disable_its_safety_are_refused_at_start() {
    for (flag, value) in [
        ("--watchdog", "NaN"),
        ("--watchdog", "inf"),
        ("--watchdog", "-1"),
        ("--idle-exit", "NaN"),
        ("--time-scale", "0"),
        ("--max-wheel-speed", "inf"),
        ("--handshake", "NaN"),
    ] {
        // A port that is taken: a run that got as far as binding would fail
        // with "binding UDP", not with the flag's name.
        let taken = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
        let addr = taken.local_addr().unwrap().to_string();
        let out = Command::new(env!("CARGO_BIN_EXE_locus"))
            .args(["robot", "--udp", &addr, &format!("{flag}={value}")])
            .output()
            .expect("run locus");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{flag} {value} accepted");
        let name = flag.trim_start_matches("--").replace('-', "_");
        assert!(
            stderr.contains(&name) && !stderr.contains("binding UDP"),
            "{flag} {value}: {stderr}"
        );
    }
}

/// Issue 34, fault 11: `--baud 0` (on a real serial line, speed 0 means
/// hang up) and `--baud 4000000000` were accepted by `locus host --robot
/// serial:` and `locus robot --serial`, which then waited on the line. A
/// speed outside what UARTs use is refused at argument parsing, naming the
/// flag and the accepted range, before the device is opened.
#[test]
fn serial_speeds_no_uart_uses_are_refused_naming_the_flag_and_range() {
    use serialport::{SerialPort, TTYPort};
    // A real pseudo-terminal: a run that accepted the speed would open it
    // and wait for the far end.
    let (_master, slave) = TTYPort::pair().expect("pty pair");
    let device = slave.name().expect("pty path");
    drop(slave);
    let serial = format!("serial:{device}");
    for baud in ["0", "4000000000", "49"] {
        for args in [
            ["host", "--robot", serial.as_str(), "--baud", baud],
            ["robot", "--serial", device.as_str(), "--baud", baud],
        ] {
            let err = common::fails_within(&args, 5.0);
            assert!(
                err.contains("--baud") && err.contains("50") && err.contains("4000000"),
                "{args:?}: {err}"
            );
        }
    }
}

/// Issue 34, fault 12: when the robot went quiet before the laps were
/// done (a dropped link, a stream without frame delimiters), `locus host`
/// printed "0 laps" and exited 0, as for a completed run. A robot killed
/// mid-run over a real loopback socket: the host still prints what it
/// received, then fails, saying how long the robot was silent, what was
/// received and that the run is incomplete.
#[test]
fn a_robot_that_goes_silent_before_the_end_fails_the_host_run() {
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let addr = format!("127.0.0.1:{port}");
    // Real time: two laps of the square take far longer than the test
    // lets the robot live.
    let mut robot = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["robot", "--udp", &addr])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .expect("spawn locus robot");
    let host = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["host", "--robot", &addr])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn locus host");
    std::thread::sleep(core::time::Duration::from_secs(3));
    robot.kill().expect("kill the robot");
    robot.wait().expect("reap the robot");
    let host = host.wait_with_output().expect("host output");
    let out = String::from_utf8_lossy(&host.stdout);
    let err = String::from_utf8_lossy(&host.stderr);
    assert!(
        !host.status.success(),
        "an incomplete run exited 0:\n{out}\n{err}"
    );
    assert!(
        err.contains("silent") && err.contains("incomplete") && err.contains("packets"),
        "{err}"
    );
    // What was received is still printed.
    assert!(out.contains("packets applied / lost"), "{out}");
}
