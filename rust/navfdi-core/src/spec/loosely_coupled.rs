//! Loosely coupled strapdown INS configuration: the IMU's noise figures and mounting, the
//! antenna lever arm, initial alignment, the GNSS sensors that aid it (each with detectors and
//! a deciding detector) and the optional vehicle constraints (zero velocity, non-holonomic),
//! each a detection channel like any sensor.

use super::check::{bad, non_negative, positive};
use super::detectors::DetectorSpec;
use super::{default_true, CentralSensorSpec, Channel, ScenarioSpec, SensorKind};
use crate::error::Result;
use crate::ins::error_filter::ImuNoise;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// Name of the zero-velocity channel in records.
pub const ZUPT: &str = "zupt";
/// Name of the non-holonomic-constraint channel in records.
pub const NHC: &str = "nhc";

/// Initial alignment of the strapdown INS.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AlignmentSpec {
    /// GNSS ground speed (m/s) above which the heading is taken from the GNSS velocity's
    /// course and navigation starts.
    pub speed: f64,
    /// Heading at the start of navigation (rad from north), instead of the GNSS course.
    #[serde(default)]
    pub heading: Option<f64>,
    /// GNSS ground speed (m/s) below which the vehicle counts as at rest for the static
    /// levelling and gyro-bias estimate before it starts moving.
    #[serde(default = "default_static_speed")]
    pub static_speed: f64,
    /// Estimate the gyro biases as the mean rate over the static start (else start at 0).
    #[serde(default = "default_true")]
    pub gyro_bias: bool,
    /// Initial σ: level (roll, pitch) attitude (rad).
    pub sigma_level: f64,
    /// Initial σ: heading (rad); with the heading from the GNSS course, at least the course's
    /// own σ (velocity σ over speed) is used.
    pub sigma_heading: f64,
    /// Initial σ: position (m) and velocity (m/s) per axis.
    pub sigma_position: f64,
    /// See [`AlignmentSpec::sigma_position`].
    pub sigma_velocity: f64,
}

fn default_static_speed() -> f64 {
    0.05
}

/// A vehicle constraint used as a measurement.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintSpec {
    /// Noise σ per component (m/s): zero velocity north, east, down (3); non-holonomic body
    /// right and down velocity (2).
    pub noise: Vec<f64>,
    /// Detectors run on the constraint's innovation.
    #[serde(default)]
    pub detectors: Vec<DetectorSpec>,
    /// Detector whose alarm drops the constraint for the epoch (None: never).
    #[serde(default)]
    pub decision: Option<String>,
    /// Zero velocity: IMU window (s) over which rest is detected. Non-holonomic: unused.
    #[serde(default = "default_window")]
    pub window: f64,
    /// Zero velocity: largest σ of the specific-force magnitude over the window (m/s²).
    /// Non-holonomic: least INS speed (m/s) for the constraint to apply.
    pub threshold: f64,
    /// Zero velocity: largest mean magnitude of the bias-corrected angular rate over the
    /// window (rad/s). Non-holonomic: largest yaw rate (rad/s) for it to apply (sliding in
    /// tight turns).
    pub rate_threshold: f64,
}

fn default_window() -> f64 {
    0.5
}

/// Loosely coupled configuration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LooselyCoupledSpec {
    /// The IMU's noise figures.
    pub imu: ImuNoise,
    /// IMU-to-body mounting roll, pitch, yaw (rad; body forward-right-down).
    pub mounting: [f64; 3],
    /// GNSS antenna position from the IMU in body axes, forward-right-down (m).
    pub lever_arm: [f64; 3],
    /// Seconds added to the IMU time stamps (logging delay).
    #[serde(default)]
    pub imu_time_offset: f64,
    /// Initial alignment.
    pub alignment: AlignmentSpec,
    /// GNSS sensors aiding the INS, updated in this order, each with its detectors and the
    /// detector whose alarm excludes its measurement (a centralized sensor's fields).
    pub sensors: Vec<CentralSensorSpec>,
    /// Zero-velocity updates at rest detected from the IMU.
    #[serde(default)]
    pub zupt: Option<ConstraintSpec>,
    /// Non-holonomic constraint (no lateral or vertical body velocity) for wheeled vehicles.
    #[serde(default)]
    pub nhc: Option<ConstraintSpec>,
    /// A GNSS channel's alarm excludes it only when another GNSS channel of the same epoch
    /// passes its test (default): when position and velocity both alarm, the INS is as likely
    /// at fault (after an outage, or a manoeuvre beyond its noise model) and excluding both
    /// would lock good GNSS out. `false`: every alarm excludes.
    #[serde(default = "default_true")]
    pub witness: bool,
    /// An alarming GNSS measurement keeps the components that pass: the one with the largest
    /// w-test statistic is left out until the χ² test of the rest passes at the deciding
    /// detector's pf (default). `false`: the whole measurement is excluded.
    #[serde(default = "default_true")]
    pub isolate_components: bool,
    /// An isolated position component is accommodated (default): its offset from the INS when
    /// isolated is removed from its later fixes, which are used as relative fixes while that
    /// offset explains them (a step fault); when it does not (a ramp, the fault's end) the
    /// component is excluded, and used as it is again once it agrees with the INS.
    #[serde(default = "default_true")]
    pub accommodate: bool,
    /// Deciding detectors act (default). `false`: they report but every measurement is used.
    #[serde(default = "default_true")]
    pub isolate: bool,
    /// Convergence rule: the filter counts as converged from the first epoch at which every
    /// tested GNSS channel's predicted σ (`√(mean diag H P Hᵀ)`, before the update) is at most
    /// this multiple of the measurement's own σ (`√(mean diag R)`). Until then the tests
    /// report, but a measurement is excluded only when its innovation is gross (`λ` over 16
    /// times the deciding threshold: |w| above 4 times its critical value): an unsettled
    /// filter's innovations are not yet a fault's evidence. 0: converged from the start.
    #[serde(default = "default_convergence")]
    pub convergence: f64,
    /// Scale of the GNSS measurement σ in the tests: None (`"auto"`, default) estimates it per
    /// channel from its own innovations (median-based, over the last 60 fixes used as
    /// measured; clamped to [1, 10]: an optimistic σ no longer makes the tests alarm at good
    /// fixes, and they never get more sensitive than the σ given — on the bundled RTK drive the
    /// innovations' median is half the σ floor, and tests twice as sensitive cost accuracy in
    /// its manoeuvres); a number fixes it. The filter's update uses the σ as given either way.
    #[serde(default)]
    pub noise_scale: Option<f64>,
    /// Correlation time τ (s) of the GNSS position errors, as a first-order Gauss-Markov
    /// process: in the update each fix counts as the fraction `(1 − ρ)/(1 + ρ)` of an
    /// independent fix that it is worth (`ρ = e^(−Δt/τ)`, Δt the fix interval), i.e. its
    /// position variance is multiplied by `(1 + ρ)/(1 − ρ)` (not in the tests, whose σ is the
    /// errors' size). 0 (default): white errors, the update as before. None (`"auto"`): the
    /// errors' white and correlated parts and τ estimated from the log's fixes and the
    /// receiver's velocities, the fix weighted by `(σ_w² + σ_g² (1 + ρ)/(1 − ρ)) / (σ_w² + σ_g²)`
    /// (white where the log does not show a correlation, or has no velocities).
    #[serde(default = "default_correlation")]
    pub position_correlation: Option<f64>,
}

fn default_correlation() -> Option<f64> {
    Some(0.0)
}

fn default_convergence() -> f64 {
    3.0
}

impl LooselyCoupledSpec {
    /// Detection channels: the aiding sensors, then `zupt` and `nhc` when configured.
    pub fn channels(&self) -> Vec<Channel<'_>> {
        let mut out: Vec<Channel> = self
            .sensors
            .iter()
            .map(|a| Channel {
                sensor: &a.sensor,
                detectors: Cow::Borrowed(&a.detectors),
                decision: a.decision.as_deref(),
                satellite: None,
            })
            .collect();
        for (name, c) in [(ZUPT, &self.zupt), (NHC, &self.nhc)] {
            if let Some(c) = c {
                out.push(Channel {
                    sensor: name,
                    detectors: Cow::Borrowed(&c.detectors),
                    decision: c.decision.as_deref(),
                    satellite: None,
                });
            }
        }
        out
    }
}

impl ScenarioSpec {
    pub(super) fn validate_loosely_coupled(&self) -> Result<()> {
        let l = self.loosely_coupled()?;
        let p = "loosely_coupled";
        validate_strapdown(
            p,
            &l.imu,
            &l.mounting,
            &l.lever_arm,
            l.imu_time_offset,
            &l.alignment,
        )?;
        if l.sensors.is_empty() {
            return Err(bad(
                format!("{p}.sensors"),
                "at least one GNSS sensor is required",
            ));
        }
        for (i, a) in l.sensors.iter().enumerate() {
            let q = format!("{p}.sensors[{i}]");
            let dup = l.sensors[..i].iter().any(|o| o.sensor == a.sensor);
            self.check_sensor_ref(&q, &a.sensor, dup, "is listed twice")?;
            let si = self.sensor_index(&a.sensor).unwrap_or(0);
            let kind = self.sensors[si].kind;
            if !matches!(
                kind,
                SensorKind::Gnss | SensorKind::GnssPosition | SensorKind::GnssVelocity
            ) {
                return Err(bad(
                    format!("{q}.sensor"),
                    format!("{:?} is {kind:?}: a loosely coupled INS is aided by gnss, gnss_position or gnss_velocity sensors", a.sensor),
                ));
            }
            self.validate_detectors(&q, &a.detectors, false)?;
            check_decision(&q, &a.decision, &a.detectors)?;
        }
        // A GNSS sensor the INS is not given would be silently unused (a receiver's velocities
        // left out turn the run into one on positions alone).
        if let Some((i, s)) = self.sensors.iter().enumerate().find(|(_, s)| {
            matches!(
                s.kind,
                SensorKind::Gnss | SensorKind::GnssPosition | SensorKind::GnssVelocity
            ) && !l.sensors.iter().any(|a| a.sensor == s.name)
        }) {
            return Err(bad(
                format!("sensors[{i}]"),
                format!(
                    "{:?} (kind {}) is not in [[{p}.sensors]], so the INS would not use it: add {{ sensor = {:?}, detectors = [...], decision = \"exclude\" }} there, or remove it",
                    s.name,
                    serde_json::to_string(&s.kind).unwrap_or_default().trim_matches('"'),
                    s.name
                ),
            ));
        }
        for (name, c, dim) in [(ZUPT, &l.zupt, 3), (NHC, &l.nhc, 2)] {
            let Some(c) = c else { continue };
            let q = format!("{p}.{name}");
            if c.noise.len() != dim || c.noise.iter().any(|v| !(*v > 0.0 && v.is_finite())) {
                return Err(bad(
                    format!("{q}.noise"),
                    format!("{dim} positive finite σ (m/s) are required"),
                ));
            }
            positive(&format!("{q}.window"), c.window)?;
            non_negative(&format!("{q}.threshold"), c.threshold)?;
            non_negative(&format!("{q}.rate_threshold"), c.rate_threshold)?;
            self.validate_detectors(&q, &c.detectors, false)?;
            check_decision(&q, &c.decision, &c.detectors)?;
        }
        if !(l.convergence >= 0.0 && l.convergence <= 1e6) {
            return Err(bad(
                format!("{p}.convergence"),
                format!(
                    "{}: a multiple of the GNSS σ in [0, 1e6] (0: converged from the start)",
                    l.convergence
                ),
            ));
        }
        if let Some(tau) = l.position_correlation {
            if !(0.0..=1e5).contains(&tau) {
                return Err(bad(
                    format!("{p}.position_correlation"),
                    format!(
                        "{tau} s: a correlation time in [0, 1e5] s (0: white errors) or \"auto\""
                    ),
                ));
            }
        }
        if let Some(c) = l.noise_scale {
            if !(c > 0.0 && c <= 1e3) {
                return Err(bad(
                    format!("{p}.noise_scale"),
                    format!("{c}: \"auto\" or a positive factor up to 1000"),
                ));
            }
        }
        if self.state_chi2.is_some() {
            return Err(bad("state_chi2", "the state chi-square test needs the error model's Φ and Q of a simulated scenario; it is not available with loosely_coupled"));
        }
        if self.sensors.iter().any(|s| s.name == ZUPT || s.name == NHC) {
            return Err(bad("sensors", "the names \"zupt\" and \"nhc\" are the constraint channels' of a loosely coupled INS; rename the sensor"));
        }
        Ok(())
    }
}

/// Check a strapdown INS's IMU noise figures, mounting, lever arm, time offset and alignment
/// (errors name the field under `p`).
pub(super) fn validate_strapdown(
    p: &str,
    imu: &ImuNoise,
    mounting: &[f64; 3],
    lever_arm: &[f64; 3],
    imu_time_offset: f64,
    alignment: &AlignmentSpec,
) -> Result<()> {
    for (n, v) in imu
        .gyro_noise
        .iter()
        .map(|v| ("imu.gyro_noise", *v))
        .chain(imu.accel_noise.iter().map(|v| ("imu.accel_noise", *v)))
        .chain([
            ("imu.gyro_bias", imu.gyro_bias),
            ("imu.accel_bias", imu.accel_bias),
            ("imu.bias_tau", imu.bias_tau),
            ("alignment.speed", alignment.speed),
            ("alignment.static_speed", alignment.static_speed),
            ("alignment.sigma_level", alignment.sigma_level),
            ("alignment.sigma_heading", alignment.sigma_heading),
            ("alignment.sigma_position", alignment.sigma_position),
            ("alignment.sigma_velocity", alignment.sigma_velocity),
        ])
    {
        positive(&format!("{p}.{n}"), v)?;
    }
    for (n, v) in [
        ("imu.gyro_scale", imu.gyro_scale),
        ("imu.accel_scale", imu.accel_scale),
    ] {
        non_negative(&format!("{p}.{n}"), v)?;
        if v >= 0.1 {
            return Err(bad(
                format!("{p}.{n}"),
                format!("{v}: a scale-factor σ is a small fraction (e.g. 1e-3 for 1000 ppm)"),
            ));
        }
    }
    for (i, v) in mounting.iter().chain(lever_arm.iter()).enumerate() {
        if !v.is_finite() {
            let f = if i < 3 { "mounting" } else { "lever_arm" };
            return Err(bad(format!("{p}.{f}"), "must be finite numbers"));
        }
    }
    if lever_arm.iter().any(|v| v.abs() > 100.0) {
        return Err(bad(
            format!("{p}.lever_arm"),
            "a component exceeds 100 m: give it in metres",
        ));
    }
    if !(imu_time_offset.abs() <= 10.0) {
        return Err(bad(format!("{p}.imu_time_offset"), "must be within ±10 s"));
    }
    if let Some(h) = alignment.heading {
        if !h.is_finite() {
            return Err(bad(format!("{p}.alignment.heading"), "must be finite"));
        }
    }
    Ok(())
}

fn check_decision(q: &str, decision: &Option<String>, dets: &[DetectorSpec]) -> Result<()> {
    if let Some(dn) = decision {
        if !dets.iter().any(|d| &d.name == dn) {
            return Err(bad(
                format!("{q}.decision"),
                format!("{dn:?} is not one of its detectors"),
            ));
        }
    }
    Ok(())
}
