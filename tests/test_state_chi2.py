"""Dual-propagator state chi-square test (METHODS §8): false-alarm rate, a drift the filter
follows, the age rule, ill-conditioned V, bad input, pickling."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
from scipy import stats

import navfdi


def model(dt=1.0, q=0.01, r=1.0):
    """Two axes of position + velocity (n = 4), position measured."""
    F = np.array([[1.0, dt], [0.0, 1.0]])
    Qa = q * np.array([[dt**3 / 3, dt**2 / 2], [dt**2 / 2, dt]])
    Phi = np.kron(np.eye(2), F)
    Q = np.kron(np.eye(2), Qa)
    H = np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]])
    R = np.eye(2) * r
    return Phi, Q, H, R


def run(T, seed, drift=None, pf=0.05, reset_every=20, min_age=10):
    Phi, Q, H, R = model()
    rng = np.random.default_rng(seed)
    L = np.linalg.cholesky(Q + np.eye(4) * 1e-15)
    P0 = np.eye(4) * 4.0
    x = np.linalg.cholesky(P0) @ rng.normal(size=4)
    kf = navfdi.KalmanFilter(np.zeros(4), P0)
    det = navfdi.StateChi2(pf, 4, reset_every, min_age)
    res = navfdi.ResidualChi2(pf)
    out = []
    for k in range(T):
        if k:
            x = Phi @ x + L @ rng.normal(size=4)
            kf.predict(Phi, Q)
        z = H @ x + rng.normal(size=2)
        if drift is not None:
            z = z + drift(k)
        inn = kf.update(z, H, R)
        d = det.step(kf.x, kf.P, Phi, Q)
        out.append((d, res.test(inn.residual, inn.covariance).alarm))
    return out


def test_false_alarm_rate_is_pf_once_the_age_rule_is_met():
    """One decision per reset period (the older propagator at age 1.5 Δ), from runs long enough
    for 12 000 samples: inside a 99 % binomial interval of pf."""
    pf, reset = 0.05, 20
    samples = alarms = 0
    for seed in range(4):
        for d, _ in run(60_000, seed, pf=pf, reset_every=reset, min_age=10):
            if d.ready and d.age == reset + reset // 2:
                samples += 1
                alarms += d.alarm
    lo, hi = stats.binom.interval(0.99, samples, pf)
    assert samples > 11_000
    assert lo <= alarms <= hi, (alarms, samples, lo, hi)


def test_a_drift_the_filter_follows_is_caught_by_the_state_test():
    """A 0.05 m/epoch position drift from epoch 300: the filter follows it (its residual test
    stays near pf), the state test alarms within a few reset periods."""
    out = run(700, 11, drift=lambda k: np.full(2, 0.05 * max(k - 300, 0)), pf=0.01, reset_every=40, min_age=20)
    state = np.array([d.alarm for d, _ in out])
    resid = np.array([a for _, a in out])
    first_state = int(np.argmax(state[300:])) + 300
    assert state[300:].any() and first_state < 420, first_state
    assert resid[300:].mean() < 0.05
    assert state[:300].mean() < 0.05


def test_age_rule_and_ill_conditioned_v():
    det = navfdi.StateChi2(0.01, 2, reset_every=4, min_age=2)
    x, P, Phi = np.zeros(2), np.eye(2), np.eye(2)
    d0 = det.step(x, P, Phi, np.eye(2))
    d1 = det.step(x, P, Phi, np.eye(2))
    d2 = det.step(x, P, Phi, np.eye(2))
    assert not d0.ready and not d1.ready and np.isnan(d1.statistic)
    assert d2.ready and d2.propagator == 0 and d2.age == 2 and np.isfinite(d2.statistic)
    # Without process noise and with P unchanged, V = 0: reported, never divided by.
    z = navfdi.StateChi2(0.01, 2, reset_every=4, min_age=1)
    z.step(x, P, Phi, np.zeros((2, 2)))
    d = z.step(x, P, Phi, np.zeros((2, 2)))
    assert d.ready and d.ill_conditioned and np.isnan(d.statistic) and not d.alarm
    assert navfdi.StateChi2(0.01, 4, 10, states=[0, 2]).threshold == pytest.approx(stats.chi2.isf(0.01, 2))


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(pf=1.5, n=2, reset_every=4), "pf"),
        (dict(pf=0.01, n=0, reset_every=4), "n"),
        (dict(pf=0.01, n=2, reset_every=0), "reset_every"),
        (dict(pf=0.01, n=2, reset_every=4, min_age=5), "min_age"),
        (dict(pf=0.01, n=2, reset_every=4, states=[0, 0]), r"states\[1\]"),
        (dict(pf=0.01, n=2, reset_every=4, states=[3]), r"states\[0\]"),
        (dict(pf=0.01, n=2, reset_every=4, states=[-1]), r"states\[0\]"),
    ],
)
def test_bad_parameters_are_named(kwargs, match):
    with pytest.raises(ValueError, match=match):
        navfdi.StateChi2(**kwargs)


def test_bad_inputs_leave_the_detector_unchanged():
    det = navfdi.StateChi2(0.01, 2, 4, 2)
    det.step(np.zeros(2), np.eye(2), np.eye(2), np.eye(2))
    before = pickle.dumps(det)
    with pytest.raises(ValueError, match="x"):
        det.step(np.zeros(3), np.eye(2), np.eye(2), np.eye(2))
    with pytest.raises(ValueError, match="P"):
        det.step(np.zeros(2), -np.eye(2), np.eye(2), np.eye(2))
    with pytest.raises(ValueError, match="Phi"):
        det.step(np.zeros(2), np.eye(2), np.full((2, 2), np.nan), np.eye(2))
    with pytest.raises(ValueError, match="Q"):
        det.step(np.zeros(2), np.eye(2), np.eye(2), np.eye(3))
    assert pickle.dumps(det) == before


def test_pickle_and_copy_continue_exactly():
    out = run(50, 3)
    Phi, Q, _, _ = model()
    det = navfdi.StateChi2(0.05, 4, 20, 10)
    rng = np.random.default_rng(0)
    xs = rng.normal(size=(60, 4))
    for k in range(30):
        det.step(xs[k], np.eye(4) * 0.5, Phi, Q)
    a, b = pickle.loads(pickle.dumps(det)), copy.deepcopy(det)
    for k in range(30, 60):
        d = det.step(xs[k], np.eye(4) * 0.5, Phi, Q)
        for other in (a, b):
            e = other.step(xs[k], np.eye(4) * 0.5, Phi, Q)
            assert (e.statistic == d.statistic or (np.isnan(e.statistic) and np.isnan(d.statistic))) and e.alarm == d.alarm
    assert out  # the helper ran


def state_scenario(faults=True, **state):
    raw = copy.deepcopy(navfdi.load_scenario("gao_fading").base().raw)
    if not faults:
        raw["faults"] = []
    raw["state_chi2"] = {"pf": 0.05, "reset_every": "60 s", "min_age": "30 s", "states": ["vel_e", "vel_n", "vel_u", "lat", "lon", "h"], **state}
    return navfdi.load_scenario(raw)


def test_scenario_state_test_false_alarm_rate_is_pf():
    """[state_chi2] on the centralized INS/GNSS filter of gao_fading without faults: one sample
    per reset period (older propagator at 1.5 periods) over 40 runs, inside a 99 % binomial
    interval of pf."""
    sc = state_scenario(faults=False)
    alarms = samples = 0
    idx = np.arange(90, 1500, 60)
    for seed in range(40):
        st = navfdi.run_scenario(sc, seed=seed, compare_isolation=False).record["state_chi2"]
        ok = st["ready"][idx] & ~st["ill_conditioned"][idx]
        samples += int(ok.sum())
        alarms += int(st["alarm"][idx][ok].sum())
    lo, hi = stats.binom.interval(0.99, samples, 0.05)
    assert samples > 800 and lo <= alarms <= hi, (alarms, samples)


def test_scenario_state_test_is_recorded_and_matched_to_faults(tmp_path):
    res = navfdi.run_scenario(state_scenario(), seed=1, compare_isolation=False)
    st = res.record["state_chi2"]
    assert st["states"] == [3, 4, 5, 6, 7, 8] and st["statistic"].shape == res.t.shape
    ev = res.events()
    mine = ev[ev["detector"] == "state_chi2"]
    assert (mine["subfilter"] == "navigation").all()
    assert "lat-step" in set(mine["fault_id"].dropna())
    ts = res.timeseries()
    assert {"state_chi2.statistic", "state_chi2.alarm", "state_chi2.ready"} <= set(ts.columns)
    names = {p.name for p in res.write(tmp_path)}
    assert "detector_navigation_state_chi2.png" in names


@pytest.mark.parametrize(
    "state, match",
    [
        (dict(pf=2.0), r"state_chi2\.pf"),
        (dict(min_age="90 s"), r"state_chi2\.min_age"),
        (dict(reset_every="0.5 s"), r"state_chi2\.reset_every"),
        (dict(states=["clock_bias"]), r"state_chi2\.states\[0\].*out of range"),
        (dict(states=["lat", "lat"]), r"state_chi2\.states\[1\]"),
        (dict(states=["altitude"]), r"state_chi2\.states\[0\] = 'altitude': not a state"),
        (dict(every="1 s"), r"state_chi2: unknown field"),
    ],
)
def test_scenario_state_config_errors_name_the_field(state, match):
    with pytest.raises(navfdi.ScenarioError, match=match):
        state_scenario(**state)


def test_enormous_state_is_refused_before_allocating():
    with pytest.raises(MemoryError, match="states"):
        navfdi.StateChi2(0.01, 1_000_000, 10)
    # A huge variance window costs nothing until filled.
    f = navfdi.WeightedFusion([1.0] * 1000, window=1_000_000)
    assert f.step(np.ones(1000), 1.0, [True] * 1000).value == pytest.approx(1.0)
