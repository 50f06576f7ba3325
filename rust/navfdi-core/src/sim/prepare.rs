//! Everything about a simulated scenario that does not depend on the random seed, computed
//! once: the truth trajectory, the measurement streams' models along it ([`Models`]), and what
//! the simulator needs to draw a run (factors of `Q_k` and `P0`, the systematic errors).

use super::ranges::ranges_along;
use super::trajectory::{generate, TruthEpoch};
use crate::error::{Error, Result};
use crate::gnss::ranges::CLOCK_BIAS;
use crate::ins::{earth, ErrorModel, ATT, N_STATES, POS, VEL};
use crate::spec::{ScenarioSpec, SensorKind};
use crate::stream::{inject, Models, Nominal};
use nalgebra::{Cholesky, DMatrix, DVector};

/// A prepared scenario.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The scenario (validated).
    pub spec: ScenarioSpec,
    /// Truth trajectory per epoch.
    pub truth: Vec<TruthEpoch>,
    /// The measurement streams' models (epoch times `k·dt`, linearised about the truth).
    pub models: Models,
    /// A factor `L_k` with `L_k L_kᵀ = Q_k`, for drawing the true process noise.
    pub q_factor: Vec<DMatrix<f64>>,
    /// Factor of P0.
    pub p0_factor: DMatrix<f64>,
    /// Per sensor and epoch: the systematic error added to each component: the terrain under
    /// a radio altimeter, then the injected faults ([`inject`]); all zero without them.
    /// Empty vectors for a `gnss_ranges` sensor, whose per-satellite faults are in
    /// [`Models::ranges`].
    pub fault: Vec<Vec<DVector<f64>>>,
}

/// East and north (m) of each truth epoch from the first, with the radii of curvature at the
/// start point (the local frame of terrain, waypoints and targets).
pub fn local_en(truth: &[TruthEpoch]) -> Vec<(f64, f64)> {
    let Some(t0) = truth.first() else {
        return Vec::new();
    };
    let rm = earth::r_meridian(t0.lat) + t0.h;
    let rn = (earth::r_normal(t0.lat) + t0.h) * t0.lat.cos();
    truth
        .iter()
        .map(|e| ((e.lon - t0.lon) * rn, (e.lat - t0.lat) * rm))
        .collect()
}

/// Measurement matrix of a sensor at a kinematic state (m × 15; a `gnss_ranges` sensor's
/// matrices depend on the satellites in view and are in [`crate::gnss::ranges::RangeStream`]: 0 × 15 here).
pub fn measurement_matrix(kind: SensorKind, lat: f64, h: f64) -> DMatrix<f64> {
    if kind == SensorKind::GnssRanges {
        return DMatrix::zeros(0, N_STATES);
    }
    let m = kind.dim();
    let mut hm = DMatrix::zeros(m, N_STATES);
    let rm = earth::r_meridian(lat) + h;
    let rn = earth::r_normal(lat) + h;
    let pos = |hm: &mut DMatrix<f64>, row: usize| {
        hm[(row, POS + 1)] = rn * lat.cos(); // east (m) from δλ
        hm[(row + 1, POS)] = rm; // north (m) from δL
        hm[(row + 2, POS + 2)] = 1.0; // up (m)
    };
    match kind {
        SensorKind::Cns => {
            for i in 0..3 {
                hm[(i, ATT + i)] = 1.0;
            }
        }
        SensorKind::Gnss => {
            pos(&mut hm, 0);
            for i in 0..3 {
                hm[(3 + i, VEL + i)] = 1.0;
            }
        }
        SensorKind::GnssPosition | SensorKind::Vision => pos(&mut hm, 0),
        SensorKind::GnssVelocity => {
            for i in 0..3 {
                hm[(i, VEL + i)] = 1.0;
            }
        }
        SensorKind::Baro | SensorKind::RadioAltimeter => hm[(0, POS + 2)] = 1.0,
        SensorKind::GnssRanges => {}
    }
    hm
}

/// A factor `L` with `L Lᵀ = M` for a symmetric PSD `M` whose diagonal spans many orders of
/// magnitude: Cholesky of the correlation matrix (with a 1e-12 jitter), rescaled.
pub fn psd_factor(name: &str, m: &DMatrix<f64>) -> Result<DMatrix<f64>> {
    let n = m.nrows();
    let s: Vec<f64> = (0..n).map(|i| m[(i, i)].max(0.0).sqrt()).collect();
    let mut c = DMatrix::zeros(n, n);
    for i in 0..n {
        for j in 0..n {
            c[(i, j)] = if s[i] > 0.0 && s[j] > 0.0 {
                m[(i, j)] / (s[i] * s[j])
            } else {
                0.0
            };
        }
        c[(i, i)] = 1.0 + 1e-12;
    }
    let l = Cholesky::new(c)
        .ok_or_else(|| Error::NotPositiveDefinite {
            name: name.to_string(),
            detail: "cannot factor to draw noise".into(),
        })?
        .unpack();
    Ok(DMatrix::from_fn(n, n, |i, j| s[i] * l[(i, j)]))
}

/// The truth must stay where the navigation model holds: finite, and clear of the poles
/// (the ENU error model is singular there).
fn check_truth(truth: &[TruthEpoch]) -> Result<()> {
    for e in truth {
        let finite = [
            e.lat, e.lon, e.h, e.v.x, e.v.y, e.v.z, e.f_b.x, e.f_b.y, e.f_b.z,
        ]
        .iter()
        .all(|v| v.is_finite());
        if !finite || !(e.lat.abs() < 89.0f64.to_radians()) {
            return Err(Error::Invalid(format!(
                "trajectory: at t = {} s the truth {} (latitude {:.3}°); change the segments (speeds, headings, durations)",
                e.t,
                if finite { "comes within 1° of a pole, where the ENU model is singular" } else { "is no longer finite" },
                e.lat.to_degrees()
            )));
        }
    }
    Ok(())
}

impl Prepared {
    /// Prepare a validated scenario.
    pub fn new(spec: ScenarioSpec) -> Result<Self> {
        spec.validate()?;
        let epochs = spec.epochs();
        let dt = spec.dt;
        let truth = generate(spec.trajectory()?, dt, epochs);
        check_truth(&truth)?;
        let model = ErrorModel {
            params: *spec.ins()?,
        };
        let n = spec.n_states();
        let clock = spec
            .sensors
            .iter()
            .find_map(|s| s.ranges.as_ref().map(|r| r.clock));
        // A receiver clock adds bias b (m) and drift d (m/s): b' = b + d·dt, d' = d, with
        // white-frequency (bias_psd) and random-walk-frequency (drift_psd) noise.
        let embed = |m15: DMatrix<f64>, clk: [[f64; 2]; 2]| -> DMatrix<f64> {
            if n == N_STATES {
                return m15;
            }
            let mut m = DMatrix::zeros(n, n);
            m.view_mut((0, 0), (N_STATES, N_STATES)).copy_from(&m15);
            for a in 0..2 {
                for b in 0..2 {
                    m[(CLOCK_BIAS + a, CLOCK_BIAS + b)] = clk[a][b];
                }
            }
            m
        };
        let (phi_clk, q_clk) =
            clock.map_or(([[1.0, dt], [0.0, 1.0]], [[0.0; 2]; 2]), |c| c.discrete(dt));
        let mut phi = Vec::with_capacity(epochs);
        let mut q = Vec::with_capacity(epochs);
        let mut q_factor = Vec::with_capacity(epochs);
        phi.push(DMatrix::identity(n, n));
        q.push(DMatrix::zeros(n, n));
        q_factor.push(DMatrix::zeros(n, n));
        for k in 1..epochs {
            // Transition over [t_{k−1}, t_k], linearised at the start of the interval.
            let (p, qd) = model.discretize(&truth[k - 1].kinematics(), dt);
            let qd = embed(qd, q_clk);
            q_factor.push(psd_factor(&format!("Q[{k}]"), &qd)?);
            phi.push(embed(p, phi_clk));
            q.push(qd);
        }
        let p0 = embed(
            model.initial_covariance(truth[0].lat, truth[0].h),
            clock.map_or([[0.0; 2]; 2], |c| {
                [[c.bias * c.bias, 0.0], [0.0, c.drift * c.drift]]
            }),
        );
        let p0_factor = psd_factor("P0", &p0)?;
        let t: Vec<f64> = (0..epochs).map(|k| k as f64 * dt).collect();
        let mut h = Vec::new();
        let mut r = Vec::new();
        let mut r_epoch = Vec::new();
        let mut available: Vec<Vec<bool>> = Vec::new();
        let mut fault = Vec::new();
        let mut ranges = None;
        for (si, s) in spec.sensors.iter().enumerate() {
            let pad = |m: DMatrix<f64>| -> DMatrix<f64> {
                if m.ncols() == n {
                    m
                } else {
                    let mut out = DMatrix::zeros(m.nrows(), n);
                    out.view_mut((0, 0), (m.nrows(), m.ncols())).copy_from(&m);
                    out
                }
            };
            if let Some(rs) = &s.ranges {
                let faults: Vec<_> = spec.faults.iter().filter(|f| f.sensor == s.name).collect();
                ranges = Some(ranges_along(si, rs, &s.noise, &truth, &t, n, &faults));
            }
            h.push(
                truth
                    .iter()
                    .map(|e| pad(measurement_matrix(s.kind, e.lat, e.h)))
                    .collect(),
            );
            r.push(if s.ranges.is_some() {
                DMatrix::zeros(0, 0)
            } else {
                DMatrix::from_diagonal(&DVector::from_iterator(
                    s.noise.len(),
                    s.noise.iter().map(|n| n * n),
                ))
            });
            let period = (1.0 / (s.rate * dt)).round().max(1.0) as usize;
            available.push(
                (0..epochs)
                    .map(|k| {
                        k % period == 0 && !s.outages.iter().any(|w| t[k] >= w[0] && t[k] < w[1])
                    })
                    .collect(),
            );
            let m = if s.ranges.is_some() { 0 } else { s.kind.dim() };
            let faults: Vec<_> = spec
                .faults
                .iter()
                .filter(|f| spec.sensor_index(&f.sensor) == Some(si) && m > 0)
                .collect();
            // A radio altimeter read as altitude over a flat reference errs by the terrain
            // height under the vehicle.
            let terrain: Vec<f64> = match (&spec.terrain, s.kind) {
                (Some(tr), SensorKind::RadioAltimeter) => local_en(&truth)
                    .iter()
                    .map(|&(e, n)| tr.height(e, n))
                    .collect(),
                _ => vec![0.0; truth.len()],
            };
            // Height above the terrain (whose zero is height 0) sets a proportional σ.
            r_epoch.push(if s.proportional_noise > 0.0 {
                truth
                    .iter()
                    .zip(&terrain)
                    .map(|(e, th)| {
                        let agl = (e.h - th).max(0.0);
                        s.noise[0].powi(2) + (s.proportional_noise * agl).powi(2)
                    })
                    .collect()
            } else {
                Vec::new()
            });
            fault.push(
                t.iter()
                    .zip(&terrain)
                    .map(|(&tk, &th)| {
                        let mut v = DVector::zeros(m);
                        if m > 0 {
                            v[0] += th;
                        }
                        inject(&faults, tk, &mut v);
                        v
                    })
                    .collect(),
            );
        }
        // Navigation modes: a sensor outside the active mode takes no measurement.
        let mut mode = Vec::new();
        if let Some(ms) = &spec.modes {
            let gnss = spec.sensor_index(&ms.gnss).unwrap_or(0);
            let outages = &spec.sensors[gnss].outages;
            let en = local_en(&truth);
            for k in 0..epochs {
                let (e, n) = en[k];
                let near = (e - ms.target[0]).hypot(n - ms.target[1]) <= ms.radius;
                let gnss_ok = !outages.iter().any(|w| t[k] >= w[0] && t[k] < w[1]);
                let (q, list) = if near {
                    (3, &ms.q3)
                } else if gnss_ok {
                    (1, &ms.q1)
                } else {
                    (2, &ms.q2)
                };
                mode.push(q);
                for (si, s) in spec.sensors.iter().enumerate() {
                    if !list.contains(&s.name) {
                        available[si][k] = false;
                    }
                }
            }
        }
        let nominal = truth
            .iter()
            .map(|e| Nominal {
                lat: e.lat,
                lon: e.lon,
                h: e.h,
            })
            .collect();
        Ok(Prepared {
            spec,
            truth,
            models: Models {
                t,
                nominal,
                phi,
                q,
                p0,
                h,
                r,
                r_epoch,
                available,
                ranges,
                mode,
                logged: None,
            },
            q_factor,
            p0_factor,
            fault,
        })
    }

    /// Number of epochs.
    pub fn epochs(&self) -> usize {
        self.models.epochs()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::{SensorSpec, TerrainSpec, TerrainWave};

    #[test]
    fn radio_altimeter_error_is_the_terrain_under_the_vehicle() {
        let mut spec: ScenarioSpec =
            serde_json::from_str(include_str!("../../../../benches/yang2013.json")).unwrap();
        spec.duration = 300.0;
        spec.faults.clear();
        spec.sensors.push(SensorSpec {
            name: "ra".into(),
            kind: SensorKind::RadioAltimeter,
            noise: vec![0.5],
            bias: vec![],
            proportional_noise: 0.0,
            rate: 1.0,
            outages: vec![],
            ranges: None,
        });
        let wave = TerrainWave {
            amplitude: 4.0,
            wavelength: 700.0,
            heading: 0.4,
            phase: 0.3,
        };
        spec.terrain = Some(TerrainSpec { waves: vec![wave] });
        let prep = Prepared::new(spec).unwrap();
        let si = prep.spec.sensor_index("ra").unwrap();
        let t0 = &prep.truth[0];
        let mut spread = (f64::INFINITY, f64::NEG_INFINITY);
        for (k, e) in prep.truth.iter().enumerate() {
            // Independent local coordinates: ECEF difference rotated to ENU at the start.
            let d = crate::gnss::geodesy::ecef_to_enu(t0.lat, t0.lon)
                * (crate::gnss::geodesy::lla_to_ecef(e.lat, e.lon, t0.h)
                    - crate::gnss::geodesy::lla_to_ecef(t0.lat, t0.lon, t0.h));
            let want = 4.0
                * (std::f64::consts::TAU * (d.x * 0.4f64.sin() + d.y * 0.4f64.cos()) / 700.0 + 0.3)
                    .sin();
            let got = prep.fault[si][k][0];
            // navfdi's local frame scales latitude and longitude at the start point; over the
            // few km flown it differs from the rotated ECEF difference by centimetres at most.
            assert!((got - want).abs() < 0.05, "k = {k}: {got} vs {want}");
            spread = (spread.0.min(got), spread.1.max(got));
        }
        assert!(
            spread.1 - spread.0 > 4.0,
            "the vehicle crosses the waves: {spread:?}"
        );
    }
}
