"""Integrity on real GNSS files: protection levels for every epoch of a :class:`GnssSolution`.

Per solved epoch, over the satellites the solution used (after exclusion):

* ARAIM (:func:`navfdi.araim`, ADD v3.0 multiple-hypothesis solution separation) with the
  allocation (``lpv200``: HAL 40 m, VAL 35 m, EMT 15 m) and the default integrity support
  message; the nominal error model is the solution's own (its weights σ², the code noise and
  elevation model the least squares used, on single-frequency data with broadcast ionosphere)
  plus σ_URA² (σ_URE² for accuracy): the ADD's dual-frequency airborne models would understate
  the errors of a single-frequency receiver;
* snapshot RAIM (:func:`navfdi.integrity.snapshot_pl`): slope-based levels of the same global
  test (its threshold and weights) at the missed-detection probability ``p_md``, with the
  fault-free error from an overbounding model (:func:`range_error_model`: σ_URA, the Klobuchar
  residual the solve reports per satellite (``iono_sigma``), the troposphere and the
  solution's own σ, plus the nominal bias); each term per
  used satellite-epoch in ``satellites`` (``raim_sigma_ura``, ``iono_sigma`` from the solve,
  ``raim_sigma_tropo``, ``raim_sigma_total``, m).

Columns added to ``solution``: ``hpl``, ``vpl``, ``emt`` (ARAIM, m), ``hpl_raim``,
``vpl_raim`` (snapshot, m) and ``integrity``: ``available`` (ARAIM available and HPL ≤ HAL,
VPL ≤ VAL, EMT ≤ the EMT limit), ``unavailable``, ``alarm`` (the global test still fails after
exclusion) or ``no_solution``. With a truth, :func:`integrity_summary` counts the epochs where
the error exceeds the protection level: misleading (MI) when the epoch was available,
hazardously misleading (HMI) when the error also exceeds the alert limit.

ARAIM's own fault detection and exclusion runs beside them (:func:`navfdi.araim` with
``residuals``) over the satellites the snapshot test saw (used and excluded), from their
residuals about the solution: ``hpl_fde``, ``vpl_fde`` (m, after ARAIM's exclusion),
``fde_ratio`` (largest separation / threshold), ``fde_excluded`` (satellite names),
``fde_de``, ``fde_dn``, ``fde_du`` (m: ARAIM's position minus the solution's, east/north/up)
and ``integrity_fde`` (``available`` / ``unavailable`` / ``alarm`` / ``no_solution``); the
summary's ``araim_fde_*`` entries count its detections, exclusions, alarms and the misleading
epochs of ARAIM's own position against its levels.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass
from pathlib import Path
from statistics import NormalDist
from collections.abc import Sequence
from typing import Any

import numpy as np

from navfdi import _core
from navfdi.integrity import Allocation, Ism, araim, lpv200

#: Alert limits (m) and EMT limit of the named allocations.
LIMITS = {"lpv200": {"hal": 40.0, "val": 35.0, "emt": 15.0}}

#: Keys of an allocation file's tables (see :func:`load_allocation_file`).
_FILE_KEYS = {
    "allocation": ("p_hmi_vert", "p_hmi_hor", "p_fa_vert", "p_fa_hor", "p_thres", "p_emt", "tol_pl"),
    "limits": ("hal", "val", "emt"),
    "ism": ("sigma_ura", "sigma_ure", "b_nom", "p_sat", "p_const"),
}


@dataclass(frozen=True)
class IntegritySettings:
    """What ``--integrity`` resolves to: the allocation's ``name`` (``"lpv200"`` or the file's),
    the :class:`~navfdi.integrity.Allocation`, the alert and EMT ``limits`` (m: ``hal``,
    ``val``, ``emt``), the :class:`~navfdi.integrity.Ism` and the ``source`` (the file's path,
    or ``None`` for a named allocation)."""

    name: str
    allocation: Allocation
    limits: dict[str, float]
    ism: Ism
    source: str | None = None


def check_systems(settings: IntegritySettings, systems: Sequence[str], ism: Ism | None = None) -> None:
    """``ValueError`` (once, before any epoch is solved) when the integrity support message has
    no constellation fault prior for one of ``systems`` (letters), saying which key to add."""
    ism = ism or settings.ism
    missing = [x for x in systems if x not in ism.p_const]
    if missing:
        where = f"the allocation file {settings.source}" if settings.source else "an allocation file (navfdi gnss --integrity FILE)"
        raise ValueError(
            f"integrity: the integrity support message has no constellation fault prior for system(s) {', '.join(missing)} "
            f"(it has {', '.join(sorted(ism.p_const))}); add it to [ism] p_const of {where}, e.g. p_const = {{"
            + ", ".join(f"{x} = 1e-4" for x in sorted(set(systems) | set(ism.p_const))) + "}, or leave the system out of --systems")


def allocation_by_name(name: str) -> tuple[Allocation, dict[str, float]]:
    """The allocation and limits of a name (``lpv200``)."""
    if name not in LIMITS:
        raise ValueError(f"integrity {name!r}: unknown allocation (known: {', '.join(LIMITS)}), and no such allocation file")
    return lpv200(), LIMITS[name]


def resolve_integrity(spec: str | os.PathLike[str] | IntegritySettings) -> IntegritySettings:
    """``--integrity``'s argument: a named allocation (``lpv200``) or the path of an allocation
    file (:func:`load_allocation_file`). ``ValueError`` names an unknown name or a bad file."""
    if isinstance(spec, IntegritySettings):
        return spec
    text = os.fspath(spec)
    if text not in LIMITS and (text.endswith(".toml") or Path(text).is_file()):
        return load_allocation_file(text)
    alloc, limits = allocation_by_name(text)  # an unknown name raises, naming the known ones
    return IntegritySettings(text, alloc, dict(limits), Ism())


def load_allocation_file(path: str | os.PathLike[str]) -> IntegritySettings:
    """An allocation file (TOML) for ``navfdi gnss --integrity FILE``: optional ``name`` (default
    the file's stem), and three optional tables whose absent keys keep LPV-200's values —
    ``[allocation]`` ``p_hmi_vert``, ``p_hmi_hor``, ``p_fa_vert``, ``p_fa_hor``, ``p_thres``,
    ``p_emt`` (probabilities per epoch) and ``tol_pl`` (m); ``[limits]`` ``hal``, ``val``,
    ``emt`` (m, the alert limits and the EMT limit of the ``available`` state); ``[ism]``
    ``sigma_ura``, ``sigma_ure``, ``b_nom`` (m), ``p_sat`` and ``p_const`` (a table of
    per-system priors, e.g. ``{G = 1e-4, E = 1e-4, C = 1e-4}``, replacing the default one).

    Raises ``ValueError`` naming the file and the key for a missing or unreadable file, TOML
    syntax, unknown keys, non-numbers and values out of range (probabilities in (0, 1),
    lengths positive and finite, ``tol_pl`` in [0, 10] m)."""
    p = Path(path)
    where = f"integrity file {os.fspath(path)!r}"
    if not p.is_file():
        raise ValueError(f"{where}: no such file")
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8-sig"))
    except (OSError, UnicodeDecodeError) as e:
        raise ValueError(f"{where}: cannot read it ({e})") from None
    except tomllib.TOMLDecodeError as e:
        raise ValueError(f"{where}: not valid TOML ({e})") from None
    unknown = sorted(set(doc) - {"name", *_FILE_KEYS})
    if unknown:
        raise ValueError(f"{where}: unknown key(s) {', '.join(unknown)} (known: name, {', '.join(_FILE_KEYS)})")
    tables: dict[str, dict[str, Any]] = {}
    for table, keys in _FILE_KEYS.items():
        t = doc.get(table, {})
        if not isinstance(t, dict):
            raise ValueError(f"{where}: {table} must be a table ([{table}])")
        bad = sorted(set(t) - set(keys))
        if bad:
            raise ValueError(f"{where}: [{table}] unknown key(s) {', '.join(bad)} (known: {', '.join(keys)})")
        tables[table] = t

    def number(table: str, key: str, low: float, high: float, closed_low: bool = False) -> float:
        v = tables[table][key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ValueError(f"{where}: [{table}] {key} = {v!r}: a finite number is required")
        if not ((low <= v if closed_low else low < v) and v < high):
            rng = f"{'[' if closed_low else '('}{low:g}, {high:g})"
            raise ValueError(f"{where}: [{table}] {key} = {v!r}: must be in {rng}")
        return float(v)

    base = lpv200()
    a = {f: getattr(base, f) for f in _FILE_KEYS["allocation"]}
    for key in tables["allocation"]:
        a[key] = number("allocation", key, 0.0, 10.0, closed_low=True) if key == "tol_pl" else number("allocation", key, 0.0, 1.0)
    limits = dict(LIMITS["lpv200"])
    for key in tables["limits"]:
        limits[key] = number("limits", key, 0.0, 1e7)
    ism_kw: dict[str, Any] = {}
    for key in tables["ism"]:
        if key == "p_const":
            pc = tables["ism"][key]
            if not isinstance(pc, dict) or not pc:
                raise ValueError(f"{where}: [ism] p_const must be a table of system priors, e.g. {{G = 1e-4, E = 1e-4}}")
            out = {}
            for letter, v in pc.items():
                if letter.upper() not in ("G", "E", "C", "J", "R", "I", "S"):
                    raise ValueError(f"{where}: [ism] p_const.{letter}: not a system letter (G, E, C, J, R, I, S)")
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 < v < 1:
                    raise ValueError(f"{where}: [ism] p_const.{letter} = {v!r}: must be in (0, 1)")
                out[letter.upper()] = float(v)
            ism_kw["p_const"] = out
        elif key == "p_sat":
            ism_kw[key] = number("ism", key, 0.0, 1.0)
        else:
            ism_kw[key] = number("ism", key, 0.0, 1e4, closed_low=key == "b_nom")
    name = doc.get("name", p.stem)
    if not isinstance(name, str) or not name.strip():
        raise ValueError(f"{where}: name must be a non-empty string")
    return IntegritySettings(name.strip(), Allocation(**a, hal=limits["hal"], val=limits["val"]), limits, Ism(**ism_kw), os.fspath(p))


def snapshot_pl(los_enu: Any, systems: list[str], sigma2: Any, threshold: float, p_md: float = 1e-3, overbound: tuple[Any, Any] | None = None) -> dict[str, Any]:
    """Slope-based snapshot RAIM protection levels (see :mod:`navfdi_core::integrity::snapshot`):
    ``los_enu`` (n, 3) unit lines of sight, ``systems`` (n) letters (one clock each),
    ``sigma2`` (n) m² (the test's weights), ``threshold`` the global test's χ² quantile, ``p_md``
    the missed-detection probability (two-sided normal quantile), ``overbound`` optional
    ``(variances (n) m², nominal biases (n) m)`` of an overbounding error model for the
    fault-free terms (:func:`range_error_model`). Returns ``hpl``, ``vpl``, ``sigma_h``,
    ``sigma_v`` (m), ``hslope``, ``vslope``, ``critical``."""
    if not 0 < p_md < 1:
        raise ValueError(f"p_md = {p_md!r}: must be in (0, 1)")
    letters = sorted(set(systems), key=systems.index)
    k_md = NormalDist().inv_cdf(1 - p_md / 2)
    los = np.asarray(los_enu, dtype=float)
    ob = None if overbound is None else ([float(v) for v in np.asarray(overbound[0], dtype=float)], [float(v) for v in np.asarray(overbound[1], dtype=float)])
    return _core.snapshot_pl(los.tolist(), [letters.index(s) for s in systems], [float(v) for v in np.asarray(sigma2, dtype=float)], float(threshold), k_md, ob)


def range_error_model(elevation: Any, sigma_iono: Any, sigma_noise: Any, ism: Ism) -> dict[str, np.ndarray]:
    """The overbounding pseudorange error model of the snapshot RAIM levels, per satellite
    (arrays (n,), m; ``elevation`` in rad): ``ura`` (the ISM's σ_URA: orbit and clock),
    ``iono`` (``sigma_iono``: the solution's ``iono_sigma``, the Klobuchar residual by DO-229's
    single-frequency model, ``navfdi_core::gnss::atmosphere::klobuchar_residual_sigma``),
    ``tropo`` (the ADD's ``0.12 m · 1.001 / sqrt(0.002001 + sin² el)``, as ARAIM's), ``noise``
    (the solution's own σ: code noise and multipath by elevation or C/N0, with ``--noise``
    applied), ``total`` (the root sum of squares) and ``b_nom`` (the ISM's nominal bias)."""
    from navfdi.integrity import elevation_variances

    el = np.asarray(elevation, dtype=float)
    n = el.size
    per = lambda v: np.broadcast_to(np.asarray(v, dtype=float), (n,)).astype(float)  # noqa: E731
    ura = per(ism.sigma_ura)
    iono = per(sigma_iono)
    tropo = np.sqrt(elevation_variances(el)[0])
    noise = per(sigma_noise)
    return {"ura": ura, "iono": iono, "tropo": tropo, "noise": noise, "total": np.sqrt(ura**2 + iono**2 + tropo**2 + noise**2), "b_nom": per(ism.b_nom)}


def add_integrity(solution: Any, name: str | os.PathLike[str] | IntegritySettings = "lpv200", p_md: float = 1e-3, ism: Ism | None = None) -> None:
    """Add the integrity columns to ``solution.solution`` (see the module docs) and record the
    settings in ``solution.config["integrity"]``. ``name``: a named allocation (``lpv200``), an
    allocation file's path or resolved :class:`IntegritySettings`; ``ism`` overrides the
    settings' integrity support message."""
    settings = resolve_integrity(name)
    alloc, limits = settings.allocation, settings.limits
    ism = ism or settings.ism
    for f in ("sigma_ura", "sigma_ure", "b_nom", "p_sat"):
        if np.ndim(getattr(ism, f)) != 0:
            raise ValueError(f"ism.{f}: a file's epochs see different satellites; give one value for all")
    sol, sats = solution.solution, solution.satellites
    # Configuration errors once, before the epochs: every system solved needs a prior.
    check_systems(settings, sorted({str(x)[0] for x in sats["satellite"].astype(str).unique()} | set(solution.config.get("systems", []))), ism)
    failures: dict[str, int] = {}

    def record_failure(kind: str, e: Exception) -> None:
        key = f"{kind}: {e}"
        failures[key] = failures.get(key, 0) + 1

    # Each epoch's rows as positions into numpy columns read once (a pandas group per epoch
    # cost more than the levels themselves).
    status = sats["status"].astype(str).to_numpy()
    residual = sats["residual"].to_numpy(float)
    epoch_of = sats["epoch"].to_numpy(int)
    col = {k: sats[k].to_numpy(float) for k in ("elevation", "azimuth", "sigma", "iono_sigma")}
    names_all = sats["satellite"].astype(str).to_numpy()

    def rows(mask: np.ndarray) -> dict[int, np.ndarray]:
        pos = np.flatnonzero(mask)
        ep = epoch_of[pos]
        order = np.argsort(ep, kind="stable")
        pos, ep = pos[order], ep[order]
        cut = np.flatnonzero(np.diff(ep)) + 1
        return {int(epoch_of[c[0]]): c for c in np.split(pos, cut)} if len(pos) else {}

    by_epoch = rows(status == "used")
    all_by_epoch = rows(np.isin(status, ["used", "excluded"]) & np.isfinite(residual))
    n = len(sol)
    cols = {k: np.full(n, np.nan) for k in ("hpl", "vpl", "emt", "hpl_raim", "vpl_raim", "hpl_fde", "vpl_fde", "fde_ratio", "fde_de", "fde_dn", "fde_du")}
    state = np.full(n, "no_solution", dtype=object)
    state_fde = np.full(n, "no_solution", dtype=object)
    # The snapshot RAIM levels' error model per used satellite-epoch (NaN elsewhere).
    terms = {k: np.full(len(sats), np.nan) for k in ("ura", "tropo", "total")}
    fde_excluded = np.full(n, "", dtype=object)
    sol_status = sol["status"].astype(str).to_numpy()
    sol_threshold = sol["threshold"].to_numpy(float)
    sol_statistic = sol["statistic"].to_numpy(float)
    ura = np.asarray(ism.sigma_ura, dtype=float) ** 2
    ure = np.asarray(ism.sigma_ure, dtype=float) ** 2

    def geometry(r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        el, az = np.radians(col["elevation"][r]), np.radians(col["azimuth"][r])
        return el, np.column_stack([np.cos(el) * np.sin(az), np.cos(el) * np.cos(az), np.sin(el)])

    for i in range(n):
        if sol_status[i] != "no_solution" and i in all_by_epoch:
            r = all_by_epoch[i]
            _, los = geometry(r)
            s2 = col["sigma"][r] ** 2
            state_fde[i], fde_excluded[i] = _araim_fde_epoch(los, names_all[r].tolist(), s2 + ura, s2 + ure, residual[r], cols, i, ism, alloc, limits, record_failure)
        if sol_status[i] == "no_solution" or i not in by_epoch:
            continue
        r = by_epoch[i]
        el, los = geometry(r)
        systems = [str(x)[0] for x in names_all[r]]
        s2 = col["sigma"][r] ** 2
        try:
            a = araim(los, systems, c_int=s2 + ura, c_acc=s2 + ure, ism=ism, allocation=alloc)
            cols["hpl"][i], cols["vpl"][i], cols["emt"][i] = a.hpl, a.vpl, a.emt
            ok = a.available and a.hpl <= limits["hal"] and a.vpl <= limits["val"] and a.emt <= limits["emt"]
        except ValueError as e:
            record_failure("ARAIM", e)
            ok = False
        thr = float(sol_threshold[i])
        if math.isfinite(thr) and thr > 0:
            try:
                em = range_error_model(el, col["iono_sigma"][r], np.sqrt(s2), ism)
                for k in terms:
                    terms[k][r] = em[k]
                p = snapshot_pl(los, systems, s2, thr, p_md, overbound=(em["total"] ** 2, em["b_nom"]))
                cols["hpl_raim"][i], cols["vpl_raim"][i] = p["hpl"], p["vpl"]
            except ValueError as e:
                record_failure("snapshot RAIM", e)
        failed = sol_status[i] == "unidentified" or (sol_statistic[i] >= thr if math.isfinite(thr) else False)
        state[i] = "alarm" if failed else ("available" if ok else "unavailable")
    for k, v in cols.items():
        sol[k] = v
    for k, v in terms.items():
        sats[f"raim_sigma_{k}"] = v
    sol["integrity"] = state
    sol["integrity_fde"] = state_fde
    sol["fde_excluded"] = fde_excluded
    solution.config["integrity"] = {
        "allocation": settings.name,
        **limits,
        "p_md_raim": p_md,
        "raim_error_model": "sigma^2 = sigma_URA^2 + sigma_iono^2 (DO-229 Klobuchar residual) + sigma_tropo^2 (ADD) + the solution's sigma^2; plus b_nom",
        "sigma_ura": np.asarray(ism.sigma_ura, dtype=float).tolist(),
        "sigma_ure": np.asarray(ism.sigma_ure, dtype=float).tolist(),
        "b_nom": float(np.asarray(ism.b_nom, dtype=float)),
        "p_sat": float(np.asarray(ism.p_sat, dtype=float)),
        "p_const": dict(ism.p_const),
        "probabilities": {f: getattr(alloc, f) for f in _FILE_KEYS["allocation"]},
        "file": settings.source,
        "failed_epochs": failures,
    }


def _araim_fde_epoch(los: np.ndarray, names: list[str], c_int: np.ndarray, c_acc: np.ndarray, residuals: np.ndarray, cols: dict[str, np.ndarray], i: int, ism: Ism, alloc: Allocation, limits: dict[str, float], record_failure: Any) -> tuple[str, str]:
    """ARAIM's own fault detection and exclusion on one epoch's tested satellites (used and
    excluded by the snapshot test: lines of sight ``los`` (k, 3) east/north/up, ``names``,
    integrity and accuracy variances ``c_int``, ``c_acc`` (m²) and ``residuals`` (m) about the
    solution): fills ``hpl_fde``,
    ``vpl_fde``, ``fde_ratio`` and the correction ``fde_de/dn/du`` (m) of row ``i``; returns
    the state and the excluded satellites' names. An epoch it cannot compute is passed to
    ``record_failure(kind, error)`` (counted per reason) and is ``unavailable``."""
    try:
        r = araim(los, [s[0] for s in names], c_int=c_int, c_acc=c_acc, ism=ism, allocation=alloc, residuals=residuals)
    except ValueError as e:
        record_failure("ARAIM FDE", e)
        return "unavailable", ""
    cols["hpl_fde"][i], cols["vpl_fde"][i], cols["fde_ratio"][i] = r.hpl, r.vpl, r.test_ratio
    cols["fde_de"][i], cols["fde_dn"][i], cols["fde_du"][i] = r.correction
    excluded = " ".join(names[k] for k in r.excluded)
    if r.alarm:
        return "alarm", excluded
    ok = r.available and r.hpl <= limits["hal"] and r.vpl <= limits["val"]
    return ("available" if ok else "unavailable"), excluded


def integrity_summary(solution: Any) -> dict[str, Any]:
    """Availability and, with a truth, the counts of the Stanford diagram per direction:
    epochs where the error exceeds the protection level (``mi``: misleading, available epochs
    only; ``hmi``: the error also exceeds the alert limit), for ARAIM and snapshot RAIM."""
    sol = solution.solution
    cfg = solution.config["integrity"]
    st = sol["integrity"]
    solved = st != "no_solution"
    out: dict[str, Any] = {
        "allocation": cfg["allocation"],
        "availability": float((st == "available").sum() / solved.sum()) if solved.any() else math.nan,
        "alarm_epochs": int((st == "alarm").sum()),
        "failed_epochs": dict(cfg.get("failed_epochs", {})),
    }
    if "integrity_fde" in sol:
        sf = sol["integrity_fde"]
        out["araim_fde_availability"] = float((sf == "available").sum() / solved.sum()) if solved.any() else math.nan
        out["araim_fde_detections"] = int((sol["fde_ratio"].to_numpy(float) > 1).sum())
        out["araim_fde_exclusions"] = {str(k): int(v) for k, v in sol.loc[sol["fde_excluded"] != "", "fde_excluded"].value_counts().items()}
        out["araim_fde_alarms"] = int((sf == "alarm").sum())
    if solution.truth is None:
        return out
    e, nn, u = (sol[c].to_numpy(float) for c in ("east", "north", "up"))
    errors = {"araim": (np.hypot(e, nn), np.abs(u), (st == "available").to_numpy())}
    errors["raim"] = errors["araim"]
    if "integrity_fde" in sol:
        # ARAIM's own output position: the solution plus the kept subset's correction.
        errors["araim_fde"] = (
            np.hypot(e + sol["fde_de"].to_numpy(float), nn + sol["fde_dn"].to_numpy(float)),
            np.abs(u + sol["fde_du"].to_numpy(float)),
            (sol["integrity_fde"] == "available").to_numpy(),
        )
    for kind, h, v in (("araim", "hpl", "vpl"), ("raim", "hpl_raim", "vpl_raim"), ("araim_fde", "hpl_fde", "vpl_fde")):
        if kind not in errors:
            continue
        he, ve, avail = errors[kind]
        for d, err, pl, al in (("horizontal", he, sol[h].to_numpy(float), cfg["hal"]), ("vertical", ve, sol[v].to_numpy(float), cfg["val"])):
            ok = np.isfinite(pl) & np.isfinite(err)
            mi = ok & (err > pl)
            out[f"{kind}_{d}_misleading"] = int((mi & avail).sum())
            out[f"{kind}_{d}_hazardously_misleading"] = int((mi & (err > al)).sum())
            out[f"{kind}_{d}_pl_median"] = float(np.median(pl[ok])) if ok.any() else math.nan
            out[f"{kind}_{d}_error_over_pl_max"] = float(np.max(err[ok] / pl[ok])) if ok.any() else math.nan
        # Every epoch with finite levels, available or not: the share the levels were allotted.
        hp, vp = sol[h].to_numpy(float), sol[v].to_numpy(float)
        tested = np.isfinite(hp) & np.isfinite(vp) & np.isfinite(he) & np.isfinite(ve)
        out[f"{kind}_tested_epochs"] = int(tested.sum())
        out[f"{kind}_exceeded_epochs"] = int((tested & ((he > hp) | (ve > vp))).sum())
    return out


def allotted_share(config: dict[str, Any], kind: str) -> float:
    """The per-epoch probability of error > PL a level kind (``araim``, ``raim``,
    ``araim_fde``) is built for, from ``solution.config["integrity"]``."""
    if kind == "raim":
        return float(config["p_md_raim"])
    p = config["probabilities"]
    return float(p["p_hmi_vert"] + p["p_hmi_hor"])


def not_holding(solution: Any, summary: dict[str, Any] | None = None) -> list[str]:
    """One line per level kind whose levels the error exceeds at more epochs than its
    allotted share allows (binomial, 1 % significance): empty when every kind holds or there is
    no truth. ``summary``: :func:`integrity_summary` of ``solution`` when already computed."""
    if solution.truth is None or "integrity" not in solution.config:
        return []
    s = integrity_summary(solution) if summary is None else summary
    names = {"araim": "ARAIM", "raim": "snapshot RAIM", "araim_fde": "ARAIM after its own exclusion"}
    lines = []
    for kind, name in names.items():
        n, k = s.get(f"{kind}_tested_epochs", 0), s.get(f"{kind}_exceeded_epochs", 0)
        p = allotted_share(solution.config["integrity"], kind)
        if k and _binom_sf(k, n, p) < 0.01:
            lines.append(f"{name} levels exceeded by the error at {k} of {n} epochs, more than their allotted {p:.1e} per epoch: they do not hold on these data")
    return lines


def _binom_sf(k: int, n: int, p: float) -> float:
    """P(X ≥ k) for X ~ Binomial(n, p) (log-space terms; k ≤ n)."""
    if k <= 0:
        return 1.0
    lp, lq = math.log(p), math.log1p(-p)
    below = sum(math.exp(math.lgamma(n + 1) - math.lgamma(j + 1) - math.lgamma(n - j + 1) + j * lp + (n - j) * lq) for j in range(k))
    return max(0.0, 1.0 - below)


def plot_stanford(solution: Any, out: Path) -> list[Path]:
    """Stanford diagrams (``stanford_horizontal.png``, ``stanford_vertical.png``): error
    against the ARAIM protection level per epoch as a 2-D histogram, the alert limit and the
    diagonal, and the four regions' counts (normal operation, MI, unavailable, HMI)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sol = solution.solution
    cfg = solution.config["integrity"]
    paths = []
    for d, err, pl, al in (
        ("horizontal", np.hypot(sol["east"].to_numpy(float), sol["north"].to_numpy(float)), sol["hpl"].to_numpy(float), cfg["hal"]),
        ("vertical", np.abs(sol["up"].to_numpy(float)), sol["vpl"].to_numpy(float), cfg["val"]),
    ):
        ok = np.isfinite(err) & np.isfinite(pl)
        top = max(al * 1.5, float(np.nanmax(pl[ok], initial=0)) * 1.1, float(np.nanmax(err[ok], initial=0)) * 1.1)
        fig, ax = plt.subplots(figsize=(6.5, 5.5), constrained_layout=True)
        if ok.any():
            h = ax.hist2d(err[ok], pl[ok], bins=60, range=[[0, top], [0, top]], cmin=1, cmap="viridis")
            fig.colorbar(h[3], ax=ax, label="epochs")
        ax.plot([0, top], [0, top], "k-", lw=0.8)
        ax.axhline(al, color="tab:red", lw=0.8)
        ax.axvline(al, color="tab:red", lw=0.8, ls="--")
        normal = int((ok & (err <= pl) & (pl <= al)).sum())
        mi = int((ok & (err > pl) & (err <= al)).sum())
        unavailable = int((ok & (pl > al) & (err <= pl)).sum())
        hmi = int((ok & (err > pl) & (err > al)).sum())
        ax.text(0.02, 0.97, f"normal operation {normal}\nunavailable {unavailable}\nmisleading (MI) {mi}\nhazardously misleading {hmi}", transform=ax.transAxes, va="top", fontsize=8, bbox={"fc": "white", "alpha": 0.8})
        ax.set_xlim(0, top)
        ax.set_ylim(0, top)
        ax.set_xlabel(f"{d} position error [m]")
        ax.set_ylabel(f"{'HPL' if d == 'horizontal' else 'VPL'} (ARAIM) [m]")
        ax.set_title(f"{Path(solution.config['obs']).name}: Stanford diagram, {d} ({cfg['allocation']}, alert limit {al:g} m)", fontsize=9)
        p = out / f"stanford_{d}.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    return paths
