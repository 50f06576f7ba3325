"""Units accepted at the scenario edge. Everything inside navfdi is SI and radians.

A dimensional value is written as a string ``"<number> <unit>"``, e.g. ``"0.01 deg/h"``,
``"0.0017 deg"``, ``"20 sigma"``. Bare numbers are refused for dimensional fields, so a unit
is never guessed.
"""

from __future__ import annotations

import math

_G0 = 9.80665

UNITS: dict[str, dict[str, float]] = {
    "angle": {"rad": 1.0, "mrad": 1e-3, "urad": 1e-6, "deg": math.pi / 180, "arcmin": math.pi / 180 / 60, "arcsec": math.pi / 180 / 3600},
    "angular_rate": {"rad/s": 1.0, "deg/s": math.pi / 180, "deg/h": math.pi / 180 / 3600, "rad/h": 1 / 3600},
    "acceleration": {"m/s2": 1.0, "m/s^2": 1.0, "g": _G0, "mg": _G0 * 1e-3, "ug": _G0 * 1e-6},
    "length": {"m": 1.0, "km": 1e3, "cm": 1e-2},
    "velocity": {"m/s": 1.0, "km/h": 1 / 3.6, "kn": 1852 / 3600},
    "time": {"s": 1.0, "ms": 1e-3, "min": 60.0, "h": 3600.0},
    "frequency": {"Hz": 1.0},
    "fraction": {"%": 0.01, "ppm": 1e-6},
    "length2_per_time": {"m^2/s": 1.0, "m2/s": 1.0},
    "length2_per_time3": {"m^2/s^3": 1.0, "m2/s3": 1.0},
    "carrier_to_noise": {"dB-Hz": 1.0},
    "chips2_per_time": {"chips^2/s": 1.0, "chip^2/s": 1.0},
    "frequency2_per_time3": {"Hz^2/s^3": 1.0},
    "angular_rate_density": {"rad/s/sqrt(Hz)": 1.0, "deg/s/sqrt(Hz)": math.pi / 180, "deg/h/sqrt(Hz)": math.pi / 180 / 3600, "deg/sqrt(h)": math.pi / 180 / 60, "rad/sqrt(s)": 1.0, "deg/sqrt(s)": math.pi / 180},
    "acceleration_density": {"m/s2/sqrt(Hz)": 1.0, "m/s^2/sqrt(Hz)": 1.0, "g/sqrt(Hz)": _G0, "mg/sqrt(Hz)": _G0 * 1e-3, "ug/sqrt(Hz)": _G0 * 1e-6,
                             # Velocity random walk, as datasheets give it: 1 m/s/√h = 1/60 m/s/√s.
                             "m/s/sqrt(h)": 1 / 60, "m/s/sqrt(s)": 1.0, "ft/s/sqrt(h)": 0.3048 / 60},
}


class UnitError(ValueError):
    """A value without a unit, with an unknown unit, or with a unit of the wrong kind."""


def parse(value: object, dimension: str, path: str) -> float:
    """Convert ``"<number> <unit>"`` of the given dimension to SI.

    Parameters
    ----------
    value : str
        E.g. ``"0.01 deg/h"``.
    dimension : str
        A key of :data:`UNITS`.
    path : str
        Field path used in error messages, e.g. ``"ins.gyro_bias"``.

    Returns
    -------
    float
        The value in SI units (radians for angles).
    """
    allowed = UNITS[dimension]
    if isinstance(value, bool) or not isinstance(value, str):
        raise UnitError(f"{path} = {value!r}: needs a unit, e.g. \"{value} {next(iter(allowed))}\" (units for {dimension}: {', '.join(allowed)})")
    parts = value.split()
    if len(parts) != 2:
        raise UnitError(f"{path} = {value!r}: expected \"<number> <unit>\" (units for {dimension}: {', '.join(allowed)})")
    try:
        number = float(parts[0])
    except ValueError:
        raise UnitError(f"{path} = {value!r}: {parts[0]!r} is not a number") from None
    unit = parts[1]
    if unit not in allowed:
        raise UnitError(f"{path} = {value!r}: unknown unit {unit!r} for {dimension} (use one of: {', '.join(allowed)})")
    if not math.isfinite(number):
        raise UnitError(f"{path} = {value!r}: must be finite")
    return number * allowed[unit]


def split(value: object, path: str) -> tuple[float, str]:
    """Split ``"<number> <unit>"`` into its number and unit without converting."""
    if isinstance(value, bool) or not isinstance(value, str) or len(value.split()) != 2:
        raise UnitError(f"{path} = {value!r}: expected \"<number> <unit>\"")
    number, unit = value.split()
    try:
        x = float(number)
    except ValueError:
        raise UnitError(f"{path} = {value!r}: {number!r} is not a number") from None
    if not math.isfinite(x):
        raise UnitError(f"{path} = {value!r}: must be finite")
    return x, unit
