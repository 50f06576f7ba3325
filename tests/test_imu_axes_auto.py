"""``[loosely_coupled] imu_axes = "auto"``: where the IMU's x, y, z point, from the log alone
(gravity for up; the accelerations along and across the GNSS track for forward and right:
:func:`navfdi.frames.estimate_imu_axes`), on simulated drives with IMUs mounted every way and
on the bundled real drives against their own (independently given) mountings."""

from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import ScenarioError, logs
from navfdi._lc_schema import _AXES, _rot
from navfdi.calibrate import calibrate, write_calibrated
from navfdi.frames import estimate_imu_axes
from navfdi.scenario import load_scenario
from navfdi.simlog import simulate_log


def _data(scenario):
    sc = load_scenario(scenario) if isinstance(scenario, (str, Path)) else scenario
    return logs.load_source(sc.raw["source"], logs.scenario_folder(sc))


@pytest.mark.parametrize("axes", [("forward", "right", "down"), ("right", "forward", "up"), ("back", "left", "down"), ("down", "right", "back"),
                                  ("up", "back", "right")])
def test_simulated_mountings_are_told(tmp_path: Path, axes):
    log = simulate_log(tmp_path, duration=240, seed=3, imu_axes=axes, boresight_deg=(1.0, -2.0, 3.0), gnss_rate=1.0, gnss_sigma=1.0)
    d = _data(log.scenario)
    found, fit, nxt = estimate_imu_axes(d["imu_log"].t, d["imu_log"].accel, d["gnss_log"])
    assert tuple(found) == axes and fit > 1.8 and nxt < 0.5


@pytest.mark.parametrize("axes", [("right", "forward", "up"), ("down", "right", "back")])
def test_meter_level_positions_alone_tell_them_too(tmp_path: Path, axes):
    """No receiver velocities, fixes with 2 m Gauss-Markov errors, white noise and multipath
    bursts: the accelerations from the positions (over 6 s) still tell the axes."""
    log = simulate_log(tmp_path, duration=600, seed=4, imu_axes=axes, gnss_rate=1.0, gnss_sigma=2.0, gnss_tau=30.0, gnss_white=1.0,
                       gnss_velocity=False, burst_rate=0.01, burst_size=15.0, burst_duration=10.0)
    d = _data(log.scenario)
    found, fit, nxt = estimate_imu_axes(d["imu_log"].t, d["imu_log"].accel, d["gnss_log"])
    assert tuple(found) == axes and fit > 1.5 and nxt < 0.5


def _nearest_axes(mounting_deg):
    c = _rot(*[math.radians(x) for x in mounting_deg]).T  # columns: the IMU's axes in the body
    return [max(_AXES, key=lambda n: float(np.dot(_AXES[n], c[:, a]))) for a in range(3)]


def test_the_bundled_drives_are_told_as_their_mountings_say():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        drive, comma = _data("drive_lc"), _data("comma_lc")
    # drive_lc is given as mounting angles (179.71, −6.60, 185.35 deg): the nearest axes.
    found = estimate_imu_axes(drive["imu_log"].t, drive["imu_log"].accel, drive["gnss_log"])[0]
    assert found == _nearest_axes((179.71, -6.60, 185.35)) == ["back", "right", "up"]
    assert estimate_imu_axes(comma["imu_log"].t, comma["imu_log"].accel, comma["gnss_log"])[0] == \
        list(load_scenario("comma_lc").raw["loosely_coupled"]["imu_axes"])


def test_a_scenario_with_auto_axes_runs_as_with_the_true_ones(tmp_path: Path):
    log = simulate_log(tmp_path, duration=240, seed=2, imu_axes=("right", "forward", "up"), gnss_rate=1.0, gnss_sigma=1.0)
    text = re.sub(r"mounting = \[.*?\]", 'imu_axes = "auto"', Path(log.scenario).read_text())
    auto = tmp_path / "auto.toml"
    auto.write_text(text)
    a, b = navfdi.run_scenario(str(auto)), navfdi.run_scenario(str(log.scenario))
    assert a.runs["fde"].errors() == b.runs["fde"].errors()
    cal = calibrate(load_scenario(str(auto)), ["imu_axes"])
    assert cal.imu_axes == ["right", "forward", "up"]
    assert any(ln.startswith("IMU axes (x, y, z): right, forward, up") for ln in cal.lines())
    out = write_calibrated(auto, cal, tmp_path / "calibrated.toml")
    assert 'imu_axes = ["right", "forward", "up"]   # navfdi calibrate' in out.read_text()


def test_logs_that_do_not_say_are_refused(tmp_path: Path):
    still = {"latitude": "40 deg", "longitude": "-105 deg", "height": "1600 m", "heading": "0 deg", "speed": "0 m/s",
             "segments": [{"kind": "stationary", "duration": "120 s"}]}
    log = simulate_log(tmp_path / "still", duration=120, seed=1, trajectory=still, gnss_rate=1.0)
    d = _data(log.scenario)
    with pytest.raises(ScenarioError, match=r"imu_axes = \"auto\": .* fewer than 30 GNSS epochs above 3 m/s"):
        estimate_imu_axes(d["imu_log"].t, d["imu_log"].accel, d["gnss_log"])
    tilted = simulate_log(tmp_path / "tilted", duration=240, seed=1, boresight_deg=(45.0, 0.0, 0.0), gnss_rate=1.0)
    d = _data(tilted.scenario)
    with pytest.raises(ScenarioError, match=r"more than 30° from every axis"):
        estimate_imu_axes(d["imu_log"].t, d["imu_log"].accel, d["gnss_log"])


def test_a_word_that_is_not_auto_is_named(tmp_path: Path):
    log = simulate_log(tmp_path, duration=60, seed=1, gnss_rate=1.0)
    text = re.sub(r"mounting = \[.*?\]", 'imu_axes = "sideways"', Path(log.scenario).read_text())
    (tmp_path / "s.toml").write_text(text)
    with pytest.raises(ScenarioError, match=r"imu_axes = 'sideways': three of forward, back, .* or \"auto\""):
        load_scenario(str(tmp_path / "s.toml"))
