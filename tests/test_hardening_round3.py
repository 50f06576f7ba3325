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
    every epoch after the alignment is still measured (the alignment within one epoch of the
    clean run's), and the solution stays within metres of the clean run."""
    from importlib import resources

    obs = Path(str(resources.files("navfdi") / "data" / "walk_0827" / "gnss_1730.obs.gz"))
    text = gzip.open(obs, "rt").read()
    fn = (lambda k: 0.002 if k % 2 else -0.002) if how == "jitter" else (lambda k: 5e-6 * 0.25 * k)
    clean = navfdi.run_scenario(_walk(tmp_path), compare_isolation=False).runs["innovation"]
    moved = navfdi.run_scenario(_walk(tmp_path, _jitter(text, fn)), compare_isolation=False).runs["innovation"]
    # The only epochs without a measurement are those before the alignment (a leading run);
    # the alignment, which reads the receiver's speed from the moved tags, within one epoch.
    unmeasured = {name: np.flatnonzero(np.asarray(r.record["satellites"]["status"]) == 5) for name, r in (("clean", clean), ("moved", moved))}
    for idx in unmeasured.values():
        assert np.array_equal(idx, np.arange(len(idx)))
    assert abs(len(unmeasured["moved"]) - len(unmeasured["clean"])) <= 1
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


# ---- 5. unbounded reads ----------------------------------------------------------------------


def _imu_cols():
    return {"time": "t", "gyro": ["gx", "gy", "gz"], "accel": ["ax", "ay", "az"]}


def _imu_text(n=50):
    return "t,gx,gy,gz,ax,ay,az\n" + "".join(f"{1e9 + k * 0.01:.2f},0.01,0,0,0,0,-9.8\n" for k in range(n))


@pytest.mark.parametrize("filler", [b"\n", b",,,,,,\n", b"0" * 64 + b"\n"])
def test_a_compressed_log_that_inflates_implausibly_is_refused_while_read(tmp_path, filler):
    """An 852 kB .csv.gz inflating to 300 M newlines peaked at 4.9 GB: now refused at 200
    times its size while being read (IMU CSV, .pos and RINEX alike)."""
    import zlib

    from navfdi.logs import read_imu, read_pos

    body = _imu_text().encode() + filler * (80_000_000 // len(filler))
    p = tmp_path / "imu.csv.gz"
    co = zlib.compressobj(9, zlib.DEFLATED, 31)
    p.write_bytes(co.compress(body) + co.flush())
    # Refused as a bomb, or earlier at its first bad row: either way without inflating it.
    with pytest.raises(navfdi.ScenarioError, match="decompresses to more than|is missing|fields, the header has"):
        read_imu(p, _imu_cols())
    pos = tmp_path / "g.pos.gz"
    pos.write_bytes(gzip.compress(b"% GPST latitude(deg) longitude(deg) height(m)\n" + filler * (80_000_000 // len(filler)), 9))
    with pytest.raises(navfdi.ScenarioError, match="decompresses to more than"):
        read_pos(pos)
    rnx = tmp_path / "r.obs.gz"
    text = gzip.open(OBS).read()
    head = text[: text.index(b"END OF HEADER") + 14]
    rnx.write_bytes(gzip.compress(head + filler * (80_000_000 // len(filler)), 9))
    with pytest.raises(navfdi.FileFormatError, match="decompresses to more than"):
        navfdi.read_rinex(rnx)


@pytest.mark.parametrize("target", ["/dev/zero", "fifo", "dir"])
def test_a_source_path_that_is_not_a_regular_file_is_refused(tmp_path, target):
    """/dev/zero or a FIFO as a [source] path read forever or blocked."""
    import os

    from navfdi.logs import read_imu, read_pos

    if target == "fifo":
        p = tmp_path / "fifo"
        os.mkfifo(p)
    elif target == "dir":
        p = tmp_path
    else:
        p = Path(target)
    with pytest.raises((navfdi.ScenarioError, OSError), match="not a regular file|directory"):
        read_imu(p, _imu_cols())
    with pytest.raises((navfdi.ScenarioError, OSError), match="not a regular file|directory"):
        read_pos(p)
    with pytest.raises(OSError, match="not a regular file|directory"):
        navfdi.gnss_solve(OBS, NAV, truth=None) if False else navfdi.read_rinex(p)
    with pytest.raises(OSError, match="not a regular file|directory"):
        from navfdi.gnss import read_truth_file

        read_truth_file(p)


# ---- 7. old formats truncated ----------------------------------------------------------------


@pytest.mark.parametrize("name, cut", [("delf0010.21o.gz", 5), ("delf0010.21o.gz", 1), ("delf0010.21d.gz", 3), ("delf0010.21d.gz", 2)])
def test_a_rinex2_or_compact_rinex1_file_cut_mid_epoch_is_named(tmp_path, name, cut):
    from navfdi._core import read_rinex_obs

    src = Path(__file__).parent / "data" / "rinex_formats" / name
    lines = gzip.open(src, "rt").read().splitlines()
    f = tmp_path / name.removesuffix(".gz")
    f.write_text("\n".join(lines[:-cut]) + "\n")
    with pytest.raises(navfdi.FileFormatError, match=r"line \d+: the file ends inside this epoch: \d+ satellites announced, observations for \d+"):
        read_rinex_obs(str(f))


# ---- 8. one bad ephemeris --------------------------------------------------------------------


def _nav_with(tmp_path, sat, af0):
    import re

    text = NAV.read_text()
    new = re.sub(rf"^({sat} \d{{4}} \d\d \d\d \d\d \d\d \d\d)([ -]\d\.\d{{12}}[ED][+-]\d\d)", lambda m: m.group(1) + af0, text, flags=re.M)
    assert new != text
    p = tmp_path / "b.nav"
    p.write_text(new)
    return p


@pytest.mark.parametrize("sat, af0", [("G13", " 1.000000000000E+00"), ("G13", "-5.000000000000E-03"), ("G05", " 1.000000000000E+00"), ("E12", " 2.000000000000E-01")])
def test_one_implausible_ephemeris_costs_its_satellite_not_the_file(tmp_path, sat, af0):
    """A GPS record with a 1 s clock bias made every epoch 'no first fix' (solved 0): the
    satellite is reported bad_ephemeris and the others solve."""
    truth = "35.13469901,136.97757549,104.8626"
    clean = navfdi.gnss_solve(OBS, NAV, systems="G,E", truth=truth).summary()
    s = navfdi.gnss_solve(OBS, _nav_with(tmp_path, sat, af0), systems="G,E", truth=truth)
    sm = s.summary()
    assert sm["solved"] == clean["solved"]
    assert sm["skipped"].get("bad_ephemeris", 0) > clean["skipped"].get("bad_ephemeris", 0)
    st = s.satellites
    assert (st.loc[st["satellite"] == sat, "status"].isin(["bad_ephemeris", "below_mask"])).all()
    assert sm["horizontal_rms"] < clean["horizontal_rms"] + 1.0


# ---- 9. huge but finite values ---------------------------------------------------------------


@pytest.mark.parametrize("column, value", [("gx", "1e300"), ("az", "-1e12"), ("gy", "150")])
def test_implausible_imu_samples_are_refused_at_reading(tmp_path, column, value):
    from navfdi.logs import read_imu

    text = _imu_text().splitlines()
    head = text[0].split(",")
    row = text[5].split(",")
    row[head.index(column)] = value
    text[5] = ",".join(row)
    p = tmp_path / "imu.csv"
    p.write_text("\n".join(text) + "\n")
    with pytest.raises(navfdi.ScenarioError, match=rf"line 6, column '{column}': .* beyond any IMU's range"):
        read_imu(p, _imu_cols())


def test_deg_per_s_declared_as_rad_per_s_is_refused(tmp_path):
    """deg/s data declared as rad/s ran with exit 0 and 8.5 m RMS."""
    from navfdi.logs import read_imu

    p = tmp_path / "imu.csv"
    p.write_text("t,gx,gy,gz,ax,ay,az\n" + "".join(f"{1e9 + k * 0.01:.2f},{60 + k % 7},-3,20,0,0,-9.8\n" for k in range(200)))
    with pytest.raises(navfdi.ScenarioError, match=r"median angular rate .* check source.imu.gyro_unit"):
        read_imu(p, _imu_cols())


def _pos_with(tmp_path, column, value):
    from importlib import resources

    src = Path(str(resources.files("navfdi") / "data" / "drive_0708" / "gnss_1934_sf.pos.gz"))
    lines = gzip.open(src, "rt").read().splitlines()
    head = next(ln for ln in lines if "latitude" in ln)[1:].split()
    k = next(i for i, ln in enumerate(lines) if not ln.startswith("%")) + 10
    tok = lines[k].split()
    tok[1 + head.index(column)] = value
    lines[k] = " ".join(tok)
    p = tmp_path / "g.pos"
    p.write_text("\n".join(lines) + "\n")
    return p, k + 1


@pytest.mark.parametrize("column, value", [("height(m)", "1e20"), ("sdn(m)", "1e300"), ("ve(m/s)", "-3e5"), ("latitude(deg)", "91.0"), ("sde(m)", "-1"), ("latitude(deg)", "nan")])
def test_implausible_pos_values_are_refused_with_line_and_column(tmp_path, column, value):
    from navfdi.logs import read_pos

    p, line = _pos_with(tmp_path, column, value)
    what = "not a number" if value == "nan" else "is outside"
    with pytest.raises(navfdi.ScenarioError, match=rf"line {line}, column '{re_escape(column)}': .*{what}"):
        read_pos(p)


def re_escape(s):
    import re

    return re.escape(s)


def test_a_run_that_fails_in_a_campaign_is_recorded_and_the_campaign_goes_on(monkeypatch):
    """A run failing on its draw (here: an innovation covariance that is not positive
    definite from a 1e150 m fault) is recorded as failed with its error; the other runs'
    figures stand (was: the finished runs were lost)."""
    sc = navfdi.load_scenario("drive_lc").with_values({
        "faults[0].draw.shapes[0].magnitude": ["10 m", "1e154 m"],
    })
    camp = navfdi.montecarlo(sc, runs=8, seed=5, workers=2, progress=False)
    f = camp.failures()
    ok = camp.completed_runs()
    # 8 runs × 2 variants; the variant without FDE takes the 1e154 m fault and fails.
    assert f["count"] > 0 and f["count"] + len(ok.drop_duplicates(["point", "run", "variant"])) == 16
    assert all("t = " in m and "epoch" in m for m in f["errors"])
    assert "failed and are left out" in camp.format_table()
    s = camp.summary()
    assert s["runs"].max() <= 8


# ---- 10. readers -----------------------------------------------------------------------------


def test_a_pos_without_velocity_columns_reads_and_positions_still_run(tmp_path):
    from importlib import resources

    from navfdi.logs import read_pos

    src = Path(str(resources.files("navfdi") / "data" / "drive_0708" / "gnss_1934_sf.pos.gz"))
    lines = gzip.open(src, "rt").read().splitlines()
    cut = []
    for ln in lines:
        tok = ln.split()
        if "latitude" in ln:
            cut.append(" ".join(tok[:13]))  # up to sdun(m): no velocity columns
        elif ln.startswith("%"):
            cut.append(ln)
        else:
            cut.append(" ".join(tok[:14]))
    p = tmp_path / "novel.pos"
    p.write_text("\n".join(cut) + "\n")
    log = read_pos(p)
    assert np.isnan(log.vel).all() and np.isfinite(log.sd_pos).all()


def test_columns_are_matched_by_name_not_prefix(tmp_path):
    """sdun was taken for sdu when it came first."""
    from navfdi.logs import read_pos

    head = "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdun(m)   sdn(m)   sde(m)   sdu(m)\n"
    row = "2025/07/08 19:34:18.499 40.0966268 -105.1474483 1601.474 1 21 0.5 0.01 0.02 0.03\n"
    p = tmp_path / "x.pos"
    p.write_text(head + row + row.replace("18.499", "19.499"))
    log = read_pos(p)
    assert log.sd_pos[0].tolist() == [0.02, 0.01, 0.03]


@pytest.mark.parametrize("kind", ["imu", "pos", "rinex", "toml", "truth"])
def test_a_utf8_byte_order_mark_is_accepted_by_every_reader(tmp_path, kind):
    from navfdi.logs import read_imu, read_pos

    bom = "\ufeff"
    if kind == "imu":
        p = tmp_path / "imu.csv"
        p.write_text(bom + _imu_text(), encoding="utf-8")
        assert read_imu(p, _imu_cols()).t.size == 50
    elif kind == "pos":
        head = "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n"
        row = "2025/07/08 19:34:18.499 40.0966268 -105.1474483 1601.474 1 21 0.01 0.02 0.03\n"
        p = tmp_path / "x.pos"
        p.write_text(bom + head + row, encoding="utf-8")
        assert read_pos(p).t.size == 1
    elif kind == "rinex":
        p = tmp_path / "r.obs"
        p.write_text(bom + gzip.open(OBS, "rt").read(), encoding="utf-8")
        assert len(navfdi.read_rinex(p)) > 0
    elif kind == "toml":
        from importlib import resources

        p = tmp_path / "y.toml"
        p.write_text(bom + (resources.files("navfdi") / "scenarios" / "yang2013.toml").read_text(), encoding="utf-8")
        assert navfdi.load_scenario(p).name == "yang2013"
    else:
        from navfdi.gnss import read_truth_file

        p = tmp_path / "truth.txt"
        p.write_text(bom + "35.13469901 136.97757549 104.8626\n", encoding="utf-8")
        assert np.linalg.norm(read_truth_file(p)) > 6e6


@pytest.mark.parametrize(
    "text, match",
    [
        ("t,gx,gy,gz,ax,ay,az\n", "no samples"),
        (None, r"line 3: 8 fields, the header has 7 \(a trailing comma\?\)"),
        ("", "empty file"),
        (None, "blank"),
    ],
)
def test_imu_reader_edge_cases_name_file_and_line(tmp_path, text, match):
    from navfdi.logs import read_imu

    p = tmp_path / "imu.csv"
    if match.startswith("line 3"):
        lines = _imu_text(5).splitlines()
        lines[2] += ","
        text = "\n".join(lines) + "\n"
    if match == "blank":
        lines = _imu_text(5).splitlines()
        lines.insert(2, "")
        lines.insert(2, "")
        lines[5] = lines[5].replace("0.01", "abc", 1)
        p.write_text("\n".join(lines) + "\n")
        # The bad value is on the file's line 6 (blank lines count).
        with pytest.raises(navfdi.ScenarioError, match=r"line 6, column 'gx': 'abc'"):
            read_imu(p, _imu_cols())
        return
    p.write_text(text)
    with pytest.raises(navfdi.ScenarioError, match=match) as e:
        read_imu(p, _imu_cols())
    assert str(p) in str(e.value)


@pytest.mark.parametrize("key, value, match", [("max_gap", "abc", "max_gap"), ("max_gap", float("nan"), "max_gap"), ("max_gap", -1, "max_gap"), ("gyro_units", "deg/s", "gyro_unit"), ("acel", ["a"], "accel")])
def test_source_imu_keys_and_values_are_checked(key, value, match):
    sc = navfdi.load_scenario("drive_lc").with_value(f"source.imu.{key}", value, create=True)
    with pytest.raises(navfdi.ScenarioError, match=match):
        navfdi.run_scenario(sc)


# ---- 11. gross observations ------------------------------------------------------------------


@pytest.mark.parametrize("value", [-2.0e7, 9e9, 5.0, -1.0])
def test_a_gross_pseudorange_is_recorded_and_excluded_not_dropped(tmp_path, value):
    text = gzip.open(OBS, "rt").read().splitlines()
    i = next(i for i, ln in enumerate(text) if ln.startswith("G13"))
    text[i] = text[i][:19] + f"{value:14.3f}" + text[i][33:]
    p = tmp_path / "g.obs"
    p.write_text("\n".join(text) + "\n")
    s = navfdi.gnss_solve(p, NAV, systems="G", truth="35.13469901,136.97757549,104.8626")
    st = s.satellites
    row = st[(st["epoch"] == 0) & (st["satellite"] == "G13")]
    assert row["status"].tolist() == ["excluded"]
    assert s.summary()["exclusions"].get("G13", 0) >= 1
    assert s.summary()["solved"] == len(s.solution)


# ---- 12. workers -----------------------------------------------------------------------------


@pytest.mark.parametrize("workers", [1_000_000, 5000, 4 * 4096])
def test_absurd_worker_counts_are_refused_with_the_machines_numbers(workers):
    import os

    with pytest.raises(ValueError, match=rf"workers = {workers}: this machine has {os.cpu_count()} core"):
        navfdi.montecarlo("yang2013", runs=2, workers=workers)
    assert main(["montecarlo", "yang2013", "--runs", "2", "--workers", str(workers)]) == 2


# ---- 13. smaller -----------------------------------------------------------------------------


def test_set_errors_name_set(capsys):
    assert main(["run", "yang2013", "--set", "=x"]) == 2
    err = capsys.readouterr().err
    assert "--set '=x'" in err and "--sweep" not in err


def test_a_binary_truth_file_is_named(tmp_path):
    from navfdi.gnss import read_truth_file

    p = tmp_path / "t.bin"
    p.write_bytes(bytes(range(256)) * 10)
    with pytest.raises(ValueError, match=r"--truth-file .*not a text file"):
        read_truth_file(p)
    p.write_text("35.1 136.9\n")
    with pytest.raises(ValueError, match="--truth-file"):
        read_truth_file(p)


def test_one_fault_string_is_one_fault_and_mask_is_a_number():
    one = navfdi.gnss_solve(OBS, NAV, faults="G13:step:20m:100s:200s")
    assert [f.satellite for f in one.faults] == ["G13"]
    for bad in (True, "10", float("nan"), 90.0):
        with pytest.raises(ValueError, match="mask"):
            navfdi.gnss_solve(OBS, NAV, mask_deg=bad)


def test_a_one_epoch_pos_log_says_so(tmp_path):
    import copy
    from importlib import resources

    from navfdi.scenario import from_dict

    base = Path(str(resources.files("navfdi") / "scenarios"))
    raw = copy.deepcopy(navfdi.load_scenario("drive_lc").raw)
    raw["source"]["imu"]["file"] = str((base / raw["source"]["imu"]["file"]).resolve())
    raw["source"].pop("reference")
    head = "%  GPST                  latitude(deg) longitude(deg)  height(m)   Q  ns   sdn(m)   sde(m)   sdu(m)\n"
    p = tmp_path / "one.pos"
    p.write_text(head + "2025/07/08 19:35:18.499 40.0966268 -105.1474483 1601.474 1 21 0.01 0.02 0.03\n")
    raw["source"]["gnss"] = str(p)
    with pytest.raises(navfdi.ScenarioError, match=r"1 epoch\(s\); a run needs at least two") as e:
        navfdi.run_scenario(from_dict(raw, source=str(tmp_path / "x.toml")))
    assert "nan" not in str(e.value)


# ---- no panic reachable from Python ----------------------------------------------------------

BAD = [math.nan, math.inf, -math.inf, -1.0, -1e300, 1e300, 0.0, 5e-324]


def _calls():
    """(name, function of the arguments, valid arguments): every public constructor, method
    and function with numeric arguments."""
    from navfdi import _core

    eye3 = np.eye(3)
    sky = _sky(8)
    rx = np.array([-2.18e6, 4.38e6, 4.08e6])
    sats = rx + 2.2e7 * sky[:, [1, 0, 2]]
    rho = np.linalg.norm(sats - rx, axis=1)

    def kf_predict(x0, P0, Phi, Q):
        navfdi.KalmanFilter(x0, P0).predict(Phi=Phi, Q=Q)

    def kf_update(z, H, R):
        navfdi.KalmanFilter(np.zeros(3), eye3).update(z=z, H=H, R=R)

    def state_step(x, P, Phi, Q):
        navfdi.StateChi2(0.01, 3, 10).step(x, P, Phi, Q)

    def fusion_step(values, predicted):
        navfdi.WeightedFusion([3.0, 1.0, 0.5], window=5).step(values, predicted=predicted, healthy=[True, True, True])

    def pre_step(z_code, z_freq, cn0):
        navfdi.Prefilter().step(z_code, z_freq, cn0)

    alloc = (9.8e-8, 2e-9, 3.9e-6, 9e-8, 8e-8, 1e-5, 0.05)
    return [
        ("chi2_threshold", navfdi.chi2_threshold, [0.01, 3]),
        ("sprt_threshold", navfdi.sprt_threshold, [0.01, 0.01]),
        ("noncentrality", navfdi.noncentrality, [0.01, 0.05, 3]),
        ("ncx2_cdf", navfdi.ncx2_cdf, [2.0, 3, 1.0]),
        ("mdb", navfdi.mdb, [eye3, 0.01, 0.05]),
        ("dll_variance", navfdi.dll_variance, [45.0, 0.02, 1.0]),
        ("fll_variance", navfdi.fll_variance, [45.0, 0.02]),
        ("KalmanFilter", navfdi.KalmanFilter, [np.zeros(3), eye3]),
        ("KalmanFilter.predict", kf_predict, [np.zeros(3), eye3, eye3, eye3 * 0.1]),
        ("KalmanFilter.update", kf_update, [np.ones(3), eye3, eye3]),
        ("ResidualChi2", lambda pf, r, a: navfdi.ResidualChi2(pf).test(r, a), [0.01, np.ones(3), eye3]),
        ("ImprovedSprt", lambda pf, pm, r, a: navfdi.ImprovedSprt(pf, pm).test(r, a), [0.01, 0.01, np.ones(3), eye3]),
        ("JointChi2Sprt", lambda pf, pm, r, a: navfdi.JointChi2Sprt(pf, pm).test(r, a), [0.01, 0.01, np.ones(3), eye3]),
        ("Aime", lambda pf, w, r, a: navfdi.Aime(pf, w).test(r, a), [0.01, 5, np.ones(3), eye3]),
        ("TwoStageAime", lambda pf, w1, w2, q, b, r: navfdi.TwoStageAime(pf, w1, w2, q=q, b=b).test(r, eye3), [0.01, 2, 10, 10.0, 0.99, np.ones(3)]),
        ("StateChi2", lambda pf, n, every: navfdi.StateChi2(pf, n, every), [0.01, 3, 10]),
        ("StateChi2.step", state_step, [np.zeros(3), eye3, eye3, eye3 * 0.01]),
        ("WeightedFusion", lambda s, w: navfdi.WeightedFusion(s, window=w), [[3.0, 1.0], 5]),
        ("WeightedFusion.step", fusion_step, [[101.0, 99.0, 100.0], 100.0]),
        ("Prefilter", lambda t, j, c, s: navfdi.Prefilter(t=t, jerk_psd=j, code_psd=c, spacing=s), [0.02, 1.0, 0.0, 1.0]),
        ("Prefilter.step", pre_step, [1.0, 0.5, 45.0]),
        ("run_filter", lambda x0, P0, Phi, Q, zs, H, R, f: navfdi.run_filter(x0, P0, Phi, Q, zs, H, R, fading=f), [np.zeros(3), eye3, eye3, eye3 * 0.01, np.ones((4, 3)), eye3, eye3, 1.0]),
        ("snapshot_fde", lambda p, r, s, a: navfdi.snapshot_fde(p, r, s, alpha=a), [sats, rho, np.full(8, 3.0), 0.01]),
        ("araim", lambda los, ci, ca, res: navfdi.araim(los, ["G"] * 8, c_int=ci, c_acc=ca, residuals=res), [sky, np.ones(8), np.ones(8), np.zeros(8)]),
        ("araim_epoch", lambda rows, ci, ca, b, ps, pc, al: _core.araim_epoch(rows, [0] * 8, ci, ca, b, ps, pc, tuple(al)), [(-sky).tolist(), [1.0] * 8, [1.0] * 8, [0.5] * 8, [1e-5] * 8, [1e-4], list(alloc)]),
        ("snapshot_pl", lambda los, s2, thr, k: _core.snapshot_pl(los, [0] * 8, s2, thr, k), [sky.tolist(), [1.0] * 8, 20.0, 3.29]),
        ("Ism", lambda u, e, b, p: navfdi.Ism(u, e, b, p), [0.75, 0.5, 0.5, 1e-5]),
        ("Allocation", lambda *a: navfdi.Allocation(*a), [9.8e-8, 2e-9, 3.9e-6, 9e-8, 8e-8, 1e-5, 40.0, 35.0, 0.05]),
    ]


def _variants(args):
    """Each numeric argument (a scalar, one element of an array or list) replaced by each bad
    value, one at a time."""
    for i, a in enumerate(args):
        for bad in BAD:
            out = list(args)
            if isinstance(a, (bool, str)):
                continue
            if isinstance(a, (int, float)):
                out[i] = bad
            elif isinstance(a, np.ndarray):
                b = a.astype(float).copy()
                b.flat[0] = bad
                out[i] = b
            elif isinstance(a, list) and a and all(isinstance(v, (int, float)) for v in a):
                out[i] = [bad, *a[1:]]
            elif isinstance(a, list) and a and isinstance(a[0], list):
                out[i] = [[bad, *a[0][1:]], *a[1:]]
            else:
                continue
            yield i, bad, out


@pytest.mark.parametrize("name, fn, args", _calls(), ids=[c[0] for c in _calls()])
def test_no_numeric_input_reaches_a_panic(name, fn, args):
    """NaN, ±inf, negative, huge and tiny values to every public constructor and function with
    numeric arguments: a result or an ordinary exception, never a PanicException (which
    ``except Exception`` does not catch)."""
    fn(*args)  # the valid call works
    for i, bad, a in _variants(args):
        try:
            fn(*a)
        except Exception:
            pass
        except BaseException as e:  # PanicException derives from BaseException
            pytest.fail(f"{name}: argument {i} = {bad!r} raised {type(e).__name__}: {e}")


def test_pos_time_parses_and_refuses_like_the_calendar() -> None:
    """The .pos time parser (day start cached, time of day by hand): the same GPS seconds as
    the calendar, and every malformed or out-of-range field refused."""
    import datetime as _dt

    from navfdi._logtime import GPS_EPOCH, pos_time

    for d, tod in (("2021/07/08", "01:02:03.250"), ("2024/02/29", "23:59:59.999"), ("2017/01/01", "00:00:00")):
        want = (_dt.datetime.strptime(f"{d} {tod}", "%Y/%m/%d %H:%M:%S.%f" if "." in tod else "%Y/%m/%d %H:%M:%S") - GPS_EPOCH).total_seconds()
        assert pos_time(d, tod) == pytest.approx(want, abs=1e-6)
    for d, tod in (("2021/07/08", "24:00:00"), ("2021/07/08", "01:60:00"), ("2021/07/08", "1:2"), ("2021/07/08", "01:00:nan"),
                   ("2021/07/08", "01:00:-1"), ("2021/13/08", "01:00:00"), ("2023/02/29", "01:00:00"), ("2021/07/08", "a1:00:00")):
        with pytest.raises(ValueError):
            pos_time(d, tod)
