"""Schema of the INS/GNSS coupling sections — ``[loosely_coupled]`` and the strapdown INS on
recorded logs, ``[tight]`` (with ``[tight.strapdown]``) and ``[ultra_tight]``: user form with
units → the SI form of the Rust core's ``LooselyCoupledSpec``, ``TightSpec`` and
``UltraTightSpec``."""

from __future__ import annotations

import math

import numpy as np

from collections.abc import Mapping, Sequence
from typing import Any

from navfdi._errors import ScenarioError
from navfdi._fields import _bool, _check_keys, _detectors, _list, _name, _need, _number, _str, _unit


def _constraint(c: Any, p: str, dim: int) -> dict[str, Any]:
    zupt = dim == 3
    _check_keys(c, "constraint", p)
    noise = _need(c, "noise", p)
    noise = [noise] * dim if isinstance(noise, str) else _list(noise, f"{p}.noise")
    if len(noise) != dim:
        raise ScenarioError(f"{p}.noise: expected one value or {dim}, got {len(noise)}")
    out: dict[str, Any] = {
        "noise": [_unit(v, "velocity", f"{p}.noise[{i}]") for i, v in enumerate(noise)],
        "detectors": _detectors(c.get("detectors", []), p),
        "decision": None if c.get("decision") is None else _str(c["decision"], f"{p}.decision"),
        "window": _unit(c.get("window", "0.5 s"), "time", f"{p}.window"),
        "threshold": _unit(_need(c, "threshold", p), "acceleration" if zupt else "velocity", f"{p}.threshold"),
        "rate_threshold": _unit(_need(c, "rate_threshold", p), "angular_rate", f"{p}.rate_threshold"),
    }
    return out


def _axes(v: Any, dim: str, q: str) -> list[float]:
    vals = [v] * 3 if isinstance(v, str) else _list(v, q)
    if len(vals) != 3:
        raise ScenarioError(f"{q}: expected one value or three (x, y, z), got {len(vals)}")
    return [_unit(x, dim, f"{q}[{i}]") for i, x in enumerate(vals)]


_AXES = {"forward": (1, 0, 0), "back": (-1, 0, 0), "right": (0, 1, 0), "left": (0, -1, 0), "down": (0, 0, 1), "up": (0, 0, -1)}


def axes_mounting(axes: Sequence[str]) -> tuple[float, float, float]:
    """The mounting (roll, pitch, yaw, rad; ``navfdi_core::ins::strapdown::mounting``'s
    convention) of an IMU whose x, y, z axes point along ``axes`` of the vehicle (each one of
    forward, back, right, left, down, up; a right-handed set)."""
    if len(axes) != 3 or any(a not in _AXES for a in axes):
        raise ValueError(f"imu_axes = {list(axes)!r}: three of {', '.join(_AXES)}")
    c = np.array([_AXES[a] for a in axes], dtype=float).T  # columns: IMU axes in body = C_imu^b
    if abs(np.linalg.det(c) - 1.0) > 1e-9:
        raise ValueError(f"imu_axes = {list(axes)!r}: not a right-handed set of axes (the third must be the cross product of the first two)")
    return _euler_of_mounting(c)


def _euler_of_mounting(c_imu_b: np.ndarray) -> tuple[float, float, float]:
    """Roll, pitch, yaw (rad) with ``mounting(r, p, y) = c_imu_b``, i.e. ``R_z R_y R_x = c_imu_bᵀ``.

    At a pitch of ±90° (an IMU whose x axis is vertical) only roll ∓ yaw is defined and the
    general formulas read 0/0 for both: the roll is then 0 and the yaw carries the rest (the
    first column is (0, 0, ∓1), the second (−sin yaw, cos yaw, 0)). Read with the general
    formulas, six of the 24 axis sets (x up or down) became the mounting of another set, y and
    z turned 180° about x: ``imu_axes = ["up", "left", "back"]`` was the mounting of
    ``["down", "right", "back"]``."""
    m = c_imu_b.T
    pitch = -math.asin(max(-1.0, min(1.0, m[2, 0])))
    if abs(m[2, 0]) > 1.0 - 1e-12:
        return 0.0, pitch, math.atan2(-m[0, 1], m[1, 1])
    roll = math.atan2(m[2, 1], m[2, 2])
    yaw = math.atan2(m[1, 0], m[0, 0])
    return roll, pitch, yaw


def _rot(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return rz @ ry @ rx


def true_mounting(axes: Sequence[str], boresight_deg: Sequence[float]) -> tuple[float, float, float]:
    """The mounting (rad) of an IMU with nominal ``axes`` and a boresight error (roll, pitch,
    yaw, deg: rotations about the vehicle's forward, right and down axes, in the ``mounting``
    convention, so that for forward-right-down axes the mounting is the boresight itself):
    ``C_imu^b = R_boreᵀ · C_axes``."""
    r0 = axes_mounting(axes)
    c_axes = _rot(*r0).T
    bore = _rot(*np.radians(boresight_deg))
    return _euler_of_mounting(bore.T @ c_axes)


def _mounting(t: Any, p: str) -> list[float]:
    """``mounting`` (roll, pitch, yaw of the IMU in the forward-right-down body frame) or
    ``imu_axes`` (where the IMU's x, y, z point: forward, back, right, left, down, up), with an
    optional ``boresight`` (roll, pitch, yaw, small angles) on top: the mounting angles (rad)."""
    given = [k for k in ("mounting", "imu_axes") if k in t]
    if len(given) != 1:
        raise ScenarioError(f"{p}: give the IMU's orientation as imu_axes (e.g. [\"right\", \"forward\", \"up\"]: where its x, y, z axes point; "
                            f"or \"auto\", a ground vehicle's estimated from its recorded log) or as mounting (roll, pitch, yaw angles), "
                            f"{'not both' if given else 'one of them'}")
    bore = [math.degrees(v) for v in _axes(t["boresight"], "angle", f"{p}.boresight")] if "boresight" in t else [0.0, 0.0, 0.0]
    if "imu_axes" in t:
        if isinstance(t["imu_axes"], str):
            raise ScenarioError(f"{p}.imu_axes = {t['imu_axes']!r}: three of {', '.join(_AXES)} (where the IMU's x, y, z point), "
                                f"or \"auto\" (estimated from a recorded log)")
        axes = _list(t["imu_axes"], f"{p}.imu_axes")
        try:
            return list(true_mounting([str(a) for a in axes], bore))
        except ValueError as e:
            raise ScenarioError(f"{p}.{e}") from None
    m = _axes(t["mounting"], "angle", f"{p}.mounting")
    if any(bore):
        c = _rot(*m).T
        return list(_euler_of_mounting(_rot(*np.radians(bore)).T @ c))
    return m


#: ``[loosely_coupled]`` fields that may be ``"auto"``: estimated from the log before the run
#: (:func:`navfdi.calibrate.resolve_auto`, the same estimates as ``navfdi calibrate``).
AUTO_FIELDS = ("imu.gyro_noise", "imu.accel_noise", "boresight", "imu_time_offset", "imu_axes")
# What an "auto" field holds in the SI form until it is resolved (never run: an unresolved
# scenario is refused by navfdi.logs.scored_source).
_AUTO_PLACEHOLDER: dict[str, Any] = {"imu.gyro_noise": "0.01 deg/s/sqrt(Hz)", "imu.accel_noise": "0.1 mg/sqrt(Hz)", "boresight": "0 deg", "imu_time_offset": "0 s",
                                     "imu_axes": ["forward", "right", "down"]}


def auto_fields(raw: Mapping[str, Any]) -> list[str]:
    """The :data:`AUTO_FIELDS` a user-form scenario ``raw`` sets to ``"auto"`` in
    ``[loosely_coupled]`` (paths relative to it, e.g. ``"imu.gyro_noise"``)."""
    lc = raw.get("loosely_coupled")
    out = []
    for f in AUTO_FIELDS:
        t: Any = lc
        *head, last = f.split(".")
        for k in head:
            t = t.get(k) if isinstance(t, Mapping) else None
        if isinstance(t, Mapping) and t.get(last) == "auto":
            out.append(f)
    return out


def _auto(t: Any, p: str) -> Any:
    """``t`` with its ``"auto"`` fields replaced by placeholders (loosely coupled only)."""
    if not isinstance(t, Mapping):
        return t
    found = auto_fields({"loosely_coupled": t})
    if not found:
        return t
    if p != "loosely_coupled":
        raise ScenarioError(f"{p}.{found[0]} = \"auto\": estimated from the log for [loosely_coupled] only (navfdi calibrate); give the value")
    t = {**t, "imu": dict(t["imu"]) if isinstance(t.get("imu"), Mapping) else t.get("imu")}
    for f in found:
        if f.startswith("imu."):
            t["imu"][f[4:]] = _AUTO_PLACEHOLDER[f]
        else:
            t[f] = _AUTO_PLACEHOLDER[f]
    return t


def _strapdown(t: Any, p: str) -> dict[str, Any]:
    """The strapdown INS fields of table ``t`` at field path ``p``: ``imu``, ``mounting``,
    ``lever_arm``, ``imu_time_offset``, ``alignment`` (SI). ``"auto"`` fields (see
    :data:`AUTO_FIELDS`) hold placeholders until resolved."""
    t = _auto(t, p)
    imu = _need(t, "imu", p)
    _check_keys(imu, "strapdown.imu", f"{p}.imu")
    al = _need(t, "alignment", p)
    _check_keys(al, "strapdown.alignment", f"{p}.alignment")
    return {
        "imu": {
            "gyro_noise": _axes(_need(imu, "gyro_noise", f"{p}.imu"), "angular_rate_density", f"{p}.imu.gyro_noise"),
            "accel_noise": _axes(_need(imu, "accel_noise", f"{p}.imu"), "acceleration_density", f"{p}.imu.accel_noise"),
            "gyro_bias": _unit(_need(imu, "gyro_bias", f"{p}.imu"), "angular_rate", f"{p}.imu.gyro_bias"),
            "accel_bias": _unit(_need(imu, "accel_bias", f"{p}.imu"), "acceleration", f"{p}.imu.accel_bias"),
            "bias_tau": _unit(_need(imu, "bias_tau", f"{p}.imu"), "time", f"{p}.imu.bias_tau"),
            "gyro_scale": _unit(imu.get("gyro_scale", "0 ppm"), "fraction", f"{p}.imu.gyro_scale"),
            "accel_scale": _unit(imu.get("accel_scale", "0 ppm"), "fraction", f"{p}.imu.accel_scale"),
        },
        "mounting": _mounting(t, p),
        "lever_arm": _axes(_need(t, "lever_arm", p), "length", f"{p}.lever_arm"),
        "imu_time_offset": _unit(t.get("imu_time_offset", "0 s"), "time", f"{p}.imu_time_offset"),
        "alignment": {
            "speed": _unit(_need(al, "speed", f"{p}.alignment"), "velocity", f"{p}.alignment.speed"),
            "heading": None if "heading" not in al else _unit(al["heading"], "angle", f"{p}.alignment.heading"),
            "static_speed": _unit(al.get("static_speed", "0.05 m/s"), "velocity", f"{p}.alignment.static_speed"),
            "gyro_bias": _bool(al.get("gyro_bias", True), f"{p}.alignment.gyro_bias"),
            "sigma_level": _unit(_need(al, "sigma_level", f"{p}.alignment"), "angle", f"{p}.alignment.sigma_level"),
            "sigma_heading": _unit(_need(al, "sigma_heading", f"{p}.alignment"), "angle", f"{p}.alignment.sigma_heading"),
            "sigma_position": _unit(_need(al, "sigma_position", f"{p}.alignment"), "length", f"{p}.alignment.sigma_position"),
            "sigma_velocity": _unit(_need(al, "sigma_velocity", f"{p}.alignment"), "velocity", f"{p}.alignment.sigma_velocity"),
        },
    }


def _tight_strapdown(t: Any) -> dict[str, Any]:
    """``[tight.strapdown]``: the strapdown INS of a tight filter on recorded logs."""
    p = "tight.strapdown"
    _check_keys(t, "tight.strapdown", p)
    return _strapdown(t, p)


def _loosely_coupled(lc: Any) -> dict[str, Any]:
    p = "loosely_coupled"
    _check_keys(lc, "loosely_coupled", p)
    out: dict[str, Any] = {
        **_strapdown(lc, p),
        "sensors": [],
        "witness": _bool(lc.get("witness", True), f"{p}.witness"),
        "isolate_components": _bool(lc.get("isolate_components", True), f"{p}.isolate_components"),
        "accommodate": _bool(lc.get("accommodate", True), f"{p}.accommodate"),
        "isolate": _bool(lc.get("isolate", True), f"{p}.isolate"),
        "convergence": _number(lc.get("convergence", 3.0), f"{p}.convergence"),
        "noise_scale": None if lc.get("noise_scale", "auto") == "auto" else _number(lc["noise_scale"], f"{p}.noise_scale"),
        "position_correlation": None if lc.get("position_correlation", "0 s") == "auto" else _unit(lc.get("position_correlation", "0 s"), "time", f"{p}.position_correlation"),
    }
    for i, a in enumerate(_list(_need(lc, "sensors", p), f"{p}.sensors")):
        q = f"{p}.sensors[{i}]"
        _check_keys(a, "centralized.sensors", q)
        out["sensors"].append({
            "sensor": _str(_need(a, "sensor", q), f"{q}.sensor"),
            "detectors": _detectors(a.get("detectors", []), q),
            "decision": None if a.get("decision") is None else _str(a["decision"], f"{q}.decision"),
        })
    if "zupt" in lc:
        out["zupt"] = _constraint(lc["zupt"], f"{p}.zupt", 3)
    if "nhc" in lc:
        out["nhc"] = _constraint(lc["nhc"], f"{p}.nhc", 2)
    return out


def _tight(t: Any) -> dict[str, Any]:
    """The ``[tight]`` table."""
    _check_keys(t, "tight", "tight")
    fde = _str(_need(t, "fde", "tight"), "tight.fde")
    if fde not in ("ls_precheck", "innovation", "gnss_filter", "separation", "none"):
        raise ScenarioError(f"tight.fde = {fde!r}: use ls_precheck, innovation, gnss_filter, separation or none")
    rates = _bool(t.get("rates", True), "tight.rates")
    ls_test = _str(t.get("ls_test", "global"), "tight.ls_test")
    if ls_test not in ("global", "wtest", "both", "auto"):
        raise ScenarioError(f"tight.ls_test = {ls_test!r}: use global (the chi-square test), wtest (data snooping), both or auto")
    return {
        "sensor": _str(_need(t, "sensor", "tight"), "tight.sensor"),
        "fde": fde,
        "alpha": _number(_need(t, "alpha", "tight"), "tight.alpha"),
        "k": None if t.get("k") is None else _number(t["k"], "tight.k"),
        "ls_test": ls_test,
        "rates": rates,
        "accel_psd": _unit(t.get("accel_psd", "1 m^2/s^3"), "length2_per_time3", "tight.accel_psd"),
        "strapdown": None if "strapdown" not in t else _tight_strapdown(t["strapdown"]),
        "integrity": None if "integrity" not in t else _tight_integrity(t["integrity"]),
        "range_states": _range_states(t.get("range_states", "white")),
    }


def _range_states(v: Any) -> dict[str, float] | None:
    """``[tight] range_states``: ``"white"`` (default: no states, None), ``"auto"`` (estimated
    from the recorded log before the run, :func:`navfdi.logs.range_error_process`) or a table
    ``{ fraction = share of the pseudorange variance in [0, 1), tau = correlation time }``.
    ``"auto"`` is None in the core scenario until it is resolved; a run refuses it unresolved
    (:func:`navfdi.logs.logged_source`)."""
    p = "tight.range_states"
    if v in ("white", "auto"):
        return None
    if not isinstance(v, dict):
        raise ScenarioError(f"{p} = {v!r}: use 'white', 'auto' (estimated from the log's residuals) or a table {{ fraction = 0.6, tau = \"20 s\" }}")
    _check_keys(v, "tight.range_states", p)
    return gauss_markov_share(v, p)


def gauss_markov_share(v: dict[str, Any], p: str) -> dict[str, float]:
    """A ``{ fraction, tau }`` table at path ``p`` (its keys already checked): the share in
    [0, 1) of each pseudorange's variance that is a first-order Gauss-Markov process, and its
    correlation time (s)."""
    fraction = _number(_need(v, "fraction", p), f"{p}.fraction")
    if not 0.0 <= fraction < 1.0:
        raise ScenarioError(f"{p}.fraction = {fraction!r}: a share in [0, 1) of the pseudorange variance is required")
    return {"fraction": fraction, "tau": _unit(_need(v, "tau", p), "time", f"{p}.tau")}


_INTEGRITY_KEYS = ("p_sat", "p_hmi_vert", "p_hmi_hor", "p_fa_vert", "p_fa_hor", "tol_pl")


def _tight_integrity(a: Any) -> dict[str, Any]:
    """The ``[tight.integrity]`` table: filter protection levels (probabilities per epoch, and
    ``tol_pl`` in m, the ADD's PL search tolerance; absent keys take the LPV-200 defaults in
    Rust)."""
    p = "tight.integrity"
    if not isinstance(a, dict):
        raise ScenarioError(f"{p}: expected a table, got {type(a).__name__}")
    _check_keys(a, "tight.integrity", p)
    return {key: _number(a[key], f"{p}.{key}") for key in _INTEGRITY_KEYS if key in a}


def range_error_factor(raw: Any) -> float | str | None:
    """``[tight.integrity] range_errors`` of a raw scenario: ``None`` (absent or ``"white"``:
    the pseudorange noise as given), ``"overbound"`` (a variance factor still to be estimated
    from a recorded log, :func:`navfdi.logs.range_error_overbound`) or the variance factor
    (a number in [1, 10⁴]) by which the tight filter's pseudorange noise variance is
    multiplied — a white-noise overbound of time-correlated range errors."""
    t = raw.get("tight") if isinstance(raw, dict) else None
    ig = t.get("integrity") if isinstance(t, dict) else None
    if not isinstance(ig, dict) or "range_errors" not in ig:
        return None
    v = ig["range_errors"]
    p = "tight.integrity.range_errors"
    if v == "white":
        return None
    if v == "overbound":
        return "overbound"
    if isinstance(v, str) or isinstance(v, bool) or not isinstance(v, (int, float)) or not (1.0 <= v <= 1e4):
        raise ScenarioError(f"{p} = {v!r}: use 'white', 'overbound' (estimated from a recorded log) or a variance factor in [1, 10000]")
    return float(v)


def apply_range_errors(raw: Any, core: dict[str, Any], logged: bool) -> None:
    """Scale the tight filter's pseudorange noise (its sensor's first ``noise`` component, in
    ``core``) by the square root of ``range_errors``'s variance factor; refuse
    ``"overbound"`` on a simulated scenario (its range errors are white)."""
    f = range_error_factor(raw)
    if f is None:
        return
    rs = raw.get("tight", {}).get("range_states", "white") if isinstance(raw.get("tight"), dict) else "white"
    if rs != "white":
        raise ScenarioError("tight.range_states and tight.integrity.range_errors both model the time correlation of the range errors: "
                            "keep one (range_states carries it as filter states; range_errors inflates the white noise)")
    if f == "overbound":
        if not logged:
            raise ScenarioError(
                "tight.integrity.range_errors = 'overbound': the factor is estimated from a recorded RINEX log's residuals; "
                "a simulated scenario's range errors are known from its [sensors.ranges] (white unless correlated is set): give a variance factor, e.g. 4, to study one")
        return
    name = core.get("tight", {}).get("sensor")
    for s in core.get("sensors", []):
        if s.get("name") == name and s.get("noise"):
            s["noise"] = [s["noise"][0] * math.sqrt(float(f)), *s["noise"][1:]]

def _ultra_tight(u: Any) -> dict[str, Any]:
    """The ``[ultra_tight]`` table (paper 004)."""
    p = "ultra_tight"
    _check_keys(u, "ultra_tight", p)
    method = _str(_need(u, "method", p), f"{p}.method")
    if method not in ("m1", "m2", "m3"):
        raise ScenarioError(f"{p}.method = {method!r}: use m1 (navigation-filter AIME), m2 (prefilter AIME) or m3 (two-stage AIME)")
    nav_input = _str(u.get("nav_input", "discriminator"), f"{p}.nav_input")
    if nav_input not in ("discriminator", "prefilter"):
        raise ScenarioError(
            f"{p}.nav_input = {nav_input!r}: use discriminator (the epoch's discriminator outputs averaged, "
            "paper eq. 2) or prefilter (the prefilter estimates averaged)"
        )
    sats = [_name(s, f"{p}.satellites[{i}]") for i, s in enumerate(_list(_need(u, "satellites", p), f"{p}.satellites"))]
    return {
        "sensor": _str(_need(u, "sensor", p), f"{p}.sensor"),
        "satellites": sats,
        "method": method,
        "pf": _number(_need(u, "pf", p), f"{p}.pf"),
        "cn0": _unit(_need(u, "cn0", p), "carrier_to_noise", f"{p}.cn0"),
        "integration": _unit(u.get("integration", "20 ms"), "time", f"{p}.integration"),
        "nav_input": nav_input,
        "nav_window": _unit(u.get("nav_window", "20 s"), "time", f"{p}.nav_window"),
        "prefilter_window": _unit(u.get("prefilter_window", "20 s"), "time", f"{p}.prefilter_window"),
        "stage1_window": _unit(u.get("stage1_window", "2 s"), "time", f"{p}.stage1_window"),
        "stage2_window": _unit(u.get("stage2_window", "10 s"), "time", f"{p}.stage2_window"),
        "stage_q": _number(u.get("stage_q", 10.0), f"{p}.stage_q"),
        "stage_period": _unit(u.get("stage_period", "1 s"), "time", f"{p}.stage_period"),
        "stage_r0": _number(u.get("stage_r0", 1.0), f"{p}.stage_r0"),
        "fading_b": _number(u.get("fading_b", 0.99), f"{p}.fading_b"),
        "jerk_psd": _unit(u.get("jerk_psd", "1 Hz^2/s^3"), "frequency2_per_time3", f"{p}.jerk_psd"),
        "code_psd": _unit(u.get("code_psd", "0 chips^2/s"), "chips2_per_time", f"{p}.code_psd"),
        "spacing": _number(u.get("spacing", 1.0), f"{p}.spacing"),
        "exclude": _bool(u.get("exclude", True), f"{p}.exclude"),
        "arm_after": _unit(u.get("arm_after", "30 s"), "time", f"{p}.arm_after"),
    }


#: The console's note under a channel of positions only (:func:`positions_only_channels`).
POSITIONS_ONLY = ("positions without the receiver's velocity: steps are held out; a slow drift is followed as without FDE "
                  "and its end may be held as a step — give the receiver's velocities where drifts matter "
                  "(docs/meter_fde.md, logs of positions only)")


def positions_only_channels(raw: Mapping[str, Any]) -> set[str]:
    """The loosely coupled GNSS channels of scenario ``raw`` (its TOML as a dict) when every
    one is a ``gnss_position`` sensor (a log of positions only: no receiver velocity) and FDE
    is on (``isolate`` not false); else an empty set."""
    lc = raw.get("loosely_coupled")
    if not isinstance(lc, Mapping) or lc.get("isolate") is False:
        return set()
    names = {str(x.get("sensor")) for x in lc.get("sensors", []) if isinstance(x, Mapping)}
    kinds = {str(x.get("name")): x.get("kind") for x in raw.get("sensors", []) if isinstance(x, Mapping)}
    return names if names and all(kinds.get(n) == "gnss_position" for n in names) else set()
