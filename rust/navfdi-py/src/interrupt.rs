//! Long computations that a user's Ctrl-C can stop.
//!
//! Python handles signals on the main thread only, between bytecodes or in
//! `PyErr_CheckSignals`. A long Rust loop with the GIL released would therefore see a Ctrl-C
//! only when it ends. [`run`] executes the computation on a worker thread while the calling
//! thread waits with the GIL released and, every [`POLL`], checks for signals; on an interrupt
//! it sets the computation's [`Cancel`] flag, waits for the worker to stop (within one epoch)
//! and raises the `KeyboardInterrupt`. A panic on the worker becomes a `RuntimeError`, never a
//! crash.

use crate::errors::to_py;
use navfdi_core::cancel::Cancel;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use std::sync::mpsc::{channel, RecvTimeoutError};
use std::time::Duration;

/// How often the waiting thread checks for signals.
pub const POLL: Duration = Duration::from_millis(20);

/// Run `f` with the GIL released, stoppable by Ctrl-C (see the module documentation).
pub fn run<T, F>(py: Python<'_>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce(&Cancel) -> navfdi_core::Result<T> + Send,
{
    let cancel = Cancel::new();
    let (tx, rx) = channel::<std::thread::Result<navfdi_core::Result<T>>>();
    std::thread::scope(|s| {
        let flag = &cancel;
        let spawned = std::thread::Builder::new()
            .name("navfdi-worker".into())
            .spawn_scoped(s, move || {
                let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(flag)));
                let _ = tx.send(r);
            });
        if let Err(e) = spawned {
            return Err(PyRuntimeError::new_err(format!(
                "cannot start a worker thread: {e}"
            )));
        }
        let mut rx = rx;
        loop {
            let (got, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
            rx = back;
            match got {
                Ok(Ok(result)) => return result.map_err(to_py),
                Ok(Err(_)) | Err(RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err(
                        "internal error in navfdi's Rust core (a worker thread panicked); please report it with the inputs that caused it",
                    ))
                }
                Err(RecvTimeoutError::Timeout) => {
                    if let Err(e) = py.check_signals() {
                        cancel.cancel();
                        // Wait (GIL released) for the worker to see the flag and stop.
                        let _ = py.detach(move || rx.recv());
                        return Err(e);
                    }
                }
            }
        }
    })
}
