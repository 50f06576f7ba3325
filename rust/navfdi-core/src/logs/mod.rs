//! Recorded logs as a source of measurement streams: an IMU log, GNSS positions and
//! velocities with their σ (e.g. an RTKLIB `.pos` file) and an optional reference, turned into
//! the [`Models`], [`Measurements`] and [`Reference`] every architecture reads. Faults are
//! injected into the recorded measurements with [`crate::stream::inject`] (the same step as
//! the simulator's) and outages remove them, so a scenario's `[[faults]]`, `outages` and
//! `[[variants]]` work on logged data as on simulated data. Parsing files is the caller's
//! (Python reads them with pandas and names the file, line and column of bad input); this
//! layer checks the arrays again (finite, increasing, overlapping) before anything runs.
//!
//! The record epochs are the GNSS log's epochs (time 0 = its first epoch). A GNSS sensor of
//! the scenario takes a measurement at the epochs on its `rate` grid outside its outages.
//! The reference is scored only at epochs where no GNSS measurement was an input.

mod ranges;

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
}

impl GnssLog {
    pub(crate) fn check(&self, what: &str) -> Result<()> {
        let n = self.t.len();
        if self.pos.len() != n
            || self.vel.len() != n
            || self.sd_pos.len() != n
            || self.sd_vel.len() != n
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
            let finite = self.t[k].is_finite()
                && p.lat.is_finite()
                && p.lon.is_finite()
                && p.h.is_finite()
                && self.vel[k].iter().all(|v| v.is_finite());
            if !finite {
                return Err(Error::Invalid(format!(
                    "{what}: epoch {k} has a NaN or infinite time, position or velocity"
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
#[derive(Debug, Clone)]
pub struct LoggedSource {
    /// Models of the run (the same for every fault draw).
    pub models: Models,
    /// Recorded measurements, faults not yet injected.
    pub recorded: Measurements,
    /// Reference at the epochs not used as input.
    pub reference: Reference,
}

/// Whether epoch time `t` (s) is on the grid of a sensor of `rate` Hz starting at 0.
fn on_grid(t: f64, rate: f64) -> bool {
    let x = t * rate;
    (x - x.round()).abs() < 1e-3
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
                if out || !on_grid(t, sen.rate) {
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
        // Scored only where no GNSS measurement was an input.
        let enu = reference.map_or_else(
            || vec![[f64::NAN; 6]; epochs],
            |r| {
                reference_enu(r, &gnss.t, &origin, 1e-3, |k| {
                    available.iter().any(|a| a[k])
                })
            },
        );
        let logged = Logged {
            imu,
            origin,
            sigma,
            fixes: Vec::new(),
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

/// The reference's antenna east, north, up (m, from `origin`) and velocity per record epoch
/// `t` (s): its epochs matched within `tol` s, NaN where unmatched or where `skip(k)`.
fn reference_enu(
    r: &GnssLog,
    t: &[f64],
    origin: &Nominal,
    tol: f64,
    skip: impl Fn(usize) -> bool,
) -> Vec<[f64; 6]> {
    let mut enu = vec![[f64::NAN; 6]; t.len()];
    for (j, &tr) in r.t.iter().enumerate() {
        let k = t.partition_point(|&x| x < tr - tol);
        if k >= t.len() || (t[k] - tr).abs() > tol || skip(k) {
            continue;
        }
        let p = origin.to_enu(&r.pos[j]);
        let v = r.vel[j];
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
