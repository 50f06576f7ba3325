//! Receiver clock model shared by the tight filters and the simulated `gnss_ranges` sensor.

use serde::{Deserialize, Serialize};

/// Receiver clock model: bias (m) and drift (m/s) as a two-state random process with
/// white frequency noise (`bias_psd`, m²/s) and random-walk frequency noise (`drift_psd`,
/// m²/s³); `bias` and `drift` are the initial standard deviations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClockSpec {
    /// Initial clock-bias σ (m).
    pub bias: f64,
    /// Initial clock-drift σ (m/s).
    pub drift: f64,
    /// Spectral density of the bias noise (m²/s).
    pub bias_psd: f64,
    /// Spectral density of the drift noise (m²/s³).
    pub drift_psd: f64,
}
