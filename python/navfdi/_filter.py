"""Whole-sequence Kalman filtering (the epoch loop runs in Rust with the GIL released)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from navfdi import _core


class FilterRun(NamedTuple):
    """Per-epoch outputs of :func:`run_filter` (T epochs, n states, m measurements).

    Attributes
    ----------
    x : ndarray, shape (T, n)
        Posterior state after each epoch's update.
    P : ndarray, shape (T, n, n)
        Posterior covariance.
    residual : ndarray, shape (T, m)
        Innovation ``r = z - H x⁻``; NaN for components that were missing (NaN in ``zs``).
    covariance : ndarray, shape (T, m, m)
        Innovation covariance ``A = H P⁻ Hᵀ + R``; NaN rows/columns for missing components.
    statistic : ndarray, shape (T,)
        ``λ = rᵀ A⁻¹ r`` over the used components (χ²(dof) under no fault); NaN when none.
    used : ndarray of bool, shape (T, m)
        Components of ``zs`` used at each epoch.
    """

    x: NDArray[np.float64]
    P: NDArray[np.float64]
    residual: NDArray[np.float64]
    covariance: NDArray[np.float64]
    statistic: NDArray[np.float64]
    used: NDArray[np.bool_]


def run_filter(
    x0: ArrayLike,
    P0: ArrayLike,
    Phi: ArrayLike,
    Q: ArrayLike,
    zs: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    fading: float = 1.0,
) -> FilterRun:
    """Run a linear Kalman filter over a whole measurement sequence in one call.

    At each epoch ``k`` the filter predicts with ``Phi[k], Q[k]`` and then updates with
    ``zs[k], H[k], R[k]``; ``x0, P0`` describe the state before epoch 0. The loop runs in Rust
    with the GIL released. All inputs are validated before the first epoch.

    Parameters
    ----------
    x0 : array_like, shape (n,)
        Initial state.
    P0 : array_like, shape (n, n)
        Initial covariance, symmetric positive semi-definite.
    Phi : array_like, shape (n, n) or (T, n, n)
        State transition matrix, one for all epochs or one per epoch.
    Q : array_like, shape (n, n) or (T, n, n)
        Process-noise covariance already mapped to the state (ΓQΓᵀ), symmetric PSD.
    zs : array_like, shape (T, m)
        Measurements, one row per epoch; NaN marks a missing component (reduced update).
    H : array_like, shape (m, n) or (T, m, n)
        Measurement matrix.
    R : array_like, shape (m, m) or (T, m, m)
        Measurement-noise covariance, symmetric PSD.
    fading : float, default 1.0
        Fading factor ``S >= 1`` applied at every prediction (``P⁻ = S ΦPΦᵀ + Q``).

    Returns
    -------
    FilterRun
        Named tuple ``(x, P, residual, covariance, statistic, used)``.

    Raises
    ------
    ValueError
        Wrong shapes, non-finite values, covariances not symmetric PSD, ``fading < 1``.
    LinAlgError
        The innovation covariance is not positive definite at some epoch (the epoch is named).
    """
    return FilterRun(*_core.run_filter(x0, P0, Phi, Q, zs, H, R, fading))
