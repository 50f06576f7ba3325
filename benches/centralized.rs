//! Centralized run cost against `run_filter` (paper-002 issue's speed targets).
//!
//! gao_fading (n = 15; one GNSS sensor, m = 6, two detectors; T = 1500 epochs), measured in
//! the same criterion run:
//!
//! * `centralized_{chi2,sprt,fading}`: one variant's epoch loop (`run_architecture`, no MDB,
//!   as in Monte-Carlo campaigns) over one simulated run;
//! * `three_variants`: the three variants on the same simulated run (as `navfdi run` does);
//! * `run_filter_m6`: plain `run_filter` over the same T, n and m.
//!
//! Targets: a centralized run ≤ 1.3 × `run_filter`; three variants ≤ 3.5 × one variant.

use criterion::{criterion_group, criterion_main, Criterion};
use navfdi_core::arch::run_architecture;
use navfdi_core::cancel::NEVER;
use navfdi_core::run::{run_filter, MatrixSeq};
use navfdi_core::sim::noise::simulate;
use navfdi_core::sim::prepare::Prepared;
use navfdi_core::spec::ScenarioSpec;
use std::hint::black_box;

fn spec(json: &str) -> ScenarioSpec {
    ScenarioSpec::from_json(json).expect("valid scenario")
}

fn bench(c: &mut Criterion) {
    let preps: Vec<(&str, Prepared)> = [
        ("chi2", include_str!("gao_fading_chi2.json")),
        ("sprt", include_str!("gao_fading_sprt.json")),
        ("fading", include_str!("gao_fading_fading.json")),
    ]
    .into_iter()
    .map(|(n, j)| (n, Prepared::new(spec(j)).expect("prepared")))
    .collect();
    let sim = simulate(&preps[0].1, 1, 0);
    let t = preps[0].1.epochs();
    let mut g = c.benchmark_group("centralized");
    g.sample_size(20);
    for (name, prep) in &preps {
        g.bench_function(format!("centralized_{name}"), |b| {
            b.iter(|| {
                black_box(
                    run_architecture(&prep.spec, &sim.streams(&preps[0].1), true, false, &NEVER)
                        .expect("run"),
                )
            })
        });
    }
    g.bench_function("three_variants", |b| {
        b.iter(|| {
            for (_, prep) in &preps {
                black_box(
                    run_architecture(&prep.spec, &sim.streams(&preps[0].1), true, false, &NEVER)
                        .expect("run"),
                );
            }
        })
    });
    let prep = &preps[0].1;
    let phi = MatrixSeq::PerEpoch(prep.models.phi.clone());
    let q = MatrixSeq::PerEpoch(prep.models.q.clone());
    let zs: Vec<f64> = sim.meas.z[0]
        .iter()
        .flat_map(|z| z.iter().copied())
        .collect();
    let h = MatrixSeq::PerEpoch(prep.models.h[0].clone());
    let r = MatrixSeq::Const(prep.models.r[0].clone());
    g.bench_function("run_filter_m6", |b| {
        b.iter(|| {
            black_box(
                run_filter(
                    nalgebra::DVector::zeros(15),
                    prep.models.p0.clone(),
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
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
