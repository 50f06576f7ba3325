"""Tight INS/GNSS on a recorded IMU and raw GNSS: the bundled ``walk_tc`` (a handheld
walk, u-blox pseudoranges and Dopplers, consumer IMU) against its must-shows — fault-free spread
below single-point positioning's with no exclusion, a 20 m step on a high and a low satellite
excluded with the position held, an outage bridged, the outputs of a tight run, a campaign with
drawn satellites — and the clear errors of bad configurations."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import navfdi
from navfdi import ScenarioError, logs

R_EARTH = 6.371e6


@pytest.fixture(scope="module")
def clean() -> navfdi.Scenario:
    return navfdi.load_scenario("walk_tc").with_value("faults", [])


@pytest.fixture(scope="module")
def fault_free(clean) -> dict[str, dict]:
    src = logs.logged_source(clean)
    return {name: src.run([v.to_json()])[0] for name, v in clean.variants()}


def _runs(sc: navfdi.Scenario) -> dict[str, dict]:
    src = logs.logged_source(sc)
    return {name: src.run([v.to_json()])[0] for name, v in sc.variants()}


def _moved(r: dict, r0: dict) -> np.ndarray:
    a, b = r["nav"], r0["nav"]
    return np.hypot((a[:, 0] - b[:, 0]) * R_EARTH, (a[:, 1] - b[:, 1]) * R_EARTH * np.cos(b[:, 0]))


def _spread(en: np.ndarray) -> float:
    d = en - en.mean(axis=0)
    return float(np.sqrt(np.mean(d[:, 0] ** 2 + d[:, 1] ** 2)))


def test_fault_free_spread_beats_single_point_and_nothing_is_excluded(clean, fault_free) -> None:
    folder = logs.scenario_folder(clean)
    src = clean.raw["source"]
    ref = logs.read_pos(folder / src["reference"])
    # The σ model as given (elevation weights, factor 1), then the best SPP setting below.
    spp = navfdi.gnss_solve(str(folder / src["rinex_obs"]), str(folder / src["rinex_nav"]), systems="G,E", weighting="elevation", noise_scale=1.0).solution
    t0 = logs.logged_source(clean).time0
    r = fault_free["innovation"]
    e, ok = r["error"], np.isfinite(r["error"][:, 6])
    assert ok.sum() > 450
    # Single-point fixes against the reference at the same epochs (ms apart), offset removed too.
    ts = spp["gps_seconds"].to_numpy(float)
    k = np.clip(np.searchsorted(ref.t, ts - 0.005), 0, len(ref.t) - 1)
    same = (np.abs(ref.t[k] - ts) < 0.005) & np.isin(np.round(ts - t0, 2), np.round(r["t"][ok], 2))
    en_spp = np.column_stack([
        np.radians(spp["lon"].to_numpy(float) - ref.lon[k]) * R_EARTH * np.cos(np.radians(ref.lat[k])),
        np.radians(spp["lat"].to_numpy(float) - ref.lat[k]) * R_EARTH,
    ])[same]
    assert len(en_spp) == ok.sum()
    tight, single = _spread(e[ok, 6:8]), _spread(en_spp)
    assert tight < 0.6 * single, (tight, single)
    # Also below the single-point solution with C/N0 weighting (the best SPP setting here).
    cn0 = navfdi.gnss_solve(str(folder / src["rinex_obs"]), str(folder / src["rinex_nav"]), systems="G,E", weighting="cn0", noise_scale="auto").solution
    assert np.allclose(cn0["gps_seconds"], spp["gps_seconds"])
    en_cn0 = np.column_stack([
        np.radians(cn0["lon"].to_numpy(float) - ref.lon[k]) * R_EARTH * np.cos(np.radians(ref.lat[k])),
        np.radians(cn0["lat"].to_numpy(float) - ref.lat[k]) * R_EARTH,
    ])[same]
    assert tight < _spread(en_cn0) < single
    # The reference's own offset (its base): several metres east and north, the same for both.
    assert 4.0 < e[ok, 6].mean() < 9.0 and 3.0 < e[ok, 7].mean() < 7.0
    alpha = clean.core["tight"]["alpha"]
    for name, rec in fault_free.items():
        sat = rec["satellites"]
        measured = np.asarray(sat["status"]) != sat["status_names"].index("no_measurement")
        excluded = np.asarray(sat["excluded"]).any(axis=1)[measured]
        assert excluded.mean() <= alpha, (name, excluded.sum())


@pytest.mark.parametrize("sat, hurt", [("E26", 5.0), ("G27", 1.0)])  # elevation about 80° and 32°
def test_step_on_one_satellite_is_excluded_and_the_position_held(clean, fault_free, sat, hurt) -> None:
    f = {"id": "step", "sensor": "gnss", "satellite": sat, "components": ["pseudorange"], "kind": "step",
         "magnitude": "20 m", "start": "50 s", "end": "90 s"}
    runs = _runs(clean.with_value("faults", [f]))
    for name, r in runs.items():
        t = r["t"]
        w = (t >= 50) & (t < 90)
        s = r["satellites"]
        j = s["names"].index(sat)
        ex = np.asarray(s["excluded"])
        fw = w & np.asarray(s["in_view"])[:, j]
        exact = (ex[fw, j] & (ex[fw].sum(axis=1) == 1)).mean()
        move = np.nanmax(_moved(r, fault_free[name])[w])
        if name == "none":
            assert exact == 0.0 and move > hurt, (name, move)
        else:
            assert exact >= 0.95, (name, exact)
            assert move <= 1.0, (name, move)
    # Scored as paper 001's table: every exclusion in the fault is the faulty satellite.
    m = next(m for m in runs["innovation"]["satellites"]["metrics"] if m["fault"] == 0)
    assert m["exact_epochs"] == m["exclusion_epochs"] > 0


def test_a_ten_second_outage_is_bridged(clean, fault_free) -> None:
    sc = clean.with_value("sensors[0].outages", [["60 s", "70 s"]], create=True)
    r = _runs(sc)["innovation"]
    d = _moved(r, fault_free["innovation"])
    t = r["t"]
    inside = (t >= 60) & (t < 70)
    assert np.isfinite(r["nav"][inside, 0]).all()  # the INS navigates through it
    assert np.asarray(r["satellites"]["used"])[inside].sum() == 0
    assert d[np.searchsorted(t, 72.0)] < 1.0
    assert d[inside].max() > d[np.searchsorted(t, 72.0)]


def test_run_writes_the_tight_outputs(tmp_path: Path) -> None:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = navfdi.run_scenario("walk_tc")
        paths = res.write(tmp_path)
    names = {p.name for p in paths}
    assert {"satellites.csv", "identified_satellites.png", "innovation_track.png", "report.html"} <= names
    ts = pd.read_parquet(tmp_path / "timeseries.parquet")
    for c in ("variant", "time", "lat", "lon", "height", "sat.G27.w", "sat.G27.excluded", "sat.G27.in_view", "fde.status"):
        assert c in ts.columns, c
    inn = ts[ts["variant"] == "innovation"]
    fault = (inn["time"] >= 50) & (inn["time"] < 90)
    assert inn.loc[fault, "sat.G27.excluded"].mean() > 0.9 and not inn.loc[~fault, "sat.G27.excluded"].any()
    assert 40.09 < np.nanmedian(inn["lat"]) < 40.10 and -105.15 < np.nanmedian(inn["lon"]) < -105.14
    errors = pd.read_csv(tmp_path / "errors.csv")
    assert {"hor_rel_rms_m", "offset_e_m", "hor_rms_m"} <= set(errors.columns)
    row = errors[errors["variant"] == "innovation"].iloc[0]
    assert row["hor_rel_rms_m"] < 0.2 * row["hor_rms_m"]
    sats = pd.read_csv(tmp_path / "satellites.csv")
    assert set(sats["variant"]) == {"innovation", "ls_precheck", "none"}


def test_campaign_draws_satellite_start_and_size() -> None:
    c = navfdi.montecarlo("walk_tc", runs=8, seed=3, progress=False)
    r = c.runs[(c.runs["fault_id"] == "sat_fault") & (c.runs["variant"] == "innovation")]
    drawn = set(navfdi.load_scenario("walk_tc").faults()[0]["draw"]["satellites"])
    assert set(r["fault_satellite"]) <= drawn and r["fault_satellite"].nunique() > 1
    assert r["fault_start"].between(15, 90).all()
    steps = r[r["fault_kind"] == "step"]["fault_magnitude"]
    assert steps.between(10, 40).all()
    s = c.summary()
    inn = s[(s["variant"] == "innovation") & (s["fault_id"] == "sat_fault")].iloc[0]
    none = s[(s["variant"] == "none") & (s["fault_id"] == "sat_fault")].iloc[0]
    assert inn["detection_rate"] > 0.6 and inn["identification_rate"] > 0.9 and none["detection_rate"] == 0
    assert inn["fault_horizontal_error_max_offset_removed_mean"] < none["fault_horizontal_error_max_offset_removed_mean"]


@pytest.mark.parametrize(
    "values, match",
    [
        ({"faults[0].satellite": "G05"}, r"faults\[0\]\.satellite: \"G05\" is never in view.*in view: G10"),
        ({"faults[0].satellite": "X99"}, r"faults\[0\]\.satellite.*not a satellite name"),
        ({"tight.fde": "gnss_filter"}, r"tight\.fde: gnss_filter is not available on recorded logs"),
        ({"tight.strapdown.imu.gyro_scale": "1000 ppm"}, r"tight\.strapdown\.imu.*scale-factor"),
        ({"sensors[0].ranges.cn0_reference": "90 dB-Hz"}, r"cn0_reference.*\(10, 70\)"),
        ({"source.rinex_obs": "missing.obs"}, r"source\.rinex_obs: .*missing\.obs: no such file"),
        ({"duration": "140 s"}, r"duration = 140 s.*spans 133\.75 s"),
    ],
)
def test_bad_configurations_are_named(values, match) -> None:
    sc = navfdi.load_scenario("walk_tc")
    with pytest.raises(ScenarioError, match=match):
        logs.logged_source(sc.with_values(values, create=True))


def test_simulated_ranges_refuse_cn0_weighting() -> None:
    with pytest.raises(ScenarioError, match="cn0_reference.*recorded C/N0"):
        navfdi.load_scenario("shao2018").with_value("sensors[0].ranges.cn0_reference", "45 dB-Hz", create=True)
