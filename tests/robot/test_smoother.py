"""The reference navigator's velocity smoother: commands within the drive's accelerations
(Nav2's rule for which limit applies), a braking path that ends standing, and safety first:
a smoothed command whose braking path would run into a laser point is not sent."""

from __future__ import annotations

import math

import numpy as np
import pytest

from rei.catalogue.model import DriveSpec
from rei.runtime.robot.contract import STOP, VelocityCommand
from rei.runtime.robot.navigator.reference import ReferenceNavigator
from rei.runtime.robot.navigator.smoother import (
    VelocitySmoother,
    clear_to_brake,
    smooth_safely,
)

DRIVE = DriveSpec(0.26, 1.82, 0.287, 0.033)  # Nav2's defaults: 2.5 m/s^2, 3.2 rad/s^2
HALF = (0.1405, 0.153)


def test_each_tick_moves_at_most_the_allowed_change() -> None:
    s = VelocitySmoother(DRIVE, 0.1)
    sent = [s.sent(s.smoothed(VelocityCommand(0.26, 1.82), 0.1 * k), 0.1 * k)
            for k in range(8)]
    assert sent[0] == VelocityCommand(pytest.approx(0.25), pytest.approx(0.32))
    assert sent[1].linear == pytest.approx(0.26)
    assert [c.angular for c in sent[:6]] == pytest.approx([0.32, 0.64, 0.96, 1.28, 1.6, 1.82])
    # slowing down takes the deceleration limit, reversing too (Nav2's rule)
    s.drive = DriveSpec(0.26, 1.82, 0.287, 0.033, max_linear_decel=1.0,
                        max_angular_decel=2.0)
    assert s.smoothed(STOP, 0.8) == VelocityCommand(pytest.approx(0.16), pytest.approx(1.62))
    assert s.smoothed(VelocityCommand(-0.26, -1.82), 0.8).linear == pytest.approx(0.16)


def test_a_late_tick_is_limited_by_the_time_since_the_last_one() -> None:
    s = VelocitySmoother(DRIVE, 0.1)
    s.sent(STOP, 0.0)
    assert s.smoothed(VelocityCommand(0.26, 0.0), 0.05).linear == pytest.approx(0.125)
    assert s.smoothed(VelocityCommand(0.26, 0.0), 0.0).linear == 0.0


def test_the_braking_path_ends_standing_within_the_deceleration_limits() -> None:
    s = VelocitySmoother(DRIVE, 0.1)
    poses = s.braking_poses(VelocityCommand(0.26, 1.0))
    steps = np.diff(poses, axis=0)
    # one period at the command, then v falls by 2.5 m/s^2 and w by 3.2 rad/s^2
    travel = float(np.hypot(steps[:, 0], steps[:, 1]).sum())
    assert travel == pytest.approx(0.026 + 0.26 ** 2 / 5.0, abs=0.006)
    assert float(poses[-1, 2]) == pytest.approx(0.1 + 1.0 / 6.4, abs=0.03)
    assert np.hypot(*steps[-1, :2]) < 1e-9 and abs(steps[-1, 2]) < 1e-9


def test_a_smoothed_command_running_into_a_point_is_not_sent() -> None:
    s = VelocitySmoother(DRIVE, 0.1)
    s.sent(VelocityCommand(0.26, 0.0), 0.0)
    # the planner turns away from a point 3 cm ahead of the front and to the left: the
    # smoothed command keeps driving ahead while it ramps the turn
    point = np.array([[HALF[0] + 0.03, 0.0]])
    planner = VelocityCommand(0.0, -1.09)
    smoothed = s.smoothed(planner, 0.1)
    assert not clear_to_brake(s, smoothed, point, HALF, 0.04)
    sent = smooth_safely(s, planner, 0.1, point, HALF, 0.04)
    assert sent == planner and s.bypassed == 1
    # with nothing near, the smoothed command is sent
    s2 = VelocitySmoother(DRIVE, 0.1)
    s2.sent(VelocityCommand(0.26, 0.0), 0.0)
    far = np.array([[2.0, 0.0]])
    assert smooth_safely(s2, planner, 0.1, far, HALF, 0.04) == smoothed
    assert s2.bypassed == 0 and not math.isclose(smoothed.angular, planner.angular)


def test_a_new_run_gets_a_new_smoother() -> None:
    from tests.robot.test_reference_recovery import context_of, corridor_walls  # noqa: PLC0415

    nav = ReferenceNavigator()
    nav.reset(context_of(corridor_walls()))
    first = nav._smoother
    first.sent(VelocityCommand(0.2, 0.0), 5.0)
    nav.reset(context_of(corridor_walls()))
    assert nav._smoother is not first and nav._smoother.last == STOP
