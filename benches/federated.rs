//! Federated run cost against its filters' `run_filter` costs.
//!
//! yang2013 (n = 15; CNS sub-filter m = 3 with three detectors, GNSS sub-filter m = 6 with
//! one; T = 1000 epochs). Measured in the same criterion run:
//!
//! * `federated_run`: the federated loop of one simulated run (`run_federated`, isolation on);
//! * `run_filter_m3` and `run_filter_m6`: plain `run_filter` over the same T with the same
//!   n and the two sub-filters' measurement sizes;
//! * `campaign_run`: one Monte-Carlo run as a campaign makes it (`montecarlo::one_run`: the
//!   simulation, the federated loop and the run's metrics), against which the campaign's
//!   per filter-epoch cost is `campaign_run / (run_filter_m3 + run_filter_m6)`.
//!
//! Criterion times each benchmark in turn, and this machine's speed drifts by up to 1.5×
//! within minutes, so the last two ratios are also measured interleaved: after criterion,
//! `campaign_ratio` runs one campaign run, `run_filter_m3` and `run_filter_m6` back to back,
//! 41 times, and prints the median and quartiles of the per-round ratios.
//!
//! Target: federated ≤ 2 × (m3 + m6).

use criterion::{criterion_group, Criterion};
use navfdi_core::arch::federated::run_federated;
use navfdi_core::cancel::NEVER;
use navfdi_core::montecarlo::{cells, one_run};
use navfdi_core::run::{run_filter, MatrixSeq};
use navfdi_core::sim::noise::{simulate, Simulated};
use navfdi_core::sim::prepare::Prepared;
use navfdi_core::spec::ScenarioSpec;
use std::hint::black_box;

fn yang2013() -> ScenarioSpec {
    // The bundled scenario in its SI form (as produced by navfdi.scenario).
    let json = include_str!("yang2013.json");
    ScenarioSpec::from_json(json).expect("valid scenario")
}

/// The two sub-filters of yang2013 as plain `run_filter` inputs: the simulated run's
/// measurements, the per-epoch Φ, Q and H, and R.
struct SubFilters {
    phi: MatrixSeq,
    q: MatrixSeq,
    /// Per sub-filter: measurements (T × m, row-major), H and R.
    inputs: Vec<(Vec<f64>, MatrixSeq, MatrixSeq)>,
}

impl SubFilters {
    fn new(prep: &Prepared, sim: &Simulated) -> Self {
        let inputs = [0usize, 1]
            .iter()
            .map(|&si| {
                let zs = sim.meas.z[si]
                    .iter()
                    .flat_map(|z| z.iter().copied())
                    .collect();
                let h = MatrixSeq::PerEpoch(prep.models.h[si].clone());
                let r = MatrixSeq::Const(prep.models.r[si].clone());
                (zs, h, r)
            })
            .collect();
        SubFilters {
            phi: MatrixSeq::PerEpoch(prep.models.phi.clone()),
            q: MatrixSeq::PerEpoch(prep.models.q.clone()),
            inputs,
        }
    }

    /// `run_filter` over every epoch with sub-filter `si`'s inputs.
    fn run(&self, prep: &Prepared, si: usize) {
        let (zs, h, r) = &self.inputs[si];
        let x0 = nalgebra::DVector::zeros(prep.models.p0.nrows());
        black_box(
            run_filter(
                x0,
                prep.models.p0.clone(),
                &self.phi,
                &self.q,
                zs,
                prep.epochs(),
                h,
                r,
                1.0,
                &NEVER,
            )
            .expect("run"),
        );
    }
}

fn bench(c: &mut Criterion) {
    let prep = Prepared::new(yang2013()).expect("prepared");
    let sim = simulate(&prep, 1, 0);
    let mut g = c.benchmark_group("federated");
    g.sample_size(20);
    g.bench_function("federated_run", |b| {
        b.iter(|| {
            black_box(run_federated(&prep.spec, &sim.streams(&prep), true, &NEVER).expect("run"))
        })
    });
    let cells = cells(&prep);
    let mut run = 0u64;
    g.bench_function("campaign_run", |b| {
        b.iter(|| {
            run += 1;
            black_box(one_run(&prep, 0, run, &cells, false, &NEVER).expect("run"))
        })
    });
    let filters = SubFilters::new(&prep, &sim);
    for (label, si) in [("run_filter_m3", 0usize), ("run_filter_m6", 1usize)] {
        g.bench_function(label, |b| b.iter(|| filters.run(&prep, si)));
    }
    g.finish();
}

/// The campaign's per filter-epoch cost against `run_filter`'s on the same two filters,
/// measured interleaved (see the module doc): median and quartiles of 41 rounds.
fn campaign_ratio() {
    use std::time::Instant;
    let prep = Prepared::new(yang2013()).expect("prepared");
    let sim = simulate(&prep, 1, 0);
    let cells = cells(&prep);
    let filters = SubFilters::new(&prep, &sim);
    let mut ratios = Vec::new();
    for round in 0..42u64 {
        let t0 = Instant::now();
        black_box(one_run(&prep, 0, round, &cells, false, &NEVER).expect("run"));
        let campaign = t0.elapsed().as_secs_f64();
        let t0 = Instant::now();
        filters.run(&prep, 0);
        filters.run(&prep, 1);
        let filters_time = t0.elapsed().as_secs_f64();
        if round > 0 {
            ratios.push(campaign / filters_time); // round 0 warms up
        }
    }
    ratios.sort_by(f64::total_cmp);
    let quantile = |f: f64| ratios[((ratios.len() - 1) as f64 * f).round() as usize];
    println!(
        "campaign_ratio: campaign run / (run_filter_m3 + run_filter_m6), interleaved, {} rounds: median {:.3} (quartiles {:.3}–{:.3})",
        ratios.len(),
        quantile(0.5),
        quantile(0.25),
        quantile(0.75)
    );
}

criterion_group!(benches, bench);

fn main() {
    benches();
    campaign_ratio();
    Criterion::default().configure_from_args().final_summary();
}
