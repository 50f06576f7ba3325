//! Federated filter: reset mode equals the centralised Kalman filter on a linear system.

use nalgebra::{DMatrix, DVector};
use navfdi_core::detect::{Detector, ResidualChi2};
use navfdi_core::fusion::{FederatedFilter, SubFilterConfig};
use navfdi_core::spec::FusionMode;
use navfdi_core::KalmanFilter;

/// Small deterministic pseudo-random numbers (no RNG dependency in the test).
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
    fn matrix(&mut self, r: usize, c: usize) -> DMatrix<f64> {
        DMatrix::from_fn(r, c, |_, _| self.next())
    }
}

fn spd(rng: &mut Lcg, n: usize, eps: f64) -> DMatrix<f64> {
    let b = rng.matrix(n, n);
    &b * b.transpose() / n as f64 + DMatrix::identity(n, n) * eps
}

fn block_diag(blocks: &[DMatrix<f64>]) -> DMatrix<f64> {
    let m: usize = blocks.iter().map(|b| b.nrows()).sum();
    let mut out = DMatrix::zeros(m, m);
    let mut o = 0;
    for b in blocks {
        out.view_mut((o, o), (b.nrows(), b.ncols())).copy_from(b);
        o += b.nrows();
    }
    out
}

type Setup = (
    FederatedFilter,
    KalmanFilter,
    Vec<DMatrix<f64>>,
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    DMatrix<f64>,
    Lcg,
);

fn setup(master_share: f64, shares: &[f64]) -> Setup {
    let mut rng = Lcg(42);
    let n = 5;
    let dims = [2usize, 3, 1];
    let hs: Vec<DMatrix<f64>> = dims.iter().map(|&m| rng.matrix(m, n)).collect();
    let rs: Vec<DMatrix<f64>> = dims.iter().map(|&m| spd(&mut rng, m, 0.1)).collect();
    let phi = DMatrix::identity(n, n) + rng.matrix(n, n) * 0.05;
    let q = spd(&mut rng, n, 1e-3) * 0.01;
    let p0 = spd(&mut rng, n, 0.1);
    let x0 = DVector::from_fn(n, |_, _| rng.next());
    let subs = (0..3)
        .map(|i| SubFilterConfig {
            name: format!("s{i}"),
            h: hs[i].clone(),
            r: rs[i].clone(),
            share: shares[i],
            detectors: vec![(
                "chi2".into(),
                Detector::Chi2(ResidualChi2::new(0.01).unwrap()),
            )],
            isolation: None,
        })
        .collect();
    let fed = FederatedFilter::new(
        x0.clone(),
        p0.clone(),
        subs,
        FusionMode::Reset,
        master_share,
        true,
    )
    .unwrap();
    let central = KalmanFilter::new(x0, p0).unwrap();
    let h_all = DMatrix::from_rows(
        &hs.iter()
            .flat_map(|h| h.row_iter().map(|r| r.into_owned()).collect::<Vec<_>>())
            .collect::<Vec<_>>(),
    );
    let r_all = block_diag(&rs);
    (fed, central, hs, h_all, r_all, phi, q, rng)
}

fn check_equivalence(master_share: f64, shares: &[f64]) {
    let (mut fed, mut central, hs, h_all, r_all, phi, q, mut rng) = setup(master_share, shares);
    for k in 0..60 {
        let zs: Vec<DVector<f64>> = hs
            .iter()
            .map(|h| DVector::from_fn(h.nrows(), |_, _| 2.0 * rng.next()))
            .collect();
        let z_all =
            DVector::from_iterator(h_all.nrows(), zs.iter().flat_map(|z| z.iter().copied()));
        let rep = fed.step(&phi, &q, &zs).unwrap();
        assert_eq!(rep.sources, 3 + usize::from(master_share > 0.0));
        central.predict(&phi, &q, 1.0).unwrap();
        central.update(&z_all, &h_all, &r_all).unwrap();
        let dx = (fed.x() - central.x()).amax() / central.x().amax().max(1.0);
        let dp = (fed.p() - central.p()).amax() / central.p().amax();
        assert!(dx < 1e-9 && dp < 1e-9, "epoch {k}: dx {dx:e}, dp {dp:e}");
    }
}

#[test]
fn reset_mode_equals_centralised_filter() {
    check_equivalence(0.0, &[0.5, 0.3, 0.2]);
}

#[test]
fn reset_mode_with_master_share_equals_centralised_filter() {
    check_equivalence(0.25, &[0.25, 0.25, 0.25]);
}

#[test]
fn missing_measurements_match_centralised_reduced_update() {
    let (mut fed, mut central, hs, h_all, r_all, phi, q, mut rng) = setup(0.0, &[0.4, 0.4, 0.2]);
    for k in 0..30 {
        let mut zs: Vec<DVector<f64>> = hs
            .iter()
            .map(|h| DVector::from_fn(h.nrows(), |_, _| rng.next()))
            .collect();
        if k % 3 == 0 {
            zs[1] = DVector::from_element(3, f64::NAN); // sensor 1 missing this epoch
        }
        let z_all =
            DVector::from_iterator(h_all.nrows(), zs.iter().flat_map(|z| z.iter().copied()));
        fed.step(&phi, &q, &zs).unwrap();
        central.predict(&phi, &q, 1.0).unwrap();
        central.update(&z_all, &h_all, &r_all).unwrap();
        assert!(
            (fed.x() - central.x()).amax() < 1e-9 * central.x().amax().max(1.0),
            "epoch {k}"
        );
    }
}

/// Two 2-state sub-filters measuring the state directly (R = 0.1 I), shares 0.5/0.5, reset
/// mode; only "bad" is isolated by its chi-square detector (pf 1e-4).
fn good_and_bad() -> FederatedFilter {
    let mk = |name: &str, iso: bool| SubFilterConfig {
        name: name.into(),
        h: DMatrix::identity(2, 2),
        r: DMatrix::identity(2, 2) * 0.1,
        share: 0.5,
        detectors: vec![(
            "chi2".into(),
            Detector::Chi2(ResidualChi2::new(1e-4).unwrap()),
        )],
        isolation: if iso { Some(0) } else { None },
    };
    FederatedFilter::new(
        DVector::zeros(2),
        DMatrix::identity(2, 2),
        vec![mk("good", false), mk("bad", true)],
        FusionMode::Reset,
        0.0,
        true,
    )
    .unwrap()
}

#[test]
fn isolated_subfilter_is_left_out_and_reinstated() {
    let mut rng = Lcg(7);
    let n = 2;
    let mut fed = good_and_bad();
    let phi = DMatrix::identity(n, n);
    let q = DMatrix::identity(n, n) * 1e-4;
    let mut saw_isolation = false;
    for k in 0..80 {
        let noise = |rng: &mut Lcg| DVector::from_fn(2, |_, _| 0.3 * rng.next());
        let good = noise(&mut rng);
        let fault = if (30..40).contains(&k) { 50.0 } else { 0.0 };
        let bad = noise(&mut rng).add_scalar(fault);
        let rep = fed.step(&phi, &q, &[good, bad]).unwrap();
        if (30..40).contains(&k) {
            // The faulty sub-filter is isolated at once and the global estimate stays near 0.
            assert!(rep.subs[1].isolated, "epoch {k}");
            assert!(!rep.subs[1].fused);
            assert_eq!(rep.sources, 1);
            assert!(fed.x().amax() < 2.0, "epoch {k}: {}", fed.x());
            saw_isolation = true;
        }
        if rep.subs[1].reinstated {
            // Reset from the global solution.
            assert_eq!(fed.sub_x(1).unwrap(), fed.x());
        }
    }
    assert!(saw_isolation);
    assert!(!fed.isolated()[1], "reinstated after the fault");
}

#[test]
fn step_rejects_bad_input_and_keeps_state() {
    let (mut fed, _, hs, _, _, phi, q, _) = setup(0.0, &[0.5, 0.3, 0.2]);
    let zs: Vec<DVector<f64>> = hs.iter().map(|h| DVector::zeros(h.nrows())).collect();
    fed.step(&phi, &q, &zs).unwrap();
    let before = (fed.x().clone(), fed.p().clone());
    assert!(fed.step(&phi, &q, &zs[..2]).is_err());
    let mut bad = zs.clone();
    bad[0][0] = f64::INFINITY;
    assert!(fed.step(&phi, &q, &bad).is_err());
    assert!(fed.step(&phi, &(-&q), &zs).is_err());
    assert_eq!((fed.x().clone(), fed.p().clone()), before);
}

#[test]
fn isolated_modes_track_predict_update() {
    use navfdi_core::spec::IsolatedMode;
    let run = |mode: IsolatedMode| {
        let mut rng = Lcg(11);
        let n = 2;
        let mut fed = good_and_bad();
        fed.set_isolated_mode(mode);
        let (phi, q) = (DMatrix::identity(n, n), DMatrix::identity(n, n) * 1e-4);
        let mut during = Vec::new();
        let mut cleared_at = None;
        for k in 0..120 {
            let good = DVector::from_fn(2, |_, _| 0.3 * rng.next());
            let bad = DVector::from_fn(2, |_, _| 0.3 * rng.next())
                .add_scalar(if (30..40).contains(&k) { 50.0 } else { 0.0 });
            let rep = fed.step(&phi, &q, &[good, bad]).unwrap();
            if (31..40).contains(&k) {
                during.push((fed.sub_x(1).unwrap() - fed.x()).amax());
            }
            if k >= 40 && cleared_at.is_none() && !rep.subs[1].isolated {
                cleared_at = Some(k);
            }
        }
        (during, cleared_at)
    };
    // Track: while isolated the sub-filter holds the global solution; it clears at the fault's end.
    let (d, c) = run(IsolatedMode::Track);
    assert!(d.iter().all(|v| *v == 0.0), "{d:?}");
    assert_eq!(c, Some(40));
    // Predict: it keeps its own (unupdated) state, close to but not equal to the global.
    let (d, c) = run(IsolatedMode::Predict);
    assert!(d.iter().all(|v| *v > 0.0 && *v < 1.0), "{d:?}");
    assert_eq!(c, Some(40));
    // Update: it absorbs the 50-unit fault, and its residual stays large after the fault ends.
    let (d, c) = run(IsolatedMode::Update);
    assert!(d.last().unwrap() > &5.0, "{d:?}");
    assert!(c.is_none_or(|k| k > 45), "{c:?}");
}
