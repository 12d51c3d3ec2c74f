"""Hazard clearance: how near ahead the laser saw a person or a moving object (issue 22).

The REACTION_TIME requirement asks how soon a robot slows down once it *could* know of a
hazard ahead. What it could know is what its laser measured, so this reads the scan itself
(the simulated ground-truth scan, never what the navigator claims to have seen): a beam whose
end point lies on the footprint of a person or a moving object (roles ``human`` and
``dynamic``; static objects are on the map and walls are not hazards) sees that hazard. A
hazard hidden behind a wall stub is not seen, so a robot is never asked to react to what no
beam reached. How near the hazard is: the distance from the robot's footprint to the seeing
beam's end point (0 inside it), the measure a navigator's own slow zone uses on its laser
points (the reference's, runtime/robot/navigator/reference.py), so a navigator that slows for a
laser point within some distance of its footprint is judged on the same number. (Along the
beam, as ``laser_clearance`` measures, a point ahead and to the side reads farther than it
is: the clock would start a scan after such a navigator decided.) Only beams ahead count
(within ``AHEAD`` of the robot's heading): a careful robot may keep its speed while it drives
away from a person.

This module must never import the simulator or keep module-level state.
"""

from __future__ import annotations

import math

import numpy as np

from rei.runtime.messages import LaserScan, StreamHeader
from rei.runtime.observation.model.geometry import _point_segment, inside_polygon, local_shape
from rei.runtime.observation.model.laser_clearance import beam_angles

HAZARD_ROLES = ("human", "dynamic")
"""Roles whose bodies are hazards a robot must react to (people and moving objects)."""
AHEAD = math.pi / 2
"""rad: beams within this of the robot's heading look ahead (the front half-plane)."""
HIT_TOLERANCE = 0.05
"""m: a beam ending this near a hazard's footprint saw it (the laser's 1 cm range noise and
the difference between a body's collision shape and its footprint; the default .vepl's
laser_tolerance)."""
LOOK_WITHIN = 3.0
"""m: hazards farther than this (footprint distance) are not looked for in the scan; the
requirements ask about hazards within about a metre."""
NONE_SEEN = 1e3
"""The clearance when no beam ahead sees a hazard (as far as FAR_AWAY in the model)."""


class HazardSensor:
    """Per run: the hazards of the stream header and their footprints, prepared once."""

    def __init__(self, header: StreamHeader) -> None:
        self.mount = (float(header.laser_mount[0]), float(header.laser_mount[1]))
        self.indices = [i for i, o in enumerate(header.objects) if o.role in HAZARD_ROLES]
        self.shapes = [local_shape(header.objects[i].footprint, header.tile_size)
                       for i in self.indices]
        self.robot_shape = local_shape(header.robot.footprint, header.tile_size)

    def clearance(self, scan: LaserScan, robot_pose: tuple[float, float, float],
                  poses: np.ndarray, distance: np.ndarray) -> float:
        """The smallest distance from the robot's footprint to the end point of a beam
        ahead that ends on a hazard's footprint; ``NONE_SEEN`` when no beam does."""
        near = [k for k, i in enumerate(self.indices) if distance[i] < LOOK_WITHIN]
        if not near:
            return NONE_SEEN
        ranges = np.asarray(scan.ranges, dtype=np.float64)
        angles = beam_angles(scan)
        ahead = np.abs(np.remainder(angles + math.pi, math.tau) - math.pi) <= AHEAD
        # NaN and inf ranges, and ranges at range_max, are beams without a return
        use = ahead & (ranges < scan.range_max)
        if not use.any():
            return NONE_SEEN
        r, a = ranges[use], angles[use]
        # the end points in the robot's frame, then in the world
        local_ends = np.stack((self.mount[0] + r * np.cos(a), self.mount[1] + r * np.sin(a)),
                              axis=1)
        x, y, yaw = robot_pose
        c, s = math.cos(yaw), math.sin(yaw)
        ends = np.stack((x + c * local_ends[:, 0] - s * local_ends[:, 1],
                         y + s * local_ends[:, 0] + c * local_ends[:, 1]), axis=1)
        seen = np.zeros(len(r), dtype=bool)
        pose_array = np.asarray(poses, dtype=np.float64)
        for k in near:
            ox, oy, oyaw = pose_array[self.indices[k]]
            poly, radius = self.shapes[k]
            dx, dy = ends[:, 0] - ox, ends[:, 1] - oy
            if poly is None:
                seen |= np.hypot(dx, dy) - radius <= HIT_TOLERANCE
                continue
            # into the object's frame, then the distance to its polygon (0 inside)
            oc, os_ = math.cos(oyaw), math.sin(oyaw)
            local = np.stack((oc * dx + os_ * dy, -os_ * dx + oc * dy), axis=1)
            seen |= _polygon_distance(local, poly) <= HIT_TOLERANCE
        if not seen.any():
            return NONE_SEEN
        points = local_ends[seen]
        poly, radius = self.robot_shape
        if poly is None:
            return float(max(0.0, float((np.hypot(points[:, 0], points[:, 1]) - radius).min())))
        return float(_polygon_distance(points, poly).min())


def _polygon_distance(points: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """(N,) distance from each point to a simple polygon's area (0 inside)."""
    following = np.roll(poly, -1, axis=0)
    edges = _point_segment(points[:, None, :], poly[None, :, :], following[None, :, :])
    return np.where(inside_polygon(points, poly, following), 0.0, edges.min(axis=1))
