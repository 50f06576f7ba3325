//! # navfdi-core
//!
//! Pure-Rust core of navfdi: Kalman filtering and fault-detection statistics for multi-sensor
//! integrated navigation. No Python here; the `navfdi-py` crate binds it.
//!
//! * [`kalman`]: predict / update (Cholesky, Joseph form), reduced-dimension update for
//!   missing components, fading factor.
//! * [`detect`]: residual chi-square, improved SPRT, joint chi-square/SPRT detector.
//! * [`stats`]: thresholds, non-central chi-square, minimal detectable bias.
//! * [`run`]: a whole filter run over a sequence in one call.
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
pub mod kalman;
pub mod linalg;
pub mod memory;
pub mod run;
pub mod stats;
pub mod validate;

pub use error::{Error, Result};
pub use kalman::{Innovation, KalmanFilter};
pub mod sim;
