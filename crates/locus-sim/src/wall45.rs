//! The `wall45` scenario of seed 000 (spec section 2): a skid-steer robot
//! (Pioneer 3-AT) with a laser range finder aimed straight ahead at the wall
//! `x + y = a` (45 degrees), driving the path of the paper's Table III, and
//! the Monte Carlo reproduction of that table ([`table3`]).
//!
//! # The path (Table III)
//! The robot rests at instant 1 (the origin, heading 0), drives straight to
//! instant 2, turns on the spot to +47.5 deg (instant 3), drives straight to
//! instant 4, turns to 61.7 deg (instant 5) and drives straight to instant 6.
//! Leg lengths and turn angles are those of the table's "real" column
//! ([`PAPER_TABLE3`]); a straight leg of length `s` at the \[assumed\]
//! 0.10 m/s takes `n = ceil(s / (0.10 dT))` steps at the speed `s / (n dT)`,
//! a turn likewise at 0.3 rad/s, so each leg ends exactly on the table's
//! heading and leg length (the table's real positions are not exactly on
//! its headings: leg 3-4 points at 47.15 deg, leg 5-6 at 62.9 deg, so the
//! true positions differ from the table's by up to 4 mm).
//! The robot dwells [`Wall45Config::dwell`] seconds at rest at every instant
//! (the paper's `R` has a rest and a motion regime), and an instant's
//! figures are taken at the end of its dwell.
//!
//! # One step of `dT` (s)
//! 1. The robot moves under the leg's tread speeds.
//! 2. The measured tread speeds `u = [V_L, V_R]` (m/s) drive the EKF
//!    prediction with [`SkidSteer`] (paper 000, eq. 7-11): while moving with
//!    `Q = diag(s_VL^2, s_VR^2)` = [`Wall45Config::filter_speed_sigma`]^2,
//!    at rest (the encoders read exactly 0) with
//!    [`Wall45Config::rest_speed_sigma`]^2. An odometry-only belief runs
//!    alongside (prediction only).
//! 3. The laser beam (mount `x_si = 0.17 m`, `y_si = 0`, `beta = 0`) reads
//!    the range `gamma` (m) to the wall; the EKF corrects with
//!    [`Ekf::correct_sequential`] using the chosen [`LaserModel`]: the
//!    paper's [`LaserWallPaper`] (eq. 12-15: `Z = gamma [cos beta, sin beta]`,
//!    `R = diag(s_u^2, s_v^2)`, `H` with the hit point held fixed) or the
//!    exact [`LaserRange`] (`z = gamma`, `R = s_gamma^2`, exact Jacobian).
//!    `s` is [`Wall45Config::laser_sigma_rest`] at rest and
//!    [`Wall45Config::laser_sigma_moving`] while moving.
//!
//! # Noise ([`Wall45Noise`])
//! * `Realistic` (default): the truth drives the table's path exactly on
//!   the true kinematics (exact arcs, [`Kinematics::SkidSteer`]) whose
//!   effective track is `D (1 + track_error)` (a skid-steer robot's
//!   effective track is poorly known; the filter uses `D`); the tread speeds
//!   the encoders give are the true ones plus `N(0, true_speed_sigma^2)`
//!   while moving and exactly 0 at rest; the laser ([`Laser`]) casts its
//!   beam on [`World::wall45`] and adds `N(0, s^2)` to the range. The true
//!   start is the origin and the estimate starts at
//!   [`Wall45Config::start_estimate`] (the paper's `X0 = [2 cm, 0.1 cm, 0]`).
//! * `Ideal`: the noise exactly as the filter assumes, for checking its
//!   consistency: the true start is drawn from `N(X0, P0)`; the truth moves
//!   with the filter's own model `X' = f(X, u, q)`, `q ~ N(0, Q)` (the `Q`
//!   of the regime), `u` the commanded speeds (computed with `D`); the
//!   measurement is `z = h(X_true) + r`, `r ~ N(0, R)` of the chosen model.
//!
//! All randomness comes from one `StdRng` seeded with the run's seed; the
//! random stream does not depend on the laser model, so the two models see
//! the same truth and the same readings for a given seed. Units: SI (m, rad,
//! s) everywhere; cm and degrees only in [`PAPER_TABLE3`].

use locus_core::nalgebra::{Matrix3, SVector, Vector1, Vector2, Vector3};
use locus_core::{Belief, ChiSquareGate, Ekf, MeasurementModel, MotionModel, wrap_angle};
use locus_models::laser_wall::{BeamLimits, LaserMount, LaserRange, LaserWallPaper, WallLine};
use locus_models::skid_steer::{SkidSteer, TreadSpeeds};
use rand::SeedableRng;
use rand::rngs::StdRng;
use serde::{Deserialize, Serialize};

use crate::closed_loop::Error;
use crate::noise::gauss;
use crate::robot::{DriveCommand, Kinematics, Pose, Robot};
use crate::sensors::Laser;
use crate::world::World;
use locus_eval::{Record, Sample, Summary, Tally};

/// Table III of seed 000 (spec section 2), as the paper gives it: for each
/// instant 1..=6, `[real x (cm), real y (cm), real theta (deg), EKF x (cm),
/// EKF y (cm), EKF theta (deg)]`.
pub const PAPER_TABLE3: [[f64; 6]; 6] = [
    [0.0, 0.0, 0.0, -0.05, 0.1, -0.001],
    [27.36, 0.0, 0.0, 24.821, 0.092, 0.27],
    [27.36, 0.0, 47.5, 24.17, -1.36, 49.14],
    [38.38, 11.88, 47.5, 34.75, 10.92, 49.24],
    [38.38, 11.88, 61.7, 35.01, 11.52, 63.81],
    [46.47, 27.7, 61.7, 44.18, 30.13, 63.64],
];

/// Number of instants of Table III.
pub const INSTANTS: usize = 6;

/// Which laser measurement model the EKF corrects with.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LaserModel {
    /// The paper's model (eq. 12-15, [`LaserWallPaper`]): `Z = [u, v]`, `H`
    /// with the hit point held fixed.
    #[default]
    Paper,
    /// The exact range model ([`LaserRange`]): `z = gamma`, exact Jacobian.
    Exact,
}

/// How the simulated noise is generated (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Wall45Noise {
    /// Exact-arc truth with a track error, noisy tread speeds, laser range
    /// noise; fixed true start at the origin.
    #[default]
    Realistic,
    /// Noise exactly as the filter's `Q` and `R` assume.
    Ideal,
}

/// Configuration of the `wall45` scenario (SI units: m, s, rad). The
/// defaults ([`Wall45Config::default`]) are the spec's values, \[assumed\]
/// where the paper gives none.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct Wall45Config {
    /// Sample time `dT` (s). \[assumed\] 0.1 s.
    pub dt: f64,
    /// Straight-leg speed (m/s). \[assumed\] 0.10 m/s.
    pub speed: f64,
    /// Turn rate on the spot (rad/s). \[assumed\] 0.3 rad/s.
    pub turn_rate: f64,
    /// Time at rest at each of the six instants (s), the figures being taken
    /// at its end. \[assumed\] 2 s.
    pub dwell: f64,
    /// The wall `x + y = a`: `a` (m). 1.17 m.
    pub wall_a: f64,
    /// Effective track width `D` of the filter's model (m). \[assumed\] 0.50 m.
    pub track: f64,
    /// Relative error of the true effective track (`Realistic` only): the
    /// robot turns about `D (1 + track_error)`. \[assumed\] 0.03.
    pub track_error: f64,
    /// Standard deviation of each measured tread speed while moving
    /// (`Realistic` only, m/s). \[assumed\] 0.01 m/s.
    pub true_speed_sigma: f64,
    /// The filter's `s_VL = s_VR` while moving (m/s). \[assumed\] 0.02 m/s
    /// (covers the speed noise and the track error).
    pub filter_speed_sigma: f64,
    /// The filter's `s_VL = s_VR` at rest (m/s; the encoders read 0).
    /// \[assumed\] 1e-4 m/s.
    pub rest_speed_sigma: f64,
    /// Laser mount `[x_si (m), y_si (m), beta_i (rad)]`. `[0.17, 0, 0]`.
    pub mount: [f64; 3],
    /// Laser range noise at rest, 1 sigma (m): the simulated noise and the
    /// filter's `s_u = s_v = s_gamma`. \[assumed\] 0.005 m.
    pub laser_sigma_rest: f64,
    /// Laser range noise while moving (m). \[assumed\] 0.02 m (the scanner is
    /// less accurate in motion).
    pub laser_sigma_moving: f64,
    /// Largest laser range (m). 8 m.
    pub max_range: f64,
    /// The filter's measurement model. Default [`LaserModel::Paper`].
    pub model: LaserModel,
    /// Initial estimate `X0` (m, m, rad): the paper's `[2 cm, 0.1 cm, 0]`.
    pub start_estimate: [f64; 3],
    /// Standard deviation of the initial estimate (m, m, rad).
    /// \[assumed\] `[0.03, 0.03, 0.035]` (3 cm, 3 cm, 2 deg).
    pub initial_std: [f64; 3],
    /// Confidence of a chi-square gate on the NIS (`None`: no gate, as the
    /// paper). Default `None`.
    pub gate_confidence: Option<f64>,
    /// How the simulated noise is generated. Default `Realistic`.
    pub noise: Wall45Noise,
}

impl Default for Wall45Config {
    fn default() -> Self {
        Self {
            dt: 0.1,
            speed: 0.10,
            turn_rate: 0.3,
            dwell: 2.0,
            wall_a: 1.17,
            track: locus_models::skid_steer::DEFAULT_EFFECTIVE_TRACK,
            track_error: 0.03,
            true_speed_sigma: 0.01,
            filter_speed_sigma: 0.02,
            rest_speed_sigma: 1e-4,
            mount: [0.17, 0.0, 0.0],
            laser_sigma_rest: 0.005,
            laser_sigma_moving: 0.02,
            max_range: locus_models::laser_wall::DEFAULT_MAX_RANGE,
            model: LaserModel::Paper,
            start_estimate: [0.02, 0.001, 0.0],
            initial_std: [0.03, 0.03, 0.035],
            gate_confidence: None,
            noise: Wall45Noise::Realistic,
        }
    }
}

impl Wall45Config {
    /// The ideal-noise variant ([`Wall45Noise::Ideal`]) of the default.
    #[must_use]
    pub fn ideal() -> Self {
        Self {
            noise: Wall45Noise::Ideal,
            ..Self::default()
        }
    }

    /// `Ok(())` if every value is in its domain.
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the first bad field.
    pub fn validate(&self) -> Result<(), Error> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        let non_neg = |v: f64| v.is_finite() && v >= 0.0;
        let checks: [(bool, &'static str, &'static str); 16] = [
            (pos(self.dt), "dt", "must be finite and > 0"),
            (pos(self.speed), "speed", "must be finite and > 0"),
            (pos(self.turn_rate), "turn_rate", "must be finite and > 0"),
            (
                non_neg(self.dwell) && self.dwell >= 0.5 * self.dt,
                "dwell",
                "must be finite and >= dt / 2 (one step at rest per instant)",
            ),
            (self.wall_a.is_finite(), "wall_a", "must be finite"),
            (pos(self.track), "track", "must be finite and > 0"),
            (
                self.track_error.is_finite() && self.track_error > -1.0,
                "track_error",
                "must be finite and > -1",
            ),
            (
                non_neg(self.true_speed_sigma),
                "true_speed_sigma",
                "must be finite and >= 0",
            ),
            (
                pos(self.filter_speed_sigma),
                "filter_speed_sigma",
                "must be finite and > 0",
            ),
            (
                pos(self.rest_speed_sigma),
                "rest_speed_sigma",
                "must be finite and > 0",
            ),
            (
                self.mount.iter().all(|v| v.is_finite()),
                "mount",
                "must be finite",
            ),
            (
                pos(self.laser_sigma_rest),
                "laser_sigma_rest",
                "must be finite and > 0",
            ),
            (
                pos(self.laser_sigma_moving),
                "laser_sigma_moving",
                "must be finite and > 0",
            ),
            (pos(self.max_range), "max_range", "must be finite and > 0"),
            (
                self.start_estimate.iter().all(|v| v.is_finite())
                    && self.initial_std.iter().all(|v| pos(*v)),
                "start_estimate",
                "must be finite and initial_std finite and > 0",
            ),
            (
                self.gate_confidence
                    .is_none_or(|c| c.is_finite() && c > 0.0 && c < 1.0),
                "gate_confidence",
                "must be in (0, 1)",
            ),
        ];
        match checks.iter().find(|(ok, _, _)| !ok) {
            Some(&(_, field, reason)) => Err(Error::Invalid { field, reason }),
            None => Ok(()),
        }
    }
}

/// One step of `wall45` (SI units, world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Wall45Record {
    /// The common figures (truth, estimate, covariance, odometry alone,
    /// NEES, NIS).
    pub sample: Sample,
    /// The Table III instant (1..=6) whose dwell ends at this step, if any.
    pub instant: Option<usize>,
    /// Whether the robot was moving during the step.
    pub moving: bool,
    /// Measured tread speeds `[V_L, V_R]` (m/s) given to the filter.
    pub tread_speeds: [f64; 2],
    /// The laser range reading (m), if the beam hit the wall.
    pub range: Option<f64>,
    /// Innovation of the correction (m): the range component (`u` for the
    /// paper's model, `gamma` for the exact one), if corrected.
    pub innovation: Option<f64>,
}

fn fmt_opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, |v| format!("{v:.9}"))
}

impl Record for Wall45Record {
    fn csv_header() -> String {
        [
            "step",
            "time[s]",
            "instant",
            "moving",
            "true_x[m]",
            "true_y[m]",
            "true_theta[rad]",
            "ekf_x[m]",
            "ekf_y[m]",
            "ekf_theta[rad]",
            "p_xx[m2]",
            "p_yy[m2]",
            "p_thth[rad2]",
            "p_xy[m2]",
            "odo_x[m]",
            "odo_y[m]",
            "odo_theta_err[rad]",
            "v_l[m/s]",
            "v_r[m/s]",
            "range[m]",
            "innovation[m]",
            "nis",
            "applied",
            "nees",
        ]
        .join(",")
    }

    fn csv_row(&self) -> String {
        let s = &self.sample;
        let f = |v: f64| format!("{v:.9}");
        let (odo, odo_th) = s.odometry.unwrap_or(([f64::NAN; 3], f64::NAN));
        let (nis, applied) = s.correction.map_or((None, String::new()), |(n, _, a)| {
            (Some(n), u8::from(a).to_string())
        });
        [
            s.step.to_string(),
            format!("{:.2}", s.time),
            self.instant.map_or_else(String::new, |i| i.to_string()),
            u8::from(self.moving).to_string(),
            f(s.truth[0]),
            f(s.truth[1]),
            f(s.truth_heading),
            f(s.estimate[0]),
            f(s.estimate[1]),
            f(s.estimate_heading),
            format!("{:.6e}", s.covariance[0][0]),
            format!("{:.6e}", s.covariance[1][1]),
            format!("{:.6e}", s.covariance[2][2]),
            format!("{:.6e}", s.covariance[0][1]),
            f(odo[0]),
            f(odo[1]),
            f(odo_th),
            f(self.tread_speeds[0]),
            f(self.tread_speeds[1]),
            fmt_opt(self.range),
            fmt_opt(self.innovation),
            fmt_opt(nis),
            applied,
            format!("{:.6}", s.nees),
        ]
        .join(",")
    }

    fn sample(&self) -> Sample {
        self.sample
    }
}

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

/// NEES `e^T P^-1 e` of `x` against `truth` (heading wrapped); NaN if `P`
/// is not positive definite.
fn nees(x: &Vector3<f64>, p: &Matrix3<f64>, truth: &Vector3<f64>) -> f64 {
    let e = Vector3::new(
        truth[0] - x[0],
        truth[1] - x[1],
        wrap_angle(truth[2] - x[2]),
    );
    locus_eval::nees(&e, p)
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
    // Draw the ideal start whatever the mode, so both modes share the rest
    // of the random stream's layout.
    let drawn = Vector3::new(
        x0[0] + gauss(&mut rng, sd[0]),
        x0[1] + gauss(&mut rng, sd[1]),
        wrap_angle(x0[2] + gauss(&mut rng, sd[2])),
    );
    let mut true_x = if ideal { drawn } else { Vector3::zeros() };

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
                        if paper.h(&belief.x).is_some() {
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

            let p = &belief.p;
            let mut covariance = [[0.0; 3]; 3];
            for (i, row) in covariance.iter_mut().enumerate() {
                for (j, c) in row.iter_mut().enumerate() {
                    *c = p[(i, j)];
                }
            }
            let sample = Sample {
                step,
                time: (step + 1) as f64 * cfg.dt,
                truth: [true_x[0], true_x[1], 0.0],
                truth_heading: true_x[2],
                estimate: [belief.x[0], belief.x[1], 0.0],
                estimate_heading: belief.x[2],
                heading_error: wrap_angle(true_x[2] - belief.x[2]),
                covariance,
                var_z: 0.0,
                odometry: Some(([odo.x[0], odo.x[1], 0.0], wrap_angle(true_x[2] - odo.x[2]))),
                nees: nees(&belief.x, &belief.p, &true_x),
                nees_dof: 3,
                correction,
                measured: range.is_some(),
            };
            tally.push(&sample);
            sink(&Wall45Record {
                sample,
                instant: if k + 1 == n { instant } else { None },
                moving,
                tread_speeds: [u.v_l, u.v_r],
                range,
                innovation,
            });
            step += 1;
        }
    }
    Ok(tally.summary(0))
}

/// Monte Carlo figures of one Table III instant for one laser model (SI:
/// m, rad).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct InstantStats {
    /// Mean true pose `[x, y, theta]` over the runs (m, m, rad).
    pub truth: [f64; 3],
    /// Mean EKF estimate `[x, y, theta]` (m, m, rad; heading as the mean
    /// of wrapped errors subtracted from the mean truth).
    pub estimate: [f64; 3],
    /// EKF position RMSE over the runs (m).
    pub position_rmse: f64,
    /// EKF heading RMSE (rad).
    pub heading_rmse: f64,
    /// Mean NEES (3 dof; 3 for a consistent filter).
    pub mean_nees: f64,
    /// Odometry-alone position RMSE (m).
    pub odometry_position_rmse: f64,
    /// Odometry-alone heading RMSE (rad).
    pub odometry_heading_rmse: f64,
}

/// The Monte Carlo reproduction of Table III: per instant, per model.
#[derive(Debug, Clone, PartialEq)]
pub struct Table3 {
    /// Runs (seeds) per model.
    pub runs: usize,
    /// The six instants with the paper's `H` ([`LaserModel::Paper`]).
    pub paper_h: [InstantStats; INSTANTS],
    /// The six instants with the exact model ([`LaserModel::Exact`]).
    pub exact: [InstantStats; INSTANTS],
}

/// The six instants' samples of one run.
fn instants_of_run(cfg: &Wall45Config, seed: u64) -> Result<[Sample; INSTANTS], Error> {
    let mut out = [Sample::default(); INSTANTS];
    let mut seen = 0usize;
    run_wall45(cfg, seed, &mut |r: &Wall45Record| {
        if let Some(i) = r.instant {
            out[i - 1] = r.sample;
            seen += 1;
        }
    })?;
    if seen == INSTANTS {
        Ok(out)
    } else {
        Err(Error::Config(
            "dwell must give at least one step per instant",
        ))
    }
}

/// Accumulates the runs' samples of each instant into [`InstantStats`].
#[allow(clippy::cast_precision_loss)]
fn stats(runs: &[[Sample; INSTANTS]]) -> [InstantStats; INSTANTS] {
    let n = runs.len().max(1) as f64;
    let mut out = [InstantStats::default(); INSTANTS];
    for (i, st) in out.iter_mut().enumerate() {
        let (mut sq_pos, mut sq_th, mut nees) = (0.0, 0.0, 0.0);
        let (mut odo_pos, mut odo_th) = (0.0, 0.0);
        let (mut truth, mut est) = ([0.0; 3], [0.0; 3]);
        for run in runs {
            let s = &run[i];
            sq_pos += s.position_error_sq();
            sq_th += s.heading_error * s.heading_error;
            nees += s.nees;
            if let Some((p, th)) = s.odometry {
                odo_pos += (s.truth[0] - p[0]).powi(2) + (s.truth[1] - p[1]).powi(2);
                odo_th += th * th;
            }
            truth[0] += s.truth[0];
            truth[1] += s.truth[1];
            truth[2] += s.truth_heading;
            est[0] += s.estimate[0];
            est[1] += s.estimate[1];
            est[2] += s.truth_heading - s.heading_error;
        }
        *st = InstantStats {
            truth: truth.map(|v| v / n),
            estimate: est.map(|v| v / n),
            position_rmse: (sq_pos / n).sqrt(),
            heading_rmse: (sq_th / n).sqrt(),
            mean_nees: nees / n,
            odometry_position_rmse: (odo_pos / n).sqrt(),
            odometry_heading_rmse: (odo_th / n).sqrt(),
        };
    }
    out
}

/// Table III by Monte Carlo: `cfg` run from every seed of `seeds` with the
/// paper's `H` and with the exact model (in parallel, rayon), calling
/// `progress` once per finished run (two per seed). The other fields of
/// `cfg` (including `model`) are kept; `model` is overridden per column.
///
/// # Errors
/// [`Error::Config`] for an invalid configuration or an empty seed range;
/// the first run error otherwise.
pub fn table3(
    cfg: &Wall45Config,
    seeds: core::ops::Range<u64>,
    progress: &(impl Fn() + Sync),
) -> Result<Table3, Error> {
    use rayon::prelude::*;

    cfg.validate()?;
    if seeds.is_empty() {
        return Err(Error::Config("table3 needs at least one seed"));
    }
    let column = |model: LaserModel| -> Result<Vec<[Sample; INSTANTS]>, Error> {
        let c = Wall45Config { model, ..*cfg };
        seeds
            .clone()
            .into_par_iter()
            .map(|seed| {
                let r = instants_of_run(&c, seed);
                progress();
                r
            })
            .collect()
    };
    let paper = column(LaserModel::Paper)?;
    let exact = column(LaserModel::Exact)?;
    Ok(Table3 {
        runs: paper.len(),
        paper_h: stats(&paper),
        exact: stats(&exact),
    })
}
