"""Paper 003 end to end (bundled scenario ``geng2016``, docs/geng2016.md): modes, the radio
altimeter's terrain error seen by the residual and state chi-square tests, altitude fusion
with a fault matrix, and a baro drift only the state test catches."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import navfdi
from navfdi.scenario import ScenarioError

SEEDS = range(20)
VARIANTS = [{"name": "no_isolation", "set": {"centralized.isolate": False}}, {"name": "isolation", "set": {"centralized.isolate": True}}]


@pytest.fixture(scope="module")
def runs():
    sc = navfdi.load_scenario("geng2016")
    return [navfdi.run_scenario(sc, seed=s) for s in SEEDS]


def _stat(run, sensor, det):
    return run.detector(sensor, det)["statistic"]


def test_radio_altimeter_statistics_far_above_gnss_and_baro(runs):
    """Fig. 11: the RA's residual and state statistics are far above GNSS's and baro's
    (median over the flight, ratio ≥ 10) in every seed, in the isolation variant."""
    for res in runs:
        r = res["isolation"]
        for det in ("chi2", "state"):
            med = {s: np.nanmedian(_stat(r, s, det)) for s in ("gnss", "baro", "ra")}
            assert med["ra"] >= 10 * max(med["gnss"], med["baro"]), (res.seed, det, med)


def test_radio_altimeter_isolated_most_of_the_time_gnss_and_baro_not(runs):
    """Fractions over the epochs each sensor measures (an absent sensor keeps its last
    decision, which says nothing)."""
    for res in runs:
        r = res["isolation"]
        frac = {}
        for s in ("gnss", "baro", "ra"):
            present = np.isfinite(_stat(r, s, "chi2"))
            frac[s] = r.isolated(s)[present].mean()
        assert frac["ra"] > 0.5 and frac["gnss"] < 0.05 and frac["baro"] < 0.05, (res.seed, frac)
        assert not any(res["no_isolation"].isolated(s).any() for s in ("gnss", "slam", "baro", "ra"))


def test_fused_altitude_error_with_isolation_is_at_most_a_third(runs):
    """Fig. 10 vs Fig. 12, pooled over the seeds (errors.csv carries the per-run figures)."""
    ms = {"isolation": [], "no_isolation": []}
    for res in runs:
        err = res.errors().set_index("variant")
        for v in ms:
            f = res[v].record["fused_alt"]
            rms = math.sqrt(np.nanmean(f**2))
            assert err.loc[v, "fused_alt_rms"] == pytest.approx(rms, rel=1e-12)
            assert err.loc[v, "fused_alt_max"] == pytest.approx(np.nanmax(np.abs(f)), rel=1e-12)
            ms[v].append(rms**2)
    ratio = math.sqrt(np.mean(ms["isolation"]) / np.mean(ms["no_isolation"]))
    assert ratio <= 1 / 3, ratio


def test_mode_sequence_matches_outage_and_target_windows(runs):
    """q2 in the GNSS outage (15–25 s), q3 within 20 m of (100, 100) m, q1 elsewhere; a
    sensor outside the active mode gives no measurement."""
    r = runs[0]["isolation"]
    t = r.t
    t_near = (100 * math.sqrt(2) - 20) / 2.83  # straight leg at 2.83 m/s
    want = np.where(t >= t_near - 1e-9, 3, np.where((t >= 15) & (t < 25), 2, 1))
    off = np.flatnonzero(r.record["mode"] != want)
    assert off.size <= 1 and all(abs(t[k] - t_near) < 0.11 for k in off), t[off]
    mode = r.record["mode"]
    assert np.isnan(_stat(r, "gnss", "chi2")[mode == 2]).all()
    assert np.isnan(_stat(r, "slam", "chi2")[mode == 1]).all()
    assert np.isfinite(_stat(r, "slam", "chi2")[mode == 2]).all()
    ts = runs[0].timeseries()
    assert set(ts["mode"]) == {"q1", "q2", "q3"}
    assert {"ra.state.statistic", "fused_alt.error", "fused_alt.ra.weight", "fused_alt.baro.error"} <= set(ts.columns)


def _drift(slope):
    raw = copy.deepcopy(navfdi.load_scenario("geng2016").raw)
    raw["faults"] = [{"id": "baro-drift", "sensor": "baro", "components": "all", "kind": "ramp", "magnitude": slope, "start": "10 s", "end": "50 s"}]
    return navfdi.load_scenario(raw)


def _sustained(alarm, t, start, window=20, share=0.2):
    """Delay to the first 2 s window after ``start`` with ≥ 20 % of its epochs in alarm
    (isolated chance alarms at pf = 0.01 do not count); None if never."""
    k = np.convolve(alarm.astype(float), np.ones(window) / window)[: t.size]
    hit = np.flatnonzero((k >= share) & (t >= start))
    return float(t[hit[0]] - start) if hit.size else None


def test_slow_baro_drift_the_filter_follows_is_caught_by_the_state_test():
    """A 0.1 m/s baro ramp from 10 s: the baro dominates the fused altitude, so the filter
    follows it and the residual test stays at its false-alarm level; the state test (the baro
    sub-filter against the older propagator) catches it. Measured delays in docs/geng2016.md."""
    sc = _drift("0.1 m/s")
    state_hits, resid_rate = 0, []
    for seed in SEEDS:
        r = navfdi.run_scenario(sc, seed=seed)["isolation"]
        t = r.t
        st, ch = r.detector("baro", "state")["alarm"], r.detector("baro", "chi2")["alarm"]
        state_hits += _sustained(st, t, 10.0) is not None
        resid_rate.append(ch[t >= 10].mean())
    assert state_hits >= 18, state_hits
    assert np.mean(resid_rate) < 0.05, np.mean(resid_rate)


def test_state_detector_needs_centralized_and_a_schedule():
    raw = copy.deepcopy(navfdi.load_scenario("geng2016").raw)
    no_schedule = copy.deepcopy(raw)
    del no_schedule["state_chi2"]
    with pytest.raises(ScenarioError, match=r"centralized\.sensors\[0\]\.detectors\[1\]\.kind.*\[state_chi2\]"):
        navfdi.load_scenario(no_schedule)
    fed = copy.deepcopy(navfdi.load_scenario("yang2013").raw)
    fed["state_chi2"] = {"pf": 0.01, "reset_every": "10 s", "min_age": "5 s"}
    fed["federated"]["subfilters"][0]["detectors"].append({"name": "state", "kind": "state_chi2", "pf": 0.01})
    with pytest.raises(ScenarioError, match=r"detectors\[\d\]\.kind.*centralized"):
        navfdi.load_scenario(fed)
    bad = copy.deepcopy(raw)
    bad["centralized"]["altitude_fusion"]["estimate"] = "median"
    with pytest.raises(ScenarioError, match=r"altitude_fusion\.estimate"):
        navfdi.load_scenario(bad)
    bias = copy.deepcopy(raw)
    bias["sensors"][2]["bias"] = "-0.1 m"
    with pytest.raises(ScenarioError, match=r"sensors\[2\]\.bias"):
        navfdi.load_scenario(bias)
    bias["sensors"][2]["bias"] = "1e200 m"
    with pytest.raises(ScenarioError, match=r"sensors\[2\]\.bias\[0\].*beyond"):
        navfdi.load_scenario(bias)
    bias["sensors"][2]["bias"] = "0.1 m"
    bias["sensors"][2]["noise"] = "1e200 m"
    with pytest.raises(ScenarioError, match=r"sensors\[2\]\.noise\[0\].*beyond"):
        navfdi.load_scenario(bias)


def test_bias_is_a_constant_per_run_and_leaves_other_draws_alone():
    """The baro's offset is constant within a run, differs between runs, and a scenario
    without offsets draws exactly the noise it drew before (own random stream)."""
    sc = navfdi.load_scenario("geng2016")
    raw = copy.deepcopy(sc.raw)
    raw["sensors"][2].pop("bias")
    plain = navfdi.load_scenario(raw)
    a = navfdi.run_scenario(sc, seed=3)["no_isolation"].record["fusion"]
    b = navfdi.run_scenario(plain, seed=3)["no_isolation"].record["fusion"]
    j = a["sensors"].index("baro")
    d = a["error"][:, j] - b["error"][:, j]
    ok = np.isfinite(d)
    assert ok.sum() > 400 and np.ptp(d[ok]) < 1e-9 and abs(d[ok][0]) > 1e-6
    other = [i for i, s in enumerate(a["sensors"]) if s != "baro"]
    np.testing.assert_array_equal(a["error"][:, other], b["error"][:, other])
    c = navfdi.run_scenario(sc, seed=4)["no_isolation"].record["fusion"]
    e = navfdi.run_scenario(plain, seed=4)["no_isolation"].record["fusion"]
    d4 = (c["error"][:, j] - e["error"][:, j])[ok]
    assert abs(d4[0] - d[ok][0]) > 1e-6


def test_run_writes_the_paper_figures(tmp_path):
    res = navfdi.run_scenario("geng2016", seed=1)
    names = {p.name for p in res.write(tmp_path)}
    for v in ("isolation", "no_isolation"):
        assert {f"{v}_altitude_fusion.png", f"{v}_altitude_statistics.png", f"{v}_modes.png"} <= names
    assert "variant_fused_altitude.png" in names
    import pandas as pd

    err = pd.read_csv(tmp_path / "errors.csv").set_index("variant")
    assert err.loc["isolation", "fused_alt_rms_m"] < err.loc["no_isolation", "fused_alt_rms_m"]


def test_montecarlo_reports_fused_altitude():
    c = navfdi.montecarlo("geng2016", runs=8, seed=0, progress=False)
    s = c.summary().set_index(["variant", "subfilter", "detector"])
    iso = s.loc[("isolation", "ra", "chi2"), "fused_alt_rms"]
    no = s.loc[("no_isolation", "ra", "chi2"), "fused_alt_rms"]
    runs = c.runs
    want = math.sqrt(np.mean(runs[(runs.variant == "isolation") & (runs.subfilter == "ra") & (runs.detector == "chi2")]["fused_alt_rms"] ** 2))
    assert iso == pytest.approx(want, rel=1e-12) and iso < no


def test_radio_altimeter_noise_scales_with_the_height_above_the_terrain():
    """σ_k² = noise² + (2 % · AGL_k)²: across runs, the RA's error at an epoch is the terrain
    under the vehicle (the same in every run) plus noise of that variance."""
    sc = navfdi.load_scenario("geng2016")
    errs = []
    for seed in range(120):
        fu = navfdi.run_scenario(sc, seed=seed)["no_isolation"].record["fusion"]
        errs.append(fu["error"][:, fu["sensors"].index("ra")])
    e = np.array(errs)  # runs × epochs
    terrain = e.mean(axis=0)
    want = 0.02**2 + (0.02 * (8.0 - terrain)) ** 2
    ratio = e.var(axis=0, ddof=1) / want
    assert 0.95 < ratio.mean() < 1.05, ratio.mean()
    # Where the vehicle is low over a crest the noise is smaller than over a trough.
    lo, hi = terrain > 1.0, terrain < -1.0
    assert e.var(axis=0)[lo].mean() < e.var(axis=0)[hi].mean()


@pytest.mark.parametrize(
    "sensor, value, match",
    [
        (3, "150 %", r"sensors\[3\]\.proportional_noise.*between"),
        (3, "0.02", r"sensors\[3\]\.proportional_noise.*unit"),
        (2, "2 %", r"sensors\[2\]\.proportional_noise: only a radio_altimeter"),
    ],
)
def test_bad_proportional_noise_is_named(sensor, value, match):
    raw = copy.deepcopy(navfdi.load_scenario("geng2016").raw)
    raw["sensors"][sensor]["proportional_noise"] = value
    with pytest.raises(ScenarioError, match=match):
        navfdi.load_scenario(raw)


def test_proportional_noise_in_a_federated_filter():
    """The federated architecture takes the per-epoch R too (its RA sub-filter's residual
    statistic stays χ²(1)-sized where the terrain is flat under the vehicle)."""
    raw = copy.deepcopy(navfdi.load_scenario("yang2013").raw)
    raw.update(duration="200 s", faults=[])
    raw.pop("variants", None)
    raw["terrain"] = {"waves": [{"amplitude": "0.001 m", "wavelength": "1000 m", "heading": "0 deg"}]}
    raw["sensors"].append({"name": "ra", "kind": "radio_altimeter", "noise": "0.1 m", "proportional_noise": "1 %", "rate": "1 Hz"})
    raw["federated"]["subfilters"].append({"sensor": "ra", "share": 0.2, "detectors": [{"name": "chi2", "kind": "chi2", "pf": 0.01}]})
    raw["federated"]["subfilters"][0]["share"] = 0.4
    raw["federated"]["subfilters"][1]["share"] = 0.4
    sc = navfdi.load_scenario(raw)
    stats_ = []
    for seed in range(10):
        r = navfdi.run_scenario(sc, seed=seed, compare_isolation=False)
        stats_.append(r.detector("ra", "chi2")["statistic"][20:])
    # With the fixed 0.1 m σ the statistic would be ~ (1 % · ~500+ m / 0.1 m)² ≈ 25+ times larger.
    assert 0.7 < np.nanmean(stats_) < 1.5, np.nanmean(stats_)


def test_the_state_test_can_decide_the_fault_matrix():
    """``decision = "state"``: the RA's M_i follows its state test (in alarm most of the
    flight), and the fused altitude improves on no isolation as with the residual test."""
    raw = copy.deepcopy(navfdi.load_scenario("geng2016").raw)
    for cs in raw["centralized"]["sensors"]:
        cs["decision"] = "state"
    res = navfdi.run_scenario(navfdi.load_scenario(raw), seed=2)
    r = res["isolation"]
    state = r.detector("ra", "state")
    np.testing.assert_array_equal(r.isolated("ra")[state["alarm"]], True)
    present = np.isfinite(state["statistic"])
    assert r.isolated("ra")[present].mean() > 0.5
    err = res.errors().set_index("variant")
    assert err.loc["isolation", "fused_alt_rms"] < 0.5 * err.loc["no_isolation", "fused_alt_rms"]
    text = res.format_tables()
    assert "fused altitude error per variant" in text and "whole run: no faults" in text
