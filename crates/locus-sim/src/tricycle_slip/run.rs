//! The room and the run of `tricycle-slip` ([`run_tricycle_slip`]).

use locus_core::nalgebra::{Matrix3, Vector1, Vector3};
use locus_core::{Belief, ChiSquareGate, Ekf, MeasurementModel};
use locus_models::laser_wall::{LaserMount, LaserRange, Segment};
use locus_models::{CountNoise, RearCounts, TricycleRear};
use locus_odometry::redundant::{Integration, Odometry, Reading, Selection};
use locus_odometry::{Libm, wrapping_diff};
use rand::SeedableRng;
use rand::rngs::StdRng;

use super::config::TricycleSlipConfig;
use super::record::TricycleSlipRecord;
use crate::closed_loop::Error;
use crate::noise::gauss;
use crate::robot::{DriveCommand, Kinematics, Pose, Robot, Slip, SlipSchedule, Wheel};
use crate::sensors::{Encoder, Laser};
use crate::world::World;
use locus_eval::{Sample, Summary, Tally};

/// Width of the encoders' wrapping counter (bits).
const COUNTER_BITS: u32 = locus_odometry::counter::PAPER_BITS;

/// The four walls of the room `[x_min, y_min, x_max, y_max]` (m).
pub fn room(r: [f64; 4]) -> World {
    let [x0, y0, x1, y1] = r;
    World::new(vec![
        Segment::new([x0, y0], [x1, y0]),
        Segment::new([x1, y0], [x1, y1]),
        Segment::new([x1, y1], [x0, y1]),
        Segment::new([x0, y1], [x0, y0]),
    ])
}

/// Runs `tricycle-slip` with `cfg` from `seed`, calling `sink` with every
/// step's record as the run goes, and returns the summary (its odometry
/// figures are the rear-only dead reckoning's; 3-dof NEES).
///
/// # Errors
/// [`Error::Config`] for an invalid configuration; a robot, sensor or
/// filter error stops the run (the records already sunk stay valid).
#[allow(
    clippy::too_many_lines,
    clippy::cast_precision_loss,
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss
)]
pub fn run_tricycle_slip(
    cfg: &TricycleSlipConfig,
    seed: u64,
    sink: &mut impl FnMut(&TricycleSlipRecord),
) -> Result<Summary, Error> {
    cfg.validate()?;
    let tri = cfg.tricycle();
    tri.validate()
        .map_err(|_| Error::Config("tricycle geometry or encoders invalid"))?;
    let mut tally = Tally::new(3)?;
    let mut rng = StdRng::seed_from_u64(seed);

    let sd = cfg.initial_std;
    let true_start = Pose::new(
        gauss(&mut rng, sd[0]),
        gauss(&mut rng, sd[1]),
        gauss(&mut rng, sd[2]),
    );
    let mut slip = SlipSchedule::bumps(
        Wheel::Left,
        cfg.bump_start,
        cfg.bump_length,
        cfg.bump_spacing,
        cfg.bump_count,
        cfg.bump_scale,
    );
    slip.push(Slip {
        wheel: Wheel::Front,
        start: cfg.patch_start,
        end: cfg.patch_start + cfg.patch_length,
        scale: cfg.patch_scale,
    });
    let mut robot = Robot::new(
        Kinematics::Tricycle {
            wheelbase: cfg.wheelbase,
            rear_track: cfg.track,
        },
        true_start,
    )
    .with_slip(slip);

    let mut enc_l = Encoder::new(tri.rear)?;
    let mut enc_r = Encoder::new(tri.rear)?;
    let mut enc_f = Encoder::new(tri.front)?;
    let mut last = [enc_l.read(), enc_r.read(), enc_f.read()];

    let mut rear_odo = Odometry::new(
        tri,
        Selection::Rear,
        Integration::Euler,
        Libm,
        locus_core::Pose::default(),
    );
    let mut rej_odo = Odometry::new(
        tri,
        cfg.rejection.selection(),
        Integration::Euler,
        Libm,
        locus_core::Pose::default(),
    );

    let model = TricycleRear::new(
        cfg.rear_radius,
        tri.rear.counts_per_rev(),
        cfg.track,
        CountNoise {
            floor: cfg.count_var_floor,
            per_count: cfg.count_var_per_count,
        },
    );
    let mut ekf = Ekf::<f64>::default();
    if let Some(c) = cfg.gate_confidence {
        ekf = ekf.with_gate(ChiSquareGate::new(c)?);
    }
    let p0 = Matrix3::from_diagonal(&Vector3::new(sd[0] * sd[0], sd[1] * sd[1], sd[2] * sd[2]));
    let mut belief = Belief::new(Vector3::zeros(), p0);

    let world = room(cfg.room);
    let mounts = cfg.beams.map(|b| LaserMount::new(b[0], b[1], b[2]));
    let laser = Laser::new(mounts.to_vec(), cfg.laser_sigma, cfg.laser_max_range)?;

    // The steering profile: straight, then the arc.
    let steer_arc = (cfg.wheelbase / cfg.arc_radius).atan();
    let legs = [
        (cfg.straight, 0.0),
        (cfg.arc_radius * cfg.arc_angle, steer_arc),
    ];
    let mut step = 0usize;
    for (length, phi) in legs {
        if length <= 0.0 {
            continue;
        }
        let n = ((length / (cfg.speed * cfg.dt)) - 1e-9).ceil().max(1.0) as usize;
        // Front speed giving the rear-axle speed that ends the leg exactly.
        let v = length / (n as f64 * cfg.dt);
        let front_speed = v / phi.cos();
        for _ in 0..n {
            let out = robot.step(
                &DriveCommand::Steered {
                    speed: front_speed,
                    steering: phi,
                },
                cfg.dt,
            )?;
            let m = out.measured_travel;
            let mut noisy = |d: f64| d + gauss(&mut rng, cfg.travel_noise * d.abs().sqrt());
            let (dl, dr, df) = (noisy(m.left), noisy(m.right), noisy(m.front));
            enc_l.advance(dl, &mut rng)?;
            enc_r.advance(dr, &mut rng)?;
            enc_f.advance(df, &mut rng)?;
            let now = [enc_l.read(), enc_r.read(), enc_f.read()];
            let reading = Reading {
                n_l: wrapping_diff(now[0], last[0], COUNTER_BITS),
                n_r: wrapping_diff(now[1], last[1], COUNTER_BITS),
                n_f: wrapping_diff(now[2], last[2], COUNTER_BITS),
                n_s: (phi / tri.steering.quantum()).round() as i32,
            };
            last = now;
            rear_odo.step(&reading);
            rej_odo.step(&reading);

            belief = ekf.predict(
                &belief,
                &model,
                &RearCounts::from_counts(reading.n_l, reading.n_r),
            )?;

            let truth = out.pose;
            let mut ranges = [None; 3];
            let mut correction: Option<(f64, u32, bool)> = None;
            if (step + 1) % cfg.laser_period == 0 {
                let read = laser.read(&world.walls, [truth.x, truth.y, truth.theta], &mut rng)?;
                for (i, (mount, z)) in mounts.iter().zip(read).enumerate() {
                    ranges[i] = z;
                    let Some(z) = z else { continue };
                    let exact = LaserRange {
                        limits: locus_models::laser_wall::BeamLimits::with_max_range(
                            cfg.laser_max_range,
                        ),
                        ..LaserRange::new(*mount, &world.walls, cfg.laser_sigma.powi(2))
                    };
                    if exact.h(&belief.x).is_none() {
                        continue;
                    }
                    let c = ekf.correct_sequential(&belief, &exact, &Vector1::new(z))?;
                    belief = c.belief;
                    // The step's NIS is the sum over the beams (independent
                    // scalar updates), its dof their count; applied if any.
                    correction = Some(match correction {
                        None => (c.nis, c.dof, c.applied),
                        Some((n, d, a)) => (n + c.nis, d + c.dof, a || c.applied),
                    });
                }
            }

            let rp = rear_odo.pose();
            let sp = rej_odo.pose();
            let sample = Sample::planar(
                step,
                (step + 1) as f64 * cfg.dt,
                &truth,
                &belief,
                Some(&rp),
                correction,
                ranges.iter().any(Option::is_some),
            );
            tally.push(&sample);
            sink(&TricycleSlipRecord {
                sample,
                slip_rejecting: [sp.x, sp.y, sp.theta],
                rear_only: [rp.x, rp.y, rp.theta],
                reading,
                ranges,
            });
            step += 1;
        }
    }
    Ok(tally.summary(0))
}
