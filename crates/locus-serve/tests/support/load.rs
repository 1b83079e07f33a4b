//! The load test: `clients` concurrent WebSocket clients on loopback for
//! `duration`, each running its own session at `speed`, changing R every
//! second and teleoperating now and then, counting every message received.

use std::net::SocketAddr;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use futures_util::{SinkExt, StreamExt};
use tokio_tungstenite::tungstenite::Message;

/// What a load run measured.
#[derive(Debug, Clone, Copy)]
pub struct LoadReport {
    /// Clients.
    pub clients: usize,
    /// Wall-clock duration (s).
    pub seconds: f64,
    /// Messages received by all clients.
    pub received: u64,
    /// Simulation samples received by all clients.
    pub samples: u64,
    /// Messages sent by all clients.
    pub sent: u64,
    /// Errors: failed connections, sends, unparsable or `error` messages.
    pub errors: u64,
    /// RSS before and after (kB).
    pub rss_before_kb: u64,
    /// RSS at the end, clients gone (kB).
    pub rss_after_kb: u64,
    /// Largest RSS seen while running (kB).
    pub rss_peak_kb: u64,
    /// Sessions still open after the clients closed.
    pub sessions_after: u64,
}

impl LoadReport {
    /// Messages received per second, all clients together.
    #[allow(clippy::cast_precision_loss)]
    pub fn messages_per_second(&self) -> f64 {
        self.received as f64 / self.seconds
    }
}

#[derive(Default)]
struct Counters {
    received: AtomicU64,
    samples: AtomicU64,
    sent: AtomicU64,
    errors: AtomicU64,
}

async fn client(addr: SocketAddr, index: usize, until: Instant, speed: f64, c: Arc<Counters>) {
    let url = format!("ws://{addr}/ws");
    let Ok((ws, _)) = tokio_tungstenite::connect_async(url.as_str()).await else {
        c.errors.fetch_add(1, Ordering::Relaxed);
        return;
    };
    let (mut tx, mut rx) = ws.split();
    let send = async |tx: &mut futures_util::stream::SplitSink<_, Message>,
                      v: serde_json::Value| {
        let ok = tx.send(Message::text(v.to_string())).await.is_ok();
        c.sent.fetch_add(1, Ordering::Relaxed);
        if !ok {
            c.errors.fetch_add(1, Ordering::Relaxed);
        }
    };
    send(
        &mut tx,
        serde_json::json!({"type": "speed", "factor": speed}),
    )
    .await;
    send(&mut tx, serde_json::json!({"type": "start"})).await;
    let mut every = tokio::time::interval(Duration::from_millis(1000));
    let mut k = index;
    loop {
        tokio::select! {
            m = rx.next() => match m {
                Some(Ok(Message::Text(t))) => {
                    c.received.fetch_add(1, Ordering::Relaxed);
                    match serde_json::from_str::<serde_json::Value>(t.as_str()) {
                        Ok(v) if v["type"] == "error" => {
                            eprintln!("client {index}: error message {v}");
                            c.errors.fetch_add(1, Ordering::Relaxed);
                        }
                        Ok(v) => {
                            let n = v["samples"].as_array().map_or(0, Vec::len);
                            c.samples.fetch_add(n as u64, Ordering::Relaxed);
                            if v["type"] == "state" && v["finished"] == true {
                                send(&mut tx, serde_json::json!({"type": "reset"})).await;
                                send(&mut tx, serde_json::json!({"type": "start"})).await;
                            }
                        }
                        Err(_) => { c.errors.fetch_add(1, Ordering::Relaxed); }
                    }
                }
                Some(Ok(_)) => {}
                Some(Err(e)) => {
                    eprintln!("client {index}: {e}");
                    c.errors.fetch_add(1, Ordering::Relaxed);
                    return;
                }
                None => {
                    eprintln!("client {index}: closed by the server");
                    c.errors.fetch_add(1, Ordering::Relaxed);
                    return;
                }
            },
            _ = every.tick() => {
                if Instant::now() >= until { break; }
                k += 1;
                // Alternate R, and teleoperate one second in five.
                let r = if k % 2 == 0 { "2.5e-5" } else { "1e-4" };
                send(&mut tx, serde_json::json!({"type": "params", "values": {"r11": r, "r22": r}})).await;
                if k % 5 == 0 {
                    send(&mut tx, serde_json::json!({"type": "teleop", "v": 0.05, "w": 0.5})).await;
                }
            }
        }
    }
    let _ = tx.send(Message::Close(None)).await;
}

/// Runs the load test against a fresh in-process server.
pub async fn run(clients: usize, duration: Duration, speed: f64) -> LoadReport {
    let config = locus_serve::Config::default();
    let addr = super::start_server(config).await;
    let rss_before_kb = super::rss_kb();
    let counters = Arc::new(Counters::default());
    let start = Instant::now();
    let until = start + duration;
    let handles: Vec<_> = (0..clients)
        .map(|i| tokio::spawn(client(addr, i, until, speed, Arc::clone(&counters))))
        .collect();
    let mut rss_peak_kb = rss_before_kb;
    while Instant::now() < until {
        tokio::time::sleep(Duration::from_millis(250)).await;
        rss_peak_kb = rss_peak_kb.max(super::rss_kb());
    }
    for h in handles {
        if h.await.is_err() {
            counters.errors.fetch_add(1, Ordering::Relaxed);
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    // The server notices the closes.
    let mut sessions_after = u64::MAX;
    for _ in 0..50 {
        sessions_after = super::sessions(addr).await;
        if sessions_after == 0 {
            break;
        }
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    LoadReport {
        clients,
        seconds,
        received: counters.received.load(Ordering::Relaxed),
        samples: counters.samples.load(Ordering::Relaxed),
        sent: counters.sent.load(Ordering::Relaxed),
        errors: counters.errors.load(Ordering::Relaxed),
        rss_before_kb,
        rss_after_kb: super::rss_kb(),
        rss_peak_kb,
        sessions_after,
    }
}

/// Prints the report in one block.
pub fn print(r: &LoadReport) {
    println!(
        "load: {} clients, {:.1} s: {} messages received ({:.0} messages/s), {} simulation steps streamed ({:.0} steps/s), {} sent, {} errors; RSS {} MB before, {} MB peak, {} MB after; sessions after close: {}",
        r.clients,
        r.seconds,
        r.received,
        r.messages_per_second(),
        r.samples,
        r.samples as f64 / r.seconds,
        r.sent,
        r.errors,
        r.rss_before_kb / 1024,
        r.rss_peak_kb / 1024,
        r.rss_after_kb / 1024,
        r.sessions_after
    );
}
