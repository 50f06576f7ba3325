"""Geometry of a single-point solution: the σ of its position from the satellites it used."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["enu_sigma"]


def enu_sigma(sats: Any, n_epochs: int) -> np.ndarray:
    """σ (m) of each epoch's position east, north and up from its used satellites: the
    square roots of the diagonal of ``(Hᵀ W H)⁻¹`` with ``H`` the lines of sight and one clock
    per system, ``W = 1/σ²`` the weights of the solve (``satellites``: ``epoch``,
    ``satellite``, ``elevation``, ``azimuth`` in deg, ``sigma`` in m, ``status``). Shape
    (n_epochs, 3); NaN where fewer satellites than unknowns were used. The σ of the solve's
    noise model, not of its error: the range errors it leaves out (ionosphere, multipath)
    scale it (the loosely coupled filter estimates that scale, ``noise_scale``)."""
    out = np.full((n_epochs, 3), np.nan)
    used = sats[sats["status"] == "used"]
    if not len(used):
        return out
    ep = used["epoch"].to_numpy(np.int64)
    el, az = np.radians(used["elevation"].to_numpy(float)), np.radians(used["azimuth"].to_numpy(float))
    sysl = used["satellite"].astype(str).str[0].to_numpy()
    letters = sorted(set(sysl))
    p = 3 + len(letters)
    h = np.zeros((len(used), p))
    h[:, 0], h[:, 1], h[:, 2] = -np.cos(el) * np.sin(az), -np.cos(el) * np.cos(az), -np.sin(el)
    for j, s_ in enumerate(letters):
        h[sysl == s_, 3 + j] = 1.0
    w = 1.0 / used["sigma"].to_numpy(float) ** 2
    n = np.zeros((n_epochs, p, p))
    np.add.at(n, ep, w[:, None, None] * h[:, :, None] * h[:, None, :])
    count = np.bincount(ep, minlength=n_epochs)
    clocks = np.zeros(n_epochs, dtype=np.int64)
    for j, s_ in enumerate(letters):  # a system absent from an epoch: its clock decoupled
        present = np.bincount(ep[sysl == s_], minlength=n_epochs) > 0
        clocks += present
        n[~present, 3 + j, 3 + j] = 1.0
    ok = (count >= 3 + clocks) & np.isfinite(n).all(axis=(1, 2))
    for i in np.flatnonzero(ok):
        try:
            c = np.linalg.inv(n[i])
        except np.linalg.LinAlgError:
            continue
        d = np.diag(c)[:3]
        if (d > 0).all():
            out[i] = np.sqrt(d)
    return out
