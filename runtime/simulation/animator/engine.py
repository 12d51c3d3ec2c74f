"""The animator: moves humans and dynamic objects along splines by velocity (thesis 4.2.2, 6.2.2).

Each physics step sets the body's planar velocity to the spline's displacement over the step,
(r(s + ds) - r(s)) / dt at the body's path time s, plus a bounded pull back towards r(s)
(refreshed at the control rate) so a body that was pushed or held up by a contact (the
robot, a wall) rejoins its path instead of walking a parallel one.

How the path time runs is the body's behaviour (yielding.py, social_force.py): a
``scripted`` body's is the clock (delayed and scaled by its seeded variation); a
``yielding`` human's only advances while the robot leaves its way free; a ``social``
human's velocity comes from the social force model, towards a target point whose path time
only advances while the human keeps up with it. A reactive human that turned back (held
back for its patience: the package docstring) walks its path backwards: its path time
runs back.

A trajectory with a start trigger (``when robot within D of FLOOR``) keeps its clock
at zero, so its body stands at its first vertex, until a control tick finds the robot's centre
within D of the floor's centre; from that tick on its clock runs as a scripted one's does from
the start of the run (a seeded variation keeps its speed scale but drops its start delay).
Encounters are then timed by where the robot is, not by when.

The body is never teleported, so collisions with the robot are real contacts. Humans turn to
face their direction of motion. Loops repeat; open trajectories stop at their last vertex.
This module only moves bodies: it is given the robot's ground-truth pose and velocity each
control tick, and must never decide anything about the robot or the mission, nor import
pybullet or the monitor.

It holds one idea, the ``Animator``, and so stays one module though it is longer than most:
its per-run state (path times, sides, patience, dodges) is shared by the scripted, yielding
and social branches of every control tick, so splitting the class would spread one state
machine over modules. What it is given lives elsewhere: the bodies and the reactions'
parameters (bodies.py, re-exported here), the reactive models' pure functions (yielding.py,
social_force.py, walls.py).
"""

from __future__ import annotations

import math

import numpy as np

from rei.lang.room.model import WALKING_SPEEDS
from rei.runtime.simulation.animator.agent import Agent, Vec
from rei.runtime.simulation.animator.bodies import (
    Animated,
    Reactions,
)
from rei.runtime.simulation.animator.social_force import (
    Dodge,
    SocialForce,
    dodge_sides,
    fits_past,
    held_back,
    keep_clear,
    limit_speed,
    pass_side,
    social_acceleration,
)
from rei.runtime.simulation.animator.variation import mean_speed
from rei.runtime.simulation.animator.walls import room_aside, wall_normals, way_aside
from rei.runtime.simulation.animator.yielding import gap_beside, gap_in_the_way, speed_share

CATCH_UP_GAIN = 1.0
"""1/s: how fast a displaced body returns to its path."""
MAX_CATCH_UP = 0.5
"""m/s added at most on top of the path's own speed."""
TURN_TIME = 0.5
"""s: time constant of a human turning towards where it walks."""
BLOCK = 1000
"""Physics steps whose curve displacements are computed together."""
LEASH = (0.3, 1.0)
"""m: a social human's target point slows down once the human is this far behind it, and
stands at the second distance, so a detour never leaves the human chasing a far target."""
FACING_SPEED = 0.05
"""m/s below which a reactive human keeps its heading instead of turning to its velocity."""
STEP_LOOK = 0.1
"""m: a human stepping aside stops where a step this long would bring it nearer a wall than
its radius."""

Pose = tuple[float, float, float]


def _pull(ex: float, ey: float) -> tuple[float, float]:
    err = math.hypot(ex, ey)
    if err <= 1e-9:
        return 0.0, 0.0
    pull = min(CATCH_UP_GAIN * err, MAX_CATCH_UP) / err
    return ex * pull, ey * pull


def _turn(face_motion: bool, vx: float, vy: float, yaw: float, threshold: float) -> float:
    if not face_motion or math.hypot(vx, vy) <= threshold:
        return 0.0
    return math.remainder(math.atan2(vy, vx) - yaw, math.tau) / TURN_TIME


class Animator:
    """Drives every animated body: the curve's displacement each physics step, plus a pull
    back to the curve and a turn towards the walking direction, refreshed at the control rate.

    Scripted curves' displacements are evaluated for a block of steps at once (vectorised),
    so a physics step only looks its velocity up; the feedback, which only needs to be
    stable, and the reactive humans' decisions run at the control rate. The per-run state
    (path times, social velocities) lives in this object, never in the module.
    """

    def __init__(self, items: list[Animated], physics_rate: float, robot_radius: float = 0.0,
                 reactions: Reactions | None = None, walls: np.ndarray | None = None) -> None:
        self.walls = walls if walls is not None else np.zeros((0, 5))
        """The fixed bodies as ``wall_boxes``: social humans pass the robot where they fit."""
        self.items = items
        self.rate = physics_rate
        self.robot_radius = robot_radius
        self.reactions = reactions or Reactions()
        self._feedback = [(0.0, 0.0, 0.0)] * len(items)
        self._block: int | None = None
        self._steps: list[tuple[list[float], list[float]]] = []
        self._path_time = [0.0] * len(items)
        """Reactive bodies: where along their spline they are (seconds of spline time)."""
        self._advance = [1.0] * len(items)
        """Reactive bodies: share of full path speed their path time advances at."""
        self._velocity = [(0.0, 0.0)] * len(items)
        """Social humans: velocity from the social force model."""
        self._side = [1.0] * len(items)
        """Social humans: the side they pass others on (1 right, -1 left)."""
        self._held = [0.0] * len(items)
        """Social humans: seconds held back from where they want to walk."""
        self._stood = [0.0] * len(items)
        """Yielding humans: seconds stood with the robot in the way."""
        self._way = [1.0] * len(items)
        """Reactive humans: 1 walking their path forwards, -1 turned back along it."""
        self._back = [0.0] * len(items)
        """Reactive humans turned back: seconds they still walk backwards."""
        self._tried = [False] * len(items)
        """Social humans: switched side while held back, not yet got on since."""
        self._free = [0.0] * len(items)
        """Social humans: seconds not held back."""
        self._dodge: list[Dodge | None] = [None] * len(items)
        """Social humans: the sides they get past a robot coming at them by."""
        self._dodge_age = [0.0] * len(items)
        """Social humans: seconds since the robot last came at them (``dodge_memory``)."""
        self._giving_way = [False] * len(items)
        self._away = [False] * len(items)
        """Yielding humans giving way: stepping away from the robot (no room across)."""
        self._aside = [0.0] * len(items)
        """Yielding humans giving way: seconds since they began to."""
        self._last_correct: int | None = None
        self._started: list[int | None] = [None if item.start_when is not None else 0
                                           for item in items]
        """The physics step each body's clock started at; None while its trigger waits."""
        self._path_speed = [item.variation.speed_scale * mean_speed(item.spline)
                            for item in items]

    def clock(self, k: int, step: int) -> float | None:
        """Seconds on body ``k``'s clock at ``step``; None while its start trigger waits."""
        started = self._started[k]
        return None if started is None else (step - started) / self.rate

    def started_at(self, k: int) -> float | None:
        """Seconds into the run body ``k``'s clock started at; None if it never did."""
        started = self._started[k]
        return None if started is None else started / self.rate

    def path_time(self, k: int, step: int) -> float:
        """Where along its spline body ``k`` is at ``step`` (reactive: after the last step)."""
        item = self.items[k]
        if item.behaviour != "scripted":
            return self._path_time[k]
        v, clock = item.variation, self.clock(k, step)
        return 0.0 if clock is None else max(0.0, v.speed_scale * (clock - v.phase_s))

    def _trigger(self, step: int, robot_pose: Pose | None) -> None:
        """Start the clocks whose robot-position trigger this tick meets."""
        if robot_pose is None:
            return
        for k, item in enumerate(self.items):
            if self._started[k] is None and item.start_when is not None:
                x, y, within = item.start_when
                if math.hypot(robot_pose[0] - x, robot_pose[1] - y) <= within:
                    self._started[k] = step
                    self._block = None  # the precomputed displacements assumed it stood

    def correct(self, step: int, poses: list[Pose], robot_pose: Pose | None = None,
                robot_twist: Pose | None = None) -> None:
        """Refresh each body's pull back to its curve from its ground-truth pose, and the
        reactive humans' decisions from the robot's (``robot_twist``: world-frame vx, vy, wz,
        which the social force uses to repel earlier from a robot coming closer)."""
        dt = 0.0 if self._last_correct is None else (step - self._last_correct) / self.rate
        self._last_correct = step
        self._trigger(step, robot_pose)
        rvx, rvy = (robot_twist[0], robot_twist[1]) if robot_twist is not None else (0.0, 0.0)
        robot = (None if robot_pose is None
                 else Agent(robot_pose[0], robot_pose[1], self.robot_radius, rvx, rvy))
        # Other humans' velocities: a social human's own, the others' path velocity is not
        # worth a second look-up (they are repelled by distance alone).
        humans = [(j, Agent(p[0], p[1], item.radius, *self._velocity[j]))
                  for j, (item, p) in enumerate(zip(self.items, poses, strict=True))
                  if item.face_motion]
        for k, (item, pose) in enumerate(zip(self.items, poses, strict=True)):
            if item.behaviour != "scripted":
                self._walk_back(k, item, dt)
            if item.behaviour == "social":
                others = [a for j, a in humans if j != k] + ([robot] if robot else [])
                self._social(k, item, pose, dt, others, robot)
                continue
            s = self.path_time(k, step)
            x0, y0 = item.spline.position(s)
            cx, cy = _pull(x0 - pose[0], y0 - pose[1])
            vx, vy = item.spline.velocity(s)
            vx, vy = vx * self._way[k], vy * self._way[k]
            if item.behaviour == "yielding":
                clock = self.clock(k, step)
                walking = clock is not None and clock >= item.variation.phase_s
                # Before its start and at the end of an open path the human stands: then
                # the robot waits on it when it is near on any side (its goal may be where
                # the human stands), not only ahead.
                standing = not walking or math.hypot(vx, vy) < 1e-9
                # "In its way" along where it actually goes: its path's direction plus the
                # pull back to the path (returning from a step aside must not walk into it)
                going = (vx * item.variation.speed_scale + cx,
                         vy * item.variation.speed_scale + cy)
                rule = self.reactions.yielding
                if robot is None:
                    gap = None
                elif standing:
                    gap = gap_beside(rule, pose[0], pose[1], item.radius, robot)
                else:
                    gap = gap_in_the_way(rule, pose[0], pose[1], item.radius, going, robot)
                # Which way it gives way if its patience runs out
                way_out = ("across" if robot is None or gap is None
                           else self._steps_aside(pose, item.radius, robot, robot_pose))
                share = self._yield(k, gap, dt, standing, way_out)
                self._advance[k] = share if walking else 0.0
                if self._giving_way[k] and robot is not None:
                    cx, cy = self._step_away(k, pose, item.radius, robot, gap, robot_pose)
                else:
                    cx, cy = cx * share, cy * share
            self._feedback[k] = (cx, cy, _turn(item.face_motion, vx, vy, pose[2], 1e-3))

    def _walk_back(self, k: int, item: Animated, dt: float) -> None:
        """A human that turned back turns round again once it has walked back its
        ``turn_back_time`` or reached the start of an open path."""
        if self._way[k] > 0.0:
            return
        self._back[k] -= dt
        if self._back[k] <= 0.0 or (not item.spline.loop and self._path_time[k] <= 0.0):
            self._way[k], self._back[k] = 1.0, 0.0

    def _turn_back(self, k: int, walk_back: float) -> None:
        """Turn round along the path: backwards for ``walk_back`` seconds, or forwards again
        if it had turned back already (the robot followed it)."""
        spline = self.items[k].spline
        if not spline.loop:  # its path time ran on past an open path's end while it stood
            self._path_time[k] = min(self._path_time[k], float(spline.t[-1]))
        self._way[k] = -self._way[k]
        self._back[k] = walk_back if self._way[k] < 0.0 else 0.0

    def _yield(self, k: int, gap: float | None, dt: float, standing: bool = False,
               way_out: str = "across") -> float:
        """The share of path speed a yielding human walks at; 0 while it gives way.
        ``standing``: the human has nowhere to walk (before its start, at its path's end),
        so a robot anywhere within ``gap_beside`` is waiting on it. ``way_out``: how it gives way
        when its patience runs out (``_steps_aside``): it steps "across" or "away", or turns
        "back" along its path."""
        rule = self.reactions.yielding
        if self._giving_way[k]:
            self._aside[k] += dt
            if gap is not None and self._aside[k] < rule.give_way_time:
                return 0.0
            # The robot is out of the way, or waited as long as the human stood aside (its
            # goal may be where the human stands): back to the path, yielding afresh there.
            self._giving_way[k] = False
        share = speed_share(rule, gap)
        # The share falls off with the gap, so a human closes in on stop_gap ever slower:
        # one creeping at a tenth of its speed is waiting as much as one standing.
        waited_on = share < 0.1 or (standing and gap is not None and gap < rule.slow_gap)
        self._stood[k] = self._stood[k] + dt if waited_on else 0.0
        if self._stood[k] >= rule.patience:
            self._stood[k] = 0.0
            if way_out != "back" or rule.turn_back_time <= 0.0:
                self._giving_way[k], self._aside[k] = True, 0.0
                self._away[k] = way_out == "away"
            else:
                self._turn_back(k, rule.turn_back_time)
            return 0.0
        return share

    def _step_away(self, k: int, pose: Pose, radius: float, robot: Agent, gap: float | None,
                   robot_pose: Pose | None) -> tuple[float, float]:
        """A human giving way steps aside out of the robot's way: across the robot's heading,
        on the side it already stands (straight away from a robot coming at it would keep it
        in the robot's path, and at a turning point back along its own path leads into the
        robot), until give_way_gap or a step short of a wall; or, where across had no room to
        begin with, away from the robot (``way_aside``); then it stands; its pull brings it
        back to its path once the robot is out of the way."""
        rule = self.reactions.yielding
        if gap is None or gap >= rule.give_way_gap \
                or math.hypot(pose[0] - robot.x, pose[1] - robot.y) < 1e-9:
            return 0.0, 0.0
        across, _ = self._directions(pose, robot, robot_pose)
        # Across (as far as the walls let it: it looks one short step ahead), or away if
        # across had no room to begin with.
        if self._away[k]:
            step = self._way_aside(pose, radius, robot, robot_pose, STEP_LOOK)
        elif rule.aside_room <= 0.0 or room_aside(self.walls, pose[0], pose[1], radius, across,
                                                  STEP_LOOK):
            step = across
        else:
            step = None
        if step is None:
            return 0.0, 0.0
        return rule.give_way_speed * step[0], rule.give_way_speed * step[1]

    def _steps_aside(self, pose: Pose, radius: float, robot: Agent, robot_pose: Pose | None
                     ) -> str:
        """How a yielding human whose patience ran out gives way: it steps "across" the
        robot's heading where it has room; else "away" from the robot where it has room
        (straight or up to 90 degrees off: ``way_aside``); else it turns "back" along its
        path."""
        reach = self.reactions.yielding.aside_room
        across, _ = self._directions(pose, robot, robot_pose)
        if reach <= 0.0 or room_aside(self.walls, pose[0], pose[1], radius, across, reach):
            return "across"
        return "away" if self._way_aside(pose, radius, robot, robot_pose) is not None else "back"

    def _way_aside(self, pose: Pose, radius: float, robot: Agent, robot_pose: Pose | None,
                   reach: float | None = None) -> tuple[float, float] | None:
        """The unit direction a human giving way steps in (see ``_step_away``), None where
        it has no room to step ``reach`` (default ``aside_room``; ``way_aside``)."""
        across, away = self._directions(pose, robot, robot_pose)
        aside_room = self.reactions.yielding.aside_room
        return way_aside(self.walls, pose[0], pose[1], radius, across, away,
                         aside_room if reach is None or aside_room <= 0.0 else reach)

    @staticmethod
    def _directions(pose: Pose, robot: Agent, robot_pose: Pose | None
                    ) -> tuple[tuple[float, float], tuple[float, float]]:
        """Across the robot's heading on the side the human stands (with a little of away,
        so a human beside it still leaves), and straight away from the robot: unit vectors
        (zero for a human on the robot's centre)."""
        dx, dy = pose[0] - robot.x, pose[1] - robot.y
        dist = math.hypot(dx, dy)
        if dist < 1e-9:
            return (0.0, 0.0), (0.0, 0.0)
        ux, uy = dx / dist, dy / dist
        if robot_pose is None:
            return (ux, uy), (ux, uy)
        hx, hy = math.cos(robot_pose[2]), math.sin(robot_pose[2])
        side = 1.0 if hx * dy - hy * dx >= 0.0 else -1.0
        ax, ay = -hy * side + 0.3 * ux, hx * side + 0.3 * uy
        norm = math.hypot(ax, ay)
        return (ax / norm, ay / norm), (ux, uy)

    def _social(self, k: int, item: Animated, pose: Pose, dt: float,
                others: list[Agent], robot: Agent | None = None) -> None:
        model = self.reactions.social
        s = self._path_time[k]
        tx, ty = item.spline.position(s)
        ex, ey = tx - pose[0], ty - pose[1]
        px, py = item.spline.velocity(s)
        px, py = px * self._way[k], py * self._way[k]
        # Only a target ahead of the human waits for it; one the human has overtaken (after
        # a detour cut a corner) walks on, and the pull slows the human until it catches up.
        behind = ex * px + ey * py > 0.0
        lag = math.hypot(ex, ey) if behind else 0.0
        clock = None if self._last_correct is None else self.clock(k, self._last_correct)
        walking = clock is not None and clock >= item.variation.phase_s
        self._advance[k] = (min(1.0, max(0.0, (LEASH[1] - lag) / (LEASH[1] - LEASH[0])))
                            if walking else 0.0)
        scale = item.variation.speed_scale if walking else 0.0
        cx, cy = _pull(ex, ey)
        v_max = model.max_speed_factor * max(self._path_speed[k], WALKING_SPEEDS[0])
        desired = limit_speed(scale * px + cx, scale * py + cy, v_max)
        vx, vy = self._velocity[k]
        # Pass the robot on the side where it fits (the other, if only that one does).
        if robot is not None and not fits_past(model, self.walls, pose[0], pose[1], item.radius,
                                               desired, robot, self._side[k]) \
                and fits_past(model, self.walls, pose[0], pose[1], item.radius, desired, robot,
                              -self._side[k]):
            self._side[k], self._held[k] = -self._side[k], 0.0
        dodge = self._dodge_sides(k, model, pose, item.radius, (vx, vy), desired, robot, dt)
        ax, ay = social_acceleration(model, pose[0], pose[1], vx, vy, item.radius, desired,
                                     others, self._path_speed[k], self._side[k], robot, dodge)
        vx, vy = limit_speed(vx + ax * dt, vy + ay * dt, v_max)
        # What it touches of walls and fixed objects: a velocity into one is not kept but
        # turned along it by the contact, and must not be turned into the robot.
        touching = (wall_normals(self.walls, pose[0], pose[1],
                                 item.radius + model.clearance_margin)
                    if model.wall_stop else [])
        vx, vy = keep_clear(model, pose[0], pose[1], vx, vy, item.radius, others, touching)
        # Held back (a wall on the side it turns to, the robot ahead): try the other side;
        # held back on that one too, turn back along the path.
        held = held_back(model, vx, vy, desired)
        self._held[k] = self._held[k] + dt if held else 0.0
        self._free[k] = 0.0 if held else self._free[k] + dt
        if self._free[k] >= model.patience:
            self._tried[k] = False
        if self._tried[k] and self._held[k] >= model.patience and model.turn_back_time > 0.0:
            self._turn_back(k, model.turn_back_time)
            self._held[k], self._tried[k] = 0.0, False
        side = pass_side(model, self._side[k], self._held[k])
        if side != self._side[k]:
            self._side[k], self._held[k], self._tried[k] = side, 0.0, True
        self._velocity[k] = (vx, vy)
        self._feedback[k] = (0.0, 0.0, _turn(item.face_motion, vx, vy, pose[2], FACING_SPEED))

    def _dodge_sides(self, k: int, model: SocialForce, pose: Pose, radius: float,
                     velocity: Vec, desired: Vec, robot: Agent | None, dt: float
                     ) -> Dodge | None:
        """The sides social human ``k`` gets past the robot by (``dodge_sides``): chosen when
        the robot comes at it and kept while it does, and for ``dodge_memory`` after."""
        if robot is None:
            return None
        kept = self._dodge[k]
        near = math.hypot(pose[0] - robot.x, pose[1] - robot.y) - radius - robot.radius \
            <= model.dodge_near
        chosen = dodge_sides(model, self.walls, pose[0], pose[1], radius, velocity, desired,
                             robot, self._side[k], kept if model.dodge_memory > 0.0 else None)
        if chosen is not None and near:
            self._dodge[k], self._dodge_age[k] = chosen, 0.0
            return chosen
        self._dodge_age[k] += dt
        if kept is not None and self._dodge_age[k] >= model.dodge_memory:
            self._dodge[k] = kept = None
        return chosen if chosen is not None else kept

    def commands(self, step: int) -> list[tuple[int, float, float, float]]:
        """(body, vx, vy, wz) moving each body along its curve from ``step`` to ``step + 1``."""
        block, j = divmod(step, BLOCK)
        if self._block != block:
            self._fill(block)
        out = []
        for k, item in enumerate(self.items):
            cx, cy, wz = self._feedback[k]
            if item.behaviour == "scripted":
                vx, vy = self._steps[k]
                out.append((item.body, vx[j] + cx, vy[j] + cy, wz))
                continue
            s = self._path_time[k]
            s_next = s + self._way[k] * item.variation.speed_scale * self._advance[k] / self.rate
            if not item.spline.loop:
                s_next = max(s_next, 0.0)
            self._path_time[k] = s_next
            if item.behaviour == "social":
                vx_s, vy_s = self._velocity[k]
                out.append((item.body, vx_s, vy_s, wz))
                continue
            (x0, y0), (x1, y1) = item.spline.position(s), item.spline.position(s_next)
            out.append((item.body, (x1 - x0) * self.rate + cx, (y1 - y0) * self.rate + cy, wz))
        return out

    def _fill(self, block: int) -> None:
        """The curve's per-step displacements of a block of steps, for every body at once."""
        steps = block * BLOCK + np.arange(BLOCK + 1)
        self._steps = []
        for item, started in zip(self.items, self._started, strict=True):
            if item.behaviour != "scripted":
                self._steps.append(([], []))
                continue
            if started is None:  # stands at its first vertex until its trigger starts it
                self._steps.append(([0.0] * BLOCK, [0.0] * BLOCK))
                continue
            v = item.variation
            times = np.maximum(0.0, v.speed_scale * ((steps - started) / self.rate - v.phase_s))
            moves = np.diff(item.spline.positions(times), axis=0) * self.rate
            self._steps.append((moves[:, 0].tolist(), moves[:, 1].tolist()))
        self._block = block
