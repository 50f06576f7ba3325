//! Detector bindings, one file per family: the residual chi-square and the SPRTs
//! ([`chi2_sprt`]), AIME and two-stage AIME ([`aime`]), the state chi-square test
//! ([`state_chi2`]), and what they share ([`common`]: `Decision`, `DetectionRun`).

pub mod aime;
pub mod chi2_sprt;
pub mod common;
pub mod state_chi2;

pub use aime::{PyAime, PyTwoStageAime};
pub use chi2_sprt::{PyImprovedSprt, PyJointChi2Sprt, PyResidualChi2};
pub use common::{positive_dof, PyDecision, PyDetectionRun};
pub use state_chi2::{PyStateChi2, PyStateDecision};
