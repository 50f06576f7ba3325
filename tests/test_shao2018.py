"""Paper 001 (shao2018): satellite FDE before the filter (least squares) vs on innovations,
over 20 seeds. Claims the simulation does not reproduce are strict xfails with the reason;
docs/shao2018.md has the numbers beside the paper's."""

from __future__ import annotations

import pytest
from scipy import stats

import navfdi

RUNS = 20
ALPHA = 0.05


@pytest.fixture(scope="module")
def summary():
    c = navfdi.montecarlo("shao2018", runs=RUNS, seed=2018)
    return c.summary().set_index(["variant", "fault_id"]), c.runs


def test_step_is_always_detected_by_the_ls_precheck(summary):
    s, _ = summary
    assert s.loc[("ls_precheck", "step60"), "detection_rate"] >= 0.99


def test_exact_identification_falls_short_only_by_the_repeated_test(summary):
    """After the faulty satellite is excluded the global test is repeated at α: it fails (and
    one more satellite goes) in about α of the epochs. So exactly-the-faulty-satellite epochs
    / faulty epochs ≈ detection · (1 − α): inside a 99 % binomial interval of it."""
    s, runs = summary
    g = runs[(runs["variant"] == "ls_precheck") & (runs["fault_id"] == "step60")]
    exact, faulty = int(g["fde_exact_epochs"].sum()), int(g["fde_faulty_epochs"].sum())
    p = s.loc[("ls_precheck", "step60"), "detection_rate"] * (1 - ALPHA)
    lo, hi = stats.binom.interval(0.99, faulty, p)
    assert lo <= exact <= hi, (exact, faulty, lo, hi)


@pytest.mark.xfail(strict=True, reason="not reproduced: with α = 0.05 and correctly modelled noise the repeated global test "
                   "excludes a second satellite in ~5 % of the faulty epochs (see the test above), so exact identification "
                   "is ~95 %, not ≥ 99 %")
def test_step_exactly_identified_in_99_percent(summary):
    _, runs = summary
    g = runs[(runs["variant"] == "ls_precheck") & (runs["fault_id"] == "step60")]
    assert g["fde_exact_epochs"].sum() / g["fde_faulty_epochs"].sum() >= 0.99


def test_detection_grows_with_ramp_slope(summary):
    s, _ = summary
    for v in ("ls_precheck", "innovation", "gnss_filter"):
        assert s.loc[(v, "ramp4"), "detection_rate"] > s.loc[(v, "ramp2"), "detection_rate"], v


def test_ls_global_test_false_alarm_rate_is_alpha(summary):
    """Outside faults the least-squares global test alarms in α of the epochs (99 % interval)."""
    _, runs = summary
    g = runs[(runs["variant"] == "ls_precheck") & (runs["fault_id"] == "none")]
    fa, n = int(g["false_alarm_epochs"].sum()), int(g["outside_epochs"].sum())
    lo, hi = stats.binom.interval(0.99, n, ALPHA)
    assert lo <= fa <= hi, (fa, n, lo, hi)


def test_fde_keeps_the_navigation_error_at_metres(summary):
    s, _ = summary
    for v in ("ls_precheck", "innovation", "gnss_filter"):
        assert s.loc[(v, "none"), "position_error_rms"] < 2.0, v
    assert s.loc[("none", "none"), "position_error_rms"] > 10.0


@pytest.mark.xfail(strict=True, reason="not reproduced: the tight filter excludes the faulty satellite before it can "
                   "follow the fault, so both placements identify equally (within ±1 point, sign varying by mode); "
                   "the paper's 100 % vs 86.36 % is not seen")
def test_ls_identifies_at_least_as_well_as_innovation_in_every_mode(summary):
    s, _ = summary
    for f in ("step60", "ramp2", "ramp4"):
        assert s.loc[("ls_precheck", f), "identification_rate"] >= s.loc[("innovation", f), "identification_rate"], f


@pytest.mark.xfail(strict=True, reason="not reproduced: no after-effect in the tight filter's innovations (the faulty "
                   "satellite never updates it once detected); after-fault alarm rates of both are ~α")
def test_innovation_has_more_after_fault_alarms(summary):
    s, _ = summary
    for f in ("step60", "ramp2", "ramp4"):
        assert s.loc[("innovation", f), "after_fault_alarm_rate"] > s.loc[("ls_precheck", f), "after_fault_alarm_rate"], f


def test_innovation_identification_is_high_in_every_mode(summary):
    """What the simulation shows instead: both placements identify the faulty satellite in
    more than 90 % of the epochs with an exclusion, in every mode."""
    s, _ = summary
    for v in ("ls_precheck", "innovation", "gnss_filter"):
        for f in ("step60", "ramp2", "ramp4"):
            assert s.loc[(v, f), "identification_rate"] > 0.9, (v, f)
