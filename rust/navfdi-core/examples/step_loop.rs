//! A fixed number of filter steps (n = 15, m = 6, the benchmark problem), for deterministic
//! instruction counts where hardware counters are not available:
//!
//! ```text
//! cargo build --release --example step_loop
//! valgrind --tool=callgrind target/release/examples/step_loop 1200   # and 200; difference / 1000
//! target/release/examples/step_loop 1000000 step   # the fixed-model step (set_model, step)
//! ```
//!
//! Wall-clock timings on a shared machine vary by ±20 %; instruction counts do not.

#[path = "../../../benches/ins_problem.rs"]
mod ins_problem;

use navfdi_core::KalmanFilter;

fn main() {
    let (x0, p0, phi, q, h, r) = ins_problem::problem();
    let z = ins_problem::measurement();
    let mut kf = KalmanFilter::new(x0, p0).expect("valid P0");
    let iters: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1000);
    if std::env::args().nth(2).as_deref() == Some("step") {
        // The fixed-model step (`KalmanFilter.step` from Python).
        kf.set_model(phi, q, h, r).expect("valid model");
        for _ in 0..iters {
            std::hint::black_box(kf.step(&z).expect("step"));
        }
    } else {
        for _ in 0..iters {
            kf.predict_trusted(&phi, &q, 1.0).expect("predict");
            std::hint::black_box(kf.update_trusted(&z, &h, &r).expect("update"));
        }
    }
    println!("{}", kf.x()[0]);
}
