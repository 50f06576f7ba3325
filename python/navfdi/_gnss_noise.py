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


def _tested(solution: Any, statistic: str, dof: str) -> tuple[np.ndarray, np.ndarray]:
    """The statistic and its degrees of freedom over the epochs of ``solution`` (a DataFrame or
    a mapping of columns) that were tested (dof > 0, finite statistic)."""
    t = np.asarray(solution[statistic], dtype=float)
    d = np.asarray(solution[dof], dtype=float)
    ok = (d > 0) & np.isfinite(t)
    return t[ok], d[ok].astype(int)


def _factor(solution: Any, statistic: str, dof: str, tail: float) -> float | None:
    """√ of the (1 − tail)-quantile over the tested epochs of ``solution[statistic]`` divided
    by χ²(dof)'s threshold at ``tail``: the σ factor that puts that quantile of the statistic
    on χ²'s; None with fewer than 20 tested epochs. ``solution`` a DataFrame or a mapping of
    columns."""
    t, d = _tested(solution, statistic, dof)
    if t.size < 20:
        return None
    levels, at = np.unique(d, return_inverse=True)
    thr = np.array([_core.chi2_threshold(tail, int(k)) for k in levels])[at]
    return float(np.sqrt(np.quantile(t / thr, 1.0 - tail)))


class TooFewEpochs(ValueError):
    """A file with fewer than 20 epochs that can be tested (``tested`` of them): too few to
    estimate a σ factor."""

    def __init__(self, message: str, tested: int) -> None:
        super().__init__(message)
        self.tested = tested


def estimate_noise_scale(solution: Any) -> float:
    """The σ factor that makes the global test fit a file (see :func:`navfdi.gnss.gnss_solve`'s
    ``noise_scale="auto"``): √ of the 90th percentile over the tested epochs of
    ``first_statistic / χ²₀.₉(first_dof)``. Needs at least 20 tested epochs
    (:class:`TooFewEpochs` otherwise). ``solution`` a DataFrame or a mapping of columns."""
    f = _factor(solution, "first_statistic", "first_dof", 0.1)
    if f is None:
        n = _tested(solution, "first_statistic", "first_dof")[0].size
        raise TooFewEpochs(f"noise_scale='auto': {n} epochs could be tested; at least 20 are needed to estimate the noise", n)
    return f


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
    w = np.asarray(first.satellites["w"], dtype=float)
    w = w[np.isfinite(w)]
    # Start below both fixed points: the residuals' median absolute w (robust to faulty
    # satellites unless the least-squares fit smears several over every residual), and never
    # above the σ model as given.
    s = min(1.4826 * float(np.median(np.abs(w))), 1.0) if w.size else 1.0
    s = max(s, 1e-3)
    robust, iterations = math.nan, 0
    for iterations in range(1, 31):
        # The same percentile of the statistic left after the exclusions.
        r = _factor(solve(exclude=True, noise_scale=s).solution, "statistic", "dof", 0.1)
        if r is None or not r > 0:
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


def tail_ratio(solution: Any) -> float:
    """How far a file's global statistics are from the χ² of a fitting σ model, in shape only:
    ``|log(f90 / f50)|`` with ``f_q = √(q-quantile of T / χ²_q(dof))`` over the epochs tested
    without exclusion (0 for residuals that are Gaussian with any common scale; larger for
    heavier or lighter tails than the model's). NaN with fewer than 20 tested epochs."""
    f50 = _factor(solution, "first_statistic", "first_dof", 0.5)
    f90 = _factor(solution, "first_statistic", "first_dof", 0.1)
    if f50 is None or f90 is None or not (f50 > 0 and f90 > 0):
        return math.nan
    return abs(math.log(f90 / f50))


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


def robust_sd(w: np.ndarray) -> float:
    """1.4826 × the median absolute deviation of ``w`` (NaN with fewer than two values)."""
    return float(1.4826 * np.median(np.abs(w - np.median(w)))) if w.size > 1 else math.nan


#: Edges of the C/N0 classes (dB-Hz) of :func:`robust_sd_by`.
CN0_EDGES = (30.0, 35.0, 40.0, 45.0)


def robust_sd_by(sats: pd.DataFrame) -> tuple[dict[str, float], dict[str, float]]:
    """The clean w's robust SD (:func:`robust_sd`) per system letter and per C/N0 class
    (``"<30"``, ``"30-35"``, …, ``">=45"`` dB-Hz, from the satellite table's ``cn0``) of the
    satellite rows ``sats`` (clean, used), each group with at least 30 values: a receiver whose
    systems differ in noise (a ``--noise-factor`` evens them out), or whose weak signals the
    σ model over- or under-penalises, shows it here."""
    cw = sats[["satellite", "w"] + (["cn0"] if "cn0" in sats else [])].dropna(subset=["w"])
    by_sys = {str(g): robust_sd(v.to_numpy(float)) for g, v in cw.groupby(cw["satellite"].astype(str).str[0])["w"] if len(v) >= 30}
    by_cn0: dict[str, float] = {}
    if "cn0" in cw:
        c = cw["cn0"].to_numpy(float)
        edges = (-math.inf, *CN0_EDGES, math.inf)
        for lo, hi in zip(edges[:-1], edges[1:]):
            m = (c >= lo) & (c < hi)
            if m.sum() >= 30:
                by_cn0[f"<{hi:g}" if lo == -math.inf else (f">={lo:g}" if hi == math.inf else f"{lo:g}-{hi:g}")] = robust_sd(cw["w"].to_numpy(float)[m])
    return by_sys, by_cn0


def by_system_text(s: dict[str, Any]) -> str:
    """``"; per system G 0.94, E 1.70"`` for the summary line (empty with one system), with the
    ``--noise-factor`` that evens the systems out when they differ by more than 1.5×, then
    ``"; per C/N0 (dB-Hz) <30 0.42, …"`` where two or more classes have values, saying which
    way the weakest and strongest classes differ when they do by more than 1.5×."""
    by = {k: v for k, v in s.get("clean_w_sd_robust_by_system", {}).items() if math.isfinite(v) and v > 0}
    text = ""
    if len(by) >= 2:
        text = "; per system " + ", ".join(f"{k} {v:.2f}" for k, v in by.items())
        lo = min(by.values())
        if max(by.values()) > 1.5 * lo:
            text += " — the systems differ; --noise-factor " + " ".join(f"{k}={v / lo:.2g}" for k, v in by.items() if v > 1.5 * lo) + " models that"
    cn = {k: v for k, v in s.get("clean_w_sd_robust_by_cn0", {}).items() if math.isfinite(v) and v > 0}
    if len(cn) >= 2:
        text += "; per C/N0 (dB-Hz) " + ", ".join(f"{k} {v:.2f}" for k, v in cn.items())
        first, last = next(iter(cn.values())), list(cn.values())[-1]
        if max(first, last) > 1.5 * min(first, last):
            text += " — " + ("weak signals noisier than modelled" if first > last else "weak signals penalised more than they need")
    return text


#: The smallest slope ``cn0_slope="auto"`` uses: the σ–ε model's. A code-tracking loop's
#: thermal noise variance falls no faster than 1/(C/N0) as the signal strengthens, so a file
#: whose w call for less is carrying errors that do not follow C/N0 (multipath on strong
#: signals, broadcast orbit and atmosphere residuals), which a smaller slope would trade for
#: weight on the weak, multipath-prone signals: on the walk's u-blox (fitted 0.60) that cost
#: 6 points of exclusions of 5 m steps and 1.3 % false exclusions (docs/gnss_real.md).
CN0_SLOPE_FLOOR = 1.0

#: Width (dB-Hz) of the C/N0 bins of :func:`estimate_cn0_slope`, the fewest clean w per bin,
#: the smallest C/N0 span (dB-Hz) between the outer bins' medians, the change of the slope
#: at which its iteration stops and the most solves it takes.
CN0_SLOPE_BIN, CN0_SLOPE_MIN_ROWS, CN0_SLOPE_MIN_SPAN, CN0_SLOPE_TOL, CN0_SLOPE_SOLVES = 2.5, 30, 5.0, 0.02, 10


def cn0_slope_step(sats: Any, reference: float) -> tuple[float, int, float] | None:
    """One step of :func:`estimate_cn0_slope` from the satellite rows of a solve without
    exclusion (``status`` or a boolean ``used``, ``w``, ``cn0`` dB-Hz; a DataFrame or a
    mapping of columns): the weighted least-squares slope of
    ``log10(robust SD² of w)`` over :data:`CN0_SLOPE_BIN` dB-Hz bins (each with at least
    :data:`CN0_SLOPE_MIN_ROWS` used rows, weighted by their count) against
    ``(reference − median C/N0 of the bin) / 10`` — 0 when the model's slope fits — with the
    number of bins and the C/N0 span (dB-Hz) between the outer bins; None when the rows have no
    C/N0 or fewer than two bins :data:`CN0_SLOPE_MIN_SPAN` dB-Hz apart."""
    if "cn0" not in sats:
        return None
    used = np.asarray(sats["used"], dtype=bool) if "used" in sats else np.asarray(sats["status"]) == "used"
    w = np.asarray(sats["w"], dtype=float)[used]
    c = np.asarray(sats["cn0"], dtype=float)[used]
    ok = np.isfinite(w) & np.isfinite(c)
    w, c = w[ok], c[ok]
    if w.size < 2 * CN0_SLOPE_MIN_ROWS:
        return None
    b = np.floor(c / CN0_SLOPE_BIN)
    xs, ys, ns = [], [], []
    for k in np.unique(b):
        m = b == k
        sd = robust_sd(w[m])
        if m.sum() >= CN0_SLOPE_MIN_ROWS and sd > 0:
            xs.append((reference - float(np.median(c[m]))) / 10.0)
            ys.append(math.log10(sd * sd))
            ns.append(float(m.sum()))
    if len(xs) < 2 or 10.0 * (max(xs) - min(xs)) < CN0_SLOPE_MIN_SPAN:
        return None
    x, y, n = np.array(xs), np.array(ys), np.array(ns)
    xm, ym = np.average(x, weights=n), np.average(y, weights=n)
    return float(np.sum(n * (x - xm) * (y - ym)) / np.sum(n * (x - xm) ** 2)), len(xs), 10.0 * float(x.max() - x.min())


def estimate_cn0_slope(solve: Callable[[float], Any], reference: float) -> dict[str, Any]:
    """``cn0_slope="auto"``: the slope ``s`` of the C/N0 model (variance ``× 10^(s (reference −
    C/N0)/10)``) that leaves the clean w with one spread at every C/N0, for a file that
    ``solve(s)`` solves without exclusion (a :class:`navfdi.gnss.GnssSolution`). From s = 1
    (the σ–ε model), each solve's w spread per C/N0 bin is regressed on the C/N0
    (:func:`cn0_slope_step`) and the slope moved by the regression's slope (the misfit's, in
    the same units), kept in ``[0, CN0_SLOPE_MAX]``, until it moves by less than
    :data:`CN0_SLOPE_TOL` (at most :data:`CN0_SLOPE_SOLVES` solves). The scale is not
    estimated here (``noise_scale="auto"`` does that at the slope found). ``{"slope",
    "estimate", "settled", "solves", "bins", "span_dbhz", "path"}``: ``estimate`` the slope
    found, ``slope`` the one to use — the estimate, not below :data:`CN0_SLOPE_FLOOR`; ``slope``
    1, ``estimate`` NaN and ``settled`` False with a ``reason`` when the file's C/N0 does not
    span enough to estimate it."""
    s, path, solves = 1.0, [1.0], 0
    step, prev = None, None
    moved = math.inf
    for solves in range(1, CN0_SLOPE_SOLVES + 1):
        step = cn0_slope_step(solve(s).satellites, reference)
        if step is None:
            why = f"fewer than two C/N0 bins of {CN0_SLOPE_MIN_ROWS} used satellite-epochs {CN0_SLOPE_MIN_SPAN:g} dB-Hz apart"
            return {"slope": 1.0, "estimate": math.nan, "settled": False, "solves": solves, "bins": 0, "span_dbhz": math.nan, "path": path, "reason": why}
        # The misfit's slope shrinks as the model's nears the file's, but by less than one for
        # one (the w's spread is partly the weights' own): a secant on it from the second
        # solve, the misfit's own step where the secant is flat or points the wrong way.
        new = s + step[0]
        if prev is not None and (prev[1] - step[0]) * (s - prev[0]) > 0:
            new = s - step[0] * (s - prev[0]) / (step[0] - prev[1])
        prev = (s, step[0])
        new = min(max(new, 0.0), _core.CN0_SLOPE_MAX)
        moved, s = abs(new - s), new
        path.append(s)
        if moved < CN0_SLOPE_TOL:
            break
    assert step is not None
    out = {"slope": max(s, CN0_SLOPE_FLOOR), "estimate": s, "settled": moved < CN0_SLOPE_TOL, "solves": solves, "bins": step[1], "span_dbhz": step[2], "path": path}
    if not out["settled"]:
        out["reason"] = f"the slope still moved by {moved:.3f} after {solves} solves"
    return out
