//! Centralized fault-tolerant filtering (paper 002, METHODS §7).
//!
//! One Kalman filter over the 15-state INS error model, updated each epoch by the stacked
//! measurements of the chosen sensors. Each sensor's block of the innovation (`r_i`, `A_ii`) is
//! tested by that sensor's detectors *before* the update (test before update), and the
//! deciding detector's alarms act through the scenario's policy:
//!
//! * `exclude`: an alarm drops the sensor's whole measurement this epoch (prediction only for
//!   it), as a residual chi-square system does;
//! * `latched`: the plain improved SPRT; every component whose statistic is at or above the
//!   threshold is left out of the update, until its statistic falls below the threshold
//!   (which, without a reset, takes long after a fault ends);
//! * `fading` (paper 002): on an alarm of component i, i's SPRT restarts from zero (the
//!   "pseudo-normal" state) and i is left out of the update (reduced-dimension update). i keeps
//!   being tested against the prediction; a re-alarm restarts it again, and once its restarted
//!   SPRT has stayed below the threshold for `confirm` seconds the fault is declared over and i
//!   rejoins the update (**resolution** of METHODS §7). After each new detection the fading
//!   factor `S = fading` multiplies `ΦPΦᵀ` for `fading_duration` seconds.
//!
//! Recorded per channel: the innovation statistic of the sensor block, its components used,
//! `isolated` = some component of the sensor left out of this epoch's update, `reinstated` =
//! a fault declared over this epoch, `fused` = the sensor updated the filter. The deciding
//! detector's `alarm` is the policy's fault state (for `fading`: a component is faulty), so
//! event matching scores what the policy decided.

use super::common::{channel_sensors, make_detector, varying_h};
use crate::cancel::Cancel;
use crate::detect::Detector;
use crate::error::{Error, Result};
use crate::ins::N_STATES;
use crate::kalman::KalmanFilter;
use crate::record::{FusionRecord, RunRecord};
use crate::spec::{DetectorKind, Policy, ScenarioSpec};
use crate::stream::Streams;
use nalgebra::{DMatrix, DVector};

/// Per-component state of the `fading` policy.
#[derive(Debug, Clone, Copy, Default)]
struct Component {
    faulty: bool,
    below: u32,
}

/// One test of a sensor: an innovation detector, or paper 003's state test (its threshold).
enum SensorTest {
    Innovation(Detector),
    State(f64),
}

/// Run the centralized filter of scenario `spec` over one run's streams. `isolation = false`: the detectors run
/// and report but the policy never acts (every measurement is used).
///
/// `mdb`: also record the minimal detectable bias per epoch (a factorisation and inverse of
/// each sensor block per epoch; Monte-Carlo runs that keep no series skip it).
pub fn run_centralized(
    spec: &ScenarioSpec,
    src: &Streams,
    isolation: bool,
    mdb: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    let models = src.models;
    let c = spec.centralized()?;
    let channels = spec.channels();
    let sensor_idx = channel_sensors(spec);
    let varying = varying_h(spec, &sensor_idx);
    let dims: Vec<usize> = sensor_idx
        .iter()
        .map(|&si| spec.sensors[si].kind.dim())
        .collect();
    let offsets: Vec<usize> = dims
        .iter()
        .scan(0, |acc, d| {
            let o = *acc;
            *acc += d;
            Some(o)
        })
        .collect();
    let m: usize = dims.iter().sum();
    // Altitude fusion: the fused sensors' height rows (stack indices) and their fusion (priors
    // σ from the sensors), and one extra row at the end of the stack for the fused altitude
    // (always NaN in `z`, so the detectors never see it).
    let mut fusion = match c.altitude_fusion.as_ref() {
        Some(af) => {
            let rows: Vec<(usize, usize)> = af
                .sensors
                .iter()
                .filter_map(|name| {
                    let i = channels.iter().position(|ch| ch.sensor == name.as_str())?;
                    let si = sensor_idx[i];
                    let j = spec.sensors[si].kind.height_component()?;
                    Some((i, offsets[i] + j))
                })
                .collect();
            // A proportional σ's prior is its value at the first epoch.
            let prior: Vec<f64> = rows
                .iter()
                .map(|&(i, row)| match models.r_epoch[sensor_idx[i]].first() {
                    Some(var) => var.sqrt(),
                    None => spec.sensors[sensor_idx[i]].noise[row - offsets[i]],
                })
                .collect();
            let fuser =
                crate::fusion::WeightedFusion::new(&prior, af.samples)?.with_estimate(af.estimate);
            Some((rows, fuser))
        }
        None => None,
    };
    let mut rec = RunRecord::empty(spec, models);
    let extra = usize::from(fusion.is_some());
    rec.fusion = c.altitude_fusion.as_ref().map(|af| FusionRecord {
        sensors: af.sensors.clone(),
        ..Default::default()
    });
    let mut h = DMatrix::zeros(m + extra, N_STATES);
    let mut r = DMatrix::zeros(m + extra, m + extra);
    if extra == 1 {
        h[(m, crate::ins::POS + 2)] = 1.0;
        r[(m, m)] = 1.0;
    }
    for (i, &si) in sensor_idx.iter().enumerate() {
        let (o, d) = (offsets[i], dims[i]);
        h.view_mut((o, 0), (d, N_STATES))
            .copy_from(&models.h[si][0]);
        r.view_mut((o, o), (d, d)).copy_from(&models.r[si]);
    }
    let mut kf = KalmanFilter::new(DVector::zeros(N_STATES), models.p0.clone())?;
    // Each sensor's tests: innovation detectors, and state tests with their thresholds.
    let tested = rec
        .state
        .as_ref()
        .map_or(0, |st| st.detector.states().len());
    let mut detectors: Vec<Vec<SensorTest>> = Vec::with_capacity(channels.len());
    let mut decision: Vec<Option<usize>> = Vec::with_capacity(channels.len());
    for ch in &channels {
        detectors.push(
            ch.detectors
                .iter()
                .map(|d| match d.kind {
                    DetectorKind::StateChi2 => {
                        crate::stats::chi2_threshold(d.pf, tested).map(SensorTest::State)
                    }
                    _ => make_detector(d.kind, d.pf, d.pm, d.variance.as_deref(), d.min_samples)
                        .map(SensorTest::Innovation),
                })
                .collect::<Result<_>>()?,
        );
        decision.push(
            ch.decision
                .and_then(|n| ch.detectors.iter().position(|d| d.name == n)),
        );
    }
    // λ0 for the MDB: the deciding detector's pf and pm (the first detector's without one),
    // standard definition F_{χ²(d, λ0)}(T_D) = pm (METHODS §6).
    let lambda0: Vec<f64> = channels
        .iter()
        .zip(&dims)
        .map(|(ch, &d)| {
            let det = ch
                .decision
                .and_then(|n| ch.detectors.iter().find(|x| x.name == n))
                .or(ch.detectors.first());
            det.map_or(Ok(f64::NAN), |x| {
                crate::stats::noncentrality(x.pf, x.pm.unwrap_or(x.pf), d)
            })
        })
        .collect::<Result<_>>()?;
    let dt = spec.dt;
    let confirm = (c.confirm / dt).round().max(1.0) as u32;
    let fading_epochs = (c.fading_duration / dt).round() as usize;
    let mut fading_left = 0usize;
    let mut comps: Vec<Vec<Component>> = dims
        .iter()
        .map(|&d| vec![Component::default(); d])
        .collect();
    let mut pairs: Vec<[Option<KalmanFilter>; 2]> = channels.iter().map(|_| [None, None]).collect();
    let mut z = DVector::from_element(m + extra, f64::NAN);
    let mut z_used = z.clone();
    let mut sig = DVector::zeros(N_STATES);
    for k in 0..spec.epochs() {
        cancel.check()?;
        let s = if fading_left > 0 { c.fading } else { 1.0 };
        fading_left = fading_left.saturating_sub(1);
        kf.predict_trusted(&models.phi[k], &models.q[k], s)
            .map_err(|e| crate::run::at_epoch(k, e))?;
        for (i, &si) in sensor_idx.iter().enumerate() {
            let (o, d) = (offsets[i], dims[i]);
            z.rows_mut(o, d).copy_from(&src.meas.z[si][k]);
            if varying[i] {
                h.view_mut((o, 0), (d, N_STATES))
                    .copy_from(&models.h[si][k]);
            }
            if let Some(var) = models.r_epoch[si].get(k) {
                r[(o, o)] = *var;
            }
        }
        // Test before update: the innovation of every available component, kept so that an
        // epoch without exclusions applies it without recomputation.
        let (inn, pending) = kf
            .innovation_pending(&z, &h, &r)
            .map_err(|e| crate::run::at_epoch(k, e))?;
        if let Some(st) = rec.state.as_mut() {
            st.detector.advance(&models.phi[k], &models.q[k]);
        }
        // Paper 003's sensor sub-filters: each runs on its own sensor's measurement alone.
        for (i, pair) in pairs.iter_mut().enumerate() {
            if pair.iter().all(Option::is_none) {
                continue;
            }
            let (o, d) = (offsets[i], dims[i]);
            let zi: DVector<f64> = z.rows(o, d).into_owned();
            let hi: DMatrix<f64> = h.rows(o, d).into_owned();
            let ri: DMatrix<f64> = r.view((o, o), (d, d)).into_owned();
            for f in pair.iter_mut().flatten() {
                f.predict_trusted(&models.phi[k], &models.q[k], 1.0)
                    .map_err(|e| crate::run::at_epoch(k, e))?;
                if zi.iter().any(|v| !v.is_nan()) {
                    f.update_trusted(&zi, &hi, &ri)
                        .map_err(|e| crate::run::at_epoch(k, e))?;
                }
            }
        }
        let single = channels.len() == 1;
        let mut any_excluded = false;
        z_used.copy_from(&z);
        let mut sources = 0u32;
        for (i, ch_det) in detectors.iter_mut().enumerate() {
            let (o, d) = (offsets[i], dims[i]);
            let ri: DVector<f64> = inn.residual.rows(o, d).into_owned();
            let ai: DMatrix<f64> = inn.covariance.view((o, o), (d, d)).into_owned();
            let (lambda, dof) = if single {
                (inn.statistic, inn.dof())
            } else if ri.iter().all(|v| v.is_nan()) {
                (f64::NAN, 0)
            } else {
                crate::detect::ResidualChi2::statistic(&ri, &ai)
                    .map_err(|e| crate::run::at_epoch(k, e))?
            };
            let sub = &mut rec.subs[i];
            sub.statistic.push(lambda);
            sub.dof.push(dof as u32);
            if mdb {
                if dof == d && lambda0[i].is_finite() {
                    let v = crate::stats::mdb_with(&ai, lambda0[i])
                        .map_err(|e| crate::run::at_epoch(k, e))?;
                    sub.mdb.extend_from_slice(&v);
                } else {
                    sub.mdb.extend(std::iter::repeat_n(f64::NAN, d));
                }
            }
            let mut decisions = Vec::with_capacity(ch_det.len());
            for det in ch_det.iter_mut() {
                decisions.push(match det {
                    SensorTest::Innovation(det) => det
                        .test_innovation(&ri, &ai, lambda, dof)
                        .map_err(|e| crate::run::at_epoch(k, e))?,
                    SensorTest::State(threshold) => {
                        let st = rec.state.as_ref().ok_or_else(|| {
                            Error::Invalid("a state_chi2 detector needs [state_chi2]".into())
                        })?;
                        // Tested in the epochs the sensor measures, as the residual test.
                        let pair = &pairs[i];
                        let measured = ri.iter().any(|v| !v.is_nan());
                        st.detector
                            .test_with(
                                |q| {
                                    pair[q]
                                        .as_ref()
                                        .filter(|_| measured)
                                        .map(|f| (f.x(), f.p()))
                                },
                                *threshold,
                            )
                            .into()
                    }
                });
            }
            let mut excluded = vec![false; d];
            let mut reinstated = false;
            if let Some(di) = decision[i] {
                match c.policy {
                    Policy::Exclude => {
                        if decisions[di].alarm {
                            excluded.iter_mut().for_each(|e| *e = true);
                        }
                    }
                    Policy::Latched => {
                        let (stats, thr) = sprt_components(&ch_det[di])?;
                        for (j, e) in excluded.iter_mut().enumerate() {
                            *e = stats.get(j).is_some_and(|l| *l >= thr);
                        }
                    }
                    Policy::Fading => {
                        let (stats, thr) = sprt_components(&ch_det[di])?;
                        let mut new_detection = false;
                        for j in 0..d {
                            let cj = &mut comps[i][j];
                            let alarmed =
                                stats.get(j).is_some_and(|l| *l >= thr) && decisions[di].alarm;
                            if alarmed {
                                if !cj.faulty {
                                    new_detection = true;
                                }
                                cj.faulty = true;
                                cj.below = 0;
                                if let SensorTest::Innovation(Detector::Sprt(sp)) = &mut ch_det[di]
                                {
                                    sp.reset_component(j); // the "pseudo-normal" state
                                }
                            } else if cj.faulty && !ri[j].is_nan() {
                                cj.below += 1;
                                if cj.below >= confirm {
                                    cj.faulty = false;
                                    cj.below = 0;
                                    reinstated = true;
                                }
                            }
                            excluded[j] = cj.faulty;
                        }
                        if new_detection {
                            fading_left = fading_epochs;
                        }
                        decisions[di].alarm = comps[i].iter().any(|cj| cj.faulty);
                    }
                }
            }
            let act = isolation && decision[i].is_some();
            let mut used_any = false;
            for j in 0..d {
                if act && excluded[j] && !z_used[o + j].is_nan() {
                    z_used[o + j] = f64::NAN;
                    any_excluded = true;
                } else if !z_used[o + j].is_nan() {
                    used_any = true;
                }
            }
            let sub = &mut rec.subs[i];
            sub.isolated.push(act && excluded.iter().any(|e| *e));
            sub.reinstated.push(reinstated);
            sub.fused.push(used_any);
            sources += used_any as u32;
            for (dr, dec) in sub.detectors.iter_mut().zip(&decisions) {
                dr.statistic.push(dec.statistic);
                dr.threshold.push(dec.threshold);
                dr.alarm.push(dec.alarm);
            }
        }
        if let Some((rows, fu)) = fusion.as_mut() {
            // Fault matrix: a sensor's height counts when its row survived the policy.
            let values: Vec<f64> = rows.iter().map(|&(_, row)| z[row]).collect();
            let healthy: Vec<bool> = rows.iter().map(|&(_, row)| !z_used[row].is_nan()).collect();
            let predicted = h.row(m).dot(&kf.x().transpose());
            let out = fu
                .step(&values, predicted, &healthy)
                .map_err(|e| crate::run::at_epoch(k, e))?;
            for &(_, row) in rows.iter() {
                z_used[row] = f64::NAN;
            }
            // Fused-altitude error against the true height error (the measurement's error).
            let truth = src
                .reference
                .map_or(f64::NAN, |r| r.x_true[k][crate::ins::POS + 2]);
            if let Some(fr) = rec.fusion.as_mut() {
                fr.error.extend(values.iter().map(|v| v - truth));
                fr.weight.extend_from_slice(&out.weights);
            }
            match out.value {
                Some(v) => {
                    z_used[m] = v;
                    r[(m, m)] = out.variance;
                    rec.fused_alt.push(v - truth);
                }
                None => rec.fused_alt.push(f64::NAN),
            }
            any_excluded = true;
        }
        match (any_excluded, pending) {
            (false, Some(p)) => kf.apply_pending(p, &r),
            (false, None) => Ok(()),
            (true, _) => kf.update_trusted(&z_used, &h, &r).map(|_| ()),
        }
        .map_err(|e| crate::run::at_epoch(k, e))?;
        rec.sources.push(sources);
        let due = rec.state.as_ref().and_then(|st| st.detector.reset_due());
        rec.push_navigation(src, k, kf.x(), kf.p(), &mut sig);
        // Sensor sub-filters restart with their propagator, from the same filter output.
        if let Some(q) = due {
            for (pair, tests) in pairs.iter_mut().zip(&detectors) {
                if tests.iter().any(|t| matches!(t, SensorTest::State(_))) {
                    pair[q] = Some(
                        KalmanFilter::new(kf.x().clone(), kf.p().clone())
                            .map_err(|e| crate::run::at_epoch(k, e))?,
                    );
                }
            }
        }
    }
    Ok(rec)
}

/// Per-component statistics and threshold of a deciding SPRT (validated to be one).
fn sprt_components(d: &SensorTest) -> Result<(Vec<f64>, f64)> {
    match d {
        SensorTest::Innovation(Detector::Sprt(s)) => Ok((s.component_statistics(), s.threshold())),
        _ => Err(Error::Invalid(
            "centralized: the latched and fading policies need an sprt deciding detector".into(),
        )),
    }
}
