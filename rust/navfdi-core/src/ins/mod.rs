//! Strapdown INS error model (METHODS §5 context; paper 000's SINS).
//!
//! * [`clip`]: IMU samples at the sensor's full scale (clipped).
//! * [`earth`]: WGS-84 constants and radii of curvature.
//! * [`error_model`]: the 15-state psi-angle error model in the ENU navigation frame, its
//!   continuous-time `F` along a truth trajectory, and the discretised `Φ` and `ΓQΓᵀ`.
//! * [`strapdown`]: mechanisation of recorded IMU samples (attitude, velocity, position).
//! * [`error_filter`]: the closed-loop 15-state error-state filter of that mechanisation.
//! * [`range_states`]: per-satellite Gauss-Markov range-error states beside the tight
//!   filter's error state.

pub mod clip;
pub mod earth;
pub mod error_filter;
pub mod error_model;
pub mod range_states;
pub mod strapdown;

pub use error_model::{ErrorModel, InsErrorParams, ACC, ATT, GYRO, N_STATES, POS, VEL};
