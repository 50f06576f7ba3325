//! Measurement streams: what an architecture consumes, whatever produced it.
//!
//! A source — the simulator ([`crate::sim`]) today, recorded logs next — produces, per epoch and
//! sensor, the measurement, its noise model and availability, the models the filter needs
//! (the INS error model's `Φ_k`, `Q_k` along the trajectory, each sensor's `H_k` and `R`), and
//! optionally a reference (the true error state) used only for scoring. Faults are injected
//! into the measurements by [`inject`], the same step for any source. The architectures
//! ([`crate::arch`]) read only these types: none of them knows where the numbers came from.
//!
//! Split by lifetime: [`Models`] do not depend on the run's noise and are built once;
//! [`Measurements`] and [`Reference`] are per run; [`Streams`] borrows the three for one run.

use crate::spec::{FaultSpec, ScenarioSpec};
use nalgebra::{DMatrix, DVector, Vector3};

use crate::gnss::ranges::RangeStream;

/// The point each epoch's error states are linearised about: latitude (rad), longitude
/// (rad) and height (m) of the navigation solution (or, in simulation, of the truth). Error
/// states in radians convert to metres there.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Nominal {
    /// Latitude (rad).
    pub lat: f64,
    /// Longitude (rad).
    pub lon: f64,
    /// Height (m).
    pub h: f64,
}

/// Everything about a run's measurements that does not depend on its noise.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct Models {
    /// Epoch times (s from the run's time 0).
    pub t: Vec<f64>,
    /// Linearisation point per epoch.
    pub nominal: Vec<Nominal>,
    /// Error-state transition into epoch k (`Φ_0 = I`), n × n.
    pub phi: Vec<DMatrix<f64>>,
    /// Process noise into epoch k (`Q_0 = 0`), n × n.
    pub q: Vec<DMatrix<f64>>,
    /// Initial error covariance, n × n.
    pub p0: DMatrix<f64>,
    /// Per sensor: measurement matrix per epoch (m × n; 0 × n for a `gnss_ranges` sensor,
    /// whose rows are in [`Models::ranges`]).
    pub h: Vec<Vec<DMatrix<f64>>>,
    /// Per sensor: `R` (diagonal of the noise variances; 0 × 0 for `gnss_ranges`).
    pub r: Vec<DMatrix<f64>>,
    /// Per sensor: the variance of its single component per epoch when it changes along the
    /// run (replacing `r` then); empty otherwise.
    pub r_epoch: Vec<Vec<f64>>,
    /// Per sensor and epoch: a measurement is taken (rate, outages, modes).
    pub available: Vec<Vec<bool>>,
    /// The satellites in view per epoch of the `gnss_ranges` sensor, if any.
    pub ranges: Option<RangeStream>,
    /// Navigation mode per epoch (1, 2, 3 for q1, q2, q3; empty without modes).
    pub mode: Vec<u8>,
    /// Recorded IMU samples and per-epoch measurement σ of a recorded-data source (None for
    /// the simulator's error-state streams).
    pub logged: Option<Logged>,
}

/// Recorded IMU samples: time (s from the run's time 0, as logged: the configured time offset
/// is applied by the architecture), angular rate (rad/s) and specific force (m/s²) in the
/// IMU's own axes.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ImuSamples {
    /// Sample times (s), strictly increasing.
    pub t: Vec<f64>,
    /// Angular rate per sample (rad/s, IMU axes).
    pub gyro: Vec<Vector3<f64>>,
    /// Specific force per sample (m/s², IMU axes).
    pub accel: Vec<Vector3<f64>>,
}

/// What a recorded-data source adds to [`Models`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Logged {
    /// The IMU log.
    pub imu: ImuSamples,
    /// Origin of the local east-north-up coordinates the position measurements are given in
    /// (`e = Δlon (R_N + h₀) cos lat₀`, `n = Δlat (R_M + h₀)`, `u = Δh` at the origin's radii:
    /// an exactly invertible map, so a fault of d metres moves the fix by d metres to 1e-4).
    pub origin: Nominal,
    /// Per sensor and epoch: the σ of each measurement component as recorded (NaN-free where
    /// the sensor is available; empty vectors elsewhere).
    pub sigma: Vec<Vec<DVector<f64>>>,
    /// Per epoch, where the source has them: the snapshot (single-point) fix of a raw-GNSS
    /// log, east, north, up (m, from the origin) and velocity east, north, up (m/s), NaN
    /// where there is none (the tight filter aligns on them); empty otherwise.
    pub fixes: Vec<[f64; 6]>,
    /// Per epoch, where the source has it: the receiver's solution quality in RTKLIB's codes
    /// (1 fixed, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP; 0 unknown); empty otherwise.
    #[serde(default)]
    pub quality: Vec<u8>,
}

impl Nominal {
    /// Local east, north, up (m) of the point `p` from this origin (see [`Logged::origin`]).
    pub fn to_enu(&self, p: &Nominal) -> Vector3<f64> {
        let rm = crate::ins::earth::r_meridian(self.lat) + self.h;
        let rn = crate::ins::earth::r_normal(self.lat) + self.h;
        Vector3::new(
            (p.lon - self.lon) * rn * self.lat.cos(),
            (p.lat - self.lat) * rm,
            p.h - self.h,
        )
    }

    /// The point at local east, north, up `enu` (m) from this origin (inverse of
    /// [`Nominal::to_enu`]).
    pub fn from_enu(&self, enu: &Vector3<f64>) -> Nominal {
        let rm = crate::ins::earth::r_meridian(self.lat) + self.h;
        let rn = crate::ins::earth::r_normal(self.lat) + self.h;
        Nominal {
            lat: self.lat + enu.y / rm,
            lon: self.lon + enu.x / (rn * self.lat.cos()),
            h: self.h + enu.z,
        }
    }
}

impl Models {
    /// Number of epochs.
    pub fn epochs(&self) -> usize {
        self.t.len()
    }
}

/// One run's measurements.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Measurements {
    /// Per sensor and epoch: the measurement (NaN when not taken). For a `gnss_ranges` sensor
    /// the tight measurement `z = ρ − ρ̂_INS` of the satellites in view (pseudoranges, then
    /// rates; empty when not taken).
    pub z: Vec<Vec<DVector<f64>>>,
    /// Raw observations of the `gnss_ranges` sensor per epoch: pseudoranges (m), then rates
    /// (m/s) of the satellites in view (empty when not taken or without such a sensor).
    pub raw: Vec<DVector<f64>>,
    /// The INS position (ECEF, m) per epoch, where the `gnss_ranges` sensor's ranges are
    /// predicted from (empty without such a sensor).
    pub ins_position: Vec<Vector3<f64>>,
}

/// The reference a run is scored against (never an input of the filters).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Reference {
    /// True error state `x_INS − x_true` per epoch (n); empty for a recorded-data source.
    pub x_true: Vec<DVector<f64>>,
    /// A recorded reference per epoch: the antenna's east, north, up (m, from
    /// [`Logged::origin`]) and velocity east, north, up (m/s); NaN where the reference has no
    /// epoch or the epoch was an input of the filter (scored only on the others).
    pub enu: Vec<[f64; 6]>,
    /// The true body (forward-right-down) to north-east-down attitude per epoch, where the
    /// source knows it (simulated logs; empty for recorded ones): with it a strapdown
    /// architecture records its normalised estimation error squared.
    pub attitude: Vec<nalgebra::UnitQuaternion<f64>>,
}

/// One run's streams: its models, measurements and optional reference.
#[derive(Debug, Clone, Copy)]
pub struct Streams<'a> {
    /// Noise-free models.
    pub models: &'a Models,
    /// Measurements.
    pub meas: &'a Measurements,
    /// Reference for scoring, when the source has one (errors are NaN without it).
    pub reference: Option<&'a Reference>,
    /// Seed and stream of the run: an architecture that simulates more of its own (the
    /// ultra-tight tracking loops' discriminator noise) derives its generator from them.
    pub seed: u64,
    /// See [`Streams::seed`].
    pub stream: u64,
}

impl Streams<'_> {
    /// Number of epochs.
    pub fn epochs(&self) -> usize {
        self.models.epochs()
    }
}

/// Fault injection, one step for every source: the value each fault adds at time `t` (s) to
/// the components of a measurement vector `v` (the faults of one sensor). The simulator adds
/// it before the noise, a recorded-data source to the recorded measurement.
pub fn inject(faults: &[&FaultSpec], t: f64, v: &mut DVector<f64>) {
    for f in faults {
        for &c in &f.components {
            v[c] += f.value(t);
        }
    }
}

/// Per fault of `spec`: whether it ever reaches a measurement of `models` — its sensor takes
/// a measurement inside the window (rate, outages, modes) and, for a satellite fault, the
/// satellite is in view then. A fault that never does says nothing about the detectors:
/// records carry this so tables and campaigns leave it out of the detection statistics.
pub fn faults_applied(spec: &ScenarioSpec, models: &Models) -> Vec<bool> {
    spec.faults
        .iter()
        .map(|f| {
            let Some(si) = spec.sensor_index(&f.sensor) else {
                return false;
            };
            let sat = match (&models.ranges, &f.satellite) {
                (Some(rp), Some(name)) if rp.sensor == si => {
                    match rp.names.iter().position(|n| n == name) {
                        Some(s) => Some(s),
                        None => return false,
                    }
                }
                _ => None,
            };
            models.t.iter().enumerate().any(|(k, &t)| {
                t >= f.start
                    && t < f.end
                    && models.available.get(si).is_some_and(|a| a[k])
                    && sat.is_none_or(|s| {
                        models
                            .ranges
                            .as_ref()
                            .is_some_and(|rp| rp.epochs[k].sats.contains(&s))
                    })
            })
        })
        .collect()
}
