//! Helpers shared by the socket tests, the load test and the load bench:
//! an in-process server on 127.0.0.1:0 (or one attached to a simulated
//! robot on loopback UDP), a raw HTTP GET, the process RSS.
#![allow(dead_code, clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

use std::net::SocketAddr;

use tokio::io::{AsyncReadExt, AsyncWriteExt};

pub mod browser;
pub mod load;

/// Starts `locus_serve::serve_with_robot`, attached over loopback UDP to
/// the robot at `robot` (a host session with the `square` robot's filter
/// and controller, laps without end), on an ephemeral loopback port in
/// the current runtime; returns its address.
pub async fn start_robot_server(robot: SocketAddr) -> SocketAddr {
    let mut cfg = locus_simlink::host_config(&locus_sim::SquareConfig::default());
    cfg.laps = usize::MAX;
    let link = locus_serve::robot::Link::udp("127.0.0.1:0".parse().unwrap(), robot).unwrap();
    let attached =
        locus_serve::robot::Attached::start(link, &cfg, 0.01, std::time::Duration::from_millis(50))
            .unwrap();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
        .await
        .expect("bind 127.0.0.1:0");
    let addr = listener.local_addr().expect("local addr");
    tokio::spawn(locus_serve::serve_with_robot(
        listener,
        locus_serve::Config::default(),
        attached,
    ));
    addr
}

/// A simulated robot on loopback UDP in its own thread (detached: it ends
/// `idle_exit` robot seconds after the host stops sending); its address.
pub fn spawn_robot(time_scale: f64) -> std::net::SocketAddr {
    let socket = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    let addr = socket.local_addr().unwrap();
    let cfg = locus_simlink::RobotConfig {
        square: locus_sim::SquareConfig {
            max_time: 5000.0,
            ..locus_sim::SquareConfig::default()
        },
        time_scale,
        // Generous for a loaded machine: the host answers every packet.
        idle_exit: 30.0,
        handshake: std::time::Duration::from_secs(60),
        ..locus_simlink::RobotConfig::default()
    };
    std::thread::spawn(move || locus_simlink::run_robot(&socket, &cfg));
    addr
}

/// Starts `locus_serve::serve` with `config` on an ephemeral loopback port
/// in the current runtime; returns its address.
pub async fn start_server(config: locus_serve::Config) -> SocketAddr {
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0")
        .await
        .expect("bind 127.0.0.1:0");
    let addr = listener.local_addr().expect("local addr");
    tokio::spawn(async move {
        locus_serve::serve(listener, config).await.expect("serve");
    });
    addr
}

/// `GET path` over a plain TCP connection; returns (status, body).
pub async fn http_get(addr: SocketAddr, path: &str) -> (u16, String) {
    let mut s = tokio::net::TcpStream::connect(addr).await.expect("connect");
    let req = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    s.write_all(req.as_bytes()).await.expect("write");
    let mut out = Vec::new();
    s.read_to_end(&mut out).await.expect("read");
    let text = String::from_utf8_lossy(&out).into_owned();
    let status = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or(0);
    let body = text.split("\r\n\r\n").nth(1).unwrap_or("").to_string();
    (status, body)
}

/// The live session count from `/api/health`.
pub async fn sessions(addr: SocketAddr) -> u64 {
    let (status, body) = http_get(addr, "/api/health").await;
    assert_eq!(status, 200, "health: {body}");
    // The body may be chunked: take the JSON object.
    let start = body.find('{').expect("json");
    let end = body.rfind('}').expect("json");
    let v: serde_json::Value = serde_json::from_str(&body[start..=end]).expect("health json");
    v["sessions"].as_u64().expect("sessions")
}

/// Resident set size of this process (kB), from /proc/self/status.
pub fn rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmRSS:"))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        })
        .unwrap_or(0)
}
