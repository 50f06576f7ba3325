"""Logs whose time lines disagree by seconds (a GNSS log in UTC read as GPS time: 18 s) are
refused before the run with the lag found, instead of running to hundreds of metres of error;
logs that agree, a real IMU offset set in the scenario, and logs without turns pass."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi.frames import check_turns
from navfdi.logs import read_pos
from navfdi.scenario import ScenarioError, from_dict, load_scenario
from navfdi.simlog import CAR_DRIVE, simulate_log


def _shifted(folder: Path, shift: float, velocity: bool = True) -> Path:
    """A simulated car drive whose IMU time stamps are `shift` s early (the GNSS's, and the
    reference's, `shift` s later than the IMU's)."""
    log = simulate_log(folder, duration=600, seed=2, gnss_sigma=2.0, gnss_tau=30.0, gnss_white=0.3, gnss_velocity=velocity)
    lines = log.imu.read_text(encoding="utf-8").splitlines()
    out = [lines[0]]
    for ln in lines[1:]:
        f = ln.split(",")
        f[1] = f"{float(f[1]) - shift:.6f}"
        out.append(",".join(f))
    log.imu.write_text("\n".join(out) + "\n", encoding="utf-8")
    return log.scenario


@pytest.mark.parametrize("velocity", [True, False])
def test_a_gnss_log_in_utc_is_refused_with_the_leap_seconds_named(tmp_path: Path, velocity: bool) -> None:
    path = _shifted(tmp_path, 18.0, velocity)
    with pytest.raises(ScenarioError, match=r"stamped 18\.\d s later in the GNSS log.*GPS − UTC.*imu_time_offset = \"\+18\.\d s\""):
        navfdi.run_scenario(load_scenario(str(path)))


def test_a_few_seconds_are_refused_and_the_offset_set_in_the_scenario_runs(tmp_path: Path) -> None:
    """3 s late GNSS stamps: refused, the message giving the offset; with that offset set
    (the IMU's clock taken as 3 s behind) the run is as accurate as the unshifted log's."""
    path = _shifted(tmp_path / "a", 3.0)
    with pytest.raises(ScenarioError, match=r"stamped 3\.\d s later in the GNSS log.*imu_time_offset = \"\+3\.\d s\""):
        navfdi.run_scenario(load_scenario(str(path)))
    raw = dict(load_scenario(str(path)).raw)
    raw["loosely_coupled"] = {**raw["loosely_coupled"], "imu_time_offset": "3 s"}
    e = navfdi.run_scenario(from_dict(raw, source=str(path))).runs["fde"].errors()
    ok = navfdi.run_scenario(load_scenario(str(_shifted(tmp_path / "b", 0.0)))).runs["fde"].errors()
    assert e["hor_rms"] < 1.5 * ok["hor_rms"] + 0.2, (e, ok)


def test_logs_in_line_or_without_turns_pass(tmp_path: Path) -> None:
    """The check says nothing where it cannot tell: a drive's logs in line (within a receiver
    latency), and a straight drive with the GNSS shifted by 18 s (no turns to line up)."""
    log = simulate_log(tmp_path / "a", duration=300, seed=2, gnss_sigma=1.0)
    imu = np.loadtxt(log.imu, delimiter=",", skiprows=1)
    gnss = read_pos(log.gnss)
    # GPS seconds, as the GNSS log's (week and seconds of week: the seconds alone never overlap
    # it, and the check had nothing to say).
    t_imu = imu[:, 0] * 604_800.0 + imu[:, 1]
    check_turns(t_imu + 0.3, np.radians(imu[:, 2:5]), gnss, 0.0, "loosely_coupled")
    with pytest.raises(ScenarioError, match="stamped 18"):
        check_turns(t_imu - 18.0, np.radians(imu[:, 2:5]), gnss, 0.0, "loosely_coupled")
    straight = {**{k: v for k, v in CAR_DRIVE.items() if k != "segments"}, "speed": "15 m/s", "segments": [{"duration": "300 s", "kind": "level"}]}
    log2 = simulate_log(tmp_path / "b", duration=300, seed=2, gnss_sigma=1.0, trajectory=straight)
    imu2 = np.loadtxt(log2.imu, delimiter=",", skiprows=1)
    check_turns(imu2[:, 0] * 604_800.0 + imu2[:, 1] - 18.0, np.radians(imu2[:, 2:5]), read_pos(log2.gnss), 0.0, "loosely_coupled")


@pytest.mark.parametrize(("unit", "factor"), [("rad/s", "180/π"), ("deg/s", "π/180")])
def test_a_gyro_unit_read_wrong_is_refused_by_the_size_of_the_turns(tmp_path: Path, unit: str, factor: str) -> None:
    """Gyro columns in deg/s declared rad/s (the turns 57x the course's), or in rad/s declared
    deg/s (a 57th): refused before the run naming the unit; before, the first ran to 32 m of
    horizontal RMS with no message."""
    log = simulate_log(tmp_path, duration=300, seed=1, gnss_sigma=2.0, gnss_tau=30.0, gnss_white=0.3)
    raw = dict(load_scenario(str(log.scenario)).raw)
    if unit == "deg/s":
        # Rewrite the file's rates in rad/s, keeping the scenario's "deg/s".
        lines = log.imu.read_text(encoding="utf-8").splitlines()
        out = [lines[0]]
        for ln in lines[1:]:
            f = ln.split(",")
            f[2:5] = [f"{float(v) * np.pi / 180.0:.9f}" for v in f[2:5]]
            out.append(",".join(f))
        log.imu.write_text("\n".join(out) + "\n", encoding="utf-8")
    else:
        raw["source"] = {**raw["source"], "imu": {**raw["source"]["imu"], "gyro_unit": unit}}
    with pytest.raises(ScenarioError, match=rf"rotation rate is .* times the GNSS course's rate.*{factor} is in that range.*gyro_unit = \"{'deg/s' if unit == 'rad/s' else 'rad/s'}\""):
        navfdi.run_scenario(from_dict(raw, source=str(log.scenario)))


def test_a_short_log_with_one_turn_lines_up_or_says_nothing(tmp_path: Path) -> None:
    """Two minutes with one turn: on meter-level positions alone (σ 2 m, course rate noise of
    several deg/s) that turn lined up with noise 29-30 s away better than with itself
    (correlation 0.48-0.54 against 0.10-0.21), and a log in line was refused for a 30 s lag.
    One turn now says a lag only where the correlation is clear (≥ 0.7), as the receiver's
    velocities make it: an 18 s shift there is still refused."""
    kw = {"duration": 120, "seed": 11, "gnss_rate": 1.0, "gnss_sigma": 2.0, "gnss_tau": 30.0, "gnss_white": 0.5,
          "gnss_velocity_sigma": 0.1, "stale_rate": 1 / 120, "stale_duration": 4.0}
    log = simulate_log(tmp_path / "a", gnss_velocity=False, **kw)
    imu = np.loadtxt(log.imu, delimiter=",", skiprows=1)
    t_imu = imu[:, 0] * 604_800.0 + imu[:, 1]
    check_turns(t_imu, np.radians(imu[:, 2:5]), read_pos(log.gnss), 0.0, "loosely_coupled")
    log2 = simulate_log(tmp_path / "b", gnss_velocity=True, **kw)
    imu2 = np.loadtxt(log2.imu, delimiter=",", skiprows=1)
    t2 = imu2[:, 0] * 604_800.0 + imu2[:, 1]
    with pytest.raises(ScenarioError, match=r"stamped 18\.\d s later in the GNSS log"):
        check_turns(t2 - 18.0, np.radians(imu2[:, 2:5]), read_pos(log2.gnss), 0.0, "loosely_coupled")


def test_a_log_without_turns_says_nothing_on_a_noisy_course(tmp_path: Path) -> None:
    """75 s of driving with no turn (the drive's first turn is at 78 s), σ 2 m positions alone:
    the course's rate from them has several deg/s of noise, which passed for turns, and the
    IMU's quiet rate at 0.001-0.005 of it was refused as a gyro unit read wrong. The IMU turns
    at no point: the check now says nothing there."""
    log = simulate_log(tmp_path, duration=75, seed=1, gnss_rate=1.0, gnss_sigma=2.0, gnss_tau=30.0, gnss_white=0.5,
                       gnss_velocity_sigma=0.1, gnss_velocity=False)
    imu = np.loadtxt(log.imu, delimiter=",", skiprows=1)
    check_turns(imu[:, 0] * 604_800.0 + imu[:, 1], np.radians(imu[:, 2:5]), read_pos(log.gnss), 0.0, "loosely_coupled")


def test_a_burst_lined_up_with_a_turn_by_chance_is_not_a_lag(tmp_path: Path) -> None:
    """200 s of positions alone at 5 Hz, σ 3 m white with 15 m multipath bursts (found by
    random set-ups): the course from such fixes is mostly noise (its rate's σ 38 deg/s), and a
    burst lined up with a turn 32 s away at a correlation of 0.40 (none at 0 s): the log in
    line was refused for a 32 s lag. Over 89 independent 2 s windows a chance correlation has
    σ 0.11: a lag is now said from 5 of them (0.53) — and the same check still finds 3 and
    18 s shifts on the 60 random set-ups it found them on before."""
    log = simulate_log(tmp_path, duration=200, seed=8, gnss_rate=5.0, imu_rate=200.0, gnss_sigma=3.0, gnss_white=0.5,
                       gnss_velocity=False, burst_rate=1 / 60, burst_size=15.0, burst_duration=8.0, stale_rate=1 / 120,
                       stale_duration=4.0, imu_axes=("right", "forward", "up"))
    imu = np.loadtxt(log.imu, delimiter=",", skiprows=1)
    check_turns(imu[:, 0] * 604_800.0 + imu[:, 1], np.radians(imu[:, 2:5]), read_pos(log.gnss), 0.0, "loosely_coupled")


def test_stale_fixes_caught_up_are_no_turn(tmp_path: Path) -> None:
    """100 s of positions alone at 1 Hz (σ 1 m, τ 10 s, 15 m bursts) ending in 4 s of
    repeated fixes (found by random set-ups): differenced across the repeats, the catch-up
    read as 29–35 m/s turning at 60 deg/s, two epochs that lined up with the log's one turn
    15.5 s away at a correlation of 0.94 (0.10 at none), and the log in line was refused for
    a 15.5 s lag. A repeated fix is now no end of a difference: the log passes."""
    log = simulate_log(tmp_path, duration=100, seed=8, gnss_rate=1.0, imu_rate=100.0, gnss_sigma=1.0, gnss_tau=10.0,
                       gnss_white=0.5, burst_rate=1 / 60, burst_size=15.0, burst_duration=8.0, stale_rate=1 / 120,
                       stale_duration=4.0, imu_axes=("right", "forward", "up"), gnss_velocity=False)
    gnss = read_pos(log.gnss)
    assert np.sum((np.diff(gnss.lat) == 0) & (np.diff(gnss.lon) == 0)) >= 3
    imu = np.loadtxt(log.imu, delimiter=",", skiprows=1)
    t_imu = imu[:, 0] * 604_800.0 + imu[:, 1]
    check_turns(t_imu, np.radians(imu[:, 2:5]), gnss, 0.0, "loosely_coupled")
