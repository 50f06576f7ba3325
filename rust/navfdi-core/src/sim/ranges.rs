//! The simulated `gnss_ranges` sensor: its constellation evaluated along the truth trajectory.
//!
//! Truth: `ρ_i = |r_s,i − r| + b + ε_i (+ fault)`, `ρ̇_i = u_iᵀ(v_s,i − v) + d + ε̇_i (+ fault)`,
//! with `u_i` the unit line of sight from the receiver to satellite i (ECEF), `b`, `d` the
//! receiver clock bias (m) and drift (m/s). Satellite positions are evaluated at the epoch
//! time in the Earth-fixed frame (no signal travel time or Sagnac term: the simulation and
//! the solvers use the same model).

use super::trajectory::TruthEpoch;
use crate::gnss::geodesy::{ecef_to_enu, elevation_azimuth, lla_to_ecef};
use crate::gnss::ranges::{RangeEpoch, RangeStream, CLOCK_BIAS, CLOCK_DRIFT};
use crate::ins::{earth, POS, VEL};
use crate::spec::{FaultSpec, RangesSpec};
use nalgebra::DMatrix;

/// Evaluate the constellation along `truth`; `noise = [σ_ρ, σ_ρ̇]`; `n` filter states;
/// `faults` of this sensor (each naming its satellite); `t` epoch times (s).
pub fn ranges_along(
    sensor: usize,
    spec: &RangesSpec,
    noise: &[f64],
    truth: &[TruthEpoch],
    t: &[f64],
    n: usize,
    faults: &[&FaultSpec],
) -> RangeStream {
    let orbits = spec.orbits();
    let names: Vec<String> = orbits.iter().map(|o| o.name.clone()).collect();
    let fault_sat: Vec<Option<usize>> = faults
        .iter()
        .map(|f| {
            f.satellite
                .as_ref()
                .and_then(|s| names.iter().position(|x| x == s))
        })
        .collect();
    let mut epochs = Vec::with_capacity(truth.len());
    for (k, e) in truth.iter().enumerate() {
        let rx = lla_to_ecef(e.lat, e.lon, e.h);
        let c = ecef_to_enu(e.lat, e.lon);
        let v_rx = c.transpose() * e.v;
        let rm = earth::r_meridian(e.lat) + e.h;
        let rn = earth::r_normal(e.lat) + e.h;
        let mut ep = RangeEpoch {
            sats: Vec::new(),
            sat_pos: Vec::new(),
            sat_vel: Vec::new(),
            los: Vec::new(),
            range: Vec::new(),
            rate: Vec::new(),
            elevation: Vec::new(),
            sigma: Vec::new(),
            sigma_rate: Vec::new(),
            h: DMatrix::zeros(0, n),
            fault: Vec::new(),
            rx,
        };
        for (i, o) in orbits.iter().enumerate() {
            let (rs, vs) = o.ecef(spec.epoch + t[k]);
            let (el, _) = elevation_azimuth(&rx, e.lat, e.lon, &rs);
            if el < spec.elevation_mask {
                continue;
            }
            let d = rs - rx;
            let range = d.norm();
            let u = d / range;
            let scale = if spec.elevation_noise {
                1.0 / el.sin().max(0.05)
            } else {
                1.0
            };
            ep.sats.push(i);
            ep.sat_pos.push(rs);
            ep.sat_vel.push(vs);
            ep.los.push(u);
            ep.range.push(range);
            ep.rate.push(u.dot(&(vs - v_rx)));
            ep.elevation.push(el);
            ep.sigma.push(noise[0] * scale);
            ep.sigma_rate.push(noise[1] * scale);
        }
        let m = ep.sats.len();
        let mut h = DMatrix::zeros(2 * m, n);
        let mut fault = vec![0.0; 2 * m];
        for (j, u) in ep.los.iter().enumerate() {
            let ue = c * u;
            h[(j, POS)] = ue.y * rm;
            h[(j, POS + 1)] = ue.x * rn * e.lat.cos();
            h[(j, POS + 2)] = ue.z;
            h[(j, CLOCK_BIAS)] = 1.0;
            for a in 0..3 {
                h[(m + j, VEL + a)] = ue[a];
            }
            h[(m + j, CLOCK_DRIFT)] = 1.0;
            for (f, fs) in faults.iter().zip(&fault_sat) {
                if *fs == Some(ep.sats[j]) {
                    let v = f.value(t[k]);
                    for &comp in &f.components {
                        fault[comp * m + j] += v;
                    }
                }
            }
        }
        ep.h = h;
        ep.fault = fault;
        epochs.push(ep);
    }
    RangeStream {
        sensor,
        names,
        epochs,
    }
}
