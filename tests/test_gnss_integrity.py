"""Integrity on the bundled static RINEX (issue 24): ARAIM and snapshot-RAIM protection levels
per epoch with ``--integrity lpv200``; no hazardously misleading epoch fault-free or with a
20 m step on any used satellite."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi.gnss import read_truth_file
from navfdi.gnss_integrity import snapshot_pl

D = Path(__file__).parent / "data" / "rinex"
OBS, NAV = str(D / "rover.obs.gz"), str(D / "base.nav")
TRUTH = read_truth_file(D / "rover_position.txt")


def _hmi(s) -> int:
    ig = s.summary()["integrity"]
    return sum(ig[f"{k}_{d}_hazardously_misleading"] for k in ("araim", "raim") for d in ("horizontal", "vertical"))


@pytest.fixture(scope="module")
def gps_galileo():
    return navfdi.gnss_solve(OBS, NAV, systems="G,E", truth=TRUTH, integrity="lpv200")


def test_fault_free_levels_bound_the_errors(gps_galileo) -> None:
    s = gps_galileo
    sol = s.solution
    assert {"hpl", "vpl", "emt", "hpl_raim", "vpl_raim", "integrity"} <= set(sol.columns)
    ig = s.summary()["integrity"]
    assert ig["availability"] == 1.0 and _hmi(s) == 0
    assert ig["araim_horizontal_misleading"] == 0 and ig["araim_vertical_misleading"] == 0
    # The ARAIM levels protect against more (constellation and multiple faults) than the
    # snapshot levels of the same test.
    assert (sol["vpl"] > sol["vpl_raim"]).all() and (sol["hpl"] > sol["hpl_raim"]).all()
    # GPS alone cannot be protected against a GPS constellation fault (P_const 1e-4): ARAIM
    # unavailable, snapshot levels still there.
    g = navfdi.gnss_solve(OBS, NAV, systems="G", truth=TRUTH, integrity="lpv200")
    assert (g.solution["integrity"] == "unavailable").all() and np.isfinite(g.solution["vpl_raim"]).all()
    assert _hmi(g) == 0


def test_no_hazardously_misleading_epoch_with_a_20m_step_on_any_satellite(gps_galileo) -> None:
    sats = gps_galileo.satellites
    used = sorted(sats.loc[sats["status"] == "used", "satellite"].astype(str).unique())
    assert len(used) >= 8
    for sat in used:
        s = navfdi.gnss_solve(OBS, NAV, systems="G,E", truth=TRUTH, integrity="lpv200", faults=[f"{sat}:step:20m:100s:200s"])
        assert _hmi(s) == 0, sat


def test_outputs_and_errors(tmp_path: Path, gps_galileo) -> None:
    paths = gps_galileo.write(tmp_path)
    names = {p.name for p in paths}
    assert {"stanford_horizontal.png", "stanford_vertical.png"} <= names
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert summary["summary"]["integrity"]["allocation"] == "lpv200"
    with pytest.raises(ValueError, match="unknown allocation"):
        navfdi.gnss_solve(OBS, NAV, integrity="lpv999")
    with pytest.raises(ValueError, match="p_md"):
        snapshot_pl(np.eye(3), ["G"] * 3, [1.0] * 3, 10.0, p_md=2.0)
    with pytest.raises(ValueError, match="no redundancy"):
        snapshot_pl(np.eye(3), ["G"] * 3, [1.0] * 3, 10.0)
