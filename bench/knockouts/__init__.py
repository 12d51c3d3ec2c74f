"""Knock-out families: one defect a navigator can have, at graded severities, around any
navigator, for the detection thresholds of the bug-finding benchmark (bench/bugs.py
``--families``).

Every knock-out is a wrapper written only against the public controller protocol
(rei.runtime.robot.contract): it changes what the navigator is told, what it sees, or what
reaches the base, and never reaches into the navigator, so no refactoring of the reference can
make one equivalent to it (bench/defects' hand-written defects are subclasses of the reference
and can). A family grades its defect from mild to severe; the mildest severity a test suite
catches on every seed is its detection threshold for that family.

Run one with ``rei run MISSION --controller bench.knockouts:NAME`` from the repository root,
``NAME`` a family and a severity in the family's unit (``footprint_50``, ``delay_300``; any
severity in the family's range works, ``KNOCKOUTS`` lists the benchmark's). The wrapped
navigator is ``reference`` unless ``REI_KNOCKOUT_BASE`` names another as ``--controller``
takes it (``REI_KNOCKOUT_BASE=mystack:Navigator``), so a user measures their suite against
their own navigator. This package must never import pybullet or the simulation.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

from bench.knockouts.commands import Delay, Dropped, Held
from bench.knockouts.recovery import AbortsRecovery
from bench.knockouts.sensing import BlindSector, LaserNoise
from bench.knockouts.told import Footprint, GoalTolerance, SpeedLimit
from bench.knockouts.wrapper import BASE_VARIABLE, Wrapper, base_controller, base_spec
from rei.runtime.robot.contract import Controller


@dataclass(frozen=True)
class Family:
    """One defect, graded."""

    name: str
    wrapper: Callable[[str, Controller, int], Wrapper]
    """Makes the knock-out: (its name, the navigator it wraps, the severity)."""
    severities: tuple[int, ...]
    """The benchmark's severities, from mild to severe."""
    unit: str
    """How a severity reads, ``{}`` standing for it."""
    limits: tuple[int, int]
    """The severities a name may ask for, both ends included."""
    shown: float = 1.0
    """What the unit shows of a severity (tolerance: 150 shows as 1.5)."""

    def label(self, severity: int) -> str:
        return self.unit.format(f"{severity * self.shown:g}")


FAMILIES: tuple[Family, ...] = (
    Family("footprint", Footprint, (90, 70, 50, 30), "told {} % of its size", (1, 100)),
    Family("delay", Delay, (100, 200, 300, 500), "commands {} ms late", (1, 60_000)),
    Family("recovery", AbortsRecovery, (4, 3, 2, 1), "aborts at recovery round {}", (1, 100)),
    Family("noise", LaserNoise, (20, 50, 100, 200), "laser noise σ {} mm", (1, 10_000)),
    Family("blind", BlindSector, (15, 30, 60, 90), "{}° ahead blind", (1, 360)),
    Family("held", Held, (10, 25, 50, 75), "{} % of commands held", (1, 100)),
    Family("dropped", Dropped, (10, 25, 50, 75), "{} % of commands dropped", (1, 100)),
    Family("tolerance", GoalTolerance, (150, 200, 300, 400), "goal tolerance × {}",
           (1, 10_000), 0.01),
    Family("overspeed", SpeedLimit, (5, 10, 25, 50), "speed limit told {} % higher",
           (1, 1_000)),
)
"""Every family of the benchmark, in table order."""


@dataclass(frozen=True)
class Knockout:
    """One family at one severity."""

    name: str
    family: str
    severity: int
    label: str
    spec: str
    """``module:attr`` as ``--controller`` takes it."""


def _knockout(family: Family, severity: int) -> Knockout:
    name = f"{family.name}_{severity}"
    return Knockout(name, family.name, severity, family.label(severity),
                    f"bench.knockouts:{name}")


KNOCKOUTS: tuple[Knockout, ...] = tuple(_knockout(f, s) for f in FAMILIES for s in f.severities)
"""The benchmark's knock-outs: every family at each of its severities, mild to severe."""

_NAME = re.compile(r"([a-z]+)_([0-9]+)")
_BY_NAME = {f.name: f for f in FAMILIES}


class UnknownKnockout(ValueError):
    """A name that is no family at a severity in its range; ``str()`` says what was expected."""


def parse(name: str) -> tuple[Family, int]:
    """The family and severity ``name`` asks for (``footprint_50``)."""
    match = _NAME.fullmatch(name)
    family = _BY_NAME.get(match.group(1)) if match else None
    if match is None or family is None:
        raise UnknownKnockout(f"knock-out '{name}': expected FAMILY_SEVERITY with FAMILY among "
                              f"{', '.join(_BY_NAME)} (e.g. {KNOCKOUTS[0].name})")
    severity = int(match.group(2))
    low, high = family.limits
    if not low <= severity <= high:
        raise UnknownKnockout(f"knock-out '{name}': a {family.name} severity is {low} to "
                              f"{high}, found {severity}")
    return family, severity


def make(name: str, inner: Controller | None = None) -> Wrapper:
    """The knock-out ``name`` around ``inner`` (default: a fresh ``REI_KNOCKOUT_BASE``)."""
    family, severity = parse(name)
    return family.wrapper(name, base_controller() if inner is None else inner, severity)


def __getattr__(name: str) -> Callable[[], Wrapper]:
    """``bench.knockouts:footprint_50`` as ``--controller`` loads it: a factory of the
    knock-out around the base navigator."""
    try:
        parse(name)
    except UnknownKnockout as problem:
        raise AttributeError(str(problem)) from None

    def factory() -> Wrapper:
        return make(name)

    factory.__name__ = name
    return factory


__all__ = ["BASE_VARIABLE", "FAMILIES", "KNOCKOUTS", "Family", "Knockout", "UnknownKnockout",
           "Wrapper", "base_spec", "make", "parse"]
