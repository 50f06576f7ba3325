"""Channel prefilter of an ultra-tight receiver (paper 004, METHODS §11) against a numpy
Kalman filter, its innovation statistics, the discriminator noise formulas and bad input."""

from __future__ import annotations

import copy
import math
import pickle

import numpy as np
import pytest
from scipy import stats

import navfdi

BETA = 1.023e6 / 1575.42e6


def numpy_step(x, P, Phi, Q, z, r):
    """Predict + update with H = [I₂ 0] over the non-NaN components of z (Joseph form)."""
    x = Phi @ x
    P = Phi @ P @ Phi.T + Q
    used = ~np.isnan(z)
    H = np.eye(3)[:2][used]
    R = np.diag(r[used])
    A = H @ P @ H.T + R
    v = z[used] - H @ x
    K = P @ H.T @ np.linalg.inv(A)
    x = x + K @ v
    IKH = np.eye(3) - K @ H
    P = IKH @ P @ IKH.T + K @ R @ K.T
    return x, (P + P.T) / 2, float(v @ np.linalg.solve(A, v))


def test_discriminator_noise_follows_kaplan_hegarty():
    """Eq. 5.71 and 5.64 with B = 1/(2T) written out independently."""
    for cn0 in (28.0, 35.0, 48.0):
        c, T = 10 ** (cn0 / 10), 0.02
        for d in (0.5, 1.0):
            want = (1 / (2 * T)) * d / (2 * c) * (1 + 2 / ((2 - d) * T * c))
            assert navfdi.dll_variance(cn0, T, d) == pytest.approx(want, rel=1e-12)
        for F in (1, 2):
            want = (1 / (2 * math.pi * T)) ** 2 * 4 * F * (1 / (2 * T)) / c * (1 + 1 / (T * c))
            assert navfdi.fll_variance(cn0, T, F == 2) == pytest.approx(want, rel=1e-12)
    # At 48 dB-Hz, 20 ms, 1 chip: σ ≈ 0.0141 chips (≈ 4.1 m) and ≈ 0.32 Hz (≈ 6 cm/s).
    assert math.sqrt(navfdi.dll_variance(48.0)) * 293.05 == pytest.approx(4.13, abs=0.02)
    assert math.sqrt(navfdi.fll_variance(48.0)) * 0.1903 == pytest.approx(0.0603, abs=0.001)


def test_matches_a_numpy_kalman_filter_with_missing_outputs():
    rng = np.random.default_rng(2)
    pf = navfdi.Prefilter(jerk_psd=3.0, code_psd=1e-6, x0=[0.01, 0.5, 0.0], P0=np.diag([1e-3, 4.0, 1.0]))
    x, P = np.array([0.01, 0.5, 0.0]), np.diag([1e-3, 4.0, 1.0])
    Phi, Q = pf.phi, pf.q
    np.testing.assert_allclose(Phi, [[1, BETA * 0.02, BETA * 0.02**2 / 2], [0, 1, 0.02], [0, 0, 1]], rtol=1e-15)
    r = np.array([navfdi.dll_variance(40.0), navfdi.fll_variance(40.0)])
    for k in range(500):
        z = rng.normal(size=2) * np.sqrt(r)
        if k % 7 == 3:
            z[0] = np.nan
        if k % 11 == 5:
            z[1] = np.nan
        if k % 77 == 38:
            z[:] = np.nan
        out = pf.step(z[0], z[1], 40.0)
        if np.isnan(z).all():
            x, P = Phi @ x, Phi @ P @ Phi.T + Q
            assert np.isnan(out.statistic) and out.dof == 0
        else:
            x, P, lam = numpy_step(x, P, Phi, Q, z, r)
            assert out.statistic == pytest.approx(lam, rel=1e-9)
            assert out.dof == int((~np.isnan(z)).sum())
        np.testing.assert_allclose(pf.x, x, rtol=1e-9, atol=1e-14)
        np.testing.assert_allclose(pf.P, P, rtol=1e-9, atol=1e-18)


def test_innovations_are_chi_square_on_simulated_tracking_errors():
    """Truth from the prefilter's own model (jerk random walk), discriminators with the
    formulas' noise: λ ~ χ²(2), mean 2, 99 % of the epochs below the 99 % quantile."""
    rng = np.random.default_rng(5)
    pf = navfdi.Prefilter(jerk_psd=5.0)
    Phi, Q = pf.phi, pf.q
    L = np.linalg.cholesky(Q + np.eye(3) * 1e-30)
    cn0 = 45.0
    sd = np.sqrt([navfdi.dll_variance(cn0), navfdi.fll_variance(cn0)])
    truth = rng.multivariate_normal(np.zeros(3), np.diag([0.01, 1.0, 1.0]))
    lams = []
    for k in range(20_000):
        truth = Phi @ truth + L @ rng.normal(size=3)
        z = truth[:2] + sd * rng.normal(size=2)
        lams.append(pf.step(z[0], z[1], cn0).statistic)
    lam = np.array(lams[200:])
    assert lam.mean() == pytest.approx(2.0, rel=0.04)
    frac = (lam > stats.chi2.ppf(0.99, 2)).mean()
    lo, hi = stats.binom.interval(0.999, lam.size, 0.01)
    assert lo / lam.size <= frac <= hi / lam.size, frac


def test_a_code_ramp_shows_in_the_aime_of_the_innovations():
    """A pseudorange ramp on the channel (code error growing at 0.5 m/s with no matching
    carrier frequency, as a multipath or spoofing ramp) cannot be absorbed by the prefilter's
    frequency states, which the frequency discriminator pins: its code innovations keep a
    bias that a 2 s AIME on them (pf = 0.001) flags. Without the ramp the AIME stays near pf."""

    def run(slope_m_s, seed):
        rng = np.random.default_rng(seed)
        pf = navfdi.Prefilter(jerk_psd=1.0)
        det = navfdi.Aime(0.001, 100)
        cn0 = 48.0
        sd = np.sqrt([navfdi.dll_variance(cn0), navfdi.fll_variance(cn0)])
        alarms = np.zeros(1500, bool)
        for k in range(1500):
            code = slope_m_s * max(k * 0.02 - 10.0, 0.0) / 293.05  # chips
            z = np.array([code, 0.0]) + sd * rng.normal(size=2)
            s = pf.step(z[0], z[1], cn0)
            alarms[k] = det.test(s.residual[:1], s.covariance[:1, :1]).alarm
        return alarms

    t = np.arange(1500) * 0.02
    for seed in range(5):
        ramp, clean = run(0.5, seed), run(0.0, seed)
        assert ramp[t >= 20].mean() > 0.9, seed
        first = t[(t >= 10) & ramp][0]
        assert 10 < first < 20, first
        assert clean[t >= 2].mean() < 0.01, seed


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(t=0.0), "t"),
        (dict(t=2.0), "t"),
        (dict(beta=-1.0), "beta"),
        (dict(jerk_psd=-1.0), "jerk_psd"),
        (dict(code_psd=float("nan")), "code_psd"),
        (dict(spacing=2.0), "spacing"),
        (dict(x0=[0, 0]), "x0"),
        (dict(x0=[0, np.nan, 0]), "x0"),
        (dict(P0=-np.eye(3)), "P0"),
        (dict(P0=np.eye(2)), "P0"),
    ],
)
def test_bad_parameters_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        navfdi.Prefilter(**kwargs)


def test_bad_steps_change_nothing_and_pickle_continues():
    pf = navfdi.Prefilter()
    pf.step(0.001, 0.1, 45.0)
    before = pickle.dumps(pf)
    with pytest.raises(ValueError, match="cn0"):
        pf.step(0.0, 0.0, 120.0)
    with pytest.raises(ValueError, match="z_code"):
        pf.step(float("inf"), 0.0, 45.0)
    with pytest.raises(ValueError, match="dx"):
        pf.shift([0.0, float("nan"), 0.0])
    assert pickle.dumps(pf) == before
    a, b = pickle.loads(before), copy.deepcopy(pf)
    for k in range(20):
        s = pf.step(0.001 * k, 0.1, 45.0)
        for o in (a, b):
            assert o.step(0.001 * k, 0.1, 45.0).statistic == s.statistic
    pf.shift([0.5, 0.0, 0.0])
    assert pf.x[0] == pytest.approx(a.x[0] + 0.5)
