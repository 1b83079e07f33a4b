//! Seeded 2-D simulator of Locus: a world of wall segments, robots with
//! ground-truth kinematics (differential drive, skid-steer, tricycle) with
//! configurable wheel slip and bumps, and noisy sensors: wheel encoders whose
//! counts go through the firmware's quadrature decoder (`locus-odometry`),
//! Sharp-type IR sensors through their nonlinear curve, and laser beams ray
//! cast on the map. All randomness comes from a caller's seeded `StdRng`, so a
//! run is reproducible from its seed.
//!
//! The scenarios of `locus run` (paper 001's square closed loop, wall45,
//! tricycle-slip, hover) and the guide build on it; so does the simulated
//! robot of the link (`locus-simlink`).
#![forbid(unsafe_code)]

pub mod beam_log;
pub mod closed_loop;
mod error;
pub mod family;
pub mod firmware_data;
pub mod guide;
pub mod hover;
mod noise;
pub mod robot;
pub mod scenario_file;
pub mod sensors;
pub mod tricycle_slip;
pub mod wall45;
pub mod world;

pub use closed_loop::{
    CorrectionDetail, LiveParams, SimStep, SquareConfig, SquareSim, StepRecord, Teleop, run_square,
};
pub use error::Error;
pub use robot::{
    DriveCommand, Kinematics, Pose, Robot, RobotError, Slip, SlipSchedule, TravelByWheel,
};
pub use sensors::{Encoder, IrPairSensor, IrReading, Laser, SensorError, SharpIr};
pub use world::{Hit, World};
