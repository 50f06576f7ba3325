//! The scenario schema in SI units (radians, metres, seconds), one file per part: trajectory
//! and terrain, sensors and modes, faults, detectors, and one file per architecture. The
//! Python layer reads the user's TOML (with explicit units), converts to this structure and
//! passes it as JSON. [`ScenarioSpec::validate`] checks the semantics and names the offending
//! field path in the same spelling as the TOML (`faults[1].sensor`,
//! `federated.subfilters[0].share`, ...).
//!
//! Configuration types sit here, below the sources (`sim`) and the architectures (`arch`) that
//! read them; the few that lower layers need live with those layers and are re-exported here
//! ([`ClockSpec`] in `gnss`, [`FusionMode`] and [`IsolatedMode`] in `fusion`).

mod centralized;
mod check;
mod detectors;
mod faults;
mod federated;
mod loosely_coupled;
mod sensors;
mod tight;
mod trajectory;
mod ultra_tight;

pub use crate::fusion::federated::{FusionMode, IsolatedMode};
pub use crate::gnss::clock::ClockSpec;
pub use centralized::{AltitudeFusionSpec, CentralSensorSpec, CentralizedSpec, Policy};
pub use detectors::{DetectorKind, DetectorSpec, StateChi2Spec};
pub use faults::{FaultKind, FaultSpec};
pub use federated::{FederatedSpec, SubfilterSpec};
pub use loosely_coupled::{AlignmentSpec, ConstraintSpec, LooselyCoupledSpec};
pub use sensors::{ModesSpec, RangesSpec, SensorKind, SensorSpec};
pub use tight::{FdePlacement, FilterIntegritySpec, RangeStatesSpec, TightSpec, TIGHT_DETECTOR};
pub use trajectory::{SegmentSpec, TerrainSpec, TerrainWave, TrajectorySpec};
pub use ultra_tight::{AimeMethod, NavInput, UltraTightSpec};

use crate::error::{Error, Result};
use crate::ins::InsErrorParams;
use check::{bad, non_negative, positive};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// A whole scenario.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ScenarioSpec {
    /// Scenario name.
    pub name: String,
    /// Length of the run (s).
    pub duration: f64,
    /// Filter period (s).
    pub dt: f64,
    /// Truth trajectory (simulated scenarios; a `loosely_coupled` scenario's motion comes from
    /// its recorded logs).
    #[serde(default)]
    pub trajectory: Option<TrajectorySpec>,
    /// IMU error model and initial errors (simulated scenarios).
    #[serde(default)]
    pub ins: Option<InsErrorParams>,
    /// Auxiliary sensors.
    pub sensors: Vec<SensorSpec>,
    /// Injected faults.
    #[serde(default)]
    pub faults: Vec<FaultSpec>,
    /// Integration architecture (default: federated).
    #[serde(default)]
    pub architecture: Architecture,
    /// Federated filter configuration (architecture `federated`).
    #[serde(default)]
    pub federated: Option<FederatedSpec>,
    /// Centralized filter configuration (architecture `centralized`).
    #[serde(default)]
    pub centralized: Option<CentralizedSpec>,
    /// Tightly coupled filter configuration (architecture `tight`).
    #[serde(default)]
    pub tight: Option<TightSpec>,
    /// Ultra-tight (vector-tracking) configuration (architecture `ultra_tight`).
    #[serde(default)]
    pub ultra_tight: Option<UltraTightSpec>,
    /// Loosely coupled strapdown INS configuration (architecture `loosely_coupled`).
    #[serde(default)]
    pub loosely_coupled: Option<LooselyCoupledSpec>,
    /// Terrain under the trajectory (radio altimeters); flat when absent.
    #[serde(default)]
    pub terrain: Option<TerrainSpec>,
    /// Dual-propagator state chi-square test on the navigation solution (any architecture).
    #[serde(default)]
    pub state_chi2: Option<StateChi2Spec>,
    /// Navigation modes (paper 003): which sensors feed the filter, epoch by epoch.
    #[serde(default)]
    pub modes: Option<ModesSpec>,
}

/// Integration architecture of a scenario.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Architecture {
    /// One sub-filter per sensor, master fusion, isolation (paper 000).
    #[default]
    Federated,
    /// One Kalman filter over the INS error state updated by all chosen sensors, detectors
    /// per sensor and a fault-handling policy (paper 002).
    Centralized,
    /// INS error state plus receiver clock (17 states) updated with the pseudoranges and
    /// pseudorange rates of the satellites in view, with satellite FDE (paper 001).
    Tight,
    /// The 17-state filter at the navigation rate on pseudorange and rate residuals averaged
    /// from per-channel prefilters at 50 Hz, with vector tracking and AIME (paper 004).
    UltraTight,
    /// A strapdown INS mechanised from recorded IMU samples in a closed-loop 15-state
    /// error-state filter, aided by GNSS positions and velocities and by vehicle constraints
    /// (zero velocity, non-holonomic), each with its detectors.
    LooselyCoupled,
}

/// A detection channel: a sensor tested by detectors, whatever the architecture (a federated
/// sub-filter, one sensor of a centralized filter, the satellites of a tight filter).
#[derive(Debug, Clone)]
pub struct Channel<'a> {
    /// Sensor name.
    pub sensor: &'a str,
    /// Detectors (a tight filter's one detector, `global`, is made from its settings).
    pub detectors: Cow<'a, [DetectorSpec]>,
    /// Detector whose alarm isolates / excludes (None: none).
    pub decision: Option<&'a str>,
    /// The satellite of an ultra-tight channel (None: the channel is the whole sensor).
    pub satellite: Option<&'a str>,
}

impl Channel<'_> {
    /// The channel's name in records and tables: its satellite (ultra-tight), else its sensor.
    pub fn name(&self) -> &str {
        self.satellite.unwrap_or(self.sensor)
    }

    /// Whether fault `f` is one this channel should detect: on its sensor and, for a
    /// satellite channel, on its satellite.
    pub fn sees(&self, f: &FaultSpec) -> bool {
        f.sensor == self.sensor
            && self
                .satellite
                .is_none_or(|s| f.satellite.as_deref() == Some(s))
    }
}

fn default_true() -> bool {
    true
}

impl ScenarioSpec {
    /// Parse from JSON (the form the Python layer produces) and validate.
    pub fn from_json(s: &str) -> Result<Self> {
        let spec: ScenarioSpec =
            serde_json::from_str(s).map_err(|e| Error::Invalid(format!("scenario: {e}")))?;
        spec.validate()?;
        Ok(spec)
    }

    /// Estimated bytes for the prepared scenario plus `runs` runs held at once (simulated
    /// measurements and the per-epoch record of each run). Computed in floating point so that
    /// absurd durations cannot overflow.
    pub fn memory_estimate(&self, runs: f64) -> f64 {
        let epochs = (self.duration / self.dt + 1e-9).floor().max(1.0);
        let n = self.n_states() as f64;
        let mat = |r: f64, c: f64| r * c * 8.0 + 48.0;
        // Prepared: Φ, Q and a factor of Q per epoch, the truth epoch, times; per sensor H,
        // the fault vector and the availability flag.
        let mut prep = 3.0 * mat(n, n) + 360.0 + 8.0;
        // One run: the true state, measurements; the record: error and sigma (9 each), sources.
        let mut run = mat(n, 1.0) + 2.0 * 9.0 * 8.0 + 4.0;
        for s in &self.sensors {
            let mut m = s.kind.dim() as f64;
            if let Some(r) = &s.ranges {
                // Every satellite could be in view: per satellite and epoch its ECEF position,
                // velocity, line of sight, range, rate, σ, fault (prepared), raw observations
                // and the FDE record (run).
                let sats = r.orbits().len() as f64;
                m *= sats;
                prep += sats * (3.0 * 24.0 + 6.0 * 8.0 + 8.0);
                run += mat(m, 1.0) + sats * (8.0 + 3.0);
            }
            prep += mat(m, n) + mat(m, 1.0) + 1.0;
            run += mat(m, 1.0);
        }
        for ch in self.channels() {
            run += 8.0 + 4.0 + 3.0 + ch.detectors.len() as f64 * 17.0;
        }
        if self.tight.as_ref().is_some_and(|t| t.integrity.is_some()) {
            // The integrity record: four levels, the statistic, the alarm and the mode count.
            run += 5.0 * 8.0 + 1.0 + 4.0;
        }
        epochs * (prep + runs * run)
    }

    /// The detection channels in configuration order.
    pub fn channels(&self) -> Vec<Channel<'_>> {
        match self.architecture {
            Architecture::Federated => self.federated.as_ref().map_or_else(Vec::new, |f| {
                f.subfilters
                    .iter()
                    .map(|sf| Channel {
                        sensor: &sf.sensor,
                        detectors: Cow::Borrowed(&sf.detectors),
                        decision: sf.isolation.as_deref(),
                        satellite: None,
                    })
                    .collect()
            }),
            Architecture::Centralized => self.centralized.as_ref().map_or_else(Vec::new, |c| {
                c.sensors
                    .iter()
                    .map(|cs| Channel {
                        sensor: &cs.sensor,
                        detectors: Cow::Borrowed(&cs.detectors),
                        decision: cs.decision.as_deref(),
                        satellite: None,
                    })
                    .collect()
            }),
            Architecture::Tight => self.tight.as_ref().map_or_else(Vec::new, |t| {
                vec![Channel {
                    sensor: &t.sensor,
                    detectors: Cow::Owned(vec![DetectorSpec {
                        name: TIGHT_DETECTOR.into(),
                        kind: DetectorKind::Chi2,
                        pf: t.alpha,
                        pm: None,
                        variance: None,
                        min_samples: None,
                    }]),
                    decision: (t.fde != FdePlacement::None).then_some(TIGHT_DETECTOR),
                    satellite: None,
                }]
            }),
            Architecture::UltraTight => self.ultra_tight.as_ref().map_or_else(Vec::new, |u| {
                u.satellites
                    .iter()
                    .map(|sat| Channel {
                        sensor: &u.sensor,
                        detectors: Cow::Owned(vec![DetectorSpec {
                            name: u.method.name().into(),
                            kind: DetectorKind::Chi2,
                            pf: u.pf,
                            pm: None,
                            variance: None,
                            min_samples: None,
                        }]),
                        decision: u.exclude.then_some(u.method.name()),
                        satellite: Some(sat),
                    })
                    .collect()
            }),
            Architecture::LooselyCoupled => self
                .loosely_coupled
                .as_ref()
                .map_or_else(Vec::new, |l| l.channels()),
        }
    }

    /// The tight configuration (validated to exist for that architecture).
    pub fn tight(&self) -> Result<&TightSpec> {
        self.tight
            .as_ref()
            .ok_or_else(|| bad("tight", "missing (architecture = \"tight\")"))
    }

    /// The ultra-tight configuration (validated to exist for that architecture).
    pub fn ultra_tight(&self) -> Result<&UltraTightSpec> {
        self.ultra_tight
            .as_ref()
            .ok_or_else(|| bad("ultra_tight", "missing (architecture = \"ultra_tight\")"))
    }

    /// Number of filter states: 15 (INS error), 17 with a receiver clock (a `gnss_ranges`
    /// sensor).
    pub fn n_states(&self) -> usize {
        if self
            .sensors
            .iter()
            .any(|s| s.kind == SensorKind::GnssRanges)
        {
            crate::ins::N_STATES + 2
        } else {
            crate::ins::N_STATES
        }
    }

    /// The federated configuration (validated to exist for that architecture).
    pub fn federated(&self) -> Result<&FederatedSpec> {
        self.federated
            .as_ref()
            .ok_or_else(|| bad("federated", "missing (architecture = \"federated\")"))
    }

    /// The centralized configuration (validated to exist for that architecture).
    pub fn centralized(&self) -> Result<&CentralizedSpec> {
        self.centralized
            .as_ref()
            .ok_or_else(|| bad("centralized", "missing (architecture = \"centralized\")"))
    }

    /// Refuse a scenario whose prepared data and `runs` simultaneous runs would not fit in
    /// memory ([`crate::memory::check`]); the message names `duration` and `dt`.
    pub fn check_memory(&self, runs: f64) -> Result<()> {
        let epochs = (self.duration / self.dt + 1e-9).floor();
        crate::memory::check(
            "scenario",
            self.memory_estimate(runs),
            &format!(
                "{} epochs = duration {} s / dt {} s, {runs} run(s) at once",
                crate::error::num(epochs),
                crate::error::num(self.duration),
                crate::error::num(self.dt)
            ),
            "shorten duration or increase dt",
        )
    }

    /// Check that `variant` (validated here) may run on this scenario's measurements: it may
    /// differ only in its filter (`architecture`, `federated`, `centralized`, `tight`,
    /// `ultra_tight`, `state_chi2`); anything else differing is an error naming the field.
    pub fn check_variant(&self, variant: &ScenarioSpec) -> Result<()> {
        variant.validate()?;
        let (base, spec) = (self, variant);
        let same = [
            ("duration", base.duration == spec.duration),
            ("dt", base.dt == spec.dt),
            ("trajectory", base.trajectory == spec.trajectory),
            ("ins", base.ins == spec.ins),
            ("sensors", base.sensors == spec.sensors),
            ("faults", base.faults == spec.faults),
            ("terrain", base.terrain == spec.terrain),
            ("modes", base.modes == spec.modes),
        ];
        if let Some((field, _)) = same.iter().find(|(_, eq)| !eq) {
            return Err(Error::Invalid(format!(
                "variant {:?}: its {field} differ from the base scenario's; variants may only change the filter (architecture, federated, centralized, tight) so that they run on the same simulated measurements",
                spec.name
            )));
        }
        Ok(())
    }

    /// Number of filter epochs: `floor(duration / dt)`.
    pub fn epochs(&self) -> usize {
        (self.duration / self.dt + 1e-9).floor() as usize
    }

    /// Index of a sensor by name.
    pub fn sensor_index(&self, name: &str) -> Option<usize> {
        self.sensors.iter().position(|s| s.name == name)
    }

    /// Check the semantics; errors name the field path.
    pub fn validate(&self) -> Result<()> {
        positive("duration", self.duration)?;
        positive("dt", self.dt)?;
        if self.epochs() < 1 {
            return Err(bad(
                "duration",
                format!(
                    "{} s is shorter than one filter period dt = {} s",
                    self.duration, self.dt
                ),
            ));
        }
        // One run with isolation and its no-isolation baseline, as `navfdi run` holds them.
        self.check_memory(2.0)?;
        self.validate_trajectory()?;
        self.validate_ins()?;
        self.validate_sensors()?;
        self.validate_faults()?;
        let others: Vec<(&str, bool)> = vec![
            ("federated", self.federated.is_some()),
            ("centralized", self.centralized.is_some()),
            ("tight", self.tight.is_some()),
            ("ultra_tight", self.ultra_tight.is_some()),
            ("loosely_coupled", self.loosely_coupled.is_some()),
        ];
        let arch = match self.architecture {
            Architecture::Federated => "federated",
            Architecture::Centralized => "centralized",
            Architecture::Tight => "tight",
            Architecture::UltraTight => "ultra_tight",
            Architecture::LooselyCoupled => "loosely_coupled",
        };
        for (name, given) in others {
            if given && name != arch {
                return Err(bad(
                    name,
                    format!("given, but architecture is {arch:?} (set architecture = {name:?} or remove it)"),
                ));
            }
        }
        if arch != "tight" && arch != "ultra_tight" {
            if let Some((i, _)) = self
                .sensors
                .iter()
                .enumerate()
                .find(|(_, s)| s.kind == SensorKind::GnssRanges)
            {
                return Err(bad(
                    format!("sensors[{i}].kind"),
                    format!("gnss_ranges (satellite pseudoranges) needs architecture = \"tight\" or \"ultra_tight\", not {arch:?}"),
                ));
            }
        }
        self.validate_modes()?;
        self.validate_state_chi2()?;
        match self.architecture {
            Architecture::Tight => self.validate_tight(),
            Architecture::UltraTight => self.validate_ultra_tight(),
            Architecture::Federated => self.validate_federated(),
            Architecture::Centralized => self.validate_centralized(),
            Architecture::LooselyCoupled => self.validate_loosely_coupled(),
        }
    }

    /// Whether the scenario runs a strapdown INS on recorded logs (architecture
    /// `loosely_coupled`, or `tight` with `tight.strapdown`) rather than a simulation.
    pub fn runs_on_logs(&self) -> bool {
        match self.architecture {
            Architecture::LooselyCoupled => true,
            Architecture::Tight => self.tight.as_ref().is_some_and(|t| t.strapdown.is_some()),
            _ => false,
        }
    }

    fn validate_ins(&self) -> Result<()> {
        let logged = self.runs_on_logs();
        let Some(ins) = self.ins.as_ref() else {
            if logged {
                return Ok(());
            }
            return Err(bad(
                "ins",
                "required: the IMU error model of a simulated scenario",
            ));
        };
        if logged {
            return Err(bad("ins", "given, but this scenario runs a strapdown INS on recorded IMU samples: its noise figures are loosely_coupled.imu or tight.strapdown.imu"));
        }

        for (p, v) in [
            ("ins.gyro_bias", ins.gyro_bias),
            ("ins.gyro_white", ins.gyro_white),
            ("ins.gyro_markov", ins.gyro_markov),
            ("ins.accel_markov", ins.accel_markov),
            ("ins.init_level", ins.init_level),
            ("ins.init_heading", ins.init_heading),
            ("ins.init_velocity", ins.init_velocity),
            ("ins.init_position", ins.init_position),
        ] {
            non_negative(p, v)?;
        }
        positive("ins.gyro_tau", ins.gyro_tau)?;
        positive("ins.accel_tau", ins.accel_tau)?;
        for p in [
            ins.init_level,
            ins.init_heading,
            ins.init_velocity,
            ins.init_position,
        ] {
            if p == 0.0 {
                return Err(bad("ins", "initial-error standard deviations must be positive (P0 must be positive definite)"));
            }
        }

        Ok(())
    }

    /// The truth trajectory of a simulated scenario.
    pub fn trajectory(&self) -> Result<&TrajectorySpec> {
        self.trajectory.as_ref().ok_or_else(|| {
            bad(
                "trajectory",
                "required: the truth trajectory of a simulated scenario",
            )
        })
    }

    /// The IMU error model of a simulated scenario.
    pub fn ins(&self) -> Result<&InsErrorParams> {
        self.ins.as_ref().ok_or_else(|| {
            bad(
                "ins",
                "required: the IMU error model of a simulated scenario",
            )
        })
    }

    /// The loosely coupled configuration (validated to exist for that architecture).
    pub fn loosely_coupled(&self) -> Result<&LooselyCoupledSpec> {
        self.loosely_coupled.as_ref().ok_or_else(|| {
            bad(
                "loosely_coupled",
                "required by architecture \"loosely_coupled\"",
            )
        })
    }

    fn sensor_names(&self) -> String {
        self.sensors
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}
