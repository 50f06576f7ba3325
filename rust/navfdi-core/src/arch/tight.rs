//! Tightly coupled INS/GNSS with satellite fault detection and exclusion (paper 001,
//! METHODS §10).
//!
//! One Kalman filter over the 15-state INS error model plus receiver clock bias and drift (17
//! states), updated each epoch with the pseudorange and (optionally) pseudorange-rate
//! residuals of the satellites in view ([`crate::gnss::ranges`]); the measurement dimension
//! changes as satellites rise and set. Satellite FDE by placement ([`FdePlacement`]):
//!
//! * `ls_precheck` (method 1): before the filter, snapshot least squares on the raw
//!   pseudoranges (position + clock, start value: the INS position and the filter's clock
//!   estimate) with the global test and w-test exclusion loop; with rates, the same on the
//!   pseudorange rates of the remaining satellites (velocity + drift). Excluded satellites
//!   (either test) update the filter with neither observable. When too few satellites remain
//!   to test (`no_solution`), the satellites not excluded so far update the filter untested.
//! * `innovation` (method 2): the innovation `r`, `A = HP⁻Hᵀ + R` of all observations;
//!   global test `rᵀA⁻¹r ~ χ²(m)` (m observations); when it fails, the general w-test
//!   `w_i = (A⁻¹r)_i / sqrt((A⁻¹)_ii)` (Teunissen, the paper's ref. 9) per observation; the
//!   satellite of the largest |w| above K is excluded (both its rows) and the test repeated on
//!   the remaining rows until it passes (**resolution**: the paper's equations (10)–(14) are
//!   lost; this is the standard filter form, with the dof = number of innovation components
//!   rather than n − u).
//! * `gnss_filter` (method 2 as the paper ran it, "before the INS/GNSS integration"): the same
//!   innovation test in a GNSS-only position-velocity filter ([`PvFilter`]); satellites it
//!   excludes update neither filter.
//! * `none`: every satellite updates the filter; the innovation global test is recorded.
//!
//! Cost: when no per-satellite w is recorded (Monte-Carlo runs), `innovation` and `none`
//! first update row by row ([`KalmanFilter::sequential_pending`], which yields the global
//! statistic `rᵀA⁻¹r` without factoring A); only an epoch whose test fails under `innovation`
//! goes on to the batch innovation and the w-test exclusion loop. Same filter, same test, to
//! rounding.
//!
//! Recorded: the channel's one detector `global` (the first global test of the epoch:
//! statistic, threshold, alarm), `isolated` = some satellite excluded, `fused` = the ranges
//! updated the filter; and the per-satellite [`SatRecord`] with its FDE counts. With
//! `isolation = false` the FDE runs and reports but every satellite updates the filter.

use super::common::{record_sat_fde, record_untested, snapshot_araim};
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::gnss::innovation::{innovation_fde, snapshot_sat_fde, update_without, SatFde};
use crate::gnss::pv_filter::PvFilter;
use crate::gnss::ranges::{RangeStream, CLOCK_BIAS};
use crate::gnss::snapshot::{FdeConfig, FdeStatus, PositionModel, RateModel};
use crate::integrity::araim::Allocation;

use crate::integrity::filter_ss::SeparationBank;
use crate::kalman::{KalmanFilter, Sequential};
use crate::record::{IntegrityRecord, RunRecord, SatRecord};
use crate::spec::{FdePlacement, ScenarioSpec};
use crate::stream::{Nominal, Streams};
use nalgebra::{DMatrix, DVector};

/// Run the tight filter of scenario `spec` over one run's streams (`isolation = false`: FDE reports, never
/// excludes). `full`: also compute the innovation w-test of epochs whose global test passes
/// (for the record; Monte-Carlo runs that keep no series pass false). `cancel` is checked
/// every epoch.
pub fn run_tight(
    spec: &ScenarioSpec,
    src: &Streams,
    isolation: bool,
    full: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    let models = src.models;
    let t = spec.tight()?;
    let rp = models
        .ranges
        .as_ref()
        .ok_or_else(|| Error::Invalid("tight: the scenario has no gnss_ranges sensor".into()))?;
    let si = rp.sensor;
    let n = spec.n_states();
    let cfg =
        FdeConfig::new(t.alpha, t.k)?.with_test(t.ls_test, crate::gnss::lsq::DEFAULT_POWER)?;
    let mut kf = KalmanFilter::new(DVector::zeros(n), models.p0.clone())?;
    let s_count = rp.names.len();
    let epochs = src.epochs();
    let mut rec = RunRecord::empty(spec, models);
    let mut sat = SatRecord::new(rp.names.clone(), epochs);
    let mut sig = DVector::zeros(crate::ins::N_STATES);
    let mut pv = match (t.fde, &spec.sensors[si].ranges) {
        (FdePlacement::GnssFilter, Some(r)) => Some(PvFilter::new(spec.dt, t.accel_psd, &r.clock)),
        _ => None,
    };
    let mut seq = Sequential::new(n);
    let mut r_diag: Vec<f64> = Vec::new();
    let mut bank = t
        .integrity
        .as_ref()
        .map(|fi| SeparationBank::new(s_count, n, fi.p_sat, fi.allocation()));
    let mut integ = bank
        .as_ref()
        .map(|_| IntegrityRecord::with_capacity(epochs));
    for k in 0..epochs {
        cancel.check()?;
        kf.predict_trusted(&models.phi[k], &models.q[k], 1.0)
            .map_err(|e| crate::run::at_epoch(k, e))?;
        if let Some(b) = bank.as_mut() {
            b.predict(&models.phi[k], &models.q[k])
                .map_err(|e| crate::run::at_epoch(k, e))?;
            b.sync_view(&kf, &rp.epochs[k].sats);
        }
        if let Some(pv) = &mut pv {
            pv.predict().map_err(|e| crate::run::at_epoch(k, e))?;
        }
        let ep = &rp.epochs[k];
        let m = ep.len();
        for &s in &ep.sats {
            sat.in_view[k * s_count + s] = true;
        }
        if !(models.available[si][k] && m > 0) {
            record_untested(&mut rec, &mut sat);
            if let (Some(b), Some(ir)) = (bank.as_ref(), integ.as_mut()) {
                // Coasting: the levels of the predicted filter, nothing tested.
                let nom = &models.nominal[k];
                let lv = b.levels(&kf, nom.lat, nom.h);
                ir.push(&lv, [f64::NAN; 2], false);
            }
            rec.push_navigation(src, k, kf.x(), kf.p(), &mut sig);
            continue;
        }
        let rows = if t.rates { 2 * m } else { m };
        let z: DVector<f64> = src.meas.z[si][k].rows(0, rows).into_owned();
        let h: DMatrix<f64> = ep.h.rows(0, rows).into_owned();
        r_diag.clear();
        r_diag.extend(
            ep.sigma
                .iter()
                .map(|s| s * s)
                .chain(ep.sigma_rate.iter().map(|s| s * s))
                .take(rows),
        );
        let r = DMatrix::from_diagonal(&DVector::from_column_slice(&r_diag));
        if let (FdePlacement::Separation, Some(b), Some(ir)) =
            (t.fde, bank.as_mut(), integ.as_mut())
        {
            let updated = separation_epoch(
                &mut kf,
                b,
                ir,
                &mut rec,
                &mut sat,
                src,
                rp,
                k,
                (&z, &h, &r, &r_diag),
                isolation,
            )
            .map_err(|e| crate::run::at_epoch(k, e))?;
            rec.subs[0].fused.push(updated > 0);
            sat.used.push(updated as u32);
            rec.sources.push(u32::from(updated > 0));
            rec.push_navigation(src, k, kf.x(), kf.p(), &mut sig);
            continue;
        }
        let mut sequential = false;
        let (out, pending) = match t.fde {
            FdePlacement::LsPrecheck => (ls_precheck(src, k, kf.x(), t.rates, &cfg)?, None),
            // Fast path (no per-satellite w wanted): the update row by row, which yields the
            // global statistic; only an epoch whose test fails (and that may exclude) goes on
            // to the batch innovation and the w-test.
            FdePlacement::Innovation | FdePlacement::None
                if !full
                    && seq_passes(&kf, &z, &h, &r_diag, &mut seq, &cfg, t.fde)
                        .map_err(|e| crate::run::at_epoch(k, e))? =>
            {
                sequential = true;
                let thr = cfg.threshold(seq.dof)?;
                let out = SatFde {
                    excluded: Vec::new(),
                    status: FdeStatus::Passed,
                    first: (seq.statistic, thr, seq.dof),
                    w: vec![f64::NAN; m],
                };
                (out, None)
            }
            FdePlacement::GnssFilter => {
                let raw = src.meas.raw[k].as_slice();
                let pv = pv
                    .as_mut()
                    .ok_or_else(|| Error::Invalid("tight: no GNSS filter".into()))?;
                let out = pv
                    .step(
                        &ep.sat_pos,
                        &ep.sat_vel,
                        &raw[..m],
                        &raw[m..2 * m],
                        &ep.sigma,
                        &ep.sigma_rate,
                        t.rates,
                        &cfg,
                    )
                    .map_err(|e| crate::run::at_epoch(k, e))?;
                // Before the GNSS filter is initialised (fewer than 5 satellites so far) the
                // satellites pass untested.
                let out = out.unwrap_or_else(|| SatFde {
                    excluded: Vec::new(),
                    status: FdeStatus::NoSolution,
                    first: (f64::NAN, f64::NAN, 0),
                    w: vec![f64::NAN; m],
                });
                (out, None)
            }
            FdePlacement::Innovation | FdePlacement::None | FdePlacement::Separation => {
                let (inn, pending) = kf
                    .innovation_pending(&z, &h, &r)
                    .map_err(|e| crate::run::at_epoch(k, e))?;
                let out = innovation_fde(
                    &inn.residual,
                    &inn.covariance,
                    m,
                    t.fde == FdePlacement::Innovation,
                    Some(inn.statistic),
                    full,
                    &cfg,
                )?;
                (out, pending)
            }
        };
        record_sat_fde(
            &mut rec,
            &mut sat,
            k,
            &out,
            |j| ep.sats[j],
            t.fde == FdePlacement::None,
        );
        let excluded: &[usize] = if isolation { &out.excluded } else { &[] };
        let updated = if sequential {
            kf.commit_sequential(&mut seq)
                .map_err(|e| crate::run::at_epoch(k, e))?;
            m
        } else {
            update_without(&mut kf, &z, &h, &r, m, excluded, pending)
                .map_err(|e| crate::run::at_epoch(k, e))?
        };
        if let (Some(b), Some(ir)) = (bank.as_mut(), integ.as_mut()) {
            // Protection levels of the filter as it was updated (the sub-filters leave out
            // what it left out); the test is reported, the placement decides.
            let used: Vec<bool> = (0..m).map(|j| !excluded.contains(&j)).collect();
            b.update(&z, &h, &r_diag, &ep.sats, &used)
                .map_err(|e| crate::run::at_epoch(k, e))?;
            let nom = &models.nominal[k];
            let lv = b.levels(&kf, nom.lat, nom.h);
            let snap = snapshot_levels(rp, nom, k, &used, b.allocation_spec());
            ir.push(&lv, snap, lv.alarm);
        }
        rec.subs[0].fused.push(updated > 0);
        sat.used.push(updated as u32);
        rec.sources.push(u32::from(updated > 0));
        rec.push_navigation(src, k, kf.x(), kf.p(), &mut sig);
    }
    rec.integrity = integ;
    // Satellite-FDE counts per fault on the sensor.
    sat.score(&rec.t, &spec.faults, &spec.sensors[si].name);
    rec.sats = Some(sat);
    Ok(rec)
}

/// The sequential update of `z` into `seq` and whether it can be committed as it is: the
/// global test passes, or nothing would be excluded anyway (placement `none`). False sends the
/// epoch to the batch innovation and w-test exclusion loop (the filter is unchanged).
fn seq_passes(
    kf: &KalmanFilter,
    z: &DVector<f64>,
    h: &DMatrix<f64>,
    r_diag: &[f64],
    seq: &mut Sequential,
    cfg: &FdeConfig,
    placement: FdePlacement,
) -> Result<bool> {
    kf.sequential_pending(z, h, r_diag, seq)?;
    Ok(placement == FdePlacement::None || seq.statistic < cfg.threshold(seq.dof)?)
}

/// Method 1: snapshot FDE on the raw pseudoranges (and rates) of epoch `k`.
fn ls_precheck(
    src: &Streams,
    k: usize,
    x_hat: &DVector<f64>,
    rates: bool,
    cfg: &FdeConfig,
) -> Result<SatFde> {
    let rp = src
        .models
        .ranges
        .as_ref()
        .ok_or_else(|| Error::Invalid("no ranges".into()))?;
    let ep = &rp.epochs[k];
    let m = ep.len();
    let raw = &src.meas.raw[k];
    // Start value: the INS position and the filter's clock estimate, as a receiver-side
    // implementation would have them.
    let r_ins = src.meas.ins_position[k];
    let x0 = [r_ins.x, r_ins.y, r_ins.z, x_hat[CLOCK_BIAS]];
    let rho = &raw.as_slice()[..m];
    let model = PositionModel::new(&ep.sat_pos, rho, x0);
    if rates {
        let rate = RateModel::new(&ep.los, &ep.sat_vel, &raw.as_slice()[m..2 * m]);
        let sigma: Vec<f64> = ep.sigma.iter().chain(&ep.sigma_rate).copied().collect();
        snapshot_sat_fde(model, Some(rate), sigma, cfg)
    } else {
        snapshot_sat_fde(model, None, ep.sigma.clone(), cfg)
    }
}

/// One epoch of placement `separation`: the filter updates with every satellite in view not
/// excluded, the bank with the same less its own; on an alarm (and `isolation`) the satellite
/// [`SeparationBank::identify`] names, if it names one, is excluded
/// ([`SeparationBank::exclude`]), and the levels are those after it. Excluded satellites rejoin after a consistent spell
/// ([`SeparationBank::readmit`]). Returns the satellites that updated the filter.
#[allow(clippy::too_many_arguments)]
fn separation_epoch(
    kf: &mut KalmanFilter,
    bank: &mut SeparationBank,
    ir: &mut IntegrityRecord,
    rec: &mut RunRecord,
    sat: &mut SatRecord,
    src: &Streams,
    rp: &RangeStream,
    k: usize,
    (z, h, r, r_diag): (&DVector<f64>, &DMatrix<f64>, &DMatrix<f64>, &[f64]),
    isolation: bool,
) -> Result<usize> {
    let ep = &rp.epochs[k];
    let m = ep.len();
    let before: Vec<usize> = (0..m).filter(|&j| bank.is_excluded(ep.sats[j])).collect();
    let mut updated = update_without(kf, z, h, r, m, &before, None)?;
    let used: Vec<bool> = (0..m).map(|j| !before.contains(&j)).collect();
    bank.update(z, h, r_diag, &ep.sats, &used)?;
    let nom = &src.models.nominal[k];
    let first = bank.levels(kf, nom.lat, nom.h);
    let mut excluded = before.clone();
    let mut lv = first;
    let mut identified = false;
    if first.alarm {
        if let Some(s) = bank.identify(kf) {
            identified = true;
            let j = ep.sats.iter().position(|&x| x == s);
            if isolation && bank.exclude(kf, s)? {
                updated -= 1;
                lv = bank.levels(kf, nom.lat, nom.h);
            }
            excluded.extend(j);
        }
    }
    // Satellites excluded earlier that agree with the filter again rejoin from the next epoch.
    bank.readmit(kf, z, h, r_diag, &ep.sats);
    // An alarm without a clear culprit stands without an exclusion (`unidentified`).
    let status = if first.alarm && !identified {
        FdeStatus::Unidentified
    } else if excluded.is_empty() {
        FdeStatus::Passed
    } else {
        FdeStatus::Excluded
    };
    let out = SatFde {
        excluded,
        status,
        first: (first.statistic, 1.0, first.modes),
        w: vec![f64::NAN; m],
    };
    record_sat_fde(rec, sat, k, &out, |j| ep.sats[j], false);
    let used_now: Vec<bool> = (0..m)
        .map(|j| !out.excluded.contains(&j) || !isolation)
        .collect();
    let snap = snapshot_levels(
        rp,
        &src.models.nominal[k],
        k,
        &used_now,
        bank.allocation_spec(),
    );
    ir.push(&lv, snap, first.alarm);
    Ok(updated)
}

/// Snapshot ARAIM HPL and VPL (m) of epoch `k`'s pseudoranges of the satellites `used[j]`
/// ([`super::common::snapshot_araim`]).
fn snapshot_levels(
    rp: &RangeStream,
    nom: &Nominal,
    k: usize,
    used: &[bool],
    (p_sat, alloc): (f64, Allocation),
) -> [f64; 2] {
    let ep = &rp.epochs[k];
    let pick = |j: &usize| used.get(*j).copied().unwrap_or(false);
    let js: Vec<usize> = (0..ep.len()).filter(pick).collect();
    let los: Vec<_> = js.iter().map(|&j| ep.los[j]).collect();
    let systems: Vec<char> = js
        .iter()
        .map(|&j| rp.names[ep.sats[j]].chars().next().unwrap_or('G'))
        .collect();
    let sigma: Vec<f64> = js.iter().map(|&j| ep.sigma[j]).collect();
    snapshot_araim(&los, &systems, &sigma, nom.lat, nom.lon, p_sat, &alloc)
}
