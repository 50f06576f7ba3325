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
                if prep.models.available[si][k] && m > 0 {
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
