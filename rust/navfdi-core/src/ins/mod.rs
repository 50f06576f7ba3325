//! Strapdown INS error model (METHODS §5 context; paper 000's SINS).
//!
//! * [`earth`]: WGS-84 constants and radii of curvature.
//! * [`error_model`]: the 15-state psi-angle error model in the ENU navigation frame, its
//!   continuous-time `F` along a truth trajectory, and the discretised `Φ` and `ΓQΓᵀ`.

pub mod earth;
pub mod error_model;

pub use error_model::{ErrorModel, InsErrorParams, ACC, ATT, GYRO, N_STATES, POS, VEL};
