//! The simulated robot side of the closed loop: the true robot drawn
//! from the seed, and the ideal mode's observation on the truth.

use locus_core::nalgebra::{Vector2, Vector3};
use locus_core::{MeasurementModel, wrap_angle};
use locus_models::{IrPairObservation, associate_ir_wall};
use rand::rngs::StdRng;

use super::{Error, SquareConfig};
use crate::noise::gauss;
use crate::robot::{Kinematics, Pose, Robot, SlipSchedule, Wheel};
use crate::sensors::{IrPairSensor, SharpIr};
use crate::world::World;

impl SquareConfig {
    /// The true robot of a run, and its start pose: the start drawn from
    /// the initial estimate's distribution (`start`, `initial_std`), then
    /// the slip bumps of each wheel over the first lap. Draws from `rng` in
    /// this fixed order, so [`run_square`](super::run_square) and the
    /// robot-link endpoint simulate the same robot from the same seed.
    pub fn true_robot(&self, rng: &mut StdRng) -> (Robot, Pose) {
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

/// An ideal-mode observation and its `z` (m, rad).
type IdealObservation = (IrPairObservation<f64>, Vector2<f64>);

/// The ideal-mode observation at the true state `true_x` with reading noise
/// `noise` (m): `None` unless both noise-free readings are in the sensor's
/// useful range and both beams see the wall the data association on the
/// true pose returns; otherwise the observation (noise-free readings, the
/// true wall, `R` of `cfg`) and `z = h(X_true) + V n`, heading wrapped.
pub(super) fn ideal_observation(
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
