//! The `square` closed loop as a stepper ([`SquareSim`]) and a run
//! ([`run_square`]).

use locus_control::{Controller, FollowPath, wheel_speeds};
use locus_core::nalgebra::{Matrix3, Vector2, Vector3};
use locus_core::{Belief, ChiSquareGate, Ekf, MeasurementModel, MotionModel};
use locus_models::{DiffDrive, IrPair, IrPairObservation, WheelTravel, associate_ir_wall};
use locus_odometry::{Wheel as EncoderWheel, wrapping_diff};
use rand::SeedableRng;
use rand::rngs::StdRng;

use super::live::correction_detail;
use super::plant::ideal_observation;
use super::record::{mat3, nees};
use super::{Error, LiveParams, NoiseModel, SimStep, SquareConfig, StepRecord, Teleop};
use crate::noise::gauss;
use crate::robot::{Command, Pose, Robot};
use crate::scenario::{Record, Summary, Tally};
use crate::sensors::{Encoder, IrPairSensor, SharpIr};
use crate::world::World;

/// Width of the encoders' wrapping counter (bits), as in
/// [`locus_odometry::Counter::paper`].
const COUNTER_BITS: u32 = locus_odometry::counter::PAPER_BITS;

/// The `square` closed loop as a stepper: [`SquareSim::step`] runs one step
/// of `dt` (the loop of the [module documentation](super)), so a caller can
/// interleave steps with parameter changes and teleoperation (the teaching
/// UI). [`run_square`] is a loop over it.
#[derive(Debug)]
pub struct SquareSim {
    cfg: SquareConfig,
    rng: StdRng,
    world: World,
    robot: Robot,
    wheel: EncoderWheel<f64>,
    enc_right: Encoder,
    enc_left: Encoder,
    last_right: u32,
    last_left: u32,
    pair: IrPair<f64>,
    ir: IrPairSensor,
    model: DiffDrive<f64>,
    ekf: Ekf<f64>,
    belief: Belief<f64, 3>,
    odo: Belief<f64, 3>,
    true_x: Vector3<f64>,
    truth: Pose,
    controller: FollowPath<4>,
    max_steps: usize,
    laps: usize,
    steps: usize,
    finished: bool,
    details: bool,
}

impl SquareSim {
    /// A simulation of `cfg` from `seed`, before its first step (the same
    /// draws from the seed as [`run_square`]).
    ///
    /// # Errors
    /// [`Error::Invalid`] for an invalid configuration; a sensor or gate
    /// construction error.
    #[allow(clippy::cast_precision_loss, clippy::cast_sign_loss)]
    pub fn new(cfg: &SquareConfig, seed: u64) -> Result<Self, Error> {
        cfg.validate()?;
        let mut rng = StdRng::seed_from_u64(seed);
        let world = World::square_arena();

        let (robot, true_start) = cfg.true_robot(&mut rng);
        let (s, sd) = (cfg.start, cfg.initial_std);

        let wheel = EncoderWheel::new(cfg.encoder_lines, cfg.encoder_gear, cfg.wheel_radius);
        let enc_right = Encoder::new(wheel)?;
        let enc_left = Encoder::new(wheel)?;
        let (last_right, last_left) = (enc_right.read(), enc_left.read());

        let pair = IrPair::centred(cfg.ir_spacing);
        let ir = IrPairSensor::new(pair, SharpIr::assumed(cfg.ir_sigma)?)?;

        let model = DiffDrive::new(cfg.wheelbase, cfg.q11, cfg.q22);
        let ekf = Self::ekf(cfg.gate_confidence)?;
        let x0 = Vector3::new(s[0], s[1], s[2]);
        let p0 = Matrix3::from_diagonal(&Vector3::new(sd[0] * sd[0], sd[1] * sd[1], sd[2] * sd[2]));
        let belief = Belief::new(x0, p0);

        Ok(Self {
            cfg: *cfg,
            rng,
            world,
            robot,
            wheel,
            enc_right,
            enc_left,
            last_right,
            last_left,
            pair,
            ir,
            model,
            ekf,
            belief,
            odo: belief,
            true_x: Vector3::new(true_start.x, true_start.y, true_start.theta),
            truth: true_start,
            controller: FollowPath::square(cfg.control),
            max_steps: (cfg.max_time / cfg.dt).ceil() as usize,
            laps: 0,
            steps: 0,
            finished: false,
            details: false,
        })
    }

    fn ekf(gate: Option<f64>) -> Result<Ekf<f64>, Error> {
        let mut ekf = Ekf::<f64>::default();
        if let Some(c) = gate {
            ekf = ekf.with_gate(ChiSquareGate::new(c)?);
        }
        Ok(ekf)
    }

    /// Whether [`SimStep::correction`] is filled in (off by default: it
    /// costs a second linearisation per correction).
    #[must_use]
    pub fn with_details(mut self, on: bool) -> Self {
        self.details = on;
        self
    }

    /// The configuration in use (with the live parameters last set).
    #[must_use]
    pub fn config(&self) -> &SquareConfig {
        &self.cfg
    }

    /// Changes the live parameters from the next step on (the filter's
    /// `Q`, `R` and gate, the injected IR noise, the controller's speeds
    /// and gains, keeping its progress along the path).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first bad field; the simulation then
    /// keeps its previous parameters.
    pub fn set_live(&mut self, live: &LiveParams) -> Result<(), Error> {
        let cfg = live.apply_to(&self.cfg);
        cfg.validate()?;
        let ir = IrPairSensor::new(self.pair, SharpIr::assumed(cfg.ir_sigma)?)?;
        let ekf = Self::ekf(cfg.gate_confidence)?;
        self.ir = ir;
        self.ekf = ekf;
        self.model = DiffDrive::new(cfg.wheelbase, cfg.q11, cfg.q22);
        self.controller.set_config(cfg.control);
        self.cfg = cfg;
        Ok(())
    }

    /// The EKF belief now.
    #[must_use]
    pub fn belief(&self) -> &Belief<f64, 3> {
        &self.belief
    }

    /// The true pose now.
    #[must_use]
    pub fn truth(&self) -> Pose {
        self.truth
    }

    /// The odometry-only belief now.
    #[must_use]
    pub fn odometry(&self) -> &Belief<f64, 3> {
        &self.odo
    }

    /// The arena's walls.
    #[must_use]
    pub fn world(&self) -> &World {
        &self.world
    }

    /// The IR pair sensor (its beams' mountings: [`IrPairSensor::mounts`]).
    #[must_use]
    pub fn ir_sensor(&self) -> &IrPairSensor {
        &self.ir
    }

    /// Steps run so far.
    #[must_use]
    pub fn steps(&self) -> usize {
        self.steps
    }

    /// Laps of the square completed so far.
    #[must_use]
    pub fn laps(&self) -> usize {
        self.laps
    }

    /// Whether the run has ended (laps done or `max_time` reached).
    #[must_use]
    pub fn is_finished(&self) -> bool {
        self.finished
    }

    /// Runs one step of `dt`: with `teleop`, its command instead of the
    /// path controller's (the controller then neither advances nor ends
    /// the run). `Ok(None)` once the run has ended (the laps are done or
    /// `max_time` is reached; teleoperation still runs after the laps,
    /// up to `max_time`).
    ///
    /// # Errors
    /// A robot, sensor or filter error; the simulation should not be
    /// stepped further.
    #[allow(clippy::cast_precision_loss, clippy::too_many_lines)]
    pub fn step(&mut self, teleop: Option<Teleop>) -> Result<Option<SimStep>, Error> {
        let cfg = self.cfg;
        if self.steps >= self.max_steps {
            self.finished = true;
            return Ok(None);
        }
        if self.finished && teleop.is_none() {
            return Ok(None);
        }
        let belief_before = self.belief;
        let command = if let Some(t) = teleop {
            locus_control::Command {
                v: t.v,
                w: t.w,
                done: false,
            }
        } else {
            let est =
                locus_control::Pose::new(self.belief.x[0], self.belief.x[1], self.belief.x[2]);
            let mut command = self.controller.command(est);
            if command.done {
                self.laps += 1;
                if self.laps >= cfg.laps {
                    self.finished = true;
                    return Ok(None);
                }
                self.controller.reset();
                command = self.controller.command(est);
            }
            command
        };
        let (v1, v2) = wheel_speeds(command, cfg.wheelbase);
        let ideal = cfg.noise == NoiseModel::Ideal;
        let (truth, u) = if ideal {
            // The truth moves with the filter's model and noise.
            let u = WheelTravel {
                d1: v1 * cfg.dt,
                d2: v2 * cfg.dt,
            };
            let q_std = [cfg.q11.sqrt(), cfg.q22.sqrt()];
            let q = Vector2::new(
                gauss(&mut self.rng, q_std[0]),
                gauss(&mut self.rng, q_std[1]),
            );
            self.true_x = self.model.f(&self.true_x, &u, &q);
            let x = &self.true_x;
            (Pose::new(x[0], x[1], x[2]), u)
        } else {
            let out = self.robot.step(
                &Command::Wheels {
                    left: v2,
                    right: v1,
                },
                cfg.dt,
            )?;

            // Encoders -> wrapping count differences -> wheel travels.
            self.enc_right.advance(
                out.measured_travel.right * (1.0 + cfg.right_scale_error),
                &mut self.rng,
            )?;
            self.enc_left
                .advance(out.measured_travel.left, &mut self.rng)?;
            let (now_right, now_left) = (self.enc_right.read(), self.enc_left.read());
            let wheel = &self.wheel;
            let u = WheelTravel {
                d1: wheel.distance(wrapping_diff(now_right, self.last_right, COUNTER_BITS)),
                d2: wheel.distance(wrapping_diff(now_left, self.last_left, COUNTER_BITS)),
            };
            (self.last_right, self.last_left) = (now_right, now_left);
            (out.pose, u)
        };
        self.truth = truth;

        self.belief = self.ekf.predict(&self.belief, &self.model, &u)?;
        self.odo = self.ekf.predict(&self.odo, &self.model, &u)?;

        let (mut innovation, mut nis, mut applied, mut gain) = (None, None, false, None);
        let mut detail = None;
        // The raw readings (for the log) and, if associated, the observation.
        let (reading, observation) = if ideal {
            let r_std = [cfg.r11.sqrt(), cfg.r22.sqrt()];
            let noise = Vector2::new(
                gauss(&mut self.rng, r_std[0]),
                gauss(&mut self.rng, r_std[1]),
            );
            match ideal_observation(&cfg, &self.ir, &self.world, &self.true_x, &noise)? {
                Some((obs, z)) => (
                    Some((obs.ds1 + noise[0], obs.ds2 + noise[1])),
                    Some((obs, z)),
                ),
                None => (None, None),
            }
        } else {
            let reading = self.ir.read(
                &self.world.walls,
                [truth.x, truth.y, truth.theta],
                &mut self.rng,
            )?;
            let (pair, walls, belief) = (self.pair, &self.world.walls, &self.belief);
            let observation = reading.and_then(|(ds1, ds2)| {
                let wall = associate_ir_wall(&belief.x, &pair, walls, cfg.association_range)?;
                let obs = IrPairObservation {
                    pair,
                    wall,
                    ds1,
                    ds2,
                    r11: cfg.r11,
                    r22: cfg.r22,
                };
                Some((obs, obs.z()))
            });
            (reading, observation)
        };
        let observation = observation.filter(|_| cfg.use_ir);
        if let Some((obs, z)) = observation {
            let prior = self.belief;
            let c = self.ekf.correct(&prior, &obs, &z)?;
            gain = Some(if c.applied {
                gain_diagonal(&obs, &prior)
            } else {
                [0.0, 0.0]
            });
            innovation = Some([c.innovation[0], c.innovation[1]]);
            nis = Some(c.nis);
            applied = c.applied;
            self.belief = c.belief;
            detail = self.details.then(|| {
                correction_detail(
                    &obs,
                    &z,
                    &belief_before,
                    [u.d1, u.d2],
                    &prior,
                    &c,
                    self.ekf.gate.map(|g| g.threshold(2)),
                )
            });
        }

        let belief = &self.belief;
        let n = nees(&belief.x, &belief.p, &truth);
        self.steps += 1;
        let record = StepRecord {
            step: self.steps - 1,
            time: self.steps as f64 * cfg.dt,
            truth,
            ekf: [belief.x[0], belief.x[1], belief.x[2]],
            ekf_cov: mat3(&belief.p),
            odometry: [self.odo.x[0], self.odo.x[1], self.odo.x[2]],
            wheel_travel: [u.d1, u.d2],
            ir: reading,
            innovation,
            nis,
            applied,
            gain,
            nees: n,
        };
        Ok(Some(SimStep {
            record,
            command: (command.v, command.w),
            wheel_speeds: (v1, v2),
            teleop: teleop.is_some(),
            correction: detail,
        }))
    }
}

/// Diagonal of `H K = H P H^T S^-1` at the prior `belief` for `obs`
/// (`S = H P H^T + V R V^T`); `[0, 0]` if `S` is singular.
fn gain_diagonal(obs: &IrPairObservation<f64>, belief: &Belief<f64, 3>) -> [f64; 2] {
    let h = obs.jacobian(&belief.x);
    let hph = h * belief.p * h.transpose();
    let s = hph + obs.noise(&belief.x);
    s.try_inverse().map_or([0.0, 0.0], |si| {
        let hk = hph * si;
        [hk[(0, 0)], hk[(1, 1)]]
    })
}

/// Runs the `square` scenario with `cfg` from `seed`, calling `sink` with
/// every step's record as the run goes, and returns the summary (a
/// [`Tally`] of every step's [`Record::sample`]). A loop over
/// [`SquareSim::step`] without teleoperation.
///
/// # Errors
/// [`Error::Config`] for an invalid configuration; a robot, sensor or
/// filter error stops the run (the records already sunk stay valid).
pub fn run_square(
    cfg: &SquareConfig,
    seed: u64,
    sink: &mut impl FnMut(&StepRecord),
) -> Result<Summary, Error> {
    cfg.validate()?;
    let mut tally = Tally::new(3)?;
    let mut sim = SquareSim::new(cfg, seed)?;
    while let Some(step) = sim.step(None)? {
        tally.push(&step.record.sample());
        sink(&step.record);
    }
    Ok(tally.summary(sim.laps()))
}
