"""Paper 000 (yang2013) end to end over a fixed set of seeds; the issue's must-show list.

Paper's delays: chi-square 23 s on the ramp and 0 s on the step; SPRT 3–6 s on the ramp and
the step missed; joint 3–6 s and 0 s. What navfdi reproduces, and why not the rest, is in
docs/yang2013.md.
"""

from __future__ import annotations

import numpy as np
import pytest

import navfdi
from navfdi._intervals import alarm_intervals

SEEDS = range(10)


@pytest.fixture(scope="module")
def runs():
    sc = navfdi.load_scenario("yang2013").base()
    return [navfdi.run_scenario(sc, seed=s) for s in SEEDS]


def lasting_from(run, det, t_last):
    """Start of the alarm interval still raised at t_last (None if not in alarm)."""
    for iv in alarm_intervals(run.detector("cns", det)["alarm"], run.t):
        if iv.start <= t_last and (iv.end is None or iv.end > t_last):
            return iv.start
    return None


def test_sprt_without_reset_never_sees_the_step(runs):
    for r in runs:
        sprt = r.detector("cns", "sprt")["alarm"]
        assert sprt[799] and sprt[800], r.seed  # still in alarm from the ramp
        starts = [iv.start for iv in alarm_intervals(sprt, r.t)]
        assert not any(800 <= s <= 850 for s in starts), r.seed  # no new alarm for the step
        row = next(m for m in r.fault_table() if m.fault_id == "cns-step" and m.detector == "sprt")
        assert row.detected_at is None and "in alarm since" in row.note


def test_joint_detects_both_faults_and_clears(runs):
    for r in runs:
        joint = r.detector("cns", "joint")["alarm"]
        t = r.t
        # Ramp: a lasting alarm before the end of the ramp, cleared within 5 s of 500 s.
        assert lasting_from(r, "joint", 499.0) is not None, r.seed
        assert not joint[(t >= 500) & (t <= 505)].all(), r.seed
        end = next(iv.end for iv in alarm_intervals(joint, t) if iv.start <= 499 < (iv.end or np.inf))
        assert end is not None and 500 <= end <= 505, (r.seed, end)
        # Step: in alarm within 1 s of 800 s, cleared within 5 s of 850 s.
        assert joint[800] or joint[801], r.seed
        end = next(iv.end for iv in alarm_intervals(joint, t) if iv.start <= 849 < (iv.end or np.inf))
        assert end is not None and 850 <= end <= 855, (r.seed, end)
        # Each fault is detected (an alarm raised inside its window), or the joint detector was
        # already in alarm when it began (pf = 0.1: a false alarm just before; reported as such,
        # not as a detection) and stays in alarm through it.
        rows = {m.fault_id: m for m in r.fault_table() if m.detector == "joint"}
        for fid in ("cns-ramp", "cns-step"):
            m = rows[fid]
            assert m.detected_at is not None or (m.in_alarm_at_onset and m.alarm_fraction > 0.9), (r.seed, m)
            assert (m.detected_at is None) == m.note.startswith("missed"), m


def test_chi2_lasting_alarm_matches_papers_delay(runs):
    """Chi-square's lasting ramp alarm starts 10–35 s into the ramp (paper: 23 s)."""
    delays = [lasting_from(r, "chi2", 499.0) - 300.0 for r in runs]
    assert all(10 <= d <= 35 for d in delays), delays
    assert 15 <= np.median(delays) <= 28


def test_joint_lasting_alarm_no_later_than_chi2():
    """Over 30 seeds the joint detector's lasting ramp alarm starts no later than chi-square's
    in most runs (measured: 28 of 30); it is never much later."""
    sc = navfdi.load_scenario("yang2013").base()
    diffs = []
    for s in range(30):
        r = navfdi.run_scenario(sc, seed=s, compare_isolation=False)
        diffs.append(lasting_from(r, "joint", 499.0) - lasting_from(r, "chi2", 499.0))
    diffs = np.array(diffs)
    assert (diffs <= 0).mean() >= 0.8, diffs
    assert diffs.max() <= 5, diffs


@pytest.mark.xfail(strict=True, reason="not reproduced: the SPRT of METHODS §3 accumulates from the run start, so 300 s of fault-free data dilute the ramp (see docs/yang2013.md)")
def test_papers_claim_sprt_finds_ramp_well_before_chi2():
    sc = navfdi.load_scenario("yang2013").base()
    sprt, chi2 = [], []
    for s in range(30):
        r = navfdi.run_scenario(sc, seed=s, compare_isolation=False)
        sprt.append(lasting_from(r, "sprt", 499.0))
        chi2.append(lasting_from(r, "chi2", 499.0))
    # Paper: SPRT 305 s vs chi-square 323 s.
    assert np.median(sprt) <= np.median(chi2) - 10


def test_isolation_reduces_master_attitude_error(runs):
    for r in runs:
        with_iso = r.attitude_rms(*r.error_window(), isolation=True)
        without = r.attitude_rms(*r.error_window(), isolation=False)
        assert with_iso < 0.2 * without, (r.seed, with_iso, without)
        # The CNS sub-filter is isolated during both faults (the joint detector decides).
        iso = r.isolated("cns")
        assert iso[(r.t >= 330) & (r.t < 500)].all() and iso[(r.t >= 801) & (r.t < 850)].all()


def test_runs_are_deterministic_in_the_seed():
    sc = navfdi.load_scenario("yang2013").base()
    a, b, c = navfdi.run_scenario(sc, 5), navfdi.run_scenario(sc, 5), navfdi.run_scenario(sc, 6)
    np.testing.assert_array_equal(a.error(), b.error())
    np.testing.assert_array_equal(a.detector("cns", "joint")["statistic"], b.detector("cns", "joint")["statistic"])
    assert not np.array_equal(a.error(), c.error())


def test_cli_run_writes_outputs(tmp_path):
    import json
    import subprocess
    import sys

    import pandas as pd

    out = tmp_path / "out"
    proc = subprocess.run([sys.executable, "-m", "navfdi", "run", "yang2013", "--seed", "3", "--out", str(out)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "fault cns-ramp on cns" in proc.stdout and "fault cns-step on cns" in proc.stdout
    assert "master attitude error RMS over 300–999 s (first fault to end of run), arcsec: isolation" in proc.stdout
    ev = pd.read_csv(out / "events.csv")
    assert list(ev.columns) == ["variant", "subfilter", "detector", "alarm_start_s", "alarm_end_s", "tests", "fault_id", "fault_start_s", "fault_end_s", "delay_s"]
    assert set(ev.variant) == {"isolation", "no_isolation"}
    step = ev[(ev.variant == "isolation") & (ev.detector == "joint") & (ev.fault_id == "cns-step")]
    assert len(step) >= 1 and step.delay_s.min() <= 1
    ts = pd.read_parquet(out / "timeseries.parquet")
    assert len(ts) == 2 * 1000
    for col in ["variant", "t", "cns.joint.statistic", "cns.joint.threshold", "cns.joint.alarm", "cns.isolated", "error.att_e", "sigma.att_e"]:
        assert col in ts.columns, col
    assert not ts[ts.variant == "no_isolation"]["cns.isolated"].any() and ts[ts.variant == "isolation"]["cns.isolated"].any()
    err = pd.read_csv(out / "errors.csv")
    assert list(err.variant) == ["isolation", "no_isolation"] and (err.att_e_rms_rad.iloc[0] < err.att_e_rms_rad.iloc[1])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["seed"] == 3 and summary["scenario"]["name"] == "yang2013" and "navfdi" in summary["versions"]
    assert set(summary["variants"]) == {"isolation", "no_isolation"}
    pngs = sorted(p.name for p in out.glob("*.png"))
    for v in ("isolation", "no_isolation"):
        for f in ["detector_cns_chi2.png", "detector_cns_joint.png", "detector_cns_sprt.png", "master_attitude_error.png"]:
            assert f"{v}_{f}" in pngs
    assert "variant_errors.png" in pngs


def test_with_and_without_isolation_as_variants_keeps_the_numbers():
    """yang2013's comparison is two variants now; each equals the former run with isolation and
    its no-isolation baseline, bit for bit."""
    sc = navfdi.load_scenario("yang2013")
    assert sc.variant_names() == ["isolation", "no_isolation"]
    for seed in (0, 4):
        v = navfdi.run_scenario(sc, seed=seed)
        old = navfdi.run_scenario(sc.base(), seed=seed, compare_isolation=True)
        np.testing.assert_array_equal(v["isolation"].record["error"], old.record["error"])
        np.testing.assert_array_equal(v["no_isolation"].record["error"], old.baseline["error"])
        for a, b in zip(v["no_isolation"].record["subfilters"], old.baseline["subfilters"]):
            for da, db in zip(a["detectors"], b["detectors"]):
                np.testing.assert_array_equal(da["alarm"], db["alarm"])


def test_cli_run_reports_bad_scenario(tmp_path):
    import subprocess
    import sys

    f = tmp_path / "s.toml"
    text = (navfdi.scenario.resources.files("navfdi") / "scenarios" / "yang2013.toml").read_text(encoding="utf-8")
    bad = text.replace('id = "cns-ramp"\nsensor = "cns"', 'id = "cns-ramp"\nsensor = "cnss"')
    assert bad != text
    f.write_text(bad, encoding="utf-8")
    proc = subprocess.run([sys.executable, "-m", "navfdi", "run", str(f)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 2
    assert "faults[0].sensor = 'cnss'" in proc.stderr and "Traceback" not in proc.stderr


def test_isolated_update_mode_absorbs_the_ramp():
    """With isolated = "update" (METHODS §5 read literally) the isolated CNS sub-filter absorbs
    the ramp, and its joint alarm outlasts the ramp by minutes instead of clearing at 500 s."""
    raw = navfdi.load_scenario("yang2013").base().raw
    import copy

    raw = copy.deepcopy(raw)
    raw["federated"]["isolated"] = "update"
    r = navfdi.run_scenario(navfdi.load_scenario(raw), seed=1, compare_isolation=False)
    joint = r.detector("cns", "joint")["alarm"]
    end = next(iv.end for iv in alarm_intervals(joint, r.t) if iv.start <= 499 < (iv.end or np.inf))
    assert end is None or end > 560
