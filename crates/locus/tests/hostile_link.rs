//! `locus robot` refuses timing and limit flags that would switch off its
//! safety (a NaN watchdog never fires, a negative one never lets the wheels
//! move) before it binds a socket or waits for a host.

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
