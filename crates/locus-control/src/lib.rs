//! Paper 001's path controller (seed 001, "A. Control Module"; spec `MODELS.md`
//! section 3): the `GoXYTheta`, `FollowLine` and `FollowCircle` routines and
//! `FollowPath`, each turning a pose estimate `(x, y, theta)` into a body twist
//! [`Twist`] (the unicycle command `(V, W)`), and the wheel speeds
//! `V1 = V + b W / 2` (right), `V2 = V - b W / 2` (left). `no_std`, no
//! allocation.
//!
//! ```
//! use locus_control::{wheel_speeds, Config, Controller, FollowPath, Pose};
//!
//! let mut path = FollowPath::square(Config::default());
//! let twist = path.command(Pose::new(-0.85, -0.85, 0.0));
//! assert!(!twist.done && twist.v > 0.0);
//! let (v1_right, v2_left) = wheel_speeds(twist, 0.12);
//! assert!(((v1_right + v2_left) / 2.0 - twist.v).abs() < 1e-12);
//! ```
#![no_std]
#![forbid(unsafe_code)]

pub mod path;

pub use path::{
    Config, Controller, Direction, FollowPath, Point, Pose, Routine, SQUARE_HALF_SIDE, Segment,
    Twist, square, wheel_speeds, wrap_angle,
};
