//! Criterion benchmarks of the core filter step (n = 15 states, m = 6 measurements).
//!
//! `step_checked` is the validated public path (`predict` + `update`), `step_trusted` the path
//! used inside whole runs after validating the inputs once, and `run_filter_per_epoch` a
//! 10 000-epoch `run_filter` divided by the number of epochs (reference: `step_trusted`).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::{DMatrix, DVector};
use navfdi_core::run::{run_filter, MatrixSeq};
use navfdi_core::KalmanFilter;
use std::hint::black_box;

const N: usize = 15;
const M: usize = 6;

/// `x0, P0, Φ, Q, H, R`.
type Problem = (
    DVector<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
);

/// A deterministic INS-like error model at 1 Hz: attitude (0..3), velocity (3..6), position
/// (6..9), gyro drift (9..12), accelerometer bias (12..15); position and velocity measured.
fn problem() -> Problem {
    let dt = 1.0;
    let mut f = DMatrix::<f64>::zeros(N, N);
    // attitude ← gyro drift; velocity ← attitude × specific force (≈ g up) and accel bias;
    // position ← velocity; biases first-order Markov.
    for i in 0..3 {
        f[(i, 9 + i)] = -1.0;
        f[(3 + i, 12 + i)] = 1.0;
        f[(6 + i, 3 + i)] = 1.0;
        f[(9 + i, 9 + i)] = -1.0 / 3600.0;
        f[(12 + i, 12 + i)] = -1.0 / 1800.0;
    }
    f[(3, 1)] = -9.8;
    f[(4, 0)] = 9.8;
    let phi = DMatrix::identity(N, N) + &f * dt + &f * &f * (dt * dt / 2.0);
    let x0 = DVector::zeros(N);
    let mut p0 = DMatrix::zeros(N, N);
    let sd = [
        1e-3, 1e-3, 3e-3, 0.6, 0.6, 0.6, 50.0, 50.0, 50.0, 1e-6, 1e-6, 1e-6, 1e-3, 1e-3, 1e-3,
    ];
    for i in 0..N {
        p0[(i, i)] = sd[i] * sd[i];
    }
    let mut q = DMatrix::zeros(N, N);
    for i in 0..3 {
        q[(i, i)] = 1e-12;
        q[(3 + i, 3 + i)] = 1e-8;
        q[(9 + i, 9 + i)] = 1e-14;
        q[(12 + i, 12 + i)] = 1e-9;
    }
    let h = DMatrix::from_fn(M, N, |i, j| {
        if (i < 3 && j == 6 + i) || (i >= 3 && j == i) {
            1.0
        } else {
            0.0
        }
    });
    let r = DMatrix::from_diagonal(&DVector::from_vec(vec![25.0, 25.0, 25.0, 0.01, 0.01, 0.01]));
    (x0, p0, phi, q, h, r)
}

fn bench(c: &mut Criterion) {
    let (x0, p0, phi, q, h, r) = problem();
    let z = DVector::from_fn(M, |i, _| 0.1 * i as f64);
    let mut g = c.benchmark_group("core");
    g.throughput(Throughput::Elements(1));
    // A persistent filter stepped repeatedly (steady state, as inside a run).
    let base = KalmanFilter::new(x0.clone(), p0.clone()).unwrap();
    let mut kf = base.clone();
    g.bench_function("step_checked", |b| {
        b.iter(|| {
            kf.predict(&phi, &q, 1.0).unwrap();
            black_box(kf.update(&z, &h, &r).unwrap());
        })
    });
    let mut kf = base.clone();
    g.bench_function("step_trusted", |b| {
        b.iter(|| {
            kf.predict_trusted(&phi, &q, 1.0).unwrap();
            black_box(kf.update_trusted(&z, &h, &r).unwrap());
        })
    });
    let t = 10_000;
    let zs: Vec<f64> = (0..t * M)
        .map(|i| ((i * 37 % 101) as f64 - 50.0) / 50.0)
        .collect();
    let (phi_s, q_s, h_s, r_s) = (
        MatrixSeq::Const(phi.clone()),
        MatrixSeq::Const(q.clone()),
        MatrixSeq::Const(h.clone()),
        MatrixSeq::Const(r.clone()),
    );
    g.throughput(Throughput::Elements(t as u64));
    g.sample_size(20);
    g.bench_function("run_filter_10000_epochs", |b| {
        b.iter(|| {
            black_box(
                run_filter(
                    x0.clone(),
                    p0.clone(),
                    &phi_s,
                    &q_s,
                    &zs,
                    t,
                    &h_s,
                    &r_s,
                    1.0,
                )
                .unwrap(),
            )
        })
    });
    g.finish();
}

criterion_group!(benches, bench, parts);
criterion_main!(benches);

fn parts(c: &mut Criterion) {
    let (x0, p0, phi, q, h, r) = problem();
    let z = DVector::from_fn(M, |i, _| 0.1 * i as f64);
    let base = KalmanFilter::new(x0, p0).unwrap();
    let mut g = c.benchmark_group("parts");
    let mut kf = base.clone();
    g.bench_function("predict_trusted", |b| {
        b.iter(|| kf.predict_trusted(&phi, &q, 1.0).unwrap())
    });
    let mut kf = base.clone();
    g.bench_function("update_trusted", |b| {
        b.iter(|| black_box(kf.update_trusted(&z, &h, &r).unwrap()))
    });
    g.finish();
}
