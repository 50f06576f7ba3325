//! Auxiliary sensors, the satellites of a `gnss_ranges` sensor, and navigation modes.

use super::check::{bad, non_negative, positive, sensor_scale};
use super::ScenarioSpec;
use crate::error::Result;
use crate::gnss::clock::ClockSpec;
use crate::gnss::constellation::{self, Orbit, System};
use serde::{Deserialize, Serialize};

/// What an auxiliary sensor measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SensorKind {
    /// Celestial attitude: misalignment east, north, up (rad); 3 components.
    Cns,
    /// GNSS position (east, north, up, m) and velocity (east, north, up, m/s); 6 components.
    Gnss,
    /// GNSS position east, north, up (m); 3 components.
    GnssPosition,
    /// GNSS velocity east, north, up (m/s); 3 components.
    GnssVelocity,
    /// Barometric height (m); 1 component.
    Baro,
    /// Vision / SLAM position east, north, up (m); 3 components.
    Vision,
    /// Pseudorange (m) and pseudorange rate (m/s) of every satellite in view (the
    /// components' noise σ); needs the sensor's `ranges` table and architecture `tight`.
    GnssRanges,
    /// Radio altimeter: height above the terrain under the vehicle, used as altitude over a
    /// flat reference (m); 1 component. Its error includes the terrain height
    /// ([`TerrainSpec`](crate::spec::trajectory::TerrainSpec)).
    RadioAltimeter,
}

impl SensorKind {
    /// Number of measurement components.
    pub fn dim(self) -> usize {
        match self {
            SensorKind::Gnss => 6,
            SensorKind::Baro | SensorKind::RadioAltimeter => 1,
            SensorKind::GnssRanges => 2,
            _ => 3,
        }
    }

    /// Component names, in order.
    pub fn components(self) -> &'static [&'static str] {
        match self {
            SensorKind::Cns => &["phi_e", "phi_n", "phi_u"],
            SensorKind::Gnss => &["pos_e", "pos_n", "pos_u", "vel_e", "vel_n", "vel_u"],
            SensorKind::GnssPosition | SensorKind::Vision => &["pos_e", "pos_n", "pos_u"],
            SensorKind::GnssVelocity => &["vel_e", "vel_n", "vel_u"],
            SensorKind::Baro | SensorKind::RadioAltimeter => &["h"],
            SensorKind::GnssRanges => &["pseudorange", "rate"],
        }
    }
}

impl SensorKind {
    /// Index of the height component (up position or altitude), if the sensor has one.
    pub fn height_component(self) -> Option<usize> {
        match self {
            SensorKind::Gnss | SensorKind::GnssPosition | SensorKind::Vision => Some(2),
            SensorKind::Baro | SensorKind::RadioAltimeter => Some(0),
            _ => None,
        }
    }
}

/// An auxiliary sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorSpec {
    /// Unique name, referenced by faults and sub-filters.
    pub name: String,
    /// Measurement type.
    pub kind: SensorKind,
    /// Noise σ per component (SI units of the component), length = kind dimension.
    pub noise: Vec<f64>,
    /// σ per component of a constant offset drawn once per run (e.g. a barometer's bias; the
    /// filter does not model it); empty: none.
    #[serde(default)]
    pub bias: Vec<f64>,
    /// Radio altimeter: noise proportional to the height above the terrain (a fraction, e.g.
    /// 0.02 for ±2 %): σ_k² = noise² + (proportional_noise · AGL_k)², in the simulation and in
    /// the filter's R; 0: none.
    #[serde(default)]
    pub proportional_noise: f64,
    /// Measurement rate (Hz); at most the filter rate.
    pub rate: f64,
    /// Windows `[start, end)` (s) without measurements.
    #[serde(default)]
    pub outages: Vec<[f64; 2]>,
    /// Satellites and clock (kind `gnss_ranges` only).
    #[serde(default)]
    pub ranges: Option<RangesSpec>,
}

/// Satellites and receiver clock of a `gnss_ranges` sensor.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RangesSpec {
    /// Satellite systems (nominal Walker constellations, see [`crate::gnss::constellation`]).
    pub systems: Vec<System>,
    /// Elevation mask (rad).
    pub elevation_mask: f64,
    /// Noise σ grows as `σ / sin(elevation)` when true; constant when false.
    #[serde(default)]
    pub elevation_noise: bool,
    /// Constellation time at the start of the run (s): chooses the geometry.
    #[serde(default)]
    pub epoch: f64,
    /// Receiver clock.
    pub clock: ClockSpec,
    /// Recorded logs only: C/N0 weighting, the C/N0 (dB-Hz) at which σ is `noise`; σ grows
    /// as `10^((cn0_reference − C/N0)/20)` (the σ–ε model's `σ² ∝ 10^(−C/N0/10)`, Hartinger
    /// and Brunner 1999), on top of the elevation growth. None: no C/N0 weighting.
    #[serde(default)]
    pub cn0_reference: Option<f64>,
    /// Simulation only: the time-correlated part of the pseudorange errors, a first-order
    /// Gauss-Markov process per satellite of variance `fraction · σ²` (σ the pseudorange σ
    /// by elevation) and correlation time `tau` (s), the rest of σ² white. None: white.
    #[serde(default)]
    pub correlated: Option<super::tight::RangeStatesSpec>,
}

impl RangesSpec {
    /// The satellites of the configured systems, in order (GPS first).
    pub fn orbits(&self) -> Vec<Orbit> {
        let mut out = Vec::new();
        for s in &self.systems {
            out.extend(match s {
                System::Gps => constellation::gps(),
                System::Galileo => constellation::galileo(),
            });
        }
        out
    }
}

/// Navigation modes (METHODS §9, paper 003): `q3` within `radius` of the `target` point,
/// otherwise `q1` while the `gnss` sensor is outside its outages, `q2` during them. A sensor not
/// in the active mode gives no measurement that epoch (it neither feeds the filter nor is
/// tested).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModesSpec {
    /// Sensor whose outages mean "GNSS unavailable".
    pub gnss: String,
    /// Target point: east, north (m) from the trajectory's start point.
    pub target: [f64; 2],
    /// Radius around the target (m).
    pub radius: f64,
    /// Sensors of mode q1 (GNSS available, away from the target).
    pub q1: Vec<String>,
    /// Sensors of mode q2 (GNSS unavailable, away from the target).
    pub q2: Vec<String>,
    /// Sensors of mode q3 (near the target).
    pub q3: Vec<String>,
}

impl ScenarioSpec {
    pub(super) fn validate_ranges(&self, p: &str, s: &SensorSpec) -> Result<()> {
        let Some(r) = &s.ranges else {
            if s.kind == SensorKind::GnssRanges {
                return Err(bad(
                    format!("{p}.ranges"),
                    "missing: a gnss_ranges sensor needs its satellites and clock (systems, elevation_mask, clock)",
                ));
            }
            return Ok(());
        };
        if s.kind != SensorKind::GnssRanges {
            return Err(bad(
                format!("{p}.ranges"),
                format!(
                    "only a gnss_ranges sensor has satellites; this one is {:?}",
                    s.kind
                ),
            ));
        }
        if r.systems.is_empty() {
            return Err(bad(
                format!("{p}.ranges.systems"),
                "at least one system is required",
            ));
        }
        for (j, sys) in r.systems.iter().enumerate() {
            if r.systems[..j].contains(sys) {
                return Err(bad(
                    format!("{p}.ranges.systems[{j}]"),
                    format!("{sys:?} is listed twice"),
                ));
            }
        }
        if !(r.elevation_mask >= 0.0 && r.elevation_mask < 80f64.to_radians()) {
            return Err(bad(
                format!("{p}.ranges.elevation_mask"),
                format!(
                    "{} deg must be in [0, 80) deg",
                    crate::error::num(r.elevation_mask.to_degrees())
                ),
            ));
        }
        if let Some(c) = r.cn0_reference {
            if !self.runs_on_logs() {
                return Err(bad(
                    format!("{p}.ranges.cn0_reference"),
                    "C/N0 weighting needs recorded C/N0 (a scenario on RINEX logs); the simulated ranges have none",
                ));
            }
            if !(c > 10.0 && c < 70.0) {
                return Err(bad(
                    format!("{p}.ranges.cn0_reference"),
                    format!("{c} dB-Hz: expected a carrier-to-noise density in (10, 70) dB-Hz"),
                ));
            }
        }
        if !r.epoch.is_finite() {
            return Err(bad(format!("{p}.ranges.epoch"), "must be finite"));
        }
        if let Some(c) = &r.correlated {
            if self.runs_on_logs() {
                return Err(bad(
                    format!("{p}.ranges.correlated"),
                    "a simulation setting: a recorded log's range errors are what the receiver recorded (model them with [tight] range_states)",
                ));
            }
            c.validate(&format!("{p}.ranges.correlated"))?;
        }
        positive(&format!("{p}.ranges.clock.bias"), r.clock.bias)?;
        positive(&format!("{p}.ranges.clock.drift"), r.clock.drift)?;
        non_negative(&format!("{p}.ranges.clock.bias_psd"), r.clock.bias_psd)?;
        non_negative(&format!("{p}.ranges.clock.drift_psd"), r.clock.drift_psd)?;
        Ok(())
    }

    /// Every sensor: name, noise, offsets, rate, outages, satellites.
    pub(super) fn validate_sensors(&self) -> Result<()> {
        if self.sensors.is_empty() {
            return Err(bad("sensors", "at least one auxiliary sensor is required"));
        }
        for (i, s) in self.sensors.iter().enumerate() {
            let p = format!("sensors[{i}]");
            if s.name.is_empty() {
                return Err(bad(format!("{p}.name"), "must not be empty"));
            }
            if self.sensors[..i].iter().any(|o| o.name == s.name) {
                return Err(bad(
                    format!("{p}.name"),
                    format!("{:?} is used by an earlier sensor", s.name),
                ));
            }
            if s.noise.len() != s.kind.dim() {
                return Err(bad(
                    format!("{p}.noise"),
                    format!(
                        "{} values given; a {:?} sensor has {} components ({})",
                        s.noise.len(),
                        s.kind,
                        s.kind.dim(),
                        s.kind.components().join(", ")
                    ),
                ));
            }
            for (j, n) in s.noise.iter().enumerate() {
                positive(&format!("{p}.noise[{j}]"), *n)?;
                sensor_scale(&format!("{p}.noise[{j}]"), *n, "noise")?;
            }
            if !s.bias.is_empty() && (s.bias.len() != s.kind.dim() || s.ranges.is_some()) {
                return Err(bad(
                    format!("{p}.bias"),
                    format!(
                        "{} values given; a {:?} sensor has {} components (no bias for gnss_ranges)",
                        s.bias.len(),
                        s.kind,
                        s.kind.dim()
                    ),
                ));
            }
            for (j, b) in s.bias.iter().enumerate() {
                non_negative(&format!("{p}.bias[{j}]"), *b)?;
                sensor_scale(&format!("{p}.bias[{j}]"), *b, "offset")?;
            }
            if s.proportional_noise != 0.0 {
                if s.kind != SensorKind::RadioAltimeter {
                    return Err(bad(
                        format!("{p}.proportional_noise"),
                        format!("only a radio_altimeter's noise scales with the height above the terrain (this one is {:?})", s.kind),
                    ));
                }
                if !(s.proportional_noise > 0.0 && s.proportional_noise < 1.0) {
                    return Err(bad(
                        format!("{p}.proportional_noise"),
                        format!(
                            "{} must be a fraction in (0, 1), e.g. 0.02 for 2 %",
                            crate::error::num(s.proportional_noise)
                        ),
                    ));
                }
            }
            positive(&format!("{p}.rate"), s.rate)?;
            if s.rate * self.dt > 1.0 + 1e-9 {
                return Err(bad(
                    format!("{p}.rate"),
                    format!(
                        "{} Hz exceeds the filter rate 1/dt = {} Hz",
                        s.rate,
                        1.0 / self.dt
                    ),
                ));
            }
            for (j, w) in s.outages.iter().enumerate() {
                if !(w[0].is_finite() && w[1].is_finite() && w[0] < w[1]) {
                    return Err(bad(
                        format!("{p}.outages[{j}]"),
                        format!(
                            "[{}, {}] must be a finite window with start < end",
                            w[0], w[1]
                        ),
                    ));
                }
            }
            self.validate_ranges(&p, s)?;
        }
        Ok(())
    }

    /// Navigation modes.
    pub(super) fn validate_modes(&self) -> Result<()> {
        if let Some(m) = &self.modes {
            if self.sensor_index(&m.gnss).is_none() {
                return Err(bad(
                    "modes.gnss",
                    format!(
                        "{:?} is not a sensor (known: {})",
                        m.gnss,
                        self.sensor_names()
                    ),
                ));
            }
            positive("modes.radius", m.radius)?;
            if !(m.target[0].is_finite() && m.target[1].is_finite()) {
                return Err(bad("modes.target", "must be finite"));
            }
            for (q, list) in [("q1", &m.q1), ("q2", &m.q2), ("q3", &m.q3)] {
                if list.is_empty() {
                    return Err(bad(format!("modes.{q}"), "at least one sensor is required"));
                }
                for (i, name) in list.iter().enumerate() {
                    if self.sensor_index(name).is_none() {
                        return Err(bad(
                            format!("modes.{q}[{i}]"),
                            format!("{name:?} is not a sensor (known: {})", self.sensor_names()),
                        ));
                    }
                    if list[..i].contains(name) {
                        return Err(bad(
                            format!("modes.{q}[{i}]"),
                            format!("{name:?} is listed twice"),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}
