"""Bad input gets a clear exception naming the problem, and leaves objects as they were."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import navfdi

N, M = 4, 3


def make_filter():
    rng = np.random.default_rng(0)
    B = rng.standard_normal((N, N))
    return navfdi.KalmanFilter(rng.standard_normal(N), B @ B.T + np.eye(N))


def good():
    return dict(Phi=np.eye(N), Q=np.eye(N) * 0.01, z=np.ones(M), H=np.eye(M, N), R=np.eye(M))


def snapshot(kf):
    return kf.x.copy(), kf.P.copy()


def assert_unchanged(kf, snap):
    np.testing.assert_array_equal(kf.x, snap[0])
    np.testing.assert_array_equal(kf.P, snap[1])


bad_value = st.sampled_from([np.nan, np.inf, -np.inf])


def corrupt(a, data, value):
    a = np.array(a, dtype=float)
    idx = tuple(data.draw(st.integers(0, s - 1)) for s in a.shape)
    a[idx] = value
    return a, idx


@settings(max_examples=60, deadline=None)
@given(data=st.data(), which=st.sampled_from(["Phi", "Q"]), value=bad_value)
def test_predict_rejects_non_finite(data, which, value):
    kf = make_filter()
    snap = snapshot(kf)
    args = good()
    args[which], _ = corrupt(args[which], data, value)
    with pytest.raises(ValueError, match=which):
        kf.predict(args["Phi"], args["Q"])
    assert_unchanged(kf, snap)


@settings(max_examples=60, deadline=None)
@given(data=st.data(), which=st.sampled_from(["H", "R"]), value=bad_value)
def test_update_rejects_non_finite(data, which, value):
    kf = make_filter()
    snap = snapshot(kf)
    args = good()
    args[which], _ = corrupt(args[which], data, value)
    with pytest.raises(ValueError, match=which):
        kf.update(args["z"], args["H"], args["R"])
    assert_unchanged(kf, snap)


@settings(max_examples=30, deadline=None)
@given(data=st.data(), value=st.sampled_from([np.inf, -np.inf]))
def test_update_rejects_infinite_measurement(data, value):
    kf = make_filter()
    snap = snapshot(kf)
    z, _ = corrupt(np.ones(M), data, value)
    with pytest.raises(ValueError, match="z"):
        kf.update(z, np.eye(M, N), np.eye(M))
    assert_unchanged(kf, snap)


shapes = st.tuples(st.integers(0, 6), st.integers(0, 6))


@settings(max_examples=80, deadline=None)
@given(which=st.sampled_from(["Phi", "Q", "H", "R"]), shape=shapes)
def test_wrong_shapes_are_named(which, shape):
    expected = {"Phi": (N, N), "Q": (N, N), "H": (M, N), "R": (M, M)}[which]
    if shape == expected:
        return
    kf = make_filter()
    snap = snapshot(kf)
    args = good()
    args[which] = np.eye(*shape) if 0 not in shape else np.zeros(shape)
    with pytest.raises(ValueError, match=which):
        if which in ("Phi", "Q"):
            kf.predict(args["Phi"], args["Q"])
        else:
            kf.update(args["z"], args["H"], args["R"])
    assert_unchanged(kf, snap)


@settings(max_examples=60, deadline=None)
@given(
    which=st.sampled_from(["Q", "R"]),
    kind=st.sampled_from(["asymmetric", "indefinite", "negative diagonal"]),
    size=st.floats(0.1, 10.0),
)
def test_covariances_must_be_symmetric_psd(which, kind, size):
    kf = make_filter()
    snap = snapshot(kf)
    args = good()
    d = args[which].shape[0]
    C = np.eye(d)
    if kind == "asymmetric":
        C[0, 1] += size
    elif kind == "indefinite":
        C[0, 1] = C[1, 0] = 1.0 + size  # |off-diagonal| > diagonal → negative eigenvalue
    else:
        C[0, 0] = -size
    args[which] = C
    with pytest.raises(ValueError, match=rf"{which}: not (symmetric|positive semi-definite)"):
        if which == "Q":
            kf.predict(args["Phi"], args["Q"])
        else:
            kf.update(args["z"], args["H"], args["R"])
    assert_unchanged(kf, snap)


@settings(max_examples=40, deadline=None)
@given(fading=st.one_of(st.floats(max_value=0.999999), st.just(np.nan), st.just(np.inf)))
def test_fading_below_one_is_rejected(fading):
    kf = make_filter()
    snap = snapshot(kf)
    with pytest.raises(ValueError, match="fading"):
        kf.predict(np.eye(N), np.eye(N), fading=fading)
    assert_unchanged(kf, snap)


def test_singular_innovation_covariance_is_linalg_error():
    kf = navfdi.KalmanFilter(np.zeros(2), np.zeros((2, 2)))
    snap = snapshot(kf)
    with pytest.raises(navfdi.LinAlgError, match="innovation covariance"):
        kf.update([1.0], [[1.0, 0.0]], [[0.0]])
    assert issubclass(navfdi.LinAlgError, ValueError)
    assert_unchanged(kf, snap)


@pytest.mark.parametrize(
    ("x0", "P0", "needle"),
    [
        ([], np.zeros((0, 0)), "x0"),
        ([0.0, np.nan], np.eye(2), "x0"),
        ([0.0, 0.0], np.eye(3), "P0"),
        ([0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]], "P0: not positive semi-definite"),
        ([0.0, 0.0], [[1.0, 0.5], [0.0, 1.0]], "P0: not symmetric"),
        ([0.0, 0.0], [[1.0, np.inf], [np.inf, 1.0]], "P0"),
        ("abc", np.eye(2), "x0"),
        ([[0.0, 0.0]], np.eye(2), "x0"),
    ],
)
def test_constructor_rejects(x0, P0, needle):
    with pytest.raises(ValueError, match=needle):
        navfdi.KalmanFilter(x0, P0)


def test_set_state_rejects_and_keeps_state():
    kf = make_filter()
    snap = snapshot(kf)
    with pytest.raises(ValueError, match="P"):
        kf.set_state(np.zeros(N), -np.eye(N))
    with pytest.raises(ValueError, match="x"):
        kf.set_state(np.zeros(N + 1), np.eye(N))
    assert_unchanged(kf, snap)


@settings(max_examples=40, deadline=None)
@given(p=st.one_of(st.floats(max_value=0.0), st.floats(min_value=1.0), st.just(np.nan)))
def test_probabilities_outside_unit_interval(p):
    for make in (
        lambda: navfdi.ResidualChi2(p),
        lambda: navfdi.ImprovedSprt(p, 0.1),
        lambda: navfdi.ImprovedSprt(0.1, p),
        lambda: navfdi.JointChi2Sprt(p, 0.1),
    ):
        with pytest.raises(ValueError, match="p[fm]"):
            make()


def test_unknown_variance_mode():
    with pytest.raises(ValueError, match="variance"):
        navfdi.ImprovedSprt(0.1, 0.1, variance="estimated")


@pytest.mark.parametrize(
    "make", [lambda: navfdi.ResidualChi2(0.1), lambda: navfdi.ImprovedSprt(0.1, 0.1), lambda: navfdi.JointChi2Sprt(0.1, 0.1)]
)
def test_detectors_reject_bad_residuals_and_keep_state(make):
    det = make()
    det.test([3.0, 3.0, 3.0], np.eye(3))
    ref = make()
    ref.test([3.0, 3.0, 3.0], np.eye(3))
    bad = [
        (([1.0, 2.0], np.eye(3)), "covariance"),
        (([1.0, np.inf, 0.0], np.eye(3)), "residual"),
        (([1.0, 1.0, 1.0], np.full((3, 3), np.nan)), "covariance"),
        (([1.0, 1.0, 1.0], [[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]]), "covariance"),
    ]
    for args, needle in bad:
        with pytest.raises(ValueError, match=needle):
            det.test(*args)
    # State unchanged: the next decision equals that of an untouched twin.
    a, b = det.test([0.1, 0.2, 0.3], np.eye(3)), ref.test([0.1, 0.2, 0.3], np.eye(3))
    assert (a.statistic, a.alarm) == (b.statistic, b.alarm)


def test_sequence_error_names_epoch_and_keeps_state():
    det = navfdi.JointChi2Sprt(0.1, 0.1)
    det.test([3.0, 3.0], np.eye(2))
    residuals = np.ones((5, 2))
    covs = np.stack([np.eye(2)] * 5)
    covs[3] = [[1.0, 2.0], [2.0, 1.0]]
    with pytest.raises(navfdi.LinAlgError, match="epoch 3"):
        det.test_sequence(residuals, covs)
    assert det.alarm  # still the state after the first test
    with pytest.raises(ValueError, match="covariances"):
        det.test_sequence(residuals, covs[:4])


def test_run_filter_errors():
    n, m, T = 2, 1, 5
    args = dict(x0=np.zeros(n), P0=np.eye(n), Phi=np.eye(n), Q=np.eye(n) * 0.1, zs=np.ones((T, m)), H=np.ones((m, n)), R=np.eye(m))
    navfdi.run_filter(**args)
    with pytest.raises(ValueError, match=r"Phi: a stack of 3 matrices was given for 5 epochs"):
        navfdi.run_filter(**{**args, "Phi": np.stack([np.eye(n)] * 3)})
    bad_R = np.stack([np.eye(m)] * T)
    bad_R[2] = -1.0
    with pytest.raises(ValueError, match=r"R\[2\]: not positive semi-definite"):
        navfdi.run_filter(**{**args, "R": bad_R})
    with pytest.raises(ValueError, match="zs"):
        navfdi.run_filter(**{**args, "zs": np.ones(T)})
    zs = np.ones((T, m))
    zs[1, 0] = np.inf
    with pytest.raises(ValueError, match=r"zs: element \[1, 0\]"):
        navfdi.run_filter(**{**args, "zs": zs})
    with pytest.raises(ValueError, match="fading"):
        navfdi.run_filter(**args, fading=0.5)
    with pytest.raises(navfdi.LinAlgError, match="epoch 0"):
        navfdi.run_filter(**{**args, "P0": np.zeros((n, n)), "Q": np.zeros((n, n)), "R": np.zeros((m, m))})
