//! One epoch loop per integration architecture. Each drives its filters, detectors and
//! fault-handling policy over a prepared scenario and a simulated run, and fills the same
//! [`crate::sim::run::RunRecord`] (one channel per tested sensor), so metrics, Monte-Carlo,
//! outputs and plots serve every architecture. The federated loop lives in
//! [`crate::sim::run::run_federated`].

pub mod centralized;
pub mod tight;
pub mod ultra_tight;
