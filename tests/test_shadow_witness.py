"""A receiver of positions alone at meter level (σ 1 m Gauss-Markov, 1 Hz): the INS follows a
slow ramp through its own velocity, and where the ramp ends the fixes jump back across it (the
picture of a step's onset) — held as a step for the rest of the log, or taken in and then held
as a ramp while the INS drifted on (20–55 m off for minutes). A copy of the filter carried on
the IMU and the vehicle's constraints alone since before the hold began is the witness
(``arch/loosely_coupled/shadow.rs``): the fix on it and the INS off it, the INS is moved onto
the fix. A step's onset takes the fix off the copy, so steps stay held from their first fix to
their last."""

from __future__ import annotations

import copy
from functools import cache
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi.scenario import from_dict, load_scenario
from navfdi.simlog import simulate_log

from loglib import horizontal_error


@cache
def _log(folder: str) -> Path:
    return simulate_log(folder, duration=600, seed=2, gnss_rate=1.0, gnss_sigma=1.0, gnss_tau=30.0,
                        gnss_white=0.3, gnss_velocity_sigma=0.1, gnss_velocity=False).scenario


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("shadow")


def _run(folder: Path, fault: dict) -> navfdi.ScenarioRun:
    path = _log(str(folder))
    raw = copy.deepcopy(dict(load_scenario(str(path)).raw))
    for s in raw["sensors"]:
        s["rate"] = "1 Hz"
    raw["faults"] = [fault]
    return navfdi.run_scenario(from_dict(raw, source=str(path)))


def _fault(kind: str, comp: str, size: str, start: float, end: float) -> dict:
    return {"id": "f", "sensor": "gnss_pos", "components": [comp], "kind": kind, "magnitude": size,
            "start": f"{start} s", "end": f"{end} s"}


@pytest.mark.parametrize("start, comp", [(160.0, "pos_n"), (366.0, "pos_e"), (400.0, "pos_n")])
def test_a_followed_ramps_end_moves_the_ins_back_onto_the_fixes(folder: Path, start: float, comp: str) -> None:
    """0.5 m/s over 40 s: before the witness, 20.2 / 34.6 / 23.7 m 20–60 s after the end
    (without FDE 5.2 / 2.2 / 4.4 m); now the INS is moved within 10 s of the end and the error
    after it is no worse than without FDE's by more than 2 m. Not every end is released: where
    no two copies are sharp enough the hold stays (on this log the same ramps from 120 s east
    and 170 s north; the sweep's shares are in docs/meter_fde.md)."""
    end = start + 40.0
    runs = _run(folder, _fault("ramp", comp, "0.5 m/s", start, end)).runs
    x, y = runs["fde"], runs["no_fde"]
    moved = [t for t in x.record.get("reanchored", []) if start <= t <= end + 10.0]
    assert moved, x.record.get("reanchored")
    after = (x.t >= end + 20.0) & (x.t <= end + 60.0)
    fde, no_fde = np.nanmax(horizontal_error(x)[after]), np.nanmax(horizontal_error(y)[after])
    assert fde <= no_fde + 2.0, (fde, no_fde)


@pytest.mark.parametrize("start, comp", [(170.0, "pos_n"), (366.0, "pos_e"), (250.0, "pos_n")])
def test_a_step_stays_held_from_its_first_fix_to_its_last(folder: Path, start: float, comp: str) -> None:
    """20 m for 30 s on the same log: every fix of it left out (or used relative to its held
    offset), the INS not moved onto it, and nothing held 5 s after it."""
    end = start + 30.0
    runs = _run(folder, _fault("step", comp, "20 m", start, end)).runs
    x = runs["fde"]
    sub = next(s for s in x.record["subfilters"] if s["sensor"] == "gnss_pos")
    reason, tested = np.asarray(sub["reason"]), np.asarray(sub["dof"]) > 0
    during = tested & (x.t >= start) & (x.t < end)
    assert during.sum() >= 25 and (reason[during] > 0).all()
    assert not [t for t in x.record.get("reanchored", []) if start <= t <= end]
    assert not (reason[tested & (x.t >= end + 5.0) & (x.t < end + 60.0)] > 0).any()
    err = horizontal_error(x)[(x.t >= start) & (x.t < end)]
    assert np.nanmax(err) < 6.0, np.nanmax(err)
