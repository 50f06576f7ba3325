//! Helpers shared by the architectures: detectors built from their specs, the sensor of each
//! detection channel, which measurement matrices change along the run, and the record of a
//! tight filter's satellite FDE per epoch.

use crate::detect::{Detector, ImprovedSprt, JointChi2Sprt, ResidualChi2, SprtVariance};
use crate::error::Result;
use crate::gnss::innovation::SatFde;
use crate::record::{RunRecord, SatRecord, SAT_NO_MEASUREMENT};
use crate::spec::{DetectorKind, ScenarioSpec, SensorKind};

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

/// Sensor index of each detection channel.
pub fn channel_sensors(spec: &ScenarioSpec) -> Vec<usize> {
    spec.channels()
        .iter()
        .map(|ch| spec.sensor_index(ch.sensor).unwrap_or(0))
        .collect()
}

/// Whether each channel's measurement matrix changes along the trajectory (position sensors).
pub fn varying_h(spec: &ScenarioSpec, sensor_idx: &[usize]) -> Vec<bool> {
    sensor_idx
        .iter()
        .map(|&si| {
            !matches!(
                spec.sensors[si].kind,
                SensorKind::Cns
                    | SensorKind::GnssVelocity
                    | SensorKind::Baro
                    | SensorKind::RadioAltimeter
                    | SensorKind::GnssRanges
            )
        })
        .collect()
}

/// FDE status code of an epoch whose global test alarms with placement `none`.
const ALARM: u8 = 4;

/// Record a tight filter's epoch `k` on its one channel: the first global test of `out`, the
/// w of each tested satellite and the excluded ones (`global[j]`: the satellite index of
/// local satellite j, `s_count` satellites in the record), the status (`alarm` for an alarm
/// of placement `none`).
pub fn record_sat_fde(
    rec: &mut RunRecord,
    sat: &mut SatRecord,
    k: usize,
    out: &SatFde,
    global: impl Fn(usize) -> usize,
    none_placement: bool,
) {
    let s_count = sat.names.len();
    let (stat, thr, dof) = out.first;
    let sub = &mut rec.subs[0];
    let det = &mut sub.detectors[0];
    det.statistic.push(stat);
    det.threshold.push(thr);
    det.alarm.push(stat >= thr);
    sub.statistic.push(stat);
    sub.dof.push(dof as u32);
    sub.isolated.push(!out.excluded.is_empty());
    sub.reinstated.push(false);
    for (j, w) in out.w.iter().enumerate() {
        sat.w[k * s_count + global(j)] = *w;
    }
    for &j in &out.excluded {
        sat.excluded[k * s_count + global(j)] = true;
    }
    sat.status.push(if none_placement && stat >= thr {
        ALARM
    } else {
        out.status.code()
    });
}

/// Record a tight filter's epoch without a test (no measurement, or no navigation): NaN
/// statistics, nothing fused, no satellite used.
pub fn record_untested(rec: &mut RunRecord, sat: &mut SatRecord) {
    rec.subs[0].push_untested();
    sat.status.push(SAT_NO_MEASUREMENT);
    sat.used.push(0);
    rec.sources.push(0);
}

/// Snapshot ARAIM HPL and VPL (m) of one epoch's pseudoranges, beside a filter's protection
/// levels: unit lines of sight `los_ecef` (receiver to satellite), system letters `systems`,
/// code σ `sigma` (m, as `C_int = C_acc`), no nominal bias, the filter's satellite prior
/// `p_sat` and allocation `alloc`, no constellation fault (the filter's bank does not monitor
/// one either), one clock per system, at latitude `lat` and longitude `lon` (rad). NaN when
/// the satellites give no solution with redundancy.
pub fn snapshot_araim(
    los_ecef: &[nalgebra::Vector3<f64>],
    systems: &[char],
    sigma: &[f64],
    lat: f64,
    lon: f64,
    p_sat: f64,
    alloc: &crate::integrity::araim::Allocation,
) -> [f64; 2] {
    let c = crate::gnss::geodesy::ecef_to_enu(lat, lon);
    let mut letters: Vec<char> = Vec::new();
    let constellation: Vec<usize> = systems
        .iter()
        .map(|&sys| match letters.iter().position(|&x| x == sys) {
            Some(i) => i,
            None => {
                letters.push(sys);
                letters.len() - 1
            }
        })
        .collect();
    let rows: Vec<[f64; 3]> = los_ecef
        .iter()
        .map(|l| {
            let e = c * l;
            [-e.x, -e.y, -e.z]
        })
        .collect();
    let n = rows.len();
    if n <= 3 + letters.len() || sigma.len() != n || constellation.len() != n {
        return [f64::NAN; 2];
    }
    let c_int: Vec<f64> = sigma.iter().map(|s| s * s).collect();
    let ism = crate::integrity::araim::Ism {
        c_acc: c_int.clone(),
        c_int,
        b_nom: vec![0.0; n],
        p_sat: vec![p_sat; n],
        p_const: vec![0.0; letters.len()],
    };
    match crate::integrity::araim::araim(&rows, &constellation, &ism, alloc) {
        Ok(a) if a.vpl.is_finite() && a.hpl.is_finite() => [a.hpl, a.vpl],
        _ => [f64::NAN; 2],
    }
}
