"""Scenario schema: units, field-path errors, bundled scenarios, trajectory."""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

import navfdi
from navfdi import _core
from navfdi.scenario import load_scenario
from navfdi.units import parse


@pytest.fixture(scope="module")
def raw():
    return copy.deepcopy(load_scenario("yang2013").raw)


def test_bundled_list_and_units_converted():
    assert "yang2013" in navfdi.bundled_scenarios()
    sc = navfdi.load_scenario("yang2013")
    core = sc.core
    assert core["ins"]["gyro_bias"] == pytest.approx(math.radians(0.01) / 3600)
    assert core["ins"]["accel_markov"] == pytest.approx(0.001)
    assert core["sensors"][0]["noise"] == [pytest.approx(math.radians(0.0017))] * 3
    ramp, step = sc.faults()
    # 0.1 σ/s and 20 σ with σ = 0.0017°
    assert ramp["magnitude"] == pytest.approx(0.1 * math.radians(0.0017))
    assert step["magnitude"] == pytest.approx(20 * math.radians(0.0017))
    assert ramp["components"] == [0, 1, 2] and (ramp["start"], ramp["end"]) == (300.0, 500.0)


@pytest.mark.parametrize(
    ("text", "dim", "si"),
    [("0.01 deg/h", "angular_rate", math.radians(0.01) / 3600), ("10 ug", "acceleration", 9.80665e-5), ("3 arcsec", "angle", math.radians(3 / 3600)), ("2 min", "time", 120.0)],
)
def test_units(text, dim, si):
    assert parse(text, dim, "x") == pytest.approx(si)


def set_path(raw, path, value):
    d = raw
    parts = path.replace("]", "").replace("[", ".").split(".")
    for p in parts[:-1]:
        d = d[int(p)] if p.isdigit() else d[p]
    last = parts[-1]
    if value is DELETE:
        del d[last]
    else:
        d[int(last) if last.isdigit() else last] = value


DELETE = object()


@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        ("ins.gyro_bias", 0.01, r"ins\.gyro_bias = 0\.01: needs a unit"),
        ("ins.gyro_bias", "0.01 furlong/h", r"ins\.gyro_bias = '0\.01 furlong/h': unknown unit 'furlong/h'"),
        ("ins.gyro_tau", "3600 m", r"ins\.gyro_tau = '3600 m': unknown unit 'm' for time"),
        ("duration", "ten s", r"duration = 'ten s': 'ten' is not a number"),
        ("trajectory.segments.1.kind", "loop", r"trajectory\.segments\[1\]\.kind = 'loop': unknown segment"),
        ("trajectory.segments.2.rate", "-5 m/s", r"trajectory\.segments\[2\]\.rate: -5 must be a positive"),
        ("sensors.0.kind", "lidar", r"sensors\[0\]\.kind = 'lidar': unknown sensor"),
        ("sensors.1.noise", ["5 m", "5 m"], r"sensors\[1\]\.noise: 2 values for a gnss sensor with 6 components"),
        ("sensors.0.rate", "5 Hz", r"sensors\[0\]\.rate: 5 Hz exceeds the filter rate"),
        ("faults.0.sensor", "cnss", r"faults\[0\]\.sensor = 'cnss': not a sensor \(known: 'cns', 'gnss'\)"),
        ("faults.1.components", ["roll"], r"faults\[1\]\.components\[0\] = 'roll': not a component of cns \(phi_e, phi_n, phi_u\)"),
        ("faults.0.magnitude", "0.1 sigma", r"faults\[0\]\.magnitude = '0\.1 sigma': a ramp needs a unit ending in '/s'"),
        ("faults.1.magnitude", "20 m", r"faults\[1\]\.magnitude = '20 m': unknown unit 'm' for angle"),
        ("faults.1.end", "700 s", r"faults\[1\]: window start = 800, end = 700"),
        ("federated.subfilters.0.share", 0.7, r"federated: shares must sum to 1"),
        ("federated.subfilters.0.isolation", "cusum", r"federated\.subfilters\[0\]\.isolation: \"cusum\" is not one of this sub-filter's detectors"),
        ("federated.subfilters.0.detectors.1.pm", 0.95, r"federated\.subfilters\[0\]\.detectors\[1\].*pf \+ pm"),
        ("federated.subfilters.0.detectors.0.pf", 1.5, r"federated\.subfilters\[0\]\.detectors\[0\]\.pf = 1\.5"),
        ("federated.mode", "sometimes", r"federated\.mode = 'sometimes'"),
        ("trajectory.latitude", "90 deg", r"trajectory\.latitude"),
        ("ins.init_position", DELETE, r"ins\.init_position: missing"),
        ("sensors.0.colour", "red", r"sensors\[0\]: unknown field\(s\) colour"),
    ],
)
def test_errors_name_the_field(raw, path, value, message):
    bad = copy.deepcopy(raw)
    set_path(bad, path, value)
    with pytest.raises(navfdi.ScenarioError, match=message):
        navfdi.load_scenario(bad)


def test_files_and_names(tmp_path):
    with pytest.raises(navfdi.ScenarioError, match="neither a scenario file nor a bundled scenario"):
        navfdi.load_scenario("nope")
    with pytest.raises(navfdi.ScenarioError, match="no such scenario file"):
        navfdi.load_scenario(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("name = 'x'\nduration = [", encoding="utf-8")
    before = bad.read_text(encoding="utf-8")
    with pytest.raises(navfdi.ScenarioError, match="malformed TOML"):
        navfdi.load_scenario(bad)
    assert bad.read_text(encoding="utf-8") == before  # files are left as they were


def test_with_value_sweeps_a_field():
    sc = navfdi.load_scenario("yang2013")
    steeper = sc.with_value("faults[0].magnitude", "0.2 sigma/s")
    assert steeper.faults()[0]["magnitude"] == pytest.approx(2 * sc.faults()[0]["magnitude"])
    assert sc.faults()[0]["magnitude"] == pytest.approx(0.1 * math.radians(0.0017))  # original unchanged
    with pytest.raises(navfdi.ScenarioError, match=r"faults\[7\]\.magnitude: no such field"):
        sc.with_value("faults[7].magnitude", "1 sigma/s")
    with pytest.raises(navfdi.ScenarioError, match="needs a unit"):
        sc.with_value("ins.gyro_bias", 3)


def test_trajectory_follows_segments():
    sc = navfdi.load_scenario("yang2013")
    tr = _core.scenario_trajectory(sc.to_json())
    t = tr["t"]
    assert t.size == 1000
    assert np.allclose(tr["v"][:20], 0.0)  # at rest, heading north
    assert tr["h"][40] == pytest.approx(500.0, abs=1e-6) and tr["h"][140] == pytest.approx(1000.0, abs=1e-6)  # 100 s at 5 m/s
    assert math.degrees(tr["euler"][380, 2]) == pytest.approx(90.0, abs=1e-6)  # after the first 90° turn
    assert math.degrees(tr["euler"][700, 2]) == pytest.approx(0.0, abs=1e-6)  # turned back
    assert tr["euler"][330, 0] > 0.1  # banked in the turn
    assert math.degrees(tr["lat"][0]) == pytest.approx(20.0) and math.degrees(tr["lon"][0]) == pytest.approx(110.0)
    # Specific force at rest is gravity along body up.
    assert tr["f_b"][5, 2] == pytest.approx(9.786, abs=0.01)


def test_rust_fixture_matches_bundled_scenario():
    """benches/yang2013.json (used by the Rust tests and benches) is the bundled TOML in SI."""
    import json
    from pathlib import Path

    fixture = json.loads((Path(__file__).resolve().parents[1] / "benches" / "yang2013.json").read_text())
    assert fixture == navfdi.load_scenario("yang2013").core


def all_kinds_scenario():
    """Every sensor kind, every fault shape, outages, no-reset mode with isolation."""
    raw = copy.deepcopy(load_scenario("yang2013").base().raw)
    raw["duration"] = "400 s"
    raw["sensors"] = [
        {"name": "cns", "kind": "cns", "noise": "6 arcsec", "rate": "1 Hz"},
        {"name": "gpos", "kind": "gnss_position", "noise": ["3 m", "3 m", "5 m"], "rate": "1 Hz", "outages": [["100 s", "150 s"]]},
        {"name": "gvel", "kind": "gnss_velocity", "noise": "0.05 m/s", "rate": "0.5 Hz"},
        {"name": "baro", "kind": "baro", "noise": "2 m", "rate": "1 Hz"},
        {"name": "slam", "kind": "vision", "noise": "1 m", "rate": "1 Hz"},
    ]
    raw["faults"] = [
        {"id": "baro-quad", "sensor": "baro", "components": ["h"], "kind": "quadratic", "magnitude": "0.01 m/s2", "start": "200 s", "end": "300 s"},
        {"id": "slam-step", "sensor": "slam", "components": ["pos_e", "pos_n"], "kind": "step", "magnitude": "30 m", "start": "250 s", "end": "270 s"},
        {"id": "gvel-ramp", "sensor": "gvel", "components": "all", "kind": "ramp", "magnitude": "0.02 m/s/s", "start": "320 s", "end": "380 s"},
    ]
    chi2 = [{"name": "chi2", "kind": "chi2", "pf": 1e-4}]
    raw["federated"] = {
        "mode": "no_reset",
        "subfilters": [
            {"sensor": s["name"], "share": 0.2, "detectors": chi2, "isolation": "chi2"} for s in raw["sensors"]
        ],
    }
    return raw


def test_every_sensor_kind_fault_shape_and_outage_runs():
    raw = all_kinds_scenario()
    # A velocity ramp is in velocity per second; "0.02 m/s" reads as length per second.
    bad = copy.deepcopy(raw)
    bad["faults"][2]["magnitude"] = "0.02 m/s"
    with pytest.raises(navfdi.ScenarioError, match=r"faults\[2\]\.magnitude = '0\.02 m/s': unknown unit 'm' for velocity per second: a ramp on gvel's velocity component\(s\) takes m/s2"):
        navfdi.load_scenario(bad)
    sc = navfdi.load_scenario(raw)
    assert sc.faults()[0]["magnitude"] == pytest.approx(0.01)
    assert sc.faults()[2]["magnitude"] == pytest.approx(0.02)
    r = navfdi.run_scenario(sc, seed=4)
    t = r.t
    subs = {s["sensor"]: s for s in r.record["subfilters"]}
    # Outage: no GNSS position between 100 and 150 s (no statistic, no components).
    out = (t >= 100) & (t < 150)
    assert np.isnan(subs["gpos"]["statistic"][out]).all() and (subs["gpos"]["dof"][out] == 0).all()
    assert np.isfinite(subs["gpos"]["statistic"][~out]).all()
    # 0.5 Hz velocity: a measurement every other epoch.
    assert np.isnan(subs["gvel"]["statistic"][1::2]).all() and np.isfinite(subs["gvel"]["statistic"][0::2]).all()
    rows = {(m.fault_id, m.detector): m for m in r.fault_table()}
    # A 30 m step on a 1 m vision sensor is found at once; the quadratic barometer fault within
    # its window; the velocity ramp within its window.
    assert rows[("slam-step", "chi2")].delay == 0
    assert rows[("baro-quad", "chi2")].detected_at is not None
    assert rows[("gvel-ramp", "chi2")].detected_at is not None
    # Isolation of the faulty sub-filters during their faults.
    iso = r.isolated("slam")
    assert iso[(t >= 251) & (t < 270)].all()
    # No-reset fusion keeps a solution; the horizontal error stays far below the vision fault.
    assert np.abs(r.error()[260, 6:8]).max() < 10.0


from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

_junk = st.one_of(st.none(), st.booleans(), st.integers(-5, 5), st.floats(allow_nan=True), st.text(max_size=8), st.lists(st.integers(), max_size=2), st.dictionaries(st.text(max_size=3), st.integers(), max_size=2))


def _paths(obj, prefix=()):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield (*prefix, k)
            yield from _paths(v, (*prefix, k))
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield (*prefix, i)
            yield from _paths(v, (*prefix, i))


_PATHS = list(_paths(load_scenario("yang2013").raw))


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(path=st.sampled_from(_PATHS), junk=_junk, drop=st.booleans())
def test_malformed_scenarios_raise_scenario_error_only(path, junk, drop):
    """Any field replaced by junk (or removed) gives a ScenarioError or a valid scenario,
    never another exception."""
    raw = copy.deepcopy(load_scenario("yang2013").raw)
    d = raw
    for p in path[:-1]:
        d = d[p]
    if drop and isinstance(d, dict):
        del d[path[-1]]
    else:
        d[path[-1]] = junk
    try:
        sc = navfdi.load_scenario(raw)
    except navfdi.ScenarioError as e:
        assert str(e)
    else:
        assert sc.to_json()
