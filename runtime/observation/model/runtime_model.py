"""The runtime model the queries read (thesis 5.1.5.1), updated from the sample stream.

Concrete environment: pose, twist and footprint of every observed object, and the footprint
distance from the robot to each (vectorised, rei.runtime.observation.model.geometry). Abstract
environment: the floor the robot and every observed object stands on, through the generators'
inverse mapping (the floor centres in the stream header, thesis 5.1; the look-up is
rei.runtime.observation.model.floors), the floors of the mission's goals and which floors are
neighbours. Robot description: odometry, laser minimum, laser clearance (from the latest scan,
rei.runtime.observation.model.laser_clearance), navigation state, mission and task states, and
the robot's own motion apart from motion it was given (rei.runtime.observation.model.pushes).
This module holds ``RuntimeModel`` and its task records; the sample hygiene
(rei.runtime.observation.model.sample_checks) and the inputs between two samples
(rei.runtime.observation.model.interpolation) are re-exported from here. It must never import
pybullet, the simulation, the evaluator or the monitor's host.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import ClassVar

import numpy as np

from rei.lang.vepl.linker import NAMED_STATES
from rei.lang.vepl.model import MISSION_STATES, TASK_FAILURES, TASK_STATES
from rei.runtime.messages import MissionEvent, Sample, StreamHeader
from rei.runtime.observation.automata.records import QueryInputs
from rei.runtime.observation.model.commands import CommandTracker
from rei.runtime.observation.model.efficiency import TaskEfficiency, TaskProgress, judge_task
from rei.runtime.observation.model.floors import FloorMap
from rei.runtime.observation.model.free_space import FloorGraph, FreeSpace, footprint_shapes
from rei.runtime.observation.model.geometry import FootprintSet
from rei.runtime.observation.model.hazard import HazardSensor
from rei.runtime.observation.model.laser_clearance import BeamEdges, clearance
from rei.runtime.observation.model.pushes import PUSH_CONTACT, PushTracker
from rei.runtime.observation.model.situations import SituationLog

FAR_AWAY = 1e3
"""Distances and laser readings of the baseline before the first sample: nothing is near,
so a run that starts close to an object enters CLOSE with a FAR -> CLOSE transition."""
TASK_CODE = {s: i for i, s in enumerate(TASK_STATES)}
MISSION_CODE = {s: i for i, s in enumerate(MISSION_STATES)}
NAV_CODE = {s: i for i, s in enumerate(NAMED_STATES["nav_state"])}
FAILURE_CODE = {s: i for i, s in enumerate(TASK_FAILURES)}
APPROACH_RANGE = 0.5
"""m: the approach speed is worked out for objects nearer than this (others read 0): it
only matters at contact, and the extra footprint distance costs time."""
APPROACH_LOOKAHEAD = 0.05
"""s: the commanded motion is projected this far ahead to see whether it closes in."""
MOVING = 0.05
"""m/s: above this ground-truth speed the robot counts as moving (personal space)."""
FLOOR_MARGIN = 1e-5
"""m: a robot this far inside the tile it stood on at the last sample is still on it (the
floors of a grid are 1e-6 m from it at most, so no other tile can claim the point)."""


@dataclass
class TaskRecord:
    key: str
    name: str
    index: int | None
    started: float
    ended: float | None = None
    status: str = "active"
    cause: str = "none"
    """TASK_FAILURES entry: why it failed ('none' while it has not)."""
    reason: str = ""
    """The mission executor's words for the failure."""


class RuntimeModel:
    """Per-run state; built from the stream header, updated by every accepted sample."""

    FOOTPRINT_PATHS: ClassVar[bool] = False
    """Judge the efficiency requirements against the footprint estimate (``FreeSpace``, issue
    25) instead of the tile one. Off: re-judged over the 1,000-run medium campaign it fails
    the reference once (room_0390.r00: a 28 s stall at a 0.61 m gap and a 4 m detour round
    a shelf, path ratio 1.53; bench/RESULTS.md, wp-footprint), and the reference must pass.
    """

    def __init__(self, header: StreamHeader, cutoff: float = math.inf) -> None:
        self.header = header
        self.cutoff = cutoff
        self.footprints = FootprintSet.build(header.robot.footprint,
                                             [o.footprint for o in header.objects],
                                             header.tile_size)
        self.object_names = tuple(o.name for o in header.objects)
        masks: dict[str, np.ndarray] = {}
        for i, o in enumerate(header.objects):
            for key in (o.role, o.type):
                masks.setdefault(key, np.zeros(len(header.objects), dtype=bool))[i] = True
        self.kind_masks = masks
        self.human_mask = masks.get("human", np.zeros(len(header.objects), dtype=bool))
        self._any_human = bool(self.human_mask.any())
        self._humans = np.flatnonzero(self.human_mask)
        self._no_approach = np.zeros(len(header.objects))
        self._no_approach.setflags(write=False)  # shared by every sample nothing approaches
        self.floor_names = tuple(f[0] for f in header.floors)
        self._floor_xy = np.array([(f[1], f[2]) for f in header.floors], dtype=float).reshape(
            -1, 2)
        self.floors = FloorMap(self._floor_xy, header.tile_size)
        self._floor_centres = [(float(fx), float(fy)) for fx, fy in self._floor_xy]
        self._floor_masks: dict[int, np.ndarray] = {}
        """The robot-floor mask of each floor index (-1: none), shared and read-only."""
        self._floor_last = -1
        self._floors_disjoint = self.floors.on_grid and len(
            {(int(i), int(j)) for i, j in self.floors.cells}) == len(self.floor_names)
        self.no_floors = np.full(len(header.objects), -1, dtype=np.int64)
        self.inradius = self.footprints.robot_inradius()
        self.beam_edges = BeamEdges(header.robot.footprint, header.laser_mount)
        self.laser_clearance = FAR_AWAY
        """Of the latest scan a sample carried; scans come only when new, so it is kept."""
        self.hazards = HazardSensor(header)
        self.hazard_clearance = FAR_AWAY
        """Of the latest scan: the nearest beam ahead that ends on a person or a moving
        object (rei.runtime.observation.model.hazard), kept between scans like laser_clearance."""
        self.circumradius = self.footprints.robot_bound
        self.tasks: list[TaskRecord] = []
        self.task_codes = np.zeros(0, dtype=np.int64)
        self.mission_state = MISSION_CODE["pending"]
        self.mission_began: float | None = None
        self.mission_ended: float | None = None
        self.path_length = 0.0
        self.min_distance_to_human = math.inf
        self.min_distance_to_human_moving = math.inf
        """Personal space: the closest the robot came to a person while it was moving."""
        self._last_xy: tuple[float, float] | None = None
        self.push = PushTracker()
        self.pushed_time = 0.0
        """Simulated seconds the robot was moved beyond its command by a contact it did not
        drive into (a measurement: the shove is recorded, not blamed)."""
        self.pushed_top_speed = 0.0
        self._last_time: float | None = None
        self._task: TaskProgress | None = None
        self._graph: FreeSpace | FloorGraph | None = None
        self._graph_built = False
        self.efficiency: list[tuple[str, TaskEfficiency]] = []
        """(task, figures) of every task that succeeded, in order."""
        self._judged = TaskEfficiency(0.0, 0.0, 0.0, 0.0)
        """The figures of the last task that succeeded, until the next task starts."""
        self.idle_travel = 0.0
        """Metres of the robot's own motion since its last task ended while no task runs (the
        settle period after the last goal); 0 while a task runs."""
        self._idle = False
        self._idle_since = 0.0
        """When the last task ended (the settle period's start, while ``_idle``)."""
        self.commands = CommandTracker()
        self.situations = SituationLog(header)
        """The situations the run met (summary.json's ``situations``)."""
        self.task_failures = np.zeros(0, dtype=np.int64)
        roles = [o.role for o in header.objects]
        self.humans = float(roles.count("human"))
        self.dynamic_objects = float(roles.count("dynamic"))
        facts = header.mission_facts
        self.speed_limit = facts.speed_limit if facts is not None else math.inf
        self.turn_limit = facts.turn_limit if facts is not None else math.inf
        self.accel_limit = facts.accel_limit if facts is not None else math.inf
        self.decel_limit = facts.decel_limit if facts is not None else math.inf
        self.turn_accel_limit = facts.turn_accel_limit if facts is not None else math.inf
        self.turn_decel_limit = facts.turn_decel_limit if facts is not None else math.inf
        self.cycles = float(facts.cycles) if facts is not None else 1.0
        self.headed_goals = float(sum(g.heading is not None for g in facts.goals)) \
            if facts is not None else 0.0
        self.goals = float(len(facts.goals)) if facts is not None else 0.0
        self.goal_floor = np.zeros(len(self.floor_names), dtype=bool)
        self.neighbouring_goals = 0.0
        if facts is not None and facts.goals:
            at = self.floors.of(np.array([(g.x, g.y) for g in facts.goals], dtype=float))
            self.goal_floor[at[at >= 0]] = True
            self.neighbouring_goals = float(sum(self.floors.side_by_side(int(a), int(b))
                                                for a, b in zip(at, at[1:], strict=False)))
        self.floor_adjacent = self.floors.adjacent

    # ---- per sample -----------------------------------------------------------------------

    def baseline(self) -> QueryInputs:
        n = len(self.object_names)
        return QueryInputs(np.full(n, FAR_AWAY), self.kind_masks,
                           np.zeros(len(self.floor_names), dtype=bool), self.task_codes.copy(),
                           FAR_AWAY, FAR_AWAY, 0.0, 0.0, 0.0, self.inradius,
                           self.circumradius,
                           MISSION_CODE["pending"], NAV_CODE["idle"],
                           approach=np.zeros(n), task_failure=self.task_failures.copy(),
                           speed_limit=self.speed_limit, turn_limit=self.turn_limit,
                           accel_limit=self.accel_limit, decel_limit=self.decel_limit,
                           turn_accel_limit=self.turn_accel_limit,
                           turn_decel_limit=self.turn_decel_limit,
                           humans=self.humans, dynamic_objects=self.dynamic_objects,
                           cycles=self.cycles, headed_goals=self.headed_goals, goals=self.goals,
                           neighbouring_goals=self.neighbouring_goals,
                           object_floors=lambda: self.no_floors, goal_floor=self.goal_floor,
                           adjacency=self.floor_adjacent)

    def _approach(self, s: Sample, distance: np.ndarray) -> np.ndarray:
        """How fast the robot's own commanded motion (as the motor executes it: clipped to
        the limits) closes the footprint distance to each near object, m/s. A body that
        moves into a robot standing still gets 0: the contact is not the robot's doing."""
        linear, angular = s.belief.cmd
        near = distance < APPROACH_RANGE
        if (linear == 0.0 and angular == 0.0) or not np.count_nonzero(near):
            return self._no_approach
        out = np.zeros(len(distance))
        v = min(max(linear, -self.speed_limit), self.speed_limit)
        w = min(max(angular, -self.turn_limit), self.turn_limit)
        x, y, yaw = s.robot_pose
        dt = APPROACH_LOOKAHEAD
        ahead = (x + v * math.cos(yaw) * dt, y + v * math.sin(yaw) * dt, yaw + w * dt)
        later = self.footprints.refine(distance.copy(), near, ahead, s.poses)
        out[near] = (distance[near] - later[near]) / dt
        return out

    def observe(self, s: Sample) -> QueryInputs:
        """The query inputs of an accepted sample (and the run's measurements updated)."""
        x, y, _ = s.robot_pose
        distance = self.footprints.distances(s.robot_pose, s.poses, self.cutoff)
        approach = self._approach(s, distance)  # from the geometry, before contacts count
        if s.contacts:
            # A physical contact is always a collision: pybullet saw the bodies touch, maybe
            # between two samples, while the sampled footprints may stand a little apart.
            touched = np.asarray(s.contacts, dtype=np.intp)
            distance[touched] = np.minimum(distance[touched], 0.0)
        speed = math.hypot(s.robot_twist[0], s.robot_twist[1])
        own = self.push.update(speed, s.robot_twist[2], s.belief.cmd, distance < PUSH_CONTACT,
                               approach)
        dt = max(0.0, s.time - self._last_time) if self._last_time is not None else 0.0
        if own.pushed:
            self.pushed_time += dt
            self.pushed_top_speed = max(self.pushed_top_speed, speed)
        if self._idle and self.mission_state == MISSION_CODE["running"]:
            self.idle_travel += own.speed * dt
        self._last_time = s.time
        if self._any_human:
            self._nearest_human(s, distance, speed > MOVING)
        step = 0.0
        if self._last_xy is not None:
            step = math.hypot(x - self._last_xy[0], y - self._last_xy[1])
            self.path_length += step
        self._last_xy = (x, y)
        if not self._graph_built:
            self._graph, self._graph_built = self.path_space(s), True
        if self._task is not None:
            self._task.observe((x, y), step, own.speed, own.yaw_rate, dt)
        scan = s.belief.scan
        if scan is not None:
            edges = self.beam_edges.of(scan)
            self.laser_clearance = clearance(scan, edges)
            if self.hazards.indices:
                self.hazard_clearance = self.hazards.clearance(scan, s.robot_pose, s.poses,
                                                               distance)
        self.situations.observe(s, distance, self.hazard_clearance)
        ox, oy, _ = s.belief.odom
        linear, angular = s.belief.cmd
        rates = self.commands.observe(s.time, s.belief.cmd)
        return QueryInputs(
            distance, self.kind_masks, self._robot_floor(x, y), self.task_codes,
            float(s.belief.laser_min), self.laser_clearance, speed,
            s.time, math.hypot(ox - x, oy - y), self.inradius, self.circumradius,
            self.mission_state, NAV_CODE.get(s.belief.nav_state.value, 0),
            approach=approach, task_failure=self.task_failures,
            cmd_speed=abs(linear), cmd_turn=abs(angular), cmd_linear=linear,
            cmd_yaw_rate=angular, cmd_accel=rates.accel, cmd_decel=rates.decel,
            cmd_turn_accel=rates.turn_accel, cmd_turn_decel=rates.turn_decel,
            turn_rate=abs(s.robot_twist[2]), yaw_rate=s.robot_twist[2], yaw=s.robot_pose[2],
            own_speed=own.speed, own_turn_rate=abs(own.yaw_rate), own_yaw_rate=own.yaw_rate,
            pushed=1.0 if own.pushed else 0.0, hazard_clearance=self.hazard_clearance,
            settle_travel=self.idle_travel if self._idle else 0.0,
            settle_time=self._settle_time(s.time),
            path_ratio=self._judged.path_ratio, time_ratio=self._judged.time_ratio,
            goal_spin=self._judged.spin,
            # the scenario's facts, constant through the run
            speed_limit=self.speed_limit, turn_limit=self.turn_limit,
            accel_limit=self.accel_limit, decel_limit=self.decel_limit,
            turn_accel_limit=self.turn_accel_limit, turn_decel_limit=self.turn_decel_limit,
            humans=self.humans,
            dynamic_objects=self.dynamic_objects, cycles=self.cycles,
            headed_goals=self.headed_goals, goals=self.goals,
            neighbouring_goals=self.neighbouring_goals,
            object_floors=_Once(self.floors.of, s.poses),
            goal_floor=self.goal_floor,
            adjacency=self.floor_adjacent)

    def _settle_time(self, time: float) -> float:
        """Seconds of the settle period at ``time`` (0 outside it)."""
        if self._idle and self.mission_state == MISSION_CODE["running"]:
            return max(0.0, time - self._idle_since)
        return 0.0

    def _nearest_human(self, s: Sample, distance: np.ndarray, moving: bool) -> None:
        """Update the closest approach to a person (and, while moving, personal space). The
        exact distance is worked out once, and only when a person might beat a minimum."""
        bound = float(np.minimum.reduce(distance.take(self._humans)))
        if bound >= self.min_distance_to_human and not (
                moving and bound < self.min_distance_to_human_moving):
            return
        nearest = self.footprints.nearest(distance, distance <= self.cutoff, self.human_mask,
                                          s.robot_pose, s.poses)
        self.min_distance_to_human = min(self.min_distance_to_human, nearest)
        if moving:
            self.min_distance_to_human_moving = min(self.min_distance_to_human_moving, nearest)

    def _robot_floor(self, x: float, y: float) -> np.ndarray:
        """The floor the robot stands on, as a mask over the floors (shared, read-only)."""
        half = self.header.tile_size / 2
        last = self._floor_last
        if last >= 0 and self._floors_disjoint:
            fx, fy = self._floor_centres[last]
            if abs(fx - x) <= half - FLOOR_MARGIN and abs(fy - y) <= half - FLOOR_MARGIN:
                return self._floor_masks[last]  # well inside last sample's tile: still on it
        at = -1
        if len(self.floor_names):
            inside = (np.abs(self._floor_xy[:, 0] - x) <= half) & (
                np.abs(self._floor_xy[:, 1] - y) <= half)
            hits = np.flatnonzero(inside)
            if len(hits):
                at = int(hits[0])  # on a shared edge the first floor in header order wins
        self._floor_last = at
        mask = self._floor_masks.get(at)
        if mask is None:
            mask = np.zeros(len(self.floor_names), dtype=bool)
            if at >= 0:
                mask[at] = True
            mask.setflags(write=False)
            self._floor_masks[at] = mask
        return mask

    def apply(self, e: MissionEvent, w: QueryInputs) -> QueryInputs:
        """The inputs after a mission event (thesis 6.1.4: mission and task states)."""
        if e.kind == "begin":
            self.mission_state = MISSION_CODE["running"]
            self.mission_began = e.time
        elif e.kind == "end":
            self.mission_state = MISSION_CODE["ended"]
            self.mission_ended = e.time
            self._idle = False
        else:
            key = str(e.index) if e.index is not None else (e.task or "")
            record = next((t for t in self.tasks if t.key == key), None)
            self._idle = e.kind != "task_start"
            self._idle_since = e.time
            self.idle_travel = 0.0
            self._task_event(e)
            if e.kind == "task_start":
                if record is None:
                    record = TaskRecord(key, e.task or key, e.index, e.time)
                    self.tasks.append(record)
                    self.task_codes = np.append(self.task_codes, TASK_CODE["active"])
                    self.task_failures = np.append(self.task_failures, FAILURE_CODE["none"])
                else:
                    self._own_task_arrays()
                    record.status, record.started, record.ended = "active", e.time, None
                    record.cause, record.reason = "none", ""
                    self.task_codes[self.tasks.index(record)] = TASK_CODE["active"]
                    self.task_failures[self.tasks.index(record)] = FAILURE_CODE["none"]
            elif record is not None:
                self._own_task_arrays()
                record.status = "succeeded" if e.kind == "task_success" else "failed"
                record.ended = e.time
                self.task_codes[self.tasks.index(record)] = TASK_CODE[record.status]
                if e.kind == "task_fail":
                    # an unknown or missing cause still fails the task: it reads 'aborted'
                    record.cause = e.cause if e.cause in FAILURE_CODE and e.cause != "none" \
                        else "aborted"
                    record.reason = e.reason
                    self.task_failures[self.tasks.index(record)] = FAILURE_CODE[record.cause]
        return replace(w, task_state=self.task_codes, mission_state=self.mission_state,
                       task_failure=self.task_failures,
                       settle_travel=self.idle_travel if self._idle else 0.0,
                       settle_time=self._settle_time(w.time),
                       path_ratio=self._judged.path_ratio, time_ratio=self._judged.time_ratio,
                       goal_spin=self._judged.spin)

    def _task_event(self, e: MissionEvent) -> None:
        """Start gathering a task's progress, or judge how well a task that succeeded went."""
        self._judged = TaskEfficiency(0.0, 0.0, 0.0, 0.0)
        if e.kind == "task_start":
            facts = self.header.mission_facts
            goal = facts.goals[e.index % len(facts.goals)] \
                if facts is not None and facts.goals and e.index is not None else None
            xy = self._last_xy if self._last_xy is not None else (math.nan, math.nan)
            self._task = TaskProgress(xy, e.time, goal)
            return
        task, self._task = self._task, None
        if e.kind != "task_success" or task is None or task.goal is None:
            return  # a failed task is MISSION_GOALS_REACHED's; efficiency judges successes
        shortest = math.inf
        if self._graph is not None:
            shortest = self._graph.distance(task.start_xy, (task.goal.x, task.goal.y))
        self._judged = judge_task(task, e.time, shortest, self.speed_limit)
        self.efficiency.append((task.goal.name, self._judged))

    def path_space(self, s: Sample) -> FreeSpace | FloorGraph | None:
        """The space the efficiency requirements' shortest paths are searched in, from the
        first sample's poses (static objects stay put): the footprint estimate when
        ``FOOTPRINT_PATHS`` is set, else the tile estimate; None when the floors are
        off-grid."""
        tiles = self.tile_space(s)
        return self.free_space(s, tiles) if self.FOOTPRINT_PATHS and tiles is not None \
            else tiles

    def tile_space(self, s: Sample) -> FloorGraph | None:
        """The floor tiles, a tile under a static object's centre blocked; None when the
        floors are off-grid."""
        if not self.floors.on_grid or not len(self.floor_names):
            return None
        blocked = np.zeros(len(self.floor_names), dtype=bool)
        static = [i for i, o in enumerate(self.header.objects) if o.role == "static"]
        if static:
            under = self.floors.of(np.asarray(s.poses, dtype=float)[static, :2])
            blocked[under[under >= 0]] = True
        return FloorGraph(self.floors.grid, self.floors.origin, self.floors.tile, blocked)

    def free_space(self, s: Sample, tiles: FloorGraph) -> FreeSpace | FloorGraph:
        """The robot's real free space: the floors less the walls' and static objects'
        footprints inflated by the robot's inradius; ``tiles`` (the tile estimate, which it
        falls back to) when the header lists neither."""
        solid = [i for i, o in enumerate(self.header.objects) if o.role in ("wall", "static")]
        if not solid:
            return tiles
        shapes = footprint_shapes([self.header.objects[i].footprint for i in solid],
                                  np.asarray(s.poses, dtype=float)[solid, :3],
                                  self.floors.tile, self.inradius)
        return FreeSpace(tiles, shapes, self.inradius)

    def _own_task_arrays(self) -> None:
        """Copy the task arrays before changing them in place: the inputs handed out
        share them (copy on write instead of a copy per sample)."""
        self.task_codes = self.task_codes.copy()
        self.task_failures = self.task_failures.copy()

    def describe(self, objects: tuple[str, ...]) -> str:
        """Words for the objects an event involved: a failed task adds the executor's
        reason, so a verdict says why the goal was missed."""
        parts = []
        for name in objects:
            failed = [t for t in self.tasks if t.name == name and t.status == "failed"]
            if failed:
                t = failed[-1]
                parts.append(f"task {name} (#{t.index}) failed: {t.reason or t.cause}")
            else:
                parts.append(name)
        return "; ".join(parts)

    def names(self, domain: str) -> tuple[str, ...]:
        if domain == "object":
            return self.object_names
        if domain == "floor":
            return self.floor_names
        return tuple(t.name for t in self.tasks)


class _Once:
    """``of(poses[:, :2])``, worked out on the first call and kept (a sample's object
    floors: most specifications never ask)."""

    __slots__ = ("_of", "_poses", "_value")

    def __init__(self, of: Callable[[np.ndarray], np.ndarray], poses: np.ndarray) -> None:
        self._of = of
        self._poses = poses
        self._value: np.ndarray | None = None

    def __call__(self) -> np.ndarray:
        if self._value is None:
            self._value = self._of(np.asarray(self._poses)[:, :2])
        return self._value
