//! A fixed number of ARAIM epochs (`integrity::araim`, LPV-200, satellites alternating between
//! two constellations on the geometry of `benches/bench_integrity.py`), for deterministic
//! instruction counts:
//!
//! ```text
//! cargo build --release --example araim_loop
//! valgrind --tool=callgrind target/release/examples/araim_loop 40 30   # and 40 10; difference / 20
//! ```
//!
//! Arguments: satellites (default 40), epochs (default 1000). Prints the mean VPL and the wall
//! time per call (µs).

use navfdi_core::integrity::araim::{araim, Allocation, Ism};

fn main() {
    let arg = |k: usize, default: usize| {
        std::env::args()
            .nth(k)
            .and_then(|a| a.parse().ok())
            .unwrap_or(default)
    };
    let (n, iters) = (arg(1, 40).max(5), arg(2, 1000));
    let (mut rows, mut cons, mut c_int, mut c_acc) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for i in 0..n {
        let az = i as f64 * 2.399_963;
        let el = (10.0 + 75.0 * ((i * 7) % n) as f64 / (n - 1) as f64).to_radians();
        rows.push([-el.cos() * az.sin(), -el.cos() * az.cos(), -el.sin()]);
        cons.push(i % 2);
        // Troposphere (the ADD's model) and a user term, on σ_URA 0.75 m / σ_URE 0.5 m.
        let t = 0.12 * 1.001 / (0.002_001 + el.sin().powi(2)).sqrt();
        c_int.push(0.5625 + t * t + 0.1);
        c_acc.push(0.25 + t * t + 0.1);
    }
    let ism = Ism {
        c_int,
        c_acc,
        b_nom: vec![0.5; n],
        p_sat: vec![1e-5; n],
        p_const: vec![1e-4, 1e-4],
    };
    let alloc = Allocation::lpv200();
    let t = std::time::Instant::now();
    let mut vpl = 0.0;
    for _ in 0..iters {
        vpl += araim(&rows, &cons, &ism, &alloc)
            .expect("a solvable geometry")
            .vpl;
    }
    let per_call = t.elapsed().as_secs_f64() * 1e6 / iters.max(1) as f64;
    println!(
        "{n} satellites: mean VPL {:.4} m, {per_call:.1} µs per call",
        vpl / iters.max(1) as f64
    );
}
