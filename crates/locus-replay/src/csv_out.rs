//! A replay written to its CSV files as it runs ([`replay_to_csv`]):
//! `log.csv` (one row per step, [`Step::csv_header`]) and, when smoothing,
//! the smoothed trajectory ([`Step::smoothed_csv_header`]).
//!
//! The rows are formatted and written on a thread of their own, beside the
//! filter rather than after each step (formatting the numbers is about a
//! quarter of a replay's time); the steps reach it in order, so the bytes
//! are those of writing after each step. Each file is written under a
//! temporary name (`log.csv.partial`) and given its own name only once the
//! replay and the writing have both finished: a replay that is killed or
//! fails leaves no file a reader could take for a complete one.

use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{SyncSender, sync_channel};
use std::thread::{Scope, ScopedJoinHandle};

use crate::{Config, Log, Report, Step, replay};

/// Steps handed to the writer at a time.
const CHUNK: usize = 1024;
/// Chunks that may wait for the writer.
const QUEUE: usize = 4;

/// Errors of [`replay_to_csv`].
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// The replay failed (the files are left under their temporary names).
    #[error(transparent)]
    Replay(#[from] crate::Error),
    /// A file could not be created, written or renamed.
    #[error("{what} {}: {source}", path.display())]
    Io {
        /// `creating`, `writing` or `renaming`.
        what: &'static str,
        /// The file.
        path: PathBuf,
        /// The cause.
        source: io::Error,
    },
}

/// [`replay`] of `log` with `cfg`, each step written to `csv` and, with
/// `smoothed` (used with [`Config::smooth`]), its smoothed pose to that
/// file, and handed to `sink` (for a progress bar, pictures). Returns the
/// replay's report once both files are complete.
///
/// # Errors
/// The replay's error, or a file that cannot be created, written or
/// renamed, naming the file.
pub fn replay_to_csv(
    log: &Log,
    cfg: &Config,
    csv: &Path,
    smoothed: Option<&Path>,
    mut sink: impl FnMut(&Step),
) -> Result<Report, Error> {
    std::thread::scope(|scope| {
        let mut writer = Writer::start(scope, csv, smoothed)?;
        let report = replay(log, cfg, |step| {
            sink(step);
            writer.push(step);
        });
        let written = writer.finish(report.is_ok());
        let report = report?;
        written?;
        Ok(report)
    })
}

/// The temporary name of `path` while it is written: `path.partial`.
fn partial(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".partial");
    PathBuf::from(name)
}

fn io_error(what: &'static str, path: &Path) -> impl FnOnce(io::Error) -> Error {
    let path = path.to_path_buf();
    move |source| Error::Io { what, path, source }
}

/// `path` created, with `header` as its first line.
fn create(path: &Path, header: &str) -> Result<BufWriter<File>, Error> {
    let file = File::create(path).map_err(io_error("creating", path))?;
    let mut w = BufWriter::new(file);
    writeln!(w, "{header}").map_err(io_error("writing", path))?;
    Ok(w)
}

/// One output file: its writer and its temporary name.
struct Out {
    w: BufWriter<File>,
    path: PathBuf,
}

impl Out {
    /// Appends the row `fill` writes and a newline.
    fn row(&mut self, row: &mut String, fill: impl FnOnce(&mut String)) -> Result<(), Error> {
        row.clear();
        fill(row);
        row.push('\n');
        self.w
            .write_all(row.as_bytes())
            .map_err(io_error("writing", &self.path))
    }
}

/// The writing thread and the chunk being filled.
struct Writer<'scope> {
    chunk: Vec<Step>,
    tx: Option<SyncSender<Vec<Step>>>,
    handle: ScopedJoinHandle<'scope, Result<(), Error>>,
    /// Each file's temporary name and its own.
    names: Vec<(PathBuf, PathBuf)>,
}

impl<'scope> Writer<'scope> {
    /// Creates `csv` (and `smoothed`, if given) under their temporary
    /// names with their headers and starts the writer on `scope`.
    fn start(
        scope: &'scope Scope<'scope, '_>,
        csv: &Path,
        smoothed: Option<&Path>,
    ) -> Result<Self, Error> {
        let names: Vec<(PathBuf, PathBuf)> = core::iter::once(csv)
            .chain(smoothed)
            .map(|p| (partial(p), p.to_path_buf()))
            .collect();
        let mut log = Out {
            w: create(&names[0].0, Step::csv_header())?,
            path: names[0].0.clone(),
        };
        let mut smooth = match names.get(1) {
            Some((p, _)) => Some(Out {
                w: create(p, Step::smoothed_csv_header())?,
                path: p.clone(),
            }),
            None => None,
        };
        let (tx, rx) = sync_channel::<Vec<Step>>(QUEUE);
        let handle = scope.spawn(move || -> Result<(), Error> {
            let mut row = String::with_capacity(512);
            for chunk in rx {
                for step in &chunk {
                    log.row(&mut row, |r| step.write_csv_row(r))?;
                    if let Some(s) = smooth.as_mut() {
                        s.row(&mut row, |r| step.write_smoothed_csv_row(r))?;
                    }
                }
            }
            for mut out in core::iter::once(log).chain(smooth) {
                out.w.flush().map_err(io_error("writing", &out.path))?;
            }
            Ok(())
        });
        Ok(Self {
            chunk: Vec::with_capacity(CHUNK),
            tx: Some(tx),
            handle,
            names,
        })
    }

    /// Queues `step`. After a write error the rest is dropped;
    /// [`Writer::finish`] returns the error.
    fn push(&mut self, step: &Step) {
        self.chunk.push(*step);
        if self.chunk.len() == CHUNK {
            self.send();
        }
    }

    fn send(&mut self) {
        let full = core::mem::replace(&mut self.chunk, Vec::with_capacity(CHUNK));
        if let Some(tx) = &self.tx
            && tx.send(full).is_err()
        {
            // The writer stopped on an error: `finish` reports it.
            self.tx = None;
        }
    }

    /// Hands over what is left, waits for the writer, and returns how the
    /// writing went. With `complete` (the replay finished) and the writing
    /// done, gives each file its own name; otherwise leaves them under
    /// their temporary names.
    fn finish(mut self, complete: bool) -> Result<(), Error> {
        self.send();
        drop(self.tx.take());
        self.handle
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))?;
        if complete {
            for (from, to) in &self.names {
                std::fs::rename(from, to).map_err(io_error("renaming", from))?;
            }
        }
        Ok(())
    }
}
