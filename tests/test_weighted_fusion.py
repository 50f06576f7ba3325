"""Weighted fusion with a fault matrix (METHODS §9) against the formula in numpy."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import navfdi


def reference(values, predicted, healthy, hist, prior, window, estimate="mean_square"):
    """Windowed mean-square deviations (or their variance) floored at the prior →
    inverse-variance weights over healthy sensors."""
    n = len(values)
    s2 = np.empty(n)
    for i in range(n):
        if np.isfinite(values[i]):
            hist[i].append(values[i] - predicted)
            del hist[i][:-window]
        if len(hist[i]) < 2:
            s2[i] = prior[i] ** 2
        else:
            est = np.mean(np.square(hist[i])) if estimate == "mean_square" else np.var(hist[i], ddof=1)
            s2[i] = max(est, prior[i] ** 2)
    use = np.array(healthy) & np.isfinite(values)
    if not use.any():
        return None, s2
    w = np.where(use, 1 / s2, 0.0)
    return float(np.sum(w * np.where(use, values, 0.0)) / w.sum()), s2


@pytest.mark.parametrize("estimate", ["mean_square", "variance"])
def test_matches_numpy_over_a_random_sequence(estimate):
    rng = np.random.default_rng(3)
    # Priors below the sensors' noise so that the floor binds only sometimes.
    prior, window = [1.0, 0.3, 3.0], 8
    f = navfdi.WeightedFusion(prior, window, estimate)
    floored = 0
    hist = [[], [], []]
    nones = 0
    for k in range(300):
        values = 100 + rng.normal(size=3) * [2.0, 0.5, 5.0] + [0, 0, 3.0 * np.sin(k / 10)]
        values[rng.random(3) < 0.1] = np.nan
        healthy = list(rng.random(3) > 0.2)
        predicted = 100 + rng.normal() * 0.3
        got = f.step(values, predicted, healthy)
        want, s2 = reference(values, predicted, healthy, hist, prior, window, estimate)
        np.testing.assert_allclose(got.sigma2, s2, rtol=1e-12)
        floored += int(np.sum(s2 == np.square(prior)))
        if want is None:
            nones += 1
            assert got.value is None and np.isnan(got.variance) and not got.weights.any()
        else:
            assert got.value == pytest.approx(want, rel=1e-12)
            assert got.weights.sum() == pytest.approx(1.0)
    assert nones > 0
    assert 0 < floored < 300 * 3  # the floor was exercised, but not always


def test_variance_keeps_a_constant_offset_and_is_never_below_the_prior():
    """Paper 003's eq. 35 (variance about the mean) does not see a constant offset; the mean
    square does; neither estimate goes below the sensor's stated σ."""
    ms = navfdi.WeightedFusion([0.1, 0.1], 10, "mean_square")
    var = navfdi.WeightedFusion([0.1, 0.1], 10, "variance")
    rng = np.random.default_rng(1)
    for _ in range(10):
        v = 8.0 + rng.normal(size=2) * [0.5, 0.5] + [0.0, 2.0]
        a, b = ms.step(v, 8.0, [True, True]), var.step(v, 8.0, [True, True])
    assert a.weights[1] < 0.2 and 0.2 < b.weights[1] < 0.8
    const = navfdi.WeightedFusion([0.1, 0.1], 4, "variance")
    for _ in range(4):
        out = const.step(np.array([8.0, 9.0]), 8.0, [True, True])
    np.testing.assert_allclose(out.sigma2, [0.01, 0.01])
    with pytest.raises(ValueError, match="estimate"):
        navfdi.WeightedFusion([0.1, 0.1], 4, "median")


def test_a_biased_sensor_loses_weight_and_isolation_removes_it():
    f = navfdi.WeightedFusion([1.0, 1.0, 1.0], window=10)
    rng = np.random.default_rng(0)
    for k in range(50):
        vals = np.array([10.0, 10.0, 10.0]) + rng.normal(size=3) * 0.5 + [0, 0, 8.0]
        out = f.step(vals, 10.0, [True, True, True])
    assert out.weights[2] < 0.02
    out = f.step(np.array([10.0, 10.0, 30.0]), 10.0, [True, True, False])
    assert out.weights[2] == 0 and abs(out.value - 10.0) < 0.01


def test_bad_input_is_named_and_changes_nothing():
    with pytest.raises(ValueError, match=r"prior_sigma\[1\]"):
        navfdi.WeightedFusion([1.0, -1.0])
    with pytest.raises(ValueError, match="window"):
        navfdi.WeightedFusion([1.0], window=1)
    f = navfdi.WeightedFusion([1.0, 2.0], window=4)
    f.step([1.0, 2.0], 1.5, [True, True])
    before = pickle.dumps(f)
    with pytest.raises(ValueError, match="values"):
        f.step([1.0], 1.5, [True, True])
    with pytest.raises(ValueError, match="healthy"):
        f.step([1.0, 2.0], 1.5, [True])
    with pytest.raises(ValueError, match="predicted"):
        f.step([1.0, 2.0], float("nan"), [True, True])
    with pytest.raises(ValueError, match="values"):
        f.step([1.0, np.inf], 1.5, [True, True])
    assert pickle.dumps(f) == before
    g = pickle.loads(before)
    assert g.step([1.0, 2.0], 1.5, [True, True]).value == f.step([1.0, 2.0], 1.5, [True, True]).value
