//! Tightly coupled INS/GNSS on a recorded IMU and raw GNSS logs, with paper 001's satellite
//! FDE placements (METHODS §10): the strapdown INS of [`super::inertial`] in an 18-state
//! closed-loop error filter (the 15 INS errors, a receiver clock bias per system — GPS with
//! QZSS, Galileo — and the common clock drift; [`crate::ins::error_filter::N_CLOCK`]), updated
//! at each GNSS epoch with the pseudoranges and (with `rates`) Doppler range rates of every
//! satellite in view, predicted from the mechanised state at the antenna (lever arm applied):
//!
//! `ρ̂ᵢ = |sᵢ − r| + ω_e (sᵢ,x r_y − sᵢ,y r_x)/c + b_sys`, `ρ̇̂ᵢ = eᵢ·(vᵢ − v) + d` with `eᵢ` the
//! unit vector to the satellite; the rows of `H` are `−eᵢᵀ` (north-east-down) on position or
//! velocity, `−eᵢᵀ [(C l)×]` or `−eᵢᵀ [(C (ω × l))×]` on the attitude error and 1 on the clock.
//! The recorded observations come corrected for the satellite clock, group delay and
//! atmosphere ([`crate::logs`]).
//!
//! Placements (as on simulated ranges, [`super::tight`]): `innovation` — the innovation
//! chi-square test and the w-test with iterative exclusion of the satellite of the largest
//! |w| ([`crate::gnss::innovation::innovation_fde`]); `ls_precheck` — snapshot least squares
//! on the raw pseudoranges (and rates) from the INS antenna position and the filter's clocks
//! (the Galileo pseudoranges moved onto the GPS clock by the filter's inter-system bias; the
//! Sagnac rotation applied to the satellite positions), global test and w-test exclusion,
//! before the filter; `none` — every satellite updates the filter, the innovation test is
//! recorded; `separation` (with `[tight.integrity]`) — the bank's separation test: on an alarm
//! the satellite whose sub-filter separates most, if that sub-filter's navigator explains the
//! epoch (the other satellites agree with it, the named one does not), is excluded and the
//! filter takes that navigator over; at most `MAX_SEPARATION_OUT` out at once, each back
//! after [`crate::integrity::filter_ss::READMIT_EPOCHS`] epochs in a row of agreeing with the
//! filter. With `rates`, a satellite without a Doppler at an epoch is left out of it.
//!
//! With `[tight.integrity]` a bank of strapdown sub-filters gives the filter's protection levels
//! (`super::tight_ins_pl`; the test reports and, under `separation`, excludes), beside the
//! snapshot ARAIM levels of the epoch's pseudoranges.
//!
//! Alignment as the loosely coupled filter's ([`super::inertial::align`]) on the source's
//! snapshot fixes; the clocks start from the alignment epoch's observations at the aligned
//! position.

use super::common::{record_sat_fde, record_untested, snapshot_araim};
use super::inertial::{align, antenna, record_nav, shift, BodyImu, Mechaniser};
use super::tight_ins_pl::StrapdownBank;
use crate::cancel::Cancel;
use crate::error::{Error, Result};
use crate::gnss::broadcast::{Sat, Sys};
use crate::gnss::geodesy::{ecef_to_enu, lla_to_ecef, sagnac};
use crate::gnss::innovation::{innovation_fde, snapshot_sat_fde, SatFde};
use crate::gnss::ranges::RangeEpoch;
use crate::gnss::snapshot::{FdeConfig, FdeStatus, PositionModel, RateModel};
use crate::ins::error_filter::{ErrorFilter, CB, CD, N_CLOCK, PHI, R, V};
use crate::ins::range_states::{self as rs, RangeStates};
use crate::ins::strapdown::{skew, NavState};
use crate::record::{IntegrityRecord, RunRecord, SatRecord, NAV_COLUMNS};
use crate::spec::{FdePlacement, ScenarioSpec};
use crate::stream::Streams;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// One epoch's rows: pseudoranges of `m` satellites, then (with rates) their range rates.
struct Rows {
    /// Local satellite index (into the epoch's) of each used satellite.
    idx: Vec<usize>,
    /// `ẑ − z` (pseudoranges, then rates).
    res: DVector<f64>,
    h: DMatrix<f64>,
    sigma: Vec<f64>,
    /// Unit vectors antenna → satellite (ECEF), satellite positions rotated for the Sagnac
    /// effect, the pseudoranges on the GPS clock and the rates: the snapshot check's inputs.
    los: Vec<Vector3<f64>>,
    sat_rot: Vec<Vector3<f64>>,
    rho_gps: Vec<f64>,
    rate: Vec<f64>,
    sat_vel: Vec<Vector3<f64>>,
}

/// Clock column of a satellite system (GPS and QZSS 0, Galileo 1).
fn clock_column(name: &str) -> usize {
    match Sat::parse(name).map(|s| s.sys) {
        Some(Sys::Galileo) => 1,
        _ => 0,
    }
}

/// Run the tight filter of scenario `spec` (with `tight.strapdown`) over one run's streams of
/// a recorded-data source (`isolation = false`: FDE reports, never excludes). `full`: the
/// w-test of every epoch for the record.
pub fn run_tight_ins(
    spec: &ScenarioSpec,
    src: &Streams,
    isolation: bool,
    full: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    let t = spec.tight()?;
    let sd = t
        .strapdown
        .as_ref()
        .ok_or_else(|| Error::Invalid("tight.strapdown: missing".into()))?;
    let models = src.models;
    let logged = models.logged.as_ref().ok_or_else(|| {
        Error::Invalid(
            "tight.strapdown runs a strapdown INS on recorded IMU samples: run the scenario from its [source] logs".into(),
        )
    })?;
    let rp = models
        .ranges
        .as_ref()
        .ok_or_else(|| Error::Invalid("tight: the source has no satellite ranges".into()))?;
    let si = rp.sensor;
    let sensor = &spec.sensors[si];
    let clock = sensor
        .ranges
        .as_ref()
        .map(|r| r.clock)
        .ok_or_else(|| Error::Invalid(format!("sensors[{si}].ranges: missing")))?;
    let cfg =
        FdeConfig::new(t.alpha, t.k)?.with_test(t.ls_test, crate::gnss::lsq::DEFAULT_POWER)?;
    let epochs = models.epochs();
    let mut rec = RunRecord::empty(spec, models);
    rec.nav = Vec::with_capacity(epochs * NAV_COLUMNS.len());
    let s_count = rp.names.len();
    let cols: Vec<usize> = rp.names.iter().map(|n| clock_column(n)).collect();
    let mut sat = SatRecord::new(rp.names.clone(), epochs);
    let imu = BodyImu::new(&logged.imu, sd.mounting, sd.imu_time_offset)?;
    let lever = Vector3::from(sd.lever_arm);
    let fix = |k: usize, o: usize| -> Option<Vector3<f64>> {
        let f = logged.fixes.get(k)?;
        let v = Vector3::new(f[o], f[o + 1], f[o + 2]);
        v.iter().all(|x| x.is_finite()).then_some(v)
    };
    let sig_rate = sensor.noise.get(1).copied().unwrap_or(0.1);
    let aligned = align(
        &sd.alignment,
        "tight.strapdown",
        &imu,
        &models.t,
        &logged.origin,
        |k| fix(k, 3),
        |k| fix(k, 0),
        |_| sig_rate,
        false,
    )?;
    let ka = aligned.epoch;
    let mut s = aligned.state;
    let to_imu = -(s.q * lever);
    shift(&mut s, &to_imu);
    let clocks = initial_clocks(&s, &lever, &rp.epochs[ka], &src.meas.z[si][ka], &cols);
    let mut kf = ErrorFilter::<N_CLOCK>::new(
        sd.alignment.sigma_position,
        sd.alignment.sigma_velocity,
        aligned.sig_att,
        aligned.bg0,
        sd.imu,
    )
    .with_mounting(&crate::ins::strapdown::mounting(
        sd.mounting[0],
        sd.mounting[1],
        sd.mounting[2],
    ))
    .with_clock(
        clocks,
        [clock.bias, clock.bias, clock.drift],
        (clock.bias_psd, clock.drift_psd),
    );
    // With range-error states: satellites excluded at the previous epoch (stream indices),
    // kept out while their own innovation disagrees.
    let mut held: Vec<bool> = vec![false; s_count];
    // Placement `separation`: satellites the bank excluded, and their epochs in a row since
    // consistent with the filter (readmitted after READMIT_EPOCHS).
    let mut sep_out: Vec<bool> = vec![false; s_count];
    let mut sep_ok: Vec<u32> = vec![0; s_count];
    let mut gm = match &t.range_states {
        Some(r) => {
            kf.track_transition();
            Some(RangeStates::new(s_count, r.fraction, r.tau, models.t[ka])?)
        }
        None => None,
    };
    for _ in 0..ka {
        skip(&mut rec, &mut sat);
    }
    let mut mech = Mechaniser::new(&imu, models.t[ka], &kf.bg);
    let mut bank = t
        .integrity
        .as_ref()
        .map(|fi| StrapdownBank::new(s_count, fi.p_sat, fi.allocation()));
    let mut integ = bank.as_ref().map(|_| {
        let mut ir = IntegrityRecord::with_capacity(epochs);
        for _ in 0..ka {
            ir.push_none();
        }
        ir
    });
    for k in ka..epochs {
        if k % 64 == 0 {
            cancel.check()?;
        }
        let tk = models.t[k];
        if tk > imu.end() {
            skip(&mut rec, &mut sat);
            if let Some(ir) = integ.as_mut() {
                ir.push_none();
            }
            continue;
        }
        mech.advance(&imu, &mut s, &mut kf, tk);
        let ep = &rp.epochs[k];
        if let Some(b) = bank.as_mut() {
            b.advance(&imu, tk);
            b.sync_view(&s, &kf, gm.as_ref(), &mech, &ep.sats, tk);
        }
        for &j in &ep.sats {
            sat.in_view[k * s_count + j] = true;
        }
        let rows = if models.available[si][k] {
            build_rows(
                &s,
                &kf,
                &lever,
                &mech.w_last,
                ep,
                &src.meas.z[si][k],
                &cols,
                t.rates,
            )
        } else {
            None
        };
        let Some(mut rows) = rows else {
            record_untested(&mut rec, &mut sat);
            if let (Some(b), Some(ir)) = (bank.as_ref(), integ.as_mut()) {
                // Coasting: the levels of the mechanised filter, nothing tested.
                let lv = b.levels(&s, &kf);
                ir.push(&lv, [f64::NAN; 2], false);
            }
            record_nav(&mut rec, &s, &kf, &lever, &logged.origin, src, k);
            continue;
        };
        let m = rows.idx.len();
        let r_diag: Vec<f64> = rows.sigma.iter().map(|x| x * x).collect();
        let row_sats: Vec<usize> = (0..rows.res.len())
            .map(|i| ep.sats[rows.idx[i % m]])
            .collect();
        if let Some(g) = gm.as_mut() {
            g.propagate(&mut kf, tk, &row_sats[..m], &rows.sigma[..m]);
            g.correct(&mut rows.res, &row_sats, m);
            // The innovation placements' rules for what a state took in; under `separation`
            // the sub-filter without the satellite is the reference instead.
            if !matches!(t.fde, FdePlacement::None | FdePlacement::Separation) {
                restart_returned(g, &kf, &mut rows, &r_diag, &row_sats, &held, cfg.k);
                flag_absorbed(g, &mut rows, &row_sats, &mut held, cfg.k);
            }
        }
        // The innovation covariance of the batch (for the w-test), with the range-error
        // states when the filter has them.
        let inn_cov = |kf: &ErrorFilter<N_CLOCK>| -> Result<DMatrix<f64>> {
            match gm.as_ref() {
                Some(g) => Ok(g.innovation_cov(kf, &rows.h, &r_diag, &row_sats, m)),
                None => {
                    let r = DMatrix::from_diagonal(&DVector::from_column_slice(&r_diag));
                    Ok(kf.innovation(&rows.res, &rows.h, &r)?.s)
                }
            }
        };
        // The update row by row yields the global statistic without factoring the m × m
        // innovation covariance; only an epoch whose test fails under `innovation` (or whose
        // w are recorded) goes on to the batch innovation and the w-test.
        let (pending, lambda) =
            rs::sequential(&kf, gm.as_ref(), &rows.res, &rows.h, &r_diag, &row_sats, m)
                .map_err(|e| crate::run::at_time(k, tk, e))?;
        let thr = cfg.threshold(rows.res.len())?;
        if t.fde == FdePlacement::Separation {
            readmit(
                &mut sep_out,
                &mut sep_ok,
                &kf,
                gm.as_ref(),
                &rows,
                &r_diag,
                &row_sats,
                cfg.k,
            );
        }
        let out = match t.fde {
            FdePlacement::LsPrecheck => ls_precheck(&rows, &s, &kf, &lever, t.rates, &cfg)?,
            FdePlacement::Separation => SatFde {
                excluded: (0..m).filter(|&j| sep_out[row_sats[j]]).collect(),
                status: FdeStatus::Passed,
                first: (lambda, thr, rows.res.len()),
                w: vec![f64::NAN; m],
            },
            _ if lambda < thr || t.fde == FdePlacement::None => {
                let w = if full {
                    let s_inn = inn_cov(&kf).map_err(|e| crate::run::at_time(k, tk, e))?;
                    innovation_fde(&rows.res, &s_inn, m, false, Some(lambda), true, &cfg)?.w
                } else {
                    vec![f64::NAN; m]
                };
                SatFde {
                    excluded: Vec::new(),
                    status: FdeStatus::Passed,
                    first: (lambda, thr, rows.res.len()),
                    w,
                }
            }
            _ => {
                let s_inn = inn_cov(&kf).map_err(|e| crate::run::at_time(k, tk, e))?;
                innovation_fde(&rows.res, &s_inn, m, true, Some(lambda), full, &cfg)?
            }
        };
        let mut out = out;
        if let (Some(g), false) = (gm.as_ref(), t.fde == FdePlacement::Separation) {
            hold_excluded(
                &mut out, &mut held, g, &kf, &rows, &r_diag, &row_sats, cfg.k,
            );
        }
        let excluded: Vec<usize> = if isolation {
            out.excluded.clone()
        } else {
            Vec::new()
        };
        let excluded = excluded.as_slice();
        let mut used = m - excluded.len();
        if excluded.is_empty() {
            rs::commit(&mut kf, gm.as_mut(), &mut s, pending)?;
        } else if used > 0 {
            let keep: Vec<usize> = (0..rows.res.len())
                .filter(|i| !excluded.contains(&(i % m)))
                .collect();
            let res = rows.res.select_rows(&keep);
            let h = rows.h.select_rows(&keep);
            let rk: Vec<f64> = keep.iter().map(|&i| r_diag[i]).collect();
            let ks: Vec<usize> = keep.iter().map(|&i| row_sats[i]).collect();
            let (up, _) = rs::sequential(&kf, gm.as_ref(), &res, &h, &rk, &ks, used)
                .map_err(|e| crate::run::at_time(k, tk, e))?;
            rs::commit(&mut kf, gm.as_mut(), &mut s, up)?;
        }
        if let (Some(b), Some(ir)) = (bank.as_mut(), integ.as_mut()) {
            // The sub-filters leave out what the filter left out, and their own satellite.
            let gone: Vec<usize> = excluded.iter().map(|&j| ep.sats[rows.idx[j]]).collect();
            let z = &src.meas.z[si][k];
            let rows_of = |sn: &NavState, f: &ErrorFilter<N_CLOCK>, w: &Vector3<f64>| {
                let r = build_rows(sn, f, &lever, w, ep, z, &cols, t.rates)?;
                let m = r.idx.len();
                let sats = (0..r.res.len()).map(|i| ep.sats[r.idx[i % m]]).collect();
                Some((r.res, r.h, r.sigma, sats, m))
            };
            b.update(rows_of, &gone, tk)
                .map_err(|e| crate::run::at_time(k, tk, e))?;
            let mut lv = b.levels(&s, &kf);
            if t.fde == FdePlacement::Separation && lv.alarm {
                // The satellite the bank names, if its sub-filter explains the epoch: the
                // filter takes that sub-filter's navigator (isolation), or reports it. At most
                // MAX_SEPARATION_OUT out at once: an alarm with that many out says the
                // exclusions did not clear the fault, and excluding more from a filter that
                // holds it only spreads it — the alarm stands instead.
                let full = sep_out.iter().filter(|&&x| x).count() >= MAX_SEPARATION_OUT;
                let named = b
                    .identify(&s, &kf)
                    .filter(|&g| !full && b.explains(g, rows_of, &gone, cfg.k));
                match named.and_then(|g| (0..m).find(|&j| row_sats[j] == g).map(|j| (g, j))) {
                    Some((g, j)) => {
                        if isolation && b.exclude(g, &mut s, &mut kf, &mut gm, &mut mech) {
                            sep_out[g] = true;
                            sep_ok[g] = 0;
                            used -= 1;
                            lv = b.levels(&s, &kf);
                        }
                        out.excluded.push(j);
                        out.status = FdeStatus::Excluded;
                    }
                    None => out.status = FdeStatus::Unidentified,
                }
            }
            let js: Vec<usize> = (0..m).filter(|j| !excluded.contains(j)).collect();
            let los: Vec<Vector3<f64>> = js.iter().map(|&j| rows.los[j]).collect();
            let systems: Vec<char> = js
                .iter()
                .map(|&j| rp.names[ep.sats[rows.idx[j]]].chars().next().unwrap_or('G'))
                .collect();
            let sigma: Vec<f64> = js.iter().map(|&j| rows.sigma[j]).collect();
            let (p_sat, alloc) = b.allocation();
            let snap = snapshot_araim(&los, &systems, &sigma, s.lat, s.lon, p_sat, &alloc);
            ir.push(&lv, snap, lv.alarm);
        }
        record_sat_fde(
            &mut rec,
            &mut sat,
            k,
            &out,
            |j| ep.sats[rows.idx[j]],
            t.fde == FdePlacement::None,
        );
        rec.subs[0].fused.push(used > 0);
        sat.used.push(used as u32);
        rec.sources.push(u32::from(used > 0));
        record_nav(&mut rec, &s, &kf, &lever, &logged.origin, src, k);
    }
    rec.integrity = integ;
    sat.score(&rec.t, &spec.faults, &sensor.name);
    rec.sats = Some(sat);
    rec.restrict_faults_to_navigated(spec, models);
    Ok(rec)
}

/// With range-error states, a satellite the FDE excluded stays out at the next epochs while its
/// pseudorange's own normalised innovation `|ν|/√s` exceeds the w-test's critical value `k`,
/// whatever the global test says: re-admitted while its fault lasts — at an epoch whose σ
/// spikes with a dip of the signal and hides it — its range-error state would take in part of
/// the fault, and every later epoch would see less of it (the white filter forgets such an
/// epoch; the state carries it over its correlation time). `held` (stream indices) is updated
/// to this epoch's exclusions.
#[allow(clippy::too_many_arguments)]
fn hold_excluded(
    out: &mut SatFde,
    held: &mut [bool],
    gm: &RangeStates,
    kf: &ErrorFilter<N_CLOCK>,
    rows: &Rows,
    r_diag: &[f64],
    row_sats: &[usize],
    k: f64,
) {
    let m = rows.idx.len();
    for j in 0..m {
        let g = row_sats[j];
        if held[g] && !out.excluded.contains(&j) && out.excluded.len() + 1 < m {
            let s = gm.row_variance(kf, &rows.h, j, r_diag[j], g, true);
            if (rows.res[j] / s.sqrt()).abs() > k {
                out.excluded.push(j);
            }
        }
    }
    held.iter_mut().for_each(|h| *h = false);
    for &j in &out.excluded {
        held[row_sats[j]] = true;
    }
}

/// A held satellite (excluded at the previous epoch) whose pseudorange disagrees with its
/// range-error state but agrees with no range error at all has returned: a slow fault (a
/// ramp) that the state took in before it was excluded has ended, and the state still holds
/// it. Its state restarts from its stationary variance (and its row's correction is removed),
/// so the satellite is used again instead of being held until the state decays.
fn restart_returned(
    gm: &mut RangeStates,
    kf: &ErrorFilter<N_CLOCK>,
    rows: &mut Rows,
    r_diag: &[f64],
    row_sats: &[usize],
    held: &[bool],
    k: f64,
) {
    for j in 0..rows.idx.len() {
        let g = row_sats[j];
        if !held[g] {
            continue;
        }
        let s = gm.row_variance(kf, &rows.h, j, r_diag[j], g, true);
        let b = gm.bias(g);
        let s0 = gm.restarted_row_variance(kf, &rows.h, j, r_diag[j], g);
        if (rows.res[j] / s.sqrt()).abs() > k && ((rows.res[j] - b) / s0.sqrt()).abs() <= k {
            gm.restart(g);
            rows.res[j] -= b;
        }
    }
}

/// A satellite whose range-error estimate has grown beyond what its model allows
/// (`|b̂| > k √(a σ̄² − P_bb)`, the estimate's own σ under the model) has taken in a slow fault
/// (a ramp looks like a correlated error to the innovation test): its state restarts, its
/// row's correction is removed, and it is marked held, so [`hold_excluded`] keeps it out while
/// its pseudorange disagrees with no range error at all.
fn flag_absorbed(
    gm: &mut RangeStates,
    rows: &mut Rows,
    row_sats: &[usize],
    held: &mut [bool],
    k: f64,
) {
    for (j, &g) in row_sats.iter().enumerate().take(rows.idx.len()) {
        if held[g] {
            continue;
        }
        let (b, sd) = (gm.bias(g), gm.estimate_sigma(g));
        if sd > 0.0 && b.abs() > k * sd {
            gm.restart(g);
            rows.res[j] -= b;
            held[g] = true;
        }
    }
}

/// Most satellites the separation placement keeps out at once. One (the single-fault modes
/// the bank monitors) left a wrong first exclusion — a low satellite's natural error named
/// before a slow ramp elsewhere — standing while the ramp went in (20 m errors in 3 of 100
/// walk runs); unlimited, a fault named late spread into a cascade of exclusions (92 m in one
/// run of 100); two had neither.
const MAX_SEPARATION_OUT: usize = 2;

/// Placement `separation`: each satellite the bank excluded (`out`, stream indices) that is in
/// view counts the epochs in a row at which every row of it agrees with the filter before its
/// update (normalised innovation within `k`); after
/// [`crate::integrity::filter_ss::READMIT_EPOCHS`] it rejoins (the bank gives it a sub-filter
/// again, a copy of the filter's navigator, as for any satellite without one).
#[allow(clippy::too_many_arguments)]
fn readmit(
    out: &mut [bool],
    consistent: &mut [u32],
    kf: &ErrorFilter<N_CLOCK>,
    gm: Option<&RangeStates>,
    rows: &Rows,
    r_diag: &[f64],
    row_sats: &[usize],
    k: f64,
) {
    let m = rows.idx.len();
    for (j, &g) in row_sats.iter().enumerate().take(m) {
        if !out[g] {
            continue;
        }
        let agrees = (j..rows.res.len()).step_by(m).all(|i| {
            let var = rs::row_variance(kf, gm, &rows.h, i, r_diag[i], g, i < m);
            var > 0.0 && (rows.res[i] / var.sqrt()).abs() <= k
        });
        consistent[g] = if agrees { consistent[g] + 1 } else { 0 };
        if consistent[g] >= crate::integrity::filter_ss::READMIT_EPOCHS {
            out[g] = false;
            consistent[g] = 0;
        }
    }
}

/// An epoch without navigation (before the alignment, after the IMU log).
fn skip(rec: &mut RunRecord, sat: &mut SatRecord) {
    record_untested(rec, sat);
    rec.error.extend([f64::NAN; 9]);
    rec.sigma.extend([f64::NAN; 9]);
    rec.nav.extend([f64::NAN; NAV_COLUMNS.len()]);
}

/// The antenna's ECEF position (m) and the ECEF → north-east-down rotation there.
fn antenna_ecef(s: &NavState, lever: &Vector3<f64>) -> (Vector3<f64>, Matrix3<f64>) {
    let a = antenna(s, lever);
    let enu = ecef_to_enu(a.lat, a.lon);
    let ned = Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0) * enu;
    (lla_to_ecef(a.lat, a.lon, a.h), ned)
}

/// Per-system clock biases (m) and drift (m/s) from the observations `z` of epoch `ep` at the
/// state `s` (the mean of each system's ranges minus the geometry; the mean rate residual).
fn initial_clocks(
    s: &NavState,
    lever: &Vector3<f64>,
    ep: &RangeEpoch,
    z: &DVector<f64>,
    cols: &[usize],
) -> [f64; 3] {
    let m = ep.len();
    if z.len() != 2 * m || m == 0 {
        return [0.0; 3];
    }
    let (r, _) = antenna_ecef(s, lever);
    let mut sum = [0.0; 2];
    let mut n = [0usize; 2];
    let (mut d, mut nd) = (0.0, 0usize);
    let (_, c_en) = antenna_ecef(s, lever);
    let v_ecef = c_en.transpose() * s.v;
    for j in 0..m {
        let sp = sagnac(&ep.sat_pos[j], &r);
        let c = cols[ep.sats[j]];
        let res = z[j] - (sp - r).norm();
        if res.is_finite() {
            sum[c] += res;
            n[c] += 1;
        }
        let e = (sp - r).normalize();
        let rd = z[m + j] - e.dot(&(ep.sat_vel[j] - v_ecef));
        if rd.is_finite() {
            d += rd;
            nd += 1;
        }
    }
    let mean = |c: usize| (n[c] > 0).then(|| sum[c] / n[c] as f64);
    let g = mean(0).or(mean(1)).unwrap_or(0.0);
    let e = mean(1).unwrap_or(g);
    [g, e, if nd > 0 { d / nd as f64 } else { 0.0 }]
}

/// The rows of epoch `ep` at state `s`: every satellite in view (with rates, those with a
/// finite range rate).
#[allow(clippy::too_many_arguments)]
fn build_rows(
    s: &NavState,
    kf: &ErrorFilter<N_CLOCK>,
    lever: &Vector3<f64>,
    w: &Vector3<f64>,
    ep: &RangeEpoch,
    z: &DVector<f64>,
    cols: &[usize],
    rates: bool,
) -> Option<Rows> {
    let m_all = ep.len();
    if m_all == 0 || z.len() != 2 * m_all {
        return None;
    }
    let idx: Vec<usize> = (0..m_all)
        .filter(|&j| z[j].is_finite() && (!rates || z[m_all + j].is_finite()))
        .collect();
    let m = idx.len();
    if m == 0 {
        return None;
    }
    let (r, c_en) = antenna_ecef(s, lever);
    let cbn = s.q.to_rotation_matrix().into_inner();
    let cl = cbn * lever;
    let vl = cbn * w.cross(lever);
    let v_ecef = c_en.transpose() * (s.v + vl);
    let n_rows = if rates { 2 * m } else { m };
    let mut out = Rows {
        idx: idx.clone(),
        res: DVector::zeros(n_rows),
        h: DMatrix::zeros(n_rows, N_CLOCK),
        sigma: Vec::with_capacity(n_rows),
        los: Vec::with_capacity(m),
        sat_rot: Vec::with_capacity(m),
        rho_gps: Vec::with_capacity(m),
        rate: Vec::with_capacity(m),
        sat_vel: Vec::with_capacity(m),
    };
    let (skew_cl, skew_vl) = (skew(&cl), skew(&vl));
    for (row, &j) in idx.iter().enumerate() {
        let col = cols[ep.sats[j]];
        let sp = sagnac(&ep.sat_pos[j], &r);
        let d = sp - r;
        let range = d.norm();
        let e = d / range;
        let e_ned = c_en * e;
        out.res[row] = range + kf.clock[col] - z[j];
        let hp = -e_ned.transpose();
        let hphi_r = hp * skew_cl;
        for q in 0..3 {
            out.h[(row, R + q)] = hp[q];
            out.h[(row, PHI + q)] = hphi_r[q];
        }
        out.h[(row, CB + col)] = 1.0;
        out.sigma.push(ep.sigma[j]);
        out.los.push(e);
        out.sat_rot.push(sp);
        out.rho_gps.push(z[j] - kf.clock[col] + kf.clock[0]);
        out.rate.push(z[m_all + j]);
        out.sat_vel.push(ep.sat_vel[j]);
        if rates {
            let rr = m + row;
            out.res[rr] = e.dot(&(ep.sat_vel[j] - v_ecef)) + kf.clock[2] - z[m_all + j];
            let hphi_v = hp * skew_vl;
            for q in 0..3 {
                out.h[(rr, V + q)] = hp[q];
                out.h[(rr, PHI + q)] = hphi_v[q];
            }
            out.h[(rr, CD)] = 1.0;
        }
    }
    if rates {
        out.sigma.extend(idx.iter().map(|&j| ep.sigma_rate[j]));
    }
    Some(out)
}

/// Method 1: snapshot FDE on the raw pseudoranges (and rates) from the INS antenna and the
/// filter's clocks.
fn ls_precheck(
    rows: &Rows,
    s: &NavState,
    kf: &ErrorFilter<N_CLOCK>,
    lever: &Vector3<f64>,
    rates: bool,
    cfg: &FdeConfig,
) -> Result<SatFde> {
    let (r, _) = antenna_ecef(s, lever);
    let x0 = [r.x, r.y, r.z, kf.clock[0]];
    let model = PositionModel::new(&rows.sat_rot, &rows.rho_gps, x0);
    let rate = rates.then(|| RateModel::new(&rows.los, &rows.sat_vel, &rows.rate));
    snapshot_sat_fde(model, rate, rows.sigma.clone(), cfg)
}
