"""The forms an RTKLIB solution file (``.pos``) comes in, turned into the one
:func:`navfdi.logs.read_pos` returns (GPST, latitude/longitude in degrees, σ and velocity
east/north/up):

* time in GPST, UTC or JST (RTKLIB ``out-timesys``; ``rnx2rtkp -u``): UTC and JST become GPST
  with the leap seconds of their date (:func:`navfdi._logtime.utc_count_to_gps`);
* positions as latitude/longitude/height in decimal degrees, in degrees-minutes-seconds
  (``out-degform = dms``, ``rnx2rtkp -g``: three tokens per angle, the sign on the degrees,
  ``-0`` included) or as ECEF x/y/z (``out-solformat = xyz``, ``rnx2rtkp -e``): converted on
  the WGS-84 ellipsoid, the σ ``sdx … sdzx`` (RTKLIB's signed square roots of the covariance)
  and the velocities ``vx … sdvzx`` rotated to east/north/up at each epoch's position.

Baselines (``e-baseline``, ``rnx2rtkp -a``) need the base's position and are refused.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from navfdi._errors import ScenarioError
from navfdi._logtime import utc_count_to_gps

__all__ = ["PosForm", "pos_form"]

_DMS = "latitude(d'\")", "longitude(d'\")"
_TIME_SCALES = {"GPST": 0.0, "UTC": 0.0, "JST": 9 * 3600.0}


class PosForm:
    """A ``.pos`` header's form: ``scale`` (``"GPST"``, ``"UTC"``, ``"JST"``), ``angles``
    (``"deg"``, ``"dms"``, ``"xyz"``), ``fields`` (the header's names after the time) and
    ``tokens`` (the names of the data tokens after the two time tokens: a dms angle is three)."""

    def __init__(self, scale: str, angles: str, fields: Sequence[str]):
        self.scale, self.angles, self.fields = scale, angles, list(fields)
        self.tokens: list[str] = []
        for name in self.fields:
            if name in _DMS:
                self.tokens += [f"{name[:-5]}(deg)", f"{name[:-5]}(arcmin)", f"{name[:-5]}(arcsec)"]
            else:
                self.tokens.append(name)

    def gpst(self, t: np.ndarray) -> np.ndarray:
        """GPS seconds of the file's times ``t`` (seconds on the GPS epoch's count, in the file's
        time scale)."""
        if self.scale == "GPST":
            return t
        return utc_count_to_gps(t - _TIME_SCALES[self.scale])

    def columns(self, path: Path, col: dict[str, np.ndarray], line_of: Sequence[int]) -> dict[str, np.ndarray]:
        """The columns by the names of the latitude/longitude form (``latitude(deg)``, ``sde(m)``,
        ``ve(m/s)``, ``sdve`` …) from the file's ``col`` (by token name)."""
        if self.angles == "deg":
            return col
        out = dict(col)
        if self.angles == "dms":
            for name in ("latitude", "longitude"):
                d, m, s = (out.pop(f"{name}({u})") for u in ("deg", "arcmin", "arcsec"))
                for part, v in (("arcmin", m), ("arcsec", s)):
                    bad = ~((v >= 0.0) & (v < 60.0 + 1e-9))
                    if bad.any():
                        k = int(np.argmax(bad))
                        raise ScenarioError(f"{path}, line {line_of[k]}, column {name!r}: {part} {float(v[k])!r} is outside [0, 60)")
                out[f"{name}(deg)"] = np.copysign(np.abs(d) + m / 60.0 + s / 3600.0, d)
            return out
        from navfdi.gnss import ecef_to_lla, enu_rotation

        xyz = np.column_stack([out.pop(f"{c}-ecef(m)") for c in "xyz"])
        lla = ecef_to_lla(xyz)
        out["latitude(deg)"], out["longitude(deg)"], out["height(m)"] = lla[:, 0], lla[:, 1], lla[:, 2]
        r = enu_rotation(lla[:, 0], lla[:, 1])
        for prefix, unit, names in (("sd", "(m)", ("sde(m)", "sdn(m)", "sdu(m)")), ("sdv", "", ("sdve", "sdvn", "sdvu"))):
            c = _covariance(out, prefix, unit)
            if c is not None:
                enu = np.einsum("kij,kjl,kml->kim", r, c, r)
                for j, name in enumerate(names):
                    out[name] = np.sqrt(np.maximum(enu[:, j, j], 0.0))
        vel = [out[f"v{c}(m/s)"] for c in "xyz" if f"v{c}(m/s)" in out]
        if len(vel) == 3:
            venu = np.einsum("kij,kj->ki", r, np.column_stack(vel))
            out["ve(m/s)"], out["vn(m/s)"], out["vu(m/s)"] = venu[:, 0], venu[:, 1], venu[:, 2]
        return out


def _covariance(col: dict[str, np.ndarray], prefix: str, unit: str) -> np.ndarray | None:
    """(M, 3, 3) ECEF covariance from RTKLIB's σ ``{prefix}x{unit}`` … and signed square roots
    ``{prefix}xy{unit}``, ``{prefix}yz{unit}``, ``{prefix}zx{unit}``; None without them."""
    names = [f"{prefix}{k}{unit}" for k in ("x", "y", "z", "xy", "yz", "zx")]
    if not all(n in col for n in names):
        return None
    sx, sy, sz, sxy, syz, szx = (col[n] for n in names)
    cxy, cyz, czx = (np.sign(s) * s * s for s in (sxy, syz, szx))
    return np.stack([np.stack([sx * sx, cxy, czx], -1), np.stack([cxy, sy * sy, cyz], -1), np.stack([czx, cyz, sz * sz], -1)], -2)


def pos_form(path: Path, head: Sequence[str]) -> PosForm:
    """The form of a ``.pos`` file from its header lines ``head`` (those starting with ``%``);
    :class:`~navfdi.ScenarioError` naming the file for a form that cannot be read."""
    names = None
    for ln in head:
        if ("latitude" in ln and "longitude" in ln) or "x-ecef" in ln:
            names = ln[1:].split()
    if names is None:
        if any("e-baseline" in ln for ln in head):
            raise ScenarioError(f"{path}: baselines (east/north/up from a base station); write the solution as latitude/longitude/height or ECEF x/y/z (RTKLIB out-solformat = llh or xyz)")
        raise ScenarioError(f"{path}: no '% ... latitude(deg) longitude(deg) height(m)' (or x-ecef(m) y-ecef(m) z-ecef(m)) header line: not an RTKLIB solution file")
    scale = names[0]
    if scale not in _TIME_SCALES:
        raise ScenarioError(f"{path}: time column {scale!r}; GPST, UTC or JST expected (RTKLIB out-timesys)")
    fields = names[1:]
    if "x-ecef(m)" in fields:
        missing = [n for n in ("x-ecef(m)", "y-ecef(m)", "z-ecef(m)") if n not in fields]
        if missing:
            raise ScenarioError(f"{path}: header without {', '.join(missing)}")
        return PosForm(scale, "xyz", fields)
    if any(n in _DMS for n in fields):
        return PosForm(scale, "dms", fields)
    if any("'" in n for n in fields[:2]):
        raise ScenarioError(f"{path}: latitude and longitude in a form not known ({fields[0]} {fields[1]}); decimal degrees or RTKLIB's degrees-minutes-seconds expected")
    return PosForm(scale, "deg", fields)
