//! Scenario simulation: trajectory, sensors, faults, and the one-run executor.
//!
//! A scenario ([`spec::ScenarioSpec`], SI units) is prepared once ([`prepare::Prepared`]: the
//! truth trajectory and everything that does not depend on the random seed: `Φ_k`, `Q_k`,
//! measurement models), then any number of runs draw their noise from a generator seeded by
//! `(seed, run index)` ([`noise::simulate`]) and filter it ([`run::run_federated`]).

pub mod metrics;
pub mod montecarlo;
pub mod noise;
pub mod prepare;
pub mod run;
pub mod spec;
pub mod trajectory;
