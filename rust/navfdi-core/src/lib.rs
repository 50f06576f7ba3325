//! # navfdi-core
//!
//! Pure-Rust core of navfdi: Kalman filtering and fault-detection statistics for multi-sensor
//! integrated navigation. No Python here; the `navfdi-py` crate binds it.
//!
//! Modules, lowest layer first (a module imports only from the layers above it in this list;
//! `docs/ARCHITECTURE.md` draws the picture):
//!
//! * Ground floor
//!   * [`error`]: the one error enum, and number formatting for messages.
//!   * [`validate`]: shape, finiteness, symmetry and probability checks naming the argument.
//!   * [`linalg`]: matrix products (small and large), symmetrisation.
//!   * [`memory`]: refusing allocations that would not fit in memory, before they are made.
//!   * [`cancel`]: the cancellation flag checked by long loops (Ctrl-C).
//! * Estimation and statistics
//!   * [`kalman`]: predict / update (Cholesky, Joseph form), reduced-dimension update for
//!     missing components, fading factor, row-by-row update.
//!   * [`stats`]: thresholds, non-central chi-square, minimal detectable bias.
//!   * [`run`]: a whole filter run over a sequence in one call.
//! * Building blocks
//!   * [`detect`]: residual chi-square, improved SPRT, joint chi-square/SPRT, AIME and
//!     two-stage AIME, state chi-square.
//!   * [`ins`]: Earth model and the 15-state INS error model.
//!   * [`gnss`]: geodesy, constellations, RINEX, broadcast ephemerides, single-point
//!     positioning, snapshot and innovation FDE, prefilters, the `gnss_ranges` stream type.
//!   * [`fusion`]: federated master fusion, weighted fusion with a fault matrix.
//!   * [`integrity`]: protection levels (ARAIM, snapshot RAIM).
//! * Configuration
//!   * [`spec`]: the scenario schema (one file per part and per architecture) and its
//!     validation.
//! * Streams, records, metrics
//!   * [`stream`]: the measurement streams an architecture consumes (models, measurements,
//!     reference) and fault injection.
//!   * [`record`]: what one run records per epoch.
//!   * [`metrics`]: the one event-matching engine (alarms ↔ faults, satellite FDE counts).
//! * Sources and architectures (neither imports the other)
//!   * [`sim`]: the simulator, a source of streams (truth, models, noise, faults).
//!   * [`arch`]: one epoch loop per architecture (federated, centralized, tight,
//!     ultra-tight) and the dispatcher.
//! * Campaigns
//!   * [`montecarlo`]: Monte-Carlo runs (simulate, run an architecture, reduce to metrics)
//!     on rayon threads.
//!
//! Equations and the resolutions of the papers' ambiguities: `docs/METHODS.md`.

#![warn(missing_docs)]
// `!(x > 0.0)` is used on purpose throughout: unlike `x <= 0.0` it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod arch;
pub mod cancel;
pub mod detect;
pub mod error;
pub mod fusion;
pub mod gnss;
pub mod ins;
pub mod integrity;
pub mod kalman;
pub mod linalg;
pub mod logs;
pub mod memory;
pub mod metrics;
pub mod montecarlo;
pub mod record;
pub mod run;
pub mod sim;
pub mod spec;
pub mod stats;
pub mod stream;
pub mod validate;

pub use error::{Error, Result};
pub use kalman::{Innovation, KalmanFilter};
