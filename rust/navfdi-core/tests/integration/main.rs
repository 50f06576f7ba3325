//! The core's integration tests, one binary (each file a module): the federated filter against
//! a centralised one, Monte-Carlo determinism, property tests of the filter and detectors, and
//! the strapdown INS on simulated logs (NEES), loosely and tightly coupled.
//! One binary instead of three saves about 80 MB of target/ and two links per build.

mod federated;
mod montecarlo;
mod properties;
mod strapdown;
mod strapdown_tight;
