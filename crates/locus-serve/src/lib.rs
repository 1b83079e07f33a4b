//! Paper 001's teaching interface in the browser, with the production
//! filter behind it.
//!
//! [`app`] is the axum [`Router`]: `GET /` is the page, `GET /assets/..`
//! its scripts and styles (embedded in the binary: it works offline, no
//! CDN), `GET /ws` the WebSocket, `GET /api/health` the session count.
//! Every WebSocket connection gets its own [`session::Session`]: a
//! [`locus_sim::SquareSim`] stepped on the server at the page's speed
//! factor, with a `state` frame every tick ([`Config::tick`]) and commands
//! back from the page ([`protocol`]).
//!
//! [`app_with_robot`] attaches the page to a robot instead
//! ([`robot::Attached`]: one host session over UDP or a serial line, on
//! its own thread, shared by every page): the same arena, estimate,
//! ellipse, plots and NIS, plus the link's health; what a live robot
//! cannot do (step-through, reset, speed factor, presets, export) is
//! refused, and nothing that needs ground truth is shown.
//!
//! # Safety of the server
//! - [`serve`] binds what it is given; the binary binds `127.0.0.1` unless
//!   told otherwise.
//! - A WebSocket upgrade whose `Origin` is not the page's own
//!   (`http://` + the `Host` header) is refused with 403, so another site
//!   open in the browser cannot drive the simulation.
//! - Every value from the page is validated ([`params`]): finite, in range;
//!   a bad one is an `error` message naming the field and the run keeps its
//!   last good values.
//! - Messages are bounded in size ([`Limits::max_message_bytes`]; larger
//!   ones close the connection) and rate ([`Limits::messages_per_second`],
//!   a token bucket; excess messages are dropped with an error), and the
//!   sessions in number ([`Limits::max_sessions`]; 503 beyond).

extern crate alloc;

pub mod foxglove;
pub mod params;
pub mod presets;
pub mod protocol;
pub mod robot;
pub mod session;

use alloc::sync::Arc;
use core::net::SocketAddr;
use core::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use core::time::Duration;
use std::time::Instant;

use axum::Router;
use axum::extract::State;
use axum::extract::ws::rejection::WebSocketUpgradeRejection;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::http::{HeaderMap, HeaderValue, StatusCode, header};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use locus_sim::SquareConfig;

use crate::protocol::ServerMsg;
use crate::session::Session;

/// Errors of the server.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The simulation refused its configuration or failed.
    #[error("simulation: {0}")]
    Sim(#[from] locus_sim::closed_loop::Error),
    /// The scenario is not one the teaching UI runs.
    #[error(
        "the teaching UI runs square-kind scenarios (square, square-ideal, or a file with scenario = \"square\"), not `{0}`"
    )]
    Scenario(String),
    /// Binding or serving failed.
    #[error("server: {0}")]
    Io(#[from] std::io::Error),
    /// The robot's link could not be opened or its host configuration is
    /// invalid.
    #[error("robot link: {0}")]
    Link(#[from] locus_net::Error),
}

/// Bounds on what clients may ask of the server.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Largest WebSocket message (and frame) accepted, bytes; a larger one
    /// closes the connection. Default 16 KiB (the largest legitimate
    /// message, a full `params`, is under 1 KiB).
    pub max_message_bytes: usize,
    /// Sustained messages per second accepted from one client; default 50
    /// (teleoperation repeats at 10 per second).
    pub messages_per_second: f64,
    /// Burst of messages accepted above the rate; default 100.
    pub burst: f64,
    /// Concurrent sessions; default 64.
    pub max_sessions: usize,
    /// Most simulation steps run per tick (bounds the CPU a client can ask
    /// for); default 200.
    pub max_steps_per_tick: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_message_bytes: 16 * 1024,
            messages_per_second: 50.0,
            burst: 100.0,
            max_sessions: 64,
            max_steps_per_tick: 200,
        }
    }
}

/// The server's configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// The scenario's name (shown on the page).
    pub scenario_name: String,
    /// The scenario each new session starts from.
    pub scenario: SquareConfig,
    /// Seed of every session's simulation (a reset replays it).
    pub seed: u64,
    /// Interval between state frames while a run moves. Default 50 ms.
    pub tick: Duration,
    /// Bounds on clients.
    pub limits: Limits,
}

impl Default for Config {
    /// The `square` scenario, seed 1 (as `locus run`), 50 ms ticks,
    /// default limits.
    fn default() -> Self {
        Self {
            scenario_name: locus_sim::scenario_file::Scenario::Square.to_string(),
            scenario: SquareConfig::default(),
            seed: 1,
            tick: Duration::from_millis(50),
            limits: Limits::default(),
        }
    }
}

impl Config {
    /// A configuration for `scenario` named `name`.
    ///
    /// # Errors
    /// [`Error::Sim`] if the simulator refuses it.
    pub fn new(name: &str, scenario: SquareConfig) -> Result<Self, Error> {
        scenario.validate()?;
        Ok(Self {
            scenario_name: name.to_string(),
            scenario,
            ..Self::default()
        })
    }
}

/// State shared by the handlers.
#[derive(Debug)]
struct Shared {
    config: Config,
    sessions: AtomicUsize,
    next_id: AtomicU64,
    /// The robot every page is attached to, if any.
    robot: Option<robot::Attached>,
}

/// Counts a session for as long as it lives.
struct SessionGuard(Arc<Shared>);

impl Drop for SessionGuard {
    fn drop(&mut self) {
        self.0.sessions.fetch_sub(1, Ordering::SeqCst);
    }
}

/// The embedded assets: path under `/assets/`, content type, bytes.
const ASSETS: [(&str, &str, &[u8]); 5] = [
    (
        "app.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../assets/app.js"),
    ),
    (
        "style.css",
        "text/css; charset=utf-8",
        include_bytes!("../assets/style.css"),
    ),
    (
        "vendor/uPlot.iife.min.js",
        "text/javascript; charset=utf-8",
        include_bytes!("../assets/vendor/uPlot.iife.min.js"),
    ),
    (
        "vendor/uPlot.min.css",
        "text/css; charset=utf-8",
        include_bytes!("../assets/vendor/uPlot.min.css"),
    ),
    (
        "favicon.svg",
        "image/svg+xml",
        include_bytes!("../assets/favicon.svg"),
    ),
];

/// The page.
const INDEX: &str = include_str!("../assets/index.html");

/// The router of the teaching UI for `config`: the page, its assets, the
/// WebSocket and `/api/health`. Serve it with [`serve`] or drive it with
/// `tower::ServiceExt::oneshot` in tests.
pub fn app(config: Config) -> Router {
    router(config, None)
}

/// The router of the teaching UI attached to `robot`: every page drives
/// and watches that one host session instead of a simulation of its own
/// (`config` gives the limits and the tick; its scenario is not run).
pub fn app_with_robot(config: Config, robot: robot::Attached) -> Router {
    router(config, Some(robot))
}

fn router(config: Config, robot: Option<robot::Attached>) -> Router {
    let shared = Arc::new(Shared {
        config,
        sessions: AtomicUsize::new(0),
        next_id: AtomicU64::new(1),
        robot,
    });
    Router::new()
        .route("/", get(index))
        .route("/assets/{*path}", get(asset))
        .route("/api/health", get(health))
        .route("/ws", get(ws))
        .with_state(shared)
}

/// Serves [`app`] on `listener` until the process ends.
///
/// # Errors
/// [`Error::Io`] if serving fails.
pub async fn serve(listener: tokio::net::TcpListener, config: Config) -> Result<(), Error> {
    axum::serve(
        listener,
        app(config).into_make_service_with_connect_info::<SocketAddr>(),
    )
    .await?;
    Ok(())
}

/// Serves [`app_with_robot`] on `listener` until the process ends.
///
/// # Errors
/// [`Error::Io`] if serving fails.
pub async fn serve_with_robot(
    listener: tokio::net::TcpListener,
    config: Config,
    robot: robot::Attached,
) -> Result<(), Error> {
    axum::serve(
        listener,
        app_with_robot(config, robot).into_make_service_with_connect_info::<SocketAddr>(),
    )
    .await?;
    Ok(())
}

/// Headers of every page response: no caching of stale assets, no framing
/// by other sites, no sniffing.
fn secure(mut response: Response) -> Response {
    let h = response.headers_mut();
    h.insert(header::CACHE_CONTROL, HeaderValue::from_static("no-cache"));
    h.insert(header::X_FRAME_OPTIONS, HeaderValue::from_static("DENY"));
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        HeaderValue::from_static("nosniff"),
    );
    h.insert(
        header::CONTENT_SECURITY_POLICY,
        HeaderValue::from_static(
            "default-src 'self'; connect-src 'self'; img-src 'self' data: blob:; style-src 'self' 'unsafe-inline'",
        ),
    );
    response
}

async fn index() -> Response {
    secure(([(header::CONTENT_TYPE, "text/html; charset=utf-8")], INDEX).into_response())
}

async fn asset(axum::extract::Path(path): axum::extract::Path<String>) -> Response {
    match ASSETS.iter().find(|(p, _, _)| *p == path) {
        Some((_, mime, bytes)) => secure(([(header::CONTENT_TYPE, *mime)], *bytes).into_response()),
        None => (StatusCode::NOT_FOUND, "no such asset").into_response(),
    }
}

async fn health(State(shared): State<Arc<Shared>>) -> Response {
    axum::Json(serde_json::json!({
        "sessions": shared.sessions.load(Ordering::SeqCst),
        "max_sessions": shared.config.limits.max_sessions,
    }))
    .into_response()
}

/// Whether the upgrade's `Origin` is the page's own: absent (not a browser:
/// no other site is involved) or `http://` + `Host`, where `Host` names
/// this machine by `localhost` or by an IP address. A domain name is
/// refused even when Origin and Host agree: that is what a DNS-rebinding
/// page (a foreign site whose name now resolves to this server) sends.
fn origin_allowed(headers: &HeaderMap) -> bool {
    let Some(origin) = headers.get(header::ORIGIN) else {
        return true;
    };
    let Some(host) = headers.get(header::HOST).and_then(|h| h.to_str().ok()) else {
        return false;
    };
    host_is_address(host)
        && origin
            .to_str()
            .is_ok_and(|o| o.strip_prefix("http://") == Some(host))
}

/// Whether a `Host` header value (`name[:port]`, `[v6][:port]`) names the
/// server by `localhost` or an IP literal rather than by a domain name.
fn host_is_address(host: &str) -> bool {
    let name = if let Some(rest) = host.strip_prefix('[') {
        // An IPv6 literal: `[addr]` or `[addr]:port`.
        match rest.split_once(']') {
            Some((addr, tail)) if tail.is_empty() || tail.starts_with(':') => addr,
            _ => return false,
        }
    } else {
        host.rsplit_once(':').map_or(host, |(name, _port)| name)
    };
    name.eq_ignore_ascii_case("localhost") || name.parse::<core::net::IpAddr>().is_ok()
}

async fn ws(
    State(shared): State<Arc<Shared>>,
    headers: HeaderMap,
    upgrade: Result<WebSocketUpgrade, WebSocketUpgradeRejection>,
) -> Response {
    if !origin_allowed(&headers) {
        return (
            StatusCode::FORBIDDEN,
            "WebSocket refused: foreign Origin (open the page from this server)",
        )
            .into_response();
    }
    let upgrade = match upgrade {
        Ok(u) => u,
        Err(rejection) => return rejection.into_response(),
    };
    let limits = shared.config.limits;
    // Count the session now, so a burst of upgrades cannot exceed the cap.
    let n = shared.sessions.fetch_add(1, Ordering::SeqCst);
    let guard = SessionGuard(Arc::clone(&shared));
    if n >= limits.max_sessions {
        drop(guard);
        return (
            StatusCode::SERVICE_UNAVAILABLE,
            "too many sessions; try again later",
        )
            .into_response();
    }
    upgrade
        .max_message_size(limits.max_message_bytes)
        .max_frame_size(limits.max_message_bytes)
        .on_upgrade(move |socket| async move {
            run_session(socket, &shared).await;
            drop(guard);
        })
}

/// Sends `msg` as JSON text; `false` if the client has gone.
async fn send(socket: &mut WebSocket, msg: &ServerMsg) -> bool {
    match serde_json::to_string(msg) {
        Ok(text) => socket.send(Message::Text(text.into())).await.is_ok(),
        Err(_) => false,
    }
}

/// A token bucket of `rate` per second and `burst`.
struct Bucket {
    tokens: f64,
    rate: f64,
    burst: f64,
    at: Instant,
    /// When the client was last told it is too fast.
    warned: Option<Instant>,
}

impl Bucket {
    fn new(rate: f64, burst: f64) -> Self {
        Self {
            tokens: burst,
            rate,
            burst,
            at: Instant::now(),
            warned: None,
        }
    }

    fn take(&mut self, now: Instant) -> bool {
        let dt = now.saturating_duration_since(self.at).as_secs_f64();
        self.at = now;
        self.tokens = (self.tokens + dt * self.rate).min(self.burst);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }
}

/// Tells the client it is too fast, at most once a second; `false` if
/// the client has gone.
async fn too_fast(
    socket: &mut WebSocket,
    bucket: &mut Bucket,
    limits: &Limits,
    now: Instant,
) -> bool {
    if bucket
        .warned
        .is_none_or(|w| now.duration_since(w) >= Duration::from_secs(1))
    {
        bucket.warned = Some(now);
        let e = ServerMsg::Error {
            field: "message".into(),
            message: format!(
                "too many messages (over {} per second): dropped",
                limits.messages_per_second
            ),
        };
        return send(socket, &e).await;
    }
    true
}

/// What one WebSocket message from a page comes to after the checks every
/// page gets (simulator or robot): a JSON text within the rate limit and
/// when it arrived, or nothing to act on, or the end of the connection.
enum Incoming {
    Text(axum::extract::ws::Utf8Bytes, Instant),
    Skip,
    Close,
}

/// Checks one received message: binary messages are answered with an
/// error, pings skipped, a page over its rate limit warned ([`too_fast`]).
async fn incoming(
    msg: Option<Result<Message, axum::Error>>,
    socket: &mut WebSocket,
    bucket: &mut Bucket,
    limits: &Limits,
) -> Incoming {
    let Some(Ok(msg)) = msg else {
        return Incoming::Close;
    };
    let now = Instant::now();
    let text = match msg {
        Message::Text(t) => t,
        Message::Binary(_) => {
            let e = ServerMsg::Error {
                field: "message".into(),
                message: "binary messages are not accepted; send JSON text".into(),
            };
            return if send(socket, &e).await {
                Incoming::Skip
            } else {
                Incoming::Close
            };
        }
        Message::Close(_) => return Incoming::Close,
        Message::Ping(_) | Message::Pong(_) => return Incoming::Skip,
    };
    if !bucket.take(now) {
        return if too_fast(socket, bucket, limits, now).await {
            Incoming::Skip
        } else {
            Incoming::Close
        };
    }
    Incoming::Text(text, now)
}

/// A page attached to the robot: its messages go to the host thread (after
/// the same size and rate limits), the host's frames come back.
async fn run_robot_page(mut socket: WebSocket, shared: &Shared, robot: &robot::Attached) {
    let limits = shared.config.limits;
    let id = shared.next_id.fetch_add(1, Ordering::SeqCst);
    let (first, mut frames) = robot.connect(id, &limits);
    for m in &first {
        if !send(&mut socket, m).await {
            return;
        }
    }
    let mut bucket = Bucket::new(limits.messages_per_second, limits.burst);
    loop {
        tokio::select! {
            msg = socket.recv() => {
                let text = match incoming(msg, &mut socket, &mut bucket, &limits).await {
                    Incoming::Text(text, _) => text,
                    Incoming::Skip => continue,
                    Incoming::Close => break,
                };
                for out in robot.handle_text(text.as_str()) {
                    if !send(&mut socket, &out).await { return }
                }
            }
            frame = frames.recv() => match frame {
                Ok(m) => if !send(&mut socket, &m).await { break },
                // A slow page skips frames (their samples are lost to it).
                Err(tokio::sync::broadcast::error::RecvError::Lagged(_)) => {}
                Err(tokio::sync::broadcast::error::RecvError::Closed) => break,
            },
        }
    }
}

async fn run_session(mut socket: WebSocket, shared: &Shared) {
    if let Some(robot) = &shared.robot {
        run_robot_page(socket, shared, robot).await;
        return;
    }
    let cfg = &shared.config;
    let id = shared.next_id.fetch_add(1, Ordering::SeqCst);
    let Ok(mut session) = Session::new(id, &cfg.scenario_name, &cfg.scenario, cfg.seed, cfg.limits)
    else {
        return;
    };
    if !send(&mut socket, &session.hello()).await
        || !send(&mut socket, &session.params()).await
        || !send(&mut socket, &session.frame()).await
    {
        return;
    }
    let mut bucket = Bucket::new(cfg.limits.messages_per_second, cfg.limits.burst);
    let mut ticker = tokio::time::interval(cfg.tick);
    ticker.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
    let mut last = Instant::now();
    loop {
        tokio::select! {
            msg = socket.recv() => {
                let (text, now) = match incoming(msg, &mut socket, &mut bucket, &cfg.limits).await {
                    Incoming::Text(text, now) => (text, now),
                    Incoming::Skip => continue,
                    Incoming::Close => break,
                };
                for out in session.handle_text(text.as_str(), now) {
                    if !send(&mut socket, &out).await { return }
                }
            }
            _ = ticker.tick() => {
                let now = Instant::now();
                let elapsed = now.duration_since(last);
                last = now;
                if let Some(frame) = session.tick(elapsed, now)
                    && !send(&mut socket, &frame).await
                {
                    break;
                }
            }
        }
    }
}
