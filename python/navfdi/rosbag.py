"""ROS bags (ROS 1 ``.bag`` files and ROS 2 bag folders, SQLite or MCAP storage), read with the
``rosbags`` library (no ROS installation): the IMU from a ``sensor_msgs/Imu`` topic and the GNSS
fixes from a ``sensor_msgs/NavSatFix`` topic, optionally with the receiver's velocity from a
``geometry_msgs/TwistWithCovarianceStamped`` or ``TwistStamped`` topic (east, north, up, as the
u-blox and NMEA drivers publish it). Robotics data sets (UrbanNav, UrbanLoco, KAIST's and many
others) ship their logs so.

Times are the messages' ``header.stamp`` — ROS time, which is Unix time (UTC) on a computer
whose clock is set by NTP or by the receiver (``time_scale = "unix"``, the default: turned into
GPS time with the leap seconds), or GPS time where the driver stamps so (``time_scale =
"gpst"``). The IMU is read in its own axes (``header.frame_id``); its ``linear_acceleration`` is
the specific force (gravity included, as REP 145 asks of IMU drivers): a topic with gravity
removed is refused by its median.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from navfdi._errors import ScenarioError
from navfdi._logtime import unix_to_gps
from navfdi.gnsslogger import checked_imu
from navfdi.logs import ImuLog

__all__ = ["is_rosbag", "ros_topics", "read_ros_imu", "fix_messages", "IMU_KEYS", "TIME_SCALES"]

#: The keys ``[source.imu]`` takes with ``format = "rosbag"``.
IMU_KEYS = ("file", "format", "topic", "time_scale", "max_gap")
#: The stamps' time scales: ROS time (Unix time, UTC) or GPS time.
TIME_SCALES = ("unix", "gpst")
_IMU = ("sensor_msgs/msg/Imu",)
_FIX = ("sensor_msgs/msg/NavSatFix",)
_TWIST = ("geometry_msgs/msg/TwistWithCovarianceStamped", "geometry_msgs/msg/TwistStamped")


def is_rosbag(path: Path) -> bool:
    """Whether ``path`` is a ROS 1 bag (a ``.bag`` file) or a ROS 2 bag (a folder with a
    ``metadata.yaml``)."""
    return (path.is_file() and path.suffix == ".bag") or (path.is_dir() and (path / "metadata.yaml").is_file())


def _open(path: Path) -> Any:
    try:
        from rosbags.highlevel import AnyReader
    except ImportError:  # pragma: no cover - installed with navfdi[ros] and navfdi[test]
        raise ScenarioError(f"{path}: reading ROS bags needs the 'rosbags' package: pip install 'navfdi[ros]' (or rosbags)") from None
    if not is_rosbag(path):
        raise ScenarioError(f"{path}: not a ROS bag (a ROS 1 .bag file, or a ROS 2 bag folder with its metadata.yaml)")
    return AnyReader([path])


def ros_topics(path: str | Path) -> dict[str, str]:
    """The topics of a ROS bag and their message types (``sensor_msgs/msg/Imu``, …)."""
    path = Path(path)
    reader = _open(path)
    try:
        with reader as r:
            return {c.topic: c.msgtype for c in r.connections}
    except Exception as e:  # the library's errors, and whatever a damaged bag raises in it
        raise ScenarioError(f"{path}: not a readable ROS bag ({type(e).__name__}: {e})") from None


def _topic(path: Path, topic: Any, types: tuple[str, ...], field: str) -> str:
    """``topic`` checked against the bag's topics, or the bag's one topic of ``types``."""
    topics = ros_topics(path)
    listing = ", ".join(f"{k} ({v.split('/')[-1]})" for k, v in sorted(topics.items())) or "none"
    kinds = " or ".join(t.replace("/msg/", "/") for t in types)
    if topic is None:
        have = [k for k, v in topics.items() if v in types]
        if len(have) != 1:
            raise ScenarioError(f"{field}: {path} has {len(have)} {kinds} topics; name one (topic = …). Its topics: {listing}")
        return have[0]
    if not isinstance(topic, str) or topic not in topics:
        raise ScenarioError(f"{field} = {topic!r}: not a topic of {path}; its topics: {listing}")
    if topics[topic] not in types:
        raise ScenarioError(f"{field} = {topic!r}: a {topics[topic]} topic, not {kinds}")
    return topic


def _messages(path: Path, topic: str, values: Callable[[Any], tuple[float, ...]]) -> np.ndarray:
    """(K, 1 + m): per message on ``topic``, in bag order, its stamp (s of its own scale) and
    the m numbers ``values`` takes from it (the messages themselves are not kept: an hour of
    a 400 Hz IMU is 1.4 million of them)."""
    out = []
    reader = _open(path)
    try:
        with reader as r:
            conns = [c for c in r.connections if c.topic == topic]
            for conn, _, raw in r.messages(connections=conns):
                m = r.deserialize(raw, conn.msgtype)
                out.append((m.header.stamp.sec + m.header.stamp.nanosec * 1e-9, *values(m)))
    except Exception as e:  # the library's errors, and whatever a damaged bag raises in it
        raise ScenarioError(f"{path}: the ROS bag's topic {topic} cannot be read ({type(e).__name__}: {e})") from None
    return np.array(out, float).reshape(len(out), -1)


def _gps(t: np.ndarray, scale: Any, field: str) -> np.ndarray:
    if scale not in TIME_SCALES:
        raise ScenarioError(f"{field} = {scale!r}: 'unix' (ROS time: Unix time, UTC; the default) or 'gpst' (a driver stamping GPS time)")
    return unix_to_gps(t) if scale == "unix" else t


def read_ros_imu(path: str | Path, topic: str | None = None, time_scale: str = "unix", max_gap: float = 1.0) -> ImuLog:
    """The IMU of a ROS bag's ``sensor_msgs/Imu`` topic (``topic``; the bag's only one when
    None) as an :class:`~navfdi.logs.ImuLog`: ``angular_velocity`` (rad/s) and
    ``linear_acceleration`` (m/s²) in the IMU's axes at the messages' stamps, on GPS time
    (``time_scale``: "unix" or "gpst"). Messages at the time of the one before them are left out
    with a :class:`~navfdi.LeftOutSamplesWarning`; messages out of time order are sorted.
    Raises :class:`~navfdi.ScenarioError` for a missing or ambiguous topic (listing the bag's),
    a gap longer than ``max_gap`` s, a sample beyond any IMU's range, gravity removed."""
    path = Path(path)
    topic = _topic(path, topic, _IMU, "source.imu.topic")
    msgs = _messages(path, topic, lambda m: (m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z,
                                             m.linear_acceleration.x, m.linear_acceleration.y, m.linear_acceleration.z))
    if len(msgs) < 2:
        raise ScenarioError(f"{path}: {len(msgs)} message(s) on {topic}: too few for an IMU log")
    t, w, f = msgs[:, 0], msgs[:, 1:4], msgs[:, 4:7]
    order = np.argsort(t, kind="stable")
    t, w, f = t[order], w[order], f[order]
    twice = np.r_[False, np.diff(t) == 0]
    if twice.any():
        import warnings

        from navfdi._errors import LeftOutSamplesWarning

        warnings.warn(f"the IMU log {path}: {int(twice.sum())} message(s) on {topic} stamped at the time of the one before them left out",
                      LeftOutSamplesWarning, stacklevel=2)
        t, w, f = t[~twice], w[~twice], f[~twice]
    return checked_imu(_gps(t, time_scale, "source.imu.time_scale"), w, f, path, max_gap)


def fix_messages(path: str | Path, topic: str | None = None, velocity_topic: str | None = None, time_scale: str = "unix") -> dict[str, np.ndarray]:
    """The fixes of a ROS bag's ``sensor_msgs/NavSatFix`` topic (the bag's only one when
    ``topic`` is None) as arrays (M,) or (M, 3): ``t`` GPS seconds, ``lat``, ``lon`` (deg),
    ``height`` (m; NavSatFix's altitude is above the WGS 84 ellipsoid), ``sd`` σ east, north,
    up (m, from ``position_covariance``'s diagonal, east-north-up; NaN where its type is
    unknown), ``q`` (RTKLIB's codes from ``status.status``: 0 fix → 5 single, 1 SBAS → 3, 2
    ground-based augmentation (DGPS, RTK) → 4), ``no_fix`` (status −1: no fix) and, with
    ``velocity_topic``, ``vel`` and ``sd_vel`` east, north, up (m/s) at the fixes stamped the
    same (within 5 ms; NaN elsewhere). Read by :func:`navfdi.gnss_logs.read_ros_fixes`."""
    path = Path(path)
    topic = _topic(path, topic, _FIX, "source.gnss.topic")
    def fix(m: Any) -> tuple[float, ...]:
        c = np.asarray(m.position_covariance, float)[[0, 4, 8]] if m.position_covariance_type > 0 else (math.nan,) * 3
        return (m.latitude, m.longitude, m.altitude, *c, float(m.status.status))

    msgs = _messages(path, topic, fix)
    if not len(msgs):
        raise ScenarioError(f"{path}: no message on {topic}")
    t = _gps(msgs[:, 0], time_scale, "source.gnss.time_scale")
    cov, status = msgs[:, 4:7], msgs[:, 7]
    out = {
        "t": t, "lat": msgs[:, 1], "lon": msgs[:, 2], "height": msgs[:, 3], "sd": np.sqrt(np.where(cov > 0, cov, np.nan)),
        "q": np.select([status == 0, status == 1, status == 2], [5.0, 3.0, 4.0], 0.0), "no_fix": status < 0,
        "vel": np.full((len(msgs), 3), np.nan), "sd_vel": np.full((len(msgs), 3), np.nan),
    }
    if velocity_topic is not None:
        vt = _topic(path, velocity_topic, _TWIST, "source.gnss.velocity_topic")

        def twist(m: Any) -> tuple[float, ...]:
            x = m.twist.twist if hasattr(m.twist, "twist") else m.twist  # with covariance, or a plain TwistStamped
            c = np.asarray(m.twist.covariance, float)[[0, 7, 14]] if hasattr(m.twist, "covariance") else (math.nan,) * 3
            return (x.linear.x, x.linear.y, x.linear.z, *c)

        vm = _messages(path, vt, twist)
        if len(vm):
            tv = _gps(vm[:, 0], time_scale, "source.gnss.time_scale")
            v, var = vm[:, 1:4], vm[:, 4:7]
            order = np.argsort(tv)
            tv, v, var = tv[order], v[order], var[order]
            j = np.clip(np.searchsorted(tv, t), 1, len(tv)) - 1
            j = np.where((j + 1 < len(tv)) & (np.abs(tv[np.minimum(j + 1, len(tv) - 1)] - t) < np.abs(tv[j] - t)), j + 1, j)
            near = np.abs(tv[j] - t) <= 5e-3
            out["vel"][near] = v[j[near]]
            out["sd_vel"][near] = np.sqrt(np.where(var[j[near]] > 0, var[j[near]], np.nan))
    if not math.isfinite(float(np.nanmax(np.abs(out["lat"])))):
        raise ScenarioError(f"{path}: no fix on {topic} has a latitude")
    return out
