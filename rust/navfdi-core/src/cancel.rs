//! Co-operative cancellation of long loops.
//!
//! Whole-run functions ([`crate::run::run_filter`], [`crate::arch::federated::run_federated`],
//! [`crate::montecarlo::run_chunk`]) take a [`Cancel`] and check it once per epoch (a
//! relaxed atomic load). A binding sets it when the user interrupts (Ctrl-C), and the loop then
//! returns [`crate::Error::Cancelled`] within one epoch instead of running to its end.

use crate::error::{Error, Result};
use std::sync::atomic::{AtomicBool, Ordering};

/// A cancellation flag shared between a long computation and whoever may stop it.
#[derive(Debug, Default)]
pub struct Cancel(AtomicBool);

/// A flag that is never set, for callers that do not cancel.
pub static NEVER: Cancel = Cancel(AtomicBool::new(false));

impl Cancel {
    /// A new, unset flag.
    pub const fn new() -> Self {
        Cancel(AtomicBool::new(false))
    }

    /// Ask the computation to stop.
    pub fn cancel(&self) {
        self.0.store(true, Ordering::Relaxed);
    }

    /// Whether [`Cancel::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.0.load(Ordering::Relaxed)
    }

    /// `Err(Error::Cancelled)` once cancelled.
    #[inline]
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(Error::Cancelled)
        } else {
            Ok(())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_after_cancel() {
        let c = Cancel::new();
        assert!(c.check().is_ok());
        c.cancel();
        assert_eq!(c.check(), Err(Error::Cancelled));
        assert!(NEVER.check().is_ok());
    }
}
