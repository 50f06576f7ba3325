"""Tight architecture (paper 001): schema, records, outputs and Monte-Carlo columns."""

from __future__ import annotations

import copy

import numpy as np
import pandas as pd
import pytest

import navfdi
from navfdi.scenario import ScenarioError, load_scenario


@pytest.fixture(scope="module")
def raw():
    return copy.deepcopy(load_scenario("shao2018").base().raw)


def bad(raw, match, **changes):
    r = copy.deepcopy(raw)
    for path, value in changes.items():
        target = r
        parts = path.split("/")
        for p in parts[:-1]:
            target = target[int(p)] if p.isdigit() else target[p]
        last = parts[-1]
        if value is None:
            del target[int(last) if last.isdigit() else last]
        else:
            target[int(last) if last.isdigit() else last] = value
    with pytest.raises(ScenarioError, match=match):
        navfdi.load_scenario(r)


def test_schema_errors_name_the_field(raw):
    bad(raw, r"faults\[0\]\.satellite.*missing", **{"faults/0/satellite": None})
    bad(raw, r"faults\[0\]\.satellite.*G99.*not a satellite", **{"faults/0/satellite": "G99"})
    bad(raw, r"sensors\[0\]\.ranges.*missing", **{"sensors/0/ranges": None})
    bad(raw, r"sensors\[0\]\.ranges\.systems\[0\].*glonass", **{"sensors/0/ranges/systems": ["glonass"]})
    bad(raw, r"elevation_mask", **{"sensors/0/ranges/elevation_mask": "85 deg"})
    bad(raw, r"clock\.bias", **{"sensors/0/ranges/clock/bias": "0 m"})
    bad(raw, r"tight\.fde", **{"tight/fde": "raim"})
    bad(raw, r"tight\.alpha", **{"tight/alpha": 1.5})
    bad(raw, r"tight\.k", **{"tight/k": -1.0})
    bad(raw, r"tight\.accel_psd", **{"tight/accel_psd": "0 m^2/s^3"})
    bad(raw, r"tight: missing|tight.*missing", **{"tight": None})
    bad(raw, r"needs architecture = \"tight\"", architecture="centralized", tight=None, centralized={"policy": "exclude", "sensors": [{"sensor": "gnss_ranges"}]})
    r = copy.deepcopy(raw)
    r["sensors"].append({"name": "baro", "kind": "baro", "noise": "1 m", "rate": "1 Hz"})
    with pytest.raises(ScenarioError, match=r"sensors\[1\].*only its gnss_ranges sensor"):
        navfdi.load_scenario(r)
    r = copy.deepcopy(raw)
    r["sensors"][0]["kind"] = "baro"
    r["sensors"][0]["noise"] = "3 m"
    with pytest.raises(ScenarioError, match=r"sensors\[0\]\.ranges: only a gnss_ranges"):
        navfdi.load_scenario(r)


def test_record_shapes_and_shared_measurements():
    res = navfdi.run_scenario("shao2018", seed=3)
    assert set(res.runs) == {"ls_precheck", "innovation", "gnss_filter", "none"}
    recs = {n: r.record for n, r in res.runs.items()}
    T = res["none"].t.size
    assert T == 1000
    for rec in recs.values():
        sat = rec["satellites"]
        S = len(sat["names"])
        assert sat["in_view"].shape == (T, S) == sat["excluded"].shape == sat["w"].shape
        n = sat["in_view"].sum(axis=1)
        assert 10 <= n.min() and n.max() <= 11
        # excluded satellites are in view; used + excluded = in view
        assert not (sat["excluded"] & ~sat["in_view"]).any()
        np.testing.assert_array_equal(sat["used"] + sat["excluded"].sum(axis=1), n)
    # Same satellites in view in every variant (same measurements); none never excludes.
    np.testing.assert_array_equal(recs["none"]["satellites"]["in_view"], recs["innovation"]["satellites"]["in_view"])
    assert not recs["none"]["satellites"]["excluded"].any()
    # Without FDE the faults corrupt the position; with either method it stays at metres.
    err = res.errors().set_index("variant")
    assert err.loc["none", "pos_u_max"] > 50
    for v in ("ls_precheck", "innovation", "gnss_filter"):
        assert err.loc[v, "pos_u_max"] < 10, v
    # The innovation global test of the "none" variant is the same statistic as the
    # "innovation" variant's first test up to the first epoch that excludes anything.
    a = res["none"].detector("gnss_ranges", "global")["statistic"]
    b = res["innovation"].detector("gnss_ranges", "global")["statistic"]
    first = int(np.argmax(recs["innovation"]["satellites"]["excluded"].any(axis=1)))
    np.testing.assert_array_equal(a[: first + 1], b[: first + 1])


def test_outputs(tmp_path):
    res = navfdi.run_scenario("shao2018", seed=0)
    paths = res.write(tmp_path)
    names = {p.name for p in paths}
    assert {"satellites.csv", "identified_satellites.png", "timeseries.parquet"} <= names
    sats = pd.read_csv(tmp_path / "satellites.csv")
    assert set(sats["variant"]) == {"ls_precheck", "innovation", "gnss_filter", "none"}
    assert set(sats["fault_id"]) == {"step60", "ramp2", "ramp4", "none"}
    ts = pd.read_parquet(tmp_path / "timeseries.parquet")
    for c in ("fde.status", "fde.excluded", "fde.used", "sat.G03.w", "sat.G03.excluded"):
        assert c in ts.columns
    g3 = ts[(ts["variant"] == "ls_precheck") & (ts["t"] >= 40) & (ts["t"] < 110)]
    assert g3["fde.excluded"].str.contains("G03").mean() > 0.9
    text = res.format_tables()
    assert "satellite FDE (ls_precheck" in text and "83.33 %" in text


def test_montecarlo_summary_has_satellite_columns():
    c = navfdi.montecarlo("shao2018", runs=4, seed=1)
    s = c.summary()
    for col in ("variant", "fault_id", "detection_rate", "identification_rate", "false_exclusion_rate", "after_fault_alarm_rate"):
        assert col in s.columns
    rows = s.set_index(["variant", "fault_id"])
    assert rows.loc[("ls_precheck", "step60"), "detection_rate"] > 0.95
    assert rows.loc[("none", "step60"), "detection_rate"] == 0
    assert np.isnan(rows.loc[("ls_precheck", "none"), "detection_rate"])
    assert 0 <= rows.loc[("ls_precheck", "none"), "false_exclusion_rate"] < 0.2
    # The same run's counts in Monte-Carlo and in navfdi run (one metrics engine).
    run = navfdi.run_scenario("shao2018", seed=1)
    # Monte-Carlo run i uses stream i; run_scenario uses stream 0 = Monte-Carlo run 0.
    r0 = c.runs[(c.runs["run"] == 0) & (c.runs["variant"] == "ls_precheck") & (c.runs["fault_id"] == "ramp2")]
    m = next(m for m in run["ls_precheck"].record["satellites"]["metrics"] if m["fault"] == 1)
    assert int(r0["fde_detected_epochs"].iloc[0]) == m["detected_epochs"]
    assert int(r0["fde_exact_epochs"].iloc[0]) == m["exact_epochs"]


def test_rust_fixture_matches_bundled_scenario():
    """benches/shao2018.json (used by the criterion benchmark) is the bundled TOML in SI."""
    import json
    from pathlib import Path

    fixture = json.loads((Path(__file__).resolve().parents[1] / "benches" / "shao2018.json").read_text())
    assert fixture == navfdi.load_scenario("shao2018").base().core


def test_results_do_not_depend_on_threads():
    """A tight campaign gives the same per-run counts with 1 and 2 threads."""
    a = navfdi.montecarlo("shao2018", runs=4, seed=9, workers=1).runs
    b = navfdi.montecarlo("shao2018", runs=4, seed=9, workers=2).runs
    pd.testing.assert_frame_equal(a, b)


def test_rate_fault_is_excluded_by_the_stacked_precheck():
    """A fault on one satellite's pseudorange rate (components = ["rate"]) is caught by the
    ls_precheck's stacked pseudorange + rate test and by the innovation test."""
    r = copy.deepcopy(load_scenario("shao2018").raw)
    r["faults"] = [{"id": "rate", "sensor": "gnss_ranges", "satellite": "G03", "components": ["rate"], "kind": "step", "magnitude": "2 m/s", "start": "100 s", "end": "200 s"}]
    res = navfdi.run_scenario(navfdi.load_scenario(r), seed=4)
    for v in ("ls_precheck", "innovation"):
        tab = res[v].satellite_table().set_index("fault_id")
        assert tab.loc["rate", "detection_rate"] > 0.99, v
    assert res["none"].satellite_table().set_index("fault_id").loc["rate", "detection_rate"] == 0


def test_elevation_dependent_noise_and_changing_geometry():
    """elevation_noise = true scales σ by 1/sin(elevation): a low satellite's w-test residuals
    stay standardised (false-exclusion rate still about α) while its raw residuals grow."""
    r = copy.deepcopy(load_scenario("shao2018").base().raw)
    r["faults"] = []
    r["sensors"][0]["ranges"]["elevation_noise"] = True
    r["tight"]["fde"] = "ls_precheck"
    c = navfdi.montecarlo(navfdi.load_scenario(r), runs=10, seed=5)
    s = c.summary().set_index("fault_id")
    assert 0.02 < s.loc["none", "false_alarm_rate"] < 0.08
    # A GPS-only constellation with a low mask sees satellites rise and set within 500 s.
    r["sensors"][0]["ranges"].update(systems=["gps"], elevation_mask="5 deg", epoch="0 s")
    run = navfdi.run_scenario(navfdi.load_scenario(r), seed=0)
    n = run.record["satellites"]["in_view"].sum(axis=1)
    assert n.min() < n.max()


def test_simulated_correlated_range_errors(raw):
    """``[sensors.ranges] correlated``: a share of each pseudorange's variance drawn as a
    first-order Gauss-Markov process per satellite. The white-noise filter cannot average it
    out (its position error grows several-fold at the same σ); a zero share draws exactly
    the white errors of a scenario without the key; bad values are named."""
    bad(raw, r"sensors\[0\]\.ranges\.correlated\.fraction", **{"sensors/0/ranges/correlated": {"fraction": 1.0, "tau": "10 s"}})
    bad(raw, r"sensors\[0\]\.ranges\.correlated.*tau", **{"sensors/0/ranges/correlated": {"fraction": 0.5}})
    bad(raw, r"correlated.*tau.*correlation time", **{"sensors/0/ranges/correlated": {"fraction": 0.5, "tau": "0 s"}})
    bad(raw, r"sensors\[0\]\.ranges\.correlated.*sigma", **{"sensors/0/ranges/correlated": {"fraction": 0.5, "tau": "10 s", "sigma": "1 m"}})
    base = copy.deepcopy(raw)
    base.pop("faults", None)

    def run(correlated):
        r = copy.deepcopy(base)
        if correlated is not None:
            r["sensors"][0]["ranges"]["correlated"] = correlated
        return navfdi.run_scenario(navfdi.load_scenario(r), seed=2)

    white, zero, slow = run(None), run({"fraction": 0.0, "tau": "60 s"}), run({"fraction": 0.8, "tau": "60 s"})
    np.testing.assert_array_equal(white.record["error"], zero.record["error"])
    e_white, e_slow = white.errors(), slow.errors()
    for c in ("pos_e_rms", "pos_n_rms", "pos_u_rms"):
        assert e_slow[c] > 3 * e_white[c], (c, e_white[c], e_slow[c])
