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
from navfdi.scenario import LeftOutFixesWarning, NeverAppliedWarning, PartialLogWarning, Scenario, ScenarioError, bundled_scenarios, load_scenario
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
    "LeftOutFixesWarning",
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
