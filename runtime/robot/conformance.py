"""``check_controller``: does a controller keep the contract? (run over every built-in one).

It drives the controller through a small synthetic mission in an empty 4 m x 4 m room
(no simulator: observations are made up from the commands it sends, by unicycle
integration) and reports every broken promise as a sentence. A controller that conforms
returns an empty list. This module must never import pybullet.
"""

from __future__ import annotations

import math

import numpy as np

from rei.catalogue import DriveSpec, LaserSpec
from rei.runtime.messages import LaserScan, NavState
from rei.runtime.robot.contract import (
    TERMINAL,
    ContractViolation,
    Controller,
    ControllerContext,
    MapObstacle,
    NavGoal,
    Observation,
    VelocityCommand,
    checked_command,
    checked_feedback,
    observable_transition,
    read_only_scan,
)

DT = 0.1


def checker_context() -> ControllerContext:
    walls = []
    for k in range(-1, 6):
        for (x, y) in ((k, -1), (k, 5), (-1, k), (5, k)):
            walls.append(MapObstacle(f"w{x}_{y}", "wall", float(x), float(y), 0.0, "box",
                                     1.0, 1.0))
    unique = {w.name: w for w in walls}
    return ControllerContext(
        robot_size=(0.281, 0.306), drive=DriveSpec(0.26, 1.82, 0.287, 0.033),
        laser=LaserSpec(90, 0.12, 3.5, 5.0, 2 * math.pi), start_pose=(0.0, 0.0, 0.0),
        obstacles=tuple(unique[k] for k in sorted(unique)), bounds=(-1.5, -1.5, 5.5, 5.5),
        tile_size=1.0, control_rate=1 / DT, seed=0)


def _scan() -> LaserScan:
    return LaserScan(-math.pi, 2 * math.pi / 90, 0.12, 3.5, np.full(90, 3.5))


def _drive(controller: Controller, ctx: ControllerContext, steps: int, t0: float,
           pose: list[float], problems: list[str], trace: list[VelocityCommand],
           states: list[NavState]) -> float:
    t = t0
    for _ in range(steps):
        obs = Observation(t, (pose[0], pose[1], pose[2]), (0.0, 0.0), read_only_scan(_scan()),
                          t)
        try:  # the run's own boundary check: what fails here ends a run in error
            cmd = checked_command(controller.step(obs))
        except ContractViolation as problem:
            what = "sent a non-finite command" if problem.non_finite else "broke the contract"
            problems.append(f"step() {what}: {problem}")
            return t
        if (abs(cmd.linear) > ctx.drive.max_linear + 1e-9
                or abs(cmd.angular) > ctx.drive.max_angular + 1e-9):
            problems.append(f"step() exceeded the drive limits: {cmd}")
        trace.append(cmd)
        pose[0] += cmd.linear * math.cos(pose[2]) * DT
        pose[1] += cmd.linear * math.sin(pose[2]) * DT
        pose[2] = math.remainder(pose[2] + cmd.angular * DT, math.tau)
        try:
            fb = checked_feedback(controller.feedback())
        except ContractViolation as problem:
            problems.append(f"feedback() broke the contract: {problem}")
            return t
        if not observable_transition(states[-1], fb.state):
            problems.append(f"illegal goal state change {states[-1].value} -> {fb.state.value}")
        states.append(fb.state)
        t += DT
        if fb.state in TERMINAL:
            break
    return t


def check_controller(controller: Controller, steps: int = 600) -> list[str]:
    """Problems of ``controller`` with the contract (empty when it conforms)."""
    problems: list[str] = []
    for attr in ("name", "reset", "send_goal", "cancel_goal", "feedback", "step"):
        if not hasattr(controller, attr):
            problems.append(f"has no '{attr}'")
    if problems:
        return problems
    ctx = checker_context()
    runs: list[list[VelocityCommand]] = []
    for _ in range(2):
        trace: list[VelocityCommand] = []
        try:
            controller.reset(ctx)
            fb = controller.feedback()
            if fb.state != NavState.IDLE:
                problems.append(f"after reset() the goal state is {fb.state.value}, expected idle")
            states = [NavState.IDLE]
            goal = NavGoal("check", 1.0, 0.0, None, 0.3, 60.0)
            controller.send_goal(goal)
            fb = controller.feedback()
            if fb.state not in (NavState.PENDING, NavState.ACTIVE):
                problems.append(f"after send_goal() the state is {fb.state.value}, expected "
                                f"pending or active")
            states.append(fb.state)
            pose = [0.0, 0.0, 0.0]
            t = _drive(controller, ctx, steps, 0.0, pose, problems, trace, states)
            if states[-1] not in TERMINAL:
                problems.append(f"a goal 1 m ahead in an empty room did not end in {steps} steps "
                                f"(state {states[-1].value})")
            # A second goal, cancelled while running, must end PREEMPTED (or already be over).
            controller.send_goal(NavGoal("cancelled", 3.0, 3.0, 0.0, 0.3, 60.0))
            states.append(controller.feedback().state)
            _drive(controller, ctx, 3, t, pose, problems, trace, states)
            was_running = controller.feedback().state in (NavState.PENDING, NavState.ACTIVE)
            controller.cancel_goal()
            end = controller.feedback().state
            if was_running and end != NavState.PREEMPTED:
                problems.append(f"cancel_goal() on a running goal left it {end.value}, "
                                f"expected preempted")
        except Exception as exc:  # noqa: BLE001  (a broken controller is what we report)
            problems.append(f"raised {type(exc).__name__}: {exc}")
            return list(dict.fromkeys(problems))
        runs.append(trace)
    if runs[0] != runs[1]:
        problems.append("two runs after reset() with the same observations gave different "
                        "commands (state leaks across reset or the controller is not "
                        "deterministic)")
    # Both runs (and every step) meet the same broken promise: say each one once.
    return list(dict.fromkeys(problems))
