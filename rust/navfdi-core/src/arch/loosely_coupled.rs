//! Loosely coupled INS/GNSS on recorded IMU samples: a strapdown INS
//! ([`crate::ins::strapdown`]) in a closed-loop 15-state error-state filter
//! ([`crate::ins::error_filter`]), aided at the record epochs by GNSS positions and
//! velocities (lever arm applied) and by the optional vehicle constraints: zero velocity when
//! the IMU shows rest, and the non-holonomic constraint (no lateral or vertical body
//! velocity). Every aiding measurement is a detection channel: its innovation `λ` is tested by
//! the channel's detectors, and an alarm of its deciding detector drops the measurement for
//! the epoch (with isolation; a constraint's deciding detector always gates it, with or
//! without isolation: a constraint that fails its test does not hold at that epoch). Reads only the streams: the IMU samples and measurement σ in
//! [`crate::stream::Logged`], the measurements (faults already injected) and the reference.
//!
//! Alignment: levelling and gyro biases from the mean IMU output over the last static stretch
//! (GNSS speed below `alignment.static_speed`) before the first GNSS velocity above
//! `alignment.speed`; heading from that velocity's course (or given); position and velocity
//! from that epoch's fix. Epochs before it are recorded as NaN.

mod blame;
mod checks;
mod correlation;
mod diverge;
mod hold;
mod noise_scale;
mod own_noise;
mod pull;
mod receiver;
mod rest;
mod shadow;
mod window;

use super::common::make_detector;
use super::inertial::{align, record_nav, repeated_fixes, BodyImu, Mechaniser};
use crate::cancel::Cancel;
use crate::detect::Detector;
use crate::error::{Error, Result};
use crate::ins::error_filter::{ErrorFilter, N, N_SCALE, PHI, R};
use crate::ins::strapdown::{mounting, NavState};
use crate::record::{RunRecord, NAV_COLUMNS};
use crate::spec::{ScenarioSpec, SensorKind};
use crate::stream::{Nominal, Streams};
use checks::{
    antenna, enu, gnss_measurement, isolate, nhc_applies, nhc_meas, rows, shift, sigma_h, still,
    three, update, zupt_meas, Meas,
};
use nalgebra::{DMatrix, DVector, Vector3};

/// One aiding channel's configuration resolved against the scenario.
struct Aid {
    /// Sensor index in the scenario (None for a constraint).
    sensor: Option<usize>,
    /// Offset of the position east/north/up components in the sensor's vector.
    pos: Option<usize>,
    /// Offset of the velocity components.
    vel: Option<usize>,
    detectors: Vec<Detector>,
    decision: Option<usize>,
    /// False-alarm probability of the deciding detector (component isolation's tests).
    decision_pf: f64,
    /// Fallback σ per component (the sensor's `noise`), a floor under the recorded σ.
    floor: Vec<f64>,
}

/// Per-epoch outcome of one channel.
#[derive(Clone)]
struct Outcome {
    lambda: f64,
    dof: u32,
    excluded: bool,
    fused: bool,
    /// Per detector: statistic, threshold, alarm.
    tests: Vec<(f64, f64, bool)>,
    /// Some components excluded (the rest used).
    partial: bool,
    /// Innovation and its covariance (tested measurements).
    inn: Option<(DVector<f64>, DMatrix<f64>)>,
    /// Whitened innovation `L⁻¹ r` (tested measurements).
    white: Option<DVector<f64>>,
    /// Why (some of) it was left out ([`crate::record::EXCLUSION_REASONS`]; 0: used as
    /// measured).
    reason: u8,
    /// Scale of the measurement σ in its test (1 for constraints).
    scale: f64,
}

const NOT_MEASURED: Outcome = Outcome {
    lambda: f64::NAN,
    dof: 0,
    excluded: false,
    fused: false,
    tests: Vec::new(),
    partial: false,
    inn: None,
    white: None,
    reason: 0,
    scale: f64::NAN,
};

/// The heading σ (rad) below which the filter may count as converged (with its GNSS channels'
/// predicted σ within `loosely_coupled.convergence` times their own): an unsettled heading
/// turns the speed into position innovations that no GNSS fault explains.
pub const CONVERGED_HEADING: f64 = 2.0 * std::f64::consts::PI / 180.0;

/// Run the loosely coupled filter over one run's streams (`isolation = false`: detectors
/// report but every measurement updates the filter).
pub fn run_loosely_coupled(
    spec: &ScenarioSpec,
    src: &Streams,
    isolation: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    if spec.loosely_coupled()?.imu.scale_factors() {
        run::<N_SCALE>(spec, src, isolation, cancel)
    } else {
        run::<N>(spec, src, isolation, cancel)
    }
}

/// [`run_loosely_coupled`] with `NS` error states (15, or 21 with scale factors).
fn run<const NS: usize>(
    spec: &ScenarioSpec,
    src: &Streams,
    isolation: bool,
    cancel: &Cancel,
) -> Result<RunRecord> {
    let l = spec.loosely_coupled()?;
    let models = src.models;
    let logged = models.logged.as_ref().ok_or_else(|| {
        Error::Invalid(
            "architecture loosely_coupled runs a strapdown INS on recorded IMU samples: run the scenario from its [source] logs"
                .into(),
        )
    })?;
    let epochs = models.epochs();
    let mut rec = RunRecord::empty(spec, models);
    rec.nav = Vec::with_capacity(epochs * NAV_COLUMNS.len());

    // IMU in body axes on the corrected time line.
    let m = mounting(l.mounting[0], l.mounting[1], l.mounting[2]);
    let imu = BodyImu::new(&logged.imu, l.mounting, l.imu_time_offset)?;
    let lever = Vector3::from(l.lever_arm);

    let mut aids = build_aids(spec)?;
    let pos_aid = aids.iter().position(|a| a.pos.is_some());
    let vel_aid = aids.iter().position(|a| a.vel.is_some());
    let Some(pos_aid) = pos_aid else {
        return Err(Error::Invalid(
            "loosely_coupled.sensors: the alignment needs GNSS positions (a gnss or a gnss_position sensor)".into(),
        ));
    };
    let n_gnss = l.sensors.len();
    // Without a velocity channel the receiver's consistency compares its displacement with
    // the INS's, and a jump of a position innovation against the INS also marks a step.
    let vel_aid_none = !aids.iter().take(n_gnss).any(|a| a.vel.is_some());
    correlation::positions_alone(l.position_correlation, vel_aid_none)?;
    let zupt_ch = l.zupt.as_ref().map(|_| n_gnss);
    let nhc_ch = l
        .nhc
        .as_ref()
        .map(|_| n_gnss + usize::from(l.zupt.is_some()));

    // Alignment.
    // Sensor `si`'s three components from offset `o` at epoch k, where given and finite.
    let measured_at = |si: usize, o: usize, k: usize| -> Option<Vector3<f64>> {
        if !models.available[si][k] {
            return None;
        }
        let z = &src.meas.z[si][k];
        let v = Vector3::new(z[o], z[o + 1], z[o + 2]);
        v.iter().all(|x| x.is_finite()).then_some(v)
    };
    let measure = |aid: &Aid, k: usize, off: Option<usize>| measured_at(aid.sensor?, off?, k);
    // A log without velocities: the alignment takes them from the positions' differences
    // (own_noise::alignment_velocities).
    let derived = match vel_aid {
        Some(_) => None,
        None => {
            let aid = &aids[pos_aid];
            let interval = aid.sensor.map_or(1.0, |si| 1.0 / spec.sensors[si].rate);
            Some(own_noise::alignment_velocities(
                &models.t,
                |k| measure(aid, k, aid.pos),
                |k| sigma_h(logged, aid, k),
                interval,
            ))
        }
    };
    // Fixes that repeat the one before them exactly: the alignment, in motion, does not take
    // its position from one (the receiver held it while the vehicle moved).
    let repeated = repeated_fixes(epochs, |k| measure(&aids[pos_aid], k, aids[pos_aid].pos));
    let aligned = align(
        &l.alignment,
        "loosely_coupled",
        &imu,
        &models.t,
        &logged.origin,
        |k| match (&derived, vel_aid) {
            (Some(d), _) => d[k].map(|(v, _)| v),
            (None, Some(va)) => measure(&aids[va], k, aids[va].vel),
            (None, None) => None,
        },
        |k| measure(&aids[pos_aid], k, aids[pos_aid].pos).filter(|_| !repeated[k]),
        |k| match (&derived, vel_aid) {
            (Some(d), _) => d[k].map_or(0.1, |(_, s)| s),
            (None, va) => va
                .and_then(|va| {
                    logged
                        .sigma
                        .get(aids[va].sensor.unwrap_or(0))
                        .and_then(|s| s.get(k))
                        .and_then(|s| s.get(aids[va].vel.unwrap_or(0)).copied())
                })
                .unwrap_or(0.1),
        },
        true,
    )?;
    let (ka, mut s) = (aligned.epoch, aligned.state);
    let q = s.q;
    // The INS point is the IMU's: move from the antenna by −C l.
    shift(&mut s, &-(q * lever));
    // A velocity from positions is known to its own σ at best.
    let sigma_velocity = derived
        .as_ref()
        .and_then(|d| d[ka])
        .map_or(l.alignment.sigma_velocity, |(_, s)| {
            l.alignment.sigma_velocity.max(s)
        });
    let mut kf = ErrorFilter::<NS>::new(
        l.alignment.sigma_position,
        sigma_velocity,
        aligned.sig_att,
        aligned.bg0,
        l.imu,
    )
    .with_mounting(&m);

    let mut outcomes = vec![NOT_MEASURED.clone(); aids.len()];
    let dims: Vec<usize> = aids.iter().map(|a| a.floor.len()).collect();
    for _ in 0..ka {
        push_empty(&mut rec, &mut outcomes, &dims, n_gnss);
    }
    let mut mech = Mechaniser::new(&imu, models.t[ka], &kf.bg);
    let fix_interval: Vec<f64> = aids
        .iter()
        .map(|a| a.sensor.map_or(1.0, |si| 1.0 / spec.sensors[si].rate))
        .collect();
    // The receiver's own consistency needs no INS: fed from the first fix.
    let mut receivers: Vec<hold::ReceiverConsistency> =
        vec![hold::ReceiverConsistency::default(); aids.len()];
    for k in 0..ka {
        receiver_epoch(
            &aids,
            n_gnss,
            models,
            src,
            k,
            &fix_interval,
            None,
            &mut receivers,
        );
    }
    let mut excluded_before = vec![false; aids.len()];
    // Per GNSS channel: the position hold (faults held to their end) and the time of its
    // last fix, against its nominal interval (a longer gap forgets the jump reference).
    let mut holds: Vec<hold::PositionHold> = vec![hold::PositionHold::default(); aids.len()];
    // The receiver's own horizontal velocity at epoch k (east, north; m/s), where it gives
    // one: its fixes' jumps are read against it (`diverge::Jumps::push_with`).
    let vel_of: Vec<(usize, usize)> = (aids.iter().take(n_gnss))
        .filter_map(|a| Some((a.sensor?, a.vel?)))
        .collect();
    let own_vel = |k: usize| {
        (vel_of.iter())
            .find_map(|&(si, o)| measured_at(si, o, k))
            .map(|v| [v.x, v.y])
    };
    // The INS watched per channel, from its first fix (before the alignment too).
    let mut watch: Vec<diverge::InsWatch> = aids
        .iter()
        .zip(&fix_interval)
        .map(|(aid, &dt)| {
            let fix =
                |k: usize| measure(aid, k, aid.pos).map(|p| (models.t[k], [p.x, p.y], own_vel(k)));
            let first = (0..epochs).find_map(fix).map(|f| f.0);
            diverge::InsWatch::new(first, dt, (0..ka).filter_map(fix))
        })
        .collect();
    let mut last_fix_t: Vec<Option<f64>> = vec![None; aids.len()];
    // Time-correlated position errors: each fix's position variance in the update multiplied by
    // what it is worth (given τ, or "auto": its white and correlated parts read from the log).
    let models_of = |a: usize| {
        let (aid, sh) = (&aids[a], |k| sigma_h(logged, &aids[a], k));
        let (t, pos) = (&models.t, |k| measure(aid, k, aid.pos));
        let dt = fix_interval[a];
        aid.pos
            .map(|_| correlation::from_log(t, pos, own_vel, sh, &logged.origin, dt))
    };
    let pc = l.position_correlation;
    let (weight, errors) = correlation::weights(pc, &fix_interval, pos_aid, models_of);
    (rec.position_errors, rec.position_wander) = (errors.used, errors.unused);
    let mut scales: Vec<noise_scale::NoiseScale> = aids
        .iter()
        .map(|_| noise_scale::NoiseScale::new(l.noise_scale, 1.0, 10.0))
        .collect();
    // A receiver of positions alone: its own noise against the σ it records, from the fixes
    // before the alignment on (with velocities, those hold the INS to the receiver).
    let mut own: Vec<Option<own_noise::OwnNoise>> = (0..aids.len())
        .map(|a| {
            let aid = &aids[a];
            (vel_aid_none && a < n_gnss && aid.pos.is_some()).then(|| {
                let mut o = own_noise::OwnNoise::default();
                for k in 0..ka {
                    if let Some(p) = measure(aid, k, aid.pos) {
                        let (t, sig) = (models.t[k], sigma_h(logged, aid, k));
                        o.push(t, [p.x, p.y], sig, fix_interval[a], false);
                    }
                }
                o
            })
        })
        .collect();
    let any_own = own.iter().any(Option::is_some);

    // Velocity components left out for the receiver's own inconsistency.
    let mut blame = blame::VelocityBlame::default();
    // How far the GNSS updates moved the INS lately (one history: it is the filter's).
    let mut pull = pull::PullHistory::default();
    let (mut fix_rest, mut resting) = (rest::FixRest::default(), false);
    // Positions alone: copies of the filter carried without GNSS, witnesses of a hold's cause.
    let mut shadows = shadow::Shadows::<NS>::default();
    let (use_shadows, mut unheld) = (vel_aid_none && isolation, false);
    // The INS antenna in the log's east, north, up frame (m).
    let antenna_enu = |s: &NavState| {
        let a = antenna(s, &lever);
        logged.origin.to_enu(&Nominal {
            lat: a.lat,
            lon: a.lon,
            h: a.h,
        })
    };
    for k in ka..epochs {
        if k % 256 == 0 {
            cancel.check()?;
        }
        let tk = models.t[k];
        let at = |e: Error| crate::run::at_time(k, tk, e);
        if tk > imu.end() {
            // The IMU log has ended: no navigation.
            push_empty(&mut rec, &mut outcomes, &dims, n_gnss);
            continue;
        }
        mech.advance(&imu, &mut s, &mut kf, tk);
        let (i, w_last) = (mech.i, mech.w_last);
        if any_own {
            let prior = antenna_enu(&s);
            own.iter_mut()
                .flatten()
                .for_each(|o| o.mechanised([prior.x, prior.y]));
        }
        outcomes.iter_mut().for_each(|o| *o = NOT_MEASURED.clone());
        // Constraints first, then GNSS; on positions alone a rest starts where the fixes stand.
        let ap = &aids[pos_aid];
        if let (true, Some(p)) = (vel_aid_none, measure(ap, k, ap.pos)) {
            fix_rest.push(tk, p, sigma_h(logged, ap, k), fix_interval[pos_aid]);
        }
        let moving = !resting && fix_rest.moving(tk, fix_interval[pos_aid], s.v.xy().norm());
        let mut at_rest = false;
        if let (Some(ch), Some(c)) = (zupt_ch, l.zupt.as_ref()) {
            if !moving && still(&imu.t, &imu.acc, &imu.gyro, &kf.bg, i, tk, c) {
                at_rest = true;
                let meas = zupt_meas::<NS>(&s, c);
                outcomes[ch] = apply(&mut kf, &mut s, &mut aids[ch], &meas, true).map_err(at)?;
            }
        }
        resting = at_rest;
        if let (Some(ch), Some(c)) = (nhc_ch, l.nhc.as_ref()) {
            if nhc_applies(&s, &w_last, at_rest, c) {
                let meas = nhc_meas::<NS>(&s, c);
                outcomes[ch] = apply(&mut kf, &mut s, &mut aids[ch], &meas, true).map_err(at)?;
            }
        }
        if use_shadows {
            shadows.advance(&imu, tk, at_rest, l.zupt.as_ref(), l.nhc.as_ref());
        }
        // GNSS: every channel tested on the pre-update state (its raw fix: the detectors'
        // records show what the receiver gave); with `witness`, a channel's alarm excludes it
        // only if another GNSS channel of the epoch passes.
        let ant_enu = antenna_enu(&s);
        let mut tested: Vec<(usize, Meas, Outcome)> = Vec::new();
        let mut stale_epoch = false;
        // A receiver without velocities: its fixes' displacement is compared with the INS's
        // (the antenna's velocity, east, north, up) instead.
        let ins_vel = vel_aid_none.then(|| enu(&(s.v + s.q * w_last.cross(&lever))));
        let mut recv = receiver_epoch(
            &aids,
            n_gnss,
            models,
            src,
            k,
            &fix_interval,
            ins_vel,
            &mut receivers,
        );
        // At rest (or nearly) the receiver's consistency is not measured, and the INS, held
        // by the constraints, is at its best: a jump against it marks a step.
        let slow = s.v.xy().norm() < hold::MOVING;
        for (a, aid) in aids.iter_mut().enumerate().take(n_gnss) {
            let Some(si) = aid.sensor else { continue };
            if !models.available[si][k] {
                continue;
            }
            let z = &src.meas.z[si][k];
            if z.iter().any(|x| !x.is_finite()) {
                continue;
            }
            if let Some(off) = aid.pos {
                if last_fix_t[a].is_some_and(|t0| tk - t0 > 2.5 * fix_interval[a]) {
                    holds[a].gap();
                }
                last_fix_t[a] = Some(tk);
                let fix = Vector3::new(z[off], z[off + 1], z[off + 2]);
                stale_epoch |= holds[a].stale(&fix, &ant_enu);
            }
            if let (Some(o), Some(off)) = (own[a].as_mut(), aid.pos) {
                let sig = sigma_h(logged, aid, k);
                o.push(tk, [z[off], z[off + 1]], sig, fix_interval[a], true);
                scales[a].set_own(o.ratio().unwrap_or(1.0));
            }
            let sig = logged.sigma.get(si).and_then(|v| v.get(k));
            // Tested with the σ scaled by the channel's noise scale; updated with it as given.
            let mut meas = gnss_measurement::<NS>(&s, aid, z, sig, &logged.origin, &lever, &w_last);
            let q = logged.quality.get(k).copied().unwrap_or(0);
            let c = scales[a].scale_for(q);
            meas.r *= c * c;
            let mut o = test(&kf, aid, &meas, isolation).map_err(at)?;
            o.scale = c;
            scales[a].observe((q, tk), o.inn.as_ref(), &meas.r, c);
            tested.push((a, meas, o));
        }
        // Convergence: every tested GNSS channel's predicted σ within `convergence` times its
        // measurement σ. Before it, only gross innovations exclude.
        if rec.converged_at.is_none() && !tested.is_empty() {
            let heading_settled = kf.p[(PHI + 2, PHI + 2)].max(0.0).sqrt() <= CONVERGED_HEADING;
            // A channel of positions alone has its own noise measured first: the σ it records
            // may be optimistic.
            let own_known = tested
                .iter()
                .all(|(a, _, _)| own[*a].as_ref().is_none_or(|o| o.ratio().is_some()));
            let settled = l.convergence == 0.0
                || heading_settled
                    && own_known
                    && tested.iter().all(|(_, meas, o)| {
                        o.inn.as_ref().is_some_and(|(_, sv)| {
                            let m = meas.r.nrows() as f64;
                            let r = meas.r.diagonal().sum() / m;
                            let hph = (sv.diagonal().sum() - meas.r.diagonal().sum()) / m;
                            hph.max(0.0) <= l.convergence * l.convergence * r
                        })
                    });
            if settled {
                rec.converged_at = Some(tk);
            }
        }
        let converged = rec.converged_at.is_some();
        let gross_of = |aid: &Aid, o: &Outcome| {
            aid.decision
                .and_then(|j| o.tests.get(j))
                .is_some_and(|&(st, th, _)| st >= 16.0 * th)
        };
        // A witness is another GNSS channel of the epoch that passes; with one channel (a log
        // of positions only, or one `gnss` sensor) there is none to ask, and the alarm acts.
        let witnessed =
            !l.witness || tested.len() < 2 || tested.iter().any(|(_, _, o)| !o.excluded);
        // One receiver is one source: where its displacement contradicts its velocity and the
        // INS sides with the displacement, the velocity is left out (and what its error put
        // into the consistency's sequential tests forgotten), not the position held.
        let mut blamed = [false; 3];
        if isolation && stale_epoch {
            blame.reset();
        } else if isolation {
            let pos_ch = (0..n_gnss).find(|&a| recv[a].is_some_and(|c| !c.ins_referenced));
            let inn = |o: &Outcome, off: usize| o.inn.as_ref().map(|(r, sv)| three(r, sv, off));
            let vel_inn = tested.iter().find_map(|(a, _, o)| inn(o, aids[*a].vel?));
            let pos_inn = pos_ch.and_then(|pa| {
                tested
                    .iter()
                    .find(|(a, _, _)| *a == pa)
                    .and_then(|(a, _, o)| inn(o, aids[*a].pos?))
            });
            if let (Some(pa), Some((dv, s_dv)), Some((dp, s_dp))) = (pos_ch, vel_inn, pos_inn) {
                if let Some(c) = recv[pa].as_mut() {
                    let wp2 = dp.component_mul(&dp).component_div(&s_dp);
                    blamed = blame.step(c, &dv, &s_dv, &wp2, fix_interval[pa]);
                    for j in (0..3).filter(|&j| blamed[j]) {
                        receivers[pa].forget(j);
                        holds[pa].release_drift(j);
                        c.e[j] = 0.0;
                        c.ramp[j] = false;
                        c.onset[j] = None;
                    }
                }
            }
        }
        let had_gnss = !tested.is_empty();
        // Position variance (east, north, up) before the GNSS updates: what they take off it.
        let pos_var = |kf: &ErrorFilter<NS>| {
            Vector3::new(kf.p[(R + 1, R + 1)], kf.p[(R, R)], kf.p[(R + 2, R + 2)])
        };
        let p_before = pos_var(&kf);
        for (a, meas, mut o) in tested {
            let alarm = o.excluded;
            let gross = gross_of(&aids[a], &o);
            o.excluded &= witnessed && (converged || gross);
            let mut keep: Vec<usize> = (0..meas.res.len()).collect();
            let mut fresh_adj: Vec<(usize, f64, f64)> = Vec::new();
            let mut reason = 0u8;
            if stale_epoch && isolation {
                // The receiver repeated its last fix while the INS moved: position and
                // velocity of this epoch are its stale state.
                o.excluded = true;
                reason = hold::STALE;
            } else if let (Some(off), true) = (aids[a].pos, isolation) {
                // Position: the hold machine decides each component.
                let (r, sv) = o
                    .inn
                    .clone()
                    .unwrap_or_else(|| (meas.res.clone(), meas.r.clone()));
                let (d, sd) = three(&r, &sv, off);
                let thr1 =
                    crate::stats::chi2_threshold(aids[a].decision_pf, 1).unwrap_or(f64::INFINITY);
                let isolated: Vec<usize> = if alarm && l.isolate_components {
                    let kept = isolate(&r, &sv, aids[a].decision_pf).map_err(at)?;
                    (0..3).filter(|j| !kept.contains(&(off + j))).collect()
                } else {
                    vec![0, 1, 2]
                };
                if scales[a].float_ended(tk, d.norm()) {
                    (0..3).for_each(|j| holds[a].release_drift(j));
                }
                let p = measure(&aids[a], k, aids[a].pos).map(|p| [p.x, p.y]);
                let ins = (&s, shadow::horizontal(&kf));
                let ant = |st: &NavState| antenna_enu(st).xy();
                let fix_h = p.map(|p| (p.into(), shadow::block(&meas.r, off)));
                let side = shadows.side(watch[a].onset().filter(|_| use_shadows), ant, fix_h, ins);
                holds[a].copies_with_ins = side == Some(false);
                let uses = holds[a].decide(
                    tk,
                    &d,
                    &sd,
                    alarm && witnessed,
                    &isolated,
                    thr1,
                    recv[a].as_ref(),
                    vel_aid_none || slow,
                    converged,
                    gross,
                    l.accommodate,
                    Some(&pull),
                );
                // A held step the receiver's jump back ended: its sequential tests start anew.
                for j in (0..3).filter(|&j| holds[a].step_ended_at(j, tk)) {
                    receivers[a].forget(j);
                }
                // The INS is moved onto held fixes it runs from (or drifts from for minutes, the
                // copies siding with them), a step held past the fixes before, or a float's end.
                let held = uses[..2].iter().any(|u| !matches!(u, hold::Use::Raw));
                let step = !holds[a].ramp_held();
                let state = (converged, scales[a].resolved(tk, d.norm()));
                let on_fix = side == Some(true);
                let moved =
                    watch[a].push(tk, p, own_vel(k), [d[0], d[1]], held, (step, on_fix), state);
                // A hold a copy of the filter carried without GNSS since before its onset calls
                // the INS's error: the end of a fault it followed, or its runaway; it replaces the INS.
                let mut witness = None;
                let moved = moved.or_else(|| {
                    let onset = watch[a].onset().filter(|_| held && use_shadows)?;
                    witness = shadows.returned((tk, onset, step), ant, fix_h?, ins);
                    witness.as_ref().map(|_| [0.0; 2])
                });
                if let (Some(f), false, true) = (fix_h, held, use_shadows) {
                    shadows.observe(tk, ant, f);
                }
                unheld |= !held;
                let mut uses = match moved {
                    Some(rate) => {
                        holds[a] = hold::PositionHold::default();
                        rec.reanchored.push(tk);
                        shadows.clear();
                        // The INS becomes the witness, or is moved onto the fix; the fix then
                        // updates it.
                        match witness.take() {
                            Some(w) => (s, kf, mech) = (w.s, w.kf, w.mech),
                            None => diverge::reanchor(&mut s, &mut kf, &d, &sd, rate),
                        }
                        [hold::Use::Raw; 3]
                    }
                    None => uses,
                };
                if watch[a].vertical(tk, holds[a].up_step(), state) {
                    diverge::reanchor_up(&mut s, &mut kf, d.z, sd.z, &mut holds[a]);
                    rec.reanchored.push(tk);
                    uses[2] = hold::Use::Raw;
                }
                keep.retain(|&i| i < off || i >= off + 3);
                for (j, u) in uses.iter().enumerate() {
                    match *u {
                        hold::Use::Raw => keep.push(off + j),
                        hold::Use::Relative(b, var) => {
                            keep.push(off + j);
                            fresh_adj.push((off + j, b, var));
                            let why = match holds[a].comps[j] {
                                hold::Comp::Drift { .. } => hold::RAMP,
                                _ => hold::STEP,
                            };
                            reason = reason.max(why);
                        }
                        hold::Use::Out(why) => reason = reason.max(why),
                    }
                }
                keep.sort_unstable();
                // The other components of a channel (velocity of a `gnss` sensor) follow its
                // deciding test.
                if alarm && o.excluded && aids[a].vel.is_some() {
                    let vo = aids[a].vel.unwrap_or(0);
                    keep.retain(|&i| i < vo || i >= vo + 3);
                }
                o.excluded = keep.is_empty();
                o.partial = !o.excluded && (keep.len() < meas.res.len() || !fresh_adj.is_empty());
            } else if o.excluded && l.isolate_components && aids[a].decision_pf.is_finite() {
                // Velocity: of an alarming measurement keep what passes.
                if let Some((r, sv)) = o.inn.as_ref() {
                    keep = isolate(r, sv, aids[a].decision_pf).map_err(at)?;
                }
                if !keep.is_empty() {
                    o.excluded = false;
                    o.partial = true;
                }
                reason = hold::TEST;
            } else if o.excluded {
                reason = hold::TEST;
            }
            if let (Some(vo), true) = (aids[a].vel, blamed.iter().any(|&b| b)) {
                if !o.excluded {
                    keep.retain(|&i| !(i >= vo && i < vo + 3 && blamed[i - vo]));
                    o.excluded = keep.is_empty();
                    o.partial = !o.excluded;
                    reason = reason.max(hold::RECEIVER);
                }
            }
            if o.excluded && reason == 0 {
                reason = hold::TEST;
            }
            o.fused = !o.excluded;
            o.reason = reason;
            // The noise scale learns from fixes used as measured.
            if reason == 0 && !o.excluded && !o.partial {
                if let Some(inn) = o.inn.as_ref() {
                    scales[a].used(tk, inn, &meas.r, o.scale);
                }
            }
            if o.fused {
                // Re-linearised after the updates before it in this epoch.
                let si = aids[a].sensor.unwrap_or(0);
                let z = &src.meas.z[si][k];
                let sig = logged.sigma.get(si).and_then(|v| v.get(k));
                let mut fresh =
                    gnss_measurement::<NS>(&s, &aids[a], z, sig, &logged.origin, &lever, &w_last);
                if let Some(off) = aids[a].pos {
                    for i in off..off + 3 {
                        fresh.r[(i, i)] *= weight[a];
                    }
                }
                for &(i, b, var) in &fresh_adj {
                    fresh.res[i] -= b;
                    fresh.r[(i, i)] += var;
                }
                update(&mut kf, &mut s, &rows(&fresh, &keep)).map_err(at)?;
            }
            outcomes[a] = o;
        }
        if use_shadows && converged && std::mem::take(&mut unheld) {
            shadows.start(tk, &s, &kf, &mech);
        }
        // How far the GNSS updates moved the INS antenna this epoch, and how much position
        // variance they took off; not an epoch where the INS was moved onto the fixes (or
        // replaced by a witness): that move is no update's pull. Counted as one, the move
        // (12 m east after a burst the filter had followed) made the next burst, jumping
        // west, "the fix back where the updates had pulled the INS from", and the INS was
        // moved onto it. Forgetting the history at such a move instead lost the ramps the
        // filter follows again after it (4 of 200 drive_lc ramps on positions only worse).
        if had_gnss && rec.reanchored.last() != Some(&tk) {
            let moved = antenna_enu(&s) - ant_enu;
            let dvar = p_before - pos_var(&kf);
            pull.add(tk, &moved, &dvar);
        }
        if any_own {
            let post = antenna_enu(&s);
            own.iter_mut()
                .flatten()
                .for_each(|o| o.updated([post.x, post.y]));
        }
        // Record.
        let mut fused = 0;
        for (c, o) in outcomes.iter().enumerate() {
            fused += u32::from(o.fused);
            let sub = &mut rec.subs[c];
            sub.statistic.push(o.lambda);
            sub.dof.push(o.dof);
            sub.isolated.push(o.excluded || o.partial);
            sub.reinstated
                .push(excluded_before[c] && o.fused && !o.excluded);
            sub.fused.push(o.fused);
            match &o.white {
                Some(w) if w.len() == dims[c] => sub.whitened.extend(w.iter()),
                _ => sub.whitened.extend(std::iter::repeat_n(f64::NAN, dims[c])),
            }
            sub.reason.push(o.reason);
            if c < n_gnss {
                sub.noise_scale.push(o.scale);
            }
            for (j, d) in sub.detectors.iter_mut().enumerate() {
                let (st, th, al) = o
                    .tests
                    .get(j)
                    .copied()
                    .unwrap_or((f64::NAN, f64::NAN, false));
                d.statistic.push(st);
                d.threshold.push(th);
                d.alarm.push(al);
            }
            if o.fused || o.excluded {
                excluded_before[c] = o.excluded;
            }
        }
        rec.sources.push(fused);
        record_nav(&mut rec, &s, &kf, &lever, &logged.origin, src, k);
    }
    rec.restrict_faults_to_navigated(spec, models);
    Ok(rec)
}

/// Feed epoch `k`'s GNSS position fixes and the receiver's velocity (or, for a receiver that
/// gives none, `ins_vel`: the INS antenna velocity east, north, up, m/s) to each position
/// channel's [`hold::ReceiverConsistency`]; what each says (None without a velocity, a fix or
/// enough history).
#[allow(clippy::too_many_arguments)]
fn receiver_epoch(
    aids: &[Aid],
    n_gnss: usize,
    models: &crate::stream::Models,
    src: &Streams,
    k: usize,
    intervals: &[f64],
    ins_vel: Option<Vector3<f64>>,
    receivers: &mut [hold::ReceiverConsistency],
) -> Vec<Option<hold::Consistency>> {
    let measured = |aid: &Aid, off: Option<usize>| -> Option<Vector3<f64>> {
        let (si, o) = (aid.sensor?, off?);
        if !models.available[si][k] {
            return None;
        }
        let z = &src.meas.z[si][k];
        let v = Vector3::new(z[o], z[o + 1], z[o + 2]);
        v.iter().all(|x| x.is_finite()).then_some(v)
    };
    let own = aids.iter().take(n_gnss).find_map(|a| measured(a, a.vel));
    let vel = own.or(ins_vel);
    let mut out = vec![None; aids.len()];
    for (a, aid) in aids.iter().enumerate().take(n_gnss) {
        if let (Some(p), Some(v)) = (measured(aid, aid.pos), vel) {
            out[a] = receivers[a]
                .step(models.t[k], &p, &v, 2.5 * intervals[a], own.is_some())
                .map(|c| hold::Consistency {
                    ins_referenced: own.is_none(),
                    ..c
                });
        }
    }
    out
}

/// Test one measurement with the channel's detectors: the outcome says whether its deciding
/// detector alarms (excluded, with isolation); nothing is updated.
fn test<const NS: usize>(
    kf: &ErrorFilter<NS>,
    aid: &mut Aid,
    meas: &Meas,
    isolation: bool,
) -> Result<Outcome> {
    let inn = kf.innovation(&meas.res, &meas.h, &meas.r)?;
    let dof = meas.res.len();
    let mut alarm = false;
    let mut stats = Vec::with_capacity(aid.detectors.len());
    for (j, d) in aid.detectors.iter_mut().enumerate() {
        let dec = d.test_innovation(&inn.r, &inn.s, inn.lambda, dof)?;
        if Some(j) == aid.decision && dec.alarm {
            alarm = true;
        }
        stats.push((dec.statistic, dec.threshold, dec.alarm));
    }
    let excluded = alarm && isolation;
    Ok(Outcome {
        lambda: inn.lambda,
        dof: dof as u32,
        excluded,
        fused: !excluded,
        tests: stats,
        partial: false,
        white: Some(inn.whitened()),
        inn: Some((inn.r, inn.s)),
        reason: 0,
        scale: 1.0,
    })
}

/// Test a constraint and update with it unless excluded.
fn apply<const NS: usize>(
    kf: &mut ErrorFilter<NS>,
    s: &mut NavState,
    aid: &mut Aid,
    meas: &Meas,
    isolation: bool,
) -> Result<Outcome> {
    let o = test(kf, aid, meas, isolation)?;
    if !o.excluded {
        update(kf, s, meas)?;
    }
    Ok(o)
}

fn push_empty(rec: &mut RunRecord, outcomes: &mut [Outcome], dims: &[usize], n_gnss: usize) {
    for (c, o) in outcomes.iter_mut().enumerate() {
        *o = NOT_MEASURED.clone();
        rec.subs[c].push_untested();
        rec.subs[c]
            .whitened
            .extend(std::iter::repeat_n(f64::NAN, dims[c]));
        rec.subs[c].reason.push(0);
        if c < n_gnss {
            rec.subs[c].noise_scale.push(f64::NAN);
        }
    }
    rec.sources.push(0);
    rec.error.extend([f64::NAN; 9]);
    rec.sigma.extend([f64::NAN; 9]);
    rec.nav.extend([f64::NAN; NAV_COLUMNS.len()]);
}

fn build_aids(spec: &ScenarioSpec) -> Result<Vec<Aid>> {
    let l = spec.loosely_coupled()?;
    let mut out = Vec::new();
    let dets = |specs: &[crate::spec::DetectorSpec]| -> Result<Vec<Detector>> {
        specs
            .iter()
            .map(|d| make_detector(d.kind, d.pf, d.pm, d.variance.as_deref(), d.min_samples))
            .collect()
    };
    for a in &l.sensors {
        let si = spec.sensor_index(&a.sensor).ok_or_else(|| {
            Error::Invalid(format!("loosely_coupled: unknown sensor {:?}", a.sensor))
        })?;
        let kind = spec.sensors[si].kind;
        let (pos, vel) = match kind {
            SensorKind::Gnss => (Some(0), Some(3)),
            SensorKind::GnssPosition => (Some(0), None),
            SensorKind::GnssVelocity => (None, Some(0)),
            _ => (None, None),
        };
        out.push(Aid {
            sensor: Some(si),
            pos,
            vel,
            decision: a
                .decision
                .as_ref()
                .and_then(|n| a.detectors.iter().position(|d| &d.name == n)),
            decision_pf: a
                .decision
                .as_ref()
                .and_then(|n| a.detectors.iter().find(|d| &d.name == n))
                .map_or(f64::NAN, |d| d.pf),
            detectors: dets(&a.detectors)?,
            floor: spec.sensors[si].noise.clone(),
        });
    }
    for c in [&l.zupt, &l.nhc].into_iter().flatten() {
        out.push(Aid {
            sensor: None,
            pos: None,
            vel: None,
            decision: c
                .decision
                .as_ref()
                .and_then(|n| c.detectors.iter().position(|d| &d.name == n)),
            decision_pf: f64::NAN,
            detectors: dets(&c.detectors)?,
            floor: c.noise.clone(),
        });
    }
    Ok(out)
}
