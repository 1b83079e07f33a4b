#![doc = include_str!("../README.md")]
#![no_std]
#![forbid(unsafe_code)]

pub mod diff_drive;
pub mod ir_wall;

pub use diff_drive::{DiffDrive, WheelTravel};
pub use ir_wall::{AxisWall, IrPair, IrPairObservation, Side, WallAxis};
