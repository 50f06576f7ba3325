//! A fixed number of filter steps (n = 15, m = 6, the benchmark problem), for deterministic
//! instruction counts where hardware counters are not available:
//!
//! ```text
//! cargo build --release --example step_loop
//! valgrind --tool=callgrind target/release/examples/step_loop 1200   # and 200; difference / 1000
//! ```
//!
//! Wall-clock timings on a shared machine vary by ±20 %; instruction counts do not.

use nalgebra::{DMatrix, DVector};
use navfdi_core::KalmanFilter;
fn main() {
    let n = 15;
    let m = 6;
    let mut f = DMatrix::<f64>::zeros(n, n);
    for i in 0..3 {
        f[(i, 9 + i)] = -1.0;
        f[(3 + i, 12 + i)] = 1.0;
        f[(6 + i, 3 + i)] = 1.0;
        f[(9 + i, 9 + i)] = -1.0 / 3600.0;
        f[(12 + i, 12 + i)] = -1.0 / 1800.0;
    }
    f[(3, 1)] = -9.8;
    f[(4, 0)] = 9.8;
    let phi = DMatrix::identity(n, n) + &f + &f * &f * 0.5;
    let p0 = DMatrix::from_diagonal(&DVector::from_fn(n, |i, _| 1.0 + i as f64));
    let q = DMatrix::from_diagonal(&DVector::from_element(n, 1e-6));
    let h = DMatrix::from_fn(m, n, |i, j| {
        if (i < 3 && j == 6 + i) || (i >= 3 && j == i) {
            1.0
        } else {
            0.0
        }
    });
    let r = DMatrix::identity(m, m);
    let z = DVector::from_fn(m, |i, _| 0.1 * i as f64);
    let mut kf = KalmanFilter::new(DVector::zeros(n), p0).expect("valid P0");
    let iters: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1000);
    for _ in 0..iters {
        kf.predict_trusted(&phi, &q, 1.0).expect("predict");
        std::hint::black_box(kf.update_trusted(&z, &h, &r).expect("update"));
    }
    println!("{}", kf.x()[0]);
}
