"""navfdi.FederatedFilter (per-epoch step API) against a centralised filter, and its errors."""

from __future__ import annotations

import numpy as np
import pytest

import navfdi
from reference import predict, random_spd, update


def make(rng, mode="reset", shares=(0.5, 0.3, 0.2), master_share=0.0, isolation=True):
    n = 4
    dims = [2, 3, 1]
    Hs = [rng.standard_normal((m, n)) for m in dims]
    Rs = [random_spd(rng, m, eps=0.2) for m in dims]
    subs = [
        {"name": f"s{i}", "H": Hs[i], "R": Rs[i], "share": shares[i], "detectors": [{"name": "chi2", "kind": "chi2", "pf": 1e-6}], "isolation": "chi2"}
        for i in range(3)
    ]
    x0, P0 = rng.standard_normal(n), random_spd(rng, n, eps=0.1)
    fed = navfdi.FederatedFilter(x0, P0, subs, mode=mode, master_share=master_share, isolation=isolation)
    return fed, x0, P0, Hs, Rs


@pytest.mark.parametrize(("shares", "master"), [((0.5, 0.3, 0.2), 0.0), ((0.2, 0.2, 0.2), 0.4)])
def test_reset_mode_matches_centralised_filter(shares, master):
    rng = np.random.default_rng(0)
    fed, x0, P0, Hs, Rs = make(rng, shares=shares, master_share=master)
    n = x0.size
    Phi = np.eye(n) + 0.05 * rng.standard_normal((n, n))
    Q = random_spd(rng, n, scale=0.01)
    H = np.vstack(Hs)
    R = np.zeros((6, 6))
    o = 0
    for Ri in Rs:
        R[o : o + Ri.shape[0], o : o + Ri.shape[0]] = Ri
        o += Ri.shape[0]
    x, P = x0.copy(), P0.copy()
    for _ in range(50):
        zs = [rng.standard_normal(h.shape[0]) for h in Hs]
        step = fed.step(Phi, Q, zs)
        x, P = predict(x, P, Phi, Q)
        x, P, *_ = update(x, P, np.concatenate(zs), H, R)
        assert step.sources == 3 + (master > 0)
        np.testing.assert_allclose(step.x, x, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(step.P, P, rtol=1e-9, atol=1e-12 * np.abs(P).max())


def test_isolation_and_decisions():
    rng = np.random.default_rng(1)
    fed, x0, P0, Hs, Rs = make(rng)
    n = x0.size
    for k in range(40):
        zs = [Hs[i] @ np.zeros(n) + 0.01 * rng.standard_normal(Hs[i].shape[0]) for i in range(3)]
        if 20 <= k < 25:
            zs[1] = zs[1] + 1e3  # gross fault on s1
        step = fed.step(np.eye(n), np.eye(n) * 1e-4, zs)
        if 20 <= k < 25:
            assert step.isolated == [False, True, False] and step.fused == [True, False, True]
            assert step.decisions["s1"]["chi2"].alarm
            assert np.abs(step.x).max() < 5.0
    assert fed.isolated == [False, False, False]
    assert fed.names == ["s0", "s1", "s2"]


def test_bad_configuration_and_input():
    rng = np.random.default_rng(2)
    fed, x0, P0, Hs, Rs = make(rng)
    n = x0.size
    good = [{"name": "a", "H": np.eye(2, n), "R": np.eye(2), "share": 1.0}]
    with pytest.raises(ValueError, match="shares must sum to 1"):
        navfdi.FederatedFilter(x0, P0, [{**good[0], "share": 0.5}])
    with pytest.raises(ValueError, match=r"subfilters\[0\] \(a\)\.H: expected shape"):
        navfdi.FederatedFilter(x0, P0, [{**good[0], "H": np.eye(2, n + 1)}])
    with pytest.raises(ValueError, match=r"subfilters\[0\]\.isolation = \"joint\""):
        navfdi.FederatedFilter(x0, P0, [{**good[0], "isolation": "joint"}])
    with pytest.raises(ValueError, match=r"detectors\[0\]\.pm: required"):
        navfdi.FederatedFilter(x0, P0, [{**good[0], "detectors": [{"kind": "sprt", "pf": 0.1}]}])
    with pytest.raises(ValueError, match="mode"):
        navfdi.FederatedFilter(x0, P0, good, mode="sometimes")
    before = (fed.x, fed.P)
    with pytest.raises(ValueError, match="measurements"):
        fed.step(np.eye(n), np.eye(n) * 0.01, [np.zeros(2), np.zeros(3)])
    with pytest.raises(ValueError, match="Q"):
        fed.step(np.eye(n), -np.eye(n), [np.zeros(2), np.zeros(3), np.zeros(1)])
    np.testing.assert_array_equal(fed.x, before[0])
    np.testing.assert_array_equal(fed.P, before[1])


def test_set_model_changes_the_measurement_model():
    rng = np.random.default_rng(3)
    fed, x0, P0, Hs, Rs = make(rng)
    n = x0.size
    with pytest.raises(ValueError, match="no such sub-filter"):
        fed.set_model("zz", Hs[0], Rs[0])
    with pytest.raises(ValueError, match="H: expected shape"):
        fed.set_model("s0", np.eye(3, n), Rs[0])
    with pytest.raises(ValueError, match="R: not positive semi-definite"):
        fed.set_model("s0", Hs[0], -np.eye(2))
    H0 = np.zeros((2, n))
    H0[0, 0] = H0[1, 1] = 1.0
    fed.set_model("s0", H0, np.eye(2) * 1e-6)
    # s0 now measures states 0 and 1 almost exactly.
    step = fed.step(np.eye(n), np.zeros((n, n)), [np.array([3.0, -2.0]), np.full(3, np.nan), np.full(1, np.nan)])
    np.testing.assert_allclose(step.x[:2], [3.0, -2.0], atol=1e-3)
