//! The server without a browser: routes through `app()` with no socket
//! (tower's `oneshot`), sessions driven directly, and the WebSocket on a
//! real loopback socket (origin check, size and rate limits, session
//! count); plus the vendored chart library against the npm lock.
#![allow(clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

mod support;

use std::time::{Duration, Instant};

use axum::body::Body;
use axum::http::{Request, StatusCode, header};
use futures_util::{SinkExt, StreamExt};
use locus_serve::protocol::ServerMsg;
use locus_serve::session::Session;
use locus_serve::{Config, Limits, app};
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;
use tower::ServiceExt;

async fn get(path: &str, headers: &[(&str, &str)]) -> (StatusCode, axum::http::HeaderMap, Vec<u8>) {
    let mut req = Request::builder().uri(path);
    for (k, v) in headers {
        req = req.header(*k, *v);
    }
    let resp = app(Config::default())
        .oneshot(req.body(Body::empty()).unwrap())
        .await
        .unwrap();
    let status = resp.status();
    let h = resp.headers().clone();
    let body = axum::body::to_bytes(resp.into_body(), 1 << 22)
        .await
        .unwrap();
    (status, h, body.to_vec())
}

#[tokio::test]
async fn page_and_embedded_assets() {
    let (s, h, body) = get("/", &[]).await;
    assert_eq!(s, StatusCode::OK);
    assert!(
        h[header::CONTENT_TYPE]
            .to_str()
            .unwrap()
            .starts_with("text/html")
    );
    assert!(h.contains_key(header::CONTENT_SECURITY_POLICY));
    let html = String::from_utf8(body).unwrap();
    assert!(html.contains("/assets/vendor/uPlot.iife.min.js"));
    assert!(!html.contains("https://"), "no CDN: every asset is local");
    for (path, mime) in [
        ("/assets/app.js", "text/javascript"),
        ("/assets/style.css", "text/css"),
        ("/assets/vendor/uPlot.iife.min.js", "text/javascript"),
        ("/assets/vendor/uPlot.min.css", "text/css"),
        ("/assets/favicon.svg", "image/svg+xml"),
    ] {
        let (s, h, body) = get(path, &[]).await;
        assert_eq!(s, StatusCode::OK, "{path}");
        assert!(
            h[header::CONTENT_TYPE].to_str().unwrap().starts_with(mime),
            "{path}"
        );
        assert!(!body.is_empty(), "{path}");
    }
    let (s, _, _) = get("/assets/../Cargo.toml", &[]).await;
    assert_eq!(s, StatusCode::NOT_FOUND);
    let (s, _, _) = get("/assets/nope.js", &[]).await;
    assert_eq!(s, StatusCode::NOT_FOUND);
}

#[tokio::test]
async fn health_counts_sessions() {
    let (s, _, body) = get("/api/health", &[]).await;
    assert_eq!(s, StatusCode::OK);
    let v: Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(v, json!({"sessions": 0, "max_sessions": 64}));
}

const UPGRADE: [(&str, &str); 4] = [
    ("connection", "upgrade"),
    ("upgrade", "websocket"),
    ("sec-websocket-version", "13"),
    ("sec-websocket-key", "dGhlIHNhbXBsZSBub25jZQ=="),
];

#[tokio::test]
async fn websocket_with_a_foreign_origin_is_refused() {
    for origin in [
        "http://evil.example",
        "http://127.0.0.1:9999",
        "https://localhost:8080",
        "null",
    ] {
        let mut h = UPGRADE.to_vec();
        h.push(("host", "localhost:8080"));
        h.push(("origin", origin));
        let (s, _, body) = get("/ws", &h).await;
        assert_eq!(s, StatusCode::FORBIDDEN, "{origin}");
        assert!(String::from_utf8_lossy(&body).contains("foreign Origin"));
    }
    // DNS rebinding: a foreign name that now resolves to this server sends
    // matching Origin and Host; a domain name is refused.
    for host in [
        "evil.example:8080",
        "evil.example",
        "rebind.127.0.0.1.nip.io:8080",
    ] {
        let mut h = UPGRADE.to_vec();
        h.push(("host", host));
        let origin = format!("http://{host}");
        h.push(("origin", &origin));
        let (s, _, _) = get("/ws", &h).await;
        assert_eq!(s, StatusCode::FORBIDDEN, "{host}");
    }
    // The page's own origin passes the check (without a real connection the
    // upgrade itself cannot complete: not a 403), by localhost or by address.
    for host in [
        "localhost:8080",
        "127.0.0.1:8080",
        "[::1]:8080",
        "192.168.1.20:8080",
    ] {
        let mut h = UPGRADE.to_vec();
        h.push(("host", host));
        let origin = format!("http://{host}");
        h.push(("origin", &origin));
        let (s, _, _) = get("/ws", &h).await;
        assert_ne!(s, StatusCode::FORBIDDEN, "{host}");
    }
}

fn session() -> Session {
    Session::new(
        1,
        "square",
        &locus_sim::SquareConfig::default(),
        1,
        Limits::default(),
    )
    .unwrap()
}

fn errors(out: &[ServerMsg]) -> Vec<(String, String)> {
    out.iter()
        .filter_map(|m| match m {
            ServerMsg::Error { field, message } => Some((field.clone(), message.clone())),
            _ => None,
        })
        .collect()
}

#[test]
fn bad_values_are_refused_by_name_and_nothing_is_applied() {
    let mut s = session();
    let now = Instant::now();
    let before = *s.config();
    for (msg, field) in [
        (json!({"type": "params", "values": {"r11": "abc"}}), "r11"),
        (
            json!({"type": "params", "values": {"r11": "1e-4", "q22": "1e999"}}),
            "q22",
        ),
        (json!({"type": "params", "values": {"r22": -1}}), "r22"),
        (json!({"type": "params", "values": {"v_ref": 100}}), "v_ref"),
        (json!({"type": "params", "values": {"gate": 1.5}}), "gate"),
        (
            json!({"type": "params", "values": {"use_ir": "maybe"}}),
            "use_ir",
        ),
        (json!({"type": "params", "values": {"dt": 1}}), "dt"),
        (
            json!({"type": "params", "values": {"r11": 1e-4, "ir_noise": 0.01}}),
            "ir_noise",
        ),
        (
            json!({"type": "initial", "values": {"start_z": 0}}),
            "start_z",
        ),
        // Outside the limits the simulator shares (locus_models::settings).
        (
            json!({"type": "params", "values": {"ir_sigma": 0.2}}),
            "ir_sigma",
        ),
        (json!({"type": "speed", "factor": 0}), "speed"),
        (json!({"type": "teleop", "v": 5, "w": 0}), "teleop_v"),
        (json!({"type": "initial", "values": {"std_x": 0}}), "std_x"),
        (json!({"type": "preset", "step": "z"}), "preset"),
        (json!({"type": "scenario", "name": "wall45"}), "scenario"),
        (json!({"type": "launch_missiles"}), "message"),
        (json!({"type": "start", "bogus": 1}), "bogus"),
        (json!({"no": "type"}), "message"),
    ] {
        let out = s.handle_text(&msg.to_string(), now);
        let e = errors(&out);
        assert_eq!(e.len(), 1, "{msg}: {out:?}");
        assert_eq!(e[0].0, field, "{msg}: {}", e[0].1);
    }
    assert_eq!(*s.config(), before, "nothing applied");
    let out = s.handle_text("{not json", now);
    assert_eq!(errors(&out)[0].0, "message");
}

#[test]
fn live_parameters_apply_to_the_running_simulation() {
    let mut s = session();
    let now = Instant::now();
    let out = s.handle_text(
        &json!({"type": "params", "values": {"r11": "1e-4", "r22": 1e-4, "q11": "1e-7", "v_ref": 0.2, "gate": 0}}).to_string(),
        now,
    );
    assert!(errors(&out).is_empty(), "{out:?}");
    let c = s.config();
    assert_eq!(
        (c.r11, c.r22, c.q11, c.control.v_ref),
        (1e-4, 1e-4, 1e-7, 0.2)
    );
    assert_eq!(c.gate_confidence, None);
    // They survive a reset; the initial values apply there.
    s.handle_text(
        &json!({"type": "initial", "values": {"start_x": -0.8, "std_x": 0.05}}).to_string(),
        now,
    );
    assert_eq!(
        s.config().start[0],
        -0.85,
        "initial values wait for the reset"
    );
    s.handle_text(&json!({"type": "reset"}).to_string(), now);
    assert_eq!(s.config().r11, 1e-4);
    assert_eq!(s.config().start[0], -0.8);
    assert_eq!(s.config().initial_std[0], 0.05);
}

#[test]
fn ticks_run_at_the_speed_factor_and_export_the_log() {
    let mut s = session();
    let now = Instant::now();
    assert!(
        s.tick(Duration::from_millis(50), now).is_none(),
        "paused: no frame"
    );
    s.handle_text(r#"{"type":"speed","factor":"4"}"#, now);
    s.handle_text(r#"{"type":"start"}"#, now);
    // 1 s of wall clock at 4x = 4 s of simulated time = 400 steps.
    for _ in 0..20 {
        let Some(ServerMsg::State { samples, .. }) = s.tick(Duration::from_millis(50), now) else {
            panic!("a state frame while running");
        };
        assert_eq!(samples.len(), 20);
    }
    assert_eq!(s.steps(), 400);
    s.handle_text(r#"{"type":"stop"}"#, now);
    let out = s.handle_text(r#"{"type":"export"}"#, now);
    let Some(ServerMsg::Csv {
        csv,
        truncated,
        filename,
    }) = out.into_iter().next()
    else {
        panic!("a csv answer");
    };
    assert!(!truncated);
    assert!(filename.ends_with(".csv"));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], locus_sim::StepRecord::CSV_COLUMNS.join(","));
    assert_eq!(lines.len(), 401);
}

#[test]
fn teleoperation_times_out_and_step_correction_stops_at_one() {
    let mut s = session();
    let t0 = Instant::now();
    s.handle_text(r#"{"type":"teleop","v":0,"w":"1"}"#, t0);
    s.handle_text(r#"{"type":"start"}"#, t0);
    let Some(ServerMsg::State { teleop, .. }) = s.tick(Duration::from_millis(50), t0) else {
        panic!()
    };
    assert!(teleop);
    let later = t0 + Duration::from_secs(1);
    let Some(ServerMsg::State { teleop, .. }) = s.tick(Duration::from_millis(50), later) else {
        panic!()
    };
    assert!(!teleop, "no repeat for 1 s: back to the controller");

    let out = s.handle_text(r#"{"type":"step_correction"}"#, later);
    let Some(ServerMsg::State {
        correction,
        running,
        ..
    }) = out.into_iter().next()
    else {
        panic!()
    };
    assert!(!running);
    let d = correction.expect("a correction within 10 s");
    assert!(d.nis.is_finite() && d.s[0][0] > 0.0);
}

#[test]
fn presets_load_the_guide_steps() {
    let mut s = session();
    let now = Instant::now();
    let out = s.handle_text(r#"{"type":"preset","step":"e"}"#, now);
    assert!(errors(&out).is_empty());
    assert_eq!((s.config().q11, s.config().q22), locus_sim::guide::Q_HUGE);
    let Some(ServerMsg::Params { preset, .. }) = out.first() else {
        panic!()
    };
    assert_eq!(*preset, Some('e'));
    s.handle_text(r#"{"type":"start"}"#, now);
    let Some(ServerMsg::State { figure, .. }) = s.tick(Duration::from_millis(200), now) else {
        panic!()
    };
    let f = figure.expect("the preset's live figure");
    assert_eq!(f.step, 'e');
    assert!(
        f.measured.contains("mean wall-coordinate gain"),
        "{}",
        f.measured
    );
    // The ideal scenario has no guide.
    s.handle_text(r#"{"type":"scenario","name":"square-ideal"}"#, now);
    let out = s.handle_text(r#"{"type":"preset","step":"a"}"#, now);
    assert_eq!(errors(&out)[0].0, "preset");
}

async fn connect(
    addr: std::net::SocketAddr,
    origin: Option<&str>,
) -> Result<
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>,
    tokio_tungstenite::tungstenite::Error,
> {
    let mut req = format!("ws://{addr}/ws").into_client_request().unwrap();
    if let Some(o) = origin {
        req.headers_mut().insert("origin", o.parse().unwrap());
    }
    tokio_tungstenite::connect_async(req)
        .await
        .map(|(ws, _)| ws)
}

async fn next_json(
    ws: &mut tokio_tungstenite::WebSocketStream<
        tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>,
    >,
) -> Option<Value> {
    loop {
        match tokio::time::timeout(Duration::from_secs(5), ws.next()).await {
            Ok(Some(Ok(Message::Text(t)))) => return serde_json::from_str(t.as_str()).ok(),
            Ok(Some(Ok(Message::Close(_)) | Err(_)) | None) | Err(_) => return None,
            Ok(Some(Ok(_))) => {}
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn websocket_sessions_limits_and_origin_on_a_socket() {
    let addr = support::start_server(Config::default()).await;

    // Foreign origin: the handshake is refused.
    let err = connect(addr, Some("http://evil.example"))
        .await
        .unwrap_err();
    assert!(err.to_string().contains("403"), "{err}");
    // Own origin: hello, params, state.
    let mut ws = connect(addr, Some(&format!("http://{addr}")))
        .await
        .unwrap();
    assert_eq!(next_json(&mut ws).await.unwrap()["type"], "hello");
    assert_eq!(next_json(&mut ws).await.unwrap()["type"], "params");
    assert_eq!(next_json(&mut ws).await.unwrap()["type"], "state");
    assert_eq!(support::sessions(addr).await, 1);

    // Each client has its own session.
    let mut other = connect(addr, None).await.unwrap();
    for _ in 0..3 {
        next_json(&mut other).await.unwrap();
    }
    ws.send(Message::text(
        r#"{"type":"params","values":{"r11":"4e-4"}}"#,
    ))
    .await
    .unwrap();
    let p = next_json(&mut ws).await.unwrap();
    assert_eq!(p["values"]["r11"], 4e-4);
    other
        .send(Message::text(r#"{"type":"step"}"#))
        .await
        .unwrap();
    let st = next_json(&mut other).await.unwrap();
    assert_eq!(st["steps"], 1);
    other
        .send(Message::text(r#"{"type":"params","values":{}}"#))
        .await
        .unwrap();
    let p = next_json(&mut other).await.unwrap();
    assert_eq!(p["values"]["r11"], 2.5e-5, "the other session kept its R");
    assert_eq!(support::sessions(addr).await, 2);

    // Rate: a burst far above the limit gets an error and is dropped.
    for _ in 0..300 {
        other
            .send(Message::text(r#"{"type":"stop"}"#))
            .await
            .unwrap();
    }
    let mut rate_error = false;
    while let Some(v) = next_json(&mut other).await {
        if v["type"] == "error" {
            assert!(v["message"].as_str().unwrap().contains("too many messages"));
            rate_error = true;
            break;
        }
    }
    assert!(rate_error, "the burst was not limited");

    // Size: a message over the limit closes the connection.
    let big = format!(
        r#"{{"type":"params","values":{{"r11":"{}"}}}}"#,
        "1".repeat(64 * 1024)
    );
    let _ = ws.send(Message::text(big)).await;
    let mut closed = false;
    for _ in 0..20 {
        if next_json(&mut ws).await.is_none() {
            closed = true;
            break;
        }
    }
    assert!(closed, "an oversized message closes the connection");

    drop(ws);
    drop(other);
    let start = Instant::now();
    while support::sessions(addr).await != 0 {
        assert!(
            start.elapsed() < Duration::from_secs(5),
            "sessions not released"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sessions_beyond_the_cap_are_refused() {
    let mut config = Config::default();
    config.limits.max_sessions = 2;
    let addr = support::start_server(config).await;
    let a = connect(addr, None).await.unwrap();
    let b = connect(addr, None).await.unwrap();
    let err = connect(addr, None).await.unwrap_err();
    assert!(err.to_string().contains("503"), "{err}");
    drop((a, b));
    let start = Instant::now();
    while support::sessions(addr).await != 0 {
        assert!(start.elapsed() < Duration::from_secs(5));
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert!(connect(addr, None).await.is_ok(), "a slot is free again");
}

/// The vendored uPlot is the one the npm lock pins: VENDORED records the
/// lock's version and integrity and the files' SHA-256 (scripts/vendor-ui.sh
/// writes it after `npm ci`, which checks the tarball against the lock);
/// the files must match those hashes, and, when `web/node_modules` is
/// installed, the installed package's files byte for byte.
#[test]
fn vendored_chart_library_matches_the_lock() {
    use base64::Engine as _;
    use sha2::Digest as _;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let lock: Value =
        serde_json::from_str(&std::fs::read_to_string(root.join("web/package-lock.json")).unwrap())
            .unwrap();
    let entry = &lock["packages"]["node_modules/uplot"];
    let (version, integrity) = (
        entry["version"].as_str().unwrap(),
        entry["integrity"].as_str().unwrap(),
    );
    assert!(integrity.starts_with("sha512-"));
    assert_eq!(
        base64::engine::general_purpose::STANDARD
            .decode(&integrity["sha512-".len()..])
            .unwrap()
            .len(),
        64
    );
    let manifest = std::fs::read_to_string(root.join("assets/vendor/VENDORED")).unwrap();
    assert!(
        manifest
            .lines()
            .any(|l| l == format!("package uplot {version} {integrity}")),
        "VENDORED is not for the locked uplot {version}: run scripts/vendor-ui.sh"
    );
    let mut checked = 0;
    for line in manifest.lines().filter(|l| l.starts_with("sha256 ")) {
        let mut f = line.split_whitespace().skip(1);
        let (hash, name) = (f.next().unwrap(), f.next().unwrap());
        let bytes = std::fs::read(root.join("assets/vendor").join(name)).unwrap();
        let got: String = sha2::Sha256::digest(&bytes)
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect();
        assert_eq!(got, hash, "{name} differs from what was vendored");
        let installed = root.join("web/node_modules/uplot").join(match name {
            "uPlot.LICENSE" => "LICENSE".to_string(),
            n => format!("dist/{n}"),
        });
        if installed.is_file() {
            assert_eq!(
                std::fs::read(&installed).unwrap(),
                bytes,
                "{name} vs installed"
            );
        }
        checked += 1;
    }
    assert_eq!(checked, 3);
    let pkg = root.join("web/node_modules/uplot/package.json");
    if pkg.is_file() {
        let v: Value = serde_json::from_str(&std::fs::read_to_string(pkg).unwrap()).unwrap();
        assert_eq!(v["version"], version);
    }
}
