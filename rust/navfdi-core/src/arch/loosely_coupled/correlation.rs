//! The GNSS position errors' correlation from the log itself (`position_correlation = "auto"`).
//!
//! A receiver's single-point or SBAS error wanders over tens of seconds; a filter that takes
//! its fixes as white follows the wander, and a slow ramp with it. Weighting each fix by what
//! it is worth (`checks::correlation_weight`) needs the errors' correlation time τ, which a
//! user rarely knows. Where the receiver gives its velocities (Doppler: independent of the
//! position errors), the log says it: the fixes' displacement over a lag `L` minus the
//! integral of the velocities over it is `e(t + L) − e(t)` plus the integral's own error, and
//! for a white part of σ_w and a first-order Gauss-Markov part of σ_g and τ its variance (the
//! structure function) is
//!
//! `D(L) = 2σ_w² + 2σ_g² (1 − e^(−L/τ)) + q L + c L²`
//!
//! where `q L` and `c L²` take the velocities' own error (white, and a bias), which grows
//! without bound where the Gauss-Markov part levels off. `D` is read robustly per lag (the
//! median of the squared differences over the χ²₁ median 0.4549: bursts and faults a minority
//! of the pairs move it little) and the model fitted by non-negative least squares on relative
//! residuals over a grid of τ. The correlated part counts only where it is at least a quarter
//! of the white part's variance and τ at least two fix intervals (shorter, the fixes are white
//! at their rate) and within the grid ([`TAU_MAX`]), and where its σ is at most
//! [`STATED_MAX`] times the σ the receiver states: on RTK fixes (σ 1 cm) the velocities'
//! integral drifts by decimetres over a minute, and a τ read from that would weight centimetre
//! fixes as decimetre ones. The two components are fitted together and each alone, and all
//! three fits must show it (a velocity bias drifts one component, and the pooled median of two
//! differently drifting ones passes for a wander). A receiver whose velocities come out of the
//! same navigation filter as its positions carries its wander in both: `p − ∫v` cancels it, and
//! the log reads white (`comma_lc`'s u-blox).

/// The longest lag (s) the structure function is read at.
pub const LAG_MAX: f64 = 300.0;
/// The longest correlation time (s) fitted: a third of [`LAG_MAX`] (beyond it the
/// Gauss-Markov part's rise is not told from the velocities' drift).
pub const TAU_MAX: f64 = 100.0;
/// Pairs of fixes needed at a lag for it to count.
const PAIRS_MIN: usize = 30;
/// Lags needed for a fit.
const LAGS_MIN: usize = 8;
/// The correlated part counts where its variance is at least this fraction of the white part's.
const CORRELATED_MIN: f64 = 0.25;
/// The largest correlated σ, in multiples of the σ the receiver states, taken as its fixes'
/// (a receiver may understate its σ threefold; a wander beyond five times it is the
/// velocities' drift).
pub const STATED_MAX: f64 = 5.0;
/// Median of χ²₁.
const CHI2_1_MEDIAN: f64 = 0.454_936_423_119_572_8;

/// A channel's horizontal position error model (σ per component), read from its fixes and
/// velocities ([`estimate`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorModel {
    /// σ (m) of the white part.
    pub white: f64,
    /// σ (m) of the first-order Gauss-Markov part (0: white errors).
    pub correlated: f64,
    /// Its correlation time τ (s; 0 where `correlated` is 0).
    pub tau: f64,
}

impl ErrorModel {
    /// The factor on a fix's position variance in the update, fixes `dt` s apart: the white
    /// part counts once, the correlated part as the fraction `(1 − ρ)/(1 + ρ)` of an
    /// independent fix (`ρ = e^(−dt/τ)`), so `(σ_w² + σ_g² coth(dt/2τ)) / (σ_w² + σ_g²)`
    /// (1 for white errors).
    pub fn weight(&self, dt: f64) -> f64 {
        let (w2, g2) = (self.white * self.white, self.correlated * self.correlated);
        if !(g2 > 0.0 && self.tau > 0.0 && dt > 0.0) {
            return 1.0;
        }
        (w2 + g2 * super::checks::correlation_weight(dt, self.tau)) / (w2 + g2)
    }
}

/// The error model of fixes `(t, [east, north], [v_east, v_north])` (s, m, m/s; in time order,
/// repeated fixes left out by the caller), nominally `interval` s apart, stating a horizontal σ
/// of `stated` m per component (their median): pairs are taken only where every fix between
/// is present (a gap longer than 1.5 intervals breaks the track).
/// The two components are read together and each alone (a velocity bias drifts one of them):
/// the errors are correlated where all three fits say so, with the pooled fit's σ and τ;
/// else white. None where
/// the log is too short to say (fewer than [`LAGS_MIN`] lags with [`PAIRS_MIN`] pairs each)
/// or the differences are all zero.
pub fn estimate(
    fixes: &[(f64, [f64; 2], [f64; 2])],
    interval: f64,
    stated: f64,
) -> Option<ErrorModel> {
    if !(interval > 0.0) || fixes.len() < 2 * PAIRS_MIN {
        return None;
    }
    // The velocities' integral (trapezoid) and the contiguous stretch each fix belongs to.
    let n = fixes.len();
    let mut integral = vec![[0.0f64; 2]; n];
    let mut stretch = vec![0usize; n];
    for k in 1..n {
        let (t0, _, v0) = fixes[k - 1];
        let (t1, _, v1) = fixes[k];
        let dt = t1 - t0;
        stretch[k] = stretch[k - 1] + usize::from(!(dt > 0.0 && dt <= 1.5 * interval));
        integral[k] = [0, 1].map(|j| integral[k - 1][j] + 0.5 * (v0[j] + v1[j]) * dt);
    }
    let span = fixes[n - 1].0 - fixes[0].0;
    let longest = LAG_MAX.min(span / 3.0);
    // Lags in fix intervals, geometrically spaced from one interval to the longest.
    let mut lags: Vec<usize> = Vec::new();
    let steps = 24;
    for i in 0..steps {
        let s = interval * (longest / interval).powf(i as f64 / (steps - 1) as f64);
        let l = (s / interval).round().max(1.0) as usize;
        if lags.last() != Some(&l) {
            lags.push(l);
        }
    }
    // Both components pooled, then each alone (a velocity bias drifts one of them): the
    // correlation counts where every one of the three fits shows it.
    let mut models: Vec<ErrorModel> = Vec::with_capacity(3);
    for comps in [&[0usize, 1][..], &[0][..], &[1][..]] {
        let mut points: Vec<(f64, f64)> = Vec::new();
        let mut sq: Vec<f64> = Vec::new();
        for &l in &lags {
            sq.clear();
            for k in 0..n.saturating_sub(l) {
                if stretch[k + l] != stretch[k] {
                    continue;
                }
                for &j in comps {
                    let u =
                        (fixes[k + l].1[j] - fixes[k].1[j]) - (integral[k + l][j] - integral[k][j]);
                    if u.is_finite() {
                        sq.push(u * u);
                    }
                }
            }
            if sq.len() >= PAIRS_MIN * comps.len() {
                let d = crate::stats::median_of(&mut sq) / CHI2_1_MEDIAN;
                if d > 0.0 {
                    points.push((l as f64 * interval, d));
                }
            }
        }
        if points.len() < LAGS_MIN {
            return None;
        }
        let (a, b, tau) = fit(&points)?;
        let correlated = (0.5 * b).sqrt();
        let plausible = correlated <= STATED_MAX * stated;
        models.push(
            if b >= CORRELATED_MIN * a && b > 0.0 && tau >= 2.0 * interval && plausible {
                ErrorModel {
                    white: (0.5 * a).sqrt(),
                    correlated,
                    tau,
                }
            } else {
                ErrorModel {
                    white: (0.5 * (a + b)).sqrt(),
                    correlated: 0.0,
                    tau: 0.0,
                }
            },
        );
    }
    let pooled = models[0];
    Some(if models.iter().all(|m| m.correlated > 0.0) {
        pooled
    } else {
        ErrorModel {
            white: pooled.white.hypot(pooled.correlated),
            correlated: 0.0,
            tau: 0.0,
        }
    })
}

/// A given correlation time `tau` (s) on a log of positions alone (`alone`: no velocity
/// channel) is refused; "auto" (None) is not: it finds nothing to read there and leaves the
/// fixes white. Measured on simulated σ 2 m fixes at 4 Hz with τ 30 s: without velocities the
/// INS cannot carry the position between fixes weighted that little (10–20 m steps left out
/// at their first fix 1.00 → 0.80, false exclusions 0.0056 → 0.0150 per clean epoch;
/// docs/meter_fde.md).
pub fn positions_alone(tau: Option<f64>, alone: bool) -> crate::error::Result<()> {
    match tau {
        Some(tau) if alone && tau > 0.0 => Err(crate::error::Error::Invalid(format!(
            "loosely_coupled.position_correlation = {tau} s needs the receiver's velocities (a gnss or gnss_velocity sensor): on positions alone, weighting the fixes for their correlation lets the INS drift; leave it at 0 s"
        ))),
        _ => Ok(()),
    }
}

/// A channel's error model from the log (`position_correlation = "auto"`): its fixes at the
/// epochs `t` (s) — `pos(k)` east, north, up (m) in `origin`'s local coordinates, None where
/// none — with the receiver's velocity `vel(k)` (east, north, m/s; None: not given) and the σ
/// it states `stated(k)` (m); fixes that repeat the one before them are left out.
/// The velocities are turned into the local map's rates (its east and north scales are the
/// origin's: over a drive of kilometres a true metre per second and a map one differ by parts
/// in 10⁴, metres over minutes). None without velocities or where [`estimate`] cannot say.
pub fn from_log(
    t: &[f64],
    pos: impl Fn(usize) -> Option<nalgebra::Vector3<f64>>,
    vel: impl Fn(usize) -> Option<[f64; 2]>,
    stated: impl Fn(usize) -> f64,
    origin: &crate::stream::Nominal,
    interval: f64,
) -> Option<ErrorModel> {
    use crate::ins::earth::{r_meridian, r_normal};
    let (rm0, rn0) = (
        r_meridian(origin.lat) + origin.h,
        r_normal(origin.lat) + origin.h,
    );
    let repeated = super::super::inertial::repeated_fixes(t.len(), &pos);
    let mut sig: Vec<f64> = Vec::new();
    let fixes: Vec<(f64, [f64; 2], [f64; 2])> = (0..t.len())
        .filter(|&k| !repeated[k])
        .filter_map(|k| {
            let p = pos(k)?;
            let v = vel(k)?;
            let at = origin.from_enu(&p);
            let (rm, rn) = (r_meridian(at.lat) + at.h, r_normal(at.lat) + at.h);
            let map = [
                v[0] * rn0 * origin.lat.cos() / (rn * at.lat.cos()),
                v[1] * rm0 / rm,
            ];
            let s = stated(k);
            if s.is_finite() && s > 0.0 {
                sig.push(s);
            }
            Some((t[k], [p.x, p.y], map))
        })
        .collect();
    if sig.is_empty() {
        return None;
    }
    estimate(&fixes, interval, crate::stats::median_of(&mut sig))
}

/// What the position channel's weighting records ([`weights`]): the model used
/// (`"auto"`), or one the log shows while the fixes are taken as white (a suggestion).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Recorded {
    /// `"auto"`: σ_w, σ_g (m), τ (s) and the factor used (NaN, NaN, NaN, 1: not read).
    pub used: Option<[f64; 4]>,
    /// Fixes taken as white (τ 0) where the log shows a correlation: σ_w, σ_g, τ and the
    /// factor `"auto"` would use.
    pub unused: Option<[f64; 4]>,
}

/// Per channel (fixes `interval` s apart) the factor on its fixes' position variance in the
/// update, and what the record says of it: with a correlation time `tau` given (s; 0: white)
/// `(1 + ρ)/(1 − ρ)` — and, at 0, the position channel `pos_aid`'s model where the log shows a
/// correlation ([`Recorded::unused`]); with None (`"auto"`) the channel's error model
/// `model_of(a)` (None: not a position channel; Some(None): the log could not say, white)
/// and, recorded, the position channel's σ_w, σ_g, τ and factor ([`Recorded::used`]).
pub fn weights(
    tau: Option<f64>,
    interval: &[f64],
    pos_aid: usize,
    model_of: impl Fn(usize) -> Option<Option<ErrorModel>>,
) -> (Vec<f64>, Recorded) {
    let row = |m: ErrorModel, w: f64| [m.white, m.correlated, m.tau, w];
    let Some(auto) = tau
        .is_none()
        .then(|| (0..interval.len()).map(&model_of).collect::<Vec<_>>())
    else {
        let tau = tau.unwrap_or(0.0);
        let w = interval
            .iter()
            .map(|&dt| super::checks::correlation_weight(dt, tau));
        let unused = (tau == 0.0)
            .then(|| model_of(pos_aid).flatten())
            .flatten()
            .filter(|m| m.correlated > 0.0)
            .map(|m| row(m, m.weight(interval[pos_aid])));
        return (w.collect(), Recorded { used: None, unused });
    };
    let w: Vec<f64> = (interval.iter().zip(&auto))
        .map(|(&dt, m)| m.flatten().map_or(1.0, |m| m.weight(dt)))
        .collect();
    let nan = [f64::NAN, f64::NAN, f64::NAN, 1.0];
    let used = auto[pos_aid].flatten().map_or(nan, |m| row(m, w[pos_aid]));
    (
        w,
        Recorded {
            used: Some(used),
            unused: None,
        },
    )
}

/// Fit `D(L) = a + b (1 − e^(−L/τ)) + q L + c L²` (a, b, q, c ≥ 0) to `points` (L s, D m²) by
/// least squares on relative residuals, τ on a geometric grid from the shortest lag over 2 to
/// [`TAU_MAX`]: per τ every subset of the four terms is solved and the best non-negative
/// solution kept. Returns (a, b, τ).
fn fit(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let lo = 0.5 * points[0].0;
    let grid = 120;
    let mut best: Option<(f64, [f64; 4], f64)> = None;
    for g in 0..grid {
        let tau = lo * (TAU_MAX / lo).powf(g as f64 / (grid - 1) as f64);
        let basis = |l: f64| [1.0, 1.0 - (-l / tau).exp(), l, l * l];
        for mask in 1u8..16 {
            let idx: Vec<usize> = (0..4).filter(|i| mask & (1 << i) != 0).collect();
            let m = idx.len();
            // Normal equations of the weighted problem (rows scaled by 1/D).
            let mut ata = nalgebra::DMatrix::<f64>::zeros(m, m);
            let mut atb = nalgebra::DVector::<f64>::zeros(m);
            for &(l, d) in points {
                let row = basis(l);
                for (r, &i) in idx.iter().enumerate() {
                    atb[r] += row[i] / d;
                    for (c, &i2) in idx.iter().enumerate() {
                        ata[(r, c)] += row[i] * row[i2] / (d * d);
                    }
                }
            }
            let Some(x) = ata.cholesky().map(|ch| ch.solve(&atb)) else {
                continue;
            };
            if x.iter().any(|v| !(*v >= 0.0)) {
                continue;
            }
            let mut coef = [0.0; 4];
            for (r, &i) in idx.iter().enumerate() {
                coef[i] = x[r];
            }
            let res: f64 = points
                .iter()
                .map(|&(l, d)| {
                    let row = basis(l);
                    let f: f64 = (0..4).map(|i| row[i] * coef[i]).sum();
                    (f / d - 1.0).powi(2)
                })
                .sum();
            if best.as_ref().is_none_or(|b| res < b.0 - 1e-15) {
                best = Some((res, coef, tau));
            }
        }
    }
    best.map(|(_, c, tau)| (c[0], c[1], tau))
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

    /// Fixes of a car turning at 12 m/s, `secs` s at `interval`, with white errors of σ
    /// `white`, Gauss-Markov errors of σ `gm` and τ `tau`, velocities with white noise of σ
    /// `sv` and a bias `bias` (m/s).
    #[allow(clippy::too_many_arguments)]
    fn log(
        secs: f64,
        interval: f64,
        white: f64,
        gm: f64,
        tau: f64,
        sv: f64,
        bias: f64,
        seed: u64,
    ) -> Vec<(f64, [f64; 2], [f64; 2])> {
        let mut g = gauss(seed);
        let phi = if tau > 0.0 {
            (-interval / tau).exp()
        } else {
            0.0
        };
        let mut e = [gm * g(), gm * g()];
        let n = (secs / interval) as usize;
        (0..n)
            .map(|k| {
                let t = k as f64 * interval;
                let w = 0.02;
                let p = [600.0 * (w * t).sin(), 600.0 * (1.0 - (w * t).cos())];
                let v = [12.0 * (w * t).cos(), 12.0 * (w * t).sin()];
                if k > 0 {
                    for x in e.iter_mut() {
                        *x = phi * *x + gm * (1.0 - phi * phi).sqrt() * g();
                    }
                }
                (
                    t,
                    [p[0] + e[0] + white * g(), p[1] + e[1] + white * g()],
                    [v[0] + bias + sv * g(), v[1] + sv * g()],
                )
            })
            .collect()
    }

    #[test]
    fn the_correlation_time_is_read_from_fixes_and_velocities() {
        // σ_g 2 m, τ 30 s, white 0.3 m at 1 Hz over 20 minutes: τ within a factor 2 (what the
        // weighting tolerates: docs/meter_fde.md, a τ of 15 or 60 s for 30 s costs little).
        for seed in 1..4 {
            let m = estimate(&log(1200.0, 1.0, 0.3, 2.0, 30.0, 0.05, 0.0, seed), 1.0, 2.0).unwrap();
            assert!((15.0..60.0).contains(&m.tau), "{seed}: {m:?}");
            assert!((1.5..2.6).contains(&m.correlated), "{seed}: {m:?}");
            assert!(m.white < 0.6, "{seed}: {m:?}");
            // Worth about a 40th to a 90th of an independent fix.
            assert!((25.0..120.0).contains(&m.weight(1.0)), "{seed}: {m:?}");
        }
        // τ 10 s with white 1 m at 5 Hz.
        let m = estimate(&log(900.0, 0.2, 1.0, 2.0, 10.0, 0.05, 0.0, 7), 0.2, 2.2).unwrap();
        assert!((6.0..15.0).contains(&m.tau), "{m:?}");
    }

    #[test]
    fn white_fixes_and_drifting_velocities_are_not_a_correlation() {
        // White fixes: no correlated part, weight 1.
        for seed in 1..4 {
            let m = estimate(&log(1200.0, 1.0, 1.5, 0.0, 0.0, 0.05, 0.0, seed), 1.0, 1.5).unwrap();
            assert_eq!(m.weight(1.0), 1.0, "{seed}: {m:?}");
            assert!((1.3..1.7).contains(&m.white), "{seed}: {m:?}");
        }
        // RTK-like fixes (1 cm white) with velocities of 4 cm/s noise and a 1 cm/s bias: the
        // integral drifts by metres, the fixes do not wander.
        for seed in 1..4 {
            let m = estimate(
                &log(600.0, 0.25, 0.01, 0.0, 0.0, 0.04, 0.01, seed),
                0.25,
                0.01,
            )
            .unwrap();
            assert_eq!(m.weight(0.25), 1.0, "{seed}: {m:?}");
        }
    }

    #[test]
    fn a_log_too_short_or_broken_says_nothing() {
        assert!(estimate(&log(40.0, 1.0, 1.0, 2.0, 30.0, 0.05, 0.0, 1), 1.0, 2.0).is_none());
        assert!(estimate(&[], 1.0, 1.0).is_none());
        let fixes = log(600.0, 1.0, 1.0, 2.0, 30.0, 0.05, 0.0, 1);
        assert!(estimate(&fixes, 0.0, 1.0).is_none());
        // Every fix 3 intervals from the next: no pairs within a stretch.
        let sparse: Vec<_> = fixes.iter().step_by(3).copied().collect();
        assert!(estimate(&sparse, 1.0, 1.0).is_none());
        // Standing still: every difference zero.
        let still: Vec<_> = (0..600).map(|k| (k as f64, [0.0; 2], [0.0; 2])).collect();
        assert!(estimate(&still, 1.0, 1.0).is_none());
    }
}
