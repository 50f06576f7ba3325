//! The measurement stream of a `gnss_ranges` sensor: per epoch, the satellites in view with
//! their geometry, noise and tight-coupling rows (produced by the simulator, [`crate::sim`], or
//! later by a recorded-data source).
//!
//! Truth: `ρ_i = |r_s,i − r| + b + ε_i (+ fault)`, `ρ̇_i = u_iᵀ(v_s,i − v) + d + ε̇_i (+ fault)`,
//! with `u_i` the unit line of sight from the receiver to satellite i (ECEF), `b`, `d` the
//! receiver clock bias (m) and drift (m/s). Satellite positions are evaluated at the epoch
//! time in the Earth-fixed frame (no signal travel time or Sagnac term: the simulation and
//! the solvers use the same model).
//!
//! Tight-coupling measurement (error state `x` = INS − truth, plus clock bias and drift):
//! `z_i = ρ_i − |r_s,i − r_INS| = u_iᵀ δr + b + ε_i` and
//! `ż_i = ρ̇_i − u_iᵀ(v_s,i − v_INS) = u_iᵀ δv + d + ε̇_i`, so the rows of `H` are
//! `[u_n (R_M + h), u_e (R_N + h) cos L, u_u]` on `(δL, δλ, δh)` with 1 on the clock bias, and
//! `u_enu` on `δv` with 1 on the clock drift.

use nalgebra::{DMatrix, Vector3};

/// Index of the clock-bias state in a 17-state filter.
pub const CLOCK_BIAS: usize = crate::ins::N_STATES;
/// Index of the clock-drift state.
pub const CLOCK_DRIFT: usize = crate::ins::N_STATES + 1;

/// The satellites in view at one epoch, with everything the simulation and the filters need.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RangeEpoch {
    /// Satellite indices (into [`RangeStream::names`]) in view, in constellation order.
    pub sats: Vec<usize>,
    /// ECEF positions (m).
    pub sat_pos: Vec<Vector3<f64>>,
    /// ECEF velocities (m/s).
    pub sat_vel: Vec<Vector3<f64>>,
    /// Unit lines of sight receiver → satellite (ECEF).
    pub los: Vec<Vector3<f64>>,
    /// True geometric ranges (m).
    pub range: Vec<f64>,
    /// True geometric range rates (m/s).
    pub rate: Vec<f64>,
    /// Elevations (rad).
    pub elevation: Vec<f64>,
    /// Pseudorange noise σ (m).
    pub sigma: Vec<f64>,
    /// Rate noise σ (m/s).
    pub sigma_rate: Vec<f64>,
    /// Tight measurement matrix (2m × n): m pseudorange rows, then m rate rows.
    pub h: DMatrix<f64>,
    /// Fault added to each observation (2m: pseudoranges, then rates).
    pub fault: Vec<f64>,
    /// True receiver ECEF position (m).
    pub rx: Vector3<f64>,
}

impl RangeEpoch {
    /// Number of satellites in view.
    pub fn len(&self) -> usize {
        self.sats.len()
    }

    /// True when no satellite is in view.
    pub fn is_empty(&self) -> bool {
        self.sats.is_empty()
    }
}

/// Satellite geometry of a `gnss_ranges` sensor over a run (the satellites in view per epoch).
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct RangeStream {
    /// Index of the sensor in the scenario.
    pub sensor: usize,
    /// Satellite names, e.g. `G03`.
    pub names: Vec<String>,
    /// Per epoch.
    pub epochs: Vec<RangeEpoch>,
}

impl RangeStream {
    /// Fewest and most satellites in view over the run.
    pub fn in_view_range(&self) -> (usize, usize) {
        let it = self.epochs.iter().map(|e| e.len());
        (it.clone().min().unwrap_or(0), it.max().unwrap_or(0))
    }
}
