"""What a new user meets: the detection definition, console output that fits 100
columns, commands that say what they did, and objects that explain themselves."""

from __future__ import annotations

import io
import math
import subprocess
import sys
import warnings
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi._intervals import GRACE, match_events, window_alarm
from navfdi.cli import main

DATA = Path(__file__).parent / "data" / "rinex"


# ---- detection definition ------------------------------------------------------------------


def _alarm(t, start, end=None):
    return (t >= start) & (t < (np.inf if end is None else end))


def test_detection_is_an_onset_inside_the_window():
    t = np.arange(0.0, 100.0)
    window = [(40.0, 60.0)]
    # Onset inside: detected, delay from the fault's start; not "in alarm at onset".
    a = _alarm(t, 45, 70)
    [(iv, m)] = match_events(a, t, window)
    assert m == 0 and iv.start == 45
    assert window_alarm(a, t, 40, 60) == (False, 0.75)
    # Alarm running at onset (raised at 30 s): no detection, reported as in alarm at onset,
    # with every fault epoch in alarm.
    a = _alarm(t, 30, 70)
    [(iv, m)] = match_events(a, t, window)
    assert m is None
    assert window_alarm(a, t, 40, 60) == (True, 1.0)
    # Onset after the end (beyond the grace): no detection.
    a = _alarm(t, 60 + GRACE + 1, 80)
    [(iv, m)] = match_events(a, t, window)
    assert m is None and window_alarm(a, t, 40, 60) == (False, 0.0)
    # Onset within the grace after the end (one epoch): detected.
    assert match_events(_alarm(t, 60 + GRACE, 80), t, window)[0][1] == 0


def test_run_tables_report_alarms_running_at_onset_separately():
    """yang2013 seed 0: the joint detector is in alarm from 799 s, so the 800 s step is not
    'detected at 800, delay 0' any more but missed, in alarm at onset, 100 % in alarm."""
    r = navfdi.run_scenario("yang2013", seed=0)
    rows = {(m.fault_id, m.detector): m for m in r.runs["isolation"].fault_table()}
    step = rows[("cns-step", "joint")]
    assert step.detected_at is None and step.in_alarm_at_onset and step.alarm_fraction == 1.0
    assert "before the fault" in step.note
    ramp = rows[("cns-ramp", "chi2")]
    assert ramp.detected_at is not None and ramp.delay >= 0 and not ramp.in_alarm_at_onset


def test_campaign_summary_has_onset_and_alarm_fraction_beside_pdet():
    c = navfdi.montecarlo("gao_fading", runs=3, seed=0, progress=False)
    s = c.summary()
    f = s[(s.fault_id != "none") & (s.detector == "chi2") & (s.variant == "chi2")].iloc[0]
    assert 0.0 <= f["alarm_fraction"] < 0.2 and f["in_alarm_at_onset"] == 0.0
    assert {"at_onset", "alarm_fraction"} <= set(c.runs.columns)


# ---- console output --------------------------------------------------------------------------


def _cli(*args: str) -> str:
    buf = io.StringIO()
    with warnings.catch_warnings(), redirect_stdout(buf):
        warnings.simplefilter("ignore")
        assert main(list(args)) == 0
    return buf.getvalue()


@pytest.mark.parametrize("name", navfdi.bundled_scenarios())
def test_run_and_montecarlo_output_fit_100_columns(name, tmp_path):
    for out in (_cli("run", name, "--out", str(tmp_path / "run"), "--no-figures"), _cli("montecarlo", name, "--runs", "2", "--workers", "2")):
        long = [line for line in out.splitlines() if len(line) > 100]
        assert not long, long
        assert "Some(" not in out and " nan " not in out


def test_other_commands_fit_100_columns(tmp_path):
    for out in (
        _cli("demo"),
        _cli("scenarios"),
        _cli("gnss", str(DATA / "rover.obs.gz"), str(DATA / "base.nav"), "--fault", "G13:step:20m:100s:200s", "--truth-file", str(DATA / "rover_position.txt")),
    ):
        long = [line for line in out.splitlines() if len(line) > 100]
        assert not long, long


def test_montecarlo_pools_many_channels_and_stays_short():
    out = _cli("montecarlo", "liu2022", "--runs", "2", "--workers", "2")
    assert len(out.splitlines()) < 60
    assert "8 channels" in out


def test_variant_output_prints_the_legend_and_paper_remark_once():
    out = _cli("run", "geng2016")
    assert out.count("paper 002's λ0 = 17.872") == 1
    assert out.count("lasting from: start of the alarm") <= 1
    out = _cli("run", "liu2022")
    assert "8–8" not in out


def test_without_out_the_commands_say_nothing_was_written():
    out = _cli("run", "calibration")
    assert "nothing written: add --out DIR" in out


def test_scenarios_show_and_export(tmp_path):
    text = _cli("scenarios", "--show", "yang2013")
    assert text.startswith("#") and 'name = "yang2013"' in text
    out = _cli("scenarios", "--export", "yang2013", str(tmp_path))
    assert (tmp_path / "yang2013.toml").read_text() == text and "navfdi run" in out
    assert main(["scenarios", "--export", "yang2013", str(tmp_path)]) == 2  # never overwritten
    assert main(["scenarios", "--show", "nope"]) == 2
    sc = navfdi.load_scenario(tmp_path / "yang2013.toml")
    assert sc.name == "yang2013"


def test_a_closed_pipe_ends_quietly():
    p = subprocess.run(f"{sys.executable} -m navfdi scenarios --show shao2018 | head -1", shell=True, capture_output=True, text=True)
    assert p.returncode == 0 and "Broken pipe" not in p.stderr and p.stdout.startswith("#")


# ---- objects that explain themselves -------------------------------------------------------


def test_a_missing_variant_names_the_variants():
    r = navfdi.run_scenario("yang2013", seed=0)
    with pytest.raises(KeyError, match=r"no variant 'isolated'; the variants are: 'isolation', 'no_isolation'"):
        r.runs["isolated"]
    with pytest.raises(KeyError, match="the variants are"):
        r["isolated"]


@pytest.mark.parametrize("make", [lambda: navfdi.JointChi2Sprt(pf="1e-3", pm=1e-3), lambda: navfdi.ImprovedSprt(1e-3, "x"), lambda: navfdi.ResidualChi2(pf=None), lambda: navfdi.Aime("0.01", 5), lambda: navfdi.StateChi2(pf=True, n=2, reset_every=2)])
def test_a_wrong_argument_type_is_named(make):
    with pytest.raises(TypeError, match=r"^(pf|pm): expected a number"):
        make()


def test_help_describes_the_kalman_filter():
    doc = navfdi.KalmanFilter.__doc__ or ""
    assert "predict(" in doc and "update(" in doc and "Joseph" in doc and "see `navfdi._core.pyi`" not in doc


def test_printing_a_scenario_is_one_line():
    text = repr(navfdi.load_scenario("shao2018"))
    assert "\n" not in text and len(text) < 300 and "tight" in text and "ls_precheck" in text


def test_an_interrupted_campaign_keeps_its_variants_comparable(monkeypatch):
    """Chunks run point by point in turn: stopping after three chunks leaves both variants of
    yang2013 with runs (before, the first variant took every chunk until it was done)."""
    mc = sys.modules["navfdi.montecarlo"]

    calls = {"n": 0}
    real = mc._chunk

    def stop_after_three(*a, **k):
        calls["n"] += 1
        if calls["n"] > 3:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(mc, "_chunk", stop_after_three)
    c = navfdi.montecarlo("yang2013", runs=64, seed=0, chunk_size=16, workers=2, progress=False)
    assert c.partial and all(n > 0 for n in c.runs_per_point()), c.runs_per_point()


def test_figures_name_the_variant_they_show(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    seen = []
    real = plt.Figure.savefig

    def grab(self, path, *a, **k):
        if str(path).endswith("master_attitude_error.png"):
            seen.append((Path(path).name, [t.get_text() for ax in self.axes for t in (ax.get_legend().get_texts() if ax.get_legend() else [])], [ax.get_title() for ax in self.axes]))
        return real(self, path, *a, **k)

    with pytest.MonkeyPatch.context() as m:
        m.setattr(plt.Figure, "savefig", grab)
        navfdi.run_scenario("yang2013", seed=0).write(tmp_path)
    labels = {name: (texts, titles) for name, texts, titles in seen}
    texts, titles = labels["no_isolation_master_attitude_error.png"]
    assert "variant no_isolation" in texts and "with isolation" not in texts and "fault window" in texts
    assert "(no_isolation)" in titles[0]
