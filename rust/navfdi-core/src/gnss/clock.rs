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

impl ClockSpec {
    /// The clock's exact discrete model over `dt` s: transition `[[1, dt], [0, 1]]` and process
    /// noise `[[q_b dt + q_d dt³/3, q_d dt²/2], [q_d dt²/2, q_d dt]]` of (bias, drift).
    pub fn discrete(&self, dt: f64) -> ([[f64; 2]; 2], [[f64; 2]; 2]) {
        let (sb, sd) = (self.bias_psd, self.drift_psd);
        (
            [[1.0, dt], [0.0, 1.0]],
            [
                [sb * dt + sd * dt.powi(3) / 3.0, sd * dt * dt / 2.0],
                [sd * dt * dt / 2.0, sd * dt],
            ],
        )
    }
}
