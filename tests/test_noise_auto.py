"""``noise_scale="auto"`` on files whose statistic is set by their faults: the walk's RINEX with
multipath-like bursts (10–40 m on each satellite for ~10 % of its time) added to its code
observations, beside the same file clean."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import ModuleType

import pytest

import navfdi
from navfdi.cli import main
from navfdi._gnss_noise import AUTO_NOISE_CONTAMINATION_RATIO, estimate_noise_scale

PKG = Path(navfdi.__file__).parent / "data" / "walk_0827"
OBS, NAV = PKG / "gnss_1730.obs.gz", str(PKG / "gnss_1730.nav")


@pytest.mark.parametrize("weighting", ["elevation", "cn0"])
def test_auto_keeps_the_whole_file_factor_on_a_clean_receiver(weighting: str) -> None:
    """Clean walk: both estimates agree within the contamination ratio, so the whole file's
    factor (the one that holds α on these heavy-tailed residuals) is used, unchanged."""
    auto = navfdi.gnss_solve(str(OBS), NAV, systems="G,E", weighting=weighting, noise_scale="auto")
    a = auto.config["noise_scale_auto"]
    plain = navfdi.gnss_solve(str(OBS), NAV, systems="G,E", weighting=weighting, exclude=False, noise_scale=1.0)
    assert a["method"] == "whole file"
    assert a["scale"] == auto.config["noise_scale"] == estimate_noise_scale(plain.solution)
    # The iteration from below lands under the whole file's factor (heavier tails than a
    # Gaussian), within the ratio.
    assert a["faults_excluded"] < a["whole_file"] <= AUTO_NOISE_CONTAMINATION_RATIO * a["faults_excluded"]
    assert auto.summary()["false_exclusion_rate"] <= 0.02


def test_the_factor_is_the_receivers_whatever_the_test() -> None:
    """The faults-excluded iteration excludes with the global test whatever ``test`` runs: on
    the elevation-weighted walk with GPS's σ × 1.31, data snooping's exclusions used to let
    it settle at 1.04 (just under half the whole file's 2.11), and ``test="auto"`` then
    excluded a satellite in 29 % of the fault-free epochs."""
    runs = {t: navfdi.gnss_solve(str(OBS), NAV, systems="G,E", noise_scale="auto", noise_factors={"G": 1.31}, test=t) for t in ("global", "auto")}
    a, b = (runs[t].config["noise_scale_auto"] for t in ("global", "auto"))
    assert a == b
    assert a["method"] == "whole file"
    assert runs["auto"].summary()["false_exclusion_rate"] <= 0.03


@pytest.mark.parametrize("weighting", ["elevation", "cn0"])
def test_auto_finds_the_noise_under_multipath_bursts(tmp_path: Path, weighting: str, docs_script: Callable[[str], ModuleType]) -> None:
    """Bursts on ~10 % of every satellite's epochs inflate the whole file's factor ~10×
    (nothing is ever excluded with it, a 20 m step drowns); with the faults excluded the
    factor is within 25 % of the clean file's, and the step is found again."""
    script = docs_script("noise_auto_bursts")
    obs = str(script.bursts(tmp_path / "bursts.obs", 0.1, 0))
    clean = navfdi.gnss_solve(str(OBS), NAV, systems="G,E", weighting=weighting, noise_scale="auto").config["noise_scale"]
    auto = navfdi.gnss_solve(obs, NAV, systems="G,E", weighting=weighting, noise_scale="auto")
    a = auto.config["noise_scale_auto"]
    assert a["method"] == "faults excluded"
    assert a["whole_file"] > 5 * clean
    assert 0.75 * clean < a["scale"] < 1.25 * clean
    assert "faults excluded" in auto.format_summary() and "whole file" in auto.format_summary()
    step = ["E26:step:20m:40s:100s"]
    found = script.excluded_share(navfdi.gnss_solve(obs, NAV, systems="G,E", weighting=weighting, noise_scale=a["scale"], faults=step))
    drowned = script.excluded_share(navfdi.gnss_solve(obs, NAV, systems="G,E", weighting=weighting, noise_scale=a["whole_file"], faults=step))
    assert drowned < 0.05
    assert found >= 0.8


def test_auto_on_the_command_line_prints_both_estimates(tmp_path: Path, capsys: pytest.CaptureFixture[str], docs_script: Callable[[str], ModuleType]) -> None:
    obs = str(docs_script("noise_auto_bursts").bursts(tmp_path / "bursts.obs", 0.1, 0))
    assert main(["gnss", obs, NAV, "--systems", "G,E", "--noise", "auto", "--out", str(tmp_path / "o")]) == 0
    out = capsys.readouterr().out
    assert "estimated from the file (--noise auto): faults excluded (whole file" in out
    import json

    s = json.loads((tmp_path / "o" / "summary.json").read_text())["summary"]
    assert s["noise_scale_auto"]["method"] == "faults excluded"
    assert s["noise_scale"] == s["noise_scale_auto"]["scale"]


def _without_cn0(dst: Path) -> Path:
    """The walk's observation file with every GPS and Galileo C/N0 field (the fourth
    observation: S1C, S1X) blanked."""
    import gzip

    out, header = [], True
    for line in gzip.open(OBS, "rt").read().splitlines(keepends=True):
        if header:
            header = "END OF HEADER" not in line
        elif line[:1] in "GE" and line[1:3].isdigit() and len(line) > 3 + 16 * 3:
            body = line.rstrip("\n")
            a, b = 3 + 16 * 3, min(3 + 16 * 4, len(body))
            line = body[:a] + " " * (b - a) + body[b:] + "\n"
        out.append(line)
    dst.write_text("".join(out))
    return dst


def test_weighting_auto_takes_the_cn0_model_where_it_fits(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The walk (handheld u-blox): --weighting auto picks the C/N0 model (its statistic's
    tails nearer a fitting model's), which with --noise auto holds α (no fault-free epoch with
    an exclusion) with a smaller median MDB than the elevation model's; the same file with its
    C/N0 blanked gets the elevation model (both models are the same there)."""
    auto = navfdi.gnss_solve(str(OBS), NAV, systems="G,E", weighting="auto", noise_scale="auto")
    wa = auto.config["weighting_auto"]
    assert wa["chosen"] == "cn0" and wa["tail"]["cn0"] < wa["tail"]["elevation"]
    elev = navfdi.gnss_solve(str(OBS), NAV, systems="G,E", weighting="elevation", noise_scale="auto").summary()
    s = auto.summary()
    assert s["false_exclusion_rate"] <= 0.01 < elev["false_exclusion_rate"]
    assert s["mdb_median"] < elev["mdb_median"]
    assert s["weighting_auto"]["chosen"] == "cn0"
    plain = _without_cn0(tmp_path / "no_cn0.obs")
    none = navfdi.gnss_solve(str(plain), NAV, systems="G,E", weighting="auto").config["weighting_auto"]
    assert none["chosen"] == "elevation" and none["tail"]["cn0"] == none["tail"]["elevation"]
    assert main(["gnss", str(OBS), NAV, "--systems", "G,E", "--weighting", "auto", "--out", str(tmp_path / "o")]) == 0
    assert "weighting: cn0, chosen from the file (--weighting auto" in capsys.readouterr().out


def test_the_clean_w_spread_is_reported_per_system(capsys: pytest.CaptureFixture[str]) -> None:
    """The bundled static receiver's Galileo and GPS residuals differ in spread: the summary
    gives the robust clean-w SD per system (GPS's within 5 % of what its satellites' own w
    give) and, where they differ by more than 1.5x, the --noise-factor that models it; the
    summary line says so."""
    import numpy as np

    from navfdi._gnss_noise import robust_sd

    root = Path(__file__).parent / "data" / "rinex"
    sol = navfdi.gnss_solve(str(root / "rover.obs.gz"), str(root / "base.nav"), systems="G,E", weighting="elevation", noise_scale="auto")
    s = sol.summary()
    by = s["clean_w_sd_robust_by_system"]
    assert set(by) == {"E", "G"}
    sats = sol.satellites
    clean_epochs = np.flatnonzero((sol.solution["faulty"] == "").to_numpy())
    g = sats[sats["epoch"].isin(clean_epochs) & (sats["status"] == "used") & sats["satellite"].str.startswith("G")]["w"].to_numpy(float)
    assert by["G"] == pytest.approx(robust_sd(g[np.isfinite(g)]), rel=1e-12)
    assert max(by.values()) > 1.5 * min(by.values())
    main(["gnss", str(root / "rover.obs.gz"), str(root / "base.nav"), "--systems", "G,E", "--weighting", "elevation", "--noise", "auto"])
    out = capsys.readouterr().out.replace("\n  ", " ")
    assert "per system E" in out and "the systems differ; --noise-factor G=" in out, out
