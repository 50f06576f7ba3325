"""The σ model of ``navfdi gnss`` estimated from the file by default (``weighting="auto"``,
``noise_scale="auto"``), on one reading of the files: ``GnssRun.restart`` solves the same
observations again with other settings, to the same bits as a fresh run."""

from __future__ import annotations

import gzip
import warnings
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import _core
from navfdi.cli import main

WALK = Path(navfdi.__file__).parent / "data" / "walk_0827"
OBS, NAV = str(WALK / "gnss_1730.obs.gz"), str(WALK / "gnss_1730.nav")
SEQ = ((1e-3, 1e-3), (1e-3, 10), (1.0, 5.0, 60.0, 20, 0.02))


def _run(weighting: str = "elevation", slope: float = 1.0, factors: dict[str, float] | None = None, exclude: bool = False,
         test: str = "global") -> _core.GnssRun:
    return _core.GnssRun(OBS, NAV, ["G", "E"], 10.0, 0.01, None, exclude, (0.3, 0.3), weighting, True, True, [], {},
                         factors or {}, *SEQ, 45.0, test, 0.8, slope)  # fmt: skip


def _solved(run: _core.GnssRun) -> tuple[dict, dict]:
    while run.done < run.n_epochs:
        run.advance(200)
    return run.epoch_table(), run.estimation_table()


def test_restart_solves_as_a_fresh_run_does() -> None:
    run = _run()
    _solved(run)
    settings = ("cn0", 1.5, {"G": 2.0, "E": 0.7}, True, "wtest")
    run.restart(*settings)
    assert run.done == 0
    ep, est = _solved(run)
    ep0, est0 = _solved(_run(*settings))
    for k in ("statistic", "dof", "first_statistic", "first_dof", "x", "k0"):
        assert np.array_equal(ep[k], ep0[k], equal_nan=True), k
    assert ep["excluded"] == ep0["excluded"] and any(ep["excluded"])
    for k in ("w", "cn0", "used"):
        assert np.array_equal(est[k], est0[k], equal_nan=True), k
    # The estimation table is the tables' columns, without their strings.
    sats = run.satellite_table()
    assert np.array_equal(est["used"], np.asarray(sats["status"]) == "used")
    assert np.array_equal(est["w"], sats["w"], equal_nan=True)


def test_a_bad_restart_is_named_and_leaves_the_run_as_it_was() -> None:
    run = _run()
    ep, _ = _solved(run)
    for bad, what in ((("snr", 1.0, {}, True, "global"), "weighting: 'snr'"), (("cn0", 9.0, {}, True, "global"), "cn0_slope: 9"),
                      (("elevation", 1.0, {"R": 2.0}, True, "global"), "systems: 'R'"),
                      (("elevation", 1.0, {}, True, "chi2"), "chi2")):  # fmt: skip
        with pytest.raises(ValueError, match=what):
            run.restart(*bad)
        assert run.done == run.n_epochs
        assert np.array_equal(run.epoch_table()["statistic"], ep["statistic"], equal_nan=True)


def test_the_default_estimates_the_model_from_the_file() -> None:
    """The walk's handheld u-blox: the σ model as given excludes at a third of the fault-free
    epochs; the default (the C/N0 model, the factor fitted) at none, as ``auto`` given by hand,
    and the estimates' solves are counted."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        given = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="elevation", noise_scale=1.0)
        default = navfdi.gnss_solve(OBS, NAV, systems="G,E")
        by_hand = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="auto", noise_scale="auto", cn0_slope="auto")
    assert given.summary()["false_exclusion_rate"] > 0.25
    assert default.summary()["false_exclusion_rate"] <= 0.01
    c = default.config
    assert c["weighting"] == "cn0" and c["noise_scale_estimated"] and 1.0 < c["noise_scale"] < 2.0
    assert c["estimation_solves"] >= 2 + 1 + c["noise_scale_auto"]["iterations"]
    assert default.solution.equals(by_hand.solution)
    # The console says what was estimated.
    assert "--weighting auto" in default.format_summary() and "--noise auto" in default.format_summary()


def _cut(tmp_path: Path, epochs: int) -> str:
    """The walk's observation file cut to its first ``epochs`` epochs."""
    lines = gzip.open(OBS, "rt").read().split("\n")
    end = next(i for i, line in enumerate(lines) if "END OF HEADER" in line)
    out, seen = lines[: end + 1], 0
    for line in lines[end + 1 :]:
        if line.startswith(">"):
            seen += 1
            if seen > epochs:
                break
        out.append(line)
    p = tmp_path / "short.obs"
    p.write_text("\n".join(out) + "\n")
    return str(p)


def test_a_short_file_keeps_the_model_as_given_with_a_warning(tmp_path: Path, capsys) -> None:
    short = _cut(tmp_path, 12)
    with pytest.warns(UserWarning, match="at least 20 are needed.*the sigma factor stays 1"):
        sol = navfdi.gnss_solve(short, NAV, systems="G,E")
    assert sol.config["noise_scale"] == 1.0 and len(sol.solution) == 12
    assert sol.config["noise_scale_auto"]["method"].startswith("too few epochs")
    assert main(["gnss", short, NAV, "--systems", "G,E", "--no-figures"]) == 0
    out = capsys.readouterr().out.replace("\n  ", " ")
    assert "noise: sigma factor 1 (--noise auto: too few epochs could be tested to estimate it; 20 needed)" in out
    assert "too few epochs to compare the models" in out and "nan" not in out.split("weighting:")[1]
    # A factor given by hand is taken as it is, without estimates.
    fixed = navfdi.gnss_solve(short, NAV, systems="G,E", weighting="elevation", noise_scale=2.0)
    assert fixed.config["noise_scale"] == 2.0 and "noise_scale_auto" not in fixed.config


def test_residuals_that_are_not_code_noise_are_named(tmp_path: Path) -> None:
    """The bundled static file twice, the copy's epochs moved on by the file's span (the
    satellites are then not where its ranges say): the factor would be 10^5; the run says the
    residuals are not code noise."""
    import sys

    sys.path.insert(0, str(Path(__file__).parent.parent / "benches"))
    from bench_memory import DATA, day_file

    day_file(tmp_path / "two.rnx", 2)
    with pytest.warns(UserWarning, match="times the sigma model's: they are not code noise"):
        sol = navfdi.gnss_solve(str(tmp_path / "two.rnx"), str(DATA / "base.nav"), systems="G,E")
    assert sol.config["noise_scale"] > 1e3


def test_a_long_file_is_estimated_on_every_kth_epoch(monkeypatch) -> None:
    """The estimates solve at most MAX_ESTIMATION_EPOCHS epochs: with the limit at 100 the
    walk (536 epochs) is estimated on every 6th, its epochs solved being those; the factor
    lands near the whole file's."""
    from navfdi import _gnss_auto

    run = _run()
    run.restart("elevation", 1.0, {}, False, "global", 6)
    ep, est = _solved(run)
    assert run.done == run.n_epochs and len(ep["statistic"]) == -(-run.n_epochs // 6)
    full = _run()
    ep1, _ = _solved(full)
    # The epochs solved are the file's 0th, 6th, …: the first is solved alike (the same start).
    assert ep["first_statistic"][0] == ep1["first_statistic"][0]
    with pytest.raises(ValueError, match="every = 0"):
        run.restart("elevation", 1.0, {}, False, "global", 0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="elevation")
        monkeypatch.setattr(_gnss_auto, "MAX_ESTIMATION_EPOCHS", 100)
        strided = navfdi.gnss_solve(OBS, NAV, systems="G,E", weighting="elevation")
    assert whole.config["estimation_every"] == 1 and strided.config["estimation_every"] == 6
    assert len(strided.solution) == 536  # the run itself solves every epoch
    assert strided.config["noise_scale"] == pytest.approx(whole.config["noise_scale"], rel=0.15)
