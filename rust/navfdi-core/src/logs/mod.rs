//! Recorded logs as a source of measurement streams: an IMU log, GNSS positions and
//! velocities with their σ (e.g. an RTKLIB `.pos` file) and an optional reference, turned into
//! the [`Models`], [`Measurements`] and [`Reference`] every architecture reads. Faults are
//! injected into the recorded measurements with [`crate::stream::inject`] (the same step as
//! the simulator's) and outages remove them, so a scenario's `[[faults]]`, `outages` and
//! `[[variants]]` work on logged data as on simulated data. Parsing files is the caller's
//! (the IMU CSV reader [`imu_csv`], the `.pos` rows [`pos_text`] and u-blox NAV-PVT
//! solutions [`ubx`] are here, the checks that
//! name the file, line and column of bad input partly in Python); this layer checks the
//! arrays again (finite, increasing, overlapping) before anything runs.
//!
//! The record epochs are the GNSS log's epochs (time 0 = its first epoch). A GNSS sensor of
//! the scenario takes a measurement at every n-th log epoch (its `rate` the log's divided by
//! n; `sample_epochs`) outside its outages, each at its own recorded time.
//! The reference is scored only at epochs where no GNSS measurement was an input.

pub mod imu_csv;
pub mod pos_text;
pub mod ranges;
pub mod shipped;
pub mod ubx;

use crate::error::{Error, Result};
use crate::spec::{ScenarioSpec, SensorKind};
use crate::stream::{inject, ImuSamples, Logged, Measurements, Models, Nominal, Reference};
use nalgebra::{DMatrix, DVector, Vector3};

/// A GNSS solution log: per epoch time (s from the run's time 0), latitude and longitude
/// (rad), height (m), velocity east, north, up (m/s) and the σ of each (m, m/s; NaN where
/// the log has none).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GnssLog {
    /// Epoch times (s), strictly increasing.
    pub t: Vec<f64>,
    /// Position per epoch.
    pub pos: Vec<Nominal>,
    /// Velocity east, north, up per epoch (m/s).
    pub vel: Vec<Vector3<f64>>,
    /// σ of the position east, north, up (m).
    pub sd_pos: Vec<Vector3<f64>>,
    /// σ of the velocity east, north, up (m/s).
    pub sd_vel: Vec<Vector3<f64>>,
    /// Solution quality per epoch in RTKLIB's codes (1 fixed, 2 float, 3 SBAS, 4 DGPS, 5
    /// single, 6 PPP; 0 unknown), or empty where the log has none.
    pub q: Vec<u8>,
}

impl GnssLog {
    pub(crate) fn check(&self, what: &str) -> Result<()> {
        let n = self.t.len();
        if self.pos.len() != n
            || self.vel.len() != n
            || self.sd_pos.len() != n
            || self.sd_vel.len() != n
            || !(self.q.is_empty() || self.q.len() == n)
        {
            return Err(Error::Invalid(format!(
                "{what}: columns of different lengths"
            )));
        }
        if n == 0 {
            return Err(Error::Invalid(format!("{what}: no epochs")));
        }
        for k in 0..n {
            let p = &self.pos[k];
            // Velocity may be missing (NaN: RTKLIB writes none by default), not infinite.
            let finite = self.t[k].is_finite()
                && p.lat.is_finite()
                && p.lon.is_finite()
                && p.h.is_finite()
                && !self.vel[k].iter().any(|v| v.is_infinite());
            if !finite {
                return Err(Error::Invalid(format!(
                    "{what}: epoch {k} has a NaN or infinite time or position, or an infinite velocity"
                )));
            }
            if k > 0 && self.t[k] <= self.t[k - 1] {
                return Err(Error::Invalid(format!(
                    "{what}: time does not increase at epoch {k} ({} s after {} s)",
                    self.t[k],
                    self.t[k - 1]
                )));
            }
            if p.lat.abs() > 1.5 {
                return Err(Error::Invalid(format!(
                    "{what}: epoch {k}: latitude {} rad is within 4° of a pole or not in radians",
                    p.lat
                )));
            }
        }
        Ok(())
    }
}

/// A recorded-data source prepared for a scenario: the models (epochs, availability, IMU,
/// σ), the recorded measurements before faults, and the reference.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct LoggedSource {
    /// Models of the run (the same for every fault draw).
    pub models: Models,
    /// Recorded measurements, faults not yet injected.
    pub recorded: Measurements,
    /// Reference at the epochs not used as input.
    pub reference: Reference,
}

/// The log epochs a sensor of `rate` Hz (`sensor`: its field path for messages) measures at:
/// every epoch when the rate is the log's, else every n-th interval (n = log rate / rate, an
/// integer): from the first epoch, an epoch is taken when at least n − ½ median intervals
/// have passed since the last one taken. Epochs are taken at their own time, so receiver
/// time-tag jitter (a few ms) and a drifting receiver clock neither drop nor move them, and a
/// gap restarts the count. A rate above the log's, or not the log's divided by an integer,
/// is an error naming the rates the log allows.
pub(crate) fn sample_epochs(t: &[f64], rate: f64, sensor: &str) -> Result<Vec<bool>> {
    let n = t.len();
    if n < 2 {
        return Ok(vec![true; n]);
    }
    let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    d.sort_by(f64::total_cmp);
    let dt = d[d.len() / 2];
    let log_rate = 1.0 / dt;
    let ratio = log_rate / rate;
    let every = ratio.round();
    if !(rate > 0.0) || every < 1.0 || (ratio - every).abs() > 0.02 * every {
        let allowed: Vec<String> = (1..=4)
            .map(|k| format!("{:.4} Hz", log_rate / k as f64))
            .collect();
        return Err(Error::Invalid(format!(
            "{sensor}.rate = {rate} Hz: the log's epochs are {dt} s apart ({log_rate:.4} Hz); a sensor measures at the log's rate divided by an integer ({}, ...)",
            allowed.join(", ")
        )));
    }
    let step = (every - 0.5) * dt;
    let mut out = vec![false; n];
    let mut last = f64::NEG_INFINITY;
    for (k, &tk) in t.iter().enumerate() {
        if tk - last >= step {
            out[k] = true;
            last = tk;
        }
    }
    Ok(out)
}

impl LoggedSource {
    /// Prepare `spec`'s streams from an IMU log, a GNSS log and an optional reference log
    /// (its epochs matched to the GNSS log's within 1 ms; unmatched ones are not used).
    pub fn new(
        spec: &ScenarioSpec,
        imu: ImuSamples,
        gnss: &GnssLog,
        reference: Option<&GnssLog>,
    ) -> Result<Self> {
        Self::with_scoring(spec, imu, gnss, reference, false)
    }

    /// As [`LoggedSource::new`]; `score_inputs`: the reference is scored at every matched
    /// epoch, the GNSS input epochs included (the filter's error after their update), for a
    /// reference that has no other epochs.
    pub fn with_scoring(
        spec: &ScenarioSpec,
        imu: ImuSamples,
        gnss: &GnssLog,
        reference: Option<&GnssLog>,
        score_inputs: bool,
    ) -> Result<Self> {
        spec.validate()?;
        check_imu(&imu)?;
        gnss.check("GNSS log")?;
        if let Some(r) = reference {
            r.check("reference log")?;
        }
        overlap(&imu, &gnss.t, "GNSS log")?;
        let epochs = gnss.t.len();
        let origin = gnss.pos[0];
        let ns = spec.sensors.len();
        let mut available = vec![vec![false; epochs]; ns];
        let mut z = vec![vec![DVector::zeros(0); epochs]; ns];
        let mut sigma = vec![vec![DVector::zeros(0); epochs]; ns];
        for (si, sen) in spec.sensors.iter().enumerate() {
            let grid = sample_epochs(&gnss.t, sen.rate, &format!("sensors[{si}]"))?;
            if matches!(sen.kind, SensorKind::Gnss | SensorKind::GnssVelocity)
                && !gnss.vel.iter().any(|v| v.iter().all(|x| x.is_finite()))
            {
                return Err(Error::Invalid(format!(
                    "sensors[{si}] ({:?}, kind {:?}): the GNSS log has no velocity (no ve, vn, vu columns); use a gnss_position sensor, or a log with velocities",
                    sen.name, sen.kind
                )));
            }
            let (pos, vel) = match sen.kind {
                SensorKind::Gnss => (true, true),
                SensorKind::GnssPosition => (true, false),
                SensorKind::GnssVelocity => (false, true),
                other => {
                    return Err(Error::Invalid(format!(
                        "sensors[{si}]: a {other:?} sensor has no column in a GNSS log; recorded scenarios take gnss, gnss_position and gnss_velocity sensors"
                    )))
                }
            };
            for k in 0..epochs {
                let t = gnss.t[k];
                let out = sen.outages.iter().any(|w| t >= w[0] && t < w[1]);
                if out || !grid[k] {
                    z[si][k] = DVector::from_element(sen.kind.dim(), f64::NAN);
                    continue;
                }
                available[si][k] = true;
                let mut v = Vec::with_capacity(6);
                let mut s = Vec::with_capacity(6);
                if pos {
                    v.extend(origin.to_enu(&gnss.pos[k]).iter());
                    s.extend(gnss.sd_pos[k].iter());
                }
                if vel {
                    v.extend(gnss.vel[k].iter());
                    s.extend(gnss.sd_vel[k].iter());
                }
                z[si][k] = DVector::from_vec(v);
                sigma[si][k] = DVector::from_vec(s);
            }
        }
        // Scored only where no GNSS measurement was an input (unless asked to score those).
        let enu = reference.map_or_else(
            || vec![[f64::NAN; 6]; epochs],
            |r| {
                reference_enu(r, &gnss.t, &origin, 1e-3, |k| {
                    !score_inputs && available.iter().any(|a| a[k])
                })
            },
        );
        let logged = Logged {
            imu,
            origin,
            sigma,
            fixes: Vec::new(),
            quality: gnss.q.clone(),
        };
        let models = logged_models(gnss.t.clone(), gnss.pos.clone(), available, None, logged);
        Ok(LoggedSource::assemble(models, z, enu))
    }

    /// A source of `models`, the recorded measurements `z` (per sensor and epoch) and the
    /// reference east, north, up and velocity per epoch `enu`.
    fn assemble(models: Models, z: Vec<Vec<DVector<f64>>>, enu: Vec<[f64; 6]>) -> Self {
        LoggedSource {
            models,
            recorded: Measurements {
                z,
                raw: Vec::new(),
                ins_position: Vec::new(),
            },
            reference: Reference {
                x_true: Vec::new(),
                enu,
                attitude: Vec::new(),
            },
        }
    }

    /// The measurements of a run of scenario `spec` (the one prepared, or a variant of it with
    /// other faults): the recorded ones with `spec`'s faults injected.
    pub fn measurements(&self, spec: &ScenarioSpec) -> Measurements {
        let mut m = self.recorded.clone();
        for (si, sen) in spec.sensors.iter().enumerate() {
            let faults: Vec<_> = spec
                .faults
                .iter()
                .filter(|f| f.sensor == sen.name)
                .collect();
            if faults.is_empty() || si >= m.z.len() {
                continue;
            }
            if let Some(rp) = self.models.ranges.as_ref().filter(|rp| rp.sensor == si) {
                // Per satellite: component c of satellite j is row c·m + j.
                for (k, v) in m.z[si].iter_mut().enumerate() {
                    if !self.models.available[si][k] {
                        continue;
                    }
                    let ep = &rp.epochs[k];
                    let n = ep.len();
                    for f in &faults {
                        let Some(j) = ep
                            .sats
                            .iter()
                            .position(|&s| f.satellite.as_ref() == Some(&rp.names[s]))
                        else {
                            continue;
                        };
                        let d = f.value(self.models.t[k]);
                        for &c in &f.components {
                            v[c * n + j] += d;
                        }
                    }
                }
                continue;
            }
            for (k, v) in m.z[si].iter_mut().enumerate() {
                if self.models.available[si][k] {
                    inject(&faults, self.models.t[k], v);
                }
            }
        }
        m
    }
}

/// The reference east, north, up (m from `origin`) and velocity (m/s) at the epochs `t`: each
/// reference epoch is matched to the nearest epoch within `tol` s (or a tenth of the epochs'
/// median interval, if larger: receiver time tags jitter by milliseconds), moved to that
/// epoch's time with its own velocity when it has one; epochs `skip` says are not scored.
fn reference_enu(
    r: &GnssLog,
    t: &[f64],
    origin: &Nominal,
    tol: f64,
    skip: impl Fn(usize) -> bool,
) -> Vec<[f64; 6]> {
    let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    d.sort_by(f64::total_cmp);
    let tol = d.get(d.len() / 2).map_or(tol, |m| tol.max(0.1 * m));
    let mut enu = vec![[f64::NAN; 6]; t.len()];
    for (j, &tr) in r.t.iter().enumerate() {
        let k = t.partition_point(|&x| x < tr - tol);
        if k >= t.len() || (t[k] - tr).abs() > tol || skip(k) {
            continue;
        }
        let v = r.vel[j];
        let shift = if v.iter().all(|x| x.is_finite()) {
            v * (t[k] - tr)
        } else {
            Vector3::zeros()
        };
        let p = origin.to_enu(&r.pos[j]) + shift;
        enu[k] = [p.x, p.y, p.z, v.x, v.y, v.z];
    }
    enu
}

/// The [`Models`] of a recorded-data source: epochs `t`, linearisation points, availability
/// per sensor, the satellite ranges (raw GNSS logs) and the logged IMU (no Φ, Q or H: the
/// strapdown architectures build their own).
fn logged_models(
    t: Vec<f64>,
    nominal: Vec<Nominal>,
    available: Vec<Vec<bool>>,
    ranges: Option<crate::gnss::ranges::RangeStream>,
    logged: Logged,
) -> Models {
    let ns = available.len();
    Models {
        t,
        nominal,
        phi: Vec::new(),
        q: Vec::new(),
        p0: DMatrix::zeros(0, 0),
        h: vec![Vec::new(); ns],
        r: vec![DMatrix::zeros(0, 0); ns],
        r_epoch: vec![Vec::new(); ns],
        available,
        ranges,
        mode: Vec::new(),
        logged: Some(logged),
    }
}

/// An error unless the IMU log and the GNSS epochs `t` (s) overlap in time.
fn overlap(imu: &ImuSamples, t: &[f64], what: &str) -> Result<()> {
    let (i0, i1) = (imu.t[0], imu.t[imu.t.len() - 1]);
    let (g0, g1) = (t[0], t[t.len() - 1]);
    if i1 <= g0 || g1 <= i0 {
        return Err(Error::Invalid(format!(
            "the {what} ({g0:.3}–{g1:.3} s) and the IMU log ({i0:.3}–{i1:.3} s) do not overlap in time"
        )));
    }
    Ok(())
}

pub(crate) fn check_imu(imu: &ImuSamples) -> Result<()> {
    let n = imu.t.len();
    if imu.gyro.len() != n || imu.accel.len() != n {
        return Err(Error::Invalid(
            "IMU log: columns of different lengths".into(),
        ));
    }
    if n < 2 {
        return Err(Error::Invalid("IMU log: fewer than two samples".into()));
    }
    for i in 0..n {
        if !(imu.t[i].is_finite()
            && imu.gyro[i].iter().all(|v| v.is_finite())
            && imu.accel[i].iter().all(|v| v.is_finite()))
        {
            return Err(Error::Invalid(format!(
                "IMU log: sample {i} has a NaN or infinite value"
            )));
        }
        if i > 0 && imu.t[i] <= imu.t[i - 1] {
            return Err(Error::Invalid(format!(
                "IMU log: time does not increase at sample {i} ({} s after {} s)",
                imu.t[i],
                imu.t[i - 1]
            )));
        }
    }
    Ok(())
}

#[cfg(test)]
mod sampling_tests {
    use super::sample_epochs;

    #[test]
    fn jitter_and_clock_drift_drop_no_epoch() {
        // 4 Hz with ±2 ms jitter, and with an unsteered clock drifting 5 µs/s over 200 s.
        let jitter: Vec<f64> = (0..800)
            .map(|k| k as f64 * 0.25 + if k % 2 == 0 { 0.002 } else { -0.002 })
            .collect();
        assert!(sample_epochs(&jitter, 4.0, "s").unwrap().iter().all(|&x| x));
        let one = sample_epochs(&jitter, 1.0, "s").unwrap();
        assert_eq!(one.iter().filter(|&&x| x).count(), 200);
        let drift: Vec<f64> = (0..800).map(|k| k as f64 * 0.25 * (1.0 + 5e-6)).collect();
        assert!(sample_epochs(&drift, 4.0, "s").unwrap().iter().all(|&x| x));
        // A gap restarts the count: epochs 0, 1 s, then 2.75 s (after the gap), 3.75 s.
        let gap = [0.0, 0.25, 0.5, 0.75, 1.0, 1.25, 2.75, 3.0, 3.25, 3.5, 3.75];
        let g = sample_epochs(&gap, 1.0, "s").unwrap();
        let taken: Vec<f64> = gap.iter().zip(&g).filter(|x| *x.1).map(|x| *x.0).collect();
        assert_eq!(taken, vec![0.0, 1.0, 2.75, 3.75]);
    }

    #[test]
    fn a_rate_the_log_cannot_give_is_refused() {
        let t: Vec<f64> = (0..40).map(|k| k as f64 * 0.25).collect();
        for r in [3.0, 8.0, 0.0, -1.0, f64::NAN] {
            let e = sample_epochs(&t, r, "sensors[0]").unwrap_err().to_string();
            assert!(
                e.contains("sensors[0].rate") && e.contains("4.0000 Hz"),
                "{e}"
            );
        }
        assert!(sample_epochs(&t, 2.0, "s").is_ok());
    }
}
