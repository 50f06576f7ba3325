"""Figures of a scenario run (matplotlib, Agg backend): the paper's Fig. 3–5 style."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from navfdi.federated import ScenarioRun


def plot_run(run: ScenarioRun, out: Path) -> list[Path]:
    """Write PNG figures for a run into ``out``:

    * ``detector_{sub}_{det}.png``: statistic (log scale) against threshold, alarm epochs, fault
      windows shaded, for every detector of every sub-filter with faults;
    * ``master_attitude_error.png``: master attitude error (arcsec) per axis with and without
      isolation.

    Returns the paths written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    t = run.t
    faults = run.scenario.faults()
    for s in run.record["subfilters"]:
        sub = s["sensor"]
        mine = [f for f in faults if f["sensor"] == sub]
        if not mine:
            continue
        for d in s["detectors"]:
            fig, ax = plt.subplots(figsize=(9, 3.6), constrained_layout=True)
            for f in mine:
                ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.12, lw=0)
            stat = np.where(np.isfinite(d["statistic"]), np.maximum(d["statistic"], 1e-6), np.nan)
            ax.semilogy(t, stat, lw=0.8, color="tab:blue", label="statistic")
            ax.semilogy(t, d["threshold"], lw=1.0, color="k", ls="--", label="threshold")
            al = d["alarm"].astype(bool)
            ax.scatter(t[al], stat[al], s=4, color="tab:red", label="alarm", zorder=3)
            iso = run.isolated(sub)
            if np.any(iso):
                ax.fill_between(t, 0, 0.04, where=iso, color="tab:orange", step="mid", label="isolated", transform=ax.get_xaxis_transform())
            ax.set_ylim(1e-3, max(1e2, np.nanmax(stat) * 2))
            ax.set_xlabel("time [s]")
            ax.set_ylabel("statistic")
            ax.set_title(f"{run.scenario.name}: {sub} sub-filter, detector {d['name']} (seed {run.seed}); faults shaded")
            ax.legend(loc="upper left", fontsize=8, ncol=4)
            p = out / f"detector_{sub}_{d['name']}.png"
            fig.savefig(p, dpi=110)
            plt.close(fig)
            paths.append(p)
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True, constrained_layout=True)
    arcsec = np.degrees(1.0) * 3600
    for i, (ax, name) in enumerate(zip(axes, ["east", "north", "up"])):
        for f in faults:
            ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.1, lw=0)
        if run.baseline is not None:
            ax.plot(t, run.error(False)[:, i] * arcsec, lw=0.8, color="tab:gray", label="without isolation")
        ax.plot(t, run.error(True)[:, i] * arcsec, lw=0.8, color="tab:blue", label="with isolation")
        ax.set_ylabel(f"φ_{name[0].upper()} [arcsec]")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8)
    axes[0].set_title(f"{run.scenario.name}: master attitude error (seed {run.seed})")
    axes[-1].set_xlabel("time [s]")
    p = out / "master_attitude_error.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    return paths
