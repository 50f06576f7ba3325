"""Every array input gives the same result, bit for bit, whatever its memory layout.

Issue: Fortran-ordered arrays (``np.asfortranarray``, ``Phi.T``, ``DataFrame.to_numpy()``)
were read as if row-major, i.e. silently transposed. Each array-taking function is run with
every argument in C order and again with each argument in a layout drawn by hypothesis: F
order, a transposed view, negative strides, a non-contiguous slice, another dtype.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import navfdi
from reference import random_spd

LAYOUTS = ["c", "fortran", "transposed_view", "negative_strides", "strided_slice", "float32_exact", "list"]


def relayout(a: np.ndarray, how: str):
    """The same values as ``a`` (C order, float64) in another memory layout."""
    a = np.ascontiguousarray(a, dtype=np.float64)
    if how == "c":
        return a
    if how == "fortran":
        return np.asfortranarray(a)
    if how == "transposed_view":
        return np.ascontiguousarray(a.T).T  # F-contiguous view of the transpose's buffer
    if how == "negative_strides":
        rev = a[(slice(None, None, -1),) * a.ndim].copy()
        return rev[(slice(None, None, -1),) * a.ndim]
    if how == "strided_slice":
        big = np.full(tuple(2 * s + 1 for s in a.shape), np.nan)
        big[(slice(1, None, 2),) * a.ndim] = a
        return big[(slice(1, None, 2),) * a.ndim]
    if how == "float32_exact":
        # Values exactly representable in float32 so the cast is lossless.
        return a.astype(np.float32) if np.array_equal(a.astype(np.float32).astype(np.float64), a, equal_nan=True) else a
    if how == "list":
        return a.tolist()
    raise AssertionError(how)


def check_layout(view, a: np.ndarray, how: str) -> None:
    """The relayout really has the layout it claims (so the test tests something)."""
    if how in ("fortran", "transposed_view") and a.ndim >= 2 and min(a.shape) > 1:
        assert view.flags.f_contiguous and not view.flags.c_contiguous
    if how == "negative_strides" and a.size > 1:
        assert any(s < 0 for s in view.strides)
    if how == "strided_slice" and a.size > 1:
        assert not view.flags.c_contiguous and not view.flags.f_contiguous
    if how != "list" and how != "float32_exact":
        np.testing.assert_array_equal(np.asarray(view), a)


def equal(a, b):
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def exact(rng, shape):
    """Random values exactly representable in float32 (so every layout holds the same numbers)."""
    return np.round(rng.standard_normal(shape) * 64) / 64


def spd(rng, n):
    m = exact(rng, (n, n))
    return m @ m.T + n * np.eye(n)


layout = st.sampled_from(LAYOUTS)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), lay=st.lists(layout, min_size=7, max_size=7))
def test_kalman_filter_step_api(seed, lay):
    rng = np.random.default_rng(seed)
    n, m = 4, 3
    x0, P0 = exact(rng, n), spd(rng, n)
    Phi = np.eye(n) + exact(rng, (n, n)) / 4  # not symmetric: a transposed read changes P
    Q, R = spd(rng, n) / 8, spd(rng, m)
    H, z = exact(rng, (m, n)), exact(rng, m)
    args = [x0, P0, Phi, Q, z, H, R]
    for a, how in zip(args, lay):
        check_layout(relayout(a, how), a, how)

    def run(arrs):
        kf = navfdi.KalmanFilter(arrs[0], arrs[1])
        kf.predict(arrs[2], arrs[3])
        inn = kf.update(arrs[4], arrs[5], arrs[6])
        kf.set_state(arrs[0], arrs[1])
        kf.predict(arrs[2], arrs[3])
        return kf.x, kf.P, inn.residual, inn.covariance, inn.statistic

    ref = run(args)
    got = run([relayout(a, how) for a, how in zip(args, lay)])
    for r, g in zip(ref, got):
        equal(r, g)


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), lay=st.lists(layout, min_size=7, max_size=7), stacked=st.booleans())
def test_run_filter(seed, lay, stacked):
    rng = np.random.default_rng(seed)
    n, m, T = 3, 2, 6
    x0, P0 = exact(rng, n), spd(rng, n)
    if stacked:
        Phi = np.stack([np.eye(n) + exact(rng, (n, n)) / 4 for _ in range(T)])
        Q = np.stack([spd(rng, n) / 8 for _ in range(T)])
        H = exact(rng, (T, m, n))
        R = np.stack([spd(rng, m) for _ in range(T)])
    else:
        Phi, Q, H, R = np.eye(n) + exact(rng, (n, n)) / 4, spd(rng, n) / 8, exact(rng, (m, n)), spd(rng, m)
    zs = exact(rng, (T, m))
    zs[2, 1] = np.nan
    args = [x0, P0, Phi, Q, zs, H, R]
    ref = navfdi.run_filter(*args)
    got = navfdi.run_filter(*[relayout(a, how) for a, how in zip(args, lay)])
    for r, g in zip(ref, got):
        equal(r, g)


@pytest.mark.parametrize("kind", ["chi2", "sprt", "joint"])
@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), lay=st.lists(layout, min_size=4, max_size=4))
def test_detectors(kind, seed, lay):
    rng = np.random.default_rng(seed)
    T, m = 8, 3
    rs = exact(rng, (T, m))
    As = np.stack([spd(rng, m) for _ in range(T)])
    As[:, 0, 1] += 1 / 64  # not symmetric in general: a transposed read would differ ...
    As[:, 1, 0] += 1 / 64  # ... but a covariance must be symmetric, so keep it symmetric
    make = {"chi2": lambda: navfdi.ResidualChi2(0.01), "sprt": lambda: navfdi.ImprovedSprt(0.01, 0.01), "joint": lambda: navfdi.JointChi2Sprt(0.01, 0.01)}[kind]
    ref_seq = make().test_sequence(rs, As)
    got_seq = make().test_sequence(relayout(rs, lay[0]), relayout(As, lay[1]))
    equal(ref_seq.statistic, got_seq.statistic)
    equal(ref_seq.alarm, got_seq.alarm)
    # Residuals (T, m) read transposed would mix epochs and components: the per-epoch API too.
    d_ref, d_got = make(), make()
    for k in range(T):
        a = d_ref.test(rs[k], As[k])
        b = d_got.test(relayout(rs[k], lay[2]), relayout(As[k], lay[3]))
        equal(a.statistic, b.statistic)
        assert a.alarm == b.alarm


@settings(max_examples=25, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), lay=st.lists(layout, min_size=8, max_size=8))
def test_federated_filter(seed, lay):
    rng = np.random.default_rng(seed)
    n = 4
    Hs = [exact(rng, (2, n)), exact(rng, (3, n))]
    Rs = [spd(rng, 2), spd(rng, 3)]
    x0, P0 = exact(rng, n), spd(rng, n)
    Phi, Q = np.eye(n) + exact(rng, (n, n)) / 4, spd(rng, n) / 8
    zs = [exact(rng, 2), exact(rng, 3)]

    def run(t):
        subs = [
            {"name": f"s{i}", "H": t(Hs[i], lay[2 * i]), "R": t(Rs[i], lay[2 * i + 1]), "share": 0.5, "detectors": [{"name": "chi2", "kind": "chi2", "pf": 1e-6}], "isolation": "chi2"}
            for i in range(2)
        ]
        fed = navfdi.FederatedFilter(t(x0, lay[4]), t(P0, lay[5]), subs)
        s = fed.step(t(Phi, lay[6]), t(Q, lay[7]), [t(zs[0], lay[0]), t(zs[1], lay[1])])
        fed.set_model("s1", t(Hs[1], lay[3]), t(Rs[1], lay[1]))
        s2 = fed.step(t(Phi, lay[7]), t(Q, lay[6]), [t(zs[0], lay[5]), t(zs[1], lay[4])])
        return s.x, s.P, s.statistic, s2.x, s2.P

    ref = run(lambda a, how: a)
    got = run(relayout)
    for r, g in zip(ref, got):
        equal(r, g)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), how=layout)
def test_mdb(seed, how):
    rng = np.random.default_rng(seed)
    A = spd(rng, 4)
    equal(navfdi.mdb(A, 0.1, 0.05), navfdi.mdb(relayout(A, how), 0.1, 0.05))


def test_dataframe_to_numpy_is_read_as_shown():
    """The user's report: a DataFrame's ``to_numpy()`` is Fortran-ordered."""
    Phi = np.array([[1.0, 2.0], [0.0, 1.0]])
    arr = pd.DataFrame(Phi).to_numpy()
    assert arr.flags.f_contiguous and not arr.flags.c_contiguous
    a, b = navfdi.KalmanFilter(np.zeros(2), np.eye(2)), navfdi.KalmanFilter(np.zeros(2), np.eye(2))
    a.predict(Phi, np.zeros((2, 2)))
    b.predict(arr, np.zeros((2, 2)))
    equal(a.P, b.P)
    np.testing.assert_allclose(b.P, Phi @ Phi.T)  # [[5, 2], [2, 1]]: transposed would be [[1, 2], [2, 5]]


@pytest.mark.parametrize(
    ("value", "message"),
    [
        (np.eye(2, dtype=complex), r"Phi: complex values are not accepted"),
        (np.array([["1", "0"], ["0", "1"]]), r"Phi: expected real numbers, got an array of dtype <U1"),
        ([["a", "b"], ["c", "d"]], r"Phi: expected real numbers"),
        ([[1j, 0], [0, 1]], r"Phi: complex values are not accepted"),
        (np.array([[1, 0], [0, 1]], dtype=object), r"Phi: expected real numbers, got an array of dtype object"),
        ([[1.0, 0.0], [0.0]], r"Phi: expected an array of numbers"),
        ("abc", r"Phi: expected real numbers"),
    ],
)
def test_non_real_arrays_are_refused(value, message):
    kf = navfdi.KalmanFilter(np.zeros(2), np.eye(2))
    P = kf.P
    with pytest.raises(ValueError, match=message):
        kf.predict(value, np.zeros((2, 2)))
    equal(kf.P, P)


def test_integer_and_bool_arrays_are_cast():
    kf = navfdi.KalmanFilter(np.zeros(2, dtype=np.int64), np.eye(2, dtype=np.int32))
    kf.predict(np.eye(2, dtype=bool), np.zeros((2, 2), dtype=np.uint8))
    equal(kf.P, np.eye(2))
