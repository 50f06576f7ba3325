//! Raw GNSS logs (RINEX observations and broadcast ephemerides) as the `gnss_ranges` stream of a
//! tight filter on a recorded IMU: per epoch and satellite the pseudorange corrected for the
//! satellite clock (relativistic term included), the broadcast group delay and the modelled
//! ionosphere (Klobuchar, the navigation file's coefficients or none) and troposphere
//! (Saastamoinen), the Doppler range rate `−λ D` corrected for the satellite clock drift, the
//! satellite's position at transmission and its velocity (as `navfdi gnss` computes them), and
//! σ from the sensor's `noise` (grown as 1/sin el with `elevation_noise`, and as
//! `10^((cn0_reference − C/N0)/20)` with the recorded C/N0 — `S1C` beside `C1C` — when
//! `cn0_reference` is set).
//!
//! The atmosphere, the elevations (mask, weights) and the time 0 come from a single-point
//! solution of the same recorded epochs ([`crate::gnss::spp`], with its exclusion loop): a
//! position error of metres changes them by millimetres. That solution and its Doppler
//! velocity are also the fixes the filter aligns on ([`crate::stream::Logged::fixes`]). The
//! pseudorange code per system is chosen as `navfdi gnss` chooses it
//! ([`crate::gnss::signals`]); a satellite without an ephemeris or below the mask is not in
//! view. Faults are injected into these recorded observations by
//! [`super::LoggedSource::measurements`].

use super::{check_imu, logged_models, overlap, reference_enu, GnssLog, LoggedSource};
use crate::error::{Error, Result};
use crate::gnss::atmosphere::{klobuchar, saastamoinen};
use crate::gnss::broadcast::{select, Sat, Sys};
use crate::gnss::constellation::System;
use crate::gnss::doppler::doppler_velocity;
use crate::gnss::geodesy::{ecef_to_enu, ecef_to_lla, elevation_azimuth};
use crate::gnss::ranges::{RangeEpoch, RangeStream};
use crate::gnss::rinex::{NavData, ObsData};
use crate::gnss::signals::select_codes;
use crate::gnss::snapshot::FdeConfig;
use crate::gnss::spp::{frequency, solve, SppConfig, SppRun, SppState, F_L1};
use crate::gnss::C;
use crate::spec::{ScenarioSpec, SensorKind};
use crate::stream::{ImuSamples, Logged, Nominal};
use nalgebra::{DMatrix, DVector, Vector3};

/// One satellite's observables at one epoch, as the tight filter takes them.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeRow {
    /// The satellite.
    pub sat: Sat,
    /// Pseudorange (m) corrected for the satellite clock, group delay and modelled
    /// atmosphere: the geometric range to `pos` after the Sagnac rotation, plus the receiver
    /// clock bias and the range's error.
    pub rho: f64,
    /// Range rate (m/s, `−λ D` corrected for the satellite clock drift; NaN without Doppler).
    pub rate: f64,
    /// Satellite ECEF position at transmission (m).
    pub pos: Vector3<f64>,
    /// Satellite ECEF velocity (m/s).
    pub vel: Vector3<f64>,
    /// Elevation (rad).
    pub el: f64,
    /// C/N0 (dB-Hz; NaN when not recorded).
    pub cn0: f64,
}

impl LoggedSource {
    /// Prepare the tight scenario `spec` (architecture `tight` with `tight.strapdown`) from an
    /// IMU log (times in s from the first observation epoch), RINEX observations `obs` and
    /// navigation data `nav`, and an optional reference log (times on the same scale; its
    /// epochs matched to the observation epochs within 2 ms and scored at every matched
    /// epoch: the reference is no input of a filter on raw pseudoranges).
    pub fn from_rinex(
        spec: &ScenarioSpec,
        imu: ImuSamples,
        obs: &ObsData,
        nav: &NavData,
        reference: Option<&GnssLog>,
    ) -> Result<Self> {
        let (_, rs) = tight_ranges_sensor(spec, &imu, reference)?;
        let Some(first) = obs.epochs.first() else {
            return Err(Error::Invalid("RINEX observations: no epochs".into()));
        };
        let systems: Vec<Sys> = rs
            .systems
            .iter()
            .map(|s| match s {
                System::Gps => Sys::Gps,
                System::Galileo => Sys::Galileo,
            })
            .collect();
        let codes = select_codes(obs, &systems, &[])?;
        // The single-point solution: time 0, atmosphere, elevations and the alignment fixes.
        let fde = FdeConfig::new(1e-3, None)?;
        let mut cfg = SppConfig::new(fde.clone());
        cfg.systems = systems.clone();
        cfg.codes = codes.clone();
        cfg.mask = rs.elevation_mask;
        let mut run = SppRun::default();
        solve(
            obs,
            nav,
            &cfg,
            &[],
            0..obs.epochs.len(),
            &mut SppState::default(),
            &mut run,
            &crate::cancel::Cancel::default(),
        )?;
        let vel = doppler_velocity(obs, nav, &cfg, &run, (0.05, 0.05), &fde)?;
        let Some(r0) = run.epochs.iter().find_map(|e| e.position) else {
            return Err(Error::Invalid(
                "RINEX observations: no epoch has a single-point solution (too few satellites with ephemerides?)".into(),
            ));
        };
        let (lat0, lon0, h0) = ecef_to_lla(&r0);
        let origin = Nominal {
            lat: lat0,
            lon: lon0,
            h: h0,
        };
        let klob = nav.klobuchar.unwrap_or([0.0; 8]);
        let epochs = obs.epochs.len();
        let times: Vec<f64> = obs
            .epochs
            .iter()
            .map(|e| e.time.diff(&first.time))
            .collect();
        overlap(&imu, &times, "RINEX observations")?;
        let mut fixes = vec![[f64::NAN; 6]; epochs];
        let mut nominal = vec![origin; epochs];
        let mut rows: Vec<Vec<RangeRow>> = Vec::with_capacity(epochs);
        let mut last = r0;
        for (k, ep) in obs.epochs.iter().enumerate() {
            if k > 0 && times[k] <= times[k - 1] {
                return Err(Error::Invalid(format!(
                    "RINEX observations: epoch {k} is not after the one before it"
                )));
            }
            if let Some(p) = run.epochs[k].position {
                last = p;
                let (lat, lon, h) = ecef_to_lla(&p);
                let here = Nominal { lat, lon, h };
                nominal[k] = here;
                let e = origin.to_enu(&here);
                let v = vel[k]
                    .velocity
                    .map(|(v, _)| ecef_to_enu(lat, lon) * v)
                    .unwrap_or(Vector3::repeat(f64::NAN));
                fixes[k] = [e.x, e.y, e.z, v.x, v.y, v.z];
            }
            let (lat, lon, h) = ecef_to_lla(&last);
            let mut out = Vec::new();
            for &(sys, ref code) in &codes {
                let (Some(ci), Some(f)) = (obs.code_index(code), frequency(sys, code)) else {
                    continue;
                };
                let di = obs.code_index(&format!("D{}", &code[1..]));
                let si_code = obs.code_index(&format!("S{}", &code[1..]));
                let scale = (F_L1 / f).powi(2);
                let lambda = C / f;
                for o in ep.obs.iter().filter(|o| o.sat.sys == sys && o.code == ci) {
                    // Blank (zero) is no observation; a gross value is one, left to the FDE
                    // (the satellite placed at a nominal travel time), as in `navfdi gnss`.
                    if o.value == 0.0 || !o.value.is_finite() {
                        continue;
                    }
                    let rho_tx = if (1e7..=1e8).contains(&o.value) {
                        o.value
                    } else {
                        crate::gnss::spp::NOMINAL_RANGE
                    };
                    let Some(eph) = nav
                        .ephemerides
                        .get(&o.sat)
                        .and_then(|v| select(v, &ep.time).ok())
                    else {
                        continue;
                    };
                    let ttx = eph.transmission_time(&ep.time, rho_tx);
                    let st = eph.state(&ttx);
                    let rn = st.pos.norm();
                    if !(rn > 1e7 && rn < 6e7 && st.clock.is_finite() && st.clock.abs() < 1.0) {
                        continue;
                    }
                    let (vel, drift) = eph.rates(&ttx);
                    let (el, az) = elevation_azimuth(&last, lat, lon, &st.pos);
                    if !(el >= rs.elevation_mask) {
                        continue;
                    }
                    let iono = klobuchar(&klob, ep.time.sow, lat, lon, h, az, el) * scale;
                    let tropo = saastamoinen(lat, h, el, 0.7);
                    let doppler = di.and_then(|d| {
                        ep.obs
                            .iter()
                            .find(|x| x.sat == o.sat && x.code == d)
                            .map(|x| x.value)
                            .filter(|v| v.is_finite() && *v != 0.0)
                    });
                    let cn0 = si_code
                        .and_then(|c| {
                            ep.obs
                                .iter()
                                .find(|x| x.sat == o.sat && x.code == c)
                                .map(|x| x.value)
                        })
                        .filter(|v| v.is_finite() && *v > 0.0)
                        .unwrap_or(f64::NAN);
                    out.push(RangeRow {
                        sat: o.sat,
                        rho: o.value + C * st.clock - C * eph.tgd - iono - tropo,
                        rate: doppler.map_or(f64::NAN, |d| -lambda * d + C * drift),
                        pos: st.pos,
                        vel,
                        el,
                        cn0,
                    });
                }
            }
            out.sort_by_key(|r| r.sat);
            rows.push(out);
        }
        Self::from_range_rows(spec, imu, times, rows, fixes, origin, nominal, reference)
    }

    /// Prepare the tight scenario `spec` from an IMU log and the satellites' observables per
    /// epoch (`rows`, at `times` s on the IMU's scale, strictly increasing): the part of
    /// [`LoggedSource::from_rinex`] after reading, shared with simulated range logs
    /// ([`crate::sim::range_logs`]). `fixes`: per epoch the snapshot fix east, north, up (m
    /// from `origin`) and velocity (m/s), NaN where there is none (the alignment uses them);
    /// `nominal`: per epoch the point the rows were formed about; `reference` on the same
    /// time scale, matched within 2 ms and scored at every matched epoch.
    #[allow(clippy::too_many_arguments)]
    pub fn from_range_rows(
        spec: &ScenarioSpec,
        imu: ImuSamples,
        times: Vec<f64>,
        mut rows: Vec<Vec<RangeRow>>,
        fixes: Vec<[f64; 6]>,
        origin: Nominal,
        nominal: Vec<Nominal>,
        reference: Option<&GnssLog>,
    ) -> Result<Self> {
        let (si, rs) = tight_ranges_sensor(spec, &imu, reference)?;
        let sen = &spec.sensors[si];
        let epochs = times.len();
        if rows.len() != epochs || fixes.len() != epochs || nominal.len() != epochs {
            return Err(Error::Invalid(format!(
                "range logs: {epochs} epochs, but {} rows, {} fixes and {} nominal points",
                rows.len(),
                fixes.len(),
                nominal.len()
            )));
        }
        if let Some(k) = (1..epochs).find(|&k| !(times[k] > times[k - 1])) {
            return Err(Error::Invalid(format!(
                "range logs: epoch {k} is not after the one before it"
            )));
        }
        overlap(&imu, &times, "range logs")?;
        for r in &mut rows {
            r.sort_by_key(|r| r.sat);
        }
        // Satellite names: every satellite in view at some epoch.
        let mut sats: Vec<Sat> = rows.iter().flatten().map(|r| r.sat).collect();
        sats.sort();
        sats.dedup();
        let names: Vec<String> = sats.iter().map(Sat::name).collect();
        for (i, f) in spec.faults.iter().enumerate() {
            let mut asked: Vec<&String> = f.satellite.iter().collect();
            if let Some(d) = &f.draw {
                asked.extend(d.satellites.iter());
            }
            for n in asked {
                if !names.contains(n) {
                    return Err(Error::Invalid(format!(
                        "faults[{i}].satellite: {n:?} is never in view in the log (above the mask, with an ephemeris); in view: {}",
                        names.join(", ")
                    )));
                }
            }
        }
        let ns = spec.sensors.len();
        let mut available = vec![vec![false; epochs]; ns];
        let mut z = vec![vec![DVector::zeros(0); epochs]; ns];
        let mut range_epochs = Vec::with_capacity(epochs);
        let elevation_noise = rs.elevation_noise;
        let (sig_rho, sig_rate) = (
            sen.noise.first().copied().unwrap_or(f64::NAN),
            sen.noise.get(1).copied().unwrap_or(f64::NAN),
        );
        let grid = super::sample_epochs(&times, sen.rate, &format!("sensors[{si}]"))?;
        for (k, ep_rows) in rows.iter().enumerate() {
            let out = sen
                .outages
                .iter()
                .any(|w| times[k] >= w[0] && times[k] < w[1]);
            let on = !out && grid[k] && !ep_rows.is_empty();
            let m = ep_rows.len();
            let grow = |r: &RangeRow| {
                let el = if elevation_noise {
                    1.0 / r.el.sin().max(0.05)
                } else {
                    1.0
                };
                let cn0 = match rs.cn0_reference {
                    Some(c) if r.cn0.is_finite() => 10f64.powf((c - r.cn0) / 20.0),
                    _ => 1.0,
                };
                el * cn0
            };
            let rx = Vector3::repeat(f64::NAN);
            range_epochs.push(RangeEpoch {
                sats: ep_rows
                    .iter()
                    .map(|r| sats.binary_search(&r.sat).unwrap_or(0))
                    .collect(),
                sat_pos: ep_rows.iter().map(|r| r.pos).collect(),
                sat_vel: ep_rows.iter().map(|r| r.vel).collect(),
                los: Vec::new(),
                range: Vec::new(),
                rate: Vec::new(),
                elevation: ep_rows.iter().map(|r| r.el).collect(),
                sigma: ep_rows.iter().map(|r| sig_rho * grow(r)).collect(),
                sigma_rate: ep_rows.iter().map(|r| sig_rate * grow(r)).collect(),
                h: DMatrix::zeros(0, 0),
                fault: Vec::new(),
                rx,
            });
            available[si][k] = on;
            z[si][k] = if on {
                DVector::from_iterator(
                    2 * m,
                    ep_rows
                        .iter()
                        .map(|r| r.rho)
                        .chain(ep_rows.iter().map(|r| r.rate)),
                )
            } else {
                DVector::zeros(0)
            };
        }
        let enu = reference.map_or_else(
            || vec![[f64::NAN; 6]; epochs],
            |r| reference_enu(r, &times, &origin, 2e-3, |_| false),
        );
        let logged = Logged {
            imu,
            origin,
            sigma: Vec::new(),
            fixes,
            quality: Vec::new(),
        };
        let ranges = RangeStream {
            sensor: si,
            names,
            epochs: range_epochs,
        };
        let models = logged_models(times, nominal, available, Some(ranges), logged);
        Ok(LoggedSource::assemble(models, z, enu))
    }
}

/// Check the tight scenario `spec` (strapdown, gnss_ranges sensor only), the IMU log and the
/// reference; the ranges sensor's index and its satellites' settings.
fn tight_ranges_sensor<'a>(
    spec: &'a ScenarioSpec,
    imu: &ImuSamples,
    reference: Option<&GnssLog>,
) -> Result<(usize, &'a crate::spec::RangesSpec)> {
    spec.validate()?;
    check_imu(imu)?;
    let t = spec.tight()?;
    if t.strapdown.is_none() {
        return Err(Error::Invalid(
                "tight.strapdown: missing; a tight scenario on recorded IMU and RINEX logs needs its strapdown INS".into(),
            ));
    }
    if let Some(r) = reference {
        r.check("reference log")?;
    }
    if spec
        .sensors
        .iter()
        .any(|s| s.kind != SensorKind::GnssRanges)
    {
        return Err(Error::Invalid(
            "sensors: a tight scenario on RINEX logs takes its gnss_ranges sensor only".into(),
        ));
    }
    let si = spec.sensor_index(&t.sensor).unwrap_or(0);
    let rs = spec.sensors[si]
        .ranges
        .as_ref()
        .ok_or_else(|| Error::Invalid(format!("sensors[{si}].ranges: missing")))?;
    Ok((si, rs))
}
