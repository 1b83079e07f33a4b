//! Long calls run on a thread of their own while the caller's thread waits
//! detached from the interpreter (the GIL released), checking for Ctrl-C
//! every [`POLL`]: on an interrupt the work is asked to stop (the flag it
//! polls) and the call raises `KeyboardInterrupt` at once.

use alloc::sync::Arc;
use core::sync::atomic::{AtomicBool, Ordering};
use core::time::Duration;
use std::sync::mpsc;

use pyo3::prelude::*;

/// How often the waiting thread checks for a signal.
const POLL: Duration = Duration::from_millis(50);

/// Whether the caller asked the work to stop.
#[derive(Clone, Default)]
pub struct Stop(Arc<AtomicBool>);

impl Stop {
    /// Whether to stop now.
    pub fn asked(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }
}

/// Runs `work` on a new thread with the GIL released, and returns its
/// result. Ctrl-C (a signal the interpreter has recorded) sets the work's
/// [`Stop`] and raises `KeyboardInterrupt`; the work's thread ends at its
/// next check of the flag. A panic in `work` becomes a `RuntimeError`: it
/// never crosses into Python.
pub fn run<R: Send + 'static>(
    py: Python<'_>,
    work: impl FnOnce(&Stop) -> R + Send + 'static,
) -> PyResult<R> {
    let stop = Stop::default();
    let (tx, rx) = mpsc::channel();
    let flag = stop.clone();
    std::thread::Builder::new()
        .name("locus-work".into())
        .spawn(move || {
            let out = std::panic::catch_unwind(core::panic::AssertUnwindSafe(|| work(&flag)));
            let _ = tx.send(out);
        })
        .map_err(|e| {
            pyo3::exceptions::PyRuntimeError::new_err(format!("starting a thread: {e}"))
        })?;
    let mut rx = rx;
    loop {
        let (got, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match got {
            Ok(Ok(out)) => return Ok(out),
            Ok(Err(panic)) => {
                let why = panic
                    .downcast_ref::<&str>()
                    .map(|s| (*s).to_string())
                    .or_else(|| panic.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "unknown".to_string());
                return Err(pyo3::exceptions::PyRuntimeError::new_err(format!(
                    "internal error in Locus (a bug: please report it): {why}"
                )));
            }
            Err(mpsc::RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    stop.0.store(true, Ordering::Relaxed);
                    return Err(e);
                }
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                return Err(pyo3::exceptions::PyRuntimeError::new_err(
                    "internal error in Locus: the work's thread ended without a result",
                ));
            }
        }
    }
}
