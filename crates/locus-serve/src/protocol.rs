//! The WebSocket protocol: one JSON object per text message, tagged by
//! `type` (docs/ui.md lists every message with an example).
//!
//! The page sends [`ClientMsg`]; the server answers with [`ServerMsg`]: a
//! `hello` on connection, a `state` frame every tick while the run moves
//! (and after every command), `params` when the values in use change,
//! `error` for a refused message or value, `csv` for an export.

use locus_sim::CorrectionDetail;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use crate::params::{InitialPatch, Invalid, Limit, ParamPatch};
use crate::presets::{LiveFigure, Preset};

/// A message from the page.
///
/// The messages without fields are empty struct variants (`Start {}`), not
/// unit variants: serde's `deny_unknown_fields` ignores the extra keys of
/// an internally tagged unit variant, and docs/ui.md promises that unknown
/// fields are refused on every message.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum ClientMsg {
    /// Run (at the speed factor).
    Start {},
    /// Pause.
    Stop {},
    /// Restart the run from the initial pose and covariance (new values of
    /// `initial` apply here), same seed.
    Reset {},
    /// One step of `dt` (pauses first).
    Step {},
    /// Steps until the next correction (at most 10 s of simulated time),
    /// paused, for the step-through view.
    StepCorrection {},
    /// The speed factor (simulated over wall-clock time), `speed` limit.
    Speed {
        /// The factor: a number or its text.
        factor: Value,
    },
    /// Keyboard teleoperation: this command until `teleop_off` or 0.5 s
    /// without a repeat.
    Teleop {
        /// Linear speed (m/s).
        v: Value,
        /// Turn rate (rad/s).
        w: Value,
    },
    /// Back to the path controller.
    TeleopOff {},
    /// Live parameters; each field is optional, all or nothing is applied;
    /// an unknown field makes the message invalid.
    Params {
        /// The fields: `q11`, `q22`, `r11`, `r22`, `ir_sigma`, `use_ir`,
        /// `gate` (0: no gate), `v_ref`, `w_ref`, `k_cross`, `k_heading`,
        /// `k_pos`;
        /// numbers or their text.
        values: ParamPatch,
    },
    /// Initial pose and covariance (standard deviations), applied at the
    /// next reset: `start_x`, `start_y`, `start_theta`, `std_x`, `std_y`,
    /// `std_theta`.
    Initial {
        /// The fields, numbers or their text.
        values: InitialPatch,
    },
    /// Switch scenario (`square` or `square-ideal`) and reset.
    Scenario {
        /// Its name.
        name: String,
    },
    /// Apply a guide step's configuration (`a` to `f`) and reset.
    Preset {
        /// The step's letter.
        step: String,
    },
    /// Ask for the run's log as CSV (the format of `locus run`'s `log.csv`).
    Export {},
}

/// One step as the page plots it (SI units).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Sample {
    /// Simulated time (s).
    pub t: f64,
    /// True pose `[x, y, theta]`; `None` (JSON `null`) for a robot on the
    /// link, which sends no ground truth.
    pub truth: Option<[f64; 3]>,
    /// EKF estimate `[x, y, theta]`.
    pub ekf: [f64; 3],
    /// `[P_xx, P_yy, P_thth, P_xy]` (m^2, m^2, rad^2, m^2).
    pub p: [f64; 4],
    /// Odometry-only position `[x, y]`; `None` for a robot on the link (the
    /// host runs no odometry-only filter).
    pub odo: Option<[f64; 2]>,
    /// Wheel speeds `[V1 (right), V2 (left)]` (m/s).
    pub wheels: [f64; 2],
    /// IR distances `[d_s1, d_s2]` (m) when both were in range.
    pub ir: Option<[f64; 2]>,
    /// Innovation `[m, rad]` when a reading was associated.
    pub innovation: Option<[f64; 2]>,
    /// Its NIS.
    pub nis: Option<f64>,
    /// Whether the correction passed the gate.
    pub applied: bool,
    /// NEES of the estimate (needs the truth: `None` for a robot on the
    /// link; `null` too when P does not factor).
    pub nees: Option<f64>,
}

/// A sensor beam in the world frame, from the true pose: origin and end
/// (m); `hit` when the sensor read a distance (the end is the reading),
/// else the end is at the sensor's range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Beam {
    /// Origin `[x, y]`.
    pub from: [f64; 2],
    /// End `[x, y]`.
    pub to: [f64; 2],
    /// Whether the sensor read a distance.
    pub hit: bool,
}

/// The parameter values in use (the panel's fields).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ParamValues {
    /// `Q11` (m^2 per step).
    pub q11: f64,
    /// `Q22` (rad^2 per step).
    pub q22: f64,
    /// `R11` (m^2).
    pub r11: f64,
    /// `R22` (m^2).
    pub r22: f64,
    /// Injected IR noise (m); `None` for a robot on the link (its noise is
    /// its own).
    pub ir_sigma: Option<f64>,
    /// Whether the filter uses the IR.
    pub use_ir: bool,
    /// Gate confidence (0: no gate).
    pub gate: f64,
    /// `V_ref` (m/s).
    pub v_ref: f64,
    /// `W_ref` (rad/s).
    pub w_ref: f64,
    /// Cross-track gain (rad/m).
    pub k_cross: f64,
    /// Heading gain (1/s).
    pub k_heading: f64,
    /// Position gain of the corner approach (1/s).
    pub k_pos: f64,
    /// Initial pose x (m), at the next reset.
    pub start_x: f64,
    /// Initial pose y (m).
    pub start_y: f64,
    /// Initial heading (rad).
    pub start_theta: f64,
    /// Initial standard deviation of x (m).
    pub std_x: f64,
    /// Of y (m).
    pub std_y: f64,
    /// Of the heading (rad).
    pub std_theta: f64,
    /// Speed factor; `None` for a robot on the link (it runs in real
    /// time).
    pub speed: Option<f64>,
}

/// What the page is attached to when it drives a robot over the link
/// (`hello.robot`); absent for the in-process simulation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RobotInfo {
    /// The link, e.g. `udp 127.0.0.1:7700` or `serial /dev/rfcomm0 at
    /// 115200 baud`.
    pub link: String,
    /// Whether the robot sends its true pose: always `false` (the link
    /// carries none), so RMSE, NEES and error figures are not available.
    pub ground_truth: bool,
    /// The message types a live robot cannot do (they are answered with an
    /// `error`): step-through, reset, speed factor, scenario, presets,
    /// initial values, export.
    pub unavailable: Vec<&'static str>,
}

/// The link's health (`state.link`) while attached to a robot: the host's
/// counters (docs/protocol.md defines each), latency and clock.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LinkHealth {
    /// No packet applied for the host's `quiet` time (or none yet): the
    /// host is sending zero-speed hellos until the robot answers.
    pub silent: bool,
    /// Who drives: `path` (the controller), `stopped` (zero speeds) or
    /// `keyboard`.
    pub drive: &'static str,
    /// Telemetry packets applied.
    pub applied: u64,
    /// Packets never received (sequence gaps).
    pub lost: u64,
    /// Packets received twice.
    pub duplicate: u64,
    /// Packets older than the newest applied one.
    pub late: u64,
    /// Packets with a bad CRC.
    pub corrupt: u64,
    /// Packets with a good CRC and an impossible layout.
    pub malformed: u64,
    /// Packets whose sequence number jumped too far.
    pub suspect: u64,
    /// Packets whose content the plausibility limits refused.
    pub implausible: u64,
    /// Times the host followed a robot that restarted.
    pub resync: u64,
    /// Serial frames the COBS decoder dropped as malformed (0 on UDP).
    pub frames_malformed: u64,
    /// Serial frames dropped as oversize (0 on UDP).
    pub frames_oversize: u64,
    /// Filter errors (the belief was kept).
    pub filter_errors: u64,
    /// IR corrections applied.
    pub corrections: u64,
    /// Commands sent (zero-speed hellos included).
    pub commands_sent: u64,
    /// Receive-to-command latency, median over the last 1000 commands
    /// (us).
    pub latency_p50_us: Option<f64>,
    /// Its largest value over the same commands (us).
    pub latency_max_us: Option<f64>,
    /// Robot clock offset of the estimator's fit (s): `robot = offset + (1
    /// + drift) host`.
    pub clock_offset_s: Option<f64>,
    /// Its drift (ppm).
    pub clock_drift_ppm: Option<f64>,
}

/// A message to the page. (Built, serialised and dropped at once: the
/// size difference of the variants does not matter.)
#[derive(Debug, Clone, Serialize)]
#[allow(clippy::large_enum_variant)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ServerMsg {
    /// Sent once on connection: the arena and everything static.
    Hello {
        /// The session's number (for the page's title; not a secret).
        session: u64,
        /// The scenario's name.
        scenario: String,
        /// The scenarios one can switch to.
        scenarios: Vec<&'static str>,
        /// Walls `[[ax, ay], [bx, by]]` (m).
        walls: Vec<[[f64; 2]; 2]>,
        /// Corners of the square path (m), in driving order.
        path: Vec<[f64; 2]>,
        /// Filter step (s).
        dt: f64,
        /// The guide's presets.
        presets: Vec<Preset>,
        /// Accepted ranges of every numeric field.
        limits: Vec<Limit>,
        /// The largest text message accepted (bytes).
        max_message_bytes: usize,
        /// The most messages accepted per second (sustained).
        max_messages_per_second: f64,
        /// The robot the page is attached to; `None`: the in-process
        /// simulation.
        robot: Option<RobotInfo>,
    },
    /// The values in use.
    Params {
        /// The values.
        values: ParamValues,
        /// The preset applied last (`None` once a value is changed by hand).
        preset: Option<char>,
    },
    /// The run's state and the steps since the previous frame.
    State {
        /// Whether the run is moving.
        running: bool,
        /// Whether the run has ended (laps done or time limit).
        finished: bool,
        /// Simulated time (s); for a robot, the robot's time of its last
        /// applied packet.
        time: f64,
        /// Steps run; for a robot, telemetry packets applied.
        steps: usize,
        /// Laps done.
        laps: usize,
        /// Whether the keyboard is driving.
        teleop: bool,
        /// The steps since the previous frame.
        samples: Vec<Sample>,
        /// The sensor beams at the last step.
        beams: Vec<Beam>,
        /// The last correction, if one happened since the previous frame.
        correction: Option<CorrectionDetail>,
        /// The preset's criterion on this run.
        figure: Option<LiveFigure>,
        /// Why the run stopped, if the simulation (or the robot's link)
        /// failed.
        failure: Option<String>,
        /// The link's health when attached to a robot; `None` for the
        /// simulation.
        link: Option<LinkHealth>,
    },
    /// A refused message or value; nothing of it was applied.
    Error {
        /// The field (or `message` for the message itself).
        field: String,
        /// Why.
        message: String,
    },
    /// The run's log.
    Csv {
        /// Suggested file name.
        filename: String,
        /// The CSV text (header line, then one line per step).
        csv: String,
        /// Whether the log was cut at its size limit (the first steps kept).
        truncated: bool,
    },
}

impl From<Invalid> for ServerMsg {
    fn from(e: Invalid) -> Self {
        Self::Error {
            field: e.field,
            message: e.reason,
        }
    }
}

/// The `error` answer to a message that could not be read as a
/// [`ClientMsg`]: its field is the unknown key when that is why (serde's
/// `unknown field `KEY`` of `deny_unknown_fields`, in a message or in its
/// `values`), else `message`.
#[must_use]
pub fn unreadable(e: &serde_json::Error) -> ServerMsg {
    let text = e.to_string();
    let field = text
        .strip_prefix("unknown field `")
        .and_then(|rest| rest.split_once('`'))
        .map_or("message", |(key, _)| key);
    ServerMsg::Error {
        field: field.to_string(),
        message: format!("not a valid message: {text}"),
    }
}
