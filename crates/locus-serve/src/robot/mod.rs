//! The page attached to a robot over the link (`locus serve --robot`):
//! one host session ([`locus_net::host::run_host_live`] over UDP or a
//! serial line) on its own thread, shared by every page that connects.
//!
//! The host thread runs [`Host`] between packets: it applies the pages'
//! commands (start, stop, keyboard, live settings) from a channel, turns
//! every applied packet into a [`Sample`](crate::protocol::Sample) and broadcasts a `state` frame
//! every tick with the link's health ([`LinkHealth`](crate::protocol::LinkHealth)). The pages' socket
//! tasks only validate messages and forward frames, so no blocking I/O runs
//! on the async runtime.
//!
//! A robot is not a simulation: it sends no ground truth (no true pose,
//! RMSE or NEES), runs in real time (no speed factor) and cannot be
//! stepped, rewound or reset; those messages are answered with an `error`
//! ([`UNAVAILABLE`]). `step_correction` does not pause it: the next IR
//! correction the host tries (within [`STEP_CORRECTION_MAX_TIME`](crate::session::STEP_CORRECTION_MAX_TIME) of host
//! time) arrives in `state.correction`, to every page. The host starts
//! stopped (zero wheel speeds) until a page sends `start`.
//!
//! Files: this one ([`Attached`], [`Link`]), `command.rs` (the pages'
//! [`Command`]s and [`Settings`], checked), `publisher.rs` (the host
//! thread's side: commands in, `state` frames out).

mod command;
mod publisher;

pub use command::{Command, Settings, command};
use publisher::{Publisher, params_msg};

use alloc::collections::VecDeque;
use alloc::sync::Arc;
use core::net::SocketAddr;
use core::time::Duration;
use std::net::UdpSocket;
use std::sync::{Mutex, PoisonError, mpsc};

use locus_net::host::{Host, HostConfig, LiveTick, run_host_live};
use locus_net::transport::{Serial, Udp};
use tokio::sync::broadcast;

use crate::params::{self};
use crate::protocol::{ClientMsg, RobotInfo, ServerMsg};
use crate::{Error, Limits};

/// The message types a live robot cannot do: it cannot be stepped,
/// rewound, reset, sped up or switched to another scenario, and the host
/// keeps no log to export. (`step_correction` shows the host's next
/// correction while the robot runs on.)
pub const UNAVAILABLE: [&str; 7] = [
    "step", "reset", "speed", "scenario", "preset", "initial", "export",
];

/// How often the host thread looks at the pages' commands when no packet
/// arrives.
const POLL: Duration = Duration::from_millis(20);

/// Latencies kept for the link's median and maximum.
const LATENCY_WINDOW: usize = 1000;

/// State frames buffered per page before a slow page skips some.
const FRAMES_BUFFERED: usize = 64;

/// The link to the robot, already opened.
#[derive(Debug)]
pub enum Link {
    /// UDP datagrams to the robot's address from a bound socket.
    Udp {
        /// The host's socket.
        socket: UdpSocket,
        /// The robot's address.
        robot: SocketAddr,
    },
    /// COBS frames on a serial line (a Bluetooth SPP link is one).
    Serial {
        /// The device path (for the page).
        device: String,
        /// Its line speed (bits per second).
        baud: u32,
        /// The opened port (boxed: it holds a read buffer).
        port: Box<Serial>,
    },
}

impl Link {
    /// A UDP link to `robot` from a socket bound to `bind`.
    ///
    /// # Errors
    /// [`Error::Io`] if the address cannot be bound.
    pub fn udp(bind: SocketAddr, robot: SocketAddr) -> Result<Self, Error> {
        Ok(Self::Udp {
            socket: UdpSocket::bind(bind)?,
            robot,
        })
    }

    /// A serial link on `device` at `baud`.
    ///
    /// # Errors
    /// [`Error::Link`] naming the device if it cannot be opened.
    pub fn serial(device: &str, baud: u32) -> Result<Self, Error> {
        Ok(Self::Serial {
            device: device.to_string(),
            baud,
            port: Box::new(Serial::open(device, baud)?),
        })
    }

    /// What the page shows of the link.
    fn describe(&self) -> String {
        match self {
            Self::Udp { robot, .. } => format!("udp {robot}"),
            Self::Serial { device, baud, .. } => format!("serial {device} at {baud} baud"),
        }
    }
}

/// The newest `params` and `state` (without samples) for a page that
/// connects.
#[derive(Debug, Clone)]
struct Latest {
    params: ServerMsg,
    state: ServerMsg,
}

/// A running host session attached to a robot, shared by the pages.
/// Dropping it (with every page gone) ends the host thread at its next
/// poll: the host stops sending, and the robot's watchdog stops it.
#[derive(Debug)]
pub struct Attached {
    commands: mpsc::Sender<Command>,
    frames: broadcast::Sender<ServerMsg>,
    latest: Arc<Mutex<Latest>>,
    link: String,
    walls: Vec<[[f64; 2]; 2]>,
    dt: f64,
}

impl Attached {
    /// Starts the host session for `cfg` over `link` on its own thread,
    /// stopped (zero wheel speeds until a page sends `start`), publishing
    /// a `state` frame every `tick`. `dt` is the robot's telemetry period
    /// (s), shown on the page.
    ///
    /// # Errors
    /// [`Error::Link`] if `cfg` is invalid; [`Error::Io`] if the thread
    /// cannot be started.
    pub fn start(link: Link, cfg: &HostConfig, dt: f64, tick: Duration) -> Result<Self, Error> {
        Self::start_with(link, cfg, dt, tick, None)
    }

    /// As [`Attached::start`], also publishing every applied packet to the
    /// Foxglove server `foxglove` (its map latched to the arena's walls).
    ///
    /// # Errors
    /// As [`Attached::start`].
    pub fn start_with(
        link: Link,
        cfg: &HostConfig,
        dt: f64,
        tick: Duration,
        foxglove: Option<crate::foxglove::Live>,
    ) -> Result<Self, Error> {
        if let Some(live) = &foxglove {
            // Time 0 is always a Foxglove time.
            let _ = live.latch(&crate::foxglove::arena(cfg), 0.0);
        }
        let mut probe = Host::new(cfg)?;
        probe.set_stopped(true);
        let (commands, inbox) = mpsc::channel();
        let (frames, _) = broadcast::channel(FRAMES_BUFFERED);
        let mut publisher = Publisher {
            inbox,
            frames: frames.clone(),
            latest: Arc::new(Mutex::new(Latest {
                params: params_msg(&probe),
                state: ServerMsg::Error {
                    field: "message".into(),
                    message: "no state yet".into(),
                },
            })),
            tick,
            last_frame: None,
            pending: Vec::new(),
            time: 0.0,
            latencies: VecDeque::new(),
            last: None,
            due: true,
            capture: None,
            foxglove,
        };
        let state = publisher.state(&probe, None, None);
        publisher.lock().state = state;
        let latest = Arc::clone(&publisher.latest);
        let description = link.describe();
        let walls = cfg.walls.iter().map(|w| [w.a, w.b]).collect();
        let cfg = *cfg;
        std::thread::Builder::new()
            .name("locus-serve-host".into())
            .spawn(move || {
                let each = |host: &mut Host, tick: &LiveTick| publisher.each(host, tick);
                let result = match link {
                    Link::Udp { socket, robot } => {
                        run_host_live(&mut Udp::to(&socket, robot), &cfg, POLL, each)
                    }
                    Link::Serial { mut port, .. } => run_host_live(&mut *port, &cfg, POLL, each),
                };
                if let Err(e) = result {
                    publisher.fail(&format!("the link failed: {e}"));
                }
            })?;
        Ok(Self {
            commands,
            frames,
            latest,
            link: description,
            walls,
            dt,
        })
    }

    /// The `hello` of page `session`.
    fn hello(&self, session: u64, limits: &Limits) -> ServerMsg {
        let h = locus_control::SQUARE_HALF_SIDE;
        ServerMsg::Hello {
            session,
            scenario: format!("robot ({})", self.link),
            scenarios: Vec::new(),
            walls: self.walls.clone(),
            path: vec![[-h, -h], [h, -h], [h, h], [-h, h]],
            dt: self.dt,
            presets: Vec::new(),
            limits: params::LIMITS.to_vec(),
            max_message_bytes: limits.max_message_bytes,
            max_messages_per_second: limits.messages_per_second,
            robot: Some(RobotInfo {
                link: self.link.clone(),
                ground_truth: false,
                unavailable: UNAVAILABLE.to_vec(),
            }),
        }
    }

    /// What a page gets on connection: `hello`, the newest `params` and
    /// `state`, and the frames from now on.
    pub fn connect(
        &self,
        session: u64,
        limits: &Limits,
    ) -> (Vec<ServerMsg>, broadcast::Receiver<ServerMsg>) {
        // Subscribe first: a frame sent meanwhile is not lost.
        let rx = self.frames.subscribe();
        let latest = self
            .latest
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .clone();
        (
            vec![self.hello(session, limits), latest.params, latest.state],
            rx,
        )
    }

    /// Handles a page's text message: a valid command goes to the host
    /// thread (its effect arrives in the next frames, to every page);
    /// the answer is an `error` for a refused one, else nothing.
    pub fn handle_text(&self, text: &str) -> Vec<ServerMsg> {
        let msg = match serde_json::from_str::<ClientMsg>(text) {
            Ok(m) => m,
            Err(e) => return vec![crate::protocol::unreadable(&e)],
        };
        match command(msg) {
            Ok(c) => {
                if self.commands.send(c).is_err() {
                    return vec![ServerMsg::Error {
                        field: "message".into(),
                        message: "the host session has ended (see the state's failure)".into(),
                    }];
                }
                Vec::new()
            }
            Err(e) => vec![e.into()],
        }
    }
}
