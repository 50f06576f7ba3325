"""Navigation modes (paper 003, METHODS §9): q3 near the target, q1 with GNSS, q2 in a GNSS
outage; a sensor outside the active mode gives no measurement."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import navfdi
from navfdi.scenario import ScenarioError, load_scenario


def raw_scenario():
    raw = copy.deepcopy(load_scenario("yang2013").base().raw)
    raw.update(duration="120 s", dt="0.5 s", faults=[])
    raw["trajectory"] = {"latitude": "55.75 deg", "longitude": "37.62 deg", "height": "0 m", "waypoints": [["0 m", "0 m", "8 m"], ["100 m", "100 m", "8 m"]], "speed": "2 m/s"}
    raw["sensors"] = [
        {"name": "gnss", "kind": "gnss_position", "noise": "2 m", "rate": "1 Hz", "outages": [["20 s", "40 s"]]},
        {"name": "slam", "kind": "vision", "noise": "0.5 m", "rate": "2 Hz"},
        {"name": "baro", "kind": "baro", "noise": "1 m", "rate": "2 Hz"},
    ]
    raw["federated"]["subfilters"] = [
        {"sensor": s, "share": 1 / 3, "detectors": [{"name": "chi2", "kind": "chi2", "pf": 0.01}]} for s in ("gnss", "slam", "baro")
    ]
    raw["federated"]["master_share"] = 0.0
    raw["modes"] = {"gnss": "gnss", "target": ["100 m", "100 m"], "radius": "20 m", "q1": ["gnss", "baro"], "q2": ["slam", "baro"], "q3": ["gnss", "slam", "baro"]}
    return raw


def test_mode_sequence_matches_outage_and_target_windows_exactly(tmp_path):
    sc = navfdi.load_scenario(raw_scenario())
    res = navfdi.run_scenario(sc, seed=1, compare_isolation=False)
    t = res.t
    # Distance to the target along the straight leg at 2 m/s from (0, 0): 100·√2 − 2t (before
    # the stop), so within 20 m from t = (100√2 − 20) / 2.
    t_near = (100 * math.sqrt(2) - 20) / 2
    want = np.where(t >= t_near - 1e-6, 3, np.where((t >= 20) & (t < 40), 2, 1))
    mode = res.record["mode"]
    # The boundary epoch of the target radius may fall either side of the analytic time.
    off = np.flatnonzero(mode != want)
    assert off.size <= 1 and all(abs(t[k] - t_near) < 0.5 for k in off), t[off]
    ts = res.timeseries()
    assert set(ts["mode"]) == {"q1", "q2", "q3"}
    # A sensor outside the active mode gives no measurement: slam only in q2/q3, gnss not in q2.
    slam = next(s for s in res.record["subfilters"] if s["sensor"] == "slam")
    gnss = next(s for s in res.record["subfilters"] if s["sensor"] == "gnss")
    assert np.isnan(slam["statistic"][mode == 1]).all()
    assert np.isfinite(slam["statistic"][mode == 2]).all()
    assert np.isnan(gnss["statistic"][mode == 2]).all()
    assert "modes.png" in {p.name for p in res.write(tmp_path)}


@pytest.mark.parametrize(
    "change, match",
    [
        ({"gnss": "gps"}, r"modes\.gnss.*not a sensor"),
        ({"radius": "0 m"}, r"modes\.radius"),
        ({"q1": []}, r"modes\.q1: at least one"),
        ({"q2": ["slam", "slam"]}, r"modes\.q2\[1\]"),
        ({"q3": ["lidar"]}, r"modes\.q3\[0\].*not a sensor"),
        ({"target": ["1 m"]}, r"modes\.target"),
    ],
)
def test_bad_modes_are_named(change, match):
    raw = raw_scenario()
    raw["modes"].update(change)
    with pytest.raises(ScenarioError, match=match):
        navfdi.load_scenario(raw)
