"""The σ factor of ``navfdi gnss --noise auto`` (:func:`navfdi.gnss.gnss_solve`'s
``noise_scale="auto"``): from the whole file's global statistic, or, when the file's faults set
that statistic, from the statistic left after FDE's exclusions
(docs/gnss_real.md, "The noise factor on files with multipath")."""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np

from navfdi import _core

if TYPE_CHECKING:
    import pandas as pd


def estimate_noise_scale(solution: pd.DataFrame) -> float:
    """The σ factor that makes the global test fit a file (see :func:`navfdi.gnss.gnss_solve`'s
    ``noise_scale="auto"``): √ of the 90th percentile over the tested epochs of
    ``first_statistic / χ²₀.₉(first_dof)``. Needs at least 20 tested epochs."""
    ok = (solution["first_dof"] > 0) & np.isfinite(solution["first_statistic"])
    if ok.sum() < 20:
        raise ValueError(f"noise_scale='auto': {int(ok.sum())} epochs could be tested; at least 20 are needed to estimate the noise")
    t = solution.loc[ok, "first_statistic"].to_numpy(float)
    q = np.array([_core.chi2_threshold(0.1, int(d)) for d in solution.loc[ok, "first_dof"]])
    return float(np.sqrt(np.quantile(t / q, 0.9)))


def _final_statistic_ratio(solution: pd.DataFrame) -> float:
    """√ of the 90th percentile of ``statistic / χ²₀.₉(dof)`` over the epochs tested after
    their exclusions (NaN with fewer than 20)."""
    ok = (solution["dof"] > 0) & np.isfinite(solution["statistic"])
    if ok.sum() < 20:
        return math.nan
    t = solution.loc[ok, "statistic"].to_numpy(float)
    q = np.array([_core.chi2_threshold(0.1, int(d)) for d in solution.loc[ok, "dof"]])
    return float(np.sqrt(np.quantile(t / q, 0.9)))


#: ``noise_scale="auto"`` takes the factor found with the faults excluded when the whole
#: file's factor is more than this many times larger (see :func:`navfdi.gnss.gnss_solve`).
AUTO_NOISE_CONTAMINATION_RATIO = 2.0


def auto_noise_scale(solve: Callable[..., Any]) -> dict[str, Any]:
    """``noise_scale="auto"`` for a file that ``solve(exclude=…, noise_scale=…)`` solves (a
    :class:`navfdi.gnss.GnssSolution` with ``solution`` and ``satellites``):
    ``{"scale", "whole_file", "faults_excluded", "iterations", "method"}``
    — the whole file's factor, the factor found with the faults excluded (a fixed point
    climbed from below; NaN when the iteration did not settle in 30 solves), the solves taken
    and which factor is used (``"whole file"`` or ``"faults excluded"``); see
    :func:`navfdi.gnss.gnss_solve`."""
    first = solve(exclude=False, noise_scale=1.0)
    whole = estimate_noise_scale(first.solution)
    w = first.satellites["w"].to_numpy(float)
    w = w[np.isfinite(w)]
    # Start below both fixed points: the residuals' median absolute w (robust to faulty
    # satellites unless the least-squares fit smears several over every residual), and never
    # above the σ model as given.
    s = min(1.4826 * float(np.median(np.abs(w))), 1.0) if w.size else 1.0
    s = max(s, 1e-3)
    robust, iterations = math.nan, 0
    for iterations in range(1, 31):
        r = _final_statistic_ratio(solve(exclude=True, noise_scale=s).solution)
        if not math.isfinite(r) or r <= 0:
            break
        s *= r
        if abs(r - 1.0) < 0.01:
            robust = s
            break
    if math.isfinite(robust) and whole > AUTO_NOISE_CONTAMINATION_RATIO * robust:
        method = "faults excluded"
        scale = robust
    else:
        method = "whole file"
        scale = whole
    return {"scale": scale, "whole_file": whole, "faults_excluded": robust, "iterations": iterations, "method": method}


def tail_ratio(solution: pd.DataFrame) -> float:
    """How far a file's global statistics are from the χ² of a fitting σ model, in shape only:
    ``|log(f90 / f50)|`` with ``f_q = √(q-quantile of T / χ²_q(dof))`` over the epochs tested
    without exclusion (0 for residuals that are Gaussian with any common scale; larger for
    heavier or lighter tails than the model's). NaN with fewer than 20 tested epochs."""
    ok = (solution["first_dof"] > 0) & np.isfinite(solution["first_statistic"])
    if ok.sum() < 20:
        return math.nan
    t = solution.loc[ok, "first_statistic"].to_numpy(float)
    dof = solution.loc[ok, "first_dof"].to_numpy(int)
    f = []
    for q in (0.5, 0.9):
        thr = np.array([_core.chi2_threshold(1.0 - q, int(d)) for d in dof])
        f.append(float(np.sqrt(np.quantile(t / thr, q))))
    return abs(math.log(f[1] / f[0])) if f[0] > 0 and f[1] > 0 else math.nan


def auto_weighting(solve: Callable[..., Any]) -> dict[str, Any]:
    """``weighting="auto"`` for a file that ``solve(weighting=…)`` solves without exclusion:
    the elevation model and the C/N0 model (the elevation model scaled by the recorded C/N0)
    each solved, the one whose statistic has the shape of a fitting model's
    (:func:`tail_ratio` nearer 0) chosen; the elevation model on a tie — which is what a file
    without C/N0 gives, both models being the same there. ``{"chosen", "tail"}`` with the
    ratio per model."""
    tail = {w: tail_ratio(solve(weighting=w).solution) for w in ("elevation", "cn0")}
    cn0_better = math.isfinite(tail["cn0"]) and (not math.isfinite(tail["elevation"]) or tail["cn0"] < tail["elevation"] - 1e-9)
    return {"chosen": "cn0" if cn0_better else "elevation", "tail": tail}
