"""Plausibility of a scenario's terrain: warnings for a terrain no planet has and for a
trajectory that passes below it (a radio altimeter there reads nonsense)."""

from __future__ import annotations

import math
from typing import Any

from navfdi import _core
from navfdi._errors import ScenarioWarning

#: Highest terrain on Earth (m): Everest, 8 849 m.
MAX_TERRAIN = 8849.0


def check_terrain(core: dict[str, Any], text: str) -> None:
    """Warn (:class:`ScenarioWarning`) about a terrain no planet has (a wave amplitude above
    Everest) and a trajectory that passes below its terrain (a radio altimeter there reads
    nonsense, and its statistics explode)."""
    import warnings

    import numpy as np

    waves = core["terrain"]["waves"]
    for i, w in enumerate(waves):
        if w["amplitude"] > MAX_TERRAIN:
            warnings.warn(f"terrain.waves[{i}].amplitude = {w['amplitude']:g} m is higher than any terrain on Earth (Everest: {MAX_TERRAIN:g} m)", ScenarioWarning, stacklevel=4)
    tr = _core.scenario_trajectory(text)
    lat, lon, h, t = tr["lat"], tr["lon"], tr["h"], tr["t"]
    if not len(t):
        return
    a, e2 = 6378137.0, 6.69437999014e-3
    s2 = math.sin(lat[0]) ** 2
    rm = a * (1 - e2) / (1 - e2 * s2) ** 1.5 + h[0]
    rn = (a / math.sqrt(1 - e2 * s2) + h[0]) * math.cos(lat[0])
    east, north = (lon - lon[0]) * rn, (lat - lat[0]) * rm
    ground = sum(w["amplitude"] * np.sin(2 * math.pi * (east * math.sin(w["heading"]) + north * math.cos(w["heading"])) / w["wavelength"] + w["phase"]) for w in waves)
    below = np.flatnonzero(h < ground)
    if below.size:
        k = int(below[0])
        warnings.warn(
            f"the trajectory passes below the terrain: at t = {t[k]:g} s it is {ground[k] - h[k]:.1f} m under the ground "
            f"({below.size} of {len(t)} epochs); raise trajectory.height or lower terrain.waves[].amplitude",
            ScenarioWarning,
            stacklevel=4,
        )
