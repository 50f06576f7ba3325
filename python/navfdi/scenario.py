"""Scenarios: one schema, read from TOML (or the same structure from Python), validated.

Dimensional values carry explicit units (``"0.0017 deg"``, ``"0.01 deg/h"``, ``"20 sigma"``;
see :mod:`navfdi.units`). :func:`load_scenario` converts the user's structure to the SI form the
Rust core runs (``Scenario.core``); structural and unit problems raise :class:`ScenarioError`
naming the field path and value (``faults[1].magnitude = '20 furlongs': unknown unit ...``),
and the core then checks the semantics (sensor references, shares summing to one, ...) with
the same path spelling.

Fault magnitudes use the unit of the faulted component (angle for ``cns``, length for
positions, velocity for velocities), per second for ramps and per second squared for
quadratics, or multiples of the sensor's noise σ of that component: ``"20 sigma"``,
``"0.1 sigma/s"``, ``"0.001 sigma/s2"``.
"""

from __future__ import annotations

import copy
import json
import math
import re
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from navfdi import _core
from navfdi._errors import ImuClippingWarning, ImuGapWarning, LeftOutFixesWarning, LeftOutSamplesWarning, NeverAppliedWarning, PartialLogWarning, ScenarioError, ScenarioTooLarge, ScenarioWarning
from navfdi._bundled import bundled_scenarios, bundled_toml
from navfdi._logtime import resolve_log_times
from navfdi._terrain import check_terrain
from navfdi.units import UNITS, UnitError, split
from navfdi._fields import _bool, _check_keys, _count, _detectors, _list, _name, _need, _number, _str, _unit
from navfdi._lc_schema import _loosely_coupled, _tight, _ultra_tight, apply_range_errors, gauss_markov_share


#: Component names and dimensions per sensor kind (order = measurement order).
SENSOR_COMPONENTS: dict[str, list[tuple[str, str]]] = {
    "cns": [("phi_e", "angle"), ("phi_n", "angle"), ("phi_u", "angle")],
    "gnss": [("pos_e", "length"), ("pos_n", "length"), ("pos_u", "length"), ("vel_e", "velocity"), ("vel_n", "velocity"), ("vel_u", "velocity")],
    "gnss_position": [("pos_e", "length"), ("pos_n", "length"), ("pos_u", "length")],
    "gnss_velocity": [("vel_e", "velocity"), ("vel_n", "velocity"), ("vel_u", "velocity")],
    "baro": [("h", "length")],
    "vision": [("pos_e", "length"), ("pos_n", "length"), ("pos_u", "length")],
    "gnss_ranges": [("pseudorange", "length"), ("rate", "velocity")],
    "radio_altimeter": [("h", "length")],
}


def _terrain(t: Any) -> dict[str, Any]:
    """The ``[terrain]`` table: ``waves`` of amplitude, wavelength, heading, phase."""
    _check_keys(t, "terrain", "terrain")
    waves = []
    for i, w in enumerate(_list(_need(t, "waves", "terrain"), "terrain.waves")):
        p = f"terrain.waves[{i}]"
        _check_keys(w, "terrain.waves", p)
        waves.append(
            {
                "amplitude": _unit(_need(w, "amplitude", p), "length", f"{p}.amplitude"),
                "wavelength": _unit(_need(w, "wavelength", p), "length", f"{p}.wavelength"),
                "heading": _unit(w.get("heading", "0 deg"), "angle", f"{p}.heading"),
                "phase": _unit(w.get("phase", "0 deg"), "angle", f"{p}.phase"),
            }
        )
    return {"waves": waves}

_CLOCK = {"bias": "length", "drift": "velocity", "bias_psd": "length2_per_time", "drift_psd": "length2_per_time3"}


def _ranges(r: Any, p: str) -> dict[str, Any]:
    """The ``ranges`` table of a ``gnss_ranges`` sensor at path ``p``."""
    _check_keys(r, "sensors.ranges", p)
    systems = []
    for j, sys_ in enumerate(_list(r.get("systems", ["gps"]), f"{p}.systems")):
        name = _str(sys_, f"{p}.systems[{j}]")
        if name not in ("gps", "galileo"):
            raise ScenarioError(f"{p}.systems[{j}] = {name!r}: use gps or galileo")
        systems.append(name)
    en = _bool(r.get("elevation_noise", False), f"{p}.elevation_noise")
    clock = _need(r, "clock", p)
    _check_keys(clock, "sensors.ranges.clock", f"{p}.clock")
    return {
        "systems": systems,
        "elevation_mask": _unit(_need(r, "elevation_mask", p), "angle", f"{p}.elevation_mask"),
        "elevation_noise": en,
        "epoch": _unit(r.get("epoch", "0 s"), "time", f"{p}.epoch"),
        "clock": {k: _unit(_need(clock, k, f"{p}.clock"), dim, f"{p}.clock.{k}") for k, dim in _CLOCK.items()},
        "cn0_reference": None if "cn0_reference" not in r else _unit(r["cn0_reference"], "carrier_to_noise", f"{p}.cn0_reference"),
        "correlated": None if "correlated" not in r else _correlated(r["correlated"], f"{p}.correlated"),
    }


def _correlated(c: Any, p: str) -> dict[str, float]:
    """A simulated ``gnss_ranges`` sensor's ``correlated`` table: ``fraction`` of each
    pseudorange's variance (σ by elevation, squared) in [0, 1) that is a first-order
    Gauss-Markov process per satellite, of correlation time ``tau``."""
    if not isinstance(c, dict):
        raise ScenarioError(f"{p} = {c!r}: expected a table {{ fraction = 0.5, tau = \"10 s\" }}")
    _check_keys(c, "sensors.ranges.correlated", p)
    return gauss_markov_share(c, p)


def _waypoints(tr: Mapping[str, Any], duration: float) -> dict[str, Any]:
    """``[trajectory]`` given as ``waypoints`` ``[[east, north, up], ...]`` (with units) in a
    local ENU frame around ``latitude``, ``longitude``, ``height`` (the reference point), flown
    at ground ``speed`` with turns at ``turn_rate`` (default 30 deg/s) → the segment form:
    start at the first waypoint heading for the second at ``speed``; at each intermediate
    waypoint a level coordinated turn centred on it (radius r = speed / turn_rate, passing
    r·(1/cos(Δψ/2) − 1) from it); straight level, climb or descent segments between the turns
    (height changes happen on the straights, so the height at each waypoint is exact); a stop
    at 1 m/s² (or less) ending on the last waypoint, then rest until the end of the run
    (``duration``, s). Local distances use
    the radii of curvature at the reference."""
    _check_keys(tr, "trajectory_waypoints", "trajectory")
    lat0 = _unit(_need(tr, "latitude", "trajectory"), "angle", "trajectory.latitude")
    lon0 = _unit(_need(tr, "longitude", "trajectory"), "angle", "trajectory.longitude")
    h0 = _unit(_need(tr, "height", "trajectory"), "length", "trajectory.height")
    speed = _unit(_need(tr, "speed", "trajectory"), "velocity", "trajectory.speed")
    if not speed > 0:
        raise ScenarioError(f"trajectory.speed = {tr['speed']!r}: waypoints are flown at a positive ground speed")
    rate = _unit(tr.get("turn_rate", "30 deg/s"), "angular_rate", "trajectory.turn_rate")
    if not rate > 0:
        raise ScenarioError(f"trajectory.turn_rate = {tr.get('turn_rate')!r}: must be positive")
    pts = []
    for i, w in enumerate(_list(_need(tr, "waypoints", "trajectory"), "trajectory.waypoints")):
        w = _list(w, f"trajectory.waypoints[{i}]")
        if len(w) != 3:
            raise ScenarioError(f"trajectory.waypoints[{i}] = {w!r}: expected [east, north, up] with units")
        pts.append([_unit(v, "length", f"trajectory.waypoints[{i}][{j}]") for j, v in enumerate(w)])
    if len(pts) < 2:
        raise ScenarioError("trajectory.waypoints: at least two waypoints are required")
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    s2 = math.sin(lat0) ** 2
    rm = a * (1 - e2) / (1 - e2 * s2) ** 1.5 + h0
    rn = (a / math.sqrt(1 - e2 * s2) + h0) * math.cos(lat0)
    legs = []
    for i in range(len(pts) - 1):
        de, dn, du = (pts[i + 1][j] - pts[i][j] for j in range(3))
        horiz = math.hypot(de, dn)
        if horiz < 1e-6:
            raise ScenarioError(f"trajectory.waypoints[{i + 1}]: same horizontal position as waypoint {i}; a leg needs a horizontal length")
        legs.append((horiz, math.atan2(de, dn), du))
    # Turns are centred on the waypoints: each starts `lead` = r·tan(|Δψ|/2) before it (r =
    # speed / turn_rate) and the leg after it starts `lead` after it; the stop ends on the last.
    radius = speed / rate
    dpsi = [0.0] + [(legs[i][1] - legs[i - 1][1] + math.pi) % (2 * math.pi) - math.pi for i in range(1, len(legs))] + [0.0]
    lead = [radius * math.tan(abs(d) / 2) for d in dpsi]
    decel = min(1.0, speed)
    stop = speed * speed / (2 * decel)
    segs: list[dict[str, str]] = []
    for i, (horiz, _, du) in enumerate(legs):
        if i > 0 and abs(dpsi[i]) > 1e-9:
            segs.append({"kind": "turn", "duration": f"{abs(dpsi[i]) / rate!r} s", "rate": f"{math.copysign(rate, dpsi[i])!r} rad/s"})
        straight = horiz - lead[i] - lead[i + 1] - (stop if i == len(legs) - 1 else 0.0)
        if straight <= 1e-6:
            raise ScenarioError(
                f"trajectory.waypoints[{i + 1}]: the leg from waypoint {i} ({horiz:.3g} m) is too short for the turns "
                f"(radius speed / turn_rate = {radius:.3g} m) and the stop; lower the speed or raise turn_rate"
            )
        dur = straight / speed
        if abs(du) < 1e-9:
            segs.append({"kind": "level", "duration": f"{dur!r} s"})
        else:
            segs.append({"kind": "climb" if du > 0 else "descent", "duration": f"{dur!r} s", "rate": f"{abs(du) / dur!r} m/s"})
    segs.append({"kind": "accelerate", "duration": f"{speed / decel!r} s", "acceleration": f"{-decel!r} m/s2"})
    first = legs[0][1]
    flown = sum(float(sg["duration"].split()[0]) for sg in segs)
    segs.append({"kind": "stationary", "duration": f"{max(duration - flown, 1.0)!r} s"})
    e0, n0, u0 = pts[0]
    return {
        "latitude": f"{lat0 + n0 / rm!r} rad",
        "longitude": f"{lon0 + e0 / rn!r} rad",
        "height": f"{h0 + u0!r} m",
        "heading": f"{first!r} rad",
        "speed": f"{speed!r} m/s",
        "segments": segs,
    }


_SEGMENTS: dict[str, dict[str, str]] = {
    "stationary": {"duration": "time"},
    "accelerate": {"duration": "time", "acceleration": "acceleration"},
    "climb": {"duration": "time", "rate": "velocity"},
    "level": {"duration": "time"},
    "turn": {"duration": "time", "rate": "angular_rate"},
    "descent": {"duration": "time", "rate": "velocity"},
}

_INS = {
    "gyro_bias": "angular_rate",
    "gyro_white": "angular_rate",
    "gyro_markov": "angular_rate",
    "gyro_tau": "time",
    "accel_markov": "acceleration",
    "accel_tau": "time",
    "init_level": "angle",
    "init_heading": "angle",
    "init_velocity": "velocity",
    "init_position": "length",
}


#: Top-level fields a variant may override: the filter, never what is simulated.
VARIANT_FIELDS = ("architecture", "federated", "centralized", "tight", "ultra_tight", "loosely_coupled", "state_chi2")

#: Names of the filter states, in order (15 INS error states; 17 with a receiver clock).
STATE_NAMES = ["att_e", "att_n", "att_u", "vel_e", "vel_n", "vel_u", "lat", "lon", "h", "gyro_x", "gyro_y", "gyro_z", "acc_x", "acc_y", "acc_z", "clock_bias", "clock_drift"]


def _modes(m: Any) -> dict[str, Any]:
    """The ``[modes]`` table: gnss (sensor), target [east, north], radius, q1, q2, q3."""
    _check_keys(m, "modes", "modes")
    target = _list(_need(m, "target", "modes"), "modes.target")
    if len(target) != 2:
        raise ScenarioError(f"modes.target = {target!r}: expected [east, north] with units")
    out: dict[str, Any] = {
        "gnss": _str(_need(m, "gnss", "modes"), "modes.gnss"),
        "target": [_unit(v, "length", f"modes.target[{i}]") for i, v in enumerate(target)],
        "radius": _unit(_need(m, "radius", "modes"), "length", "modes.radius"),
    }
    for q in ("q1", "q2", "q3"):
        out[q] = [_str(v, f"modes.{q}[{i}]") for i, v in enumerate(_list(_need(m, q, "modes"), f"modes.{q}"))]
    return out


def _state_chi2(sc: Any) -> dict[str, Any]:
    """The ``[state_chi2]`` table: pf, reset_every, min_age (times), states (names)."""
    _check_keys(sc, "state_chi2", "state_chi2")
    reset = _unit(_need(sc, "reset_every", "state_chi2"), "time", "state_chi2.reset_every")
    states = None
    if "states" in sc:
        states = []
        for i, name in enumerate(_list(sc["states"], "state_chi2.states")):
            name = _str(name, f"state_chi2.states[{i}]")
            if name not in STATE_NAMES:
                raise ScenarioError(f"state_chi2.states[{i}] = {name!r}: not a state (use {', '.join(STATE_NAMES)})")
            states.append(STATE_NAMES.index(name))
    return {
        "pf": _number(_need(sc, "pf", "state_chi2"), "state_chi2.pf"),
        "reset_every": reset,
        "min_age": _unit(sc.get("min_age", f"{reset!r} s"), "time", "state_chi2.min_age"),
        "states": states,
    }


def _centralized(c: Any) -> dict[str, Any]:
    _check_keys(c, "centralized", "centralized")
    policy = _str(_need(c, "policy", "centralized"), "centralized.policy")
    if policy not in ("exclude", "latched", "fading"):
        raise ScenarioError(f"centralized.policy = {policy!r}: use exclude, latched or fading")
    sensors = []
    for i, cs in enumerate(_list(_need(c, "sensors", "centralized"), "centralized.sensors")):
        p = f"centralized.sensors[{i}]"
        _check_keys(cs, "centralized.sensors", p)
        dec = cs.get("decision")
        sensors.append(
            {
                "sensor": _str(_need(cs, "sensor", p), f"{p}.sensor"),
                "detectors": _detectors(cs.get("detectors", []), p),
                "decision": None if dec is None else _str(dec, f"{p}.decision"),
            }
        )
    out = {
        "policy": policy,
        "sensors": sensors,
        "fading": _number(c.get("fading", 1.0), "centralized.fading"),
        "fading_duration": _unit(c.get("fading_duration", "0 s"), "time", "centralized.fading_duration"),
        "confirm": _unit(c.get("confirm", "0 s"), "time", "centralized.confirm"),
    }
    if "altitude_fusion" in c:
        out["altitude_fusion"] = _altitude_fusion(c["altitude_fusion"])
    if "isolate" in c:
        out["isolate"] = _bool(c["isolate"], "centralized.isolate")
    return out


def _per_component(value: Any, comps: list[tuple[str, str]], kind: str, path: str, positive: bool) -> list[float]:
    """A sensor's per-component σ (``noise`` > 0, ``bias`` ≥ 0): one value for every
    component or one per component, in the components' units."""
    values = value if isinstance(value, list) else [value] * len(comps)
    if len(values) != len(comps):
        raise ScenarioError(
            f"{path}: {len(values)} values for a {kind} sensor with {len(comps)} components ({', '.join(c for c, _ in comps)}); give one value or one per component"
        )
    out = []
    for j, (v, (_, dim)) in enumerate(zip(values, comps)):
        vp = f"{path}[{j}]" if isinstance(value, list) else path
        x = _unit(v, dim, vp)
        if not (x > 0 if positive else x >= 0):
            raise ScenarioError(f"{vp} = {v!r}: a {'noise' if positive else 'bias'} standard deviation must be {'positive' if positive else 'zero or positive'}")
        out.append(x)
    return out


def _altitude_fusion(a: Any) -> dict[str, Any]:
    """``centralized.altitude_fusion``: sensors (names), samples (window N), estimate
    (``mean_square``, default, or ``variance`` as paper 003's eq. 35)."""
    p = "centralized.altitude_fusion"
    _check_keys(a, "centralized.altitude_fusion", p)
    estimate = _str(a.get("estimate", "mean_square"), f"{p}.estimate")
    if estimate not in ("mean_square", "variance"):
        raise ScenarioError(f"{p}.estimate = {estimate!r}: use mean_square or variance")
    return {
        "sensors": [_str(v, f"{p}.sensors[{i}]") for i, v in enumerate(_list(_need(a, "sensors", p), f"{p}.sensors"))],
        "samples": _count(a.get("samples", 20), f"{p}.samples"),
        "estimate": estimate,
    }


def _magnitude(mag_raw: Any, kind: str, comps: list[tuple[str, str]], idx: list[int], noise: list[float], sensor: str, p: str) -> float:
    """A fault magnitude in SI: the faulted components' unit (per s for ramps, per s² for
    quadratics) or a multiple of the sensor's noise σ (``p``: the field path)."""
    per = {"step": "", "ramp": "/s", "quadratic": "/s2"}
    try:
        number, unit = split(mag_raw, f"{p}.magnitude")
    except UnitError as e:
        raise ScenarioError(str(e)) from None
    suffix = per[kind]
    dims_early = {d for _, d in (comps[j] for j in idx)}
    if dims_early == {"velocity"} and kind != "step":
        # A velocity ramp (quadratic) is a velocity per second (squared): m/s² (m/s³).
        alias = {"ramp": {"m/s2": "m/s/s", "m/s^2": "m/s/s", "m/s²": "m/s/s"}, "quadratic": {"m/s3": "m/s/s2", "m/s^3": "m/s/s2", "m/s³": "m/s/s2"}}[kind]
        unit = alias.get(unit, unit)
    if not unit.endswith(suffix) or (suffix == "/s" and unit.endswith("/s2")):
        raise ScenarioError(f"{p}.magnitude = {mag_raw!r}: a {kind} needs a unit ending in {suffix!r}" if suffix else f"{p}.magnitude = {mag_raw!r}: a step takes a plain unit (no /s)")
    base = unit[: len(unit) - len(suffix)] if suffix else unit
    dims = {d for _, d in (comps[j] for j in idx)}
    if base == "sigma":
        sig = [noise[j] for j in idx]
        if max(sig) - min(sig) > 1e-12 * max(sig):
            raise ScenarioError(f"{p}.magnitude = {mag_raw!r}: components with different noise cannot share a sigma magnitude; split the fault")
        return number * sig[0]
    else:
        if len(dims) != 1:
            raise ScenarioError(f"{p}.components: mixes {', '.join(sorted(dims))}; split the fault or use a sigma magnitude")
        dim = dims.pop()
        if base not in UNITS[dim]:
            if kind == "step":
                want = ", ".join(UNITS[dim])
            elif dim == "velocity":
                want = "m/s2" if kind == "ramp" else "m/s3"
            else:
                want = ", ".join(f"{u}{suffix}" for u in UNITS[dim])
            what = {"step": dim, "ramp": f"{dim} per second", "quadratic": f"{dim} per second squared"}[kind]
            raise ScenarioError(f"{p}.magnitude = {mag_raw!r}: unknown unit {base!r} for {what}: a {kind} on {sensor}'s {dim} component(s) takes {want} (or sigma{suffix})")
        return number * UNITS[dim][base]


def _component_set(v: Any, names: list[str], p: str) -> list[int]:
    idx: list[int] = []
    for j, c in enumerate(_list(v, p)):
        if c not in names:
            raise ScenarioError(f"{p}[{j}] = {c!r}: not a component ({', '.join(names)})")
        if names.index(c) in idx:
            raise ScenarioError(f"{p}[{j}] = {c!r}: listed twice")
        idx.append(names.index(c))
    if not idx:
        raise ScenarioError(f"{p}: at least one component is required")
    return idx


def _draw(d: Any, p: str, comps: list[tuple[str, str]], names: list[str], noise: list[float], sensor: str, own: list[int]) -> dict[str, Any]:
    """``faults[i].draw``: what a Monte-Carlo campaign on recorded logs draws per run —
    ``start = [lo, hi]`` (the window's length kept), ``components = [[...], ...]`` (sets to
    choose from), ``shapes = [{kind, magnitude = [lo, hi]}, ...]`` and ``satellites``
    (names to choose from, a satellite fault on raw GNSS logs)."""
    q = f"{p}.draw"
    _check_keys(d, "faults.draw", q)
    out: dict[str, Any] = {"start": None, "components": [], "shapes": [], "satellites": []}
    for j, sat in enumerate(_list(d.get("satellites", []), f"{q}.satellites")):
        out["satellites"].append(_str(sat, f"{q}.satellites[{j}]"))
    if "start" in d:
        r = _list(d["start"], f"{q}.start")
        if len(r) != 2:
            raise ScenarioError(f"{q}.start: expected [low, high], got {r!r}")
        out["start"] = [_unit(r[0], "time", f"{q}.start[0]"), _unit(r[1], "time", f"{q}.start[1]")]
    for j, cs in enumerate(_list(d.get("components", []), f"{q}.components")):
        out["components"].append(_component_set(cs, names, f"{q}.components[{j}]"))
    sets = out["components"] or [own]
    for j, sh in enumerate(_list(d.get("shapes", []), f"{q}.shapes")):
        sp = f"{q}.shapes[{j}]"
        _check_keys(sh, "faults.draw.shapes", sp)
        kind = _str(_need(sh, "kind", sp), f"{sp}.kind")
        if kind not in ("step", "ramp", "quadratic"):
            raise ScenarioError(f"{sp}.kind = {kind!r}: use step, ramp or quadratic")
        r = _list(_need(sh, "magnitude", sp), f"{sp}.magnitude")
        if len(r) != 2:
            raise ScenarioError(f"{sp}.magnitude: expected [low, high], got {r!r}")
        lo, hi = (_magnitude(v, kind, comps, sets[0], noise, sensor, sp) for v in r)
        out["shapes"].append([kind, [lo, hi]])
    return out


def _sensors_and_faults(raw: Mapping[str, Any], core: dict[str, Any]) -> None:
    """Convert ``[[sensors]]`` and ``[[faults]]`` into ``core``."""
    sensors = []
    noise_si: dict[str, list[float]] = {}
    kinds: dict[str, str] = {}
    for i, s in enumerate(_list(_need(raw, "sensors", ""), "sensors")):
        p = f"sensors[{i}]"
        _check_keys(s, "sensors", p)
        name = _name(_need(s, "name", p), f"{p}.name")
        kind = _str(_need(s, "kind", p), f"{p}.kind")
        if kind not in SENSOR_COMPONENTS:
            raise ScenarioError(f"{p}.kind = {kind!r}: unknown sensor (use one of: {', '.join(SENSOR_COMPONENTS)})")
        comps = SENSOR_COMPONENTS[kind]
        noise = _need(s, "noise", p)
        ns = _per_component(noise, comps, kind, f"{p}.noise", positive=True)
        bias = [] if "bias" not in s else _per_component(s["bias"], comps, kind, f"{p}.bias", positive=False)
        outages = []
        for j, w in enumerate(_list(s.get("outages", []), f"{p}.outages")):
            w = _list(w, f"{p}.outages[{j}]")
            if len(w) != 2:
                raise ScenarioError(f"{p}.outages[{j}]: expected [start, end], got {w!r}")
            outages.append([_unit(w[0], "time", f"{p}.outages[{j}][0]"), _unit(w[1], "time", f"{p}.outages[{j}][1]")])
        entry: dict[str, Any] = {"name": name, "kind": kind, "noise": ns, "rate": _unit(_need(s, "rate", p), "frequency", f"{p}.rate"), "outages": outages}
        if bias:
            entry["bias"] = bias
        if "proportional_noise" in s:
            if kind != "radio_altimeter":
                raise ScenarioError(f"{p}.proportional_noise: only a radio_altimeter's noise scales with the height above the terrain (this one is {kind})")
            frac = _unit(s["proportional_noise"], "fraction", f"{p}.proportional_noise")
            if not 0 < frac < 1:
                raise ScenarioError(f"{p}.proportional_noise = {s['proportional_noise']!r}: must be between 0 % and 100 % (exclusive)")
            entry["proportional_noise"] = frac
        if kind == "gnss_ranges":
            entry["ranges"] = _ranges(_need(s, "ranges", p), f"{p}.ranges")
        elif "ranges" in s:
            raise ScenarioError(f"{p}.ranges: only a gnss_ranges sensor has satellites (this one is {kind})")
        sensors.append(entry)
        noise_si[name] = ns
        kinds[name] = kind
    core["sensors"] = sensors

    faults = []
    for i, f in enumerate(_list(raw.get("faults", []), "faults")):
        p = f"faults[{i}]"
        _check_keys(f, "faults", p)
        sensor = _str(_need(f, "sensor", p), f"{p}.sensor")
        if sensor not in kinds:
            raise ScenarioError(f"{p}.sensor = {sensor!r}: not a sensor (known: {', '.join(repr(k) for k in kinds)})")
        comps = SENSOR_COMPONENTS[kinds[sensor]]
        names = [c for c, _ in comps]
        want = _need(f, "components", p)
        if want == "all":
            idx = list(range(len(comps)))
        else:
            idx = []
            for j, c in enumerate(_list(want, f"{p}.components")):
                if c not in names:
                    raise ScenarioError(f"{p}.components[{j}] = {c!r}: not a component of {sensor} ({', '.join(names)})")
                if names.index(c) in idx:
                    raise ScenarioError(f"{p}.components[{j}] = {c!r}: listed twice (the fault would be added twice)")
                idx.append(names.index(c))
            if not idx:
                raise ScenarioError(f"{p}.components: at least one component is required (or \"all\")")
        kind = _str(_need(f, "kind", p), f"{p}.kind")
        per = {"step": "", "ramp": "/s", "quadratic": "/s2"}
        if kind not in per:
            raise ScenarioError(f"{p}.kind = {kind!r}: use step, ramp or quadratic")
        magnitude = _magnitude(_need(f, "magnitude", p), kind, comps, idx, noise_si[sensor], sensor, p)
        fault: dict[str, Any] = {
                "id": _name(_need(f, "id", p), f"{p}.id"),
                "sensor": sensor,
                "components": idx,
                "kind": kind,
                "magnitude": magnitude,
                "start": _unit(_need(f, "start", p), "time", f"{p}.start"),
                "end": _unit(_need(f, "end", p), "time", f"{p}.end"),
        }
        if "satellite" in f:
            fault["satellite"] = _name(f["satellite"], f"{p}.satellite")
        if "draw" in f:
            fault["draw"] = _draw(f["draw"], p, comps, names, noise_si[sensor], sensor, idx)
        faults.append(fault)
    core["faults"] = faults



def convert_trajectory(tr: Any, duration: float) -> dict[str, Any]:
    """A ``[trajectory]`` table (segments or waypoints, values with units) in its SI form for
    a run of ``duration`` s; errors name the field. Warns (:class:`ScenarioWarning`) when the
    segments cover less than the run (the last one is held)."""
    if isinstance(tr, Mapping) and "waypoints" in tr:
        tr = _waypoints(tr, duration)
    _check_keys(tr, "trajectory", "trajectory")
    segs = []
    for i, s in enumerate(_list(_need(tr, "segments", "trajectory"), "trajectory.segments")):
        p = f"trajectory.segments[{i}]"
        kind = _str(_need(s, "kind", p), f"{p}.kind")
        if kind not in _SEGMENTS:
            raise ScenarioError(f"{p}.kind = {kind!r}: unknown segment (use one of: {', '.join(_SEGMENTS)})")
        _check_keys(s, f"segment.{kind}", p)
        seg: dict[str, Any] = {"kind": kind}
        for key, dim in _SEGMENTS[kind].items():
            seg[key] = _unit(_need(s, key, p), dim, f"{p}.{key}")
        segs.append(seg)
    covered = sum(seg["duration"] for seg in segs)
    if segs and covered < duration - 1e-9 * max(duration, 1.0):
        import warnings

        warnings.warn(
            f"trajectory.segments cover {covered:g} s of the {duration:g} s run: the last segment "
            f"({segs[-1]['kind']}) is held for the remaining {duration - covered:g} s",
            ScenarioWarning,
            stacklevel=4,
        )
    return {
        "latitude": _unit(_need(tr, "latitude", "trajectory"), "angle", "trajectory.latitude"),
        "longitude": _unit(_need(tr, "longitude", "trajectory"), "angle", "trajectory.longitude"),
        "height": _unit(_need(tr, "height", "trajectory"), "length", "trajectory.height"),
        "heading": _unit(tr.get("heading", "0 deg"), "angle", "trajectory.heading"),
        "speed": _unit(tr.get("speed", "0 m/s"), "velocity", "trajectory.speed"),
        "segments": segs,
    }


def _convert(raw: Mapping[str, Any]) -> dict[str, Any]:
    """User structure (with units) → core structure (SI)."""
    _check_keys(raw, "", "")
    tight = raw.get("tight")
    logged_tight = raw.get("architecture") == "tight" and isinstance(tight, Mapping) and "strapdown" in tight
    logged = raw.get("architecture") == "loosely_coupled" or logged_tight
    if logged and "source" not in raw:
        what = "tight with [tight.strapdown]" if logged_tight else "architecture = \"loosely_coupled\""
        raise ScenarioError(f"source: required by {what} (the IMU and GNSS logs the strapdown INS runs on)")
    if "source" in raw and not logged:
        raise ScenarioError("source: recorded logs run with architecture = \"loosely_coupled\", or \"tight\" with a [tight.strapdown] INS")
    core: dict[str, Any] = {
        "name": _str(_need(raw, "name", ""), "name"),
        "duration": _unit(_need(raw, "duration", ""), "time", "duration"),
        "dt": _unit(_need(raw, "dt", ""), "time", "dt"),
    }
    if logged:
        return _convert_logged(raw, core)
    core["trajectory"] = convert_trajectory(_need(raw, "trajectory", ""), core["duration"])
    if "terrain" in raw:
        core["terrain"] = _terrain(raw["terrain"])
    if "state_chi2" in raw:
        core["state_chi2"] = _state_chi2(raw["state_chi2"])
    if "modes" in raw:
        core["modes"] = _modes(raw["modes"])
    ins = _need(raw, "ins", "")
    _check_keys(ins, "ins", "ins")
    core["ins"] = {k: _unit(_need(ins, k, "ins"), dim, f"ins.{k}") for k, dim in _INS.items()}

    _sensors_and_faults(raw, core)
    arch = _str(raw.get("architecture", "federated"), "architecture")
    if arch not in ("federated", "centralized", "tight", "ultra_tight"):
        raise ScenarioError(f"architecture = {arch!r}: use federated, centralized, tight, ultra_tight or loosely_coupled")
    core["architecture"] = arch
    _variants(raw)
    for other in ("federated", "centralized", "tight", "ultra_tight"):
        if other != arch and other in raw:
            raise ScenarioError(f"{other}: given, but architecture is {arch!r} (remove it, or set architecture = {other!r})")
    if arch == "tight":
        core["tight"] = _tight(_need(raw, "tight", ""))
        apply_range_errors(raw, core, logged=False)
        if raw["tight"].get("range_states", "white") != "white":
            raise ScenarioError("tight.range_states: range-error states are carried by the strapdown tight filter on IMU and range logs "
                                "([tight.strapdown] and [source]); the simulated INS-error tight filter has none (correlated range errors "
                                "drawn by its simulator, [sensors.ranges] correlated, meet its white-noise model)")
        return core
    if arch == "ultra_tight":
        core["ultra_tight"] = _ultra_tight(_need(raw, "ultra_tight", ""))
        return core
    if arch == "centralized":
        core["centralized"] = _centralized(_need(raw, "centralized", ""))
        return core
    fed = _need(raw, "federated", "")
    _check_keys(fed, "federated", "federated")
    mode = _str(_need(fed, "mode", "federated"), "federated.mode")
    if mode not in ("reset", "no_reset"):
        raise ScenarioError(f"federated.mode = {mode!r}: use reset or no_reset")
    subs = []
    for i, sf in enumerate(_list(_need(fed, "subfilters", "federated"), "federated.subfilters")):
        p = f"federated.subfilters[{i}]"
        _check_keys(sf, "federated.subfilters", p)
        dets = _detectors(sf.get("detectors", []), p)
        iso = sf.get("isolation")
        subs.append(
            {
                "sensor": _str(_need(sf, "sensor", p), f"{p}.sensor"),
                "share": _number(_need(sf, "share", p), f"{p}.share"),
                "detectors": dets,
                "isolation": None if iso is None else _str(iso, f"{p}.isolation"),
            }
        )
    iu = fed.get("isolated", "track")
    if iu not in ("track", "predict", "update"):
        raise ScenarioError(f"federated.isolated = {iu!r}: use track, predict or update")
    isolate = _bool(fed.get("isolate", True), "federated.isolate")
    core["federated"] = {
        "mode": mode,
        "master_share": _number(fed.get("master_share", 0.0), "federated.master_share"),
        "subfilters": subs,
        "isolated": iu,
        "isolate": isolate,
    }
    return core


@dataclass(frozen=True)
class Scenario:
    """A validated scenario.

    Attributes
    ----------
    raw : dict
        The user's structure, with units, exactly as given (used for sweeps and reports).
    core : dict
        The same in SI units and radians, as run by the Rust core.
    source : str
        Where it came from (bundled name, file path or ``"<python>"``).
    """

    raw: dict[str, Any]
    core: dict[str, Any]
    source: str = "<python>"
    _json: str = field(default="", repr=False, compare=False)

    def text(self) -> str:
        """The scenario as the user wrote it: the bundled or file TOML when it came from one
        (and was not changed since: ``with_value`` sources say ``… (modified)``), else its
        ``raw`` structure as JSON."""
        text = None
        if self.source in bundled_scenarios():
            text = bundled_toml(self.source)
        elif Path(self.source).suffix == ".toml" and Path(self.source).is_file():
            text = Path(self.source).read_text(encoding="utf-8")
        if text is not None:
            try:
                same = tomllib.loads(text) == self.raw
            except tomllib.TOMLDecodeError:
                same = False
            if same:
                return text
        return "# changed from " + self.source + " (shown as JSON of the user's structure)\n" + json.dumps(self.raw, indent=2, default=str)

    def __repr__(self) -> str:
        """One line: name, architecture, duration, sensors, faults, variants and source (the
        whole structure is in ``raw`` and ``core``; ``navfdi scenarios --show`` prints a
        bundled one's TOML)."""
        c = self.core
        sensors = ", ".join(s["name"] for s in c.get("sensors", []))
        faults = ", ".join(f["id"] for f in c.get("faults", [])) or "none"
        variants = ", ".join(self.variant_names()) or "none"
        return (
            f"Scenario({self.name!r}, {c.get('architecture', 'federated')}, {c['duration']:g} s at dt {c['dt']:g} s; "
            f"sensors: {sensors}; faults: {faults}; variants: {variants}; source: {self.source})"
        )

    @property
    def name(self) -> str:
        """Scenario name."""
        return str(self.core["name"])

    def to_json(self) -> str:
        """The SI structure as JSON (what the Rust core receives)."""
        return self._json or json.dumps(self.core)

    def faults(self) -> list[dict[str, Any]]:
        """Faults in SI: ``id, sensor, components, kind, magnitude, start (s), end (s)``."""
        return [dict(f) for f in self.core["faults"]]

    def base(self) -> Scenario:
        """The scenario without its ``[[variants]]`` (itself when it has none)."""
        if "variants" not in self.raw:
            return self
        return from_dict({k: v for k, v in self.raw.items() if k != "variants"}, source=self.source)

    def variant_names(self) -> list[str]:
        """Names of the scenario's ``[[variants]]`` (empty without variants)."""
        return [n for n, _ in _variants(self.raw)]

    def variants(self) -> list[tuple[str, Scenario]]:
        """``(name, scenario)`` per ``[[variants]]`` entry: the base with the variant's
        overrides applied (validated), without the ``variants`` table. Without variants:
        ``[("base", self)]``."""
        vs = _variants(self.raw)
        if not vs:
            return [("base", self)]
        base = self.base()
        out = []
        for i, (name, sets) in enumerate(vs):
            try:
                out.append((name, base.with_values(sets, create=True)))
            except ScenarioError as e:
                raise ScenarioError(f"variants[{i}] ({name}): {e}") from None
        return out

    def with_value(self, path: str, value: Any, create: bool = False) -> Scenario:
        """A copy with the user-level field at ``path`` (e.g. ``"faults[0].magnitude"``)
        replaced by ``value``, validated anew. ``create=True`` also allows setting a table key
        that the scenario does not have yet (used by variants)."""
        return self.with_values({path: value}, create)

    def with_values(self, values: Mapping[str, Any], create: bool = False) -> Scenario:
        """:meth:`with_value` for several fields at once, validated once after all are set
        (so fields that must change together, such as a policy and its detector, can)."""
        raw = copy.deepcopy(self.raw)
        for path, value in values.items():
            _set_path(raw, path, value, create, self.name)
        return from_dict(raw, source=self.source)


def _set_path(raw: Any, path: str, value: Any, create: bool, name: str) -> None:
    target: Any = raw
    parts = _parse_path(path)
    for part in parts[:-1]:
        try:
            target = target[part]
        except (KeyError, IndexError, TypeError):
            raise ScenarioError(f"{path}: no such field in scenario {name!r}") from None
    last = parts[-1]
    if not (create and isinstance(target, dict) and isinstance(last, str)):
        try:
            target[last]  # must exist
        except (KeyError, IndexError, TypeError):
            raise ScenarioError(f"{path}: no such field in scenario {name!r}") from None
    target[last] = value


_PATH = re.compile(r"[A-Za-z_]\w*(\[\d+\])*(\.[A-Za-z_]\w*(\[\d+\])*)*")


def _variants(raw: Mapping[str, Any]) -> list[tuple[str, dict[str, Any]]]:
    """``[[variants]]``: ``(name, {path: value})`` pairs, checked for form (each variant is
    validated as a whole scenario by :meth:`Scenario.variants`)."""
    out: list[tuple[str, dict[str, Any]]] = []
    for i, v in enumerate(_list(raw.get("variants", []), "variants")):
        p = f"variants[{i}]"
        _check_keys(v, "variants", p)
        name = _name(_need(v, "name", p), f"{p}.name")
        if any(name == n for n, _ in out):
            raise ScenarioError(f"{p}.name = {name!r}: used by an earlier variant")
        sets = v.get("set", {})
        if not isinstance(sets, Mapping):
            raise ScenarioError(f"{p}.set: expected a table of field path = value")
        for path in sets:
            parts = _parse_path(str(path))
            if parts[0] not in VARIANT_FIELDS:
                raise ScenarioError(
                    f"{p}.set: {path!r} would change the simulated measurements; variants compare filters on the same "
                    f"measurements and may only set {', '.join(VARIANT_FIELDS)} fields"
                )
        out.append((name, dict(sets)))
    return out


def _parse_path(path: str) -> list[str | int]:
    """``"faults[0].magnitude"`` → ``["faults", 0, "magnitude"]``; malformed paths (unbalanced
    brackets, empty parts, non-integer indices) raise :class:`ScenarioError`."""
    if not isinstance(path, str) or not _PATH.fullmatch(path):
        raise ScenarioError(
            f"{path!r}: malformed field path; write names joined by dots with list indices in "
            "brackets, e.g. faults[0].magnitude or sensors[1].noise"
        )
    out: list[str | int] = []
    for name, idx in re.findall(r"([A-Za-z_]\w*)|\[(\d+)\]", path):
        out.append(name if name else int(idx))
    return out


def _convert_logged(raw: Mapping[str, Any], core: dict[str, Any]) -> dict[str, Any]:
    """A recorded-data scenario: no trajectory or INS error model (the motion and the IMU come
    from the logs); ``[source]`` stays in the Python layer (see :mod:`navfdi.logs`).
    Architecture ``loosely_coupled`` (GNSS solution logs) or ``tight`` with
    ``[tight.strapdown]`` (RINEX observations and navigation data)."""
    arch = str(raw.get("architecture"))
    for k in ("trajectory", "ins", "terrain", "modes", "state_chi2"):
        if k in raw:
            raise ScenarioError(f"{k}: not used by a {arch} scenario on recorded logs (remove it)")
    src = _need(raw, "source", "")
    if arch == "tight":
        _check_keys(src, "source.tight", "source")
        for k in ("rinex_obs", "rinex_nav"):
            _need(src, k, "source")
    else:
        _check_keys(src, "source.loosely_coupled", "source")
    _sensors_and_faults(raw, core)
    core["architecture"] = arch
    _variants(raw)
    for other in ("federated", "centralized", "tight", "ultra_tight", "loosely_coupled"):
        if other != arch and other in raw:
            raise ScenarioError(f"{other}: given, but architecture is {arch!r} (remove it)")
    if arch == "tight":
        core["tight"] = _tight(_need(raw, "tight", ""))
        apply_range_errors(raw, core, logged=True)
    else:
        core["loosely_coupled"] = _loosely_coupled(_need(raw, "loosely_coupled", ""))
    return core


def from_dict(raw: Mapping[str, Any], source: str = "<python>") -> Scenario:
    """Validate a scenario given as a Python mapping with the TOML structure."""
    if not isinstance(raw, Mapping):
        raise ScenarioError(f"scenario: expected a table, got {type(raw).__name__}")
    core = _convert(resolve_log_times(raw, source))
    text = json.dumps(core)
    try:
        _core.validate_scenario(text)
    except MemoryError as e:
        raise ScenarioTooLarge(str(e)) from None
    except ValueError as e:
        raise ScenarioError(str(e)) from None
    if core.get("terrain"):
        check_terrain(core, text)
    return Scenario(raw=copy.deepcopy(dict(raw)), core=core, source=source, _json=text)


def load_scenario(source: str | Path | Mapping[str, Any]) -> Scenario:
    """Load a scenario: a bundled name (see :func:`bundled_scenarios`), a TOML file path, or a
    mapping with the same structure.

    A bundled name wins over a file or directory of the same name in the working directory;
    write ``./name`` (or a path ending in ``.toml``) to load such a file instead.

    Raises
    ------
    ScenarioError
        Unknown name, missing file, malformed TOML, or an invalid field (named with its path).
    ScenarioTooLarge
        The run would need more memory than is available (a :class:`ScenarioError` and a
        ``MemoryError``); the message names ``duration`` and ``dt``.

    Warns
    -----
    ScenarioWarning
        The trajectory's segments are shorter than the run (the last segment is held).
    """
    if isinstance(source, Mapping):
        return from_dict(source)
    s = str(source)
    if not s:
        raise ScenarioError("scenario: empty name; give a bundled scenario name or a TOML file path")
    path = Path(s)
    names = bundled_scenarios()
    # A bundled name wins over a file or directory of the same name in the working directory
    # unless the argument is written as a path (with a separator, or ending in .toml).
    looks_like_path = isinstance(source, Path) or "/" in s or "\\" in s or path.suffix == ".toml"
    if s in names and not looks_like_path:
        text = (resources.files("navfdi") / "scenarios" / f"{s}.toml").read_text(encoding="utf-8")
        origin = s
    elif looks_like_path or path.exists():
        if path.is_dir():
            raise ScenarioError(f"{s}: is a directory, not a scenario file")
        if not path.is_file():
            raise ScenarioError(f"{s}: no such scenario file")
        try:
            text = path.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError) as e:
            raise ScenarioError(f"{s}: cannot read the scenario file: {e}") from None
        origin = str(path)
    else:
        raise ScenarioError(f"{s!r}: neither a scenario file nor a bundled scenario (bundled: {', '.join(names)})")
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        raise ScenarioError(f"{origin}: malformed TOML: {e}") from None
    return from_dict(raw, source=origin)


def fault_on(fault: Mapping[str, Any], channel: str) -> bool:
    """Whether ``fault`` is one a record channel named ``channel`` should detect: a fault on
    that sensor, or (an ultra-tight channel is named by its satellite) on that satellite."""
    return bool(fault["sensor"] == channel or fault.get("satellite") == channel)
