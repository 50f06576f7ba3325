//! One run's randomness: the true INS error trajectory and the sensor measurements.
//!
//! The generator is ChaCha8 seeded with `seed` on stream `stream` (the Monte-Carlo run
//! index), and the draws happen in a fixed order (initial error, then per epoch: process
//! noise, then each sensor's noise, drawn whether or not the sensor measures), so a run's
//! numbers depend only on `(seed, stream)`.

use super::prepare::Prepared;
use crate::gnss::geodesy::ecef_to_enu;
use crate::ins::{earth, POS};
use crate::stream::{Measurements, Reference, Streams};
use nalgebra::{DVector, Vector3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Simulated truth and measurements of one run.
#[derive(Debug, Clone)]
pub struct Simulated {
    /// The measurements: per sensor `z = H x + f + ε` (NaN when not taken); for a
    /// `gnss_ranges` sensor the tight measurements of the satellites in view, the raw
    /// pseudoranges and rates (sharing their noise) and the INS position they are predicted
    /// from (truth + the run's INS error).
    pub meas: Measurements,
    /// True INS error state per epoch (15 or 17).
    pub reference: Reference,
    /// The run's seed and stream (architectures that draw more noise of their own, such as
    /// the ultra-tight discriminators, derive their generator from them).
    pub seed: u64,
    /// See [`Simulated::seed`].
    pub stream: u64,
}

impl Simulated {
    /// The run's measurement streams over the prepared models, with the truth as reference.
    pub fn streams<'a>(&'a self, prep: &'a Prepared) -> Streams<'a> {
        Streams {
            models: &prep.models,
            meas: &self.meas,
            reference: Some(&self.reference),
            seed: self.seed,
            stream: self.stream,
        }
    }
}

/// The INS position (ECEF, m) of a run at epoch `k`: the truth displaced by the run's true
/// INS position error `x` (δL, δλ, δh).
fn ins_position(prep: &Prepared, k: usize, x: &DVector<f64>, rx: &Vector3<f64>) -> Vector3<f64> {
    let tr = &prep.truth[k];
    let rm = earth::r_meridian(tr.lat) + tr.h;
    let rn = earth::r_normal(tr.lat) + tr.h;
    let d_enu = Vector3::new(x[POS + 1] * rn * tr.lat.cos(), x[POS] * rm, x[POS + 2]);
    rx + ecef_to_enu(tr.lat, tr.lon).transpose() * d_enu
}

/// Stream offset of the per-run sensor offsets.
const BIAS_STREAM: u64 = 0x00B1_A50F_F5E7;

/// Stream offset of the correlated range errors.
const RANGE_GM_STREAM: u64 = 0x6A55_C0EE_0E44;

/// Unit-variance first-order Gauss-Markov processes, one per satellite of a constellation,
/// drawn from their own ChaCha8 stream (so a run without them draws what it drew before):
/// `g(t + Δt) = e^(−Δt/τ) g(t) + √(1 − e^(−2Δt/τ)) w`, started from the stationary law.
#[derive(Debug, Clone)]
pub struct UnitMarkov {
    rng: ChaCha8Rng,
    tau: f64,
    t: f64,
    /// The processes' values at the last time advanced to.
    pub g: Vec<f64>,
}

impl UnitMarkov {
    /// `n` processes of correlation time `tau` (s) at time `t0` (s), from `(seed, stream)`.
    pub fn new(n: usize, tau: f64, t0: f64, seed: u64, stream: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream ^ RANGE_GM_STREAM);
        let g = (0..n).map(|_| StandardNormal.sample(&mut rng)).collect();
        UnitMarkov { rng, tau, t: t0, g }
    }

    /// Advance every process to time `t` (s; not before the last).
    pub fn advance(&mut self, t: f64) {
        let dt = (t - self.t).max(0.0);
        self.t = t;
        if dt == 0.0 {
            return;
        }
        let phi = (-dt / self.tau).exp();
        let q = (1.0 - phi * phi).sqrt();
        for g in &mut self.g {
            let w: f64 = StandardNormal.sample(&mut self.rng);
            *g = phi * *g + q * w;
        }
    }
}

fn normals(rng: &mut ChaCha8Rng, n: usize) -> DVector<f64> {
    DVector::from_fn(n, |_, _| StandardNormal.sample(rng))
}

/// Draw one run.
pub fn simulate(prep: &Prepared, seed: u64, stream: u64) -> Simulated {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    let n = prep.models.p0.nrows();
    let epochs = prep.epochs();
    let mut x = &prep.p0_factor * normals(&mut rng, n);
    let mut x_true = Vec::with_capacity(epochs);
    let mut z: Vec<Vec<DVector<f64>>> = prep
        .spec
        .sensors
        .iter()
        .map(|_| Vec::with_capacity(epochs))
        .collect();
    let mut raw = Vec::new();
    let mut ins = Vec::new();
    // Per-run constant sensor offsets, from their own stream so that runs without them draw
    // exactly what they drew before offsets existed.
    let bias: Vec<DVector<f64>> = {
        let mut brng = ChaCha8Rng::seed_from_u64(seed);
        brng.set_stream(stream ^ BIAS_STREAM);
        prep.spec
            .sensors
            .iter()
            .map(|s| {
                let v = normals(&mut brng, s.bias.len());
                DVector::from_fn(s.bias.len(), |c, _| s.bias[c] * v[c])
            })
            .collect()
    };
    // Correlated pseudorange errors of the gnss_ranges sensor, where it asks for them.
    let mut range_gm = prep.models.ranges.as_ref().and_then(|rp| {
        let c = prep.spec.sensors[rp.sensor].ranges.as_ref()?.correlated?;
        let t0 = prep.models.t.first().copied().unwrap_or(0.0);
        let gm = UnitMarkov::new(rp.names.len(), c.tau, t0, seed, stream);
        Some((gm, (1.0 - c.fraction).sqrt(), c.fraction.sqrt()))
    });
    for k in 0..epochs {
        if k > 0 {
            let w = &prep.q_factor[k] * normals(&mut rng, n);
            x = &prep.models.phi[k] * &x + w;
        }
        for (si, s) in prep.spec.sensors.iter().enumerate() {
            if let Some(rp) = prep.models.ranges.as_ref().filter(|r| r.sensor == si) {
                // Two draws per satellite of the constellation, in view or not, so a run's
                // numbers do not depend on the geometry.
                let v = normals(&mut rng, 2 * rp.names.len());
                let ep = &rp.epochs[k];
                let m = ep.len();
                ins.push(ins_position(prep, k, &x, &ep.rx));
                if let Some((gm, _, _)) = range_gm.as_mut() {
                    gm.advance(prep.models.t[k]);
                }
                if prep.models.available[si][k] && m > 0 {
                    let mut zk = &ep.h * &x;
                    let mut rk = DVector::zeros(2 * m);
                    for j in 0..m {
                        let sat = ep.sats[j];
                        let unit = match &range_gm {
                            Some((gm, white, slow)) => white * v[2 * sat] + slow * gm.g[sat],
                            None => v[2 * sat],
                        };
                        let e_r = ep.sigma[j] * unit + ep.fault[j];
                        let e_d = ep.sigma_rate[j] * v[2 * sat + 1] + ep.fault[m + j];
                        zk[j] += e_r;
                        zk[m + j] += e_d;
                        rk[j] = ep.range[j] + x[crate::gnss::ranges::CLOCK_BIAS] + e_r;
                        rk[m + j] = ep.rate[j] + x[crate::gnss::ranges::CLOCK_DRIFT] + e_d;
                    }
                    z[si].push(zk);
                    raw.push(rk);
                } else {
                    z[si].push(DVector::zeros(0));
                    raw.push(DVector::zeros(0));
                }
                continue;
            }
            let m = s.noise.len();
            let v = normals(&mut rng, m);
            if prep.models.available[si][k] {
                let mut zk = &prep.models.h[si][k] * &x + &prep.fault[si][k];
                for c in 0..m {
                    let sd = match prep.models.r_epoch[si].get(k) {
                        Some(var) if c == 0 => var.sqrt(),
                        _ => s.noise[c],
                    };
                    zk[c] += sd * v[c] + bias[si].get(c).copied().unwrap_or(0.0);
                }
                z[si].push(zk);
            } else {
                z[si].push(DVector::from_element(m, f64::NAN));
            }
        }
        x_true.push(x.clone());
    }
    Simulated {
        meas: Measurements {
            z,
            raw,
            ins_position: ins,
        },
        reference: Reference {
            x_true,
            enu: Vec::new(),
            attitude: Vec::new(),
        },
        seed,
        stream,
    }
}

#[cfg(test)]
mod tests {
    use super::UnitMarkov;

    /// Unit variance, lag correlation e^(−L Δt / τ), and the same draws for the same stream.
    #[test]
    fn unit_markov_has_its_variance_and_correlation() {
        let (n, tau, dt) = (400, 5.0, 1.0);
        let mut gm = UnitMarkov::new(n, tau, 0.0, 3, 7);
        let mut again = UnitMarkov::new(n, tau, 0.0, 3, 7);
        let (mut var, mut lag1, mut lag5, mut count) = (0.0, 0.0, 0.0, 0.0);
        let mut hist: Vec<Vec<f64>> = Vec::new();
        for k in 0..300 {
            gm.advance(k as f64 * dt);
            again.advance(k as f64 * dt);
            assert_eq!(gm.g, again.g);
            hist.push(gm.g.clone());
            if k >= 5 {
                for ((g, g1), g5) in hist[k].iter().zip(&hist[k - 1]).zip(&hist[k - 5]) {
                    var += g * g;
                    lag1 += g * g1;
                    lag5 += g * g5;
                }
                count += n as f64;
            }
        }
        let (var, r1, r5) = (var / count, lag1 / count, lag5 / count);
        assert!((var - 1.0).abs() < 0.03, "variance {var}");
        assert!((r1 - (-dt / tau).exp()).abs() < 0.03, "lag 1: {r1}");
        assert!((r5 - (-5.0 * dt / tau).exp()).abs() < 0.03, "lag 5: {r5}");
    }
}
