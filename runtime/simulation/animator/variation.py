"""Seeded per-run variations of the humans, so repeats of a mission are not copies.

Each human's start delay and walking-speed scale are drawn from the run's seed through a
generator of their own (``default_rng([seed, VARIATION_STREAM])``): the laser-noise stream,
seeded with the seed alone, draws exactly what it drew before. Same seed, same variations;
every draw happens for every human in declaration order, so adding a human never changes
what an earlier one drew. This module must never touch the simulator.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rei.lang.room.model import WALKING_SPEEDS
from rei.lang.room.spline import CatmullRom

VARIATION_STREAM = 1
"""Second word of the variations' seed sequence (the run's own stream is the seed alone)."""
MAX_PHASE_INTERVALS = 1.0
"""The start delay is drawn from [0, this many mean vertex intervals of the trajectory)."""
SPEED_SPREAD = 0.15
"""The speed scale is drawn from [1 - spread, 1 + spread]."""


@dataclass(frozen=True)
class HumanVariation:
    """How one run's human differs from the room as written.

    Its path time is ``speed_scale * (t - phase_s)`` (never negative): the human stands on
    its first vertex for ``phase_s`` seconds, then walks its spline ``speed_scale`` times as
    fast. A delay rather than a jump ahead along the spline, because the human then starts
    where the room puts it, which the checker and the generator have kept clear of the robot.
    """

    phase_s: float = 0.0
    speed_scale: float = 1.0


NO_VARIATION = HumanVariation()


def clamp_scale(scale: float, mean_speed: float) -> float:
    """``scale`` limited so ``scale * mean_speed`` stays in WALKING_SPEEDS (or, for a
    trajectory written outside it, no farther out than written)."""
    if mean_speed <= 0.0:
        return scale
    low = min(WALKING_SPEEDS[0], mean_speed) / mean_speed
    high = max(WALKING_SPEEDS[1], mean_speed) / mean_speed
    return min(max(scale, low), high)


def mean_speed(spline: CatmullRom) -> float:
    """Control-polygon length over duration: the speed a trajectory was written for."""
    length = float(np.hypot(*np.diff(spline.p, axis=0).T).sum())
    return length / spline.duration if spline.duration > 0 else 0.0


def draw_variations(seed: int, splines: Sequence[CatmullRom]) -> tuple[HumanVariation, ...]:
    """One variation per spline (in order), a pure function of ``seed``."""
    rng = np.random.default_rng([seed, VARIATION_STREAM])
    out = []
    for spline in splines:
        phase_u, scale_u = rng.random(2)
        interval = spline.duration / (len(spline.t) - 1)
        phase = float(phase_u) * MAX_PHASE_INTERVALS * interval
        scale = 1.0 + SPEED_SPREAD * (2.0 * float(scale_u) - 1.0)
        out.append(HumanVariation(phase, clamp_scale(scale, mean_speed(spline))))
    return tuple(out)
