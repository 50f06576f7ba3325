"""A user's own IMU + GNSS log: GPS-time windows, duration and dt from the log, a reference on
the input epochs scored (and labelled), a GPS-time column, and exported bundled scenarios that
run from where they are written."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi._logtime import gps_seconds
from navfdi.scenario import ScenarioError, from_dict, load_scenario
from navfdi.simlog import START, simulate_log


@pytest.fixture(scope="module")
def log(tmp_path_factory: pytest.TempPathFactory):
    return simulate_log(tmp_path_factory.mktemp("own"), duration=300, seed=4, gnss_rate=1.0)


def _raw(log) -> dict:
    return dict(load_scenario(str(log.scenario)).raw)


def test_gps_time_forms() -> None:
    assert gps_seconds("2374:243500.5", "f") == 2374 * 604800.0 + 243500.5
    # 2017 onwards GPS = UTC + 18 s.
    assert gps_seconds("2025-07-08T00:00:00 UTC", "f") - gps_seconds("2025-07-08T00:00:00 GPST", "f") == 18.0
    assert gps_seconds("440 s", "f") is None
    with pytest.raises(ScenarioError, match="WEEK:SECONDS"):
        gps_seconds("2374:", "f")
    with pytest.raises(ScenarioError, match="below 604800"):
        gps_seconds("2374:700000", "f")


def test_windows_in_gps_time_and_duration_from_the_log(log) -> None:
    """Faults in GPS week:seconds and ISO GPST land where seconds from the first epoch do;
    duration and dt come from the GNSS log when omitted."""
    week, sow0 = START
    raw = _raw(log)
    given = load_scenario(str(log.scenario)).core
    del raw["duration"], raw["dt"]
    rel = {"id": "f", "sensor": "gnss_pos", "components": ["pos_n"], "kind": "step", "magnitude": "20 m", "start": "150 s", "end": "200 s"}
    gps = {**rel, "start": f"{week}:{sow0 + 150}", "end": f"{week}:{sow0 + 200.0}"}
    sc = from_dict({**raw, "faults": [gps]}, source=str(log.scenario))
    assert sc.core["duration"] == pytest.approx(given["duration"]) and sc.core["dt"] == pytest.approx(1.0)
    assert (sc.faults()[0]["start"], sc.faults()[0]["end"]) == (150.0, 200.0)
    ref = from_dict({**raw, "faults": [rel]}, source=str(log.scenario))
    assert sc.core == ref.core
    # The user's table keeps what they wrote.
    assert sc.raw["faults"][0]["start"] == gps["start"] and "duration" not in sc.raw
    # A GPS time outside the log is named.
    bad = {**gps, "start": f"{week - 1}:{sow0}"}
    with pytest.raises(ScenarioError, match=r"faults\[0\].start: GPS time .* not this log's time"):
        from_dict({**raw, "faults": [bad]}, source=str(log.scenario))


def test_reference_on_the_input_epochs_is_scored_and_labelled(log) -> None:
    """The simulator's reference shares the 1 Hz input epochs: scored after the update, said
    so; held_out refuses to score them (no reason-less nan: the console says why)."""
    run = navfdi.run_scenario(str(log.scenario)).runs["fde"]
    e = run.errors()
    assert e["scored"] > 200 and np.isfinite(e["hor_rms"])
    assert run.scored_at == "inputs"
    assert "after their update" in run.format_tables()
    raw = _raw(log)
    raw["source"] = {**raw["source"], "reference_epochs": "held_out"}
    held = navfdi.run_scenario(from_dict(raw, source=str(log.scenario))).runs["fde"]
    assert held.errors()["scored"] == 0
    assert "no reference epoch scored" in held.format_tables()
    raw["source"]["reference_epochs"] = "everything"
    with pytest.raises(ScenarioError, match="reference_epochs"):
        navfdi.run_scenario(from_dict(raw, source=str(log.scenario)))


def test_timeseries_has_gps_time(log) -> None:
    run = navfdi.run_scenario(str(log.scenario)).runs["fde"]
    ts = run.timeseries()
    week, sow0 = START
    assert (ts["gps_week"] == week).all()
    np.testing.assert_allclose(ts["gps_sow"] - ts["t"], sow0, atol=1e-6)


def test_exported_scenario_runs_from_where_it_is_written(tmp_path: Path) -> None:
    out = tmp_path / "sub" / "my.toml"
    out.parent.mkdir()
    subprocess.run([sys.executable, "-m", "navfdi", "scenarios", "--export", "drive_lc", str(out)], check=True, capture_output=True)
    sc = load_scenario(out)
    assert Path(sc.raw["source"]["gnss"]).is_absolute()
    run = navfdi.run_scenario(sc)
    assert run.runs["fde"].errors()["hor_rms"] < 0.1


def test_noise_in_datasheet_units() -> None:
    """Angle and velocity random walk as datasheets give them (deg/√h, m/s/√h), biases in
    deg/h and mg, beside the SI densities."""
    from navfdi.units import parse

    assert parse("0.15 deg/sqrt(h)", "angular_rate_density", "x") == pytest.approx(np.radians(0.15) / 60)
    assert parse("0.06 m/s/sqrt(h)", "acceleration_density", "x") == pytest.approx(0.001)
    assert parse("10 deg/h", "angular_rate", "x") == pytest.approx(np.radians(10) / 3600)
    assert parse("2 mg", "acceleration", "x") == pytest.approx(2e-3 * 9.80665)
