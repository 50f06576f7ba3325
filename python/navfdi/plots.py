"""Figures of a scenario run (matplotlib, Agg backend): the paper's Fig. 3–5 style."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from navfdi._intervals import alarm_intervals, tested_epochs
from navfdi.scenario import fault_on

if TYPE_CHECKING:
    from navfdi.record import RunRecord


def plot_run(run: RunRecord, out: Path, prefix: str = "") -> list[Path]:
    """Write PNG figures for a run into ``out``:

    * ``detector_{sub}_{det}.png``: statistic (log scale) against threshold, alarm epochs, fault
      windows shaded, for every detector of every sub-filter with faults;
    * ``modes.png``: the navigation mode per epoch (scenarios with ``[modes]``);
    * ``detector_navigation_state_chi2.png``: the state chi-square test of the navigation
      solution (scenarios with ``[state_chi2]``);
    * ``altitude_fusion.png`` (altitude fusion, paper 003's Fig. 9, 10, 12): each fused
      sensor's height measurement error, the fused altitude's error and the weights;
    * ``altitude_statistics.png`` (altitude fusion, paper 003's Fig. 11): residual and state
      chi-square statistics of every fused sensor;
    * ``channel_statistics.png`` (ultra-tight): every channel's statistic against the
      threshold, faulty channels highlighted, exclusions marked (paper 004's Fig. 11–15);
    * ``master_attitude_error.png``: master attitude error (arcsec) per axis with and without
      isolation (simulated runs);
    * ``protection_levels.png`` (tight filter with ``[tight.integrity]``): horizontal and
      vertical error against the filter and snapshot protection levels;
    * runs on recorded logs: every GNSS channel's detectors, and ``track.png``,
      ``errors.png``, ``biases.png`` (:func:`navfdi.plots_logged.plot_logged`).

    Returns the paths written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    paths = []
    t = run.t
    faults = run.scenario.faults()
    for name, fig in detector_figures(run, prefix):
        p = out / name
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    if "mode" in run.record:
        fig, ax = plt.subplots(figsize=(9, 2.4), constrained_layout=True)
        ax.step(t, run.record["mode"], where="post", color="k", lw=1.0)
        ax.set_yticks([1, 2, 3], ["q1", "q2", "q3"])
        ax.set_ylim(0.5, 3.5)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("mode")
        var = f", variant {run.variant}" if prefix else ""
        ax.set_title(f"{run.scenario.name}{var}: navigation mode (seed {run.seed})")
        p = out / f"{prefix}modes.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    for s in run.record["subfilters"]:
        if "mdb" not in s:
            continue
        comps = run.components(s["sensor"])
        groups = [("position", [j for j, c in enumerate(comps) if c.startswith("pos")], "m"), ("velocity", [j for j, c in enumerate(comps) if c.startswith("vel")], "m/s")]
        groups = [g for g in groups if g[1]] or [("measurement", list(range(len(comps))), "")]
        fig, axes = plt.subplots(len(groups), 1, figsize=(9, 3 + 2.5 * len(groups)), sharex=True, constrained_layout=True, squeeze=False)
        for ax, (label, idx, unit) in zip(axes[:, 0], groups):
            for f in faults:
                if fault_on(f, s["sensor"]):
                    ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.1, lw=0)
            for gi, j in enumerate(idx):
                ax.plot(t, s["mdb"][:, j], lw=1.0, marker=MARKERS[gi % len(MARKERS)], markevery=max(1, t.size // 20), ms=3, label=comps[j])
            ax.set_ylabel(f"MDB, {label} [{unit}]")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8, ncol=3)
        import re

        found = re.search(r"λ0 = ([0-9.]+)", run.mdb_note())
        lam = found.group(1) if found else "?"
        axes[0, 0].set_title(f"{run.scenario.name}: minimal detectable bias of {s['sensor']} (seed {run.seed}); λ0 = {lam} (standard; paper 002: 17.872)", fontsize=9)
        axes[-1, 0].set_xlabel("time [s]")
        p = out / f"{prefix}mdb_{s['sensor']}.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)
    if "fusion" in run.record:
        paths += _plot_altitude(run, out, prefix, plt)
    if run.scenario.core.get("architecture") == "ultra_tight":
        paths.append(_plot_channels(run, out, prefix, plt))
    if "nav" in run.record:
        # Recorded logs: no attitude reference; the track, errors and biases instead.
        from navfdi.plots_logged import plot_logged

        return paths + plot_logged(run, out, prefix)
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True, constrained_layout=True)
    arcsec = np.degrees(1.0) * 3600
    sigma = run.record["sigma"]
    for i, (ax, name) in enumerate(zip(axes, ["east", "north", "up"])):
        for f in faults:
            ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.1, lw=0)
        s = sigma[:, i] * arcsec
        main_label = "with isolation" if run.baseline is not None else f"variant {run.variant}"
        ax.fill_between(t, -s, s, color="tab:blue", alpha=0.15, lw=0, label=f"±1σ (filter, {main_label})")
        if run.baseline is not None:
            ax.plot(t, run.error(False)[:, i] * arcsec, lw=0.8, color="tab:gray", label="without isolation")
        ax.plot(t, run.error(True)[:, i] * arcsec, lw=0.8, color="tab:blue", label=main_label)
        ax.set_ylabel(f"φ_{name[0].upper()} [arcsec]")
        ax.grid(alpha=0.3)
    axes[0].legend(loc="upper left", fontsize=8, ncol=3)
    if faults:
        axes[0].axvspan(np.nan, np.nan, color="tab:red", alpha=0.1, lw=0, label="fault window")
        axes[0].legend(loc="upper left", fontsize=8, ncol=4)
    what = "" if run.baseline is not None else f" ({run.variant})"
    axes[0].set_title(f"{run.scenario.name}{what}: master attitude error and its ±1σ envelope (seed {run.seed})")
    axes[-1].set_xlabel("time [s]")
    p = out / f"{prefix}master_attitude_error.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    if run.record.get("integrity") is not None:
        paths.append(_plot_protection_levels(run, out, prefix, plt))
    return paths


def detector_figures(run: RunRecord, prefix: str = ""):
    """The detector figures of :func:`plot_run`, as ``(file name, matplotlib Figure)`` pairs
    (the caller saves and closes them): ``{prefix}detector_{sub}_{det}.png`` for every
    detector of every channel with faults (every GNSS channel on recorded logs) and
    ``{prefix}detector_navigation_state_chi2.png`` with ``[state_chi2]``. Each draws the
    statistic and threshold at the epochs the detector tested (line label ``statistic`` and
    ``threshold``; a sensor slower than the record is tested only at its own epochs), alarms
    as red dots, exclusions or isolations as orange spans over the channel's tests, fault
    windows shaded; a detector that never tested says so in the frame."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = run.t
    faults = run.scenario.faults()
    var = f", variant {run.variant}" if prefix else ""
    for s in run.record["subfilters"]:
        sub = s["sensor"]
        mine = [f for f in faults if fault_on(f, sub)]
        if not mine and ("nav" not in run.record or sub in ("zupt", "nhc")):
            continue
        for d in s["detectors"]:
            fig, ax = plt.subplots(figsize=(9, 3.6), constrained_layout=True)
            stat = _statistic_axes(ax, t, d, mine)
            iso = np.asarray(run.isolated(sub), bool)
            if iso.any():
                by = _isolating_detector(run, sub)
                label = f"{sub} isolated (by {by})" if by else f"{sub} isolated"
                if run.scenario.core.get("architecture") == "tight":
                    label = f"a satellite excluded (by {by})" if by else "a satellite excluded"
                tested = np.asarray(s["dof"]) > 0 if "dof" in s else None
                for j, iv in enumerate(alarm_intervals(iso, t, tested)):
                    end = iv.end if iv.end is not None else float(t[-1])
                    ax.axvspan(iv.start, max(end, iv.start + 1e-9), ymin=0, ymax=0.04, color="tab:orange", lw=0, label=label if j == 0 else None)
            finite = stat[np.isfinite(stat)]
            ax.set_ylim(1e-3, max(1e2, float(finite.max()) * 2 if finite.size else 1e2))
            ax.set_xlim(float(t[0]), float(t[-1]))
            ax.set_xlabel("time [s]")
            ax.set_ylabel("statistic")
            what = {"federated": "sub-filter", "tight": "satellites"}.get(run.scenario.core.get("architecture", "federated"), "sensor")
            ax.set_title(f"{run.scenario.name}{var}: {sub} {what}, detector {d['name']} (seed {run.seed}); faults shaded")
            ax.legend(loc="upper left", fontsize=8, ncol=4)
            yield f"{prefix}detector_{sub}_{d['name']}.png", fig
    st = run.record.get("state_chi2")
    if st is not None:
        fig, ax = plt.subplots(figsize=(9, 3.6), constrained_layout=True)
        _statistic_axes(ax, t, st, faults)
        ax.set_xlabel("time [s]")
        ax.set_ylabel("λ = βᵀV⁻¹β")
        ax.set_title(f"{run.scenario.name}{var}: state chi-square of the navigation solution (seed {run.seed}); faults shaded")
        ax.legend(loc="upper left", fontsize=8, ncol=3)
        yield f"{prefix}detector_navigation_state_chi2.png", fig


def _plot_protection_levels(run: RunRecord, out: Path, prefix: str, plt: Any) -> Path:
    """``protection_levels.png``: horizontal and vertical position error (m, log scale)
    against the filter's HPL / VPL and the snapshot ARAIM levels of the same epochs, the
    separation test's alarms marked, fault windows shaded."""
    it = run.record["integrity"]
    t = run.t
    e = run.record["error"]
    errs = (np.hypot(e[:, 6], e[:, 7]), np.abs(e[:, 8]))
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True, constrained_layout=True)
    for ax, err, key, name in zip(axes, errs, ("hpl", "vpl"), ("horizontal", "vertical")):
        for f in run.scenario.faults():
            ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.1, lw=0)
        ax.plot(t, err, lw=0.8, color="tab:blue", label=f"{name} error")
        ax.plot(t, it[key], lw=1.0, color="tab:green", label=f"filter {key.upper()}")
        ax.plot(t, it[f"{key}_snapshot"], lw=0.8, color="tab:orange", ls="--", label=f"snapshot ARAIM {key.upper()}")
        alarm = np.asarray(it["alarm"], bool)
        if alarm.any():
            ax.plot(t[alarm], err[alarm], "v", ms=4, color="tab:red", label="separation alarm")
        ax.set_yscale("log")
        ax.set_ylabel(f"{name} [m]")
        ax.grid(alpha=0.3, which="both")
    if run.scenario.faults():
        axes[0].axvspan(np.nan, np.nan, color="tab:red", alpha=0.1, lw=0, label="fault window")
    axes[0].legend(loc="upper left", fontsize=8, ncol=3)
    what = "" if run.variant is None else f" ({run.variant})"
    axes[0].set_title(f"{run.scenario.name}{what}: position error against the protection levels (seed {run.seed})")
    axes[-1].set_xlabel("time [s]")
    p = out / f"{prefix}protection_levels.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return p


def _plot_channels(run: RunRecord, out: Path, prefix: str, plt: Any) -> Path:
    """``channel_statistics.png`` (ultra-tight; paper 004's Fig. 11–15): every tracked
    channel's statistic (log scale) against the threshold, faulty channels in colour and
    healthy ones in grey, a cross where a channel was excluded."""
    t = run.t
    faults = run.scenario.faults()
    fig, ax = plt.subplots(figsize=(9, 4.2), constrained_layout=True)
    thr = None
    ci = 0
    for s in run.record["subfilters"]:
        sub = s["sensor"]
        d = s["detectors"][0]
        st = np.asarray(d["statistic"], float)
        faulty = any(fault_on(f, sub) for f in faults)
        kw: dict[str, Any] = {"lw": 1.2, "color": f"C{ci % 10}", "label": f"{sub} (faulty)"} if faulty else {"lw": 0.7, "color": "0.6", "alpha": 0.8, "label": sub}
        ci += int(faulty)
        ax.plot(t, np.where(st > 0, st, np.nan), **kw)
        iso = np.asarray(s["isolated"])
        if iso.any():
            k = int(np.argmax(iso))
            ax.plot(t[k], max(st[k], 1e-3) if np.isfinite(st[k]) else 1.0, "x", color=kw["color"], ms=8)
        thr = np.asarray(d["threshold"], float)
    if thr is not None:
        ax.plot(t, thr, "k--", lw=1.0, label="threshold")
    for f in faults:
        ax.axvline(f["start"], color="tab:red", lw=0.8, alpha=0.6)
    ax.set_yscale("log")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("statistic")
    var = f", variant {run.variant}" if prefix else ""
    u = run.scenario.core["ultra_tight"]
    ax.set_title(f"{run.scenario.name}{var}: {u['method']} per channel (seed {run.seed}); x = excluded, red line = fault start")
    ax.legend(loc="upper left", fontsize=7, ncol=5)
    ax.grid(alpha=0.3)
    p = out / f"{prefix}channel_statistics.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return p


def _state_detector(run: RunRecord, sub: str) -> str | None:
    """Name of a sensor's ``state_chi2`` detector (centralized architecture), if any."""
    for cs in run.scenario.core.get("centralized", {}).get("sensors", []):
        if cs["sensor"] == sub:
            for d in cs["detectors"]:
                if d["kind"] == "state_chi2":
                    return str(d["name"])
    return None


def _plot_altitude(run: RunRecord, out: Path, prefix: str, plt: Any) -> list[Path]:
    """The altitude-fusion figures of :func:`plot_run`."""
    t = run.t
    fu = run.record["fusion"]
    var = f", variant {run.variant}" if prefix else ""
    fig, axes = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, constrained_layout=True, gridspec_kw={"height_ratios": [2, 1]})
    for j, name in enumerate(fu["sensors"]):
        axes[0].plot(t, fu["error"][:, j], lw=0.8, marker=MARKERS[j % len(MARKERS)], markevery=max(1, t.size // 20), ms=3, label=name)
        axes[1].plot(t, fu["weight"][:, j], lw=0.8, marker=MARKERS[j % len(MARKERS)], markevery=max(1, t.size // 20), ms=3, label=name)
    axes[0].plot(t, run.record["fused_alt"], lw=1.4, color="k", label="fused")
    axes[0].set_ylabel("height measurement error [m]")
    axes[1].set_ylabel("weight w_i M_i / Σ w M")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, ncol=len(fu["sensors"]) + 1)
    axes[0].set_title(f"{run.scenario.name}{var}: altitude fusion (seed {run.seed}); gaps: sensor absent or fused value absent")
    axes[1].set_xlabel("time [s]")
    paths = [out / f"{prefix}altitude_fusion.png"]
    fig.savefig(paths[0], dpi=110)
    plt.close(fig)
    subs = {s["sensor"]: s for s in run.record["subfilters"]}
    fig, axes = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True, constrained_layout=True)
    for j, name in enumerate(fu["sensors"]):
        s = subs[name]
        state = _state_detector(run, name)
        series = [(axes[1], s["statistic"])]
        if state is not None:
            series.append((axes[0], run.detector(name, state)["statistic"]))
        for ax, stat in series:
            ax.semilogy(t, np.where(np.isfinite(stat), np.maximum(stat, 1e-6), np.nan), lw=0.8, marker=MARKERS[j % len(MARKERS)], markevery=max(1, t.size // 20), ms=3, label=name)
    axes[0].set_ylabel("state χ² λ = βᵀV⁻¹β")
    axes[1].set_ylabel("residual χ² rᵀA⁻¹r")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=len(fu["sensors"]))
    axes[0].set_title(f"{run.scenario.name}{var}: state (top) and residual (bottom) chi-square per fused sensor (seed {run.seed})")
    axes[1].set_xlabel("time [s]")
    paths.append(out / f"{prefix}altitude_statistics.png")
    fig.savefig(paths[1], dpi=110)
    plt.close(fig)
    return paths


def _statistic_axes(ax: Any, t: np.ndarray, d: dict[str, Any], faults: list[dict[str, Any]]) -> np.ndarray:
    """Shade the fault windows and draw a detector's statistic (log scale, floored at 1e-6)
    and threshold at the epochs it tested (joined across the untested epochs between them;
    markers when the tests are sparse), and its alarmed tests; returns the statistic at every
    epoch (NaN where untested). Writes "no test in this run" in the frame when there is
    none."""
    for f in faults:
        ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.12, lw=0)
    raw = np.asarray(d["statistic"], float)
    tested = tested_epochs(raw)
    stat = np.where(tested, np.maximum(np.nan_to_num(raw, posinf=1e300), 1e-6), np.nan)
    if not tested.any():
        ax.text(0.5, 0.5, "no test in this run (the sensor never measured)", ha="center", va="center", transform=ax.transAxes)
        ax.set_yscale("log")
        return stat
    tt = t[tested]
    marker = "." if tt.size <= 600 else None
    ax.semilogy(tt, stat[tested], lw=0.8, color="tab:blue", marker=marker, ms=3, label="statistic")
    ax.semilogy(tt, np.asarray(d["threshold"], float)[tested], lw=1.0, color="k", ls="--", label="threshold")
    al = np.asarray(d["alarm"], bool) & tested
    ax.scatter(t[al], stat[al], s=6, color="tab:red", label="alarm", zorder=3)
    return stat


def _isolating_detector(run: RunRecord, sub: str) -> str | None:
    """Name of the detector whose alarm isolates (federated) or excludes (centralized) the
    channel of sensor ``sub`` (None if none does)."""
    core = run.scenario.core
    if core.get("architecture") == "tight":
        return None if core["tight"]["fde"] == "none" else f"{core['tight']['fde']} FDE"
    if core.get("architecture") == "ultra_tight":
        u = core["ultra_tight"]
        return str(u["method"]) if u["exclude"] else None
    if core.get("architecture") == "loosely_coupled":
        for cs in core["loosely_coupled"]["sensors"]:
            if cs["sensor"] == sub:
                return cs.get("decision")
        return None
    if core.get("architecture", "federated") == "centralized":
        for cs in core["centralized"]["sensors"]:
            if cs["sensor"] == sub:
                return cs.get("decision")
        return None
    for sf in core["federated"]["subfilters"]:
        if sf["sensor"] == sub:
            return sf.get("isolation")
    return None


def plot_variant_errors(runs, out: Path) -> list[Path]:
    """``variant_errors.png``: latitude (north), east and up position error per variant over
    time, with each variant's ±1σ envelope, faults shaded (paper 002's Fig. 3b style); with
    altitude fusion also ``variant_fused_altitude.png``, the fused altitude's error per
    variant (paper 003's Fig. 10b and 12b)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(3, 1, figsize=(9, 7.5), sharex=True, constrained_layout=True)
    first = next(iter(runs.runs.values()))
    if "nav" in first.record:
        # Recorded logs: horizontal and vertical error at the scored epochs.
        plt.close(fig)
        fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True, constrained_layout=True)
        for gi, (name, r) in enumerate(runs.runs.items()):
            e = r.record["error"]
            ok = np.isfinite(e[:, 6])
            rms = r.errors()["hor_rms"]
            axes[0].plot(r.t[ok], np.hypot(e[ok, 6], e[ok, 7]), lw=0.8, marker=MARKERS[gi % len(MARKERS)], markevery=max(1, int(ok.sum()) // 25), ms=3, label=f"{name} (RMS {rms:.3f} m)")
            axes[1].plot(r.t[ok], e[ok, 8], lw=0.8, marker=MARKERS[gi % len(MARKERS)], markevery=max(1, int(ok.sum()) // 25), ms=3, label=name)
        for ax, label in zip(axes, ["horizontal error [m]", "up error [m]"]):
            for f in first.scenario.faults():
                ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.1, lw=0)
            ax.set_ylabel(label)
            ax.grid(alpha=0.3)
        axes[0].set_yscale("symlog", linthresh=0.1)
        axes[0].legend(fontsize=8)
        axes[0].set_title(f"{first.scenario.name}: error per variant against the reference's non-input epochs; faults shaded", fontsize=10)
        axes[-1].set_xlabel("time [s]")
        p = out / "variant_errors.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        return [p]
    for ax, (col, label) in zip(axes, [(7, "latitude (north) error [m]"), (6, "east error [m]"), (8, "up error [m]")]):
        for f in first.scenario.faults():
            ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.1, lw=0)
        for gi, (name, r) in enumerate(runs.runs.items()):
            line = ax.plot(r.t, r.record["error"][:, col], lw=0.9, label=name, marker=MARKERS[gi % len(MARKERS)], markevery=max(1, r.t.size // 25), ms=3)
            s = r.record["sigma"][:, col]
            ax.fill_between(r.t, -s, s, color=line[0].get_color(), alpha=0.08, lw=0)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, ncol=len(runs.runs))
    axes[0].set_title(f"{first.scenario.name}: position error per variant with ±1σ (seed {runs.seed}); faults shaded")
    axes[-1].set_xlabel("time [s]")
    p = out / "variant_errors.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths = [p]
    if "fused_alt" in first.record:
        # Paper 003's Fig. 10b / 12b: the fused altitude's error without and with isolation.
        fig, ax = plt.subplots(figsize=(9, 3.6), constrained_layout=True)
        for gi, (name, r) in enumerate(runs.runs.items()):
            rms = r.errors()["fused_alt_rms"]
            ax.plot(r.t, r.record["fused_alt"], lw=0.9, marker=MARKERS[gi % len(MARKERS)], markevery=max(1, r.t.size // 25), ms=3, label=f"{name} (RMS {rms:.3f} m)")
        ax.set_xlabel("time [s]")
        ax.set_ylabel("fused altitude error [m]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"{first.scenario.name}: fused altitude error per variant (seed {runs.seed})")
        paths.append(out / "variant_fused_altitude.png")
        fig.savefig(paths[-1], dpi=110)
        plt.close(fig)
    return paths


MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*", "<", ">"]


def _offsets(count: int, width: float = 0.25) -> np.ndarray:
    """Small x offsets that spread ``count`` series around each sweep point, so lines that
    coincide (e.g. detection probability 1 for every detector) stay distinguishable."""
    if count <= 1:
        return np.zeros(max(count, 1))
    return np.linspace(-width / 2, width / 2, count)


def plot_campaign(campaign, out: Path) -> list[Path]:
    """Write PNG plots of a Monte-Carlo campaign into ``out``:

    * ``delay.png`` (when the scenario has faults): detection delay (median, bars to the 95th
      percentile) per detector and fault against the sweep point;
    * ``rates.png``: detection probability per detector and fault, and false-alarm rate per
      epoch per detector, with their 95 % Wilson intervals, against the sweep point.

    Returns the paths written.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = campaign.summary()
    cols = campaign.sweep_columns
    labels = [", ".join(f"{v}" for v in pt.values()) or "(no sweep)" for pt in campaign.points]
    xlabel = " × ".join(cols) if cols else ""
    x = np.arange(len(campaign.points))

    def point_index(df):
        if not cols:
            return np.zeros(len(df), dtype=int)
        keys = [tuple(pt[c] for c in cols) for pt in campaign.points]
        return np.array([keys.index(tuple(r[c] for c in cols)) for _, r in df.iterrows()])

    paths = []
    faults = s[s["fault_id"] != "none"]
    if faults.empty:
        fig = None
    else:
        fig, ax = plt.subplots(figsize=(8, 4.5), constrained_layout=True)
    if fig is not None:
        groups = list(faults.groupby(["subfilter", "detector", "fault_id"], sort=False))
        off = _offsets(len(groups))
        for gi, ((sub, det, fid), g) in enumerate(groups):
            xi = point_index(g) + off[gi]
            med, p95 = g["delay_median"].to_numpy(), g["delay_p95"].to_numpy()
            ax.errorbar(xi, med, yerr=[np.zeros_like(med), np.maximum(p95 - med, 0)], marker=MARKERS[gi % len(MARKERS)], ls="none", capsize=3, label=f"{sub}/{det} · {fid}")
        ax.set_xticks(x, labels, rotation=20, ha="right")
        ax.set_ylim(bottom=0)
        ax.set_xlabel(xlabel)
        ax.set_ylabel("detection delay [s] (median, bar to p95)")
        ax.set_title(f"{campaign.scenario.name}: detection delay, median and 95th percentile ({_runs_label(campaign)})")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        p = out / "delay.png"
        fig.savefig(p, dpi=110)
        plt.close(fig)
        paths.append(p)

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12, 4.8), constrained_layout=True)
    groups = list(faults.groupby(["subfilter", "detector", "fault_id"], sort=False))
    off = _offsets(len(groups))
    for gi, ((sub, det, fid), g) in enumerate(groups):
        xi = point_index(g) + off[gi]
        pd_ = g["detection_probability"].to_numpy()
        err = np.clip([pd_ - g["detection_ci_low"].to_numpy(), g["detection_ci_high"].to_numpy() - pd_], 0, None)
        a1.errorbar(xi, pd_, yerr=err, marker=MARKERS[gi % len(MARKERS)], ls="none", capsize=3, label=f"{sub}/{det} · {fid}")
    a1.set_ylim(-0.05, 1.12)
    a1.axhline(1.0, color="k", lw=0.6, alpha=0.4)
    a1.set_ylabel("detection probability (95 % Wilson)")
    a1.set_title("detection probability per fault")
    none = s[s["fault_id"] == "none"]
    groups = list(none.groupby(["subfilter", "detector"], sort=False))
    off = _offsets(len(groups))
    colours: dict[float, str] = {}
    for gi, ((sub, det), g) in enumerate(groups):
        xi = point_index(g) + off[gi]
        fa = g["false_alarm_rate"].to_numpy()
        err = np.clip([fa - g["false_alarm_ci_low"].to_numpy(), g["false_alarm_ci_high"].to_numpy() - fa], 0, None)
        line = a2.errorbar(xi, fa, yerr=err, marker=MARKERS[gi % len(MARKERS)], ls="none", capsize=3, label=f"{sub}/{det} (pf {g['pf'].iloc[0]:g})")
        colours.setdefault(float(g["pf"].iloc[0]), line[0].get_color())
    for pf, colour in colours.items():
        a2.axhline(pf, ls="--", lw=1.0, color=colour, alpha=0.8, label=f"nominal pf = {pf:g}")
    # Rates are ≥ 0: a linear scale below 1e-4 and logarithmic above, never negative.
    a2.set_yscale("symlog", linthresh=1e-4)
    top = max([float(np.nanmax(none["false_alarm_ci_high"])) if len(none) else 0.0, *colours]) if (len(none) or colours) else 1e-3
    a2.set_ylim(0, top * 3 if top > 0 else 1e-3)
    a2.set_ylabel("false alarms per epoch outside faults")
    a2.set_title("false-alarm rate (dashed: nominal pf)")
    fig.suptitle(f"{campaign.scenario.name}: detection and false alarms ({_runs_label(campaign)})")
    if faults.empty:
        a1.text(0.5, 0.5, "no faults in this scenario", ha="center", va="center", transform=a1.transAxes)
    for a in (a1, a2):
        a.set_xticks(x, labels, rotation=20, ha="right")
        a.set_xlabel(xlabel)
        a.grid(alpha=0.3)
        if a.get_legend_handles_labels()[0]:
            a.legend(fontsize=7)
    p = out / "rates.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    paths.append(p)
    return paths


def _runs_label(campaign) -> str:
    per_point = campaign.runs_per_point()
    if len(set(per_point)) == 1:
        text = f"{per_point[0]} runs per point"
    else:
        text = f"runs per point {', '.join(map(str, per_point))}"
    return text + (", PARTIAL" if campaign.partial else "")


def plot_identified_satellites(runs: Any, out: Path) -> list[Path]:
    """``identified_satellites.png``: per variant of a tight-architecture run, the satellites
    excluded at each epoch (like paper 001's Fig. 3–8), fault windows shaded and the faulty
    satellite's row marked. Nothing is written without satellite records."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    items = [(name, r) for name, r in runs.runs.items() if "satellites" in r.record]
    if not items:
        return []
    first = items[0][1]
    names = first.record["satellites"]["names"]
    seen = np.flatnonzero(np.any([r.record["satellites"]["in_view"].any(axis=0) for _, r in items], axis=0))
    row = {j: i for i, j in enumerate(seen)}
    faults = [f for f in first.scenario.faults() if f.get("satellite")]
    fig, axes = plt.subplots(len(items), 1, figsize=(9, 1.2 + 2.4 * len(items)), sharex=True, constrained_layout=True, squeeze=False)
    for ax, (name, r) in zip(axes[:, 0], items):
        sat = r.record["satellites"]
        k, j = np.nonzero(sat["excluded"])
        for f in faults:
            ax.axvspan(f["start"], f["end"], color="tab:red", alpha=0.1, lw=0)
            if f["satellite"] in names and names.index(f["satellite"]) in row:
                ax.axhline(row[names.index(f["satellite"])], color="tab:red", lw=0.5, ls=":")
        ax.scatter(r.t[k], [row[x] for x in j], s=5, color="k")
        ax.set_yticks(range(len(seen)), [names[x] for x in seen], fontsize=7)
        ax.set_ylim(-0.5, len(seen) - 0.5)
        ax.set_ylabel("excluded")
        ax.set_title(f"{first.scenario.name}, variant {name} (seed {r.seed}): satellites excluded per epoch; faults shaded", fontsize=9)
    axes[-1, 0].set_xlabel("time [s]")
    p = out / "identified_satellites.png"
    fig.savefig(p, dpi=110)
    plt.close(fig)
    return [p]
