"""Figures of ``navfdi gnss`` (:meth:`navfdi.gnss.GnssSolution.write`): the position error
against the truth, the global statistic against its threshold, and the satellites used and
excluded per epoch, each with the injected faults' windows shaded."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def plot(s: Any, d: Path) -> list[Path]:
    """Write ``errors.png`` (with a truth), ``statistic.png`` and ``exclusions.png`` of ``s`` (a
    :class:`navfdi.gnss.GnssSolution`; typed loosely to keep this module below it) into ``d``;
    their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sol, sats = s.solution, s.satellites
    t = sol["gps_seconds"].to_numpy()
    tau = t - t[0] if len(t) else t
    cfg = s.config
    what = f"{Path(cfg['obs']).name}: {','.join(cfg['systems'])}, mask {cfg['mask_deg']:g}°, α {cfg['alpha']:g}, {'FDE' if cfg['exclude'] else 'no exclusion'}"
    paths = []
    if s.truth is not None:
        fig, ax = plt.subplots(figsize=(9, 4))
        for c in ("east", "north", "up"):
            ax.plot(tau, sol[c], label=c, lw=1)
        ax.grid(alpha=0.3)
        paths.append(finish(plt, fig, ax, s.faults, d / "errors.png", {}, what, ylabel="error (m)", title="Position error against the truth"))
    fig, ax = plt.subplots(figsize=(9, 4))
    ax.semilogy(tau, sol["first_statistic"], lw=1, label="global test, all satellites")
    ax.semilogy(tau, sol["first_threshold"], "k--", lw=1, label="threshold")
    ax.grid(alpha=0.3)
    paths.append(finish(plt, fig, ax, s.faults, d / "statistic.png", {}, what, ylabel="VᵀD⁻¹V", title="Global test statistic vs threshold"))
    fig, ax = plt.subplots(figsize=(9, 4))
    names = sorted(str(n) for n in sats["satellite"].unique())
    pos = {n: i for i, n in enumerate(names)}
    used = sats[sats["status"] == "used"]
    ex = sats[sats["status"] == "excluded"]
    ax.scatter(tau[used["epoch"]], [pos[str(n)] for n in used["satellite"]], s=2, c="0.75", label="used")
    ax.scatter(tau[ex["epoch"]], [pos[str(n)] for n in ex["satellite"]], s=8, c="C3", label="excluded")
    ax.set_yticks(range(len(names)), names, fontsize=7)
    paths.append(finish(plt, fig, ax, s.faults, d / "exclusions.png", {"loc": "upper left", "bbox_to_anchor": (1.01, 1.0)}, what, title="Satellites used and excluded per epoch"))
    return paths


def finish(plt: Any, fig: Any, ax: Any, faults: list[Any], path: Path, legend: dict[str, Any], what: str = "", **labels: str) -> Path:
    """Shade the fault windows (one legend entry naming them), label the time axis, title the
    figure with ``labels["title"]`` and what was run (``what``: file, systems, mask), add the
    legend, save ``path`` and close."""
    shade_faults(ax, faults)
    if faults:
        ax.axvspan(np.nan, np.nan, color="C1", alpha=0.12, label="injected: " + ", ".join(f"{f.satellite} {f.shape}" for f in faults))
    if what and "title" in labels:
        labels = {**labels, "title": f"{labels['title']}\n{what}"}
    ax.set(xlabel="time since first epoch (s)", **labels)
    ax.legend(**legend)
    fig.savefig(path, dpi=110, bbox_inches="tight")
    plt.close(fig)
    return path


def shade_faults(ax: Any, faults: list[Any]) -> None:
    """Shade each fault's window [start, end) s on ``ax``'s time axis."""
    for f in faults:
        ax.axvspan(f.start, min(f.end, ax.get_xlim()[1]), color="C1", alpha=0.12)
