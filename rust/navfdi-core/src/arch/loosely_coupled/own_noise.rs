//! A position channel's own noise from one fix to the next, against the σ it records.
//!
//! A receiver that writes σ of 0.6 m but scatters by 2 m from fix to fix (white) has its
//! fixes tested at a third of their noise: most fail, the noise scale ([`super::noise_scale`])
//! learns only from fixes used as measured and stays at 1, and the INS runs on without them
//! (simulated positions-only logs at 1 Hz: 13–46 m RMS with FDE, 1.4–5.9 m without). The fixes
//! themselves say how noisy they are: the third difference `p(k) − 3p(k−1) + 3p(k−2) − p(k−3)`
//! of white errors of σ has σ √20 per component, and a step or a burst moves its median little.
//! A vehicle's own motion adds to it little (a second difference carries the acceleration — a
//! car's 1.5 m/s² is 1.5 m at 1 Hz, three times a 0.5 m receiver's noise — a third one only its
//! change: 0.15 m in that turn at 0.1 rad/s), and the INS's mechanised displacement between the
//! fixes takes out even that — where the IMU's mounting is right: a wrong one adds its own
//! misfit. Both are measured, and the smaller decides ([`OwnNoise::ratio`]): fixes whose
//! scatter is that of their σ around their own track or around the INS's (a right receiver, or
//! a wrong mounting under honest fixes) give a ratio near 1 or below.

use super::super::inertial::{repeated_fixes, velocity_from_positions};
use super::diverge::{Differences, Jumps};
use super::noise_scale::{Rolling, OWN_SCALE};
use nalgebra::Vector3;

/// A channel's third differences (the last [`OWN_WINDOW`] sizes).
type ThirdDifferences = Differences<3, OWN_WINDOW>;

/// Record the third difference the fix `p` (east, north, m) at `t` (s) makes in `w`, the fixes
/// `interval` s apart.
fn record(w: &mut ThirdDifferences, t: f64, p: [f64; 2], interval: f64) {
    if let Some(d) = w.push(t, p, interval) {
        let size = d[0].hypot(d[1]);
        if size.is_finite() {
            w.record(size);
        }
    }
}

/// Third differences the own noise is measured over.
pub const OWN_WINDOW: usize = 120;
/// Third differences needed before the own noise is measured.
pub const OWN_MIN: usize = 20;

/// A position channel's fixes: their third differences, raw and against the INS's
/// mechanised track, and the σ they record.
#[derive(Debug, Clone, Default)]
pub struct OwnNoise {
    raw: ThirdDifferences,
    ins: ThirdDifferences,
    stated: Rolling<OWN_WINDOW>,
    /// The INS antenna's mechanised track (east, north, m): its displacements from epoch to
    /// epoch without the updates' corrections, summed.
    track: [f64; 2],
    /// The INS antenna after the last epoch's updates (east, north, m).
    post: Option<[f64; 2]>,
}

impl OwnNoise {
    /// The INS antenna at an epoch after the mechanisation, before any update (east, north,
    /// m): the track moves by its displacement since the last epoch's updates.
    pub fn mechanised(&mut self, prior: [f64; 2]) {
        if let Some(p) = self.post {
            self.track = [0, 1].map(|j| self.track[j] + prior[j] - p[j]);
        }
    }

    /// The INS antenna after an epoch's updates (east, north, m).
    pub fn updated(&mut self, post: [f64; 2]) {
        self.post = Some(post);
    }

    /// The fix `p` (east, north, m) at `t` (s) with its horizontal σ `stated` (m per component,
    /// as recorded), the fixes `interval` s apart; `navigated`: the INS runs (after the
    /// alignment), and the fix is also taken against its track.
    pub fn push(&mut self, t: f64, p: [f64; 2], stated: f64, interval: f64, navigated: bool) {
        record(&mut self.raw, t, p, interval);
        if navigated {
            let rel = [p[0] - self.track[0], p[1] - self.track[1]];
            record(&mut self.ins, t, rel, interval);
        }
        if stated.is_finite() && stated > 0.0 {
            self.stated.push(stated);
        }
    }

    /// The fixes' own σ (m per component: the smaller of their third differences' σ, raw and
    /// against the INS's track, over √20; the raw ones' alone until [`OWN_MIN`] are against the
    /// track) over the median σ they record; None with fewer than [`OWN_MIN`] raw ones. The
    /// raw ones start with the log, before the alignment: a receiver is known for what it is
    /// when the INS starts.
    pub fn ratio(&self) -> Option<f64> {
        let raw = self.raw.sigma(OWN_MIN)?;
        let own = self.ins.sigma(OWN_MIN).map_or(raw, |s| s.min(raw)) / 20f64.sqrt();
        let stated = self.stated.median();
        (stated > 0.0).then(|| own / stated)
    }
}

/// σ per component (m) of a channel's fixes `(t, [east, north])` (s, m; fixes that repeat
/// the one before them left out) from their own scatter over the whole log: the median size
/// of their third differences (the fixes `interval` s apart) over 1.1774 √20, as
/// [`OwnNoise::ratio`]'s raw one; None with fewer than [`OWN_MIN`].
pub fn log_sigma(fixes: impl IntoIterator<Item = (f64, [f64; 2])>, interval: f64) -> Option<f64> {
    let mut w = Differences::<3, 1>::default();
    let mut sizes: Vec<f64> = fixes
        .into_iter()
        .filter_map(|(t, p)| w.push(t, p, interval))
        .map(|d| d[0].hypot(d[1]))
        .filter(|s| s.is_finite())
        .collect();
    (sizes.len() >= OWN_MIN)
        .then(|| crate::stats::median_of(&mut sizes) / crate::stats::RAYLEIGH_MEDIAN / 20f64.sqrt())
}

/// The alignment's velocities on a log of positions only: the fixes `pos` (east, north, up,
/// m; None: no fix) differenced over about 2 s, or two fix intervals if longer
/// ([`velocity_from_positions`]), none across a jump of the fixes ([`Jumps`]); their σ from
/// the fixes' horizontal σ `sig_p` (m) as recorded or, where larger by [`OWN_SCALE`], as
/// their own scatter over the log says ([`log_sigma`]): a receiver that writes 0.56 m and
/// scatters by 1.1 m (white) moves 2 m/s between two fixes 2 s apart now and then while the
/// car stands, 5σ of the velocity its σ gives, and the alignment read the heading from it
/// (simulated at 10 Hz: aligned at rest 19 s before the car moved off, about 50° off, 9.9 m
/// RMS against 2.3 m without FDE).
pub fn alignment_velocities(
    t: &[f64],
    pos: impl Fn(usize) -> Option<Vector3<f64>>,
    sig_p: impl Fn(usize) -> f64,
    interval: f64,
) -> Vec<Option<(Vector3<f64>, f64)>> {
    let mut jumps = Jumps::new(interval);
    let jumped: Vec<bool> = (0..t.len())
        .map(|k| pos(k).is_some_and(|p| jumps.push(t[k], [p.x, p.y]).is_some()))
        .collect();
    let repeated = repeated_fixes(t.len(), &pos);
    let own = log_sigma(
        (0..t.len())
            .filter(|&k| !repeated[k])
            .filter_map(|k| pos(k).map(|p| (t[k], [p.x, p.y]))),
        interval,
    )
    .unwrap_or(0.0);
    let sig = |k: usize| {
        let stated = sig_p(k);
        if own > OWN_SCALE * stated {
            own
        } else {
            stated
        }
    };
    velocity_from_positions(t, &pos, sig, |k| jumped[k], interval.max(1.0), interval)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A normal deviate stream (the crates' ChaCha and standard normal, seeded).
    fn gauss(seed: u64) -> impl FnMut() -> f64 {
        use rand::SeedableRng;
        use rand_distr::{Distribution, StandardNormal};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        move || StandardNormal.sample(&mut rng)
    }

    /// A car turning (1.5 m/s² of lateral acceleration at 1 Hz) with fixes of white σ `own`
    /// that record `stated`; the INS mechanises the truth plus `ins_misfit` m/s² of a wrong
    /// mounting along the acceleration. The ratio after 200 fixes.
    fn ratio(own: f64, stated: f64, ins_misfit: f64, seed: u64) -> f64 {
        let mut g = gauss(seed);
        let mut n = OwnNoise::default();
        let (w, r) = (0.1f64, 15.0); // 0.1 rad/s on a 15 m radius: 1.5 m/s²
        let truth = |t: f64| [r * (w * t).cos(), r * (w * t).sin()];
        let mut ins = truth(0.0);
        for k in 0..200 {
            let t = k as f64;
            if k > 0 {
                // The INS's displacement: the truth's, and the misfit's along −r̂ (½ a t²).
                let (a, b) = (truth(t - 1.0), truth(t));
                let u = [-a[0] / r, -a[1] / r];
                let prior = [0, 1].map(|j| ins[j] + b[j] - a[j] + 0.5 * ins_misfit * u[j]);
                n.mechanised(prior);
                // An update pulls the INS halfway to the truth (not part of the track).
                ins = [0, 1].map(|j| 0.5 * (prior[j] + b[j]));
            }
            n.updated(ins);
            let p = truth(t);
            n.push(t, [p[0] + own * g(), p[1] + own * g()], stated, 1.0, true);
        }
        n.ratio().unwrap()
    }

    #[test]
    fn the_log_says_its_fixes_noise_and_the_alignment_takes_it_where_larger() {
        // 300 fixes at 1 Hz of a car at 10 m/s north, 2 m of white noise per component.
        let mut g = gauss(11);
        let t: Vec<f64> = (0..300).map(f64::from).collect();
        let pos: Vec<Vector3<f64>> = t
            .iter()
            .map(|&x| Vector3::new(2.0 * g(), 10.0 * x + 2.0 * g(), 0.0))
            .collect();
        let own = log_sigma(
            t.iter()
                .map(|&x| (x, [pos[x as usize].x, pos[x as usize].y])),
            1.0,
        );
        assert!((own.unwrap() - 2.0).abs() < 0.3, "{own:?}");
        // Velocities over 2 s: written 0.6 m gives σ 0.42 m/s; the fixes' own 2 m, 1.41 m/s.
        let v = alignment_velocities(&t, |k| Some(pos[k]), |_| 0.6, 1.0);
        let s = v[100].unwrap().1;
        assert!((s - own.unwrap() * 2f64.sqrt() / 2.0).abs() < 1e-9, "{s}");
        // Written honestly (or within 1.5x of the scatter), the written σ is kept.
        let v = alignment_velocities(&t, |k| Some(pos[k]), |_| 1.5, 1.0);
        assert!((v[100].unwrap().1 - 1.5 * 2f64.sqrt() / 2.0).abs() < 1e-9);
        // Too few fixes: no own σ.
        assert!(log_sigma((0..OWN_MIN).map(|k| (k as f64, [0.0, 0.0])), 1.0).is_none());
    }

    #[test]
    fn optimistic_fixes_show_their_own_noise_and_honest_ones_do_not() {
        // 2 m of white noise recorded as 0.6 m: 3.3 within the median's scatter.
        let r = ratio(2.0, 0.6, 0.0, 3);
        assert!((r - 2.0 / 0.6).abs() < 0.6, "{r}");
        // Honest σ: near 1, however the car turns.
        let r = ratio(2.0, 2.0, 0.0, 4);
        assert!((0.8..1.2).contains(&r), "{r}");
        // RTK (1 cm) on a turning car: the raw third differences are the turn's (0.15 m), the
        // INS's track takes it out.
        let r = ratio(0.01, 0.01, 0.0, 5);
        assert!(r < 1.3, "{r}");
        // A wrong mounting under honest fixes: the INS's misfit, not the fixes'.
        let r = ratio(2.0, 2.0, 3.0, 6);
        assert!(r < 1.3, "{r}");
        // 0.5 m honest fixes at 1 Hz in the turn, the INS with a wrong mounting: the raw
        // second differences would be the turn's 1.5 m (a ratio of 1.6), the third ones are not.
        let r = ratio(0.5, 0.5, 3.0, 7);
        assert!(r < 1.3, "{r}");
        // Too few fixes: no ratio.
        let mut n = OwnNoise::default();
        for k in 0..OWN_MIN + 2 {
            n.push(k as f64, [0.0, 0.0], 1.0, 1.0, false);
        }
        assert!(n.ratio().is_none());
        // Before the INS runs the raw differences alone: at rest, the fixes' noise.
        let mut g = gauss(8);
        let mut n = OwnNoise::default();
        for k in 0..60 {
            n.push(k as f64, [2.0 * g(), 2.0 * g()], 0.6, 1.0, false);
        }
        let r = n.ratio().unwrap();
        assert!((r - 2.0 / 0.6).abs() < 0.8, "{r}");
    }
}
