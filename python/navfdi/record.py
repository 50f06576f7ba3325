"""One run's record as the Rust core returns it, with accessors by channel and detector.

The layer below :mod:`navfdi.runs` (tables, files) and :mod:`navfdi.plots` (figures), which
both read runs through :class:`RunRecord`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from navfdi import _core
from navfdi.scenario import Scenario

ERROR_COLUMNS = ["att_e", "att_n", "att_u", "vel_e", "vel_n", "vel_u", "pos_e", "pos_n", "pos_u"]


def integrity_figures(m: Any) -> dict[str, float]:
    """The filter-integrity figures of ``run`` and ``montecarlo`` from the Rust metrics
    engine's sums over one run or many (``m[name]``: ``epochs``, ``mi_h_epochs``,
    ``mi_v_epochs``, ``hmi_h_epochs``, ``hmi_v_epochs``, ``alarm_epochs``,
    ``compared_epochs``, ``hpl_sum``, ``vpl_sum``, ``hpl_ratio_sum``, ``vpl_ratio_sum`` and the
    maxima ``error_over_hpl_max``, ``error_over_vpl_max``): ``epochs``, ``misleading_h/v``,
    ``hazardous_h/v``, ``alarm_epochs``, ``error_over_hpl/vpl_max``, ``hpl_mean``,
    ``vpl_mean`` (m) and ``hpl_ratio_mean``, ``vpl_ratio_mean`` (filter / snapshot level)."""
    div = lambda a, b: float(a) / b if b else float("nan")  # noqa: E731
    ep, cmp_ = int(m["epochs"]), int(m["compared_epochs"])
    return {
        "epochs": ep,
        "misleading_h": int(m["mi_h_epochs"]),
        "misleading_v": int(m["mi_v_epochs"]),
        "hazardous_h": int(m["hmi_h_epochs"]),
        "hazardous_v": int(m["hmi_v_epochs"]),
        "alarm_epochs": int(m["alarm_epochs"]),
        "error_over_hpl_max": float(m["error_over_hpl_max"]),
        "error_over_vpl_max": float(m["error_over_vpl_max"]),
        "hpl_mean": div(m["hpl_sum"], ep),
        "vpl_mean": div(m["vpl_sum"], ep),
        "hpl_ratio_mean": div(m["hpl_ratio_sum"], cmp_),
        "vpl_ratio_mean": div(m["vpl_ratio_sum"], cmp_),
    }


class RunRecord:
    """One run of a scenario: its records (with and without isolation) and accessors.

    :class:`navfdi.ScenarioRun` adds the tables and files.

    Attributes
    ----------
    scenario : Scenario
        The scenario as run.
    seed : int
        Random seed.
    t : ndarray, shape (T,)
        Epoch times (s).
    record : dict
        Raw record of the run with isolation (arrays from the Rust core).
    baseline : dict or None
        Raw record of the same run without isolation (None if not computed).
    variant : str
        Variant name (``"base"`` for a scenario without variants).
    scored_at : str
        Runs on recorded logs: where the reference is scored, ``"held_out"`` (epochs that
        were not GNSS inputs) or ``"inputs"`` (the GNSS input epochs, after their update).
    gps_t0 : float or None
        Runs on recorded logs: GPS seconds (GPST, since 1980-01-06) of time 0; None for
        simulated runs.
    calibration : navfdi.calibrate.Calibration or None
        Runs on recorded logs with ``"auto"`` fields: the estimates that filled them.
    """

    def __init__(self, scenario: Scenario, seed: int, record: dict[str, Any], baseline: dict[str, Any] | None, variant: str = "base"):
        self.scenario = scenario
        self.seed = seed
        self.record = record
        self.baseline = baseline
        self.variant = variant
        self.t: np.ndarray = record["t"]
        self.scored_at = "held_out"
        self.gps_t0: float | None = None
        self.calibration: Any = None

    def scored_label(self) -> str:
        """How the console and report name the scored reference epochs."""
        if self.scored_at == "held_out":
            return "not used as input"
        return "at the GNSS input epochs (after their update: not an independent check)"

    def reference_offset(self) -> np.ndarray:
        """Runs on recorded logs: the mean error (m; east, north, up) against the reference
        over its scored epochs outside the fault windows — the reference's own offset when it
        has one (shape (3,); NaN without scored epochs)."""
        e = self.record["error"]
        clean = np.isfinite(e[:, 6])
        for f in self.scenario.faults():
            clean &= ~((self.t >= f["start"]) & (self.t < f["end"]))
        return e[clean, 6:9].mean(axis=0) if clean.any() else np.full(3, np.nan)

    def steady_offset(self) -> bool:
        """Whether the horizontal error against the reference is mostly a steady offset: its
        RMS with :meth:`reference_offset` removed below half the RMS with it."""
        e = self.record["error"]
        ok = np.isfinite(e[:, 6])
        if not ok.any():
            return False
        off = self.reference_offset()
        raw = np.mean(e[ok, 6] ** 2 + e[ok, 7] ** 2)
        rel = np.mean((e[ok, 6] - off[0]) ** 2 + (e[ok, 7] - off[1]) ** 2)
        return bool(rel < 0.25 * raw)

    # ---- per sub-filter access -------------------------------------------------------------
    def subfilters(self) -> list[str]:
        """Sub-filter (sensor) names in configuration order."""
        return [s["sensor"] for s in self.record["subfilters"]]

    def detector(self, subfilter: str, name: str) -> dict[str, np.ndarray]:
        """Arrays ``statistic, threshold, alarm`` (shape (T,)) of one detector."""
        for s in self.record["subfilters"]:
            if s["sensor"] == subfilter:
                for d in s["detectors"]:
                    if d["name"] == name:
                        return d
        raise KeyError(f"no detector {name!r} on sub-filter {subfilter!r}")

    def isolated(self, subfilter: str) -> np.ndarray:
        """Isolation flag per epoch of a sub-filter, shape (T,)."""
        for s in self.record["subfilters"]:
            if s["sensor"] == subfilter:
                return s["isolated"]
        raise KeyError(f"no sub-filter {subfilter!r}")

    def error(self, isolation: bool = True) -> np.ndarray:
        """Master navigation error ``x_true − x_g``, shape (T, 9): attitude east/north/up (rad),
        velocity (m/s), position east/north/up (m). ``isolation=False``: the run without."""
        rec = self.record if isolation else self.baseline
        if rec is None:
            raise ValueError("this run was made without the no-isolation baseline")
        return rec["error"]

    def components(self, subfilter: str) -> list[str]:
        """Measurement component names of a channel's sensor (e.g. ``pos_e ... vel_u``)."""
        from navfdi.scenario import SENSOR_COMPONENTS

        kind = next(s["kind"] for s in self.scenario.core["sensors"] if s["name"] == subfilter)
        return [c for c, _ in SENSOR_COMPONENTS[kind]]

    def mdb_note(self) -> str:
        """Which λ0 the MDB uses, beside paper 002's 17.872 (METHODS §6); empty without MDB."""
        core = self.scenario.core
        if core.get("architecture") != "centralized":
            return ""
        lines = []
        for cs, s in zip(core["centralized"]["sensors"], self.record["subfilters"]):
            if "mdb" not in s:
                continue
            dets = {d["name"]: d for d in cs["detectors"]}
            det = dets.get(cs.get("decision") or "", cs["detectors"][0] if cs["detectors"] else None)
            if det is None:
                continue
            pf, pm, m = det["pf"], det["pm"] if det["pm"] is not None else det["pf"], s["mdb"].shape[1]
            lam = _core.noncentrality(pf, pm, m)
            med = np.nanmedian(s["mdb"], axis=0)
            comps = ", ".join(f"{c} {v:.3g}" for c, v in zip(self.components(s["sensor"]), med))
            lines.append(f"MDB on {s['sensor']}: λ0 = {lam:.3f} (m = {m}, Pf = {pf:g}, Pm = {pm:g}); median {comps}")
        if lines:
            lines.append(f"MDB note: paper 002's λ0 = 17.872 is m = 6, Pf = 0.1, Pm = 0.05 ({_core.noncentrality(0.1, 0.05, 6):.3f}); navfdi: standard λ0 above")
        return "\n".join(lines)

