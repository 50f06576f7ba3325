//! Tightly coupled filter configuration (paper 001).

use super::check::{bad, positive};
use super::loosely_coupled::validate_strapdown;
use super::{default_true, AlignmentSpec, ScenarioSpec, SensorKind};
use crate::error::{Error, Result};
use crate::ins::error_filter::ImuNoise;
use serde::{Deserialize, Serialize};

/// Where a tightly coupled filter detects and excludes faulty satellites (paper 001).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FdePlacement {
    /// No satellite FDE: every satellite in view updates the filter (the innovation global
    /// test is still recorded).
    None,
    /// Paper 001's method 1: snapshot least squares, global test + w-test on the raw
    /// pseudoranges (and rates) before the filter; excluded satellites do not update it.
    LsPrecheck,
    /// Paper 001's method 2 as the issue defines it: the innovation chi-square test +
    /// standardised-innovation w-test with iterative exclusion inside the tight filter.
    Innovation,
    /// Paper 001's method 2 as the paper ran it: the same innovation test in a GNSS-only
    /// position-velocity Kalman filter before the integration filter
    /// ([`crate::gnss::pv_filter`]); excluded satellites update neither filter.
    GnssFilter,
    /// Filter solution separation ([`crate::integrity::filter_ss`]): a bank of sub-filters,
    /// each without one satellite, beside the filter; a separation beyond its threshold
    /// excludes the satellite whose sub-filter separates most (the filter takes that
    /// sub-filter's state). Needs `[tight.integrity]`.
    Separation,
}

/// Tightly coupled filter configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TightSpec {
    /// Name of the `gnss_ranges` sensor.
    pub sensor: String,
    /// FDE placement.
    pub fde: FdePlacement,
    /// False-alarm probability of the global test.
    pub alpha: f64,
    /// w-test critical value (None: the two-sided normal quantile of `alpha`).
    #[serde(default)]
    pub k: Option<f64>,
    /// What opens `ls_precheck`'s exclusion loop: the global test (default), data snooping
    /// (`wtest`), `both` or `auto` ([`crate::gnss::snapshot::Detection`]).
    #[serde(default)]
    pub ls_test: crate::gnss::snapshot::Detection,
    /// Also update with (and test) the pseudorange rates (default true).
    #[serde(default = "default_true")]
    pub rates: bool,
    /// White-acceleration spectral density of the GNSS-only filter (`gnss_filter`), m²/s³
    /// (default 1).
    #[serde(default = "default_accel_psd")]
    pub accel_psd: f64,
    /// The strapdown INS of a tight filter on recorded IMU and RINEX logs (None: the simulated
    /// INS error model of `ins`).
    #[serde(default)]
    pub strapdown: Option<StrapdownSpec>,
    /// Filter protection levels by solution separation (None: not computed).
    #[serde(default)]
    pub integrity: Option<FilterIntegritySpec>,
    /// Per-satellite Gauss-Markov range-error states in the strapdown tight filter and its
    /// sub-filters ([`crate::ins::range_states`]; None: white pseudorange errors).
    #[serde(default)]
    pub range_states: Option<RangeStatesSpec>,
}

/// The time-correlated part of the pseudorange errors, carried as one first-order
/// Gauss-Markov state per satellite.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangeStatesSpec {
    /// Share of each pseudorange's variance (the sensor's σ by elevation, squared) that is
    /// correlated, in [0, 1); the rest stays white.
    pub fraction: f64,
    /// Correlation time (s).
    pub tau: f64,
}

impl RangeStatesSpec {
    /// `fraction` in [0, 1) and `tau` in (0, 100 000] s, else an error naming `path`'s key.
    pub(crate) fn validate(&self, path: &str) -> Result<()> {
        if !(0.0..1.0).contains(&self.fraction) {
            return Err(bad(
                format!("{path}.fraction"),
                format!(
                    "{}: a share in [0, 1) of the pseudorange variance is required",
                    self.fraction
                ),
            ));
        }
        if !(self.tau > 0.0 && self.tau <= 1e5) {
            return Err(bad(
                format!("{path}.tau"),
                format!(
                    "{} s: a correlation time in (0, 100000] s is required",
                    self.tau
                ),
            ));
        }
        Ok(())
    }
}

/// Integrity allocation and fault prior of the filter protection levels
/// ([`crate::integrity::filter_ss`]); the defaults are LPV-200's (ARAIM ADD) and the ADD's
/// satellite prior.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilterIntegritySpec {
    /// Prior probability of a fault of each satellite per epoch (default 1e-5).
    #[serde(default = "default_p_sat")]
    pub p_sat: f64,
    /// Integrity budget of the vertical (default 9.8e-8).
    #[serde(default = "default_p_hmi_vert")]
    pub p_hmi_vert: f64,
    /// Integrity budget of the horizontal (default 2e-9).
    #[serde(default = "default_p_hmi_hor")]
    pub p_hmi_hor: f64,
    /// Continuity budget of the vertical separation tests (default 3.9e-6).
    #[serde(default = "default_p_fa_vert")]
    pub p_fa_vert: f64,
    /// Continuity budget of the horizontal separation tests (default 9e-8).
    #[serde(default = "default_p_fa_hor")]
    pub p_fa_hor: f64,
    /// The ADD's protection-level tolerance TOL_PL (m; default 0.05): the levels are the upper
    /// end of the ADD's half-interval search, at most this much above the root; 0 solves to
    /// 1 µm.
    #[serde(default = "default_tol_pl")]
    pub tol_pl: f64,
}

impl Default for FilterIntegritySpec {
    fn default() -> Self {
        FilterIntegritySpec {
            p_sat: default_p_sat(),
            p_hmi_vert: default_p_hmi_vert(),
            p_hmi_hor: default_p_hmi_hor(),
            p_fa_vert: default_p_fa_vert(),
            p_fa_hor: default_p_fa_hor(),
            tol_pl: default_tol_pl(),
        }
    }
}

impl FilterIntegritySpec {
    /// The allocation in the ARAIM module's form (P_THRES and P_EMT from LPV-200).
    pub fn allocation(&self) -> crate::integrity::araim::Allocation {
        crate::integrity::araim::Allocation {
            p_hmi_vert: self.p_hmi_vert,
            p_hmi_hor: self.p_hmi_hor,
            p_fa_vert: self.p_fa_vert,
            p_fa_hor: self.p_fa_hor,
            tol_pl: self.tol_pl,
            ..crate::integrity::araim::Allocation::lpv200()
        }
    }
}

fn default_p_sat() -> f64 {
    1e-5
}
fn default_p_hmi_vert() -> f64 {
    9.8e-8
}
fn default_p_hmi_hor() -> f64 {
    2e-9
}
fn default_p_fa_vert() -> f64 {
    3.9e-6
}
fn default_p_fa_hor() -> f64 {
    9e-8
}
fn default_tol_pl() -> f64 {
    0.05
}

/// A strapdown INS on a recorded IMU log, as the tight filter runs it: the IMU's noise figures
/// and mounting, the antenna lever arm (body axes, m), the IMU time offset (s) and the
/// alignment (as the loosely coupled filter's; the GNSS fixes it needs are single-point
/// solutions of the same pseudoranges and Dopplers).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StrapdownSpec {
    /// IMU noise figures (SI).
    pub imu: ImuNoise,
    /// IMU-to-body mounting roll, pitch, yaw (rad).
    pub mounting: [f64; 3],
    /// Antenna position from the IMU in body axes forward, right, down (m).
    pub lever_arm: [f64; 3],
    /// Added to the IMU time stamps (s).
    #[serde(default)]
    pub imu_time_offset: f64,
    /// Initial alignment.
    pub alignment: AlignmentSpec,
}

fn default_accel_psd() -> f64 {
    1.0
}

/// Name of the one detector of a tight filter's channel: the first global test of each epoch
/// (least-squares residuals for `ls_precheck`, innovations otherwise).
pub const TIGHT_DETECTOR: &str = "global";

impl ScenarioSpec {
    pub(super) fn validate_tight(&self) -> Result<()> {
        let t = self.tight()?;
        self.check_sensor_ref("tight", &t.sensor, false, "")?;
        let si = self.sensor_index(&t.sensor).unwrap_or(0);
        if self.sensors[si].kind != SensorKind::GnssRanges {
            return Err(bad(
                "tight.sensor",
                format!(
                    "{:?} is a {:?} sensor; a tight filter uses a gnss_ranges sensor",
                    t.sensor, self.sensors[si].kind
                ),
            ));
        }
        if let Some((i, o)) = self.sensors.iter().enumerate().find(|(i, _)| *i != si) {
            return Err(bad(
                format!("sensors[{i}]"),
                format!("{:?}: a tight filter uses only its gnss_ranges sensor (other sensors are not supported in it yet); remove it", o.name),
            ));
        }
        crate::validate::check_probability("tight.alpha", t.alpha)
            .map_err(|e| Error::Invalid(e.to_string()))?;
        if let Some(k) = t.k {
            positive("tight.k", k)?;
        }
        positive("tight.accel_psd", t.accel_psd)?;
        if let Some(fi) = &t.integrity {
            for (name, v) in [
                ("p_sat", fi.p_sat),
                ("p_hmi_vert", fi.p_hmi_vert),
                ("p_hmi_hor", fi.p_hmi_hor),
                ("p_fa_vert", fi.p_fa_vert),
                ("p_fa_hor", fi.p_fa_hor),
            ] {
                if !(v > 0.0 && v < 0.5) {
                    return Err(bad(
                        format!("tight.integrity.{name}"),
                        format!("{v}: a probability in (0, 0.5) is required"),
                    ));
                }
            }
            if !(0.0..=10.0).contains(&fi.tol_pl) {
                return Err(bad(
                    "tight.integrity.tol_pl",
                    format!("{} m: a tolerance in [0, 10] m is required", fi.tol_pl),
                ));
            }
        }
        if t.fde == FdePlacement::Separation && t.integrity.is_none() {
            return Err(bad(
                "tight.fde",
                "separation needs a [tight.integrity] table (empty for the LPV-200 defaults)",
            ));
        }
        if let Some(r) = &t.range_states {
            if t.strapdown.is_none() {
                return Err(bad("tight.range_states", "range-error states are carried by the strapdown tight filter ([tight.strapdown], on recorded or simulated IMU and range logs); the simulated INS-error tight filter has none (its correlated range errors, [sensors.ranges] correlated, are left to its white model)"));
            }
            r.validate("tight.range_states")?;
        }
        if let Some(sd) = &t.strapdown {
            validate_strapdown(
                "tight.strapdown",
                &sd.imu,
                &sd.mounting,
                &sd.lever_arm,
                sd.imu_time_offset,
                &sd.alignment,
            )?;
            if sd.imu.scale_factors() {
                return Err(bad("tight.strapdown.imu", "scale-factor states (gyro_scale, accel_scale) are not available in the tight filter yet (its 18 states are the 15 INS errors and the receiver clock); set them to 0"));
            }
            if t.fde == FdePlacement::GnssFilter {
                return Err(bad("tight.fde", "gnss_filter is not available on recorded logs; use ls_precheck, innovation or none"));
            }
            if self.state_chi2.is_some() {
                return Err(bad("state_chi2", "the state chi-square test needs the error model's Φ and Q of a simulated scenario; it is not available on recorded logs"));
            }
        }
        Ok(())
    }
}
