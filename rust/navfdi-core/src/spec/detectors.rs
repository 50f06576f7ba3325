//! Detectors attached to a channel, and the state chi-square test of the navigation solution.

use super::check::{bad, positive};
use super::ScenarioSpec;
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Detector type.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum DetectorKind {
    /// Residual chi-square.
    Chi2,
    /// Improved SPRT.
    Sprt,
    /// Joint chi-square / SPRT.
    Joint,
    /// State chi-square of the sensor's sub-filter against the navigation solution's
    /// propagators (paper 003, METHODS §8; centralized architecture with `[state_chi2]`,
    /// whose schedule and tested states it uses, with this detector's `pf`).
    StateChi2,
}

/// A detector attached to a sub-filter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DetectorSpec {
    /// Name, unique within the sub-filter (e.g. `chi2`, `sprt`, `joint`).
    pub name: String,
    /// Type.
    pub kind: DetectorKind,
    /// False-alarm probability.
    pub pf: f64,
    /// Missed-detection probability (SPRT and joint).
    #[serde(default)]
    pub pm: Option<f64>,
    /// SPRT variance: "known" (default) or "sample".
    #[serde(default)]
    pub variance: Option<String>,
    /// SPRT: samples a component needs since its last reset before it may alarm (default 1
    /// with the known variance, 20 with the sample variance).
    #[serde(default)]
    pub min_samples: Option<u64>,
}

/// The state chi-square test of the navigation solution (METHODS §8), run beside the
/// architecture's detectors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StateChi2Spec {
    /// False-alarm probability per epoch.
    pub pf: f64,
    /// Seconds between resets of each propagator (they alternate, half a period apart).
    pub reset_every: f64,
    /// Seconds a propagator must have run before it is tested (≤ `reset_every`).
    pub min_age: f64,
    /// Tested state indices (None: all).
    #[serde(default)]
    pub states: Option<Vec<usize>>,
}

impl StateChi2Spec {
    /// `(reset_every, min_age)` in epochs of `dt`.
    pub fn epochs(&self, dt: f64) -> (u64, u64) {
        let r = (self.reset_every / dt).round().max(1.0) as u64;
        let a = (self.min_age / dt).round().max(1.0) as u64;
        (r, a.min(r))
    }
}

impl ScenarioSpec {
    pub(super) fn validate_detectors(
        &self,
        p: &str,
        detectors: &[DetectorSpec],
        centralized: bool,
    ) -> Result<()> {
        for (j, d) in detectors.iter().enumerate() {
            let dp = format!("{p}.detectors[{j}]");
            if d.kind == DetectorKind::StateChi2 && !(centralized && self.state_chi2.is_some()) {
                return Err(bad(
                    format!("{dp}.kind"),
                    "state_chi2 detectors run in the centralized architecture and need a [state_chi2] section (its propagator schedule and states)",
                ));
            }
            if d.name.is_empty() || detectors[..j].iter().any(|o| o.name == d.name) {
                return Err(bad(
                    format!("{dp}.name"),
                    format!(
                        "{:?} must be non-empty and unique in the sub-filter",
                        d.name
                    ),
                ));
            }
            crate::validate::check_probability(&format!("{dp}.pf"), d.pf)
                .map_err(|e| Error::Invalid(e.to_string()))?;
            match (d.kind, d.pm) {
                (DetectorKind::Chi2 | DetectorKind::StateChi2, _) => {}
                (_, None) => {
                    return Err(bad(
                        format!("{dp}.pm"),
                        "required for sprt and joint detectors",
                    ))
                }
                (_, Some(pm)) => {
                    crate::stats::sprt_threshold(d.pf, pm).map_err(|e| bad(dp.clone(), e))?;
                }
            }
            if d.min_samples == Some(0) {
                return Err(bad(format!("{dp}.min_samples"), "0 must be at least 1"));
            }
            if let Some(v) = &d.variance {
                if v != "known" && v != "sample" {
                    return Err(bad(
                        format!("{dp}.variance"),
                        format!("{v:?} must be \"known\" or \"sample\""),
                    ));
                }
            }
        }
        Ok(())
    }

    /// `{p}.sensor` must name a sensor, and not one an earlier entry already uses (`dup`).
    pub(super) fn check_sensor_ref(
        &self,
        p: &str,
        sensor: &str,
        dup: bool,
        dup_msg: &str,
    ) -> Result<()> {
        if self.sensor_index(sensor).is_none() {
            return Err(bad(
                format!("{p}.sensor"),
                format!(
                    "{sensor:?} is not a sensor (known: {})",
                    self.sensor_names()
                ),
            ));
        }
        if dup {
            return Err(bad(
                format!("{p}.sensor"),
                format!("sensor {sensor:?} {dup_msg}"),
            ));
        }
        Ok(())
    }

    /// The state chi-square test of the navigation solution.
    pub(super) fn validate_state_chi2(&self) -> Result<()> {
        if let Some(sc) = &self.state_chi2 {
            crate::validate::check_probability("state_chi2.pf", sc.pf)
                .map_err(|e| Error::Invalid(e.to_string()))?;
            positive("state_chi2.reset_every", sc.reset_every)?;
            positive("state_chi2.min_age", sc.min_age)?;
            if sc.reset_every < self.dt {
                return Err(bad(
                    "state_chi2.reset_every",
                    format!(
                        "{} s is shorter than one filter period dt = {} s",
                        sc.reset_every, self.dt
                    ),
                ));
            }
            if sc.min_age > sc.reset_every {
                return Err(bad("state_chi2.min_age", format!("{} s exceeds reset_every = {} s (the older propagator is at least reset_every old once both run)", sc.min_age, sc.reset_every)));
            }
            let n = self.n_states();
            if let Some(st) = &sc.states {
                if st.is_empty() {
                    return Err(bad("state_chi2.states", "at least one state is required"));
                }
                for (i, &s) in st.iter().enumerate() {
                    if s >= n {
                        return Err(bad(
                            format!("state_chi2.states[{i}]"),
                            format!("index {s} out of range for {n} states"),
                        ));
                    }
                    if st[..i].contains(&s) {
                        return Err(bad(
                            format!("state_chi2.states[{i}]"),
                            format!("state {s} is listed twice"),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}
