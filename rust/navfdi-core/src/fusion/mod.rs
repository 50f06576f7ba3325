//! Fusion of several filters: the federated filter of papers 000 and 003 (METHODS §5).

pub mod federated;

pub use federated::{FederatedFilter, StepReport, SubFilterConfig, SubReport};
