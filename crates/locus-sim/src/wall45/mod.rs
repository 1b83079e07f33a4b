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
//!
//! The files split by concern: `config` (the Table III constants, the
//! scenario's configuration and its validation), `record` (the logged
//! [`Wall45Record`] and its CSV row), `run` (the Table III path and
//! [`run_wall45`]) and `table3` (the Monte Carlo reproduction, [`table3`]).
//!
//! [`SkidSteer`]: locus_models::skid_steer::SkidSteer
//! [`Ekf::correct_sequential`]: locus_core::Ekf::correct_sequential
//! [`LaserWallPaper`]: locus_models::laser_wall::LaserWallPaper
//! [`LaserRange`]: locus_models::laser_wall::LaserRange
//! [`Kinematics::SkidSteer`]: crate::robot::Kinematics::SkidSteer
//! [`Laser`]: crate::sensors::Laser
//! [`World::wall45`]: crate::world::World::wall45

mod config;
mod record;
mod run;
mod table3;

pub use config::{INSTANTS, LaserModel, PAPER_TABLE3, Wall45Config, Wall45Noise};
pub use record::{LaserCorrection, Wall45Record};
pub use run::{run_wall45, true_start};
pub use table3::{InstantStats, Table3, table3};
