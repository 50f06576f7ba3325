//! The scenario schema in SI units (radians, metres, seconds). The Python layer reads the
//! user's TOML (with explicit units), converts to this structure and passes it as JSON.
//! [`ScenarioSpec::validate`] checks the semantics and names the offending field path in the
//! same spelling as the TOML (`faults[1].sensor`, `federated.subfilters[0].share`, ...).

use crate::error::{Error, Result};
use crate::gnss::constellation::{self, Orbit, System};
use crate::ins::InsErrorParams;
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
    /// Truth trajectory.
    pub trajectory: TrajectorySpec,
    /// IMU error model and initial errors.
    pub ins: InsErrorParams,
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
}

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

/// Receiver clock model: bias (m) and drift (m/s) as a two-state random process with
/// white frequency noise (`bias_psd`, m²/s) and random-walk frequency noise (`drift_psd`,
/// m²/s³); `bias` and `drift` are the initial standard deviations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClockSpec {
    /// Initial clock-bias σ (m).
    pub bias: f64,
    /// Initial clock-drift σ (m/s).
    pub drift: f64,
    /// Spectral density of the bias noise (m²/s).
    pub bias_psd: f64,
    /// Spectral density of the drift noise (m²/s³).
    pub drift_psd: f64,
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

fn default_fading() -> f64 {
    1.0
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
    /// flat reference (m); 1 component. Its error includes the terrain height ([`TerrainSpec`]).
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

/// Federated fusion mode (METHODS §5).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FusionMode {
    /// After fusion each healthy sub-filter is reset to `x_g`, `P_g/β_i` (Carlson).
    Reset,
    /// Sub-filters run independently; the master only fuses.
    NoReset,
}

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

fn default_true() -> bool {
    true
}

/// Behaviour of an isolated sub-filter (it never feeds the master in any mode).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IsolatedMode {
    /// After each fusion take the global solution (`x_g`, `P_g/β_i`); its detectors then test
    /// the sensor against the fault-free navigation solution.
    #[default]
    Track,
    /// Predict only (no update, no reset) until reinstated.
    Predict,
    /// Keep updating with its own sensor (absorbs the fault).
    Update,
}

/// Name of the one detector of a tight filter's channel: the first global test of each epoch
/// (least-squares residuals for `ls_precheck`, innovations otherwise).
pub const TIGHT_DETECTOR: &str = "global";

fn bad(path: impl Into<String>, msg: impl std::fmt::Display) -> Error {
    Error::Invalid(format!("{}: {msg}", path.into()))
}

fn positive(path: &str, v: f64) -> Result<()> {
    if !(v > 0.0 && v.is_finite()) {
        return Err(bad(
            path,
            format!("{} must be a positive finite number", crate::error::num(v)),
        ));
    }
    Ok(())
}

/// A sensor's σ (`what`: noise or offset) within what the filter's arithmetic can square.
fn sensor_scale(path: &str, v: f64, what: &str) -> Result<()> {
    if v > 1e7 {
        return Err(bad(
            path,
            format!(
                "{} is beyond any sensor's {what} (at most 1e7 in the component's SI unit)",
                crate::error::num(v)
            ),
        ));
    }
    Ok(())
}

fn non_negative(path: &str, v: f64) -> Result<()> {
    if !(v >= 0.0 && v.is_finite()) {
        return Err(bad(
            path,
            format!("{} must be a finite number >= 0", crate::error::num(v)),
        ));
    }
    Ok(())
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
        let tr = &self.trajectory;
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
        let ins = &self.ins;
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
        let others: Vec<(&str, bool)> = vec![
            ("federated", self.federated.is_some()),
            ("centralized", self.centralized.is_some()),
            ("tight", self.tight.is_some()),
            ("ultra_tight", self.ultra_tight.is_some()),
        ];
        let arch = match self.architecture {
            Architecture::Federated => "federated",
            Architecture::Centralized => "centralized",
            Architecture::Tight => "tight",
            Architecture::UltraTight => "ultra_tight",
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
        match self.architecture {
            Architecture::Tight => self.validate_tight(),
            Architecture::UltraTight => self.validate_ultra_tight(),
            Architecture::Federated => self.validate_federated(),
            Architecture::Centralized => self.validate_centralized(),
        }
    }

    fn validate_ranges(&self, p: &str, s: &SensorSpec) -> Result<()> {
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
                    "{} rad must be in [0°, 80°)",
                    crate::error::num(r.elevation_mask)
                ),
            ));
        }
        if !r.epoch.is_finite() {
            return Err(bad(format!("{p}.ranges.epoch"), "must be finite"));
        }
        positive(&format!("{p}.ranges.clock.bias"), r.clock.bias)?;
        positive(&format!("{p}.ranges.clock.drift"), r.clock.drift)?;
        non_negative(&format!("{p}.ranges.clock.bias_psd"), r.clock.bias_psd)?;
        non_negative(&format!("{p}.ranges.clock.drift_psd"), r.clock.drift_psd)?;
        Ok(())
    }

    fn validate_tight(&self) -> Result<()> {
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

    fn validate_ultra_tight(&self) -> Result<()> {
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

    fn validate_detectors(
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
    fn check_sensor_ref(&self, p: &str, sensor: &str, dup: bool, dup_msg: &str) -> Result<()> {
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

    fn validate_centralized(&self) -> Result<()> {
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

    fn validate_federated(&self) -> Result<()> {
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

    /// Lowest height the truth may reach (m): the lowest land surface is about −430 m.
    pub const MIN_HEIGHT: f64 = -500.0;
    /// Highest ground speed the truth may reach (m/s); the INS error model is for aircraft.
    pub const MAX_SPEED: f64 = 3000.0;
    /// Largest along-track acceleration of a segment (m/s², about 10 g).
    pub const MAX_ACCELERATION: f64 = 100.0;

    /// Kinematic limits of the trajectory over the whole run (the last segment is held until
    /// the end): height, speed and acceleration, checked segment by segment in closed form so
    /// that a descent below the surface or a runaway speed is named before anything runs.
    fn check_kinematics(&self) -> Result<()> {
        let tr = &self.trajectory;
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

    fn sensor_names(&self) -> String {
        self.sensors
            .iter()
            .map(|s| s.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    }
}
