//! Centralized filter configuration (papers 002 and 003): policy, sensors, altitude fusion.

use super::check::{bad, non_negative};
use super::detectors::DetectorSpec;
use super::{default_true, DetectorKind, ScenarioSpec};
use crate::error::Result;
use serde::{Deserialize, Serialize};

/// What a centralized filter does with a detector's alarm (METHODS §7).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Policy {
    /// The sensor's whole measurement is dropped in an epoch its deciding detector alarms.
    Exclude,
    /// Plain improved SPRT: components in alarm are left out of the update until their
    /// statistic falls below the threshold.
    Latched,
    /// Paper 002: on an alarm of component i its SPRT restarts ("pseudo-normal" state) and i is
    /// left out (reduced-dimension update) until its restarted SPRT has stayed below the
    /// threshold for `confirm` seconds; the fading factor applies for `fading_duration` after
    /// each detection.
    Fading,
}

/// One sensor of a centralized filter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CentralSensorSpec {
    /// Sensor name.
    pub sensor: String,
    /// Detectors run on this sensor's block of the innovation.
    #[serde(default)]
    pub detectors: Vec<DetectorSpec>,
    /// Name of the detector whose alarms drive the policy (None: never acted on).
    #[serde(default)]
    pub decision: Option<String>,
}

/// Centralized filter configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CentralizedSpec {
    /// Fault-handling policy.
    pub policy: Policy,
    /// Sensors updating the filter.
    pub sensors: Vec<CentralSensorSpec>,
    /// Fading factor S > 1 (policy `fading`).
    #[serde(default = "default_fading")]
    pub fading: f64,
    /// Seconds the fading factor applies after each detection (policy `fading`).
    #[serde(default)]
    pub fading_duration: f64,
    /// Seconds a restarted component must stay below the threshold before its fault is
    /// declared over (policy `fading`).
    #[serde(default)]
    pub confirm: f64,
    /// Altitude from several sensors fused with a fault matrix into one measurement (paper
    /// 003); None: each sensor updates the filter with its own height.
    #[serde(default)]
    pub altitude_fusion: Option<AltitudeFusionSpec>,
    /// The policy acts (default). `false`: detectors run and report but never exclude (every
    /// fault-matrix entry 1: the "without isolation" comparison, as a variant).
    #[serde(default = "default_true")]
    pub isolate: bool,
}

/// Weighted altitude fusion with a fault matrix inside a centralized filter (METHODS §9): the
/// height components of `sensors` do not update the filter themselves; their inverse-variance
/// fusion over the sensors whose deciding detector does not exclude them (`M_i = 1`) does,
/// as one measurement with variance `1 / Σ w_i M_i`. When every `M_i` is 0 (or no sensor
/// measured) the filter predicts only in height.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AltitudeFusionSpec {
    /// Sensors whose height is fused (each with a height component: gnss, gnss_position,
    /// vision, baro, radio_altimeter), at least two.
    pub sensors: Vec<String>,
    /// Samples N of each sensor's deviation from the predicted height in its variance
    /// estimate.
    pub samples: usize,
    /// How σ_i² is estimated from those samples (default mean square).
    #[serde(default)]
    pub estimate: crate::fusion::Estimate,
}

fn default_fading() -> f64 {
    1.0
}

impl ScenarioSpec {
    pub(super) fn validate_centralized(&self) -> Result<()> {
        let c = self.centralized()?;
        if c.sensors.is_empty() {
            return Err(bad(
                "centralized.sensors",
                "at least one sensor is required",
            ));
        }
        for (i, cs) in c.sensors.iter().enumerate() {
            let p = format!("centralized.sensors[{i}]");
            let dup = c.sensors[..i].iter().any(|o| o.sensor == cs.sensor);
            self.check_sensor_ref(&p, &cs.sensor, dup, "is listed twice")?;
            self.validate_detectors(&p, &cs.detectors, true)?;
            if let Some(dn) = &cs.decision {
                let Some(d) = cs.detectors.iter().find(|d| &d.name == dn) else {
                    return Err(bad(
                        format!("{p}.decision"),
                        format!("{dn:?} is not one of this sensor's detectors"),
                    ));
                };
                if c.policy != Policy::Exclude && d.kind != DetectorKind::Sprt {
                    return Err(bad(
                        format!("{p}.decision"),
                        format!(
                            "policy {:?} acts on residual components and needs an sprt detector; {dn:?} is {:?}",
                            c.policy, d.kind
                        ),
                    ));
                }
            }
        }
        if !(c.fading >= 1.0 && c.fading.is_finite()) {
            return Err(bad(
                "centralized.fading",
                format!(
                    "{} must be a finite number >= 1",
                    crate::error::num(c.fading)
                ),
            ));
        }
        non_negative("centralized.fading_duration", c.fading_duration)?;
        // P grows by S every epoch the fading factor applies: S^(epochs) must stay far from
        // overflow (1e300 used to pass and overflow the filter at epoch 314). Checked whatever
        // the policy, so a variant that switches the policy on cannot fail mid-run.
        let epochs = (c.fading_duration / self.dt).ceil().max(1.0);
        let growth = epochs * c.fading.log10();
        if growth > 150.0 {
            return Err(bad(
                "centralized.fading",
                format!(
                    "{}: the covariance would grow by S^{} = 1e{:.0} over fading_duration = {} s, overflowing the filter; use S closer to 1 (paper 002: 1.1–2) or a shorter fading_duration",
                    crate::error::num(c.fading),
                    crate::error::num(epochs),
                    growth,
                    crate::error::num(c.fading_duration)
                ),
            ));
        }
        if let Some(af) = &c.altitude_fusion {
            if af.sensors.len() < 2 {
                return Err(bad(
                    "centralized.altitude_fusion.sensors",
                    "at least two sensors are fused",
                ));
            }
            for (i, name) in af.sensors.iter().enumerate() {
                let p = format!("centralized.altitude_fusion.sensors[{i}]");
                if !c.sensors.iter().any(|cs| &cs.sensor == name) {
                    return Err(bad(
                        p,
                        format!("{name:?} is not one of centralized.sensors"),
                    ));
                }
                if af.sensors[..i].contains(name) {
                    return Err(bad(p, format!("{name:?} is listed twice")));
                }
                let kind = self.sensors[self.sensor_index(name).unwrap_or(0)].kind;
                if kind.height_component().is_none() {
                    return Err(bad(p, format!("{name:?} ({kind:?}) measures no height")));
                }
            }
            if !(2..=1_000_000).contains(&af.samples) {
                return Err(bad(
                    "centralized.altitude_fusion.samples",
                    format!("{} must be in 2 ..= 1000000", af.samples),
                ));
            }
        }
        non_negative("centralized.confirm", c.confirm)?;
        Ok(())
    }
}
