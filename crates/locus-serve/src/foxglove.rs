//! A live robot's estimate for Foxglove: a WebSocket server speaking the
//! Foxglove protocol (`foxglove.websocket.v1`, [`locus_foxglove::ws`]), on
//! its own thread, fed by the host loop ([`Live::publish`]). `locus host
//! --foxglove ADDR` and `locus serve --robot ... --foxglove ADDR` start one,
//! so that a robot's live estimate shows in Foxglove beside the teaching
//! page.
//!
//! The host never waits for Foxglove: messages go out through a bounded
//! broadcast channel, and a client that falls behind skips messages
//! (counted in [`Live::skipped`]) rather than slowing the robot. The map is
//! latched: a client that subscribes to it later still receives it.

use alloc::sync::Arc;
use core::net::SocketAddr;
use core::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Mutex, PoisonError};

use axum::Router;
use axum::extract::State;
use axum::extract::ws::{Message as WsMessage, WebSocket, WebSocketUpgrade};
use axum::response::Response;
use axum::routing::get;
use locus_foxglove::{Frame, Message, Scene, ws};
use tokio::sync::broadcast;

use crate::Error;

/// The frame of a host's applied packet: its estimate and covariance at
/// the robot's time, and the IR pair's correction (2 dof) if one was
/// tried. A robot sends no truth and the host keeps no odometry alone.
#[must_use]
pub fn frame_of(step: &locus_net::host::HostStep) -> Frame {
    Frame {
        time: step.robot_time,
        estimate: step.estimate,
        covariance: step.covariance,
        truth: None,
        odometry: None,
        correction: step.nis.map(|nis| (nis, 2, step.corrected)),
        nees: None,
    }
}

/// The arena's walls as a scene.
#[must_use]
pub fn arena(cfg: &locus_net::host::HostConfig) -> Scene {
    Scene {
        walls: cfg
            .walls
            .iter()
            .map(|w| [w.a[0], w.a[1], w.b[0], w.b[1]])
            .collect(),
        ..Scene::default()
    }
}

/// Messages buffered per client before a slow client skips some.
const BUFFERED: usize = 1024;
/// Largest message a client may send (subscriptions are small), bytes.
const MAX_CLIENT_MESSAGE: usize = 64 * 1024;

struct Hub {
    messages: broadcast::Sender<Arc<Message>>,
    latched: Mutex<Vec<Message>>,
    session: String,
    skipped: AtomicU64,
    refused: AtomicU64,
}

/// The running server; dropping it leaves the server running until the
/// process ends.
pub struct Live {
    hub: Arc<Hub>,
    addr: SocketAddr,
    sigma: f64,
}

impl Live {
    /// Binds `addr` and serves the Foxglove protocol on it from a thread
    /// of its own; ellipses are drawn at `sigma` standard deviations.
    ///
    /// # Errors
    /// The address cannot be bound.
    pub fn start(addr: SocketAddr, sigma: f64) -> Result<Self, Error> {
        let listener = std::net::TcpListener::bind(addr)?;
        listener.set_nonblocking(true)?;
        let addr = listener.local_addr()?;
        let (messages, _) = broadcast::channel(BUFFERED);
        let hub = Arc::new(Hub {
            messages,
            latched: Mutex::new(Vec::new()),
            session: format!("{}", std::process::id()),
            skipped: AtomicU64::new(0),
            refused: AtomicU64::new(0),
        });
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()?;
        let shared = Arc::clone(&hub);
        std::thread::Builder::new()
            .name("locus-foxglove".into())
            .spawn(move || {
                runtime.block_on(async move {
                    let Ok(listener) = tokio::net::TcpListener::from_std(listener) else {
                        return;
                    };
                    let app = Router::new().route("/", get(upgrade)).with_state(shared);
                    let _ = axum::serve(listener, app).await;
                });
            })?;
        Ok(Self { hub, addr, sigma })
    }

    /// The address served (the port chosen when 0 was asked for).
    #[must_use]
    pub const fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// Publishes one step to every subscribed client. A frame Foxglove
    /// cannot carry (a time before 0, a non-finite estimate) is counted in
    /// [`Live::refused`] and not sent.
    pub fn publish(&self, f: &Frame) {
        match locus_foxglove::frame(f, self.sigma) {
            Ok(ms) => {
                for m in ms {
                    // No client connected is fine.
                    let _ = self.hub.messages.send(Arc::new(m));
                }
            }
            Err(_) => {
                self.hub.refused.fetch_add(1, Ordering::Relaxed);
            }
        }
    }

    /// Latches the map: sent to every client that subscribes to it, now
    /// or later.
    ///
    /// # Errors
    /// A time Foxglove cannot carry.
    pub fn latch(&self, scene: &Scene, time: f64) -> Result<(), locus_foxglove::Error> {
        let ms = locus_foxglove::scene(scene, time)?;
        let mut latched = self
            .hub
            .latched
            .lock()
            .unwrap_or_else(PoisonError::into_inner);
        for m in &ms {
            let _ = self.hub.messages.send(Arc::new(m.clone()));
        }
        *latched = ms;
        Ok(())
    }

    /// Messages skipped by clients that fell behind, over all clients.
    #[must_use]
    pub fn skipped(&self) -> u64 {
        self.hub.skipped.load(Ordering::Relaxed)
    }

    /// Steps not sent because Foxglove cannot carry them.
    #[must_use]
    pub fn refused(&self) -> u64 {
        self.hub.refused.load(Ordering::Relaxed)
    }
}

async fn upgrade(State(hub): State<Arc<Hub>>, ws: WebSocketUpgrade) -> Response {
    ws.protocols([ws::SUBPROTOCOL])
        .max_message_size(MAX_CLIENT_MESSAGE)
        .on_upgrade(move |socket| client(socket, hub))
}

/// One Foxglove client: server info and channels, then its subscriptions'
/// messages until it leaves.
async fn client(mut socket: WebSocket, hub: Arc<Hub>) {
    let mut rx = hub.messages.subscribe();
    for text in [ws::server_info("locus", &hub.session), ws::advertise()] {
        if socket.send(WsMessage::Text(text.into())).await.is_err() {
            return;
        }
    }
    let mut subs = ws::Subscriptions::default();
    // The latched messages sent on subscribing: topic and time.
    let mut sent: Vec<(locus_foxglove::Topic, u64)> = Vec::new();
    loop {
        tokio::select! {
            incoming = socket.recv() => {
                let text = match incoming {
                    Some(Ok(WsMessage::Text(t))) => t,
                    Some(Ok(WsMessage::Binary(_))) => {
                        let s = ws::status(1, "ignored a binary message: this server only publishes");
                        if socket.send(WsMessage::Text(s.into())).await.is_err() { return; }
                        continue;
                    }
                    Some(Ok(_)) => continue,
                    Some(Err(_)) | None => return,
                };
                let before = subs.clone();
                if let Some(status) = subs.apply(text.as_str())
                    && socket.send(WsMessage::Text(status.into())).await.is_err()
                {
                    return;
                }
                // The latched map, to a client that has just subscribed to it.
                let latched: Vec<Vec<u8>> = hub
                    .latched
                    .lock()
                    .unwrap_or_else(PoisonError::into_inner)
                    .iter()
                    .filter(|m| before.frame(m).is_none())
                    .filter_map(|m| {
                        if !sent.contains(&(m.topic, m.time)) {
                            sent.push((m.topic, m.time));
                        }
                        subs.frame(m)
                    })
                    .collect();
                for bytes in latched {
                    if socket.send(WsMessage::Binary(bytes.into())).await.is_err() { return; }
                }
            }
            m = rx.recv() => match m {
                // A latched message this client already has (it latched
                // while the client was subscribing) is not sent twice.
                Ok(m) if sent.contains(&(m.topic, m.time)) => {}
                Ok(m) => {
                    if let Some(bytes) = subs.frame(&m)
                        && socket.send(WsMessage::Binary(bytes.into())).await.is_err()
                    {
                        return;
                    }
                }
                Err(broadcast::error::RecvError::Lagged(n)) => {
                    hub.skipped.fetch_add(n, Ordering::Relaxed);
                }
                Err(broadcast::error::RecvError::Closed) => return,
            },
        }
    }
}
