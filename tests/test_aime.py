"""AIME (paper 004, METHODS §11) as a detector on any innovations."""

from __future__ import annotations

import pickle

import numpy as np
import pytest
from scipy import stats

import navfdi


def reference(rs: np.ndarray, As: np.ndarray, n: int) -> np.ndarray:
    """Plain numpy AIME statistic per epoch (window n, all components present)."""
    out = np.empty(len(rs))
    for k in range(len(rs)):
        lo = max(0, k - n + 1)
        inv = np.linalg.inv(As[lo : k + 1])
        S = inv.sum(axis=0)
        s = np.einsum("kij,kj->i", inv, rs[lo : k + 1])
        rbar = np.linalg.solve(S, s)
        out[k] = rbar @ S @ rbar
    return out


def random_cov(rng: np.random.Generator, t: int, m: int) -> np.ndarray:
    L = rng.normal(size=(t, m, m)) * 0.3 + np.eye(m)
    return L @ np.transpose(L, (0, 2, 1)) + 0.1 * np.eye(m)


@pytest.mark.parametrize("m, n", [(1, 1), (2, 5), (4, 20)])
def test_statistic_matches_numpy(m, n):
    rng = np.random.default_rng(m * 10 + n)
    t = 300
    rs = rng.normal(size=(t, m)) * 2.0
    As = random_cov(rng, t, m)
    det = navfdi.Aime(0.01, n)
    run = det.test_sequence(rs, As)
    want = reference(rs, As, n)
    np.testing.assert_allclose(run.statistic, want, rtol=1e-9, atol=1e-12)
    assert np.all(run.threshold == pytest.approx(stats.chi2.ppf(0.99, m)))
    # The per-epoch API gives the same numbers and the same final state.
    d2 = navfdi.Aime(0.01, n)
    got = [d2.test(r, A).statistic for r, A in zip(rs, As)]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-12)
    assert d2.filled == min(n, t)


def test_false_alarm_rate_on_white_innovations():
    # Non-overlapping windows give independent statistics: sample every n-th epoch.
    n, m, pf = 10, 3, 0.01
    rng = np.random.default_rng(7)
    blocks = 20_000
    A = np.eye(m) * 4.0
    rs = rng.normal(size=(n * blocks, m)) * 2.0
    det = navfdi.Aime(pf, n)
    run = det.test_sequence(rs, np.broadcast_to(A, (len(rs), m, m)))
    alarms = int(np.sum(run.alarm[n - 1 :: n]))
    lo, hi = stats.binom.interval(0.99, blocks, pf)
    assert lo <= alarms <= hi, (alarms, lo, hi)


def test_a_small_bias_is_caught_by_averaging_where_chi2_is_not():
    rng = np.random.default_rng(1)
    rs = rng.normal(size=(400, 1))
    rs[200:] += 1.0  # 1 σ bias
    A = np.ones((400, 1, 1))
    aime = navfdi.Aime(1e-3, 30).test_sequence(rs, A)
    chi2 = navfdi.ResidualChi2(1e-3).test_sequence(rs, A)
    assert not aime.alarm[:200].any()
    assert aime.alarm[230:].mean() > 0.9
    assert chi2.alarm[200:].mean() < 0.1


def test_missing_components_pickle_and_bad_input():
    det = navfdi.Aime(0.05, 3)
    d = det.test([1.0, np.nan], np.eye(2))
    assert d.dof == 1 and d.statistic == pytest.approx(1.0)
    none = det.test([np.nan, np.nan], np.eye(2))
    assert np.isnan(none.statistic) and det.filled == 1
    det.test([1.0, 2.0], np.eye(2))
    clone = pickle.loads(pickle.dumps(det))
    a = det.test([0.5, -0.5], np.eye(2) * 2)
    b = clone.test([0.5, -0.5], np.eye(2) * 2)
    assert a.statistic == b.statistic and clone.filled == det.filled
    with pytest.raises(ValueError, match="reset"):
        det.test([1.0], np.eye(1))
    assert det.filled == 3
    with pytest.raises(ValueError, match="window"):
        navfdi.Aime(0.01, 0)
    with pytest.raises(ValueError, match="pf"):
        navfdi.Aime(1.0, 3)
    with pytest.raises(navfdi.LinAlgError):
        det.test([1.0, 1.0], -np.eye(2))
    det.reset()
    assert det.filled == 0
    det.test([1.0], np.eye(1))


def two_stage_reference(rs: np.ndarray, n1: int, n2: int, q: float, b: float) -> np.ndarray:
    """numpy two-stage AIME on scalar unit-variance innovations."""
    s1 = reference(rs, np.ones((len(rs), 1, 1)), n1)
    out = np.full(len(rs), np.nan)
    x, p, r = s1[0], q, 1.0
    nus, vs = [], []
    for k in range(1, len(rs)):
        r = b * r + (1 - b) * 0.5 * (s1[k] - s1[k - 1]) ** 2
        pp = p + q
        nu, v = s1[k] - x, pp + r
        nus.append(nu)
        vs.append(v)
        w = 1 / np.array(vs[-n2:])
        out[k] = (np.sum(w * np.array(nus[-n2:]))) ** 2 / np.sum(w)
        g = pp / v
        x, p = x + g * nu, (1 - g) * pp
    return out


@pytest.mark.parametrize("q, b", [(10.0, 0.99), (0.5, 0.9)])
def test_two_stage_matches_numpy(q, b):
    rng = np.random.default_rng(5)
    rs = rng.normal(size=(200, 1))
    rs[100:, 0] += 0.1 * np.arange(100)
    det = navfdi.TwoStageAime(0.001, 5, 10, q=q, b=b)
    run = det.test_sequence(rs, np.ones((200, 1, 1)))
    np.testing.assert_allclose(run.statistic, two_stage_reference(rs, 5, 10, q, b), rtol=1e-9, atol=1e-12, equal_nan=True)
    assert run.threshold[-1] == pytest.approx(stats.chi2.ppf(0.999, 1))
    assert det.stage1_statistic == pytest.approx(reference(rs, np.ones((200, 1, 1)), 5)[-1])
    clone = pickle.loads(pickle.dumps(det))
    a, c = det.test([1.0], [[1.0]]), clone.test([1.0], [[1.0]])
    assert a.statistic == c.statistic
    with pytest.raises(ValueError, match="q"):
        navfdi.TwoStageAime(0.01, 2, 10, q=0.0)
    with pytest.raises(ValueError, match="b"):
        navfdi.TwoStageAime(0.01, 2, 10, b=1.0)
    with pytest.raises(ValueError, match="window2"):
        navfdi.TwoStageAime(0.01, 2, 0)


def test_two_stage_decimation_from_python():
    """``every``: the statistic filter and stage 2 take every N-th stage-1 statistic; the
    decision is repeated in between; bad values are named; pickling keeps the setting."""
    import pickle

    rng = np.random.default_rng(4)
    d = navfdi.TwoStageAime(1e-3, 5, 4, q=1e-3, b=0.99, every=5, r0=4.0)
    a = np.eye(2)
    decisions = [d.test(rng.normal(size=2), a) for _ in range(60)]
    for i, dec in enumerate(decisions):
        if (i + 1) % 5 != 0 and i > 5:
            prev = decisions[i - 1]
            assert (dec.statistic == prev.statistic or (np.isnan(dec.statistic) and np.isnan(prev.statistic))) and dec.alarm == prev.alarm
    e = pickle.loads(pickle.dumps(d))
    r = rng.normal(size=2)
    assert e.test(r, a).statistic == pytest.approx(d.test(r, a).statistic, nan_ok=True)
    with pytest.raises(ValueError, match="every"):
        navfdi.TwoStageAime(1e-3, 5, 4, every=0)
    with pytest.raises(ValueError, match="r0"):
        navfdi.TwoStageAime(1e-3, 5, 4, every=2, r0=float("nan"))


def test_fresh_two_stage_pickles():
    """A TwoStageAime whose stage-1 statistic is still NaN (fresh, or right after the filter's
    initialisation) survives pickling (JSON has no NaN: written as null, read back as NaN)."""
    import pickle

    for every in (1, 5):
        d = navfdi.TwoStageAime(1e-3, 5, 4, every=every)
        e = pickle.loads(pickle.dumps(d))
        assert np.isnan(e.stage1_statistic)
        for _ in range(every):
            d.test(np.ones(2), np.eye(2))
        e = pickle.loads(pickle.dumps(d))
        r = np.array([0.3, -0.2])
        a, b = d.test(r, np.eye(2)), e.test(r, np.eye(2))
        assert (np.isnan(a.statistic) and np.isnan(b.statistic)) or a.statistic == b.statistic
