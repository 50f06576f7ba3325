//! Faults injected into a sensor's measurements (any source: simulated or recorded).

use super::check::bad;
use super::{Architecture, ScenarioSpec};
use crate::error::Result;
use serde::{Deserialize, Serialize};

/// Fault shape over its window `[start, end)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaultKind {
    /// `magnitude`.
    Step,
    /// `magnitude · (t − start)`.
    Ramp,
    /// `magnitude · (t − start)²`.
    Quadratic,
}

/// A fault added to chosen components of a sensor's measurement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultSpec {
    /// Unique identifier.
    pub id: String,
    /// Sensor name.
    pub sensor: String,
    /// Component indices affected.
    pub components: Vec<usize>,
    /// Shape.
    pub kind: FaultKind,
    /// Size (SI unit of the component; per s for ramps, per s² for quadratics).
    pub magnitude: f64,
    /// Window start (s).
    pub start: f64,
    /// Window end (s), exclusive.
    pub end: f64,
    /// Satellite name (faults on a `gnss_ranges` sensor only), e.g. `G03`.
    #[serde(default)]
    pub satellite: Option<String>,
}

impl FaultSpec {
    /// Fault value at time `t` (s).
    pub fn value(&self, t: f64) -> f64 {
        if t < self.start || t >= self.end {
            return 0.0;
        }
        let d = t - self.start;
        match self.kind {
            FaultKind::Step => self.magnitude,
            FaultKind::Ramp => self.magnitude * d,
            FaultKind::Quadratic => self.magnitude * d * d,
        }
    }
}

impl ScenarioSpec {
    /// Every fault: sensor, components, shape, satellite, window, and a channel that sees it.
    pub(super) fn validate_faults(&self) -> Result<()> {
        for (i, f) in self.faults.iter().enumerate() {
            let p = format!("faults[{i}]");
            if self.faults[..i].iter().any(|o| o.id == f.id) {
                return Err(bad(
                    format!("{p}.id"),
                    format!("{:?} is used by an earlier fault", f.id),
                ));
            }
            let Some(si) = self.sensor_index(&f.sensor) else {
                return Err(bad(
                    format!("{p}.sensor"),
                    format!(
                        "{:?} is not a sensor (known: {})",
                        f.sensor,
                        self.sensor_names()
                    ),
                ));
            };
            let dim = self.sensors[si].kind.dim();
            if f.components.is_empty() {
                return Err(bad(
                    format!("{p}.components"),
                    "at least one component is required",
                ));
            }
            for (j, c) in f.components.iter().enumerate() {
                if f.components[..j].contains(c) {
                    return Err(bad(
                        format!("{p}.components[{j}]"),
                        format!(
                            "component {:?} is listed twice (the fault would be added twice)",
                            self.sensors[si]
                                .kind
                                .components()
                                .get(*c)
                                .copied()
                                .unwrap_or("?")
                        ),
                    ));
                }
                if *c >= dim {
                    return Err(bad(
                        format!("{p}.components[{j}]"),
                        format!(
                            "index {c} out of range for sensor {:?} with {dim} components",
                            f.sensor
                        ),
                    ));
                }
            }
            if !f.magnitude.is_finite() {
                return Err(bad(format!("{p}.magnitude"), "must be finite"));
            }
            match (&self.sensors[si].ranges, &f.satellite) {
                (Some(r), Some(sat)) => {
                    let orbits = r.orbits();
                    if !orbits.iter().any(|o| &o.name == sat) {
                        return Err(bad(
                            format!("{p}.satellite"),
                            format!(
                                "{sat:?} is not a satellite of sensor {:?} ({} to {})",
                                f.sensor,
                                orbits.first().map_or("", |o| o.name.as_str()),
                                orbits.last().map_or("", |o| o.name.as_str())
                            ),
                        ));
                    }
                }
                (Some(_), None) => {
                    return Err(bad(
                        format!("{p}.satellite"),
                        format!("missing: a fault on the gnss_ranges sensor {:?} names its satellite, e.g. \"G03\"", f.sensor),
                    ))
                }
                (None, Some(_)) => {
                    return Err(bad(
                        format!("{p}.satellite"),
                        format!("only faults on a gnss_ranges sensor name a satellite; {:?} is {:?}", f.sensor, self.sensors[si].kind),
                    ))
                }
                (None, None) => {}
            }
            if !(f.start.is_finite() && f.end.is_finite() && f.start < f.end) {
                return Err(bad(
                    p.clone(),
                    format!(
                        "window start = {}, end = {} must be finite with start < end",
                        f.start, f.end
                    ),
                ));
            }
            let last = (self.epochs().saturating_sub(1)) as f64 * self.dt;
            if f.start > last || f.end <= 0.0 {
                return Err(bad(
                    p.clone(),
                    format!(
                        "window [{}, {}] s lies outside the run, whose epochs span [0, {last}] s",
                        f.start, f.end
                    ),
                ));
            }
            if !self.channels().iter().any(|ch| ch.sensor == f.sensor) {
                // A misspelt sensor in the filter's configuration (or no satellite to track) is
                // the cause to name, not the fault.
                self.check_channel_sensors()?;
                return Err(bad(
                    format!("{p}.sensor"),
                    format!(
                        "no {} uses sensor {:?}, so the fault would never be seen; add one for it or remove the fault",
                        match self.architecture {
                            Architecture::Federated => "sub-filter",
                            Architecture::Centralized => "centralized.sensors entry",
                            Architecture::Tight => "tight filter (tight.sensor)",
                            Architecture::UltraTight => "ultra-tight filter (ultra_tight.sensor)",
                        },
                        f.sensor
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Every sensor the architecture's configuration names exists (and an ultra-tight filter
    /// tracks at least one satellite); errors name the configuration field.
    pub(super) fn check_channel_sensors(&self) -> Result<()> {
        let names: Vec<(String, &str)> = match self.architecture {
            Architecture::Federated => self
                .federated
                .iter()
                .flat_map(|f| {
                    f.subfilters.iter().enumerate().map(|(i, s)| {
                        (
                            format!("federated.subfilters[{i}].sensor"),
                            s.sensor.as_str(),
                        )
                    })
                })
                .collect(),
            Architecture::Centralized => self
                .centralized
                .iter()
                .flat_map(|c| {
                    c.sensors.iter().enumerate().map(|(i, s)| {
                        (
                            format!("centralized.sensors[{i}].sensor"),
                            s.sensor.as_str(),
                        )
                    })
                })
                .collect(),
            Architecture::Tight => self
                .tight
                .iter()
                .map(|t| ("tight.sensor".to_string(), t.sensor.as_str()))
                .collect(),
            Architecture::UltraTight => {
                if let Some(u) = &self.ultra_tight {
                    if u.satellites.is_empty() {
                        return Err(bad(
                            "ultra_tight.satellites",
                            "at least one satellite to track is required",
                        ));
                    }
                }
                self.ultra_tight
                    .iter()
                    .map(|u| ("ultra_tight.sensor".to_string(), u.sensor.as_str()))
                    .collect()
            }
        };
        for (path, name) in names {
            if self.sensor_index(name).is_none() {
                return Err(bad(
                    path,
                    format!("{name:?} is not a sensor (known: {})", self.sensor_names()),
                ));
            }
        }
        Ok(())
    }
}
