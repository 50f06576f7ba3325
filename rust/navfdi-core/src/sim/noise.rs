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
    /// Per sensor and epoch: the measurement (NaN when not taken).
    pub z: Vec<Vec<DVector<f64>>>,
}

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
    for k in 0..epochs {
        if k > 0 {
            let w = &prep.q_factor[k] * normals(&mut rng, n);
            x = &prep.phi[k] * &x + w;
        }
        for (si, s) in prep.spec.sensors.iter().enumerate() {
            let m = s.noise.len();
            let v = normals(&mut rng, m);
            if prep.available[si][k] {
                let mut zk = &prep.h[si][k] * &x + &prep.fault[si][k];
                for c in 0..m {
                    zk[c] += s.noise[c] * v[c];
                }
                z[si].push(zk);
            } else {
                z[si].push(DVector::from_element(m, f64::NAN));
            }
        }
        x_true.push(x.clone());
    }
    Simulated { x_true, z }
}
