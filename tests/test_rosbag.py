"""ROS bags as logs (robotics data sets ship theirs so): a ``sensor_msgs/Imu`` topic as the IMU
log, a ``sensor_msgs/NavSatFix`` topic (with a velocity twist topic) as the GNSS log, read
without ROS by the ``rosbags`` library. The bundled drive written as a ROS 1 bag and as a ROS 2
bag, stamped in ROS time (Unix time, UTC), reads back as its own logs and runs as they do."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi import LeftOutFixesWarning, ScenarioError
from navfdi.gnss_logs import read_gnss
from navfdi.logs import read_imu, read_pos
from navfdi.scenario import from_dict, load_scenario

pytest.importorskip("rosbags")  # installed with navfdi[test]; navfdi[ros] for users

from rosbags.rosbag1 import Writer as Writer1  # noqa: E402
from rosbags.rosbag2 import Writer as Writer2  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

PKG = Path(str(resources.files("navfdi")))
SCENARIOS = PKG / "scenarios"
DRIVE = PKG / "data" / "drive_0708"
UNIX_GPS = 315964800  # the GPS epoch in Unix seconds
LEAP = 18


def drive_imu():
    return read_imu(DRIVE / "imu_1934_gpst.csv.gz", dict(load_scenario("drive_lc").raw["source"]["imu"]))


def write(path: Path, ros: int, end: float | None = None, no_fix: int | None = None) -> Path:
    """The drive as a ROS ``ros`` (1 or 2) bag up to ``end`` s: /imu/data (Imu), /imu/free (Imu
    with gravity removed), /ublox/fix (NavSatFix, every fix with status 2, σ² on the
    covariance's diagonal; fix number ``no_fix`` with status −1) and /ublox/fix_velocity
    (TwistWithCovarianceStamped, east, north, up), stamped in ROS time."""
    ts = get_typestore(Stores.ROS1_NOETIC if ros == 1 else Stores.ROS2_HUMBLE)
    T = ts.types
    imu, pos = drive_imu(), read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    last = pos.t[-1] if end is None else pos.t[0] + end
    ser = ts.serialize_ros1 if ros == 1 else ts.serialize_cdr

    def header(g: float):
        ns = int(round((g - LEAP + UNIX_GPS) * 1e9))
        stamp = T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        extra = {"seq": 0} if ros == 1 else {}
        return ns, T["std_msgs/msg/Header"](stamp=stamp, frame_id="imu_link", **extra)

    def v3(v):
        return T["geometry_msgs/msg/Vector3"](x=float(v[0]), y=float(v[1]), z=float(v[2]))

    def imu_msg(h, w, f):
        return T["sensor_msgs/msg/Imu"](header=h, orientation=T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0),
                                        orientation_covariance=np.full(9, -1.0), angular_velocity=v3(w),
                                        angular_velocity_covariance=np.zeros(9), linear_acceleration=v3(f),
                                        linear_acceleration_covariance=np.zeros(9))

    writer = Writer1(path) if ros == 1 else Writer2(path, version=9)
    with writer as w:
        ci = w.add_connection("/imu/data", "sensor_msgs/msg/Imu", typestore=ts)
        cf = w.add_connection("/imu/free", "sensor_msgs/msg/Imu", typestore=ts)
        cg = w.add_connection("/ublox/fix", "sensor_msgs/msg/NavSatFix", typestore=ts)
        cv = w.add_connection("/ublox/fix_velocity", "geometry_msgs/msg/TwistWithCovarianceStamped", typestore=ts)
        events = []
        for k in np.flatnonzero((imu.t >= pos.t[0] - 1) & (imu.t <= last + 1)):
            ns, h = header(float(imu.t[k]))
            events.append((ns, ci, imu_msg(h, imu.gyro[k], imu.accel[k]), "sensor_msgs/msg/Imu"))
            if k % 50 == 0:
                events.append((ns, cf, imu_msg(h, imu.gyro[k], imu.accel[k] * 0.01), "sensor_msgs/msg/Imu"))
        for j in np.flatnonzero(pos.t <= last):
            ns, h = header(float(pos.t[j]))
            cov = np.zeros(9)
            cov[[0, 4, 8]] = pos.sd_pos[j] ** 2
            fix = T["sensor_msgs/msg/NavSatFix"](header=h, status=T["sensor_msgs/msg/NavSatStatus"](status=-1 if j == no_fix else 2, service=1),
                                                 latitude=float(pos.lat[j]), longitude=float(pos.lon[j]), altitude=float(pos.height[j]),
                                                 position_covariance=cov, position_covariance_type=2)
            events.append((ns, cg, fix, "sensor_msgs/msg/NavSatFix"))
            vcov = np.zeros(36)
            vcov[[0, 7, 14]] = pos.sd_vel[j] ** 2
            tw = T["geometry_msgs/msg/TwistWithCovariance"](twist=T["geometry_msgs/msg/Twist"](linear=v3(pos.vel[j]), angular=v3((0, 0, 0))),
                                                            covariance=vcov)
            events.append((ns, cv, T["geometry_msgs/msg/TwistWithCovarianceStamped"](header=h, twist=tw),
                           "geometry_msgs/msg/TwistWithCovarianceStamped"))
        for ns, conn, msg, kind in sorted(events, key=lambda e: e[0]):
            w.write(conn, ns, ser(msg, kind))
    return path


@pytest.fixture(scope="module", params=[1, 2])
def bag(request: pytest.FixtureRequest, tmp_path_factory: pytest.TempPathFactory) -> Path:
    folder = tmp_path_factory.mktemp(f"ros{request.param}")
    return write(folder / ("drive.bag" if request.param == 1 else "drive"), request.param)


def test_the_imu_and_fixes_read_back_on_gps_time(bag: Path, tmp_path: Path):
    want = drive_imu()
    got = read_imu(bag, {"file": str(bag), "format": "rosbag", "topic": "/imu/data", "max_gap": 0.1})
    i = int(np.searchsorted(want.t, got.t[0] - 1e-4))
    np.testing.assert_allclose(got.t, want.t[i:i + len(got.t)], rtol=0, atol=2e-6)  # ns stamps; float64 GPS seconds
    np.testing.assert_array_equal(got.gyro, want.gyro[i:i + len(got.t)])
    np.testing.assert_array_equal(got.accel, want.accel[i:i + len(got.t)])
    pos = read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    fixes = read_gnss({"file": str(bag), "velocity_topic": "/ublox/fix_velocity"}, tmp_path)  # format told from the bag
    np.testing.assert_allclose(fixes.t, pos.t, rtol=0, atol=2e-6)
    np.testing.assert_array_equal(fixes.lat, pos.lat)
    np.testing.assert_allclose(fixes.sd_pos, pos.sd_pos, rtol=1e-12)
    np.testing.assert_array_equal(fixes.vel, pos.vel)
    assert (fixes.q == 4).all()  # status 2: ground-based augmentation, RTKLIB's DGPS code
    from navfdi.gnss_logs import read_reference

    ref, has_quality = read_reference({"file": str(bag), "topic": "/ublox/fix"}, tmp_path)
    assert not has_quality and len(ref.t) == len(pos.t)  # a bag's fixes as the reference: every epoch


def run(source: dict) -> navfdi.VariantRuns:
    """``drive_lc`` with ``source`` in place of its logs (its reference kept)."""
    raw = dict(load_scenario("drive_lc").raw)
    raw["source"] = {"reference": str((SCENARIOS / raw["source"]["reference"]).resolve()), "reference_quality": [1], **source}
    return navfdi.run_scenario(from_dict(raw, source=str(SCENARIOS / "drive_lc.toml")))


def test_the_drive_from_a_bag_runs_as_from_its_own_logs(bag: Path, tmp_path: Path):
    # The same fixes (one solution quality, as in the bag) and velocities as a CSV, and the IMU CSV.
    pos = read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    csv = tmp_path / "fixes.csv"
    cols = (pos.t, pos.lat, pos.lon, pos.height, *pos.vel.T, *pos.sd_pos.T, *pos.sd_vel.T)
    csv.write_text("t,lat,lon,h,ve,vn,vu,se,sn,su,sve,svn,svu\n" + "\n".join(",".join(repr(float(x)) for x in r) for r in zip(*cols)) + "\n")
    imu = dict(load_scenario("drive_lc").raw["source"]["imu"])
    imu["file"] = str((SCENARIOS / imu["file"]).resolve())
    columns = {"time": "t", "lat": "lat", "lon": "lon", "height": "h", "vel": ["ve", "vn", "vu"], "sd": ["se", "sn", "su"], "sd_vel": ["sve", "svn", "svu"]}
    a = run({"gnss": {"file": str(csv), "format": "csv", "columns": columns}, "imu": imu})
    b = run({"gnss": {"file": str(bag), "format": "rosbag", "topic": "/ublox/fix", "velocity_topic": "/ublox/fix_velocity"},
             "imu": {"file": str(bag), "format": "rosbag", "topic": "/imu/data", "max_gap": 0.1}})
    for v in ("fde", "no_fde"):
        ea, eb = a.runs[v].errors(), b.runs[v].errors()
        for k in ("hor_rms", "hor_max", "ver_rms"):
            assert eb[k] == pytest.approx(ea[k], rel=1e-4), (v, k, ea[k], eb[k])
    assert b.runs["fde"].errors()["hor_rms"] < 0.15 < 1.0 < b.runs["no_fde"].errors()["hor_rms"]  # the 20 m step held out


def test_bad_bags_and_settings_are_named(bag: Path, tmp_path: Path):
    with pytest.raises(ScenarioError, match=r"source.imu.topic: .* has 2 sensor_msgs/Imu topics; name one .*/imu/free \(Imu\)"):
        read_imu(bag, {"file": str(bag), "format": "rosbag"})
    with pytest.raises(ScenarioError, match=r"source.imu.topic = '/ublox/fix': a sensor_msgs/msg/NavSatFix topic, not sensor_msgs/Imu"):
        read_imu(bag, {"file": str(bag), "format": "rosbag", "topic": "/ublox/fix"})
    with pytest.raises(ScenarioError, match=r"source.imu.topic = '/imu': not a topic of"):
        read_imu(bag, {"file": str(bag), "format": "rosbag", "topic": "/imu"})
    with pytest.raises(ScenarioError, match=r"median specific force is 0.0\d+ m/s².*gravity removed"):
        read_imu(bag, {"file": str(bag), "format": "rosbag", "topic": "/imu/free", "max_gap": 1.0})
    with pytest.raises(ScenarioError, match=r"source.imu: gyro: not read with format = \"rosbag\""):
        read_imu(bag, {"file": str(bag), "format": "rosbag", "gyro": ["x", "y", "z"]})
    with pytest.raises(ScenarioError, match=r"source.imu.time_scale = 'boot': 'unix'"):
        read_imu(bag, {"file": str(bag), "format": "rosbag", "topic": "/imu/data", "time_scale": "boot", "max_gap": 0.1})
    with pytest.raises(ScenarioError, match=r"source.gnss.topic: read for format = \"rosbag\" only"):
        read_gnss({"file": str(DRIVE / "gnss_1934_sf.pos.gz"), "topic": "/fix"}, tmp_path)
    with pytest.raises(ScenarioError, match=r"source.gnss.velocity_topic = '/imu/data': a sensor_msgs/msg/Imu topic"):
        read_gnss({"file": str(bag), "velocity_topic": "/imu/data"}, tmp_path)
    broken = tmp_path / "broken.bag"
    broken.write_bytes(b"#ROSBAG V2.0\n" + bytes(200))
    with pytest.raises(ScenarioError, match=r"broken.bag: not a readable ROS bag"):
        read_gnss({"file": str(broken)}, tmp_path)


def test_fixes_without_a_fix_are_left_out_and_said(tmp_path: Path):
    path = write(tmp_path / "nofix.bag", 1, end=20.0, no_fix=3)
    with pytest.warns(LeftOutFixesWarning, match=r"1 fix\(es\) whose status says no fix"):
        got = read_gnss({"file": str(path)}, tmp_path)
    pos = read_pos(DRIVE / "gnss_1934_sf.pos.gz")
    want = np.delete(pos.t[pos.t <= pos.t[0] + 20.0], 3)
    np.testing.assert_allclose(got.t, want, rtol=0, atol=2e-6)
    assert np.isnan(got.vel).all()  # no velocity topic named: positions only
