//! How far the GNSS updates have moved the INS: the evidence that tells the end of a fault the
//! filter followed from the start of a new one.
//!
//! Without the receiver's velocity a slow ramp is followed by the filter (with it, a ramp
//! across a stop, where ZUPT holds the velocity and the position corrections move the INS),
//! and where it ends the fixes jump back across the INS: the same picture, in the
//! innovations, as a step's onset.
//! What differs is the past: before a ramp's end the GNSS updates had pushed the INS the way
//! the fixes then jump back from; before a step's onset they only followed the receiver's
//! correlated error. Only the updates' direct position corrections are summed: what they move
//! through the velocity, integrated over a window, is dominated by the filter following the
//! receiver's Gauss-Markov error (tens of metres over 120 s on σ 2 m fixes, measured), and
//! says nothing.

use nalgebra::Vector3;
use std::collections::VecDeque;

/// Seconds of GNSS corrections looked back over (longer than the ramps the hold must release;
/// the Gauss-Markov error of a meter-level receiver decorrelates well within it).
pub const PULL_WINDOW: f64 = 120.0;
/// A pull must reach this many `√(2 S)` (the change of the innovation's own spread between two
/// independent draws). Fault-free, the largest pull over the window's starts has a median of
/// 1.3–1.6 and is below 2 at about two epochs in three (simulated σ 2 m Gauss-Markov fixes,
/// five seeds); the second condition, half the jump, is what keeps a step's onset held.
pub const PULL_Z: f64 = 2.0;

/// A pull must also reach this many σ of the corrections' own spread, `√Σ(P⁻ − P⁺)` of the
/// position over the window (each update's correction has the variance it takes off P): an INS
/// whose drift the updates keep correcting (a MEMS IMU) is pulled steadily one way without any
/// fault. Fault-free with a 100 deg/h IMU, the largest over the window's starts is 3.3 at the
/// 99th percentile (3.8 at most; simulated, three seeds); without it, 10 m and 20 m step onsets
/// on such a log were taken for ends (16 and 4 of 40 steps not held, against 10 and 0).
pub const PULL_VAR_Z: f64 = 4.0;

/// The GNSS updates' corrections of the INS antenna position (east, north, up, m) and the
/// position variance they took off (m²), summed, at each epoch with a GNSS update over the
/// last [`PULL_WINDOW`] s.
#[derive(Debug, Clone, Default)]
pub struct PullHistory {
    sum: Vector3<f64>,
    /// Σ of the updates' position-variance reductions (m², east, north, up).
    var: Vector3<f64>,
    past: VecDeque<(f64, Vector3<f64>, Vector3<f64>)>,
}

impl PullHistory {
    /// Add the correction `dp` (m, east, north, up) the GNSS updates of the epoch at `t` (s)
    /// made to the INS antenna position, and the position variance `dvar` (m²) they took off.
    pub fn add(&mut self, t: f64, dp: &Vector3<f64>, dvar: &Vector3<f64>) {
        if self.past.is_empty() {
            self.past.push_back((t, self.sum, self.var));
        }
        self.sum += dp;
        self.var += dvar;
        self.past.push_back((t, self.sum, self.var));
        while self
            .past
            .front()
            .is_some_and(|&(t0, _, _)| t - t0 > PULL_WINDOW)
        {
            self.past.pop_front();
        }
    }

    /// Whether the updates since some stored epoch moved component `j` of the INS the way an
    /// innovation `d` (INS − fix, m; variance `s`, m²) points, by at least half of `d`, by
    /// [`PULL_Z`] `√(2 s)` and by [`PULL_VAR_Z`] σ of the corrections' spread: the fix has come
    /// back to where the INS was before the updates pulled it away.
    pub fn back(&self, j: usize, d: f64, s: f64) -> bool {
        self.past.iter().any(|(_, c, v)| {
            let m = (self.sum[j] - c[j]) * d.signum();
            m >= 0.5 * d.abs()
                && m >= PULL_Z * (2.0 * s).sqrt()
                && m * m >= PULL_VAR_Z * PULL_VAR_Z * (self.var[j] - v[j]).max(0.0)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ramp_followed_and_jumped_back_from_is_a_pull_back() {
        let mut p = PullHistory::default();
        // 40 s of a 0.4 m/s north pull, then 10 s quiet.
        for k in 0..50 {
            let dn = if k < 40 { 0.4 } else { 0.0 };
            p.add(k as f64, &Vector3::new(0.0, dn, 0.0), &Vector3::zeros());
        }
        // The fix jumps 16 m south of the INS: d = INS − fix = +16 north.
        assert!(p.back(1, 16.0, 4.0));
        // Not the other way, nor on east, nor a jump the pull cannot explain half of.
        assert!(!p.back(1, -16.0, 4.0));
        assert!(!p.back(0, 16.0, 4.0));
        assert!(!p.back(1, 40.0, 4.0));
        // Nor a pull within the correlated error's reach (σ_S 6 m: 2·√2·6 = 17 m).
        assert!(!p.back(1, 16.0, 36.0));
    }

    #[test]
    fn a_pull_the_updates_variance_accounts_for_is_not_a_pull_back() {
        // An INS drifting north that every update corrects by 0.4 m, each taking 0.5 m² off
        // the position variance (σ of the sum over 40 updates: √20 = 4.5 m; a 16 m pull is
        // 3.6 of it, within what a MEMS INS is corrected by without a fault).
        let pulled = |dvar: f64| {
            let mut p = PullHistory::default();
            for k in 0..40 {
                p.add(
                    k as f64,
                    &Vector3::new(0.0, 0.4, 0.0),
                    &Vector3::new(0.0, dvar, 0.0),
                );
            }
            p
        };
        assert!(!pulled(0.5).back(1, 16.0, 4.0));
        // The same pull with the variance a settled filter takes off (0.05 m² per update).
        assert!(pulled(0.05).back(1, 16.0, 4.0));
    }

    #[test]
    fn the_window_forgets_old_pulls() {
        let mut p = PullHistory::default();
        for k in 0..40 {
            p.add(k as f64, &Vector3::new(0.4, 0.0, 0.0), &Vector3::zeros());
        }
        for k in 40..200 {
            p.add(k as f64, &Vector3::zeros(), &Vector3::zeros());
        }
        assert!(!p.back(0, 16.0, 4.0));
        assert!(p.past.len() <= PULL_WINDOW as usize + 2);
    }
}
