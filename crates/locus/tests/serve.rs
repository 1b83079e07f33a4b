//! `locus serve` as a process: binds loopback by default, prints its
//! address, serves the page and the health route, refuses non-square
//! scenarios with a clear message; `--robot` attaches it to a `locus robot`
//! process over UDP, and a missing serial device is named.
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

/// Reads one unmasked server frame's payload from a WebSocket stream
/// (RFC 6455 section 5.2: FIN/opcode byte, length 7 bits, or 126 + 16
/// bits, or 127 + 64 bits).
fn ws_frame(s: &mut TcpStream) -> (u8, Vec<u8>) {
    let mut head = [0u8; 2];
    s.read_exact(&mut head).unwrap();
    let len = match head[1] & 0x7f {
        126 => {
            let mut b = [0u8; 2];
            s.read_exact(&mut b).unwrap();
            u64::from(u16::from_be_bytes(b))
        }
        127 => {
            let mut b = [0u8; 8];
            s.read_exact(&mut b).unwrap();
            u64::from_be_bytes(b)
        }
        n => u64::from(n),
    };
    let mut payload = vec![0u8; usize::try_from(len).unwrap()];
    s.read_exact(&mut payload).unwrap();
    (head[0] & 0x0f, payload)
}

/// `locus serve --robot ADDR` with `locus robot --udp ADDR` as processes:
/// the banner names the robot, the WebSocket's hello is the robot's, and
/// state frames count the packets the host applied.
#[test]
fn serve_attaches_to_a_robot_process_over_udp() {
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let robot_addr = format!("127.0.0.1:{port}");
    let mut robot = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["robot", "--udp", &robot_addr, "--time-scale", "5"])
        .args(["--idle-exit", "20"])
        .stdout(Stdio::null())
        .spawn()
        .unwrap();
    let mut serve = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args(["serve", "--addr", "127.0.0.1:0", "--robot", &robot_addr])
        .stdout(Stdio::piped())
        .spawn()
        .unwrap();
    let mut line = String::new();
    BufReader::new(serve.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line
        .split("http://")
        .nth(1)
        .and_then(|r| r.split('/').next())
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .to_string();
    let check = || -> Result<(), String> {
        if !line.contains(&format!("attached to the robot at {robot_addr}")) {
            return Err(format!("banner: {line}"));
        }
        let mut s = TcpStream::connect(&addr).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
        write!(
            s,
            "GET /ws HTTP/1.1\r\nHost: {addr}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
             Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n"
        )
        .unwrap();
        let mut head = Vec::new();
        while !head.ends_with(b"\r\n\r\n") {
            let mut b = [0u8; 1];
            s.read_exact(&mut b).unwrap();
            head.push(b[0]);
        }
        let head = String::from_utf8_lossy(&head);
        if !head.starts_with("HTTP/1.1 101") {
            return Err(format!("upgrade: {head}"));
        }
        let (_, hello) = ws_frame(&mut s);
        let hello = String::from_utf8_lossy(&hello).into_owned();
        if !hello.contains(&format!("\"link\":\"udp {robot_addr}\""))
            || !hello.contains("\"ground_truth\":false")
        {
            return Err(format!("hello: {hello}"));
        }
        for _ in 0..400 {
            let (op, frame) = ws_frame(&mut s);
            let text = String::from_utf8_lossy(&frame);
            if op == 1 && text.contains("\"type\":\"state\"") && !text.contains("\"applied\":0,") {
                return Ok(());
            }
        }
        Err("no state frame with applied packets".into())
    };
    let result = check();
    let _ = serve.kill();
    let _ = serve.wait();
    let _ = robot.kill();
    let _ = robot.wait();
    result.unwrap();
}

#[test]
fn serve_with_a_missing_serial_device_fails_and_names_it() {
    let out = Command::new(env!("CARGO_BIN_EXE_locus"))
        .args([
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--robot",
            "serial:/dev/locus-no-such-tty",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("/dev/locus-no-such-tty"), "{err}");
}
