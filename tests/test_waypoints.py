"""Trajectories given as waypoints in a local ENU frame (paper 003 flies (0, 0, 8) m →
(100, 100, 8) m)."""

from __future__ import annotations

import copy
import math
import warnings

import numpy as np
import pytest

import navfdi
from navfdi.scenario import ScenarioError, load_scenario

LAT0, LON0, H0 = 55.75, 37.62, 150.0


def scenario(waypoints, speed="2 m/s", duration="200 s", **extra):
    raw = copy.deepcopy(load_scenario("yang2013").base().raw)
    raw.update(duration=duration, dt="0.1 s", faults=[])
    raw["trajectory"] = {"latitude": f"{LAT0} deg", "longitude": f"{LON0} deg", "height": f"{H0} m", "waypoints": waypoints, "speed": speed, **extra}
    return navfdi.load_scenario(raw)


def local(tr):
    lat0, lon0 = math.radians(LAT0), math.radians(LON0)
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    s2 = math.sin(lat0) ** 2
    rm = a * (1 - e2) / (1 - e2 * s2) ** 1.5 + H0
    rn = (a / math.sqrt(1 - e2 * s2) + H0) * math.cos(lat0)
    return (tr["lon"] - lon0) * rn, (tr["lat"] - lat0) * rm, tr["h"] - H0


def test_the_flight_passes_its_waypoints_and_stops_on_the_last():
    wps = [[0, 0, 8], [100, 100, 8], [100, 200, 20], [0, 250, 20]]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the rest after the last waypoint is planned, not held
        sc = scenario([[f"{v} m" for v in w] for w in wps], duration="300 s")
    tr = navfdi._core.scenario_trajectory(sc.to_json())
    e, n, u = local(tr)
    r = 2.0 / math.radians(30)  # speed / default turn rate
    for i, w in enumerate(wps):
        d = np.hypot(e - w[0], n - w[1])
        k = int(d.argmin())
        if 0 < i < len(wps) - 1:
            dpsi = abs((math.atan2(wps[i + 1][0] - w[0], wps[i + 1][1] - w[1]) - math.atan2(w[0] - wps[i - 1][0], w[1] - wps[i - 1][1]) + math.pi) % (2 * math.pi) - math.pi)
            assert d[k] == pytest.approx(r * (1 / math.cos(dpsi / 2) - 1), abs=0.05), i
        else:
            assert d[k] < 0.01, i
        assert u[k] == pytest.approx(w[2], abs=0.01), i
    # At rest on the last waypoint at the end.
    assert np.hypot(e[-1] - wps[-1][0], n[-1] - wps[-1][1]) < 0.01
    assert np.linalg.norm(tr["v"][-1]) < 1e-9


def test_paper_003_leg_runs_through_the_filters():
    sc = scenario([["0 m", "0 m", "8 m"], ["100 m", "100 m", "8 m"]], duration="100 s")
    res = navfdi.run_scenario(sc, seed=1)
    assert np.isfinite(res.record["error"]).all()


@pytest.mark.parametrize(
    "waypoints, extra, match",
    [
        ([["0 m", "0 m", "8 m"]], {}, "at least two waypoints"),
        ([["0 m", "0 m", "8 m"], ["0 m", "0 m", "20 m"]], {}, r"waypoints\[1\]: same horizontal position"),
        ([["0 m", "0 m"], ["1 m", "1 m", "1 m"]], {}, r"waypoints\[0\]"),
        ([["0 m", "0 m", "8 s"], ["10 m", "0 m", "8 m"]], {}, r"waypoints\[0\]\[2\]"),
        ([["0 m", "0 m", "8 m"], ["3 m", "0 m", "8 m"], ["3 m", "3 m", "8 m"]], {}, r"too short for the turns"),
        ([["0 m", "0 m", "8 m"], ["30 m", "0 m", "8 m"]], {"turn_rate": "0 deg/s"}, "turn_rate"),
        ([["0 m", "0 m", "8 m"], ["30 m", "0 m", "8 m"]], {"segments": []}, "unknown field"),
    ],
)
def test_bad_waypoints_are_named(waypoints, extra, match):
    with pytest.raises(ScenarioError, match=match):
        scenario(waypoints, **extra)
    with pytest.raises(ScenarioError, match="speed"):
        scenario([["0 m", "0 m", "8 m"], ["30 m", "0 m", "8 m"]], speed="0 m/s")
