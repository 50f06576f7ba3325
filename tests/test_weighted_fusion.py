"""Weighted fusion with a fault matrix (METHODS §9) against the formula in numpy."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import navfdi


def reference(values, predicted, healthy, hist, prior, window):
    """Windowed mean-square deviations → inverse-variance weights over healthy sensors."""
    n = len(values)
    s2 = np.empty(n)
    for i in range(n):
        if np.isfinite(values[i]):
            hist[i].append(values[i] - predicted)
            del hist[i][:-window]
        s2[i] = np.mean(np.square(hist[i])) if len(hist[i]) >= 2 else prior[i] ** 2
    use = np.array(healthy) & np.isfinite(values)
    if not use.any():
        return None, s2
    w = np.where(use, 1 / s2, 0.0)
    return float(np.sum(w * np.where(use, values, 0.0)) / w.sum()), s2


def test_matches_numpy_over_a_random_sequence():
    rng = np.random.default_rng(3)
    prior, window = [2.0, 0.5, 5.0], 8
    f = navfdi.WeightedFusion(prior, window)
    hist = [[], [], []]
    nones = 0
    for k in range(300):
        values = 100 + rng.normal(size=3) * [2.0, 0.5, 5.0] + [0, 0, 3.0 * np.sin(k / 10)]
        values[rng.random(3) < 0.1] = np.nan
        healthy = list(rng.random(3) > 0.2)
        predicted = 100 + rng.normal() * 0.3
        got = f.step(values, predicted, healthy)
        want, s2 = reference(values, predicted, healthy, hist, prior, window)
        np.testing.assert_allclose(got.sigma2, s2, rtol=1e-12)
        if want is None:
            nones += 1
            assert got.value is None and np.isnan(got.variance) and not got.weights.any()
        else:
            assert got.value == pytest.approx(want, rel=1e-12)
            assert got.weights.sum() == pytest.approx(1.0)
    assert nones > 0


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
