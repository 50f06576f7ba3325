//! Federated filter configuration (paper 000).

use super::check::{bad, non_negative, positive};
use super::detectors::DetectorSpec;
use super::{default_true, ScenarioSpec};
use crate::error::Result;
use crate::fusion::federated::{FusionMode, IsolatedMode};
use serde::{Deserialize, Serialize};

/// One sub-filter: INS error state + one sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SubfilterSpec {
    /// Sensor name.
    pub sensor: String,
    /// Information-sharing factor β_i.
    pub share: f64,
    /// Detectors run on this sub-filter's residuals.
    #[serde(default)]
    pub detectors: Vec<DetectorSpec>,
    /// Name of the detector whose alarm isolates the sub-filter (None: never isolated).
    #[serde(default)]
    pub isolation: Option<String>,
}

/// Federated filter configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FederatedSpec {
    /// Reset or no-reset mode.
    pub mode: FusionMode,
    /// Master's information share β_m (≥ 0); `Σβ_i + β_m = 1`.
    #[serde(default)]
    pub master_share: f64,
    /// Sub-filters.
    pub subfilters: Vec<SubfilterSpec>,
    /// What an isolated sub-filter does (default: track the global solution).
    #[serde(default)]
    pub isolated: IsolatedMode,
    /// Isolation active (default). `false`: the detectors run and report but never isolate
    /// (the "without isolation" comparison, as a variant).
    #[serde(default = "default_true")]
    pub isolate: bool,
}

impl ScenarioSpec {
    pub(super) fn validate_federated(&self) -> Result<()> {
        let fed = self.federated()?;
        non_negative("federated.master_share", fed.master_share)?;
        if fed.subfilters.is_empty() {
            return Err(bad(
                "federated.subfilters",
                "at least one sub-filter is required",
            ));
        }
        let mut total = fed.master_share;
        for (i, sf) in fed.subfilters.iter().enumerate() {
            let p = format!("federated.subfilters[{i}]");
            let dup = fed.subfilters[..i].iter().any(|o| o.sensor == sf.sensor);
            self.check_sensor_ref(&p, &sf.sensor, dup, "already has a sub-filter")?;
            positive(&format!("{p}.share"), sf.share)?;
            total += sf.share;
            self.validate_detectors(&p, &sf.detectors, false)?;
            if let Some(iso) = &sf.isolation {
                if !sf.detectors.iter().any(|d| &d.name == iso) {
                    return Err(bad(
                        format!("{p}.isolation"),
                        format!("{iso:?} is not one of this sub-filter's detectors"),
                    ));
                }
            }
        }
        if (total - 1.0).abs() > 1e-6 {
            return Err(bad(
                "federated",
                format!("shares must sum to 1 (Σβ_i + master_share = {total})"),
            ));
        }
        Ok(())
    }
}
