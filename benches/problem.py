"""The benchmark problem shared by the Python benchmarks: an INS-like error model.

n = 15 states at 1 Hz (attitude 0..3, velocity 3..6, position 6..9, gyro drift 9..12,
accelerometer bias 12..15), m = 6 measurements (position and velocity), T = 10 000 epochs.
The same model as ``benches/core_step.rs``.
"""

from __future__ import annotations

import time

import numpy as np

N, M, T = 15, 6, 10_000


def problem(T: int = T, seed: int = 0):
    """Return ``x0 (n,), P0 (n,n), Phi (n,n), Q (n,n), zs (T,m), H (m,n), R (m,m)``."""
    F = np.zeros((N, N))
    for i in range(3):
        F[i, 9 + i] = -1.0
        F[3 + i, 12 + i] = 1.0
        F[6 + i, 3 + i] = 1.0
        F[9 + i, 9 + i] = -1.0 / 3600.0
        F[12 + i, 12 + i] = -1.0 / 1800.0
    F[3, 1], F[4, 0] = -9.8, 9.8
    Phi = np.eye(N) + F + F @ F / 2.0
    sd = np.array([1e-3, 1e-3, 3e-3, 0.6, 0.6, 0.6, 50, 50, 50, 1e-6, 1e-6, 1e-6, 1e-3, 1e-3, 1e-3])
    P0 = np.diag(sd**2)
    Q = np.diag([1e-12] * 3 + [1e-8] * 3 + [0.0] * 3 + [1e-14] * 3 + [1e-9] * 3)
    H = np.zeros((M, N))
    H[0:3, 6:9] = np.eye(3)
    H[3:6, 3:6] = np.eye(3)
    R = np.diag([25.0] * 3 + [0.01] * 3)
    rng = np.random.default_rng(seed)
    zs = rng.standard_normal((T, M)) * np.sqrt(np.diag(R))
    return np.zeros(N), P0, Phi, Q, zs, H, R


def step_api(x0, P0, Phi, Q, zs, H, R):
    """navfdi's per-epoch step API driven from a Python loop; returns the final state."""
    import navfdi

    kf = navfdi.KalmanFilter(x0, P0)
    for z in zs:
        kf.predict(Phi, Q)
        kf.update(z, H, R)
    return kf.x


def step_model_api(x0, P0, Phi, Q, zs, H, R):
    """navfdi's step API with the model fixed once (``set_model``, then ``step(z)`` per epoch,
    as filterpy keeps F, Q, H, R on its object); returns the final state."""
    import navfdi

    kf = navfdi.KalmanFilter(x0, P0)
    kf.set_model(Phi, Q, H, R)
    for z in zs:
        kf.step(z)
    return kf.x


def filterpy_loop(x0, P0, Phi, Q, zs, H, R):
    """The reference: filterpy's KalmanFilter, predict + update per epoch; final state."""
    from filterpy.kalman import KalmanFilter

    kf = KalmanFilter(dim_x=x0.size, dim_z=zs.shape[1])
    kf.x, kf.P, kf.F, kf.Q, kf.H, kf.R = x0.copy(), P0.copy(), Phi, Q, H, R
    for z in zs:
        kf.predict()
        kf.update(z)
    return kf.x


def run_filter(x0, P0, Phi, Q, zs, H, R):
    """navfdi.run_filter over the whole sequence; final state."""
    import navfdi

    return navfdi.run_filter(x0, P0, Phi, Q, zs, H, R).x[-1]


def best(f, rounds: int = 7) -> float:
    """Shortest wall time (s) of ``rounds`` calls of ``f()``."""
    out = []
    for _ in range(rounds):
        t = time.perf_counter()
        f()
        out.append(time.perf_counter() - t)
    return min(out)
