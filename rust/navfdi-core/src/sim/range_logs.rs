//! The simulator as a source of recorded-style *raw GNSS* logs for the strapdown tight
//! filter: the IMU samples and the truth of [`super::logs`], and per GNSS epoch the
//! satellites of a `gnss_ranges` sensor's constellation above its mask, with pseudoranges and
//! Doppler range rates in the form the RINEX reader hands them to the filter
//! ([`crate::logs::ranges::RangeRow`]: already corrected for everything but the receiver
//! clock and the range errors). The strapdown tight filter, its range-error states and its
//! protection levels can then be checked where the truth is known (NEES, misleading epochs).
//!
//! Truth per satellite `i`: `ρ_i = |S(r_s,i) − r| + b + σ_i (√(1 − a) w_i + √a g_i)`,
//! `ρ̇_i = e_iᵀ(v_s,i − v) + d + σ̇_i ẇ_i`, with `S` the Sagnac rotation the filter applies
//! ([`crate::gnss::geodesy::sagnac`]), `e_i` the unit line of sight to `S(r_s,i)`, `b`, `d`
//! the receiver clock bias and drift (one clock for every system, drawn from the sensor's
//! clock model), `σ_i` the sensor's σ grown as 1/sin(elevation) when asked, `w` white and
//! `g_i` a unit first-order Gauss-Markov process per satellite of correlation time τ
//! (`ranges.correlated = {fraction a, tau}`; none: white).

use super::logs::{simulate_logs, LogNoise};
use super::noise::UnitMarkov;
use crate::error::{Error, Result};
use crate::gnss::broadcast::Sat;
use crate::gnss::geodesy::{ecef_to_enu, elevation_azimuth, lla_to_ecef, sagnac};
use crate::logs::ranges::RangeRow;
use crate::logs::GnssLog;
use crate::spec::{RangesSpec, TrajectorySpec};
use crate::stream::{ImuSamples, Nominal};
use nalgebra::{Matrix2, UnitQuaternion, Vector2};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Stream offset of the range logs' white noise and clock.
const RANGE_NOISE_STREAM: u64 = 0x0052_A46E_4C06;

/// One simulated run of IMU and raw GNSS logs, and its truth.
#[derive(Debug, Clone)]
pub struct SimulatedRangeLogs {
    /// IMU samples (as [`super::logs::SimulatedLogs::imu`]).
    pub imu: ImuSamples,
    /// GNSS epoch times (s, the IMU's scale).
    pub times: Vec<f64>,
    /// Per epoch the satellites above the mask and their observables.
    pub rows: Vec<Vec<RangeRow>>,
    /// Per epoch a snapshot-like fix: the truth plus the log noise's GNSS errors, east, north,
    /// up (m from `origin`) and velocity east, north, up (m/s) (the filter aligns on them).
    pub fixes: Vec<[f64; 6]>,
    /// Origin of the fixes: the true position at the first epoch.
    pub origin: Nominal,
    /// Per epoch the fix's position (the point the rows are formed about on a real log).
    pub nominal: Vec<Nominal>,
    /// The truth at the GNSS epochs (σ zero).
    pub reference: GnssLog,
    /// True body (forward-right-down) to north-east-down attitude at the GNSS epochs.
    pub attitude: Vec<UnitQuaternion<f64>>,
    /// Per epoch and row the pseudorange error drawn (m): white plus Gauss-Markov.
    pub range_errors: Vec<Vec<f64>>,
    /// True receiver clock bias (m) and drift (m/s) per epoch.
    pub clock: Vec<[f64; 2]>,
}

/// Simulate `duration` s of IMU and raw GNSS logs along `trajectory`: the IMU and the fixes
/// with `noise` (its `gnss_dt` is the GNSS epoch interval), the satellites of `ranges` (its
/// systems, mask, elevation growth, constellation epoch, clock and `correlated` errors) with
/// pseudorange and rate σ `sigma` (m, m/s at zenith), from ChaCha8 `(seed, stream = run)`.
pub fn simulate_range_logs(
    trajectory: &TrajectorySpec,
    duration: f64,
    noise: &LogNoise,
    ranges: &RangesSpec,
    sigma: [f64; 2],
    seed: u64,
    run: u64,
) -> Result<SimulatedRangeLogs> {
    if !(sigma.iter().all(|s| *s > 0.0 && s.is_finite())) {
        return Err(Error::Invalid(format!(
            "simulated range logs: sigma = {sigma:?} must be positive and finite"
        )));
    }
    if let Some(c) = &ranges.correlated {
        c.validate("simulated range logs: ranges.correlated")?;
    }
    let sim = simulate_logs(trajectory, duration, noise, seed, run)?;
    let orbits = ranges.orbits();
    let sats: Vec<Sat> = orbits
        .iter()
        .map(|o| {
            Sat::parse(&o.name).ok_or_else(|| {
                Error::Invalid(format!("simulated range logs: satellite name {}", o.name))
            })
        })
        .collect::<Result<_>>()?;
    let times = sim.reference.t.clone();
    let t0 = times.first().copied().unwrap_or(0.0);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(run ^ RANGE_NOISE_STREAM);
    let mut normal = move || -> f64 { StandardNormal.sample(&mut rng) };
    let (a, tau) = ranges
        .correlated
        .map_or((0.0, 1.0), |c| (c.fraction, c.tau));
    let mut gm = UnitMarkov::new(orbits.len(), tau, t0, seed, run);
    let (white, slow) = ((1.0 - a).sqrt(), a.sqrt());
    // Receiver clock: bias and drift, the two-state model of the tight filters, exactly
    // discretised between epochs.
    let ck = ranges.clock;
    let mut clock = Vector2::new(ck.bias * normal(), ck.drift * normal());
    let origin = sim.reference.pos[0];
    let mut out = SimulatedRangeLogs {
        imu: sim.imu,
        times: Vec::with_capacity(times.len()),
        rows: Vec::with_capacity(times.len()),
        fixes: Vec::with_capacity(times.len()),
        origin,
        nominal: Vec::with_capacity(times.len()),
        reference: sim.reference.clone(),
        attitude: sim.attitude,
        range_errors: Vec::with_capacity(times.len()),
        clock: Vec::with_capacity(times.len()),
    };
    for (k, &t) in times.iter().enumerate() {
        if k > 0 {
            let dt = t - times[k - 1];
            let (phi, q) = ck.discrete(dt);
            let (phi, q) = (Matrix2::from(phi).transpose(), Matrix2::from(q));
            let l = q.cholesky().map_or(Matrix2::zeros(), |c| c.l());
            clock = phi * clock + l * Vector2::new(normal(), normal());
        }
        gm.advance(t);
        let p = sim.reference.pos[k];
        let r = lla_to_ecef(p.lat, p.lon, p.h);
        let v = ecef_to_enu(p.lat, p.lon).transpose() * sim.reference.vel[k];
        let mut rows = Vec::new();
        let mut errors = Vec::new();
        for (i, o) in orbits.iter().enumerate() {
            let (rs, vs) = o.ecef(ranges.epoch + t);
            let (el, _) = elevation_azimuth(&r, p.lat, p.lon, &rs);
            // Two draws per satellite of the constellation, in view or not.
            let (w, wd) = (normal(), normal());
            if el < ranges.elevation_mask {
                continue;
            }
            let grow = if ranges.elevation_noise {
                1.0 / el.sin().max(0.05)
            } else {
                1.0
            };
            let d = sagnac(&rs, &r) - r;
            let e = d / d.norm();
            let err = sigma[0] * grow * (white * w + slow * gm.g[i]);
            rows.push(RangeRow {
                sat: sats[i],
                rho: d.norm() + clock.x + err,
                rate: e.dot(&(vs - v)) + clock.y + sigma[1] * grow * wd,
                pos: rs,
                vel: vs,
                el,
                cn0: f64::NAN,
            });
            errors.push(err);
        }
        let f = &sim.gnss;
        let fe = origin.to_enu(&f.pos[k]);
        out.times.push(t);
        out.fixes
            .push([fe.x, fe.y, fe.z, f.vel[k].x, f.vel[k].y, f.vel[k].z]);
        out.nominal.push(f.pos[k]);
        out.rows.push(rows);
        out.range_errors.push(errors);
        out.clock.push([clock.x, clock.y]);
    }
    Ok(out)
}
