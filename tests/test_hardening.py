"""Hostile inputs a new user gave (issue 'Hardening'): each gets the right answer or a clear
error naming the problem, never a crash, a traceback on the command line or silent acceptance.
"""

from __future__ import annotations

import _thread
import copy
import signal
import subprocess
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import _core
from navfdi.scenario import ScenarioTooLarge, ScenarioWarning


def equal(a, b) -> None:
    np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


def cli(*args: str, cwd: Path | None = None, timeout: float = 300) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "navfdi", *args], capture_output=True, text=True, timeout=timeout, cwd=cwd)


@pytest.fixture(scope="module")
def yang():
    return navfdi.load_scenario("yang2013")


# ---- 2. duplicate fault components ----------------------------------------------------------
def test_duplicate_fault_components_are_refused(yang):
    with pytest.raises(navfdi.ScenarioError, match=r"faults\[0\]\.components\[1\] = 'phi_e': listed twice"):
        yang.with_value("faults[0].components", ["phi_e", "phi_e"])


# ---- 3. Ctrl-C --------------------------------------------------------------------------------
KI_SCRIPT = """
import sys
import numpy.lib
orig = numpy.lib.NumpyVersion
calls = [0]
def fake(v):
    calls[0] += 1
    if calls[0] > {ok}:
        raise KeyboardInterrupt
    return orig(v)
numpy.lib.NumpyVersion = fake
try:
    import navfdi
except KeyboardInterrupt:
    print("KeyboardInterrupt")
    sys.exit(130)
print("imported")
"""


@pytest.mark.parametrize("ok", [0, 1])
def test_interrupt_while_numpy_api_loads_is_a_keyboard_interrupt(ok):
    """rust-numpy loads numpy's C API with Python code (NumpyVersion) and panics if that raises:
    a Ctrl-C there was a PanicException. ok=0: the interrupt hits navfdi's own pre-load;
    ok=1: it hits rust-numpy's load, which navfdi guards."""
    out = subprocess.run([sys.executable, "-c", KI_SCRIPT.format(ok=ok)], capture_output=True, text=True, timeout=60)
    assert "Panic" not in out.stderr, out.stderr
    assert out.returncode == 130 and "KeyboardInterrupt" in out.stdout, (out.stdout, out.stderr)


def _interrupt_after(seconds: float) -> threading.Timer:
    timer = threading.Timer(seconds, _thread.interrupt_main)
    timer.start()
    return timer


def test_long_rust_loop_stops_on_ctrl_c(yang, sigint_handled):
    """A chunk of 400 runs on one thread takes seconds; the interrupt must stop it at once."""
    prep = _core.PreparedScenario(yang.to_json())
    t0 = time.perf_counter()
    prep.run_chunk(0, 0, 8, 1)
    per_run = (time.perf_counter() - t0) / 8
    runs = int(6.0 / per_run) + 1  # about 6 s of work
    timer = _interrupt_after(0.3)
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        prep.run_chunk(0, 0, runs, 1)
    elapsed = time.perf_counter() - t0
    timer.cancel()
    assert elapsed < 0.3 + 2.0, f"stopped after {elapsed:.2f} s of a {runs * per_run:.1f} s chunk"
    # the object is still usable afterwards
    assert prep.run_chunk(0, 0, 1, 1)["run"].tolist() == [0]


def test_run_filter_stops_on_ctrl_c(sigint_handled):
    """A run_filter of about 4 s (large state, bounded memory) stops within ~1 s of Ctrl-C."""
    rng = np.random.default_rng(0)
    n = 150
    P0, Q = np.eye(n), np.eye(n) * 1e-3
    H = rng.standard_normal((1, n))
    t0 = time.perf_counter()
    navfdi.run_filter(np.zeros(n), P0, np.eye(n), Q, np.zeros((20, 1)), H, np.eye(1))
    per_epoch = (time.perf_counter() - t0) / 20
    T = int(4.0 / per_epoch) + 1
    zs = rng.standard_normal((T, 1))
    timer = _interrupt_after(0.2)
    t0 = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        navfdi.run_filter(np.zeros(n), P0, np.eye(n), Q, zs, H, np.eye(1))
    elapsed = time.perf_counter() - t0
    timer.cancel()
    assert elapsed < 0.2 + 1.5, f"stopped after {elapsed:.2f} s of a {T * per_epoch:.1f} s run"


def test_ctrl_c_mid_chunk_on_the_command_line(tmp_path, sigint_child):
    """One chunk of 4000 runs (tens of seconds); SIGINT must end the process within seconds,
    with exit 130 and the (empty) partial results written."""
    out = tmp_path / "mc"
    proc = subprocess.Popen(
        [sys.executable, "-m", "navfdi", "montecarlo", "yang2013", "--runs", "4000", "--chunk-size", "4000", "--out", str(out)],
        preexec_fn=sigint_child,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    time.sleep(4.0)
    t0 = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    elapsed = time.perf_counter() - t0
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "Panic" not in stderr
    assert elapsed < 3.0, f"took {elapsed:.1f} s to stop"
    assert (out / "campaign.json").exists() and (out / "summary.csv").exists()


# ---- 4. enormous runs -------------------------------------------------------------------------
@pytest.mark.parametrize(("path", "value"), [("duration", "1e9 s"), ("dt", "1e-6 s"), ("duration", "1e300 s")])
def test_enormous_runs_are_refused_before_allocating(yang, path, value):
    with pytest.raises(ScenarioTooLarge, match=r"needs about .* of memory .* shorten duration or increase dt") as e:
        yang.with_value(path, value)
    assert isinstance(e.value, MemoryError) and isinstance(e.value, navfdi.ScenarioError)


def test_enormous_run_on_the_command_line(tmp_path):
    text = (Path(navfdi.__file__).parent / "scenarios" / "yang2013.toml").read_text()
    f = tmp_path / "big.toml"
    f.write_text(text.replace('duration = "1000 s"', 'duration = "1e9 s"'))
    out = cli("run", str(f))
    assert out.returncode == 2 and "needs about" in out.stderr and "duration" in out.stderr
    assert "Traceback" not in out.stderr and out.stderr.count("navfdi: error:") == 1


def test_run_filter_output_too_large_is_refused():
    """T × n × n covariances that cannot fit are refused before allocating."""
    n = 1000
    zs = np.zeros((100_000, 1))  # 100 000 × 1000² × 8 B = 800 GB of P
    with pytest.raises(MemoryError, match=r"run_filter: needs about .* \(split zs\)"):
        navfdi.run_filter(np.zeros(n), np.eye(n), np.eye(n), np.zeros((n, n)), zs, np.ones((1, n)), np.eye(1))


def test_huge_campaigns_are_refused(yang):
    with pytest.raises(ScenarioTooLarge, match=r"montecarlo: needs about"):
        navfdi.montecarlo(yang, runs=10**12, progress=False)
    with pytest.raises(ScenarioTooLarge, match=r"kept series"):
        navfdi.montecarlo(yang.with_value("duration", "1e6 s"), runs=100_000, keep_series=range(100_000), progress=False)
    out = cli("montecarlo", "yang2013", "--runs", "1e12")
    assert out.returncode == 2 and "needs about" in out.stderr and "Traceback" not in out.stderr


def test_memory_limit_from_the_environment():
    code = "import navfdi._core as c; print(c.memory_available())"
    env = {**__import__("os").environ, "NAVFDI_MEMORY_LIMIT": "123456789"}
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=60)
    assert float(out.stdout) <= 123456789


# ---- 5. tracebacks on the command line --------------------------------------------------------
@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["run", "yang2013", "--seed", str(2**64)], "outside 0 .. 2**64 - 1"),
        (["run", "yang2013", "--seed", "-1"], "outside 0 .. 2**64 - 1"),
        (["montecarlo", "yang2013", "--runs", "0"], "not a positive integer"),
        (["montecarlo", "yang2013", "--runs", "2", "--keep-series", "x"], "'x' is not a run index"),
        (["montecarlo", "yang2013", "--runs", "2", "--keep-series", "7"], "run 7 is outside the campaign's runs 0..1"),
        (["montecarlo", "yang2013", "--runs", "2", "--sweep", "faults[0.magnitude=1 sigma/s"], "malformed field path"),
        (["run", "no_such_scenario"], "neither a scenario file nor a bundled scenario"),
    ],
)
def test_cli_errors_are_one_line(args, message):
    out = cli(*args)
    assert out.returncode == 2, out.stderr
    assert message in out.stderr and "Traceback" not in out.stderr


def test_cli_debug_shows_the_traceback():
    out = cli("--debug", "run", "no_such_scenario")
    assert out.returncode == 2 and "Traceback" in out.stderr


def test_cli_unreachable_scheduler_is_named():
    out = cli("montecarlo", "yang2013", "--runs", "2", "--scheduler", "tcp://127.0.0.1:1", timeout=120)
    assert out.returncode == 2, out.stderr
    assert "cannot reach the Dask scheduler" in out.stderr and "write" not in out.stderr and "Traceback" not in out.stderr


# ---- 6. unusable --out found before any work --------------------------------------------------
def test_unusable_out_is_refused_before_the_campaign(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    t0 = time.perf_counter()
    out = cli("montecarlo", "yang2013", "--runs", "100000", "--out", str(blocker))
    assert out.returncode == 2 and "exists and is not a directory" in out.stderr
    assert time.perf_counter() - t0 < 30  # 100 000 runs would take minutes
    assert blocker.read_text() == "x"
    out = cli("run", "yang2013", "--out", "")
    assert out.returncode == 2 and "--out: empty path" in out.stderr


def test_read_only_out_is_refused(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    try:
        import os

        if os.access(ro, os.W_OK):
            pytest.skip("running as a user who can write anywhere")
        out = cli("run", "yang2013", "--out", str(ro / "sub"))
        assert out.returncode == 2 and "not writable" in out.stderr
    finally:
        ro.chmod(0o700)


# ---- 8. misleading messages -------------------------------------------------------------------
@pytest.mark.parametrize(
    ("path", "value", "message"),
    [
        ("faults[0].magnitude", "nan sigma/s", r"faults\[0\]\.magnitude = 'nan sigma/s': must be finite"),
        ("faults[0].magnitude", "inf arcsec/s", r"faults\[0\]\.magnitude = 'inf arcsec/s': must be finite"),
        ("sensors[0].noise", "-1 deg", r"sensors\[0\]\.noise = '-1 deg': a noise standard deviation must be positive"),
        ("sensors[0].noise", "0 deg", r"sensors\[0\]\.noise = '0 deg': a noise standard deviation must be positive"),
        ("sensors[0].name", "", r"sensors\[0\]\.name = '': must not be empty"),
        ("sensors[0].name", " cns", r"must not start or end with white space"),
        ("faults[0].id", "", r"faults\[0\]\.id = '': must not be empty"),
    ],
)
def test_scenario_messages_name_the_field(yang, path, value, message):
    with pytest.raises(navfdi.ScenarioError, match=message):
        yang.with_value(path, value)


def test_wrong_length_z_blames_z():
    kf = navfdi.KalmanFilter(np.zeros(3), np.eye(3))
    with pytest.raises(ValueError, match=r"^z: expected shape \(2,\) to match H"):
        kf.update(np.zeros(3), np.ones((2, 3)), np.eye(2))
    with pytest.raises(ValueError, match=r"^R: expected shape \(2, 2\)"):
        kf.update(np.zeros(2), np.ones((2, 3)), np.eye(3))


def test_sprt_dimension_message_names_a_real_method():
    for det in (navfdi.ImprovedSprt(0.01, 0.01), navfdi.JointChi2Sprt(0.01, 0.01)):
        det.test(np.zeros(2), np.eye(2))
        with pytest.raises(ValueError, match=r"reset_dimension\(\)") as e:
            det.test(np.zeros(3), np.eye(3))
        method = str(e.value).split("call ")[1].split("(")[0]
        assert hasattr(det, method)
        getattr(det, method)()
        assert det.test(np.zeros(3), np.eye(3)).dof == 3


def test_small_probabilities_print_compactly():
    assert navfdi.chi2_threshold(1e-300, 3) == pytest.approx(1388.3367738546858, rel=1e-12)
    with pytest.raises(ValueError) as e:
        navfdi.chi2_threshold(1e-320 * 0, 3)
    assert len(str(e.value)) < 120
    with pytest.raises(ValueError) as e2:
        navfdi.sprt_threshold(1e-300, 1.0)
    assert len(str(e2.value)) < 160 and "000000000" not in str(e2.value)


# ---- 9. silent acceptance ---------------------------------------------------------------------
def test_fault_window_outside_the_run(yang):
    with pytest.raises(navfdi.ScenarioError, match=r"faults\[0\]: window \[2000, 2100\] s lies outside the run"):
        yang.with_value("faults[0].end", "2100 s").with_value("faults[0].start", "2000 s")


def test_fault_on_a_sensor_without_subfilter(yang):
    raw = copy.deepcopy(yang.raw)
    raw["sensors"].append({"name": "baro", "kind": "baro", "noise": "1 m", "rate": "1 Hz"})
    raw["faults"].append({"id": "b", "sensor": "baro", "components": "all", "kind": "step", "magnitude": "5 m", "start": "10 s", "end": "20 s"})
    with pytest.raises(navfdi.ScenarioError, match=r"faults\[2\]\.sensor: no sub-filter uses sensor \"baro\""):
        navfdi.load_scenario(raw)


def test_sweep_given_as_a_string_and_malformed_paths(yang):
    with pytest.raises(navfdi.ScenarioError, match=r"expected a list of values"):
        navfdi.montecarlo(yang, runs=1, sweep={"faults[0].magnitude": "0.1 sigma/s"}, progress=False)
    for bad in ["faults[0.magnitude", "faults[x].magnitude", "faults..magnitude", "faults[0]]", ".faults"]:
        with pytest.raises(navfdi.ScenarioError, match="malformed field path"):
            yang.with_value(bad, "1 sigma/s")


def test_keep_series_outside_the_runs(yang):
    with pytest.raises(ValueError, match=r"keep_series: run 5 is outside"):
        navfdi.montecarlo(yang, runs=2, keep_series=[5], progress=False)
    with pytest.raises(ValueError, match=r"keep_series: run -1 is outside"):
        navfdi.montecarlo(yang, runs=2, keep_series=[-1], progress=False)


def test_short_trajectory_warns_that_the_last_segment_is_held(yang):
    with pytest.warns(ScenarioWarning, match=r"cover 680 s of the 1000 s run: the last segment \(level\) is held for the remaining 320 s"):
        yang.with_value("trajectory.segments[7].duration", "10 s")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        navfdi.load_scenario("yang2013")  # the bundled one covers its run


def test_short_trajectory_warning_is_one_line_on_the_command_line(tmp_path):
    text = (Path(navfdi.__file__).parent / "scenarios" / "yang2013.toml").read_text()
    f = tmp_path / "short.toml"
    f.write_text(text.replace('{ kind = "level", duration = "330 s" }', '{ kind = "level", duration = "30 s" }'))
    out = cli("run", str(f), "--no-figures")
    assert out.returncode == 0, out.stderr
    assert "navfdi: warning: trajectory.segments cover 700 s of the 1000 s run" in out.stderr


@pytest.mark.parametrize(
    ("segment", "message"),
    [
        ({"kind": "descent", "duration": "100 s", "rate": "50 m/s"}, r"trajectory\.segments\[2\]: the descent goes below the Earth's surface"),
        ({"kind": "accelerate", "duration": "20 s", "acceleration": "1000 m/s2"}, r"trajectory\.segments\[2\]\.acceleration: 1000 m/s² exceeds"),
        ({"kind": "accelerate", "duration": "100 s", "acceleration": "90 m/s2"}, r"trajectory\.segments\[2\]: the ground speed reaches"),
    ],
)
def test_impossible_trajectories(yang, segment, message):
    with pytest.raises(navfdi.ScenarioError, match=message):
        yang.with_value("trajectory.segments[2]", segment)


def test_held_descent_below_the_surface(yang):
    raw = copy.deepcopy(yang.raw)
    raw["trajectory"]["segments"] = [{"kind": "descent", "duration": "1 s", "rate": "2 m/s"}]
    with pytest.warns(ScenarioWarning):
        with pytest.raises(navfdi.ScenarioError, match=r"the last segment is held until the end of the run"):
            navfdi.load_scenario(raw)


# ---- 10. bundled names and directories --------------------------------------------------------
def test_directory_named_like_a_bundled_scenario(tmp_path):
    (tmp_path / "yang2013").mkdir()  # e.g. left by `--out yang2013`
    out = cli("run", "yang2013", "--no-figures", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "scenario yang2013 (yang2013)" in out.stdout
    out = cli("run", "./yang2013", cwd=tmp_path)
    assert out.returncode == 2 and "is a directory, not a scenario file" in out.stderr


def test_file_named_like_a_bundled_scenario_needs_a_path(tmp_path):
    text = (Path(navfdi.__file__).parent / "scenarios" / "yang2013.toml").read_text()
    (tmp_path / "yang2013").write_text(text.replace('name = "yang2013"', 'name = "mine"'))
    assert navfdi.load_scenario("yang2013").name == "yang2013"
    assert navfdi.load_scenario(tmp_path / "yang2013").name == "mine"


# ---- 7. FederatedFilter configuration --------------------------------------------------------
def _subs(**over):
    base = {"name": "a", "H": np.eye(2), "R": np.eye(2), "share": 0.5, "detectors": [{"name": "chi2", "kind": "chi2", "pf": 0.01}], "isolation": "chi2"}
    other = {"name": "b", "H": np.eye(2), "R": np.eye(2), "share": 0.5}
    base.update(over)
    return [base, other]


@pytest.mark.parametrize(
    ("subs", "message"),
    [
        (_subs(isolaton="chi2"), r"subfilters\[0\]: unknown key \"isolaton\" \(allowed: name, H, R, share, detectors, isolation\)"),
        (_subs(detectors=[{"name": "c", "kind": "chi2", "pf": 0.01, "pff": 1}]), r"subfilters\[0\]\.detectors\[0\]: unknown key \"pff\""),
        (_subs(pf="0.1"), r'unknown key "pf"'),
        (_subs(detectors=[{"kind": "chi2", "pf": "0.1"}]), r"subfilters\[0\]\.detectors\[0\]\.pf: expected a number, got str '0.1'"),
        (_subs(share="0.5"), r"subfilters\[0\]\.share: expected a number, got str '0.5'"),
        (_subs(name=3), r"subfilters\[0\]\.name: expected a string, got int 3"),
        (_subs(name="b"), r"subfilters\[1\]\.name = \"b\": used by an earlier sub-filter"),
        (_subs(detectors=[{"kind": "chi2", "pf": 0.01}, {"kind": "chi2", "pf": 0.1}], isolation=None), r"detectors\[1\]\.name = \"chi2\": used by an earlier detector"),
        (_subs(detectors=[{"kind": "sprt", "pf": 0.01, "pm": 0.01, "min_samples": 0}], isolation=None), r"min_samples"),
        (_subs(detectors=[{"kind": "sprt", "pf": 0.01, "pm": True}], isolation=None), r"pm: expected a number, got bool"),
    ],
)
def test_federated_filter_config_errors_name_the_key(subs, message):
    with pytest.raises(ValueError, match=message):
        navfdi.FederatedFilter(np.zeros(2), np.eye(2), subs)


# ---- 11. sample-variance SPRT minimum sample count --------------------------------------------
def _fault_free_alarm_share(make, runs=400, T=100, m=3, seed=11):
    rng = np.random.default_rng(seed)
    A = np.tile(np.eye(m), (T, 1, 1))
    return np.mean([make().test_sequence(rng.standard_normal((T, m)), A).alarm.any() for _ in range(runs)])


def test_sample_variance_sprt_fault_free_alarm_rate():
    """Without a minimum sample count most fault-free runs alarmed right after the start; with
    the default (20) the share of runs with any alarm in 100 epochs is as low as the
    known-variance SPRT's (both about 1 % at pf = pm = 1e-3)."""
    without = _fault_free_alarm_share(lambda: navfdi.ImprovedSprt(1e-3, 1e-3, "sample", min_samples=1))
    default = _fault_free_alarm_share(lambda: navfdi.ImprovedSprt(1e-3, 1e-3, "sample"))
    known = _fault_free_alarm_share(lambda: navfdi.ImprovedSprt(1e-3, 1e-3, "known"))
    assert without > 0.5
    assert default < 0.04 and known < 0.04
    assert navfdi.ImprovedSprt(1e-3, 1e-3, "sample").min_samples == 20
    assert navfdi.ImprovedSprt(1e-3, 1e-3).min_samples == 1


def test_min_samples_delays_but_keeps_detection():
    det = navfdi.ImprovedSprt(1e-3, 1e-3, "sample", min_samples=5)
    r = 1.0 + 0.01 * np.arange(10)[:, None]  # a clear bias with tiny spread
    seq = det.test_sequence(r, np.ones((10, 1, 1)))
    assert not seq.alarm[:4].any() and seq.alarm[4:].all()
    with pytest.raises(ValueError, match=r"min_samples = 0: must be at least 1"):
        navfdi.ImprovedSprt(1e-3, 1e-3, min_samples=0)


def test_min_samples_in_scenarios(yang):
    raw = copy.deepcopy(yang.raw)
    raw["federated"]["subfilters"][0]["detectors"][1]["min_samples"] = 0
    with pytest.raises(navfdi.ScenarioError, match=r"detectors\[1\]\.min_samples = 0: expected an integer >= 1"):
        navfdi.load_scenario(raw)


# ---- 16. threshold is a method on every detector ----------------------------------------------
def test_threshold_is_a_method_on_every_detector():
    dets = [navfdi.ResidualChi2(0.1), navfdi.ImprovedSprt(0.005, 0.005), navfdi.JointChi2Sprt(0.005, 0.005)]
    got = [d.threshold(3) for d in dets]
    assert got[0] == pytest.approx(6.2514, abs=1e-4)
    assert got[1] == got[2] == pytest.approx(5.2933, abs=1e-4)
    assert dets[1].threshold() == got[1]
    with pytest.raises(ValueError, match=r"dof: the chi-square threshold depends"):
        dets[0].threshold()
    with pytest.raises(ValueError, match=r"dof = 0"):
        dets[1].threshold(0)


# ---- 12. partial sweeps reported honestly -----------------------------------------------------
def test_partial_sweep_reports_runs_per_point(monkeypatch, tmp_path):
    import pandas as pd

    mc = sys.modules["navfdi.montecarlo"]

    sc = navfdi.load_scenario("yang2013").base()
    for path, v in [("faults[0].start", "60 s"), ("faults[0].end", "160 s"), ("faults[1].start", "220 s"), ("faults[1].end", "240 s"), ("duration", "300 s")]:
        sc = sc.with_value(path, v)
    real = mc._chunk
    calls = {"n": 0}

    def flaky(*a, **k):
        calls["n"] += 1
        if calls["n"] == 2:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(mc, "_chunk", flaky)
    camp = navfdi.montecarlo(sc, runs=4, chunk_size=4, sweep={"faults[1].magnitude": ["10 sigma", "20 sigma", "30 sigma"]}, progress=False)
    assert camp.partial and camp.runs_per_point() == [4, 0, 0]
    head = camp.format_table().splitlines()[0]
    assert "runs per point 4, 0, 0 of 4 each" in head and "PARTIAL" in head
    assert "(no finished runs)" in camp.format_table()
    camp.write(tmp_path)
    s = pd.read_csv(tmp_path / "summary.csv")
    assert set(s["faults[1].magnitude"]) == {"10 sigma", "20 sigma", "30 sigma"}
    done = s[s["faults[1].magnitude"] == "10 sigma"]
    empty = s[s["faults[1].magnitude"] != "10 sigma"]
    assert (~done.partial).all() and (done.runs == 4).all()
    assert empty.partial.all() and (empty.runs == 0).all() and empty.detection_probability.isna().all()
    assert len(empty) == 2 * len(done)


# ---- 13. pickling and copying ------------------------------------------------------------------
def _federated(rng):
    n = 3
    subs = [
        {"name": "a", "H": rng.standard_normal((2, n)), "R": np.eye(2), "share": 0.5, "detectors": [{"name": "j", "kind": "joint", "pf": 0.01, "pm": 0.01}], "isolation": "j"},
        {"name": "b", "H": rng.standard_normal((1, n)), "R": np.eye(1), "share": 0.5, "detectors": [{"kind": "sprt", "pf": 0.01, "pm": 0.01, "variance": "sample"}]},
    ]
    return navfdi.FederatedFilter(np.zeros(n), np.eye(n), subs, mode="no_reset")


@pytest.mark.parametrize("how", ["pickle", "deepcopy", "copy"])
def test_stateful_objects_pickle_and_continue_identically(how):
    import copy as copy_mod
    import pickle

    dup = {"pickle": lambda o: pickle.loads(pickle.dumps(o)), "deepcopy": copy_mod.deepcopy, "copy": copy_mod.copy}[how]
    rng = np.random.default_rng(5)
    n = 3
    Phi, Q = np.eye(n) + 0.1 * rng.standard_normal((n, n)), 0.01 * np.eye(n)
    kf = navfdi.KalmanFilter(rng.standard_normal(n), np.eye(n))
    dets = [navfdi.ResidualChi2(0.05), navfdi.ImprovedSprt(0.01, 0.01, "sample", min_samples=3), navfdi.JointChi2Sprt(0.05, 0.05)]
    fed = _federated(rng)
    H, R = rng.standard_normal((2, n)), np.eye(2)
    for _ in range(7):  # build up state
        kf.predict(Phi, Q)
        inn = kf.update(rng.standard_normal(2), H, R)
        for d in dets:
            d.test(inn.residual + 0.5, inn.covariance)
        fed.step(Phi, Q, [rng.standard_normal(2), rng.standard_normal(1)])
    copies = [dup(o) for o in (kf, *dets, fed)]
    assert all(type(c) is type(o) for c, o in zip(copies, (kf, *dets, fed)))
    kf2, dets2, fed2 = copies[0], copies[1:4], copies[4]
    for _ in range(5):
        z = rng.standard_normal(2)
        zs = [rng.standard_normal(2), rng.standard_normal(1)]
        for a in (kf, kf2):
            a.predict(Phi, Q)
        i1, i2 = kf.update(z, H, R), kf2.update(z, H, R)
        equal(i1.residual, i2.residual)
        equal(kf.P, kf2.P)
        for d1, d2 in zip(dets, dets2):
            a, b = d1.test(i1.residual + 0.5, i1.covariance), d2.test(i2.residual + 0.5, i2.covariance)
            assert a.statistic == b.statistic and a.alarm == b.alarm
        s1, s2 = fed.step(Phi, Q, zs), fed2.step(Phi, Q, zs)
        equal(s1.x, s2.x)
        equal(s1.P, s2.P)
        assert s1.isolated == s2.isolated
    assert dets2[1].min_samples == 3 and fed2.names == ["a", "b"]


def test_pickled_objects_cross_process_boundaries():
    """What Dask and multiprocessing do: unpickle in another interpreter."""
    import pickle

    kf = navfdi.KalmanFilter(np.array([1.0, 2.0]), np.eye(2))
    kf.predict(np.array([[1.0, 1.0], [0.0, 1.0]]), np.eye(2))
    code = "import pickle, sys; kf = pickle.loads(sys.stdin.buffer.read()); print(repr(kf.P.tolist()))"
    out = subprocess.run([sys.executable, "-c", code], input=pickle.dumps(kf), capture_output=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert eval(out.stdout.decode()) == kf.P.tolist()


def test_corrupt_pickle_state_is_a_clear_error():
    with pytest.raises(ValueError, match=r"cannot restore a KalmanFilter"):
        _core._restore("KalmanFilter", '{"x": [1.0], "p": "nonsense"}')
    with pytest.raises(ValueError, match=r"P0: not positive semi-definite|cannot restore"):
        _core._restore("KalmanFilter", '{"x": [0.0], "p": [[-1.0], 1, 1]}')


def test_thread_safety_is_documented():
    stub = (Path(navfdi.__file__).parent / "_core.pyi").read_text(encoding="utf-8")
    assert "not thread-safe" in stub and "Already borrowed" in stub


# ---- 15. figures ------------------------------------------------------------------------------
@pytest.fixture
def captured_figures(monkeypatch):
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    figs: dict[str, Figure] = {}

    def capture(self, fname, *a, **k):
        figs[Path(fname).name] = self

    monkeypatch.setattr(Figure, "savefig", capture)
    return figs


def test_campaign_figures_have_titles_reference_lines_and_distinct_markers(captured_figures, tmp_path):
    from navfdi.plots import plot_campaign

    camp = navfdi.montecarlo("yang2013", runs=3, sweep={"faults[0].magnitude": ["0.1 sigma/s", "0.2 sigma/s"]}, progress=False)
    plot_campaign(camp, tmp_path)
    rates, delay = captured_figures["rates.png"], captured_figures["delay.png"]
    assert rates._suptitle is not None and "yang2013" in rates._suptitle.get_text()
    a1, a2 = rates.axes[:2]
    refs = [ln for ln in a2.get_lines() if ln.get_label().startswith("nominal pf")]
    assert sorted(ln.get_ydata()[0] for ln in refs) == [0.001, 0.1]
    for ax in (a1, a2, delay.axes[0]):
        series = [ln for ln in ax.get_lines() if ln.get_marker() not in (None, "None", "", "_", "|") and ln.get_linestyle() != "--"]
        assert len({ln.get_marker() for ln in series}) == len(series) > 1  # every series its own marker
        xs = {tuple(np.round(ln.get_xdata(), 6)) for ln in series}
        assert len(xs) == len(series)  # and its own x offset: coinciding lines stay visible
    assert delay.axes[0].get_title()


def test_run_figures_name_the_isolating_detector_and_show_sigma(captured_figures, tmp_path):
    from matplotlib.collections import PolyCollection

    from navfdi.plots import plot_run

    run = navfdi.run_scenario(navfdi.load_scenario("yang2013").base(), seed=1)
    plot_run(run, tmp_path)
    det = captured_figures["detector_cns_sprt.png"]
    labels = det.axes[0].get_legend_handles_labels()[1]
    assert "cns isolated (by joint)" in labels
    att = captured_figures["master_attitude_error.png"]
    for ax in att.axes:
        env = [c for c in ax.collections if isinstance(c, PolyCollection) and "σ" in c.get_label()]
        assert len(env) == 1
        top = env[0].get_paths()[0].vertices[:, 1].max()
        sig = run.record["sigma"][:, :3].max() * np.degrees(1) * 3600
        assert top == pytest.approx(sig, rel=0.05) or top > 0


# ---- 16. docs and rules that drifted ----------------------------------------------------------
DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_demo_matches_alarms_with_the_rule_of_run_and_montecarlo():
    """The demo, run and montecarlo all match through the Rust engine (match_events), by the
    onset rule: an alarm detects a fault when it is raised inside the window or up
    to GRACE = 1 s (one epoch) after it; an alarm raised before the fault detects nothing."""
    from navfdi._intervals import GRACE, match_events
    from navfdi.demo import FAULTS

    assert GRACE == 1.0
    t = np.arange(600.0)
    windows = [(f.start, f.end) for f in FAULTS]  # ramp 20-220 s, step 400-450 s
    cases = [
        ((221, 230), 0),  # 1 s after the ramp: within the grace, the detector's latency
        ((223, 240), None),  # 3 s after: the clearing transient or a false alarm
        ((219, 221), 0),
        ((10, None), None),  # raised before the ramp: in alarm at onset, not a detection
        ((300, 410), None),  # raised before the step
        ((451, None), 1),
        ((452, None), None),
        ((405, 406), 1),
    ]
    for (start, end), expected in cases:
        alarm = (t >= start) & (t < (np.inf if end is None else end))
        [(iv, m)] = match_events(alarm, t, windows)
        assert (iv.start, iv.end) == (start, end) and m == expected, (start, end, m)


def test_documented_sprt_outside_fault_rate_is_measured():
    text = (DOCS / "montecarlo.md").read_text(encoding="utf-8")
    assert "0.716 with seed 0" in text
    s = navfdi.montecarlo("yang2013", runs=100, seed=0, progress=False).summary()
    row = s[(s.fault_id == "none") & (s.detector == "sprt")]
    assert round(float(row.false_alarm_rate.iloc[0]), 3) == 0.716


def test_cli_error_window_is_the_documented_one():
    out = cli("run", "yang2013", "--no-figures")
    assert "RMS over 300–999 s (first fault to end of run)" in out.stdout
    assert "300–999 s" in (DOCS / "yang2013.md").read_text(encoding="utf-8")
