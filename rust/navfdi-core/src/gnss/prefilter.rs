//! Channel prefilter of an ultra-tight (vector-tracking) receiver (paper 004, METHODS §11),
//! and the thermal-noise variances of the code and frequency discriminators that measure it.
//!
//! Per tracked satellite a 3-state Kalman filter on the tracking errors of the channel's
//! replica: code-phase error `τ` (chips), carrier-frequency error `δf` (Hz) and its rate
//! `δḟ` (Hz/s), with
//!
//! ```text
//! Φ = [[1, βT, βT²/2], [0, 1, T], [0, 0, 1]],   β = f_code / f_carrier,
//! ```
//!
//! propagated every coherent integration `T` (20 ms: 50 Hz) and updated by the delay-lock
//! (code) and frequency-lock (carrier) discriminator outputs `z = [τ + v_τ, δf + v_f]`, whose
//! noise follows the channel's C/N0 ([`dll_variance`], [`fll_variance`]). Process noise: a
//! random walk of `δḟ` with spectral density `jerk_psd` (Hz²/s³, the line-of-sight jerk and
//! the clock) and optionally of `τ` (`code_psd`, chips²/s: code-carrier divergence), the
//! discrete `Q` of the continuous white-noise model integrated exactly over `T`.
//!
//! Everything is fixed-size (3 × 3, 2 × 2) so a step costs a few hundred nanoseconds: the
//! paper's run is 8 channels × 12 500 steps per method.

use crate::error::{Error, Result};
use nalgebra::{Matrix2, Matrix2x3, Matrix3, Vector2, Vector3};

/// GPS L1 C/A code chipping rate (chips/s).
pub const F_CODE_L1CA: f64 = 1.023e6;
/// GPS L1 carrier frequency (Hz).
pub const F_CARRIER_L1: f64 = 1575.42e6;

/// C/N0 (dB-Hz) → ratio (Hz), checked to a plausible receiver range.
fn cn0_ratio(name: &str, cn0_dbhz: f64) -> Result<f64> {
    if !(cn0_dbhz.is_finite() && (0.0..=80.0).contains(&cn0_dbhz)) {
        return Err(Error::InvalidParameter {
            name: name.into(),
            value: cn0_dbhz,
            requirement: "C/N0 must be between 0 and 80 dB-Hz".into(),
        });
    }
    Ok(10f64.powf(cn0_dbhz / 10.0))
}

fn positive(name: &str, v: f64, requirement: &str) -> Result<()> {
    if v > 0.0 && v.is_finite() {
        Ok(())
    } else {
        Err(Error::InvalidParameter {
            name: name.into(),
            value: v,
            requirement: requirement.into(),
        })
    }
}

/// Variance (chips²) of one output of a noncoherent early-minus-late power delay
/// discriminator (normalised) after coherent integration `t` (s), with early-late spacing
/// `spacing` (chips, in (0, 2)), at `cn0_dbhz`: Kaplan & Hegarty, *Understanding GPS*, 2nd ed.
/// (2006), eq. 5.71, `σ² = B d / (2 C/N0) · (1 + 2 / ((2 − d) T C/N0))`, with the bandwidth of
/// a single output, `B = 1/(2T)`.
pub fn dll_variance(cn0_dbhz: f64, t: f64, spacing: f64) -> Result<f64> {
    let c = cn0_ratio("cn0", cn0_dbhz)?;
    positive("t", t, "the coherent integration time must be positive (s)")?;
    if !(spacing > 0.0 && spacing < 2.0) {
        return Err(Error::InvalidParameter {
            name: "spacing".into(),
            value: spacing,
            requirement: "the early-late spacing must be in (0, 2) chips".into(),
        });
    }
    let b = 1.0 / (2.0 * t);
    Ok(b * spacing / (2.0 * c) * (1.0 + 2.0 / ((2.0 - spacing) * t * c)))
}

/// Variance (Hz²) of one output of a cross-product (or ATAN2) frequency discriminator after
/// coherent integration `t` (s) at `cn0_dbhz`: Kaplan & Hegarty (2006), eq. 5.64,
/// `σ = 1/(2πT) · sqrt(4 F B / (C/N0) · (1 + 1/(T C/N0)))`, with `B = 1/(2T)` and `F = 1`
/// (high C/N0; 2 near the tracking threshold, `high_noise = true`).
pub fn fll_variance(cn0_dbhz: f64, t: f64, high_noise: bool) -> Result<f64> {
    let c = cn0_ratio("cn0", cn0_dbhz)?;
    positive("t", t, "the coherent integration time must be positive (s)")?;
    let f = if high_noise { 2.0 } else { 1.0 };
    let b = 1.0 / (2.0 * t);
    let k = 1.0 / (2.0 * std::f64::consts::PI * t);
    Ok(k * k * 4.0 * f * b / c * (1.0 + 1.0 / (t * c)))
}

/// Configuration of a [`Prefilter`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PrefilterConfig {
    /// Coherent integration time T (s): the step.
    pub t: f64,
    /// `β = f_code / f_carrier` (chips per carrier cycle).
    pub beta: f64,
    /// Spectral density of the frequency-rate random walk (Hz²/s³).
    pub jerk_psd: f64,
    /// Spectral density of a code-phase random walk (chips²/s); 0: none.
    pub code_psd: f64,
    /// Early-late spacing of the delay discriminator (chips).
    pub spacing: f64,
}

impl Default for PrefilterConfig {
    /// GPS L1 C/A, 20 ms, 1-chip spacing, jerk PSD 1 Hz²/s³, no code random walk.
    fn default() -> Self {
        PrefilterConfig {
            t: 0.02,
            beta: F_CODE_L1CA / F_CARRIER_L1,
            jerk_psd: 1.0,
            code_psd: 0.0,
            spacing: 1.0,
        }
    }
}

impl PrefilterConfig {
    /// Check every field (named in the error).
    pub fn validate(&self) -> Result<()> {
        positive(
            "t",
            self.t,
            "the coherent integration time must be positive (s)",
        )?;
        if self.t > 1.0 {
            return Err(Error::InvalidParameter {
                name: "t".into(),
                value: self.t,
                requirement: "a coherent integration longer than 1 s is not a tracking loop".into(),
            });
        }
        positive("beta", self.beta, "β = f_code / f_carrier must be positive")?;
        for (name, v) in [("jerk_psd", self.jerk_psd), ("code_psd", self.code_psd)] {
            if !(v >= 0.0 && v.is_finite()) {
                return Err(Error::InvalidParameter {
                    name: name.into(),
                    value: v,
                    requirement: "a spectral density must be finite and >= 0".into(),
                });
            }
        }
        if !(self.spacing > 0.0 && self.spacing < 2.0) {
            return Err(Error::InvalidParameter {
                name: "spacing".into(),
                value: self.spacing,
                requirement: "the early-late spacing must be in (0, 2) chips".into(),
            });
        }
        Ok(())
    }

    /// `Φ` over one step.
    pub fn phi(&self) -> Matrix3<f64> {
        let (t, b) = (self.t, self.beta);
        Matrix3::new(1.0, b * t, b * t * t / 2.0, 0.0, 1.0, t, 0.0, 0.0, 1.0)
    }

    /// Discrete process noise over one step: the exact integral of `Φ(s) G q Gᵀ Φ(s)ᵀ` for a
    /// white `δf̈` (jerk) of density `jerk_psd`, plus `code_psd · T` on `τ`.
    pub fn q(&self) -> Matrix3<f64> {
        let (t, b, q) = (self.t, self.beta, self.jerk_psd);
        let t2 = t * t;
        let t3 = t2 * t;
        let mut m = Matrix3::new(
            b * b * t3 * t2 / 20.0,
            b * t2 * t2 / 8.0,
            b * t3 / 6.0,
            b * t2 * t2 / 8.0,
            t3 / 3.0,
            t2 / 2.0,
            b * t3 / 6.0,
            t2 / 2.0,
            t,
        ) * q;
        m[(0, 0)] += self.code_psd * t;
        m
    }
}

/// One step's innovation of a [`Prefilter`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PrefilterStep {
    /// Innovation `r = z − Hx⁻` (chips, Hz); NaN where a discriminator gave no output.
    pub residual: Vector2<f64>,
    /// Its covariance `A = HP⁻Hᵀ + R` (NaN rows/columns where unused).
    pub covariance: Matrix2<f64>,
    /// `λ = rᵀA⁻¹r` over the used components (NaN when none).
    pub statistic: f64,
    /// Components used.
    pub dof: usize,
}

/// A channel prefilter (see the module docs).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Prefilter {
    cfg: PrefilterConfig,
    phi: Matrix3<f64>,
    q: Matrix3<f64>,
    x: Vector3<f64>,
    p: Matrix3<f64>,
}

impl Prefilter {
    /// A prefilter with state `x0` (chips, Hz, Hz/s) and covariance `p0` (symmetric, positive
    /// semi-definite, finite).
    pub fn new(cfg: PrefilterConfig, x0: Vector3<f64>, p0: Matrix3<f64>) -> Result<Self> {
        cfg.validate()?;
        if x0.iter().any(|v| !v.is_finite()) {
            return Err(Error::Invalid("x0: every component must be finite".into()));
        }
        check_cov3("P0", &p0)?;
        Ok(Prefilter {
            phi: cfg.phi(),
            q: cfg.q(),
            cfg,
            x: x0,
            p: p0,
        })
    }

    /// Check that a deserialised prefilter is self-consistent (its Φ and Q follow from its
    /// configuration, its state is finite), so a tampered pickle cannot smuggle in NaN.
    pub fn check_consistent(&self) -> Result<()> {
        self.cfg.validate()?;
        if self.phi != self.cfg.phi() || self.q != self.cfg.q() {
            return Err(Error::Invalid(
                "Φ and Q do not follow from the configuration".into(),
            ));
        }
        if self.x.iter().any(|v| !v.is_finite()) {
            return Err(Error::Invalid("x: every component must be finite".into()));
        }
        check_cov3("P", &self.p)
    }

    /// Configuration.
    pub fn config(&self) -> &PrefilterConfig {
        &self.cfg
    }

    /// State (chips, Hz, Hz/s).
    pub fn x(&self) -> &Vector3<f64> {
        &self.x
    }

    /// Covariance.
    pub fn p(&self) -> &Matrix3<f64> {
        &self.p
    }

    /// Shift the state by `dx` (e.g. the replica correction of vector tracking: the errors
    /// are relative to the replica, so moving the replica by `d` moves them by `−d`).
    pub fn shift(&mut self, dx: &Vector3<f64>) -> Result<()> {
        if dx.iter().any(|v| !v.is_finite()) {
            return Err(Error::Invalid("dx: every component must be finite".into()));
        }
        self.x += dx;
        Ok(())
    }

    /// One integration: predict over `T`, then update with the code discriminator output
    /// `z_code` (chips) and the frequency discriminator output `z_freq` (Hz), either NaN when
    /// absent, whose variances follow `cn0_dbhz` ([`dll_variance`], [`fll_variance`] with
    /// F = 1). Test before update: the returned innovation is the one the update used. Bad
    /// input changes nothing.
    pub fn step(&mut self, z_code: f64, z_freq: f64, cn0_dbhz: f64) -> Result<PrefilterStep> {
        for (name, v) in [("z_code", z_code), ("z_freq", z_freq)] {
            if v.is_infinite() {
                return Err(Error::NonFinite {
                    name: name.into(),
                    index: "".into(),
                    value: v,
                });
            }
        }
        let r = Vector2::new(
            dll_variance(cn0_dbhz, self.cfg.t, self.cfg.spacing)?,
            fll_variance(cn0_dbhz, self.cfg.t, false)?,
        );
        Ok(self.step_with(Vector2::new(z_code, z_freq), r))
    }

    /// [`Prefilter::step`] with the discriminator variances `r` (chips², Hz²) given and no
    /// validation (inside whole runs).
    pub fn step_with(&mut self, z: Vector2<f64>, r: Vector2<f64>) -> PrefilterStep {
        // Predict.
        self.x = self.phi * self.x;
        self.p = self.phi * self.p * self.phi.transpose() + self.q;
        let used = [!z[0].is_nan(), !z[1].is_nan()];
        let dof = used.iter().filter(|u| **u).count();
        // H = [I₂ 0]: HP⁻Hᵀ is the top-left 2 × 2 of P⁻.
        let mut a = self.p.fixed_view::<2, 2>(0, 0).into_owned();
        a[(0, 0)] += r[0];
        a[(1, 1)] += r[1];
        let resid = Vector2::new(z[0] - self.x[0], z[1] - self.x[1]);
        let mut out = PrefilterStep {
            residual: resid,
            covariance: a,
            statistic: f64::NAN,
            dof,
        };
        for (i, _) in used.iter().enumerate().filter(|(_, u)| !**u) {
            for j in 0..2 {
                out.covariance[(i, j)] = f64::NAN;
                out.covariance[(j, i)] = f64::NAN;
            }
        }
        match used {
            [true, true] => {
                let Some(chol) = a.cholesky() else {
                    return out;
                };
                let ai = chol.inverse();
                out.statistic = resid.dot(&(ai * resid));
                // K = P⁻Hᵀ A⁻¹; Joseph form with H = [I₂ 0].
                let pht = self.p.fixed_view::<3, 2>(0, 0).into_owned();
                let k = pht * ai;
                self.x += k * resid;
                let mut h = Matrix2x3::zeros();
                h[(0, 0)] = 1.0;
                h[(1, 1)] = 1.0;
                let ikh = Matrix3::identity() - k * h;
                let rk = k * Matrix2::from_diagonal(&r) * k.transpose();
                self.p = ikh * self.p * ikh.transpose() + rk;
            }
            [true, false] | [false, true] => {
                let i = usize::from(used[1]);
                let ai = a[(i, i)];
                if !(ai > 0.0) {
                    return out;
                }
                out.statistic = resid[i] * resid[i] / ai;
                let ph = self.p.column(i).into_owned();
                let k: Vector3<f64> = ph / ai;
                self.x += k * resid[i];
                let mut ikh = Matrix3::<f64>::identity();
                for row in 0..3 {
                    ikh[(row, i)] -= k[row];
                }
                self.p = ikh * self.p * ikh.transpose() + k * k.transpose() * r[i];
            }
            [false, false] => {}
        }
        self.p = (self.p + self.p.transpose()) * 0.5;
        out
    }
}

/// [`crate::validate::check_covariance`] of a 3 × 3 covariance.
fn check_cov3(name: &str, p: &Matrix3<f64>) -> Result<()> {
    crate::validate::check_covariance(
        name,
        &nalgebra::DMatrix::from_column_slice(3, 3, p.as_slice()),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn discriminator_noise_at_48_and_28_dbhz() {
        // 48 dB-Hz, 20 ms, 1 chip: σ_DLL = 0.0141 chips (≈ 4.1 m), σ_FLL = 0.317 Hz.
        let d = dll_variance(48.0, 0.02, 1.0).unwrap().sqrt();
        let f = fll_variance(48.0, 0.02, false).unwrap().sqrt();
        assert!((d - 0.014_09).abs() < 1e-4, "{d}");
        assert!((f - 0.3168).abs() < 1e-3, "{f}");
        // 20 dB weaker: about 10× the σ plus the squaring loss.
        let d28 = dll_variance(28.0, 0.02, 1.0).unwrap().sqrt();
        assert!(d28 / d > 10.0 && d28 / d < 11.5, "{}", d28 / d);
        assert!(dll_variance(90.0, 0.02, 1.0).is_err());
        assert!(dll_variance(48.0, 0.02, 2.0).is_err());
        assert!(fll_variance(48.0, 0.0, false).is_err());
    }

    #[test]
    fn q_is_the_integral_of_the_continuous_model() {
        // Numerical integral of Φ(s) G Gᵀ Φ(s)ᵀ over [0, T] against the closed form.
        let cfg = PrefilterConfig {
            jerk_psd: 2.0,
            ..Default::default()
        };
        let n = 20_000;
        let mut acc = Matrix3::zeros();
        for i in 0..n {
            let s = (i as f64 + 0.5) * cfg.t / n as f64;
            let c = PrefilterConfig { t: s, ..cfg };
            let g = c.phi().column(2).into_owned();
            acc += g * g.transpose() * (cfg.jerk_psd * cfg.t / n as f64);
        }
        let q = cfg.q();
        for (a, b) in acc.iter().zip(q.iter()) {
            assert!((a - b).abs() <= 1e-6 * b.abs().max(1e-30), "{a} {b}");
        }
    }
}
