"""Situation coverage: which situations a run put the robot in, judged on the ground truth.

Behaviour coverage (rei.runtime.robot.behaviours) says what the navigator did; this says what
the world asked of it, whatever navigator drove: a person crossing ahead, a person standing on
the robot's way for longer than a navigator's patience, a passage between the robot's width and
twice it, a goal behind the robot, an obstacle the map does not show beside it, a hazard
appearing close in the laser. A suite whose runs never meet a situation cannot test how a
navigator handles it; a campaign sums them (rei.runtime.campaigns.coverage).

Each situation is counted in episodes (consecutive samples in which it holds) with its first
time and its seconds. The geometry is the monitor's own (footprint distances to every
object, the ground-truth twists, the hazard clearance from the simulated scan), so a replay
of a trace counts the same. This module must never import the simulator.
"""

from __future__ import annotations

import math

import numpy as np

from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.observation.model.hazard import LOOK_WITHIN
from rei.runtime.robot.behaviours import EpisodeLog

SITUATIONS: dict[str, str] = {
    "person_crossing_ahead": "a person walking across the robot's way within 2 m ahead",
    "person_standing_on_route": "a person standing within 1 m ahead of the robot for 5 s or more",
    "narrow_passage": "the robot between obstacles on both sides leaving less than its width "
                      "spare (a passage narrower than twice its width)",
    "goal_behind": "a goal more than 120° off the robot's heading when its task starts",
    "unmapped_obstacle": "an object the map does not show (a cart) within 1 m of the robot",
    "hazard_appears_close": "a person or moving object first seen by the laser within 2 m "
                            "ahead (nothing seen there the sample before)",
}
"""Every situation counted, with what it means (the coverage table's rows, in order)."""

CROSSING_REACH = 2.0
"""m of footprint distance within which a person crossing ahead counts."""
CROSSING_SPEED = 0.3
"""m/s of a person's velocity across the robot's heading that is crossing."""
AHEAD = math.radians(60.0)
"""rad off the robot's heading within which a body is ahead."""
STANDING_REACH = 1.0
STANDING_SPEED = 0.1
STANDING_FOR = 5.0
"""s a person must stand on the robot's way (the reference's recovery starts after ~1 s)."""
SIDE = (math.radians(45.0), math.radians(135.0))
"""rad off the heading (either side) where a body is beside the robot."""
PASSAGE_MOVING = 0.05
"""m/s the robot must drive at for a passage to count (being pushed past one is not)."""
GOAL_BEHIND = math.radians(120.0)
UNMAPPED_REACH = 1.0
APPEARS_WITHIN = 2.0
"""m of hazard clearance (footprint to the seeing beam's end) within which a hazard first seen
appeared close: at the Waffle's top speed, under 8 s away, where a person stepping out from
behind a corner or through a door is first seen (1.4-1.7 m in the demo's stress rooms)."""
APPEARS_FROM = LOOK_WITHIN
"""m: the sample before saw no hazard within this (the monitor looks no farther), so the
hazard appeared, it did not walk up from afar."""


class SituationLog:
    """The situations of one run, sample by sample (``observe``), and its JSON."""

    def __init__(self, header: StreamHeader) -> None:
        roles = [o.role for o in header.objects]
        self._humans = np.array([r == "human" for r in roles], dtype=bool)
        self._dynamic = np.array([r == "dynamic" for r in roles], dtype=bool)
        self._static = ~(self._humans | self._dynamic)
        fp = header.robot.footprint
        size_y = getattr(fp, "size_y", None)
        self._width = float(size_y) if size_y else 2.0 * float(getattr(fp, "radius", 0.2))
        facts = header.mission_facts
        self._goals = {g.name: g for g in facts.goals} if facts is not None else {}
        self._log = EpisodeLog()
        self._standing_since: float | None = None
        self._last_hazard = math.inf

    def observe(self, s: Sample, distance: np.ndarray, hazard_clearance: float) -> None:
        """One accepted sample: ``distance`` the footprint distance to each header object,
        ``hazard_clearance`` the monitor's (inf when the laser saw no hazard ahead)."""
        now: set[str] = set()
        x, y, yaw = s.robot_pose
        heading = np.array([math.cos(yaw), math.sin(yaw)])
        if len(distance):
            rel = s.poses[:, :2] - np.array([x, y])
            bearing = np.abs(np.remainder(np.arctan2(rel[:, 1], rel[:, 0]) - yaw + math.pi,
                                          2 * math.pi) - math.pi)
            ahead = bearing < AHEAD
            speed = np.hypot(s.twists[:, 0], s.twists[:, 1])
            across = np.abs(s.twists[:, 0] * -heading[1] + s.twists[:, 1] * heading[0])
            people = self._humans & ahead
            if np.any(people & (distance < CROSSING_REACH) & (across > CROSSING_SPEED)):
                now.add("person_crossing_ahead")
            if np.any(people & (distance < STANDING_REACH) & (speed < STANDING_SPEED)):
                if self._standing_since is None:
                    self._standing_since = s.time
                if s.time - self._standing_since >= STANDING_FOR - 1e-9:
                    now.add("person_standing_on_route")
            else:
                self._standing_since = None
            if np.any(self._dynamic & (distance < UNMAPPED_REACH)):
                now.add("unmapped_obstacle")
            if math.hypot(s.robot_twist[0], s.robot_twist[1]) > PASSAGE_MOVING:
                side = (bearing > SIDE[0]) & (bearing < SIDE[1]) & self._static
                cross = heading[0] * rel[:, 1] - heading[1] * rel[:, 0]
                spare = self._width
                left = distance[side & (cross > 0)]
                right = distance[side & (cross < 0)]
                if len(left) and len(right) and float(left.min()) + float(right.min()) < spare:
                    now.add("narrow_passage")
        for event in s.events:
            goal = self._goals.get(event.task or "")
            if event.kind == "task_start" and goal is not None:
                off = abs(math.remainder(math.atan2(goal.y - y, goal.x - x) - yaw, math.tau))
                if off > GOAL_BEHIND and math.hypot(goal.x - x, goal.y - y) > goal.tolerance:
                    now.add("goal_behind")
        if hazard_clearance < APPEARS_WITHIN and self._last_hazard >= APPEARS_FROM:
            now.add("hazard_appears_close")
        self._last_hazard = hazard_clearance
        self._log.tick(s.time, now)

    def to_json(self) -> dict[str, dict[str, float | int]]:
        """``{name: {"episodes", "seconds", "first"}}`` of the situations that occurred."""
        return self._log.to_json()


__all__ = ["SITUATIONS", "SituationLog"]
