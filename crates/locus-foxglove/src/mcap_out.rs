//! A run written to an MCAP file that Foxglove opens with no set-up: one
//! channel per [`Topic`] that has messages, each with its JSON Schema,
//! chunks compressed with zstd. The file is written under a temporary name
//! (`OUT.mcap.partial`) and given its own once finished, so a killed run
//! leaves no file a reader could take for complete.

use alloc::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use crate::Error;
use crate::encode::Message;
use crate::topic::{MESSAGE_ENCODING, SCHEMA_ENCODING, Topic};

/// The error of the MCAP writer on the file `path`.
fn failed(path: &Path) -> impl FnOnce(mcap::McapError) -> Error + '_ {
    move |source| Error::Mcap {
        path: path.to_path_buf(),
        source,
    }
}

/// An MCAP file being written.
pub struct McapOut {
    writer: mcap::Writer<BufWriter<File>>,
    path: PathBuf,
    partial: PathBuf,
    /// Each topic's channel id, once it has one.
    channels: [Option<u16>; Topic::ALL.len()],
    /// Messages written per topic.
    counts: [u64; Topic::ALL.len()],
}

/// What [`McapOut::finish`] wrote.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Written {
    /// The file.
    pub path: PathBuf,
    /// Messages per topic, topics with none left out.
    pub counts: Vec<(Topic, u64)>,
}

impl McapOut {
    /// Starts `path` (written as `path.partial` until [`McapOut::finish`]).
    ///
    /// # Errors
    /// The file cannot be created.
    pub fn create(path: &Path) -> Result<Self, Error> {
        let mut name = path.as_os_str().to_owned();
        name.push(".partial");
        let partial = PathBuf::from(name);
        let file = File::create(&partial).map_err(|source| Error::Io {
            what: "creating",
            path: partial.clone(),
            source,
        })?;
        let writer = mcap::WriteOptions::new()
            .library(concat!("locus ", env!("CARGO_PKG_VERSION")))
            .create(BufWriter::new(file))
            .map_err(failed(&partial))?;
        Ok(Self {
            writer,
            path: path.to_path_buf(),
            partial,
            channels: [None; Topic::ALL.len()],
            counts: [0; Topic::ALL.len()],
        })
    }

    fn channel(&mut self, topic: Topic) -> Result<u16, Error> {
        if let Some(id) = self.channels[topic.index()] {
            return Ok(id);
        }
        let schema = topic.schema();
        let schema_id = self
            .writer
            .add_schema(schema.name, SCHEMA_ENCODING, schema.data.as_bytes())
            .map_err(failed(&self.partial))?;
        let id = self
            .writer
            .add_channel(schema_id, topic.name(), MESSAGE_ENCODING, &BTreeMap::new())
            .map_err(failed(&self.partial))?;
        self.channels[topic.index()] = Some(id);
        Ok(id)
    }

    /// Writes `m` on its topic's channel (created with its schema on the
    /// first message).
    ///
    /// # Errors
    /// The file cannot be written.
    pub fn write(&mut self, m: &Message) -> Result<(), Error> {
        let channel_id = self.channel(m.topic)?;
        let count = &mut self.counts[m.topic.index()];
        let header = mcap::records::MessageHeader {
            channel_id,
            // MCAP's sequence is 32-bit; it wraps on longer runs.
            #[allow(clippy::cast_possible_truncation)]
            sequence: *count as u32,
            log_time: m.time,
            publish_time: m.time,
        };
        *count += 1;
        self.writer
            .write_to_known_channel(&header, &m.payload)
            .map_err(failed(&self.partial))
    }

    /// Writes each of `messages`.
    ///
    /// # Errors
    /// The file cannot be written.
    pub fn write_all(&mut self, messages: &[Message]) -> Result<(), Error> {
        messages.iter().try_for_each(|m| self.write(m))
    }

    /// Writes the summary section and gives the file its own name.
    ///
    /// # Errors
    /// The file cannot be finished or renamed.
    pub fn finish(mut self) -> Result<Written, Error> {
        self.writer.finish().map_err(failed(&self.partial))?;
        drop(self.writer);
        std::fs::rename(&self.partial, &self.path).map_err(|source| Error::Io {
            what: "renaming",
            path: self.partial.clone(),
            source,
        })?;
        let counts = Topic::ALL
            .iter()
            .filter(|t| self.counts[t.index()] > 0)
            .map(|&t| (t, self.counts[t.index()]))
            .collect();
        Ok(Written {
            path: self.path,
            counts,
        })
    }
}
