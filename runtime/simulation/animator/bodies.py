"""The animated bodies of a world: which bodies move along a spline, how (``Animated``: their
behaviour and seeded variation), the parameters of the reactive behaviours (``Reactions``),
and the fixed bodies the reactive humans keep clear of (``wall_boxes``).

Built once per run from the world's manifest, before the animator (engine.py) moves them.
This module must never import pybullet or the monitor, nor decide anything about the robot.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from rei.lang.room.model import DEFAULT_BEHAVIOUR, Behaviour
from rei.lang.room.spline import CatmullRom
from rei.runtime.artifacts.world import BodySpec, Trajectory
from rei.runtime.errors import RunError
from rei.runtime.simulation.animator.social_force import SocialForce
from rei.runtime.simulation.animator.variation import (
    NO_VARIATION,
    HumanVariation,
    draw_variations,
)
from rei.runtime.simulation.animator.yielding import YieldRule


@dataclass(frozen=True)
class Animated:
    body: int
    """The body's id in the world."""
    spline: CatmullRom
    face_motion: bool
    behaviour: Behaviour = DEFAULT_BEHAVIOUR
    variation: HumanVariation = NO_VARIATION
    radius: float = 0.25
    """m, the footprint's radius others keep away from."""
    start_when: tuple[float, float, float] | None = None
    """(x, y, within): the clock starts when the robot's centre first comes within
    ``within`` m of (x, y); None: with the run."""


@dataclass(frozen=True)
class Reactions:
    """The parameters of the reactive behaviours (one object, so two runs can differ)."""

    yielding: YieldRule = field(default_factory=YieldRule)
    social: SocialForce = field(default_factory=SocialForce)


def spline_of(trajectory: Trajectory, name: str = "body") -> CatmullRom:
    """The body's spline; RunError (naming it) for control points no spline passes through
    (the checker's TRAJ-SPEED keeps generated worlds clear of them; a world.json edited by
    hand may not be)."""
    pts = np.array(trajectory.points, dtype=float).reshape(-1, 3)
    times = pts[:, 0]
    if len(times) < 2 or not np.all(np.diff(times) > 0):
        raise RunError(f"world.json: the trajectory of '{name}': expected at least two control "
                       f"points at increasing times, found times "
                       f"{', '.join(f'{t:g}' for t in times[:6])}"
                       + (" ..." if len(times) > 6 else ""))
    return CatmullRom(times, pts[:, 1:3], trajectory.loop)


def _triggered(body: BodySpec) -> bool:
    return body.trajectory is not None and body.trajectory.start_when is not None


def animated_bodies(objects: tuple[BodySpec, ...], body_ids: list[int], seed: int,
                    vary: bool) -> list[tuple[str, Animated]]:
    """The world's bodies with a trajectory, by name, in declaration order; humans get
    their behaviour and (with ``vary``) their seeded variation."""
    named = [(b.name, body_ids[i], b) for i, b in enumerate(objects) if b.trajectory is not None]
    splines = [spline_of(b.trajectory, name) for name, _, b in named if b.trajectory is not None]
    humans = [k for k, (_, _, b) in enumerate(named) if b.role == "human"]
    drawn = draw_variations(seed, [splines[k] for k in humans]) if vary else ()
    # A triggered human keeps its speed scale but not its start delay: the trigger places
    # the encounter where the robot is, and a random delay would move it again.
    variation = {k: replace(v, phase_s=0.0) if _triggered(named[k][2]) else v
                 for k, v in zip(humans, drawn, strict=False)}
    return [(name, Animated(bid, splines[k], b.role == "human",
                            b.behaviour if b.role == "human" else DEFAULT_BEHAVIOUR,
                            variation.get(k, NO_VARIATION),
                            max(b.footprint.half_extents()),
                            b.trajectory.start_when if b.trajectory is not None else None))
            for k, (name, bid, b) in enumerate(named)]


def variations_record(named: list[tuple[str, Animated]]) -> dict[str, dict[str, object]]:
    """What a run's summary shows of its humans: behaviour and what was drawn."""
    return {name: {"behaviour": a.behaviour, "phase_s": a.variation.phase_s,
                   "speed_scale": a.variation.speed_scale}
            for name, a in named if a.face_motion}


def wall_boxes(bodies: tuple[BodySpec, ...]) -> np.ndarray:
    """(x, y, yaw, half x, half y) of each fixed body (a cylinder as its bounding square):
    what ``fits_past`` looks at."""
    rows = [(b.x, b.y, b.yaw, *b.footprint.half_extents()) for b in bodies]
    return np.array(rows, dtype=float).reshape(-1, 5)
