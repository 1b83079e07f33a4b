//! The simulated robot side of the closed loop: the true robot drawn from
//! the seed, its slip and encoders, the IR pair reading the true walls,
//! and the ideal mode's truth (moved by the filter's own model) and
//! observation. Everything random in a run is drawn here, from one
//! `StdRng` seeded with the run's seed, in a fixed order per step.

use locus_core::nalgebra::{Vector2, Vector3};
use locus_core::{MeasurementModel, MotionModel, wrap_angle};
use locus_models::{DiffDrive, IrPair, IrPairObservation, WheelTravel, associate_ir_wall};
use locus_odometry::Wheel as EncoderWheel;
use rand::SeedableRng;
use rand::rngs::StdRng;

use super::{Error, SquareConfig};
use crate::noise::gauss;
use crate::robot::{DriveCommand, Kinematics, Pose, Robot, SlipSchedule, Wheel};
use crate::sensors::{Encoder, IrPairSensor, IrReading, SharpIr};
use crate::world::World;

impl SquareConfig {
    /// The true robot of a run, and its start pose: the start drawn from
    /// the initial estimate's distribution (`start`, `initial_std`), then
    /// the slip bumps of each wheel over the first lap. Draws from `rng` in
    /// this fixed order, so [`run_square`](super::run_square) and the
    /// robot-link endpoint simulate the same robot from the same seed.
    pub fn true_robot(&self, rng: &mut StdRng) -> (Robot, Pose<f64>) {
        let (s, sd) = (self.start, self.initial_std);
        let true_start = Pose::new(
            s[0] + gauss(rng, sd[0]),
            s[1] + gauss(rng, sd[1]),
            s[2] + gauss(rng, sd[2]),
        );
        // Slip bumps over the first lap's wheel travel.
        let lap_length = 8.0 * locus_control::SQUARE_HALF_SIDE;
        let mut slip = SlipSchedule::random_bumps(
            rng,
            Wheel::Left,
            (0.0, lap_length),
            self.slip_bumps_per_wheel,
            self.slip_length,
            self.slip_scale,
        );
        for z in SlipSchedule::random_bumps(
            rng,
            Wheel::Right,
            (0.0, lap_length),
            self.slip_bumps_per_wheel,
            self.slip_length,
            self.slip_scale,
        )
        .zones
        {
            slip.push(z);
        }
        let robot = Robot::new(
            Kinematics::DifferentialDrive {
                wheelbase: self.wheelbase,
                wheel_radius: self.wheel_radius,
            },
            true_start,
        )
        .with_slip(slip);
        (robot, true_start)
    }
}

/// The simulated robot of one run (the truth side of the loop).
#[derive(Debug)]
pub(super) struct Plant {
    rng: StdRng,
    /// The arena.
    pub(super) world: World,
    robot: Robot,
    /// The encoders `[right, left]`.
    encoders: [Encoder; 2],
    /// The IR pair sensor.
    pub(super) ir: IrPairSensor,
    /// The ideal mode's true state `[x, y, theta]`.
    true_x: Vector3<f64>,
    truth: Pose<f64>,
}

impl Plant {
    /// The robot of `cfg` from `seed`, with encoders on `wheel`: the
    /// draws of [`SquareConfig::true_robot`], nothing else.
    ///
    /// # Errors
    /// A sensor construction error.
    pub(super) fn new(
        cfg: &SquareConfig,
        seed: u64,
        wheel: EncoderWheel<f64>,
    ) -> Result<Self, Error> {
        let mut rng = StdRng::seed_from_u64(seed);
        let (robot, truth) = cfg.true_robot(&mut rng);
        let encoders = [Encoder::new(wheel)?, Encoder::new(wheel)?];
        let ir = IrPairSensor::new(
            IrPair::centred(cfg.ir_spacing),
            SharpIr::assumed(cfg.ir_sigma)?,
        )?;
        Ok(Self {
            rng,
            world: World::square_arena(),
            robot,
            encoders,
            ir,
            true_x: Vector3::new(truth.x, truth.y, truth.theta),
            truth,
        })
    }

    /// The true pose now.
    pub(super) fn truth(&self) -> Pose<f64> {
        self.truth
    }

    /// The encoders' counts `[right, left]` now (20-bit, wrapping).
    pub(super) fn counts(&self) -> [u32; 2] {
        [self.encoders[0].read(), self.encoders[1].read()]
    }

    /// Injects IR distance noise of standard deviation `sigma` (m) from now
    /// on.
    ///
    /// # Errors
    /// A sensor error for an invalid `sigma`; the sensor is then unchanged.
    pub(super) fn set_ir_sigma(&mut self, sigma: f64) -> Result<(), Error> {
        self.ir = IrPairSensor::new(self.ir.pair, SharpIr::assumed(sigma)?)?;
        Ok(())
    }

    /// The realistic mode's move: the robot drives the right and left
    /// wheels at `(v1, v2)` (m/s) for `dt` (exact arc, slip bumps), and each
    /// wheel's measured travel advances its encoder (the right one
    /// over-counting by `right_scale_error`). Returns the counts
    /// `[right, left]`.
    ///
    /// # Errors
    /// A robot or encoder error.
    pub(super) fn drive(
        &mut self,
        cfg: &SquareConfig,
        (v1, v2): (f64, f64),
    ) -> Result<[u32; 2], Error> {
        let out = self.robot.step(
            &DriveCommand::Wheels {
                left: v2,
                right: v1,
            },
            cfg.dt,
        )?;
        let [right, left] = &mut self.encoders;
        right.advance(
            out.measured_travel.right * (1.0 + cfg.right_scale_error),
            &mut self.rng,
        )?;
        left.advance(out.measured_travel.left, &mut self.rng)?;
        self.truth = out.pose;
        Ok(self.counts())
    }

    /// The ideal mode's move: the truth moves with the filter's own model,
    /// `X_true' = f(X_true, u, q)` (paper 001 eq. 7-13) with
    /// `q ~ N(0, diag(Q11, Q22))`.
    pub(super) fn drive_ideal(
        &mut self,
        cfg: &SquareConfig,
        model: &DiffDrive<f64>,
        u: &WheelTravel<f64>,
    ) {
        let q = Vector2::new(
            gauss(&mut self.rng, cfg.q11.sqrt()),
            gauss(&mut self.rng, cfg.q22.sqrt()),
        );
        self.true_x = model.f(&self.true_x, u, &q);
        let x = &self.true_x;
        self.truth = Pose::new(x[0], x[1], x[2]);
    }

    /// The realistic mode's IR readings on the true walls, through the
    /// sensor curve: each sensor's `[s1, s2]`, and the pair `(d_s1, d_s2)`
    /// (m) when both are in range.
    ///
    /// # Errors
    /// A sensor error.
    pub(super) fn read_ir(&mut self) -> Result<(IrReadings, [IrReading; 2]), Error> {
        let t = self.truth;
        let each = self
            .ir
            .read_each(&self.world.walls, [t.x, t.y, t.theta], &mut self.rng)?;
        Ok((each[0].distance().zip(each[1].distance()), each))
    }

    /// The ideal mode's IR pair: draws the reading noise
    /// `n ~ N(0, diag(R11, R22))` (always, so the random stream does not
    /// depend on what the sensor sees), then returns the readings (the
    /// noise-free ones plus `n`) and the observation with its `z`, when the
    /// truth's pair sees a wall (see [`ideal_observation`]), and what each
    /// sensor read: its noise-free distance plus its `n` when that
    /// distance is in the useful range.
    ///
    /// # Errors
    /// A sensor error.
    pub(super) fn observe_ideal(
        &mut self,
        cfg: &SquareConfig,
    ) -> Result<(IrReadings, [IrReading; 2], Option<IdealObservation>), Error> {
        let noise = Vector2::new(
            gauss(&mut self.rng, cfg.r11.sqrt()),
            gauss(&mut self.rng, cfg.r22.sqrt()),
        );
        let x = &self.true_x;
        let (t1, t2) = self
            .ir
            .true_distances(&self.world.walls, [x[0], x[1], x[2]])?;
        let each = |t: Option<f64>, s: &SharpIr, n: f64| match t {
            Some(d) if d < s.min_range => IrReading::Below,
            Some(d) if d <= s.max_range => IrReading::Distance(d + n),
            _ => IrReading::Beyond,
        };
        let each = [
            each(t1, &self.ir.front, noise[0]),
            each(t2, &self.ir.rear, noise[1]),
        ];
        Ok(
            match ideal_observation(cfg, &self.ir, &self.world, &self.true_x, &noise)? {
                Some((obs, z)) => (
                    Some((obs.ds1 + noise[0], obs.ds2 + noise[1])),
                    each,
                    Some((obs, z)),
                ),
                None => (None, each, None),
            },
        )
    }
}

/// The IR pair's readings `(d_s1, d_s2)` (m), when both were in range.
pub(super) type IrReadings = Option<(f64, f64)>;

/// An ideal-mode observation and its `z` (m, rad).
pub(super) type IdealObservation = (IrPairObservation<f64>, Vector2<f64>);

/// The ideal-mode observation at the true state `true_x` with reading noise
/// `noise` (m): `None` unless both noise-free readings are in the sensor's
/// useful range and both beams see the wall the data association on the
/// true pose returns; otherwise the observation (noise-free readings, the
/// true wall, `R` of `cfg`) and `z = h(X_true) + V n`, heading wrapped.
fn ideal_observation(
    cfg: &SquareConfig,
    ir: &IrPairSensor,
    world: &World,
    true_x: &Vector3<f64>,
    noise: &Vector2<f64>,
) -> Result<Option<IdealObservation>, Error> {
    let (t1, t2) = ir.true_distances(&world.walls, [true_x[0], true_x[1], true_x[2]])?;
    let in_range =
        |t: Option<f64>, s: &SharpIr| t.filter(|d| (s.min_range..=s.max_range).contains(d));
    let (Some(ds1), Some(ds2)) = (in_range(t1, &ir.front), in_range(t2, &ir.rear)) else {
        return Ok(None);
    };
    let Some(wall) = associate_ir_wall(true_x, &ir.pair, &world.walls, cfg.association_range)
    else {
        return Ok(None);
    };
    let obs = IrPairObservation {
        pair: ir.pair,
        wall,
        ds1,
        ds2,
        r11: cfg.r11,
        r22: cfg.r22,
    };
    let Some(h) = obs.h(true_x) else {
        return Ok(None);
    };
    // Both beams on that wall: the noise-free readings give exactly h.
    let r = obs.residual(&obs.z(), &h);
    if r[0].abs() > 1e-9 || r[1].abs() > 1e-9 {
        return Ok(None);
    }
    let e = obs.v() * noise;
    Ok(Some((
        obs,
        Vector2::new(h[0] + e[0], wrap_angle(h[1] + e[1])),
    )))
}
