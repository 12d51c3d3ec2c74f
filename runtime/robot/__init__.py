"""The robot under test: controller protocol, built-in controllers, conformance checker."""

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
from rei.runtime.robot.selection import BUILT_IN, load_controller, make_controller

__all__ = ["BUILT_IN", "Controller", "ControllerContext", "GoalFeedback", "GoalTracker",
           "HostedController", "MapObstacle", "NavGoal", "Observation", "VelocityCommand",
           "check_controller", "load_controller", "make_controller"]
