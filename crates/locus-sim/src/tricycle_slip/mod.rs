//! The `tricycle-slip` scenario of seed 004 (spec section 5): a tricycle
//! robot (driven, steered front wheel; two passive rear wheels with
//! encoders) drives through wheel-slip bumps; its encoders go through the
//! firmware's quadrature decoder ([`Encoder`], 20-bit wrapping counters);
//! three estimators run side by side:
//!
//! * **rear-only odometry**: dead reckoning from the rear wheels (paper 004,
//!   eq. 1-3; [`Selection::Rear`], Euler as the paper);
//! * **slip-rejecting odometry**: the redundant odometry of paper 004
//!   (eq. 1-6 and the rule of section 3.2): the increment from the rear
//!   wheels and the one from the front wheel and steering angle, keeping the
//!   smaller in magnitude ([`SlipRejection`]; the paper's component-wise
//!   minimum by default);
//! * **the EKF**: prediction with [`TricycleRear`] from the rear counts
//!   (eq. 1-3 with count noise), corrected by a three-beam laser on the
//!   walls of a rectangular room ([`LaserRange`], exact range model, one
//!   scalar sequential update per beam, chi-square gate).
//!
//! # The path and the slip (the odometry issue's slip scenario)
//! The spec's \[assumed\] robot: rear wheels R = 0.05 m, front R = 0.06 m,
//! D = 0.40 m, L = 0.45 m, every encoder 500 lines (x4: 2000 counts per
//! revolution), steering 0.18 deg per count. The rear-axle midpoint drives
//! 10 m straight along +x, then a 90 deg left arc of radius 2 m, at 1 m/s
//! (rear axle) with the odometry at 100 Hz. Slip: the rear-left wheel
//! over-counts by 10 % over three 0.3 m bumps (at 2, 5 and 8 m of its
//! travel); the front wheel over-counts by 15 % over 1 m of its travel on
//! the arc (from 11.025 m of its travel, 1 m into the arc). Besides, every
//! wheel's measured travel carries a small random error `N(0, k^2 |d|)`
//! ([`TricycleSlipConfig::travel_noise`]). The truth moves on exact arcs
//! ([`Kinematics::Tricycle`]); the steering encoder reads the true angle
//! rounded to its count.
//!
//! All randomness (start, travel noise, laser) comes from one `StdRng`
//! seeded with the run's seed. Units: SI (m, rad, s).
//!
//! The files split by concern: `config` (the slip-rejection rule, the
//! scenario's configuration and its validation), `record` (the logged
//! [`TricycleSlipRecord`] and its CSV row) and `run` (the room, [`room`],
//! and [`run_tricycle_slip`]).
//!
//! [`Encoder`]: crate::sensors::Encoder
//! [`Selection::Rear`]: locus_odometry::redundant::Selection::Rear
//! [`TricycleRear`]: locus_models::TricycleRear
//! [`LaserRange`]: locus_models::laser_wall::LaserRange
//! [`Kinematics::Tricycle`]: crate::robot::Kinematics::Tricycle

mod config;
mod record;
mod run;

pub use config::{SlipRejection, TricycleSlipConfig};
pub use record::TricycleSlipRecord;
pub use run::{room, run_tricycle_slip};
