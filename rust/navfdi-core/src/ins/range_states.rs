//! Per-satellite first-order Gauss-Markov range-error states beside the tight filter's
//! closed-loop error state ([`super::error_filter::ErrorFilter`] with [`N_CLOCK`] states).
//!
//! A recorded receiver's pseudorange errors are correlated over many seconds (multipath,
//! residual atmosphere, orbit and clock). A filter that weighs each epoch's pseudoranges as
//! independent grows too confident; its sub-filters drift apart by more than their covariances
//! say. Here each satellite's pseudorange error is split into white noise of variance
//! `(1 − a) σ²` and a first-order Gauss-Markov process `b` of stationary variance `a σ²` and
//! correlation time `τ` (`σ` the white model's σ of the satellite at the epoch, `a` the
//! correlated fraction), estimated jointly with the navigation errors:
//!
//! * the augmented state is `[δx (18); δb (S)]`, one `b` per satellite of the run (S), with
//!   `δb = b̂ − b` (the filter's convention, as its clock biases);
//! * between GNSS epochs the error filter propagates its own block and keeps the product `Φ` of
//!   its transitions ([`ErrorFilter::track_transition`]); at the epoch the cross-covariance
//!   becomes `Φ C ψ`, the range block `ψ² P_bb + (1 − ψ²) diag(a σ²)` and `b̂ ← ψ b̂`, with
//!   `ψ = exp(−Δt/τ)` (exact for the linear propagation: the process noises are independent);
//! * a pseudorange row predicts `ρ̂ + b̂` and has a 1 in its satellite's column; range-rate rows
//!   do not see `b`;
//! * after the update the navigation part is fed back as without the states, and
//!   `b̂ ← b̂ − δb̂`.
//!
//! A satellite's state starts at its first epoch in view at its stationary variance; while it
//! is away, its estimate and correlations decay with `ψ`, so a return after long absence starts
//! afresh without a rule.

use super::error_filter::{ErrorFilter, N_CLOCK};
use super::strapdown::NavState;
use crate::error::{Error, Result};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

const NX: usize = N_CLOCK;

/// The range-error states of one tight filter (or sub-filter).
#[derive(Debug, Clone)]
pub struct RangeStates {
    fraction: f64,
    tau: f64,
    /// Estimated range errors `b̂` (m), one per satellite of the run.
    b: DVector<f64>,
    /// Cross-covariance of the error state and `δb` (NX × S).
    c: DMatrix<f64>,
    /// Covariance of `δb` (S × S).
    pbb: DMatrix<f64>,
    /// Stationary variance `a σ²` of each satellite's state (m²), from its last σ; 0 before its
    /// first epoch in view.
    var: Vec<f64>,
    /// Time of the last propagation (s).
    t: f64,
}

/// An update computed and not yet committed (`RangeStates::commit`).
#[derive(Debug, Clone)]
pub enum Pending {
    /// Without range-error states: the error filter's covariance and estimate.
    White(Box<SMatrix<f64, NX, NX>>, SVector<f64, NX>),
    /// With them: the augmented covariance (NX + S) and estimate.
    Augmented(DMatrix<f64>, DVector<f64>),
}

impl RangeStates {
    /// States for `satellites` satellites, a correlated fraction `fraction` of each
    /// pseudorange's variance (in [0, 1)) with correlation time `tau` (s, > 0), from time `t0`
    /// (s).
    pub fn new(satellites: usize, fraction: f64, tau: f64, t0: f64) -> Result<Self> {
        if !(0.0..1.0).contains(&fraction) {
            return Err(Error::Invalid(format!(
                "tight.range_states.fraction = {fraction}: a fraction in [0, 1) of the pseudorange variance is required"
            )));
        }
        if !(tau > 0.0 && tau.is_finite()) {
            return Err(Error::Invalid(format!(
                "tight.range_states.tau = {tau} s: a positive, finite correlation time is required"
            )));
        }
        Ok(RangeStates {
            fraction,
            tau,
            b: DVector::zeros(satellites),
            c: DMatrix::zeros(NX, satellites),
            pbb: DMatrix::zeros(satellites, satellites),
            var: vec![0.0; satellites],
            t: t0,
        })
    }

    /// Estimated range error of satellite `g` (m).
    pub fn bias(&self, g: usize) -> f64 {
        self.b[g]
    }

    /// σ of satellite `g`'s range-error estimate (m).
    pub fn sigma(&self, g: usize) -> f64 {
        self.pbb[(g, g)].max(0.0).sqrt()
    }

    /// σ of satellite `g`'s estimate `b̂` itself under the model (m): `√(a σ̄² − P_bb)`, the
    /// stationary variance less what remains uncertain; 0 before its first epoch in view.
    pub fn estimate_sigma(&self, g: usize) -> f64 {
        (self.var[g] - self.pbb[(g, g)]).max(0.0).sqrt()
    }

    /// Propagate to time `tk` (s) with the transitions `kf` kept since the last call, and set
    /// the stationary variance of the satellites `sats` (stream indices) in view from their
    /// white-model σ `sigma` (m): a satellite seen for the first time starts there.
    pub fn propagate(&mut self, kf: &mut ErrorFilter<NX>, tk: f64, sats: &[usize], sigma: &[f64]) {
        let phi = kf.take_transition();
        let dt = (tk - self.t).max(0.0);
        self.t = tk;
        let psi = (-dt / self.tau).exp();
        let n = self.b.len();
        for g in 0..n {
            let col = SVector::<f64, NX>::from_iterator(self.c.column(g).iter().copied());
            let pc = phi * col * psi;
            self.c.column_mut(g).copy_from_slice(pc.as_slice());
        }
        self.pbb *= psi * psi;
        self.b *= psi;
        let mut fresh = vec![false; n];
        for (&g, &s) in sats.iter().zip(sigma) {
            let v = self.fraction * s * s;
            if !(v > 0.0 && v.is_finite()) {
                continue;
            }
            if self.var[g] == 0.0 {
                // First epoch in view: the stationary variance, uncorrelated with the rest.
                self.pbb[(g, g)] = v;
                self.var[g] = v;
                fresh[g] = true;
            } else {
                // The geometric mean over about τ: an epoch's σ spikes with a dip of its
                // signal (white), and must not open the slow state to that epoch's error.
                let w = 1.0 - psi;
                self.var[g] = (self.var[g].ln() * (1.0 - w) + v.ln() * w).exp();
            }
        }
        let q = 1.0 - psi * psi;
        for (g, (&f, &v)) in fresh.iter().zip(&self.var).enumerate() {
            if !f {
                self.pbb[(g, g)] += q * v;
            }
        }
    }

    /// Restart satellite `g`'s state: no estimated error, its stationary variance, no
    /// correlation with the rest.
    pub fn restart(&mut self, g: usize) {
        self.b[g] = 0.0;
        self.c.column_mut(g).fill(0.0);
        self.pbb.row_mut(g).fill(0.0);
        self.pbb.column_mut(g).fill(0.0);
        self.pbb[(g, g)] = self.var[g];
    }

    /// Add the estimated range errors to the predictions of the first `ranges` rows of `res`
    /// (`ẑ − z`; pseudoranges of the satellites `row_sats`).
    pub fn correct(&self, res: &mut DVector<f64>, row_sats: &[usize], ranges: usize) {
        for i in 0..ranges.min(res.len()) {
            res[i] += self.b[row_sats[i]];
        }
    }

    /// The white part of row `i`'s variance `r` (the pseudorange rows keep `1 − a` of theirs).
    fn white(&self, i: usize, ranges: usize, r: f64) -> f64 {
        if i < ranges {
            (1.0 - self.fraction) * r
        } else {
            r
        }
    }

    /// The augmented covariance `[[P, C], [Cᵀ, P_bb]]`.
    fn joint(&self, kf: &ErrorFilter<NX>) -> DMatrix<f64> {
        let n = self.b.len();
        let mut p = DMatrix::zeros(NX + n, NX + n);
        p.view_mut((0, 0), (NX, NX)).copy_from(&kf.p);
        p.view_mut((0, NX), (NX, n)).copy_from(&self.c);
        p.view_mut((NX, 0), (n, NX)).copy_from(&self.c.transpose());
        p.view_mut((NX, NX), (n, n)).copy_from(&self.pbb);
        p
    }

    /// The rows `h` (m × NX) extended by the range-error columns.
    fn rows(&self, h: &DMatrix<f64>, row_sats: &[usize], ranges: usize) -> DMatrix<f64> {
        let n = self.b.len();
        let mut ha = DMatrix::zeros(h.nrows(), NX + n);
        ha.view_mut((0, 0), (h.nrows(), NX)).copy_from(h);
        for i in 0..ranges.min(h.nrows()) {
            ha[(i, NX + row_sats[i])] = 1.0;
        }
        ha
    }

    /// The innovation `res` (corrected, [`RangeStates::correct`]) and its covariance
    /// `H P Hᵀ + R` of rows `h` with white-model variances `r_diag`.
    pub fn innovation_cov(
        &self,
        kf: &ErrorFilter<NX>,
        h: &DMatrix<f64>,
        r_diag: &[f64],
        row_sats: &[usize],
        ranges: usize,
    ) -> DMatrix<f64> {
        let ha = self.rows(h, row_sats, ranges);
        let mut s = &ha * self.joint(kf) * ha.transpose();
        for (i, &r) in r_diag.iter().enumerate() {
            s[(i, i)] += self.white(i, ranges, r);
        }
        s
    }

    /// The innovation variance `h P hᵀ + r` of row `i` of `h` (white-model variance `r`; a
    /// pseudorange of satellite `g` when `range`).
    pub fn row_variance(
        &self,
        kf: &ErrorFilter<NX>,
        h: &DMatrix<f64>,
        i: usize,
        r: f64,
        g: usize,
        range: bool,
    ) -> f64 {
        let v = kf.row_variance(h, i);
        if range {
            let hi = SVector::<f64, NX>::from_iterator(h.row(i).iter().copied());
            let cg = SVector::<f64, NX>::from_iterator(self.c.column(g).iter().copied());
            v + 2.0 * hi.dot(&cg) + self.pbb[(g, g)] + (1.0 - self.fraction) * r
        } else {
            v + r
        }
    }

    /// [`RangeStates::row_variance`] of pseudorange row `i` (satellite `g`) as it would be
    /// after [`RangeStates::restart`]`(g)`: no correlation, the stationary variance.
    pub fn restarted_row_variance(
        &self,
        kf: &ErrorFilter<NX>,
        h: &DMatrix<f64>,
        i: usize,
        r: f64,
        g: usize,
    ) -> f64 {
        kf.row_variance(h, i) + self.var[g] + (1.0 - self.fraction) * r
    }

    /// The sequential update of the rows `h` with residuals `res` (corrected) and white-model
    /// variances `r_diag`, not committed, and the global statistic `Σ νᵢ²/sᵢ`: the scalar
    /// row updates of [`crate::kalman::KalmanFilter::sequential_pending`] on the augmented
    /// state (zero: the error state after each feedback) and covariance.
    pub fn sequential(
        &self,
        kf: &ErrorFilter<NX>,
        res: &DVector<f64>,
        h: &DMatrix<f64>,
        r_diag: &[f64],
        row_sats: &[usize],
        ranges: usize,
    ) -> Result<(Pending, f64)> {
        let ha = self.rows(h, row_sats, ranges);
        let white: Vec<f64> = r_diag
            .iter()
            .enumerate()
            .map(|(i, &r)| self.white(i, ranges, r))
            .collect();
        let (dx, p, lambda) = crate::kalman::sequential_rows(
            DVector::zeros(ha.ncols()),
            self.joint(kf),
            res,
            &ha,
            &white,
            "a tight update with range-error states",
        )?;
        Ok((Pending::Augmented(p, dx), lambda))
    }

    /// Commit an augmented update (covariance `p`, estimate `dx`) into the error filter, the
    /// state `s` and these states.
    fn commit(
        &mut self,
        kf: &mut ErrorFilter<NX>,
        s: &mut NavState,
        p: &DMatrix<f64>,
        dx: &DVector<f64>,
    ) {
        let n = self.b.len();
        kf.p = SMatrix::<f64, NX, NX>::from_iterator(p.view((0, 0), (NX, NX)).iter().copied());
        self.c.copy_from(&p.view((0, NX), (NX, n)));
        self.pbb.copy_from(&p.view((NX, NX), (n, n)));
        let dxn = SVector::<f64, NX>::from_iterator(dx.rows(0, NX).iter().copied());
        kf.feedback(s, &dxn);
        self.b -= dx.rows(NX, n);
    }
}

/// The innovation variance of row `i` of `h` (white-model variance `r`; a pseudorange of
/// satellite `g` when `range`) with or without range-error states `gm`
/// ([`RangeStates::row_variance`], or `h_i P h_iᵀ + r`).
pub fn row_variance(
    kf: &ErrorFilter<NX>,
    gm: Option<&RangeStates>,
    h: &DMatrix<f64>,
    i: usize,
    r: f64,
    g: usize,
    range: bool,
) -> f64 {
    match gm {
        Some(gm) => gm.row_variance(kf, h, i, r, g, range),
        None => kf.row_variance(h, i) + r,
    }
}

/// The update of rows `h` (residuals `res`, white-model variances `r_diag`, satellites
/// `row_sats` of the first `ranges` rows, the pseudoranges) with or without range-error
/// states `gm`: the pending update and the global statistic. The residuals must already carry
/// the states' correction ([`RangeStates::correct`]).
pub fn sequential(
    kf: &ErrorFilter<NX>,
    gm: Option<&RangeStates>,
    res: &DVector<f64>,
    h: &DMatrix<f64>,
    r_diag: &[f64],
    row_sats: &[usize],
    ranges: usize,
) -> Result<(Pending, f64)> {
    match gm {
        Some(g) => g.sequential(kf, res, h, r_diag, row_sats, ranges),
        None => {
            let (p, dx, lambda) = kf.sequential(res, h, r_diag)?;
            Ok((Pending::White(Box::new(p), dx), lambda))
        }
    }
}

/// Commit `up` ([`sequential`]) into `kf`, `s` and `gm`; an update must be committed with the
/// states (or their absence) it was computed with.
pub fn commit(
    kf: &mut ErrorFilter<NX>,
    gm: Option<&mut RangeStates>,
    s: &mut NavState,
    up: Pending,
) -> Result<()> {
    match (gm, up) {
        (Some(g), Pending::Augmented(p, dx)) => g.commit(kf, s, &p, &dx),
        (None, Pending::White(p, dx)) => {
            kf.p = *p;
            kf.feedback(s, &dx);
        }
        _ => {
            return Err(Error::Invalid(
                "an update committed with other range-error states than it was computed with"
                    .into(),
            ))
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ins::error_filter::{CB, R};
    use nalgebra::{UnitQuaternion, Vector3};
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    fn filter() -> ErrorFilter<NX> {
        let noise = crate::ins::error_filter::tests::noise();
        let mut kf =
            ErrorFilter::<NX>::new(3.0, 0.3, Vector3::repeat(0.01), Vector3::zeros(), noise)
                .with_clock([0.0; 3], [10.0, 10.0, 1.0], (0.1, 0.1));
        kf.track_transition();
        kf
    }

    fn state() -> NavState {
        NavState {
            lat: 0.7,
            lon: 0.2,
            h: 100.0,
            v: Vector3::zeros(),
            q: UnitQuaternion::identity(),
        }
    }

    #[test]
    fn the_sequential_update_is_the_batch_kalman_update_of_the_augmented_state() {
        let kf = filter();
        let mut gm = RangeStates::new(4, 0.6, 10.0, 0.0).unwrap();
        let mut kf2 = kf.clone();
        gm.propagate(&mut kf2, 0.0, &[0, 1, 2, 3], &[1.0, 1.5, 2.0, 1.2]);
        gm.propagate(&mut kf2, 1.0, &[0, 1, 2, 3], &[1.0, 1.5, 2.0, 1.2]);
        // Four pseudoranges on position and clock, two rates on velocity.
        let sats = [0usize, 1, 2, 3, 0, 2];
        let mut h = DMatrix::zeros(6, NX);
        for (i, e) in [
            [0.3, 0.4, -0.866],
            [-0.5, 0.2, -0.84],
            [0.1, -0.7, -0.7],
            [0.8, 0.1, -0.59],
        ]
        .iter()
        .enumerate()
        {
            for q in 0..3 {
                h[(i, R + q)] = -e[q];
            }
            h[(i, CB)] = 1.0;
        }
        h[(4, 3)] = -0.3;
        h[(5, 4)] = 0.7;
        let res = DVector::from_column_slice(&[1.2, -0.4, 2.5, 0.3, 0.05, -0.02]);
        let r = [1.0, 2.25, 4.0, 1.44, 0.01, 0.02];
        let (up, lambda) = gm.sequential(&kf2, &res, &h, &r, &sats, 4).unwrap();
        let Pending::Augmented(p, dx) = up else {
            panic!("augmented")
        };
        // Batch: S = Ha P Haᵀ + R (white parts), K = P Haᵀ S⁻¹.
        let ha = gm.rows(&h, &sats, 4);
        let p0 = gm.joint(&kf2);
        let s = gm.innovation_cov(&kf2, &h, &r, &sats, 4);
        let si = s.clone().try_inverse().unwrap();
        let k = &p0 * ha.transpose() * &si;
        let pb = &p0 - &k * &s * k.transpose();
        let dxb = &k * &res;
        assert!((lambda - (res.transpose() * &si * &res)[0]).abs() < 1e-9 * lambda.max(1.0));
        assert!((&p - &pb).abs().max() < 1e-9, "{}", (&p - &pb).abs().max());
        assert!((&dx - &dxb).abs().max() < 1e-9);
        // The pseudoranges' white part is (1 − a) of their variance; the rates keep theirs.
        assert!(
            (s[(0, 0)] - (ha.row(0) * &p0 * ha.row(0).transpose())[0] - 0.4 * 1.0).abs() < 1e-12
        );
        assert!((s[(4, 4)] - (ha.row(4) * &p0 * ha.row(4).transpose())[0] - 0.01).abs() < 1e-12);
        // row_variance is the diagonal of S.
        for i in 0..6 {
            let v = gm.row_variance(&kf2, &h, i, r[i], sats[i], i < 4);
            assert!((v - s[(i, i)]).abs() < 1e-9, "row {i}");
        }
    }

    /// Range errors = Gauss-Markov (a = 0.7, τ = 5 epochs) + white: with the states the
    /// normalised innovations are white with unit variance; a white model of the same total
    /// variance gives correlated ones. The estimates follow the true range errors.
    #[test]
    fn the_states_whiten_gauss_markov_range_errors_and_track_them() {
        let (a, tau, sig) = (0.7, 5.0, 2.0);
        let n_sat = 4;
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut kf = filter();
        let mut s = state();
        let mut gm = RangeStates::new(n_sat, a, tau, 0.0).unwrap();
        let psi: f64 = (-1.0 / tau).exp();
        let mut b: Vec<f64> = (0..n_sat)
            .map(|_| {
                let w: f64 = StandardNormal.sample(&mut rng);
                (a * sig * sig).sqrt() * w
            })
            .collect::<Vec<f64>>();
        let (mut z_gm, mut z_white) = (Vec::new(), Vec::new());
        let (mut err2, mut count) = (0.0, 0);
        // Rows see only the range errors (no navigation columns): the estimate is the states'.
        let h = DMatrix::zeros(n_sat, NX);
        let sats: Vec<usize> = (0..n_sat).collect();
        let sigma = vec![sig; n_sat];
        for k in 1..4000 {
            for bj in b.iter_mut() {
                let w: f64 = StandardNormal.sample(&mut rng);
                *bj = psi * *bj + (a * (1.0 - psi * psi)).sqrt() * sig * w;
            }
            let z: Vec<f64> = b
                .iter()
                .map(|bj| {
                    let w: f64 = StandardNormal.sample(&mut rng);
                    bj + ((1.0 - a) * sig * sig).sqrt() * w
                })
                .collect();
            gm.propagate(&mut kf, k as f64, &sats, &sigma);
            let mut res = DVector::from_iterator(n_sat, z.iter().map(|x| -x));
            gm.correct(&mut res, &sats, n_sat);
            for j in 0..n_sat {
                let v = gm.row_variance(&kf, &h, j, sig * sig, j, true);
                z_gm.push(res[j] / v.sqrt());
                z_white.push(-z[j] / sig);
            }
            let r = vec![sig * sig; n_sat];
            let (up, _) = sequential(&kf, Some(&gm), &res, &h, &r, &sats, n_sat).unwrap();
            commit(&mut kf, Some(&mut gm), &mut s, up).unwrap();
            if k > 100 {
                for (j, bj) in b.iter().enumerate() {
                    err2 += (gm.bias(j) - bj).powi(2);
                    count += 1;
                }
            }
        }
        let var = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64;
        // Lag-1 correlation per satellite (the series are interleaved by satellite).
        let lag1 = |x: &[f64]| {
            let (mut num, mut den) = (0.0, 0.0);
            for i in n_sat..x.len() {
                num += x[i] * x[i - n_sat];
                den += x[i] * x[i];
            }
            num / den
        };
        assert!((var(&z_gm) - 1.0).abs() < 0.08, "variance {}", var(&z_gm));
        assert!(lag1(&z_gm).abs() < 0.05, "lag-1 {}", lag1(&z_gm));
        assert!(lag1(&z_white) > 0.5, "white model lag-1 {}", lag1(&z_white));
        // The estimate is better than no estimate (a σ² = 2.8 m²).
        let mse = err2 / count as f64;
        assert!(mse < 0.6 * a * sig * sig, "mse {mse}");
    }

    #[test]
    fn propagation_decays_to_the_stationary_variance_and_refuses_bad_settings() {
        let mut kf = filter();
        let mut gm = RangeStates::new(2, 0.5, 4.0, 0.0).unwrap();
        gm.propagate(&mut kf, 0.0, &[1], &[2.0]);
        assert_eq!(gm.sigma(0), 0.0);
        assert!((gm.sigma(1) - 2.0f64.sqrt()).abs() < 1e-12);
        gm.b[1] = 3.0;
        gm.pbb[(1, 1)] = 0.1;
        gm.propagate(&mut kf, 4.0, &[1], &[2.0]);
        assert!((gm.bias(1) - 3.0 * (-1.0f64).exp()).abs() < 1e-12);
        let psi2 = (-2.0f64).exp();
        assert!((gm.pbb[(1, 1)] - (0.1 * psi2 + (1.0 - psi2) * 2.0)).abs() < 1e-12);
        gm.c[(3, 1)] = 0.2;
        gm.pbb[(0, 1)] = 0.05;
        let h = DMatrix::from_fn(1, NX, |_, j| if j < 6 { 0.3 } else { 0.0 });
        let before = gm.restarted_row_variance(&kf, &h, 0, 1.5, 1);
        assert!(gm.row_variance(&kf, &h, 0, 1.5, 1, true) != before);
        gm.restart(1);
        assert!((gm.row_variance(&kf, &h, 0, 1.5, 1, true) - before).abs() < 1e-12);
        // An update is committed with the states it was computed with.
        let res = DVector::from_element(1, 0.5);
        let (up, _) = sequential(&kf, None, &res, &h, &[1.5], &[1], 1).unwrap();
        let mut s = state();
        assert!(commit(&mut kf, Some(&mut gm), &mut s, up).is_err());
        assert_eq!(
            (gm.bias(1), gm.c[(3, 1)], gm.pbb[(0, 1)], gm.pbb[(1, 0)]),
            (0.0, 0.0, 0.0, 0.0)
        );
        assert!((gm.sigma(1) - 2.0f64.sqrt()).abs() < 1e-12);
        assert!(RangeStates::new(2, 1.0, 4.0, 0.0).is_err());
        assert!(RangeStates::new(2, 0.5, 0.0, 0.0).is_err());
        assert!(RangeStates::new(2, -0.1, 4.0, 0.0).is_err());
    }
}
