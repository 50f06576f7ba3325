"""Per-satellite Gauss-Markov range-error states in the strapdown tight filter
(``[tight] range_states``): estimated from the recorded log's own snapshot residuals, they let
the filter's protection levels hold on the walk without inflating σ, and keep the innovation
FDE's sensitivity; bad settings are refused by name."""

from __future__ import annotations

import math

import pytest

from navfdi import logs
from navfdi.runs import run_scenario
from navfdi.scenario import ScenarioError, load_scenario


@pytest.fixture(scope="module")
def walk_gm():
    return load_scenario("walk_tc").with_values({"tight.integrity": {}, "tight.range_states": "auto"}, create=True)


def test_the_model_is_estimated_from_the_logs_residuals(walk_gm):
    """The fit of ρ(L) = a exp(−L Δt/τ) to the walk's normalised snapshot residuals: a
    correlated share and a correlation time of seconds (the receiver's 4 Hz epochs), and the
    fitted curve passes near the measured lag-1 correlation."""
    a, tau, d = logs.range_error_process(walk_gm)
    assert 0.2 < a < 0.95 and 1.0 < tau < 60.0, (a, tau)
    assert d["dt"] == pytest.approx(0.25) and d["arcs"] >= 8 and d["lags"] >= 5
    assert abs(a * math.exp(-d["dt"] / tau) - d["rho1"]) < 0.2
    resolved = logs.resolve_range_errors(walk_gm)
    rs = resolved.core["tight"]["range_states"]
    assert rs["fraction"] == pytest.approx(a, abs=1e-4) and rs["tau"] == pytest.approx(tau, rel=1e-3)


def test_walk_levels_hold_without_inflating_sigma_and_fde_keeps_its_power(walk_gm):
    """Fault-free, the separation test does not alarm (97 % of the epochs with white errors)
    and no error leaves the levels, with the pseudorange σ as given (0.7 m; the overbound
    multiplies it by 4.8); with the bundled 20 m step on G27 the innovation placement excludes
    it at least as often as the white filter does (the overbound: never)."""
    clean = run_scenario(walk_gm.with_values({"faults": []}), seed=0)
    for name, run in clean.runs.items():
        assert run.scenario.core["sensors"][0]["noise"][0] == pytest.approx(0.7)
        assert run.scenario.core["tight"]["range_states"] is not None
        i = run.integrity()
        assert i["alarm_rate_before_faults"] == 0.0, name
        assert i["misleading_h"] == 0 and i["misleading_v"] == 0, name
    white = run_scenario(load_scenario("walk_tc"), seed=0).satellite_table()
    gm = run_scenario(walk_gm, seed=0)
    t = gm.satellite_table()
    for variant in ("innovation", "ls_precheck"):
        got = t[(t.variant == variant) & (t.fault_id == "sat_fault")].iloc[0]
        ref = white[(white.variant == variant) & (white.fault_id == "sat_fault")].iloc[0]
        assert got["detection_rate"] >= ref["detection_rate"] and got["detection_rate"] > 0.9, variant
        assert got["identification_rate"] == 1.0
    assert "range-error states" in gm.format_tables()


@pytest.mark.parametrize("value, message", [
    ("pink", "use 'white', 'auto'"),
    ({"fraction": 1.2, "tau": "5 s"}, "fraction = 1.2"),
    ({"fraction": 0.5}, "tau"),
    ({"fraction": 0.5, "tau": "5 s", "sigma": 1}, "sigma"),
    ({"fraction": 0.5, "tau": "-5 s"}, "tau"),
])
def test_bad_settings_are_refused_by_name(value, message):
    with pytest.raises(ScenarioError, match=message):
        load_scenario("walk_tc").with_values({"tight.range_states": value}, create=True)


def test_one_correlation_model_at_a_time_and_only_in_the_strapdown_filter():
    with pytest.raises(ScenarioError, match="keep one"):
        load_scenario("walk_tc").with_values({"tight.integrity": {"range_errors": 4.0}, "tight.range_states": {"fraction": 0.5, "tau": "5 s"}}, create=True)
    with pytest.raises(ScenarioError, match="strapdown tight filter on IMU and range logs"):
        load_scenario("shao2018").with_values({"tight.range_states": "auto"}, create=True)
    # "auto" unresolved never reaches the filter.
    with pytest.raises(ScenarioError, match="estimated from the log before the run"):
        logs.logged_source(load_scenario("walk_tc").with_values({"tight.range_states": "auto"}, create=True))


def test_variants_asking_for_the_states_get_the_estimate_or_a_refusal():
    """A variant that sets ``tight.range_states = "auto"`` runs with the log's estimate (not
    silently white); one that hides "auto" inside a whole table is refused by name."""
    sc = load_scenario("walk_tc").with_values({"faults": [], "variants": [{"name": "white", "set": {}}, {"name": "gm", "set": {"tight.range_states": "auto"}}]})
    resolved = logs.resolve_range_errors(sc)
    got = {n: v.core["tight"]["range_states"] for n, v in resolved.variants()}
    a, tau, _ = logs.range_error_process(sc)
    assert got["white"] is None
    assert got["gm"]["fraction"] == pytest.approx(a, abs=1e-4) and got["gm"]["tau"] == pytest.approx(tau, rel=1e-3)
    hidden = load_scenario("walk_tc").with_values({"variants": [{"name": "gm", "set": {"tight": {**sc.raw["tight"], "range_states": "auto"}}}]})
    with pytest.raises(ScenarioError, match="variant 'gm'"):
        logs.resolve_range_errors(hidden)


@pytest.mark.parametrize("sat", ["G27", "E33"])
def test_a_ramp_the_states_would_take_in_is_excluded_as_often_as_with_white_noise(sat):
    """A 1 m/s ramp looks like a correlated range error: without the check of the estimate
    against its own model the states took it in (about half of a campaign's ramp epochs went
    unexcluded). With it the innovation placement excludes the ramp at least as often as the
    white filter does, and does not hold the satellite after the ramp."""
    vals = {"faults[0].satellite": sat, "faults[0].kind": "ramp", "faults[0].magnitude": "1 m/s", "faults[0].start": "40 s", "faults[0].end": "80 s"}
    white = run_scenario(load_scenario("walk_tc").with_values(vals, create=True), seed=0).satellite_table()
    gm = run_scenario(load_scenario("walk_tc").with_values({**vals, "tight.range_states": "auto"}, create=True), seed=0).satellite_table()
    pick = lambda t: t[(t.variant == "innovation") & (t.fault_id == "sat_fault")].iloc[0]  # noqa: E731
    assert pick(gm)["detection_rate"] >= pick(white)["detection_rate"] > 0.6
    assert pick(gm)["identification_rate"] == 1.0
    assert pick(gm)["after_fault_alarm_rate"] <= 0.1
