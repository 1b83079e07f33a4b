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
