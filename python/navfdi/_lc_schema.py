"""Schema of the ``[loosely_coupled]`` section (strapdown INS on recorded logs): user form
with units → the SI form of the Rust core's ``LooselyCoupledSpec``."""

from __future__ import annotations

from typing import Any

from navfdi._errors import ScenarioError
from navfdi._fields import _bool, _check_keys, _detectors, _list, _need, _str, _unit


def _constraint(c: Any, p: str, dim: int) -> dict[str, Any]:
    zupt = dim == 3
    _check_keys(c, {"noise", "detectors", "decision", "window", "threshold", "rate_threshold"}, p)
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


def _loosely_coupled(lc: Any) -> dict[str, Any]:
    p = "loosely_coupled"
    _check_keys(lc, {"imu", "mounting", "lever_arm", "imu_time_offset", "alignment", "sensors", "zupt", "nhc", "witness", "isolate_components", "accommodate", "isolate"}, p)
    imu = _need(lc, "imu", p)
    _check_keys(imu, {"gyro_noise", "accel_noise", "gyro_bias", "accel_bias", "bias_tau", "gyro_scale", "accel_scale"}, f"{p}.imu")

    def axes(v: Any, dim: str, q: str) -> list[float]:
        vals = [v] * 3 if isinstance(v, str) else _list(v, q)
        if len(vals) != 3:
            raise ScenarioError(f"{q}: expected one value or three (x, y, z), got {len(vals)}")
        return [_unit(x, dim, f"{q}[{i}]") for i, x in enumerate(vals)]

    al = _need(lc, "alignment", p)
    _check_keys(al, {"speed", "heading", "static_speed", "gyro_bias", "sigma_level", "sigma_heading", "sigma_position", "sigma_velocity"}, f"{p}.alignment")
    out: dict[str, Any] = {
        "imu": {
            "gyro_noise": axes(_need(imu, "gyro_noise", f"{p}.imu"), "angular_rate_density", f"{p}.imu.gyro_noise"),
            "accel_noise": axes(_need(imu, "accel_noise", f"{p}.imu"), "acceleration_density", f"{p}.imu.accel_noise"),
            "gyro_bias": _unit(_need(imu, "gyro_bias", f"{p}.imu"), "angular_rate", f"{p}.imu.gyro_bias"),
            "accel_bias": _unit(_need(imu, "accel_bias", f"{p}.imu"), "acceleration", f"{p}.imu.accel_bias"),
            "bias_tau": _unit(_need(imu, "bias_tau", f"{p}.imu"), "time", f"{p}.imu.bias_tau"),
            "gyro_scale": _unit(imu.get("gyro_scale", "0 ppm"), "fraction", f"{p}.imu.gyro_scale"),
            "accel_scale": _unit(imu.get("accel_scale", "0 ppm"), "fraction", f"{p}.imu.accel_scale"),
        },
        "mounting": axes(_need(lc, "mounting", p), "angle", f"{p}.mounting"),
        "lever_arm": axes(_need(lc, "lever_arm", p), "length", f"{p}.lever_arm"),
        "imu_time_offset": _unit(lc.get("imu_time_offset", "0 s"), "time", f"{p}.imu_time_offset"),
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
        "sensors": [],
        "witness": _bool(lc.get("witness", True), f"{p}.witness"),
        "isolate_components": _bool(lc.get("isolate_components", True), f"{p}.isolate_components"),
        "accommodate": _bool(lc.get("accommodate", True), f"{p}.accommodate"),
        "isolate": _bool(lc.get("isolate", True), f"{p}.isolate"),
    }
    for i, a in enumerate(_list(_need(lc, "sensors", p), f"{p}.sensors")):
        q = f"{p}.sensors[{i}]"
        _check_keys(a, {"sensor", "detectors", "decision"}, q)
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
