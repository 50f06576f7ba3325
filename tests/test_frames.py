"""IMU frames that cannot be silently wrong: mounting by axis names, and every wrong axis
assignment of a right-forward-up IMU flagged (an error where gravity lands on the wrong axis,
a FrameWarning where the run shows it)."""

from __future__ import annotations

import itertools
import math
import warnings
from pathlib import Path

import numpy as np
import pytest

import navfdi
from navfdi._lc_schema import axes_mounting
from navfdi.frames import check_gravity
from navfdi.scenario import ScenarioError, from_dict, load_scenario
from navfdi.simlog import simulate_log

_V = {"forward": (1, 0, 0), "back": (-1, 0, 0), "right": (0, 1, 0), "left": (0, -1, 0), "down": (0, 0, 1), "up": (0, 0, -1)}


def _right_handed() -> list[list[str]]:
    out = []
    for a, b in itertools.permutations(_V, 2):
        va, vb = np.array(_V[a]), np.array(_V[b])
        if va @ vb == 0:
            c = tuple(np.cross(va, vb))
            out.append([a, b, next(k for k, v in _V.items() if v == c)])
    return out


def test_axis_names_give_the_mounting() -> None:
    """Forward-right-down axes are no rotation; right-forward-up is a 180° roll and a 90° yaw
    (x right, y forward, z up); a left-handed set is refused."""
    assert np.allclose(axes_mounting(["forward", "right", "down"]), 0.0)
    r, p, y = axes_mounting(["right", "forward", "up"])
    from navfdi._lc_schema import _rot

    c = _rot(r, p, y).T  # C_imu^b: its columns are the IMU axes in the body
    assert np.allclose(c, np.array([_V["right"], _V["forward"], _V["up"]]).T)
    with pytest.raises(ValueError, match="right-handed"):
        axes_mounting(["forward", "right", "up"])
    assert len(_right_handed()) == 24


@pytest.mark.parametrize("axes", _right_handed(), ids=lambda a: "-".join(a))
def test_every_axis_set_gives_its_own_mounting(axes: list[str]) -> None:
    """All 24 axis sets: the mounting's rotation has the named axes as its columns. With x up
    or down the pitch is ±90° and the Euler angles read 0/0: six sets (up-left-back among
    them) were given the mounting of the set with y and z turned 180° about x (a user's
    correct names then refused as gravity on the wrong axis, or a simulated log written with
    the other axes)."""
    from navfdi._lc_schema import _rot

    c = _rot(*axes_mounting(axes)).T
    assert np.allclose(c, np.array([_V[a] for a in axes]).T, atol=1e-12), np.round(c, 3)


def test_a_simulated_imu_with_x_up_has_gravity_on_x(tmp_path: Path) -> None:
    """An IMU simulated with x up (y left, z back) reads the specific force at rest, +g, on
    +x (before: on −x, its axes turned 180° about x, and its own scenario's names agreed with
    the wrong data)."""
    log = simulate_log(tmp_path, duration=60, seed=1, imu_axes=("up", "left", "back"))
    acc = np.loadtxt(log.imu, delimiter=",", skiprows=1)[:, 5:8]
    f = np.median(acc, axis=0)
    assert f[0] > 9.5 and abs(f[1]) < 1.0 and abs(f[2]) < 1.0, f


@pytest.fixture(scope="module")
def rfu(tmp_path_factory: pytest.TempPathFactory) -> navfdi.Scenario:
    log = simulate_log(tmp_path_factory.mktemp("rfu"), duration=300, seed=3, imu_axes=("right", "forward", "up"), scenario_mounting="nominal")
    return load_scenario(str(log.scenario))


@pytest.mark.parametrize("axes", _right_handed(), ids=lambda a: "-".join(a))
def test_every_wrong_axis_assignment_is_flagged(rfu: navfdi.Scenario, axes: list[str]) -> None:
    raw = dict(rfu.raw)
    raw["loosely_coupled"] = {**raw["loosely_coupled"], "imu_axes": axes}
    sc = from_dict(raw, source=rfu.source)
    right = axes == ["right", "forward", "up"]
    with warnings.catch_warnings(record=True) as w:
        warnings.simplefilter("always")
        try:
            run = navfdi.run_scenario(sc).runs["fde"]
        except ScenarioError as e:
            assert not right
            assert "imu_axes" in str(e) and "+z axis carries gravity" in str(e) and 'imu_axes[2] = "up"' in str(e)
            return
    flagged = [x for x in w if issubclass(x.category, navfdi.FrameWarning)]
    if right:
        assert not flagged and run.errors()["hor_rms"] < 1.0
    else:
        assert flagged, f"{axes}: ran without a FrameWarning"
        assert "imu_axes" in str(flagged[0].message)


def test_gravity_check_leaves_the_bundled_logs_alone() -> None:
    for name, sec in (("drive_lc", "loosely_coupled"), ("walk_tc", None)):
        sc = navfdi.load_scenario(name)
        from navfdi.logs import load_source, scenario_folder

        data = load_source(sc.raw["source"], scenario_folder(sc))
        table = sc.core["loosely_coupled"] if sec else sc.core["tight"]["strapdown"]
        check_gravity(data["imu_log"].accel, table["mounting"], sec or "tight.strapdown")


def test_gravity_check_tolerates_a_tilted_mounting() -> None:
    """A 20° tilt is a mounting, not a wrong axis: accepted; 40° is refused."""
    f = np.tile([0.0, 0.0, -9.81], (100, 1))  # forward-right-down IMU at rest
    check_gravity(f, [math.radians(20.0), 0.0, 0.0], "loosely_coupled")
    with pytest.raises(ScenarioError, match="40°"):
        check_gravity(f, [math.radians(40.0), 0.0, 0.0], "loosely_coupled")


def test_a_simulated_antenna_lever_arm(tmp_path: Path) -> None:
    """``simulate_log(lever_arm=…)``: the fixes, their velocities and the reference's position
    are the antenna's (the filters record the antenna's position). Given to the filter as the
    scenario writes it, the RTK run is as accurate as one without a lever arm; taken as 0 it is
    not (the fixes swing about the IMU in the turns); and the truth's GNSS errors stay the
    receiver's own (not the arm)."""
    kw = {"duration": 600, "seed": 3, "gnss_sigma": 0.02}
    plain = navfdi.run_scenario(load_scenario(str(simulate_log(tmp_path / "p", **kw).scenario))).runs["fde"].errors()["hor_rms"]
    log = simulate_log(tmp_path / "a", lever_arm=(1.0, 0.3, -1.0), **kw)
    sc = load_scenario(str(log.scenario))
    assert [float(v.split()[0]) for v in sc.raw["loosely_coupled"]["lever_arm"]] == [1.0, 0.3, -1.0]
    given = navfdi.run_scenario(sc).runs["fde"].errors()["hor_rms"]
    assert given <= 1.1 * plain
    zero = navfdi.run_scenario(sc.with_values({"loosely_coupled.lever_arm": ["0 m", "0 m", "0 m"]})).runs["fde"].errors()["hor_rms"]
    assert zero > 1.25 * given
    truth = np.genfromtxt(log.truth, delimiter=",", names=True)
    assert np.sqrt(np.mean(truth["error_e"] ** 2 + truth["error_n"] ** 2)) < 0.05
    with pytest.raises(ValueError, match="lever_arm"):
        simulate_log(tmp_path / "bad", duration=60, lever_arm=(float("nan"), 0.0, 0.0))
