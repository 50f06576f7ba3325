"""The C/N0 model's slope estimated from the file (``cn0_slope="auto"``, the default): on the
bundled static file with code noise added whose variance falls by a known number of decades per
10 dB-Hz of the recorded C/N0, the estimate lands near that number from either side of the σ–ε
model's 1 and is used where above it; a file without C/N0 keeps 1 and says why; bad values are
named."""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import navfdi
from navfdi.cli import main

DATA = Path(__file__).parent / "data" / "rinex"
OBS, NAV = DATA / "rover.obs.gz", str(DATA / "base.nav")
WALK = Path(navfdi.__file__).parent / "data" / "walk_0827"


@pytest.fixture(autouse=True)
def quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


@pytest.fixture()
def noisy(tmp_path: Path, docs_script: Callable[[str], ModuleType]) -> Callable[[float], str]:
    """The static file with code noise following the C/N0 model at a slope, 8× the elevation
    model's σ (the generator of docs/gnss_real.md's table)."""
    make = docs_script("cn0_slope_walk").cn0_noise
    return lambda slope: str(make(OBS, NAV, tmp_path / f"noisy_{slope:g}.obs", slope, 8.0))


@pytest.mark.parametrize("slope", [0.3, 1.8])
def test_the_slope_is_found_from_either_side(noisy: Callable[[float], str], slope: float) -> None:
    from navfdi._gnss_noise import cn0_slope_step

    obs = noisy(slope)
    sol = navfdi.gnss_solve(obs, NAV, systems="G,E", weighting="cn0", cn0_slope="auto", exclude=False)
    est = sol.config["cn0_slope_auto"]
    assert est["settled"] and est["solves"] <= 6
    assert abs(est["estimate"] - slope) < 0.25, est
    # Used where steeper than the σ–ε model's, which is kept otherwise.
    assert est["slope"] == max(est["estimate"], 1.0) == sol.config["cn0_slope"]
    # At the slope found the clean w have one spread at every C/N0; at the σ–ε model's 1 they
    # do not.
    fitted = navfdi.gnss_solve(obs, NAV, systems="G,E", weighting="cn0", cn0_slope=est["estimate"], exclude=False)
    assert abs(cn0_slope_step(fitted.satellites, 45.0)[0]) < 0.05
    given = navfdi.gnss_solve(obs, NAV, systems="G,E", weighting="cn0", cn0_slope=1.0, exclude=False)
    assert abs(cn0_slope_step(given.satellites, 45.0)[0]) > 0.2


def test_the_noise_scale_is_estimated_at_the_slope_found(noisy: Callable[[float], str]) -> None:
    obs = noisy(1.8)
    sol = navfdi.gnss_solve(obs, NAV, systems="G,E", weighting="cn0", noise_scale="auto")
    assert abs(sol.config["cn0_slope"] - 1.8) < 0.25
    # The σ model then fits the added noise: factor near the 8 it was made with, and the
    # clean w near unit spread.
    assert 6.0 < sol.config["noise_scale"] < 10.0
    assert 0.7 < sol.summary()["clean_w_sd_robust"] < 1.3


def test_a_file_without_cn0_keeps_the_sigma_epsilon_slope(tmp_path: Path) -> None:
    from test_noise_auto import _without_cn0

    obs = _without_cn0(tmp_path / "blank.obs")
    sol = navfdi.gnss_solve(obs, str(WALK / "gnss_1730.nav"), systems="G,E", weighting="cn0", cn0_slope="auto", exclude=False)
    est = sol.config["cn0_slope_auto"]
    assert est["slope"] == 1.0 and not est["settled"] and "C/N0 bins" in est["reason"]


def test_bad_slopes_are_named() -> None:
    o, n = str(WALK / "gnss_1730.obs.gz"), str(WALK / "gnss_1730.nav")
    for bad, what in ((-0.5, r"cn0_slope = -0.5: a slope in \[0, 3\]"), (4.0, r"cn0_slope = 4.0"), ("steep", r"cn0_slope = 'steep'"), (float("nan"), "cn0_slope = nan"), (True, "cn0_slope = True")):
        with pytest.raises(ValueError, match=what):
            navfdi.gnss_solve(o, n, systems="G,E", weighting="cn0", cn0_slope=bad)
    # numpy scalars are numbers too.
    assert navfdi.gnss_solve(o, n, systems="G,E", weighting="cn0", cn0_slope=np.int64(2), exclude=False).config["cn0_slope"] == 2.0
    with pytest.raises(ValueError, match="weighting = 'elevation' has none"):
        navfdi.gnss_solve(o, n, systems="G,E", weighting="elevation", cn0_slope=2.0)
    with pytest.raises(ValueError, match="weighting = 'rtklib' has none"):
        navfdi.gnss_solve(o, n, systems="G,E", weighting="rtklib", cn0_slope=0.5)
    with pytest.raises(ValueError, match=r"cn0_slope: 9; expected"):
        navfdi._core.GnssRun(o, n, ["G"], 10.0, 0.01, None, True, (0.3, 0.3), "cn0", True, True, [], {}, {}, (1e-3, 1e-3), (1e-3, 10), (1.0, 5.0, 60.0, 20, 0.02), 45.0, "global", 0.8, 9.0)


def test_the_command_line_estimates_and_reports_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    o, n = str(WALK / "gnss_1730.obs.gz"), str(WALK / "gnss_1730.nav")
    assert main(["gnss", o, n, "--systems", "G,E", "--weighting", "auto", "--cn0-slope", "auto", "--noise", "auto", "--out", str(tmp_path / "o")]) == 0
    text = capsys.readouterr().out
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())["summary"]
    est = summary["cn0_slope_auto"]
    # The u-blox walk's w call for a slope below the σ–ε model's, which is kept.
    assert 0.3 < est["estimate"] < 0.9 and est["settled"] and est["slope"] == 1.0
    assert f"C/N0 slope 1.00 (variance decades per 10 dB-Hz; --cn0-slope auto: fitted {est['estimate']:.2f}" in text
    assert "not below the sigma-epsilon model's 1" in text
    assert summary["weighting_auto"]["chosen"] == "cn0"
