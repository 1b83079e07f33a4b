//! One client's session: its own simulation of the `square` closed loop,
//! run state, parameters, log and guide figures. Independent of the socket
//! (the server feeds it messages and ticks), so it is tested directly.

use core::time::Duration;
use std::time::Instant;

use locus_eval::Record;
use locus_sim::closed_loop::NoiseModel;
use locus_sim::scenario_file::{Scenario, ScenarioConfig};
use locus_sim::{CorrectionDetail, LiveParams, SquareConfig, SquareSim, StepRecord, Teleop};

use crate::params::{self, InitialPatch, Invalid, ParamPatch};
use crate::presets::{self, RunFigures};
use crate::protocol::{Beam, ClientMsg, ParamValues, Sample, ServerMsg};
use crate::{Error, Limits};

/// The scenarios a session can switch to (the built-ins of the square
/// kind).
pub const SCENARIOS: [Scenario; 2] = [Scenario::Square, Scenario::SquareIdeal];

/// Teleoperation stops this long after the last `teleop` message (the
/// page repeats it while a key is held), like the robot's watchdog.
pub const TELEOP_TIMEOUT: Duration = Duration::from_millis(500);

/// Most steps kept in the exported log (5 min at 100 Hz, about 8 MB: the
/// memory bound of a session; a default two-lap run is 14 107); later steps
/// still run and plot, the export says it was cut.
pub const MAX_LOG_STEPS: usize = 30_000;

/// Most time searched by `step_correction` (s): simulated time in a
/// simulation, host time when attached to a robot.
pub const STEP_CORRECTION_MAX_TIME: f64 = 10.0;

/// A client's session.
#[derive(Debug)]
pub struct Session {
    id: u64,
    seed: u64,
    /// The scenario's configuration as loaded (the presets build on it).
    scenario_base: SquareConfig,
    scenario: String,
    /// The configuration a reset starts from (live values included).
    cfg: SquareConfig,
    sim: SquareSim,
    running: bool,
    speed: f64,
    /// Fractional steps owed to the wall clock.
    owed: f64,
    teleop: Option<(Teleop, Instant)>,
    log: Vec<StepRecord>,
    log_truncated: bool,
    pending: Vec<Sample>,
    correction: Option<CorrectionDetail>,
    last_record: Option<StepRecord>,
    figures: RunFigures,
    guide_runs: [Option<RunFigures>; 6],
    preset: Option<char>,
    failure: Option<String>,
    limits: Limits,
}

fn sample(r: &StepRecord, wheels: (f64, f64)) -> Sample {
    let p = r.ekf_cov;
    Sample {
        t: r.time,
        truth: Some([r.truth.x, r.truth.y, r.truth.theta]),
        ekf: r.ekf,
        p: [p[0][0], p[1][1], p[2][2], p[0][1]],
        odo: Some([r.odometry[0], r.odometry[1]]),
        wheels: [wheels.0, wheels.1],
        ir: r.ir.map(|(a, b)| [a, b]),
        innovation: r.innovation,
        nis: r.nis,
        applied: r.applied,
        nees: Some(r.nees),
    }
}

impl Session {
    /// A session number `id` on `scenario` (named `name`) from `seed`,
    /// paused at its start.
    ///
    /// # Errors
    /// [`Error::Sim`] if the configuration is refused by the simulator.
    pub fn new(
        id: u64,
        name: &str,
        scenario: &SquareConfig,
        seed: u64,
        limits: Limits,
    ) -> Result<Self, Error> {
        let sim = SquareSim::new(scenario, seed)?.with_details(true);
        Ok(Self {
            id,
            seed,
            scenario_base: *scenario,
            scenario: name.to_string(),
            cfg: *scenario,
            sim,
            running: false,
            speed: 1.0,
            owed: 0.0,
            teleop: None,
            log: Vec::new(),
            log_truncated: false,
            pending: Vec::new(),
            correction: None,
            last_record: None,
            figures: RunFigures::default(),
            guide_runs: [None; 6],
            preset: None,
            failure: None,
            limits,
        })
    }

    /// Whether the run is moving.
    #[must_use]
    pub fn is_running(&self) -> bool {
        self.running
    }

    /// The configuration in use.
    #[must_use]
    pub fn config(&self) -> &SquareConfig {
        self.sim.config()
    }

    /// Steps run since the last reset.
    #[must_use]
    pub fn steps(&self) -> usize {
        self.sim.steps()
    }

    /// The `hello` message.
    #[must_use]
    pub fn hello(&self) -> ServerMsg {
        let h = locus_control::SQUARE_HALF_SIDE;
        ServerMsg::Hello {
            session: self.id,
            scenario: self.scenario.clone(),
            scenarios: SCENARIOS.map(Scenario::name).to_vec(),
            walls: self.sim.world().walls.iter().map(|w| [w.a, w.b]).collect(),
            path: vec![[-h, -h], [h, -h], [h, h], [-h, h]],
            dt: self.cfg.dt,
            presets: presets::PRESETS.to_vec(),
            limits: params::LIMITS.to_vec(),
            max_message_bytes: self.limits.max_message_bytes,
            max_messages_per_second: self.limits.messages_per_second,
            robot: None,
        }
    }

    /// The `params` message: the values in use.
    #[must_use]
    pub fn params(&self) -> ServerMsg {
        let c = self.sim.config();
        let start = &self.cfg;
        ServerMsg::Params {
            values: ParamValues {
                q11: c.q11,
                q22: c.q22,
                r11: c.r11,
                r22: c.r22,
                ir_sigma: Some(c.ir_sigma),
                use_ir: c.use_ir,
                gate: c.gate_confidence.unwrap_or(0.0),
                v_ref: c.control.v_ref,
                w_ref: c.control.w_ref,
                k_cross: c.control.k_cross,
                k_heading: c.control.k_heading,
                k_pos: c.control.k_pos,
                start_x: start.start[0],
                start_y: start.start[1],
                start_theta: start.start[2],
                std_x: start.initial_std[0],
                std_y: start.initial_std[1],
                std_theta: start.initial_std[2],
                speed: Some(self.speed),
            },
            preset: self.preset,
        }
    }

    /// Handles the text of one WebSocket message (JSON of a
    /// [`ClientMsg`]); a malformed one is an `error` answer.
    pub fn handle_text(&mut self, text: &str, now: Instant) -> Vec<ServerMsg> {
        match serde_json::from_str::<ClientMsg>(text) {
            Ok(msg) => self.handle(msg, now),
            Err(e) => vec![crate::protocol::unreadable(&e)],
        }
    }

    /// Handles one message; returns the answers (an `error`, `params`
    /// after a change, a `state` frame after a step).
    pub fn handle(&mut self, msg: ClientMsg, now: Instant) -> Vec<ServerMsg> {
        match self.apply(msg, now) {
            Ok(out) => out,
            Err(e) => vec![e.into()],
        }
    }

    fn apply(&mut self, msg: ClientMsg, now: Instant) -> Result<Vec<ServerMsg>, Invalid> {
        Ok(match msg {
            ClientMsg::Start {} => {
                if self.sim.is_finished() {
                    return Err(Invalid::new("start", "the run has ended: reset first"));
                }
                self.running = self.failure.is_none();
                self.owed = 0.0;
                vec![self.frame()]
            }
            ClientMsg::Stop {} => {
                self.running = false;
                vec![self.frame()]
            }
            ClientMsg::Reset {} => {
                self.reset()
                    .map_err(|e| Invalid::new("reset", e.to_string()))?;
                vec![self.params(), self.frame()]
            }
            ClientMsg::Step {} => {
                self.running = false;
                self.advance(1, now);
                vec![self.frame()]
            }
            ClientMsg::StepCorrection {} => {
                self.running = false;
                self.correction = None;
                let max = (STEP_CORRECTION_MAX_TIME / self.cfg.dt).ceil();
                #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
                let max = max as usize;
                for _ in 0..max {
                    if self.advance(1, now) == 0 || self.correction.is_some() {
                        break;
                    }
                }
                vec![self.frame()]
            }
            ClientMsg::Speed { factor } => {
                self.speed = params::checked("speed", &factor)?;
                vec![self.params()]
            }
            ClientMsg::Teleop { v, w } => {
                let v = params::checked("teleop_v", &v)?;
                let w = params::checked("teleop_w", &w)?;
                self.teleop = Some((Teleop { v, w }, now));
                Vec::new()
            }
            ClientMsg::TeleopOff {} => {
                self.teleop = None;
                Vec::new()
            }
            ClientMsg::Params { values } => {
                self.set_params(&values)?;
                self.preset = None;
                vec![self.params()]
            }
            ClientMsg::Initial { values } => {
                self.set_initial(&values)?;
                vec![self.params()]
            }
            ClientMsg::Scenario { name } => {
                let chosen = name
                    .parse::<Scenario>()
                    .ok()
                    .filter(|s| SCENARIOS.contains(s))
                    .map(Scenario::config);
                let Some(ScenarioConfig::Square(cfg)) = chosen else {
                    return Err(Invalid::new(
                        "scenario",
                        format!(
                            "must be one of {}",
                            SCENARIOS.map(Scenario::name).join(", ")
                        ),
                    ));
                };
                self.scenario_base = SquareConfig {
                    laps: self.scenario_base.laps,
                    max_time: self.scenario_base.max_time,
                    ..cfg
                };
                self.scenario = name;
                self.cfg = self.scenario_base;
                self.preset = None;
                self.guide_runs = [None; 6];
                self.reset()
                    .map_err(|e| Invalid::new("scenario", e.to_string()))?;
                vec![self.hello(), self.params(), self.frame()]
            }
            ClientMsg::Preset { step } => {
                let letter = match step.as_str() {
                    "a" | "b" | "c" | "d" | "e" | "f" => step.chars().next(),
                    _ => None,
                };
                let Some(letter) = letter else {
                    return Err(Invalid::new("preset", "must be one of a, b, c, d, e, f"));
                };
                if self.scenario_base.noise != NoiseModel::Realistic {
                    return Err(Invalid::new(
                        "preset",
                        "the guide runs on the `square` scenario: switch to it first",
                    ));
                }
                let Some(cfg) = locus_sim::guide::step_config(letter, &self.scenario_base) else {
                    return Err(Invalid::new("preset", "unknown step"));
                };
                self.cfg = SquareConfig {
                    start: self.cfg.start,
                    initial_std: self.cfg.initial_std,
                    ..cfg
                };
                self.preset = Some(letter);
                self.reset()
                    .map_err(|e| Invalid::new("preset", e.to_string()))?;
                vec![self.params(), self.frame()]
            }
            ClientMsg::Export {} => vec![self.export()],
        })
    }

    /// Validates `values` (all or nothing) and applies them live.
    fn set_params(&mut self, values: &ParamPatch) -> Result<(), Invalid> {
        let live = values
            .checked()?
            .applied_to(&LiveParams::of(self.sim.config()));
        self.sim
            .set_live(&live)
            .map_err(|e| Invalid::new("params", e.to_string()))?;
        // A reset keeps them.
        self.cfg = live.apply_to(&self.cfg);
        Ok(())
    }

    /// Validates the initial pose and standard deviations (all or nothing)
    /// for the next reset.
    fn set_initial(&mut self, values: &InitialPatch) -> Result<(), Invalid> {
        let (start, std) = values.applied_to(self.cfg.start, self.cfg.initial_std)?;
        self.cfg.start = start;
        self.cfg.initial_std = std;
        Ok(())
    }

    /// Restarts the run with the current configuration, same seed.
    fn reset(&mut self) -> Result<(), Error> {
        let sim = SquareSim::new(&self.cfg, self.seed)?.with_details(true);
        self.sim = sim;
        self.running = false;
        self.owed = 0.0;
        self.teleop = None;
        self.log.clear();
        self.log_truncated = false;
        self.pending.clear();
        self.correction = None;
        self.last_record = None;
        self.figures = RunFigures::default();
        self.failure = None;
        Ok(())
    }

    /// Runs up to `n` steps; returns how many ran.
    fn advance(&mut self, n: usize, now: Instant) -> usize {
        if self
            .teleop
            .is_some_and(|(_, at)| now.saturating_duration_since(at) > TELEOP_TIMEOUT)
        {
            self.teleop = None;
        }
        let teleop = self.teleop.map(|(t, _)| t);
        let mut ran = 0;
        for _ in 0..n {
            match self.sim.step(teleop) {
                Ok(Some(s)) => {
                    ran += 1;
                    let r = s.record;
                    self.pending.push(sample(&r, s.wheel_speeds));
                    if s.correction.is_some() {
                        self.correction = s.correction;
                    }
                    self.figures.push(&r, self.sim.config());
                    if let Some(i) = self.preset.map(|c| (c as usize) - ('a' as usize)) {
                        self.guide_runs[i] = Some(self.figures);
                    }
                    if self.log.len() < MAX_LOG_STEPS {
                        self.log.push(r);
                    } else {
                        self.log_truncated = true;
                    }
                    self.last_record = Some(r);
                }
                Ok(None) => {
                    self.running = false;
                    break;
                }
                Err(e) => {
                    self.running = false;
                    self.failure = Some(e.to_string());
                    break;
                }
            }
        }
        ran
    }

    /// Advances by `elapsed` wall-clock time at the speed factor (at most
    /// `max_steps_per_tick`) and returns the state frame, or `None` when
    /// paused (nothing changed).
    pub fn tick(&mut self, elapsed: Duration, now: Instant) -> Option<ServerMsg> {
        if !self.running {
            return None;
        }
        self.owed += elapsed.as_secs_f64() * self.speed / self.cfg.dt;
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let n = (self.owed.floor() as usize).min(self.limits.max_steps_per_tick);
        #[allow(clippy::cast_precision_loss)]
        {
            self.owed = (self.owed - n as f64).min(1.0);
        }
        self.advance(n, now);
        Some(self.frame())
    }

    /// The beams of the IR pair at the last true pose.
    fn beams(&self) -> Vec<Beam> {
        let ir = self.sim.ir_sensor();
        let t = self.sim.truth();
        let reading = self.last_record.and_then(|r| r.ir);
        let (s, c) = t.theta.sin_cos();
        ir.mounts()
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let from = [t.x + c * m.x_si - s * m.y_si, t.y + s * m.x_si + c * m.y_si];
                let read = reading.map(|(a, b)| if i == 0 { a } else { b });
                let len = read.unwrap_or(ir.front.max_range);
                let (bs, bc) = (t.theta + m.beta).sin_cos();
                Beam {
                    from,
                    to: [from[0] + len * bc, from[1] + len * bs],
                    hit: read.is_some(),
                }
            })
            .collect()
    }

    /// The state frame: run state and the samples since the last frame
    /// (taken: the next frame holds only later samples).
    pub fn frame(&mut self) -> ServerMsg {
        let figure = self.preset.map(|p| {
            presets::live_figure(p, &self.figures, &self.guide_runs, self.sim.is_finished())
        });
        ServerMsg::State {
            running: self.running,
            finished: self.sim.is_finished(),
            time: self.last_record.map_or(0.0, |r| r.time),
            steps: self.sim.steps(),
            laps: self.sim.laps(),
            teleop: self.teleop.is_some(),
            samples: core::mem::take(&mut self.pending),
            beams: self.beams(),
            correction: self.correction.take(),
            figure,
            failure: self.failure.clone(),
            link: None,
        }
    }

    /// The log as CSV, `locus run`'s `log.csv` format.
    fn export(&self) -> ServerMsg {
        let mut csv = StepRecord::csv_header();
        csv.push('\n');
        for r in &self.log {
            csv.push_str(&r.csv_row());
            csv.push('\n');
        }
        let preset = self.preset.map_or(String::new(), |p| format!("-{p}"));
        ServerMsg::Csv {
            filename: format!("locus-{}{preset}-seed{}.csv", self.scenario, self.seed),
            csv,
            truncated: self.log_truncated,
        }
    }
}
