//! The `square` closed loop as a stepper ([`SquareSim`]) and a run
//! ([`run_square`]).

use locus_control::{Controller, FollowPath, Twist, wheel_speeds};
use locus_core::{Belief, Ekf};
use locus_models::{IrCorrection, IrOutcome, IrPairObservation, Localiser, WheelTravel};

use super::plant::{IrReadings, Plant};
use super::{Error, LiveParams, NoiseModel, SimStep, SquareConfig, StepRecord, Teleop};
use crate::robot::Pose;
use crate::sensors::{IrPairSensor, IrReading};
use crate::world::World;
use locus_eval::{Record, Summary, Tally};
use locus_eval::{matrix3, planar_nees};

/// Width of the simulated decoder's wrapping counters (bits), as in
/// [`locus_odometry::Counter::paper`].
const COUNTER_BITS: u32 = locus_odometry::counter::PAPER_BITS;

/// The `square` closed loop as a stepper: [`SquareSim::step`] runs one step
/// of `dt` (the loop of the [module documentation](super)), so a caller can
/// interleave steps with parameter changes and teleoperation (the teaching
/// UI). [`run_square`] is a loop over it.
///
/// The filter side is paper 001's [`Localiser`] (20-bit counters); the
/// odometry-only belief is predicted with the same model and wheel travels.
#[derive(Debug)]
pub struct SquareSim {
    cfg: SquareConfig,
    plant: Plant,
    localiser: Localiser<f64>,
    odometry: Belief<f64, 3>,
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
        let mut localiser = cfg.localiser(COUNTER_BITS).localiser()?;
        let plant = Plant::new(cfg, seed, *localiser.odometer.wheel())?;
        // The encoders' counts at the start are the odometer's reference.
        localiser.odometer = localiser.odometer.with_reference(plant.counts());
        Ok(Self {
            cfg: *cfg,
            plant,
            odometry: *localiser.belief(),
            localiser,
            controller: FollowPath::square(cfg.control),
            max_steps: (cfg.max_time / cfg.dt).ceil() as usize,
            laps: 0,
            steps: 0,
            finished: false,
            details: false,
        })
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

    /// Changes the live parameters from the next step on: the localiser's
    /// rules (gate), model (`Q`) and association (`R`), the injected IR
    /// noise, the controller's speeds and gains (keeping its progress along
    /// the path).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first bad field; the simulation then
    /// keeps its previous parameters.
    pub fn set_live(&mut self, live: &LiveParams) -> Result<(), Error> {
        let cfg = live.apply_to(&self.cfg);
        cfg.validate()?;
        let fresh = cfg.localiser(COUNTER_BITS).localiser()?;
        self.plant.set_ir_sigma(cfg.ir_sigma)?;
        self.localiser.filter.set_rules(*fresh.filter.rules());
        self.localiser.model = fresh.model;
        self.localiser.ir = fresh.ir;
        self.controller.set_config(cfg.control);
        self.cfg = cfg;
        Ok(())
    }

    /// The localiser (its belief, rules, model, odometer, association and
    /// NIS monitor).
    #[must_use]
    pub fn localiser(&self) -> &Localiser<f64> {
        &self.localiser
    }

    /// The EKF belief now.
    #[must_use]
    pub fn belief(&self) -> &Belief<f64, 3> {
        self.localiser.belief()
    }

    /// The true pose now.
    #[must_use]
    pub fn truth(&self) -> Pose<f64> {
        self.plant.truth()
    }

    /// The odometry-only belief now.
    #[must_use]
    pub fn odometry(&self) -> &Belief<f64, 3> {
        &self.odometry
    }

    /// The arena's walls.
    #[must_use]
    pub fn world(&self) -> &World {
        &self.plant.world
    }

    /// The IR pair sensor (its beams' mountings: [`IrPairSensor::mounts`]).
    #[must_use]
    pub fn ir_sensor(&self) -> &IrPairSensor {
        &self.plant.ir
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

    /// Runs one step of `dt`: with `teleop`, its body twist instead of the
    /// path controller's (the controller then neither advances nor ends
    /// the run). `Ok(None)` once the run has ended (the laps are done or
    /// `max_time` is reached; teleoperation still runs after the laps,
    /// up to `max_time`).
    ///
    /// # Errors
    /// A robot, sensor or filter error; the simulation should not be
    /// stepped further.
    pub fn step(&mut self, teleop: Option<Teleop>) -> Result<Option<SimStep>, Error> {
        if self.steps >= self.max_steps {
            self.finished = true;
            return Ok(None);
        }
        if self.finished && teleop.is_none() {
            return Ok(None);
        }
        let before = *self.localiser.belief();
        let Some(twist) = self.twist(teleop) else {
            return Ok(None);
        };
        let (v1, v2) = wheel_speeds(twist, self.cfg.wheelbase);
        let u = self.predict((v1, v2))?;
        let (reading, each, corrected) = self.correct()?;
        let gate = self.localiser.filter.rules().ekf.gate;
        let detail = corrected
            .filter(|_| self.details)
            .and_then(|c| c.detail(&before, [u.d1, u.d2], gate.map(|g| g.threshold(2))));
        self.steps += 1;
        Ok(Some(SimStep {
            record: self.record(&u, (reading, each), corrected.as_ref()),
            twist: (twist.v, twist.w),
            wheel_speeds: (v1, v2),
            teleop: teleop.is_some(),
            correction: detail,
        }))
    }

    /// Step 1: the body twist, from `teleop` or from the path controller
    /// on the estimate; `None` (and the run finished) when the last lap is
    /// done.
    fn twist(&mut self, teleop: Option<Teleop>) -> Option<Twist> {
        if let Some(t) = teleop {
            return Some(Twist {
                v: t.v,
                w: t.w,
                done: false,
            });
        }
        let x = &self.localiser.belief().x;
        let est = locus_control::Pose::new(x[0], x[1], x[2]);
        let mut twist = self.controller.command(est);
        if twist.done {
            self.laps += 1;
            if self.laps >= self.cfg.laps {
                self.finished = true;
                return None;
            }
            self.controller.reset();
            twist = self.controller.command(est);
        }
        Some(twist)
    }

    /// Steps 2-4: the plant moves with wheel speeds `(V1, V2)` (m/s); the
    /// wheel travels `u` (the encoders' counts through the localiser's
    /// odometer; in the ideal mode, the commanded travels `V_i dt`) predict
    /// both beliefs (paper 001 eq. 7-13). Returns `u`.
    fn predict(&mut self, (v1, v2): (f64, f64)) -> Result<WheelTravel<f64>, Error> {
        let cfg = &self.cfg;
        let u = match cfg.noise {
            NoiseModel::Ideal => {
                let u = WheelTravel {
                    d1: v1 * cfg.dt,
                    d2: v2 * cfg.dt,
                };
                self.plant.drive_ideal(cfg, &self.localiser.model, &u);
                u
            }
            NoiseModel::Realistic => {
                let counts = self.plant.drive(cfg, (v1, v2))?;
                // The reference was set at the start, so there is always a
                // travel.
                self.localiser
                    .odometer
                    .travel(counts)
                    .unwrap_or(WheelTravel { d1: 0.0, d2: 0.0 })
            }
        };
        self.localiser.predict(&u)?;
        self.odometry = Ekf::default().predict(&self.odometry, &self.localiser.model, &u)?;
        Ok(u)
    }

    /// Step 5: the IR pair's readings and each sensor's (for the log) and,
    /// when they were associated with a wall and the filter uses IR, the
    /// correction of the localiser behind its gate. Realistic mode: the
    /// localiser associates on its estimate ([`Localiser::ir`]); ideal
    /// mode: the plant's observation, associated on the truth.
    fn correct(&mut self) -> Result<(IrReadings, [IrReading; 2], Option<IrCorrection>), Error> {
        let use_ir = self.cfg.use_ir;
        let prior = *self.localiser.belief();
        let corrected = |observation: IrPairObservation<f64>, z, update| IrCorrection {
            observation,
            z,
            prior,
            update,
        };
        if self.cfg.noise == NoiseModel::Ideal {
            let (reading, each, observed) = self.plant.observe_ideal(&self.cfg)?;
            let Some((obs, z)) = observed.filter(|_| use_ir) else {
                return Ok((reading, each, None));
            };
            let update = self.localiser.filter.correct(&obs, &z)?;
            return Ok((reading, each, Some(corrected(obs, z, update))));
        }
        let (reading, each) = self.plant.read_ir()?;
        let Some((ds1, ds2)) = reading.filter(|_| use_ir) else {
            return Ok((reading, each, None));
        };
        Ok(
            match self.localiser.ir(&self.plant.world.walls, [ds1, ds2])? {
                IrOutcome::Associated {
                    observation,
                    update,
                } => (
                    reading,
                    each,
                    Some(corrected(observation, observation.z(), update)),
                ),
                IrOutcome::Unassociated => (reading, each, None),
            },
        )
    }

    /// The record of the step just run (`self.steps` already counts it).
    #[allow(clippy::cast_precision_loss)]
    fn record(
        &self,
        u: &WheelTravel<f64>,
        (reading, each): (IrReadings, [IrReading; 2]),
        corrected: Option<&IrCorrection>,
    ) -> StepRecord {
        let belief = self.localiser.belief();
        let truth = self.plant.truth();
        let (x, odo) = (&belief.x, &self.odometry.x);
        // The NIS and innovation of the reading against the prior.
        let first = corrected.and_then(|c| c.update.first_attempt());
        StepRecord {
            step: self.steps - 1,
            time: self.steps as f64 * self.cfg.dt,
            truth,
            ekf: [x[0], x[1], x[2]],
            ekf_cov: matrix3(&belief.p),
            odometry: [odo[0], odo[1], odo[2]],
            wheel_travel: [u.d1, u.d2],
            ir: reading,
            ir_each: each,
            innovation: first.map(|c| [c.innovation[0], c.innovation[1]]),
            nis: first.map(|c| c.nis),
            applied: corrected.is_some_and(|c| c.update.applied()),
            gain: corrected.and_then(IrCorrection::gain_diagonal),
            nees: planar_nees(x, &belief.p, &truth),
        }
    }
}

/// Runs the `square` scenario with `cfg` from `seed`, calling `sink` with
/// every step's record as the run goes, and returns the summary (a
/// [`Tally`] of every step's [`Record::sample`]). A loop over
/// [`SquareSim::step`] without teleoperation.
///
/// # Errors
/// [`Error::Invalid`] for an invalid configuration; a robot, sensor or
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
