"""Tested epochs are the unit: per-test rates, alarm intervals and figures on records whose
sensors are slower than the record (the metrics engine's rule, navfdi_core::metrics)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import navfdi
from navfdi._bundled import bundled_scenarios
from navfdi.plots import detector_figures


def _campaign_rates(sc, runs):
    camp = navfdi.montecarlo(sc, runs=runs, seed=3, workers=2, progress=False)
    s = camp.summary()
    return s[s["fault_id"] == "none"].set_index(["subfilter", "detector"])


def test_a_multirate_record_gives_the_single_rate_per_test_rates():
    """The calibration flight at dt = 1 s and at dt = 0.1 s with the same 1 Hz sensors: the
    chi-square tests' false-alarm rates per test agree between the two and with pf, not
    pf / 10. (Chi-square only: its tests are independent, so the binomial interval is
    right; the SPRT's statistic is a random walk whose epochs are strongly correlated within
    a run, and its pooled interval says nothing.)"""
    base = navfdi.load_scenario("calibration")
    fast = base.with_value("dt", "0.1 s")
    runs = 40
    slow_rates = _campaign_rates(base, runs)
    fast_rates = _campaign_rates(fast, runs)
    for key in [("cns", "chi2"), ("gnss", "chi2")]:
        a, b = slow_rates.loc[key], fast_rates.loc[key]
        # Rates per test: the 10 Hz record's untested epochs are not in the denominator.
        lo = max(a["false_alarm_ci_low"], b["false_alarm_ci_low"])
        hi = min(a["false_alarm_ci_high"], b["false_alarm_ci_high"])
        assert lo <= hi, f"{key}: per-test rates differ: {a['false_alarm_rate']:.4f} at 1 Hz, {b['false_alarm_rate']:.4f} at 10 Hz"
    # chi-square holds its pf per test (not pf / 10) on the 10 Hz record.
    cns = fast_rates.loc[("cns", "chi2")]
    assert cns["false_alarm_ci_low"] <= 0.1 <= cns["false_alarm_ci_high"], cns["false_alarm_rate"]


def test_a_multirate_campaign_counts_tests_not_record_epochs():
    fast = navfdi.load_scenario("calibration").with_value("dt", "0.1 s")
    camp = navfdi.montecarlo(fast, runs=2, seed=1, workers=1, progress=False)
    df = camp.runs
    row = df[(df["subfilter"] == "cns") & (df["detector"] == "chi2") & (df["fault_id"] == "none")]
    # 1000 s of 1 Hz tests (the first epoch has no measurement), not 10 000 record epochs.
    assert set(row["outside_epochs"]) <= {1000, 999}, set(row["outside_epochs"])


def test_a_ramp_on_the_drive_is_one_alarm_interval_in_alarm_at_every_test():
    """drive_lc's 1 Hz GNSS on its 4 Hz record, a 2 m/s ramp over 200-260 s: one alarm
    interval for the whole fault per detector (not one per test), in alarm at >= 95 % of
    its tests, cleared at the first passing test."""
    sc = navfdi.load_scenario("drive_lc").with_values({
        "faults[0].kind": "ramp", "faults[0].magnitude": "2 m/s",
        "faults[0].start": "200 s", "faults[0].end": "260 s",
    })
    r = navfdi.run_scenario(sc).runs["fde"]
    ev = r.events()
    mine = ev[(ev["subfilter"] == "gnss_pos") & (ev["fault_id"] == "gnss_fault")]
    for det in ("chi2", "exclude"):
        rows = mine[mine["detector"] == det]
        assert len(rows) == 1, rows
        assert rows["tests"].iloc[0] >= 57  # 1 Hz tests in a 60 s window
    for m in r.fault_table():
        if m.subfilter == "gnss_pos":
            assert m.alarm_fraction >= 0.95, (m.detector, m.alarm_fraction)
            assert m.cleared_at is not None and m.cleared_at >= 260.0


def _figure_runs():
    for name in sorted(bundled_scenarios()):
        out = navfdi.run_scenario(name, seed=1)
        runs = out.runs if hasattr(out, "runs") else {None: out}
        for variant, r in runs.items():
            yield name, variant, r


def test_every_detector_figure_of_every_bundled_scenario_draws_its_statistic_and_threshold():
    """Read the figure data (matplotlib lines), not the pixels: the statistic and the
    threshold lines hold finite points at the detector's tests."""
    import matplotlib.pyplot as plt

    seen = 0
    for name, variant, r in _figure_runs():
        for fname, fig in detector_figures(r, f"{variant}_" if variant else ""):
            try:
                ax = fig.axes[0]
                lines = {ln.get_label(): ln for ln in ax.get_lines()}
                where = f"{name}/{variant}/{fname}"
                assert "statistic" in lines and "threshold" in lines, where
                y = np.asarray(lines["statistic"].get_ydata(), float)
                th = np.asarray(lines["threshold"].get_ydata(), float)
                assert np.isfinite(y).sum() >= 2 and np.isfinite(th).sum() >= 2, where
                # Consecutive finite points exist, so a line is drawn (not isolated dots).
                ok = np.isfinite(y)
                assert (ok[1:] & ok[:-1]).any(), where
                seen += 1
            finally:
                plt.close(fig)
    assert seen >= 20


def test_a_detector_that_never_tested_says_so():
    import matplotlib.pyplot as plt

    from navfdi.plots import _statistic_axes

    fig, ax = plt.subplots()
    t = np.arange(5.0)
    _statistic_axes(ax, t, {"statistic": np.full(5, np.nan), "threshold": np.full(5, np.nan), "alarm": np.zeros(5, bool)}, [])
    assert any("no test" in txt.get_text() for txt in ax.texts)
    plt.close(fig)


@pytest.mark.parametrize("held", [False, True])
def test_alarm_intervals_over_tests(held):
    t = np.arange(24) * 0.25
    tested = np.arange(24) % 4 == 0
    alarm = ((np.arange(24) >= 8) & (np.arange(24) < 20)) & (held | tested)
    [iv] = navfdi.alarm_intervals(alarm, t, tested)
    assert (iv.start, iv.end, iv.tests) == (2.0, 5.0, 3)
    # Without `tested` every epoch counts: the 1 Hz alarm splits into one interval per test.
    assert len(navfdi.alarm_intervals(alarm, t)) == (1 if held else 3)
    with pytest.raises(ValueError, match="tested"):
        navfdi.alarm_intervals(alarm, t, tested[:-1])
    assert math.isclose(navfdi._intervals.window_alarm(alarm, t, 2.0, 5.0, tested)[1], 1.0)


def test_a_logged_run_without_a_reference_speaks_for_itself():
    """drive_lc without its reference: the console has the filter's own consistency (per
    channel λ/m, alarm rates against pf, whiteness, biases, heading against course), says
    "no reference", and holds no "nan" anywhere."""
    import copy
    from importlib import resources

    from navfdi.scenario import from_dict

    raw = copy.deepcopy(navfdi.load_scenario("drive_lc").raw)
    del raw["source"]["reference"]
    raw["source"].pop("reference_quality", None)
    sc = from_dict(raw, source=str(resources.files("navfdi") / "scenarios" / "drive_lc_noref.toml"))
    runs = navfdi.run_scenario(sc)
    text = runs.format_tables()
    assert "nan" not in text.lower(), [ln for ln in text.splitlines() if "nan" in ln.lower()]
    assert "no reference" in text
    assert "filter consistency" in text and "gnss_pos/exclude" in text and "lag-1" in text
    c = runs.runs["fde"].summary()["consistency"]
    pos = c["channels"]["gnss_pos"]
    assert pos["tests"] > 400 and 0 < pos["mean_nis"] < 10 and abs(pos["lag1"]) < 1
    assert 0 < c["biases"]["gyro_bias_z"]["reduction"] < 1
    assert c["heading"]["median_deg"] < 2 and c["converged_at"] >= c["navigating_from"]


@pytest.mark.parametrize("size, gross", [("1 m", False), ("20 m", True)])
def test_before_convergence_only_gross_innovations_exclude(size, gross):
    """[loosely_coupled] convergence: until the filter has settled, an alarm excludes only a
    gross innovation (λ over 16 times the deciding threshold). A filter that never counts as
    converged (convergence = 1e-6) lets a 1 m step on drive_lc's 2 cm RTK positions in
    (λ up to 209 on 3 dof: over the 58 threshold, under 16 × 58) and still excludes a 20 m one;
    converged from the start (0), both are excluded."""
    base = navfdi.load_scenario("drive_lc").with_value("faults[0].magnitude", size)

    def excluded(conv):
        r = navfdi.run_scenario(base.with_value("loosely_coupled.convergence", conv, create=True)).runs["fde"]
        iso = np.asarray(r.isolated("gnss_pos"), bool)
        win = (r.t >= 440) & (r.t < 500)
        return iso[win].any(), r.record.get("converged_at")

    never, at_never = excluded(1e-6)
    always, at_always = excluded(0.0)
    assert at_never is None and at_always is not None
    assert always
    assert never == gross


@pytest.mark.parametrize("bad", [-1.0, float("nan"), 1e9, "abc"])
def test_convergence_is_validated(bad):
    with pytest.raises(ValueError, match="convergence"):
        navfdi.run_scenario(navfdi.load_scenario("drive_lc").with_value("loosely_coupled.convergence", bad, create=True))
