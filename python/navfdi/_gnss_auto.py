"""The ``"auto"`` settings of :func:`navfdi.gnss.gnss_solve` — the C/N0 model's slope, the
variance model and the σ factor — estimated on one reading of the files: every estimate solves
the file several times (docs/gnss_real.md), and each solve restarts the same run
(``_core.GnssRun.restart``) instead of reading the RINEX files again."""

from __future__ import annotations

import math
import os
import warnings
from types import SimpleNamespace
from typing import Any

import numpy as np

from navfdi import _core
from navfdi._gnss_noise import TooFewEpochs, auto_noise_scale, auto_weighting, estimate_cn0_slope

#: The σ factor above which ``noise_scale="auto"`` warns: the residuals are then not code noise
#: (a navigation file of another constellation set, unmodelled clock jumps or biases), and the
#: tests at that factor find nothing smaller than its multiple of the model's σ.
IMPLAUSIBLE_NOISE_SCALE = 30.0

#: The largest σ factor :func:`navfdi.gnss.gnss_solve` takes (exclusive).
MAX_NOISE_SCALE = 1e6

#: The most epochs an estimate solves: a longer file is solved at every k-th epoch, k the
#: smallest that keeps to this (an hour of 1 Hz fixes; the estimates are quantiles and robust
#: spreads over the epochs, which this many pin down, and their solves then cost what an
#: hour's file costs however long the file is).
MAX_ESTIMATION_EPOCHS = 3600


def scaled_factors(noise_factors: dict[str, float] | None, scale: float) -> dict[str, float]:
    """Per-system σ factors by system letter (``noise_factors``, letters upper-cased), each
    system's times ``scale`` (every system's, given or 1, when ``scale`` is not 1)."""
    given = {str(k).upper(): float(v) for k, v in (noise_factors or {}).items()}
    return given if scale == 1.0 else {s: given.get(s, 1.0) * float(scale) for s in ("G", "E", "C", "J")}


def new_run(obs: str | os.PathLike[str], nav: str | os.PathLike[str], common: dict[str, Any], *, exclude: bool, weighting: str,
            cn0_slope: float, factors: dict[str, float], faults: list[tuple[str, str, float, float, float]]) -> _core.GnssRun:
    """``_core.GnssRun`` reading ``obs`` and ``nav`` with the solver settings ``common`` (see
    :class:`EstimationRun`) and these: exclusion, variance model and its C/N0 slope,
    per-system σ ``factors`` and the faults ``(satellite, shape, magnitude, start_s, end_s)``."""
    c = common
    return _core.GnssRun(
        os.fspath(obs), os.fspath(nav), list(c["systems"]), float(c["mask_deg"]), float(c["alpha"]),
        None if c["k"] is None else float(c["k"]), bool(exclude), (float(c["noise"][0]), float(c["noise"][1])), weighting,
        bool(c["ionosphere"]), bool(c["troposphere"]), faults, dict(c["codes"] or {}), factors,
        (float(c["sprt"][0]), float(c["sprt"][1])), (float(c["aime"][0]), int(c["aime"][1])),
        (float(c["cusum"][0]), float(c["cusum"][1]), float(c["cusum"][2]), int(c["cusum"][3]), float(c["cusum"][4])),
        float(c["cn0_reference"]), str(c["test"]), float(c["power"]), float(cn0_slope),
    )  # fmt: skip


class EstimationRun:
    """One reading of ``obs`` and ``nav`` with the solver settings ``common`` (the keyword
    arguments of :func:`navfdi.gnss.gnss_solve` other than the ones estimated, the faults, the
    truth and the integrity), solved again by :meth:`solve` with other σ settings — at every
    ``every``-th epoch, ``every`` the smallest that keeps to :data:`MAX_ESTIMATION_EPOCHS`."""

    def __init__(self, obs: str | os.PathLike[str], nav: str | os.PathLike[str], common: dict[str, Any]) -> None:
        self.given = common["noise_factors"]
        self.test = str(common["test"])
        self.run = new_run(obs, nav, common, exclude=False, weighting="elevation", cn0_slope=1.0,
                           factors=scaled_factors(self.given, 1.0), faults=[])
        self.solves = 0
        self.every = max(1, -(-self.run.n_epochs // MAX_ESTIMATION_EPOCHS))

    def solve(self, *, weighting: str, cn0_slope: float = 1.0, noise_scale: float = 1.0, exclude: bool = False,
              test: str | None = None) -> SimpleNamespace:
        """The file solved from its first epoch with this variance model (``cn0_slope`` the C/N0
        model's), every system's σ factor times ``noise_scale``, exclusion on or off and
        ``test`` (default the run's): ``.solution`` (per epoch: ``statistic``, ``dof``,
        ``first_statistic``, ``first_dof``) and ``.satellites`` (per satellite-epoch: ``w``,
        ``cn0`` dB-Hz, ``used`` bool) as mappings of numpy columns — what the estimators of
        :mod:`navfdi._gnss_noise` read (no pandas: the run keeps the file's observations, and
        the peak memory of a day file is what that costs)."""
        factors = scaled_factors(self.given, noise_scale)
        self.run.restart(weighting, float(cn0_slope), factors, bool(exclude), self.test if test is None else test, self.every)
        while self.run.done < self.run.n_epochs:
            self.run.advance(1 << 30)
        self.solves += 1
        t = self.run.estimation_table()
        epochs = {c: t.pop(c) for c in ("statistic", "dof", "first_statistic", "first_dof")}
        return SimpleNamespace(solution=epochs, satellites=t)


def resolve_auto(obs: str | os.PathLike[str], nav: str | os.PathLike[str], common: dict[str, Any], weighting: str,
                 cn0_slope: float | str, noise_scale: float | str) -> tuple[str, float, float, dict[str, Any]]:
    """The settings :func:`navfdi.gnss.gnss_solve` solves with, its ``"auto"`` ones estimated
    from the file (without the injected faults), in this order: the C/N0 model's slope (where
    the C/N0 model may be used), the variance model, the σ factor (with the global test's
    exclusions whatever ``test`` is: the factor is the receiver's, and data snooping's false
    exclusions grow with the satellites on heavy-tailed errors, which would pull it down).
    ``(weighting, cn0_slope, noise_scale, config)``, ``config`` the estimates' reports
    (``cn0_slope_auto``, ``weighting_auto``, ``noise_scale_auto``, ``noise_scale_estimated``).
    With fewer than 20 epochs that can be tested, the σ factor stays 1 with a warning."""
    config: dict[str, Any] = {}
    est: EstimationRun | None = None

    def run() -> EstimationRun:
        nonlocal est
        if est is None:
            est = EstimationRun(obs, nav, common)
        return est

    if isinstance(cn0_slope, str):
        if weighting in ("cn0", "auto"):
            slope = estimate_cn0_slope(lambda s_: run().solve(weighting="cn0", cn0_slope=s_), float(common["cn0_reference"]))
            config["cn0_slope_auto"] = slope
            cn0_slope = float(slope["slope"])
        else:
            cn0_slope = 1.0  # the models without a C/N0 term have no slope to estimate
    slope_ = float(cn0_slope)
    if weighting == "auto":
        chosen = auto_weighting(lambda weighting: run().solve(weighting=weighting, cn0_slope=slope_ if weighting == "cn0" else 1.0))
        config["weighting_auto"] = chosen
        weighting = chosen["chosen"]
    if weighting != "cn0":
        slope_ = 1.0
    if isinstance(noise_scale, str):
        try:
            auto = auto_noise_scale(lambda **kw: run().solve(weighting=weighting, cn0_slope=slope_, test="global", **kw))
        except TooFewEpochs as e:
            if e.tested:  # with none, the run that follows says why nothing was solved
                warnings.warn(f"{e}; the sigma factor stays 1 (--noise 1)", UserWarning, stacklevel=3)
            auto = {"scale": 1.0, "whole_file": math.nan, "faults_excluded": math.nan, "iterations": 0, "method": "too few epochs: 1"}
        why = ("they are not code noise (a navigation file that does not belong to the observations, receiver clock jumps, "
               "unmodelled biases)")
        if not (np.isfinite(auto["scale"]) and 0 < auto["scale"] < MAX_NOISE_SCALE):
            raise ValueError(f"noise_scale='auto': the file's residuals are {auto['scale']:.3g} times the sigma model's: {why}; "
                             "give a factor (--noise) to solve it anyway")
        if auto["scale"] > IMPLAUSIBLE_NOISE_SCALE:
            warnings.warn(f"noise_scale='auto': the file's residuals are {auto['scale']:.3g} times the sigma model's: {why}; the tests "
                          "at that factor find only faults of that many sigma", UserWarning, stacklevel=3)
        config["noise_scale_estimated"] = True
        config["noise_scale_auto"] = auto
        noise_scale = float(auto["scale"])
    config["estimation_solves"] = est.solves if est is not None else 0
    config["estimation_every"] = est.every if est is not None else 1
    est = None  # the file's observations freed before the solve that follows reads them again
    return weighting, slope_, float(noise_scale), config
