"""Navigators with one known defect each, for the bug-finding benchmark (bench/bugs.py).

Every class is the reference navigator (runtime/robot/navigator/reference.py) with one realistic
defect
of a kind real navigation stacks ship with, a few lines on top of it. Its docstring says the
defect, the real-world bug it imitates and which requirement should catch it. Run one with
``rei run MISSION --controller bench.defects.MODULE:Class`` from the repository root (REI adds
the current folder to the import path for ``module:Class`` controllers).

Modules follow the part of the stack the defect is in: ``perception``, ``planning``,
``control``, ``localisation``, ``mission`` and ``timing``. This package must never import
pybullet, and a defect must never be more than the one defect its docstring names.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Defect:
    """One defective navigator of the benchmark."""

    name: str
    kind: str
    """The part of the stack the defect is in (the module's name)."""
    spec: str
    """``module:Class`` as ``--controller`` takes it."""


def _defect(kind: str, cls: str, name: str) -> Defect:
    return Defect(name, kind, f"bench.defects.{kind}:{cls}")


DEFECTS: tuple[Defect, ...] = (
    _defect("perception", "IgnoresHumans", "ignores-humans"),
    _defect("perception", "BlindSector", "blind-sector"),
    _defect("timing", "StaleScans", "stale-scans"),
    _defect("timing", "ControlLatency", "control-latency"),
    _defect("timing", "CommandDropout", "command-dropout"),
    _defect("timing", "DelayedScans", "delayed-scans"),
    _defect("control", "ExceedsDriveLimit", "exceeds-drive-limit"),
    _defect("control", "IgnoresMissionSpeed", "ignores-mission-speed"),
    _defect("control", "NoSlowZone", "no-slow-zone"),
    _defect("control", "OscillatingHeading", "oscillating-heading"),
    _defect("control", "InvertedApproachScaling", "inverted-approach-scaling"),
    _defect("control", "SpinsWhenTurning", "spins-when-turning"),
    _defect("planning", "FootprintTooSmall", "footprint-too-small"),
    _defect("planning", "NeverClearsObstacles", "never-clears-obstacles"),
    _defect("localisation", "OdometryOffset", "odometry-offset"),
    _defect("mission", "IgnoresGoalHeading", "ignores-goal-heading"),
    _defect("mission", "AbortsEveryGoal", "aborts-every-goal"),
    _defect("mission", "ClaimsSuccessEarly", "claims-success-early"),
    _defect("mission", "NeverReportsSuccess", "never-reports-success"),
    _defect("mission", "SkipsSecondGoal", "skips-second-goal"),
)
"""Every defect of the benchmark, in table order."""

__all__ = ["DEFECTS", "Defect"]
