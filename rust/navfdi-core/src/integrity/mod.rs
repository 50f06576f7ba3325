//! Integrity: how large an undetected position error can be (protection levels).
//!
//! * [`araim`]: advanced RAIM by multiple-hypothesis solution separation (ARAIM ADD v3.0),
//!   one epoch from the geometry and the integrity support message;
//!   [`araim_fde`]: its fault detection and exclusion on residuals; [`araim_model`]: the
//!   ADD's error models from the lines of sight.
//! * [`filter_ss`]: protection levels of the tight Kalman filter by solution separation
//!   against a bank of sub-filters, and the exclusion they drive.
//! * [`snapshot`]: slope-based protection levels of the snapshot least-squares global test.

pub mod araim;
pub mod araim_fde;
pub mod araim_model;
pub mod filter_ss;
pub mod snapshot;
mod subsets;
