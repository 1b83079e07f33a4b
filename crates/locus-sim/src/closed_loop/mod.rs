//! The closed loop of paper 001 on the `square` scenario (spec section 3):
//! controller -> wheel speeds -> simulated differential-drive robot ->
//! quadrature encoders -> paper 001's [`Localiser`] (counts -> wheel travel
//! -> prediction with [`DiffDrive`] -> IR pair -> wall association ->
//! correction with [`IrPairObservation`] behind the gate), with the
//! controller steering on the estimate. An odometry-only belief (prediction
//! only, the same wheel travels) runs alongside for comparison.
//!
//! The files split by concern: `config` (the scenario's configuration and
//! its validation), `plant` (the simulated robot: truth, slip, encoders, IR
//! readings, the ideal mode's observation), `record` (the logged
//! [`StepRecord`]), `live` (what the teaching UI needs: live parameters,
//! teleoperation, correction details) and `sim` ([`SquareSim`],
//! [`run_square`]).
//!
//! # One step of `dt` (s)
//! 1. The path controller ([`FollowPath::square`]) maps the estimate to
//!    `(V, W)`; [`wheel_speeds`] gives `V1` (right), `V2` (left).
//! 2. The robot moves (exact arc, [`Kinematics::DifferentialDrive`]), with
//!    random slip bumps making the encoders over-count.
//! 3. Each wheel's measured travel drives an [`Encoder`]; the right encoder
//!    also carries a constant calibration error
//!    ([`SquareConfig::right_scale_error`]). The localiser's [`Odometer`]
//!    turns the wrapping 20-bit counts into wheel travels `d1` (right) and
//!    `d2` (left), m (paper 001 eq. 9: the count difference since the last
//!    step times the count quantum).
//! 4. Both beliefs are predicted with [`DiffDrive`] (eq. 7-13).
//! 5. The IR pair ([`IrPairSensor`]) reads the true walls; when both sensors
//!    are in range, [`Localiser::ir`] picks the wall the estimate's sensing
//!    ray hits (or drops the reading) and corrects (eq. 3-5, 17-20; 99 %
//!    chi-square gate by default).
//!
//! # The `square-ideal` scenario ([`NoiseModel::Ideal`])
//! The same loop with the simulated noise exactly as the filter assumes, for
//! checking the filter's consistency (NEES): no slip, no encoder
//! quantisation, no calibration error. Step 2-3 become: the odometry input
//! `u` is the commanded wheel travel (`V_i dt`), and the truth moves with the
//! filter's own discrete model, `X_true' = f(X_true, u, q)` ([`DiffDrive`])
//! with `q ~ N(0, diag(Q11, Q22))`, while the filter predicts with
//! `f(X, u, 0)`. Step 5 becomes: the noise-free readings of the IR pair are
//! cast on the true walls; when both are in the sensor's useful range and
//! see the wall the truth's IR pair points at (found by data association
//! on the true pose, so the association is always right), the observation is
//! `z = h(X_true) + V n` with `n ~ N(0, diag(R11, R22))` and `V` evaluated at
//! the noise-free readings, and the filter uses that same `V` (its
//! `V R V^T` is the exact covariance of `z`); the localiser's running
//! filter corrects with it behind its gate. Heading components are
//! wrapped. The record's `ir` field then holds the noise-free readings plus
//! `n`.
//!
//! All randomness comes from one `StdRng` seeded with the run's seed, so a
//! run is reproducible from `(config, seed)` (wall-clock timing aside).
//!
//! [`DiffDrive`]: locus_models::DiffDrive
//! [`Localiser`]: locus_models::Localiser
//! [`Localiser::ir`]: locus_models::Localiser::ir
//! [`Odometer`]: locus_models::Odometer
//! [`IrPairObservation`]: locus_models::IrPairObservation
//! [`FollowPath::square`]: locus_control::FollowPath::square
//! [`wheel_speeds`]: locus_control::wheel_speeds
//! [`Kinematics::DifferentialDrive`]: crate::robot::Kinematics::DifferentialDrive
//! [`Encoder`]: crate::sensors::Encoder
//! [`IrPairSensor`]: crate::sensors::IrPairSensor

mod config;
mod live;
mod plant;
mod record;
mod sim;

pub use crate::error::Error;
pub use config::{NoiseModel, SquareConfig};
pub use live::{LiveParams, SimStep, Teleop};
pub use locus_models::CorrectionDetail;
pub use record::StepRecord;
pub use sim::{SquareSim, run_square};
