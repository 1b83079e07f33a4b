//! The crate's errors. Each names where: the file, the record (its ordinal
//! in the file, and for a message its topic and log time), the schema and
//! its line, the field and its byte offset in the message.

use std::path::PathBuf;

/// A `ros2msg` schema that does not parse.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("schema {schema}, line {line}: {reason}")]
pub struct SchemaError {
    /// The schema's type name.
    pub schema: String,
    /// The line of the schema text, 1-based (0: the name itself).
    pub line: usize,
    /// What is wrong.
    pub reason: String,
}

/// A message whose CDR bytes do not decode with its schema.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("field {field} at byte {offset}: {reason}")]
pub struct CdrError {
    /// The field's path in the message (`twist.twist.linear.x`,
    /// `ranges[12]`; empty for the encapsulation header).
    pub field: String,
    /// The byte offset in the message (the encapsulation header included).
    pub offset: usize,
    /// What is wrong.
    pub reason: String,
}

/// What went wrong reading a bag.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    /// The file could not be read.
    #[error("{}: {source}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The MCAP container is broken: truncated, a bad CRC, a record that
    /// does not parse, a record longer than [`crate::RECORD_LIMIT`].
    #[error("{}: record {record}: {reason}", file.display())]
    Container {
        /// The file.
        file: PathBuf,
        /// The record's ordinal in the file, 1-based (the one being read).
        record: u64,
        /// The MCAP reader's message.
        reason: String,
    },
    /// A channel Locus cannot decode: not CDR, or its schema not `ros2msg`,
    /// or a schema that does not parse.
    #[error("{}: topic {topic}: {reason}", file.display())]
    Channel {
        /// The file.
        file: PathBuf,
        /// The channel's topic.
        topic: String,
        /// What is wrong.
        reason: String,
    },
    /// A message that does not decode with its schema.
    #[error("{}: record {record}: message on {topic} at {log_time_ns} ns ({type_name}): {source}", file.display())]
    Message {
        /// The file.
        file: PathBuf,
        /// The record's ordinal in the file, 1-based.
        record: u64,
        /// The channel's topic.
        topic: String,
        /// The message type.
        type_name: String,
        /// The message's log time, ns.
        log_time_ns: u64,
        /// Where in the message, and what.
        source: Box<CdrError>,
    },
    /// A mapped field that a message of its topic does not have, or has
    /// of another kind.
    #[error("{}: record {record}: {problem}", file.display())]
    Field {
        /// The bag.
        file: PathBuf,
        /// The record's ordinal in the file, 1-based.
        record: u64,
        /// The topic, its type, the field and what is wrong.
        problem: Box<FieldProblem>,
    },
    /// A mapping file that does not parse, or has another shape (an
    /// unknown key, a missing `velocity`): the file, the line and the
    /// parser's message ([`Mapping::from_toml`](crate::Mapping::from_toml)).
    #[error("{0}")]
    MappingFile(String),
    /// A mapping that does not fit the bag: a topic it does not have, a
    /// frame `/tf_static` does not reach.
    #[error("{file}: {key}: {reason}")]
    Mapping {
        /// The mapping file.
        file: String,
        /// The mapping's key.
        key: String,
        /// What is wrong.
        reason: String,
    },
}

/// A mapped field a message does not have, or has of another kind.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("topic {topic} ({type_name}), field {field}: {reason}")]
pub struct FieldProblem {
    /// The topic.
    pub topic: String,
    /// Its message type.
    pub type_name: String,
    /// The field's path (or the mapping's key).
    pub field: String,
    /// What is wrong.
    pub reason: String,
}
