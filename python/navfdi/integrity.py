"""Integrity: ARAIM protection levels and fault detection and exclusion.

:func:`araim` runs the EU–US ARAIM Technical Subgroup's Reference Airborne Algorithm (ADD v3.0,
multiple-hypothesis solution separation) on one epoch, in Rust
(``navfdi_core::integrity::araim``). On the ADD's Appendix D example it gives VPL 19.223 m,
HPL 14.464 m, EMT 7.819 m and σ_acc,v 1.468 m against the ADD's 19.2, 14.5, 7.8 and 1.47 m
(the levels by the ADD's half-interval search with TOL_PL 5 cm; the roots of the PL equations
are 19.217 and 14.416 m).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from navfdi import _core

#: GPS L1 and L5 carrier frequencies (MHz) of the dual-frequency user-error model
#: (:func:`elevation_variances`; the model runs in Rust).
F_L1, F_L5 = 1575.42, 1176.45


@dataclass(frozen=True)
class Ism:
    """Integrity support message: ``sigma_ura`` (m, integrity) and ``sigma_ure`` (m, accuracy)
    of the satellite clock and orbit, ``b_nom`` (m) the nominal bias bound, ``p_sat`` the prior
    of a satellite fault, ``p_const`` the prior of a constellation fault per system letter.
    Scalars apply to every satellite; arrays (n,) give one value per satellite."""

    sigma_ura: float | Sequence[float] = 0.75
    sigma_ure: float | Sequence[float] = 0.5
    b_nom: float | Sequence[float] = 0.5
    p_sat: float | Sequence[float] = 1e-5
    p_const: Mapping[str, float] = field(default_factory=lambda: {"G": 1e-4, "E": 1e-4})

    def __post_init__(self) -> None:
        # Every value checked here, naming the field: a NaN bias or prior would make the
        # levels vanish, a negative prior would reach a quantile function.
        for name, low_open in (("sigma_ura", True), ("sigma_ure", True), ("b_nom", False)):
            _check_values(f"Ism.{name}", getattr(self, name), low=0.0, low_open=low_open, high=1e4, what="m")
        _check_values("Ism.p_sat", self.p_sat, low=0.0, low_open=True, high=1.0, high_open=True, what="a probability")
        if not isinstance(self.p_const, Mapping) or not self.p_const:
            raise ValueError(f"Ism.p_const: a mapping of system letter to prior, e.g. {{'G': 1e-4}}, got {self.p_const!r}")
        for k, v in self.p_const.items():
            if not isinstance(k, str) or len(k) != 1:
                raise ValueError(f"Ism.p_const: key {k!r} is not a system letter (G, E, C, J, R, I, S)")
            _check_values(f"Ism.p_const[{k!r}]", v, low=0.0, low_open=False, high=1.0, high_open=True, what="a probability")


@dataclass(frozen=True)
class Allocation:
    """Integrity and continuity allocation: ``p_hmi_vert``, ``p_hmi_hor``, ``p_fa_vert``,
    ``p_fa_hor``, ``p_thres`` (largest unmonitored probability), ``p_emt`` (smallest prior
    counted in the EMT). Alert limits ``hal``, ``val`` (m) for the availability figures.
    ``tol_pl`` (m): the ADD's TOL_PL — the levels are the upper end of the ADD's half-interval
    search once its bracket is this narrow, so at most ``tol_pl`` above the root of the PL
    equation (per axis); ``0`` solves the equation to 1 µm."""

    p_hmi_vert: float
    p_hmi_hor: float
    p_fa_vert: float
    p_fa_hor: float
    p_thres: float
    p_emt: float
    hal: float = 40.0
    val: float = 35.0
    tol_pl: float = 0.05

    def __post_init__(self) -> None:
        for name in ("p_hmi_vert", "p_hmi_hor", "p_fa_vert", "p_fa_hor", "p_thres", "p_emt"):
            _check_values(f"Allocation.{name}", getattr(self, name), low=0.0, low_open=True, high=1.0, high_open=True, what="a probability", scalar=True)
        if self.p_hmi_vert + self.p_hmi_hor >= 1.0:
            raise ValueError(f"Allocation: p_hmi_vert + p_hmi_hor = {self.p_hmi_vert + self.p_hmi_hor!r} must be below 1")
        for name in ("hal", "val"):
            _check_values(f"Allocation.{name}", getattr(self, name), low=0.0, low_open=True, high=1e7, what="m", scalar=True)
        _check_values("Allocation.tol_pl", self.tol_pl, low=0.0, low_open=False, high=10.0, what="m", scalar=True)


def _check_values(name: str, v: Any, *, low: float, low_open: bool, high: float, high_open: bool = False, what: str, scalar: bool = False) -> None:
    """``ValueError`` naming ``name`` unless ``v`` (a number, or a sequence of numbers unless
    ``scalar``) lies in the interval (NaN and booleans never do)."""
    if isinstance(v, (bool, np.bool_)) or (scalar and np.ndim(v) != 0):
        raise ValueError(f"{name}: expected a number ({what}), got {v!r}")
    if isinstance(v, (int, float)) and math.isfinite(v) and (v > low if low_open else v >= low) and (v < high if high_open else v <= high):
        return  # the common case, a plain number in range, without numpy (µs per field)
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{name}: expected {'a number' if scalar else 'a number or numbers'} ({what}), got {v!r}") from None
    if a.ndim > 1 or a.size == 0:
        raise ValueError(f"{name}: expected a number or a 1-D sequence, got shape {a.shape}")
    ok = np.isfinite(a) & ((a > low) if low_open else (a >= low)) & ((a < high) if high_open else (a <= high))
    if not ok.all():
        bad = float(a.reshape(-1)[int(np.argmin(ok.reshape(-1)))])
        rng = f"{'(' if low_open else '['}{low:g}, {high:g}{')' if high_open else ']'}"
        unit = "a probability" if what == "a probability" else f"a length ({what})"
        raise ValueError(f"{name} = {bad!r}: must be {unit} in {rng}")


def lpv200() -> Allocation:
    """The LPV-200 allocation of the ADD: P_HMI 1e-7 (9.8e-8 vertical, 2e-9 horizontal), P_FA
    3.9e-6 / 9e-8, P_THRES 8e-8, P_EMT 1e-5; HAL 40 m, VAL 35 m; TOL_PL 5 cm."""
    return Allocation(9.8e-8, 2e-9, 3.9e-6, 9e-8, 8e-8, 1e-5)


#: The defaults of :func:`araim`, built (and checked) once: building them per call cost more
#: than the levels themselves at 10 satellites.
_DEFAULT_ISM = Ism()
_LPV200 = lpv200()


@dataclass(frozen=True)
class AraimResult:
    """Result of :func:`araim` (lengths in m). ``vpl``, ``hpl``, ``emt``; ``sigma_acc_v``,
    ``sigma_acc_h`` (east, north); ``available``: the unmonitored probability is at most
    P_THRES and both PLs are finite; ``p_unmonitored``; ``k_fa_v``; ``modes``: one dict per
    monitored fault mode (``satellites`` indices, ``constellations``, ``prior``, and per axis
    east/north/up ``sigma``, ``sigma_ss``, ``bias``, ``threshold``, ``separation``), built on
    first access from the columns in ``mode_table`` (arrays: ``prior`` (N,), the per-axis
    values (N, 3)).

    With ``residuals`` (fault detection and exclusion): ``detected`` (a solution separation
    test failed), ``test_ratio`` (largest |separation| / threshold), ``excluded`` (indices of
    the satellites excluded), ``alarm`` (a detection no single exclusion resolves; then
    ``vpl``/``hpl`` are inf), and ``vpl``, ``hpl``, ``available`` are those of the solution
    kept (after exclusion: the subset's own levels); ``vpl_any``/``hpl_any`` the largest over
    every exclusion candidate that passed (a bound if the wrong one was excluded);
    ``correction`` (east, north, up, m) the kept solution's least-squares correction: its
    position is the residuals' linearisation point plus it (NaN on an alarm). Without
    residuals: ``detected``/``alarm`` False, ``test_ratio``/``vpl_any``/``hpl_any`` NaN,
    ``excluded`` ``()``, and ``vpl``/``hpl`` the all-in-view levels."""

    vpl: float
    hpl: float
    emt: float
    sigma_acc_v: float
    sigma_acc_h: tuple[float, float]
    available: bool
    p_unmonitored: float
    k_fa_v: float
    mode_table: dict[str, np.ndarray]
    detected: bool = False
    test_ratio: float = math.nan
    excluded: tuple[int, ...] = ()
    alarm: bool = False
    vpl_any: float = math.nan
    hpl_any: float = math.nan
    correction: tuple[float, float, float] = (math.nan, math.nan, math.nan)

    @property
    def modes(self) -> list[dict[str, Any]]:
        """The fault modes as dicts (see the class docs); built from ``mode_table``."""
        t = self.mode_table
        sats = np.split(t["satellites"], np.cumsum(t["satellites_count"])[:-1]) if len(t["prior"]) else []
        cons = np.split(t["constellations"], np.cumsum(t["constellations_count"])[:-1]) if len(t["prior"]) else []
        return [
            {
                "satellites": [int(i) for i in sats[k]],
                "constellations": [int(c) for c in cons[k]],
                "prior": float(t["prior"][k]),
                **{name: [float(v) for v in t[name][k]] for name in ("sigma", "sigma_ss", "bias", "threshold", "separation")},
            }
            for k in range(len(t["prior"]))
        ]


def elevation_variances(elevation: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """``(σ_tropo², σ_user²)`` (m², each of ``elevation``'s shape) at elevations (rad) by the
    ADD's models: the troposphere ``0.12 · 1.001 / sqrt(0.002001 + sin² el)`` and the
    dual-frequency (L1/L5) user term ``(f1⁴ + f5⁴)/(f1² − f5²)² · (σ_MP² + σ_noise²)`` with
    ``σ_MP = 0.13 + 0.53 e^(−el/10°)`` and ``σ_noise = 0.15 + 0.43 e^(−el/6.9°)`` (the airborne
    GPS model, used for every system). In Rust
    (``navfdi_core::integrity::araim_model``), as :func:`araim` uses them."""
    tropo, user = _core.araim_variances(elevation)
    return tropo[()], user[()]


def araim(
    los_enu: ArrayLike,
    systems: Sequence[str],
    *,
    c_int: ArrayLike | None = None,
    c_acc: ArrayLike | None = None,
    ism: Ism | None = None,
    allocation: Allocation | None = None,
    residuals: ArrayLike | None = None,
) -> AraimResult:
    """ARAIM protection levels of one epoch (ADD v3.0; see the module docs), with fault
    detection and exclusion when ``residuals`` are given.

    Parameters
    ----------
    los_enu : array_like, shape (n, 3)
        Unit vectors from the receiver to the satellites, east/north/up (the ADD's geometry
        rows are their negatives).
    systems : sequence of str, length n
        Each satellite's system letter (``"G"``, ``"E"``, …); one clock per system.
    c_int, c_acc : array_like, shape (n,), optional
        Integrity and accuracy variances (m²); by default ``σ_URA² (σ_URE²) + σ_tropo² +
        σ_user²`` from :func:`elevation_variances`.
    ism : Ism, optional
        Default :class:`Ism` ().
    allocation : Allocation, optional
        Default :func:`lpv200`.
    residuals : array_like, shape (n,), optional
        Pseudorange residuals (m) of the linearised model, e.g. the all-in-view least-squares
        residuals (the separations do not depend on the linearisation point): each mode's
        solution separation is tested against its threshold; on a detection each single
        satellite, then each constellation, is tried for exclusion (ARAIM recomputed on the
        subset, which must pass all of its own tests), and the levels are recomputed after
        the exclusion.

    Raises
    ------
    ValueError
        Wrong shapes, non-finite or non-unit lines of sight, non-positive variances, a system
        without a constellation prior, non-finite residuals.
    """
    ism = ism or _DEFAULT_ISM
    allocation = allocation or _LPV200
    los = np.asarray(los_enu, dtype=float)
    if los.ndim != 2 or los.shape[1] != 3 or los.shape[0] == 0:
        raise ValueError(f"los_enu: expected shape (n, 3), got {los.shape}")
    n = los.shape[0]
    systems = [str(s).upper() for s in systems]
    if len(systems) != n:
        raise ValueError(f"systems: {len(systems)} letters for {n} satellites")
    index = {s: k for k, s in enumerate(dict.fromkeys(systems))}
    missing = [s for s in index if s not in ism.p_const]
    if missing:
        raise ValueError(f"ism.p_const: no constellation prior for system(s) {', '.join(missing)}")
    # The lines of sight are checked (finite, unit) and the ADD's variances computed in Rust
    # (``_core.araim_los``); scalars go as one value for every satellite.
    r = _core.araim_los(
        los,
        [index[s] for s in systems],
        _values(ism.sigma_ura, "ism.sigma_ura"),
        _values(ism.sigma_ure, "ism.sigma_ure"),
        None if c_int is None else _values(c_int, "c_int"),
        None if c_acc is None else _values(c_acc, "c_acc"),
        _values(ism.b_nom, "ism.b_nom"),
        _values(ism.p_sat, "ism.p_sat"),
        [float(ism.p_const[s]) for s in index],
        (allocation.p_hmi_vert, allocation.p_hmi_hor, allocation.p_fa_vert, allocation.p_fa_hor, allocation.p_thres, allocation.p_emt, allocation.tol_pl),
        None if residuals is None else _residuals(residuals, n),
    )
    common = dict(
        emt=r["emt"],
        sigma_acc_v=r["sigma_acc"][2],
        sigma_acc_h=(r["sigma_acc"][0], r["sigma_acc"][1]),
        p_unmonitored=r["p_unmonitored"],
        k_fa_v=r["k_fa"][2],
        mode_table=r["modes"],
    )
    if residuals is None:
        return AraimResult(vpl=r["vpl"], hpl=r["hpl"], available=bool(r["available"]) and math.isfinite(r["vpl"]), **common)
    f = r["fde"]
    return AraimResult(
        vpl=f["vpl"],
        hpl=f["hpl"],
        available=bool(f["available"]),
        detected=bool(f["detected"]),
        test_ratio=float(f["test_ratio"]),
        excluded=tuple(int(i) for i in f["excluded"]),
        alarm=bool(f["alarm"]),
        vpl_any=float(f["vpl_any"]),
        hpl_any=float(f["hpl_any"]),
        correction=(float(f["correction"][0]), float(f["correction"][1]), float(f["correction"][2])),
        **common,
    )


def _residuals(v: ArrayLike, n: int) -> list[float]:
    """``v`` as n floats; ``ValueError`` for another shape (non-finite values: from Rust)."""
    y = np.asarray(v, dtype=float)
    if y.shape != (n,):
        raise ValueError(f"residuals: expected shape ({n},), one per satellite, got {y.shape}")
    return [float(x) for x in y]


def _values(v: Any, name: str) -> list[float]:
    """``v`` (a scalar or one value per satellite) as a list of floats: one for every satellite,
    or each's (their count is checked against the satellites in Rust,
    ``navfdi_core::integrity::araim_model::per_satellite``); ``ValueError`` naming ``name`` for
    more than one dimension."""
    if isinstance(v, (int, float)):
        return [float(v)]
    a = np.asarray(v, dtype=float)
    if a.ndim > 1:
        raise ValueError(f"{name}: expected a scalar or one value per satellite, got shape {a.shape}")
    return a.reshape(-1).tolist()
