//! Property tests of the Kalman filter (proptest).

use approx::relative_eq;
use nalgebra::{DMatrix, DVector};
use navfdi_core::KalmanFilter;
use proptest::prelude::*;

/// A random SPD matrix `B Bᵀ + εI` from entries in [-1, 1].
fn spd(n: usize, entries: &[f64], eps: f64) -> DMatrix<f64> {
    let b = DMatrix::from_row_slice(n, n, &entries[..n * n]);
    &b * b.transpose() + DMatrix::identity(n, n) * eps
}

#[derive(Debug, Clone)]
struct System {
    n: usize,
    m: usize,
    x0: DVector<f64>,
    p0: DMatrix<f64>,
    phi: DMatrix<f64>,
    q: DMatrix<f64>,
    h: DMatrix<f64>,
    r: DMatrix<f64>,
    z: DVector<f64>,
}

fn system() -> impl Strategy<Value = System> {
    (1usize..=8, 1usize..=6).prop_flat_map(|(n, m)| {
        let v = |len: usize| prop::collection::vec(-1.0f64..1.0, len);
        (v(n), v(n * n), v(n * n), v(n * n), v(m * n), v(m * m), v(m)).prop_map(
            move |(x0, p0, phi, q, h, r, z)| System {
                n,
                m,
                x0: DVector::from_vec(x0),
                p0: spd(n, &p0, 1e-3),
                phi: DMatrix::from_row_slice(n, n, &phi) + DMatrix::identity(n, n),
                q: spd(n, &q, 0.0) * 0.1,
                h: DMatrix::from_row_slice(m, n, &h),
                r: spd(m, &r, 1e-2),
                z: DVector::from_vec(z) * 3.0,
            },
        )
    })
}

fn is_symmetric_psd(p: &DMatrix<f64>) -> bool {
    let n = p.nrows();
    for i in 0..n {
        for j in 0..n {
            if p[(i, j)] != p[(j, i)] {
                return false;
            }
        }
    }
    let scale = p.amax().max(1e-300);
    let eig = p.clone().symmetric_eigen();
    eig.eigenvalues.iter().all(|l| *l >= -1e-10 * scale)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn covariance_stays_symmetric_psd(s in system(), steps in 1usize..20) {
        let mut kf = KalmanFilter::new(s.x0.clone(), s.p0.clone()).unwrap();
        for _ in 0..steps {
            kf.predict(&s.phi, &s.q, 1.0).unwrap();
            prop_assert!(is_symmetric_psd(kf.p()));
            kf.update(&s.z, &s.h, &s.r).unwrap();
            prop_assert!(is_symmetric_psd(kf.p()), "P = {}", kf.p());
        }
    }

    #[test]
    fn joseph_equals_short_form_for_optimal_gain(s in system()) {
        let mut kf = KalmanFilter::new(s.x0.clone(), s.p0.clone()).unwrap();
        kf.predict(&s.phi, &s.q, 1.0).unwrap();
        let pm = kf.p().clone();
        let xm = kf.x().clone();
        kf.update(&s.z, &s.h, &s.r).unwrap();
        // Short form with an explicit inverse, as an independent reference.
        let a = &s.h * &pm * s.h.transpose() + &s.r;
        let k = &pm * s.h.transpose() * a.clone().try_inverse().unwrap();
        let p_short = (DMatrix::identity(s.n, s.n) - &k * &s.h) * &pm;
        let x_ref = &xm + &k * (&s.z - &s.h * &xm);
        let scale = pm.amax().max(1.0);
        for (a, b) in kf.p().iter().zip(p_short.iter()) {
            prop_assert!((a - b).abs() <= 1e-8 * scale, "Joseph {} vs short {}", a, b);
        }
        for (a, b) in kf.x().iter().zip(x_ref.iter()) {
            prop_assert!(relative_eq!(*a, *b, epsilon = 1e-8, max_relative = 1e-8));
        }
    }

    #[test]
    fn reduced_update_equals_update_without_nan_rows(s in system(), mask in prop::collection::vec(any::<bool>(), 6)) {
        let used: Vec<usize> = (0..s.m).filter(|i| mask[*i]).collect();
        prop_assume!(!used.is_empty());
        let mut z_nan = s.z.clone();
        for (i, keep) in mask.iter().take(s.m).enumerate() {
            if !keep { z_nan[i] = f64::NAN; }
        }
        let mut a = KalmanFilter::new(s.x0.clone(), s.p0.clone()).unwrap();
        let mut b = a.clone();
        let ia = a.update(&z_nan, &s.h, &s.r).unwrap();
        let ib = b.update(
            &s.z.select_rows(&used),
            &s.h.select_rows(&used),
            &s.r.select_rows(&used).select_columns(&used),
        ).unwrap();
        prop_assert_eq!(ia.dof(), used.len());
        prop_assert!(relative_eq!(ia.statistic, ib.statistic, max_relative = 1e-12, epsilon = 1e-14));
        prop_assert!(relative_eq!(a.x(), b.x(), max_relative = 1e-12, epsilon = 1e-14));
        prop_assert!(relative_eq!(a.p(), b.p(), max_relative = 1e-12, epsilon = 1e-14));
        for (ri, &i) in used.iter().enumerate() {
            prop_assert_eq!(ia.residual[i], ib.residual[ri]);
        }
        for (i, &keep) in mask.iter().take(s.m).enumerate() {
            prop_assert_eq!(ia.used[i], keep);
            if !keep { prop_assert!(ia.residual[i].is_nan()); }
        }
    }

    #[test]
    fn statistic_is_whitened_residual_norm(s in system()) {
        let mut kf = KalmanFilter::new(s.x0.clone(), s.p0.clone()).unwrap();
        let inn = kf.update(&s.z, &s.h, &s.r).unwrap();
        let a_inv = inn.covariance.clone().try_inverse().unwrap();
        let reference = (inn.residual.transpose() * a_inv * &inn.residual)[(0, 0)];
        prop_assert!(relative_eq!(inn.statistic, reference, max_relative = 1e-8, epsilon = 1e-10));
    }
}
