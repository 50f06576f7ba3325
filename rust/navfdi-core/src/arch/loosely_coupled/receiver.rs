//! The receiver's own consistency ([`ReceiverConsistency`]): its position displacement between
//! fixes against its velocity, the sequential tests on it (CUSUM and drift windows), and what
//! it reports per fix ([`Consistency`]) to the position hold ([`super::hold`]).

use super::noise_scale::{SCALE_MIN, SCALE_WINDOW};
use nalgebra::Vector3;

/// INS motion (m) between two identical fixes that marks the second as stale.
pub const STALE_MOTION: f64 = 0.5;

/// A fix equal to the previous one (to 1 mm) after a motion (m) beyond [`STALE_MOTION`].
pub(super) fn repeated(fix: &Vector3<f64>, last: &Vector3<f64>, motion: f64) -> bool {
    (fix - last).amax() < 1e-3 && motion > STALE_MOTION
}

/// The receiver's own consistency: its position displacement between two fixes against its
/// velocity, `e = p_k − p_{k−1} − ½(v_k + v_{k−1})(t_k − t_{k−1})` per component (east,
/// north, up, m). A position fault shows in it and nothing of the INS does: a step as one
/// `e` of the step's size (and one of the opposite sign at its end), a ramp as a steady bias
/// of rate × interval, which a two-sided Page CUSUM on `e / σ_e` accumulates (reference
/// [`CUSUM_K`], threshold [`CUSUM_H`]; `σ_e` robust, from the median |e| of the last
/// [`SCALE_WINDOW`] values while moving, above [`MOVING`]; the velocity's latency estimated
/// and removed). Beside the CUSUM, a window test ([`super::window::DriftWindow`]) compares the
/// sums of `e` over 15–60 s with their own measured spread: a receiver's time-correlated
/// error makes those sums saturate where the CUSUM's random-walk model lets them grow, so
/// slow ramps stand out sooner. Needs a velocity channel from the same receiver.
#[derive(Debug, Clone, Default)]
pub struct ReceiverConsistency {
    prev: Option<(f64, Vector3<f64>, Vector3<f64>)>,
    abs_e: [super::noise_scale::Rolling<SCALE_WINDOW>; 3],
    up: [f64; 3],
    down: [f64; 3],
    /// The sums of `e` (m) and their count since each CUSUM side was last at zero: the
    /// ramp's displacement from its estimated onset.
    acc_up: [(f64, u32); 3],
    acc_down: [(f64, u32); 3],
    /// The last [`HISTORY`] values of `e` per component, for the window sum.
    hist: [std::collections::VecDeque<f64>; 3],
    /// The last [`HISTORY`] raw `e` and velocity changes, for the velocity's latency.
    pairs: std::collections::VecDeque<(Vector3<f64>, Vector3<f64>)>,
    /// The window drift test per component (slow ramps against the measured noise of the
    /// receiver's window sums).
    windows: [super::window::DriftWindow; 3],
}
/// Fixes over which the receiver's displacement is compared with its velocity
/// ([`Consistency::window`]).
pub const HISTORY: usize = 120;

/// A jump of the receiver's position against its velocity beyond this many σ_e, confirmed
/// by the INS, is a step ([`PositionHold::decide`](super::hold::PositionHold::decide)).
pub const RECEIVER_JUMP: f64 = 8.0;

/// A receiver drift beyond this many σ of a window test's sums, with the fix off the INS the
/// same way, that a jump goes back across is the end of a slow fault ([`PositionHold::decide`](super::hold::PositionHold::decide)).
pub const RETURN_Z: f64 = 3.0;

/// Fixes (while moving) before the receiver's consistency speaks: its σ_e is their median.
pub const RECEIVER_MIN: usize = 10;
/// CUSUM reference value (σ_e per fix).
pub const CUSUM_K: f64 = 0.5;
/// CUSUM threshold (σ_e).
pub const CUSUM_H: f64 = 12.0;
/// Speed (m/s) below which the receiver's consistency is not measured: at rest its
/// displacement noise is millimetres, in motion its velocity's latency makes it decimetres,
/// and one σ_e would not fit both.
pub const MOVING: f64 = 0.5;

/// What [`ReceiverConsistency::step`] reports for one fix.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Consistency {
    /// `e` per component (m).
    pub e: Vector3<f64>,
    /// Its robust σ per component (m).
    pub sigma: Vector3<f64>,
    /// The CUSUM or the window test flags a ramp per component.
    pub ramp: [bool; 3],
    /// Where a ramp is flagged: the receiver's displacement against its velocity since the
    /// ramp's estimated onset (m; the fault's size at this fix) and its variance (m²).
    pub onset: [Option<(f64, f64)>; 3],
    /// The sum of `e` over the previous fixes (up to [`HISTORY`], this one excluded, m): a
    /// jump `e` that cancels it returns the receiver to where its velocity says it is.
    pub window: Vector3<f64>,
    /// Per component, the receiver's drift before this fix over each of the window test's
    /// lengths (m) and its size in σ of that window
    /// ([`super::window::DriftWindow::excursions`]; zeros where not measured).
    pub excursion: [[(f64, f64); super::window::LAGS.len()]; 3],
    /// Per component, the window test's structure function: the variance (m²) of the
    /// receiver's drift over each of its lengths (NaN where not measured).
    pub structure: [[f64; super::window::LAGS.len()]; 3],
    /// `e` compares the fixes with the INS's displacement (a receiver without velocities),
    /// not with the receiver's own velocity: after a fault the filter followed, the INS has
    /// followed it too, and the window's sums say nothing of where the receiver should be
    /// (no return is read from them).
    pub ins_referenced: bool,
}

impl ReceiverConsistency {
    /// Forget component `j`'s sequential tests (CUSUM and window sums): its `e` measured a
    /// faulty velocity ([`super::blame::VelocityBlame`]), not a drift of the position.
    pub fn forget(&mut self, j: usize) {
        self.up[j] = 0.0;
        self.down[j] = 0.0;
        self.acc_up[j] = (0.0, 0);
        self.acc_down[j] = (0.0, 0);
        self.hist[j].clear();
        self.windows[j].restart();
    }

    /// Feed the fix `p` (east, north, up, m) and velocity `v` (m/s) at time `t` (s); None for
    /// the first fixes (until `σ_e` is estimated) or after a gap of more than `max_gap` s
    /// (the CUSUM restarts); with `own_velocity` (`v` is the receiver's), None for a stale fix.
    pub fn step(
        &mut self,
        t: f64,
        p: &Vector3<f64>,
        v: &Vector3<f64>,
        max_gap: f64,
        own_velocity: bool,
    ) -> Option<Consistency> {
        // A fix identical to the previous one while the receiver moved more than
        // [`STALE_MOTION`] by its own velocity: the receiver repeating its last fix
        // ([`PositionHold::stale`]), not a position. It is not taken in; the displacement is
        // measured from the last fresh fix, across the spell (a gap when that is long) — fed in,
        // the first fresh fix after it read as a jump back, and a held step was let in. (Against
        // the INS's displacement, on positions only, the restart cost more than it saved:
        // docs/meter_fde.md.)
        if let (true, Some((t0, p0, v0))) = (own_velocity, self.prev) {
            if repeated(p, &p0, 0.5 * (v + v0).norm() * (t - t0)) {
                return None;
            }
        }
        let prev = self.prev.replace((t, *p, *v));
        let (t0, p0, v0) = prev?;
        let dt = t - t0;
        if !(dt > 0.0 && dt <= max_gap) {
            self.up = [0.0; 3];
            self.down = [0.0; 3];
            self.acc_up = [(0.0, 0); 3];
            self.acc_down = [(0.0, 0); 3];
            self.hist.iter_mut().for_each(|h| h.clear());
            self.windows.iter_mut().for_each(|w| w.restart());
            // The latency (`pairs`) and σ_e are the receiver's: kept across the gap.
            return None;
        }
        if v.xy().norm() < MOVING || v0.xy().norm() < MOVING {
            // Window sums across a stop would span unmeasured time.
            self.windows.iter_mut().for_each(|w| w.restart());
            return None;
        }
        // A receiver's velocity lags its position by some latency τ (≈ 0.13 s on drive_0708's
        // receiver): the trapezoid then misses τ·Δv. τ is estimated by least squares over the
        // last fixes (all components) and removed.
        let raw = p - p0 - (v + v0) * (0.5 * dt);
        let dv = v - v0;
        let (sxy, sxx) = self
            .pairs
            .iter()
            .fold((0.0, 0.0), |(a, b), (e, x)| (a + e.dot(x), b + x.dot(x)));
        let tau = if self.pairs.len() >= SCALE_MIN && sxx > 0.0 {
            (sxy / sxx).clamp(-dt, dt)
        } else {
            0.0
        };
        let e = raw - dv * tau;
        let mut pending = Some((raw, dv));
        let mut sigma = Vector3::zeros();
        let mut ramp = [false; 3];
        let mut onset = [None; 3];
        let mut window = Vector3::zeros();
        let mut excursion = [[(0.0, 0.0); super::window::LAGS.len()]; 3];
        let mut structure = [[f64::NAN; super::window::LAGS.len()]; 3];
        for j in 0..3 {
            window[j] = self.hist[j].iter().sum();
            excursion[j] = self.windows[j].excursions();
            structure[j] = self.windows[j].structure();
            if self.hist[j].len() == HISTORY {
                self.hist[j].pop_front();
            }
            self.hist[j].push_back(e[j]);
            let w = &mut self.abs_e[j];
            let med = if w.len() >= RECEIVER_MIN {
                w.median()
            } else {
                f64::NAN
            };
            sigma[j] = if med.is_finite() {
                (med / 0.674_489_75).max(1e-3)
            } else {
                f64::NAN
            };
            w.push(e[j].abs());
            // A jump or a fault's drift does not teach the latency.
            if !(sigma[j].is_finite() && e[j].abs() <= 4.0 * sigma[j]) {
                pending = None;
            }
            // Clipped at 4σ: one jump (a step) cannot fire the CUSUM, a ramp of any rate
            // does within a few fixes.
            if sigma[j].is_finite() {
                let x = (e[j] / sigma[j]).clamp(-4.0, 4.0);
                self.up[j] = (self.up[j] + x - CUSUM_K).max(0.0);
                self.down[j] = (self.down[j] - x - CUSUM_K).max(0.0);
                let acc = |a: (f64, u32), stat: f64| {
                    if stat > 0.0 {
                        (a.0 + e[j], a.1 + 1)
                    } else {
                        (0.0, 0)
                    }
                };
                self.acc_up[j] = acc(self.acc_up[j], self.up[j]);
                self.acc_down[j] = acc(self.acc_down[j], self.down[j]);
                let window = self.windows[j].add(t, e[j], sigma[j]);
                // Against the INS's displacement (no velocity of the receiver's own) `e`
                // carries the INS's velocity error, correlated over tens of seconds — on
                // drive_0708, an accelerometer scale error while the car gathers speed: 7 cm/s
                // for 15 s at σ_e 3.7 cm — which a test built for white `e` reads as a ramp
                // (held out, the INS coasted 58 m off). There only the window test, whose
                // sums' spread is measured from the data, flags ramps.
                // The height the same way, and more so: the INS's vertical velocity is aided
                // there only by the heights and, through the pitch, the non-holonomic
                // constraint; with the up component held as a ramp it drifts unaided at the
                // rates of the ramps the hold is built for, and the fix never meets it again
                // (drive_0708 on positions alone with a simulated 60 s float stretch: held
                // from 210 s to the end, the height 22 m off). A jump of the height is still
                // held as a step, and watched (`InsWatch::vertical`).
                let window = window.filter(|_| own_velocity || j < 2);
                let fired = if own_velocity && self.up[j] > CUSUM_H {
                    Some((
                        self.acc_up[j].0,
                        f64::from(self.acc_up[j].1) * sigma[j] * sigma[j],
                    ))
                } else if own_velocity && self.down[j] > CUSUM_H {
                    Some((
                        self.acc_down[j].0,
                        f64::from(self.acc_down[j].1) * sigma[j] * sigma[j],
                    ))
                } else {
                    window
                };
                if let Some(drift) = fired {
                    ramp[j] = true;
                    onset[j] = Some(drift);
                    self.windows[j].hold_off();
                    self.up[j] = 0.0;
                    self.down[j] = 0.0;
                    self.acc_up[j] = (0.0, 0);
                    self.acc_down[j] = (0.0, 0);
                }
            }
        }
        if let Some(pair) = pending {
            if self.pairs.len() == HISTORY {
                self.pairs.pop_front();
            }
            self.pairs.push_back(pair);
        }
        // Until σ_e is known (the first fixes) the receiver says nothing.
        sigma.iter().all(|x| x.is_finite()).then_some(Consistency {
            e,
            sigma,
            ramp,
            onset,
            window,
            excursion,
            structure,
            ins_referenced: false,
        })
    }
}

#[cfg(test)]
mod consistency_tests {
    use super::*;

    #[test]
    fn steps_jump_once_and_ramps_accumulate() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut rc = ReceiverConsistency::default();
        let v = Vector3::new(10.0, 0.0, 0.0);
        let mut flagged = Vec::new();
        for k in 0..200 {
            let t = k as f64;
            let n: f64 = StandardNormal.sample(&mut rng);
            let noise = 0.3 * n;
            // A 0.5 m/s ramp on north from 120 s.
            let ramp = if k >= 120 { 0.5 * (t - 120.0) } else { 0.0 };
            let p = Vector3::new(10.0 * t, noise + ramp, 0.0);
            if let Some(c) = rc.step(t, &p, &v, 2.5, true) {
                if c.ramp[1] {
                    flagged.push(k);
                }
            }
        }
        assert!(flagged.iter().all(|&k| k >= 120), "{flagged:?}");
        assert!(flagged.first().is_some_and(|&k| k <= 150), "{flagged:?}");
    }

    /// Against the INS's displacement (no receiver velocity) `e` carries the INS's own
    /// velocity error, correlated over many fixes (here Gauss-Markov, 5 cm/s, τ 15 s, beside
    /// 3.7 cm of white displacement noise): the CUSUM, built for white `e`, takes it for ramps
    /// against the receiver's own velocity, and is not run against the INS's; there the window
    /// test, whose spread is measured from the same `e`, stays quiet — and still flags a 1 m/s
    /// ramp within 40 s (36 s here: each `e` clipped at 4σ_e, its sums rise over that
    /// spread slowly).
    #[test]
    fn a_correlated_ins_velocity_error_is_no_ramp_against_the_ins() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let run = |own: bool, ramp: f64| {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
            let mut rc = ReceiverConsistency::default();
            let v = Vector3::new(10.0, 0.0, 0.0);
            let (mut north, mut dv) = (0.0, 0.0);
            let a = (-1.0_f64 / 15.0).exp();
            let mut flagged = Vec::new();
            for k in 0..400 {
                let t = k as f64;
                let n: [f64; 2] = [
                    StandardNormal.sample(&mut rng),
                    StandardNormal.sample(&mut rng),
                ];
                dv = a * dv + 0.05 * (1.0 - a * a).sqrt() * n[0];
                north += 0.037 * n[1] + dv + if k >= 300 { ramp } else { 0.0 };
                let p = Vector3::new(10.0 * t, north, 0.0);
                if rc.step(t, &p, &v, 2.5, own).is_some_and(|c| c.ramp[1]) {
                    flagged.push(k);
                }
            }
            flagged
        };
        assert!(!run(true, 0.0).is_empty());
        assert!(run(false, 0.0).is_empty(), "{:?}", run(false, 0.0));
        assert!(
            run(false, 1.0)
                .first()
                .is_some_and(|&k| (300..340).contains(&k)),
            "{:?}",
            run(false, 1.0)
        );
    }
}
