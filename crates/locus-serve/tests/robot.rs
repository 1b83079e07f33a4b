//! `locus serve --robot`: the page's WebSocket attached to a host session
//! that localises a simulated robot (`locus_simlink::run_robot`)
//! over loopback UDP. Over a real WebSocket: the host starts stopped (zero
//! wheel speeds), `start` drives the path, an `R` multiplied by 100 on the
//! page lowers the NIS of the host's corrections, the keyboard twist turns
//! the robot and lapses back to the controller, "next correction" shows
//! the host's next correction while the robot runs on, `stop` sends zero speeds,
//! the link's counters arrive, there is no ground truth, and what a live
//! robot cannot do is refused. And the same page attached over a serial
//! line (two pseudo-terminals joined by a cable thread).
#![allow(clippy::std_instead_of_core, clippy::std_instead_of_alloc)]

mod support;

use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use serde_json::{Value, json};
use tokio_tungstenite::tungstenite::Message;

type Ws =
    tokio_tungstenite::WebSocketStream<tokio_tungstenite::MaybeTlsStream<tokio::net::TcpStream>>;

/// Robot seconds per wall second.
const TIME_SCALE: f64 = 10.0;

async fn next_json(ws: &mut Ws) -> Value {
    loop {
        match tokio::time::timeout(Duration::from_secs(10), ws.next()).await {
            Ok(Some(Ok(Message::Text(t)))) => return serde_json::from_str(t.as_str()).unwrap(),
            Ok(Some(Ok(_))) => {}
            other => panic!("no message: {other:?}"),
        }
    }
}

/// Reads messages until `done` holds for a `state` frame (or panics after
/// `timeout`); returns every sample of the frames read.
async fn samples_until(
    ws: &mut Ws,
    timeout: Duration,
    mut done: impl FnMut(&Value) -> bool,
) -> Vec<Value> {
    let start = Instant::now();
    let mut out = Vec::new();
    loop {
        assert!(start.elapsed() < timeout, "timed out after {timeout:?}");
        let m = next_json(ws).await;
        if m["type"] != "state" {
            continue;
        }
        out.extend(m["samples"].as_array().unwrap().iter().cloned());
        if done(&m) {
            return out;
        }
    }
}

async fn send(ws: &mut Ws, v: &Value) {
    ws.send(Message::text(v.to_string())).await.unwrap();
}

/// The next `error` message (other messages skipped).
async fn next_error(ws: &mut Ws) -> Value {
    loop {
        let m = next_json(ws).await;
        if m["type"] == "error" {
            return m;
        }
    }
}

#[allow(clippy::cast_precision_loss)]
fn mean_nis(samples: &[Value], after: f64) -> (f64, usize) {
    let v: Vec<f64> = samples
        .iter()
        .filter(|s| s["t"].as_f64().unwrap() > after)
        .filter_map(|s| s["nis"].as_f64())
        .collect();
    (v.iter().sum::<f64>() / v.len() as f64, v.len())
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_drives_a_robot_over_udp() {
    let robot = support::spawn_robot(TIME_SCALE);
    let addr = support::start_robot_server(robot).await;
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
        .await
        .unwrap();
    let long = Duration::from_secs(60);

    let hello = next_json(&mut ws).await;
    assert_eq!(hello["type"], "hello");
    assert_eq!(
        hello["robot"]["link"],
        json!(format!("udp {robot}")),
        "{hello}"
    );
    assert_eq!(hello["robot"]["ground_truth"], json!(false));
    assert_eq!(hello["presets"], json!([]), "no guide without ground truth");
    let params = next_json(&mut ws).await;
    assert_eq!(params["type"], "params");
    assert_eq!(params["values"]["ir_sigma"], Value::Null);
    assert_eq!(params["values"]["speed"], Value::Null);
    let r11 = params["values"]["r11"].as_f64().unwrap();
    assert_eq!(next_json(&mut ws).await["type"], "state");

    // Stopped until a page starts it: packets flow, the wheels get zero.
    let stopped = samples_until(&mut ws, long, |m| {
        m["link"]["applied"].as_u64().unwrap() > 200
    })
    .await;
    assert!(stopped.len() > 100);
    for s in &stopped {
        assert_eq!(s["wheels"], json!([0.0, 0.0]), "stopped: {s}");
        assert_eq!(s["truth"], Value::Null, "no ground truth: {s}");
        assert_eq!(s["nees"], Value::Null);
        assert_eq!(s["odo"], Value::Null);
    }
    let x0 = stopped.last().unwrap()["ekf"].clone();

    // Start: the path controller drives, the estimate moves.
    send(&mut ws, &json!({"type": "start"})).await;
    let t_start = stopped.last().unwrap()["t"].as_f64().unwrap();
    let driving = samples_until(&mut ws, long, |m| {
        m["time"].as_f64().unwrap() > t_start + 25.0
    })
    .await;
    let last = &driving.last().unwrap()["ekf"];
    let moved = (last[0].as_f64().unwrap() - x0[0].as_f64().unwrap())
        .hypot(last[1].as_f64().unwrap() - x0[1].as_f64().unwrap());
    assert!(moved > 0.3, "the estimate moves: {moved} m");
    assert!(driving.iter().any(|s| s["wheels"] != json!([0.0, 0.0])));
    let (nis_before, n) = mean_nis(&driving, t_start + 3.0);
    assert!(n > 200, "{n} corrections with R");

    // R x 100 from the page: applied in the host, echoed to the page, the
    // NIS of the following corrections falls.
    send(
        &mut ws,
        &json!({"type": "params", "values": {"r11": 100.0 * r11, "r22": 100.0 * r11}}),
    )
    .await;
    let t_change = loop {
        let m = next_json(&mut ws).await;
        if m["type"] == "params" {
            assert_eq!(m["values"]["r11"].as_f64().unwrap(), 100.0 * r11);
            break driving.last().unwrap()["t"].as_f64().unwrap();
        }
        assert_ne!(m["type"], "error", "{m}");
    };
    let after = samples_until(&mut ws, long, |m| {
        m["time"].as_f64().unwrap() > t_change + 25.0
    })
    .await;
    let (nis_after, n) = mean_nis(&after, t_change + 1.0);
    assert!(n > 200, "{n} corrections with 100 R");
    println!("mean NIS {nis_before:.3} with R, {nis_after:.3} with 100 R");
    assert!(
        nis_after < nis_before / 5.0,
        "mean NIS {nis_before} -> {nis_after}"
    );

    // Next correction: the host's next one, step by step, while the robot
    // runs on; it is the correction of a sample in the same frame.
    send(&mut ws, &json!({"type": "step_correction"})).await;
    let mut frame = Value::Null;
    samples_until(&mut ws, long, |m| {
        frame = m.clone();
        !m["correction"].is_null()
    })
    .await;
    let d = &frame["correction"];
    assert_eq!(frame["running"], json!(true), "the robot runs on");
    let sample = frame["samples"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["nis"] == d["nis"])
        .unwrap_or_else(|| panic!("no sample of the correction {d} in {frame}"));
    assert_eq!(sample["ekf"], d["x_post"]);
    assert_eq!(sample["innovation"], d["innovation"]);
    assert_eq!(sample["applied"], d["applied"]);
    for key in [
        "x_prior", "p_prior", "z", "h", "jacobian", "noise", "s", "k", "p_post", "u",
    ] {
        assert!(d[key].is_array(), "{key}: {d}");
    }
    // Only on request: the next frames carry none.
    let m = loop {
        let m = next_json(&mut ws).await;
        if m["type"] == "state" {
            break m;
        }
    };
    assert!(m["correction"].is_null(), "{m}");

    // Keyboard: a left turn held for 1.5 s (repeated every 150 ms) turns
    // the heading estimate left by far more than the path would.
    let mut heading = Vec::new();
    let mut keyboard_frames = 0;
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(1500) {
        send(&mut ws, &json!({"type": "teleop", "v": 0, "w": 1})).await;
        let until = Instant::now() + Duration::from_millis(150);
        while Instant::now() < until {
            let Ok(Some(Ok(Message::Text(t)))) =
                tokio::time::timeout(Duration::from_millis(50), ws.next()).await
            else {
                continue;
            };
            let m: Value = serde_json::from_str(t.as_str()).unwrap();
            if m["type"] == "state" && m["teleop"] == json!(true) {
                keyboard_frames += 1;
                assert_eq!(m["link"]["drive"], "keyboard");
                heading.extend(
                    m["samples"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .map(|s| s["ekf"][2].as_f64().unwrap()),
                );
            }
        }
    }
    let turned: f64 = heading
        .windows(2)
        .map(|w| {
            (w[1] - w[0] + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI
        })
        .sum();
    assert!(keyboard_frames > 10, "{keyboard_frames} keyboard frames");
    assert!(turned > 4.0, "the left arrow turns left: {turned} rad");
    // No repeat: back to the path controller within the timeout.
    samples_until(&mut ws, long, |m| {
        m["teleop"] == json!(false) && m["link"]["drive"] == "path"
    })
    .await;

    // Stop: zero speeds while the link stays up.
    send(&mut ws, &json!({"type": "stop"})).await;
    samples_until(&mut ws, long, |m| m["running"] == json!(false)).await;
    let halted = samples_until(&mut ws, long, |m| {
        m["samples"].as_array().unwrap().len() > 50
    })
    .await;
    for s in halted.iter().skip(halted.len() - 50) {
        assert_eq!(s["wheels"], json!([0.0, 0.0]), "stopped: {s}");
    }

    // Refused: what a robot cannot do, the simulator's noise, bad values,
    // unknown fields.
    for (msg, field) in [
        (json!({"type": "step"}), "step"),
        (json!({"type": "reset"}), "reset"),
        (json!({"type": "speed", "factor": 2}), "speed"),
        (json!({"type": "export"}), "export"),
        (
            json!({"type": "params", "values": {"ir_sigma": 0.01}}),
            "ir_sigma",
        ),
        (json!({"type": "params", "values": {"r11": -1}}), "r11"),
        (json!({"type": "teleop", "v": 9, "w": 0}), "teleop_v"),
        (json!({"type": "start", "bogus": 1}), "bogus"),
        (
            json!({"type": "params", "values": {"r11": 1e-4, "q12": 1}}),
            "q12",
        ),
    ] {
        send(&mut ws, &msg).await;
        let e = next_error(&mut ws).await;
        assert_eq!(e["field"], field, "{msg}: {e}");
    }

    // The link's health.
    let m = loop {
        let m = next_json(&mut ws).await;
        if m["type"] == "state" {
            break m;
        }
    };
    let l = &m["link"];
    println!("link: {l}");
    assert_eq!(l["silent"], json!(false));
    assert!(l["applied"].as_u64().unwrap() > 3000, "{l}");
    assert!(l["commands_sent"].as_u64().unwrap() >= l["applied"].as_u64().unwrap());
    assert!(l["corrections"].as_u64().unwrap() > 400, "{l}");
    for k in [
        "lost",
        "duplicate",
        "late",
        "corrupt",
        "malformed",
        "suspect",
        "implausible",
        "frames_malformed",
        "frames_oversize",
    ] {
        assert!(l[k].is_u64(), "{k}: {l}");
    }
    assert!(l["latency_p50_us"].as_f64().unwrap() > 0.0);
    assert!(
        l["clock_offset_s"].is_f64() && l["clock_drift_ppm"].is_f64(),
        "{l}"
    );
    // The robot's clock runs TIME_SCALE times faster than the host's.
    let drift = l["clock_drift_ppm"].as_f64().unwrap() * 1e-6;
    assert!((drift - (TIME_SCALE - 1.0)).abs() < 1.0, "drift {drift}");
}

/// Copies one pty master to the other until `stop` (the cable between the
/// robot's and the host's serial ports).
fn cable(
    mut from: serialport::TTYPort,
    mut to: serialport::TTYPort,
    stop: std::sync::Arc<std::sync::atomic::AtomicBool>,
) -> std::thread::JoinHandle<()> {
    use std::io::{Read, Write};
    std::thread::spawn(move || {
        use serialport::SerialPort;
        from.set_timeout(Duration::from_millis(5)).unwrap();
        let mut buf = [0u8; 512];
        while !stop.load(std::sync::atomic::Ordering::Relaxed) {
            if let Ok(n) = from.read(&mut buf) {
                let _ = to.write_all(&buf[..n]);
            }
        }
    })
}

/// The page attached over a serial line (what `locus serve --robot
/// serial:/dev/rfcomm0` opens): the host opens the pty by its path, the
/// simulated robot speaks COBS frames on the other pty, and the page sees
/// the robot drive and the filter correct, with no frame dropped.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_drives_a_robot_over_a_serial_line() {
    use serialport::{SerialPort, TTYPort};
    use std::sync::Arc;
    use std::sync::atomic::{AtomicBool, Ordering};

    let (robot_master, robot_end) = TTYPort::pair().expect("pty pair");
    let (host_master, host_end) = TTYPort::pair().expect("pty pair");
    let device = host_end.name().expect("the pty's path");
    let stop = Arc::new(AtomicBool::new(false));
    let up = cable(
        robot_master.try_clone_native().unwrap(),
        host_master.try_clone_native().unwrap(),
        stop.clone(),
    );
    let down = cable(host_master, robot_master, stop.clone());
    let robot_cfg = locus_simlink::RobotConfig {
        square: locus_sim::SquareConfig {
            max_time: 5000.0,
            ..locus_sim::SquareConfig::default()
        },
        time_scale: TIME_SCALE,
        idle_exit: 30.0,
        handshake: Duration::from_secs(60),
        ..locus_simlink::RobotConfig::default()
    };
    std::thread::spawn(move || {
        let port: Box<dyn SerialPort> = Box::new(robot_end);
        locus_simlink::run_robot_over(&mut locus_net::transport::Serial::new(port), &robot_cfg)
    });

    let mut cfg = locus_simlink::host_config(&locus_sim::SquareConfig::default());
    cfg.laps = usize::MAX;
    let link = locus_serve::robot::Link::serial(&device, 115_200).unwrap();
    let attached =
        locus_serve::robot::Attached::start(link, &cfg, 0.01, Duration::from_millis(50)).unwrap();
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    tokio::spawn(locus_serve::serve_with_robot(
        listener,
        locus_serve::Config::default(),
        attached,
    ));
    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/ws"))
        .await
        .unwrap();
    let long = Duration::from_secs(60);
    let hello = next_json(&mut ws).await;
    assert_eq!(
        hello["robot"]["link"],
        json!(format!("serial {device} at 115200 baud")),
        "{hello}"
    );

    samples_until(&mut ws, long, |m| {
        m["link"]["applied"].as_u64().unwrap() > 100
    })
    .await;
    send(&mut ws, &json!({"type": "start"})).await;
    let driving = samples_until(&mut ws, long, |m| m["time"].as_f64().unwrap() > 15.0).await;
    let first = &driving.first().unwrap()["ekf"];
    let last = &driving.last().unwrap()["ekf"];
    let moved = (last[0].as_f64().unwrap() - first[0].as_f64().unwrap())
        .hypot(last[1].as_f64().unwrap() - first[1].as_f64().unwrap());
    assert!(moved > 0.5, "the robot drove {moved} m");
    let (nis, n) = mean_nis(&driving, 0.0);
    assert!(n > 100 && nis < 10.0, "{n} corrections, mean NIS {nis}");
    let m = loop {
        let m = next_json(&mut ws).await;
        if m["type"] == "state" {
            break m;
        }
    };
    let l = &m["link"];
    println!("serial link: {l}");
    for k in [
        "lost",
        "corrupt",
        "malformed",
        "frames_malformed",
        "frames_oversize",
    ] {
        assert_eq!(l[k], json!(0), "{k}: {l}");
    }
    drop(ws);
    stop.store(true, Ordering::Relaxed);
    up.join().unwrap();
    down.join().unwrap();
    drop(host_end);
}
