//! A rosbag2 MCAP file read from start to end, record by record, with the
//! `mcap` crate's streaming reader: chunks decompressed (zstd, lz4) and
//! their CRCs checked, as are the data and summary sections' CRCs. Nothing
//! is read whole: memory is bounded by the largest record, itself bounded
//! by [`RECORD_LIMIT`].

use alloc::sync::Arc;
use std::collections::HashMap;
use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

use mcap::records::Record;
use mcap::sans_io::{LinearReadEvent, LinearReader, LinearReaderOptions};

use crate::error::{BagError, SchemaError};
use crate::msgdef::Definitions;
use crate::value::Value;

/// The longest record read (a chunk compressed or not, a message, a
/// schema), bytes: 1 GiB.
pub const RECORD_LIMIT: usize = 1 << 30;

/// One channel (a topic) of a bag.
#[derive(Debug, Clone)]
pub struct Channel {
    /// The channel's id in the file.
    pub id: u16,
    /// Its topic.
    pub topic: String,
    /// Its message type (the schema's name, e.g. `nav_msgs/msg/Odometry`);
    /// empty without a schema.
    pub type_name: String,
    /// Its messages' encoding (`cdr` for rosbag2).
    pub message_encoding: String,
    /// Its schema's encoding (`ros2msg` for rosbag2).
    pub schema_encoding: String,
    /// The schema parsed, or why Locus cannot decode this channel.
    pub definitions: Result<Arc<Definitions>, String>,
}

impl Channel {
    /// Decodes one message `data` of this channel.
    ///
    /// # Errors
    /// The channel cannot be decoded ([`Channel::definitions`]), or the
    /// message does not decode; the error names the file, the record and
    /// the field.
    pub fn decode(&self, file: &Path, message: &RawMessage<'_>) -> Result<Value, BagError> {
        let mut value = Value::Bool(false);
        self.decode_into(file, message, &mut value)?;
        Ok(value)
    }

    /// As [`Channel::decode`], into `out`, reusing what it holds from an
    /// earlier message of this channel ([`crate::cdr::decode_into`]).
    ///
    /// # Errors
    /// As [`Channel::decode`].
    pub fn decode_into(
        &self,
        file: &Path,
        message: &RawMessage<'_>,
        out: &mut Value,
    ) -> Result<(), BagError> {
        self.with_definitions(file, message, |defs, data| {
            crate::cdr::decode_into(defs, data, out)
        })
    }

    /// `read` of this channel's definitions and `message`'s CDR bytes,
    /// its error naming the file, the record, the topic and the type.
    ///
    /// # Errors
    /// The channel cannot be decoded, or `read` fails.
    pub(crate) fn with_definitions(
        &self,
        file: &Path,
        message: &RawMessage<'_>,
        read: impl FnOnce(&Definitions, &[u8]) -> Result<(), crate::CdrError>,
    ) -> Result<(), BagError> {
        let defs = self
            .definitions
            .as_ref()
            .map_err(|reason| BagError::Channel {
                file: file.to_path_buf(),
                topic: self.topic.clone(),
                reason: reason.clone(),
            })?;
        read(defs, message.data).map_err(|source| BagError::Message {
            file: file.to_path_buf(),
            record: message.record,
            topic: self.topic.clone(),
            type_name: self.type_name.clone(),
            log_time_ns: message.log_time_ns,
            source: Box::new(source),
        })
    }
}

/// One message record, not yet decoded.
#[derive(Debug, Clone, Copy)]
pub struct RawMessage<'a> {
    /// The record's ordinal in the file, 1-based.
    pub record: u64,
    /// When it was recorded, ns since the epoch.
    pub log_time_ns: u64,
    /// When it was published (as its publisher stamped it), ns.
    pub publish_time_ns: u64,
    /// Its CDR bytes.
    pub data: &'a [u8],
}

/// Why a channel cannot be decoded, if it cannot.
fn decodable(
    message_encoding: &str,
    schema: Option<&(String, String, Vec<u8>)>,
) -> Result<Arc<Definitions>, String> {
    if message_encoding != "cdr" {
        return Err(format!(
            "message encoding {message_encoding:?}: only \"cdr\" (rosbag2's) is decoded"
        ));
    }
    let Some((name, encoding, data)) = schema else {
        return Err("the channel has no schema".into());
    };
    if encoding != "ros2msg" {
        return Err(format!(
            "schema {name} is encoded as {encoding:?}: only \"ros2msg\" (rosbag2's) is read"
        ));
    }
    let text =
        core::str::from_utf8(data).map_err(|e| format!("schema {name} is not UTF-8: {e}"))?;
    Definitions::parse(name, text)
        .map(Arc::new)
        .map_err(|e: SchemaError| e.to_string())
}

/// Reads the bag at `path` from start to end, calling `on_message` with
/// each message record and its channel. A message record before its
/// channel's record is an error of the file.
///
/// # Errors
/// The file cannot be read; the container is broken (truncated, a bad
/// CRC, a record beyond [`RECORD_LIMIT`]); or `on_message` returns an
/// error, which stops the reading.
pub fn read(
    path: &Path,
    mut on_message: impl FnMut(&Channel, &RawMessage<'_>) -> Result<(), BagError>,
) -> Result<(), BagError> {
    let io = |source| BagError::Io {
        file: path.to_path_buf(),
        source,
    };
    let mut file = File::open(path).map_err(io)?;
    let options = LinearReaderOptions::default()
        .with_validate_chunk_crcs(true)
        .with_validate_data_section_crc(true)
        .with_validate_summary_section_crc(true)
        .with_record_length_limit(RECORD_LIMIT);
    let mut reader = LinearReader::new_with_options(options);
    let mut schemas: HashMap<u16, (String, String, Vec<u8>)> = HashMap::new();
    // By id: a message's channel is looked up once per message.
    let mut channels: Vec<Option<Channel>> = Vec::new();
    let mut record = 0u64;
    let container = |record: u64, reason: String| BagError::Container {
        file: PathBuf::from(path),
        record,
        reason,
    };
    while let Some(event) = reader.next_event() {
        let event = event.map_err(|e| container(record + 1, e.to_string()))?;
        match event {
            LinearReadEvent::ReadRequest(need) => {
                let buf = reader.insert(need);
                let n = file.read(buf).map_err(io)?;
                reader.notify_read(n);
            }
            LinearReadEvent::Record { data, opcode } => {
                record += 1;
                let parsed = mcap::parse_record(opcode, data)
                    .map_err(|e| container(record, e.to_string()))?;
                match parsed {
                    Record::Schema { header, data } => {
                        schemas
                            .insert(header.id, (header.name, header.encoding, data.into_owned()));
                    }
                    Record::Channel(c) => {
                        let schema = schemas.get(&c.schema_id);
                        let (type_name, schema_encoding) = schema
                            .map(|(n, e, _)| (n.clone(), e.clone()))
                            .unwrap_or_default();
                        let definitions = decodable(&c.message_encoding, schema);
                        let slot = usize::from(c.id);
                        if channels.len() <= slot {
                            channels.resize_with(slot + 1, || None);
                        }
                        channels[slot] = Some(Channel {
                            id: c.id,
                            topic: c.topic,
                            type_name,
                            message_encoding: c.message_encoding,
                            schema_encoding,
                            definitions,
                        });
                    }
                    Record::Message { header, data } => {
                        let Some(channel) = channels
                            .get(usize::from(header.channel_id))
                            .and_then(Option::as_ref)
                        else {
                            return Err(container(
                                record,
                                format!(
                                    "a message of channel {} before that channel's record",
                                    header.channel_id
                                ),
                            ));
                        };
                        on_message(
                            channel,
                            &RawMessage {
                                record,
                                log_time_ns: header.log_time,
                                publish_time_ns: header.publish_time,
                                data: &data,
                            },
                        )?;
                    }
                    _ => {}
                }
            }
        }
    }
    Ok(())
}

/// A topic of a bag, as `ros2 bag info` lists it.
#[derive(Debug, Clone, PartialEq)]
pub struct Topic {
    /// The topic.
    pub topic: String,
    /// Its message type.
    pub type_name: String,
    /// Its messages' encoding.
    pub message_encoding: String,
    /// Messages on it.
    pub count: u64,
    /// Log time of its first and last message, ns (0 without messages).
    pub first_ns: u64,
    /// See `first_ns`.
    pub last_ns: u64,
    /// Why Locus cannot decode it, if it cannot.
    pub undecodable: Option<String>,
    /// The names of its message type's fields (empty if undecodable).
    pub fields: Vec<String>,
}

/// The topics of the bag at `path`, in the order their channels appear
/// (counted by reading every record, so a bag without a summary section,
/// as a recording cut short leaves it, is listed too).
///
/// # Errors
/// As [`read`].
pub fn topics(path: &Path) -> Result<Vec<Topic>, BagError> {
    let mut order: Vec<u16> = Vec::new();
    let mut seen: HashMap<u16, Topic> = HashMap::new();
    read(path, |c, m| {
        let t = seen.entry(c.id).or_insert_with(|| {
            order.push(c.id);
            Topic {
                topic: c.topic.clone(),
                type_name: c.type_name.clone(),
                message_encoding: c.message_encoding.clone(),
                count: 0,
                first_ns: m.log_time_ns,
                last_ns: m.log_time_ns,
                undecodable: c.definitions.as_ref().err().cloned(),
                fields: c.definitions.as_ref().map_or_else(
                    |_| Vec::new(),
                    |d| d.root.fields.iter().map(|f| f.name.to_string()).collect(),
                ),
            }
        });
        t.count += 1;
        t.first_ns = t.first_ns.min(m.log_time_ns);
        t.last_ns = t.last_ns.max(m.log_time_ns);
        Ok(())
    })?;
    Ok(order
        .into_iter()
        .filter_map(|id| seen.remove(&id))
        .collect())
}
