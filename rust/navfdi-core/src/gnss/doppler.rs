//! Receiver velocity and clock drift from Doppler: after the position of an epoch is solved,
//! the Doppler observations (`D1C` beside `C1C`, `D1X` beside `C1X`, `D2I` beside `C2I`) of the
//! satellites the position used give pseudorange rates `ρ̇ᵢ = −λᵢ Dᵢ`; with the satellites'
//! velocities and clock drifts from the broadcast ephemerides (central differences over
//! ±0.5 s, `Ephemeris::rates`), the linear model `ρ̇ᵢ + c δṫ_sᵢ = uᵢᵀ(v_sᵢ − v) + d` ([`super::snapshot::RateModel`])
//! gives the ECEF velocity v and the clock drift d (m/s), by the same weighted least squares,
//! global test and w-test exclusion as the positions, with the elevation weighting
//! `σ² = a² + b²/sin² el` of the rate noise (a, b). The Sagnac rate term (below 1 mm/s) is
//! left out.

use super::broadcast::{select, Sys};
use super::rinex::{NavData, ObsData};
use super::snapshot::{fde, FdeConfig, FdeOutcome, ObsCov, RateModel};
use super::spp::{frequency, SatStatus, SppConfig, SppRun};
use super::C;
use crate::error::Result;
use nalgebra::Vector3;

/// The Doppler solution of one epoch.
#[derive(Debug, Clone, PartialEq)]
pub struct EpochVelocity {
    /// ECEF velocity (m/s) and receiver clock drift (m/s), None without a solution.
    pub velocity: Option<(Vector3<f64>, f64)>,
    /// The rate test and exclusion.
    pub fde: FdeOutcome,
    /// Satellites with a Doppler observation tested.
    pub sats: Vec<super::broadcast::Sat>,
}

/// The Doppler code beside pseudorange code `code` (`C1C` → `D1C`).
fn doppler_code(code: &str) -> String {
    format!("D{}", &code[1..])
}

/// Doppler velocity of every solved epoch of `run` (the positions `run` solved with `cfg`),
/// rate noise `(a, b)` (m/s).
pub fn doppler_velocity(
    obs: &ObsData,
    nav: &NavData,
    cfg: &SppConfig,
    run: &SppRun,
    noise: (f64, f64),
    fde_cfg: &FdeConfig,
) -> Result<Vec<EpochVelocity>> {
    let codes: Vec<(Sys, Option<u16>, f64)> = cfg
        .codes
        .iter()
        .filter(|(s, _)| cfg.systems.contains(s))
        .map(|(s, c)| {
            let lambda = frequency(*s, c).map_or(f64::NAN, |f| C / f);
            (*s, obs.code_index(&doppler_code(c)), lambda)
        })
        .collect();
    let mut out = Vec::with_capacity(run.epochs.len());
    let mut row = 0usize;
    for (e, sol) in run.epochs.iter().enumerate() {
        let start = row;
        while row < run.sats.len() && run.sats[row].epoch == e {
            row += 1;
        }
        let none = EpochVelocity {
            velocity: None,
            fde: FdeOutcome::empty(0),
            sats: Vec::new(),
        };
        let (Some(r), Some(ep)) = (sol.position, obs.epochs.get(e)) else {
            out.push(none);
            continue;
        };
        let (mut los, mut vel, mut rate, mut sig, mut sats) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for sr in &run.sats[start..row] {
            if sr.status != SatStatus::Used {
                continue;
            }
            let Some(&(_, Some(dcode), lambda)) = codes.iter().find(|(s, _, _)| *s == sr.sat.sys)
            else {
                continue;
            };
            let Some(d) = ep
                .obs
                .iter()
                .find(|o| o.sat == sr.sat && o.code == dcode)
                .map(|o| o.value)
                .filter(|v| v.is_finite() && *v != 0.0)
            else {
                continue;
            };
            let Some(eph) = nav
                .ephemerides
                .get(&sr.sat)
                .and_then(|v| select(v, &ep.time).ok())
            else {
                continue;
            };
            let range = (sr.sat_pos - r).norm();
            let ttx = eph.transmission_time(&ep.time, range);
            let (v_s, drift_s) = eph.rates(&ttx);
            let u = (sr.sat_pos - r) / range;
            los.push(u);
            vel.push(v_s);
            rate.push(-lambda * d + C * drift_s);
            let s = sr.elevation.sin().max(0.05);
            sig.push((noise.0 * noise.0 + noise.1 * noise.1 / (s * s)).sqrt());
            sats.push(sr.sat);
        }
        if los.len() < 5 {
            out.push(EpochVelocity { sats, ..none });
            continue;
        }
        let mut model = RateModel::new(&los, &vel, &rate);
        let usable = vec![true; los.len()];
        let outcome = fde(&mut model, &ObsCov::Sigma(sig), &usable, None, fde_cfg)?;
        let velocity = outcome
            .solution
            .as_ref()
            .map(|x| (Vector3::new(x[0], x[1], x[2]), x[3]));
        out.push(EpochVelocity {
            velocity,
            fde: outcome,
            sats,
        });
    }
    Ok(out)
}
