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
    # Each row's satellite as its rank among the sorted names of the satellites present,
    # through the category codes (no filtered copies of the table: a day file has ~10^5 rows);
    # a missing name (code −1) takes the appended −1 and is left out.
    cat = sats["satellite"].astype("category").cat.remove_unused_categories().cat
    labels = [str(n) for n in cat.categories]
    names = sorted(labels)
    pos = {n: i for i, n in enumerate(names)}
    row = np.array([pos[n] for n in labels] + [-1])[cat.codes.to_numpy()]
    epoch, status = sats["epoch"].to_numpy(), sats["status"].to_numpy()
    for state, size, colour in (("used", 2, "0.75"), ("excluded", 8, "C3")):
        m = (status == state) & (row >= 0)
        ax.scatter(tau[epoch[m]], row[m], s=size, c=colour, label=state)
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
