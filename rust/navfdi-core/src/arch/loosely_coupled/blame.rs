//! Which of one receiver's two measurements its own inconsistency points at: the velocity,
//! when the velocity's innovation against the INS says what the receiver's displacement says
//! ([`VelocityBlame`]); the position otherwise (the hold machine, [`super::hold`]).

use super::receiver::Consistency;
use nalgebra::Vector3;

/// Per component east, north, up: whether the receiver's velocity, not its position, is what
/// its own consistency flags ([`VelocityBlame::step`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct VelocityBlame {
    /// Blamed at the last fix.
    held: [bool; 3],
    /// Consecutive fixes with the consistency off (`|e|` beyond 3 σ_e).
    off: [u32; 3],
    /// Consecutive fixes meeting the conditions of a first blame.
    candidate: [u32; 3],
}

impl VelocityBlame {
    /// One fix: the receiver's consistency `c`, the velocity's innovation against the INS
    /// `dv` (INS − fix, m/s) with variances `s_dv`, the position's normalised innovation
    /// squared `wp2`, the fix interval `dt` (s). The receiver's displacement disagrees with
    /// its velocity beyond 3 σ_e (`e = Δp − v̄Δt`) and the velocity's innovation says the same:
    /// of the sign of `e`, at least half of `e/Δt` (a velocity off by δv gives `e = −δv·Δt`
    /// and `dv = −δv`; a position step or ramp leaves the velocity's innovation near 0), and
    /// beyond 3σ, with the position within 4σ of the INS — at two consecutive fixes (a faulty
    /// velocity stays faulty; the velocity's own noise does not) among the first
    /// [`BLAME_FIXES`] + 1 of the inconsistency. Only then: once the filter follows a position
    /// ramp, the INS velocity takes the ramp's rate and the fix stays on the INS, which is a
    /// faulty velocity's picture too. Once blamed, a component stays blamed while `e` stays
    /// beyond 3 σ_e and the velocity's innovation keeps its sign beyond 1σ. Returns the blamed
    /// components. Nothing is blamed on a consistency against the INS (`ins_referenced`).
    pub fn step(
        &mut self,
        c: &Consistency,
        dv: &Vector3<f64>,
        s_dv: &Vector3<f64>,
        wp2: &Vector3<f64>,
        dt: f64,
    ) -> [bool; 3] {
        let mut out = [false; 3];
        if c.ins_referenced || !(dt > 0.0) {
            self.reset();
            return out;
        }
        for j in 0..3 {
            let e = c.e[j];
            let is_off = e.abs() > 3.0 * c.sigma[j];
            let same_way = e * dv[j] > 0.0;
            let first = is_off
                && self.off[j] < BLAME_FIXES + 1
                && same_way
                && dv[j].abs() >= 0.5 * e.abs() / dt
                && dv[j] * dv[j] > 9.0 * s_dv[j]
                && wp2[j] < 16.0;
            self.candidate[j] = if first { self.candidate[j] + 1 } else { 0 };
            out[j] = is_off
                && (self.held[j] && same_way && dv[j] * dv[j] > s_dv[j] || self.candidate[j] >= 2);
            self.off[j] = if is_off { self.off[j] + 1 } else { 0 };
        }
        self.held = out;
        out
    }

    /// Forget everything (a stale fix: the receiver's state is not measured).
    pub fn reset(&mut self) {
        *self = VelocityBlame::default();
    }
}

/// Fixes from the start of a receiver's inconsistency within which its velocity can first be
/// blamed ([`VelocityBlame`]).
pub const BLAME_FIXES: u32 = 3;
