"""Between two samples: the query inputs part of the way from one to the next
(``interpolate``) and where a comparison margin changes sign (``crossings``). It must never
import pybullet, the simulation, the evaluator or the monitor's host.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from rei.runtime.observation.automata.records import QueryInputs


def interpolate(a: QueryInputs, b: QueryInputs, f: float) -> QueryInputs:
    """The inputs a fraction ``f`` of the way from sample ``a`` to sample ``b`` (the
    continuous measures only; states come from ``b``).

    Distances move linearly, as the bodies do at constant velocity between two samples; the
    robot's velocities are therefore ``b``'s throughout (the command sent at ``a`` is what
    it drives until ``b``, and ``b``'s twist is the one it drove with). Interpolating them
    as well made up motions the robot never made: between a turn on the spot to the left
    and an arc to the right, a left turn while driving (issue 22: a false SMOOTH_MOTION
    failure, medium room 261)."""
    return replace(b, distance=a.distance + f * (b.distance - a.distance),
                   laser_min=a.laser_min + f * (b.laser_min - a.laser_min),
                   laser_clearance=a.laser_clearance + f * (b.laser_clearance
                                                            - a.laser_clearance),
                   settle_travel=a.settle_travel + f * (b.settle_travel - a.settle_travel),
                   time=a.time + f * (b.time - a.time),
                   odom_error=a.odom_error + f * (b.odom_error - a.odom_error))


def crossings(before: list[np.ndarray], after: list[np.ndarray]) -> list[float]:
    """Sorted distinct fractions in [0, 1] where a comparison margin changes sign (a
    crossing that rounds to the sample itself still counts: the state before it must be
    visited)."""
    found: set[float] = set()
    for m0, m1 in zip(before, after, strict=False):
        if np.ndim(m0) == 0 and np.ndim(m1) == 0:
            # one number each (most margins): Python floats, the same IEEE arithmetic
            a, b = float(m0), float(m1)
            if math.copysign(1.0, a) != math.copysign(1.0, b) and a != b:
                f = a / (a - b)
                if math.isfinite(f) and 0 <= f <= 1:
                    found.add(f)
            continue
        m0 = np.broadcast_to(m0, np.shape(m1)) if np.shape(m0) != np.shape(m1) else m0
        if np.shape(m0) != np.shape(m1):
            continue
        flipped = np.signbit(m0) != np.signbit(m1)
        if not np.any(flipped):
            continue
        a_ = np.asarray(m0)[flipped]
        b_ = np.asarray(m1)[flipped]
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            f_ = a_ / (a_ - b_)
        found.update(float(v) for v in f_[np.isfinite(f_) & (f_ >= 0) & (f_ <= 1)])
    return sorted(found)
