#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

pub mod decimal;
pub mod error;
pub mod librsf;
pub mod locus_csv;
pub mod mrclam;
pub mod noise;
pub mod sensor;
pub mod sighting;
mod text;
pub mod truth_cursor;
mod xz;

pub use error::{Error, FieldProblem, RecordProblem, Result};
pub use noise::NoiseRecords;
pub use sensor::SensorMount;
pub use sighting::{Landmark, Sighting};
pub use truth_cursor::TruthCursor;
