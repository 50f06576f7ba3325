"""numpy peers of the GNSS benchmarks (benches/gnss.rs), in one process with navfdi's Python API.

    python benches/bench_gnss.py

Prints µs per call for:

* snapshot WLS (Gauss-Newton from a warm start) + global test + w-test, 10 satellites, in
  plain numpy (the same algorithm as ``navfdi_core::gnss::snapshot``) and through
  ``navfdi.snapshot_fde`` (Python call: conversion, validation, solve, result object);
* one tight-filter epoch, 17 states, 20 measurements (10 pseudoranges + 10 rates): predict,
  innovation, chi-square test, Joseph update, in plain numpy, batch (20 x 20 A) and row by
  row (scalar Joseph updates, the statistic accumulated: what navfdi's runs do when no
  per-satellite w is wanted); navfdi's core figure is the
  criterion ``gnss/tight_epoch_17x20``; the per-epoch cost of a whole ``shao2018`` run
  through ``_core.run_scenario`` is printed beside it.
"""

from __future__ import annotations

import math
import time

import numpy as np
from scipy import stats

import navfdi
from navfdi import _core


def best(f, reps: int, rounds: int = 7) -> float:
    """Best of ``rounds`` of the mean µs per call over ``reps`` calls."""
    out = []
    for _ in range(rounds):
        t = time.perf_counter()
        for _ in range(reps):
            f()
        out.append((time.perf_counter() - t) / reps * 1e6)
    return min(out)


def scene(seed: int = 0, n: int = 10):
    rng = np.random.default_rng(seed)
    lat, lon = 0.7, 2.0
    up = np.array([math.cos(lat) * math.cos(lon), math.cos(lat) * math.sin(lon), math.sin(lat)])
    east = np.array([-math.sin(lon), math.cos(lon), 0.0])
    north = np.cross(up, east)
    rx = 6_378_137.0 * up
    sats = []
    for _ in range(n):
        el, az = math.radians(rng.uniform(15, 85)), rng.uniform(0, 2 * math.pi)
        d = math.cos(el) * (math.sin(az) * east + math.cos(az) * north) + math.sin(el) * up
        b = rx @ d
        sats.append(rx + (-b + math.sqrt(b * b - rx @ rx + 26_560_000.0**2)) * d)
    sats = np.array(sats)
    sig = np.full(n, 3.0)
    rho = np.linalg.norm(sats - rx, axis=1) + 100.0 + sig * rng.normal(size=n)
    return rx, sats, rho, sig


#: Global-test thresholds by dof, computed once (navfdi caches them too).
THRESHOLDS = {d: float(stats.chi2.isf(0.05, d)) for d in range(1, 65)}


def numpy_snapshot(sats, rho, sig, x0, k=1.6449, tol=1e-7):
    """Snapshot WLS + FDE in numpy (same algorithm and stopping rules as navfdi, α = 0.05)."""
    active = list(range(len(rho)))
    excluded = []
    while len(active) >= 5:
        S, r, w_ = sats[active], rho[active], 1.0 / sig[active] ** 2
        x = np.array(x0, float)
        for _ in range(20):
            d = S - x[:3]
            rng_ = np.sqrt((d * d).sum(1))
            B = np.empty((len(r), 4))
            B[:, :3] = -d / rng_[:, None]
            B[:, 3] = 1.0
            l = r - (rng_ + x[3])
            N = B.T @ (B * w_[:, None])
            dx = np.linalg.solve(N, B.T @ (w_ * l))
            x += dx
            if math.sqrt(dx @ dx) < tol:
                break
        d = S - x[:3]
        rng_ = np.sqrt((d * d).sum(1))
        B[:, :3] = -d / rng_[:, None]
        l = r - (rng_ + x[3])
        Ninv = np.linalg.inv(B.T @ (B * w_[:, None]))
        xh = Ninv @ (B.T @ (w_ * l))
        V = B @ xh - l
        T = V @ (w_ * V)
        F = B * w_[:, None]
        q = w_ - np.einsum("ij,jk,ik->i", F, Ninv, F)
        w = (w_ * V) / np.sqrt(q)
        if T < THRESHOLDS[len(r) - 4]:
            return x, excluded, w
        j = int(np.argmax(np.abs(w)))
        if abs(w[j]) <= k:
            return x, excluded, w
        excluded.append(active.pop(j))
    return None, excluded, None


def tight_problem(seed: int = 1):
    rng = np.random.default_rng(seed)
    n, m = 17, 20
    A = rng.normal(size=(n, n)) * 0.01
    Phi = np.eye(n) + A
    L = rng.normal(size=(n, n)) * 0.01
    Q = L @ L.T + np.eye(n) * 1e-6
    P = np.eye(n)
    H = rng.normal(size=(m, n))
    R = np.diag(rng.uniform(1, 9, m))
    x = np.zeros(n)
    z = H @ rng.normal(size=n) + rng.normal(size=m)
    return Phi, Q, P, H, R, x, z


def numpy_tight_epoch(Phi, Q, P, H, R, x, z, thr):
    x = Phi @ x
    P = Phi @ P @ Phi.T + Q
    r = z - H @ x
    PHt = P @ H.T
    A = H @ PHt + R
    c = np.linalg.cholesky(A)
    g = np.linalg.solve(c.T, np.linalg.solve(c, r))  # plain numpy (no scipy triangular solves)
    stat = r @ g
    K = PHt @ np.linalg.solve(c.T, np.linalg.solve(c, np.eye(len(r))))
    x = x + K @ r
    IKH = np.eye(len(x)) - K @ H
    P = IKH @ P @ IKH.T + K @ R @ K.T
    return x, P, stat < thr


def numpy_tight_epoch_sequential(Phi, Q, P, H, R, x, z, thr):
    """The same epoch as navfdi runs it: predict, then one scalar Joseph update per row
    (diagonal R), the statistic accumulated as sum(nu**2 / s) (= r' A^-1 r)."""
    x = Phi @ x
    P = Phi @ P @ Phi.T + Q
    stat = 0.0
    for i in range(len(z)):
        h = H[i]
        u = P @ h
        s = h @ u + R[i, i]
        nu = z[i] - h @ x
        stat += nu * nu / s
        k = u / s
        x = x + k * nu
        P = P - np.outer(k, u) - np.outer(u, k) + s * np.outer(k, k)
    P = 0.5 * (P + P.T)
    return x, P, stat < thr, stat


def main() -> None:
    rx, sats, rho, sig = scene()
    x0 = np.append(rx + [3.0, -2.0, 1.0], 100.0)
    ref = numpy_snapshot(sats, rho, sig, x0)
    got = navfdi.snapshot_fde(sats, rho, sig, k=1.6449, x0=x0)
    assert np.allclose(ref[0][:3], got.position, atol=1e-6) and ref[1] == got.excluded
    t_np = best(lambda: numpy_snapshot(sats, rho, sig, x0), 300)
    t_nv = best(lambda: navfdi.snapshot_fde(sats, rho, sig, k=1.6449, x0=x0), 3000)
    bad = rho.copy()
    bad[3] += 60.0
    t_np_x = best(lambda: numpy_snapshot(sats, bad, sig, x0), 300)
    t_nv_x = best(lambda: navfdi.snapshot_fde(sats, bad, sig, k=1.6449, x0=x0), 3000)
    prob = tight_problem()
    thr = float(stats.chi2.isf(0.05, 20))
    t_tight = best(lambda: numpy_tight_epoch(*prob, thr), 2000)
    xb, Pb, _ = numpy_tight_epoch(*prob, thr)
    xs, Ps, _, _ = numpy_tight_epoch_sequential(*prob, thr)
    assert np.allclose(xb, xs, atol=1e-9) and np.allclose(Pb, Ps, atol=1e-9)
    t_tight_seq = best(lambda: numpy_tight_epoch_sequential(*prob, thr), 500)
    sc = navfdi.load_scenario("shao2018").base().with_value("tight.fde", "innovation")
    js = sc.to_json()
    _core.run_scenario(js, 1, 0, [True])
    t_run = best(lambda: _core.run_scenario(js, 1, 0, [True]), 3, rounds=5) / 1000
    print(f"{'benchmark':<58}{'µs / call':>10}")
    print(f"{'numpy snapshot WLS + FDE, 10 satellites':<58}{t_np:>10.1f}")
    print(f"{'navfdi.snapshot_fde (Python call), 10 satellites':<58}{t_nv:>10.1f}   {t_np / t_nv:.1f}x numpy")
    print(f"{'numpy snapshot, one 60 m fault excluded':<58}{t_np_x:>10.1f}")
    print(f"{'navfdi.snapshot_fde, one 60 m fault excluded':<58}{t_nv_x:>10.1f}   {t_np_x / t_nv_x:.1f}x numpy")
    print(f"{'numpy tight epoch 17 x 20 (predict, test, Joseph update)':<58}{t_tight:>10.1f}")
    print(f"{'numpy tight epoch 17 x 20, row by row (as navfdi runs it)':<58}{t_tight_seq:>10.1f}")
    print(f"{'navfdi shao2018 run (innovation FDE) per epoch, via Python':<58}{t_run:>10.1f}   (simulation, record and metrics included)")


if __name__ == "__main__":
    main()
