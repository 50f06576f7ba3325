//! A GNSS-only position-velocity Kalman filter (extended, ECEF) with innovation FDE: paper
//! 001's method 2 as the paper ran it, on the GNSS data before the integration filter.
//!
//! State `[r (3), v (3), b, d]`: ECEF position (m), velocity (m/s), receiver clock bias (m)
//! and drift (m/s). Constant-velocity model with white acceleration noise of spectral density
//! `accel_psd` (m²/s³) per axis and the receiver clock model of the scenario. Measurements:
//! pseudoranges `|r_s − r| + b` and (optionally) rates `u·(v_s − v) + d`, linearised at the
//! prediction. Initialised at the first epoch with at least five satellites from the snapshot
//! least-squares solution (position, clock, velocity, drift), with σ 10 m, 1 m/s, 10 m,
//! 1 m/s.

use super::clock::ClockSpec;
use super::innovation::{innovation_fde, update_without, SatFde};
use super::snapshot::{fde, FdeConfig, ObsCov, PositionModel, RateModel};
use crate::error::Result;
use crate::kalman::KalmanFilter;
use nalgebra::{DMatrix, DVector, Vector3};

/// The filter and its models.
#[derive(Debug, Clone)]
pub struct PvFilter {
    kf: Option<KalmanFilter>,
    phi: DMatrix<f64>,
    q: DMatrix<f64>,
}

impl PvFilter {
    /// A filter stepping every `dt` s with acceleration PSD `accel_psd` (m²/s³) and `clock`.
    pub fn new(dt: f64, accel_psd: f64, clock: &ClockSpec) -> Self {
        let mut phi = DMatrix::identity(8, 8);
        let mut q = DMatrix::zeros(8, 8);
        for a in 0..3 {
            phi[(a, 3 + a)] = dt;
            q[(a, a)] = accel_psd * dt.powi(3) / 3.0;
            q[(a, 3 + a)] = accel_psd * dt * dt / 2.0;
            q[(3 + a, a)] = accel_psd * dt * dt / 2.0;
            q[(3 + a, 3 + a)] = accel_psd * dt;
        }
        let (phi_clk, q_clk) = clock.discrete(dt);
        for a in 0..2 {
            for b in 0..2 {
                phi[(6 + a, 6 + b)] = phi_clk[a][b];
                q[(6 + a, 6 + b)] = q_clk[a][b];
            }
        }
        PvFilter { kf: None, phi, q }
    }

    /// Predict (when initialised) over one period. Call once per epoch, before [`Self::step`].
    pub fn predict(&mut self) -> Result<()> {
        if let Some(kf) = &mut self.kf {
            kf.predict_trusted(&self.phi, &self.q, 1.0)?;
        }
        Ok(())
    }

    /// One epoch's FDE and update with the satellites in view: ECEF positions and velocities,
    /// pseudoranges `rho` (m) and rates (m/s), their σ; `rates`: use and test the rates.
    /// Returns the FDE outcome (None before the filter could be initialised).
    #[allow(clippy::too_many_arguments)]
    pub fn step(
        &mut self,
        sat_pos: &[Vector3<f64>],
        sat_vel: &[Vector3<f64>],
        rho: &[f64],
        rate: &[f64],
        sigma: &[f64],
        sigma_rate: &[f64],
        rates: bool,
        cfg: &FdeConfig,
    ) -> Result<Option<SatFde>> {
        let m = rho.len();
        let Some(kf) = &mut self.kf else {
            // Initialise from a snapshot solution with FDE.
            if m < 5 {
                return Ok(None);
            }
            // Position and clock first; the rate lines of sight need the position.
            let mut pm = PositionModel::new(sat_pos, rho, [0.0; 4]);
            let pos = fde(
                &mut pm,
                &ObsCov::Sigma(sigma.to_vec()),
                &vec![true; m],
                None,
                cfg,
            )?;
            let Some(x) = pos.solution.as_ref() else {
                return Ok(None);
            };
            let r = Vector3::new(x[0], x[1], x[2]);
            let los: Vec<Vector3<f64>> = sat_pos.iter().map(|s| (s - r).normalize()).collect();
            let mut rm = RateModel::new(&los, sat_vel, rate);
            let usable: Vec<bool> = (0..m).map(|j| !pos.excluded.contains(&j)).collect();
            let vel = fde(
                &mut rm,
                &ObsCov::Sigma(sigma_rate.to_vec()),
                &usable,
                None,
                cfg,
            )?;
            let v = vel.solution.unwrap_or_else(|| DVector::zeros(4));
            let x0 = DVector::from_vec(vec![x[0], x[1], x[2], v[0], v[1], v[2], x[3], v[3]]);
            let p0 = DMatrix::from_diagonal(&DVector::from_vec(vec![
                100.0, 100.0, 100.0, 1.0, 1.0, 1.0, 100.0, 1.0,
            ]));
            self.kf = Some(KalmanFilter::new(x0, p0)?);
            let mut excluded = pos.excluded.clone();
            excluded.extend(vel.excluded.iter().copied());
            return Ok(Some(SatFde {
                excluded,
                status: pos.status,
                first: pos.first,
                w: pos.w_with_excluded(),
            }));
        };
        let x = kf.x().clone();
        let r = Vector3::new(x[0], x[1], x[2]);
        let v = Vector3::new(x[3], x[4], x[5]);
        let rows = if rates { 2 * m } else { m };
        let mut h = DMatrix::zeros(rows, 8);
        let mut z = DVector::zeros(rows);
        let mut rr = DMatrix::zeros(rows, rows);
        for j in 0..m {
            let d = sat_pos[j] - r;
            let range = d.norm();
            let u = d / range;
            for a in 0..3 {
                h[(j, a)] = -u[a];
            }
            h[(j, 6)] = 1.0;
            // Linearised measurement: z' = z − h(x⁻) + H x⁻.
            z[j] = rho[j] - (range + x[6]) + h.row(j).dot(&x.transpose());
            rr[(j, j)] = sigma[j] * sigma[j];
            if rates {
                for a in 0..3 {
                    h[(m + j, 3 + a)] = -u[a];
                }
                h[(m + j, 7)] = 1.0;
                let pred = u.dot(&(sat_vel[j] - v)) + x[7];
                z[m + j] = rate[j] - pred + h.row(m + j).dot(&x.transpose());
                rr[(m + j, m + j)] = sigma_rate[j] * sigma_rate[j];
            }
        }
        let (inn, pending) = kf.innovation_pending(&z, &h, &rr)?;
        let out = innovation_fde(
            &inn.residual,
            &inn.covariance,
            m,
            true,
            Some(inn.statistic),
            false,
            cfg,
        )?;
        update_without(kf, &z, &h, &rr, m, &out.excluded, pending)?;
        Ok(Some(out))
    }

    /// Current state `[r, v, b, d]` (None before initialisation).
    pub fn state(&self) -> Option<&DVector<f64>> {
        self.kf.as_ref().map(|k| k.x())
    }
}
