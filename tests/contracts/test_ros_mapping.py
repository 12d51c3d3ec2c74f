"""The shared ROS 2 mapping both ways: REI -> ROS messages (RosViews) decoded by rosbags and
converted back (pose_of, scan_of, odometry_of, command_of) give REI's values within the
precision of the ROS types (float32 ranges, a yaw through a quaternion)."""

from __future__ import annotations

import math
import re
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_typestore

from rei.runtime.messages.ros import (
    NAV2_STATUS,
    ODOMETRY,
    SCAN,
    STATUS_UNKNOWN,
    TF,
    TWIST,
    RosViews,
    command_of,
    odometry_of,
    pose_of,
    scan_geometry_problem,
    scan_of,
    seconds,
    yaw_of,
)
from tests.observation.test_recording import _long_samples

STORE = get_typestore(Stores.ROS2_HUMBLE)


def test_rei_to_ros_and_back_gives_the_samples_values() -> None:
    header, samples = _long_samples(12)
    views = RosViews()
    for sample in samples:
        tf = STORE.deserialize_cdr(views.transforms(sample, header, [0, 1]), TF)
        robot = tf.transforms[0]
        assert robot.child_frame_id == header.robot.name and robot.header.frame_id == "map"
        assert seconds(robot.header.stamp) == pytest.approx(sample.time, abs=1e-9)
        x, y, yaw = pose_of(robot.transform)
        assert (x, y) == sample.robot_pose[:2]
        assert math.remainder(yaw - sample.robot_pose[2], math.tau) == pytest.approx(0, abs=1e-12)
        for item, row in zip(tf.transforms[1:], sample.poses, strict=True):
            back = pose_of(item.transform)
            assert back[:2] == tuple(row[:2])
            assert math.remainder(back[2] - row[2], math.tau) == pytest.approx(0, abs=1e-12)
        odom = STORE.deserialize_cdr(views.odometry(sample, header), ODOMETRY)
        (ox, oy, oyaw), twist = odometry_of(odom)
        assert (ox, oy) == sample.belief.odom[:2] and twist == sample.belief.odom_twist
        assert math.remainder(oyaw - sample.belief.odom[2], math.tau) == pytest.approx(
            0, abs=1e-12)
        assert command_of(STORE.deserialize_cdr(views.command(sample), TWIST)) == \
            sample.belief.cmd
        raw = views.scan(sample, header, 0.2)
        if raw is None:
            continue
        message = STORE.deserialize_cdr(raw, SCAN)
        assert scan_geometry_problem(message) == ""
        scan, original = scan_of(message), sample.belief.scan
        assert original is not None
        assert scan.angle_increment == pytest.approx(original.angle_increment, rel=1e-7)
        assert scan.range_max == pytest.approx(original.range_max, rel=1e-7)
        np.testing.assert_allclose(scan.ranges, original.ranges, rtol=1e-7)


@given(st.floats(-math.pi, math.pi))
def test_a_yaw_through_a_quaternion_comes_back(yaw: float) -> None:
    q = SimpleNamespace(x=0.0, y=0.0, z=math.sin(yaw / 2), w=math.cos(yaw / 2))
    assert math.remainder(yaw_of(q) - yaw, math.tau) == pytest.approx(0.0, abs=1e-12)


def test_no_return_is_inf_in_ros_and_range_max_in_rei() -> None:
    message = SimpleNamespace(ranges=np.array([1.0, np.inf, np.nan], dtype=np.float32),
                              angle_min=-1.0, angle_max=1.0, angle_increment=1.0,
                              range_min=0.1, range_max=3.5)
    scan = scan_of(message)
    assert scan.ranges[0] == 1.0 and scan.ranges[1] == 3.5 and math.isnan(scan.ranges[2])


@pytest.mark.parametrize(("ranges", "inc", "problem"), [
    (3, 0.0, "non-zero angle_increment"), (3, math.nan, "finite angles"),
    (5, 1.0, "3 ranges .* found 5"), (1, 1.0, "3 ranges .* found 1")])
def test_a_scan_header_that_does_not_describe_its_ranges_is_named(
        ranges: int, inc: float, problem: str) -> None:
    message = SimpleNamespace(ranges=np.ones(ranges, dtype=np.float32), angle_min=-1.0,
                              angle_max=1.0, angle_increment=inc)
    assert scan_geometry_problem(message) != ""
    assert re.search(problem, scan_geometry_problem(message))


def test_every_nav2_goal_status_has_a_navigation_state() -> None:
    status = STORE.types["action_msgs/msg/GoalStatus"]
    codes = {getattr(status, n) for n in dir(status) if n.startswith("STATUS_")}
    # STATUS_UNKNOWN is a status "not properly set" (action_msgs): it names no state
    assert status.STATUS_UNKNOWN == STATUS_UNKNOWN == 0
    assert codes - {STATUS_UNKNOWN} == set(NAV2_STATUS)
    assert STATUS_UNKNOWN not in NAV2_STATUS
