//! One run's randomness: the true INS error trajectory and the sensor measurements.
//!
//! The generator is ChaCha8 seeded with `seed` on stream `stream` (the Monte-Carlo run
//! index), and the draws happen in a fixed order (initial error, then per epoch: process
//! noise, then each sensor's noise, drawn whether or not the sensor measures), so a run's
//! numbers depend only on `(seed, stream)`.

use super::prepare::Prepared;
use nalgebra::DVector;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Simulated truth and measurements of one run.
#[derive(Debug, Clone)]
pub struct Simulated {
    /// True INS error state per epoch (15).
    pub x_true: Vec<DVector<f64>>,
    /// Per sensor and epoch: the measurement (NaN when not taken). For a `gnss_ranges` sensor
    /// the tight measurement `z = H x + ε + f` of the satellites in view (pseudoranges, then
    /// rates; empty when not taken).
    pub z: Vec<Vec<DVector<f64>>>,
    /// Raw observations of the `gnss_ranges` sensor per epoch: pseudoranges (m), then rates
    /// (m/s) of the satellites in view, sharing the noise of `z` (empty when not taken or
    /// without such a sensor).
    pub raw: Vec<DVector<f64>>,
    /// The run's seed and stream (architectures that draw more noise of their own, such as
    /// the ultra-tight discriminators, derive their generator from them).
    pub seed: u64,
    /// See [`Simulated::seed`].
    pub stream: u64,
}

/// Stream offset of the per-run sensor offsets.
const BIAS_STREAM: u64 = 0x00B1_A50F_F5E7;

fn normals(rng: &mut ChaCha8Rng, n: usize) -> DVector<f64> {
    DVector::from_fn(n, |_, _| StandardNormal.sample(rng))
}

/// Draw one run.
pub fn simulate(prep: &Prepared, seed: u64, stream: u64) -> Simulated {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    rng.set_stream(stream);
    let n = prep.p0.nrows();
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
    for k in 0..epochs {
        if k > 0 {
            let w = &prep.q_factor[k] * normals(&mut rng, n);
            x = &prep.phi[k] * &x + w;
        }
        for (si, s) in prep.spec.sensors.iter().enumerate() {
            if let Some(rp) = prep.ranges.as_ref().filter(|r| r.sensor == si) {
                // Two draws per satellite of the constellation, in view or not, so a run's
                // numbers do not depend on the geometry.
                let v = normals(&mut rng, 2 * rp.names.len());
                let ep = &rp.epochs[k];
                let m = ep.len();
                if prep.available[si][k] && m > 0 {
                    let mut zk = &ep.h * &x;
                    let mut rk = DVector::zeros(2 * m);
                    for j in 0..m {
                        let sat = ep.sats[j];
                        let e_r = ep.sigma[j] * v[2 * sat] + ep.fault[j];
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
            if prep.available[si][k] {
                let mut zk = &prep.h[si][k] * &x + &prep.fault[si][k];
                for c in 0..m {
                    let sd = match prep.r_epoch[si].get(k) {
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
        x_true,
        z,
        raw,
        seed,
        stream,
    }
}
