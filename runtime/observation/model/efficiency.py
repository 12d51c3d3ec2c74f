"""How well a navigation task was done: its path and time against the shortest collision-free
path, and how much the robot turned in place near its goal (thesis 2.4: goals reached "with
minimal manoeuvring and in the possible shortest time").

The shortest path (rei.runtime.observation.model.free_space: ``FloorGraph``, ``FreeSpace`` and
``footprint_shapes``, re-exported from here) runs from where the robot was when the task
started to the goal's point. A task is judged only when that path less the goal's tolerance is
at least ``MIN_JUDGED`` long: nearer goals give ratios of noise. This module must never import
pybullet, the simulation, the evaluator or the monitor's host.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rei.runtime.messages import GoalFacts

MIN_JUDGED = 0.5
"""m: a task whose shortest path less its tolerance is shorter is not judged (ratios 0)."""
SPIN_RADIUS = 0.5
"""m beyond the goal's tolerance within which turning in place counts as near the goal."""
IN_PLACE = 0.05
"""m/s: the robot turns in place while its own speed is below this."""


@dataclass
class TaskProgress:
    """What the model gathers about the running task."""

    start_xy: tuple[float, float]
    started: float
    goal: GoalFacts | None
    travelled: float = 0.0
    spin: float = 0.0
    """Radians turned in place near the goal."""

    def observe(self, xy: tuple[float, float], step: float, own_speed: float,
                own_yaw_rate: float, dt: float) -> None:
        self.travelled += step
        goal = self.goal
        if goal is not None and own_speed < IN_PLACE and math.hypot(
                xy[0] - goal.x, xy[1] - goal.y) <= goal.tolerance + SPIN_RADIUS:
            self.spin += abs(own_yaw_rate) * dt


@dataclass(frozen=True)
class TaskEfficiency:
    """The judged figures of a task that succeeded (ratios 0: not judged)."""

    shortest: float
    """Metres of the shortest path from the task's start to the goal's point (inf: no path
    over the floors)."""
    path_ratio: float
    """Path driven / shortest."""
    time_ratio: float
    """Time taken / the shortest path at the allowed speed."""
    spin: float


def judge_task(task: TaskProgress, ended: float, shortest: float,
               speed_limit: float) -> TaskEfficiency:
    """The task's figures against ``shortest``, the path to the goal's point itself (as SPL
    measures it): a navigator may stop anywhere within the goal's tolerance, but what it was
    sent to is the goal, and a path to its edge would make every short task of a navigator
    that drives onto its goal look long (1 m less a 0.3 m tolerance read a straight drive to
    within 0.1 m as 1.29 times the shortest path; issue 22). The tolerance only decides which
    tasks are long enough to judge."""
    tolerance = task.goal.tolerance if task.goal is not None else 0.0
    if not (math.isfinite(shortest) and shortest - tolerance >= MIN_JUDGED):
        return TaskEfficiency(shortest, 0.0, 0.0, task.spin)
    fastest = shortest / speed_limit if math.isfinite(speed_limit) and speed_limit > 0 else 0.0
    return TaskEfficiency(shortest, task.travelled / shortest,
                          (ended - task.started) / fastest if fastest > 0 else 0.0, task.spin)
