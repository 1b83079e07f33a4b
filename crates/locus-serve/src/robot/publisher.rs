//! The host thread's side of an attached page: the pages' commands in,
//! `state` frames with the link's health out.

use alloc::collections::VecDeque;
use alloc::sync::Arc;
use core::ops::ControlFlow;
use core::time::Duration;
use std::sync::{Mutex, PoisonError, mpsc};
use std::time::Instant;

use locus_models::CorrectionDetail;
use locus_net::host::{Drive, Host, LiveTick};
use tokio::sync::broadcast;

use crate::protocol::{LinkHealth, ParamValues, Sample, ServerMsg};
use crate::session::{STEP_CORRECTION_MAX_TIME, TELEOP_TIMEOUT};

use super::{Command, LATENCY_WINDOW, Latest};

/// The `params` message of the host's values in use.
pub(super) fn params_msg(host: &Host) -> ServerMsg {
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
pub(super) struct Publisher {
    pub(super) inbox: mpsc::Receiver<Command>,
    pub(super) frames: broadcast::Sender<ServerMsg>,
    pub(super) latest: Arc<Mutex<Latest>>,
    pub(super) tick: Duration,
    pub(super) last_frame: Option<Instant>,
    pub(super) pending: Vec<Sample>,
    /// Robot time of the last applied packet (s).
    pub(super) time: f64,
    pub(super) latencies: VecDeque<f64>,
    /// The last tick seen (for the link's health).
    pub(super) last: Option<LiveTick>,
    /// A frame is due now (a command changed something).
    pub(super) due: bool,
    /// A page asked for the next correction: the host's count of tried
    /// corrections and the host time (s) when it asked.
    pub(super) capture: Option<(u64, f64)>,
    /// The Foxglove server fed with every applied packet, if any.
    pub(super) foxglove: Option<crate::foxglove::Live>,
}

impl Publisher {
    pub(super) fn lock(&self) -> std::sync::MutexGuard<'_, Latest> {
        self.latest.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// Sends `msg` to every page (none connected is fine).
    fn publish(&self, msg: ServerMsg) {
        let _ = self.frames.send(msg);
    }

    /// One call of the live loop: commands, the packet's sample, a frame
    /// when due.
    pub(super) fn each(&mut self, host: &mut Host, tick: &LiveTick) -> ControlFlow<()> {
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
            if let Some(live) = &self.foxglove {
                live.publish(&crate::foxglove::frame_of(&step));
            }
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
        let correction = self.captured(host, tick.host_time);
        let now = Instant::now();
        if self.due
            || self
                .last_frame
                .is_none_or(|t| now.duration_since(t) >= self.tick)
        {
            self.due = false;
            self.last_frame = Some(now);
            let samples = core::mem::take(&mut self.pending);
            let frame = self.state(host, Some(samples), correction);
            self.lock().state = self.state(host, None, None);
            self.publish(frame);
        }
        ControlFlow::Continue(())
    }

    /// The correction a page asked for, once the host has tried it (a
    /// frame is then due); an `error` to the pages if none came within
    /// [`STEP_CORRECTION_MAX_TIME`] of host time.
    fn captured(&mut self, host: &Host, now: f64) -> Option<CorrectionDetail> {
        let (tried, asked) = self.capture?;
        if host.corrections_tried() > tried {
            self.capture = None;
            self.due = true;
            return host.last_correction().copied();
        }
        if now - asked > STEP_CORRECTION_MAX_TIME {
            self.capture = None;
            self.publish(ServerMsg::Error {
                field: "step_correction".into(),
                message: format!(
                    "no IR correction in {STEP_CORRECTION_MAX_TIME} s (no wall in range, the IR off, or the robot silent)"
                ),
            });
        }
        None
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
            Command::NextCorrection => self.capture = Some((host.corrections_tried(), now)),
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
    pub(super) fn fail(&mut self, why: &str) {
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

    /// The `state` frame of the host now, with `samples` (none: empty) and
    /// a `correction` a page asked for.
    #[allow(clippy::cast_possible_truncation)]
    pub(super) fn state(
        &self,
        host: &Host,
        samples: Option<Vec<Sample>>,
        correction: Option<CorrectionDetail>,
    ) -> ServerMsg {
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
            correction,
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
