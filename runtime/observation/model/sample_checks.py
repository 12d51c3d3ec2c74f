"""The sample hygiene: whether a sample can be used (``check_sample``), and the bad samples
of a run (``SampleProblems``): non-finite, out-of-order, duplicated, missing and malformed
samples are counted, never modelled. It must never import pybullet, the simulation, the
evaluator or the monitor's host.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rei.runtime.messages import Sample, StreamHeader

PROBLEM_KINDS = ("non_finite", "out_of_order", "duplicate", "missing", "malformed")


@dataclass
class SampleProblems:
    """Bad samples seen in a run, with when, so verdicts they touch become inconclusive."""

    counts: dict[str, int] = field(default_factory=lambda: dict.fromkeys(PROBLEM_KINDS, 0))
    times: list[float] = field(default_factory=list)

    def add(self, kind: str, time: float, n: int = 1) -> None:
        self.counts[kind] += n
        self.times.append(time)

    @property
    def total(self) -> int:
        return sum(self.counts.values())

    def within(self, start: float, end: float) -> bool:
        return any(start <= t <= end for t in self.times)



def check_sample(s: Sample, header: StreamHeader) -> str | None:
    """Why a sample cannot be used (a PROBLEM_KINDS entry), or None."""
    n = len(header.objects)
    poses = np.asarray(s.poses)
    twists = np.asarray(s.twists)
    if poses.shape != (n, 3) or twists.shape != (n, 3):
        return "malformed"
    if not all(isinstance(i, (int, np.integer)) and 0 <= i < n for i in s.contacts):
        return "malformed"
    scalars = (s.time, *s.robot_pose, *s.robot_twist, *s.belief.odom, *s.belief.odom_twist,
               s.belief.laser_min, *s.belief.cmd)
    if not all(map(math.isfinite, scalars)):
        return "non_finite"
    scan = s.belief.scan
    if scan is not None:
        ranges = np.asarray(scan.ranges)
        if ranges.ndim != 1:
            return "malformed"
        # NaN and +inf ranges are beams without a return (not counted); -inf is nonsense
        if not all(map(math.isfinite, (scan.angle_min, scan.angle_increment, scan.range_max))) \
                or np.count_nonzero(ranges == -math.inf):
            return "non_finite"
    finite = np.logical_and.reduce  # the ufunc itself: no wrapper, no warnings to silence
    if not (finite(np.isfinite(poses), axis=None) and finite(np.isfinite(twists), axis=None)):
        return "non_finite"
    return None
