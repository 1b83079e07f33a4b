//! Helpers shared by the socket tests, the load test and the load bench:
//! an in-process server on 127.0.0.1:0, a raw HTTP GET, the process RSS.
#![allow(dead_code, clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

use std::net::SocketAddr;

use tokio::io::{AsyncReadExt, AsyncWriteExt};

pub mod load;

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
