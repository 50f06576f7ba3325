"""The quick-start demo: three detectors on one simulated residual sequence.

A 3-axis measurement of a nearly constant quantity (think of a celestial attitude fix aiding a
well-initialised INS), noise σ = 1 in normalised units, 1 Hz. The filter is a 3-state random
constant with a tight prior (σ = 0.01), so it absorbs only a small part of a measurement fault:
with a loose prior the estimate follows the fault, and after the fault ends the residual is
offset by what was absorbed, which the chi-square test then reports as further alarms. (In the
federated filter, isolating the faulty sub-filter serves that purpose.) Two
faults are injected on all three axes:

* a soft fault: ramp of 0.03 σ/s over 20–220 s;
* a hard fault: step of 20 σ over 400–450 s.

The filter runs in Rust in one call (:func:`navfdi.run_filter`); each detector then runs over
the whole residual sequence in Rust (``test_sequence``). The report lists when each detector
raised and cleared its alarm. Expected behaviour (METHODS §2–§4): the SPRT finds the slow ramp
before the chi-square test but, without a reset, stays in alarm long after it ends and so never
sees the step as a new fault; the joint detector resets its SPRT when the chi-square test
declares the end of the ramp and reports both faults.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from navfdi import _core
from navfdi._filter import FilterRun, run_filter
from navfdi._intervals import match_events


@dataclass(frozen=True)
class DemoFault:
    """A fault on all three axes of the demo measurement.

    Attributes
    ----------
    name : str
        Label, e.g. ``"ramp"``.
    start, end : float
        Window [start, end) in s.
    kind : str
        ``"ramp"`` (size ``slope * (t - start)``) or ``"step"`` (size ``size``).
    size : float
        Ramp slope in σ/s, or step size in σ.
    """

    name: str
    start: float
    end: float
    kind: str
    size: float

    def value(self, t: np.ndarray) -> np.ndarray:
        """Fault value at times ``t`` (s), shape like ``t``, in σ."""
        inside = (t >= self.start) & (t < self.end)
        if self.kind == "ramp":
            return np.where(inside, self.size * (t - self.start), 0.0)
        return np.where(inside, self.size, 0.0)


FAULTS = (
    DemoFault("ramp 0.03 σ/s", 20.0, 220.0, "ramp", 0.03),
    DemoFault("step 20 σ", 400.0, 450.0, "step", 20.0),
)


def simulate(seed: int = 0, duration: float = 600.0) -> tuple[np.ndarray, np.ndarray, FilterRun]:
    """Simulate the demo measurements and filter them.

    Parameters
    ----------
    seed : int
        Seed of ``numpy.random.default_rng``.
    duration : float
        Length in s (1 Hz).

    Returns
    -------
    t : ndarray, shape (T,)
        Epoch times in s.
    zs : ndarray, shape (T, 3)
        Measurements in σ units (truth is zero).
    run : FilterRun
        Output of :func:`navfdi.run_filter`.
    """
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, duration, 1.0)
    fault = sum(f.value(t) for f in FAULTS)
    zs = rng.standard_normal((t.size, 3)) + np.asarray(fault)[:, None]
    run = run_filter(
        x0=np.zeros(3),
        P0=np.eye(3) * 0.01**2,
        Phi=np.eye(3),
        Q=np.zeros((3, 3)),
        zs=zs,
        H=np.eye(3),
        R=np.eye(3),
    )
    return t, zs, run


def report(seed: int = 0, pf: float = 1e-3, pm: float = 1e-3) -> str:
    """Run the demo and return its printed report.

    Parameters
    ----------
    seed : int
        Random seed.
    pf, pm : float
        False-alarm and missed-detection probabilities of the detectors.
    """
    t, _, run = simulate(seed)
    detectors: dict[str, _core.ResidualChi2 | _core.ImprovedSprt | _core.JointChi2Sprt] = {
        "chi2": _core.ResidualChi2(pf),
        "sprt": _core.ImprovedSprt(pf, pm),
        "joint": _core.JointChi2Sprt(pf, pm),
    }
    lines = [
        f"navfdi {_core.__version__} demo: 3-axis measurement, noise σ = 1, 1 Hz, {t.size} s, seed {seed}",
        "faults (all axes): " + "; ".join(f"{f.name} over {f.start:g}–{f.end:g} s" for f in FAULTS),
        f"detectors: pf = {pf:g}, pm = {pm:g}; chi-square threshold "
        f"{_core.chi2_threshold(pf, 3):.3f} (3 dof), SPRT threshold {_core.sprt_threshold(pf, pm):.3f}",
        "raised: first alarm matched to the fault; cleared: end of the last alarm matched to it",
        "(an alarm matches a fault when it overlaps the window and began after the previous fault ended,",
        " the rule of `navfdi run` and `navfdi montecarlo`)",
        "",
        f"{'detector':<8} {'fault':<15} {'window [s]':>10} {'raised [s]':>10} {'delay [s]':>9} "
        f"{'cleared [s]':>11} {'alarms':>6}",
    ]
    for name, det in detectors.items():
        seq = det.test_sequence(run.residual, run.covariance)
        matched = match_events(seq.alarm, t, [(f.start, f.end) for f in FAULTS])
        for fi, f in enumerate(FAULTS):
            mine = [iv for iv, m in matched if m == fi]
            window = f"{f.start:g}-{f.end:g}"
            if not mine:
                lines.append(f"{name:<8} {f.name:<15} {window:>10} {'missed':>10}")
                continue
            last = mine[-1].end
            cleared = "never" if last is None else f"{last:g}"
            lines.append(
                f"{name:<8} {f.name:<15} {window:>10} {mine[0].start:>10g} {mine[0].start - f.start:>9g} "
                f"{cleared:>11} {len(mine):>6d}"
            )
        false_alarms = sum(1 for _, m in matched if m is None)
        lines.append(f"{name:<8} {'no fault':<15} {'':>10} {false_alarms:>10d} false alarm interval(s)")
    return "\n".join(lines)
