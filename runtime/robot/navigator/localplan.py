"""The `reference` navigator's local planner: a dynamic-window search over (linear, angular)
velocity pairs within the drive limits, each rolled out for ``HORIZON`` seconds against the
points the laser sees (humans and moving objects included), scored by progress towards a
lookahead point on the path, clearance and speed; with the side of its last driving turn
held near people and in a squeeze (``TURN_COMMITMENT``, ``SQUEEZE_GAP``). Besides it, the
turn on the spot towards a path behind the robot (``ALIGN_FIRST``) and the direct approach
of the last decimetres (``FINAL_APPROACH``).

``LocalPlanner`` is a part of ``ReferenceNavigator`` (runtime/robot/navigator/reference.py),
not a navigator of its own: ``ReferenceNavigator.reset`` sets the state it reads and gives it
the path (``_lookahead``, ``_path_heading``), and a subclass of the navigator overrides its
methods as before (the tests' ``_squeezed``, ``_exact_clearance`` and ``_turn_to_path`` of
the navigator before a fix).
This module must never import pybullet.
"""
from __future__ import annotations

import math

import numpy as np

from rei.runtime.robot.contract import NavGoal, VelocityCommand
from rei.runtime.robot.navigator.clearance import box_distance
from rei.runtime.robot.navigator.perception import LaserView
from rei.runtime.robot.navigator.recovery import arc_poses, footprint_gaps


class LocalPlanner(LaserView):
    """The roll-outs, their swept-distance map, and the choice among them."""

    _vmax: float
    _wmax: float
    _radius: float
    _turn_side: float
    _clearance_of: np.ndarray | None
    _clearance: np.ndarray
    _align_first: bool

    def _lookahead(self, xy: tuple[float, float]) -> np.ndarray:
        """The point of the path the roll-outs are scored towards (the navigator's)."""
        raise NotImplementedError

    def _path_heading(self, xy: tuple[float, float]) -> float | None:
        """World direction from the robot to its lookahead point (the navigator's)."""
        raise NotImplementedError

    def _build_rollouts(self) -> None:
        """Velocity pairs, their rolled-out poses, and each one's swept-distance map.

        For every pair, ``_sweep[k, cell]`` is the distance from a cell of a robot-centred
        local grid to the footprint anywhere along the roll-out (negative inside). Computed
        once here, it turns the per-step collision check into a gather over the cells the
        laser points fall in, instead of transforming every point into every rolled-out pose.
        """
        t = self.tuning
        vs = self._vmax * np.array([-0.25, 0.0, 0.25, 0.5, 0.75, 1.0])
        ws = self._wmax * np.array([-0.6, -0.35, -0.18, -0.08, 0.0, 0.08, 0.18, 0.35, 0.6])
        v, w = np.meshgrid(vs, ws, indexing="ij")
        self._cmds = np.stack((v.ravel(), w.ravel()), axis=1)
        self._standing = int(np.nonzero((self._cmds == 0.0).all(axis=1))[0][0])
        """Index of standing still: its roll-out's clearance is the footprint's gap now."""
        fine = t.rollout_steps * 2
        ts = np.linspace(0.0, t.horizon, fine + 1)
        vv, ww = self._cmds[:, 0:1], self._cmds[:, 1:2]
        th = ww * ts[None, :]
        safe_w = np.where(np.abs(ww) < 1e-9, 1.0, ww)
        x = np.where(np.abs(ww) < 1e-9, vv * ts, vv / safe_w * np.sin(th))
        y = np.where(np.abs(ww) < 1e-9, 0.0, vv / safe_w * (1 - np.cos(th)))
        roll = np.stack((x, y, th), axis=2)  # (K, S, 3) in the robot's frame
        self._roll_end = roll[:, -1, :]
        # The grid reaches a little beyond the farthest roll-out: points outside it are clear.
        reach = float(np.abs(roll[:, :, :2]).max()) + self._radius + 0.25
        n = 2 * int(math.ceil(reach / t.local_res))
        centres = (np.arange(n) + 0.5) * t.local_res - n * t.local_res / 2
        cx, cy = np.meshgrid(centres, centres, indexing="ij")
        cells = np.stack((cx.ravel(), cy.ravel()), axis=1).astype(np.float32)
        roll = roll.astype(np.float32)
        hx, hy = self._half
        sweep = np.full((len(self._cmds), len(cells)), np.inf, dtype=np.float32)
        for step in range(roll.shape[1]):
            px, py, pt = roll[:, step, 0:1], roll[:, step, 1:2], roll[:, step, 2:3]
            dx = cells[None, :, 0] - px
            dy = cells[None, :, 1] - py
            gap = box_distance(dx, dy, np.cos(pt), np.sin(pt), hx, hy)
            sweep = np.minimum(sweep, gap)
        # A cell stands for points anywhere inside it: count them half a diagonal closer.
        self._sweep = sweep - np.float32(t.local_res * 0.7072)
        self._local_n = n

    def _choose(self, pose: tuple[float, float, float], points: np.ndarray,
                dist: float, margin: float | None = None, commit: float = 0.0,
                hold: bool = False) -> VelocityCommand | None:
        """The best admissible velocity pair, None when none is; ``margin``: the gap kept
        from the laser points (``MARGIN`` when None); ``commit``: the score an arc turning
        against the last driving turn loses (``TURN_COMMITMENT``); ``hold``: such an arc is
        not admissible at all (in a squeeze, ``SQUEEZE_GAP``, or near a person,
        ``hold_near_people``)."""
        if margin is None:
            margin = self.tuning.margin
        x, y, yaw = pose
        target = self._lookahead((x, y))
        c, s = math.cos(yaw), math.sin(yaw)
        tx = c * (target[0] - x) + s * (target[1] - y)
        ty = -s * (target[0] - x) + c * (target[1] - y)
        clearance = self._rollout_clearance(points, self._scan_pose)
        hit = clearance < margin
        clearance = np.clip(clearance, 0.0, 0.5)
        v, w = self._cmds[:, 0], self._cmds[:, 1]
        end = self._roll_end
        to_target = np.hypot(tx - end[:, 0], ty - end[:, 1])
        heading_err = np.abs(np.arctan2(ty - end[:, 1], tx - end[:, 0]) - end[:, 2])
        heading_err = np.minimum(heading_err, 2 * math.pi - heading_err)
        # Close to the goal, slow down so the robot stops within tolerance.
        slow = min(1.0, max(0.25, dist / 0.6))
        over = np.maximum(v - self._vmax * slow, 0.0)
        against = (w * self._turn_side < 0) & (v != 0.0)
        score = (-1.0 * to_target - 0.35 * heading_err + 0.6 * clearance
                 + 0.25 * v / self._vmax - 3.0 * over - 0.4 * (v < 0) - commit * against)
        score = np.where(hit | (hold & against), -np.inf, score)
        # Standing still is admissible but never progress: only chosen when nothing else is.
        score = np.where((v == 0.0) & (w == 0.0), -np.inf, score)
        best = int(np.argmax(score))
        if not np.isfinite(score[best]):
            return None
        if w[best] != 0.0 and v[best] != 0.0:
            self._turn_side = math.copysign(1.0, float(w[best]))
        return VelocityCommand(float(v[best]), float(w[best]))

    def _squeezed(self, points: np.ndarray) -> bool:
        """Whether a laser point is within ``SQUEEZE_GAP`` of the footprint where it stands."""
        clearance = self._rollout_clearance(points, self._scan_pose)
        return bool(clearance[self._standing] < self.tuning.squeeze_gap)

    def _rollout_clearance(self, points: np.ndarray,
                           pose: tuple[float, float, float]) -> np.ndarray:
        """Each roll-out's smallest gap to the laser points (robot frame, seen from ``pose``),
        0.5 when none is in reach; the same for every tick of one scan, so computed once per
        scan.

        The swept-distance grid is a fast but rounded answer: a point counts as the centre
        of its cell, half a diagonal nearer, so a gap can read up to ~5.7 cm smaller than it
        is. Beside a table's corner 4.5 cm from the robot's side, that rounding refused every
        motion, standing still included, and the robot could only back up and come back to
        the same spot until it aborted (issue 25). So where the grid puts a roll-out below
        ``MARGIN`` because of points the static map explains (walls, furniture: they stay
        where they are), the gap to those points is measured again exactly
        (``footprint_gaps`` over finely spaced poses of the arc), less ``EXACT_ALLOWANCE``:
        the margin then means what it says, and a true gap below it is still refused. Unmapped
        points (people, moving
        things, which may come nearer within the horizon) keep the grid's wider reading.
        """
        if self._clearance_of is points:
            return self._clearance
        n = self._local_n
        clearance = np.full(len(self._cmds), 0.5)
        if len(points):
            ij = np.floor(points / self.tuning.local_res + n / 2).astype(np.int64)
            inside = ((ij >= 0) & (ij < n)).all(axis=1)
            flat = ij[inside, 0] * n + ij[inside, 1]
            if len(flat):
                gaps = self._sweep[:, flat]
                clearance = gaps.min(axis=1).astype(float)
                below = np.nonzero(clearance < self.tuning.margin)[0].tolist()
                if below:
                    near = points[inside]
                    mapped = ~self._unmapped(near, pose)
                    for k in below:
                        clearance[k] = self._exact_clearance(k, near, gaps[k], mapped)
        clearance.flags.writeable = False
        self._clearance_of, self._clearance = points, clearance
        return clearance

    def _exact_clearance(self, k: int, points: np.ndarray, rounded: np.ndarray,
                         mapped: np.ndarray) -> float:
        """Roll-out ``k``'s smallest gap: measured (less ``EXACT_ALLOWANCE``) to the
        ``mapped`` points whose rounded gap (``rounded``, from the grid) is below ``MARGIN``,
        the grid's to every other one."""
        t = self.tuning
        close = (rounded < t.margin) & mapped
        if not close.any():
            return float(rounded.min())
        v, w = float(self._cmds[k, 0]), float(self._cmds[k, 1])
        # Poses spaced so that the footprint moves at most ~1 cm (or 0.02 rad) between them.
        steps = max(2, int(math.ceil(max(abs(v) * t.horizon / 0.01, abs(w) * t.horizon / 0.02))))
        exact = float(footprint_gaps(points[close], self._half,
                                     arc_poses(v, w, t.horizon, steps)).min())
        # Never read nearer than the grid did, nor wider than the truth less the allowance.
        gap = max(exact - t.exact_allowance, float(rounded[close].min()))
        rest = rounded[~close]
        return min(gap, float(rest.min())) if len(rest) else gap

    def _turn_to_path(self, pose: tuple[float, float, float], points: np.ndarray,
                      margin: float) -> VelocityCommand | None:
        """A goal's first motion when its path starts more than ``ALIGN_FIRST`` off the
        robot's heading: the turn on the spot towards it, while that turn's roll-out keeps
        ``margin`` from every laser point. None from the moment the robot faces the path, or
        the turn is not clear (the local planner then finds its own way), for the rest of
        the goal."""
        heading = self._path_heading(pose[:2])
        err = math.remainder(heading - pose[2], math.tau) if heading is not None else 0.0
        if abs(err) > self.tuning.align_first:
            w = math.copysign(0.6 * self._wmax, err)
            k = int(np.argmin(np.abs(self._cmds[:, 0]) + np.abs(self._cmds[:, 1] - w)))
            if self._rollout_clearance(points, self._scan_pose)[k] >= margin:
                return VelocityCommand(0.0, float(self._cmds[k, 1]))
        self._align_first = False
        return None

    def _approach(self, pose: tuple[float, float, float], goal: NavGoal, dist: float,
                  points: np.ndarray) -> VelocityCommand:
        """The last few decimetres: turn towards the goal, then creep onto it."""
        margin = self.tuning.margin
        x, y, yaw = pose
        err = math.remainder(math.atan2(goal.y - y, goal.x - x) - yaw, math.tau)
        w = float(np.clip(2.0 * err, -0.6 * self._wmax, 0.6 * self._wmax))
        if abs(err) > 0.3:
            return VelocityCommand(0.0, w)
        hx, hy = self._half
        ahead = points[(points[:, 0] > 0) & (np.abs(points[:, 1]) < hy + margin)] \
            if len(points) else points
        if len(ahead) and float(ahead[:, 0].min()) - hx < dist + margin:
            return VelocityCommand(0.0, w)
        return VelocityCommand(float(min(0.5 * self._vmax, 0.8 * dist + 0.02)), w)
