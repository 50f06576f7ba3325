//! Criterion benchmarks of the core filter step (n = 15 states, m = 6 measurements).
//!
//! `step_checked` is the validated public path (`predict` + `update`), `step_trusted` the path
//! used inside whole runs after validating the inputs once, and `run_filter_per_epoch` a
//! 10 000-epoch `run_filter` divided by the number of epochs (reference: `step_trusted`).

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use navfdi_core::cancel::NEVER;
use navfdi_core::run::{run_filter, MatrixSeq};
use navfdi_core::KalmanFilter;
use std::hint::black_box;

#[path = "ins_problem.rs"]
mod ins_problem;
use ins_problem::{measurement, problem, M};

fn bench(c: &mut Criterion) {
    let (x0, p0, phi, q, h, r) = problem();
    let z = measurement();
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
                    &NEVER,
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
    let z = measurement();
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
