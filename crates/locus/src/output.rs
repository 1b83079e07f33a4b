//! The terminal output of the commands. Printing to standard output
//! without panicking: `println!` panics when the reader has gone
//! (`locus run | head`); [`print_out`] returns the error instead, and
//! `main` ends quietly on a broken pipe ([`is_broken_pipe`]). Progress bars
//! on standard error in one style ([`progress_bar`]).

use std::io::Write;

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

/// Whether `err` (or one of its causes) is a broken pipe: the reader of
/// standard output has gone, which is not a failure of the command.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
