//! Trajectory (start state and flight segments) and the terrain under it.

use super::check::{bad, non_negative, positive};
use super::ScenarioSpec;
use crate::error::Result;
use serde::{Deserialize, Serialize};

/// Start state and flight segments.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrajectorySpec {
    /// Start latitude (rad).
    pub latitude: f64,
    /// Start longitude (rad).
    pub longitude: f64,
    /// Start height (m).
    pub height: f64,
    /// Start heading, clockwise from north (rad).
    pub heading: f64,
    /// Start ground speed (m/s).
    #[serde(default)]
    pub speed: f64,
    /// Segments flown in order; the last one is held until the end of the run.
    pub segments: Vec<SegmentSpec>,
}

/// One flight segment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum SegmentSpec {
    /// At rest (speed must be zero).
    Stationary {
        /// Duration (s).
        duration: f64,
    },
    /// Level along-track acceleration (take-off run).
    Accelerate {
        /// Duration (s).
        duration: f64,
        /// Along-track acceleration (m/s²).
        acceleration: f64,
    },
    /// Constant-speed climb.
    Climb {
        /// Duration (s).
        duration: f64,
        /// Climb rate (m/s), positive.
        rate: f64,
    },
    /// Constant-speed level flight.
    Level {
        /// Duration (s).
        duration: f64,
    },
    /// Coordinated level turn.
    Turn {
        /// Duration (s).
        duration: f64,
        /// Turn rate (rad/s), positive to the right (clockwise heading change).
        rate: f64,
    },
    /// Constant-speed descent.
    Descent {
        /// Duration (s).
        duration: f64,
        /// Descent rate (m/s), positive.
        rate: f64,
    },
}

impl SegmentSpec {
    /// Segment duration (s).
    pub fn duration(&self) -> f64 {
        match self {
            SegmentSpec::Stationary { duration }
            | SegmentSpec::Accelerate { duration, .. }
            | SegmentSpec::Climb { duration, .. }
            | SegmentSpec::Level { duration }
            | SegmentSpec::Turn { duration, .. }
            | SegmentSpec::Descent { duration, .. } => *duration,
        }
    }
}

/// One sinusoidal wave of the terrain height field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainWave {
    /// Amplitude (m).
    pub amplitude: f64,
    /// Wavelength (m).
    pub wavelength: f64,
    /// Direction of travel of the wave crests' normal, clockwise from north (rad).
    pub heading: f64,
    /// Phase at the trajectory's start point (rad).
    #[serde(default)]
    pub phase: f64,
}

/// Terrain height above the reference surface as a sum of sinusoids over the local east and
/// north distances (m) from the trajectory's start point (paper 003's "wavy" map):
/// `T(e, n) = Σ A_i sin(2π (e sin θ_i + n cos θ_i) / λ_i + φ_i)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainSpec {
    /// The waves.
    pub waves: Vec<TerrainWave>,
}

impl TerrainSpec {
    /// Terrain height (m) at east `e`, north `n` (m) from the start point.
    pub fn height(&self, e: f64, n: f64) -> f64 {
        self.waves
            .iter()
            .map(|w| {
                let (s, c) = w.heading.sin_cos();
                w.amplitude
                    * (std::f64::consts::TAU * (e * s + n * c) / w.wavelength + w.phase).sin()
            })
            .sum()
    }
}

impl ScenarioSpec {
    /// Lowest height the truth may reach (m): the lowest land surface is about −430 m.
    pub const MIN_HEIGHT: f64 = -500.0;
    /// Highest ground speed the truth may reach (m/s); the INS error model is for aircraft.
    pub const MAX_SPEED: f64 = 3000.0;
    /// Largest along-track acceleration of a segment (m/s², about 10 g).
    pub const MAX_ACCELERATION: f64 = 100.0;

    /// Kinematic limits of the trajectory over the whole run (the last segment is held until
    /// the end): height, speed and acceleration, checked segment by segment in closed form so
    /// that a descent below the surface or a runaway speed is named before anything runs.
    pub(super) fn check_kinematics(&self) -> Result<()> {
        let Some(tr) = self.trajectory.as_ref() else {
            return Ok(());
        };
        let end = self.duration;
        let (mut t0, mut h, mut speed) = (0.0f64, tr.height, tr.speed);
        let n = tr.segments.len();
        for (i, seg) in tr.segments.iter().enumerate() {
            let p = format!("trajectory.segments[{i}]");
            if t0 >= end {
                break;
            }
            let last = i + 1 == n;
            let dur = if last {
                (end - t0).max(0.0)
            } else {
                seg.duration().min(end - t0)
            };
            let held = if last && end - t0 > seg.duration() {
                " (the last segment is held until the end of the run)"
            } else {
                ""
            };
            match *seg {
                SegmentSpec::Accelerate { acceleration, .. } => {
                    if acceleration.abs() > Self::MAX_ACCELERATION {
                        return Err(bad(
                            format!("{p}.acceleration"),
                            format!(
                                "{acceleration} m/s² exceeds the {} m/s² (about 10 g) the INS error model is meant for",
                                Self::MAX_ACCELERATION
                            ),
                        ));
                    }
                    let d = seg.duration().min(end - t0);
                    speed = (speed + acceleration * d).max(0.0);
                    if speed > Self::MAX_SPEED {
                        return Err(bad(
                            p.clone(),
                            format!(
                                "the ground speed reaches {speed:.0} m/s at t = {:.0} s, beyond the {} m/s the model is meant for",
                                t0 + d,
                                Self::MAX_SPEED
                            ),
                        ));
                    }
                }
                SegmentSpec::Climb { rate, .. } => h += rate * dur,
                SegmentSpec::Descent { rate, .. } => {
                    h -= rate * dur;
                    if h < Self::MIN_HEIGHT {
                        let t_hit = t0 + (h + rate * dur - Self::MIN_HEIGHT) / rate;
                        return Err(bad(
                            p.clone(),
                            format!(
                                "the descent goes below the Earth's surface: the height reaches {} m at t = {t_hit:.0} s{held}; shorten the descent or lower its rate",
                                Self::MIN_HEIGHT
                            ),
                        ));
                    }
                }
                _ => {}
            }
            t0 += seg.duration();
        }
        if tr.height < Self::MIN_HEIGHT {
            return Err(bad(
                "trajectory.height",
                format!(
                    "{} m is below the Earth's surface (lowest allowed {} m)",
                    tr.height,
                    Self::MIN_HEIGHT
                ),
            ));
        }
        Ok(())
    }

    /// Start point, segments and terrain.
    pub(super) fn validate_trajectory(&self) -> Result<()> {
        let logged = self.runs_on_logs();
        let tr = match (self.trajectory.as_ref(), logged) {
            (None, true) => return Ok(()),
            (Some(_), true) => return Err(bad("trajectory", "given, but a scenario on recorded logs (loosely_coupled, or tight with tight.strapdown) takes its motion from them (remove [trajectory])")),
            (None, false) => return Err(bad("trajectory", "required: the truth trajectory of a simulated scenario")),
            (Some(tr), false) => tr,
        };
        if !(tr.latitude.abs() < 89.0f64.to_radians()) {
            return Err(bad(
                "trajectory.latitude",
                format!(
                    "{} rad: must be within ±89° (the ENU model is singular at the poles)",
                    tr.latitude
                ),
            ));
        }
        for (p, v) in [
            ("trajectory.longitude", tr.longitude),
            ("trajectory.height", tr.height),
            ("trajectory.heading", tr.heading),
        ] {
            if !v.is_finite() {
                return Err(bad(p, format!("{} must be finite", crate::error::num(v))));
            }
        }
        non_negative("trajectory.speed", tr.speed)?;
        if tr.segments.is_empty() {
            return Err(bad(
                "trajectory.segments",
                "at least one segment is required",
            ));
        }
        self.check_kinematics()?;
        if let Some(t) = &self.terrain {
            for (i, w) in t.waves.iter().enumerate() {
                let p = format!("terrain.waves[{i}]");
                non_negative(&format!("{p}.amplitude"), w.amplitude)?;
                positive(&format!("{p}.wavelength"), w.wavelength)?;
                for (f, v) in [("heading", w.heading), ("phase", w.phase)] {
                    if !v.is_finite() {
                        return Err(bad(format!("{p}.{f}"), "must be finite"));
                    }
                }
            }
        }
        for (i, s) in tr.segments.iter().enumerate() {
            let p = format!("trajectory.segments[{i}]");
            positive(&format!("{p}.duration"), s.duration())?;
            match s {
                SegmentSpec::Accelerate { acceleration, .. } if !acceleration.is_finite() => {
                    return Err(bad(format!("{p}.acceleration"), "must be finite"));
                }
                SegmentSpec::Climb { rate, .. } | SegmentSpec::Descent { rate, .. } => {
                    positive(&format!("{p}.rate"), *rate)?
                }
                SegmentSpec::Turn { rate, .. } if !rate.is_finite() => {
                    return Err(bad(format!("{p}.rate"), "must be finite"))
                }
                _ => {}
            }
        }
        Ok(())
    }
}
