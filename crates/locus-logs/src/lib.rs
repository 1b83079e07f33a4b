#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

pub mod error;
pub mod locus_csv;
pub mod mrclam;
mod text;

pub use error::{Error, FieldProblem, RecordProblem, Result};
