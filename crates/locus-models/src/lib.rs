#![doc = include_str!("../README.md")]
#![no_std]
#![forbid(unsafe_code)]

pub mod association;
pub mod calibrated_range;
pub mod calibrated_range_bearing;
pub mod calibrated_unicycle;
pub mod camera;
pub mod diff_drive;
pub mod ir_correction;
pub mod ir_wall;
pub mod laser_wall;
pub mod observer;
pub mod on_pose;
pub mod planar_beam;
pub mod plausible;
pub mod range_bearing;
pub mod settings;
pub mod skid_steer;
pub mod square001;
pub mod tricycle;
pub mod unicycle;

pub use association::{associate_ir_wall, axis_wall};
pub use camera::{CameraMark, CameraMarks, CameraMarks4, EulerRotation, Intrinsics, RandomWalk6};
pub use diff_drive::{DiffDrive, WheelTravel};
pub use ir_correction::{CorrectionDetail, IrCorrection};
pub use ir_wall::{AxisWall, IrPair, IrPairObservation, Side, WallAxis};
pub use laser_wall::{BeamLimits, LaserMount, LaserRange, LaserWallPaper, Segment, WallLine};
pub use observer::{ContinuousObserver, ObserverState};
pub use range_bearing::RangeBearing;
pub use skid_steer::{SkidSteer, TreadSpeeds};
pub use square001::{IrAssociation, IrOutcome, Localiser, LocaliserConfig, Odometer};
pub use tricycle::{
    CountNoise, FrontReading, RearCounts, TricycleFront, TricycleRear, counts_per_rev,
};
pub use unicycle::{Unicycle, Velocities};
