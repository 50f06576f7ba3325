//! Closed-loop 15-state error-state Kalman filter of a strapdown INS ([`super::strapdown`]):
//! position error (m, north-east-down), velocity error (m/s), attitude error φ (rad), gyro
//! bias (rad/s) and accelerometer bias (m/s²), biases as first-order Gauss-Markov processes.
//! `F`, `Φ ≈ I + F Δt` and `Q` are built from the mechanised state and the IMU's noise
//! figures at every sample (never from a truth); corrections are fed back into the
//! mechanisation after every update and the error state reset to zero.
//!
//! Conventions (KF-GINS's): `δr = r̂ − r`, `δv = v̂ − v`, `Ĉ_b^n = (I − [φ×]) C_b^n`; the
//! bias states are the estimated biases themselves, removed from the IMU increments.

use super::earth;
use super::strapdown::{frame_rates, skew, NavState};
use crate::error::{Error, Result};
use nalgebra::{Cholesky, DMatrix, DVector, Matrix3, SMatrix, SVector, UnitQuaternion, Vector3};

/// Number of error states without scale factors.
pub const N: usize = 15;
/// Number of error states with gyro and accelerometer scale factors.
pub const N_SCALE: usize = 21;
/// Index of the gyro scale-factor error (dimensionless, body axes; [`N_SCALE`] states).
pub const SG: usize = 15;
/// Index of the accelerometer scale-factor error.
pub const SA: usize = 18;
/// Number of error states with receiver clock states (tight coupling): the 15 plus one
/// clock bias per system (GPS, Galileo; m) and the common clock drift (m/s).
pub const N_CLOCK: usize = 18;
/// Index of the first clock-bias error (GPS; Galileo's follows) in [`N_CLOCK`] states (m).
pub const CB: usize = 15;
/// Index of the clock-drift error in [`N_CLOCK`] states (m/s).
pub const CD: usize = 17;
/// Index of the position error (north, east, down; m).
pub const R: usize = 0;
/// Index of the velocity error (north, east, down; m/s).
pub const V: usize = 3;
/// Index of the attitude error φ (rad, navigation axes).
pub const PHI: usize = 6;
/// Index of the gyro bias (rad/s, body axes).
pub const BG: usize = 9;
/// Index of the accelerometer bias (m/s², body axes).
pub const BA: usize = 12;

/// The IMU's noise figures, in SI units.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImuNoise {
    /// Angle random walk: gyro white-noise density per IMU axis x, y, z (rad/s/√Hz).
    pub gyro_noise: [f64; 3],
    /// Velocity random walk: accelerometer white-noise density per IMU axis (m/s²/√Hz).
    pub accel_noise: [f64; 3],
    /// Gyro bias instability: σ of the Gauss-Markov bias (rad/s).
    pub gyro_bias: f64,
    /// Accelerometer bias instability: σ of the Gauss-Markov bias (m/s²).
    pub accel_bias: f64,
    /// Correlation time of both biases (s).
    pub bias_tau: f64,
    /// Scale-factor instability of the gyros (σ of a Gauss-Markov scale factor with the
    /// biases' correlation time, dimensionless); 0: no scale-factor states.
    #[serde(default)]
    pub gyro_scale: f64,
    /// Scale-factor instability of the accelerometers; 0: none.
    #[serde(default)]
    pub accel_scale: f64,
}

impl ImuNoise {
    /// Whether the filter carries scale-factor states ([`N_SCALE`] states).
    pub fn scale_factors(&self) -> bool {
        self.gyro_scale > 0.0 || self.accel_scale > 0.0
    }
}

/// The error-state filter: the estimated biases (and scale factors) and the error covariance,
/// `N` = 15 states, or [`N_SCALE`] = 21 with scale factors.
#[derive(Debug, Clone)]
pub struct ErrorFilter<const NS: usize = N> {
    /// Error covariance (NS × NS).
    pub p: SMatrix<f64, NS, NS>,
    /// Estimated gyro and accelerometer scale factors (dimensionless; zero without them).
    pub sg: Vector3<f64>,
    /// See [`ErrorFilter::sg`].
    pub sa: Vector3<f64>,
    /// Estimated gyro bias (rad/s, body).
    pub bg: Vector3<f64>,
    /// Estimated accelerometer bias (m/s², body).
    pub ba: Vector3<f64>,
    /// Estimated receiver clock ([`N_CLOCK`] states): bias GPS, bias Galileo (m), drift (m/s).
    pub clock: [f64; 3],
    /// Spectral densities of the clock's bias (m²/s) and drift (m²/s³) noise.
    clock_psd: (f64, f64),
    noise: ImuNoise,
    /// White-noise spectral densities in body axes (`M diag(n²) Mᵀ`).
    q_gyro: Matrix3<f64>,
    q_acc: Matrix3<f64>,
    /// Product of the transitions `Φ` since [`ErrorFilter::take_transition`] was last called
    /// (None: not tracked; [`ErrorFilter::track_transition`]).
    transition: Option<SMatrix<f64, NS, NS>>,
}

/// Outcome of one measurement's innovation, before (and whether) it updated the filter.
#[derive(Debug, Clone)]
pub struct Innovation {
    /// Innovation (m components as given).
    pub r: DVector<f64>,
    /// Its covariance `H P Hᵀ + R`.
    pub s: DMatrix<f64>,
    /// `λ = rᵀ S⁻¹ r`.
    pub lambda: f64,
    /// Cholesky factor of `s`, reused by [`ErrorFilter::update`].
    chol: Cholesky<f64, nalgebra::Dyn>,
    /// `H P` (m × NS), reused by [`ErrorFilter::update`].
    hp: DMatrix<f64>,
}

impl Innovation {
    /// The whitened innovation `L⁻¹ r` (`S = L Lᵀ`): white, unit-variance noise for a
    /// consistent filter.
    pub fn whitened(&self) -> DVector<f64> {
        self.chol
            .l_dirty()
            .solve_lower_triangular(&self.r)
            .unwrap_or_else(|| DVector::from_element(self.r.len(), f64::NAN))
    }
}

impl<const NS: usize> ErrorFilter<NS> {
    /// A filter with initial σ per state group: position (m), velocity (m/s), attitude
    /// (rad; roll, pitch, yaw — applied to north, east, down), gyro bias (rad/s), accelerometer
    /// bias (m/s²), and the IMU noise figures.
    pub fn new(
        sig_pos: f64,
        sig_vel: f64,
        sig_att: Vector3<f64>,
        bg0: Vector3<f64>,
        noise: ImuNoise,
    ) -> Self {
        let mut p = SMatrix::<f64, NS, NS>::zeros();
        for i in 0..3 {
            p[(R + i, R + i)] = sig_pos * sig_pos;
            p[(V + i, V + i)] = sig_vel * sig_vel;
            p[(PHI + i, PHI + i)] = sig_att[i] * sig_att[i];
            p[(BG + i, BG + i)] = noise.gyro_bias * noise.gyro_bias;
            p[(BA + i, BA + i)] = noise.accel_bias * noise.accel_bias;
            if NS == N_SCALE {
                p[(SG + i, SG + i)] = noise.gyro_scale * noise.gyro_scale;
                p[(SA + i, SA + i)] = noise.accel_scale * noise.accel_scale;
            }
        }
        let sq = |n: [f64; 3]| {
            Matrix3::from_diagonal(&Vector3::new(n[0] * n[0], n[1] * n[1], n[2] * n[2]))
        };
        ErrorFilter {
            p,
            sg: Vector3::zeros(),
            sa: Vector3::zeros(),
            bg: bg0,
            ba: Vector3::zeros(),
            clock: [0.0; 3],
            clock_psd: (0.0, 0.0),
            noise,
            q_gyro: sq(noise.gyro_noise),
            q_acc: sq(noise.accel_noise),
            transition: None,
        }
    }

    /// Keep the product of the transitions `Φ` of every [`ErrorFilter::propagate`] from now
    /// on, for states carried outside the filter whose cross-covariance with the error state
    /// must follow it ([`super::range_states`]).
    pub fn track_transition(&mut self) {
        self.transition = Some(SMatrix::identity());
    }

    /// The product of the transitions since the last call (or since
    /// [`ErrorFilter::track_transition`]), restarting it from the identity; the identity when
    /// transitions are not tracked.
    pub fn take_transition(&mut self) -> SMatrix<f64, NS, NS> {
        match self.transition.as_mut() {
            Some(t) => std::mem::replace(t, SMatrix::identity()),
            None => SMatrix::identity(),
        }
    }

    /// Rotate the per-axis noise densities from the IMU's axes into the body's with the
    /// mounting `m` (`C_imu^b`).
    pub fn with_mounting(mut self, m: &Matrix3<f64>) -> Self {
        self.q_gyro = m * self.q_gyro * m.transpose();
        self.q_acc = m * self.q_acc * m.transpose();
        self
    }

    /// Receiver clock states ([`N_CLOCK`] states): start values `x0` (bias GPS, bias Galileo in
    /// m, drift in m/s), their σ `sig0` (m, m, m/s) and the spectral densities of the bias
    /// (m²/s) and drift (m²/s³) noise. Does nothing with fewer states.
    pub fn with_clock(mut self, x0: [f64; 3], sig0: [f64; 3], psd: (f64, f64)) -> Self {
        if NS == N_CLOCK {
            for (j, s) in sig0.iter().enumerate() {
                self.p[(CB + j, CB + j)] = s * s;
            }
            self.clock = x0;
            self.clock_psd = psd;
        }
        self
    }

    /// The IMU's angular rate `w` (rad/s) and specific force `f` (m/s²) corrected for the
    /// estimated biases and scale factors.
    pub fn compensate(&self, w: &Vector3<f64>, f: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        (
            (w - self.bg).component_div(&(Vector3::repeat(1.0) + self.sg)),
            (f - self.ba).component_div(&(Vector3::repeat(1.0) + self.sa)),
        )
    }

    /// Propagate `P` over `dt` s with `F` from state `s` and the corrected specific force
    /// `f_b` (m/s²) and angular rate `w_b` (rad/s) of the interval.
    pub fn propagate(&mut self, s: &NavState, f_b: &Vector3<f64>, w_b: &Vector3<f64>, dt: f64) {
        self.propagate_with(s, f_b, w_b, dt, None);
    }

    /// [`Self::propagate`] over part of a gap in the IMU log (samples missing): the
    /// specific-force and angular-rate white noise per body axis is at least `acc_rate`
    /// ((m/s²)² s) and `gyro_rate` ((rad/s)² s) per second instead of the noise densities'
    /// squares — the error of the samples that bridge the gap
    /// ([`crate::arch::inertial::ImuGap`]).
    pub fn propagate_gap(
        &mut self,
        s: &NavState,
        f_b: &Vector3<f64>,
        w_b: &Vector3<f64>,
        dt: f64,
        acc_rate: &Vector3<f64>,
        gyro_rate: &Vector3<f64>,
    ) {
        let extra = |q: &Matrix3<f64>, r: &Vector3<f64>| {
            Matrix3::from_diagonal(&Vector3::from_fn(|i, _| (r[i] - q[(i, i)]).max(0.0)))
        };
        let more = (extra(&self.q_acc, acc_rate), extra(&self.q_gyro, gyro_rate));
        self.propagate_with(s, f_b, w_b, dt, Some(more));
    }

    fn propagate_with(
        &mut self,
        s: &NavState,
        f_b: &Vector3<f64>,
        w_b: &Vector3<f64>,
        dt: f64,
        more: Option<(Matrix3<f64>, Matrix3<f64>)>,
    ) {
        if dt <= 0.0 {
            return;
        }
        let c = s.q.to_rotation_matrix().into_inner();
        let (w_ie, w_en) = frame_rates(s);
        let w_in = w_ie + w_en;
        let f_n = c * f_b;
        let rm = earth::r_meridian(s.lat) + s.h;
        let rn = earth::r_normal(s.lat) + s.h;
        let mut f = SMatrix::<f64, NS, NS>::zeros();
        // Position: δr' = −[ω_en×] δr + δv (the dominant terms).
        let v = &s.v;
        f.fixed_view_mut::<3, 3>(R, R).copy_from(&Matrix3::new(
            -v.z / rm,
            0.0,
            v.x / rm,
            v.y * s.lat.tan() / rn,
            -(v.z + v.x * s.lat.tan()) / rn,
            v.y / rn,
            0.0,
            0.0,
            0.0,
        ));
        f.fixed_view_mut::<3, 3>(R, V)
            .copy_from(&Matrix3::identity());
        // Velocity: δv' = −[(2ω_ie + ω_en)×] δv + [f_n×] φ + C δba, plus gravity's height
        // term: a state δr_D too low feels gravity stronger by the free-air gradient times δr_D
        // (the mechanisation's own model), so δv_D' = +(∂g/∂d) δr_D.
        f.fixed_view_mut::<3, 3>(V, V)
            .copy_from(&(-skew(&(2.0 * w_ie + w_en))));
        f[(V + 2, R + 2)] = earth::FREE_AIR_GRADIENT;
        f.fixed_view_mut::<3, 3>(V, PHI).copy_from(&skew(&f_n));
        f.fixed_view_mut::<3, 3>(V, BA).copy_from(&c);
        // Attitude: φ' = −[ω_in×] φ − C δbg.
        f.fixed_view_mut::<3, 3>(PHI, PHI)
            .copy_from(&(-skew(&w_in)));
        f.fixed_view_mut::<3, 3>(PHI, BG).copy_from(&(-c));
        let tau = self.noise.bias_tau;
        let gauss_markov_end = if NS == N_CLOCK { BA + 3 } else { NS };
        for i in BG..gauss_markov_end {
            f[(i, i)] = -1.0 / tau;
        }
        if NS == N_CLOCK {
            // The estimated biases integrate the estimated drift.
            self.clock[0] += self.clock[2] * dt;
            self.clock[1] += self.clock[2] * dt;
            // Clock: each system's bias integrates the common drift.
            f[(CB, CD)] = 1.0;
            f[(CB + 1, CD)] = 1.0;
        }
        if NS == N_SCALE {
            // Scale factors: δv' += C diag(f_b) δs_a, φ' −= C diag(ω_b) δs_g.
            for j in 0..3 {
                for i in 0..3 {
                    f[(V + i, SA + j)] = c[(i, j)] * f_b[j];
                    f[(PHI + i, SG + j)] = -c[(i, j)] * w_b[j];
                }
            }
        }
        let _ = w_b;
        // Φ = I + F Δt, formed in F's place (the same values as `I + F·Δt`).
        let mut phi = f;
        phi *= dt;
        for i in 0..NS {
            phi[(i, i)] += 1.0;
        }
        // Discrete process noise: white noise through C, Gauss-Markov drivers on the biases.
        let (qv, qa) = match more {
            None => (
                c * self.q_acc * c.transpose() * dt,
                c * self.q_gyro * c.transpose() * dt,
            ),
            Some((ma, mg)) => (
                c * (self.q_acc + ma) * c.transpose() * dt,
                c * (self.q_gyro + mg) * c.transpose() * dt,
            ),
        };
        let qbg = 2.0 * self.noise.gyro_bias.powi(2) / tau * dt;
        let qba = 2.0 * self.noise.accel_bias.powi(2) / tau * dt;
        if let Some(t) = self.transition.as_mut() {
            *t = crate::linalg::left_block_sparse(&phi, t);
        }
        // Ten of Φ's 25 3 × 3 blocks are non-zero at 15 states: the zero ones are skipped.
        // Formed, Q added and symmetrised in P's own storage (no copies of P per sample).
        let p = &mut self.p;
        crate::linalg::sandwich_block_sparse_in_place(&phi, p);
        {
            let mut b = p.fixed_view_mut::<3, 3>(V, V);
            b += qv;
        }
        {
            let mut b = p.fixed_view_mut::<3, 3>(PHI, PHI);
            b += qa;
        }
        for i in 0..3 {
            p[(BG + i, BG + i)] += qbg;
            p[(BA + i, BA + i)] += qba;
            if NS == N_SCALE {
                p[(SG + i, SG + i)] += 2.0 * self.noise.gyro_scale.powi(2) / tau * dt;
                p[(SA + i, SA + i)] += 2.0 * self.noise.accel_scale.powi(2) / tau * dt;
            }
        }
        if NS == N_CLOCK {
            // The biases share the receiver oscillator's noise (one clock, per-system offsets).
            let (qb, qd) = self.clock_psd;
            for i in 0..2 {
                for j in 0..2 {
                    p[(CB + i, CB + j)] += qb * dt + qd * dt.powi(3) / 3.0;
                }
                p[(CB + i, CD)] += qd * dt * dt / 2.0;
                p[(CD, CB + i)] += qd * dt * dt / 2.0;
            }
            p[(CD, CD)] += qd * dt;
        }
        crate::linalg::symmetrise(p);
    }

    /// The innovation `res` of a measurement (its model's prediction from the error state,
    /// zero after each feedback, subtracted), matrix `h` (m × NS) and noise covariance `r`
    /// (m × m).
    pub fn innovation(
        &self,
        res: &DVector<f64>,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<Innovation> {
        let m = h.nrows();
        if m == 0 || h.ncols() != NS || r.nrows() != m || r.ncols() != m || res.len() != m {
            return Err(Error::Invalid(format!(
                "strapdown aiding measurement: H {}×{}, R {}×{}, residual {} for {NS} states",
                h.nrows(),
                h.ncols(),
                r.nrows(),
                r.ncols(),
                res.len()
            )));
        }
        // H P (m × NS), then S = (H P) Hᵀ + R, in loops over the static covariance (no
        // dynamic copy of P, no packing of these small products), skipping the columns of H
        // that are zero (most of a position or velocity row's: their terms are exact zeros,
        // so the sums are the same).
        let hs = h.as_slice();
        let mut cols = [0usize; NS];
        let mut nc = 0;
        for (k, hc) in hs.chunks_exact(m).enumerate() {
            if hc.iter().any(|&x| x != 0.0) {
                cols[nc] = k;
                nc += 1;
            }
        }
        let cols = &cols[..nc];
        let ps = self.p.as_slice();
        let mut hp = DMatrix::<f64>::zeros(m, NS);
        // Column-major slices: column k of H, column j of H P and of P are contiguous.
        for (hpc, pc) in hp
            .as_mut_slice()
            .chunks_exact_mut(m)
            .zip(ps.chunks_exact(NS))
        {
            for &k in cols {
                let pkj = pc[k];
                for (o, x) in hpc.iter_mut().zip(&hs[k * m..(k + 1) * m]) {
                    *o += x * pkj;
                }
            }
        }
        let mut s = r.clone();
        let hps = hp.as_slice();
        for (j, sc) in s.as_mut_slice().chunks_exact_mut(m).enumerate() {
            for &k in cols {
                let hjk = hs[j + k * m];
                for (o, x) in sc.iter_mut().zip(&hps[k * m..(k + 1) * m]) {
                    *o += x * hjk;
                }
            }
        }
        let chol = Cholesky::new(s.clone()).ok_or_else(|| Error::NotPositiveDefinite {
            name: "innovation covariance".into(),
            detail: "H P Hᵀ + R of a strapdown aiding measurement".into(),
        })?;
        let lambda = res.dot(&chol.solve(res));
        Ok(Innovation {
            r: res.clone(),
            s,
            lambda,
            chol,
            hp,
        })
    }

    /// Update with an innovation `inn` of matrix `h` (Joseph form) and return the error-state
    /// estimate to feed back ([`ErrorFilter::feedback`]). The Joseph form
    /// `(I − KH) P (I − KH)ᵀ + K R Kᵀ` is evaluated as `P − K(HP) − (K(HP))ᵀ + K S Kᵀ`
    /// (`S = HPHᵀ + R`), every product of inner dimension m, without forming `I − KH`.
    pub fn update(
        &mut self,
        inn: &Innovation,
        h: &DMatrix<f64>,
        r: &DMatrix<f64>,
    ) -> Result<SVector<f64, NS>> {
        let m = h.nrows();
        if inn.hp.nrows() != m || r.nrows() != m {
            return Err(Error::Invalid(format!(
                "strapdown update: {m} rows of H against an innovation of {} and R of {}",
                inn.hp.nrows(),
                r.nrows()
            )));
        }
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked on the line above).
            return Ok(unsafe { self.joseph_avx2(inn, m) });
        }
        Ok(self.joseph(inn, m))
    }

    /// [`ErrorFilter::joseph`] compiled with AVX2 enabled (4-wide vectors instead of the
    /// baseline's SSE2; element-wise products and sums, no fused multiply-add: the same bits).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn joseph_avx2(&mut self, inn: &Innovation, m: usize) -> SVector<f64, NS> {
        self.joseph(inn, m)
    }

    /// The gain, the state correction and the Joseph-form covariance of
    /// [`ErrorFilter::update`] (`m` rows, shapes checked there).
    #[inline(always)]
    fn joseph(&mut self, inn: &Innovation, m: usize) -> SVector<f64, NS> {
        // K = P Hᵀ S⁻¹ (NS × m) by substitution on the contiguous columns of P Hᵀ with
        // reciprocal pivots; K S Kᵀ = (K S) Kᵀ.
        let mut k = inn.hp.transpose();
        let mut inv = vec![0.0; m];
        crate::kalman::gain_from_cholesky(inn.chol.l_dirty(), &mut k, &mut inv);
        // K S (NS × m), column by column.
        let kv = k.as_slice();
        let ss = inn.s.as_slice();
        let mut ks = vec![0.0; NS * m];
        for (kc, sc) in ks.chunks_exact_mut(NS).zip(ss.chunks_exact(m)) {
            for (b, &sba) in sc.iter().enumerate() {
                for (o, x) in kc.iter_mut().zip(&kv[b * NS..(b + 1) * NS]) {
                    *o += x * sba;
                }
            }
        }
        let mut dx = SVector::<f64, NS>::zeros();
        for (a, kc) in kv.chunks_exact(NS).enumerate() {
            for (o, x) in dx.iter_mut().zip(kc) {
                *o += x * inn.r[a];
            }
        }
        let hps = inn.hp.as_slice();
        let mut khp = SMatrix::<f64, NS, NS>::zeros();
        let mut ksk = SMatrix::<f64, NS, NS>::zeros();
        for j in 0..NS {
            let mut kh = khp.column_mut(j);
            for (a, kc) in kv.chunks_exact(NS).enumerate() {
                let v = hps[a + j * m];
                for (o, x) in kh.iter_mut().zip(kc) {
                    *o += x * v;
                }
            }
            let mut kk = ksk.column_mut(j);
            for (a, kc) in ks.chunks_exact(NS).enumerate() {
                let v = kv[j + a * NS];
                for (o, x) in kk.iter_mut().zip(kc) {
                    *o += x * v;
                }
            }
        }
        // P − K H P − (K H P)ᵀ + K S Kᵀ element by element in P's storage (the order of
        // `P − KHP − (KHP)ᵀ + KSKᵀ`), then symmetrised in place.
        for j in 0..NS {
            for i in 0..NS {
                self.p[(i, j)] = self.p[(i, j)] - khp[(i, j)] - khp[(j, i)] + ksk[(i, j)];
            }
        }
        crate::linalg::symmetrise(&mut self.p);
        dx
    }

    /// `h_i P h_iᵀ` (the state's share of the innovation variance) of row `i` of `h` (rows of
    /// `NS` columns).
    pub fn row_variance(&self, h: &DMatrix<f64>, i: usize) -> f64 {
        let hi = SVector::<f64, NS>::from_iterator(h.row(i).iter().copied());
        hi.dot(&(self.p * hi))
    }

    /// The update with the rows of `h` (m × NS) and residual `res` one at a time, for a
    /// diagonal noise `r_diag` (m variances): the updated covariance (not committed), the
    /// error-state estimate and the global statistic `λ = Σ νᵢ²/sᵢ` of the sequential
    /// innovations (`rᵀS⁻¹r` of the batch, to rounding) — no m × m factorisation. Commit with
    /// `self.p = p` and [`ErrorFilter::feedback`].
    pub fn sequential(
        &self,
        res: &DVector<f64>,
        h: &DMatrix<f64>,
        r_diag: &[f64],
    ) -> Result<(SMatrix<f64, NS, NS>, SVector<f64, NS>, f64)> {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked on the line above).
            return unsafe { self.sequential_avx2(res, h, r_diag) };
        }
        self.sequential_rows(res, h, r_diag)
    }

    /// [`ErrorFilter::sequential_rows`] compiled with AVX2 enabled (the same bits, as
    /// [`ErrorFilter::joseph_avx2`]).
    ///
    /// # Safety
    /// The CPU must support AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn sequential_avx2(
        &self,
        res: &DVector<f64>,
        h: &DMatrix<f64>,
        r_diag: &[f64],
    ) -> Result<(SMatrix<f64, NS, NS>, SVector<f64, NS>, f64)> {
        self.sequential_rows(res, h, r_diag)
    }

    /// The row-by-row update of [`ErrorFilter::sequential`].
    #[inline(always)]
    fn sequential_rows(
        &self,
        res: &DVector<f64>,
        h: &DMatrix<f64>,
        r_diag: &[f64],
    ) -> Result<(SMatrix<f64, NS, NS>, SVector<f64, NS>, f64)> {
        let mut p = self.p;
        let mut dx = SVector::<f64, NS>::zeros();
        let mut lambda = 0.0;
        for i in 0..res.len() {
            let hi = SVector::<f64, NS>::from_iterator(h.row(i).iter().copied());
            let ph = p * hi;
            let s = hi.dot(&ph) + r_diag[i];
            if !(s > 0.0 && s.is_finite()) {
                return Err(Error::NotPositiveDefinite {
                    name: "innovation variance".into(),
                    detail: format!("row {i} of a sequential strapdown update: {s}"),
                });
            }
            let nu = res[i] - hi.dot(&dx);
            lambda += nu * nu / s;
            let k = ph / s;
            dx += k * nu;
            p -= k * ph.transpose();
        }
        Ok((0.5 * (p + p.transpose()), dx, lambda))
    }

    /// Feed an error-state estimate `dx` back into the mechanised state `s` and the biases.
    pub fn feedback(&mut self, s: &mut NavState, dx: &SVector<f64, NS>) {
        let rm = earth::r_meridian(s.lat) + s.h;
        let rn = earth::r_normal(s.lat) + s.h;
        s.lat -= dx[R] / rm;
        s.lon -= dx[R + 1] / (rn * s.lat.cos());
        s.h += dx[R + 2];
        s.v -= Vector3::new(dx[V], dx[V + 1], dx[V + 2]);
        let phi = Vector3::new(dx[PHI], dx[PHI + 1], dx[PHI + 2]);
        s.q = UnitQuaternion::from_scaled_axis(phi) * s.q;
        self.bg += Vector3::new(dx[BG], dx[BG + 1], dx[BG + 2]);
        self.ba += Vector3::new(dx[BA], dx[BA + 1], dx[BA + 2]);
        if NS == N_SCALE {
            self.sg += Vector3::new(dx[SG], dx[SG + 1], dx[SG + 2]);
            self.sa += Vector3::new(dx[SA], dx[SA + 1], dx[SA + 2]);
        }
        if NS == N_CLOCK {
            for j in 0..3 {
                self.clock[j] -= dx[CB + j];
            }
        }
    }

    /// σ of every error state (square roots of `P`'s diagonal).
    pub fn sigma(&self) -> SVector<f64, NS> {
        SVector::<f64, NS>::from_iterator((0..NS).map(|i| self.p[(i, i)].max(0.0).sqrt()))
    }
}

#[cfg(test)]
#[path = "error_filter_tests.rs"]
pub(crate) mod tests;
