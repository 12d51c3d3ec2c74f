"""What a reactive human reacts to: another body (``Agent``: where it is, its footprint's
radius, its velocity) and the plane's vectors (``Vec``) the reactive models compute with.

Plain frozen records, shared by the yielding rule (yielding.py), the social force model
(social_force.py) and the wall geometry (walls.py). This module must never import pybullet
or the monitor.
"""

from __future__ import annotations

from dataclasses import dataclass

Vec = tuple[float, float]


@dataclass(frozen=True)
class Agent:
    """Another body a human reacts to: where it is, its footprint's radius, its velocity."""

    x: float
    y: float
    radius: float
    vx: float = 0.0
    vy: float = 0.0
