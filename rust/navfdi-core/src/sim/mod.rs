//! The simulator: one source of measurement streams ([`crate::stream`]).
//!
//! A scenario ([`crate::spec::ScenarioSpec`], SI units) is prepared once ([`prepare::Prepared`]:
//! the truth trajectory ([`trajectory`]), the satellites in view along it ([`ranges`]) and the
//! streams' models, which do not depend on the random seed); then any number of runs draw
//! their noise from a generator seeded by `(seed, run index)` ([`noise::simulate`]), giving
//! each run's measurements and its reference (the true error state). The architectures
//! ([`crate::arch`]) consume the result through [`noise::Simulated::streams`] and never import
//! this module. [`logs`] simulates recorded-style logs (IMU samples, a GNSS solution) along a
//! trajectory for the strapdown architecture's consistency check, [`range_logs`] IMU samples
//! and raw satellite observables for the strapdown tight filter's.

pub mod logs;
pub mod noise;
pub mod prepare;
pub mod range_logs;
pub mod ranges;
pub mod trajectory;
