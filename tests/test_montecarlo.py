"""Monte-Carlo campaigns: determinism, Dask, calibration, sweeps, errors, interruption."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time

import numpy as np
import pandas as pd
import pytest
from scipy import stats

import navfdi
import importlib

mc = importlib.import_module("navfdi.montecarlo")  # the module (navfdi.montecarlo is the function)

SLOPES = ["0.05 sigma/s", "0.1 sigma/s", "0.2 sigma/s", "0.5 sigma/s"]


@pytest.fixture(scope="module")
def short():
    """yang2013 shortened to 300 s (faults moved) for fast determinism tests."""
    sc = navfdi.load_scenario("yang2013").base()
    for path, v in [("faults[0].start", "60 s"), ("faults[0].end", "160 s"), ("faults[1].start", "220 s"), ("faults[1].end", "240 s"), ("duration", "300 s")]:
        sc = sc.with_value(path, v)
    return sc


def test_identical_across_threads_and_chunking(short):
    a = navfdi.montecarlo(short, runs=12, seed=3, workers=1, chunk_size=12, progress=False)
    b = navfdi.montecarlo(short, runs=12, seed=3, workers=2, chunk_size=5, progress=False)
    pd.testing.assert_frame_equal(a.runs, b.runs)
    pd.testing.assert_frame_equal(a.summary(), b.summary())
    c = navfdi.montecarlo(short, runs=12, seed=4, workers=2, progress=False)
    assert not a.runs["att_rms"].equals(c.runs["att_rms"])


def test_identical_on_dask_local_cluster(short):
    distributed = pytest.importorskip("dask.distributed")
    local = navfdi.montecarlo(short, runs=10, seed=9, workers=2, chunk_size=3, keep_series=[4], progress=False)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        remote = navfdi.montecarlo(short, runs=10, seed=9, client=client, chunk_size=4, keep_series=[4], progress=False)
    assert remote.backend.startswith("dask")
    pd.testing.assert_frame_equal(local.runs, remote.runs)
    np.testing.assert_array_equal(local.series[(0, 4)]["error"], remote.series[(0, 4)]["error"])


@pytest.fixture(scope="module")
def calibration():
    return navfdi.montecarlo("calibration", runs=100, seed=11, sweep={"federated.mode": ["no_reset", "reset"]}, progress=False)


def rate(summary, mode, sub, det):
    row = summary[(summary["federated.mode"] == mode) & (summary.subfilter == sub) & (summary.detector == det) & (summary.fault_id == "none")]
    assert len(row) == 1
    return row.iloc[0]


def test_chi2_false_alarm_rate_matches_pf(calibration):
    """No-reset mode, no faults: chi-square alarms on a fraction pf of the epochs (99 % interval
    of a binomial with the campaign's epoch count)."""
    s = calibration.summary()
    runs = calibration.runs
    for sub, det, pf in [("cns", "chi2", 0.1), ("gnss", "chi2", 0.001)]:
        r = rate(s, "no_reset", sub, det)
        g = runs[(runs["federated.mode"] == "no_reset") & (runs.subfilter == sub) & (runs.detector == det)]
        n = int(g.outside_epochs.sum())
        k = int(g.false_alarm_epochs.sum())
        assert n == 100 * 1000
        lo, hi = stats.binom.interval(0.99, n, pf)
        assert lo <= k <= hi, (sub, det, k / n, lo / n, hi / n)
        assert r.false_alarm_ci_low <= pf <= r.false_alarm_ci_high


def test_rates_that_are_not_pf(calibration):
    s = calibration.summary()
    # Reset mode: sub-filter covariances inflated by 1/β make chi-square conservative.
    assert rate(s, "reset", "cns", "chi2").false_alarm_ci_high < 0.1
    # The improved SPRT's alarms come in long runs (its statistic is a normalised random walk),
    # so its per-run false-alarm rate spreads far more than independent epochs would allow;
    # chi-square's spread is the binomial one. (Its mean rate over campaigns happens to be
    # near 0.1 but varies from 0.08 to 0.13 between 100-run campaigns: it is not set by pf.)
    runs = calibration.runs
    ratios = {}
    for det in ("chi2", "sprt"):
        g = runs[(runs["federated.mode"] == "no_reset") & (runs.subfilter == "cns") & (runs.detector == det)]
        per_run = g.false_alarm_epochs / g.outside_epochs
        p = per_run.mean()
        ratios[det] = per_run.std() / np.sqrt(p * (1 - p) / 1000)
    assert 0.75 < ratios["chi2"] < 1.3, ratios
    assert ratios["sprt"] > 5, ratios


@pytest.fixture(scope="module")
def slope_sweep():
    return navfdi.montecarlo(navfdi.load_scenario("yang2013").base(), runs=40, seed=2, sweep={"faults[0].magnitude": SLOPES}, progress=False).summary()


def ramp_delays(summary, det):
    g = summary[(summary.detector == det) & (summary.fault_id == "cns-ramp")]
    return g.set_index("faults[0].magnitude").loc[SLOPES, "delay_mean"].to_numpy()


def test_delay_falls_as_ramp_slope_grows(slope_sweep):
    for det in ("chi2", "sprt", "joint"):
        d = ramp_delays(slope_sweep, det)
        assert np.all(np.diff(d) < 0), (det, d)
        g = slope_sweep[(slope_sweep.detector == det) & (slope_sweep.fault_id == "cns-ramp")]
        # Every run either raised an alarm inside the ramp or was already in alarm when it began
        # (a false alarm before the fault: not counted as a detection).
        assert (g.detection_probability + g.in_alarm_at_onset >= 1.0 - 1e-12).all(), g[["detection_probability", "in_alarm_at_onset"]]


@pytest.mark.xfail(strict=True, reason="not reproduced: with pf = 0.1 chi-square's first alarm is mostly a false alarm, and the SPRT is diluted by 300 s of fault-free data (docs/montecarlo.md)")
def test_papers_claim_sprt_below_chi2_at_every_slope(slope_sweep):
    assert np.all(ramp_delays(slope_sweep, "sprt") < ramp_delays(slope_sweep, "chi2"))


def test_bad_sweeps_fail_before_anything_runs(monkeypatch):
    calls = []
    monkeypatch.setattr(mc, "_chunk", lambda *a, **k: calls.append(a))
    with pytest.raises(navfdi.ScenarioError, match=r"faults\[9\]\.magnitude"):
        navfdi.montecarlo("yang2013", runs=5, sweep={"faults[9].magnitude": ["1 sigma/s"]}, progress=False)
    with pytest.raises(navfdi.ScenarioError, match=r"faults\[0\]\.magnitude='0\.3 furlong/s'.*unknown unit"):
        navfdi.montecarlo("yang2013", runs=5, sweep={"faults[0].magnitude": ["0.1 sigma/s", "0.3 furlong/s"]}, progress=False)
    with pytest.raises(navfdi.ScenarioError, match=r"detectors\[0\]\.pf"):
        navfdi.montecarlo("yang2013", runs=5, sweep={"federated.subfilters[0].detectors[0].pf": [0.1, 1.5]}, progress=False)
    with pytest.raises(navfdi.ScenarioError, match="expected PATH=v1,v2"):
        mc.parse_sweep(["faults[0].magnitude"])
    with pytest.raises(ValueError, match="runs"):
        navfdi.montecarlo("yang2013", runs=0, progress=False)
    assert calls == []


def test_interrupted_campaign_keeps_finished_runs(short, monkeypatch, tmp_path):
    real = mc._chunk
    n = {"calls": 0}

    def flaky(*a, **k):
        n["calls"] += 1
        if n["calls"] == 3:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(mc, "_chunk", flaky)
    camp = navfdi.montecarlo(short, runs=20, seed=1, chunk_size=4, progress=False)
    assert camp.partial
    assert sorted(camp.runs.run.unique()) == list(range(8))
    camp.write(tmp_path)
    info = json.loads((tmp_path / "campaign.json").read_text())
    assert info["partial"] is True and info["runs_completed"] == {"0": 8}
    assert len(pd.read_parquet(tmp_path / "runs.parquet")) == len(camp.runs)
    assert pd.read_csv(tmp_path / "summary.csv").runs.max() == 8


def test_ctrl_c_on_the_command_line(tmp_path, sigint_child):
    out = tmp_path / "mc"
    proc = subprocess.Popen(
        [sys.executable, "-m", "navfdi", "montecarlo", "yang2013", "--runs", "5000", "--workers", "1", "--chunk-size", "4", "--out", str(out)],
        preexec_fn=sigint_child,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(6.0)  # import + a few chunks
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=120)
    assert proc.returncode == 130, stderr
    assert "PARTIAL" in stdout and "interrupted" in stderr
    info = json.loads((out / "campaign.json").read_text())
    assert info["partial"] is True and 0 < info["runs_completed"]["0"] < 5000
    runs = pd.read_parquet(out / "runs.parquet")
    assert runs.run.nunique() == info["runs_completed"]["0"]


def test_cli_summary_columns(tmp_path):
    out = tmp_path / "mc"
    proc = subprocess.run(
        [sys.executable, "-m", "navfdi", "montecarlo", "yang2013", "--runs", "6", "--sweep", "faults[1].magnitude=10 sigma,20 sigma", "--keep-series", "2", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    s = pd.read_csv(out / "summary.csv")
    for col in ["subfilter", "detector", "fault_id", "pf", "runs", "detection_probability", "delay_mean", "delay_median", "delay_p95", "false_alarm_rate", "false_alarm_ci_low", "false_alarm_ci_high", "error_rms", "faults[1].magnitude"]:
        assert col in s.columns, col
    assert len(s) == 2 * 2 * (3 * 3 + 1)  # variants × points × (CNS 3 detectors × (2 faults + none) + GNSS none)
    assert set(s["faults[1].magnitude"]) == {"10 sigma", "20 sigma"} and set(s["variant"]) == {"isolation", "no_isolation"}
    runs = pd.read_parquet(out / "runs.parquet")
    assert len(runs) == 6 * len(s)
    assert all((out / f"series_p{p}_r2.parquet").exists() for p in range(4))
    assert (out / "delay.png").exists() and (out / "rates.png").exists()
    info = json.loads((out / "campaign.json").read_text())
    assert info["seed"] == 0 and info["sweep"] == {"faults[1].magnitude": ["10 sigma", "20 sigma"]} and not info["partial"]


@pytest.mark.parametrize("seed", [0, 3, 8])
def test_campaign_metrics_agree_with_single_run_tables(seed):
    """Fault matching exists in Rust (campaign metrics) and in Python (events.csv and the
    per-fault tables of `navfdi run`); run 0 of a campaign with seed S is the same simulation
    as run_scenario(seed=S), so both must report the same detections, delays and clear delays."""
    sc = navfdi.load_scenario("yang2013").base()
    single = navfdi.run_scenario(sc, seed=seed, compare_isolation=False)
    runs = navfdi.montecarlo(sc, runs=1, seed=seed, progress=False).runs
    checked = 0
    for m in single.fault_table():
        row = runs[(runs.subfilter == m.subfilter) & (runs.detector == m.detector) & (runs.fault_id == m.fault_id)].iloc[0]
        assert bool(row.detected) == (m.detected_at is not None), m
        if m.detected_at is not None:
            assert row.delay == pytest.approx(m.delay)
            expected_clear = np.nan if m.cleared_at is None else m.cleared_at - m.fault_end
            np.testing.assert_allclose(row.clear_delay, expected_clear)
        checked += 1
    assert checked == 6  # 3 detectors × 2 faults
    np.testing.assert_allclose(runs.att_rms.iloc[0], np.sqrt(np.mean(single.error()[:, :3] ** 2)), rtol=1e-12)


def test_wilson_bounds_stay_in_the_unit_interval():
    """At 0 or n successes the Wilson bounds are 0 and 1 up to rounding, which came out as
    -0.00000 in the campaign table; they are clipped."""
    from navfdi.montecarlo import wilson

    n = np.arange(1, 200_000, 7, dtype=float)
    for k in (np.zeros_like(n), n):
        lo, hi = wilson(k, n)
        assert (lo >= 0.0).all() and (hi <= 1.0).all() and (lo <= k / n).all() and (k / n <= hi).all()
        assert not np.signbit(lo).any()
