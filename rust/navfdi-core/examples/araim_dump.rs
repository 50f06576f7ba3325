//! Every output of ARAIM, to the bit, over a fixed set of geometries: 5–45 satellites in one,
//! two and three constellations, the ADD's half-interval search (`tol_pl` 0.05 m) and the exact
//! root (0), without residuals and with residuals (a 40 m bias on one satellite, through
//! `araim_fde`). For checking that a change to the ARAIM code keeps its results:
//!
//! ```text
//! cargo run --release --example araim_dump | md5sum   # before and after the change
//! ```

use navfdi_core::integrity::araim::{araim, Allocation, Ism};
use navfdi_core::integrity::araim_fde::araim_fde;

fn main() {
    for n in (5..=45).step_by(4) {
        for nc in 1..=3usize {
            for tol in [0.05, 0.0] {
                let (mut rows, mut cons, mut c_int, mut c_acc) =
                    (Vec::new(), Vec::new(), Vec::new(), Vec::new());
                for i in 0..n {
                    let az = i as f64 * 2.399_963 + nc as f64;
                    let el = (8.0 + 80.0 * ((i * 7 + nc) % n) as f64 / (n - 1) as f64).to_radians();
                    rows.push([-el.cos() * az.sin(), -el.cos() * az.cos(), -el.sin()]);
                    cons.push(i % nc);
                    let t = 0.12 * 1.001 / (0.002_001 + el.sin().powi(2)).sqrt();
                    c_int.push(0.5625 + t * t + 0.1 + 0.01 * (i % 3) as f64);
                    c_acc.push(0.25 + t * t + 0.1);
                }
                let ism = Ism {
                    c_int,
                    c_acc,
                    b_nom: vec![0.5; n],
                    p_sat: (0..n).map(|i| 1e-5 * (1.0 + (i % 4) as f64)).collect(),
                    p_const: vec![1e-4; nc],
                };
                let alloc = Allocation {
                    tol_pl: tol,
                    ..Allocation::lpv200()
                };
                match araim(&rows, &cons, &ism, &alloc) {
                    Ok(r) => println!("{n} {nc} {tol} {r:?}"),
                    Err(e) => println!("{n} {nc} {tol} error {e}"),
                }
                let y: Vec<f64> = (0..n)
                    .map(|i| 0.3 * ((i * 13 % 7) as f64 - 3.0) + if i == 2 { 40.0 } else { 0.0 })
                    .collect();
                match araim_fde(&rows, &cons, &ism, &alloc, &y) {
                    Ok(r) => println!("{n} {nc} {tol} fde {r:?}"),
                    Err(e) => println!("{n} {nc} {tol} fde error {e}"),
                }
            }
        }
    }
}
