//! The INS running away from the fixes it holds out.
//!
//! The hold machine ([`super::hold`]) takes the INS prediction as the reference a fix is
//! judged against. When the INS itself is wrong — a multipath burst absorbed before the filter
//! settled, a velocity pulled by a step's first fixes, an unobservable drift on a log of
//! positions only — the hold keeps out good fixes while the INS coasts away from them, and the
//! filter ends kilometres off (simulated positions-only logs with 30 m bursts). Every fault
//! the hold is meant for has a bounded rate against the INS: a step is a constant offset, a
//! slow ramp drifts at up to about 2 m/s. An INS whose distance to the held fixes grows
//! steadily faster than [`DIVERGE_RATE`] over [`DIVERGE_WINDOW`] — in each third of the
//! window, the same way, so a burst's jump, or a step's end and a burst's start, is not a
//! rate — is the one that is wrong: it is moved back onto the fixes ([`Divergence::push`]
//! says when and at what rate, [`reanchor`] moves it). So is a ramp held on positions alone
//! for longer than [`HOLD_LONGEST`] while the INS drifts from the fixes more slowly, the
//! copies of the filter carried without GNSS siding with the fixes. A held
//! step that outlasts every fix the INS agreed with before it is the INS's error too
//! ([`Outlast`]): the alignment's fixes were in a fault.

use super::shift;
use crate::ins::error_filter::{ErrorFilter, PHI, R, V};
use crate::ins::strapdown::NavState;
use crate::stats::{median_of, RAYLEIGH_MEDIAN};
use nalgebra::{UnitQuaternion, Vector3};
use std::collections::VecDeque;

/// The rate (m/s) of the horizontal distance between the INS and the held fixes beyond which
/// the INS is taken to have diverged: 1.5× the fastest slow fault the hold is built for
/// (2 m/s ramps; faster drifts are jumps a fix or two apart and held as steps).
pub const DIVERGE_RATE: f64 = 3.0;

/// The window (s) over which that rate is read, in thirds.
pub const DIVERGE_WINDOW: f64 = 10.0;

/// The fewest held fixes in the window.
const DIVERGE_FIXES: usize = 6;

/// Seconds a spell of held fixes may last, a ramp held at its end, while the INS drifts from
/// them slower than [`DIVERGE_RATE`] ([`Divergence::push`]): the longest any evidence that a
/// hold is the fixes' fault is kept ([`super::pull::PULL_WINDOW`], [`JUMP_MEMORY`]). Held
/// longer on positions alone, with the copies of the filter carried without GNSS nearer the
/// fix than the INS ([`super::shadow::Shadows::side`]), the drift is the INS's: a ramp
/// held relative to an offset that follows the innovation makes the INS's velocity error the
/// ramp's rate, and nothing ends it (simulated positions-only logs: about 1 m/s for seven
/// minutes, 485 m off at the end).
pub const HOLD_LONGEST: f64 = 120.0;
/// The window (s) over which a long spell's drift is read.
pub const DRIFT_WINDOW: f64 = 60.0;
/// The drift rate (m/s) of a long spell's offset that is the INS's: the slowest ramp the hold
/// is built for (a held step keeps its offset).
pub const DRIFT_RATE: f64 = 0.1;
/// How near (σ of the spell's scatter about its line) the fix the INS is moved onto must be
/// to the line of the spell's last [`DRIFT_WINDOW`] s.
pub const ON_LINE_SIGMAS: f64 = 3.0;

/// Held fixes of one GNSS channel: time (s) and the horizontal INS − fix (east, north; m).
#[derive(Debug, Clone, Default)]
pub struct Divergence {
    /// The spell's last [`DRIFT_WINDOW`] s (the runaway reads the last [`DIVERGE_WINDOW`]).
    held: VecDeque<(f64, [f64; 2])>,
    /// The start (s) of the spell of held fixes.
    spell: Option<f64>,
}

/// Least-squares slope (per s) of `y` against `t` (NaN with fewer than two distinct times).
fn slope(pts: &[(f64, [f64; 2])]) -> [f64; 2] {
    let n = pts.len() as f64;
    let tm = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let stt: f64 = pts.iter().map(|p| (p.0 - tm).powi(2)).sum();
    let mut out = [f64::NAN; 2];
    for (j, o) in out.iter_mut().enumerate() {
        let ym = pts.iter().map(|p| p.1[j]).sum::<f64>() / n;
        let sty: f64 = pts.iter().map(|p| (p.0 - tm) * (p.1[j] - ym)).sum();
        *o = sty / stt;
    }
    out
}

/// The most points a long spell's line is read from ([`robust_line`]): the window's fixes
/// are thinned to these.
const LINE_POINTS: usize = 61;

/// The Theil–Sen line of `pts` (time s, east and north m) per component — the median of the
/// pairwise slopes (per s) and the median intercept at time 0 — so that a burst of a few
/// fixes in the window neither tilts nor moves it; None with fewer than two distinct times.
fn robust_line(pts: &[(f64, [f64; 2])]) -> Option<([f64; 2], [f64; 2])> {
    let median = |v: &mut Vec<f64>| (!v.is_empty()).then(|| median_of(v));
    let mut rate = [0.0; 2];
    let mut at0 = [0.0; 2];
    for j in 0..2 {
        let mut slopes: Vec<f64> = Vec::new();
        for (a, pa) in pts.iter().enumerate() {
            for pb in &pts[a + 1..] {
                if pb.0 > pa.0 {
                    slopes.push((pb.1[j] - pa.1[j]) / (pb.0 - pa.0));
                }
            }
        }
        rate[j] = median(&mut slopes)?;
        let mut c: Vec<f64> = pts.iter().map(|p| p.1[j] - rate[j] * p.0).collect();
        at0[j] = median(&mut c)?;
    }
    Some((rate, at0))
}

/// A long spell's drift over `pts` (its last [`DRIFT_WINDOW`] s: time s, INS − fix east and
/// north m), where the last of them lies on the line of the others ([`robust_line`]): within
/// [`ON_LINE_SIGMAS`] σ of it, σ from the others' median distance from it (a 2D Gaussian's:
/// 1.1774 σ). The INS is moved onto that fix: not onto a burst's.
fn drift_on_line(pts: &[(f64, [f64; 2])]) -> Option<[f64; 2]> {
    let ((t, d), rest) = pts.split_last()?;
    let stride = rest.len().div_ceil(LINE_POINTS).max(1);
    let thin: Vec<(f64, [f64; 2])> = rest.iter().step_by(stride).copied().collect();
    let (rate, at0) = robust_line(&thin)?;
    let off = |ti: f64, di: &[f64; 2]| {
        let r: [f64; 2] = std::array::from_fn(|j| di[j] - at0[j] - rate[j] * ti);
        r[0].hypot(r[1])
    };
    let mut sizes: Vec<f64> = thin.iter().map(|(ti, di)| off(*ti, di)).collect();
    let sigma = median_of(&mut sizes) / RAYLEIGH_MEDIAN;
    (off(*t, d) <= ON_LINE_SIGMAS * sigma).then_some(rate)
}

impl Divergence {
    /// Record the fix at `t` (s) with horizontal innovation `d` (INS − fix, east and north,
    /// m) — `held`: the hold machine kept it out or used it relative to an offset (a fix used
    /// as measured, or none at this epoch, empties the window). Returns the rate (m/s, INS −
    /// fix, east and north) when the INS has diverged from the held fixes: over the last
    /// [`DIVERGE_WINDOW`] s the distance grew at more than [`DIVERGE_RATE`] in each third of
    /// the window, along the whole window's rate and within 45° of it; or, a ramp held at this
    /// fix (`ramp`), the spell of held fixes has lasted [`HOLD_LONGEST`] s and over its last
    /// [`DRIFT_WINDOW`] s the distance drifted at more than [`DRIFT_RATE`], the fix on the
    /// drift's line ([`drift_on_line`]; that rate returned). The windows then empty.
    pub fn push(&mut self, t: f64, d: [f64; 2], held: bool, ramp: bool) -> Option<[f64; 2]> {
        if !held || !d.iter().all(|x| x.is_finite()) {
            *self = Self::default();
            return None;
        }
        let since = *self.spell.get_or_insert(t);
        self.held.push_back((t, d));
        while self.held.front().is_some_and(|p| p.0 < t - DRIFT_WINDOW) {
            self.held.pop_front();
        }
        if ramp && t - since >= HOLD_LONGEST && self.held.len() >= DIVERGE_FIXES {
            let pts: Vec<(f64, [f64; 2])> = self.held.iter().copied().collect();
            let drift = drift_on_line(&pts).filter(|r| r[0].hypot(r[1]) > DRIFT_RATE);
            if let Some(rate) = drift {
                *self = Self::default();
                return Some(rate);
            }
        }
        let from = self.held.partition_point(|p| p.0 < t - DIVERGE_WINDOW);
        let pts: Vec<(f64, [f64; 2])> = self.held.range(from..).copied().collect();
        let t0 = pts.first()?.0;
        if pts.len() < DIVERGE_FIXES || t - t0 < 0.8 * DIVERGE_WINDOW {
            return None;
        }
        // Thirds of the window, each with its own rate: two jumps of one sign (a step's end
        // and a burst's start) fill two thirds at most, a runaway all three.
        let cut = |f: f64| pts.partition_point(|p| p.0 < t0 + f * (t - t0));
        let (c1, c2) = (cut(1.0 / 3.0), cut(2.0 / 3.0));
        if c1 < 3 || c2 - c1 < 3 || pts.len() - c2 < 3 {
            return None;
        }
        let whole = slope(&pts);
        let norm = |v: [f64; 2]| v[0].hypot(v[1]);
        let along = |v: [f64; 2]| (v[0] * whole[0] + v[1] * whole[1]) / norm(whole);
        let thirds = [slope(&pts[..c1]), slope(&pts[c1..c2]), slope(&pts[c2..])];
        if norm(whole) > DIVERGE_RATE
            && thirds.iter().all(|&v| {
                along(v) > DIVERGE_RATE && along(v) > std::f64::consts::FRAC_1_SQRT_2 * norm(v)
            })
        {
            *self = Self::default();
            Some(whole)
        } else {
            None
        }
    }
}

/// Seconds beyond the spell of fixes before it that a held step must last to be taken as the
/// INS's error ([`Outlast`]).
pub const OUTLAST_MARGIN: f64 = 30.0;

/// A jump of the fixes is a second difference of the horizontal position beyond this (m),
/// beyond [`JUMP_ACCEL`] × the fix interval² (a car's hardest braking: 8 m at 1 Hz) and beyond
/// [`JUMP_SIGMAS`] σ of the last [`JUMP_WINDOW`] second differences (σ per component from
/// their median size; a Gaussian's size passes 5σ once in 270 000).
pub const JUMP_M: f64 = 8.0;
/// See [`JUMP_M`] (m/s²).
pub const JUMP_ACCEL: f64 = 8.0;
/// See [`JUMP_M`].
pub const JUMP_SIGMAS: f64 = 5.0;
/// See [`JUMP_M`] (fixes).
pub const JUMP_WINDOW: usize = 120;
/// Against the receiver's velocities ([`Jumps::push_with`]) a jump is beyond [`JUMP_M`] and
/// this many σ of the last [`JUMP_WINDOW`] displacements (a Gaussian's size passes 4σ once in
/// 3 000: at 1 Hz once an hour of fixes, and a jump acts only where a later hold undoes it).
pub const JUMP_SIGMAS_VELOCITY: f64 = 4.0;
/// Seconds of a stale spell (fixes repeating the last fresh one) across which a fix is read
/// against the velocities at its two ends ([`Jumps::push_with`]): the spells the simulated
/// logs have (4 s) and a second more.
pub const STALE_SPAN: f64 = 5.0;
/// Two jumps read against the velocities, each with σ per component, are one within this
/// many σ of their difference (a 2D Gaussian's size passes 2.5σ once in 23).
pub const MATCH_SIGMAS: f64 = 2.5;
/// Seconds a jump the filter took in is remembered for a jump back to undo.
pub const JUMP_MEMORY: f64 = 120.0;
/// How close (m, or a quarter of the jump where larger) two horizontal offsets must be to be
/// one jump.
pub const MATCH_TOLERANCE: f64 = 3.0;
/// Seconds a hold that undoes a jump the filter took in lasts before the INS is moved.
pub const MATCH_CONFIRM: f64 = 5.0;
/// How far along a jump the filter took in, in multiples of the jump (plus
/// [`MATCH_TOLERANCE`]), the INS may be off the fix that undoes it: an INS that followed a
/// fault's first fixes took their velocity too and coasts past it (traced on simulated
/// positions-only logs: 18 m past a 12 m burst, 32 m past a 25 m one).
pub const FOLLOW_OVERSHOOT: f64 = 2.0;

/// Whether the horizontal offset `d` (m) is the jump `e` (m): within [`MATCH_TOLERANCE`] or a
/// quarter of the jump, or within [`MATCH_SIGMAS`] σ of the difference of two jumps each read
/// with `sigma` (m per component; [`Jumps::push_with`]).
fn same(e: [f64; 2], d: [f64; 2], sigma: f64) -> bool {
    let tolerance = MATCH_TOLERANCE
        .max(0.25 * e[0].hypot(e[1]))
        .max(MATCH_SIGMAS * std::f64::consts::SQRT_2 * sigma);
    (d[0] - e[0]).hypot(d[1] - e[1]) <= tolerance
}

/// A channel's last `ORDER` fixes (time s, east and north m) and the sizes of their horizontal
/// differences of that order (the last `CAP`): the fixes' own noise from one fix to the next.
#[derive(Debug, Clone)]
pub(super) struct Differences<const ORDER: usize, const CAP: usize> {
    last: [Option<(f64, [f64; 2])>; ORDER],
    sizes: super::noise_scale::Rolling<CAP>,
}

/// [`Differences`] of the second order: `p(k) − 2p(k−1) + p(k−2)`.
pub(super) type SecondDifferences<const CAP: usize> = Differences<2, CAP>;

impl<const ORDER: usize, const CAP: usize> Default for Differences<ORDER, CAP> {
    fn default() -> Self {
        Differences {
            last: [None; ORDER],
            sizes: Default::default(),
        }
    }
}

impl<const ORDER: usize, const CAP: usize> Differences<ORDER, CAP> {
    /// The fix `p` (east, north, m) at `t` (s), the fixes `interval` s apart: kept as the
    /// last; its difference of order `ORDER` with the fixes before it (binomial weights with
    /// alternating signs) when each is at most 1.5 intervals from the next (its size is not
    /// recorded: [`Differences::record`]).
    pub fn push(&mut self, t: f64, p: [f64; 2], interval: f64) -> Option<[f64; 2]> {
        let gap = 1.5 * interval;
        let (mut next, mut c, mut d) = (t, 1.0, Some(p));
        for (i, f) in self.last.iter().enumerate() {
            d = match (d, f) {
                (Some(d), Some((ti, pi))) if next - ti <= gap => {
                    next = *ti;
                    c = -c * (ORDER - i) as f64 / (i + 1) as f64;
                    Some([d[0] + c * pi[0], d[1] + c * pi[1]])
                }
                _ => None,
            };
        }
        if ORDER > 0 {
            self.last.rotate_right(1);
            self.last[0] = Some((t, p));
        }
        d
    }

    /// Record a difference's size (m).
    pub fn record(&mut self, size: f64) {
        self.sizes.push(size);
    }

    /// The last fixes, latest first.
    pub fn last(&self) -> [Option<(f64, [f64; 2])>; ORDER] {
        self.last
    }

    /// σ per component (m) of the recorded differences, from their median size (a 2D
    /// Gaussian's: 1.1774 σ); None with fewer than `min` recorded.
    pub fn sigma(&self, min: usize) -> Option<f64> {
        (self.sizes.len() >= min.max(1)).then(|| self.sizes.median() / RAYLEIGH_MEDIAN)
    }
}

/// A channel's fixes, one after the other: where they jump ([`JUMP_M`]).
///
/// With the receiver's velocities (at this fix and the one before), the jump is read from the
/// fix's displacement against them, `p(k) − p(k−1) − ½(v(k) + v(k−1))Δt` (the receiver's
/// own consistency, [`super::receiver`]): the car's motion is taken out, so neither a
/// braking bound nor the second difference's three fixes of noise widen it — a white noise
/// σ is √2 σ there against √6 σ in the second difference, and a 2 m receiver's 18 m burst is
/// a jump (traced: a burst under way at the alignment, invisible to the second differences'
/// 5σ of 26 m, held the good fixes after it out for 270 s). Its σ is kept apart from the
/// second differences'; without velocities the second difference decides.
#[derive(Debug, Clone)]
pub(super) struct Jumps {
    /// The fix interval (s).
    interval: f64,
    /// The last fixes and their second differences' sizes.
    steps: SecondDifferences<JUMP_WINDOW>,
    /// The last fix's jump (its second difference comes back at the next fix).
    prev: Option<[f64; 2]>,
    /// The last fresh fix with the receiver's velocity: time (s), east and north (m, m/s).
    last_v: Option<(f64, [f64; 2], [f64; 2])>,
    /// Fixes since it repeated it (a stale spell: read across, against the velocities at its
    /// two ends, up to [`STALE_SPAN`] s).
    repeats: bool,
    /// The sizes (m) of the displacements against the velocities.
    moved: Differences<0, JUMP_WINDOW>,
}

impl Jumps {
    /// For fixes `interval` s apart.
    pub fn new(interval: f64) -> Self {
        Jumps {
            interval,
            steps: Default::default(),
            prev: None,
            last_v: None,
            repeats: false,
            moved: Default::default(),
        }
    }

    /// The fix `p` (east, north, m) at `t` (s): its jump (the second difference, m), if any
    /// (not the one right after a jump, which comes back the other way).
    pub fn push(&mut self, t: f64, p: [f64; 2]) -> Option<[f64; 2]> {
        self.push_with(t, p, None).map(|(e, _)| e)
    }

    /// The fix `p` (east, north, m) at `t` (s) with the receiver's horizontal velocity `v`
    /// (east, north, m/s; None: not given): its jump (m), if any — against the velocities
    /// where this fix and the one before have them, else the second difference — and the σ
    /// per component (m) it was read with against the velocities (0 for a second
    /// difference's: those match within [`MATCH_TOLERANCE`] or a quarter).
    pub fn push_with(
        &mut self,
        t: f64,
        p: [f64; 2],
        v: Option<[f64; 2]>,
    ) -> Option<([f64; 2], f64)> {
        let second = self.second(t, p).map(|e| (e, 0.0));
        let v = v.filter(|v| v.iter().all(|x| x.is_finite()));
        // A fix repeating the last fresh one (a stale spell): no jump, and the next fresh fix
        // is read from that one, across the spell (its catch-up is motion, not a jump).
        if let (Some(_), Some((t0, p0, _))) = (v, self.last_v) {
            if t > t0 && (p[0] - p0[0]).abs().max((p[1] - p0[1]).abs()) < 1e-3 {
                self.repeats = true;
                return None;
            }
        }
        let span = if std::mem::take(&mut self.repeats) {
            STALE_SPAN
        } else {
            1.5 * self.interval
        };
        let last = std::mem::replace(&mut self.last_v, v.map(|v| (t, p, v)));
        match (v, last) {
            (Some(v), Some((t0, p0, v0))) if t - t0 <= span && t > t0 => {
                let dt = t - t0;
                let e = [
                    p[0] - p0[0] - 0.5 * (v[0] + v0[0]) * dt,
                    p[1] - p0[1] - 0.5 * (v[1] + v0[1]) * dt,
                ];
                let size = e[0].hypot(e[1]);
                let spread = self.moved.sigma(1).unwrap_or(0.0);
                self.moved.record(size);
                (size > JUMP_M.max(JUMP_SIGMAS_VELOCITY * spread)).then_some((e, spread))
            }
            _ => second,
        }
    }

    /// The second difference's jump at the fix `p` (m) at `t` (s).
    fn second(&mut self, t: f64, p: [f64; 2]) -> Option<[f64; 2]> {
        let e = self.steps.push(t, p, self.interval)?;
        let spread = self.steps.sigma(1).unwrap_or(0.0);
        self.steps.record(e[0].hypot(e[1]));
        let bound = JUMP_M
            .max(JUMP_ACCEL * self.interval * self.interval)
            .max(JUMP_SIGMAS * spread);
        let back = self
            .prev
            .is_some_and(|e0| e[0] * e0[0] + e[1] * e0[1] < 0.0);
        let jump = (e[0].hypot(e[1]) > bound && !back).then_some(e);
        self.prev = jump;
        jump
    }
}

/// A held step that outlasts the fixes the INS agreed with before it.
///
/// The INS takes its position from the fixes at the alignment. When those fixes were in a
/// fault (a multipath burst or an injected step under way at the first fix), the fault's end
/// is a jump of every later fix, which the hold takes for a step's onset and holds, the INS
/// carried off the truth by its velocity, for the rest of the log (simulated, 15–30 m to
/// 40–60 s: the error 16–31 m RMS to the end, 2–3 m without FDE). A step and a fault's end
/// look alike at the jump; what tells them apart is how long each side lasts. The fixes the
/// INS agreed with run from the channel's first fix (or the onset of the last step this rule
/// ended) to the hold's onset; a step held longer than that spell plus [`OUTLAST_MARGIN`] is
/// taken as the INS's error: it is moved onto the fixes, and the fixes since the onset become
/// the spell. A fault injected after a spell of agreeing fixes is held for that spell plus
/// 30 s at least (60 s into a log, a 90 s fault).
///
/// The fixes themselves can say more: a jump of theirs the filter took in before it had
/// converged (before the alignment, or while only gross innovations exclude), undone by
/// the jump that starts the hold — the fix jumping back by what it jumped, and the INS off
/// the fix that way (within 45°) by at most [`FOLLOW_OVERSHOOT`] times as much (it followed
/// the fault, or part of it, or past it) — makes the hold the end of a fault the INS
/// followed: it is moved after [`MATCH_CONFIRM`] s. The same jump back later in a hold (the
/// fault's own fixes, excluded once the filter converged, started it) makes the hold that
/// end from there. Jumps are read against the receiver's velocities where it gives them
/// ([`Jumps::push_with`]); a jump taken in is forgotten once the converged filter has used
/// the fixes for [`OUTLAST_MARGIN`] s (the INS came back onto them: a later burst the other
/// way is not its end).
#[derive(Debug, Clone)]
pub struct Outlast {
    /// Start (s) of the spell of fixes the INS agreed with.
    spell: f64,
    /// Onset (s) of the hold in progress, and whether it undoes a jump taken in.
    onset: Option<(f64, bool)>,
    /// The fixes' jumps.
    jumps: Jumps,
    /// Jumps the filter took in and no later jump undid: time (s), size (m), the σ it was
    /// read with (m per component; [`Jumps::push_with`]).
    open: Vec<(f64, [f64; 2], f64)>,
    /// Since when (s) the converged filter has used every fix (none held).
    agreed: Option<f64>,
    /// No fix pushed since the alignment yet: the first is the one the INS was put on.
    first: bool,
}

impl Outlast {
    /// From the channel's first fix at `first_fix` (s; before the alignment too), its fixes
    /// `interval` s apart.
    pub fn new(first_fix: f64, interval: f64) -> Self {
        Outlast {
            spell: first_fix,
            onset: None,
            jumps: Jumps::new(interval),
            open: Vec::new(),
            agreed: None,
            first: true,
        }
    }

    /// A fix the filter took in (used as measured, or before the alignment) at `t` (s), `p`
    /// (east, north, m), `v` the receiver's velocity there (east, north, m/s; None: not given:
    /// [`Jumps::push_with`]), `d` its horizontal `INS − fix` (m; None before the alignment): a
    /// jump of it away from the INS (the fix off the INS along the jump by half of it at
    /// least: not a held fault's end, which jumps back onto the INS) is remembered, or
    /// forgets the one it undoes.
    fn taken(&mut self, t: f64, p: [f64; 2], v: Option<[f64; 2]>, d: Option<[f64; 2]>) {
        self.open.retain(|&(t0, _, _)| t - t0 <= JUMP_MEMORY);
        let Some((e, sigma)) = self.jumps.push_with(t, p, v) else {
            return;
        };
        match self.open.last() {
            Some(&(_, e0, s0)) if same(e0, [-e[0], -e[1]], s0.max(sigma)) => {
                self.open.pop();
            }
            _ => {
                let away = d.is_none_or(|d| {
                    -(d[0] * e[0] + d[1] * e[1]) >= 0.5 * (e[0] * e[0] + e[1] * e[1])
                });
                if away {
                    self.open.push((t, e, sigma));
                }
            }
        }
    }

    /// The fix at `t` (s), `p` (east, north, m; None: no fix), `v` the receiver's velocity
    /// there (east, north, m/s; None: not given): `d` its horizontal `INS − fix`
    /// (m), `held` a horizontal component held (step or ramp), `step` none held as a ramp,
    /// `converged` the filter has converged (from then on its tests, not gross innovations
    /// only, decide: a jump taken in then is no fault's start), `resolved` the fix an RTK
    /// fixed one right after float fixes the filter used (`NoiseScale::resolved`). True when
    /// the step has outlasted the spell before it, or undone a jump taken in, or is the
    /// return from float and confirmed (the INS is to be moved onto the fix).
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        t: f64,
        p: Option<[f64; 2]>,
        v: Option<[f64; 2]>,
        d: [f64; 2],
        held: bool,
        step: bool,
        converged: bool,
        resolved: bool,
    ) -> bool {
        let first = p.is_some() && std::mem::take(&mut self.first);
        if !held {
            self.onset = None;
            // The converged filter using the fixes for [`OUTLAST_MARGIN`] s: the jumps taken
            // in before are behind it (the INS came back onto the fixes, or is a fault's own
            // and outlasts them), and a later hold's jump is not their end.
            if !converged {
                self.agreed = None;
            } else if t - *self.agreed.get_or_insert(t) >= OUTLAST_MARGIN {
                self.open.clear();
            }
            match p {
                // The alignment's own fix: the INS was put on it, so a jump there is read as
                // before the alignment (the INS then is where the fixes before it were).
                Some(p) if !converged => self.taken(t, p, v, (!first).then_some(d)),
                // The jump reference follows the fixes.
                Some(p) => _ = self.jumps.push_with(t, p, v),
                None => {}
            }
            return false;
        }
        self.agreed = None;
        let jump = p.and_then(|p| self.jumps.push_with(t, p, v));
        // The fix jumps back by what it jumped, and the INS is off it that way (within 45°),
        // by at most [`FOLLOW_OVERSHOOT`] times as much (it followed the fault, or part of
        // it, or past it on the velocity the fault's first fixes gave it). At the hold's
        // onset, or later in a hold the fault's own fixes started (the fault's end then comes
        // while it is held).
        let mut undone = || {
            self.open.retain(|&(t0, _, _)| t - t0 <= JUMP_MEMORY);
            let followed = |e0: [f64; 2]| {
                let (nd, ne) = (d[0].hypot(d[1]), e0[0].hypot(e0[1]));
                d[0] * e0[0] + d[1] * e0[1] > std::f64::consts::FRAC_1_SQRT_2 * nd * ne
                    && nd <= FOLLOW_OVERSHOOT * ne + MATCH_TOLERANCE
            };
            let i = jump.and_then(|(e, sigma)| {
                self.open.iter().rposition(|&(_, e0, s0)| {
                    same(e0, [-e[0], -e[1]], s0.max(sigma)) && followed(e0)
                })
            });
            i.map(|i| self.open.remove(i)).is_some()
        };
        match self.onset {
            // A hold that starts at the receiver's return to fixed fixes after the filter
            // followed float ones is that return, confirmed the same way.
            None => self.onset = Some((t, undone() || resolved)),
            // The receiver returns to fixed fixes during a hold that started while the filter
            // followed float ones, or the fixes undo a jump taken in: the hold is (from here)
            // that return, or that fault's end.
            Some((_, false)) if resolved || undone() => self.onset = Some((t, true)),
            Some((t0, undone)) => {
                let wait = if undone {
                    MATCH_CONFIRM
                } else {
                    (t0 - self.spell) + OUTLAST_MARGIN
                };
                if step && t - t0 > wait {
                    self.spell = t0;
                    self.onset = None;
                    return true;
                }
            }
        }
        false
    }
}

/// One GNSS position channel's two watches on the INS: a runaway ([`Divergence`]) and a held
/// step that outlasts the fixes before it ([`Outlast`]; none for a channel without a fix).
#[derive(Debug, Clone)]
pub struct InsWatch {
    runaway: Divergence,
    outlast: Option<Outlast>,
    /// The same watch on the up component's held steps ([`InsWatch::vertical`]).
    up: Option<Outlast>,
}

impl InsWatch {
    /// For a channel whose first fix is at `first_fix` (s; None: no fix), its fixes
    /// `interval` s apart, and its fixes before the alignment `(t, [east, north], velocity)`
    /// (s, m, the receiver's east and north velocity in m/s where it gives one).
    pub fn new(
        first_fix: Option<f64>,
        interval: f64,
        before: impl IntoIterator<Item = (f64, [f64; 2], Option<[f64; 2]>)>,
    ) -> Self {
        let mut outlast = first_fix.map(|t| Outlast::new(t, interval));
        let up = outlast.clone();
        if let Some(o) = outlast.as_mut() {
            before
                .into_iter()
                .for_each(|(t, p, v)| o.taken(t, p, v, None));
        }
        InsWatch {
            runaway: Divergence::default(),
            outlast,
            up,
        }
    }

    /// The fix at `t` (s) with its up component held as a step (`held`), `state` (the filter
    /// converged, the fix a return from float: [`Outlast::push`]): true when that step has
    /// outlasted the spell of fixes before it by [`OUTLAST_MARGIN`] ([`Outlast`], without the horizontal jumps' evidence) — the INS's
    /// height was wrong, not the fixes: it is moved onto them ([`reanchor_up`]).
    ///
    /// On drive_0708 on positions alone, float fixes 3 s after the alignment pulled the INS's
    /// height 0.35 m off; the RTK-fixed heights after them were held as a step for the rest
    /// of the drive, the height 0.36 m RMS off (0.025 m without FDE).
    pub fn vertical(&mut self, t: f64, held: bool, state: (bool, bool)) -> bool {
        self.up
            .as_mut()
            .is_some_and(|o| o.push(t, None, None, [0.0; 2], held, true, state.0, state.1))
    }

    /// The onset (s) of the horizontal hold in progress, if any.
    pub fn onset(&self) -> Option<f64> {
        self.outlast.as_ref()?.onset.map(|(t, _)| t)
    }

    /// The fix at `t` (s), `p` (east, north, m), `v` the receiver's velocity there (east,
    /// north, m/s; None: not given), with horizontal innovation `d` (INS − fix, east and
    /// north, m): `held` a horizontal component held out or used relative to an
    /// offset, `step` none of them a held ramp, `on_fix` the copies of the filter carried
    /// without GNSS nearer the fix than the INS ([`super::shadow::Shadows::side`]; a
    /// held ramp is then the INS's drift once it outlasts [`HOLD_LONGEST`]), `state` (the
    /// filter converged, the fix a return from float: [`Outlast::push`]). The rate
    /// (m/s, INS − fix, east and north; zero for an outlasting step or a followed fault's
    /// end) to move the INS onto the fix with, when it is to be moved.
    #[allow(clippy::too_many_arguments)]
    pub fn push(
        &mut self,
        t: f64,
        p: Option<[f64; 2]>,
        v: Option<[f64; 2]>,
        d: [f64; 2],
        held: bool,
        (step, on_fix): (bool, bool),
        state: (bool, bool),
    ) -> Option<[f64; 2]> {
        let outlasted = self
            .outlast
            .as_mut()
            .is_some_and(|o| o.push(t, p, v, d, held, step, state.0, state.1));
        let rate = self.runaway.push(t, d, held, held && !step && on_fix);
        let rate = rate.or(outlasted.then_some([0.0; 2]));
        if rate.is_some() {
            self.runaway = Divergence::default();
        }
        rate
    }
}

/// The heading variance (rad²) a re-anchored INS gets at least: (5°)², so that the fixes
/// after it can correct a heading the runaway came from.
const REANCHOR_HEADING_VAR: f64 = 0.087_266_462_599_716_47 * 0.087_266_462_599_716_47;

/// The speed (m/s) above which, before and after a re-anchoring, the heading is turned with
/// the course.
const REANCHOR_SPEED: f64 = 3.0;

/// Move the INS onto the fix it diverged from: its position by the fix's innovation `d`
/// (INS − fix, east, north, up; m), its horizontal velocity by `rate` (INS − fix, east, north;
/// m/s, from [`Divergence::push`]); the position variances reopened to the innovation's `var`
/// (east, north, up; m²) and the horizontal velocity's to the rate's square plus 1 m²/s², their
/// correlations with the other states dropped, and the heading variance to at least
/// (5°)²; moving before and after (above 3 m/s), the heading is turned by the change of
/// course.
pub fn reanchor<const NS: usize>(
    s: &mut NavState,
    kf: &mut ErrorFilter<NS>,
    d: &Vector3<f64>,
    var: &Vector3<f64>,
    rate: [f64; 2],
) {
    shift(s, &Vector3::new(-d.y, -d.x, d.z));
    let (old_n, old_e) = (s.v.x, s.v.y);
    s.v.x -= rate[1];
    s.v.y -= rate[0];
    // Moving on both sides, the course the fixes give turns the heading with it: a heading
    // the INS ran away on is what drove its velocity off.
    if old_n.hypot(old_e) > REANCHOR_SPEED && s.v.x.hypot(s.v.y) > REANCHOR_SPEED {
        let turn = s.v.y.atan2(s.v.x) - old_e.atan2(old_n);
        s.q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), turn) * s.q;
    }
    let diag = [
        (R, var.y),
        (R + 1, var.x),
        (R + 2, var.z),
        (V, rate[1] * rate[1] + 1.0),
        (V + 1, rate[0] * rate[0] + 1.0),
    ];
    for &(i, v) in &diag {
        reopen(kf, i, v);
    }
    let h = PHI + 2;
    kf.p[(h, h)] = kf.p[(h, h)].max(REANCHOR_HEADING_VAR);
}

/// Move the INS's height onto the fix ([`InsWatch::vertical`]): by the up innovation `d_up`
/// (INS − fix, m), its variance reopened to the innovation's `var` (m²) and its correlations
/// with the other states dropped. The vertical velocity stays: the relative fixes of the held
/// step kept aiding it; only the offset they could not see was wrong. `hold` uses the up
/// component as measured from the next fix.
pub fn reanchor_up<const NS: usize>(
    s: &mut NavState,
    kf: &mut ErrorFilter<NS>,
    d_up: f64,
    var: f64,
    hold: &mut super::hold::PositionHold,
) {
    shift(s, &Vector3::new(0.0, 0.0, d_up));
    reopen(kf, R + 2, var);
    hold.restart(2);
}

/// Error state `i`'s variance set to `var` (its correlations with the other states dropped).
fn reopen<const NS: usize>(kf: &mut ErrorFilter<NS>, i: usize, var: f64) {
    kf.p.row_mut(i).fill(0.0);
    kf.p.column_mut(i).fill(0.0);
    kf.p[(i, i)] = var;
}

#[cfg(test)]
#[path = "diverge_tests.rs"]
mod tests;
