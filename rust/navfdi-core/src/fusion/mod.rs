//! Fusion: the federated filter of papers 000 and 003 (METHODS §5) and the weighted fusion of
//! one quantity over several sensors with a fault matrix (METHODS §9).

pub mod federated;

pub use federated::{FederatedFilter, StepReport, SubFilterConfig, SubReport};
pub use weighted::{Estimate, Fused, WeightedFusion};
pub mod weighted;
