"""Choosing the robot under test: `reference`, `teleop`, `teleop:circle`, `ros2[:options]`
(a ROS 2 stack over a Zenoh router, docs/ros2.md), or `module:Class`.

``make_controller`` starts the robot under test in its own process (``HostedController``,
see ``rei.runtime.robot.host``): `rei run` and campaigns use it, so a controller cannot end,
stall or falsify its own test. ``load_controller`` makes the same controller in this process
(the host itself uses it; so may a library caller that trusts the controller, e.g. to read
its class or to call it without the cost of messages).
"""

from __future__ import annotations

import importlib
import os
import sys
from typing import TYPE_CHECKING

from rei.lang.suggest import did_you_mean
from rei.runtime.errors import RunError
from rei.runtime.robot.contract import Controller
from rei.runtime.robot.host import HostedController
from rei.runtime.robot.navigator.reference import ReferenceNavigator
from rei.runtime.robot.teleop import SCRIPTS, TeleopController

if TYPE_CHECKING:
    from rei.runtime.bus.ros2.adapter import Ros2Options

BUILT_IN = ("reference", "teleop", *(f"teleop:{s}" for s in sorted(SCRIPTS)))
"""The controllers that run on their own (``ros2`` needs a ROS 2 stack on a router)."""


def _is_ros2(spec: str) -> bool:
    return spec == "ros2" or spec.startswith("ros2:")


def make_controller(spec: str, folder: str | None = None) -> HostedController:
    """A fresh controller for ``spec`` running in its own process (stop it with ``close``;
    a user's module is imported from ``folder``, default the current one); RunError naming
    the choices when unknown, the same as ``load_controller``'s."""
    if _is_ros2(spec):
        _ros2_options(spec)  # a wrong option is said without starting a process
    elif spec not in BUILT_IN and (":" not in spec or spec.startswith("teleop:")):
        load_controller(spec)  # a mistyped built-in name is said without starting a process
    return HostedController(spec, folder)


def load_controller(spec: str, folder: str | None = None) -> Controller:
    """A fresh controller for ``spec`` in this process (a user's module imported from
    ``folder``, default the current one); RunError naming the choices when unknown."""
    if spec == "reference":
        return ReferenceNavigator()
    if spec == "teleop":
        return TeleopController()
    if _is_ros2(spec):
        from rei.runtime.bus.ros2.adapter import Ros2Controller  # noqa: PLC0415  (zenoh is heavy)
        return Ros2Controller(_ros2_options(spec))
    if spec.startswith("teleop:"):
        script = spec.split(":", 1)[1]
        if script not in SCRIPTS:
            raise RunError(f"--controller: expected a teleop script among "
                           f"{', '.join(sorted(SCRIPTS))}, found '{script}'"
                           + did_you_mean(script, sorted(SCRIPTS)))
        return TeleopController(script)
    if ":" in spec:
        module_name, _, attr = spec.partition(":")
        # Like `python -m`, a user's controller module is found from the current folder too
        # (the `rei` console script alone would only search the installed packages).
        home = os.getcwd() if folder is None else folder
        if home not in sys.path:
            sys.path.append(home)
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:
            raise RunError(f"--controller: cannot import module '{module_name}': {exc}") from None
        factory = getattr(module, attr, None)
        if factory is None:
            raise RunError(f"--controller: module '{module_name}' has no '{attr}'")
        try:
            controller = factory()
        except Exception as exc:  # noqa: BLE001  (user code)
            raise RunError(f"--controller: '{spec}()' raised {type(exc).__name__}: {exc}") from None
        if not isinstance(controller, Controller):
            raise RunError(f"--controller: '{spec}()' expected an object with name, reset, "
                           f"send_goal, cancel_goal, feedback and step, found "
                           f"{type(controller).__name__}")
        return controller
    raise RunError(f"--controller: expected one of {', '.join(BUILT_IN)}, ros2[:options] or "
                   f"module:Class, found '{spec}'" + did_you_mean(spec, [*BUILT_IN, "ros2"]))


def _ros2_options(spec: str) -> Ros2Options:
    from rei.runtime.bus.ros2.adapter import parse_options  # noqa: PLC0415
    from rei.runtime.bus.ros2.errors import Ros2Error  # noqa: PLC0415
    try:
        return parse_options(spec.partition(":")[2])
    except Ros2Error as exc:
        raise RunError(str(exc)) from None
