//! The terminal output of the commands and their output directories.
//!
//! Printing to standard output without panicking: `println!` panics when
//! the reader has gone (`locus run | head`); [`print_out`] returns the
//! error instead, and `main` ends quietly on a broken pipe
//! ([`is_broken_pipe`]); [`quiet_broken_pipe`] makes a `println!` that
//! meets a closed pipe, in any command, end the process quietly too.
//! Progress bars on standard error in one style ([`progress_bar`]).
//!
//! Output directories: [`writable_dir`] checks one before the work starts;
//! [`prepare_run_dir`] also clears the outputs of an earlier run there, so
//! that a run killed while rewriting a directory never leaves another
//! run's `metrics.json` and pictures beside its partial log.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};

/// Writes `text` to standard output and flushes it.
///
/// # Errors
/// The write error (e.g. a broken pipe), with context.
pub fn print_out(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .context("writing to standard output")
}

/// A progress bar of `len` steps: a bar of 40 characters, then `what` (an
/// `indicatif` template such as `{pos}/{len} runs, {elapsed} elapsed`).
///
/// # Errors
/// An invalid template.
pub fn progress_bar(len: u64, what: &str) -> Result<ProgressBar> {
    let style = ProgressStyle::with_template(&format!("{{bar:40}} {what}"))
        .context("progress bar template")?;
    Ok(ProgressBar::new(len).with_style(style))
}

/// A spinner for work of unknown length: `what` (an `indicatif`
/// template such as `estimating the noise, {elapsed} elapsed`), redrawn
/// ten times a second until it is finished.
///
/// # Errors
/// An invalid template.
pub fn spinner(what: &str) -> Result<ProgressBar> {
    let style =
        ProgressStyle::with_template(&format!("{{spinner}} {what}")).context("spinner template")?;
    let bar = ProgressBar::new_spinner().with_style(style);
    bar.enable_steady_tick(core::time::Duration::from_millis(100));
    Ok(bar)
}

/// Whether `err` (or one of its causes) is a broken pipe: the reader of
/// standard output has gone, which is not a failure of the command.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Installs a panic hook under which a panic of `println!` (or `print!`)
/// on a closed standard output (`locus hw | head -1`) ends the process
/// quietly with success, like [`is_broken_pipe`] errors in `main`; every
/// other panic is reported by the previous hook.
pub fn quiet_broken_pipe() {
    let previous = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let payload = info.payload();
        let message = payload
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| payload.downcast_ref::<&str>().copied())
            .unwrap_or("");
        // std's `print_to` panics with "failed printing to stdout: {io error}".
        let broken = std::io::Error::from(std::io::ErrorKind::BrokenPipe).to_string();
        let epipe = std::io::Error::from_raw_os_error(EPIPE).to_string();
        if message.starts_with("failed printing to stdout")
            && (message.ends_with(&broken) || message.ends_with(&epipe))
        {
            std::process::exit(0);
        }
        previous(info);
    }));
}

/// The operating system's "broken pipe" error number (the same on Linux,
/// macOS and the BSDs).
const EPIPE: i32 = 32;

/// Files a `locus run` or `locus replay` writes into its output directory:
/// cleared by [`prepare_run_dir`] before the new run writes any.
pub const RUN_OUTPUTS: [&str; 14] = [
    "log.csv",
    "smoothed.csv",
    "log.csv.partial",
    "smoothed.csv.partial",
    "runs.csv",
    "metrics.json",
    "map.png",
    "map.svg",
    "errors.png",
    "errors.svg",
    "covariance.png",
    "covariance.svg",
    "nis.png",
    "nis.svg",
];

/// Creates `dir` (and its parents) if missing and checks that a file can
/// be created in it, before any work: `--out` under a regular file or in a
/// read-only place is an error naming the directory.
///
/// # Errors
/// The directory cannot be created or written into.
pub fn writable_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    let probe = dir.join(format!(".locus-write-test-{}", std::process::id()));
    std::fs::File::create(&probe)
        .and_then(|_| std::fs::remove_file(&probe))
        .with_context(|| format!("{} is not writable", dir.display()))
}

/// Prepares the output directory `dir` of a run ([`writable_dir`]) and
/// removes the files of [`RUN_OUTPUTS`] an earlier run left there (no
/// other file is touched): whatever is in `dir` afterwards was written by
/// this run, and `metrics.json` appears only once it has finished.
///
/// # Errors
/// As [`writable_dir`]; a stale output that cannot be removed.
pub fn prepare_run_dir(dir: &Path) -> Result<()> {
    writable_dir(dir)?;
    for name in RUN_OUTPUTS {
        let path = dir.join(name);
        match std::fs::remove_file(&path) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
            Err(e) => {
                return Err(e).with_context(|| {
                    format!("removing {} left by an earlier run", path.display())
                });
            }
        }
    }
    Ok(())
}

/// The text of the file at `path`, at most `max` bytes (not read whole
/// first); a longer file is an error naming it and the limit.
///
/// # Errors
/// The file cannot be read, is not UTF-8 or is longer than `max` bytes.
pub fn read_bounded(path: &Path, max: u64) -> Result<String> {
    use std::io::Read;
    let mut text = String::new();
    std::fs::File::open(path)
        .and_then(|f| f.take(max + 1).read_to_string(&mut text))
        .with_context(|| format!("reading {}", path.display()))?;
    if text.len() as u64 > max {
        anyhow::bail!(
            "{}: larger than {max} bytes, the most read from such a file",
            path.display()
        );
    }
    Ok(text)
}
