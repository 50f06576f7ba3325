"""The per-epoch table of a run (``timeseries.parquet``): its columns, for
:meth:`navfdi.runs.ScenarioRun.timeseries` (which documents them)."""

from __future__ import annotations

from typing import Any

import numpy as np

from navfdi.record import ERROR_COLUMNS, RunRecord


def timeseries_columns(run: RunRecord) -> dict[str, Any]:
    """The columns of ``run``'s per-epoch table, name to array (T,), in table order."""
    cols: dict[str, Any] = {"t": run.t}
    t0 = getattr(run, "gps_t0", None)
    if t0 is not None:
        gps = t0 + np.asarray(run.t, dtype=float)
        cols["gps_week"] = np.floor(gps / 604800.0).astype(np.int64)
        cols["gps_sow"] = gps - cols["gps_week"] * 604800.0
    for s in run.record["subfilters"]:
        sub = s["sensor"]
        cols[f"{sub}.statistic"] = s["statistic"]
        if "mdb" in s:
            for j, comp in enumerate(run.components(sub)):
                cols[f"{sub}.mdb.{comp}"] = s["mdb"][:, j]
        cols[f"{sub}.isolated"] = s["isolated"]
        cols[f"{sub}.fused"] = s["fused"]
        if "noise_scale" in s:
            cols[f"{sub}.excluded"] = np.array(s["reason_names"], dtype=object)[s["reason"]]
            cols[f"{sub}.noise_scale"] = s["noise_scale"]
        for d in s["detectors"]:
            for k in ("statistic", "threshold", "alarm"):
                cols[f"{sub}.{d['name']}.{k}"] = d[k]
    if "fused_alt" in run.record:
        cols["fused_alt.error"] = run.record["fused_alt"]
    fu = run.record.get("fusion")
    if fu is not None:
        for j, name in enumerate(fu["sensors"]):
            cols[f"fused_alt.{name}.error"] = fu["error"][:, j]
            cols[f"fused_alt.{name}.weight"] = fu["weight"][:, j]
    if "mode" in run.record:
        cols["mode"] = np.array(["", "q1", "q2", "q3"], dtype=object)[run.record["mode"]]
    st = run.record.get("state_chi2")
    if st is not None:
        for k in ("statistic", "threshold", "alarm", "ready", "ill_conditioned"):
            cols[f"state_chi2.{k}"] = st[k]
    sat = run.record.get("satellites")
    if sat is not None:
        names = sat["names"]
        status = np.array(sat["status_names"], dtype=object)[sat["status"]]
        cols["fde.status"] = status
        cols["fde.used"] = sat["used"]
        cols["fde.excluded"] = [",".join(names[j] for j in np.flatnonzero(row)) for row in sat["excluded"]]
        for j, nm in enumerate(names):
            if sat["in_view"][:, j].any():
                cols[f"sat.{nm}.in_view"] = sat["in_view"][:, j]
                cols[f"sat.{nm}.excluded"] = sat["excluded"][:, j]
                cols[f"sat.{nm}.w"] = sat["w"][:, j]
    it = run.record.get("integrity")
    if it is not None:
        for k in ("hpl", "vpl", "hpl_snapshot", "vpl_snapshot", "statistic", "alarm", "modes"):
            cols[f"integrity.{k}"] = it[k]
    nav = run.record.get("nav")
    if nav is not None:
        cols["time"] = run.t
        for j, c in enumerate(run.record["nav_columns"]):
            v = nav[:, j]
            if c in ("lat", "lon"):
                v = np.degrees(v)
            elif c in ("roll", "pitch", "yaw"):
                c, v = f"{c}_deg", np.degrees(v)
            cols[c] = v
    for i, c in enumerate(ERROR_COLUMNS):
        cols[f"error.{c}"] = run.record["error"][:, i]
        cols[f"sigma.{c}"] = run.record["sigma"][:, i]
        if run.baseline is not None:
            cols[f"error_no_isolation.{c}"] = run.baseline["error"][:, i]
    return cols
