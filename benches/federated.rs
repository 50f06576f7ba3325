//! Federated run cost against its filters' `run_filter` costs.
//!
//! yang2013 (n = 15; CNS sub-filter m = 3 with three detectors, GNSS sub-filter m = 6 with
//! one; T = 1000 epochs). Measured in the same criterion run:
//!
//! * `federated_run`: the federated loop of one simulated run (`run_federated`, isolation on);
//! * `run_filter_m3` and `run_filter_m6`: plain `run_filter` over the same T with the same
//!   n and the two sub-filters' measurement sizes.
//!
//! Target: federated ≤ 2 × (m3 + m6).

use criterion::{criterion_group, criterion_main, Criterion};
use navfdi_core::arch::federated::run_federated;
use navfdi_core::cancel::NEVER;
use navfdi_core::run::{run_filter, MatrixSeq};
use navfdi_core::sim::noise::simulate;
use navfdi_core::sim::prepare::Prepared;
use navfdi_core::spec::ScenarioSpec;
use std::hint::black_box;

fn yang2013() -> ScenarioSpec {
    // The bundled scenario in its SI form (as produced by navfdi.scenario).
    let json = include_str!("yang2013.json");
    ScenarioSpec::from_json(json).expect("valid scenario")
}

fn bench(c: &mut Criterion) {
    let prep = Prepared::new(yang2013()).expect("prepared");
    let sim = simulate(&prep, 1, 0);
    let t = prep.epochs();
    let mut g = c.benchmark_group("federated");
    g.sample_size(20);
    g.bench_function("federated_run", |b| {
        b.iter(|| {
            black_box(run_federated(&prep.spec, &sim.streams(&prep), true, &NEVER).expect("run"))
        })
    });
    let phi = MatrixSeq::PerEpoch(prep.models.phi.clone());
    let q = MatrixSeq::PerEpoch(prep.models.q.clone());
    for (label, si) in [("run_filter_m3", 0usize), ("run_filter_m6", 1usize)] {
        let zs: Vec<f64> = sim.meas.z[si]
            .iter()
            .flat_map(|z| z.iter().copied())
            .collect();
        let h = MatrixSeq::PerEpoch(prep.models.h[si].clone());
        let r = MatrixSeq::Const(prep.models.r[si].clone());
        let p0 = prep.models.p0.clone();
        g.bench_function(label, |b| {
            b.iter(|| {
                black_box(
                    run_filter(
                        nalgebra::DVector::zeros(15),
                        p0.clone(),
                        &phi,
                        &q,
                        &zs,
                        t,
                        &h,
                        &r,
                        1.0,
                        &NEVER,
                    )
                    .expect("run"),
                )
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
