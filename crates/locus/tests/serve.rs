//! `locus serve` as a process: binds loopback by default, prints its
//! address, serves the page and the health route, refuses non-square
//! scenarios with a clear message.
#![allow(clippy::std_instead_of_core)]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::process::{Command, Stdio};
use std::time::Duration;

fn get(addr: &str, path: &str) -> String {
    let mut s = TcpStream::connect(addr).expect("connect to locus serve");
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut out = String::new();
    s.read_to_string(&mut out).unwrap();
    out
}

#[test]
fn serve_binds_loopback_and_serves_the_page() {
    let help = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["serve", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8_lossy(&help.stdout);
    assert!(help.contains("[default: 127.0.0.1:8080]"), "{help}");

    let mut child = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["serve", "--addr", "127.0.0.1:0", "square-ideal"])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line
        .split("http://")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_string();
    assert!(addr.starts_with("127.0.0.1:"), "{line}");
    assert!(line.contains("scenario square-ideal"), "{line}");
    let page = get(&addr, "/");
    let health = get(&addr, "/api/health");
    let _ = child.kill();
    let _ = child.wait();
    assert!(page.starts_with("HTTP/1.1 200"), "{page}");
    assert!(page.contains("Locus teaching UI"));
    assert!(health.contains("\"sessions\":0"), "{health}");
}

#[test]
fn serve_refuses_other_scenario_kinds() {
    let out = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["serve", "--addr", "127.0.0.1:0", "wall45"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("square-kind scenarios"), "{err}");
    let out = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["serve", "--addr", "127.0.0.1:0", "no-such"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown scenario"));
}
