"""Rust core of navfdi (PyO3 bindings). Re-exported from :mod:`navfdi`.

Array arguments accept real numbers in any memory layout (C or Fortran order, transposed
views, negative strides, slices; any integer, bool or float dtype; nested lists) and are read
in their logical order; complex, string and object data are refused. The fast path is a
C-contiguous float64 array. Returned arrays are new numpy arrays (copies of the Rust state).

The stateful classes (:class:`KalmanFilter`, the detectors, :class:`FederatedFilter`) can be
pickled and deep-copied (Dask, multiprocessing); the copy continues exactly where the original
was. They are not thread-safe: using one object from two threads at the same time raises
``RuntimeError: Already borrowed``; give each thread its own copy (``copy.deepcopy``).
"""

from typing import Any, Callable, final

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "__version__",
    "DETECTION_GRACE",
    "CN0_SLOPE_MAX",
    "IMU_GAP_FACTOR",
    "IMU_MAX_RATE",
    "IMU_MAX_SPECIFIC_FORCE",
    "IMU_MAX_MEDIAN_RATE",
    "IMU_MEDIAN_SPECIFIC_FORCE",
    "imu_clipped",
    "Prefilter",
    "PrefilterStep",
    "dll_variance",
    "fll_variance",
    "memory_available",
    "check_campaign_memory",
    "match_alarms",
    "run_variants",
    "_restore",
    "LinAlgError",
    "FileFormatError",
    "read_rinex_obs",
    "read_imu_csv",
    "read_ubx",
    "pos_rows",
    "simulate_logs",
    "read_rinex_nav",
    "GnssRun",
    "LoggedSource",
    "KalmanFilter",
    "Innovation",
    "run_filter",
    "Decision",
    "DetectionRun",
    "ResidualChi2",
    "Aime",
    "TwoStageAime",
    "ImprovedSprt",
    "JointChi2Sprt",
    "chi2_threshold",
    "sprt_threshold",
    "noncentrality",
    "ncx2_cdf",
    "mdb",
    "validate_scenario",
    "araim_epoch",
    "araim_los",
    "araim_variances",
    "snapshot_pl",
    "window_alarm",
    "scenario_trajectory",
    "run_scenario",
    "FederatedFilter",
    "FederatedStep",
    "PreparedScenario",
    "SnapshotFde",
    "WeightedFusion",
    "FusedValue",
    "StateChi2",
    "StateDecision",
    "snapshot_fde",
    "ls_test",
]

__version__: str

class LinAlgError(ValueError):
    """Numerical linear-algebra failure (a matrix that must be positive definite is not, or a
    result is not finite). A subclass of ``ValueError``."""

class FileFormatError(ValueError):
    """A data file (RINEX) is malformed, truncated or of the wrong kind; the message names the
    file, the line when known, and what was expected. A subclass of ``ValueError``."""

@final
class Innovation:
    """Result of one measurement update (m measurement components)."""

    @property
    def residual(self) -> NDArray[np.float64]:
        """Innovation ``r = z - H x⁻``, shape (m,), measurement units; NaN where unused."""
    @property
    def covariance(self) -> NDArray[np.float64]:
        """Innovation covariance ``A = H P⁻ Hᵀ + R``, shape (m, m); NaN rows/columns unused."""
    @property
    def statistic(self) -> float:
        """``λ = rᵀ A⁻¹ r`` over the used components (dimensionless); NaN when none used."""
    @property
    def used(self) -> NDArray[np.bool_]:
        """Components of ``z`` used in the update, shape (m,)."""
    @property
    def dof(self) -> int:
        """Number of components used (degrees of freedom of ``statistic``)."""

@final
class KalmanFilter:
    """Linear Kalman filter with state ``x`` (n,) and covariance ``P`` (n, n).

    Per-epoch step API: call :meth:`predict` then :meth:`update`, or fix a model once with
    :meth:`set_model` and call :meth:`step` with each measurement. Every call validates its
    inputs before changing anything; a rejected call leaves the filter exactly as it was.

    Parameters
    ----------
    x0 : array_like, shape (n,)
        Initial state (finite).
    P0 : array_like, shape (n, n)
        Initial covariance, symmetric positive semi-definite.

    Raises
    ------
    ValueError
        Wrong shapes, NaN/inf, ``P0`` not symmetric PSD.
    """

    def __new__(cls, x0: ArrayLike, P0: ArrayLike) -> KalmanFilter: ...
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support: ``(_restore, (class name, JSON state))``."""
    def predict(self, Phi: ArrayLike, Q: ArrayLike, fading: float = 1.0) -> None:
        """Time update ``x⁻ = Φ x``, ``P⁻ = S Φ P Φᵀ + Q``.

        Parameters
        ----------
        Phi : array_like, shape (n, n)
            State transition matrix over the step.
        Q : array_like, shape (n, n)
            Process-noise covariance mapped to the state (ΓQΓᵀ), symmetric PSD.
        fading : float, default 1.0
            Fading-memory factor ``S >= 1``.

        Raises
        ------
        ValueError
            Wrong shapes, NaN/inf, ``Q`` not symmetric PSD, ``fading < 1``.
        """
    def update(self, z: ArrayLike, H: ArrayLike, R: ArrayLike) -> Innovation:
        """Measurement update (Cholesky gain, Joseph-form covariance).

        Parameters
        ----------
        z : array_like, shape (m,)
            Measurement; NaN marks a missing component, which is skipped (reduced update).
        H : array_like, shape (m, n)
            Measurement matrix (finite).
        R : array_like, shape (m, m)
            Measurement-noise covariance, symmetric PSD.

        Returns
        -------
        Innovation
            Residual, its covariance, ``λ`` and the used-component mask.

        Raises
        ------
        ValueError
            Wrong shapes, inf in ``z``, NaN/inf in ``H`` or ``R``, ``R`` not symmetric PSD.
        LinAlgError
            ``A = H P⁻ Hᵀ + R`` of the used components is not positive definite.
        """
    def set_model(self, Phi: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike) -> None:
        """Fix the model :meth:`step` runs (kept when pickled).

        Parameters
        ----------
        Phi, Q : array_like, shape (n, n)
            State transition and process-noise covariance (symmetric PSD), as for :meth:`predict`.
        H : array_like, shape (m, n)
            Measurement matrix (finite).
        R : array_like, shape (m, m)
            Measurement-noise covariance, symmetric PSD.

        Raises
        ------
        ValueError
            Wrong shapes, NaN/inf, ``Q`` or ``R`` not symmetric PSD; the filter and any model
            it had are unchanged.
        """
    def step(self, z: ArrayLike) -> Innovation:
        """One epoch of the model set by :meth:`set_model`: :meth:`predict` then :meth:`update`
        with the same arithmetic (the same bits), converting and checking only ``z``.

        Parameters
        ----------
        z : array_like, shape (m,)
            Measurement; NaN marks a missing component (skipped; all NaN: predict only).

        Returns
        -------
        Innovation
            As :meth:`update` returns it.

        Raises
        ------
        ValueError
            No model set, ``z`` of the wrong length or with an inf.
        LinAlgError
            ``A = H P⁻ Hᵀ + R`` of the used components is not positive definite (the filter is
            then unchanged, the prediction included).
        """
    def set_state(self, x: ArrayLike, P: ArrayLike) -> None:
        """Replace the state (n,) and covariance (n, n), validated like the constructor."""
    @property
    def x(self) -> NDArray[np.float64]:
        """State estimate, shape (n,) (a copy)."""
    @property
    def P(self) -> NDArray[np.float64]:
        """State covariance, shape (n, n) (a copy)."""
    @property
    def dim(self) -> int:
        """State dimension n."""

def run_filter(
    x0: ArrayLike,
    P0: ArrayLike,
    Phi: ArrayLike,
    Q: ArrayLike,
    zs: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    fading: float = 1.0,
) -> tuple[
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.float64],
    NDArray[np.bool_],
]:
    """Whole-sequence filter; returns ``(x (T,n), P (T,n,n), residual (T,m),
    covariance (T,m,m), statistic (T,), used (T,m))``. Use :func:`navfdi.run_filter`, which
    wraps the tuple in a :class:`navfdi.FilterRun`."""

@final
class Decision:
    """One epoch's decision of a detector."""

    @property
    def statistic(self) -> float:
        """Test statistic (chi-square: ``rᵀA⁻¹r``; SPRT: largest per-component ``λ_j``);
        NaN when no residual component was available."""
    @property
    def threshold(self) -> float:
        """Threshold compared with ``statistic``."""
    @property
    def alarm(self) -> bool:
        """Fault declared this epoch."""
    @property
    def dof(self) -> int:
        """Number of residual components used."""
    @property
    def ratio(self) -> float:
        """``statistic / threshold`` (test ratio); ``>= 1`` means alarm."""
    @property
    def components(self) -> NDArray[np.float64] | None:
        """SPRT per-component statistics ``λ_j``, shape (m,); None for the chi-square test."""
    @property
    def chi2(self) -> Decision | None:
        """Joint detector only: the chi-square test's decision this epoch."""
    @property
    def reset(self) -> bool:
        """Joint detector only: True when the chi-square end-of-fault reset the SPRT."""

@final
class DetectionRun:
    """Per-epoch decisions of :meth:`ResidualChi2.test_sequence` and friends (T epochs)."""

    @property
    def statistic(self) -> NDArray[np.float64]:
        """Statistic per epoch, shape (T,)."""
    @property
    def threshold(self) -> NDArray[np.float64]:
        """Threshold per epoch, shape (T,)."""
    @property
    def alarm(self) -> NDArray[np.bool_]:
        """Alarm per epoch, shape (T,)."""
    @property
    def dof(self) -> NDArray[np.int64]:
        """Residual components used per epoch, shape (T,)."""
    @property
    def components(self) -> NDArray[np.float64] | None:
        """SPRT per-component statistics, shape (T, m); None for the chi-square test."""
    @property
    def chi2_statistic(self) -> NDArray[np.float64] | None:
        """Joint detector: chi-square statistic, shape (T,); None otherwise."""
    @property
    def chi2_threshold(self) -> NDArray[np.float64] | None:
        """Joint detector: chi-square threshold, shape (T,); None otherwise."""
    @property
    def chi2_alarm(self) -> NDArray[np.bool_] | None:
        """Joint detector: chi-square alarm, shape (T,); None otherwise."""
    @property
    def reset(self) -> NDArray[np.bool_] | None:
        """Joint detector: epochs at which the SPRT was reset, shape (T,); None otherwise."""
    def __len__(self) -> int: ...

@final
class ResidualChi2:
    """Residual chi-square test: alarm when ``rᵀA⁻¹r >= F⁻¹_{χ²(m)}(1 - pf)``.

    NaN residual components are skipped and the threshold follows the number used.

    Parameters
    ----------
    pf : float
        False-alarm probability per epoch, in (0, 1).
    """

    def __new__(cls, pf: float) -> ResidualChi2: ...
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support: ``(_restore, (class name, JSON state))``."""
    def test(self, residual: ArrayLike, covariance: ArrayLike) -> Decision:
        """Test one epoch: ``residual`` shape (m,), ``covariance`` shape (m, m), positive
        definite on the available components. Raises ``ValueError`` for bad shapes or values
        and :class:`LinAlgError` when the covariance cannot be factored; the detector is then
        unchanged."""
    def test_sequence(self, residuals: ArrayLike, covariances: ArrayLike) -> DetectionRun:
        """Test every epoch of ``residuals`` (T, m) with ``covariances`` (T, m, m) in Rust, with
        the GIL released; the detector continues from its current state and keeps the final
        one. On an error (naming the epoch) the detector is unchanged."""
    def reset(self) -> None:
        """Forget the last alarm state."""
    def threshold(self, dof: int | None = None) -> float:
        """Threshold ``T_D`` for ``dof >= 1`` components (required: it depends on ``dof``).
        Every detector has ``threshold(dof)``, so detectors can be queried alike."""
    @property
    def pf(self) -> float:
        """False-alarm probability per epoch."""
    @property
    def alarm(self) -> bool:
        """Last alarm state."""

@final
class Aime:
    """AIME (paper 004, METHODS §11): over the last ``window`` epochs,
    ``r̄ = (Σ A_j⁻¹)⁻¹ Σ A_j⁻¹ r_j``, ``Ā = (Σ A_j⁻¹)⁻¹``, statistic ``r̄ᵀĀ⁻¹r̄ ~ χ²(m)``; alarm
    when it reaches ``F⁻¹_{χ²(m)}(1 - pf)``. Sliding sums in O(m²) per epoch, recomputed exactly
    every ``window`` epochs (no drift). NaN components add no information; an epoch without
    any component leaves the window unchanged.

    Parameters
    ----------
    pf : float
        False-alarm probability per epoch, in (0, 1).
    window : int
        Window length N in epochs (1 … 1 000 000).
    """

    def __new__(cls, pf: float, window: int) -> Aime: ...
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support: ``(_restore, (class name, JSON state))``."""
    def test(self, residual: ArrayLike, covariance: ArrayLike) -> Decision:
        """Test one epoch: ``residual`` shape (m,) (m; NaN = unavailable), ``covariance`` shape
        (m, m) (m²), positive definite on the available components. The dimension m must stay
        the same until :meth:`reset`. Bad input raises ``ValueError`` / :class:`LinAlgError`
        and leaves the detector unchanged."""
    def test_sequence(self, residuals: ArrayLike, covariances: ArrayLike) -> DetectionRun:
        """Test every epoch of ``residuals`` (T, m) with ``covariances`` (T, m, m) in Rust, with
        the GIL released; on an error (naming the epoch) the detector is unchanged."""
    def reset(self) -> None:
        """Empty the window (the dimension may then change)."""
    def threshold(self, dof: int | None = None) -> float:
        """Threshold ``F⁻¹_{χ²(dof)}(1 - pf)`` for ``dof >= 1`` components."""
    @property
    def pf(self) -> float:
        """False-alarm probability per epoch."""
    @property
    def window(self) -> int:
        """Window length N (epochs)."""
    @property
    def filled(self) -> int:
        """Epochs currently in the window (≤ N)."""
    @property
    def alarm(self) -> bool:
        """Last alarm state."""

@final
class TwoStageAime:
    """Two-stage AIME (paper 004, METHODS §11): stage 1 = :class:`Aime` (``window1``) on the
    innovations; its statistic s_k feeds a scalar random-walk Kalman filter (process variance
    ``q``, the paper's 10; measurement noise ``R_k = b R_{k−1} + (1 − b)·½(s_k − s_{k−1})²``,
    ``R_0 = 1``); stage 2 = :class:`Aime` (``window2``) on that filter's innovations with
    variance ``P + q + R``; only stage 2 is compared with its χ²(1) threshold. The first epoch
    initialises the filter (NaN statistic). Under no fault the stage-2 statistic is not exactly
    χ²(1): measure its false-alarm rate.

    Parameters
    ----------
    pf : float
        False-alarm probability of the stage-2 test, in (0, 1).
    window1, window2 : int
        Windows of stage 1 and stage 2 in epochs.
    q : float
        Random-walk variance of the statistic filter (> 0).
    b : float
        Fading factor of the Allan-variance estimate, in (0, 1) (paper: 0.9–0.999).
    every : int
        The statistic filter and stage 2 take every ``every``-th stage-1 statistic (1: each;
        the stage-1 window makes the samples non-overlapping); stage 2's window counts those.
        Between them :meth:`test` repeats the last decision.
    r0 : float
        Starting R of the Allan-variance estimate (> 0; METHODS §11: 1).
    """

    def __new__(cls, pf: float, window1: int, window2: int, q: float = 10.0, b: float = 0.99, every: int = 1, r0: float = 1.0) -> TwoStageAime: ...
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support: ``(_restore, (class name, JSON state))``."""
    def test(self, residual: ArrayLike, covariance: ArrayLike) -> Decision:
        """Test one epoch (``residual`` (m,), ``covariance`` (m, m)); the decision is stage 2's.
        Bad input raises and leaves the detector unchanged."""
    def test_sequence(self, residuals: ArrayLike, covariances: ArrayLike) -> DetectionRun:
        """Test every epoch of ``residuals`` (T, m) with ``covariances`` (T, m, m) in Rust."""
    def reset(self) -> None:
        """Start over (both windows and the statistic filter)."""
    def threshold(self, dof: int | None = None) -> float:
        """Stage-2 threshold ``F⁻¹_{χ²(1)}(1 - pf)`` (``dof``, if given, must be 1)."""
    @property
    def pf(self) -> float:
        """False-alarm probability of the stage-2 test."""
    @property
    def windows(self) -> tuple[int, int]:
        """(stage-1, stage-2) windows in epochs."""
    @property
    def stage1_statistic(self) -> float:
        """The last stage-1 AIME statistic (NaN before the first epoch)."""
    @property
    def measurement_noise(self) -> float:
        """The adapted R of the statistic filter."""
    @property
    def alarm(self) -> bool:
        """Last alarm state."""

@final
class ImprovedSprt:
    """Improved SPRT per residual component: ``λ_j(k) = k x̄_k² / (2σ²)``, alarm when any
    ``λ_j >= ln((1 - pm)/pf)``.

    Parameters
    ----------
    pf, pm : float
        False-alarm and missed-detection probabilities in (0, 1), ``pf + pm < 1``.
    variance : {"known", "sample"}, default "known"
        ``"known"``: normalise component j by ``sqrt(A_jj)`` (σ = 1). ``"sample"``: running
        sample variance of the raw component (Welford).
    min_samples : int, optional
        Samples a component needs since the last reset before it may alarm (≥ 1). Default 1
        with the known variance, 20 with the sample variance: right after a reset the
        sample-variance statistic is ``(k/(k-1)) t²/2`` with Student's ``t`` on ``k - 1``
        degrees of freedom, huge by chance for small k (without the minimum most fault-free
        runs alarmed at their second epoch).

    Not thread-safe: one detector used from two threads at once raises ``RuntimeError``
    ("Already borrowed"); give each thread its own detector (``copy.deepcopy``).
    """

    def __new__(cls, pf: float, pm: float, variance: str = "known", min_samples: int | None = None) -> ImprovedSprt: ...
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support: ``(_restore, (class name, JSON state))``."""
    def test(self, residual: ArrayLike, covariance: ArrayLike) -> Decision:
        """Test one epoch (``residual`` (m,), ``covariance`` (m, m)); the dimension m is fixed
        by the first call. NaN components are skipped."""
    def test_sequence(self, residuals: ArrayLike, covariances: ArrayLike) -> DetectionRun:
        """Test a whole sequence ((T, m) and (T, m, m)) in Rust; see
        :meth:`ResidualChi2.test_sequence`."""
    def reset(self) -> None:
        """Reset every accumulator to zero."""
    def reset_dimension(self) -> None:
        """Reset and forget the residual dimension, so the next test may use another length."""
    def threshold(self, dof: int | None = None) -> float:
        """``T(H1) = ln((1 - pm)/pf)``, the same for every ``dof`` (accepted for a uniform
        call across detectors)."""
    @property
    def min_samples(self) -> int:
        """Samples a component needs since the last reset before it may alarm."""
    @property
    def pf(self) -> float:
        """False-alarm probability parameter."""
    @property
    def pm(self) -> float:
        """Missed-detection probability parameter."""
    @property
    def variance(self) -> str:
        """``"known"`` or ``"sample"``."""
    @property
    def alarm(self) -> bool:
        """Last alarm state."""

@final
class JointChi2Sprt:
    """Joint chi-square / improved-SPRT detector of paper 000 (METHODS §4).

    The alarm is the SPRT's; when the chi-square test's alarm falls (end of fault), the SPRT is
    reset so a later fault is detected as a new one. Parameters as :class:`ImprovedSprt`; the
    chi-square part uses the same ``pf``.
    """

    def __new__(cls, pf: float, pm: float, variance: str = "known", min_samples: int | None = None) -> JointChi2Sprt: ...
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support: ``(_restore, (class name, JSON state))``."""
    def test(self, residual: ArrayLike, covariance: ArrayLike) -> Decision:
        """Test one epoch; the decision carries ``chi2`` and ``reset``."""
    def test_sequence(self, residuals: ArrayLike, covariances: ArrayLike) -> DetectionRun:
        """Test a whole sequence in Rust; the run carries ``chi2_*`` and ``reset`` arrays."""
    def reset(self) -> None:
        """Reset both tests."""
    def reset_dimension(self) -> None:
        """Reset both tests and forget the residual dimension."""
    def threshold(self, dof: int | None = None) -> float:
        """SPRT threshold ``T(H1)`` (the alarm is the SPRT's), the same for every ``dof``."""
    @property
    def min_samples(self) -> int:
        """The SPRT's minimum samples per component before it may alarm."""
    @property
    def pf(self) -> float:
        """False-alarm probability parameter."""
    @property
    def pm(self) -> float:
        """Missed-detection probability parameter."""
    @property
    def variance(self) -> str:
        """``"known"`` or ``"sample"``."""
    @property
    def alarm(self) -> bool:
        """Last alarm state (the SPRT's)."""

def chi2_threshold(pf: float, dof: int) -> float:
    """Chi-square threshold ``T_D = F⁻¹_{χ²(dof)}(1 - pf)``; ``pf`` in (0, 1), ``dof >= 1``.
    E.g. ``chi2_threshold(0.1, 3) = 6.2514``."""

def sprt_threshold(pf: float, pm: float) -> float:
    """SPRT threshold ``ln((1 - pm)/pf)``; requires ``pf + pm < 1``.
    E.g. ``sprt_threshold(0.1, 0.1) = 2.1972``."""

def noncentrality(pf: float, pm: float, dof: int) -> float:
    """Non-centrality ``λ0`` with ``F_{χ²(dof, λ0)}(T_D) = pm`` (METHODS §6); requires
    ``pf + pm < 1``. E.g. ``noncentrality(0.1, 0.05, 6) = 17.87``."""

def ncx2_cdf(x: float, dof: int, noncentrality: float) -> float:
    """CDF of the non-central chi-square distribution ``χ²(dof, noncentrality)`` at ``x``."""

def mdb(A: ArrayLike, pf: float, pm: float) -> NDArray[np.float64]:
    """Minimal detectable bias per component, shape (m,), in measurement units:
    ``sqrt(λ0 / (A⁻¹)_ii)`` with ``A`` (m, m) the residual covariance (symmetric positive
    definite) and ``λ0 = noncentrality(pf, pm, m)``."""

def _restore(kind: str, state: str) -> Any:
    """Rebuild a pickled object (called by pickle; not for direct use)."""

def check_campaign_memory(spec_json: str, runs: float, points: float, kept: float, row_bytes: float) -> None:
    """Raise ``MemoryError`` (saying how much is needed and what to change) when a campaign of
    ``runs`` runs × ``points`` sweep points, with ``row_bytes`` per row of the per-run table
    (one row per metric cell) and ``kept`` full series per point, would not fit in memory."""

def memory_available() -> float:
    """Bytes of memory available to this process: the smallest of MemAvailable
    (/proc/meminfo), the cgroup v2 limit less current use, and the environment variable
    ``NAVFDI_MEMORY_LIMIT`` (bytes); 8 GiB where none can be read. Whole runs refuse (with
    ``MemoryError``) to plan beyond 80 % of it."""

def run_variants(spec_jsons: list[str], seed: int, stream: int = 0) -> list[dict[str, Any]]:
    """Simulate one run of the first scenario (noise from ``(seed, stream)``) and filter the
    same measurements with every scenario of ``spec_jsons`` (variants; only ``architecture``,
    ``federated`` and ``centralized`` may differ), isolation active. One record per variant
    (as :func:`run_scenario`). Loop in Rust with the GIL released, the variants in parallel
    (the same records to the bit as one by one); Ctrl-C stops it."""

def simulate_logs(
    trajectory_json: str, duration: float, noise: dict[str, Any], seed: int, run: int
) -> dict[str, Any]:
    """Simulate a car's recorded-style logs, GIL released: ``trajectory_json`` the SI
    trajectory, ``duration`` (s), ``noise`` the ``LogNoise`` fields (SI; ``mounting`` three
    angles in rad, ``lever_arm`` the antenna from the IMU in m (forward-right-down), ``ground`` a bool; absent fields keep their defaults), ``seed``, ``run``
    the random stream. Returns ``imu`` (N, 7: time s, gyro rad/s, accel m/s², in the IMU's
    axes), ``gnss`` and ``reference`` (M, 13: time, latitude, longitude rad, height m,
    velocity east/north/up m/s, σ position, σ velocity m, m/s), ``attitude`` (M, 4:
    body-to-NED quaternion w, x, y, z), ``gnss_error`` (M, 3: east, north, up m), ``stale``
    and ``burst`` (M,) bool. ``ValueError`` names a bad noise field."""

def read_ubx(path: str) -> dict[str, Any]:
    """The UBX-NAV-PVT solutions of a u-blox binary log (plain or gzip), GIL released: a dict
    of columns, one row per message — ``t`` (N,) GPS seconds, ``llh`` (N, 4) latitude,
    longitude (deg), height above the ellipsoid and above mean sea level (m), ``acc`` (N, 3)
    horizontal, vertical (m) and speed (m/s) accuracy estimates, ``vel_ned`` (N, 3) m/s,
    ``status`` (N, 3) uint8 satellites, fix type, fix flags — and ``corrupt`` (packets
    skipped). ``FileFormatError`` for a file that is not a UBX log, has no NAV-PVT or no valid
    UTC date; ``OSError`` for an unreadable path."""

def read_imu_csv(
    path: str,
    time: list[str],
    gyro: list[str],
    accel: list[str],
    gyro_scale: float,
    accel_scale: float,
    increments: bool,
    max_gap: float,
    unit_fields: list[str],
    time_unit: float = 1.0,
    header: bool = True,
    delimiter: str = ",",
    spread_times: bool = False,
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], tuple[int, int, int, int, bool]]:
    """Read an IMU CSV log (plain or gzip) in one streaming pass, GIL released: ``time`` one
    column name (GPS seconds, or another count: ``time_unit`` seconds per unit, default 1) or
    ``[week, seconds_of_week]``; ``header`` false: no header line, the columns named ``"1"``,
    ``"2"``, … by position; ``delimiter`` one ASCII character or ``"whitespace"`` (runs of
    spaces and tabs); ``spread_times``: samples sharing a time stamp spread evenly from it to the
    next stamp (the last batch at the median interval) instead of refused; ``gyro``, ``accel`` three column
    names each; ``gyro_scale`` to rad/s and ``accel_scale`` to m/s² (rad and m/s for
    ``increments``, which are divided by the sample interval); ``max_gap`` the largest sample
    interval accepted (s); ``unit_fields`` the two unit fields' names for messages. Returns
    ``t`` (N,) GPS seconds, ``gyro`` (N, 3) rad/s, ``accel`` (N, 3) m/s² and ``(repeated,
    line, zeroed, line, iso)``: rows left out as exact repeats of the row before them (the same
    time and values), and as placeholders (a specific force of exactly zero on every axis),
    each with the first one's line (0: none); ``iso``: the time column held ISO 8601
    date-times (told from the first row; ``t`` is then calendar seconds since 1980-01-06 as
    written, no leap seconds applied). ``FileFormatError``
    names the file, line and column of bad input (missing column, field count, non-finite
    value, time not increasing, a gap, a sample beyond any IMU's range, implausible units,
    no samples, a gzip that inflates over 200 times its size); ``OSError`` a path that is not a
    readable regular file; ``MemoryError`` a file beyond the memory limit."""

def imu_clipped(gyro: ArrayLike, accel: ArrayLike) -> tuple[list[bool], list[tuple[str, int, float, int]]]:
    """The IMU samples at a channel's full scale (clipped), GIL released: ``gyro`` (N, 3) rad/s
    and ``accel`` (N, 3) m/s² in the IMU's axes. A channel is clipped where it holds its
    largest or smallest value, exactly, on three or more consecutive samples, within 5 % of a
    range such sensors are built with (±2, 4, … 50 g; ±125, 250, … 4000 deg/s). Returns
    ``(mask, channels)``: a flag per sample, and per clipped channel ``(sensor, axis, value,
    samples)`` — ``"accel"`` or ``"gyro"``, 0–2 for x, y, z, the full-scale reading (m/s² or
    rad/s) and the samples on it. ``ValueError`` for other shapes."""

def pos_rows(text: str, n_fields: int) -> tuple[NDArray[np.float64], NDArray[np.uint64]] | None:
    """The data rows of an RTKLIB ``.pos`` file's ``text`` in one pass, GIL released:
    ``(values, lines)`` — ``values`` (N, 1 + n_fields): the GPST time as GPS seconds since
    1980-01-06, then the first ``n_fields`` numbers of the row; ``lines`` (N,) their 1-based
    line numbers — or None where any line is not in the regular form (the time as
    zero-padded ``yyyy/mm/dd hh:mm:ss.sss`` or GPS week and seconds, then at least
    ``n_fields`` plain numbers; header lines ``%…`` and blank lines skipped):
    :func:`navfdi.logs.read_pos` then reads it line by line and words the error."""

def match_alarms(t: ArrayLike, alarm: list[bool], windows: list[tuple[float, float]], tested: list[bool] | None = None) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """The one event-matching rule (used by ``run``, ``montecarlo`` and ``demo``): alarm
    intervals of ``alarm`` (times ``t`` (T,), s) over the epochs ``tested`` (T,) (None: every
    epoch; alarm flags at untested epochs are ignored and do not end an interval) and the
    fault each detects. ``windows``: fault windows ``(start, end)`` (s) sorted by start. An
    interval detects a fault when its onset lies in ``[start, end + 1 s]`` (the
    latest-starting such fault); an alarm raised before a fault began detects nothing. Returns
    ``(start_index, end_index, tests, fault_index)``, each (K,): the first alarmed test, the
    first passing test after it (-1: never ended), the tests the interval spans, and the fault
    (-1: none)."""

#: Seconds after a fault's end within which an alarm onset still detects it
#: (``navfdi_core::metrics::GRACE``).
DETECTION_GRACE: float

#: The largest C/N0 weighting slope ``GnssRun`` accepts (``cn0_slope``; variance decades per
#: 10 dB-Hz; ``navfdi_core::gnss::spp::CN0_SLOPE_MAX``).
CN0_SLOPE_MAX: float
#: An interval between IMU samples is a gap (samples missing) where it exceeds this many times
#: the log's median interval (the upper median; ``navfdi_core::arch::inertial::GAP_FACTOR``).
IMU_GAP_FACTOR: float
#: The IMU log readers' limits (``navfdi_core::logs::imu_csv``): the largest angular rate
#: (rad/s) and specific force (m/s²) of a sample, the largest median rate (rad/s) and the
#: median specific force's range (m/s²) of a log.
IMU_MAX_RATE: float
IMU_MAX_SPECIFIC_FORCE: float
IMU_MAX_MEDIAN_RATE: float
IMU_MEDIAN_SPECIFIC_FORCE: tuple[float, float]

def window_alarm(t: ArrayLike, alarm: list[bool], start: float, end: float, tested: list[bool] | None = None) -> tuple[bool, float]:
    """For a fault window ``[start, end)`` (s) and an alarm sequence over times ``t`` (T,) and
    the epochs ``tested`` (T,) (None: every epoch): whether the alarm was already raised at
    the window's first test (raised at the test before: reported, not a detection), and the
    share of the window's tests in alarm (NaN when none)."""

def validate_scenario(spec_json: str) -> None:
    """Validate a scenario in its SI JSON form (see :mod:`navfdi.scenario`); raises
    ``ValueError`` naming the field path (``faults[1].sensor: ...``)."""

def scenario_trajectory(spec_json: str) -> dict[str, NDArray[np.float64]]:
    """Truth trajectory of a scenario, T epochs: ``t`` (s), ``lat``, ``lon`` (rad), ``h`` (m),
    ``v`` (T, 3) ENU m/s, ``euler`` (T, 3) roll/pitch/heading rad, ``f_b`` (T, 3) specific force
    in body axes m/s², ``w_b`` (T, 3) body angular rate rad/s."""

def run_scenario(spec_json: str, seed: int, stream: int = 0, isolation: list[bool] | None = None) -> list[dict[str, Any]]:
    """Simulate one run (noise from ``(seed, stream)``) and filter it once per entry of
    ``isolation`` (default ``[True]``); returns one record dict per entry (arrays over T epochs: ``t``, ``error``
    (T, 9), ``sigma`` (T, 9), ``sources``, ``subfilters`` with per-detector arrays; tight
    filters ``satellites``, and with ``[tight.integrity]`` ``integrity``: ``hpl``, ``vpl``,
    ``hpl_snapshot``, ``vpl_snapshot`` (m), ``statistic``, ``alarm``, ``modes`` (T,) and
    ``metrics`` (the metrics engine's counts)). Use :func:`navfdi.run_scenario` for the typed
    result."""

@final
class FederatedStep:
    """One epoch of :class:`FederatedFilter`."""

    @property
    def x(self) -> NDArray[np.float64]:
        """Global estimate after fusion, shape (n,)."""
    @property
    def P(self) -> NDArray[np.float64]:
        """Global covariance, shape (n, n)."""
    @property
    def sources(self) -> int:
        """Sources fused this epoch (0: the global solution was propagated)."""
    @property
    def isolated(self) -> list[bool]:
        """Isolation flag per sub-filter after this epoch's decision."""
    @property
    def reinstated(self) -> list[bool]:
        """Sub-filters reinstated (reset from the global solution) this epoch."""
    @property
    def fused(self) -> list[bool]:
        """Sub-filters that fed this epoch's fusion."""
    @property
    def statistic(self) -> list[float]:
        """Innovation statistic ``λ`` per sub-filter (NaN without measurement)."""
    @property
    def decisions(self) -> dict[str, dict[str, Decision]]:
        """``{sub-filter name: {detector name: Decision}}``."""

@final
class FederatedFilter:
    """Federated Kalman filter with detection, isolation and reinstatement (METHODS §5).

    Each epoch every sub-filter predicts and forms its innovation, its detectors test it, the
    detector named in ``isolation`` isolates or reinstates the sub-filter, non-isolated
    sub-filters update, and the master fuses the healthy ones in information form. In
    ``"reset"`` mode each healthy sub-filter is then reset to ``x_g, P_g/β_i`` (shares
    renormalised over the healthy sources; this mode equals the centralised filter for linear
    systems); ``"no_reset"`` fuses independent sub-filters. A reinstated sub-filter is reset
    from the global solution. An isolated sub-filter never feeds the master; with
    ``isolated="track"`` (default) it takes the global solution after each fusion, so its
    detectors test its sensor against the fault-free solution; ``"predict"`` only predicts;
    ``"update"`` keeps updating with its own (faulty) sensor.

    Parameters
    ----------
    x0 : array_like, shape (n,)
        Initial state.
    P0 : array_like, shape (n, n)
        Initial covariance (symmetric PSD); sub-filters start from ``P0/β_i`` in reset mode.
    subfilters : list of dict
        Each ``{"name": str, "H": (m_i, n), "R": (m_i, m_i), "share": β_i > 0,
        "detectors": [{"name", "kind": "chi2"|"sprt"|"joint", "pf", "pm", "variance"}],
        "isolation": detector name or None}``.
    mode : {"reset", "no_reset"}
        Fusion mode.
    master_share : float
        Master's share ``β_m >= 0``; shares must sum to 1.
    isolation : bool
        Whether alarms isolate sub-filters (False: detectors only report).
    isolated : {"track", "predict", "update"}
        What an isolated sub-filter does (see above).
    """

    def __new__(
        cls,
        x0: ArrayLike,
        P0: ArrayLike,
        subfilters: list[dict[str, Any]],
        mode: str = "reset",
        master_share: float = 0.0,
        isolation: bool = True,
        isolated: str = "track",
    ) -> FederatedFilter: ...
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support: ``(_restore, (class name, JSON state))``."""
    def set_model(self, name: str, H: ArrayLike, R: ArrayLike) -> None:
        """Replace the measurement model of sub-filter ``name``: ``H`` (m_i, n), ``R`` (m_i, m_i)
        symmetric PSD, same m_i as before (e.g. position rows that depend on latitude)."""
    def step(self, Phi: ArrayLike, Q: ArrayLike, measurements: list[ArrayLike]) -> FederatedStep:
        """One epoch with ``Phi``, ``Q`` (n, n) and one measurement (m_i,) per sub-filter (NaN
        components are missing). Validated first; on error the filter is unchanged."""
    @property
    def x(self) -> NDArray[np.float64]:
        """Global estimate, shape (n,)."""
    @property
    def P(self) -> NDArray[np.float64]:
        """Global covariance, shape (n, n)."""
    @property
    def names(self) -> list[str]:
        """Sub-filter names."""
    @property
    def isolated(self) -> list[bool]:
        """Current isolation flags."""

@final
class PreparedScenario:
    """A scenario prepared once (truth trajectory, ``Φ_k``, ``Q_k``, measurement models) for
    many Monte-Carlo runs. Used by :func:`navfdi.montecarlo`.

    Parameters
    ----------
    spec_json : str
        The scenario in its SI JSON form (``Scenario.to_json()``).
    """

    def __new__(cls, spec_json: str) -> PreparedScenario: ...
    @property
    def faults_applied(self) -> list[bool]:
        """Per fault of the scenario: whether it ever reaches a measurement (its sensor
        measures inside the window and, for a satellite fault, the satellite is in view then).
        Seed-free."""
    @property
    def epochs(self) -> int:
        """Epochs per run."""
    @property
    def cells(self) -> list[tuple[str, str, str, float]]:
        """Metric cells ``(subfilter, detector, fault_id or "none", pf)`` in report order."""
    def run_chunk(self, seed: int, start: int, count: int, threads: int = 0, keep: list[int] | None = None) -> dict[str, Any]:
        """Runs ``start .. start+count`` (noise from ``(seed, run)``) on ``threads`` threads
        (0: all cores), GIL released. Returns arrays ``run`` (count,); ``detected``, ``delay``
        (s), ``clear_delay`` (s), ``false_alarm_epochs``, ``outside_epochs``,
        ``wrong_isolations`` (count, cells); ``att_rms``, ``att_max`` (rad), ``pos_rms``,
        ``pos_max``, ``lat_rms``, ``lat_max``, ``fused_alt_rms``, ``fused_alt_max`` (m; the
        fused-altitude ones NaN without altitude fusion) (count,); with ``[tight.integrity]``
        the filter levels against the true error (count,): ``pl_epochs``, ``mi_h_epochs``,
        ``mi_v_epochs``, ``hmi_h_epochs``, ``hmi_v_epochs``, ``pl_alarm_epochs``,
        ``pl_compared_epochs``, ``error_over_hpl_max``, ``error_over_vpl_max``, ``hpl_sum``,
        ``vpl_sum`` (m), ``hpl_ratio_sum``, ``vpl_ratio_sum`` (filter / snapshot ARAIM);
        ``records`` ({run: record} for runs in ``keep``)."""

@final
class SnapshotFde:
    """Result of :func:`snapshot_fde` for one epoch (read-only)."""

    @property
    def position(self) -> NDArray[np.float64] | None:
        """ECEF position, shape (3,), in m; None when ``status == "no_solution"``."""
    @property
    def clock(self) -> float | None:
        """Receiver clock bias c·δt in m; None without a solution."""
    @property
    def statistic(self) -> float:
        """Global-test statistic ``VᵀD⁻¹V`` of the final satellite set (NaN without a solution)."""
    @property
    def threshold(self) -> float:
        """The ``1 − alpha`` quantile of ``χ²(dof)`` (NaN without a solution)."""
    @property
    def dof(self) -> int:
        """Degrees of freedom ``n − 4`` of the final set (0 without a solution)."""
    @property
    def first_test(self) -> tuple[float, float, int]:
        """``(statistic, threshold, dof)`` of the first global test, on all satellites."""
    @property
    def w(self) -> NDArray[np.float64]:
        """w-test statistic per input satellite, shape (n,), from the final set; NaN for
        excluded satellites, satellites without redundancy and without a solution."""
    @property
    def mdb(self) -> NDArray[np.float64]:
        """Minimal detectable bias per input satellite, shape (n,), in m: the bias the deciding
        test finds with probability ``power`` at ``alpha`` (``√(λ0 / q_i)``); NaN for excluded
        satellites, satellites without redundancy and without a solution."""
    @property
    def allocation(self) -> tuple[float, float, float]:
        """``(k0, alpha0, lambda0)`` of the final set: the w-test's critical value, its
        per-satellite false-alarm probability (Šidák: ``1 − (1 − α)^(1/n)``; α/2 shared for
        ``test="both"``) and the non-centrality behind ``mdb``; NaN without a solution."""
    @property
    def excluded(self) -> list[int]:
        """Excluded satellites (indices into the inputs), in exclusion order."""
    @property
    def excluded_w(self) -> list[float]:
        """``|w|`` of each excluded satellite when it was excluded."""
    @property
    def status(self) -> str:
        """``"passed"``, ``"excluded"``, ``"unidentified"`` (the global test fails but no
        ``|w|`` exceeds ``k``; the solution is kept) or ``"no_solution"``."""
    @property
    def reason(self) -> str:
        """Why the exclusion loop stopped, in words."""

def snapshot_fde(
    sat_pos: ArrayLike,
    pseudoranges: ArrayLike,
    sigma: ArrayLike,
    alpha: float = 0.05,
    k: float | None = None,
    x0: ArrayLike | None = None,
    test: str = "global",
    power: float = 0.8,
) -> SnapshotFde:
    """Snapshot least-squares position and clock from pseudoranges with fault detection and
    exclusion (global chi-square test + Baarda w-test, iterative exclusion; METHODS §10).

    ``sat_pos`` (n, 3) ECEF in m; ``pseudoranges`` (n,) in m; ``sigma`` (n,) standard deviations
    in m or a full (n, n) covariance in m²; ``alpha`` false-alarm probability of the global test;
    ``k`` the w-test critical value (default: the two-sided normal quantile of ``alpha``, 1.96
    for 0.05); ``x0`` start ``[x, y, z]`` or ``[x, y, z, clock]`` in m (default: the Earth's
    centre); ``test`` what opens the exclusion loop: ``"global"`` (the χ² test), ``"wtest"``
    (data snooping: the largest ``|w|`` above ``k0 = z(1 − α0/2)``, ``α0 = 1 − (1 − α)^(1/n)``)
    , ``"both"`` (each at α/2) or ``"auto"`` (per call the one of the two with the smaller
    minimal detectable bias); ``power`` (in (alpha, 1)) the power β0 of the reported minimal
    detectable biases. Fewer than 5 satellites left is ``status == "no_solution"`` (no position, never
    NaN). Raises ``ValueError`` naming the argument for wrong shapes, non-finite values,
    non-positive sigma or a covariance that is not symmetric positive definite; ``MemoryError``
    when the n × n work matrices would not fit in memory."""

def ls_test(b: ArrayLike, l: ArrayLike, d: ArrayLike) -> dict[str, Any]:
    """The linear test of METHODS §10 on ``l = B x + ε``, ``ε ~ N(0, D)``: ``b`` = B (n, u) with
    n > u, ``l`` (n,), ``d`` = D (n, n) symmetric positive definite or (n,) standard deviations.
    Returns ``x`` (u,), ``v`` (n,) residuals ``B x̂ − l``, ``dv`` (n, n) their covariance
    ``D − B(BᵀD⁻¹B)⁻¹Bᵀ``, ``statistic`` ``VᵀD⁻¹V``, ``dof`` ``n − u`` and ``w`` (n,) the general
    w-test ``e_iᵀD⁻¹V / sqrt(e_iᵀD⁻¹D_VD⁻¹e_i)`` (NaN where an observation has no
    redundancy). Raises :class:`LinAlgError` when ``BᵀD⁻¹B`` is singular."""

@final
class StateDecision:
    """One epoch's decision of :class:`StateChi2` (read-only)."""

    @property
    def statistic(self) -> float:
        """``λ = βᵀV⁻¹β`` (NaN when not tested: propagator too young or V ill-conditioned)."""
    @property
    def threshold(self) -> float:
        """``F⁻¹_{χ²(dof)}(1 − pf)``."""
    @property
    def alarm(self) -> bool:
        """Fault declared this epoch."""
    @property
    def dof(self) -> int:
        """Number of tested states."""
    @property
    def propagator(self) -> int | None:
        """Index (0 or 1) of the propagator tested; None when not tested."""
    @property
    def age(self) -> int:
        """Age in epochs of the tested propagator (0 when not tested)."""
    @property
    def ready(self) -> bool:
        """The age rule is met (a propagator at least ``min_age`` epochs old exists)."""
    @property
    def ill_conditioned(self) -> bool:
        """``V = P_s − P`` could not be factored safely (condition above 1e12 or not positive
        definite); nothing was tested and no alarm raised."""
    @property
    def ratio(self) -> float:
        """Statistic over threshold (≥ 1 means alarm; NaN when not tested)."""

@final
class StateChi2:
    """Dual-propagator state chi-square test (METHODS §8, paper 003).

    Two propagators follow the filter's model without measurements and are reset alternately
    from the filter's output every ``reset_every`` epochs; each epoch the one reset longer ago,
    once at least ``min_age`` epochs old (default ``reset_every``), gives
    ``β = x̂ − x_s``, ``V = P_s − P`` and ``λ = βᵀV⁻¹β ~ χ²(d)`` over the tested ``states``
    (indices, default all ``n``). Catches faults the filter slowly follows."""

    def __new__(cls, pf: float, n: int, reset_every: int, min_age: int | None = None, states: list[int] | None = None) -> StateChi2: ...
    def step(self, x: ArrayLike, P: ArrayLike, Phi: ArrayLike, Q: ArrayLike) -> StateDecision:
        """One epoch: the filter's updated estimate ``x`` (n,) and covariance ``P`` (n, n), and
        the transition ``Phi`` (n, n) and process noise ``Q`` (n, n, symmetric PSD) from the
        previous epoch (ignored at the first). Propagate, test, then reset the propagator due at
        this epoch. Bad input raises ``ValueError`` naming the argument and changes nothing."""
    @property
    def threshold(self) -> float:
        """``F⁻¹_{χ²(len(states))}(1 − pf)``."""
    @property
    def pf(self) -> float:
        """False-alarm probability per epoch."""
    @property
    def states(self) -> list[int]:
        """Tested state indices."""
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support."""

@final
class FusedValue:
    """One epoch's output of :class:`WeightedFusion` (read-only)."""

    @property
    def value(self) -> float | None:
        """Fused value (the sensors' unit); None when no sensor contributed (every M_i = 0 or
        no value): predict only."""
    @property
    def variance(self) -> float:
        """``1 / Σ w_i M_i`` (NaN when none contributed)."""
    @property
    def weights(self) -> NDArray[np.float64]:
        """Normalised weights per sensor, shape (n,); 0 for sensors that did not contribute."""
    @property
    def sigma2(self) -> NDArray[np.float64]:
        """Estimated σ_i² per sensor, shape (n,): mean square deviation from the prediction
        over the window, or ``prior_sigma²`` before two samples."""

@final
class WeightedFusion:
    """Inverse-variance fusion of one quantity (e.g. altitude, m) over n sensors with a fault
    matrix (METHODS §9, paper 003): ``y = Σ w_i M_i x_i / Σ w_i M_i``, ``w_i = 1/σ_i²`` with
    ``σ_i²`` from sensor i's deviations from the filter's prediction over the last ``window``
    samples: their mean square (``estimate="mean_square"``, a bias counts) or their variance
    about their mean (``"variance"``, paper 003's eq. 35); ``prior_sigma[i]`` before two
    samples; never below ``prior_sigma[i]²`` (the sensor's own noise is part of every
    deviation; a smaller sample estimate is sampling error)."""

    def __new__(cls, prior_sigma: list[float], window: int = 20, estimate: str = "mean_square") -> WeightedFusion: ...
    @property
    def estimate(self) -> str:
        """``"mean_square"`` or ``"variance"``."""
    def step(self, values: ArrayLike, predicted: float, healthy: list[bool]) -> FusedValue:
        """One epoch: ``values`` (n,) per sensor (NaN: not available), the filter's
        ``predicted`` value, ``healthy`` (n,) the fault matrix M_i. Bad input raises
        ``ValueError`` naming the argument and changes nothing."""
    @property
    def sensors(self) -> int:
        """Number of sensors n."""
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support."""

def read_rinex_obs(path: str) -> dict[str, Any]:
    """Read a RINEX 3 or 4 observation file (plain, .gz or Hatanaka .crx) into columns: ``epoch`` (uint32),
    ``time`` (GPS seconds since 1980-01-06, float64), ``sat`` (uint32 code into
    ``satellites``), ``code`` (uint32 code into ``observables``), ``value`` (float64), each
    (n,); ``satellites``, ``observables`` (list[str]); ``epoch_times`` (GPS s) and ``flags``
    (per epoch); ``dropped`` observation types (e.g. ``G:X1``); ``version``; ``receiver``;
    ``approx_position`` ([x, y, z] m or None). Malformed files raise :class:`FileFormatError`."""

def read_rinex_nav(path: str) -> dict[str, Any]:
    """Read a RINEX 3 or 4 navigation file into columns, one row per GPS/Galileo/BeiDou/QZSS
    ephemeris: ``satellite`` (list[str]); ``toc``, ``toe`` (GPS s); ``af0`` s, ``af1`` s/s,
    ``af2`` s/s²; ``sqrt_a`` √m; ``e``; ``i0``, ``omega0``, ``omega``, ``m0`` rad; ``delta_n``,
    ``idot``, ``omega_dot`` rad/s; ``tgd`` s; ``health``; ``accuracy`` m; ``iod`` (float64
    arrays); ``unhealthy``, ``fnav`` (list[bool]); ``klobuchar`` (8 floats or None);
    ``records`` (records per system letter); ``version``."""

@final
class LoggedSource:
    """Recorded logs prepared for a scenario (architecture ``loosely_coupled``, or ``tight``
    with ``tight.strapdown``). Internal: use :func:`navfdi.run_scenario` on a scenario with a
    ``[source]`` table.

    ``imu``: (N, 7) float array — time (s from the run's time 0), angular rate x, y, z (rad/s),
    specific force x, y, z (m/s²), IMU axes. ``gnss``, ``reference``: (M, 13) or (M, 14) — time (s),
    latitude, longitude (rad), height (m), velocity east, north, up (m/s), σ of position
    east, north, up (m) and of velocity (m/s), and (optional) the solution quality in RTKLIB's
    codes (1 fixed, 2 float, 3 SBAS, 4 DGPS, 5 single, 6 PPP; 0 unknown). Or ``rinex`` = (observation path, navigation
    path) instead of ``gnss`` (tight scenarios): the record epochs are the observation
    epochs, time 0 the first, and ``imu`` and ``reference`` times are GPS seconds (GPST).
    ``score_inputs``: score the reference at the GNSS input epochs too (after their update),
    for a reference with no other epochs (GNSS-log sources).
    Raises ValueError naming the array and row, FileFormatError for a malformed RINEX file."""

    def __new__(
        cls,
        spec_json: str,
        imu: ArrayLike,
        gnss: ArrayLike | None = None,
        reference: ArrayLike | None = None,
        rinex: tuple[str, str] | None = None,
        score_inputs: bool = False,
    ) -> LoggedSource: ...
    @property
    def scored(self) -> int:
        """Record epochs at which the reference is scored."""
    @property
    def epochs(self) -> int:
        """Number of record epochs (the GNSS log's or the RINEX observations')."""
    @property
    def time0(self) -> float:
        """GPS seconds (GPST) of time 0 for a source read from RINEX files; 0 otherwise."""
    @property
    def times(self) -> NDArray[np.float64]:
        """Record epoch times (s from time 0), shape (T,)."""
    @property
    def satellites(self) -> list[str]:
        """Satellites in view at some epoch (RINEX sources; empty otherwise)."""
    @property
    def faults_applied(self) -> list[bool]:
        """Per fault (as given, before any draw): whether its sensor measures inside its window."""
    @property
    def cells(self) -> list[tuple[str, str, str, float]]:
        """The metric cells: ``(channel, detector, fault_id or "none", pf)``."""
    def run_chunk(self, seed: int, start: int, count: int, threads: int = 0, keep: list[int] | None = None) -> dict[str, Any]:
        """Monte-Carlo runs ``start .. start + count``: run ``i`` draws its faults' ``draw``
        ranges from ``(seed, i)``; the dict of arrays of :meth:`PreparedScenario.run_chunk`
        plus ``hor_rms``, ``hor_max``, ``fault_hor_max``, ``hor_rel_rms``,
        ``fault_hor_rel_max`` (count,) in m (the last two with the run's mean horizontal offset
        to the reference removed) and the drawn ``fault_start``, ``fault_magnitude`` (count,
        faults), ``fault_kind``, ``fault_components``, ``fault_satellite`` (lists). GIL
        released; Ctrl-C stops it."""
    def run(self, spec_jsons: list[str], isolation: bool = True) -> list[dict[str, Any]]:
        """Run each scenario (the prepared one and its variants) on the recorded measurements
        with the prepared scenario's faults injected; one record dict per scenario, with
        ``nav`` (T, 21) and ``nav_columns``. GIL released, the scenarios run in parallel (the
        same records to the bit as one by one); Ctrl-C stops it."""
    def to_bytes(self) -> bytes:
        """The prepared source as bytes (``NAVFDISR``, the navfdi version, then the scenario,
        time 0, the fault-free datum of protection-level scoring — computed now if needed —
        and the prepared streams): what a Dask worker runs chunks from. GIL released."""
    @staticmethod
    def from_bytes(data: bytes) -> LoggedSource:
        """A source from :meth:`to_bytes`'s bytes; FileFormatError names what is wrong (not a
        prepared source, another navfdi version, truncated or corrupted)."""
    def __reduce__(self) -> tuple[Any, tuple[bytes]]:
        """Pickle support: the source travels as :meth:`to_bytes`."""

@final
class GnssRun:
    """Single-point positioning with FDE over a RINEX observation file, solved in chunks of
    epochs. Internal: use :func:`navfdi.gnss_solve`."""

    def __new__(
        cls,
        obs_path: str,
        nav_path: str,
        systems: list[str],
        mask_deg: float,
        alpha: float,
        k: float | None,
        exclude: bool,
        noise: tuple[float, float],
        weighting: str,
        ionosphere: bool,
        troposphere: bool,
        faults: list[tuple[str, str, float, float, float]],
        codes: dict[str, str],
        factors: dict[str, float],
        sprt: tuple[float, float],
        aime: tuple[float, int],
        cusum: tuple[float, float, float, int, float],
        cn0_reference: float = 45.0,
        test: str = "global",
        power: float = 0.8,
        cn0_slope: float = 1.0,
    ) -> GnssRun: ...
    @property
    def codes(self) -> dict[str, str]:
        """Pseudorange code used per system letter (chosen by priority, or given)."""
    @property
    def n_epochs(self) -> int:
        """Number of epochs in the observation file."""
    @property
    def done(self) -> int:
        """Epochs solved so far."""
    def advance(self, n: int) -> int:
        """Solve up to ``n`` more epochs (GIL released; Ctrl-C stops within one epoch and
        keeps the epochs before this call); returns how many were solved (after a ``restart``
        with ``every`` > 1, of every ``every``-th epoch; ``done`` counts the file's epochs
        passed)."""
    def restart(self, weighting: str, cn0_slope: float, factors: dict[str, float], exclude: bool, test: str, every: int = 1) -> None:
        """Start again from the first epoch on the observations already read, with another
        variance model (``"elevation"``, ``"rtklib"``, ``"cn0"`` with ``cn0_slope`` decades per
        10 dB-Hz; the reference C/N0 kept), per-system σ ``factors`` (replacing the
        constructor's), ``exclude`` and ``test`` (α, k and power kept), solving every
        ``every``-th epoch only (≥ 1). Drops everything solved so far; on an error
        (ValueError) nothing changes."""
    def estimation_table(self) -> dict[str, Any]:
        """What ``navfdi.gnss_solve``'s ``"auto"`` estimates read, without the tables' strings:
        per epoch (n_epochs_solved,) ``statistic``, ``dof``, ``first_statistic``,
        ``first_dof`` (float64); per satellite-epoch row (n_rows,) ``w``, ``cn0`` dB-Hz (NaN
        where none) and ``used`` (bool: status ``used``)."""
    def velocity(self, noise: tuple[float, float] = ...) -> dict[str, Any]:
        """Receiver velocity from Doppler for the epochs solved so far (``noise`` default
        (0.05, 0.05) m/s): ``vx, vy, vz``,
        ``clock_drift`` (m/s), ``statistic``, ``threshold``, ``dof``, ``used``, ``excluded``."""
    def epoch_table(self) -> dict[str, Any]:
        """Per-epoch columns (n_epochs_solved,): ``time`` GPS s; ``x, y, z`` ECEF m (NaN without
        a solution); ``clock_G/E/C/J`` m; ``dof``, ``statistic``, ``threshold``,
        ``first_statistic``, ``first_threshold``, ``first_dof``, ``used`` (float64);
        ``excluded``, ``faulty`` (space-separated names), ``status``, ``reason`` (list[str])."""
    def satellite_table(self) -> dict[str, Any]:
        """Per epoch and satellite columns: ``epoch``; ``satellite`` (list[str]);
        ``elevation``, ``azimuth`` deg; ``residual``, ``sigma``, ``iono``, ``tropo``, ``fault``
        m; ``cn0`` dB-Hz (NaN where none); ``w``; ``sat_x, sat_y, sat_z`` m; ``sat_clock`` s; ``sprt``, ``aime``, ``cusum``
        (sequential statistics); ``sprt_alarm``, ``aime_alarm``, ``cusum_alarm`` (list[bool]); ``status`` (list[str])."""
    @property
    def dropped(self) -> list[str]:
        """Observation types dropped while reading (e.g. ``G:X1``)."""
    @property
    def receiver(self) -> str:
        """Receiver type from the observation header."""
    @property
    def systems_in_files(self) -> list[str]:
        """Letters of the systems both files let a solution use (pseudoranges on a first-band
        code in the observation file, ephemerides in the navigation file), asked for or not,
        in column order."""

def dll_variance(cn0_dbhz: float, t: float = 0.02, spacing: float = 1.0) -> float:
    """Variance (chips²) of one output of a noncoherent early-minus-late power delay
    discriminator after coherent integration ``t`` (s) with early-late ``spacing`` (chips, in
    (0, 2)) at ``cn0_dbhz`` (0–80 dB-Hz): Kaplan & Hegarty (2006) eq. 5.71 with the bandwidth
    of one output, B = 1/(2T). Bad arguments raise ``ValueError`` naming them."""

def fll_variance(cn0_dbhz: float, t: float = 0.02, high_noise: bool = False) -> float:
    """Variance (Hz²) of one output of a cross-product (ATAN2) frequency discriminator after
    coherent integration ``t`` (s) at ``cn0_dbhz``: Kaplan & Hegarty (2006) eq. 5.64 with
    B = 1/(2T) and F = 1 (2 with ``high_noise``, near the tracking threshold)."""

@final
class PrefilterStep:
    """One step's innovation of :class:`Prefilter` (read-only)."""

    def __new__(cls) -> PrefilterStep: ...
    @property
    def residual(self) -> NDArray[np.float64]:
        """Innovation (2,): code (chips) and frequency (Hz); NaN where a discriminator gave no
        output."""
    @property
    def covariance(self) -> NDArray[np.float64]:
        """Its covariance (2, 2) ``HP⁻Hᵀ + R`` (NaN rows/columns where absent)."""
    @property
    def statistic(self) -> float:
        """``λ = rᵀA⁻¹r`` over the used components (NaN when none): χ²(dof) under no fault."""
    @property
    def dof(self) -> int:
        """Components used (0–2)."""

@final
class Prefilter:
    """Channel prefilter of an ultra-tight (vector-tracking) receiver (paper 004, METHODS §11):
    a 3-state Kalman filter on the replica's code-phase error (chips), carrier-frequency error
    (Hz) and its rate (Hz/s) with ``Φ = [[1, βT, βT²/2], [0, 1, T], [0, 0, 1]]``, a random walk
    of the frequency rate (``jerk_psd``, Hz²/s³) and optionally of the code phase
    (``code_psd``, chips²/s), updated every ``t`` seconds by the delay and frequency
    discriminator outputs with the noise of :func:`dll_variance` and :func:`fll_variance`.
    ``beta`` defaults to GPS L1 C/A (1.023 MHz / 1575.42 MHz); ``x0`` (3,) defaults to zeros,
    ``P0`` (3, 3) to diag(0.01 chips², 1 Hz², 1 Hz²/s²)."""

    def __new__(
        cls,
        t: float = 0.02,
        beta: float = ...,
        jerk_psd: float = 1.0,
        code_psd: float = 0.0,
        spacing: float = 1.0,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
    ) -> Prefilter: ...
    def step(self, z_code: float, z_freq: float, cn0_dbhz: float) -> PrefilterStep:
        """One coherent integration: predict over ``t``, then update with the code (chips) and
        frequency (Hz) discriminator outputs (NaN: absent) whose noise follows ``cn0_dbhz``.
        Returns the innovation the update used. Bad input raises ``ValueError`` and changes
        nothing."""
    def shift(self, dx: ArrayLike) -> None:
        """Add ``dx`` (3,) to the state (a replica correction moves the errors by its
        negative)."""
    @property
    def x(self) -> NDArray[np.float64]:
        """State (3,): code-phase error (chips), frequency error (Hz), its rate (Hz/s)."""
    @property
    def P(self) -> NDArray[np.float64]:
        """Covariance (3, 3)."""
    @property
    def phi(self) -> NDArray[np.float64]:
        """Transition matrix Φ (3, 3) of one step."""
    @property
    def q(self) -> NDArray[np.float64]:
        """Process noise Q (3, 3) of one step."""
    def __reduce__(self) -> tuple[Callable[[str, str], Any], tuple[str, str]]:
        """Pickle support."""

def snapshot_pl(
    los_enu: list[list[float]] | list[tuple[float, float, float]],
    clock: list[int],
    sigma2: list[float],
    threshold: float,
    k_md: float,
    overbound: tuple[list[float], list[float]] | None = None,
) -> dict[str, Any]:
    """Slope-based protection levels of the snapshot least-squares global test; use
    :func:`navfdi.gnss_integrity.snapshot_pl`. ``overbound``: ``(variances m², nominal biases
    m)`` per satellite of an overbounding error model for the fault-free terms (the slopes keep
    the test's σ). Returns ``hpl``, ``vpl``, ``sigma_h``, ``sigma_v`` (m), ``hslope``,
    ``vslope``, ``critical``."""

def araim_epoch(
    rows: list[list[float]] | list[tuple[float, float, float]],
    constellation: list[int],
    c_int: list[float],
    c_acc: list[float],
    b_nom: list[float],
    p_sat: list[float],
    p_const: list[float],
    allocation: tuple[float, float, float, float, float, float, float],
    residuals: list[float] | None = None,
) -> dict[str, Any]:
    """ARAIM (ADD v3.0) on one epoch; use :func:`navfdi.integrity.araim`. ``rows`` (n, 3) ENU
    geometry rows (minus the lines of sight), ``constellation`` (n) indices, variances (m²),
    ``b_nom`` (m), priors, ``allocation`` (P_HMI,VERT, P_HMI,HOR, P_FA,VERT, P_FA,HOR,
    P_THRES, P_EMT, TOL_PL (m)), ``residuals`` (n, m; optional: fault detection and exclusion). Returns
    ``vpl, hpl, emt, sigma_acc, sigma0, bias0, k_fa, p_unmonitored, n_max, available``,
    ``modes`` (columns: ``prior`` (N,), ``sigma``, ``sigma_ss``, ``bias``, ``threshold``,
    ``separation`` (N, 3), ``satellites``/``constellations`` flat with ``*_count`` (N,)) and
    with residuals ``fde`` (``detected, test_ratio, excluded, tried, passed, vpl, hpl,
    vpl_any, hpl_any, alarm, available``)."""

def araim_los(
    los_enu: Any,
    constellation: list[int],
    sigma_ura: list[float],
    sigma_ure: list[float],
    c_int: list[float] | None,
    c_acc: list[float] | None,
    b_nom: list[float],
    p_sat: list[float],
    p_const: list[float],
    allocation: tuple[float, float, float, float, float, float, float],
    residuals: list[float] | None = None,
) -> dict[str, Any]:
    """:func:`araim_epoch` from unit lines of sight ``los_enu`` (n, 3; east, north, up), with
    the ADD's variances ``σ_URA² (σ_URE²) + σ_tropo² + σ_user²`` where ``c_int`` / ``c_acc``
    are None; use :func:`navfdi.integrity.araim`. ``sigma_ura``, ``sigma_ure`` (m),
    ``b_nom`` (m), ``p_sat``, ``c_int``, ``c_acc`` (m²): one value for every satellite or n.
    The same dict; ValueError for a wrong shape, a non-finite or non-unit line of sight."""

def araim_variances(elevation: Any) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """The ADD's ``(σ_tropo², σ_user²)`` (m²) at elevations (rad), each of the input's shape;
    use :func:`navfdi.integrity.elevation_variances`."""
