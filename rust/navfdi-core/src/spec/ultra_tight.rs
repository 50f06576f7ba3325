//! Ultra-tight (vector-tracking) configuration (paper 004).

use super::check::{bad, non_negative, positive};
use super::{default_true, ScenarioSpec};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Which AIME the ultra-tight channels run (paper 004's three methods).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AimeMethod {
    /// M1: AIME on the navigation filter's innovations, per satellite (ρ and ρ̇ residual),
    /// at the navigation rate.
    M1,
    /// M2: AIME on the channel prefilter's innovations (code and frequency discriminator),
    /// at the prefilter rate.
    M2,
    /// M3: two-stage AIME on the prefilter innovations.
    M3,
}

impl AimeMethod {
    /// The detector's name in records: `m1`, `m2`, `m3`.
    pub fn name(self) -> &'static str {
        match self {
            AimeMethod::M1 => "m1",
            AimeMethod::M2 => "m2",
            AimeMethod::M3 => "m3",
        }
    }
}

/// What the ultra-tight navigation filter takes from a channel once per epoch.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NavInput {
    /// The epoch's code and frequency discriminator outputs averaged (paper 004 eq. 1–2:
    /// "averaging, not upsampling"), variance σ²/N: independent from epoch to epoch.
    #[default]
    Discriminator,
    /// The prefilter's posterior estimates averaged over the epoch, variance the mean of its
    /// P: correlated from epoch to epoch through the prefilter's memory (the first design,
    /// kept for comparison; docs/liu2022.md).
    Prefilter,
}

/// Ultra-tight (vector-tracking) configuration (paper 004, METHODS §11). Times in s, C/N0 in
/// dB-Hz, prefilter densities in chips²/s and Hz²/s³.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UltraTightSpec {
    /// Name of the `gnss_ranges` sensor.
    pub sensor: String,
    /// Tracked satellites (one channel each), e.g. `["G01", "G05"]`.
    pub satellites: Vec<String>,
    /// Detection method.
    pub method: AimeMethod,
    /// False-alarm probability per test of the method's AIME.
    pub pf: f64,
    /// Carrier-to-noise density of every channel (dB-Hz).
    pub cn0: f64,
    /// Coherent integration time = prefilter step (s; default 0.02).
    #[serde(default = "default_integration")]
    pub integration: f64,
    /// What the navigation filter takes from each channel per epoch (default the averaged
    /// discriminator outputs, as the paper).
    #[serde(default)]
    pub nav_input: NavInput,
    /// M1 window (s; default 20).
    #[serde(default = "default_window20")]
    pub nav_window: f64,
    /// M2 window (s; default 20).
    #[serde(default = "default_window20")]
    pub prefilter_window: f64,
    /// M3 stage-1 window (s; default 2).
    #[serde(default = "default_stage1")]
    pub stage1_window: f64,
    /// M3 stage-2 window (s; default 10).
    #[serde(default = "default_stage2")]
    pub stage2_window: f64,
    /// M3 random-walk variance of the statistic filter per sample it takes (default 10, the
    /// paper's value).
    #[serde(default = "default_stage_q")]
    pub stage_q: f64,
    /// M3: the statistic filter and stage 2 take one stage-1 statistic per `stage_period`
    /// (s, a multiple of the integration time; default 1 s); stage 2's window counts those.
    #[serde(default = "default_stage_period")]
    pub stage_period: f64,
    /// M3: starting measurement noise R₀ of the statistic filter (default 1, METHODS §11).
    #[serde(default = "default_stage_r0")]
    pub stage_r0: f64,
    /// M3 fading factor of the Allan-variance estimate, in [0.9, 0.999] (default 0.99).
    #[serde(default = "default_fading_b")]
    pub fading_b: f64,
    /// Prefilter frequency-rate random-walk density (Hz²/s³; default 1).
    #[serde(default = "default_jerk_psd")]
    pub jerk_psd: f64,
    /// Prefilter code-phase random-walk density (chips²/s; default 0). The simulated truth
    /// interpolates the tracking errors linearly inside an epoch, so the code changes by
    /// the clock drift's integral while the frequency does not follow the drift's random
    /// walk: below `drift_psd·dt²/12` (converted to chips²) the prefilter is inconsistent
    /// with the simulation (docs/liu2022.md).
    #[serde(default)]
    pub code_psd: f64,
    /// Early-late spacing of the delay discriminator (chips; default 1).
    #[serde(default = "default_spacing")]
    pub spacing: f64,
    /// A channel whose AIME alarms stops feeding the navigation filter for the rest of the
    /// run (default true); false: detection reports only.
    #[serde(default = "default_true")]
    pub exclude: bool,
    /// Time from the start before which statistics are recorded but never alarm (s; default
    /// 30): the acquisition and convergence transient of the prefilters and of the
    /// navigation filter from its initial uncertainty.
    #[serde(default = "default_arm_after")]
    pub arm_after: f64,
}

fn default_arm_after() -> f64 {
    30.0
}

fn default_integration() -> f64 {
    0.02
}
fn default_window20() -> f64 {
    20.0
}
fn default_stage1() -> f64 {
    2.0
}
fn default_stage2() -> f64 {
    10.0
}
fn default_stage_q() -> f64 {
    10.0
}
fn default_stage_period() -> f64 {
    1.0
}
fn default_stage_r0() -> f64 {
    1.0
}
fn default_fading_b() -> f64 {
    0.99
}
fn default_jerk_psd() -> f64 {
    1.0
}
fn default_spacing() -> f64 {
    1.0
}

impl ScenarioSpec {
    pub(super) fn validate_ultra_tight(&self) -> Result<()> {
        let u = self.ultra_tight()?;
        self.check_sensor_ref("ultra_tight", &u.sensor, false, "")?;
        let si = self.sensor_index(&u.sensor).unwrap_or(0);
        let Some(ranges) = self.sensors[si].ranges.as_ref() else {
            return Err(bad(
                "ultra_tight.sensor",
                format!(
                    "{:?} is a {:?} sensor; an ultra-tight filter tracks the satellites of a gnss_ranges sensor",
                    u.sensor, self.sensors[si].kind
                ),
            ));
        };
        if let Some((i, o)) = self.sensors.iter().enumerate().find(|(i, _)| *i != si) {
            return Err(bad(
                format!("sensors[{i}]"),
                format!(
                    "{:?}: an ultra-tight filter uses only its gnss_ranges sensor; remove it",
                    o.name
                ),
            ));
        }
        if (self.sensors[si].rate * self.dt - 1.0).abs() > 1e-9 {
            return Err(bad(
                format!("sensors[{si}].rate"),
                format!(
                    "{} Hz: in the ultra-tight architecture the channels are tracked continuously and the sensor's rate is the navigation update rate, which must be 1/dt = {} Hz (outages are signal losses)",
                    crate::error::num(self.sensors[si].rate),
                    crate::error::num(1.0 / self.dt)
                ),
            ));
        }
        if u.satellites.is_empty() {
            return Err(bad(
                "ultra_tight.satellites",
                "track at least one satellite",
            ));
        }
        let names: Vec<String> = ranges.orbits().into_iter().map(|o| o.name).collect();
        for (i, sat) in u.satellites.iter().enumerate() {
            if !names.contains(sat) {
                return Err(bad(
                    format!("ultra_tight.satellites[{i}]"),
                    format!(
                        "{sat:?} is not a satellite of the constellation ({} … {})",
                        names[0],
                        names[names.len() - 1]
                    ),
                ));
            }
            if u.satellites[..i].contains(sat) {
                return Err(bad(
                    format!("ultra_tight.satellites[{i}]"),
                    format!("{sat:?} is listed twice"),
                ));
            }
        }
        for (i, f) in self.faults.iter().enumerate() {
            if f.sensor == u.sensor {
                match &f.satellite {
                    Some(s) if u.satellites.contains(s) => {}
                    _ => {
                        return Err(bad(
                            format!("faults[{i}].satellite"),
                            format!("{:?} is not a tracked channel (ultra_tight.satellites), so the fault would never be seen", f.satellite.as_deref().unwrap_or("(none)")),
                        ))
                    }
                }
            }
        }
        crate::validate::check_probability("ultra_tight.pf", u.pf)
            .map_err(|e| Error::Invalid(e.to_string()))?;
        if !(u.cn0.is_finite() && (15.0..=70.0).contains(&u.cn0)) {
            return Err(bad(
                "ultra_tight.cn0",
                format!(
                    "{} dB-Hz: use 15 … 70 dB-Hz (a tracked signal)",
                    crate::error::num(u.cn0)
                ),
            ));
        }
        if !(u.integration >= 1e-3 && u.integration <= 0.1) {
            return Err(bad(
                "ultra_tight.integration",
                format!("{} s: use 1 … 100 ms", crate::error::num(u.integration)),
            ));
        }
        let steps = self.dt / u.integration;
        if (steps - steps.round()).abs() > 1e-6 || steps.round() < 1.0 {
            return Err(bad(
                "ultra_tight.integration",
                format!(
                    "{} s must divide the filter period dt = {} s into whole steps",
                    crate::error::num(u.integration),
                    crate::error::num(self.dt)
                ),
            ));
        }
        for (name, v, step) in [
            ("nav_window", u.nav_window, self.dt),
            ("prefilter_window", u.prefilter_window, u.integration),
            ("stage1_window", u.stage1_window, u.integration),
            ("stage2_window", u.stage2_window, u.integration),
        ] {
            let n = v / step;
            if !(v.is_finite() && n >= 1.0 - 1e-9 && n <= crate::detect::aime::MAX_WINDOW as f64) {
                return Err(bad(
                    format!("ultra_tight.{name}"),
                    format!(
                        "{} s must hold 1 … {} steps of {} s",
                        crate::error::num(v),
                        crate::detect::aime::MAX_WINDOW,
                        crate::error::num(step)
                    ),
                ));
            }
        }
        positive("ultra_tight.stage_q", u.stage_q)?;
        positive("ultra_tight.stage_r0", u.stage_r0)?;
        let per = u.stage_period / u.integration;
        if !(u.stage_period.is_finite()
            && per.round() >= 1.0
            && (per - per.round()).abs() < 1e-6
            && per <= crate::detect::aime::MAX_WINDOW as f64)
        {
            return Err(bad(
                "ultra_tight.stage_period",
                format!(
                    "{} s must be a whole number of integration times ({} s)",
                    crate::error::num(u.stage_period),
                    crate::error::num(u.integration)
                ),
            ));
        }
        if !(u.arm_after >= 0.0 && u.arm_after <= self.duration) {
            return Err(bad(
                "ultra_tight.arm_after",
                format!(
                    "{} s must be in [0, duration = {} s]",
                    crate::error::num(u.arm_after),
                    crate::error::num(self.duration)
                ),
            ));
        }
        if !(u.fading_b >= 0.9 && u.fading_b <= 0.999) {
            return Err(bad(
                "ultra_tight.fading_b",
                format!(
                    "{}: the paper's range is 0.9 … 0.999",
                    crate::error::num(u.fading_b)
                ),
            ));
        }
        non_negative("ultra_tight.jerk_psd", u.jerk_psd)?;
        non_negative("ultra_tight.code_psd", u.code_psd)?;
        if !(u.spacing > 0.0 && u.spacing < 2.0) {
            return Err(bad(
                "ultra_tight.spacing",
                format!("{} chips must be in (0, 2)", crate::error::num(u.spacing)),
            ));
        }
        Ok(())
    }
}
