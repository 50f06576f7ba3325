//! Tests of [`super`] (the INS error-state filter): updates, propagation and the error
//! model against the mechanisation.

use super::*;

/// The IMU noise figures of the error-filter unit tests (also used by the range-error
/// states' tests).
pub(crate) fn noise() -> ImuNoise {
    ImuNoise {
        gyro_noise: [1e-3; 3],
        accel_noise: [1e-3; 3],
        gyro_bias: 1e-4,
        accel_bias: 1e-3,
        bias_tau: 3600.0,
        gyro_scale: 0.0,
        accel_scale: 0.0,
    }
}

#[test]
fn position_update_pulls_state_to_fix() {
    let mut s = NavState {
        lat: 0.7,
        lon: 0.2,
        h: 10.0,
        v: Vector3::zeros(),
        q: UnitQuaternion::identity(),
    };
    let mut kf = ErrorFilter::<N>::new(10.0, 1.0, Vector3::repeat(0.01), Vector3::zeros(), noise());
    // INS 3 m north of a fix with σ 0.1 m: the update moves it almost all the way.
    let res = DVector::from_vec(vec![3.0, 0.0, 0.0]);
    let mut h = DMatrix::zeros(3, N);
    for i in 0..3 {
        h[(i, R + i)] = 1.0;
    }
    let r = DMatrix::identity(3, 3) * 0.01;
    let inn = kf.innovation(&res, &h, &r).unwrap();
    assert!((inn.lambda - 9.0 / (100.0 + 0.01)).abs() < 1e-9);
    let dx = kf.update(&inn, &h, &r).unwrap();
    let lat0 = s.lat;
    kf.feedback(&mut s, &dx);
    let moved = (lat0 - s.lat) * (earth::r_meridian(0.7) + 10.0);
    assert!((moved - 3.0 * 100.0 / 100.01).abs() < 1e-4, "{moved}");
    assert!(kf.p[(0, 0)] < 0.0101);
}

/// Over a gap in the IMU log the velocity and attitude blocks gain the bridging samples'
/// variance beyond the noise densities' (per body axis, through the attitude), and
/// nothing else changes; a rate below the density's square adds nothing.
#[test]
fn propagate_gap_adds_the_bridging_error() {
    let s = NavState {
        lat: 0.7,
        lon: 0.2,
        h: 10.0,
        v: Vector3::new(5.0, 1.0, 0.0),
        q: UnitQuaternion::from_euler_angles(0.1, -0.05, 1.2),
    };
    let mut a = ErrorFilter::<N>::new(10.0, 1.0, Vector3::repeat(0.01), Vector3::zeros(), noise());
    let mut b = a.clone();
    let f = Vector3::new(0.3, -0.2, -9.8);
    let w = Vector3::new(0.01, 0.0, 0.2);
    let (ra, rg) = (
        Vector3::new(4e-4, 1e-7, 1e-6),
        Vector3::new(2e-6, 5e-6, 1e-7),
    );
    a.propagate(&s, &f, &w, 0.05);
    b.propagate_gap(&s, &f, &w, 0.05, &ra, &rg);
    let c = s.q.to_rotation_matrix().into_inner();
    // Densities 1e-3: squares 1e-6; the extra is what exceeds them.
    let more = |r: &Vector3<f64>| {
        c * Matrix3::from_diagonal(&r.map(|x| (x - 1e-6).max(0.0))) * c.transpose() * 0.05
    };
    let d = b.p - a.p;
    let dv = d.fixed_view::<3, 3>(V, V) - more(&ra);
    let da = d.fixed_view::<3, 3>(PHI, PHI) - more(&rg);
    assert!(
        dv.abs().max() < 1e-15 && da.abs().max() < 1e-15,
        "{dv} {da}"
    );
    assert!(more(&ra).abs().max() > 1e-6, "the case adds something");
    let mut rest = d;
    rest.fixed_view_mut::<3, 3>(V, V).fill(0.0);
    rest.fixed_view_mut::<3, 3>(PHI, PHI).fill(0.0);
    assert_eq!(rest.abs().max(), 0.0);
}

/// The error model's transition predicts what the mechanisation does with an error: a
/// state started 5 m too low (δr_D = +5 m) and a true state at rest, both fed the truth's
/// IMU increments for 60 s, differ in down velocity by ∫ (2g/R) δr_D — gravity is
/// stronger below — as Φ δx(0) says (sign and size, to 2 %).
#[test]
fn vertical_channel_follows_the_mechanisation() {
    use crate::ins::strapdown::{mechanise, Increment};
    let lat = 0.7;
    let truth0 = NavState {
        lat,
        lon: 0.3,
        h: 100.0,
        v: Vector3::zeros(),
        q: UnitQuaternion::identity(),
    };
    let dt = 0.01;
    let w_ie = Vector3::new(
        earth::OMEGA_IE * lat.cos(),
        0.0,
        -earth::OMEGA_IE * lat.sin(),
    );
    let f = Vector3::new(0.0, 0.0, -earth::gravity(lat, 100.0));
    let inc = Increment {
        dtheta: w_ie * dt,
        dvel: f * dt,
        dt,
    };
    let (mut truth, mut est) = (truth0, truth0);
    est.h -= 5.0;
    let mut kf = ErrorFilter::<N>::new(1.0, 0.1, Vector3::repeat(0.001), Vector3::zeros(), noise());
    kf.track_transition();
    let mut prev = Increment::zero(dt);
    for _ in 0..6000 {
        kf.propagate(&est, &f, &w_ie, dt);
        mechanise(&mut truth, &prev, &inc);
        mechanise(&mut est, &prev, &inc);
        prev = inc;
    }
    let mut dx0 = SVector::<f64, N>::zeros();
    dx0[R + 2] = 5.0;
    let predicted = kf.take_transition() * dx0;
    let dv_d = est.v.z - truth.v.z;
    assert!(dv_d > 0.0, "the lower state falls faster: {dv_d}");
    assert!(
        (predicted[V + 2] - dv_d).abs() < 0.02 * dv_d.abs(),
        "error model {} m/s, mechanisation {dv_d} m/s",
        predicted[V + 2]
    );
}

#[test]
fn covariance_grows_without_aiding() {
    let s = NavState {
        lat: 0.7,
        lon: 0.2,
        h: 10.0,
        v: Vector3::zeros(),
        q: UnitQuaternion::identity(),
    };
    let mut kf =
        ErrorFilter::<N>::new(0.1, 0.01, Vector3::repeat(0.001), Vector3::zeros(), noise());
    let f = Vector3::new(0.0, 0.0, -9.8);
    let p0 = kf.p[(0, 0)];
    for _ in 0..1000 {
        kf.propagate(&s, &f, &Vector3::zeros(), 0.01);
    }
    assert!(kf.p[(0, 0)] > p0 && kf.p[(3, 3)] > 1e-4);
    // Symmetric and positive definite after 1000 steps.
    assert!((kf.p - kf.p.transpose()).norm() < 1e-12);
    assert!(kf.p.cholesky().is_some());
}

/// The update in loops over the static covariance equals the textbook Joseph form
/// A measurement without rows, or with a matrix of the wrong width, is an error naming
/// the shapes (not a panic).
#[test]
fn an_empty_or_misshapen_measurement_is_an_error() {
    let kf = ErrorFilter::<N>::new(2.0, 0.2, Vector3::repeat(0.01), Vector3::zeros(), noise());
    let empty = kf.innovation(
        &DVector::zeros(0),
        &DMatrix::zeros(0, N),
        &DMatrix::zeros(0, 0),
    );
    assert!(
        matches!(empty, Err(Error::Invalid(ref m)) if m.contains("H 0×15")),
        "{empty:?}"
    );
    let narrow = kf.innovation(
        &DVector::zeros(2),
        &DMatrix::zeros(2, N - 1),
        &DMatrix::identity(2, 2),
    );
    assert!(
        matches!(narrow, Err(Error::Invalid(ref m)) if m.contains("H 2×14")),
        "{narrow:?}"
    );
}

/// `(I − KH) P (I − KH)ᵀ + K R Kᵀ` with `K = P Hᵀ S⁻¹`, computed densely, to rounding.
#[test]
fn update_is_the_joseph_form() {
    let mut kf = ErrorFilter::<N>::new(2.0, 0.2, Vector3::repeat(0.01), Vector3::zeros(), noise());
    let st = NavState {
        lat: 0.6,
        lon: 0.1,
        h: 50.0,
        v: Vector3::new(8.0, -3.0, 0.2),
        q: UnitQuaternion::from_euler_angles(0.02, -0.01, 1.1),
    };
    for _ in 0..50 {
        kf.propagate(
            &st,
            &Vector3::new(0.3, 0.1, -9.8),
            &Vector3::new(0.01, 0.0, 0.02),
            0.01,
        );
    }
    let m = 5;
    let h = DMatrix::from_fn(m, N, |i, j| ((i * 7 + j * 3) % 11) as f64 / 11.0 - 0.4);
    let r = DMatrix::from_fn(
        m,
        m,
        |i, j| if i == j { 0.5 + i as f64 * 0.1 } else { 0.05 },
    );
    let res = DVector::from_fn(m, |i, _| (i as f64).sin());
    let p = DMatrix::from_column_slice(N, N, kf.p.as_slice());
    let s = &h * &p * h.transpose() + &r;
    let k = &p * h.transpose() * s.clone().try_inverse().unwrap();
    let ikh = DMatrix::<f64>::identity(N, N) - &k * &h;
    let pj = &ikh * &p * ikh.transpose() + &k * &r * k.transpose();
    let inn = kf.innovation(&res, &h, &r).unwrap();
    assert!((&inn.s - &s).abs().max() < 1e-12 * s.abs().max());
    let dx = kf.update(&inn, &h, &r).unwrap();
    let dxj = &k * &res;
    for i in 0..N {
        assert!((dx[i] - dxj[i]).abs() < 1e-10 * dxj.abs().max(), "dx[{i}]");
        for j in 0..N {
            assert!(
                (kf.p[(i, j)] - pj[(i, j)]).abs() < 1e-10 * pj.abs().max(),
                "P[{i},{j}]"
            );
        }
    }
    // A mismatched innovation is refused, the filter untouched.
    let before = kf.p;
    let h2 = DMatrix::from_fn(2, N, |i, j| h[(i, j)]);
    assert!(kf.update(&inn, &h2, &r).is_err());
    assert_eq!(kf.p, before);
}

#[test]
fn sequential_update_equals_the_batch_and_clocks_follow_their_drift() {
    let s = NavState {
        lat: 0.7,
        lon: 0.2,
        h: 10.0,
        v: Vector3::new(1.0, 0.5, 0.0),
        q: UnitQuaternion::from_euler_angles(0.01, -0.02, 0.5),
    };
    let kf =
        ErrorFilter::<N_CLOCK>::new(3.0, 0.3, Vector3::repeat(0.02), Vector3::zeros(), noise())
            .with_clock([100.0, 102.0, -60.0], [10.0, 10.0, 1.0], (0.1, 0.1));
    // Eight range-like rows with unit vectors, clock columns, and four rate-like rows.
    let m = 12;
    let mut h = DMatrix::zeros(m, N_CLOCK);
    let mut res = DVector::zeros(m);
    for i in 0..m {
        let a = i as f64 * 0.7;
        let e = Vector3::new(a.cos() * 0.6, a.sin() * 0.6, -0.8);
        let (blk, clk) = if i < 8 { (R, CB + i % 2) } else { (V, CD) };
        for q in 0..3 {
            h[(i, blk + q)] = -e[q];
            h[(i, PHI + q)] = 0.01 * e[(q + 1) % 3];
        }
        h[(i, clk)] = 1.0;
        res[i] = (i as f64 * 1.3).sin() * 2.0;
    }
    let r_diag: Vec<f64> = (0..m)
        .map(|i| if i < 8 { 1.0 + i as f64 * 0.1 } else { 0.01 })
        .collect();
    let r = DMatrix::from_diagonal(&DVector::from_column_slice(&r_diag));
    let (p_seq, dx_seq, lambda) = kf.sequential(&res, &h, &r_diag).unwrap();
    let mut batch = kf.clone();
    let inn = batch.innovation(&res, &h, &r).unwrap();
    let dx = batch.update(&inn, &h, &r).unwrap();
    assert!(
        (lambda - inn.lambda).abs() < 1e-9 * inn.lambda.max(1.0),
        "{lambda} vs {}",
        inn.lambda
    );
    assert!((dx_seq - dx).norm() < 1e-9 * dx.norm().max(1.0));
    assert!((p_seq - batch.p).norm() < 1e-9 * batch.p.norm());
    // The clock estimates integrate the drift; feedback removes the clock errors.
    let mut kf = kf;
    let mut st = s;
    kf.propagate(&st, &Vector3::new(0.0, 0.0, -9.8), &Vector3::zeros(), 0.25);
    assert!((kf.clock[0] - (100.0 - 15.0)).abs() < 1e-12 && (kf.clock[1] - 87.0).abs() < 1e-12);
    assert!(
        kf.p[(CB, CD)] > 0.0,
        "the bias error correlates with the drift error"
    );
    let mut d = SVector::<f64, N_CLOCK>::zeros();
    d[CB] = 2.0;
    d[CD] = -0.5;
    kf.feedback(&mut st, &d);
    assert!((kf.clock[0] - 83.0).abs() < 1e-12 && (kf.clock[2] + 59.5).abs() < 1e-12);
}
