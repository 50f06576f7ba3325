//! What one run of an architecture records, per epoch: the navigation error and its 1σ, each
//! channel's statistics and decisions, satellite FDE, the state chi-square test and the
//! altitude fusion. Below the architectures, which fill it, and above the metrics engine
//! ([`crate::metrics`]) that scores it.

use crate::ins::{earth, ATT, N_STATES, POS, VEL};
use crate::spec::ScenarioSpec;
use crate::stream::{Models, Streams};
use nalgebra::DVector;

/// Per-epoch record of one detector.
#[derive(Debug, Clone, PartialEq)]
pub struct DetectorRecord {
    /// Detector name.
    pub name: String,
    /// Statistic per epoch.
    pub statistic: Vec<f64>,
    /// Threshold per epoch.
    pub threshold: Vec<f64>,
    /// Alarm per epoch.
    pub alarm: Vec<bool>,
}

/// Per-epoch record of one sub-filter.
#[derive(Debug, Clone, PartialEq)]
pub struct SubRecord {
    /// Sensor name (the satellite's, e.g. `G17`, for an ultra-tight channel).
    pub sensor: String,
    /// `λ` of the innovation.
    pub statistic: Vec<f64>,
    /// Components used.
    pub dof: Vec<u32>,
    /// Isolated after the epoch's decision.
    pub isolated: Vec<bool>,
    /// Reinstated this epoch.
    pub reinstated: Vec<bool>,
    /// Fed this epoch's fusion.
    pub fused: Vec<bool>,
    /// Detectors in configuration order.
    pub detectors: Vec<DetectorRecord>,
    /// Minimal detectable bias per component and epoch (T × m row-major, NaN where a
    /// component was missing), from the innovation covariance and the deciding detector's
    /// `pf`, `pm` (METHODS §6); empty where the architecture does not compute it (federated).
    pub mdb: Vec<f64>,
    /// Whitened innovation `L⁻¹ r` (`S = L Lᵀ`) per component and epoch (T × m row-major, NaN
    /// where untested): for a consistent filter white, unit-variance noise; its lag-1
    /// autocorrelation over consecutive tests measures the filter's consistency without a
    /// reference. Empty where the architecture does not record it (loosely coupled does).
    pub whitened: Vec<f64>,
    /// Why the measurement (or some of its components) was left out at each epoch
    /// ([`EXCLUSION_REASONS`] index; 0 where it was used as measured or not tested). Empty
    /// where the architecture does not record it (loosely coupled does).
    pub reason: Vec<u8>,
    /// Scale of the measurement σ its tests used at each epoch (the noise scale estimated
    /// from its innovations; NaN where untested). Empty where the architecture does not
    /// estimate it (loosely coupled does, for GNSS channels).
    pub noise_scale: Vec<f64>,
}

/// Names of [`SubRecord::reason`]: used as measured; left out by the deciding test; a held
/// step (used as a relative fix while its offset explains it, or left out); a stale fix (the
/// receiver's last fix repeated while the INS moved); a slow ramp flagged by the sequential
/// test, held until the fix meets the INS again.
pub const EXCLUSION_REASONS: [&str; 6] = ["", "test", "step", "stale", "ramp", "receiver"];

impl SubRecord {
    /// An epoch without a test: NaN statistics, not isolated, nothing fused.
    pub fn push_untested(&mut self) {
        self.statistic.push(f64::NAN);
        self.dof.push(0);
        self.isolated.push(false);
        self.reinstated.push(false);
        self.fused.push(false);
        for d in &mut self.detectors {
            d.statistic.push(f64::NAN);
            d.threshold.push(f64::NAN);
            d.alarm.push(false);
        }
    }
}

/// Per-epoch satellite FDE record of a tight filter (S satellites of the constellation).
#[derive(Debug, Clone, PartialEq)]
pub struct SatRecord {
    /// Satellite names (S).
    pub names: Vec<String>,
    /// In view (above the elevation mask), T × S row-major.
    pub in_view: Vec<bool>,
    /// Excluded this epoch, T × S.
    pub excluded: Vec<bool>,
    /// w of the satellite's pseudorange (least squares) or innovation in the last test that
    /// included it (for an excluded satellite: its |w| when excluded), T × S; NaN when not
    /// tested.
    pub w: Vec<f64>,
    /// FDE outcome per epoch: [`SAT_STATUS`] index.
    pub status: Vec<u8>,
    /// Satellites that updated the filter per epoch.
    pub used: Vec<u32>,
    /// Satellite-FDE counts per fault on the sensor, then outside faults.
    pub metrics: Vec<crate::metrics::SatFaultMetrics>,
}

impl SatRecord {
    /// An empty record of satellites `names` over `epochs` epochs (nothing in view, nothing
    /// excluded, w NaN; status and used filled per epoch).
    pub fn new(names: Vec<String>, epochs: usize) -> Self {
        let s_count = names.len();
        SatRecord {
            names,
            in_view: vec![false; epochs * s_count],
            excluded: vec![false; epochs * s_count],
            w: vec![f64::NAN; epochs * s_count],
            status: Vec::with_capacity(epochs),
            used: Vec::with_capacity(epochs),
            metrics: Vec::new(),
        }
    }

    /// Fill [`SatRecord::metrics`]: satellite-FDE counts per fault of `faults` on sensor
    /// `sensor` whose satellite is one of [`SatRecord::names`], then outside faults, over the
    /// epochs `t` with a measurement.
    pub fn score(&mut self, t: &[f64], faults: &[crate::spec::FaultSpec], sensor: &str) {
        let sat_faults: Vec<crate::metrics::SatFault> = faults
            .iter()
            .enumerate()
            .filter(|(_, f)| f.sensor == sensor)
            .filter_map(|(i, f)| {
                let s = self
                    .names
                    .iter()
                    .position(|x| Some(x) == f.satellite.as_ref())?;
                Some((i, s, f.start, f.end))
            })
            .collect();
        let measured: Vec<bool> = self
            .status
            .iter()
            .map(|&s| s != SAT_NO_MEASUREMENT)
            .collect();
        self.metrics = crate::metrics::satellite_metrics(
            t,
            &measured,
            &self.in_view,
            &self.excluded,
            self.names.len(),
            &sat_faults,
        );
    }
}

/// Names of the per-epoch FDE outcomes of [`SatRecord::status`]: the four of
/// [`crate::gnss::snapshot::FdeStatus`], `alarm` (placement `none`: the global test failed,
/// nothing is excluded) and `no_measurement`.
pub const SAT_STATUS: [&str; 6] = [
    "passed",
    "excluded",
    "unidentified",
    "no_solution",
    "alarm",
    "no_measurement",
];

/// [`SatRecord::status`] of an epoch without a measurement (index of `no_measurement` in
/// [`SAT_STATUS`]).
pub const SAT_NO_MEASUREMENT: u8 = 5;

/// Names of the 9 navigation-error columns of [`RunRecord::error`].
pub const ERROR_COLUMNS: [&str; 9] = [
    "att_e", "att_n", "att_u", "vel_e", "vel_n", "vel_u", "pos_e", "pos_n", "pos_u",
];

/// Outputs of one run.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunRecord {
    /// Epoch times (s).
    pub t: Vec<f64>,
    /// Master navigation error after correction, `x_true − x_g`, T × 9 row-major: attitude
    /// (rad), velocity (m/s), position east/north/up (m). See [`ERROR_COLUMNS`].
    pub error: Vec<f64>,
    /// Master 1σ from `P_g`, T × 9, same columns.
    pub sigma: Vec<f64>,
    /// Sources fused per epoch (0: propagated).
    pub sources: Vec<u32>,
    /// Sub-filters in configuration order.
    pub subs: Vec<SubRecord>,
    /// Satellite FDE (tight architecture).
    pub sats: Option<SatRecord>,
    /// State chi-square test of the navigation solution (scenario `state_chi2`).
    pub state: Option<StateRecord>,
    /// Navigation mode per epoch (1, 2, 3; empty without `modes`).
    pub mode: Vec<u8>,
    /// Error of the fused altitude measurement per epoch (m; NaN when no sensor contributed:
    /// the filter predicted only in height); empty without altitude fusion.
    pub fused_alt: Vec<f64>,
    /// Altitude fusion inputs: the fused sensors' names and, per epoch, each one's height
    /// measurement error (m, NaN when absent) and normalised weight `w_i M_i / Σ w_j M_j`
    /// (T × sensors row-major); empty without altitude fusion.
    pub fusion: Option<FusionRecord>,
    /// Per fault of the scenario: whether it ever reached a measurement
    /// ([`crate::stream::faults_applied`]).
    pub faults_applied: Vec<bool>,
    /// On recorded logs with faults: the mean position error (east, north, up, m) of the same
    /// filter on the same log without them ([`crate::montecarlo::logged_datum`]) — the
    /// reference's own datum, against which the integrity metrics score the errors.
    pub datum: Option<[f64; 3]>,
    /// The navigation solution of a strapdown INS (architecture `loosely_coupled`), T ×
    /// [`NAV_COLUMNS`] row-major; empty otherwise.
    pub nav: Vec<f64>,
    /// Filter protection levels (tight filter with `[tight.integrity]`).
    pub integrity: Option<IntegrityRecord>,
    /// Loosely coupled: time (s) of the epoch from which the filter counted as converged
    /// (`loosely_coupled.convergence`); None when it never did (or another architecture).
    pub converged_at: Option<f64>,
    /// Loosely coupled: times (s) at which the INS, diverged from the fixes it held out, was
    /// moved back onto them (`arch::loosely_coupled::diverge`), or replaced by a copy of the
    /// filter carried without GNSS that called the hold its error (`::shadow`).
    pub reanchored: Vec<f64>,
    /// Loosely coupled with `position_correlation = "auto"`: the first position channel's
    /// error model read from the log — σ of the white part (m), σ of the correlated part (m),
    /// its correlation time (s) and the factor on the fixes' position variance in the update;
    /// NaN, NaN, NaN, 1 where the log could not say (no velocities, too short). None otherwise.
    pub position_errors: Option<[f64; 4]>,
    /// Loosely coupled with the fixes taken as white (`position_correlation = 0`): the same
    /// model where the log shows a correlation (the factor `"auto"` would use); None otherwise.
    pub position_wander: Option<[f64; 4]>,
}

/// Per-epoch filter integrity of a tight run ([`crate::integrity::filter_ss`]), each T long.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct IntegrityRecord {
    /// Filter horizontal and vertical protection levels (m; NaN before the first
    /// measurement).
    pub hpl: Vec<f64>,
    /// See [`IntegrityRecord::hpl`].
    pub vpl: Vec<f64>,
    /// Snapshot ARAIM protection levels of the same epoch's pseudoranges (the satellites the
    /// filter used, their σ, the same allocation and prior; NaN when the epoch has too few
    /// satellites or no measurement), m.
    pub hpl_snapshot: Vec<f64>,
    /// See [`IntegrityRecord::hpl_snapshot`].
    pub vpl_snapshot: Vec<f64>,
    /// Largest normalised separation `|Δ|/T` (NaN when no mode is tested).
    pub statistic: Vec<f64>,
    /// The separation test alarmed.
    pub alarm: Vec<bool>,
    /// Monitored modes (sub-filters).
    pub modes: Vec<u32>,
}

impl IntegrityRecord {
    /// Append one epoch: the filter's levels and test `lv`, the snapshot HPL and VPL `snap`
    /// (m) and whether the epoch is in alarm.
    pub fn push(&mut self, lv: &crate::integrity::filter_ss::SsEpoch, snap: [f64; 2], alarm: bool) {
        self.hpl.push(lv.hpl);
        self.vpl.push(lv.vpl);
        self.hpl_snapshot.push(snap[0]);
        self.vpl_snapshot.push(snap[1]);
        self.statistic.push(lv.statistic);
        self.alarm.push(alarm);
        self.modes.push(lv.modes as u32);
    }

    /// Append an epoch without levels (no navigation solution).
    pub fn push_none(&mut self) {
        self.hpl.push(f64::NAN);
        self.vpl.push(f64::NAN);
        self.hpl_snapshot.push(f64::NAN);
        self.vpl_snapshot.push(f64::NAN);
        self.statistic.push(f64::NAN);
        self.alarm.push(false);
        self.modes.push(0);
    }

    /// Empty, with room for `epochs`.
    pub fn with_capacity(epochs: usize) -> Self {
        IntegrityRecord {
            hpl: Vec::with_capacity(epochs),
            vpl: Vec::with_capacity(epochs),
            hpl_snapshot: Vec::with_capacity(epochs),
            vpl_snapshot: Vec::with_capacity(epochs),
            statistic: Vec::with_capacity(epochs),
            alarm: Vec::with_capacity(epochs),
            modes: Vec::with_capacity(epochs),
        }
    }
}

/// Columns of [`RunRecord::nav`]: the GNSS antenna's latitude, longitude (rad) and height
/// (m); velocity east, north, up (m/s); roll, pitch, yaw (rad, body forward-right-down to
/// north-east-down); estimated gyro biases (rad/s) and accelerometer biases (m/s²) in body
/// axes; their 1σ (rad/s, m/s²); and the normalised estimation error squared of antenna
/// position, velocity and attitude (9 dof) where the reference has the true attitude (NaN
/// otherwise). NaN before the INS is aligned.
pub const NAV_COLUMNS: [&str; 22] = [
    "lat",
    "lon",
    "height",
    "vel_e",
    "vel_n",
    "vel_u",
    "roll",
    "pitch",
    "yaw",
    "gyro_bias_x",
    "gyro_bias_y",
    "gyro_bias_z",
    "accel_bias_x",
    "accel_bias_y",
    "accel_bias_z",
    "gyro_bias_x_sigma",
    "gyro_bias_y_sigma",
    "gyro_bias_z_sigma",
    "accel_bias_x_sigma",
    "accel_bias_y_sigma",
    "accel_bias_z_sigma",
    "nees",
];

/// Per-epoch inputs of the altitude fusion (see [`RunRecord::fusion`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct FusionRecord {
    /// Fused sensors in configuration order.
    pub sensors: Vec<String>,
    /// Height measurement error per epoch and sensor (m; NaN when absent), T × sensors.
    pub error: Vec<f64>,
    /// Normalised weight per epoch and sensor (0 when it did not contribute), T × sensors.
    pub weight: Vec<f64>,
}

/// Per-epoch record of the state chi-square test of the navigation solution, with the
/// detector that steps it (in [`RunRecord::push_navigation`]).
#[derive(Debug, Clone, PartialEq)]
pub struct StateRecord {
    /// The detector.
    pub detector: crate::detect::StateChi2,
    /// Statistic per epoch (NaN when not tested).
    pub statistic: Vec<f64>,
    /// Threshold per epoch.
    pub threshold: Vec<f64>,
    /// Alarm per epoch.
    pub alarm: Vec<bool>,
    /// Age rule met per epoch.
    pub ready: Vec<bool>,
    /// V ill-conditioned (not tested) per epoch.
    pub ill_conditioned: Vec<bool>,
}

fn to_nav(x: &DVector<f64>, lat: f64, h: f64, out: &mut Vec<f64>) {
    let rm = earth::r_meridian(lat) + h;
    let rn = earth::r_normal(lat) + h;
    for i in 0..3 {
        out.push(x[ATT + i]);
    }
    for i in 0..3 {
        out.push(x[VEL + i]);
    }
    out.push(x[POS + 1] * rn * lat.cos());
    out.push(x[POS] * rm);
    out.push(x[POS + 2]);
}

impl RunRecord {
    /// An empty record with one channel per detection channel of the scenario `spec`, over
    /// the epochs of `models`.
    pub fn empty(spec: &ScenarioSpec, models: &Models) -> Self {
        let epochs = models.epochs();
        RunRecord {
            t: models.t.clone(),
            error: Vec::with_capacity(epochs * 9),
            sigma: Vec::with_capacity(epochs * 9),
            sources: Vec::with_capacity(epochs),
            subs: spec
                .channels()
                .iter()
                .map(|ch| SubRecord {
                    sensor: ch.name().to_string(),
                    statistic: Vec::with_capacity(epochs),
                    dof: Vec::with_capacity(epochs),
                    isolated: Vec::with_capacity(epochs),
                    reinstated: Vec::with_capacity(epochs),
                    fused: Vec::with_capacity(epochs),
                    detectors: ch
                        .detectors
                        .iter()
                        .map(|d| DetectorRecord {
                            name: d.name.clone(),
                            statistic: Vec::with_capacity(epochs),
                            threshold: Vec::with_capacity(epochs),
                            alarm: Vec::with_capacity(epochs),
                        })
                        .collect(),
                    mdb: Vec::new(),
                    whitened: Vec::new(),
                    reason: Vec::new(),
                    noise_scale: Vec::new(),
                })
                .collect(),
            sats: None,
            mode: models.mode.clone(),
            fused_alt: Vec::new(),
            fusion: None,
            faults_applied: crate::stream::faults_applied(spec, models),
            datum: None,
            nav: Vec::new(),
            integrity: None,
            converged_at: None,
            reanchored: Vec::new(),
            position_errors: None,
            position_wander: None,
            // Parameters validated by the scenario, so the detector can always be built.
            state: spec.state_chi2.as_ref().and_then(|sc| {
                let (r, a) = sc.epochs(spec.dt);
                crate::detect::StateChi2::new(sc.pf, spec.n_states(), r, a, sc.states.clone())
                    .ok()
                    .map(|detector| StateRecord {
                        detector,
                        statistic: Vec::with_capacity(epochs),
                        threshold: Vec::with_capacity(epochs),
                        alarm: Vec::with_capacity(epochs),
                        ready: Vec::with_capacity(epochs),
                        ill_conditioned: Vec::with_capacity(epochs),
                    })
            }),
        }
    }

    /// Runs on recorded logs: a fault counts as applied only if its sensor measured at an epoch
    /// in its window that the INS navigated (after the alignment, before the IMU log ends):
    /// a fault outside the processed span is never applied, not missed.
    pub fn restrict_faults_to_navigated(&mut self, spec: &ScenarioSpec, models: &Models) {
        if self.nav.is_empty() {
            return;
        }
        let cols = NAV_COLUMNS.len();
        for (i, f) in spec.faults.iter().enumerate() {
            let Some(applied) = self.faults_applied.get_mut(i) else {
                continue;
            };
            let si = spec.sensor_index(&f.sensor);
            *applied &= models.t.iter().enumerate().any(|(k, &t)| {
                t >= f.start
                    && t < f.end
                    && self.nav.get(k * cols).is_some_and(|v| v.is_finite())
                    && si.is_some_and(|si| models.available.get(si).is_some_and(|a| a[k]))
            });
        }
    }

    /// Append epoch `k`'s navigation error `x_true − x` (NaN without a reference) and 1σ from
    /// `p`, and step the state chi-square test (if configured) on `x`, `p` with the epoch's Φ
    /// and Q.
    pub fn push_navigation(
        &mut self,
        src: &Streams,
        k: usize,
        x: &DVector<f64>,
        p: &nalgebra::DMatrix<f64>,
        sig: &mut DVector<f64>,
    ) {
        if let Some(st) = self.state.as_mut() {
            let d = st
                .detector
                .step_trusted(x, p, &src.models.phi[k], &src.models.q[k]);
            st.statistic.push(d.statistic);
            st.threshold.push(d.threshold);
            st.alarm.push(d.alarm);
            st.ready.push(d.ready);
            st.ill_conditioned.push(d.ill_conditioned);
        }
        let tr = &src.models.nominal[k];
        match src.reference {
            Some(r) => {
                let e = &r.x_true[k] - x;
                to_nav(&e, tr.lat, tr.h, &mut self.error);
            }
            None => self.error.extend([f64::NAN; 9]),
        }
        for i in 0..N_STATES {
            sig[i] = p[(i, i)].max(0.0).sqrt();
        }
        to_nav(sig, tr.lat, tr.h, &mut self.sigma);
    }
}
