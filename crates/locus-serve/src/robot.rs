//! The page attached to a robot over the link (`locus serve --robot`):
//! one host session ([`locus_net::host::run_host_live`] over UDP or a
//! serial line) on its own thread, shared by every page that connects.
//!
//! The host thread runs [`Host`] between packets: it applies the pages'
//! commands (start, stop, keyboard, live settings) from a channel, turns
//! every applied packet into a [`Sample`] and broadcasts a `state` frame
//! every tick with the link's health ([`LinkHealth`]). The pages' socket
//! tasks only validate messages and forward frames, so no blocking I/O runs
//! on the async runtime.
//!
//! A robot is not a simulation: it sends no ground truth (no true pose,
//! RMSE or NEES), runs in real time (no speed factor) and cannot be
//! stepped, rewound or reset; those messages are answered with an `error`
//! ([`UNAVAILABLE`]). The host starts stopped (zero wheel speeds) until a
//! page sends `start`.

use alloc::collections::VecDeque;
use alloc::sync::Arc;
use core::net::SocketAddr;
use core::ops::ControlFlow;
use core::time::Duration;
use std::net::UdpSocket;
use std::sync::{Mutex, PoisonError, mpsc};
use std::time::Instant;

use locus_net::host::{Drive, Host, HostConfig, LiveTick, run_host_live};
use locus_net::transport::{Serial, Udp};
use serde_json::{Map, Value};
use tokio::sync::broadcast;

use crate::params::{self, Invalid};
use crate::protocol::{ClientMsg, LinkHealth, ParamValues, RobotInfo, Sample, ServerMsg};
use crate::session::TELEOP_TIMEOUT;
use crate::{Error, Limits};

/// The message types a live robot cannot do: it cannot be stepped,
/// rewound, reset, sped up or switched to another scenario, and the host
/// keeps no log to export.
pub const UNAVAILABLE: [&str; 8] = [
    "step",
    "step_correction",
    "reset",
    "speed",
    "scenario",
    "preset",
    "initial",
    "export",
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

/// A page's command to the host thread, validated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Resume the path controller.
    Start,
    /// Zero wheel speeds (the operator's twist ends too).
    Stop,
    /// The operator's body twist (m/s, rad/s) for [`TELEOP_TIMEOUT`].
    Teleop {
        /// Linear speed (m/s).
        v: f64,
        /// Turn rate (rad/s).
        w: f64,
    },
    /// Back to the controller (or to zero speeds if stopped).
    TeleopOff,
    /// Live settings (a patch: the fields given).
    Settings(Settings),
}

/// Live settings from the page: the fields given, each already within
/// [`params::LIMITS`].
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Settings {
    /// `Q11` (m^2 per step).
    pub q11: Option<f64>,
    /// `Q22` (rad^2 per step).
    pub q22: Option<f64>,
    /// `R11` (m^2).
    pub r11: Option<f64>,
    /// `R22` (m^2).
    pub r22: Option<f64>,
    /// Whether the filter uses the IR readings.
    pub use_ir: Option<bool>,
    /// Gate confidence (0: no gate).
    pub gate: Option<f64>,
    /// `V_ref` (m/s).
    pub v_ref: Option<f64>,
    /// `W_ref` (rad/s).
    pub w_ref: Option<f64>,
    /// Cross-track gain (rad/m).
    pub k_cross: Option<f64>,
    /// Heading gain (1/s).
    pub k_heading: Option<f64>,
    /// Position gain (1/s).
    pub k_pos: Option<f64>,
}

impl Settings {
    /// The settings in `values` (the `params` message's fields), each
    /// checked against its limit; all or nothing.
    ///
    /// # Errors
    /// [`Invalid`] naming the first bad field; `ir_sigma` (the
    /// simulator's injected noise) and unknown fields are refused.
    pub fn parse(values: &Map<String, Value>) -> Result<Self, Invalid> {
        let mut s = Self::default();
        for (key, value) in values {
            let num = || params::checked(key, value).map(Some);
            match key.as_str() {
                "q11" => s.q11 = num()?,
                "q22" => s.q22 = num()?,
                "r11" => s.r11 = num()?,
                "r22" => s.r22 = num()?,
                "gate" => s.gate = num()?,
                "v_ref" => s.v_ref = num()?,
                "w_ref" => s.w_ref = num()?,
                "k_cross" => s.k_cross = num()?,
                "k_heading" => s.k_heading = num()?,
                "k_pos" => s.k_pos = num()?,
                "use_ir" => s.use_ir = Some(params::boolean(key, value)?),
                "ir_sigma" => {
                    return Err(Invalid::new(
                        key,
                        "is the simulator's injected noise: a robot's IR noise is its own",
                    ));
                }
                _ => return Err(Invalid::new(key, "is not a live parameter")),
            }
        }
        Ok(s)
    }

    /// Applies the settings to `host` from its next packet on. Values
    /// within [`params::LIMITS`] are always accepted (every limit is
    /// inside the host's domain), so a patch is applied whole.
    ///
    /// # Errors
    /// The host's [`locus_net::Error::Config`] for a value outside its
    /// domain (the noise, then the gate, then the controller are set in
    /// that order).
    pub fn apply(&self, host: &mut Host) -> Result<(), locus_net::Error> {
        let c = *host.config();
        let l = c.localiser;
        if self.q11.is_some() || self.q22.is_some() || self.r11.is_some() || self.r22.is_some() {
            host.set_noise(
                self.q11.unwrap_or(l.q11),
                self.q22.unwrap_or(l.q22),
                self.r11.unwrap_or(l.r11),
                self.r22.unwrap_or(l.r22),
            )?;
        }
        if let Some(g) = self.gate {
            host.set_gate((g > 0.0).then_some(g))?;
        }
        if let Some(on) = self.use_ir {
            host.set_use_ir(on);
        }
        let k = c.control;
        let control = locus_control::Config {
            v_ref: self.v_ref.unwrap_or(k.v_ref),
            w_ref: self.w_ref.unwrap_or(k.w_ref),
            k_cross: self.k_cross.unwrap_or(k.k_cross),
            k_heading: self.k_heading.unwrap_or(k.k_heading),
            k_pos: self.k_pos.unwrap_or(k.k_pos),
            ..k
        };
        if control != k {
            host.set_control(control)?;
        }
        Ok(())
    }
}

/// A page's message as a host command, validated.
///
/// # Errors
/// [`Invalid`]: a bad value, or a message a live robot cannot do
/// ([`UNAVAILABLE`]), named by its type.
pub fn command(msg: ClientMsg) -> Result<Command, Invalid> {
    let unavailable = |what: &str| {
        Err(Invalid::new(
            what,
            "is not available when attached to a robot (it runs live, in real time, and sends no ground truth)",
        ))
    };
    match msg {
        ClientMsg::Start {} => Ok(Command::Start),
        ClientMsg::Stop {} => Ok(Command::Stop),
        ClientMsg::Teleop { v, w } => Ok(Command::Teleop {
            v: params::checked("teleop_v", &v)?,
            w: params::checked("teleop_w", &w)?,
        }),
        ClientMsg::TeleopOff {} => Ok(Command::TeleopOff),
        ClientMsg::Params { values } => Settings::parse(&values).map(Command::Settings),
        ClientMsg::Step {} => unavailable("step"),
        ClientMsg::StepCorrection {} => unavailable("step_correction"),
        ClientMsg::Reset {} => unavailable("reset"),
        ClientMsg::Speed { .. } => unavailable("speed"),
        ClientMsg::Scenario { .. } => unavailable("scenario"),
        ClientMsg::Preset { .. } => unavailable("preset"),
        ClientMsg::Initial { .. } => unavailable("initial"),
        ClientMsg::Export {} => unavailable("export"),
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
        };
        let state = publisher.state(&probe, None);
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
            Err(e) => {
                return vec![ServerMsg::Error {
                    field: "message".into(),
                    message: format!("not a valid message: {e}"),
                }];
            }
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

/// The `params` message of the host's values in use.
fn params_msg(host: &Host) -> ServerMsg {
    let c = host.config();
    let l = &c.localiser;
    ServerMsg::Params {
        values: ParamValues {
            q11: l.q11,
            q22: l.q22,
            r11: l.r11,
            r22: l.r22,
            ir_sigma: None,
            use_ir: c.use_ir,
            gate: l.gate_confidence.unwrap_or(0.0),
            v_ref: c.control.v_ref,
            w_ref: c.control.w_ref,
            k_cross: c.control.k_cross,
            k_heading: c.control.k_heading,
            k_pos: c.control.k_pos,
            start_x: l.start[0],
            start_y: l.start[1],
            start_theta: l.start[2],
            std_x: l.initial_std[0],
            std_y: l.initial_std[1],
            std_theta: l.initial_std[2],
            speed: None,
        },
        preset: None,
    }
}

/// The host thread's side: commands in, frames out.
struct Publisher {
    inbox: mpsc::Receiver<Command>,
    frames: broadcast::Sender<ServerMsg>,
    latest: Arc<Mutex<Latest>>,
    tick: Duration,
    last_frame: Option<Instant>,
    pending: Vec<Sample>,
    /// Robot time of the last applied packet (s).
    time: f64,
    latencies: VecDeque<f64>,
    /// The last tick seen (for the link's health).
    last: Option<LiveTick>,
    /// A frame is due now (a command changed something).
    due: bool,
}

impl Publisher {
    fn lock(&self) -> std::sync::MutexGuard<'_, Latest> {
        self.latest.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Sends `msg` to every page (none connected is fine).
    fn publish(&self, msg: ServerMsg) {
        let _ = self.frames.send(msg);
    }

    /// One call of the live loop: commands, the packet's sample, a frame
    /// when due.
    fn each(&mut self, host: &mut Host, tick: &LiveTick) -> ControlFlow<()> {
        if self.last.is_none() {
            // Before anything is sent: the robot waits for a page's start.
            host.set_stopped(true);
        }
        loop {
            match self.inbox.try_recv() {
                Ok(c) => self.apply(host, c, tick.host_time),
                Err(mpsc::TryRecvError::Empty) => break,
                // The server has gone: end the session.
                Err(mpsc::TryRecvError::Disconnected) => return ControlFlow::Break(()),
            }
        }
        if let Some(step) = tick.step {
            let p = host.belief().p;
            self.time = step.robot_time;
            self.pending.push(Sample {
                t: step.robot_time,
                truth: None,
                ekf: step.estimate,
                p: [p[(0, 0)], p[(1, 1)], p[(2, 2)], p[(0, 1)]],
                odo: None,
                wheels: step
                    .command
                    .map_or([0.0; 2], |[r, l]| [f64::from(r), f64::from(l)]),
                ir: step.ir.map(|[a, b]| [f64::from(a), f64::from(b)]),
                innovation: step.innovation,
                nis: step.nis,
                applied: step.corrected,
                nees: None,
            });
        }
        if let Some(l) = tick.latency {
            if self.latencies.len() == LATENCY_WINDOW {
                self.latencies.pop_front();
            }
            self.latencies.push_back(l);
        }
        self.last = Some(*tick);
        let now = Instant::now();
        if self.due
            || self
                .last_frame
                .is_none_or(|t| now.duration_since(t) >= self.tick)
        {
            self.due = false;
            self.last_frame = Some(now);
            let samples = core::mem::take(&mut self.pending);
            let frame = self.state(host, Some(samples));
            self.lock().state = self.state(host, None);
            self.publish(frame);
        }
        ControlFlow::Continue(())
    }

    /// Applies a page's command at host time `now` (s).
    fn apply(&mut self, host: &mut Host, c: Command, now: f64) {
        self.due = true;
        match c {
            Command::Start => host.set_stopped(false),
            Command::Stop => {
                host.clear_teleop();
                host.set_stopped(true);
            }
            Command::Teleop { v, w } => {
                // Validated by the page's session: finite.
                let _ = host.set_teleop(v, w, now + TELEOP_TIMEOUT.as_secs_f64());
            }
            Command::TeleopOff => host.clear_teleop(),
            Command::Settings(s) => match s.apply(host) {
                Ok(()) => {
                    let p = params_msg(host);
                    self.lock().params = p.clone();
                    self.publish(p);
                }
                Err(e) => self.publish(ServerMsg::Error {
                    field: "params".into(),
                    message: e.to_string(),
                }),
            },
        }
    }

    /// The link ended with `why`: a last frame saying so.
    fn fail(&mut self, why: &str) {
        let mut latest = self.lock();
        if let ServerMsg::State {
            failure, running, ..
        } = &mut latest.state
        {
            *failure = Some(why.to_string());
            *running = false;
        }
        let frame = latest.state.clone();
        drop(latest);
        self.publish(frame);
    }

    /// The `state` frame of the host now, with `samples` (none: empty).
    #[allow(clippy::cast_possible_truncation)]
    fn state(&self, host: &Host, samples: Option<Vec<Sample>>) -> ServerMsg {
        let t = self.last.unwrap_or(LiveTick {
            host_time: 0.0,
            step: None,
            latency: None,
            commands_sent: 0,
            framing: locus_link::framing::FrameCounters::default(),
            silent: true,
        });
        let drive = host.drive(t.host_time);
        let c = host.counters();
        let mut lat: Vec<f64> = self.latencies.iter().copied().collect();
        lat.sort_by(f64::total_cmp);
        let clock = host.clock();
        ServerMsg::State {
            running: drive != Drive::Stopped,
            finished: false,
            time: self.time,
            steps: c.applied as usize,
            laps: host.laps(),
            teleop: matches!(drive, Drive::Teleop { .. }),
            samples: samples.unwrap_or_default(),
            beams: Vec::new(),
            correction: None,
            figure: None,
            failure: None,
            link: Some(LinkHealth {
                silent: t.silent,
                drive: match drive {
                    Drive::Path => "path",
                    Drive::Stopped => "stopped",
                    Drive::Teleop { .. } => "keyboard",
                },
                applied: c.applied,
                lost: c.lost,
                duplicate: c.duplicate,
                late: c.late,
                corrupt: c.corrupt,
                malformed: c.malformed,
                suspect: c.suspect,
                implausible: c.implausible,
                resync: c.resync,
                frames_malformed: t.framing.malformed,
                frames_oversize: t.framing.oversize,
                filter_errors: host.filter_errors(),
                corrections: host.corrections(),
                commands_sent: t.commands_sent,
                latency_p50_us: lat.get(lat.len() / 2).map(|v| v * 1e6),
                latency_max_us: lat.last().map(|v| v * 1e6),
                clock_offset_s: clock.map(|f| f.offset),
                clock_drift_ppm: clock.map(|f| f.drift * 1e6),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn host() -> Host {
        let mut cfg = locus_sim::link_robot::host_config(&locus_sim::SquareConfig::default());
        cfg.laps = usize::MAX;
        Host::new(&cfg).unwrap()
    }

    fn values(v: &Value) -> Map<String, Value> {
        v.as_object().unwrap().clone()
    }

    #[test]
    fn settings_are_checked_whole_and_applied_to_the_host() {
        for (v, field) in [
            (json!({"r11": 1e-3, "ir_sigma": 0.01}), "ir_sigma"),
            (json!({"r11": 1e-3, "q22": "1e999"}), "q22"),
            (json!({"gate": 1.5}), "gate"),
            (json!({"use_ir": "maybe"}), "use_ir"),
            (json!({"start_x": 0.1}), "start_x"),
        ] {
            assert_eq!(
                Settings::parse(&values(&v)).unwrap_err().field,
                field,
                "{v}"
            );
        }
        let mut h = host();
        let before = *h.config();
        let s = Settings::parse(&values(
            &json!({"r22": "4e-4", "gate": 0, "use_ir": false, "k_pos": 2}),
        ))
        .unwrap();
        s.apply(&mut h).unwrap();
        let c = h.config();
        assert_eq!(c.localiser.r22, 4e-4);
        assert_eq!(
            c.localiser.r11, before.localiser.r11,
            "fields not given are kept"
        );
        assert_eq!(c.localiser.gate_confidence, None, "gate 0: no gate");
        assert!(!c.use_ir);
        assert_eq!(c.control.k_pos, 2.0);
        assert_eq!(c.control.v_ref, before.control.v_ref);
    }

    #[test]
    fn what_a_live_robot_cannot_do_is_refused_by_name() {
        for kind in UNAVAILABLE {
            let text = match kind {
                "speed" => json!({"type": kind, "factor": 2}),
                "scenario" => json!({"type": kind, "name": "square"}),
                "preset" => json!({"type": kind, "step": "a"}),
                "initial" => json!({"type": kind, "values": {}}),
                _ => json!({"type": kind}),
            };
            let msg: ClientMsg = serde_json::from_value(text).unwrap();
            let e = command(msg).unwrap_err();
            assert_eq!(e.field, kind);
            assert!(e.reason.contains("not available when attached to a robot"));
        }
        let msg: ClientMsg =
            serde_json::from_value(json!({"type": "teleop", "v": 0.1, "w": -1})).unwrap();
        assert_eq!(command(msg), Ok(Command::Teleop { v: 0.1, w: -1.0 }));
    }
}
