"""Detection by data snooping beside the global test (``test = "global" | "wtest" | "both"``):
false alarms held at α on white noise, power at the reported minimal detectable bias, the
choice reaching ``snapshot_fde``, ``gnss_solve`` / ``navfdi gnss`` and the tight filter's
``ls_precheck``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

import navfdi

RX = np.array([-1276945.0, -4717214.0, 4087225.0])
D = Path(__file__).parent / "data" / "rinex"
STATIC = (str(D / "rover.obs.gz"), str(D / "base.nav"))


def _geometry(n: int, seed: int = 3) -> np.ndarray:
    """``n`` satellites spread over the sky above 15° (ECEF, m)."""
    rng = np.random.default_rng(seed)
    up = RX / np.linalg.norm(RX)
    east = np.cross([0, 0, 1.0], up)
    east /= np.linalg.norm(east)
    north = np.cross(up, east)
    out = []
    for i in range(n):
        az = 2 * np.pi * i / n + rng.uniform(0, 0.3)
        el = np.deg2rad(rng.uniform(15, 85))
        d = np.cos(el) * (np.sin(az) * east + np.cos(az) * north) + np.sin(el) * up
        out.append(RX + 2.2e7 * d)
    return np.array(out)


def _campaign(test: str, n: int, trials: int, bias: float = 0.0, faulty: int = 0, seed: int = 0):
    """Share of epochs with any exclusion and with exactly ``faulty`` excluded, over
    ``trials`` epochs of white N(0, 1 m) pseudoranges (+ ``bias`` m on ``faulty``)."""
    sats = _geometry(n)
    rho0 = np.linalg.norm(sats - RX, axis=1) + 30.0
    rng = np.random.default_rng(seed)
    anyx = exact = 0
    for _ in range(trials):
        rho = rho0 + rng.standard_normal(n)
        rho[faulty] += bias
        r = navfdi.snapshot_fde(sats, rho, np.ones(n), alpha=0.01, test=test, x0=RX)
        anyx += bool(r.excluded)
        exact += r.excluded == [faulty]
    return anyx / trials, exact / trials


@pytest.mark.parametrize("test", ["global", "wtest", "both", "auto"])
@pytest.mark.parametrize("n", [6, 14])
def test_each_test_holds_alpha_on_white_noise(test, n):
    rate, _ = _campaign(test, n, 3000, seed=n)
    hi = stats.binom.ppf(0.999, 3000, 0.01) / 3000
    assert rate <= hi, (test, n, rate)
    if test == "global":
        # The χ² test is exact: not far below α either.
        assert rate >= stats.binom.ppf(0.001, 3000, 0.01) / 3000


def _mdb(test: str, n: int, faulty: int = 0) -> tuple[float, tuple[float, float, float]]:
    sats = _geometry(n)
    rho = np.linalg.norm(sats - RX, axis=1) + 30.0
    r = navfdi.snapshot_fde(sats, rho, np.ones(n), alpha=0.01, test=test, x0=RX)
    return float(r.mdb[faulty]), r.allocation


@pytest.mark.parametrize("test", ["global", "wtest"])
def test_a_bias_of_the_reported_mdb_is_found_with_the_allocated_power(test):
    mdb, (k0, alpha0, lam) = _mdb(test, 10)
    assert mdb > 0 and k0 > 2.5 and 0 < alpha0 < 0.01 and lam > 0
    detect, exact = _campaign(test, 10, 1500, bias=mdb, seed=7)
    lo = stats.binom.ppf(0.001, 1500, 0.8) / 1500
    # The global test's power at its MDB is β0 = 0.8 exactly; the largest |w| may also fire
    # on another satellite, so at most a little above.
    assert lo <= detect <= 0.86, (test, detect)
    assert exact > 0.6


def test_data_snooping_is_the_more_powerful_with_many_satellites_and_the_less_with_few():
    many_g, many_w = _mdb("global", 16)[0], _mdb("wtest", 16)[0]
    few_g, few_w = _mdb("global", 6)[0], _mdb("wtest", 6)[0]
    assert many_w < 0.95 * many_g
    assert few_w > few_g
    # auto takes, per set, the test with the smaller MDB: snooping with many, global with few.
    assert _mdb("auto", 16)[0] == many_w and _mdb("auto", 6)[0] == few_g
    # And measured: at the global test's MDB with 16 satellites, snooping excludes more.
    g, _ = _campaign("global", 16, 1000, bias=many_g, seed=11)
    w, _ = _campaign("wtest", 16, 1000, bias=many_g, seed=11)
    assert w > g + 0.03, (g, w)


def test_test_and_power_are_checked():
    sats = _geometry(6)
    rho = np.linalg.norm(sats - RX, axis=1)
    with pytest.raises(ValueError, match="one of .global"):
        navfdi.snapshot_fde(sats, rho, np.ones(6), test="chi2")
    with pytest.raises(ValueError, match="power"):
        navfdi.snapshot_fde(sats, rho, np.ones(6), alpha=0.05, power=0.01)
    with pytest.raises(ValueError, match="power"):
        navfdi.snapshot_fde(sats, rho, np.ones(6), power=1.5)


def test_gnss_solve_reports_the_allocation_and_mdb():
    obs, nav = STATIC
    g = navfdi.gnss_solve(obs, nav, systems="G,E", weighting="elevation", noise_scale=1.0)
    w = navfdi.gnss_solve(obs, nav, systems="G,E", weighting="elevation", noise_scale=1.0, test="wtest")
    for s in (g, w):
        assert (s.solution["excluded"] == "").all()  # clean file, σ as given: no exclusion with either test
        used = s.satellites[s.satellites["status"] == "used"]
        assert used["mdb"].notna().all() and (used["mdb"] > 0).all()
    # With 9–16 satellites in view, data snooping's MDB is the smaller.
    assert w.summary()["mdb_median"] < g.summary()["mdb_median"]
    assert w.summary()["test"] == "wtest" and "data snooping" in w.format_summary()
    # With the σ model estimated from the file (the default; factor 0.59 here) each test holds
    # α on this clean file, and the MDBs shrink.
    for test, given in (("global", g), ("wtest", w)):
        auto = navfdi.gnss_solve(obs, nav, systems="G,E", test=test)
        assert auto.summary()["false_exclusion_rate"] <= 0.01, test
        assert auto.summary()["mdb_median"] < 0.8 * given.summary()["mdb_median"], test


def test_ls_precheck_takes_the_test():
    """The walk's 20 m step on G27 (50–90 s) through the tight filter's ls_precheck with each
    test: excluded alone at most of its epochs either way, and a wrong name refused."""
    from navfdi import logs
    from navfdi.scenario import ScenarioError

    sc = navfdi.load_scenario("walk_tc")
    with pytest.raises(ScenarioError, match="tight.ls_test"):
        sc.with_values({"tight.ls_test": "chi2"}, create=True).validate()
    v = dict(sc.variants())["ls_precheck"]
    src = logs.logged_source(v)
    specs = [v.with_values({"tight.ls_test": t}, create=True) for t in ("global", "wtest", "both")]
    assert [s.core["tight"]["ls_test"] for s in specs] == ["global", "wtest", "both"]
    recs = src.run([s.to_json() for s in specs])
    t = np.asarray(src.times)
    fault = (t >= 50) & (t < 90)
    for rec in recs:
        sat = rec["satellites"]
        j = sat["names"].index("G27")
        alone = sat["excluded"][fault, j] & (sat["excluded"][fault].sum(axis=1) == 1)
        assert alone.mean() > 0.8


def test_on_heavy_tails_snooping_false_alarms_grow_with_the_satellites_and_the_global_tests_do_not(docs_script):
    # The reason the default stays "global" (docs/gnss_real.md, heavy-tailed errors): with
    # Student-t errors and the σ factor --noise auto fits, the w-test's false exclusions grow
    # with the number of satellites, the global test's much less; on Gaussian errors both hold
    # α and the w-test is the more powerful with many satellites.
    ht = docs_script("heavy_tails_tests")
    few, many = ht.case("t4", 8, 800), ht.case("t4", 36, 800)
    assert many["wtest_false"] > 2.0 * many["global_false"], many
    assert many["wtest_false"] > 2.0 * few["wtest_false"], (few, many)
    assert many["global_false"] < 2.0 * few["global_false"], (few, many)
    gauss = ht.case("gauss", 36, 800)
    assert gauss["wtest_false"] < 0.03 and gauss["global_false"] < 0.03, gauss
    assert gauss["wtest_exact"] > gauss["global_exact"] + 0.1, gauss
