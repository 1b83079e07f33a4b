#![doc = include_str!("../README.md")]
#![no_std]
#![forbid(unsafe_code)]

pub mod cordic;
pub mod counter;
pub mod error;
pub mod quadrature;
pub mod redundant;
pub mod source;
pub mod speed;
pub mod wheel;

pub use cordic::{Cordic, Libm, SinCos};
pub use counter::{Counter, wrapping_diff};
pub use error::Error;
pub use quadrature::{Direction, QuadratureDecoder, Transition};
pub use redundant::{
    Increment, Integration, Motion, Odometry, Reading, Selection, Steering, Tricycle, select,
};
pub use source::{CountSource, EncoderSource};
pub use speed::{Estimate, Mode, SpeedConfig, SpeedEstimator};
pub use wheel::{Real, Wheel};
