"""Altitude fusion with a fault matrix inside a centralized filter (paper 003, METHODS §9)."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import navfdi
from navfdi.scenario import ScenarioError, load_scenario


def raw_scenario():
    raw = copy.deepcopy(load_scenario("yang2013").base().raw)
    raw.update(duration="300 s", dt="0.5 s", faults=[], architecture="centralized")
    raw.pop("federated")
    raw["trajectory"] = {"latitude": "55.75 deg", "longitude": "37.62 deg", "height": "0 m", "waypoints": [["0 m", "0 m", "8 m"], ["300 m", "300 m", "8 m"]], "speed": "2 m/s"}
    raw["terrain"] = {"waves": [{"amplitude": "1.5 m", "wavelength": "40 m", "heading": "0 deg"}, {"amplitude": "1.5 m", "wavelength": "40 m", "heading": "90 deg"}]}
    raw["sensors"] = [
        {"name": "gnss", "kind": "gnss_position", "noise": ["1.5 m", "1.5 m", "3 m"], "rate": "2 Hz", "outages": [["100 s", "150 s"]]},
        {"name": "baro", "kind": "baro", "noise": "1 m", "rate": "2 Hz", "outages": [["100 s", "150 s"]]},
        {"name": "ra", "kind": "radio_altimeter", "noise": "0.1 m", "rate": "2 Hz", "outages": [["120 s", "150 s"]]},
    ]
    raw["centralized"] = {
        "policy": "exclude",
        "sensors": [{"sensor": s, "decision": "chi2", "detectors": [{"name": "chi2", "kind": "chi2", "pf": 0.01}]} for s in ("gnss", "baro", "ra")],
        "altitude_fusion": {"sensors": ["gnss", "baro", "ra"], "samples": 20},
    }
    raw["variants"] = [{"name": "isolation", "set": {"centralized.isolate": True}}, {"name": "no_isolation", "set": {"centralized.isolate": False}}]
    return raw


def test_fused_altitude_is_recorded_and_predicts_only_without_sensors(tmp_path):
    res = navfdi.run_scenario(navfdi.load_scenario(raw_scenario()), seed=1)
    for name, r in res.runs.items():
        f = r.record["fused_alt"]
        t = r.t
        gap = (t >= 120) & (t < 150)  # every fused sensor in outage: predict only
        assert np.isnan(f[gap]).all(), name
        # Elsewhere a fused altitude exists unless every sensor present was excluded (M = 0).
        excluded_all = np.ones(t.size, bool)
        for s in r.record["subfilters"]:
            present = ~np.isnan(s["statistic"])
            excluded_all &= ~present | s["isolated"]
        np.testing.assert_array_equal(np.isnan(f) & ~gap, excluded_all & ~gap)
    err = res.errors().set_index("variant")
    assert err.loc["no_isolation", "fused_alt_predict_only"] == pytest.approx(60 / 600)
    assert err.loc["isolation", "fused_alt_predict_only"] >= 60 / 600
    # The terrain makes the radio altimeter fail its residual test; with isolate = false
    # nothing is ever excluded (every M_i = 1).
    iso = {s["sensor"]: s["isolated"].mean() for s in res["isolation"].record["subfilters"]}
    assert iso["ra"] > 0.3 and iso["baro"] < 0.05 and iso["gnss"] < 0.05
    assert not any(s["isolated"].any() for s in res["no_isolation"].record["subfilters"])
    assert "fused_alt.error" in res.timeseries().columns
    paths = {p.name for p in res.write(tmp_path)}
    assert "errors.csv" in paths


@pytest.mark.parametrize(
    "change, match",
    [
        ({"sensors": ["gnss"]}, r"altitude_fusion\.sensors: at least two"),
        ({"sensors": ["gnss", "lidar"]}, r"altitude_fusion\.sensors\[1\].*not one of centralized\.sensors"),
        ({"sensors": ["gnss", "gnss"]}, r"altitude_fusion\.sensors\[1\].*twice"),
        ({"samples": 1}, r"altitude_fusion\.samples"),
        ({"window": 3}, r"altitude_fusion: unknown field"),
    ],
)
def test_bad_fusion_config_is_named(change, match):
    raw = raw_scenario()
    raw["centralized"]["altitude_fusion"].update(change)
    with pytest.raises(ScenarioError, match=match):
        navfdi.load_scenario(raw)
