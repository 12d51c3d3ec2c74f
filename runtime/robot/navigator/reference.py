"""`reference`: a real navigator shipped with REI, so a mission runs out of the box.

Global planning: A* (``rei.runtime.robot.navigator.gridplan``) over a grid of the known static map,
cells blocked within the robot's footprint radius of any wall or static object and made dearer
near them, so paths keep to the middle of passages. Local planning (localplan.py): a
dynamic-window search over (linear, angular) velocity pairs within the drive limits, each
rolled out for a short horizon against the points the laser sees (humans and moving objects
included), scored by progress towards a lookahead point on the path, clearance and speed.

Recovery (runtime/robot/navigator/recovery.py, as ROS move_base / Nav2 do it): when the local
planner
finds no admissible motion for ``STUCK_AFTER`` seconds, or the robot makes no progress for
``OSCILLATE_AFTER`` seconds, the navigator backs up, re-plans around what the laser sees (then
with a reduced inflation), turns towards the new path, waits for a person to walk on, and
drives on with a tighter laser margin for a while. It aborts a goal only when it made no
progress for ``BLOCKED_AFTER`` seconds and every recovery has been tried since (or, at the
latest, after ``BLOCKED_AFTER + ABORT_GRACE`` seconds; blocked or oscillating, thesis 7.4.4),
and a goal with no path. It reads only its observation (odometry and laser), never the ground
truth, and never commands a motion that brings its footprint into a point the laser sees.

Slow zone (what a people-aware stack does, and what a requirement may check): a laser point
farther than ``UNMAPPED_BEYOND`` from every obstacle of the static map is not explained by the
map (a person, a moving object, another robot; perception.py). While such a point is within
``SLOW_ZONE_RADIUS`` + ``SLOW_ZONE_LEAD`` of the footprint, every command is scaled down along
its arc so that the linear speed is at most ``SLOW_ZONE_SPEED``. The lead makes the robot slow
already by the time the point is within ``SLOW_ZONE_RADIUS`` (a laser period and the drive's
deceleration later). The zone is remembered for ``SLOW_ZONE_MEMORY`` seconds after the last
such point: a person who steps next to a wall or a table merges with the map in the laser,
but is still there.

One navigator in three modules, split along the lines above: ``ReferenceNavigator`` (here:
goals, the global path, recovery and the slow zone's cap) is a ``LocalPlanner``
(localplan.py), which is a ``LaserView`` (perception.py). They share the state ``reset``
sets, and every method kept its name, so a subclass (bench/defects, the tests' navigators
before a fix) overrides what it did before. The UPPERCASE names are the fields of its
``ReferenceTuning`` (tuning.py: how the former constants and class attributes still read
and override); the signed distance to a box is geometry.py's.
This module must never import pybullet.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from rei.runtime.messages import NavState
from rei.runtime.robot.behaviours import doing_message
from rei.runtime.robot.contract import (
    STOP,
    ControllerContext,
    GoalFeedback,
    GoalTracker,
    NavGoal,
    Observation,
    VelocityCommand,
)
from rei.runtime.robot.navigator.clearance import clearance_field
from rei.runtime.robot.navigator.gridplan import GridGraph
from rei.runtime.robot.navigator.localplan import LocalPlanner
from rei.runtime.robot.navigator.recovery import Recovery
from rei.runtime.robot.navigator.smoother import VelocitySmoother, smooth_safely
from rei.runtime.robot.navigator.tuning import DEFAULT_TUNING, ReferenceTuning, Tuned

# The default tuning under the module-level names it had before the record (tests, bench
# and users' navigators import them); a navigator tuned otherwise takes a ReferenceTuning.
RESOLUTION = DEFAULT_TUNING.resolution
COMFORT = DEFAULT_TUNING.comfort
LOOKAHEAD = DEFAULT_TUNING.lookahead
HORIZON = DEFAULT_TUNING.horizon
ROLLOUT_STEPS = DEFAULT_TUNING.rollout_steps
MARGIN = DEFAULT_TUNING.margin
SENSE_RADIUS = DEFAULT_TUNING.sense_radius
LOCAL_RES = DEFAULT_TUNING.local_res
BLOCKED_AFTER = DEFAULT_TUNING.blocked_after
ABORT_GRACE = DEFAULT_TUNING.abort_grace
FINAL_APPROACH = DEFAULT_TUNING.final_approach
ALIGN_FIRST = DEFAULT_TUNING.align_first
STUCK_AFTER = DEFAULT_TUNING.stuck_after
OSCILLATE_AFTER = DEFAULT_TUNING.oscillate_after
TIGHT_MARGIN = DEFAULT_TUNING.tight_margin
TIGHT_FOR = DEFAULT_TUNING.tight_for
TURN_COMMITMENT = DEFAULT_TUNING.turn_commitment
SQUEEZE_GAP = DEFAULT_TUNING.squeeze_gap
SIDE_MEMORY = DEFAULT_TUNING.side_memory
SLOW_ZONE_RADIUS = DEFAULT_TUNING.slow_zone_radius
SLOW_ZONE_SPEED = DEFAULT_TUNING.slow_zone_speed
SLOW_ZONE_LEAD = DEFAULT_TUNING.slow_zone_lead
SLOW_ZONE_MEMORY = DEFAULT_TUNING.slow_zone_memory
UNMAPPED_BEYOND = DEFAULT_TUNING.unmapped_beyond
EXACT_ALLOWANCE = DEFAULT_TUNING.exact_allowance
MAP_FIT_RES = DEFAULT_TUNING.map_fit_res
SHADOW_GRAZE = DEFAULT_TUNING.shadow_graze
ODOMETRY_KEPT = DEFAULT_TUNING.odometry_kept
SHADOW_TOLERANCE = DEFAULT_TUNING.shadow_tolerance


class ReferenceNavigator(LocalPlanner):
    name = "reference"
    slow_zone_reach = Tuned[float]()
    """Metres from the footprint within which an unmapped laser point slows the robot (its
    forward protective field; a subclass tuned otherwise sets its own, and the default
    .vepl's ``react_zone`` is this value, to be set with `--param` for such a robot)."""
    turn_commitment = Tuned[float]()
    """Score a driving arc against the last driving turn loses while the slow zone holds
    (``TURN_COMMITMENT``; 0: none, and no side held near people either)."""
    hold_near_people = Tuned[bool]()
    """Whether, while the slow zone holds, the side of the last driving turn is held outright
    for ``SIDE_MEMORY`` (``TURN_COMMITMENT``; False: only its cost, the planner before issue
    25's TPE cand0045)."""

    smooth = Tuned[bool]()
    """Whether the commands pass the velocity smoother (``ReferenceTuning.smooth``)."""

    def __init__(self, tuning: ReferenceTuning = DEFAULT_TUNING) -> None:
        self.tuning = tuning
        self._tracker = GoalTracker()
        self._ctx: ControllerContext | None = None

    # -- setup ---------------------------------------------------------------------------

    def reset(self, context: ControllerContext) -> None:
        self._ctx = context
        self._tracker = GoalTracker()
        self._slow_until = -math.inf
        self._now = -math.inf
        """The time of the last step's observation."""
        self._doing: list[str] = []
        """What the last step did (behaviours.BEHAVIOURS' names), for the feedback."""
        self._path: np.ndarray | None = None
        self._pose = None
        self._trig_key = None
        self._tail: np.ndarray | None = None
        self._index = 0
        self._best_remaining = math.inf
        self._last_progress_time = 0.0
        self._stuck_since: float | None = None
        self._stuck_turn = 0.0
        """The direction of the turn on the spot while stuck (0: none yet)."""
        self._tight_until = -math.inf
        self._turn_side = 0.0
        """Sign of the local planner's last driving turn (0: none since the goal or a
        recovery)."""
        self._turn_time = -math.inf
        """When the local planner last chose a driving turn."""
        self._align_first = False
        hx, hy = context.robot_size[0] / 2, context.robot_size[1] / 2
        self._half = (hx, hy)
        self._radius = math.hypot(hx, hy)
        limit = context.drive.max_linear
        if context.max_speed is not None:
            limit = min(limit, context.max_speed)
        self._vmax = limit
        self._wmax = context.drive.max_angular
        self._points_of = None
        self._points = np.zeros((0, 2))
        self._odometry = []
        """(time, odometry pose) of the last ``ODOMETRY_KEPT`` steps."""
        self._scan_pose = context.start_pose
        """The odometry pose the current scan was taken from (see ``_pose_at``)."""
        # Per-scan results, keyed by the identity of the scan's points (see _laser_points).
        self._clearance_of = None
        self._clearance = np.zeros(0)
        self._near_of = None
        self._near = np.zeros((0, 2))
        self._build_grid(context)
        self._build_map_fit(context)
        self._build_rollouts()
        laser = context.laser
        # Backing up is only done where the laser sees behind the robot.
        self._recovery = Recovery(self._half, self._vmax, self._wmax,
                                  rear_visible=laser.fov >= 1.9 * math.pi)
        self._smoother = VelocitySmoother.of_run(context)

    def _build_grid(self, ctx: ControllerContext) -> None:
        res = self.tuning.resolution
        x0, y0, x1, y1 = ctx.bounds
        nx_, ny_ = int(math.ceil((x1 - x0) / res)), int(math.ceil((y1 - y0) / res))
        xs = x0 + (np.arange(nx_) + 0.5) * res
        ys = y0 + (np.arange(ny_) + 0.5) * res
        clear = clearance_field(xs, ys, ctx, self.tuning.comfort + 0.1)
        self._origin = (x0, y0)
        self._shape = (nx_, ny_)
        self._clear = clear
        self._graph = self._grid_graph(self._radius + 0.01)
        self._reduced: GridGraph | None = None

    def _grid_graph(self, inflate: float) -> GridGraph:
        """The planning graph of the cells farther than ``inflate`` from the static map."""
        clear, comfort = self._clear, self.tuning.comfort
        cost = 1.0 + 4.0 * np.clip((comfort - clear) / comfort, 0.0, 1.0)
        return GridGraph(clear > inflate, cost)

    def _reduced_graph(self) -> GridGraph:
        """The graph with the inflation cut to the half width (built on first use): passages
        the robot fits through only when aligned with them, which the local planner checks."""
        if self._reduced is None:
            self._reduced = self._grid_graph(max(self._half) + 0.01)
        return self._reduced

    # -- goals (Figure 22) ---------------------------------------------------------------

    def send_goal(self, goal: NavGoal) -> None:
        self._tracker.send(goal)

    def cancel_goal(self) -> None:
        self._tracker.cancel()

    def feedback(self) -> GoalFeedback:
        feedback = self._tracker.feedback(self._remaining if self._tracker.running else None)
        if feedback.state is not NavState.ACTIVE:
            return feedback
        # What the last step did, as behaviours.py asks a controller to report it; the slow
        # zone is the step's last word (it may scale what _navigate chose).
        doing = self._doing + (["slow_for_person"] if self._now < self._slow_until else [])
        return replace(feedback, message=doing_message(doing))

    # -- planning --------------------------------------------------------------------------

    def _cell(self, x: float, y: float) -> tuple[int, int]:
        i = int((x - self._origin[0]) / self.tuning.resolution)
        j = int((y - self._origin[1]) / self.tuning.resolution)
        return min(max(i, 0), self._shape[0] - 1), min(max(j, 0), self._shape[1] - 1)

    @staticmethod
    def _nearest_free(cell: tuple[int, int], graph: GridGraph) -> tuple[int, int] | None:
        if cell in graph:
            return cell
        free_cells = graph.free_cells
        if len(free_cells) == 0:
            return None
        d = np.abs(free_cells - np.array(cell)).sum(axis=1)
        best = free_cells[int(np.argmin(d))]
        return int(best[0]), int(best[1])

    def _plan(self, start: tuple[float, float], goal: NavGoal,
              blocked: set[tuple[int, int]] | None = None,
              reduced: bool = False) -> np.ndarray | None:
        graph = self._reduced_graph() if reduced else self._graph
        a = self._nearest_free(self._cell(*start), graph)
        b = self._nearest_free(self._cell(goal.x, goal.y), graph)
        if a is None or b is None:
            return None
        # What the laser saw is hidden for this plan only (the start and goal never are).
        cells = graph.astar(a, b, blocked)
        if cells is None:
            return None
        res, (x0, y0) = self.tuning.resolution, self._origin
        pts = [(x0 + (i + 0.5) * res, y0 + (j + 0.5) * res) for i, j in cells]
        pts.append((goal.x, goal.y))
        return np.array(pts, dtype=float)

    @property
    def _remaining(self) -> float:
        path = self._path
        if path is None or self._pose is None:
            return math.inf
        if self._tail is None or len(self._tail) != len(path):
            # Path length from each point to the end, computed once per path.
            seg = np.hypot(*np.diff(path, axis=0).T)
            self._tail = np.concatenate((np.cumsum(seg[::-1])[::-1], [0.0]))
        i = self._index
        here = math.hypot(path[i, 0] - self._pose[0], path[i, 1] - self._pose[1])
        return here + float(self._tail[i])

    # -- control ---------------------------------------------------------------------------

    _pose: tuple[float, float, float] | None = None

    def step(self, observation: Observation) -> VelocityCommand:
        self._odometry.append((observation.time, observation.odom_pose))
        t = self.tuning
        del self._odometry[:-t.odometry_kept]
        cmd = self._navigate(observation)
        points = self._laser_points(observation)
        if self._in_slow_zone(self._scan_pose, points):
            self._slow_until = observation.time + t.slow_zone_memory
        if abs(cmd.linear) > t.slow_zone_speed and observation.time < self._slow_until:
            # Scaling both keeps the arc the local planner checked against the laser.
            k = t.slow_zone_speed / abs(cmd.linear)
            cmd = VelocityCommand(cmd.linear * k, cmd.angular * k)
        # Within the drive's accelerations (smoother.py), unless braking from the smoothed
        # command would come nearer the laser points than the planner's margin allows.
        if not self.smooth:
            return cmd
        margin = t.tight_margin if observation.time < self._tight_until else t.margin
        return smooth_safely(self._smoother, cmd, observation.time, points, self._half, margin)

    def _navigate(self, observation: Observation) -> VelocityCommand:
        tracker, t = self._tracker, self.tuning
        self._pose = observation.odom_pose
        self._now = observation.time
        self._doing = []
        if not tracker.running or tracker.goal is None:
            return STOP
        goal = tracker.goal
        x, y, yaw = observation.odom_pose
        if tracker.state.value == "pending":
            tracker.accept()
            self._path = self._plan((x, y), goal)
            self._index = 0
            self._tail = None
            self._best_remaining = math.inf
            self._last_progress_time = observation.time
            self._stuck_since = None
            self._stuck_turn = 0.0
            self._turn_side = 0.0
            self._align_first = True
            if self._path is None:
                tracker.abort("no path to the goal on the static map")
                return STOP
        reach = min(0.1, 0.5 * goal.tolerance)
        dist = math.hypot(goal.x - x, goal.y - y)
        if dist <= reach:
            if goal.yaw is None:
                tracker.succeed()
                return STOP
            err = math.remainder(goal.yaw - yaw, math.tau)
            if abs(err) < 0.05:
                tracker.succeed()
                return STOP
            turn = float(np.clip(2.0 * err, -0.6 * self._wmax, 0.6 * self._wmax))
            self._doing.append("goal_heading")
            return VelocityCommand(0.0, turn)
        now = observation.time
        recovery = self._recovery
        remaining = self._advance((x, y))
        if remaining < self._best_remaining - 0.1:
            self._best_remaining = remaining
            self._last_progress_time = now
            recovery.progress()
        else:
            idle = now - self._last_progress_time
            if idle > t.blocked_after and (recovery.exhausted
                                           or idle > t.blocked_after + t.abort_grace):
                tracker.abort(f"no progress for {idle:.0f} s after {recovery.rounds} recovery "
                              f"round(s) (blocked or oscillating)")
                return STOP
        points = self._laser_points(observation)
        pose = observation.odom_pose
        if recovery.active:
            begun = len(recovery.log)
            action = recovery.step(now, pose, points,
                                   lambda reduced: self._replan_around(points, goal, (x, y),
                                                                       reduced),
                                   lambda: self._path_heading((x, y)))
            self._report_recovery(begun)
            if action.command is not None:
                return action.command
            # The level is over: drive on, keeping closer to obstacles for a while.
            self._tight_until = now + t.tight_for
            self._stuck_since = None
            self._stuck_turn = 0.0
            self._turn_side = 0.0
        if dist < t.final_approach:
            cmd = self._approach(pose, goal, dist, points)
            if cmd.linear == 0.0 and now - max(self._last_progress_time,
                                              recovery.ended_at or -math.inf) > t.oscillate_after:
                return self._start_recovery(now, pose, points, goal)
            return cmd
        margin = t.tight_margin if now < self._tight_until else t.margin
        if self._align_first:
            align = self._turn_to_path(pose, points, margin)
            if align is not None:
                return align
        slow = now < self._slow_until
        hold = now - self._turn_time < t.side_memory and (
            (slow and self.hold_near_people and self.turn_commitment > 0.0)
            or self._squeezed(points))
        chosen = self._choose(pose, points, dist, margin,
                              self.turn_commitment if slow else 0.0, hold)
        if chosen is not None and chosen.angular != 0.0 and chosen.linear != 0.0:
            self._turn_time = now
        heading = self._path_heading((x, y))
        aligned = heading is not None and abs(math.remainder(heading - yaw, math.tau)) < 0.5
        # Turning on the spot although already facing the path is the local planner's way
        # of saying that nothing ahead is admissible: as stuck as finding nothing at all.
        if chosen is None or (chosen.linear <= 0.0 and aligned):
            if self._stuck_since is None:
                self._stuck_since = now
            if now - self._stuck_since >= t.stuck_after:
                return self._start_recovery(now, pose, points, goal)
            # Nothing ahead is admissible: turn on the spot as the planner says, but never
            # back the other way while stuck (with a person in a door ahead it picked left
            # and right by turns, a chatter of commands that got it nowhere: the standing
            # stressor, COMMAND_CHATTER); stand and wait for the way to clear instead.
            if chosen is None or chosen.angular * self._stuck_turn < 0.0:
                self._doing.append("wait_for_person")
                return STOP
            self._stuck_turn = chosen.angular or self._stuck_turn
            return chosen
        self._stuck_since = None
        self._stuck_turn = 0.0
        if chosen.linear > 0.0 and self._squeezed(points):
            self._doing.append("tight_passage")
        if now - max(self._last_progress_time, recovery.ended_at or -math.inf) > t.oscillate_after:
            return self._start_recovery(now, pose, points, goal)
        return chosen

    def _start_recovery(self, now: float, pose: tuple[float, float, float], points: np.ndarray,
                        goal: NavGoal) -> VelocityCommand:
        """Begin the next level of the recovery ladder and return its first command."""
        recovery = self._recovery
        begun = len(recovery.log)
        recovery.begin(now, pose)
        self._stuck_since = None
        self._stuck_turn = 0.0
        action = recovery.step(now, pose, points,
                               lambda reduced: self._replan_around(points, goal, pose[:2],
                                                                   reduced),
                               lambda: self._path_heading(pose[:2]))
        self._report_recovery(begun)
        if action.command is not None:
            return action.command
        self._tight_until = now + self.tuning.tight_for
        return STOP

    def _report_recovery(self, begun: int) -> None:
        """Report the recovery behaviour running now and those begun since the recovery log
        held ``begun`` entries (a re-plan begins and ends within one step)."""
        recovery = self._recovery
        start = min(begun, len(recovery.log) - 1) if recovery.active else begun
        for behaviour in recovery.log[max(0, start):]:
            name = f"recovery.{behaviour}"
            if name not in self._doing:
                self._doing.append(name)

    def _path_heading(self, xy: tuple[float, float]) -> float | None:
        """World direction from the robot to the lookahead point of its path."""
        if self._path is None:
            return None
        target = self._lookahead(xy)
        if math.hypot(target[0] - xy[0], target[1] - xy[1]) < 1e-6:
            return None
        return math.atan2(target[1] - xy[1], target[0] - xy[0])

    def _advance(self, xy: tuple[float, float]) -> float:
        path = self._path
        assert path is not None
        window = path[self._index:self._index + 30]
        d = np.hypot(window[:, 0] - xy[0], window[:, 1] - xy[1])
        self._index += int(np.argmin(d))
        return self._remaining

    def _lookahead(self, xy: tuple[float, float]) -> np.ndarray:
        path = self._path
        assert path is not None
        rest = path[self._index:]
        d = np.hypot(rest[:, 0] - xy[0], rest[:, 1] - xy[1])
        beyond = np.nonzero(d >= self.tuning.lookahead)[0]
        point: np.ndarray = rest[int(beyond[0])] if len(beyond) else rest[-1]
        return point

    def _replan_around(self, points: np.ndarray, goal: NavGoal, xy: tuple[float, float],
                       reduced: bool = False) -> bool:
        """Replan with the cells around what the laser sees now marked as blocked (with the
        inflation cut to the half width when ``reduced``); True when a path was adopted."""
        if self._pose is None:
            return False
        x, y, yaw = self._pose
        c, s = math.cos(yaw), math.sin(yaw)
        wx = x + c * points[:, 0] - s * points[:, 1]
        wy = y + s * points[:, 0] + c * points[:, 1]
        # A cell is blocked when its centre lies within the inflation of a point the laser
        # sees; cells where the robot stands are free whatever the laser says around them.
        inflate = (max(self._half) if reduced else self._radius) + 0.05
        res = self.tuning.resolution
        grow = int(math.ceil(inflate / res)) + 1
        ci = np.floor((wx - self._origin[0]) / res).astype(np.int64)
        cj = np.floor((wy - self._origin[1]) / res).astype(np.int64)
        off = np.arange(-grow, grow + 1)
        ii = (ci[:, None, None] + off[None, :, None]).repeat(len(off), axis=2)
        jj = (cj[:, None, None] + off[None, None, :]).repeat(len(off), axis=1)
        cx = self._origin[0] + (ii + 0.5) * res
        cy = self._origin[1] + (jj + 0.5) * res
        near = np.hypot(cx - wx[:, None, None], cy - wy[:, None, None]) < inflate
        near &= np.hypot(cx - xy[0], cy - xy[1]) > res
        inside = (ii >= 0) & (ii < self._shape[0]) & (jj >= 0) & (jj < self._shape[1])
        keep = near & inside
        blocked: set[tuple[int, int]] = set(zip(ii[keep].tolist(), jj[keep].tolist(),
                                                strict=True))
        path = self._plan(xy, goal, blocked, reduced)
        around = path is not None and bool(blocked)
        if path is None and blocked:
            # What the laser sees shuts every way: the map alone may still have one (a
            # person about to move on); keep to it rather than to the stale path.
            path = self._plan(xy, goal, None, reduced)
        if path is None:
            return False
        if around and self._unmapped(points, self._pose).any():
            # round what the laser sees, of which the map does not show everything
            self._doing.append("replan_unmapped")
        self._path, self._index, self._tail = path, 0, None
        # A new path is measured afresh: a longer detour is not a loss of progress, but
        # adopting it is no progress either (the abort clock keeps running).
        self._best_remaining = self._remaining
        return True
