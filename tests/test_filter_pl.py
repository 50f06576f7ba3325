"""Filter protection levels of the tight INS/GNSS filter: a bank of
sub-filters beside the filter, solution-separation test and exclusion, HPL/VPL per epoch,
the snapshot ARAIM levels of the same epochs, and the metrics engine's misleading /
hazardously misleading counts in `run` and `montecarlo`."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest

from navfdi.montecarlo import montecarlo
from navfdi.runs import run_scenario
from navfdi.scenario import ScenarioError, load_scenario


@pytest.fixture(scope="module")
def runs():
    return run_scenario("shao2018_integrity", seed=3)


def test_levels_are_finite_positive_and_below_the_snapshot_levels(runs):
    for name, r in runs.runs.items():
        it = r.record["integrity"]
        for k in ("hpl", "vpl"):
            v = it[k]
            assert np.isfinite(v).all() and (v > 0).all(), (name, k)
            snap = it[f"{k}_snapshot"]
            both = np.isfinite(snap)
            assert both.mean() > 0.95, (name, k)
            # The INS's contribution: the filter bounds the error far tighter than a snapshot
            # of the same epoch's pseudoranges (measured ratio ~0.05-0.12).
            assert (v[both] < snap[both]).all(), (name, k)
        assert np.all(it["modes"][10:] >= 9), name


def test_separation_excludes_the_faulty_satellite_and_the_levels_hold(runs):
    sep = runs.runs["separation"]
    tab = sep.satellite_table().set_index("fault_id")
    # 20 m step and 0.5 m/s ramp on G03: excluded in most of their epochs, never another one.
    assert tab.loc["step", "detection_rate"] >= 0.9
    assert tab.loc["ramp", "detection_rate"] >= 0.75
    assert tab.loc["step", "identification_rate"] == 1.0
    assert tab.loc["ramp", "identification_rate"] == 1.0
    assert tab.loc["none", "false_exclusion_rate"] == 0.0
    i = sep.integrity()
    assert i["epochs"] == len(sep.t)
    assert i["hazardous_h"] == 0 and i["hazardous_v"] == 0
    assert i["misleading_h"] == 0 and i["misleading_v"] == 0
    assert i["error_over_vpl_max"] < 1.0 and i["error_over_hpl_max"] < 1.0


def test_without_exclusion_the_error_leaves_the_levels_and_the_counts_show_it(runs):
    # Variant none: nothing excluded, the fault drags the solution beyond its levels; the
    # separation test alarms there, so the epochs are misleading but not hazardous.
    r = runs.runs["none"]
    i = r.integrity()
    assert i["misleading_h"] > 50 and i["misleading_v"] > 50
    assert i["error_over_vpl_max"] > 1.5
    # The Rust metrics engine's counts equal a recount from the time series.
    ts = r.timeseries()
    hor = np.hypot(ts["error.pos_e"], ts["error.pos_n"])
    up = np.abs(ts["error.pos_u"])
    alarm = ts["integrity.alarm"].to_numpy(bool)
    assert i["misleading_h"] == int((hor > ts["integrity.hpl"]).sum())
    assert i["misleading_v"] == int((up > ts["integrity.vpl"]).sum())
    assert i["hazardous_v"] == int(((up > ts["integrity.vpl"]) & ~alarm).sum())
    assert i["error_over_vpl_max"] == pytest.approx(float((up / ts["integrity.vpl"]).max()))


def test_outputs_carry_the_levels(runs, tmp_path):
    paths = runs.write(tmp_path)
    names = {p.name for p in paths}
    assert "separation_protection_levels.png" in names
    summary = json.loads((tmp_path / "summary.json").read_text())
    integ = summary["variants"]["separation"]["integrity"]
    assert integ["hazardous_v"] == 0 and integ["vpl_mean"] > 0
    text = runs.format_tables()
    assert "filter protection levels" in text
    assert max(len(line) for line in text.splitlines()) <= 100


def test_campaign_counts_hazardous_epochs_per_point(tmp_path):
    c = montecarlo("shao2018_integrity", runs=4, seed=1)
    t = c.integrity_summary().set_index("variant")
    assert set(t.index) == {"separation", "innovation", "none"}
    assert (t["epochs"] == 4 * 1000).all()
    assert t.loc["separation", "hazardous_v"] == 0 and t.loc["separation", "hazardous_h"] == 0
    assert t.loc["none", "misleading_v"] > 0
    assert (t["vpl_ratio_mean"] < 0.5).all() and (t["hpl_ratio_mean"] < 0.5).all()
    assert "filter protection levels" in c.format_table()
    assert max(len(line) for line in c.format_table().splitlines()) <= 100
    # Rates with their intervals, and the runs with a hazardous epoch (independent).
    assert t.loc["separation", "hmi_runs"] == 0 and t.loc["separation", "hmi_runs_hi"] > 0
    assert (t["mi_rate_v_lo"] <= t["mi_rate_v"]).all() and (t["mi_rate_v"] <= t["mi_rate_v_hi"]).all()
    assert t.loc["none", "mi_rate_v_lo"] > 0
    assert t.loc["none", "mi_rate_v"] == pytest.approx(t.loc["none", "misleading_v"] / t.loc["none", "epochs"])
    paths = c.write(tmp_path, figures=False)
    assert (tmp_path / "integrity.csv") in paths


def test_separation_without_an_integrity_table_is_refused():
    sc = load_scenario("shao2018")
    with pytest.raises(ScenarioError, match=r"tight\.integrity"):
        sc.with_values({"tight.fde": "separation"}).validate()


@pytest.mark.parametrize("key,value", [("p_sat", 0.7), ("p_hmi_vert", 0.0), ("p_fa_hor", -1e-9), ("tol_pl", -0.05), ("tol_pl", 1e3)])
def test_impossible_integrity_probabilities_are_refused(key, value):
    sc = load_scenario("shao2018_integrity")
    with pytest.raises(ScenarioError, match=rf"tight\.integrity\.{key}"):
        sc.with_values({f"tight.integrity.{key}": value}).validate()


def test_unknown_integrity_keys_are_refused():
    sc = load_scenario("shao2018_integrity")
    with pytest.raises(ScenarioError, match=r"tight\.integrity"):
        sc.with_values({"tight.integrity.p_md": 1e-3}, create=True).validate()


@pytest.mark.parametrize("states", [False, True], ids=["white", "range_states"])
def test_separation_excludes_the_faulty_satellite_on_the_recorded_walk(states):
    """Placement ``separation`` on the recorded walk: the bank names the satellite whose
    sub-filter separates (its navigator must explain the epoch: the other satellites agree
    with it, the named one does not), the filter takes that navigator over. The bundled 20 m
    step on G27 (160 epochs) is excluded at nearly all its epochs (white 100 %; with range-error
    states 92.5 %: G27's state takes in the step's first 3 s before its sub-filter separates),
    no other satellite ever, and the fault-free walk has no exclusion — with white range errors
    (whose separation test alarms at nearly every epoch there) and with range-error states."""
    vals = {"tight.integrity": {}, "tight.fde": "separation"}
    if states:
        vals["tight.range_states"] = {"fraction": 0.49, "tau": "6.7 s"}
    sc = load_scenario("walk_tc").with_values(vals, create=True).with_values({"variants": []})
    run = run_scenario(sc, seed=0)
    sat = run.record["satellites"]
    names = list(sat["names"])
    t = np.asarray(run.t)
    fault = (t >= 50.0) & (t < 90.0) & sat["in_view"][:, names.index("G27")]
    assert sat["excluded"][fault, names.index("G27")].mean() >= 0.9
    others = np.delete(sat["excluded"], names.index("G27"), axis=1)
    assert not others.any()
    clean = run_scenario(sc.with_values({"faults": []}), seed=0)
    assert not clean.record["satellites"]["excluded"].any()


@pytest.fixture(scope="module")
def walk():
    sc = load_scenario("walk_tc").with_values({"tight.integrity": {}}, create=True)
    return run_scenario(sc, seed=0)


def test_levels_on_the_recorded_walk_and_why_they_are_not_usable_there(walk):
    """The strapdown bank on real IMU and RINEX logs: levels every aligned epoch, far below
    the snapshot ARAIM levels; but the separation test alarms at most fault-free epochs (the
    filter's white pseudorange noise does not describe a handheld receiver's time-correlated
    errors), and the console says the levels are not usable."""
    for name, r in walk.runs.items():
        it = r.record["integrity"]
        ok = np.isfinite(it["hpl"])
        aligned = np.isfinite(r.record["nav"][:, 0])
        assert (ok == aligned).all(), name
        both = ok & np.isfinite(it["hpl_snapshot"])
        assert (it["hpl"][both] < it["hpl_snapshot"][both]).all() and (it["vpl"][both] < it["vpl_snapshot"][both]).all()
        i = r.integrity()
        assert i["epochs"] == int(ok.sum())
        assert i["alarm_rate_before_faults"] > 0.5
        # About the reference's own datum (8 m off), the horizontal error stays inside the HPL.
        assert i["misleading_h"] == 0
    assert "levels are not usable here" in walk.format_tables()


def test_the_bundled_scenario_is_listed():
    from navfdi._bundled import bundled_scenarios

    assert "shao2018_integrity" in bundled_scenarios()


def test_an_ambiguous_alarm_excludes_nothing_until_the_culprit_is_clear():
    # G16 and G19 see the receiver along similar lines: under a slow ramp on G19 the
    # separation test alarms before the two can be told apart. Run 9 of this campaign once
    # excluded G16 there (the bank restarted from a state holding G19's bias, and the error
    # then walked past the VPL unflagged for 29 epochs); now the alarm stands unidentified
    # until G19 alone stands out, and no epoch is hazardously misleading.
    sc = load_scenario("shao2018_integrity").with_values({"faults[1].satellite": "G19", "faults[1].magnitude": "0.05 m/s"})
    c = montecarlo(sc, runs=10, seed=0, keep_series=[9])
    rec = c.series[(0, 9)]
    sat = rec["satellites"]
    t = rec["t"]
    status = np.array(sat["status_names"])[sat["status"]]
    in_ramp = (t >= 160) & (t < 262)
    assert (status[in_ramp] == "unidentified").sum() > 0
    excluded_in_ramp = {sat["names"][j] for j in np.flatnonzero(sat["excluded"][in_ramp].any(axis=0))}
    assert excluded_in_ramp == {"G19"}
    t_sum = c.integrity_summary().set_index("variant")
    assert t_sum.loc["separation", "hazardous_v"] == 0 and t_sum.loc["separation", "hazardous_h"] == 0


def test_a_logged_campaign_counts_the_levels_and_flags_the_alarms():
    sc = load_scenario("walk_tc").with_values({"tight.integrity": {}}, create=True)
    c = montecarlo(sc, runs=2, seed=0)
    t = c.integrity_summary()
    assert (t["epochs"] == 2 * 485).all()
    assert (t["alarm_epochs"] > 0.5 * t["epochs"]).all()
    text = c.format_table()
    assert "the levels do not hold on these data" in text
    assert max(len(line) for line in text.splitlines()) <= 100


def _ar1_arcs(rho: float, arcs: int = 80, n: int = 2000, seed: int = 0) -> list[tuple[np.ndarray, np.ndarray]]:
    """Stationary AR(1) arcs (160 000 samples by default: the estimate's spread is then ~3 %)."""
    from scipy.signal import lfilter

    rng = np.random.default_rng(seed)
    out = []
    for _ in range(arcs):
        e = rng.normal(size=n)
        e[0] /= np.sqrt(1 - rho**2)
        out.append((np.arange(n), lfilter([1.0], [1.0, -rho], e)))
    return out


@pytest.mark.parametrize("rho", [0.0, 0.5, 0.8])
def test_integrated_autocorrelation_of_ar1_series(rho):
    """τ = (1 + ρ)/(1 − ρ) for AR(1); arcs with gaps (missing epochs) give the same."""
    from navfdi.logs import integrated_autocorrelation

    want = (1 + rho) / (1 - rho)
    arcs = _ar1_arcs(rho)
    tau, r = integrated_autocorrelation(arcs)
    assert tau == pytest.approx(want, rel=0.1)
    assert r[0] == 1.0 and abs(r[1] - rho) < 0.03
    gappy = [(e[::3] if k % 2 else e, x[::3] if k % 2 else x) for k, (e, x) in enumerate(arcs)]
    assert integrated_autocorrelation(gappy)[0] == pytest.approx(want, rel=0.15)
    with pytest.raises(ValueError, match="at least 20"):
        integrated_autocorrelation([(np.arange(10), np.arange(10.0))])


def test_range_errors_scale_the_pseudorange_noise_or_are_refused():
    sc = load_scenario("walk_tc").with_values({"tight.integrity": {"range_errors": 9.0}}, create=True)
    assert sc.core["sensors"][0]["noise"] == pytest.approx([2.1, 0.15])
    assert "range_errors" not in sc.core["tight"]["integrity"]
    with pytest.raises(ScenarioError, match="simulated scenario's range errors are known"):
        load_scenario("shao2018_integrity").with_values({"tight.integrity.range_errors": "overbound"}, create=True)
    for bad in (0.5, "pink", True, 1e5):
        with pytest.raises(ScenarioError, match=r"tight\.integrity\.range_errors"):
            load_scenario("shao2018_integrity").with_values({"tight.integrity.range_errors": bad}, create=True)


def test_an_overbound_of_the_correlated_range_errors_makes_the_walk_levels_usable():
    """range_errors = "overbound": the pseudorange variance grows by the integrated
    autocorrelation time of the log's own snapshot residuals (not the reference), and the
    separation test no longer alarms fault-free; the errors about the reference's datum stay
    inside the levels, which stay below the snapshot ARAIM levels of the same model."""
    from navfdi.logs import range_error_overbound

    sc = load_scenario("walk_tc").with_values({"tight.integrity": {"range_errors": "overbound"}, "faults": []}, create=True)
    f, info = range_error_overbound(sc)
    assert 5.0 < f < 100.0 and info["arcs"] >= 8 and info["lags"] >= 10
    r = run_scenario(sc, seed=0)
    for name, run in r.runs.items():
        assert run.scenario.raw["tight"]["integrity"]["range_errors"] == pytest.approx(f, abs=1e-3)
        assert run.scenario.core["sensors"][0]["noise"][0] == pytest.approx(0.7 * np.sqrt(f), rel=1e-3)
        i = run.integrity()
        assert i["alarm_rate_before_faults"] == 0.0, name
        assert i["misleading_h"] == 0 and i["misleading_v"] == 0
        assert i["hpl_ratio_mean"] < 1.0 and i["vpl_ratio_mean"] < 1.0
    text = r.format_tables()
    assert "not usable" not in text and "pseudorange variance x" in text
    # The campaign path resolves it the same way.
    c = montecarlo(sc, runs=1, seed=0)
    t = c.integrity_summary()
    assert (t["alarm_epochs"] == 0).all() and (t["misleading_h"] == 0).all()


def test_sub_filters_outlive_their_satellites_absences_on_the_walk():
    """The case a 100-run logged campaign found: a 20.7 m step on G23 at 71.3–111.3 s, with
    the overbound model none of the placements excludes it. G23 drops out for a few epochs
    now and then; a sub-filter reborn from the filter at each return inherited the step's
    error, lost the clean reference, and 26 vertical epochs beyond the VPL went unflagged.
    Kept through absences (HOLD_ABSENT, 60 s), the separation alarm covers every epoch the
    error leaves the levels."""
    sc = load_scenario("walk_tc").with_values(
        {"tight.integrity": {"range_errors": 23.294}, "faults[0].satellite": "G23", "faults[0].magnitude": "20.7 m", "faults[0].start": "71.3 s", "faults[0].end": "111.3 s"},
        create=True,
    )
    r = run_scenario(sc, seed=0)
    for name, run in r.runs.items():
        i = run.integrity()
        assert i["misleading_v"] > 100, name  # the error does leave the levels
        assert i["hazardous_h"] == 0 and i["hazardous_v"] == 0, name
    in_view = np.asarray(r.runs["none"].record["satellites"]["in_view"])
    g23 = r.runs["none"].record["satellites"]["names"].index("G23")
    assert not in_view[:, g23].all()  # it does drop out


def test_a_campaign_at_the_worst_moment_stays_within_the_allocation():
    """Near-threshold steps (6, 10 m) on the worst pair (G16, G19: similar lines of sight)
    from the worst onset the campaign script found (5 s, when the sub-filters have barely
    separated). Every run carries a fault, so the allocation bounds the hazardous epochs per
    fault epoch by P_HMI / P_sat (9.8e-3 vertical, 2e-4 horizontal); the filter levels stay
    below the snapshot ones. By default 5 runs per point (2 × 10⁴ epochs per variant, 7 s);
    with ``NAVFDI_SLOW_TESTS=1`` the issue's count, 25 runs (≥ 10⁵ epochs per variant, 30 s)."""
    runs = 25 if os.environ.get("NAVFDI_SLOW_TESTS") == "1" else 5
    sweep = {"faults[0].satellite": ["G16", "G19"], "faults[0].magnitude": ["6 m", "10 m"], "faults[0].start": ["5 s"]}
    c = montecarlo("shao2018_integrity", runs=runs, seed=2, sweep=sweep, progress=False)
    t = c.integrity_summary()
    for variant, g in t.groupby("variant"):
        assert g["epochs"].sum() >= 4000 * runs, variant
        assert (g["hpl_ratio_mean"] < 1).all() and (g["vpl_ratio_mean"] < 1).all()
    sep = t[t["variant"] == "separation"]
    fault_epochs = 4 * runs * (110 - 5) * 2  # the step's window at 2 Hz, 4 points
    assert sep["hazardous_v"].sum() <= 9.8e-8 / 1e-5 * fault_epochs
    assert sep["hazardous_h"].sum() <= 2e-9 / 1e-5 * fault_epochs
