"""Robustness margins: how far a run was from failing each default requirement.

A margin is signed, in the requirement's own unit (metres, m/s, seconds, a ratio, radians):
positive or zero when the requirement passed, negative exactly when it failed (closest
approach to a person minus the allowed distance, speed headroom, slack left under a ratio
threshold, ...). Search ranks runs by it; a user reads how near a pass came to failing.

Each definition (docs/vepl.md, "Robustness margins") belongs to one requirement of the
default specification and applies only where the specification's requirement is that one
(same name, clauses and premise; its parameters are read from the specification in use).
A requirement of a user's own, or one whose verdict rests on an event pattern rather than
a measured quantity, gets no margin: ``None``, never a made-up number. Likewise an
inconclusive or not-applicable verdict gets none, and a margin whose sign would disagree
with its verdict is dropped (with a note) rather than reported: the verdict is the judge.

This module reads the monitor's per-(sub)step inputs; it must never change a verdict, read
the wall clock or import the simulator.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace

from rei.runtime.messages import MissionFacts
from rei.runtime.observation.automata.records import QueryInputs, RequirementSpec
from rei.runtime.results import Verdict


@dataclass(frozen=True)
class MarginRule:
    unit: str
    meaning: str


RULES: dict[str, MarginRule] = {
    "MISSION_WITH_HUMAN_TRAJECTORY": MarginRule(
        "m", "closest footprint distance to a person minus eps_collision"),
    "NO_ROBOT_COLLISION": MarginRule(
        "m", "closest footprint distance to a body the robot's own motion closed in on "
             "(approach above v_contact) minus eps_collision; at most 0.5 m - eps_collision, "
             "as approach is worked out within 0.5 m"),
    "HUMAN_SLOW_ZONE": MarginRule(
        "m/s", "slow_speed + speed_tolerance minus the robot's fastest own speed while "
               "nearer than slow_zone to a person (none if it never came that near)"),
    "SPEED_LIMIT": MarginRule(
        "fraction", "the smaller headroom, as a fraction of the allowed value, of the "
                    "commanded and the driven speed (limit + speed_tolerance) and turn rate "
                    "(limit + turn_tolerance)"),
    "MISSION_GOALS_REACHED": MarginRule(
        "fraction", "share of its timeout left to the slowest goal reached; -1 when a goal "
                    "failed (aborted, timed out, abandoned or claimed out of tolerance)"),
    "GOAL_HEADING": MarginRule(
        "rad", "the goal's heading_tolerance minus the heading error at the worst claimed "
               "success (of goals with a heading)"),
    "EFFICIENT_PATH": MarginRule(
        "ratio", "max_path_ratio minus the largest path ratio of a judged task (none if "
                 "no task was judged)"),
    "TIME_TO_GOAL": MarginRule(
        "ratio", "max_time_ratio minus the largest time ratio of a judged task (none if "
                 "no task was judged)"),
    "NO_SPIN_AT_GOAL": MarginRule(
        "rad", "max_goal_spin minus the most a task turned in place near its goal (none "
               "if no task succeeded)"),
    "REACTION_TIME": MarginRule(
        "s", "the requirement's window minus the slowest reaction: for every moment the "
             "robot commanded more than slow_speed + speed_tolerance while its laser showed "
             "a hazard ahead nearer than react_zone, the time to the nearest command at the "
             "slow speed before or after it; one still awaited when the run ends counts to the "
             "last sample once that exceeds the window, and leaves no margin within it (none "
             "if that never happened)"),
    "SETTLE": MarginRule(
        "m", "settle_tolerance minus the most the robot's own motion covered in a settle "
             "period"),
    "COMMAND_ACCELERATION": MarginRule(
        "fraction", "the smallest headroom, as a fraction of the allowed value (the limit "
                    "times 1 + accel_margin), of the commands' linear and angular "
                    "accelerations and decelerations (none if the limits are not known)"),
    "COMMAND_AT_REST": MarginRule(
        "m/s or rad/s", "rest_tolerance minus the largest linear or angular command from "
                        "rest_after seconds into a settle period on"),
}
"""The default requirements that have a natural margin. The others (the laser and mission
patterns of thesis 5.1.2, SMOOTH_MOTION, COMMAND_CHATTER) are decided by event patterns and get
none."""

APPROACH_RANGE = 0.5
"""Metres within which the model works out approach(o)
(rei.runtime.observation.model.runtime_model)."""


@functools.cache
def _default_requirements() -> dict[str, RequirementSpec]:
    from rei.lang.vepl.document import load_vepl  # noqa: PLC0415  (parsed once, when needed)

    return {r.name: RequirementSpec(r.name, r.description, r.clauses, r.premise)
            for r in load_vepl(None).requirements}


def _wrap(angle: float) -> float:
    return abs(math.atan2(math.sin(angle), math.cos(angle)))


class MarginTracker:
    """Watches every (sub-)step of one run, like the queries do, and keeps the extremes the
    margins are made of."""

    def __init__(self, requirements: tuple[RequirementSpec, ...],
                 parameters: Mapping[str, float], facts: MissionFacts | None) -> None:
        defaults = _default_requirements()
        self.defined = {r.name for r in requirements
                        if r.name in RULES and defaults.get(r.name) == r}
        self.p = dict(parameters)
        self.facts = facts
        self.human_distance = math.inf
        self.drive_in_distance = math.inf
        self.zone_speed = -math.inf
        self.speed_headroom = math.inf
        self.path_ratio = 0.0
        self.time_ratio = 0.0
        self.spin = -math.inf
        self.settle = 0.0
        self.command_headroom = math.inf
        self.rest_command = -math.inf
        self.goal_time_left = math.inf
        self.goal_failed = False
        self.heading_left = math.inf
        self.react_window = 0.0
        if "REACTION_TIME" in self.defined:
            clause = _default_requirements()["REACTION_TIME"].clauses[0]
            self.react_window = getattr(clause, "window", None) or 0.0
        self.last_slow = -math.inf
        self.fast_at_hazard = False
        self.reacting: list[tuple[float, float]] = []
        """(time the robot was fast with a hazard ahead, seconds since it was last slow)."""
        self.slowest_reaction = -math.inf
        self.last_time = 0.0

    def _reaction(self, w: QueryInputs) -> None:
        """REACTION_TIME's reaction times, step by step as its queries see them."""
        p = self.p
        slow = w.cmd_speed <= p.get("slow_speed", 0.15) + p.get("speed_tolerance", 0.0)
        fast_at_hazard = not slow and w.hazard_clearance < p.get("react_zone", 1.05)
        if fast_at_hazard and not self.fast_at_hazard:
            self.reacting.append((w.time, w.time - self.last_slow))
        self.fast_at_hazard = fast_at_hazard
        if slow:
            for start, before in self.reacting:
                self.slowest_reaction = max(self.slowest_reaction,
                                            min(before, w.time - start))
            self.reacting = []
            self.last_slow = w.time
        self.last_time = w.time

    def observe(self, w: QueryInputs) -> None:
        p = self.p
        if "REACTION_TIME" in self.defined:
            self._reaction(w)
        if "MISSION_WITH_HUMAN_TRAJECTORY" in self.defined or "HUMAN_SLOW_ZONE" in self.defined:
            humans = w.kind("human")
            if humans.size and humans.any():
                d = w.distance[humans]
                self.human_distance = min(self.human_distance, float(d.min()))
                if float(d.min()) < p.get("slow_zone", 0.5):
                    self.zone_speed = max(self.zone_speed, w.own_speed)
        if "NO_ROBOT_COLLISION" in self.defined and w.approach.size:
            closing = w.approach > p.get("v_contact", 0.01)
            if closing.any():
                self.drive_in_distance = min(self.drive_in_distance,
                                             float(w.distance[closing].min()))
        if "SPEED_LIMIT" in self.defined:
            for value, limit in ((max(w.cmd_speed, w.own_speed),
                                  w.speed_limit + p.get("speed_tolerance", 0.0)),
                                 (max(w.cmd_turn, w.own_turn_rate),
                                  w.turn_limit + p.get("turn_tolerance", 0.0))):
                if math.isfinite(limit) and limit > 0:
                    self.speed_headroom = min(self.speed_headroom, (limit - value) / limit)
        self.path_ratio = max(self.path_ratio, w.path_ratio)
        self.time_ratio = max(self.time_ratio, w.time_ratio)
        self.settle = max(self.settle, w.settle_travel)
        if "COMMAND_ACCELERATION" in self.defined:
            scale = 1.0 + p.get("accel_margin", 0.0)
            for rate, limit in ((w.cmd_accel, w.accel_limit), (w.cmd_decel, w.decel_limit),
                                (w.cmd_turn_accel, w.turn_accel_limit),
                                (w.cmd_turn_decel, w.turn_decel_limit)):
                allowed = limit * scale
                if math.isfinite(allowed) and allowed > 0:
                    self.command_headroom = min(self.command_headroom,
                                                (allowed - rate) / allowed)
        if w.settle_time > p.get("rest_after", 1.0):
            self.rest_command = max(self.rest_command, w.cmd_speed, w.cmd_turn)

    def task_ended(self, w: QueryInputs, index: int | None, elapsed: float, succeeded: bool,
                   cause: str) -> None:
        """A task's end as the model recorded it (``w``: the inputs at that moment)."""
        goal = None
        if self.facts is not None and self.facts.goals and index is not None:
            goal = self.facts.goals[index % len(self.facts.goals)]
        if succeeded:
            self.spin = max(self.spin, w.goal_spin)
            if goal is not None and goal.timeout > 0:
                self.goal_time_left = min(self.goal_time_left, 1.0 - elapsed / goal.timeout)
            if goal is not None and goal.heading is not None:
                error = _wrap(w.yaw - goal.heading)
                self.heading_left = min(self.heading_left, goal.heading_tolerance - error)
        elif cause not in ("heading", "cut"):
            self.goal_failed = True

    def value(self, name: str) -> float | None:
        p = self.p
        compute: dict[str, Callable[[], float | None]] = {
            "MISSION_WITH_HUMAN_TRAJECTORY": lambda: _finite(
                self.human_distance - p.get("eps_collision", 0.02)),
            "NO_ROBOT_COLLISION": lambda: min(self.drive_in_distance, APPROACH_RANGE)
            - p.get("eps_collision", 0.02),
            "HUMAN_SLOW_ZONE": lambda: _finite(
                p.get("slow_speed", 0.15) + p.get("speed_tolerance", 0.0) - self.zone_speed),
            "SPEED_LIMIT": lambda: _finite(self.speed_headroom),
            "MISSION_GOALS_REACHED": lambda: -1.0 if self.goal_failed
            else _finite(self.goal_time_left),
            "GOAL_HEADING": lambda: _finite(self.heading_left),
            "EFFICIENT_PATH": lambda: p.get("max_path_ratio", 1.5) - self.path_ratio
            if self.path_ratio > 0 else None,
            "TIME_TO_GOAL": lambda: p.get("max_time_ratio", 3.0) - self.time_ratio
            if self.time_ratio > 0 else None,
            "NO_SPIN_AT_GOAL": lambda: _finite(p.get("max_goal_spin", 4.7) - self.spin),
            "SETTLE": lambda: p.get("settle_tolerance", 0.1) - self.settle,
            "REACTION_TIME": self._reaction_margin,
            "COMMAND_ACCELERATION": lambda: _finite(self.command_headroom),
            "COMMAND_AT_REST": lambda: _finite(p.get("rest_tolerance", 0.001)
                                               - self.rest_command),
        }
        return compute[name]()

    def _reaction_margin(self) -> float | None:
        """The window minus the slowest reaction. A reaction still awaited when the run
        ended counts from its start to the last step (a slow command within the window
        before it answered it already); one awaited for less than the window has no
        number to give (the verdict fails: the run ended before the robot slowed)."""
        slowest = self.slowest_reaction
        for start, before in self.reacting:
            waited = self.last_time - start
            if before <= self.react_window:
                slowest = max(slowest, before)
            elif waited > self.react_window:
                slowest = max(slowest, waited)
            else:
                return None
        return _finite(self.react_window - slowest)

    def annotate(self, verdicts: tuple[Verdict, ...]) -> tuple[Verdict, ...]:
        """The verdicts with their margins (only pass and fail get one)."""
        out = []
        for v in verdicts:
            if v.requirement not in self.defined or v.status not in ("pass", "fail"):
                out.append(v)
                continue
            margin = self.value(v.requirement)
            unit = RULES[v.requirement].unit
            if margin is None:
                out.append(v)
            elif (margin < 0) != (v.status == "fail"):
                # the events and this margin read the same inputs; a disagreement is a
                # boundary case (a threshold met exactly): the verdict stands, no margin
                out.append(replace(v, margin_note=f"margin {margin:.6g} {unit} disagrees "
                                                  f"with the verdict; not reported"))
            else:
                out.append(replace(v, margin=margin, margin_unit=unit))
        return tuple(out)


def _finite(value: float) -> float | None:
    return value if math.isfinite(value) else None


def smallest_margin(verdicts: tuple[Verdict, ...]) -> float | None:
    """The least margin of a run (its closest call); None when no verdict has one."""
    values = [v.margin for v in verdicts if v.margin is not None]
    return min(values) if values else None
