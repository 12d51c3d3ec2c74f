"""Making the robot under test in this process from its name: `reference`, `teleop`,
`teleop:SCRIPT`, `ros2[:options]` or a user's `module:Class`.

``load_controller`` is what the controller host's process runs (rei.runtime.robot.host), and
what a library caller that trusts the controller may call itself. The ROS 2 adapter belongs
to the bus wing, above this one: it is imported by name when asked for, as a user's module
is. This module must never import pybullet, the simulation or the bus.
"""

from __future__ import annotations

import importlib
import os
import sys
from types import ModuleType
from typing import Any

from rei.lang.suggest import did_you_mean
from rei.runtime.errors import RunError
from rei.runtime.robot.contract import Controller
from rei.runtime.robot.navigator.reference import ReferenceNavigator
from rei.runtime.robot.teleop import SCRIPTS, TeleopController

BUILT_IN = ("reference", "teleop", *(f"teleop:{s}" for s in sorted(SCRIPTS)))
"""The controllers that run on their own (``ros2`` needs a ROS 2 stack on a router)."""

ROS2_ADAPTER = "rei.runtime.bus.ros2.adapter"
"""The module behind ``ros2[:options]`` (its ``parse_options``, ``Ros2Controller`` and
``Ros2Error``), imported by name when asked for, as a user's ``module:Class`` is: the ROS 2
adapter lives in the bus wing, above the robot wing, which never imports it (and zenoh is
heavy)."""


def is_ros2(spec: str) -> bool:
    return spec == "ros2" or spec.startswith("ros2:")


def load_controller(spec: str, folder: str | None = None) -> Controller:
    """A fresh controller for ``spec`` in this process (a user's module imported from
    ``folder``, default the current one); RunError naming the choices when unknown."""
    if spec == "reference":
        return ReferenceNavigator()
    if spec == "teleop":
        return TeleopController()
    if is_ros2(spec):
        controller: Controller = _ros2_adapter().Ros2Controller(ros2_options(spec))
        return controller
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


def _ros2_adapter() -> ModuleType:
    return importlib.import_module(ROS2_ADAPTER)


def ros2_options(spec: str) -> Any:
    """The adapter's ``Ros2Options`` for ``spec``'s options; RunError naming a wrong one."""
    adapter = _ros2_adapter()
    try:
        return adapter.parse_options(spec.partition(":")[2])
    except adapter.Ros2Error as exc:
        raise RunError(str(exc)) from None
