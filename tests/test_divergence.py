"""An INS that runs away from the fixes it holds out is moved back onto them.

Simulated logs of meter-level positions only (σ 2 m Gauss-Markov, 30 m multipath bursts of 8 s
once a minute, stale spells; the log's own set-up): where a burst came just after the
alignment, its first fixes went into a filter that had not settled, the INS left the fixes at
15-17 m/s, and the hold kept the good fixes out against it — kilometres of error where the
filter without FDE stayed within tens of metres. Now an INS whose distance to the held fixes
grows faster than 3 m/s in each third of 10 s is moved back onto them (said in the
console)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import navfdi
from navfdi.consistency import consistency, format_consistency
from loglib import horizontal_error


@pytest.fixture()
def burst_log(tmp_path: Path, docs_script: Callable[[str], ModuleType]) -> Callable[[int], navfdi.VariantRuns]:
    """A positions-only log with 30 m bursts, run with and without FDE (the generator of
    docs/meter_fde.md's table)."""
    make = docs_script("runaway_sweep").burst_log_run
    return lambda seed: make(tmp_path / f"log{seed}", seed, False, 30.0)


def _rms(run: navfdi.ScenarioRun) -> float:
    return float(np.sqrt(np.nanmean(horizontal_error(run) ** 2)))


@pytest.mark.parametrize(("seed", "before"), [(4, 5784.0), (11, 2877.0)])
def test_an_ins_running_from_held_fixes_is_brought_back(burst_log: Callable[[int], navfdi.VariantRuns], seed: int, before: float) -> None:
    r = burst_log(seed)
    fde, no_fde = _rms(r.runs["fde"]), _rms(r.runs["no_fde"])
    # Kilometres before; now tens of metres, as the filter without FDE (which absorbs every
    # burst): better than it on seed 4 (17 against 67 m), not on seed 11 (86 against 18 m:
    # a slower drift, below the rate, held as a ramp; docs/meter_fde.md).
    assert fde < 0.05 * before, (fde, no_fde)
    if seed == 4:
        assert fde <= no_fde, (fde, no_fde)


def test_the_rtk_set_up_on_positions_only_no_longer_runs_away(tmp_path: Path) -> None:
    """docs/meter_fde.md's seed 6 with bursts under drive_lc's settings: a ramp held after a
    step, an INS velocity already off, 301 m RMS fault-free (94 m after the held ramp's line,
    no FDE 9.8 m); then 10.9 m, the INS moved back onto the held fixes instead of coasting
    away. Since the alignment's static start is checked by the IMU and the velocities'
    mean (the "rest" had run into the drive on these 2 m fixes), the INS starts right and is
    not moved at all (10.6 m, no FDE 10.5 m); the moving back is tested on other logs here."""
    from test_positions_only import _rtk_set_up_on

    r = _rtk_set_up_on(tmp_path / "log", 6, 15.0)
    rms = {v: _rms(x) for v, x in r.runs.items()}
    assert rms["fde"] <= 1.5 * rms["no_fde"] and rms["fde"] < 20.0, rms


def test_the_console_says_when_the_ins_was_moved_back(burst_log: Callable[[int], navfdi.VariantRuns]) -> None:
    r = burst_log(4)
    c = consistency(r.runs["fde"])
    assert c["reanchored"] and all(40.0 < t < 600.0 for t in c["reanchored"])
    assert "the INS ran away from (or stayed off) the fixes it held out and was moved back onto them" in "\n".join(format_consistency(c))
    ev = r.runs["fde"].events()
    moved = ev[ev["detector"] == "reanchored"]
    assert list(moved["alarm_start"]) == c["reanchored"] and (moved["subfilter"] == "navigation").all()
    # Without FDE nothing is held, so nothing is moved.
    assert consistency(r.runs["no_fde"])["reanchored"] == []
    assert not (r.runs["no_fde"].events()["detector"] == "reanchored").any()
