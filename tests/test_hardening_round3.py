"""Hardening, round 3: integrity inputs, time tags, partial logs, unbounded reads and names.
One test per class of input with the reported inputs and more of the same class; what each
input gets is in docs/hardening.md."""

from __future__ import annotations

import gzip
import math
import shutil
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi.cli import main

DATA = Path(__file__).parent / "data" / "rinex"
OBS = DATA / "rover.obs.gz"
NAV = DATA / "base.nav"


# ---- 1. integrity objects: values that would make the levels vanish ---------------------------


@pytest.mark.parametrize(
    "kw, field",
    [
        ({"b_nom": math.nan}, "b_nom"),
        ({"p_sat": math.nan}, "p_sat"),
        ({"p_sat": -1e-5}, "p_sat"),
        ({"p_const": {"G": math.nan}}, "p_const"),
        ({"p_const": {"G": 1.0}}, "p_const"),
        ({"sigma_ura": math.inf}, "sigma_ura"),
        ({"sigma_ure": -0.5}, "sigma_ure"),
        ({"b_nom": [0.5, math.nan]}, "b_nom"),
        ({"p_sat": True}, "p_sat"),
        ({"p_const": {}}, "p_const"),
        ({"sigma_ura": "abc"}, "sigma_ura"),
    ],
)
def test_an_ism_refuses_what_would_make_its_levels_vanish(kw, field):
    with pytest.raises(ValueError, match=f"Ism.{field}"):
        navfdi.Ism(**kw)


@pytest.mark.parametrize("i, value", [(0, math.nan), (1, -1e-9), (3, 1.0), (5, math.inf), (2, 0.0)])
def test_an_allocation_refuses_non_probabilities(i, value):
    args = [9.8e-8, 2e-9, 3.9e-6, 9e-8, 8e-8, 1e-5]
    args[i] = value
    with pytest.raises(ValueError, match="Allocation"):
        navfdi.Allocation(*args)
    for kw in ({"hal": math.nan}, {"val": -1.0}, {"tol_pl": 11.0}):
        with pytest.raises(ValueError, match="Allocation"):
            navfdi.Allocation(9.8e-8, 2e-9, 3.9e-6, 9e-8, 8e-8, 1e-5, **kw)


def _sky(n=8):
    az = np.linspace(0, 2 * np.pi, n, endpoint=False)
    el = np.radians(np.linspace(15, 75, n))
    return np.column_stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)])


@pytest.mark.parametrize("bad", [math.nan, -1e-5, 2.0, math.inf, 0.0])
def test_the_core_refuses_bad_priors_even_past_the_python_objects(bad):
    """Past the dataclass checks (the binding called directly), a bad prior or bias is a
    ValueError naming it, never a PanicException and never a vanished level."""
    from navfdi import _core

    los = _sky(8)
    alloc = (9.8e-8, 2e-9, 3.9e-6, 9e-8, 8e-8, 1e-5, 0.05)
    good = dict(b_nom=[0.5] * 8, p_sat=[1e-5] * 8, p_const=[1e-4])
    for key in ("b_nom", "p_sat", "p_const"):
        kw = {k: list(v) for k, v in good.items()}
        kw[key][0] = bad
        if (key == "b_nom" and bad in (0.0, 2.0)) or (key == "p_const" and bad == 0.0):
            continue  # a zero or 2 m bias bound is valid; a zero constellation prior: none monitored
        with pytest.raises(ValueError, match=key):
            _core.araim_epoch((-los).tolist(), [0] * 8, [1.0] * 8, [1.0] * 8, kw["b_nom"], kw["p_sat"], kw["p_const"], alloc)


def test_a_system_without_a_prior_is_refused_before_solving(tmp_path):
    """--systems G,E,C --integrity lpv200: the default ISM has no BeiDou prior. Once, before
    the epochs, with the key to add (was: 0 % availability and NaN levels, no message)."""
    with pytest.raises(ValueError, match=r"no constellation fault prior for system\(s\) C.*p_const"):
        navfdi.gnss_solve(OBS, NAV, systems="G,E,C", integrity="lpv200")
    f = tmp_path / "alloc.toml"
    f.write_text("[ism]\np_const = {G = 1e-4}\n")
    with pytest.raises(ValueError, match=r"system\(s\) E.*alloc.toml"):
        navfdi.gnss_solve(OBS, NAV, systems="G,E", integrity=str(f))
    assert main(["gnss", str(OBS), str(NAV), "--systems", "G,E,C", "--integrity", "lpv200", "--out", str(tmp_path / "o")]) == 2


def test_epoch_level_integrity_failures_are_counted_with_their_reason():
    from navfdi.gnss_integrity import add_integrity

    sol = navfdi.gnss_solve(OBS, NAV, systems="G,E")
    # One epoch's satellites all at the zenith: a singular geometry for that epoch alone.
    sats = sol.satellites
    first = sats["epoch"] == sats.loc[sats["status"] == "used", "epoch"].iloc[0]
    sats.loc[first, "elevation"] = 90.0
    sats.loc[first, "azimuth"] = 0.0
    add_integrity(sol, "lpv200")
    failed = sol.config["integrity"]["failed_epochs"]
    assert failed and all(isinstance(v, int) and v >= 1 for v in failed.values()), failed
    assert any("ARAIM" in k for k in failed)
    assert "integrity not computed at" in sol.format_summary()


# ---- 3. time tags -----------------------------------------------------------------------------


def _first_obs_line(text: str) -> str:
    return next(ln for ln in text.splitlines() if "TIME OF FIRST OBS" in ln)


@pytest.mark.parametrize("field, expect", [("   ", "same"), ("GPS", "same"), ("GLO", "utc"), ("XYZ", "error"), ("TAI", "error")])
def test_the_time_system_of_first_obs_is_read_as_the_format_says(tmp_path, field, expect):
    """A blank time system is the file's own (GPS for GPS and mixed files), not TAI (was: every
    epoch 19 s off, 9.6 km RMS); GLO is UTC (was: 'hifitime parsing' without a line); an
    unknown one is an error naming the line."""
    text = gzip.open(OBS, "rt").read()
    line = _first_obs_line(text)
    f = tmp_path / "r.obs"
    f.write_text(text.replace(line, line[:48] + field + line[51:]))
    truth = "35.13469901,136.97757549,104.8626"
    if expect == "error":
        with pytest.raises(navfdi.FileFormatError, match=r"line \d+: TIME OF FIRST OBS: time system"):
            navfdi.gnss_solve(f, NAV, systems="G,E", truth=truth)
        return
    s = navfdi.gnss_solve(f, NAV, systems="G,E", truth=truth)
    t0 = str(s.solution["time"].iloc[0])
    if expect == "same":
        assert s.summary()["horizontal_rms"] < 5 and t0.endswith("08:20:00.000"), t0
    else:  # UTC tags: 18 leap seconds later in GPS time, as the file says
        assert t0.endswith("08:20:18.000"), t0


def test_a_blank_time_system_in_a_rinex2_file_is_gps(tmp_path):
    from navfdi._core import read_rinex_obs

    obs = Path(__file__).parent / "data" / "rinex_formats" / "delf0010.21o.gz"
    text = gzip.open(obs, "rt").read()
    line = _first_obs_line(text)
    f = tmp_path / "r.21o"
    f.write_text(text.replace(line, line[:48] + "   " + line[51:]))
    assert read_rinex_obs(str(f))["time"][0] == read_rinex_obs(str(obs))["time"][0]


def _walk(tmp_path, obs_text=None, **values):
    """walk_tc with absolute data paths (and its observations replaced by ``obs_text``)."""
    import copy
    from importlib import resources

    from navfdi.scenario import from_dict

    base = Path(str(resources.files("navfdi") / "scenarios"))
    raw = copy.deepcopy(navfdi.load_scenario("walk_tc").raw)
    src = raw["source"]
    for k in ("rinex_obs", "rinex_nav", "reference"):
        src[k] = str((base / src[k]).resolve())
    src["imu"]["file"] = str((base / src["imu"]["file"]).resolve())
    if obs_text is not None:
        f = tmp_path / "walk.obs"
        f.write_text(obs_text)
        src["rinex_obs"] = str(f)
    sc = from_dict(raw, source=str(tmp_path / "walk.toml"))
    return sc.with_values(values) if values else sc


def _jitter(text: str, fn) -> str:
    out = []
    k = 0
    for ln in text.splitlines():
        if ln.startswith(">"):
            sec, d = float(ln[19:29]), fn(k)
            # Stay inside the minute (a tag of 60.000 s is not a time).
            sec = sec + d if 0 <= sec + d < 60 else sec - abs(d)
            ln = ln[:19] + f"{sec:10.7f}" + ln[29:]
            k += 1
        out.append(ln)
    return "\n".join(out) + "\n"


@pytest.mark.parametrize("how", ["jitter", "drift"])
def test_time_tags_off_the_grid_drop_no_epoch(tmp_path, how):
    """±2 ms receiver jitter on walk_tc's observation time tags (was: 2 km wrong: epochs
    dropped off the 4 Hz grid), and an unsteered receiver clock drifting 5 µs/s (was: 189 m):
    every epoch is still measured, and the solution stays within metres of the clean run."""
    from importlib import resources

    obs = Path(str(resources.files("navfdi") / "data" / "walk_0827" / "gnss_1730.obs.gz"))
    text = gzip.open(obs, "rt").read()
    fn = (lambda k: 0.002 if k % 2 else -0.002) if how == "jitter" else (lambda k: 5e-6 * 0.25 * k)
    clean = navfdi.run_scenario(_walk(tmp_path), compare_isolation=False).runs["innovation"]
    moved = navfdi.run_scenario(_walk(tmp_path, _jitter(text, fn)), compare_isolation=False).runs["innovation"]
    n_clean = int((clean.record["satellites"]["status"] != 5).sum())
    n_moved = int((moved.record["satellites"]["status"] != 5).sum())
    assert n_moved == n_clean
    assert moved.errors()["hor_rel_rms"] < clean.errors()["hor_rel_rms"] + 2.0


def test_a_sensor_rate_the_log_cannot_give_is_refused():
    """--set sensors[0].rate=3 Hz on a 4 Hz log (was: silently 1 Hz)."""
    for rate in ("3 Hz", "8 Hz", "0.7 Hz"):
        with pytest.raises(navfdi.ScenarioError, match=r"sensors\[0\]\.rate"):
            navfdi.run_scenario(navfdi.load_scenario("drive_lc").with_value("sensors[0].rate", rate))


# ---- 4. partial logs -------------------------------------------------------------------------


def _drive_with_imu(tmp_path, keep):
    """drive_lc with its IMU log cut to the rows ``keep`` (a slice of the data rows)."""
    import copy
    from importlib import resources

    from navfdi.scenario import from_dict

    base = Path(str(resources.files("navfdi") / "scenarios"))
    raw = copy.deepcopy(navfdi.load_scenario("drive_lc").raw)
    for k in ("gnss", "reference"):
        raw["source"][k] = str((base / raw["source"][k]).resolve())
    lines = gzip.open((base / raw["source"]["imu"]["file"]).resolve(), "rt").read().splitlines()
    f = tmp_path / "imu.csv"
    f.write_text("\n".join([lines[0], *lines[1:][keep]]) + "\n")
    raw["source"]["imu"]["file"] = str(f)
    return from_dict(raw, source=str(tmp_path / "drive.toml"))


@pytest.mark.parametrize("keep, fault_start", [(slice(0, 30000), "440 s"), (slice(0, 45000), "470 s"), (slice(20000, None), "60 s")])
def test_a_partial_imu_log_is_said_and_its_faults_outside_are_never_applied(tmp_path, keep, fault_start):
    """An IMU log that ends 250 s before the GNSS log (or starts late): a warning with both
    spans, and a fault outside the navigated span is never applied (was: reported missed)."""
    sc = _drive_with_imu(tmp_path, keep).with_values({"faults[0].start": fault_start, "faults[0].end": f"{float(fault_start.split()[0]) + 20:g} s"})
    with pytest.warns(navfdi.PartialLogWarning, match=r"IMU log .* (ends|starts) .* GPST\).*only their overlap"):
        runs = navfdi.run_scenario(sc)
    r = runs.runs["fde"]
    [m] = [m for m in r.fault_table() if m.detector == "exclude"]
    assert not r.fault_applied("gnss_fault") and "never applied" in m.note


def test_a_campaign_on_a_partial_log_does_not_count_faults_past_its_end_as_missed(tmp_path):
    sc = _drive_with_imu(tmp_path, slice(0, 30000))  # the IMU ends ~260 s into the drive
    with pytest.warns(navfdi.PartialLogWarning):
        camp = navfdi.montecarlo(sc, runs=12, seed=2, workers=1, progress=False)
    s = camp.summary()
    row = s[(s["fault_id"] == "gnss_fault") & (s["detector"] == "exclude") & (s["variant"] == "fde")].iloc[0]
    assert row["not_applied_runs"] > 0
    assert row["runs"] - row["not_applied_runs"] > 0
    assert row["detection_probability"] == 1.0


# ---- 6. names into paths ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "path, value",
    [
        ("variants[0].name", "../../escaped"),
        ("variants[1].name", "a/b"),
        ("sensors[0].name", "gnss/pos"),
        ("faults[0].id", "../fault"),
        ("variants[0].name", ".hidden"),
        ("faults[0].id", "x" * 65),
        ("variants[0].name", "tab\\there"),
    ],
)
def test_names_that_would_become_paths_are_refused_before_the_run(tmp_path, path, value):
    """A variant named ../../escaped wrote 7 figures outside --out; a sensor or detector
    name with / failed after the run with partial output. Refused before anything runs,
    and nothing is written."""
    out = tmp_path / "out"
    with pytest.raises(navfdi.ScenarioError, match=r"only letters, digits and _ \. \+ -"):
        navfdi.load_scenario("drive_lc").with_value(path, value.replace("\\\\t", "\\t"))
    assert main(["run", "drive_lc", "--out", str(out), "--set", f"{path}={value}"]) == 2
    assert not out.exists() or not any(out.iterdir())
    assert not any(tmp_path.parent.glob("escaped*"))


def test_a_detector_name_with_a_slash_is_refused():
    with pytest.raises(navfdi.ScenarioError, match=r"detectors\[0\]\.name"):
        navfdi.load_scenario("drive_lc").with_value("loosely_coupled.sensors[0].detectors[0].name", "chi/2")
