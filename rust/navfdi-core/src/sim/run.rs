//! One federated run of a prepared scenario over simulated measurements.

use super::noise::Simulated;
use super::prepare::Prepared;
use super::spec::{Architecture, DetectorKind, SensorKind};
use crate::cancel::Cancel;
use crate::detect::{Detector, ImprovedSprt, JointChi2Sprt, ResidualChi2, SprtVariance};
use crate::error::Result;
use crate::fusion::{FederatedFilter, SubFilterConfig};
use crate::ins::{earth, ATT, N_STATES, POS, VEL};
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
    pub metrics: Vec<super::metrics::SatFaultMetrics>,
}

impl SatRecord {
    /// Fill [`SatRecord::metrics`]: satellite-FDE counts per fault of `faults` on sensor
    /// `sensor` whose satellite is one of [`SatRecord::names`], then outside faults, over the
    /// epochs `t` with a measurement.
    pub fn score(&mut self, t: &[f64], faults: &[super::spec::FaultSpec], sensor: &str) {
        let sat_faults: Vec<super::metrics::SatFault> = faults
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
        self.metrics = super::metrics::satellite_metrics(
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
#[derive(Debug, Clone, PartialEq)]
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
}

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

/// Build a detector from its spec (validated by the scenario). `min_samples` (SPRT and joint)
/// overrides the default minimum sample count of the SPRT.
pub fn make_detector(
    kind: DetectorKind,
    pf: f64,
    pm: Option<f64>,
    variance: Option<&str>,
    min_samples: Option<u64>,
) -> Result<Detector> {
    let var = if variance == Some("sample") {
        SprtVariance::Sample
    } else {
        SprtVariance::Known
    };
    let pm = pm.unwrap_or(pf);
    Ok(match kind {
        DetectorKind::Chi2 => Detector::Chi2(ResidualChi2::new(pf)?),
        DetectorKind::Sprt => {
            let d = ImprovedSprt::new(pf, pm, var)?;
            Detector::Sprt(match min_samples {
                Some(n) => d.with_min_samples(n)?,
                None => d,
            })
        }
        DetectorKind::Joint => {
            let d = JointChi2Sprt::new(pf, pm, var)?;
            Detector::Joint(match min_samples {
                Some(n) => d.with_min_samples(n)?,
                None => d,
            })
        }
        DetectorKind::StateChi2 => {
            return Err(crate::error::Error::Invalid(
                "a state_chi2 detector tests sub-filter states, not innovations (centralized architecture only)".into(),
            ))
        }
    })
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

/// Build the federated filter of a prepared scenario.
pub fn build_filter(prep: &Prepared, isolation: bool) -> Result<FederatedFilter> {
    let spec = &prep.spec;
    let mut subs = Vec::new();
    let fspec = spec.federated()?;
    for sf in &fspec.subfilters {
        let si = spec.sensor_index(&sf.sensor).unwrap_or(0);
        let mut detectors = Vec::new();
        for d in &sf.detectors {
            detectors.push((
                d.name.clone(),
                make_detector(d.kind, d.pf, d.pm, d.variance.as_deref(), d.min_samples)?,
            ));
        }
        let isolation_idx = sf
            .isolation
            .as_ref()
            .and_then(|n| sf.detectors.iter().position(|d| &d.name == n));
        subs.push(SubFilterConfig {
            name: sf.sensor.clone(),
            h: prep.h[si][0].clone(),
            r: prep.r[si].clone(),
            share: sf.share,
            detectors,
            isolation: isolation_idx,
        });
    }
    let mut fed = FederatedFilter::new(
        DVector::zeros(N_STATES),
        prep.p0.clone(),
        subs,
        fspec.mode,
        fspec.master_share,
        isolation,
    )?;
    fed.set_isolated_mode(fspec.isolated);
    Ok(fed)
}

/// Run the federated filter over one simulated run. `isolation = false` runs the same filter
/// with isolation disabled (the detectors still run and report).
///
/// `cancel` is checked every epoch ([`crate::Error::Cancelled`]).
pub fn run_federated(
    prep: &Prepared,
    sim: &Simulated,
    isolation: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    let mut fed = build_filter(prep, isolation)?;
    let epochs = prep.epochs();
    let sensor_idx = channel_sensors(prep);
    let varying_h = varying_h(prep, &sensor_idx);
    let mut rec = RunRecord::empty(prep);
    let mut zs: Vec<DVector<f64>> = sensor_idx.iter().map(|&si| sim.z[si][0].clone()).collect();
    let mut sig = DVector::zeros(N_STATES);
    for k in 0..epochs {
        cancel.check()?;
        for (i, &si) in sensor_idx.iter().enumerate() {
            zs[i].copy_from(&sim.z[si][k]);
            if varying_h[i] {
                fed.set_h_trusted(i, &prep.h[si][k]);
            }
            if let Some(var) = prep.r_epoch[si].get(k) {
                fed.set_r_trusted(i, &nalgebra::DMatrix::from_element(1, 1, *var));
            }
        }
        let rep = fed
            .step_trusted(&prep.phi[k], &prep.q[k], &zs)
            .map_err(|e| crate::run::at_epoch(k, e))?;
        rec.sources.push(rep.sources as u32);
        for (sub, r) in rec.subs.iter_mut().zip(&rep.subs) {
            sub.statistic.push(r.statistic);
            sub.dof.push(r.dof as u32);
            sub.isolated.push(r.isolated);
            sub.reinstated.push(r.reinstated);
            sub.fused.push(r.fused);
            for (d, dec) in sub.detectors.iter_mut().zip(&r.decisions) {
                d.statistic.push(dec.statistic);
                d.threshold.push(dec.threshold);
                d.alarm.push(dec.alarm);
            }
        }
        rec.push_navigation(prep, sim, k, fed.x(), fed.p(), &mut sig);
    }
    Ok(rec)
}

/// Sensor index of each detection channel.
pub fn channel_sensors(prep: &Prepared) -> Vec<usize> {
    let spec = &prep.spec;
    spec.channels()
        .iter()
        .map(|ch| spec.sensor_index(ch.sensor).unwrap_or(0))
        .collect()
}

/// Whether each channel's measurement matrix changes along the trajectory (position sensors).
pub fn varying_h(prep: &Prepared, sensor_idx: &[usize]) -> Vec<bool> {
    sensor_idx
        .iter()
        .map(|&si| {
            !matches!(
                prep.spec.sensors[si].kind,
                SensorKind::Cns
                    | SensorKind::GnssVelocity
                    | SensorKind::Baro
                    | SensorKind::RadioAltimeter
                    | SensorKind::GnssRanges
            )
        })
        .collect()
}

impl RunRecord {
    /// An empty record with one channel per detection channel of the scenario.
    pub fn empty(prep: &Prepared) -> Self {
        let epochs = prep.epochs();
        RunRecord {
            t: prep.t.clone(),
            error: Vec::with_capacity(epochs * 9),
            sigma: Vec::with_capacity(epochs * 9),
            sources: Vec::with_capacity(epochs),
            subs: prep
                .spec
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
                })
                .collect(),
            sats: None,
            mode: prep.mode.clone(),
            fused_alt: Vec::new(),
            fusion: None,
            // Parameters validated by the scenario, so the detector can always be built.
            state: prep.spec.state_chi2.as_ref().and_then(|sc| {
                let (r, a) = sc.epochs(prep.spec.dt);
                crate::detect::StateChi2::new(sc.pf, prep.spec.n_states(), r, a, sc.states.clone())
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

    /// Append epoch `k`'s navigation error `x_true − x` and 1σ from `p`, and step the state
    /// chi-square test (if configured) on `x`, `p` with the epoch's Φ and Q.
    pub fn push_navigation(
        &mut self,
        prep: &Prepared,
        sim: &Simulated,
        k: usize,
        x: &DVector<f64>,
        p: &nalgebra::DMatrix<f64>,
        sig: &mut DVector<f64>,
    ) {
        if let Some(st) = self.state.as_mut() {
            let d = st.detector.step_trusted(x, p, &prep.phi[k], &prep.q[k]);
            st.statistic.push(d.statistic);
            st.threshold.push(d.threshold);
            st.alarm.push(d.alarm);
            st.ready.push(d.ready);
            st.ill_conditioned.push(d.ill_conditioned);
        }
        let tr = &prep.truth[k];
        let e = &sim.x_true[k] - x;
        to_nav(&e, tr.lat, tr.h, &mut self.error);
        for i in 0..N_STATES {
            sig[i] = p[(i, i)].max(0.0).sqrt();
        }
        to_nav(sig, tr.lat, tr.h, &mut self.sigma);
    }
}

/// Run the scenario's architecture over one simulated run (`isolation = false`: detectors
/// report but never act). `full`: record everything, including quantities only figures and
/// time series use (the MDB); Monte-Carlo runs that keep no series pass false.
pub fn run_architecture(
    prep: &Prepared,
    sim: &Simulated,
    isolation: bool,
    full: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    match prep.spec.architecture {
        Architecture::Federated => {
            let isolate = prep.spec.federated.as_ref().is_none_or(|f| f.isolate);
            run_federated(prep, sim, isolation && isolate, cancel)
        }
        Architecture::Centralized => {
            let isolate = prep.spec.centralized.as_ref().is_none_or(|c| c.isolate);
            crate::arch::centralized::run_centralized(prep, sim, isolation && isolate, full, cancel)
        }
        Architecture::Tight => crate::arch::tight::run_tight(prep, sim, isolation, full, cancel),
        Architecture::UltraTight => {
            crate::arch::ultra_tight::run_ultra_tight(prep, sim, isolation, full, cancel)
        }
    }
}
