"""``[loosely_coupled] position_correlation``: fixes whose errors are time-correlated
(Gauss-Markov, correlation time τ) weighted in the update as the independent fixes they are
worth, on a simulated meter-level drive with known truth (σ 2 m, τ 30 s, receiver velocities)."""

from __future__ import annotations

from functools import cache
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi.scenario import from_dict, load_scenario
from navfdi.simlog import simulate_log

from loglib import horizontal_error

RAMP = [{"id": "f", "sensor": "gnss_pos", "components": ["pos_n"], "kind": "ramp", "magnitude": "0.45 m/s", "start": "300 s", "end": "340 s"}]


@cache
def _scenario(folder: str) -> navfdi.Scenario:
    path = simulate_log(folder, duration=600, seed=1, gnss_sigma=2.0, gnss_tau=30.0, gnss_white=0.3, gnss_velocity_sigma=0.1).scenario
    return load_scenario(str(path))


def _run(folder: Path, tau: str | None, faults: list[dict] | None = None) -> navfdi.ScenarioRun:
    base = _scenario(str(folder))
    raw = dict(base.raw)
    raw.pop("faults", None)
    if faults:
        raw["faults"] = faults
    if tau is not None:
        raw["loosely_coupled"] = {**raw["loosely_coupled"], "position_correlation": tau}
    return navfdi.run_scenario(from_dict(raw, source=base.source))


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("corr")


def test_zero_is_the_white_filter(folder: Path) -> None:
    a, b = _run(folder, None), _run(folder, "0 s")
    for v in ("fde", "no_fde"):
        np.testing.assert_array_equal(a.runs[v].record["error"], b.runs[v].record["error"])


def test_a_slow_ramp_the_tests_cannot_see_pulls_the_filter_less(folder: Path) -> None:
    """A 0.45 m/s north ramp over 40 s, too slow for the tests at σ 2 m: the filter that takes
    the fixes as white follows it (about 10 m); weighted for their 30 s correlation, the
    receiver's velocities hold the INS and the error stays near the fault-free run's. The
    fault-free run is no worse either (the σ 2 m errors are averaged over their correlation
    time, not followed)."""
    t = _run(folder, None).runs["fde"].t
    win = (t >= 300.0) & (t < 400.0)
    white, corr = _run(folder, None, RAMP), _run(folder, "30 s", RAMP)
    clean_white, clean_corr = _run(folder, None), _run(folder, "30 s")
    peak = lambda r: float(np.nanmax(horizontal_error(r.runs["fde"])[win]))  # noqa: E731
    rms = lambda r: float(np.sqrt(np.nanmean(horizontal_error(r.runs["fde"]) ** 2)))  # noqa: E731
    assert peak(white) > 2.0 * peak(clean_white), (peak(white), peak(clean_white))  # the ramp is followed
    assert peak(corr) < 0.5 * peak(white), (peak(corr), peak(white))
    assert peak(corr) < 1.5 * float(np.nanmax(horizontal_error(clean_corr.runs["fde"]))), peak(corr)
    assert rms(clean_corr) <= rms(clean_white), (rms(clean_corr), rms(clean_white))


@pytest.mark.parametrize("value, match", [("-1 s", r"position_correlation.*\[0, 1e5\]"), ("2 m", "position_correlation"),
                                          ("1e6 s", r"position_correlation.*\[0, 1e5\]")])
def test_the_correlation_time_is_checked(folder: Path, value: str, match: str) -> None:
    with pytest.raises(ValueError, match=match):
        _run(folder, value)


def test_positions_only_logs_refuse_it(tmp_path: Path) -> None:
    """Without the receiver's velocities the weighting lets the INS drift (measured: 10-20 m
    steps left out at their first fix in 80 % of runs instead of all): refused, naming why."""
    path = simulate_log(str(tmp_path), duration=120, seed=2, gnss_sigma=2.0, gnss_tau=30.0, gnss_velocity=False).scenario
    base = load_scenario(str(path))
    raw = dict(base.raw)
    raw["loosely_coupled"] = {**raw["loosely_coupled"], "position_correlation": "30 s"}
    with pytest.raises(ValueError, match="needs the receiver's velocities"):
        navfdi.run_scenario(from_dict(raw, source=base.source))


def test_auto_reads_the_correlation_from_the_log_and_holds_the_ramp(folder: Path) -> None:
    """``"auto"``: the errors' white and correlated parts and τ read from the fixes against the
    receiver's velocities (simulated: white 0.3 m, Gauss-Markov σ 2 m, τ 30 s) — within a
    factor 2 of τ and 1.5 of σ — and the slow ramp is held as with τ given."""
    clean = _run(folder, "auto")
    white, gm, tau, weight = clean.runs["fde"].record["position_errors"]
    assert 15.0 <= tau <= 60.0, tau
    assert 2.0 / 1.5 <= gm <= 2.0 * 1.5, gm
    assert white < gm, (white, gm)
    assert weight > 10.0, weight
    t = clean.runs["fde"].t
    win = (t >= 300.0) & (t < 400.0)
    peak = lambda r: float(np.nanmax(horizontal_error(r.runs["fde"])[win]))  # noqa: E731
    assert peak(_run(folder, "auto", RAMP)) < 0.5 * peak(_run(folder, None, RAMP))
    # What it read is said in the consistency report.
    from navfdi.consistency import consistency, format_consistency

    lines = format_consistency(consistency(clean.runs["fde"]))
    assert any(f"τ {tau:.1f} s" in ln for ln in lines), lines


def test_auto_leaves_white_fixes_and_positions_alone_white(tmp_path: Path) -> None:
    """White fixes (σ 1.5 m, no wander) read as white: the run is the white filter's to the bit.
    On positions alone nothing can be read (no velocities): white, said so, not refused."""
    path = simulate_log(str(tmp_path / "w"), duration=400, seed=3, gnss_sigma=0.0, gnss_tau=0.0, gnss_white=1.5).scenario
    base = load_scenario(str(path))
    auto = dict(base.raw)
    auto["loosely_coupled"] = {**auto["loosely_coupled"], "position_correlation": "auto"}
    a, w = navfdi.run_scenario(from_dict(auto, source=base.source)), navfdi.run_scenario(base)
    assert a.runs["fde"].record["position_errors"][1:] == [0.0, 0.0, 1.0]
    np.testing.assert_array_equal(a.runs["fde"].record["error"], w.runs["fde"].record["error"])
    path = simulate_log(str(tmp_path / "p"), duration=120, seed=2, gnss_sigma=2.0, gnss_tau=30.0, gnss_velocity=False).scenario
    base = load_scenario(str(path))
    raw = dict(base.raw)
    raw["loosely_coupled"] = {**raw["loosely_coupled"], "position_correlation": "auto"}
    rec = navfdi.run_scenario(from_dict(raw, source=base.source)).runs["fde"].record
    assert np.isnan(rec["position_errors"][:3]).all() and rec["position_errors"][3] == 1.0


def test_white_fixes_that_wander_get_auto_suggested(folder: Path) -> None:
    """Taken as white (the default), fixes that the log shows wandering against the receiver's
    velocities are reported with what ``"auto"`` would do, and the console suggests it; the
    run itself is the white filter's."""
    from navfdi.consistency import consistency, format_consistency

    white, auto = _run(folder, None), _run(folder, "auto")
    rec = white.runs["fde"].record
    assert "position_errors" not in rec
    np.testing.assert_array_equal(rec["position_wander"], auto.runs["fde"].record["position_errors"])
    lines = format_consistency(consistency(white.runs["fde"]))
    assert any('position_correlation = "auto" would weight' in ln for ln in lines), lines
    assert "position_wander" not in auto.runs["fde"].record
