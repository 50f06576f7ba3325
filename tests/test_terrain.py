"""Terrain (sum of sinusoids) and the radio altimeter sensor: its error is the terrain height
under the vehicle."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import navfdi
from navfdi.scenario import ScenarioError, load_scenario


def scenario(waves):
    raw = copy.deepcopy(load_scenario("yang2013").base().raw)
    raw["duration"] = "200 s"
    raw["sensors"] = [
        {"name": "ra", "kind": "radio_altimeter", "noise": "0.001 m", "rate": "1 Hz"},
        {"name": "baro", "kind": "baro", "noise": "0.001 m", "rate": "1 Hz"},
    ]
    raw["faults"] = []
    raw["federated"]["subfilters"] = [
        {"sensor": "ra", "share": 0.5, "detectors": [{"name": "chi2", "kind": "chi2", "pf": 0.01}]},
        {"sensor": "baro", "share": 0.5, "detectors": [{"name": "chi2", "kind": "chi2", "pf": 0.01}]},
    ]
    raw.pop("variants", None)
    if waves is not None:
        raw["terrain"] = {"waves": waves}
    return navfdi.load_scenario(raw)


def test_radio_altimeter_error_is_the_terrain_under_the_vehicle():
    waves = [{"amplitude": "3 m", "wavelength": "500 m", "heading": "30 deg", "phase": "10 deg"}, {"amplitude": "1 m", "wavelength": "120 m", "heading": "100 deg"}]
    sc = scenario(waves)
    tr = navfdi._core.scenario_trajectory(sc.to_json())
    lat0, lon0, h0 = tr["lat"][0], tr["lon"][0], tr["h"][0]
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    rm = a * (1 - e2) / (1 - e2 * math.sin(lat0) ** 2) ** 1.5 + h0
    rn = (a / math.sqrt(1 - e2 * math.sin(lat0) ** 2) + h0) * math.cos(lat0)
    east, north = (tr["lon"] - lon0) * rn, (tr["lat"] - lat0) * rm
    expected = sum(
        A * np.sin(2 * math.pi * (east * math.sin(th) + north * math.cos(th)) / lam + ph)
        for A, lam, th, ph in [(3, 500, math.radians(30), math.radians(10)), (1, 120, math.radians(100), 0.0)]
    )
    assert np.ptp(expected) > 1.0  # the vehicle crosses the waves
    # RA and baro measure the same height error; their difference is the terrain (+ tiny noise).
    flat = navfdi.run_scenario(scenario(None), seed=2, compare_isolation=False)
    wavy = navfdi.run_scenario(sc, seed=2, compare_isolation=False)
    # With the same seed the noise is identical: the statistics differ only by the terrain.
    assert not np.allclose(flat.detector("ra", "chi2")["statistic"], wavy.detector("ra", "chi2")["statistic"])
    np.testing.assert_allclose(flat.detector("baro", "chi2")["statistic"][:1], wavy.detector("baro", "chi2")["statistic"][:1])
    assert wavy.detector("ra", "chi2")["alarm"].mean() > 0.5  # metres of terrain error vs 1 mm noise


@pytest.mark.parametrize(
    "wave, match",
    [
        ({"amplitude": "-1 m", "wavelength": "10 m"}, r"terrain.waves\[0\]\.amplitude"),
        ({"amplitude": "1 m", "wavelength": "0 m"}, r"terrain.waves\[0\]\.wavelength"),
        ({"amplitude": "1 m", "wavelength": "10 s"}, r"terrain.waves\[0\]\.wavelength"),
        ({"amplitude": "1 m"}, r"terrain.waves\[0\]\.wavelength: missing"),
        ({"amplitude": "1 m", "wavelength": "10 m", "slope": 1}, r"terrain.waves\[0\]: unknown field"),
    ],
)
def test_bad_terrain_is_named(wave, match):
    with pytest.raises(ScenarioError, match=match):
        scenario([wave])
