//! The live Foxglove server ([`locus_serve::foxglove::Live`]) against
//! clients that misbehave, on a real loopback socket with a blocking
//! `tungstenite` client: messages it does not understand are answered
//! with a status and the connection stays open; an oversized message
//! costs its sender the connection and nobody else anything; a client
//! that stops reading never holds up the host's `publish`, and skips
//! messages (counted) rather than receiving stale ones; the latched map
//! reaches a late subscriber once; a frame Foxglove cannot carry is
//! counted and not sent.
//!
//! Every read has a timeout, so a server that stops answering fails a
//! test in seconds instead of hanging it.

extern crate alloc;

use alloc::collections::BTreeMap;
use alloc::sync::Arc;
use core::net::{Ipv4Addr, SocketAddr};
use core::time::Duration;
use std::io::ErrorKind;
use std::net::TcpStream;
use std::sync::mpsc;

use locus_foxglove::{Frame, Scene, Topic, nanos, ws::SUBPROTOCOL};
use locus_serve::foxglove::Live;
use serde_json::{Value, json};
use tungstenite::client::IntoClientRequest;
use tungstenite::http::HeaderValue;
use tungstenite::{Message, WebSocket};

/// How long any one read waits before the test fails.
const TIMEOUT: Duration = Duration::from_secs(5);
/// The ellipse's standard deviations.
const SIGMA: f64 = 3.0;
/// The largest message the server takes from a client (bytes).
const CLIENT_LIMIT: usize = 64 * 1024;

fn start() -> Live {
    Live::start(SocketAddr::from((Ipv4Addr::LOCALHOST, 0)), SIGMA).expect("binding loopback")
}

/// A step at `time` (s), its estimate moving along x at 0.5 m/s.
fn step(time: f64) -> Frame {
    Frame {
        time,
        estimate: [0.5 * time, 0.2, 0.1],
        covariance: [[0.01, 0.0, 0.0], [0.0, 0.02, 0.0], [0.0, 0.0, 0.003]],
        truth: None,
        odometry: None,
        correction: None,
        nees: None,
    }
}

/// `time` (s) in the protocol's nanoseconds.
fn ns(time: f64) -> u64 {
    nanos(time, "a test step").expect("a time Foxglove carries")
}

/// One Message Data frame: subscription id, time (ns), JSON payload.
#[derive(Debug)]
struct Data {
    sub: u32,
    time: u64,
    payload: Value,
}

/// What the server sent: a status (its JSON) or a message's data.
#[derive(Debug)]
enum Got {
    Status(Value),
    Data(Data),
}

/// A Foxglove client on a blocking socket with read and write timeouts.
struct Client {
    ws: WebSocket<TcpStream>,
    /// Channel id of each advertised topic.
    channels: BTreeMap<String, u32>,
}

impl Client {
    /// Connects asking for the Foxglove subprotocol, and reads the server
    /// info and the advertised channels.
    fn connect(addr: SocketAddr) -> Self {
        let stream = TcpStream::connect_timeout(&addr, TIMEOUT).expect("connecting");
        stream.set_read_timeout(Some(TIMEOUT)).unwrap();
        stream.set_write_timeout(Some(TIMEOUT)).unwrap();
        let mut req = format!("ws://{addr}/").into_client_request().unwrap();
        req.headers_mut().insert(
            "Sec-WebSocket-Protocol",
            HeaderValue::from_static(SUBPROTOCOL),
        );
        let (ws, response) = tungstenite::client(req, stream)
            .unwrap_or_else(|e| panic!("the WebSocket handshake with {addr}: {e}"));
        assert_eq!(response.headers()["Sec-WebSocket-Protocol"], SUBPROTOCOL);
        let mut c = Self {
            ws,
            channels: BTreeMap::new(),
        };
        let info = c.text();
        assert_eq!(info["op"], "serverInfo", "{info}");
        let ad = c.text();
        assert_eq!(ad["op"], "advertise", "{ad}");
        for ch in ad["channels"].as_array().expect("channels") {
            let id = u32::try_from(ch["id"].as_u64().expect("a channel id")).unwrap();
            c.channels
                .insert(ch["topic"].as_str().expect("a topic").to_string(), id);
        }
        assert_eq!(c.channels.len(), Topic::ALL.len());
        c
    }

    fn channel(&self, topic: Topic) -> u32 {
        self.channels[topic.name()]
    }

    fn send(&mut self, m: Message) {
        self.ws.send(m).expect("sending to the server");
    }

    fn send_json(&mut self, v: &Value) {
        self.send(Message::text(v.to_string()));
    }

    /// Subscribes each (subscription id, topic) pair, in one message.
    fn subscribe(&mut self, subs: &[(u32, Topic)]) {
        let subscriptions: Vec<Value> = subs
            .iter()
            .map(|&(id, t)| json!({ "id": id, "channelId": self.channel(t) }))
            .collect();
        self.send_json(&json!({ "op": "subscribe", "subscriptions": subscriptions }));
    }

    /// The next status or message data; panics on a close, an error, or
    /// nothing within [`TIMEOUT`].
    fn next(&mut self) -> Got {
        loop {
            match self.ws.read() {
                Ok(Message::Text(t)) => {
                    let v: Value = serde_json::from_str(t.as_str()).expect("JSON text");
                    assert_eq!(v["op"], "status", "unexpected text: {v}");
                    return Got::Status(v);
                }
                Ok(Message::Binary(b)) => {
                    assert!(b.len() >= 13, "a message data frame of {} bytes", b.len());
                    assert_eq!(b[0], 0x01, "the message data opcode");
                    return Got::Data(Data {
                        sub: u32::from_le_bytes(b[1..5].try_into().unwrap()),
                        time: u64::from_le_bytes(b[5..13].try_into().unwrap()),
                        payload: serde_json::from_slice(&b[13..]).expect("a JSON payload"),
                    });
                }
                Ok(Message::Ping(_) | Message::Pong(_) | Message::Frame(_)) => {}
                Ok(Message::Close(c)) => panic!("the server closed the connection: {c:?}"),
                Err(e) => panic!("reading (nothing for {TIMEOUT:?} is a timeout): {e}"),
            }
        }
    }

    /// The next text, parsed.
    fn text(&mut self) -> Value {
        match self.ws.read().expect("reading a text message") {
            Message::Text(t) => serde_json::from_str(t.as_str()).expect("JSON text"),
            other => panic!("expected text, got {other:?}"),
        }
    }

    /// The next message, which must be a warning status; its text.
    fn warning(&mut self) -> String {
        match self.next() {
            Got::Status(s) => {
                assert_eq!(s["level"], 1, "a warning: {s}");
                s["message"].as_str().expect("a status message").to_string()
            }
            Got::Data(d) => panic!("expected a status, got data {d:?}"),
        }
    }

    /// Message data until one `last` accepts (included); a status on the
    /// way fails.
    fn data_until(&mut self, last: impl Fn(&Data) -> bool) -> Vec<Data> {
        let mut out = Vec::new();
        loop {
            match self.next() {
                Got::Data(d) => {
                    let done = last(&d);
                    out.push(d);
                    if done {
                        return out;
                    }
                }
                Got::Status(s) => panic!("unexpected status: {s}"),
            }
        }
    }

    /// A round trip: sends a text that is no client op and waits for the
    /// status answering it, returning the message data received before.
    /// The server handles one client's messages in order, so everything
    /// sent before (a subscription) has taken effect when this returns.
    fn sync(&mut self) -> Vec<Data> {
        self.send(Message::text("sync"));
        let mut out = Vec::new();
        loop {
            match self.next() {
                Got::Data(d) => out.push(d),
                Got::Status(s) => {
                    assert_eq!(s["level"], 1, "{s}");
                    return out;
                }
            }
        }
    }
}

/// Each (topic) of a frame's messages, in the order `publish` sends them.
fn topics_of(f: &Frame) -> Vec<Topic> {
    locus_foxglove::frame(f, SIGMA)
        .expect("a frame Foxglove carries")
        .iter()
        .map(|m| m.topic)
        .collect()
}

#[test]
fn a_client_sending_nonsense_is_answered_with_warnings_and_stays_connected() {
    let live = start();
    let mut c = Client::connect(live.local_addr());

    // Not JSON.
    c.send(Message::text("this is not json {"));
    c.warning();
    // JSON, but no operation of the protocol's.
    c.send_json(&json!({ "op": "publish", "channel": 1 }));
    c.warning();
    // A channel that was never advertised.
    c.send_json(&json!({ "op": "subscribe", "subscriptions": [{ "id": 1, "channelId": 999 }] }));
    let w = c.warning();
    assert!(w.contains("999"), "the warning names the channel: {w}");
    // A subscription id already in use: 7 goes to /tf, then is asked
    // again for the covariance.
    c.subscribe(&[(7, Topic::Transform)]);
    c.subscribe(&[(7, Topic::Ellipse)]);
    let covariance = c.channel(Topic::Ellipse);
    let w = c.warning();
    assert!(
        w.contains(&covariance.to_string()),
        "the warning names the channel {covariance}: {w}"
    );
    // Binary: this server only publishes.
    c.send(Message::binary(vec![0x01, 0x02, 0x03]));
    c.warning();

    // Still open, and still serving: a valid subscription receives.
    c.subscribe(&[(9, Topic::Estimate)]);
    assert!(c.sync().is_empty(), "nothing was published yet");
    for t in [1.0, 2.0, 3.0] {
        live.publish(&step(t));
    }
    let got = c.data_until(|d| d.sub == 9 && d.time == ns(3.0));
    let estimates: Vec<&Data> = got.iter().filter(|d| d.sub == 9).collect();
    assert_eq!(
        estimates.iter().map(|d| d.time).collect::<Vec<_>>(),
        [ns(1.0), ns(2.0), ns(3.0)]
    );
    for (d, t) in estimates.iter().zip([1.0, 2.0, 3.0]) {
        assert_eq!(d.payload["frame_id"], "map", "{}", d.payload);
        assert_eq!(d.payload["pose"]["position"]["x"], 0.5 * t, "{}", d.payload);
    }
    // The first subscription under id 7 stands; the refused one (the
    // covariance) sends nothing.
    for d in got.iter().filter(|d| d.sub != 9) {
        assert_eq!(d.sub, 7, "only subscriptions 7 and 9 exist: {d:?}");
        assert_eq!(
            d.payload["child_frame_id"], "base_link",
            "/tf: {}",
            d.payload
        );
    }
    assert!(got.iter().any(|d| d.sub == 7), "/tf frames under id 7");
    assert_eq!(live.skipped(), 0);
    assert_eq!(live.refused(), 0);
}

#[test]
fn an_oversized_message_disconnects_its_sender_and_no_one_else() {
    let live = start();
    let mut good = Client::connect(live.local_addr());
    // A subscription padded to exactly the limit is still taken.
    let sub = json!({
        "op": "subscribe",
        "subscriptions": [{ "id": 1, "channelId": good.channel(Topic::Estimate) }],
    })
    .to_string();
    let padded = format!("{sub}{}", " ".repeat(CLIENT_LIMIT - sub.len()));
    assert_eq!(padded.len(), CLIENT_LIMIT);
    good.send(Message::text(padded));
    assert!(good.sync().is_empty());
    live.publish(&step(1.0));
    let got = good.data_until(|d| d.sub == 1);
    assert_eq!(got.last().unwrap().time, ns(1.0));

    // A second client, connected at the same time, sends one byte more.
    let mut bad = Client::connect(live.local_addr());
    bad.subscribe(&[(1, Topic::Estimate)]);
    assert!(bad.sync().is_empty());
    let oversized = Message::text("x".repeat(CLIENT_LIMIT + 1));
    // The server may already have hung up while the message was written.
    if bad.ws.send(oversized).is_ok() {
        loop {
            match bad.ws.read() {
                // The closing handshake, if the server starts one.
                Ok(Message::Close(_) | Message::Ping(_) | Message::Pong(_) | Message::Frame(_)) => {
                }
                Ok(m) => panic!("still served after an oversized message: {m:?}"),
                Err(tungstenite::Error::Io(e))
                    if matches!(e.kind(), ErrorKind::WouldBlock | ErrorKind::TimedOut) =>
                {
                    panic!("still connected {TIMEOUT:?} after an oversized message")
                }
                // Closed, reset, or ended without a closing handshake.
                Err(_) => break,
            }
        }
    }

    // The first client is served as before.
    for t in [2.0, 3.0] {
        live.publish(&step(t));
    }
    let got = good.data_until(|d| d.sub == 1 && d.time == ns(3.0));
    assert_eq!(
        got.iter().map(|d| d.time).collect::<Vec<_>>(),
        [ns(2.0), ns(3.0)]
    );
    assert!(good.sync().is_empty(), "and still answers");
}

#[test]
fn a_client_that_stops_reading_never_blocks_publish_and_skips_to_the_latest() {
    const FRAMES: u32 = 20_000;
    let time = |i: u32| f64::from(i) * 1e-3;

    let live = Arc::new(start());
    let mut c = Client::connect(live.local_addr());
    // Every topic, so that every message published reaches this client
    // or is counted as skipped: (subscription id, topic).
    let subs: Vec<(u32, Topic)> = Topic::ALL
        .iter()
        .zip(100..)
        .map(|(&t, id)| (id, t))
        .collect();
    let sub_of = |topic: Topic| subs.iter().find(|&&(_, t)| t == topic).unwrap().0;
    c.subscribe(&subs);
    assert!(c.sync().is_empty());

    // The host publishes ~60 MB of messages while the client reads
    // nothing: far past the socket's buffers and the server's queue.
    let (done, finished) = mpsc::channel();
    let host = Arc::clone(&live);
    std::thread::spawn(move || {
        for i in 1..=FRAMES {
            host.publish(&step(time(i)));
        }
        let _ = done.send(());
    });
    finished
        .recv_timeout(Duration::from_secs(20))
        .expect("publish waited on a client that does not read");

    // The client reads again: whatever it receives is in time order on
    // each subscription, and it reaches the last frame.
    let topics = topics_of(&step(time(FRAMES)));
    let per_frame = topics.len() as u64;
    let last = ns(time(FRAMES));
    let closing = sub_of(*topics.last().unwrap());
    let mut latest: BTreeMap<u32, u64> = BTreeMap::new();
    let mut received: u64 = 0;
    loop {
        let d = match c.next() {
            Got::Data(d) => d,
            Got::Status(s) => panic!("unexpected status: {s}"),
        };
        received += 1;
        if let Some(&before) = latest.get(&d.sub) {
            assert!(
                d.time > before,
                "subscription {}: {} after {before}",
                d.sub,
                d.time
            );
        }
        latest.insert(d.sub, d.time);
        if d.sub == closing && d.time == last {
            break;
        }
    }
    for &t in &topics {
        assert_eq!(
            latest.get(&sub_of(t)),
            Some(&last),
            "{} of the last frame",
            t.name()
        );
    }
    let skipped = live.skipped();
    assert!(
        skipped > 0,
        "a client that read nothing for {FRAMES} frames skipped none"
    );
    assert_eq!(
        received + skipped,
        u64::from(FRAMES) * per_frame,
        "every message is either sent or counted as skipped ({received} sent)"
    );

    // Caught up, it is served every frame again.
    live.publish(&step(time(FRAMES + 1)));
    let got = c.data_until(|d| d.sub == closing && d.time == ns(time(FRAMES + 1)));
    assert_eq!(got.len() as u64, per_frame, "{got:?}");
    assert_eq!(live.skipped(), skipped);
}

#[test]
fn a_late_subscriber_gets_the_latched_map_once_and_refused_frames_are_not_sent() {
    let live = start();
    let scene = Scene {
        walls: vec![
            [0.0, 0.0, 2.0, 0.0],
            [2.0, 0.0, 2.0, 2.0],
            [2.0, 2.0, 0.0, 2.0],
            [0.0, 2.0, 0.0, 0.0],
        ],
        ..Scene::default()
    };
    live.latch(&scene, 0.0).expect("latching the map");

    // Connected after the map was latched.
    let mut c = Client::connect(live.local_addr());
    c.subscribe(&[(1, Topic::Map), (2, Topic::Estimate)]);
    let first = c.sync();
    assert_eq!(first.len(), 1, "the map on subscribing: {first:?}");
    assert_eq!(first[0].sub, 1);
    assert_eq!(first[0].time, ns(0.0));
    let entities = first[0].payload["entities"]
        .as_array()
        .expect("a scene update");
    assert!(
        !entities.is_empty() && !entities[0]["lines"].as_array().unwrap().is_empty(),
        "the walls: {}",
        first[0].payload
    );
    // Subscribing to something else does not send the map again.
    c.subscribe(&[(3, Topic::Transform)]);
    assert!(c.sync().is_empty(), "the map again");

    // A step with a NaN estimate between two good ones.
    assert_eq!(live.refused(), 0);
    live.publish(&step(1.0));
    let mut bad = step(2.0);
    bad.estimate[0] = f64::NAN;
    live.publish(&bad);
    assert_eq!(live.refused(), 1);
    live.publish(&step(3.0));
    let mut got = c.data_until(|d| d.sub == 2 && d.time == ns(3.0));
    got.extend(c.sync());
    assert_eq!(
        got.iter()
            .filter(|d| d.sub == 2)
            .map(|d| d.time)
            .collect::<Vec<_>>(),
        [ns(1.0), ns(3.0)],
        "the estimates sent"
    );
    assert!(
        got.iter().all(|d| d.time != ns(2.0)),
        "nothing of the refused step"
    );
    assert!(got.iter().all(|d| d.sub != 1), "the map once only");
    assert_eq!(live.refused(), 1);
}
