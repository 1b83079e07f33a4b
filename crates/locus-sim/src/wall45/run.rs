//! The Table III path and the run of `wall45` ([`run_wall45`]).

use locus_core::nalgebra::{Matrix3, SVector, Vector1, Vector2, Vector3};
use locus_core::{Belief, ChiSquareGate, Ekf, MeasurementModel, MotionModel, wrap_angle};
use locus_models::laser_wall::{BeamLimits, LaserMount, LaserRange, LaserWallPaper, WallLine};
use locus_models::skid_steer::{SkidSteer, TreadSpeeds};
use rand::SeedableRng;
use rand::rngs::StdRng;

use super::config::{INSTANTS, LaserModel, PAPER_TABLE3, Wall45Config, Wall45Noise};
use super::record::{LaserCorrection, Wall45Record};
use crate::closed_loop::Error;
use crate::noise::gauss;
use crate::robot::{DriveCommand, Kinematics, Pose, Robot};
use crate::sensors::Laser;
use crate::world::World;
use locus_eval::{Sample, Summary, Tally};

/// One segment of the Table III path.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Segment {
    /// At rest for `n` steps; the instant (1..=6) ends with it.
    Dwell { n: usize, instant: usize },
    /// `n` steps at body speed `v` (m/s) and turn rate `w` (rad/s).
    Move { n: usize, v: f64, w: f64 },
}

/// Steps of at most `rate` per second covering `amount` exactly: `(n, amount
/// / (n dt))`.
#[allow(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::cast_precision_loss
)]
fn split(amount: f64, rate: f64, dt: f64) -> (usize, f64) {
    let n = ((amount.abs() / (rate * dt)) - 1e-9).ceil().max(1.0) as usize;
    (n, amount / (n as f64 * dt))
}

/// The Table III path of `cfg`: dwell, straight, dwell, turn, ... dwell.
#[allow(
    clippy::cast_possible_truncation,
    clippy::cast_sign_loss,
    clippy::cast_precision_loss
)]
fn path(cfg: &Wall45Config) -> Vec<Segment> {
    let dwell = (cfg.dwell / cfg.dt).round() as usize;
    let real = |i: usize| {
        let r = PAPER_TABLE3[i];
        (r[0] * 0.01, r[1] * 0.01, r[2].to_radians())
    };
    let mut out = vec![Segment::Dwell {
        n: dwell,
        instant: 1,
    }];
    for i in 1..INSTANTS {
        let (x0, y0, th0) = real(i - 1);
        let (x1, y1, th1) = real(i);
        let length = (x1 - x0).hypot(y1 - y0);
        let turn = wrap_angle(th1 - th0);
        if length > 1e-9 {
            let (n, v) = split(length, cfg.speed, cfg.dt);
            out.push(Segment::Move { n, v, w: 0.0 });
        } else {
            let (n, w) = split(turn, cfg.turn_rate, cfg.dt);
            out.push(Segment::Move { n, v: 0.0, w });
        }
        out.push(Segment::Dwell {
            n: dwell,
            instant: i + 1,
        });
    }
    out
}

/// The true start of a run: the first draws of its random stream (the
/// ideal mode's start from `N(X0, P0)`, drawn whatever the mode so both
/// modes share the rest of the stream's layout), or the origin in the
/// realistic mode.
fn draw_start(cfg: &Wall45Config, rng: &mut StdRng) -> Vector3<f64> {
    let (x0, sd) = (cfg.start_estimate, cfg.initial_std);
    let drawn = Vector3::new(
        x0[0] + gauss(rng, sd[0]),
        x0[1] + gauss(rng, sd[1]),
        wrap_angle(x0[2] + gauss(rng, sd[2])),
    );
    if cfg.noise == Wall45Noise::Ideal {
        drawn
    } else {
        Vector3::zeros()
    }
}

/// The true pose of a run of `cfg` from `seed` at its start (before its
/// first step), as [`run_wall45`] draws it.
#[must_use]
pub fn true_start(cfg: &Wall45Config, seed: u64) -> Pose<f64> {
    Pose::from_vector(&draw_start(cfg, &mut StdRng::seed_from_u64(seed)))
}

/// Runs `wall45` with `cfg` from `seed`, calling `sink` with every step's
/// record as the run goes, and returns the summary (3-dof NEES).
///
/// # Errors
/// [`Error::Config`] for an invalid configuration; a robot, sensor or
/// filter error stops the run (the records already sunk stay valid).
#[allow(clippy::too_many_lines, clippy::cast_precision_loss)]
pub fn run_wall45(
    cfg: &Wall45Config,
    seed: u64,
    sink: &mut impl FnMut(&Wall45Record),
) -> Result<Summary, Error> {
    cfg.validate()?;
    let mut tally = Tally::new(3)?;
    let mut rng = StdRng::seed_from_u64(seed);
    let ideal = cfg.noise == Wall45Noise::Ideal;

    let sd = cfg.initial_std;
    let x0 = Vector3::from(cfg.start_estimate);
    let p0 = Matrix3::from_diagonal(&Vector3::new(sd[0] * sd[0], sd[1] * sd[1], sd[2] * sd[2]));
    let mut belief = Belief::new(x0, p0);
    let mut odo = belief;
    let mut true_x = draw_start(cfg, &mut rng);

    let true_track = cfg.track * (1.0 + cfg.track_error);
    let mut robot = Robot::new(
        Kinematics::SkidSteer {
            effective_track: true_track,
        },
        Pose::new(true_x[0], true_x[1], true_x[2]),
    );
    let world = World::wall45(cfg.wall_a);
    let mount = LaserMount::new(cfg.mount[0], cfg.mount[1], cfg.mount[2]);
    let laser_rest = Laser::new(vec![mount], cfg.laser_sigma_rest, cfg.max_range)?;
    let laser_moving = Laser::new(vec![mount], cfg.laser_sigma_moving, cfg.max_range)?;
    let wall_line = WallLine::paper_000(cfg.wall_a);

    let var = |s: f64| s * s;
    let model_moving = SkidSteer::new(
        cfg.track,
        var(cfg.filter_speed_sigma),
        var(cfg.filter_speed_sigma),
    );
    let model_rest = SkidSteer::new(
        cfg.track,
        var(cfg.rest_speed_sigma),
        var(cfg.rest_speed_sigma),
    );
    let mut ekf = Ekf::<f64>::default();
    if let Some(c) = cfg.gate_confidence {
        ekf = ekf.with_gate(ChiSquareGate::new(c)?);
    }

    let mut step = 0usize;
    for segment in path(cfg) {
        let (n, v, w, instant) = match segment {
            Segment::Dwell { n, instant } => (n, 0.0, 0.0, Some(instant)),
            Segment::Move { n, v, w } => (n, v, w, None),
        };
        let moving = v != 0.0 || w != 0.0;
        for k in 0..n {
            // Tread speeds: commanded with the filter's D (ideal) or the
            // true D (realistic: the truth drives the table's path).
            let d = if ideal { cfg.track } else { true_track };
            let (left, right) = (v - 0.5 * w * d, v + 0.5 * w * d);
            // Two standard normals per step, whatever the mode.
            let nq = [gauss(&mut rng, 1.0), gauss(&mut rng, 1.0)];
            let model = if moving { &model_moving } else { &model_rest };
            let u = if ideal {
                let u = TreadSpeeds::new(left, right, cfg.dt);
                let q_sd = if moving {
                    cfg.filter_speed_sigma
                } else {
                    cfg.rest_speed_sigma
                };
                let q = Vector2::new(nq[0], nq[1]) * q_sd;
                true_x = model.f(&true_x, &u, &q);
                u
            } else {
                let out = robot.step(&DriveCommand::Wheels { left, right }, cfg.dt)?;
                true_x = Vector3::new(out.pose.x, out.pose.y, out.pose.theta);
                let (ml, mr) = if moving {
                    (
                        left + cfg.true_speed_sigma * nq[0],
                        right + cfg.true_speed_sigma * nq[1],
                    )
                } else {
                    (0.0, 0.0)
                };
                TreadSpeeds::new(ml, mr, cfg.dt)
            };
            belief = ekf.predict(&belief, model, &u)?;
            odo = ekf.predict(&odo, model, &u)?;

            // Laser reading.
            let sigma = if moving {
                cfg.laser_sigma_moving
            } else {
                cfg.laser_sigma_rest
            };
            let laser = if moving { &laser_moving } else { &laser_rest };
            let r_noise = [gauss(&mut rng, sigma), gauss(&mut rng, sigma)];
            let pose = [true_x[0], true_x[1], true_x[2]];
            let measured = laser.read(&world.walls, pose, &mut rng)?[0];
            let limits = BeamLimits::with_max_range(cfg.max_range);
            let paper = LaserWallPaper {
                limits,
                ..LaserWallPaper::new(mount, wall_line, var(sigma), var(sigma))
            };
            let exact = LaserRange {
                limits,
                ..LaserRange::new(mount, &world.walls, var(sigma))
            };
            let mut correction = None;
            let mut innovation = None;
            let mut laser_correction = None;
            let mut range = None;
            match cfg.model {
                LaserModel::Paper => {
                    let z = if ideal {
                        paper
                            .h(&true_x)
                            .map(|h| h + Vector2::new(r_noise[0], r_noise[1]))
                    } else {
                        measured.map(|g| paper.z_from_range(g))
                    };
                    if let Some(z) = z {
                        range = Some(z.norm());
                        if let Some(hx) = paper.h(&belief.x) {
                            laser_correction = Some(LaserCorrection {
                                prior: belief,
                                h: paper.jacobian(&belief.x),
                                r: paper.noise(&belief.x),
                                z,
                                hx,
                            });
                            let c = ekf.correct_sequential(&belief, &paper, &z)?;
                            correction = Some((c.nis, c.dof, c.applied));
                            innovation = Some(c.innovation[0]);
                            belief = c.belief;
                        }
                    }
                }
                LaserModel::Exact => {
                    let z: Option<SVector<f64, 1>> = if ideal {
                        exact.h(&true_x).map(|h| h + Vector1::new(r_noise[0]))
                    } else {
                        measured.map(Vector1::new)
                    };
                    if let Some(z) = z {
                        range = Some(z[0]);
                        if exact.h(&belief.x).is_some() {
                            let c = ekf.correct_sequential(&belief, &exact, &z)?;
                            correction = Some((c.nis, c.dof, c.applied));
                            innovation = Some(c.innovation[0]);
                            belief = c.belief;
                        }
                    }
                }
            }

            let sample = Sample::planar(
                step,
                (step + 1) as f64 * cfg.dt,
                &Pose::from_vector(&true_x),
                &belief,
                Some(&Pose::from_vector(&odo.x)),
                correction,
                range.is_some(),
            );
            tally.push(&sample);
            sink(&Wall45Record {
                sample,
                instant: if k + 1 == n { instant } else { None },
                moving,
                tread_speeds: [u.v_l, u.v_r],
                range,
                innovation,
                laser: laser_correction,
            });
            step += 1;
        }
    }
    Ok(tally.summary(0))
}
