//! GNSS position faults held out from their first epoch to their last: the INS prediction is
//! the reference a fix is tested against, and after an exclusion it stays the reference.
//!
//! Per position component (east, north, up) of one GNSS position channel:
//!
//! * **Normal**: used as measured when the channel's deciding test passes.
//! * On an alarm the components the w-test isolates are classified by the **jump** of their
//!   innovation since the previous used fix: `Δ = d_k − d_{k−1}` against `S_k + R_{k−1}` (the
//!   INS is continuous; a receiver's fault is not). A significant jump is a **step**: its size
//!   `b = d_k` (the INS was right a moment ago) is held, and while `d − b` agrees with the INS
//!   the fix is used as a relative fix (`d − b`, variance of `b` added: accommodation), so the
//!   solution stays aided through the fault. Without a jump (a ramp growing into the test, or
//!   INS drift) it is a **drift**: excluded.
//! * A held component is **re-admitted** only when its raw fix agrees with the prediction for
//!   [`AGREE`] consecutive fixes: for a step when the offset is gone (the fault ended); for a
//!   drift when the fix and the INS meet again — the INS stays anchored by the GNSS velocity
//!   and the vehicle constraints meanwhile, so its covariance does not grow toward a fault
//!   (a ramp on the position stays out until it ends), while an INS that was itself off (a
//!   drift at the start, before the heading has settled) is re-admitted once corrected.
//! * A step whose offset stops explaining the fix (the fault changed) is re-estimated.
//!
//! **Stale fixes**: a fix identical to the previous one (to 1 mm) while the INS moved more than
//! [`STALE_MOTION`](super::receiver::STALE_MOTION) m is the receiver repeating its last fix; position and velocity of the
//! epoch are left out.

use super::receiver::repeated;
pub use super::receiver::{
    Consistency, ReceiverConsistency, HISTORY, MOVING, RECEIVER_JUMP, RETURN_Z,
};
use nalgebra::Vector3;

// Why a GNSS measurement (or some of its components) was left out at an epoch: indices into
// `crate::record::EXCLUSION_REASONS`.
/// Left out by its deciding test (a gross innovation, or a channel whose faulty component the
/// w-test could not name).
pub const TEST: u8 = 1;
/// A held step (accommodated or excluded).
pub const STEP: u8 = 2;
/// A stale fix (the receiver's last fix repeated while the INS moved).
pub const STALE: u8 = 3;
/// A ramp flagged by the sequential test on the innovations, held.
pub const RAMP: u8 = 4;
/// A velocity component the receiver's own displacement contradicts, as the INS does
/// ([`super::blame::VelocityBlame`]).
pub const RECEIVER: u8 = 5;

/// Consecutive agreeing fixes before a held component is used as measured again.
pub const AGREE: u32 = 2;
/// Consecutive strictly agreeing fixes that re-admit a held step whose end the receiver's
/// consistency did not show.
pub const AGREE_LONG: u32 = 10;
/// A fix agrees with the prediction when its normalised innovation is within this (the
/// two-sided 1 % critical value: |w| ≤ 2.58).
pub const AGREE_W2: f64 = 6.634_896_6;

/// Fixes a ramp flagged by the sequential test is held before the fix must have left the
/// INS prediction (|w| > 2.58) to confirm it.
pub const PROBATION: u32 = 5;

/// The state of one position component.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Comp {
    /// Used as measured.
    Normal,
    /// The receiver has returned to where its velocity says it is (the end of a fault the
    /// INS followed, unseen or partly): its fixes are used as measured, whatever the test
    /// says, while it stays consistent, until one agrees with the INS or [`AGREE_LONG`] fixes
    /// have corrected it — a single fix does not pull an INS that is metres off.
    Return {
        /// Fixes used since the return.
        fixes: u32,
    },
    /// A held step of size `b` (innovation units: INS − fix, m) with variance `var`; `back`:
    /// the fix has jumped back since (the fault's end).
    Step {
        /// Held offset (m).
        b: f64,
        /// Its variance (m²).
        var: f64,
        /// The fix jumped back by at least half the offset since.
        back: bool,
        /// Consecutive fixes whose raw innovation agreed.
        agree: u32,
        /// Consecutive fixes since the jump back at which the receiver was consistent with its
        /// velocity (the fault is over even if the INS, having followed part of it, still
        /// disagrees).
        quiet: u32,
        /// The held offset before the receiver's last jump away from zero (m), while that
        /// jump stands: a jump back to it (a multipath burst on a held step ending) returns to
        /// the step, not to the fault's end.
        base: Option<f64>,
        /// The offset has followed the receiver's own inconsistency since the hold began (a
        /// ramp taken for a step): the INS may have followed more of the fault than it.
        moved: bool,
    },
    /// A held ramp since `since` (s): its size `b` (innovation units, m) followed by the
    /// receiver's own displacement against its velocity, with variance `var` (m²).
    Drift {
        /// Start of the hold (s).
        since: f64,
        /// The ramp's present size (INS − fix units, m).
        b: f64,
        /// Its variance (m²).
        var: f64,
        /// Its variance at the start of the hold (m²): what the receiver's drift over the hold
        /// adds to it is bounded by the drift's structure function.
        var0: f64,
        /// The fix left the INS prediction during the hold (else, after [`PROBATION`]
        /// fixes, the sequential test's alarm was a false one).
        confirmed: bool,
        /// Fixes since the hold began.
        fixes: u32,
        /// Consecutive fixes whose raw innovation agreed.
        agree: u32,
        /// The receiver's ramp size was significant at some fix of the hold.
        seen: bool,
        /// Consecutive fixes, after `seen`, at which it was within its noise again.
        quiet: u32,
        /// Time (s) and size (m) the ramp's line is measured from: the start of the hold, or
        /// the last fix that left the line.
        start: (f64, f64),
        /// Against the INS's displacement (positions only): the rate (m/s) of the ramp's line
        /// through `start`, fixed after [`AGREE_LONG`] fixes, which the size follows from then
        /// on.
        rate: Option<f64>,
    },
}

/// What to do with one component this epoch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Use {
    /// Use as measured.
    Raw,
    /// Use with the held offset removed (innovation − `b`, variance + `var`).
    Relative(f64, f64),
    /// Leave out, for this reason.
    Out(u8),
}

/// Hold state of one GNSS position channel.
#[derive(Debug, Clone)]
pub struct PositionHold {
    /// Per component east, north, up.
    pub comps: [Comp; 3],
    /// The previous fix's raw innovation and its innovation variances (diagonal of S): the
    /// reference of the next fix's jump.
    prev: Option<(Vector3<f64>, Vector3<f64>)>,
    /// The previous fix (east, north, up, m) and the INS position then (same frame).
    last_fix: Option<(Vector3<f64>, Vector3<f64>)>,
    /// Per component, when a held step was taken as over by a jump back (s) and its offset
    /// (m): a jump back to it within [`RESUME`] s resumes the fault (a burst against it ended).
    ended: [Option<(f64, f64)>; 3],
    /// Per component, the start time (s), sum of `d` (m; its sign the side) and count of the
    /// run of consecutive fixes off the INS prediction on one side (begun beyond |w| 2,
    /// carried on beyond |w| 1) while nothing was held, up to the previous fix; None
    /// otherwise.
    lag: [Option<(f64, f64, u32)>; 3],
    /// Set by the caller before each fix on positions alone: the copies of the filter carried
    /// without GNSS since before the hold's onset are all nearer the INS than the fix
    /// ([`super::shadow::Shadows::side`]) — the INS followed none of the held fault.
    pub copies_with_ins: bool,
}

/// Seconds of fixes off the INS prediction (|w| > 2, then > 1) on one side that make a jump back
/// across the INS the end of a fault the filter followed, without the receiver's own
/// drift to show it (its windows restart at every stop).
pub const LAG_RUN: f64 = 5.0;
/// The largest innovation (as a multiple of the lag before it) at which a jump back across a
/// lagging INS ([`LAG_RUN`]) is the end of a fault it followed.
pub const LAG_RATIO: f64 = 5.0;

/// A receiver's move (σ_e of its consistency) a held step's offset follows without the INS
/// confirming it: beyond any noise of a consistent receiver, as a ramp taken for a step on RTK
/// fixes is (a 0.5 m/s ramp at σ_e 4 cm: 12σ_e per fix).
pub const MOVE_ALONE: f64 = 5.0;

/// How long (s) after a held step was taken as over a jump back to its offset resumes it.
pub const RESUME: f64 = 60.0;

impl Default for PositionHold {
    fn default() -> Self {
        PositionHold {
            comps: [Comp::Normal; 3],
            prev: None,
            last_fix: None,
            ended: [None; 3],
            copies_with_ins: false,
            lag: [None; 3],
        }
    }
}

impl PositionHold {
    /// Whether `fix` (east, north, up, m) repeats the previous fix while the INS (`ins`, same
    /// frame) moved more than [`STALE_MOTION`](super::receiver::STALE_MOTION) since then; remembers both.
    pub fn stale(&mut self, fix: &Vector3<f64>, ins: &Vector3<f64>) -> bool {
        let out = self
            .last_fix
            .is_some_and(|(f, i)| repeated(fix, &f, (ins - i).norm()));
        if !out {
            self.last_fix = Some((*fix, *ins));
        }
        out
    }

    /// Decide the components of a fix with raw innovation `d` (INS − fix per component, m)
    /// and innovation variances `s` (diagonal of S) at time `t`: `alarm` the channel's
    /// deciding test on the raw fix, `isolated` the components the w-test names when it
    /// alarms (all, when it cannot say), `thr1` the 1-dof critical value of the deciding test,
    /// `ramp` the components the sequential test flags, `converged`: the filter has settled
    /// (before, only a `gross` innovation starts a hold), `accommodate`: a step is used as a
    /// relative fix, `pull`: how far the GNSS updates moved the INS lately (a jump back across
    /// such a pull ends a followed fault).
    ///
    /// An alarm whose innovation appeared since the previous fix (a jump of at least half the
    /// innovation and 2σ of the jump) is a step, held; one that grew into the test (no jump:
    /// a ramp, or the INS's own error) leaves that fix out and holds nothing — ramps are the
    /// sequential test's (`ramp`, when the fix is also off the INS by more than |w| 2.58),
    /// held until the fix meets the INS again. A held step is
    /// re-admitted after [`AGREE`] fixes that agree strictly ([`AGREE_W2`]) — or, once the fix
    /// has jumped back, within the deciding test.
    #[allow(clippy::too_many_arguments)]
    pub fn decide(
        &mut self,
        t: f64,
        d: &Vector3<f64>,
        s: &Vector3<f64>,
        alarm: bool,
        isolated: &[usize],
        thr1: f64,
        recv: Option<&Consistency>,
        ins_jumps: bool,
        converged: bool,
        gross: bool,
        accommodate: bool,
        pull: Option<&super::pull::PullHistory>,
    ) -> [Use; 3] {
        let mut out = [Use::Raw; 3];
        // The jump of this fix, in innovation units (INS − fix: a step of +x in the fix is
        // −x), and its variance: from the receiver's own consistency when known, else from
        // the innovation's change since the previous fix.
        let delta = |j: usize| -> Option<(f64, f64)> {
            match recv {
                Some(c) => Some((-c.e[j], c.sigma[j] * c.sigma[j])),
                None if ins_jumps => self.prev.map(|(pd, ps)| (d[j] - pd[j], s[j] + ps[j])),
                None => None,
            }
        };
        // A jump: most of the innovation appeared at this fix, beyond its noise (3σ of the
        // receiver's consistency, 2σ of the innovation's change).
        let k2 = if recv.is_some() { 9.0 } else { 4.0 };
        let jumped = |j: usize| {
            delta(j).is_some_and(|(dd, v)| dd * dd > 0.25 * d[j] * d[j] && dd * dd / v > k2)
        };
        let w2 = |j: usize| d[j] * d[j] / s[j];
        // A jump of the receiver that cancels its earlier inconsistency (brings the sum of `e`
        // over the window closer to zero by half the jump at least) returns it to where its
        // velocity says it is: the end of a fault the filter followed, not the start of one.
        // The jump must stand out of the window's own noise (1σ of a sum of [`HISTORY`] `e`):
        // on RTK fixes a ramp's first increment beside a window of latency residuals is not
        // a return. (A quarter of the jump instead of half lets more meter-level ramp ends
        // through, but takes 10 m steps on σ 2 m fixes for returns when the Gauss-Markov error
        // has drifted the other way over the window.)
        // Or a slow drift the filter partly followed ended: before the jump the receiver had
        // drifted beyond [`RETURN_Z`] σ of a window test's sums, the fix was off the INS
        // prediction that way (|w| > 2: the INS lagging behind it), and the jump goes back
        // across the INS — a fault's onset has the INS on the fix a moment before.
        let returned = |j: usize| {
            recv.is_some_and(|c| {
                let (w, e) = (c.window[j], c.e[j]);
                // Against the INS's displacement the window's sum holds the INS's own
                // integrated velocity error: not a receiver position to return to.
                let window_back = !c.ins_referenced
                    && e.abs() > c.sigma[j] * (HISTORY as f64).sqrt()
                    && (w + e).abs() <= w.abs() - 0.5 * e.abs();

                // The previous fix's innovation, fix − INS: the side it drifted to.
                // The second witness: the receiver's drift, or (its windows restart at a
                // stop) the fixes off the INS that way for [`LAG_RUN`] s, with the jump landing
                // within [`LAG_RATIO`] times that lag on the other side (an INS that followed
                // at most five sixths of the fault; a 30 m multipath burst starting against an
                // INS 4 m behind the fixes is no return).
                let lagging = self.prev.is_some_and(|(pd, ps)| {
                    let off = -pd[j];
                    // The lag (fix − INS): the run's last, or its mean where larger (the last
                    // fix may have dipped below |w| 2).
                    let run = self.lag[j].is_some_and(|(t0, sum, n)| {
                        let mean = -sum / f64::from(n);
                        let lag = if mean.abs() > off.abs() { mean } else { off };
                        t - t0 >= LAG_RUN
                            && lag * lag > 4.0 * ps[j]
                            && d[j].abs() <= LAG_RATIO * lag.abs()
                    });
                    off * e < 0.0
                        && (run
                            || off * off > 4.0 * ps[j]
                                && c.excursion[j]
                                    .iter()
                                    .any(|&(x, z)| z > RETURN_Z && x * off > 0.0))
                });
                e.abs() > RECEIVER_JUMP * c.sigma[j] && (window_back || lagging)
            })
        };
        // The fix has left the INS prediction the way the receiver's inconsistency `b` says
        // (|w| > 2.58, same sign, a quarter of its size at least): the second witness of a
        // ramp.
        let leaves =
            |j: usize, b: f64| w2(j) > AGREE_W2 && d[j] * b > 0.0 && d[j].abs() > 0.25 * b.abs();
        // The fix jumped back across an INS the GNSS updates had pulled the other way
        // ([`super::pull::PullHistory::back`]): the end of a fault the filter followed.
        let pulled = |j: usize| pull.is_some_and(|p| p.back(j, d[j], s[j]));
        // Held components whose fix is back on the INS (within the deciding test).
        let landed: [bool; 3] =
            std::array::from_fn(|k| matches!(self.comps[k], Comp::Step { .. }) && w2(k) <= thr1);
        for j in 0..3 {
            let jump = jumped(j);
            self.comps[j] = match self.comps[j] {
                Comp::Normal => {
                    // A jump of the receiver's own position against its velocity beyond
                    // [`RECEIVER_JUMP`] σ, confirmed by the INS (the fix off the prediction by
                    // more than |w| 2.58, the same way), is a step even below the deciding
                    // test: two witnesses of one fault.
                    let receiver_step = converged
                        && recv.is_some_and(|c| {
                            c.e[j].abs() > RECEIVER_JUMP * c.sigma[j]
                                && -c.e[j] * d[j] > 0.0
                                && w2(j) > AGREE_W2
                        });
                    let flagged =
                        (alarm && (converged || gross) && isolated.contains(&j)) || receiver_step;
                    // A jump back across an INS the updates had pulled the other way is the
                    // end of a fault it followed (without the receiver's velocity the filter
                    // follows slow ramps; with it, at rest, where ZUPT holds the velocity and
                    // only the position corrections move the INS).
                    let pulled_back = flagged && jump && pulled(j);
                    // A jump back to the offset of a step taken as over lately: the step
                    // resumes (held by the rule below), whatever the window says.
                    let resumes = self.ended[j].is_some_and(|(t0, b0)| {
                        t - t0 <= RESUME && (d[j] - b0).powi(2) <= 2.0 * AGREE_W2 * s[j]
                    });
                    if (returned(j) || pulled_back) && !(resumes && flagged && jump) {
                        // Used as measured: it corrects the filter.
                        Comp::Return { fixes: 1 }
                    } else if flagged && jump {
                        out[j] = if accommodate {
                            Use::Relative(d[j], s[j])
                        } else {
                            Use::Out(STEP)
                        };
                        Comp::Step {
                            b: d[j],
                            var: s[j],
                            back: false,
                            agree: 0,
                            quiet: 0,
                            base: None,
                            moved: false,
                        }
                    } else if let (true, Some((sum, var))) =
                        (converged, recv.and_then(|c| c.onset[j]))
                    {
                        // The receiver's displacement drifts from its velocity (CUSUM): held
                        // out, its size followed from the estimated onset; confirmed when
                        // the fix also leaves the INS prediction.
                        out[j] = Use::Out(RAMP);
                        Comp::Drift {
                            since: t,
                            b: -sum,
                            var,
                            var0: var,
                            confirmed: leaves(j, -sum),
                            fixes: 0,
                            agree: 0,
                            seen: sum * sum > AGREE_W2 * var,
                            quiet: 0,
                            start: (t, -sum),
                            rate: None,
                        }
                    } else if flagged {
                        out[j] = Use::Out(TEST);
                        Comp::Normal
                    } else {
                        Comp::Normal
                    }
                }
                Comp::Return { fixes } => {
                    // Consistent as a ramp is not: within 3σ_e of its velocity — or where the
                    // receiver's consistency is not read (at rest, after a gap): nothing says
                    // otherwise.
                    let consistent = recv.is_none_or(|c| c.e[j].abs() <= 3.0 * c.sigma[j]);
                    if w2(j) <= thr1 || fixes >= AGREE_LONG || !consistent {
                        // Corrected (or the receiver jumped again, or the return lasted
                        // [`AGREE_LONG`] fixes): tested as any fix from the next one.
                        if !consistent && alarm && isolated.contains(&j) {
                            out[j] = Use::Out(TEST);
                        }
                        Comp::Normal
                    } else {
                        Comp::Return { fixes: fixes + 1 }
                    }
                }
                Comp::Step {
                    b,
                    var,
                    back,
                    agree,
                    quiet,
                    base,
                    moved,
                } => {
                    // The jump back: from the receiver's consistency, or where it has none at
                    // this fix (moving off from rest, after a gap) from the innovation's change.
                    // Not one that takes the offset back to where it was before the receiver's
                    // last jump away (nearer that than zero): a burst on the held step ended.
                    let to_base =
                        |dd: f64| base.is_some_and(|b0| (b + dd - b0).abs() < (b + dd).abs());
                    // Nor one that leaves the fix still off the INS the fault's way beyond the
                    // deciding test: the fault changed (one multipath burst giving way to
                    // another), it did not end — at an end the fix lands on the INS, or across
                    // it where the INS followed part of the fault. Unless another held
                    // component of the fix landed on the INS at once: one receiver, one fault,
                    // which has ended, and what is left off is the INS's own drift.
                    let still_off =
                        d[j] * b > 0.0 && w2(j) > thr1 && !(0..3).any(|k| k != j && landed[k]);
                    // Nor one that lands across the INS, beyond the deciding test, further
                    // than the held offset (3σ of the innovation on top): what the INS
                    // followed of a fault is at most the fault, so the fix jumped past the
                    // end to a new fault the other way (a burst giving way to a step, or a
                    // step starting inside a burst). Only where the offset is the fault: one
                    // that has not followed the receiver's inconsistency (with its velocities)
                    // and that the fix before the jump still fitted (a ramp taken for a step
                    // grows past its offset, and the INS follows it past). Without the
                    // receiver's velocities the offset follows nothing, and the relative fixes,
                    // a return or a move onto the fixes can take the INS along a ramp taken for
                    // a step, so there the copies of the filter carried without GNSS must side
                    // with the INS (without them RTK ramps' ends were held as steps, 0.04 -> 76
                    // m after them) — and then the INS followed none of the fault, so an end
                    // lands on it: any landing across it beyond the deciding test is a new
                    // fault. Traced on positions alone: a 40 m step starting inside a 30 m
                    // burst, across the INS from it (42 m of error through the step), and a
                    // burst's end on a held 20 m step landing 20 m across the INS, inside the
                    // offset the burst renewed (5.9 m), both read as ends and used as measured.
                    let followed = if self.copies_with_ins { 0.0 } else { b.abs() };
                    let overshoots = (recv.is_some_and(|c| !c.ins_referenced)
                        || self.copies_with_ins)
                        && !moved
                        && self
                            .prev
                            .is_some_and(|(pd, ps)| (pd[j] - b).powi(2) <= thr1 * (ps[j] + var))
                        && d[j] * b < 0.0
                        && w2(j) > thr1
                        && d[j].abs() > followed + 3.0 * s[j].sqrt();
                    let jump_back = |dd: f64| {
                        dd * b < 0.0
                            && dd.abs() > 0.5 * b.abs()
                            && !to_base(dd)
                            && !still_off
                            && !overshoots
                    };
                    let receiver_jump = recv
                        .filter(|c| c.e[j].abs() > RECEIVER_JUMP * c.sigma[j])
                        .map(|c| c.e[j]);
                    let receiver_back = receiver_jump.is_some_and(|e| jump_back(-e));
                    let back = back
                        || delta(j)
                            .or_else(|| self.prev.map(|(pd, ps)| (d[j] - pd[j], s[j] + ps[j])))
                            .is_some_and(|(dd, _)| jump_back(dd));
                    // A jump away from zero (with the receiver's velocity) remembers the offset
                    // before it; one back to it forgets it.
                    // Past the end to a new fault: the old one is over, nothing to go back to.
                    let base =
                        match receiver_jump.filter(|_| recv.is_some_and(|c| !c.ins_referenced)) {
                            _ if overshoots => None,
                            Some(e) if (b - e).abs() > b.abs() => Some(b),
                            Some(e) if to_base(-e) => None,
                            _ => base,
                        };
                    let quiet = match recv {
                        Some(c) if back && c.e[j].abs() <= 3.0 * c.sigma[j] => quiet + 1,
                        _ => 0,
                    };
                    // The held offset moves with the receiver's own inconsistency where it is
                    // significant (a fault that keeps growing after its jump — a ramp taken for
                    // a step — is followed, not let into the solution; its end brings it back
                    // to zero), and stays put otherwise (a step). Significant: beyond 3σ_e
                    // where the INS confirms it (the fix found further that way), beyond
                    // [`MOVE_ALONE`] σ_e where it does not (a ramp the INS follows) — one noisy
                    // fix of a white σ 1 m receiver (2.5 m one way, then 2.5 m the other) is a
                    // 3-4σ_e jump the INS does not see. Not against
                    // the INS's displacement (a receiver without velocities): there `e` holds
                    // the INS's own drift, and an offset that followed it would keep the
                    // relative fixes agreeing with an INS drifting away (tens of km, fault-free,
                    // with an IMU noise set above the sensor's).
                    let held = b;
                    let (b, var, moved) = match recv {
                        Some(c) if !c.ins_referenced => {
                            let (e, v) = (c.e[j], c.sigma[j] * c.sigma[j]);
                            let confirmed = (d[j] - b + e).abs() < (d[j] - b).abs();
                            let z2 = e * e / v;
                            if z2 > MOVE_ALONE * MOVE_ALONE || (z2 > 9.0 && confirmed) {
                                // A move is the offset following the fault — except the
                                // jump past it just refused as the end: a new fault, the
                                // offset renewed by it (and `overshoots` implies `!moved`).
                                (b - e, var + v, !overshoots)
                            } else {
                                (b, var, moved)
                            }
                        }
                        _ => (b, var, moved),
                    };
                    // The offset is gone: the fix jumped back and agrees with the INS (the
                    // deciding test), or it agrees strictly — for [`AGREE`] fixes when no
                    // receiver consistency can show the jump back, else for [`AGREE_LONG`]
                    // (an offset of a few σ can wander into agreement with time-correlated
                    // errors while the fault lasts).
                    let needed = if recv.is_some() && !back {
                        AGREE_LONG
                    } else {
                        AGREE
                    };
                    if receiver_back || (back && quiet >= AGREE_LONG) {
                        // The receiver jumped back to where its velocity says it is: the fault
                        // is over, and what is left between the fix and the INS is the part of
                        // it the INS followed (a ramp taken for a step) — the fix corrects it,
                        // rather than being held as an offset of its own.
                        // Without the receiver at the jump (from rest): once it has agreed with
                        // its own velocity for [`AGREE_LONG`] fixes since.
                        self.ended[j] = Some((t, held));
                        Comp::Return { fixes: 1 }
                    } else if (back && w2(j) <= thr1) || w2(j) <= AGREE_W2 {
                        let agree = agree + 1;
                        if agree >= needed {
                            Comp::Normal
                        } else {
                            out[j] = Use::Out(STEP);
                            Comp::Step {
                                b,
                                var,
                                back,
                                agree,
                                quiet,
                                base,
                                moved,
                            }
                        }
                    } else if (d[j] - b).powi(2) / (s[j] + var) <= thr1 {
                        out[j] = if accommodate {
                            Use::Relative(b, var)
                        } else {
                            Use::Out(STEP)
                        };
                        Comp::Step {
                            b,
                            var,
                            back: false,
                            agree: 0,
                            quiet: 0,
                            base,
                            moved,
                        }
                    } else {
                        out[j] = Use::Out(STEP);
                        // The fault changed (a new jump the receiver cannot account for — or,
                        // against the INS's displacement, any jump of the fix: a multipath
                        // burst on a held step): a new offset; else the old one held.
                        let renew = jump && recv.is_none_or(|c| c.ins_referenced);
                        // Against the INS, a jump further from zero remembers the offset
                        // before it, as the receiver's own jump away does above: a burst on
                        // the held step, whose end jumps back to it and is no fault's end.
                        let away = recv.is_some() && d[j] * b > 0.0 && d[j].abs() > b.abs();
                        Comp::Step {
                            b: if renew { d[j] } else { b },
                            var: if renew { s[j] } else { var },
                            back: back && !renew,
                            agree: 0,
                            quiet: if renew { 0 } else { quiet },
                            base: match (renew, away) {
                                (true, true) => Some(b),
                                (true, false) => None,
                                _ => base,
                            },
                            moved: moved && !renew,
                        }
                    }
                }
                Comp::Drift {
                    since,
                    b,
                    var,
                    var0,
                    confirmed,
                    fixes,
                    agree,
                    seen,
                    quiet,
                    start,
                    rate,
                } => {
                    // The ramp's size moves with the receiver's inconsistency (its end: a
                    // jump back to zero).
                    // Without it (at rest, or after a gap) the INS, held by the constraints,
                    // is the reference: the offset is re-anchored to the fix's innovation.
                    // Against the INS's displacement the inconsistency holds the INS's own
                    // velocity error, which a size following it would hide from the relative
                    // fixes: there the size follows the line of its first fixes.
                    let (ts, bs) = start;
                    let (b, var, rate) = match recv {
                        Some(c) if c.ins_referenced => {
                            let var = var + c.sigma[j] * c.sigma[j];
                            match rate {
                                Some(r) => (bs + r * (t - ts), var, rate),
                                None => {
                                    let nb = b - c.e[j];
                                    let line = (fixes + 1 >= AGREE_LONG && t > ts)
                                        .then(|| (nb - bs) / (t - ts));
                                    (nb, var, line)
                                }
                            }
                        }
                        // Its variance grows as a random walk's, but not beyond what the
                        // receiver's drift over the hold measures (white or Gauss-Markov
                        // errors' sums saturate: a ramp's size would otherwise sink into a
                        // variance grown past it, and the hold end mid-ramp).
                        Some(c) => {
                            let rw = var + c.sigma[j] * c.sigma[j];
                            let sat = super::window::drift_var(&c.structure[j], t - since)
                                .map_or(rw, |v| rw.min(var0 + v));
                            (b - c.e[j], sat, rate)
                        }
                        None => (d[j], s[j], rate),
                    };
                    // The fix off the line beyond the deciding test (the ramp ended, or
                    // changed): the line is measured again from this fix.
                    let (b, start, rate) = match rate {
                        Some(_) if (d[j] - b).powi(2) / (s[j] + var) > thr1 => {
                            (d[j], (t, d[j]), None)
                        }
                        _ => (b, start, rate),
                    };
                    let confirmed = confirmed || leaves(j, b);
                    let fixes = fixes + 1;
                    // Over: the receiver says the fault is gone and the fix agrees with the
                    // INS, for [`AGREE`] fixes.
                    let ok = w2(j) <= thr1 && b * b <= AGREE_W2 * var;
                    let agree = if ok { agree + 1 } else { 0 };
                    // The receiver's ramp size back within its noise after it was significant,
                    // for [`AGREE_LONG`] fixes with the receiver's consistency: the ramp is
                    // over; an INS that still disagrees followed part of it.
                    let small = recv.is_some() && b * b <= AGREE_W2 * var;
                    let seen = seen || (recv.is_some() && !small);
                    let quiet = if seen && small { quiet + 1 } else { 0 };
                    // The receiver jumped back to where its velocity says it is: the ramp
                    // ended, and the fix corrects what the filter followed before the hold.
                    // Or, where the receiver's own velocity cannot say it (at rest, after a
                    // gap, on positions only), the fix jumped back across an INS the updates
                    // had pulled the ramp's way. Not where it can: on RTK fixes every fix of a
                    // fast ramp is a "jump", and it was taken for a return (0.6-1 m/s ramps'
                    // 95th percentile 4.6 -> 15 m on drive_lc).
                    let pulled_back = recv.is_none_or(|c| c.ins_referenced) && jump && pulled(j);
                    if returned(j) || quiet >= AGREE_LONG || pulled_back {
                        Comp::Return { fixes: 1 }
                    } else if (!confirmed && fixes >= PROBATION) || agree >= AGREE {
                        Comp::Normal
                    } else {
                        out[j] = if confirmed
                            && accommodate
                            && (d[j] - b).powi(2) / (s[j] + var) <= thr1
                        {
                            Use::Relative(b, var)
                        } else {
                            Use::Out(RAMP)
                        };
                        Comp::Drift {
                            since,
                            b,
                            var,
                            var0,
                            confirmed,
                            fixes,
                            agree,
                            seen,
                            quiet,
                            start,
                            rate,
                        }
                    }
                }
            };
        }
        // The next fix's jump is measured from this one's raw innovation.
        self.prev = Some((*d, *s));
        for j in 0..3 {
            // Fixes of a held fault are off the INS by the fault, not by a lagging INS.
            let used = matches!(self.comps[j], Comp::Normal);
            // Begun beyond |w| 2, carried on beyond |w| 1 on the same side (at 5–10 Hz the
            // noise of a lagging INS's innovations crosses 2 now and then).
            let w2 = d[j] * d[j] / s[j];
            self.lag[j] = match self.lag[j] {
                Some((t0, sum, n)) if used && sum * d[j] > 0.0 && w2 > 1.0 => {
                    Some((t0, sum + d[j], n + 1))
                }
                _ if used && w2 > 4.0 => Some((t, d[j], 1)),
                _ => None,
            };
        }
        out
    }

    /// Whether the fix at `t` ended a held step of component `j` by the receiver's jump back
    /// (the step is then a [`Comp::Return`]).
    pub fn step_ended_at(&self, j: usize, t: f64) -> bool {
        self.ended[j].is_some_and(|(t0, _)| t0 == t)
    }

    /// Whether a horizontal component is held as a ramp.
    pub fn ramp_held(&self) -> bool {
        self.comps[..2]
            .iter()
            .any(|c| matches!(c, Comp::Drift { .. }))
    }

    /// Whether the up component is held as a step (the INS's height is then watched:
    /// [`super::diverge::InsWatch::vertical`]).
    pub fn up_step(&self) -> bool {
        matches!(self.comps[2], Comp::Step { .. })
    }

    /// Component `j` used as measured again after the INS was moved onto its fix (this fix's
    /// innovation is then zero: the next jump is measured from there).
    pub fn restart(&mut self, j: usize) {
        self.comps[j] = Comp::Normal;
        self.ended[j] = None;
        self.lag[j] = None;
        if let Some((d, _)) = self.prev.as_mut() {
            d[j] = 0.0;
        }
    }

    /// Forget the jump reference (after an outage: no fix to measure a jump from).
    pub fn gap(&mut self) {
        self.prev = None;
        self.lag = [None; 3];
    }

    /// Use component `j` as measured again if it is held as a ramp: the drift the receiver's
    /// consistency showed was its velocity's ([`super::blame::VelocityBlame`]).
    pub fn release_drift(&mut self, j: usize) {
        if matches!(self.comps[j], Comp::Drift { .. }) {
            self.comps[j] = Comp::Normal;
        }
    }
}

#[cfg(test)]
#[path = "hold_tests.rs"]
mod tests;
