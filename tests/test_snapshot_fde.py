"""Snapshot least squares + FDE (METHODS §10) against an independent numpy implementation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

import navfdi

R_EARTH = 6_378_137.0


def random_scene(rng: np.random.Generator, n: int, min_el: float = 10.0):
    """A receiver near the surface and ``n`` satellites at GPS radius above ``min_el``."""
    lat, lon = rng.uniform(-1.2, 1.2), rng.uniform(-math.pi, math.pi)
    up = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
    east = np.array([-math.sin(lon), math.cos(lon), 0.0])
    north = np.cross(up, east)
    rx = (R_EARTH + rng.uniform(0, 1000)) * up
    sats = []
    while len(sats) < n:
        el = math.radians(rng.uniform(min_el, 90))
        az = rng.uniform(0, 2 * math.pi)
        d = math.cos(el) * (math.sin(az) * east + math.cos(az) * north) + math.sin(el) * up
        # distance along d to the sphere of radius 26 560 km
        b = rx @ d
        s = -b + math.sqrt(b * b - rx @ rx + 26_560_000.0**2)
        sats.append(rx + s * d)
    return rx, np.array(sats)


def numpy_wls(sats, rho, D, x0=None, iters=30):
    """Gauss-Newton WLS (independent of navfdi): returns x = [r, b], B, l at the solution."""
    x = np.zeros(4) if x0 is None else np.array(x0, float)
    Dinv = np.linalg.inv(D)
    for _ in range(iters):
        d = sats - x[:3]
        rng_ = np.linalg.norm(d, axis=1)
        B = np.hstack([-d / rng_[:, None], np.ones((len(rho), 1))])
        l = rho - (rng_ + x[3])
        dx = np.linalg.solve(B.T @ Dinv @ B, B.T @ Dinv @ l)
        x = x + dx
        if np.linalg.norm(dx) < 1e-7:
            break
    d = sats - x[:3]
    rng_ = np.linalg.norm(d, axis=1)
    B = np.hstack([-d / rng_[:, None], np.ones((len(rho), 1))])
    l = rho - (rng_ + x[3])
    return x, B, l


def numpy_test(B, l, D):
    """V, D_V, VᵀD⁻¹V and the general w-test, written from the formulas."""
    Dinv = np.linalg.inv(D)
    N = B.T @ Dinv @ B
    Ninv = np.linalg.inv(N)
    V = -(np.eye(len(l)) - B @ Ninv @ B.T @ Dinv) @ l
    DV = D - B @ Ninv @ B.T
    T = V @ Dinv @ V
    w = np.array([(Dinv[i] @ V) / math.sqrt(Dinv[i] @ DV @ Dinv[:, i]) for i in range(len(l))])
    return V, DV, T, w


@pytest.mark.parametrize("correlated", [False, True])
def test_linear_test_matches_numpy(correlated):
    """V, D_V, VᵀD⁻¹V and w of the linear model, 1e-9 against the formulas in numpy."""
    rng = np.random.default_rng(17 if correlated else 13)
    for _ in range(50):
        n = int(rng.integers(5, 16))
        rx, sats = random_scene(rng, n)
        d = sats - rx
        B = np.hstack([-d / np.linalg.norm(d, axis=1)[:, None], np.ones((n, 1))])
        sig = rng.uniform(0.5, 5.0, n)
        if correlated:
            A = rng.normal(size=(n, n)) * 0.4
            D = np.diag(sig**2) + A @ A.T
        else:
            D = np.diag(sig**2)
        l = np.linalg.cholesky(D) @ rng.normal(size=n) + rng.normal(size=n) * 3
        V, DV, T, w = numpy_test(B, l, D)
        got = navfdi.ls_test(B, l, D)
        np.testing.assert_allclose(got["v"], V, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(got["dv"], DV, rtol=1e-9, atol=1e-9 * np.abs(D).max())
        assert got["statistic"] == pytest.approx(T, rel=1e-9)
        np.testing.assert_allclose(got["w"], w, rtol=1e-9, atol=1e-9)
        assert got["dof"] == n - 4
        if not correlated:
            np.testing.assert_allclose(got["w"], V / np.sqrt(np.diag(DV)), rtol=1e-9, atol=1e-9)
            g2 = navfdi.ls_test(B, l, sig)  # sigma form
            np.testing.assert_allclose(g2["w"], got["w"], rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("correlated", [False, True])
def test_snapshot_matches_numpy_on_random_geometries(correlated):
    """The whole nonlinear snapshot (Gauss-Newton + test) against numpy. Ranges of 2e7 m
    carry a rounding floor of about 4e-9 m each, so residuals agree to ~1e-8 m and the
    statistic and w to ~1e-8 relative; the linear algebra itself is checked at 1e-9 above."""
    rng = np.random.default_rng(7 if correlated else 3)
    for _ in range(40):
        n = int(rng.integers(6, 14))
        rx, sats = random_scene(rng, n)
        sig = rng.uniform(0.5, 5.0, n)
        if correlated:
            A = rng.normal(size=(n, n)) * 0.4
            D = np.diag(sig**2) + A @ A.T
        else:
            D = np.diag(sig**2)
        clock = rng.uniform(-1e4, 1e4)
        rho = np.linalg.norm(sats - rx, axis=1) + clock + np.linalg.cholesky(D) @ rng.normal(size=n)
        # a tiny alpha: the first test is the final one
        res = navfdi.snapshot_fde(sats, rho, D if correlated else sig, alpha=1e-12)
        x, B, l = numpy_wls(sats, rho, D)
        V, DV, T, w = numpy_test(B, l, D)
        assert res.status == "passed"
        np.testing.assert_allclose(res.position, x[:3], rtol=0, atol=1e-6)
        assert res.clock == pytest.approx(x[3], abs=1e-6)
        assert res.statistic == pytest.approx(T, rel=1e-7, abs=1e-7)
        np.testing.assert_allclose(res.w, w, rtol=1e-7, atol=1e-7)
        assert res.dof == n - 4
        assert res.threshold == pytest.approx(stats.chi2.isf(1e-12, n - 4), rel=1e-9)


def test_ten_sigma_fault_is_excluded_exactly():
    rng = np.random.default_rng(11)
    for trial in range(30):
        rx, sats = random_scene(rng, 10, min_el=15.0)
        sig = np.full(10, 2.0)
        rho = np.linalg.norm(sats - rx, axis=1) + 100.0
        bad = trial % 10
        rho[bad] += 10 * sig[bad]
        res = navfdi.snapshot_fde(sats, rho, sig)
        assert res.excluded == [bad], (trial, res)
        assert res.status == "excluded"
        assert math.isnan(res.w[bad])
        np.testing.assert_allclose(res.position, rx, atol=1e-4)


def test_ten_sigma_fault_with_noise_is_the_first_excluded():
    rng = np.random.default_rng(12)
    first = 0
    trials = 500
    for trial in range(trials):
        rx, sats = random_scene(rng, 10, min_el=15.0)
        sig = np.full(10, 2.0)
        rho = np.linalg.norm(sats - rx, axis=1) + sig * rng.normal(size=10)
        bad = trial % 10
        rho[bad] += 10 * sig[bad]
        res = navfdi.snapshot_fde(sats, rho, sig)
        first += bool(res.excluded) and res.excluded[0] == bad
    assert first / trials >= 0.97


def test_global_false_alarm_rate_inside_binomial_interval():
    rng = np.random.default_rng(5)
    alpha, n_epochs = 0.05, 100_000
    rx, sats = random_scene(rng, 10)
    sig = np.full(10, 3.0)
    truth = np.linalg.norm(sats - rx, axis=1)
    noise = rng.normal(size=(n_epochs, 10)) * sig
    x0 = np.append(rx + 50.0, 0.0)
    alarms = 0
    for k in range(n_epochs):
        res = navfdi.snapshot_fde(sats, truth + noise[k], sig, alpha=alpha, x0=x0)
        t, thr, _ = res.first_test
        alarms += t >= thr
    lo, hi = stats.binom.interval(0.99, n_epochs, alpha)
    assert lo <= alarms <= hi, (alarms, lo, hi)


def test_default_k_and_no_solution():
    rng = np.random.default_rng(1)
    rx, sats = random_scene(rng, 4)
    rho = np.linalg.norm(sats - rx, axis=1)
    res = navfdi.snapshot_fde(sats, rho, np.ones(4))
    assert res.status == "no_solution"
    assert res.position is None and res.clock is None
    assert "u + 1 = 5" in res.reason
    assert np.isnan(res.w).all()


@pytest.mark.parametrize(
    "args, match",
    [
        ((np.zeros((5, 2)), np.zeros(5), np.ones(5)), "sat_pos"),
        ((np.zeros((5, 3)), np.zeros(4), np.ones(5)), "pseudoranges"),
        ((np.zeros((5, 3)), np.zeros(5), np.ones(4)), "sigma"),
        ((np.zeros((5, 3)), np.zeros(5), -np.ones(5)), r"sigma\[0\]"),
        ((np.zeros((5, 3)), np.full(5, np.nan), np.ones(5)), "pseudoranges"),
        ((np.full((5, 3), np.inf), np.zeros(5), np.ones(5)), "sat_pos"),
        ((np.zeros((5, 3)), np.zeros(5), -np.eye(5)), "sigma"),
        ((np.zeros((0, 3)), np.zeros(0), np.ones(0)), "sat_pos"),
    ],
)
def test_bad_input_is_named(args, match):
    with pytest.raises(ValueError, match=match):
        navfdi.snapshot_fde(*args)


def test_ls_test_bad_input():
    B = np.ones((3, 4))
    with pytest.raises(ValueError, match="B: expected shape"):
        navfdi.ls_test(B, np.zeros(3), np.eye(3))
    B = np.random.default_rng(0).normal(size=(6, 2))
    with pytest.raises(ValueError, match="l"):
        navfdi.ls_test(B, np.zeros(5), np.eye(6))
    with pytest.raises(ValueError, match="D"):
        navfdi.ls_test(B, np.zeros(6), -np.eye(6))
    with pytest.raises(navfdi.LinAlgError, match="singular"):
        navfdi.ls_test(np.zeros((6, 2)), np.zeros(6), np.eye(6))


def test_bad_parameters_are_named():
    rng = np.random.default_rng(2)
    rx, sats = random_scene(rng, 8)
    rho = np.linalg.norm(sats - rx, axis=1)
    with pytest.raises(ValueError, match="alpha"):
        navfdi.snapshot_fde(sats, rho, np.ones(8), alpha=1.5)
    with pytest.raises(ValueError, match="k"):
        navfdi.snapshot_fde(sats, rho, np.ones(8), k=-1)
    with pytest.raises(ValueError, match="x0"):
        navfdi.snapshot_fde(sats, rho, np.ones(8), x0=[1, 2])


def test_layouts_read_in_logical_order():
    rng = np.random.default_rng(4)
    rx, sats = random_scene(rng, 9)
    rho = np.linalg.norm(sats - rx, axis=1) + rng.normal(size=9)
    a = navfdi.snapshot_fde(np.ascontiguousarray(sats), rho, np.ones(9))
    b = navfdi.snapshot_fde(np.asfortranarray(sats), rho[::-1].copy()[::-1], np.ones(9))
    c = navfdi.snapshot_fde(sats.T.copy().T, rho, np.ones(9))
    for r in (b, c):
        np.testing.assert_array_equal(a.position, r.position)
        np.testing.assert_array_equal(a.w, r.w)


def test_enormous_problems_are_refused_before_allocating():
    n = 300_000  # n × n work matrices: terabytes
    with pytest.raises(MemoryError, match="observations"):
        navfdi.snapshot_fde(np.ones((n, 3)), np.zeros(n), np.ones(n))
    with pytest.raises(MemoryError, match="observations"):
        navfdi.ls_test(np.ones((n, 4)), np.zeros(n), np.ones(n))
