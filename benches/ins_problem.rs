//! The Kalman benchmark problem, shared by `benches/core_step.rs` and
//! `rust/navfdi-core/examples/step_loop.rs` (the Python twin is `benches/problem.py`).

use nalgebra::{DMatrix, DVector};

/// State dimension.
pub const N: usize = 15;
/// Measurement dimension.
pub const M: usize = 6;

/// `x0, P0, Φ, Q, H, R`.
pub type Problem = (
    DVector<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
);

/// A deterministic INS-like error model at 1 Hz: attitude (0..3), velocity (3..6), position
/// (6..9), gyro drift (9..12), accelerometer bias (12..15); position and velocity measured.
pub fn problem() -> Problem {
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

/// The measurement used at every step.
pub fn measurement() -> DVector<f64> {
    DVector::from_fn(M, |i, _| 0.1 * i as f64)
}
