//! A simulated run written as a Locus log (docs/log-format.md, version 4)
//! whose range sensors are beam sensors (issue 29: "the simulator writes its
//! IR and laser readings as beam records, so a simulated run replays
//! through the same path"): [`SquareLog`] for paper 001's closed loop
//! (`square`, `square-ideal`), [`Wall45Log`] for paper 000's laser to the
//! 45-degree wall (`wall45`). `locus run SCENARIO --export-log FILE` writes
//! it.
//!
//! What the log holds, step by step of the run (times `k dt`, as the run's
//! records have them):
//!
//! * `wall` records: the arena's walls.
//! * `beam_sensor` records, one beam each: paper 001's IR sensors s1 (id 0)
//!   and s2 (id 1), mounted as [`IrPairSensor::mounts`] says, valid from
//!   the sensor's `min_range` to its `max_range` (0.04-0.30 m); paper 000's
//!   laser (id 0) at its mount, valid up to its `max_range`.
//! * `scan` records at the end of each step (the time of the step's
//!   record), one per sensor: the distance it read, `max` where it read
//!   nothing within its range (or the laser's beam missed the wall), `-`
//!   where it read closer than its range. Ranges are stored as 32-bit
//!   floats (the format's precision, about 1e-8 m at 0.3 m).
//! * `odometry` records at the start of each step: the forward speed `v`
//!   and turn rate `omega` the replay's unicycle holds over the step. For
//!   paper 001 they come from the wheel travels the filter predicted with,
//!   `d = (d1 + d2) / 2`, `dtheta = (d1 - d2) / b` (eq. 8): `omega =
//!   dtheta / dt` and `v = d / (dt sinc(omega dt / 2))`, so that the
//!   unicycle's exact arc (a chord of `v dt sinc(omega dt / 2)` along `theta
//!   + omega dt / 2`) is paper 001's centred-difference step (a chord of `d`
//!   along `theta + dtheta / 2`) to rounding ([`chord_velocities`]). For
//!   paper 000, `v = (V_L + V_R) / 2`, `omega = (V_R - V_L) / D` of the
//!   measured tread speeds (paper 000's Euler step moves along `theta`, the
//!   unicycle along `theta + omega dt / 2`: not the same step).
//! * `start`: the filter's initial estimate (the configuration's), at 0 s.
//! * `truth`: the true pose at 0 s and at the end of every step.
//! * `noise`: the filter's own noise as the format says it. `q_v`,
//!   `q_omega` are power spectral densities (a step of `dt` gets variance
//!   `q / dt` on the speed): paper 001's per-step variances `Q11` (m^2, of
//!   `d`) and `Q22` (rad^2, of `dtheta`) are `q_v dt` and `q_omega dt`, so
//!   `q_v = Q11 / dt` and `q_omega = Q22 / dt`; paper 000's tread-speed
//!   noise `s` (m/s, each tread) gives `var(v) = s^2 / 2` and `var(omega) =
//!   2 s^2 / D^2`, so `q_v = s^2 dt / 2` and `q_omega = 2 s^2 dt / D^2`
//!   (the moving regime's; the log cannot say the rest regime's). The
//!   beams' `sigma_beam` is paper 001's `sqrt(R11)` when `R11 = R22` (the
//!   format has one range noise for all beams; none is written otherwise),
//!   paper 000's laser noise while moving.
//!
//! * `ir_pair` (version 5): s1 and s2 read as paper 001's pair, with the
//!   loop's association range, so that a replay corrects with the pair's
//!   2-D measurement of the wall's distance and angle (eq. 3-5, noise `V R
//!   V^T` at the readings) when both sensors read, as the loop does. The IR
//!   readings are 32-bit floats in the loop itself ([`SharpIr`]), so the
//!   log holds exactly what it corrected with. A replay with the loop's
//!   noise gives its estimates (docs/replay.md, "A simulated run as a
//!   log", has the measured difference).

use locus_logs::locus_csv::LocusLog;
use locus_logs::mrclam::{Groundtruth, Odometry, TruthPose};
use locus_logs::scans::{MISSING, NO_RETURN};
use locus_logs::{BeamSensor, IrPairRecord, SensorMount, Wall};
use locus_models::laser_wall::{LaserMount, Segment};
use locus_models::unicycle::{Unicycle, Velocities};
use locus_models::{DiffDrive, WheelTravel};
use rand::SeedableRng;
use rand::rngs::StdRng;

use crate::closed_loop::{SquareConfig, StepRecord};
use crate::robot::Pose;
use crate::sensors::{IrPairSensor, IrReading, SharpIr};
use crate::wall45::{Wall45Config, Wall45Record};
use crate::{Error, World};

/// The unicycle velocities `(v, omega)` (m/s, rad/s) held over `dt`
/// (s, positive) whose exact arc is the step of a chord `d` (m) along the
/// heading plus `dtheta / 2`, turning by `dtheta` (rad): paper 001's
/// differential-drive step (eq. 7-13). `omega = dtheta / dt` and
/// `v = d / (dt sinc(omega dt / 2))` with the unicycle's own `sinc`
/// ([`Unicycle::chord`]), so the unicycle's chord is `d` to rounding.
#[must_use]
pub fn chord_velocities(d: f64, dtheta: f64, dt: f64) -> (f64, f64) {
    let omega = dtheta / dt;
    let (unit_chord, _) = Unicycle::new(0.0, 0.0).chord(0.0, &Velocities { v: 1.0, omega, dt });
    (d / unit_chord, omega)
}

/// A wall of the simulator's world as a log's `wall` record.
fn wall(s: &Segment<f64>) -> Wall {
    Wall {
        x1: s.a[0],
        y1: s.a[1],
        x2: s.b[0],
        y2: s.b[1],
    }
}

/// A one-beam sensor of id `id` at `mount`, valid in `[min_range,
/// max_range)`.
fn one_beam(id: u32, mount: &LaserMount<f64>, min_range: f64, max_range: f64) -> BeamSensor {
    BeamSensor {
        id,
        // `+ 0.0` writes a mount on the axis as 0, not -0.
        mount: SensorMount {
            x: mount.x_si + 0.0,
            y: mount.y_si + 0.0,
            yaw: mount.beta + 0.0,
        },
        min_range,
        max_range,
        angle_0: 0.0,
        angle_step: 0.0,
        count: 1,
    }
}

/// The time of the end of step `k` (s): `k dt`, as the runs compute their
/// records' times.
#[allow(clippy::cast_precision_loss)]
fn step_time(k: usize, dt: f64) -> f64 {
    k as f64 * dt
}

/// A truth pose at `time`.
fn truth_pose(time: f64, p: &Pose<f64>) -> TruthPose {
    TruthPose {
        time,
        x: p.x,
        y: p.y,
        theta: p.theta,
    }
}

/// What the parts of a log built step by step share: the log so far and
/// its truth.
#[derive(Debug, Clone)]
struct Builder {
    log: LocusLog,
    truth: Vec<TruthPose>,
    dt: f64,
}

impl Builder {
    fn new(dt: f64, start: [f64; 3], true_start: &Pose<f64>) -> Self {
        let log = LocusLog {
            start: Some(TruthPose {
                time: 0.0,
                x: start[0],
                y: start[1],
                theta: start[2],
            }),
            ..LocusLog::default()
        };
        Self {
            log,
            truth: vec![truth_pose(0.0, true_start)],
            dt,
        }
    }

    /// Step `step` (0-based) ending at `time`: its odometry from its start
    /// (`(v, omega)` of a function of the step's length, s), its truth and
    /// one scan per sensor at its end.
    fn step(
        &mut self,
        step: usize,
        time: f64,
        velocities: impl FnOnce(f64) -> (f64, f64),
        truth: &Pose<f64>,
        ranges: &[f32],
    ) {
        let begin = step_time(step, self.dt);
        // The step's length as the replay computes it from the log's times.
        let (v, omega) = velocities(time - begin);
        self.log.odometry.push(Odometry {
            time: begin,
            v,
            omega,
        });
        self.truth.push(truth_pose(time, truth));
        for (id, r) in (0u32..).zip(ranges) {
            self.log.scans.push(time, id, &[*r]);
        }
    }

    fn finish(mut self) -> LocusLog {
        // Times never decrease (each step's is `(k + 1) dt`).
        self.log.truth = Groundtruth::new(self.truth).unwrap_or_default();
        self.log
    }
}

/// Paper 001's closed loop (`square`, `square-ideal`) as a Locus log with
/// its IR sensors as beam sensors (see the [module documentation](self)):
/// [`SquareLog::new`] before the run, [`SquareLog::push`] each step's
/// record as the run gives it, [`SquareLog::finish`] after.
#[derive(Debug, Clone)]
pub struct SquareLog {
    builder: Builder,
    model: DiffDrive<f64>,
    sensors: [BeamSensor; 2],
}

impl SquareLog {
    /// The log of a run of `cfg` from `seed` (its walls, sensors, noise,
    /// start and true start), before the run's first step.
    ///
    /// # Errors
    /// [`Error::Invalid`] for an invalid configuration; a sensor
    /// construction error.
    pub fn new(cfg: &SquareConfig, seed: u64) -> Result<Self, Error> {
        cfg.validate()?;
        // The run's first draws give its true start.
        let (_, true_start) = cfg.true_robot(&mut StdRng::seed_from_u64(seed));
        let ir = IrPairSensor::new(
            locus_models::IrPair::centred(cfg.ir_spacing),
            SharpIr::assumed(cfg.ir_sigma)?,
        )?;
        let [m1, m2] = ir.mounts();
        let sensors = [
            one_beam(0, &m1, ir.front.min_range, ir.front.max_range),
            one_beam(1, &m2, ir.rear.min_range, ir.rear.max_range),
        ];
        let mut builder = Builder::new(cfg.dt, cfg.start, &true_start);
        let log = &mut builder.log;
        log.walls = World::square_arena().walls.iter().map(wall).collect();
        log.beam_sensors = sensors.to_vec();
        log.ir_pairs = vec![IrPairRecord {
            front: 0,
            rear: 1,
            association_range: cfg.association_range,
        }];
        log.noise.q_v = Some(cfg.q11 / cfg.dt);
        log.noise.q_omega = Some(cfg.q22 / cfg.dt);
        log.noise.sigma_beam = (cfg.r11 == cfg.r22).then(|| cfg.r11.sqrt());
        Ok(Self {
            builder,
            model: DiffDrive::new(cfg.wheelbase, cfg.q11, cfg.q22),
            sensors,
        })
    }
}

impl RunLog for SquareLog {
    type Record = StepRecord;

    /// Adds the step of `record`: its odometry (from the wheel travels the
    /// filter predicted with), its truth and what each IR sensor read.
    fn push(&mut self, record: &StepRecord) {
        let [d1, d2] = record.wheel_travel;
        let (d, dtheta) = self.model.increments(&WheelTravel { d1, d2 });
        let ranges = [
            reading(&self.sensors[0], record.ir_each[0]),
            reading(&self.sensors[1], record.ir_each[1]),
        ];
        self.builder.step(
            record.step,
            record.time,
            |dt| chord_velocities(d, dtheta, dt),
            &record.truth,
            &ranges,
        );
    }

    /// The log of the steps pushed.
    fn finish(self) -> LocusLog {
        self.builder.finish()
    }
}

/// What an IR sensor read, as a scan of `sensor` stores it.
fn reading(sensor: &BeamSensor, r: IrReading) -> f32 {
    match r {
        IrReading::Distance(d) => sensor.reading(d),
        IrReading::Beyond => NO_RETURN,
        IrReading::Below => MISSING,
    }
}

/// A run written as a Locus log as it goes: each step's record pushed,
/// the log finished after the last.
pub trait RunLog {
    /// The run's step record.
    type Record;
    /// Adds the step of `record`.
    fn push(&mut self, record: &Self::Record);
    /// The log of the steps pushed.
    fn finish(self) -> LocusLog;
}

/// Paper 000's `wall45` run as a Locus log with its laser as a beam sensor
/// (see the [module documentation](self)): [`Wall45Log::new`] before the
/// run, [`Wall45Log::push`] each step's record, [`Wall45Log::finish`]
/// after.
#[derive(Debug, Clone)]
pub struct Wall45Log {
    builder: Builder,
    track: f64,
    sensor: BeamSensor,
}

impl Wall45Log {
    /// The log of a run of `cfg` from `seed`, before its first step.
    ///
    /// # Errors
    /// [`Error::Invalid`] for an invalid configuration.
    pub fn new(cfg: &Wall45Config, seed: u64) -> Result<Self, Error> {
        cfg.validate()?;
        let true_start = crate::wall45::true_start(cfg, seed);
        let [x, y, beta] = cfg.mount;
        let sensor = one_beam(0, &LaserMount::new(x, y, beta), 0.0, cfg.max_range);
        let mut builder = Builder::new(cfg.dt, cfg.start_estimate, &true_start);
        let log = &mut builder.log;
        log.walls = World::wall45(cfg.wall_a).walls.iter().map(wall).collect();
        log.beam_sensors = vec![sensor];
        let s2 = cfg.filter_speed_sigma * cfg.filter_speed_sigma;
        log.noise.q_v = Some(0.5 * s2 * cfg.dt);
        log.noise.q_omega = Some(2.0 * s2 * cfg.dt / (cfg.track * cfg.track));
        log.noise.sigma_beam = Some(cfg.laser_sigma_moving);
        Ok(Self {
            builder,
            track: cfg.track,
            sensor,
        })
    }
}

impl RunLog for Wall45Log {
    type Record = Wall45Record;

    /// Adds the step of `record`: its odometry (the measured tread
    /// speeds), its truth and the laser's range.
    fn push(&mut self, record: &Wall45Record) {
        let [v_l, v_r] = record.tread_speeds;
        let range = record.range.map_or(NO_RETURN, |r| self.sensor.reading(r));
        let s = &record.sample;
        let truth = Pose::new(s.truth[0], s.truth[1], s.truth_heading);
        let track = self.track;
        self.builder.step(
            s.step,
            s.time,
            |_| (0.5 * (v_l + v_r), (v_r - v_l) / track),
            &truth,
            &[range],
        );
    }

    /// The log of the steps pushed.
    fn finish(self) -> LocusLog {
        self.builder.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use locus_core::MotionModel;
    use locus_core::nalgebra::{Vector2, Vector3};

    /// The unicycle step of [`chord_velocities`] ends where paper 001's
    /// centred-difference step does, to rounding.
    #[test]
    fn the_chord_velocities_move_as_the_differential_drive() {
        let dd = DiffDrive::new(0.112, 0.0, 0.0);
        for (d1, d2, dt, theta) in [
            (1e-3, 1.2e-3, 0.01, 0.3),
            (-5e-4, 5e-4, 0.01, -2.0),
            (2e-3, 2e-3, 0.02, 3.1),
            (0.05, -0.04, 0.1, 1.0),
        ] {
            let u = WheelTravel { d1, d2 };
            let (d, dtheta) = dd.increments(&u);
            let (v, omega) = chord_velocities(d, dtheta, dt);
            let x = Vector3::new(0.4, -0.7, theta);
            let a = dd.f(&x, &u, &Vector2::zeros());
            let b = Unicycle::new(0.0, 0.0).f(&x, &Velocities { v, omega, dt }, &Vector2::zeros());
            for i in 0..3 {
                assert!(
                    (a[i] - b[i]).abs() < 1e-15,
                    "{i}: {} against {}",
                    a[i],
                    b[i]
                );
            }
        }
    }
}
