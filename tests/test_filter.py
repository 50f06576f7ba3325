"""KalmanFilter and run_filter against the plain-numpy reference."""

from __future__ import annotations

import numpy as np
import pytest

import navfdi
from reference import predict, random_spd, random_system, update

RTOL = 1e-9


def assert_close(a, b, rtol=RTOL):
    """Relative tolerance with an absolute floor scaled to the array (for near-zero entries)."""
    b = np.asarray(b)
    scale = np.nanmax(np.abs(b)) if np.any(np.isfinite(b)) else 1.0
    np.testing.assert_allclose(a, b, rtol=rtol, atol=rtol * max(scale, 1e-300), equal_nan=True)


@pytest.mark.parametrize("seed", range(12))
def test_step_api_matches_numpy(seed):
    rng = np.random.default_rng(seed)
    n, m, T = int(rng.integers(1, 9)), int(rng.integers(1, 7)), 25
    x0, P0, Phi, Q, zs, H, R = random_system(rng, n, m, T)
    zs[rng.random(zs.shape) < 0.15] = np.nan  # some missing components
    kf = navfdi.KalmanFilter(x0, P0)
    x, P = x0.copy(), P0.copy()
    fading = 1.0 + 0.05 * (seed % 3)
    for k in range(T):
        kf.predict(Phi[k], Q[k], fading=fading)
        x, P = predict(x, P, Phi[k], Q[k], fading)
        inn = kf.update(zs[k], H[k], R[k])
        x, P, r, A, lam, used = update(x, P, zs[k], H[k], R[k])
        assert_close(kf.x, x)
        assert_close(kf.P, P)
        assert_close(inn.residual, r)
        assert_close(inn.covariance, A)
        np.testing.assert_array_equal(inn.used, used)
        assert inn.dof == used.sum()
        if used.any():
            assert inn.statistic == pytest.approx(lam, rel=RTOL)
        else:
            assert np.isnan(inn.statistic)


@pytest.mark.parametrize("seed", range(6))
def test_run_filter_matches_numpy(seed):
    rng = np.random.default_rng(100 + seed)
    n, m, T = int(rng.integers(2, 9)), int(rng.integers(1, 7)), 40
    x0, P0, Phi, Q, zs, H, R = random_system(rng, n, m, T)
    zs[rng.random(zs.shape) < 0.1] = np.nan
    # Mix constant and per-epoch matrices.
    args = dict(Phi=Phi, Q=Q[0], H=H, R=R[0]) if seed % 2 else dict(Phi=Phi[0], Q=Q, H=H[0], R=R)
    run = navfdi.run_filter(x0, P0, zs=zs, **args)
    assert run.x.shape == (T, n) and run.P.shape == (T, n, n)
    assert run.residual.shape == (T, m) and run.covariance.shape == (T, m, m)
    assert run.statistic.shape == (T,) and run.used.shape == (T, m)
    x, P = x0.copy(), P0.copy()
    for k in range(T):
        get = lambda M: M if M.ndim == 2 else M[k]  # noqa: E731
        x, P = predict(x, P, get(args["Phi"]), get(args["Q"]))
        x, P, r, A, lam, used = update(x, P, zs[k], get(args["H"]), get(args["R"]))
        assert_close(run.x[k], x)
        assert_close(run.P[k], P)
        assert_close(run.residual[k], r)
        assert_close(run.covariance[k], A)
        np.testing.assert_array_equal(run.used[k], used)
        if used.any():
            assert run.statistic[k] == pytest.approx(lam, rel=RTOL)


def test_run_filter_equals_step_api():
    rng = np.random.default_rng(7)
    x0, P0, Phi, Q, zs, H, R = random_system(rng, 5, 3, 30)
    run = navfdi.run_filter(x0, P0, Phi, Q, zs, H, R, fading=1.02)
    kf = navfdi.KalmanFilter(x0, P0)
    for k in range(30):
        kf.predict(Phi[k], Q[k], 1.02)
        inn = kf.update(zs[k], H[k], R[k])
        np.testing.assert_array_equal(kf.x, run.x[k])
        np.testing.assert_array_equal(kf.P, run.P[k])
        assert inn.statistic == run.statistic[k]


def test_reduced_update_equals_removed_rows():
    rng = np.random.default_rng(3)
    n, m = 6, 5
    P0 = random_spd(rng, n)
    H, R, z = rng.standard_normal((m, n)), random_spd(rng, m), rng.standard_normal(m)
    keep = np.array([True, False, True, True, False])
    z_nan = z.copy()
    z_nan[~keep] = np.nan
    a, b = navfdi.KalmanFilter(np.zeros(n), P0), navfdi.KalmanFilter(np.zeros(n), P0)
    ia = a.update(z_nan, H, R)
    ib = b.update(z[keep], H[keep], R[np.ix_(keep, keep)])
    assert_close(a.x, b.x, 1e-12)
    assert_close(a.P, b.P, 1e-12)
    assert ia.statistic == pytest.approx(ib.statistic, rel=1e-12)
    assert_close(ia.residual[keep], ib.residual, 1e-12)
    assert np.isnan(ia.residual[~keep]).all()
    np.testing.assert_array_equal(ia.used, keep)


def test_statistic_is_chi_square_under_h0():
    """A well-specified filter's λ has mean m (χ²(m)) over many epochs."""
    rng = np.random.default_rng(11)
    n, m, T = 2, 2, 20000
    Phi = np.array([[1.0, 1.0], [0.0, 1.0]])
    Q = np.diag([0.01, 0.001])
    H, R = np.eye(2), np.eye(2)
    x = np.zeros(n)
    zs = np.empty((T, m))
    L = np.linalg.cholesky(Q)
    for k in range(T):
        x = Phi @ x + L @ rng.standard_normal(n)
        zs[k] = H @ x + rng.standard_normal(m)
    run = navfdi.run_filter(np.zeros(n), np.eye(n), Phi, Q, zs, H, R)
    lam = run.statistic[100:]
    # Mean of χ²(2) is 2 with standard error sqrt(4/N) ≈ 0.014; allow 4 standard errors.
    assert abs(lam.mean() - 2.0) < 4 * np.sqrt(4.0 / lam.size)


def test_properties_are_copies():
    kf = navfdi.KalmanFilter([1.0, 2.0], np.eye(2))
    x = kf.x
    x[0] = 99.0
    assert kf.x[0] == 1.0
    assert kf.dim == 2


def test_accepts_lists_and_integer_arrays():
    kf = navfdi.KalmanFilter([0, 0], [[1, 0], [0, 1]])
    kf.predict([[1, 0], [0, 1]], [[0, 0], [0, 0]])
    inn = kf.update([1, 2], np.eye(2, dtype=int), [[1, 0], [0, 1]])
    assert inn.residual.dtype == np.float64
    np.testing.assert_allclose(kf.x, [0.5, 1.0])


def test_predict_rechecks_a_q_that_changed():
    """An identical Q is checked once; any change (even in place) is checked again."""
    kf = navfdi.KalmanFilter(np.zeros(3), np.eye(3))
    Q = np.eye(3) * 0.1
    kf.predict(np.eye(3), Q)
    kf.predict(np.eye(3), Q)
    Q[0, 1] = 5.0  # mutated in place: no longer symmetric
    before = kf.P.copy()
    with pytest.raises(ValueError, match="Q"):
        kf.predict(np.eye(3), Q)
    np.testing.assert_array_equal(kf.P, before)
    Qn = np.eye(3) * 0.1
    Qn[0, 0] = -1.0
    with pytest.raises(ValueError, match="Q"):
        kf.predict(np.eye(3), Qn)
    kf.predict(np.eye(3), np.eye(3) * 0.1)


@pytest.mark.parametrize("seed", range(4))
def test_a_fixed_model_step_is_predict_then_update_to_the_bit(seed):
    rng = np.random.default_rng(seed)
    n, m, T = int(rng.integers(2, 16)), int(rng.integers(1, 7)), 30
    x0, P0, Phi, Q, zs, H, R = random_system(rng, n, m, T)
    zs[rng.random(zs.shape) < 0.1] = np.nan
    a, b = navfdi.KalmanFilter(x0, P0), navfdi.KalmanFilter(x0, P0)
    a.set_model(Phi[0], Q[0], H[0], R[0])
    for k in range(T):
        ia = a.step(zs[k])
        b.predict(Phi[0], Q[0])
        ib = b.update(zs[k], H[0], R[0])
        np.testing.assert_array_equal(a.x, b.x)
        np.testing.assert_array_equal(a.P, b.P)
        np.testing.assert_array_equal(ia.used, ib.used)
        assert (ia.statistic == ib.statistic) or (np.isnan(ia.statistic) and np.isnan(ib.statistic))


def test_a_fixed_model_refuses_bad_input_and_survives_pickling():
    import pickle

    rng = np.random.default_rng(7)
    x0, P0, Phi, Q, zs, H, R = random_system(rng, 4, 2, 3)
    kf = navfdi.KalmanFilter(x0, P0)
    with pytest.raises(ValueError, match="no model"):
        kf.step(zs[0])
    with pytest.raises(ValueError, match="Q"):
        kf.set_model(Phi[0], -np.eye(4), H[0], R[0])
    with pytest.raises(ValueError, match="H"):
        kf.set_model(Phi[0], Q[0], H[0][:, :3], R[0])
    kf.set_model(Phi[0], Q[0], H[0], R[0])
    x, P = kf.x, kf.P
    for bad in ([1.0, 2.0, 3.0], [np.inf, 0.0], [[1.0, 2.0]]):
        with pytest.raises(ValueError):
            kf.step(np.asarray(bad))
    np.testing.assert_array_equal(kf.x, x)
    np.testing.assert_array_equal(kf.P, P)
    back = pickle.loads(pickle.dumps(kf))
    np.testing.assert_array_equal(back.step(zs[1]).residual, kf.step(zs[1]).residual)
