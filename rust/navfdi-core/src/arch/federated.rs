//! Federated architecture (paper 000): one sub-filter per auxiliary sensor with its detectors,
//! information fusion of the healthy sub-filters in a master, isolation and reinstatement
//! ([`crate::fusion::FederatedFilter`]), run over one run's measurement streams.

use super::common::{channel_sensors, make_detector, varying_h};
use crate::cancel::Cancel;
use crate::error::Result;
use crate::fusion::{FederatedFilter, SubFilterConfig};
use crate::ins::N_STATES;
use crate::record::RunRecord;
use crate::spec::ScenarioSpec;
use crate::stream::{Models, Streams};
use nalgebra::DVector;

/// Build the federated filter of scenario `spec` over the models of its streams.
pub fn build_filter(
    spec: &ScenarioSpec,
    models: &Models,
    isolation: bool,
) -> Result<FederatedFilter> {
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
            h: models.h[si][0].clone(),
            r: models.r[si].clone(),
            share: sf.share,
            detectors,
            isolation: isolation_idx,
        });
    }
    let mut fed = FederatedFilter::new(
        DVector::zeros(N_STATES),
        models.p0.clone(),
        subs,
        fspec.mode,
        fspec.master_share,
        isolation,
    )?;
    fed.set_isolated_mode(fspec.isolated);
    Ok(fed)
}

/// Run the federated filter of scenario `spec` over one run's streams. `isolation = false`
/// runs the same filter with isolation disabled (the detectors still run and report).
///
/// `cancel` is checked every epoch ([`crate::Error::Cancelled`]).
pub fn run_federated(
    spec: &ScenarioSpec,
    src: &Streams,
    isolation: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    let models = src.models;
    let mut fed = build_filter(spec, models, isolation)?;
    let epochs = src.epochs();
    let sensor_idx = channel_sensors(spec);
    let varying_h = varying_h(spec, &sensor_idx);
    let mut rec = RunRecord::empty(spec, models);
    let mut zs: Vec<DVector<f64>> = sensor_idx
        .iter()
        .map(|&si| src.meas.z[si][0].clone())
        .collect();
    let mut sig = DVector::zeros(N_STATES);
    for k in 0..epochs {
        cancel.check()?;
        for (i, &si) in sensor_idx.iter().enumerate() {
            zs[i].copy_from(&src.meas.z[si][k]);
            if varying_h[i] {
                fed.set_h_trusted(i, &models.h[si][k]);
            }
            if let Some(var) = models.r_epoch[si].get(k) {
                fed.set_r_trusted(i, &nalgebra::DMatrix::from_element(1, 1, *var));
            }
        }
        let rep = fed
            .step_trusted(&models.phi[k], &models.q[k], &zs)
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
        rec.push_navigation(src, k, fed.x(), fed.p(), &mut sig);
    }
    Ok(rec)
}
