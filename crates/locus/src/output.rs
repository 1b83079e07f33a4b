//! Printing to standard output without panicking: `println!` panics when
//! the reader has gone (`locus run | head`); [`print_out`] returns the error
//! instead, and `main` ends quietly on a broken pipe ([`is_broken_pipe`]).

use std::io::Write;

use anyhow::{Context, Result};

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

/// Whether `err` (or one of its causes) is a broken pipe: the reader of
/// standard output has gone, which is not a failure of the command.
pub fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
