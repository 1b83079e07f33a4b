//! Foxglove out (issue 30): `--mcap OUT.mcap` of `locus run` and `locus
//! replay` read back by the `mcap` Python package and every message
//! validated against Foxglove's published schemas, fetched from the npm
//! package itself (`scripts/foxglove_check.py`); and the live Foxglove
//! WebSocket of `locus host --foxglove` and `locus serve --robot
//! --foxglove`, with a real client on loopback against `locus robot`.
//! Python comes from `LOCUS_PYTHON`, else `python3`, with
//! scripts/requirements-crosscheck.txt installed (scripts/test.sh does).

mod common;

use core::time::Duration;
use std::io::{BufRead, BufReader};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::Instant;

use common::{arc_log, locus_ok, scratch};
use serde_json::Value;

/// `scripts/foxglove_check.py` on `mcap`: its report, asserting it passed.
fn check(mcap: &Path) -> Value {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let python = std::env::var("LOCUS_PYTHON").unwrap_or_else(|_| "python3".to_owned());
    let out = Command::new(&python)
        .arg(root.join("scripts/foxglove_check.py"))
        .arg(mcap)
        .arg("--cache")
        .arg(root.join("target/foxglove-schemas"))
        .output()
        .unwrap_or_else(|e| panic!("cannot run {python}: {e}"));
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "scripts/foxglove_check.py failed on {}:\n{report}\n{}",
        mcap.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_str(&report).unwrap()
}

/// Rows of a `log.csv` (its header left out).
fn rows(csv: &Path) -> u64 {
    std::fs::read_to_string(csv).unwrap().lines().count() as u64 - 1
}

fn topic<'a>(report: &'a Value, name: &str) -> &'a Value {
    &report["topics"][name]
}

fn assert_channel(report: &Value, name: &str, schema: &str, count: u64) {
    let t = topic(report, name);
    assert_eq!(t["schema"], schema, "{name}: {t}");
    assert_eq!(t["message_encoding"], "json", "{name}");
    assert_eq!(t["schema_encoding"], "jsonschema", "{name}");
    assert_eq!(t["count"], count, "{name}: {t}");
    assert_eq!(t["invalid"], 0, "{name}: {t}");
}

#[test]
fn a_simulated_run_as_mcap_reads_back_as_valid_foxglove() {
    let dir = scratch("foxglove-run");
    let mcap = dir.join("wall45.mcap");
    let out = locus_ok(&[
        "run",
        "wall45",
        "--no-plots",
        "--out",
        dir.to_str().unwrap(),
        "--mcap",
        mcap.to_str().unwrap(),
    ]);
    assert!(
        out.contains(&format!("mcap: {} (/locus/estimate 220", mcap.display())),
        "{out}"
    );
    assert!(!dir.join("wall45.mcap.partial").exists());
    let steps = rows(&dir.join("log.csv"));
    assert_eq!(steps, 220);
    let report = check(&mcap);
    for (name, schema) in [
        ("/locus/estimate", "foxglove.PoseInFrame"),
        ("/locus/truth", "foxglove.PoseInFrame"),
        ("/locus/odometry", "foxglove.PoseInFrame"),
        ("/tf", "foxglove.FrameTransform"),
        ("/locus/covariance", "foxglove.SceneUpdate"),
        ("/locus/errors", "locus.Errors"),
    ] {
        assert_channel(&report, name, schema, steps);
    }
    // wall45 corrects at every step.
    assert_channel(&report, "/locus/nis", "locus.Nis", steps);
    assert_channel(&report, "/locus/map", "foxglove.SceneUpdate", 1);
    assert_channel(&report, "/locus/summary", "foxglove.Log", 1);
    assert_eq!(report["summary_message_count"], 6 * steps + steps + 2);
    // More than one run is refused, naming the flag.
    let err = common::fails_within(
        &[
            "run",
            "wall45",
            "--runs",
            "2",
            "--mcap",
            mcap.to_str().unwrap(),
        ],
        60.0,
    );
    assert!(err.contains("--mcap writes a single run"), "{err}");
}

#[test]
fn a_replay_as_mcap_has_a_step_per_row_and_the_landmarks() {
    let dir = scratch("foxglove-replay");
    let (log, _) = arc_log(true, "");
    let csv = dir.join("arc.csv");
    std::fs::write(&csv, log).unwrap();
    let mcap = dir.join("arc.mcap");
    let out = locus_ok(&[
        "replay",
        "csv",
        csv.to_str().unwrap(),
        "--no-plots",
        "--out",
        dir.join("out").to_str().unwrap(),
        "--mcap",
        mcap.to_str().unwrap(),
    ]);
    assert!(out.contains("mcap: "), "{out}");
    let steps = rows(&dir.join("out/log.csv"));
    let report = check(&mcap);
    assert_channel(&report, "/locus/estimate", "foxglove.PoseInFrame", steps);
    assert_channel(&report, "/locus/errors", "locus.Errors", steps);
    assert_channel(&report, "/locus/map", "foxglove.SceneUpdate", 1);
    // 57 sightings, each a correction with its NIS.
    assert_channel(&report, "/locus/nis", "locus.Nis", 57);
    assert_channel(&report, "/locus/summary", "foxglove.Log", 1);
}

/// Kills the processes when dropped (a failing test leaves none behind).
struct Processes(Vec<Child>);

impl Drop for Processes {
    fn drop(&mut self) {
        for c in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn free_udp() -> String {
    let port = std::net::UdpSocket::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    format!("127.0.0.1:{port}")
}

fn robot(addr: &str) -> Child {
    Command::new(env!("CARGO_BIN_EXE_locus"))
        .args([
            "robot",
            "--udp",
            addr,
            "--time-scale",
            "5",
            "--idle-exit",
            "20",
        ])
        .stdout(Stdio::null())
        .spawn()
        .unwrap()
}

/// The address in the first line of `child`'s output that names
/// `ws://...`, reading at most `lines` lines.
fn ws_address(child: &mut Child, lines: usize) -> String {
    let mut out = BufReader::new(child.stdout.take().unwrap());
    for _ in 0..lines {
        let mut line = String::new();
        out.read_line(&mut line).unwrap();
        if let Some(rest) = line.split("ws://").nth(1) {
            return rest.split('/').next().unwrap().to_string();
        }
    }
    panic!("no ws:// address in the first {lines} lines");
}

/// A Foxglove client: connects with the protocol's subprotocol, reads the
/// server info and the channels, subscribes to the estimate, covariance
/// and map, and returns the first `n` messages received (topic, payload),
/// each validated against its channel's advertised schema.
fn foxglove_client(addr: &str, n: usize) -> Vec<(String, Value)> {
    use tungstenite::client::IntoClientRequest;
    let mut req = format!("ws://{addr}/").into_client_request().unwrap();
    req.headers_mut().insert(
        "Sec-WebSocket-Protocol",
        "foxglove.websocket.v1".parse().unwrap(),
    );
    let deadline = Instant::now() + Duration::from_secs(30);
    let (mut ws, response) = loop {
        match tungstenite::connect(req.clone()) {
            Ok(c) => break c,
            Err(e) if Instant::now() < deadline => {
                let _ = e;
                std::thread::sleep(Duration::from_millis(50));
            }
            Err(e) => panic!("connecting to ws://{addr}/: {e}"),
        }
    };
    assert_eq!(
        response.headers()["Sec-WebSocket-Protocol"],
        "foxglove.websocket.v1"
    );
    let text = |ws: &mut tungstenite::WebSocket<_>| -> Value {
        match ws.read().unwrap() {
            tungstenite::Message::Text(t) => serde_json::from_str(t.as_str()).unwrap(),
            other => panic!("expected text, got {other:?}"),
        }
    };
    let info = text(&mut ws);
    assert_eq!(info["op"], "serverInfo");
    let ad = text(&mut ws);
    assert_eq!(ad["op"], "advertise");
    let channels = ad["channels"].as_array().unwrap().clone();
    let find = |topic: &str| {
        channels
            .iter()
            .find(|c| c["topic"] == topic)
            .unwrap()
            .clone()
    };
    let wanted = [
        find("/locus/estimate"),
        find("/locus/covariance"),
        find("/locus/map"),
    ];
    let subs: Vec<Value> = wanted
        .iter()
        .enumerate()
        .map(|(i, c)| serde_json::json!({"id": 10 + i, "channelId": c["id"]}))
        .collect();
    ws.send(tungstenite::Message::Text(
        serde_json::json!({"op": "subscribe", "subscriptions": subs})
            .to_string()
            .into(),
    ))
    .unwrap();
    let mut got = Vec::new();
    while got.len() < n {
        let bytes = match ws.read().unwrap() {
            tungstenite::Message::Binary(b) => b,
            tungstenite::Message::Text(t) => panic!("unexpected status: {t}"),
            _ => continue,
        };
        assert_eq!(bytes[0], 1, "message data opcode");
        let sub = u32::from_le_bytes(bytes[1..5].try_into().unwrap()) as usize;
        let channel = &wanted[sub - 10];
        let payload: Value = serde_json::from_slice(&bytes[13..]).unwrap();
        let schema: Value = serde_json::from_str(channel["schema"].as_str().unwrap()).unwrap();
        let v = jsonschema::validator_for(&schema).unwrap();
        assert!(v.is_valid(&payload), "{}: {payload}", channel["topic"]);
        got.push((channel["topic"].as_str().unwrap().to_string(), payload));
    }
    got
}

fn assert_live(got: &[(String, Value)]) {
    // The latched map comes on subscribing; the estimate and its ellipse
    // follow every applied packet.
    let map = got
        .iter()
        .find(|(t, _)| t == "/locus/map")
        .expect("the map");
    assert_eq!(
        map.1["entities"][0]["lines"][0]["points"]
            .as_array()
            .unwrap()
            .len(),
        8
    );
    let estimates: Vec<&Value> = got
        .iter()
        .filter(|(t, _)| t == "/locus/estimate")
        .map(|(_, v)| v)
        .collect();
    assert!(estimates.len() >= 5, "{got:?}");
    assert!(got.iter().any(|(t, _)| t == "/locus/covariance"));
    for e in estimates {
        let x = e["pose"]["position"]["x"].as_f64().unwrap();
        assert!(x.is_finite() && e["frame_id"] == "map");
    }
}

#[test]
fn locus_host_serves_the_live_estimate_to_a_foxglove_client() {
    let robot_addr = free_udp();
    let mut ps = Processes(vec![robot(&robot_addr)]);
    ps.0.push(
        Command::new(env!("CARGO_BIN_EXE_locus"))
            .args(["host", "--robot", &robot_addr, "--foxglove", "127.0.0.1:0"])
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let addr = ws_address(&mut ps.0[1], 1);
    assert!(addr.starts_with("127.0.0.1:"), "{addr}");
    assert_live(&foxglove_client(&addr, 12));
}

#[test]
fn locus_serve_with_a_robot_serves_foxglove_beside_the_page() {
    let robot_addr = free_udp();
    let mut ps = Processes(vec![robot(&robot_addr)]);
    ps.0.push(
        Command::new(env!("CARGO_BIN_EXE_locus"))
            .args([
                "serve",
                "--addr",
                "127.0.0.1:0",
                "--robot",
                &robot_addr,
                "--foxglove",
                "127.0.0.1:0",
            ])
            .stdout(Stdio::piped())
            .spawn()
            .unwrap(),
    );
    let addr = ws_address(&mut ps.0[1], 2);
    // The page's host starts stopped: the robot still reports, so the
    // estimate flows (standing still) before anyone presses Start.
    assert_live(&foxglove_client(&addr, 12));
}
