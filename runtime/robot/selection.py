"""Choosing the robot under test: `reference`, `teleop`, `teleop:circle`, `ros2[:options]`
(a ROS 2 stack over a Zenoh router, docs/ros2.md), or `module:Class`.

``make_controller`` starts the robot under test in its own process (``HostedController``,
see ``rei.runtime.robot.host``): `rei run` and campaigns use it, so a controller cannot end,
stall or falsify its own test. ``load_controller`` (``loading``) makes the same controller in
this process (the host itself uses it; so may a library caller that trusts the controller,
e.g. to read its class or to call it without the cost of messages).
"""

from __future__ import annotations

from rei.runtime.robot.host.caller import HostedController
from rei.runtime.robot.loading import (
    BUILT_IN,
    is_ros2,
    load_controller,
    ros2_options,
)


def make_controller(spec: str, folder: str | None = None) -> HostedController:
    """A fresh controller for ``spec`` running in its own process (stop it with ``close``;
    a user's module is imported from ``folder``, default the current one); RunError naming
    the choices when unknown, the same as ``load_controller``'s."""
    if is_ros2(spec):
        ros2_options(spec)  # a wrong option is said without starting a process
    elif spec not in BUILT_IN and (":" not in spec or spec.startswith("teleop:")):
        load_controller(spec)  # a mistyped built-in name is said without starting a process
    return HostedController(spec, folder)


__all__ = ["make_controller"]
