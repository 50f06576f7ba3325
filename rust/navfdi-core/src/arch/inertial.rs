//! What the architectures on a strapdown INS share: the IMU log in body axes on the corrected
//! time line, the initial alignment, and the mechanisation (with the error filter's
//! propagation) from one record epoch to the next.
//!
//! Alignment: levelling and gyro biases from the mean IMU output over the last static stretch
//! (GNSS speed below `static_speed`) before the first GNSS velocity above `speed`; heading
//! from that velocity's course (or given); position and velocity from that epoch's fix. The
//! static mean rate holds the Earth's rotation as well as the bias: it is removed with the
//! attitude at rest.

use crate::error::{Error, Result};
use crate::ins::earth;
use crate::ins::error_filter::{ErrorFilter, BA, BG, PHI, R, V};
use crate::ins::strapdown::skew;
use crate::ins::strapdown::{level, mechanise, mounting, Increment, NavState};
use crate::record::RunRecord;
use crate::spec::AlignmentSpec;
use crate::stream::Streams;
use crate::stream::{ImuSamples, Nominal};
use nalgebra::{UnitQuaternion, Vector3};

/// The IMU log in body axes: sample times with the time offset applied (s), angular rate
/// (rad/s) and specific force (m/s²).
pub struct BodyImu {
    /// Sample times (s from the run's time 0, offset applied).
    pub t: Vec<f64>,
    /// Angular rate per sample (rad/s, body axes).
    pub gyro: Vec<Vector3<f64>>,
    /// Specific force per sample (m/s², body axes).
    pub acc: Vec<Vector3<f64>>,
    /// The intervals between samples that are gaps (samples missing), in time order.
    pub gaps: Vec<ImuGap>,
}

/// An interval between two IMU samples longer than [`GAP_FACTOR`] times the log's median
/// interval: samples are missing, and the mechanisation bridges it with the mean of the two
/// samples either side. That mean's error — each sample's own scatter (vibration, noise),
/// not averaged over the missing samples — acts over the whole gap, so the velocity and
/// attitude errors it leaves grow as `Δ · σ/√2` (Δ the gap, σ the samples' scatter) instead
/// of the white-noise density's `N √Δ`. The error filter adds the difference, per body
/// axis, as extra white-noise variance per second over the gap.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImuGap {
    /// Index of the sample that ends the gap.
    pub i: usize,
    /// Specific-force variance per second of the gap, `Δ σ_f² / 2` ((m/s²)² s, body axes).
    pub acc_rate: Vector3<f64>,
    /// Angular-rate variance per second of the gap, `Δ σ_ω² / 2` ((rad/s)² s, body axes).
    pub gyro_rate: Vector3<f64>,
}

/// An interval is a gap where it exceeds this many times the log's median interval.
pub const GAP_FACTOR: f64 = 2.0;

/// Samples each side of a gap whose scatter is taken for the samples' error.
pub const GAP_SAMPLES: usize = 10;

/// The gaps of an IMU log (times `t` in s, increasing; rates and forces per sample): every
/// interval longer than [`GAP_FACTOR`] times the median one, with the scatter (variance
/// about their mean, per axis) of up to [`GAP_SAMPLES`] samples either side of it; and every
/// interval in or beside a run of `clipped` samples (at the sensor's full scale,
/// [`crate::ins::clip`]; empty: none), which are kept as a bound on the motion but whose
/// excess beyond the range is as unknown as a missing sample's: the run's span from the
/// sample before it to the one after takes the gap's noise, spread over its intervals.
pub fn imu_gaps(
    t: &[f64],
    gyro: &[Vector3<f64>],
    acc: &[Vector3<f64>],
    clipped: &[bool],
) -> Vec<ImuGap> {
    let n = t.len();
    if n < 3 {
        return Vec::new();
    }
    let mut dt: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let limit = GAP_FACTOR * crate::stats::median_of(&mut dt);
    if !(limit > 0.0) {
        return Vec::new();
    }
    let scatter = |x: &[Vector3<f64>]| -> Vector3<f64> {
        let mean = x.iter().sum::<Vector3<f64>>() / x.len() as f64;
        x.iter()
            .map(|v| (v - mean).component_mul(&(v - mean)))
            .sum::<Vector3<f64>>()
            / (x.len() as f64 - 1.0)
    };
    // The noise of the intervals (a, b] (interval i runs from sample i − 1 to i) whose
    // samples' scatter is taken from around them: one gap of their whole span.
    let gap = |a: usize, b: usize| {
        let lo = (a + 1).saturating_sub(GAP_SAMPLES);
        let hi = (b + GAP_SAMPLES).min(n);
        let span = t[b] - t[a];
        (
            scatter(&acc[lo..hi]) * (span / 2.0),
            scatter(&gyro[lo..hi]) * (span / 2.0),
        )
    };
    let mut out: Vec<ImuGap> = Vec::new();
    let mut put =
        |i: usize, (acc_rate, gyro_rate): (Vector3<f64>, Vector3<f64>)| match out.last_mut() {
            Some(g) if g.i == i => {
                g.acc_rate = g.acc_rate.sup(&acc_rate);
                g.gyro_rate = g.gyro_rate.sup(&gyro_rate);
            }
            _ => out.push(ImuGap {
                i,
                acc_rate,
                gyro_rate,
            }),
        };
    let mut i = 1;
    while i < n {
        if clipped.get(i).copied().unwrap_or(false) || clipped.get(i - 1).copied().unwrap_or(false)
        {
            // A run of clipped samples from the interval ending at i: to the first sample after it.
            let mut j = i;
            while j + 1 < n && clipped.get(j).copied().unwrap_or(false) {
                j += 1;
            }
            let noise = gap(i - 1, j);
            for k in i..=j {
                if t[k] - t[k - 1] > limit {
                    put(k, gap(k - 1, k));
                }
                put(k, noise);
            }
            i = j + 1;
        } else {
            if t[i] - t[i - 1] > limit {
                put(i, gap(i - 1, i));
            }
            i += 1;
        }
    }
    out
}

impl BodyImu {
    /// The samples of `imu` rotated by the mounting roll, pitch, yaw `mount` (rad) and shifted
    /// by `time_offset` (s); an error with fewer than two samples.
    pub fn new(imu: &ImuSamples, mount: [f64; 3], time_offset: f64) -> Result<Self> {
        let m = mounting(mount[0], mount[1], mount[2]);
        if imu.t.len() < 2 {
            return Err(Error::Invalid(
                "the IMU log has fewer than two samples".into(),
            ));
        }
        let t: Vec<f64> = imu.t.iter().map(|t| t + time_offset).collect();
        let gyro: Vec<Vector3<f64>> = imu.gyro.iter().map(|w| m * w).collect();
        let acc: Vec<Vector3<f64>> = imu.accel.iter().map(|f| m * f).collect();
        let (clipped, _) = crate::ins::clip::clipped_samples(&imu.gyro, &imu.accel);
        let gaps = imu_gaps(&t, &gyro, &acc, &clipped);
        Ok(BodyImu { t, gyro, acc, gaps })
    }

    /// The gap that ends at sample `i`, if the interval from sample `i − 1` to `i` is one.
    pub fn gap_before(&self, i: usize) -> Option<&ImuGap> {
        self.gaps
            .binary_search_by_key(&i, |g| g.i)
            .ok()
            .map(|k| &self.gaps[k])
    }

    /// Time of the last sample (s).
    pub fn end(&self) -> f64 {
        self.t[self.t.len() - 1]
    }
}

/// The aligned start: epoch index, INS state at the antenna (position from the fix, the lever
/// arm not yet applied), initial gyro bias (rad/s) and attitude σ (rad; roll, pitch, yaw).
pub struct Aligned {
    /// Record epoch of the alignment.
    pub epoch: usize,
    /// State at the antenna.
    pub state: NavState,
    /// Initial gyro bias (rad/s, body axes).
    pub bg0: Vector3<f64>,
    /// Initial attitude σ (rad).
    pub sig_att: Vector3<f64>,
}

/// Velocities from positions, for a log that has none: at each epoch `k` with a fix, the
/// difference of the last fix at least `half` s before it and the first at least `half` s
/// after it, `(p₊ − p₋)/(t₊ − t₋)` (east, north, up m/s), where neither is more than `half +
/// interval` s away (None elsewhere: a gap); with its horizontal σ `√(σ₋² + σ₊²)/(t₊ − t₋)`
/// from the positions' horizontal σ `sig_p` (m). Time-correlated position errors largely
/// cancel in the difference, so the σ is an upper bound. None too where the two fixes differ
/// and one of them, or a fix between them, repeats the one before it exactly: the receiver
/// held its position while the vehicle moved (a stale spell, a static hold released), and
/// the difference is the hold's catching up, not a velocity (a vehicle standing still, its fixes
/// repeated or not, differences to zero as before). None too where a fix after the first
/// of the two, up to the second, `jumped` (epoch index: the fix jumped from the ones before
/// it, a multipath burst's or a fault's start or end): the difference would carry the jump
/// as a velocity (simulated, a 34 m burst 1 s after the alignment gave its INS 17 m/s).
pub fn velocity_from_positions(
    t: &[f64],
    pos: impl Fn(usize) -> Option<Vector3<f64>>,
    sig_p: impl Fn(usize) -> f64,
    jumped: impl Fn(usize) -> bool,
    half: f64,
    interval: f64,
) -> Vec<Option<(Vector3<f64>, f64)>> {
    let repeats = repeated_fixes(t.len(), &pos);
    let fixes: Vec<(usize, Vector3<f64>)> = (0..t.len())
        .filter_map(|k| pos(k).map(|p| (k, p)))
        .collect();
    let mut out = vec![None; t.len()];
    for (i, &(k, _)) in fixes.iter().enumerate() {
        let before = fixes[..i].iter().rposition(|(a, _)| t[k] - t[*a] >= half);
        let after = fixes[i + 1..]
            .iter()
            .position(|(b, _)| t[*b] - t[k] >= half)
            .map(|j| i + 1 + j);
        if let (Some(ia), Some(ib)) = (before, after) {
            let ((a, pa), (b, pb)) = (fixes[ia], fixes[ib]);
            let span = t[b] - t[a];
            let held = pa != pb && fixes[ia..=ib].iter().any(|&(j, _)| repeats[j]);
            let jump = fixes[ia + 1..=ib].iter().any(|&(j, _)| jumped(j));
            if t[k] - t[a] <= half + interval
                && t[b] - t[k] <= half + interval
                && span > 0.0
                && !held
                && !jump
            {
                out[k] = Some(((pb - pa) / span, sig_p(a).hypot(sig_p(b)) / span));
            }
        }
    }
    out
}

/// Per epoch of `n`: whether its fix (`pos`, east, north, up m; None: no fix) repeats the last
/// fix before it exactly — the receiver holding its position (at rest, or stale while the
/// vehicle moves).
pub fn repeated_fixes(n: usize, pos: impl Fn(usize) -> Option<Vector3<f64>>) -> Vec<bool> {
    let mut last = None;
    (0..n)
        .map(|k| {
            let p = pos(k);
            let repeat = p.is_some() && p == last;
            last = p.or(last);
            repeat
        })
        .collect()
}

/// IMU samples a static start must hold for the alignment to level on it.
pub const MIN_LEVEL_SAMPLES: usize = 50;

/// Seconds per window of the IMU's own rest check ([`imu_rest`]).
pub const REST_WINDOW: f64 = 1.0;
/// A window whose mean angular rate or specific force is this many robust σ (of the windows'
/// means over the stretch) from their median is not at rest ([`imu_rest`]).
pub const REST_SIGMAS: f64 = 6.0;
/// ... and at least this far (rad/s; m/s² for [`REST_FLOOR_ACC`]): a vehicle moving off turns
/// at degrees per second and accelerates at tenths of g, while at rest the means of 1 s of a
/// consumer IMU scatter by a fraction of that (0.26°/s, a few mg on drive_0708's).
pub const REST_FLOOR_GYRO: f64 = 0.5 * std::f64::consts::PI / 180.0;
/// See [`REST_FLOOR_GYRO`].
pub const REST_FLOOR_ACC: f64 = 0.05;
/// Windows in a row not at rest that mark the vehicle moving off ([`imu_rest`]).
pub const REST_MOVING: usize = 3;

/// The samples of `idx` (a static start found from the GNSS speed) where the IMU itself is
/// at rest: the longest piece between runs of [`REST_MOVING`] or more [`REST_WINDOW`]
/// windows with a component of the window's mean rate or specific force beyond
/// [`REST_SIGMAS`] robust σ (and the floors) from the median over the windows. Speeds
/// differenced from meter-level fixes (σ 1.4 m/s) stay below the rest threshold (2.5σ) while
/// a car moves off at 3–5 m/s and turns: on the bundled drive with 2 m fixes the "rest" ran
/// 13 s into the drive and its turn, and its mean rate, taken as the gyro bias, turned the
/// heading 15° off (70° in 4 minutes without the non-holonomic constraint). Fewer than three
/// windows: `idx` as it is.
pub fn imu_rest(imu: &BodyImu, idx: &[usize]) -> Vec<usize> {
    let Some(&first) = idx.first() else {
        return Vec::new();
    };
    let t0 = imu.t[first];
    let mut wins: Vec<&[usize]> = Vec::new();
    let mut start = 0;
    for j in 1..=idx.len() {
        let cut = j == idx.len()
            || ((imu.t[idx[j]] - t0) / REST_WINDOW).floor()
                > ((imu.t[idx[start]] - t0) / REST_WINDOW).floor();
        if cut {
            wins.push(&idx[start..j]);
            start = j;
        }
    }
    if wins.len() < 3 {
        return idx.to_vec();
    }
    let means: Vec<[f64; 6]> = wins
        .iter()
        .map(|w| {
            let n = w.len() as f64;
            let g = w.iter().map(|&i| imu.gyro[i]).sum::<Vector3<f64>>() / n;
            let f = w.iter().map(|&i| imu.acc[i]).sum::<Vector3<f64>>() / n;
            [g.x, g.y, g.z, f.x, f.y, f.z]
        })
        .collect();
    let median = |mut v: Vec<f64>| crate::stats::median_of(&mut v);
    let mut moving = vec![false; wins.len()];
    for c in 0..6 {
        let med = median(means.iter().map(|m| m[c]).collect());
        let mad = median(means.iter().map(|m| (m[c] - med).abs()).collect());
        let floor = if c < 3 {
            REST_FLOOR_GYRO
        } else {
            REST_FLOOR_ACC
        };
        let bound = (REST_SIGMAS * mad / 0.674_489_75).max(floor);
        for (w, m) in moving.iter_mut().zip(&means) {
            *w |= (m[c] - med).abs() > bound;
        }
    }
    // Cut where the vehicle moves: every window in a run of [`REST_MOVING`] or more not at
    // rest (a door shut or a passenger getting in is a window or two, and stays in). Of the
    // pieces left, the longest (the later one of equal length): the vehicle moving off ends
    // the rest, luggage loaded for seconds splits it.
    let mut sustained = vec![false; wins.len()];
    let mut w = 0;
    while w < wins.len() {
        let run = moving[w..].iter().take_while(|&&m| m).count();
        if run >= REST_MOVING {
            sustained[w..w + run].iter_mut().for_each(|x| *x = true);
        }
        w += run.max(1);
    }
    let (mut best, mut start) = ((0, 0), None);
    let flags = sustained.iter().map(|&x| !x).chain(std::iter::once(false));
    for (w, quiet) in flags.enumerate() {
        match (quiet, start) {
            (true, None) => start = Some(w),
            (false, Some(a)) => {
                if w - a >= best.1 - best.0 {
                    best = (a, w);
                }
                start = None;
            }
            _ => {}
        }
    }
    wins[best.0..best.1].concat()
}

/// The speed, in σ of the GNSS velocity, from which the alignment reads the heading from the
/// velocity's direction (its σ then at most 1/5 rad, 11.5°: the error filter's small-angle
/// regime).
pub const HEADING_SPEED_SIGMAS: f64 = 5.0;

/// Align on record epochs `t` (s): `vel(k)`, `pos(k)` the GNSS velocity and position east,
/// north, up (m/s; m from `origin`) at epoch k where measured; `sig_v` the velocity σ at the
/// alignment epoch (m/s, given its index); `rest_by_sigma`: `sig_v` is the receiver's velocity
/// σ, speeds below 2.5 σ count as rest, and the heading is read at a speed of at least
/// [`HEADING_SPEED_SIGMAS`] σ where the log reaches it, else at half the most σ it reaches
/// (and at least `alignment.speed`). `section` names the configuration in errors.
#[allow(clippy::too_many_arguments)]
pub fn align(
    a: &AlignmentSpec,
    section: &str,
    imu: &BodyImu,
    t: &[f64],
    origin: &Nominal,
    vel: impl Fn(usize) -> Option<Vector3<f64>>,
    pos: impl Fn(usize) -> Option<Vector3<f64>>,
    sig_v: impl Fn(usize) -> f64,
    rest_by_sigma: bool,
) -> Result<Aligned> {
    let speed_at = |k: usize| vel(k).map(|v| v.xy().norm());
    let usable = |k: usize, min: f64| {
        speed_at(k).is_some_and(|s| s >= min) && pos(k).is_some() && t[k] > imu.t[0]
    };
    // The heading is read from the velocity's direction: at the first epoch where that
    // direction is known to 1/HEADING_SPEED_SIGMAS rad (the speed at least that many times
    // the velocity's σ) — at a speed of a few σ (a meter-level receiver's velocity from
    // position differences, σ ≈ 1.4 m/s, at the 1 m/s of an RTK set-up) it may be off by
    // tens of degrees, beyond what the error filter's small-angle model can correct, and the
    // INS runs away from the fixes. Where the log never gets that fast, the first epoch at
    // `speed` as before. Only where `sig_v` is the velocity's σ (`rest_by_sigma`; the tight
    // filter's is a range rate's) and no heading is given.
    let heading_sigmas = if rest_by_sigma && a.heading.is_none() {
        HEADING_SPEED_SIGMAS
    } else {
        0.0
    };
    // Where the log never gets that fast, the first epoch at half the most σ its speed
    // reaches: a first epoch at `speed` may be noise at rest (fixes with 3 m of correlated
    // error written σ 6 m moved 2 m/s between two fixes 2 s apart while the car stood, and the
    // heading was read from it).
    let best = (0..t.len())
        .filter(|&k| usable(k, a.speed))
        .filter_map(|k| Some(speed_at(k)? / sig_v(k)))
        .filter(|r| r.is_finite())
        .fold(0.0, f64::max);
    let ka = (0..t.len())
        .find(|&k| usable(k, a.speed.max(heading_sigmas * sig_v(k))))
        .or_else(|| (0..t.len()).find(|&k| usable(k, a.speed.max(0.5 * best * sig_v(k)))))
        .ok_or_else(|| {
            Error::Invalid(format!(
                "alignment: no epoch with a GNSS fix and a GNSS speed of at least {section}.alignment.speed = {} m/s inside the IMU log",
                a.speed
            ))
        })?;
    // The last static stretch before ka: speeds below the static speed or 2.5 times the
    // receiver's velocity σ (a meter-level receiver at rest reports decimetres per second);
    // it ends at the third consecutive epoch above (one or two noisy speeds do not cut it).
    // A stretch with too few IMU samples to level on is no rest but a slow or noisy moment
    // of the drive (speeds differenced from meter-level fixes, σ 1.4 m/s, fall below 2.5σ in
    // motion): the search goes on before it.
    let stretch = |from: usize| {
        let mut end = None;
        let mut start = None;
        let mut moving = 0;
        for k in (0..from).rev() {
            match speed_at(k) {
                Some(s)
                    if s < a
                        .static_speed
                        .max(if rest_by_sigma { 2.5 * sig_v(k) } else { 0.0 }) =>
                {
                    end.get_or_insert(k);
                    start = Some(k);
                    moving = 0;
                }
                Some(_) if end.is_some() => {
                    moving += 1;
                    if moving >= 3 {
                        break;
                    }
                }
                _ => {}
            }
        }
        start.zip(end)
    };
    // The IMU's samples within [t_k0, t_k1] (its times strictly increase).
    let samples = |k0: usize, k1: usize| -> Vec<usize> {
        let a = imu.t.partition_point(|&x| x < t[k0]);
        let b = imu.t.partition_point(|&x| x <= t[k1]);
        (a..b.max(a)).collect()
    };
    // At rest the velocities average to zero: a slow stretch of a turn (speeds from 2 m fixes
    // below 2.5σ for seconds) moves on average by more than 3σ of the mean of its velocities,
    // counted as one independent value per 2 s (velocities differenced over 2 s overlap), and
    // by more than the static speed.
    let still = |k0: usize, k1: usize| {
        let vs: Vec<(Vector3<f64>, f64)> = (k0..=k1)
            .filter_map(|k| vel(k).map(|v| (v, sig_v(k))))
            .collect();
        let n = vs.len().max(1) as f64;
        let mean = vs
            .iter()
            .map(|(v, _)| v.xy())
            .sum::<nalgebra::Vector2<f64>>()
            / n;
        let sig = vs.iter().map(|(_, s)| *s).fold(0.0, f64::max);
        let n_eff = ((t[k1] - t[k0]) / 2.0).max(1.0);
        // Never stricter than the static speed: where every speed of the stretch is below it
        // (a receiver whose velocity σ is small), the stretch is rest as before.
        mean.norm() <= (3.0 * sig / n_eff.sqrt()).max(a.static_speed)
    };
    // Of the stretches before ka that are at rest by both tests, the longest: with speeds
    // from meter-level fixes a slow moment of the drive can pass them for seconds (on the
    // bundled drive with 2 m fixes, 6 s of a 2 m/s crawl through a turn), the vehicle's real
    // rest before it lasts longer (34 s there).
    let mut from = ka;
    let mut found: Option<Vec<usize>> = None;
    let mut short = None;
    while let Some((k0, k1)) = stretch(from) {
        let rest = if still(k0, k1) {
            imu_rest(imu, &samples(k0, k1))
        } else {
            Vec::new()
        };
        if rest.len() >= MIN_LEVEL_SAMPLES {
            if found.as_ref().is_none_or(|f| rest.len() > f.len()) {
                found = Some(rest);
            }
        } else {
            short.get_or_insert((k0, k1, rest.len()));
        }
        from = k0;
    }
    let Some(idx) = found else {
        // No rest to level on before moving: align in motion (a car's velocity is along its
        // forward axis), else say why.
        return in_motion(a, imu, t, origin, ka, &vel, &pos, &sig_v).ok_or_else(|| {
            Error::Invalid(match short {
                Some((k0, k1, n)) => format!(
                    "alignment: the static start {:.2}–{:.2} s holds {n} IMU samples at rest; levelling needs at least {MIN_LEVEL_SAMPLES}",
                    t[k0], t[k1]
                ),
                None => format!(
                    "alignment: no static start (GNSS speed below {section}.alignment.static_speed = {} m/s) before the vehicle reaches {} m/s, and no second GNSS velocity within 2 s of that epoch to align in motion",
                    a.static_speed, a.speed
                ),
            })
        });
    };
    let mean =
        |v: &[Vector3<f64>]| idx.iter().map(|&i| v[i]).sum::<Vector3<f64>>() / idx.len() as f64;
    let f_mean = mean(&imu.acc);
    let bg0 = if a.gyro_bias {
        mean(&imu.gyro)
    } else {
        Vector3::zeros()
    };
    let (roll, pitch) = level(&f_mean);
    let v_enu = vel(ka).unwrap_or_default();
    let speed = v_enu.xy().norm();
    let yaw = a.heading.unwrap_or_else(|| v_enu.x.atan2(v_enu.y));
    let sig_heading = if a.heading.is_some() {
        a.sigma_heading
    } else {
        a.sigma_heading.max(sig_v(ka) / speed.max(1e-3))
    };
    let q = UnitQuaternion::from_euler_angles(roll, pitch, yaw);
    let bg0 = if a.gyro_bias {
        let lat = origin.lat;
        let w_ie = Vector3::new(
            earth::OMEGA_IE * lat.cos(),
            0.0,
            -earth::OMEGA_IE * lat.sin(),
        );
        bg0 - q.inverse() * w_ie
    } else {
        bg0
    };
    let fix = origin.from_enu(&pos(ka).unwrap_or_default());
    Ok(Aligned {
        epoch: ka,
        state: NavState {
            lat: fix.lat,
            lon: fix.lon,
            h: fix.h,
            v: Vector3::new(v_enu.y, v_enu.x, -v_enu.z),
            q,
        },
        bg0,
        sig_att: Vector3::new(a.sigma_level, a.sigma_level, sig_heading),
    })
}

/// In-motion alignment at epoch `ka` (the first moving one, no rest before it): TRIAD on two
/// vector pairs — the specific force averaged over the IMU samples between `ka` and the next
/// GNSS velocity (within 2 s), against the GNSS acceleration over that interval less gravity
/// (NED), which levels; and the body's forward axis against the direction of the GNSS
/// velocity, which heads (a ground vehicle moves along its forward axis: the non-holonomic
/// constraint). No gyro bias estimate (the filter's own from then on). None without a second
/// velocity or with too few IMU samples.
#[allow(clippy::too_many_arguments)]
fn in_motion(
    a: &AlignmentSpec,
    imu: &BodyImu,
    t: &[f64],
    origin: &Nominal,
    ka: usize,
    vel: &impl Fn(usize) -> Option<Vector3<f64>>,
    pos: &impl Fn(usize) -> Option<Vector3<f64>>,
    sig_v: &impl Fn(usize) -> f64,
) -> Option<Aligned> {
    let kb = (ka + 1..t.len())
        .take_while(|&k| t[k] - t[ka] <= 2.0)
        .find(|&k| vel(k).is_some())?;
    let (ta, tb) = (t[ka], t[kb]);
    let idx: Vec<usize> = (0..imu.t.len())
        .filter(|&i| imu.t[i] >= ta && imu.t[i] <= tb)
        .collect();
    if idx.len() < 5 {
        return None;
    }
    let f_b = idx.iter().map(|&i| imu.acc[i]).sum::<Vector3<f64>>() / idx.len() as f64;
    let ned = |v: Vector3<f64>| Vector3::new(v.y, v.x, -v.z);
    let (va, vb) = (ned(vel(ka)?), ned(vel(kb)?));
    let g = earth::gravity(origin.lat, origin.h);
    let f_n = (vb - va) / (tb - ta) - Vector3::new(0.0, 0.0, g);
    let v_mid = (va + vb) * 0.5;
    let speed = v_mid.xy().norm();
    let fwd_n = Vector3::new(v_mid.x, v_mid.y, v_mid.z) / v_mid.norm().max(1e-9);
    let triad = |r1: Vector3<f64>, r2: Vector3<f64>| {
        let t1 = r1.normalize();
        let t2 = r1.cross(&r2).normalize();
        let t3 = t1.cross(&t2);
        nalgebra::Matrix3::from_columns(&[t1, t2, t3])
    };
    let c_bn = triad(f_n, fwd_n) * triad(f_b, Vector3::x()).transpose();
    if !c_bn.iter().all(|x| x.is_finite()) {
        return None;
    }
    let q = UnitQuaternion::from_rotation_matrix(&nalgebra::Rotation3::from_matrix(&c_bn));
    let q = match a.heading {
        Some(yaw) => {
            let (r, p, _) = q.euler_angles();
            UnitQuaternion::from_euler_angles(r, p, yaw)
        }
        None => q,
    };
    let sig_heading = if a.heading.is_some() {
        a.sigma_heading
    } else {
        a.sigma_heading.max(sig_v(ka) / speed.max(1e-3))
    };
    // Levelling from a GNSS acceleration: its error over the interval adds to the level σ.
    let sig_level = a.sigma_level.max((2.0 * sig_v(ka) / (tb - ta)) / g);
    let fix = origin.from_enu(&pos(ka).unwrap_or_default());
    Some(Aligned {
        epoch: ka,
        state: NavState {
            lat: fix.lat,
            lon: fix.lon,
            h: fix.h,
            v: va,
            q,
        },
        bg0: Vector3::zeros(),
        sig_att: Vector3::new(sig_level, sig_level, sig_heading),
    })
}

/// Mechanisation from one record epoch to the next: the strapdown state and the error
/// filter's covariance advanced over the IMU samples (trapezoidal rate and force between
/// samples, compensated with the filter's biases).
#[derive(Debug, Clone)]
pub struct Mechaniser {
    /// Index of the next IMU sample.
    pub i: usize,
    /// Time reached (s).
    pub t: f64,
    prev: Increment,
    /// The last compensated angular rate (rad/s, body).
    pub w_last: Vector3<f64>,
}

impl Mechaniser {
    /// Start at time `t0` (s) with the filter's gyro bias `bg` (rad/s).
    pub fn new(imu: &BodyImu, t0: f64, bg: &Vector3<f64>) -> Self {
        let i = imu.t.partition_point(|&t| t <= t0);
        Mechaniser {
            i,
            t: t0,
            prev: Increment::zero(0.0),
            w_last: imu.gyro[i.min(imu.gyro.len() - 1)] - bg,
        }
    }

    /// Advance state `s` and filter `kf` to time `tk` (s).
    pub fn advance<const NS: usize>(
        &mut self,
        imu: &BodyImu,
        s: &mut NavState,
        kf: &mut ErrorFilter<NS>,
        tk: f64,
    ) {
        let n = imu.t.len();
        while self.t < tk {
            let ip = self.i.min(n - 1);
            let im = ip.saturating_sub(1);
            let (w, f) = kf.compensate(
                &(0.5 * (imu.gyro[im] + imu.gyro[ip])),
                &(0.5 * (imu.acc[im] + imu.acc[ip])),
            );
            let t_next = imu.t[ip].min(tk);
            let dt = t_next - self.t;
            if dt > 0.0 {
                let inc = Increment {
                    dtheta: w * dt,
                    dvel: f * dt,
                    dt,
                };
                mechanise(s, &self.prev, &inc);
                match imu.gap_before(ip) {
                    Some(g) => kf.propagate_gap(s, &f, &w, dt, &g.acc_rate, &g.gyro_rate),
                    None => kf.propagate(s, &f, &w, dt),
                }
                self.prev = inc;
                self.w_last = w;
            }
            self.t = t_next;
            if imu.t[ip] <= tk {
                self.i = ip + 1;
                if self.i >= n {
                    break;
                }
            }
        }
    }
}

/// Move the state's position by `d` metres north, east, down.
pub fn shift(s: &mut NavState, d: &Vector3<f64>) {
    let rm = earth::r_meridian(s.lat) + s.h;
    let rn = earth::r_normal(s.lat) + s.h;
    s.lat += d.x / rm;
    s.lon += d.y / (rn * s.lat.cos());
    s.h -= d.z;
}

/// North, east, down (m) of `p` from `q` (at `q`'s radii).
pub fn ned(p: &impl Point, q: &impl Point) -> Vector3<f64> {
    let (la, lo, h) = q.llh();
    let (pa, po, ph) = p.llh();
    let rm = earth::r_meridian(la) + h;
    let rn = earth::r_normal(la) + h;
    Vector3::new((pa - la) * rm, (po - lo) * rn * la.cos(), -(ph - h))
}

/// A point with latitude, longitude (rad) and height (m).
pub trait Point {
    /// Latitude, longitude (rad) and height (m).
    fn llh(&self) -> (f64, f64, f64);
}

impl Point for Nominal {
    fn llh(&self) -> (f64, f64, f64) {
        (self.lat, self.lon, self.h)
    }
}

impl Point for NavState {
    fn llh(&self) -> (f64, f64, f64) {
        (self.lat, self.lon, self.h)
    }
}

/// The state moved from the IMU to the antenna at `lever` (m, body forward-right-down).
pub fn antenna(s: &NavState, lever: &Vector3<f64>) -> NavState {
    let mut ant = *s;
    shift(&mut ant, &(s.q * lever));
    ant
}

/// Normalised estimation error squared of antenna position, velocity and attitude at epoch
/// `k` against a reference that has the true attitude (NaN otherwise).
pub fn nees<const NS: usize>(
    s: &NavState,
    kf: &ErrorFilter<NS>,
    lever: &Vector3<f64>,
    origin: &Nominal,
    src: &Streams,
    k: usize,
) -> f64 {
    let Some(r) = src.reference else {
        return f64::NAN;
    };
    let (Some(q_true), Some(e)) = (r.attitude.get(k), r.enu.get(k)) else {
        return f64::NAN;
    };
    if !e.iter().all(|v| v.is_finite()) {
        return f64::NAN;
    }
    let ant = antenna(s, lever);
    let truth = origin.from_enu(&Vector3::new(e[0], e[1], e[2]));
    let dr = ned(&ant, &truth);
    let dv = s.v - Vector3::new(e[4], e[3], -e[5]);
    let phi = (q_true * s.q.inverse()).scaled_axis();
    let mut err = nalgebra::SVector::<f64, 9>::zeros();
    err.fixed_rows_mut::<3>(0).copy_from(&dr);
    err.fixed_rows_mut::<3>(3).copy_from(&dv);
    err.fixed_rows_mut::<3>(6).copy_from(&phi);
    // Antenna position error = δr + [(C l)×] φ.
    let mut t = nalgebra::SMatrix::<f64, 9, NS>::zeros();
    for j in 0..3 {
        t[(j, R + j)] = 1.0;
        t[(3 + j, V + j)] = 1.0;
        t[(6 + j, PHI + j)] = 1.0;
    }
    t.fixed_view_mut::<3, 3>(0, PHI)
        .copy_from(&skew(&(s.q * lever)));
    let cov = t * kf.p * t.transpose();
    match cov.cholesky() {
        Some(ch) => err.dot(&ch.solve(&err)),
        None => f64::NAN,
    }
}

/// Record epoch `k` of a strapdown INS: the antenna's position, velocity, attitude, the
/// biases and their σ, the NEES ([`crate::record::NAV_COLUMNS`]), the errors against the
/// reference (east, north, up) and the σ of the error states.
pub fn record_nav<const NS: usize>(
    rec: &mut RunRecord,
    s: &NavState,
    kf: &ErrorFilter<NS>,
    lever: &Vector3<f64>,
    origin: &Nominal,
    src: &Streams,
    k: usize,
) {
    let ant = antenna(s, lever);
    let (roll, pitch, yaw) = s.q.euler_angles();
    let v_enu = Vector3::new(s.v.y, s.v.x, -s.v.z);
    rec.nav.extend([
        ant.lat, ant.lon, ant.h, v_enu.x, v_enu.y, v_enu.z, roll, pitch, yaw,
    ]);
    rec.nav.extend(kf.bg.iter().chain(kf.ba.iter()).copied());
    let sig = kf.sigma();
    rec.nav.extend((BG..BA + 3).map(|j| sig[j]));
    rec.nav.push(nees(s, kf, lever, origin, src, k));
    let p = origin.to_enu(&Nominal {
        lat: ant.lat,
        lon: ant.lon,
        h: ant.h,
    });
    match src.reference.and_then(|r| r.enu.get(k)) {
        Some(r) => {
            rec.error.extend([f64::NAN; 3]);
            rec.error
                .extend([v_enu.x - r[3], v_enu.y - r[4], v_enu.z - r[5]]);
            rec.error.extend([p.x - r[0], p.y - r[1], p.z - r[2]]);
        }
        None => rec.error.extend([f64::NAN; 9]),
    }
    rec.sigma.extend([
        sig[PHI + 1],
        sig[PHI],
        sig[PHI + 2],
        sig[V + 1],
        sig[V],
        sig[V + 2],
        sig[R + 1],
        sig[R],
        sig[R + 2],
    ]);
}

#[cfg(test)]
#[path = "inertial_tests.rs"]
mod tests;
