"""Integrity on the bundled static RINEX: ARAIM and snapshot-RAIM protection levels
per epoch with ``--integrity lpv200``; no hazardously misleading epoch fault-free or with a
20 m step on any used satellite."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import navfdi
from navfdi.gnss import read_truth_file
from navfdi.gnss_integrity import snapshot_pl

D = Path(__file__).parent / "data" / "rinex"
OBS, NAV = str(D / "rover.obs.gz"), str(D / "base.nav")
TRUTH = read_truth_file(D / "rover_position.txt")


def _hmi(s) -> int:
    ig = s.summary()["integrity"]
    return sum(ig[f"{k}_{d}_hazardously_misleading"] for k in ("araim", "raim", "araim_fde") for d in ("horizontal", "vertical"))


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
    # GPS alone cannot be protected against a GPS constellation fault (P_const 1e-4): ARAIM
    # unavailable, snapshot levels still there.
    g = navfdi.gnss_solve(OBS, NAV, systems="G", truth=TRUTH, integrity="lpv200")
    assert (g.solution["integrity"] == "unavailable").all() and np.isfinite(g.solution["vpl_raim"]).all()
    assert _hmi(g) == 0
    # The snapshot RAIM levels, from the overbounding error model (σ_URA, the Klobuchar
    # residual, the troposphere, the solution's σ, b_nom), bound the error at every epoch, G
    # and G + E (with the code-noise σ alone they were exceeded at 291 of 301 epochs).
    for run in (s, g):
        so = run.solution
        herr, verr = np.hypot(so["east"], so["north"]), so["up"].abs()
        assert (herr < so["hpl_raim"]).all() and (verr < so["vpl_raim"]).all()
        sat = run.satellites[run.satellites["status"] == "used"]
        tot2 = sat["raim_sigma_ura"] ** 2 + sat["iono_sigma"] ** 2 + sat["raim_sigma_tropo"] ** 2 + sat["sigma"] ** 2
        np.testing.assert_allclose(sat["raim_sigma_total"] ** 2, tot2, rtol=1e-12)
        # The ionospheric residual dominates a single-frequency receiver's error budget.
        assert (sat["iono_sigma"] > sat["sigma"]).all()


def test_levels_that_do_not_hold_are_said_in_one_line(gps_galileo) -> None:
    import copy

    from navfdi.gnss_integrity import _binom_sf, not_holding

    assert not_holding(gps_galileo) == [] and "do not hold" not in gps_galileo.format_summary()
    shrunk = copy.deepcopy(gps_galileo)
    shrunk.solution["hpl_raim"] *= 0.05  # levels far below the 2.8 m error
    lines = not_holding(shrunk)
    assert len(lines) == 1 and lines[0].startswith("snapshot RAIM levels exceeded by the error at 301 of 301 epochs")
    assert lines[0] in " ".join(shrunk.format_summary().split())  # wrapped at 100 columns
    # One exceedance in 301 epochs is within snapshot RAIM's 1e-3 per epoch; not ARAIM's 1e-7.
    assert _binom_sf(1, 301, 1e-3) > 0.01 and _binom_sf(1, 301, 1e-7) < 0.01
    assert _binom_sf(0, 10, 0.5) == 1.0 and abs(_binom_sf(5, 10, 0.5) - 0.623046875) < 1e-12


def test_klobuchar_residual_sigma_follows_do229() -> None:
    """The solve's ``iono_sigma`` per satellite (the bands and obliquity are unit-tested in
    ``gnss::atmosphere``): divided by the obliquity factor it is one of DO-229's τ_vert (9 /
    4.5 / 6 m), times (f_L1/f_B1)² for BeiDou's B1I."""
    s = navfdi.gnss_solve(OBS, NAV, systems="G,E,C")
    sat = s.satellites[s.satellites["status"].isin(["used", "excluded"])]
    el = np.radians(sat["elevation"].to_numpy(float))
    fpp = 1.0 / np.sqrt(1.0 - (6378.1363 * np.cos(el) / (6378.1363 + 350.0)) ** 2)
    tau = sat["iono_sigma"].to_numpy(float) / fpp
    beidou = sat["satellite"].astype(str).str.startswith("C").to_numpy()
    assert beidou.any() and (~beidou).any()
    scale = np.where(beidou, (1575.42 / 1561.098) ** 2, 1.0)
    bands = np.array([4.5, 6.0, 9.0])
    # (the table's elevation is the row's, a hair from the one at the final solution)
    assert np.abs(tau[:, None] / scale[:, None] - bands[None, :]).min(axis=1).max() < 1e-3

def test_no_hazardously_misleading_epoch_with_a_20m_step_on_any_satellite(gps_galileo) -> None:
    sats = gps_galileo.satellites
    used = sorted(sats.loc[sats["status"] == "used", "satellite"].astype(str).unique())
    assert len(used) >= 8
    for sat in used:
        s = navfdi.gnss_solve(OBS, NAV, systems="G,E", truth=TRUTH, integrity="lpv200", faults=[f"{sat}:step:20m:100s:200s"])
        assert _hmi(s) == 0, sat
        # ARAIM's own detection and exclusion (on the satellites before the snapshot test's
        # exclusion): the faulty satellite and no other, levels recomputed, no misleading epoch
        sol = s.solution
        st = s.satellites
        faulty = set(st.loc[(st["satellite"].astype(str) == sat) & (st["fault"] != 0), "epoch"].astype(int))
        fault = pd.Series([i in faulty for i in range(len(sol))], index=sol.index)
        assert fault.sum() == 100, sat
        assert set(sol.loc[sol["fde_excluded"] != "", "fde_excluded"]) <= {sat}, sat
        assert (sol.loc[fault, "fde_excluded"] == sat).mean() >= 0.95, sat
        assert (sol.loc[~fault, "fde_excluded"] == "").all(), sat
        ig = s.summary()["integrity"]
        assert ig["araim_fde_alarms"] == 0, sat
        assert ig["araim_fde_horizontal_misleading"] == 0 and ig["araim_fde_vertical_misleading"] == 0, sat
        # where the snapshot test excluded the same satellite, ARAIM after its exclusion has
        # the levels of ARAIM on the snapshot test's satellites (availability included: E33
        # out leaves VPL ≈ 62 m > VAL)
        snap = set(st.loc[(st["satellite"].astype(str) == sat) & (st["status"] == "excluded"), "epoch"].astype(int))
        both = fault & (sol["fde_excluded"] == sat) & pd.Series([i in snap for i in range(len(sol))], index=sol.index)
        assert both.sum() >= 90, sat
        np.testing.assert_allclose(sol.loc[both, "vpl_fde"], sol.loc[both, "vpl"], rtol=1e-9)
        assert (sol.loc[both, "integrity_fde"] == sol.loc[both, "integrity"]).all(), sat


def test_fault_free_araim_fde_detects_nothing(gps_galileo) -> None:
    sol = gps_galileo.solution
    assert (sol["fde_ratio"] < 1).all() and (sol["fde_excluded"] == "").all()
    assert (sol["integrity_fde"] == "available").all()
    np.testing.assert_allclose(sol["hpl_fde"], sol["hpl"], rtol=1e-12)


def test_araim_fde_correction_is_the_least_squares_step() -> None:
    """With the solution's own weights (σ_URA → 0), the all-in-view ARAIM position (the
    solution plus its correction) is the solution without the snapshot test's exclusion: checks
    the residuals' sign and the ENU axes against an independent solve."""
    f = ["G13:step:20m:100s:200s"]
    kept = navfdi.gnss_solve(OBS, NAV, systems="G,E", truth=TRUTH, faults=f)
    plain = navfdi.gnss_solve(OBS, NAV, systems="G,E", truth=TRUTH, faults=f, exclude=False)
    sats = kept.satellites
    ep = 150
    g = sats[(sats["epoch"] == ep) & sats["status"].isin(["used", "excluded"])]
    assert "G13" in set(g.loc[g["status"] == "excluded", "satellite"].astype(str))
    el, az = np.radians(g["elevation"].to_numpy(float)), np.radians(g["azimuth"].to_numpy(float))
    los = np.column_stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)])
    s2 = g["sigma"].to_numpy(float) ** 2
    r = navfdi.araim(los, [str(x)[0] for x in g["satellite"]], c_int=s2 + 1e-12, c_acc=s2 + 1e-12, residuals=g["residual"].to_numpy(float))
    # the correction of the subset kept (without G13) plus the G13 mode's separation gives
    # back the all-in-view step S₀y
    names = [str(x) for x in g["satellite"]]
    assert r.excluded == (names.index("G13"),)
    mode = next(m for m in r.modes if m["satellites"] == [names.index("G13")])
    step0 = np.array(r.correction) - np.array(mode["separation"])
    got = np.array([kept.solution[c].iat[ep] for c in ("east", "north", "up")]) + step0
    want = np.array([plain.solution[c].iat[ep] for c in ("east", "north", "up")])
    np.testing.assert_allclose(got, want, atol=0.02)
    # and without G13 the ARAIM position is the snapshot test's (same satellites, weights)
    np.testing.assert_allclose(r.correction, 0.0, atol=0.02)


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


def test_an_allocation_file_sets_the_budget_limits_and_ism(tmp_path: Path, gps_galileo) -> None:
    """``--integrity FILE``: absent keys keep LPV-200's (an empty file gives the lpv200 levels
    exactly); given ones change the levels and the availability the way they should."""
    empty = tmp_path / "same.toml"
    empty.write_text("# nothing: LPV-200\n")
    same = navfdi.gnss_solve(OBS, NAV, systems="G,E", truth=TRUTH, integrity=str(empty))
    for c in ("hpl", "vpl", "emt", "hpl_fde", "vpl_fde"):
        np.testing.assert_array_equal(same.solution[c].to_numpy(float), gps_galileo.solution[c].to_numpy(float))
    assert same.summary()["integrity"]["allocation"] == "same"
    strict = tmp_path / "strict.toml"
    strict.write_text(
        'name = "rail demo"\n'
        "[allocation]\np_hmi_vert = 1e-9\np_hmi_hor = 1e-9\ntol_pl = 0.0\n"
        "[limits]\nhal = 15.0\nval = 20.0\n"
        "[ism]\nsigma_ura = 1.0\np_const = {G = 1e-4, E = 1e-4, C = 1e-4}\n"
    )
    s = navfdi.gnss_solve(OBS, NAV, systems="G,E", truth=TRUTH, integrity=strict)
    base, tight = gps_galileo.solution, s.solution
    # A smaller integrity budget and a larger σ_URA both raise every level.
    assert (tight["vpl"] > base["vpl"]).all() and (tight["hpl"] > base["hpl"]).all()
    ig = s.summary()["integrity"]
    assert ig["allocation"] == "rail demo"
    # HAL 15 m against HPLs above it: unavailable wherever the HPL exceeds the HAL.
    avail = tight["integrity"] == "available"
    assert not (avail & (tight["hpl"] > 15.0)).any() and ig["availability"] < 1.0
    cfg = s.config["integrity"]
    assert cfg["hal"] == 15.0 and cfg["val"] == 20.0 and cfg["file"] == str(strict)
    assert cfg["probabilities"]["p_hmi_vert"] == 1e-9 and cfg["probabilities"]["p_fa_vert"] == 3.9e-6
    assert cfg["p_const"] == {"G": 1e-4, "E": 1e-4, "C": 1e-4} and cfg["sigma_ura"] == 1.0
    # tol_pl = 0: the roots of the PL equations, at most TOL_PL (5 cm) per axis below the
    # ADD search's levels of lpv200, never above them.
    root_file = tmp_path / "root.toml"
    root_file.write_text("[allocation]\ntol_pl = 0\n")
    root = navfdi.gnss_solve(OBS, NAV, systems="G,E", integrity=root_file).solution
    for c, slack in (("vpl", 0.05), ("hpl", 0.05 * np.sqrt(2))):
        d = base[c].to_numpy(float) - root[c].to_numpy(float)
        assert (d >= -1e-6).all() and (d <= slack).all() and d.max() > 0.0, c


@pytest.mark.parametrize(
    "text,match",
    [
        ("[allocation]\np_hmi_vert = 2.0\n", r"\[allocation\] p_hmi_vert = 2.0: must be in \(0, 1\)"),
        ("[allocation]\ntol_pl = -1\n", r"\[allocation\] tol_pl = -1: must be in \[0, 10\)"),
        ("[allocation]\np_md = 1e-3\n", r"\[allocation\] unknown key\(s\) p_md"),
        ("[limits]\nhal = 'forty'\n", r"\[limits\] hal = 'forty': a finite number"),
        ("[limit]\nhal = 40\n", r"unknown key\(s\) limit"),
        ("[ism]\np_const = {X = 1e-4}\n", r"p_const.X: not a system letter"),
        ("[ism]\np_const = 1e-4\n", r"p_const must be a table"),
        ("[allocation\n", r"not valid TOML"),
        ("name = ''\n", r"name must be a non-empty string"),
    ],
)
def test_a_bad_allocation_file_is_named_before_solving(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, text: str, match: str) -> None:
    import navfdi.gnss

    def solving(*a: object, **k: object) -> None:
        raise AssertionError("the file was solved before the allocation was checked")

    monkeypatch.setattr(navfdi.gnss._core, "GnssRun", solving)
    f = tmp_path / "alloc.toml"
    f.write_text(text)
    before = f.read_bytes()
    with pytest.raises(ValueError, match=match) as e:
        navfdi.gnss_solve(OBS, NAV, integrity=str(f))
    assert "alloc.toml" in str(e.value)
    assert f.read_bytes() == before
    with pytest.raises(ValueError, match="no such file"):
        navfdi.gnss_solve(OBS, NAV, integrity=str(tmp_path / "missing.toml"))
