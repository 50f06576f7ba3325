"""navfdi: fault detection and isolation for multi-sensor integrated navigation.

The numerical core (Kalman filters, detection statistics) is Rust (``navfdi._core``); this
package wires it together. Public names:

Filtering
    :class:`KalmanFilter` (per-epoch step API), :func:`run_filter` (a whole sequence in Rust),
    :class:`Innovation`, :class:`FilterRun`.
Detectors
    :class:`ResidualChi2`, :class:`ImprovedSprt`, :class:`JointChi2Sprt` with per-epoch
    :class:`Decision` and whole-sequence :class:`DetectionRun`; the windowed :class:`Aime` and :class:`TwoStageAime`; :func:`alarm_intervals`;
    the dual-propagator state chi-square test :class:`StateChi2` (:class:`StateDecision`).
Statistics
    :func:`chi2_threshold`, :func:`sprt_threshold`, :func:`noncentrality`, :func:`ncx2_cdf`,
    :func:`mdb`.
Fusion
    :class:`WeightedFusion` (inverse-variance fusion of one quantity with a fault matrix,
    returning :class:`FusedValue`).
Federated filtering and scenarios
    :class:`FederatedFilter` (per-epoch step API), :func:`load_scenario`, :class:`Scenario`,
    :func:`bundled_scenarios`, :func:`run_scenario` (a whole simulated run in Rust, federated
    or centralized architecture) returning a :class:`ScenarioRun`, or a :class:`VariantRuns`
    for a scenario with variants; :class:`ScenarioError` names the offending field.
GNSS
    the linear :func:`ls_test` and :func:`snapshot_fde` (snapshot least squares with global test + w-test satellite
    exclusion) returning a :class:`SnapshotFde`; ``architecture = "tight"`` scenarios.
    Real data: :func:`read_rinex` (RINEX 3 observation/navigation files as tables),
    :func:`gnss_solve` (single-point positioning with FDE, injected faults) returning a
    :class:`GnssSolution`; :class:`GnssFault`; :class:`FileFormatError` for bad files.
    Ultra-tight building blocks (paper 004): the channel :class:`Prefilter` (returning
    :class:`PrefilterStep`) and the discriminator noise :func:`dll_variance`,
    :func:`fll_variance`.
Monte-Carlo
    :func:`montecarlo` (runs × sweep points in parallel in Rust, or on Dask) returning a
    :class:`Campaign` with per-run metrics, summaries, plots.
Errors
    ``ValueError`` for bad input; :class:`LinAlgError` (a ``ValueError``) for numerical
    failures such as a covariance that is not positive definite.
"""

import os as _os
import sys as _sys


def _command_line() -> bool:
    """Whether this process is navfdi's command line (the ``navfdi`` script, or ``python -m
    navfdi`` while the package is found: ``sys.argv[0]`` is ``-m`` then)."""
    argv = getattr(_sys, "argv", None) or [""]
    return argv[0] == "-m" or _os.path.basename(argv[0]) in ("navfdi", "navfdi.exe")


# The command line's own process does its work in Rust and gives numpy's BLAS nothing large,
# but OpenBLAS starts a thread per core when numpy loads and each spins for about 0.1 s of CPU
# before it sleeps (`import numpy` alone: 0.18 s CPU, 0.08 s with one thread, on 2 cores):
# one BLAS thread there, before numpy loads. A user's setting wins, and the library imported
# by a user's own program leaves BLAS alone.
if "numpy" not in _sys.modules and _command_line():
    _os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from navfdi._core import (
    Aime,
    Decision,
    DetectionRun,
    FederatedFilter,
    FederatedStep,
    FileFormatError,
    FusedValue,
    ImprovedSprt,
    Innovation,
    JointChi2Sprt,
    KalmanFilter,
    LinAlgError,
    Prefilter,
    PrefilterStep,
    ResidualChi2,
    SnapshotFde,
    StateChi2,
    StateDecision,
    TwoStageAime,
    WeightedFusion,
    __version__,
    chi2_threshold,
    dll_variance,
    fll_variance,
    ls_test,
    mdb,
    ncx2_cdf,
    noncentrality,
    snapshot_fde,
    sprt_threshold,
)
from navfdi._filter import FilterRun, run_filter
from navfdi._intervals import AlarmInterval, alarm_intervals
from navfdi.runs import FaultMatch, ScenarioRun, VariantRuns, run_scenario
from navfdi.montecarlo import Campaign, montecarlo
from navfdi.scenario import ImuClippingWarning, ImuGapWarning, LeftOutFixesWarning, LeftOutSamplesWarning, NeverAppliedWarning, PartialLogWarning, Scenario, ScenarioError, bundled_scenarios, load_scenario
from navfdi.frames import FrameWarning
from navfdi import gnss_logs as _gnss_logs  # noqa: F401  (registers the GNSS log readers)
from navfdi.gnss import GnssFault, GnssSolution, gnss_solve, read_rinex
from navfdi.integrity import Allocation, AraimResult, Ism, araim, lpv200

__all__ = [
    "Aime",
    "AlarmInterval",
    "Campaign",
    "Decision",
    "DetectionRun",
    "FaultMatch",
    "FileFormatError",
    "FederatedFilter",
    "FederatedStep",
    "FusedValue",
    "FilterRun",
    "Allocation",
    "AraimResult",
    "GnssFault",
    "Ism",
    "araim",
    "lpv200",
    "NeverAppliedWarning",
    "ImuGapWarning",
    "ImuClippingWarning",
    "LeftOutFixesWarning",
    "LeftOutSamplesWarning",
    "PartialLogWarning",
    "FrameWarning",
    "GnssSolution",
    "ImprovedSprt",
    "Innovation",
    "JointChi2Sprt",
    "KalmanFilter",
    "LinAlgError",
    "Prefilter",
    "PrefilterStep",
    "ResidualChi2",
    "Scenario",
    "ScenarioError",
    "ScenarioRun",
    "SnapshotFde",
    "StateChi2",
    "StateDecision",
    "TwoStageAime",
    "VariantRuns",
    "WeightedFusion",
    "__version__",
    "alarm_intervals",
    "bundled_scenarios",
    "chi2_threshold",
    "dll_variance",
    "fll_variance",
    "gnss_solve",
    "load_scenario",
    "ls_test",
    "mdb",
    "montecarlo",
    "ncx2_cdf",
    "noncentrality",
    "read_rinex",
    "run_filter",
    "run_scenario",
    "snapshot_fde",
    "sprt_threshold",
]
