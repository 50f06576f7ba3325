"""Large states: ``KalmanFilter.predict`` beside numpy's ``Phi @ P @ Phi.T + Q`` (issue
'Hardening', item 14), in the same process, for n = 15, 100, 500, 2000.

``python -m pytest benches/bench_large.py --benchmark-enable`` times both with
pytest-benchmark; ``python benches/bench_large.py`` prints the table of benches/README.md.
navfdi's ``predict`` also validates its inputs (Φ finite; Q symmetric, PSD by a Cholesky
factorisation) and converts them from numpy, which numpy's expression does not.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

import navfdi

SIZES = [15, 100, 500, 2000]


def make(n: int):
    rng = np.random.default_rng(n)
    # A scaled rotation: dense and non-symmetric, and P stays bounded over many predictions.
    Phi = 0.999 * np.linalg.qr(rng.standard_normal((n, n)))[0]
    A = rng.standard_normal((n, n)) / np.sqrt(n)
    P = A @ A.T + np.eye(n)
    Q = 1e-3 * np.eye(n)
    return Phi, P, Q


def navfdi_predict(kf: navfdi.KalmanFilter, Phi, Q) -> None:
    kf.predict(Phi, Q)


def numpy_predict(Phi, P, Q):
    return Phi @ P @ Phi.T + Q


@pytest.mark.parametrize("n", SIZES)
def test_same_answer(n):
    Phi, P, Q = make(n)
    kf = navfdi.KalmanFilter(np.zeros(n), P)
    kf.predict(Phi, Q)
    ref = numpy_predict(Phi, P, Q)
    np.testing.assert_allclose(kf.P, 0.5 * (ref + ref.T), rtol=1e-10, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.benchmark(group="predict, large n")
def test_bench_navfdi_predict(benchmark, n):
    Phi, P, Q = make(n)
    kf = navfdi.KalmanFilter(np.zeros(n), P)
    benchmark(navfdi_predict, kf, Phi, Q)


@pytest.mark.parametrize("n", SIZES)
@pytest.mark.benchmark(group="predict, large n")
def test_bench_numpy_predict(benchmark, n):
    Phi, P, Q = make(n)
    benchmark(numpy_predict, Phi, P, Q)


def best_of(f, seconds: float = 1.0) -> float:
    f()
    times = []
    t_end = time.perf_counter() + seconds
    while time.perf_counter() < t_end or len(times) < 3:
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


if __name__ == "__main__":
    print("| n | navfdi predict | numpy Φ@P@Φᵀ+Q | ratio |")
    print("|---:|---:|---:|---:|")
    for n in SIZES:
        Phi, P, Q = make(n)
        kf = navfdi.KalmanFilter(np.zeros(n), P)
        a = best_of(lambda: navfdi_predict(kf, Phi, Q), 2.0)
        b = best_of(lambda: numpy_predict(Phi, P, Q), 2.0)
        unit, k = ("µs", 1e6) if a < 1e-3 else ("ms", 1e3)
        print(f"| {n} | {a * k:.3g} {unit} | {b * k:.3g} {unit} | {a / b:.2f}× |")
