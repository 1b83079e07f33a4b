#![doc = include_str!("../README.md")]
#![forbid(unsafe_code)]

pub mod aer1513;
pub mod beam_sensor;
pub mod carmen;
pub mod decimal;
pub mod error;
pub mod ir_pair;
pub mod librsf;
pub mod lines;
pub mod locus_csv;
pub mod mrclam;
pub mod noise;
pub mod relations;
pub mod scans;
pub mod se2;
pub mod sensor;
pub mod sighting;
mod text;
pub mod truth_cursor;
pub mod wall;
mod xz;

/// Longest line a log may hold, bytes (1 MiB): a record is at most a few
/// hundred bytes (a scan of a thousand beams a few tens of kilobytes); a
/// longer line is a damaged or hostile file, refused before it fills the
/// memory.
pub const MAX_LINE: usize = 1 << 20;

pub use beam_sensor::BeamSensor;
pub use error::{Error, FieldProblem, RecordProblem, Result};
pub use ir_pair::IrPairRecord;
pub use lines::Lines;
pub use noise::NoiseRecords;
pub use scans::{Scan, Scans};
pub use sensor::SensorMount;
pub use sighting::{Landmark, Sighting};
pub use truth_cursor::TruthCursor;
pub use wall::{MapPath, Wall};
