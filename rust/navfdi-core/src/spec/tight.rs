//! Tightly coupled filter configuration (paper 001).

use super::check::{bad, positive};
use super::{default_true, ScenarioSpec, SensorKind};
use crate::error::{Error, Result};
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
    /// Also update with (and test) the pseudorange rates (default true).
    #[serde(default = "default_true")]
    pub rates: bool,
    /// White-acceleration spectral density of the GNSS-only filter (`gnss_filter`), m²/s³
    /// (default 1).
    #[serde(default = "default_accel_psd")]
    pub accel_psd: f64,
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
        Ok(())
    }
}
