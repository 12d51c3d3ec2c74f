"""The robot under test: the controller contract a test engineer implements (``contract``) and
its checker (``check_controller``), the built-in controllers (``teleop``, the reference
navigator in ``navigator/``), the host that runs a controller in its own process (``host``),
the watchdog that calls it safely (``watchdog``), and choosing one by name (``selection``,
``loading``).

It may import the platform and the contracts at runtime's root; it must never import the
simulation (or pybullet), the bus or anything above: the robot sees only what its sensors
measured. The ROS 2 adapter lives in the bus wing and is loaded by module name.
"""

from rei.runtime.robot.conformance import check_controller
from rei.runtime.robot.contract import (
    Controller,
    ControllerContext,
    GoalFeedback,
    GoalTracker,
    MapObstacle,
    NavGoal,
    Observation,
    VelocityCommand,
)
from rei.runtime.robot.host import HostedController
from rei.runtime.robot.loading import BUILT_IN, load_controller
from rei.runtime.robot.selection import make_controller

__all__ = ["BUILT_IN", "Controller", "ControllerContext", "GoalFeedback", "GoalTracker",
           "HostedController", "MapObstacle", "NavGoal", "Observation", "VelocityCommand",
           "check_controller", "load_controller", "make_controller"]
