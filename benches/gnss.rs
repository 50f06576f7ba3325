//! GNSS costs (paper-001 issue's speed targets), criterion:
//!
//! * `snapshot_fde_10`: snapshot WLS (position + clock, Gauss-Newton from the previous
//!   epoch's solution) + global test + w-test, 10 satellites, one epoch, nothing excluded;
//!   `snapshot_fde_10_exclude`: the same with a 60 m fault on one satellite (one exclusion,
//!   a second solve and test);
//! * `tight_epoch_17x20`: one tight-filter epoch with the innovation FDE as runs do it:
//!   predict (17 states), the update of 10 pseudoranges + 10 rates row by row, which gives
//!   the global statistic (passing, as in most epochs), test, commit, from a copy of the
//!   run's filter (`kalman_clone_17`: the copy alone); `tight_epoch_17x20_batch`: the same
//!   epoch with the batch innovation (20 × 20 A, Cholesky, gain, Joseph form), the path of
//!   epochs that fail the test;
//!   `tight_predict_17`, `tight_innovation_17x20`: its parts; `innovation_fde_with_w_20`: the
//!   test with the w of every satellite (factorisation and inverse), as recorded by
//!   `navfdi run`;
//! * `shao2018_{variant}`: a whole 1000-epoch run of each FDE placement (per epoch: divide by
//!   1000), on one simulated run; `shao2018_innovation_pl` / `_separation_pl`: the same with
//!   filter protection levels (the sub-filter bank and a snapshot ARAIM per epoch).
//!
//! Targets: snapshot ≤ 10 µs; tight epoch ≤ 6 µs. The numpy peers run in
//! `benches/bench_gnss.py` (same machine, same algorithm).

use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::{DMatrix, DVector, Matrix3, Vector2, Vector3};
use navfdi_core::arch::run_architecture;
use navfdi_core::cancel::NEVER;
use navfdi_core::gnss::innovation::innovation_fde;
use navfdi_core::gnss::prefilter::{dll_variance, fll_variance, Prefilter, PrefilterConfig};
use navfdi_core::gnss::snapshot::{snapshot_fde, FdeConfig, ObsCov};
use navfdi_core::kalman::{KalmanFilter, Sequential};
use navfdi_core::sim::noise::simulate;
use navfdi_core::sim::prepare::Prepared;
use navfdi_core::spec::{FdePlacement, ScenarioSpec};
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let spec = ScenarioSpec::from_json(include_str!("shao2018.json")).expect("valid scenario");
    let prep = Prepared::new(spec.clone()).expect("prepared");
    let sim = simulate(&prep, 1, 0);
    let rp = prep.models.ranges.as_ref().expect("ranges");
    let n = spec.n_states();
    let cfg = FdeConfig::new(0.05, Some(1.6449)).expect("cfg");
    let r_of = |e: &navfdi_core::gnss::ranges::RangeEpoch| {
        DMatrix::from_diagonal(&DVector::from_iterator(
            2 * e.len(),
            e.sigma.iter().chain(&e.sigma_rate).map(|s| s * s),
        ))
    };
    // The filter of the run up to epoch k − 1, faulty observations left out (as FDE would);
    // k: the first epoch with exactly 10 satellites, no fault and a passing innovation test
    // (the common case).
    let mut kf = KalmanFilter::new(DVector::zeros(n), prep.models.p0.clone()).expect("kf");
    let mut k = 0;
    for j in 0..prep.epochs() {
        let e = &rp.epochs[j];
        let rj = r_of(e);
        if j > 0 && e.len() == 10 && e.fault.iter().all(|f| *f == 0.0) {
            let mut f = kf.clone();
            f.predict_trusted(&prep.models.phi[j], &prep.models.q[j], 1.0)
                .expect("predict");
            let (inn, _) = f
                .innovation_pending(&sim.meas.z[rp.sensor][j], &e.h, &rj)
                .expect("innovation");
            let o = innovation_fde(&inn.residual, &inn.covariance, 10, true, None, true, &cfg)
                .expect("fde");
            if o.excluded.is_empty() {
                k = j;
                break;
            }
        }
        kf.predict_trusted(&prep.models.phi[j], &prep.models.q[j], 1.0)
            .expect("predict");
        let mut zj = sim.meas.z[rp.sensor][j].clone();
        for (i, f) in e.fault.iter().enumerate() {
            if *f != 0.0 {
                zj[i] = f64::NAN;
            }
        }
        kf.update_trusted(&zj, &e.h, &rj).expect("update");
    }
    assert!(k > 0, "no epoch with 10 satellites and a passing test");
    eprintln!("benchmark epoch k = {k} (t = {} s)", prep.models.t[k]);
    let ep = &rp.epochs[k];
    let m = ep.len();
    let rho: Vec<f64> = sim.meas.raw[k].as_slice()[..m].to_vec();
    let cov = ObsCov::Sigma(ep.sigma.clone());
    let first = snapshot_fde(&ep.sat_pos, &rho, &cov, &cfg, None).expect("solves");
    let p = first.position.expect("solution");
    let x0 = Some([p.x + 3.0, p.y - 2.0, p.z + 1.0, first.clock.unwrap_or(0.0)]);
    let mut g = c.benchmark_group("gnss");
    g.bench_function("snapshot_fde_10", |b| {
        b.iter(|| {
            snapshot_fde(black_box(&ep.sat_pos), black_box(&rho), &cov, &cfg, x0).expect("ok")
        })
    });
    let mut bad = rho.clone();
    bad[3] += 60.0;
    g.bench_function("snapshot_fde_10_exclude", |b| {
        b.iter(|| {
            snapshot_fde(black_box(&ep.sat_pos), black_box(&bad), &cov, &cfg, x0).expect("ok")
        })
    });
    // One tight epoch, innovation FDE, from the run's state.
    let z: DVector<f64> = sim.meas.z[rp.sensor][k].clone();
    let h: DMatrix<f64> = ep.h.clone();
    let r = r_of(ep);
    let state = kf.clone();
    let r_diag: Vec<f64> = ep
        .sigma
        .iter()
        .chain(&ep.sigma_rate)
        .map(|s| s * s)
        .collect();
    let mut seq = Sequential::new(n);
    g.bench_function("tight_epoch_17x20", |b| {
        b.iter(|| {
            let mut f = state.clone();
            f.predict_trusted(&prep.models.phi[k], &prep.models.q[k], 1.0)
                .expect("predict");
            f.sequential_pending(&z, &h, &r_diag, &mut seq)
                .expect("sequential");
            let thr = cfg.threshold(seq.dof).expect("threshold");
            assert!(seq.statistic < thr);
            f.commit_sequential(&mut seq).expect("commit");
            black_box(f)
        })
    });
    g.bench_function("tight_epoch_17x20_batch", |b| {
        b.iter(|| {
            let mut f = state.clone();
            f.predict_trusted(&prep.models.phi[k], &prep.models.q[k], 1.0)
                .expect("predict");
            let (inn, pending) = f.innovation_pending(&z, &h, &r).expect("innovation");
            let out = innovation_fde(
                &inn.residual,
                &inn.covariance,
                m,
                true,
                Some(inn.statistic),
                false,
                &cfg,
            )
            .expect("fde");
            if let Some(p) = pending {
                f.apply_pending(p, &r).expect("update");
            }
            black_box((f, out))
        })
    });
    g.bench_function("kalman_clone_17", |b| b.iter(|| black_box(state.clone())));
    let mut s0 = state.clone();
    s0.predict_trusted(&prep.models.phi[k], &prep.models.q[k], 1.0)
        .expect("predict");
    let (inn0, _) = s0
        .clone()
        .innovation_pending(&z, &h, &r)
        .expect("innovation");
    g.bench_function("tight_predict_17", |b| {
        b.iter(|| {
            let mut f = state.clone();
            f.predict_trusted(&prep.models.phi[k], &prep.models.q[k], 1.0)
                .expect("predict");
            black_box(f)
        })
    });
    g.bench_function("tight_innovation_17x20", |b| {
        b.iter(|| {
            let mut f = s0.clone();
            black_box(f.innovation_pending(&z, &h, &r).expect("innovation"))
        })
    });
    let o =
        innovation_fde(&inn0.residual, &inn0.covariance, m, true, None, true, &cfg).expect("fde");
    eprintln!(
        "innovation test at k: {:?} {:?} excluded {:?}",
        o.first, o.status, o.excluded
    );
    g.bench_function("innovation_fde_with_w_20", |b| {
        b.iter(|| {
            black_box(
                innovation_fde(&inn0.residual, &inn0.covariance, m, true, None, true, &cfg)
                    .expect("fde"),
            )
        })
    });
    // Paper 004's channel prefilter: one 20 ms step (predict, both discriminators, Joseph).
    let mut pf = Prefilter::new(
        PrefilterConfig::default(),
        Vector3::zeros(),
        Matrix3::identity() * 0.01,
    )
    .expect("prefilter");
    let r = Vector2::new(
        dll_variance(48.0, 0.02, 1.0).expect("dll"),
        fll_variance(48.0, 0.02, false).expect("fll"),
    );
    let mut k = 0u32;
    g.bench_function("prefilter_step", |b| {
        b.iter(|| {
            k = k.wrapping_add(1);
            let z = Vector2::new(1e-3 * f64::from(k % 7), 0.1 * f64::from(k % 5));
            black_box(pf.step_with(black_box(z), r))
        })
    });
    g.sample_size(20);
    for (name, fde) in [
        ("ls_precheck", FdePlacement::LsPrecheck),
        ("innovation", FdePlacement::Innovation),
        ("gnss_filter", FdePlacement::GnssFilter),
        ("none", FdePlacement::None),
    ] {
        let mut s = spec.clone();
        if let Some(t) = s.tight.as_mut() {
            t.fde = fde;
        }
        prep.spec.check_variant(&s).expect("variant");
        let src = sim.streams(&prep);
        g.bench_function(format!("shao2018_{name}"), |b| {
            b.iter(|| run_architecture(&s, &src, true, false, &NEVER).expect("run"))
        });
    }
    // Filter protection levels (a filter-PL epoch with 10 satellites ≤ 20× a plain
    // tight epoch): the innovation run with the sub-filter bank and the snapshot ARAIM of each
    // epoch beside it, and the separation placement; compare with `shao2018_innovation`.
    for (name, fde) in [
        ("innovation_pl", FdePlacement::Innovation),
        ("separation_pl", FdePlacement::Separation),
    ] {
        let mut s = spec.clone();
        if let Some(t) = s.tight.as_mut() {
            t.fde = fde;
            t.integrity = Some(navfdi_core::spec::FilterIntegritySpec::default());
        }
        prep.spec.check_variant(&s).expect("variant");
        let src = sim.streams(&prep);
        g.bench_function(format!("shao2018_{name}"), |b| {
            b.iter(|| run_architecture(&s, &src, true, false, &NEVER).expect("run"))
        });
    }
    g.finish();
}

/// The IMU noise figures of the strapdown benchmarks (a consumer-grade IMU).
fn bench_imu() -> navfdi_core::ins::error_filter::ImuNoise {
    navfdi_core::ins::error_filter::ImuNoise {
        gyro_noise: [1e-3; 3],
        accel_noise: [5e-3; 3],
        gyro_bias: 1e-4,
        accel_bias: 1e-2,
        bias_tau: 300.0,
        gyro_scale: 0.0,
        accel_scale: 0.0,
    }
}

/// The tight update of a strapdown filter on recorded logs (target: ≤ 15 µs per
/// epoch with FDE at 25 satellites): the 18-state error filter updated with 25 pseudoranges and
/// 25 rates row by row (which yields the global statistic), the test, and the commit with the
/// feedback into the state — `tight_ins_update_18x50`; the rows themselves (geometry, lever
/// arm, Sagnac) are built before it in `arch::tight_ins` and are not in this figure.
fn bench_tight_ins(c: &mut Criterion) {
    use navfdi_core::ins::error_filter::{ErrorFilter, CB, CD, N_CLOCK, PHI, R, V};
    use navfdi_core::ins::strapdown::NavState;
    let noise = bench_imu();
    let mut kf =
        ErrorFilter::<N_CLOCK>::new(3.0, 0.3, Vector3::repeat(0.02), Vector3::zeros(), noise)
            .with_clock([0.0; 3], [10.0, 10.0, 1.0], (0.1, 0.1));
    let st = NavState {
        lat: 0.7,
        lon: -1.8,
        h: 1580.0,
        v: Vector3::new(1.0, 0.5, 0.0),
        q: nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, 0.4),
    };
    for _ in 0..40 {
        kf.propagate(
            &st,
            &Vector3::new(0.0, 0.0, -9.8),
            &Vector3::zeros(),
            0.00667,
        );
    }
    let m = 25;
    let mut h = DMatrix::zeros(2 * m, N_CLOCK);
    let mut res = DVector::zeros(2 * m);
    let mut r_diag = vec![0.0; 2 * m];
    for i in 0..m {
        let (az, el) = (i as f64 * 2.4, 0.2 + (i as f64 * 0.37) % 1.3);
        let e = Vector3::new(az.cos() * el.cos(), az.sin() * el.cos(), -el.sin());
        for q in 0..3 {
            h[(i, R + q)] = -e[q];
            h[(i, PHI + q)] = 0.01 * e[(q + 1) % 3];
            h[(m + i, V + q)] = -e[q];
        }
        h[(i, CB + i % 2)] = 1.0;
        h[(m + i, CD)] = 1.0;
        res[i] = (i as f64).sin();
        res[m + i] = 0.1 * (i as f64).cos();
        r_diag[i] = 0.5 / el.sin().powi(2);
        r_diag[m + i] = 0.02 / el.sin().powi(2);
    }
    let cfg = FdeConfig::new(1e-3, None).expect("config");
    let thr = cfg.threshold(2 * m).expect("threshold");
    let mut g = c.benchmark_group("tight_ins");
    g.bench_function("tight_ins_update_18x50", |b| {
        b.iter(|| {
            let mut f = kf.clone();
            let mut s = st;
            let (p, dx, lambda) = f.sequential(black_box(&res), &h, &r_diag).expect("update");
            if lambda < thr {
                f.p = p;
                f.feedback(&mut s, &dx);
            }
            black_box((f.p[(0, 0)], s.lat))
        })
    });
    g.bench_function("error_filter_clone_18", |b| {
        b.iter(|| black_box(kf.clone()))
    });
    g.finish();
}

/// The loosely coupled strapdown filter's epoch at the size of the dense benchmark (n = 15,
/// m = 6), for the ratio against filterpy's epoch of the same size (`benches/compare.py`):
/// one propagation (F from the mechanised state, Φ = I + F Δt, Φ P Φᵀ + Q on the statically
/// sized 15 × 15 covariance) and one position + velocity update as the loosely coupled
/// filter makes it (innovation with its Cholesky factor and statistic, Joseph-form update)
/// with the feedback into the state — `strapdown_epoch_15x6`; the parts alone
/// (`strapdown_propagate_15`, `strapdown_update_15x6`) and the row-by-row update of the tight
/// filter at the same size (`strapdown_sequential_15x6`).
fn bench_strapdown_epoch(c: &mut Criterion) {
    use navfdi_core::ins::error_filter::{ErrorFilter, N, N_CLOCK, R, V};
    use navfdi_core::ins::strapdown::NavState;
    let noise = bench_imu();
    let kf = ErrorFilter::<N>::new(3.0, 0.3, Vector3::repeat(0.02), Vector3::zeros(), noise);
    let st = NavState {
        lat: 0.53,
        lon: 1.99,
        h: 30.0,
        v: Vector3::new(10.0, 2.0, 0.1),
        q: nalgebra::UnitQuaternion::from_euler_angles(0.01, -0.02, 0.4),
    };
    let mut h = DMatrix::zeros(6, N);
    for i in 0..3 {
        h[(i, R + i)] = 1.0;
        h[(3 + i, V + i)] = 1.0;
    }
    let res = DVector::from_column_slice(&[0.3, -0.2, 0.5, 0.02, -0.01, 0.03]);
    let r_diag = [0.04, 0.04, 0.09, 0.01, 0.01, 0.02];
    let (f, w) = (
        Vector3::new(0.1, -0.2, -9.8),
        Vector3::new(0.001, 0.0, 0.01),
    );
    let mut g = c.benchmark_group("strapdown");
    let r = DMatrix::from_diagonal(&DVector::from_column_slice(&r_diag));
    g.bench_function("strapdown_epoch_15x6", |b| {
        let mut f15 = kf.clone();
        let mut s = st;
        b.iter(|| {
            f15.propagate(&s, black_box(&f), &w, 0.01);
            let inn = f15.innovation(black_box(&res), &h, &r).expect("innovation");
            let dx = f15.update(&inn, &h, &r).expect("update");
            f15.feedback(&mut s, &(dx * 1e-3));
            s = st;
            black_box(inn.lambda)
        })
    });
    g.bench_function("strapdown_propagate_15", |b| {
        let mut f15 = kf.clone();
        b.iter(|| {
            f15.propagate(&st, black_box(&f), &w, 0.01);
            f15.p = kf.p;
        })
    });
    // The tight filter's size (15 + 3 clock states), propagated at every IMU sample by the
    // filter and by each sub-filter of the protection-level bank.
    let k18 = ErrorFilter::<N_CLOCK>::new(3.0, 0.3, Vector3::repeat(0.02), Vector3::zeros(), noise)
        .with_clock([0.0; 3], [10.0, 10.0, 1.0], (0.1, 0.1));
    g.bench_function("strapdown_propagate_18", |b| {
        let mut f18 = k18.clone();
        b.iter(|| {
            f18.propagate(&st, black_box(&f), &w, 0.01);
            f18.p = k18.p;
        })
    });
    g.bench_function("strapdown_update_15x6", |b| {
        b.iter(|| {
            let mut f15 = kf.clone();
            let inn = f15.innovation(black_box(&res), &h, &r).expect("innovation");
            black_box(f15.update(&inn, &h, &r).expect("update"))
        })
    });
    g.bench_function("strapdown_sequential_15x6", |b| {
        b.iter(|| black_box(kf.sequential(black_box(&res), &h, &r_diag).expect("update")))
    });
    g.finish();
}

criterion_group!(benches, bench, bench_tight_ins, bench_strapdown_epoch);
criterion_main!(benches);
