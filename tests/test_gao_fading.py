"""Paper 002 (fading-memory fault tolerance) end to end: the bundled ``gao_fading`` and
``gao_fading_repeat`` scenarios, the centralized architecture's policies, variants on the same
measurements and the MDB (docs/gao_fading.md has the numbers beside the paper's)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import optimize, stats

import navfdi

SEEDS = range(20)


@pytest.fixture(scope="module")
def runs():
    return {seed: navfdi.run_scenario("gao_fading", seed=seed) for seed in SEEDS}


def coverage(run, det, start, end):
    """Share of the fault's epochs in which the detector (or policy) is in alarm."""
    d = run.detector("gnss", det)
    sel = (run.t >= start) & (run.t < end)
    return float(np.mean(d["alarm"][sel]))


def first_alarm_from(run, det, t0):
    d = run.detector("gnss", det)
    idx = np.flatnonzero(d["alarm"] & (run.t >= t0))
    return float(run.t[idx[0]]) if idx.size else None


def median_lat_rms(runs, variant):
    return float(np.median([runs[s][variant].errors()["lat_m_rms"] for s in runs]))


def test_latitude_error_rms_is_ordered_fading_sprt_chi2(runs):
    """Paper: 1.968 < 5.503 < 7.596 m (one run). Here: the median over 20 seeds, and seed by
    seed. The pooled RMS over these 20 seeds is not ordered (fading 4.98 > sprt 4.29 m): in one
    seed (10) the fading method declares the fault over during it (docs/gao_fading.md); over
    100 Monte-Carlo runs the pooled RMS is ordered again."""
    fading, sprt, chi2 = median_lat_rms(runs, "fading"), median_lat_rms(runs, "sprt"), median_lat_rms(runs, "chi2")
    assert fading < sprt < chi2, (fading, sprt, chi2)
    lat = {v: [runs[s][v].errors()["lat_m_rms"] for s in SEEDS] for v in ("chi2", "sprt", "fading")}
    assert sum(f < s for f, s in zip(lat["fading"], lat["sprt"])) >= 17
    assert sum(s < c for s, c in zip(lat["sprt"], lat["chi2"])) == len(SEEDS)


def test_chi_square_misses_30_m_and_detects_80_m(runs):
    """"Detects" = holds its alarm for at least half of the fault (the paper's chi-square 'is
    basically ineffective' at 30 m: isolated alarms, no lasting detection)."""
    missed_30 = sum(coverage(runs[s]["chi2"], "chi2", 300, 480) < 0.5 for s in SEEDS)
    assert missed_30 >= 15
    sc80 = navfdi.load_scenario("gao_fading").with_value("faults[0].magnitude", "80 m")
    detected_80 = sum(coverage(navfdi.run_scenario(sc80, seed=s)["chi2"], "chi2", 300, 480) >= 0.5 for s in SEEDS)
    assert detected_80 >= 19  # ≥ 95 % of 20


def test_sprt_and_fading_first_alarm_at_the_same_epoch(runs):
    """Until their first alarm the two variants are the same filter on the same data."""
    compared = 0
    for s in SEEDS:
        a, b = runs[s]["sprt"], runs[s]["fading"]
        if first_alarm_from(a, "sprt", 0) is not None and first_alarm_from(a, "sprt", 0) < 300:
            continue  # a false alarm before the fault already made them differ
        compared += 1
        assert first_alarm_from(a, "sprt", 300) == first_alarm_from(b, "sprt", 300), s
    assert compared >= 15


def test_fading_declares_the_end_sprt_lingers(runs):
    confirm = 10.0
    on_time = 0
    for s in SEEDS:
        fad = [m for m in runs[s]["fading"].fault_table() if m.detector == "sprt"][0]
        assert fad.cleared_at is not None and fad.cleared_at <= 480 + confirm + 5, (s, fad)
        on_time += fad.cleared_at >= 480  # not declared over while the fault lasts
        alarm = runs[s]["sprt"].detector("gnss", "sprt")["alarm"]
        assert alarm[int(np.searchsorted(runs[s]["sprt"].t, 540.0))], s
    assert on_time >= 19  # seed 10 ends it at 428 s, during the fault


def test_repeated_fault_is_new_for_fading_not_for_sprt():
    new_fading = new_sprt = 0
    for s in SEEDS:
        r = navfdi.run_scenario("gao_fading_repeat", seed=s)
        fad = {m.fault_id: m for m in r["fading"].fault_table() if m.detector == "sprt"}
        spr = {m.fault_id: m for m in r["sprt"].fault_table() if m.detector == "sprt"}
        new_fading += fad["lat-step-2"].detected_at is not None
        new_sprt += spr["lat-step-2"].detected_at is not None
        if spr["lat-step-2"].detected_at is None:
            assert "in alarm since" in spr["lat-step-2"].note
    assert new_fading >= 18 and new_sprt <= 2


def scipy_lambda0(pf, pm, m):
    td = stats.chi2.isf(pf, m)
    return optimize.brentq(lambda lam: stats.ncx2.cdf(td, m, lam) - pm, 1e-6, 1e4, xtol=1e-12)


def test_mdb_is_sqrt_lambda0_sigma_for_a_diagonal_covariance(runs):
    lam = scipy_lambda0(0.005, 0.005, 6)
    assert lam == pytest.approx(41.04, abs=0.01)
    sig = np.array([10.0, 10.0, 10.0, 0.1, 0.1, 0.1])
    np.testing.assert_allclose(navfdi.mdb(np.diag(sig**2), 0.005, 0.005), np.sqrt(lam) * sig, rtol=1e-9)
    # In the runs: after convergence A ≈ R (P is small against R), so MDB ≈ sqrt(λ0)·σ; the
    # prediction uncertainty only makes it larger.
    s = runs[0]["fading"].record["subfilters"][0]
    steady = s["mdb"][1000]
    assert np.all(steady >= np.sqrt(lam) * sig * 0.999) and np.all(steady <= np.sqrt(lam) * sig * 1.05)
    assert "λ0 = 41.040 (m = 6, Pf = 0.005, Pm = 0.005)" in runs[0]["fading"].format_tables()
    assert "navfdi: standard λ0 above" in runs[0]["fading"].format_tables()
    assert "17.872" in runs[0]["fading"].format_tables()


def test_variants_share_the_simulated_measurements():
    """Running the variants together equals running each alone with the same seed, bit for bit."""
    sc = navfdi.load_scenario("gao_fading")
    together = navfdi.run_scenario(sc, seed=7)
    for name, vsc in sc.variants():
        alone = navfdi.run_scenario(vsc, seed=7, compare_isolation=False)
        a, b = together[name].record, alone.record
        np.testing.assert_array_equal(a["error"], b["error"])
        for sa, sb in zip(a["subfilters"], b["subfilters"]):
            for da, db in zip(sa["detectors"], sb["detectors"]):
                np.testing.assert_array_equal(da["statistic"], db["statistic"])
                np.testing.assert_array_equal(da["alarm"], db["alarm"])


def test_variants_may_only_change_the_filter():
    raw = navfdi.load_scenario("gao_fading").raw
    bad = {**raw, "variants": [{"name": "x", "set": {"faults[0].magnitude": "40 m"}}]}
    with pytest.raises(navfdi.ScenarioError, match=r"variants\[0\]\.set: 'faults\[0\]\.magnitude' would change the simulated measurements"):
        navfdi.load_scenario(bad)
    dup = {**raw, "variants": [{"name": "x"}, {"name": "x"}]}
    with pytest.raises(navfdi.ScenarioError, match=r"variants\[1\]\.name = 'x': used by an earlier variant"):
        navfdi.load_scenario(dup)


def test_outputs_carry_the_variant(tmp_path):
    import pandas as pd

    r = navfdi.run_scenario("gao_fading", seed=1)
    paths = r.write(tmp_path, figures=False)
    assert {p.name for p in paths} == {"events.csv", "timeseries.parquet", "errors.csv", "summary.json", "report.html"}
    ev = pd.read_csv(tmp_path / "events.csv")
    assert ev.columns[0] == "variant" and set(ev.variant) == {"chi2", "sprt", "fading"}
    ts = pd.read_parquet(tmp_path / "timeseries.parquet")
    assert set(ts.variant) == {"chi2", "sprt", "fading"} and len(ts) == 3 * 1500
    assert {"gnss.mdb.pos_n", "gnss.sprt.alarm", "error.pos_n"} <= set(ts.columns)
    err = pd.read_csv(tmp_path / "errors.csv")
    assert list(err.variant) == ["chi2", "sprt", "fading"]
    units = {"pos": "m", "lat": "m", "vel": "m_s", "att": "rad"}
    for c in ["pos_e", "pos_n", "pos_u", "lat_m", "vel_e", "vel_n", "vel_u", "att_e", "att_n", "att_u"]:
        u = units[c[:3]]
        assert f"{c}_rms_{u}" in err.columns and f"{c}_max_{u}" in err.columns
    np.testing.assert_allclose(err.lat_m_rms_m, err.pos_n_rms_m)


def test_montecarlo_reports_per_variant(tmp_path):
    import pandas as pd

    camp = navfdi.montecarlo("gao_fading", runs=6, seed=3, progress=False)
    s = camp.summary()
    assert list(dict.fromkeys(s.variant)) == ["chi2", "sprt", "fading"]
    assert set(camp.runs.variant) == {"chi2", "sprt", "fading"}
    # The same run index has the same measurements in every variant: before any alarm the
    # sprt and fading variants are the same filter, so a run whose sprt never alarmed before
    # the fault has the same detection delay in both.
    d = camp.runs[(camp.runs.detector == "sprt") & (camp.runs.fault_id == "lat-step")].set_index(["variant", "run"]).delay
    assert (d.loc["sprt"] == d.loc["fading"]).sum() >= 4
    camp.write(tmp_path, figures=False)
    assert "variant" in pd.read_csv(tmp_path / "summary.csv").columns
    assert "variant" in pd.read_parquet(tmp_path / "runs.parquet").columns


def test_policy_configuration_errors():
    raw = navfdi.load_scenario("gao_fading").raw
    bad = {**raw, "variants": []}
    bad = {k: v for k, v in bad.items() if k != "variants"}
    bad["centralized"] = {**raw["centralized"], "policy": "fading", "sensors": [{**raw["centralized"]["sensors"][0], "decision": "chi2"}]}
    with pytest.raises(navfdi.ScenarioError, match=r"centralized\.sensors\[0\]\.decision: policy .* needs an sprt detector"):
        navfdi.load_scenario(bad)
    bad["centralized"] = {**raw["centralized"], "policy": "lazy"}
    with pytest.raises(navfdi.ScenarioError, match=r"centralized\.policy = 'lazy'"):
        navfdi.load_scenario(bad)
    bad["centralized"] = {**raw["centralized"], "fading": 0.9}
    with pytest.raises(navfdi.ScenarioError, match=r"centralized\.fading: 0\.9 must be a finite number >= 1"):
        navfdi.load_scenario(bad)
    both = {**bad, "centralized": raw["centralized"], "federated": {"mode": "reset", "subfilters": []}}
    with pytest.raises(navfdi.ScenarioError, match=r"federated: given, but architecture is 'centralized'"):
        navfdi.load_scenario(both)
