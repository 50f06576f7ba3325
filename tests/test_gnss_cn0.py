"""C/N0 weighting of the single-point solution: on the handheld u-blox walk,
whose weak satellites are its noisy ones, ``weighting="cn0"`` cuts the fault-free exclusions of
the elevation model and keeps a 20 m step on a high satellite excluded; with ``--noise auto``
none is excluded fault-free."""

from __future__ import annotations

import warnings
from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi.cli import main

P = Path(navfdi.__file__).parent / "data" / "walk_0827"
OBS, NAV = str(P / "gnss_1730.obs.gz"), str(P / "gnss_1730.nav")


def _exclusion_rate(sol) -> float:
    return float((sol.solution["excluded"].fillna("").astype(str) != "").mean())


def _exact(sol, sat: str) -> float:
    s = sol.satellites
    ep = s[(s["satellite"] == sat) & (s["fault"] != 0)]["epoch"].to_numpy()
    return float((sol.solution.iloc[ep]["excluded"].astype(str) == sat).mean())


@pytest.fixture(scope="module")
def quiet():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def test_cn0_weighting_fits_a_low_cost_receiver(quiet) -> None:
    elev = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="elevation", noise_scale=1.0)
    cn0 = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="cn0", noise_scale=1.0)
    assert _exclusion_rate(elev) > 0.25
    assert _exclusion_rate(cn0) < 0.5 * _exclusion_rate(elev)
    auto = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="cn0", noise_scale="auto")
    assert _exclusion_rate(auto) <= 0.01
    assert 1.0 < auto.config["noise_scale"] < 2.0
    assert auto.config["weighting"] == "cn0" and auto.config["cn0_reference"] == 45.0
    step = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="cn0", noise_scale="auto", faults=["E26:step:20m:40s:100s"])
    assert _exact(step, "E26") >= 0.95


def test_cn0_reference_moves_the_weights_and_bad_values_are_named(quiet) -> None:
    a = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="cn0", cn0_reference=45.0, noise_scale=1.0)
    b = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="cn0", cn0_reference=35.0, noise_scale=1.0)
    # A lower reference shrinks every σ by 10 dB: the same solution, ten times the statistic.
    ratio = (b.solution["first_statistic"] / a.solution["first_statistic"]).median()
    assert 9.0 < ratio < 11.0
    with pytest.raises(ValueError, match=r"cn0_reference: 90 dB-Hz"):
        navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="cn0", cn0_reference=90.0)
    with pytest.raises(ValueError, match="weighting: 'snr' is not 'elevation', 'rtklib', 'cn0' or 'auto'"):
        navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="snr")


def test_cli_weighting_cn0(tmp_path, capsys, quiet) -> None:
    assert main(["gnss", OBS, NAV, "--systems", "G,E", "--weighting", "cn0", "--cn0-reference", "45", "--out", str(tmp_path)]) == 0
    import json

    summary = json.loads((tmp_path / "summary.json").read_text())
    text = json.dumps(summary)
    assert '"weighting": "cn0"' in text and '"cn0_reference": 45.0' in text


def test_the_satellite_table_carries_the_recorded_cn0() -> None:
    """``satellites.cn0`` is the signal's C/N0 as the file records it (S1C for GPS C1C, S1X for
    Galileo C1X on the walk's u-blox file), for every solved satellite-epoch; NaN for rows
    never solved (no ephemeris)."""
    walk = Path(str(resources.files("navfdi") / "data" / "walk_0827"))
    obs, nav = walk / "gnss_1730.obs.gz", walk / "gnss_1730.nav"
    sol = navfdi.gnss_solve(obs, nav, systems="G,E")
    sats = sol.satellites
    raw = navfdi.read_rinex(str(obs))
    snr = raw[raw["observable"].isin(["S1C", "S1X"])]
    want = snr.set_index(["epoch", "satellite"])["value"]
    used = sats[sats["status"].isin(["used", "excluded"])]
    got = used.set_index(["epoch", used["satellite"].astype(str)])["cn0"]
    assert len(got) > 1000
    np.testing.assert_array_equal(got.to_numpy(), want.reindex(got.index).to_numpy())
    assert sats.loc[sats["status"] == "no_ephemeris", "cn0"].isna().all()


def test_the_clean_w_spread_per_cn0_class_shows_how_the_model_fits() -> None:
    """The summary's clean w robust SD per C/N0 class, on the walk: the C/N0 model (variance ×
    10 per 10 dB) over-penalises this receiver's weak signals (their w spread smallest), the
    elevation model under-penalises them (largest); the console says which."""
    walk = Path(str(resources.files("navfdi") / "data" / "walk_0827"))
    obs, nav = walk / "gnss_1730.obs.gz", walk / "gnss_1730.nav"
    got = {}
    for wt in ("cn0", "elevation"):
        sol = navfdi.gnss_solve(obs, nav, systems="G,E", weighting=wt, noise_scale="auto")
        by = sol.summary()["clean_w_sd_robust_by_cn0"]
        assert len(by) >= 4 and list(by)[0] == "<30" and list(by)[-1] == ">=45", by
        got[wt] = (by["<30"], by[">=45"], sol.format_summary())
    assert got["cn0"][0] < 0.67 * got["cn0"][1], got["cn0"][:2]
    assert "per C/N0 (dB-Hz) <30" in got["cn0"][2] and "weak signals penalised more than they need" in got["cn0"][2]
    assert got["elevation"][0] > 1.5 * got["elevation"][1], got["elevation"][:2]
    assert "weak signals noisier than modelled" in got["elevation"][2]


def test_the_console_points_an_unfitted_elevation_model_to_the_cn0_model(capsys, quiet) -> None:
    # The walk with the elevation model at factor 1: the global test alarms at 33.6 % of the
    # fault-free epochs; the file records C/N0, so the hint names --weighting auto too. The
    # static file (geodetic receiver) fits: no hint.
    assert main(["gnss", OBS, NAV, "--systems", "G,E", "--weighting", "elevation", "--noise", "1"]) == 0
    out = capsys.readouterr().out.replace("\n  ", " ")
    assert "the noise model does not fit this receiver" in out
    assert "--weighting auto (the default) takes the C/N0 model" in out
    assert main(["gnss", OBS, NAV, "--systems", "G,E", "--weighting", "cn0", "--noise", "1"]) == 0
    assert "--weighting auto takes" not in capsys.readouterr().out.replace("\n  ", " ")
