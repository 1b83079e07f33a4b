//! `log.csv` (and with `--smooth`, `smoothed.csv`) written on a thread of
//! their own while the replay runs: formatting the numbers is about a
//! quarter of the command's time (perf, MRCLAM robot 3), and this way it
//! runs beside the filter instead of after each step. The bytes are the
//! same: the steps reach the writer in order.
//!
//! Each file is written under a temporary name (`log.csv.partial`) and
//! renamed to its own once the replay and the writing have both finished:
//! a replay that is killed or fails leaves no `log.csv` that a reader
//! could take for a complete one.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{SyncSender, sync_channel};
use std::thread::{Scope, ScopedJoinHandle};

use anyhow::{Context, Result};
use locus_replay::Step;

/// Steps handed to the writer at a time.
const CHUNK: usize = 1024;
/// Chunks that may wait for the writer.
const QUEUE: usize = 4;

/// The writing thread and the chunk being filled.
pub(super) struct CsvWriter<'scope> {
    chunk: Vec<Step>,
    tx: Option<SyncSender<Vec<Step>>>,
    handle: ScopedJoinHandle<'scope, Result<()>>,
    /// Each file's temporary name and its own.
    names: Vec<(PathBuf, PathBuf)>,
}

/// The temporary name of `path` while it is written: `path.partial`.
fn partial(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".partial");
    PathBuf::from(name)
}

/// `path` created, with `header` as its first line.
fn create(path: &Path, header: &str) -> Result<BufWriter<File>> {
    let file = File::create(path).with_context(|| format!("creating {}", path.display()))?;
    let mut w = BufWriter::new(file);
    writeln!(w, "{header}").with_context(|| format!("writing {}", path.display()))?;
    Ok(w)
}

/// Appends `step`'s row (as `fill` writes it) and a newline to `out`.
fn write_row(
    out: &mut BufWriter<File>,
    path: &Path,
    row: &mut String,
    fill: impl FnOnce(&mut String),
) -> Result<()> {
    row.clear();
    fill(row);
    row.push('\n');
    out.write_all(row.as_bytes())
        .with_context(|| format!("writing {}", path.display()))
}

impl<'scope> CsvWriter<'scope> {
    /// Creates `log` (and `smoothed`, if given) under their temporary
    /// names ([`partial`]) with their headers and starts the writer on
    /// `scope`.
    pub(super) fn start(
        scope: &'scope Scope<'scope, '_>,
        log: &Path,
        smoothed: Option<&Path>,
    ) -> Result<Self> {
        let names: Vec<(PathBuf, PathBuf)> = core::iter::once(log)
            .chain(smoothed)
            .map(|p| (partial(p), p.to_path_buf()))
            .collect();
        let mut csv = (create(&names[0].0, Step::csv_header())?, names[0].0.clone());
        let mut smoothed_csv: Option<(BufWriter<File>, PathBuf)> = names
            .get(1)
            .map(|(p, _)| {
                Ok::<_, anyhow::Error>((create(p, Step::smoothed_csv_header())?, p.clone()))
            })
            .transpose()?;
        let (tx, rx) = sync_channel::<Vec<Step>>(QUEUE);
        let handle = scope.spawn(move || -> Result<()> {
            let mut row = String::with_capacity(512);
            for chunk in rx {
                for step in &chunk {
                    write_row(&mut csv.0, &csv.1, &mut row, |r| step.write_csv_row(r))?;
                    if let Some((w, path)) = smoothed_csv.as_mut() {
                        write_row(w, path, &mut row, |r| step.write_smoothed_csv_row(r))?;
                    }
                }
            }
            for (w, path) in core::iter::once(csv).chain(smoothed_csv) {
                let mut w = w;
                w.flush()
                    .with_context(|| format!("writing {}", path.display()))?;
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
    /// [`CsvWriter::finish`] returns the error.
    pub(super) fn push(&mut self, step: &Step) {
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
    pub(super) fn finish(mut self, complete: bool) -> Result<()> {
        self.send();
        drop(self.tx.take());
        self.handle
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))?;
        if complete {
            for (from, to) in &self.names {
                std::fs::rename(from, to)
                    .with_context(|| format!("renaming {} to {}", from.display(), to.display()))?;
            }
        }
        Ok(())
    }
}
