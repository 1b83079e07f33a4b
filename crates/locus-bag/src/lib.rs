//! ROS 2 bags for Locus (issue 30): a rosbag2 recording in MCAP, the
//! default storage since ROS 2 Iron, read with no converter.
//!
//! * [`bag`]: the file read record by record ([`read`], [`topics`]), with
//!   the `mcap` crate's streaming reader; CRCs checked, records bounded.
//! * [`msgdef`]: the `ros2msg` schemas rosbag2 stores beside each channel,
//!   parsed, so message types Locus has never seen still decode.
//! * [`cdr`]: a message's CDR bytes decoded with its schema into a
//!   [`Value`] tree, read by field path ([`Value::get`]); bounded against
//!   hostile counts and nesting.
//!
//! * [`mapping`] and [`convert`]: which topics and fields are the
//!   velocities, the landmark sightings and the truth (a small TOML file),
//!   and the bag read as a Locus log by it ([`convert::to_locus`]), the
//!   sensor's mount from `/tf_static`; [`read_log`] reads the mapping
//!   file too, and resolves the map file it names.
//!
//! Every error names where: the file, the record, the topic, the schema's
//! line, the field and its byte offset ([`BagError`]).

extern crate alloc;

pub mod bag;
pub mod cdr;
pub mod convert;
pub mod error;
pub mod mapping;
pub mod msgdef;
pub mod open;
pub mod project;
pub mod propose;
pub mod value;

pub use bag::{Channel, RECORD_LIMIT, RawMessage, Topic, read, topics};
pub use error::{BagError, CdrError, FieldProblem, SchemaError};
pub use mapping::Mapping;
pub use msgdef::Definitions;
pub use open::read_log;
pub use value::{Message, Value};
