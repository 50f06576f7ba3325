"""Plain-numpy reference implementations used by the tests (independent of the Rust core)."""

from __future__ import annotations

import numpy as np


def predict(x, P, Phi, Q, fading=1.0):
    """x⁻ = Φx, P⁻ = S ΦPΦᵀ + Q."""
    return Phi @ x, fading * Phi @ P @ Phi.T + Q


def update(x, P, z, H, R):
    """Joseph-form update on the non-NaN components; returns (x, P, r, A, λ, used)."""
    used = ~np.isnan(z)
    if not used.any():
        return x, P, np.full(z.shape, np.nan), np.full((z.size, z.size), np.nan), np.nan, used
    Hr, Rr, zr = H[used], R[np.ix_(used, used)], z[used]
    r = zr - Hr @ x
    A = Hr @ P @ Hr.T + Rr
    K = np.linalg.solve(A, Hr @ P).T  # K = P Hᵀ A⁻¹ (A, P symmetric)
    I_KH = np.eye(x.size) - K @ Hr
    P_new = I_KH @ P @ I_KH.T + K @ Rr @ K.T
    lam = float(r @ np.linalg.solve(A, r))
    r_full = np.full(z.shape, np.nan)
    r_full[used] = r
    A_full = np.full((z.size, z.size), np.nan)
    A_full[np.ix_(used, used)] = A
    return x + K @ r, 0.5 * (P_new + P_new.T), r_full, A_full, lam, used


def random_spd(rng, n, eps=1e-2, scale=1.0):
    """A random symmetric positive-definite n × n matrix."""
    B = rng.standard_normal((n, n))
    return scale * (B @ B.T / n + eps * np.eye(n))


def random_system(rng, n, m, T):
    """Random stable system with per-epoch matrices and measurements."""
    Phi = np.stack([np.eye(n) + 0.1 * rng.standard_normal((n, n)) / np.sqrt(n) for _ in range(T)])
    Q = np.stack([random_spd(rng, n, scale=0.01) for _ in range(T)])
    H = rng.standard_normal((T, m, n))
    R = np.stack([random_spd(rng, m, eps=0.1) for _ in range(T)])
    zs = rng.standard_normal((T, m)) * 2.0
    return np.zeros(n) + rng.standard_normal(n), random_spd(rng, n), Phi, Q, zs, H, R
