"""A run's fault stage: several faults composed, implementing ``FaultStage``.

Each channel (scans, odometry, commands) passes through its faults in declaration order: the
output of one is the input of the next. Fault i draws from ``default_rng([seed,
FAULT_STREAM, i])``: its own stream, so neither the run's other streams nor the other faults'
draws shift when a fault is added. This module must never import pybullet.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np

from rei.lang.mission.faults import FaultDefinition
from rei.runtime.errors import RunError
from rei.runtime.messages import LaserScan
from rei.runtime.simulation.faults.activation import ActivationTracker
from rei.runtime.simulation.faults.models import COMMAND_MODELS, ODOMETRY_MODELS, SCAN_MODELS
from rei.runtime.simulation.faults.stage import NO_FAULTS, Command, FaultStage, Pose, Twist

FAULT_STREAM = 17
"""Second word of every fault generator's seed (issue 17): ``default_rng([seed, 17, i])``."""


@dataclass(frozen=True)
class FaultStatistics:
    """What a fault did in a run, for the summary and for tests: ``counts`` by name (the
    Poisson fault's ``occurrences`` and ``corrupted`` scans, a dropout's ``dropped`` and
    ``beams``, a command drop's ``lost`` and ``asked``, a jump's ``jumps``)."""

    name: str
    kind: str
    counts: tuple[tuple[str, int], ...]


class FaultPlan:
    """Several faults behind the ``FaultStage`` protocol (per run; mutable)."""

    def __init__(self, definitions: Iterable[FaultDefinition], seed: int) -> None:
        self.definitions = tuple(definitions)
        for d in self.definitions:
            if not isinstance(d, FaultDefinition):
                raise RunError(f"fault stage: expected fault definitions, found "
                               f"{type(d).__name__}")
        names = [d.name for d in self.definitions]
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise RunError(f"fault stage: expected unique fault names, found "
                           f"{', '.join(repeated)} more than once (name them with 'as NAME')")
        word = int(seed) & 0xFFFFFFFFFFFFFFFF
        self.trackers = [ActivationTracker(d.activation) for d in self.definitions]
        self.models: list[Any] = []
        for i, (d, when) in enumerate(zip(self.definitions, self.trackers, strict=True)):
            rng = np.random.default_rng([word, FAULT_STREAM, i])
            factory = {**SCAN_MODELS, **ODOMETRY_MODELS, **COMMAND_MODELS}[d.kind]
            self.models.append(factory(d, when, rng))
        self._scan = [m for d, m in zip(self.definitions, self.models, strict=True)
                      if d.kind in SCAN_MODELS]
        self._odometry = [m for d, m in zip(self.definitions, self.models, strict=True)
                          if d.kind in ODOMETRY_MODELS]
        self._command = [m for d, m in zip(self.definitions, self.models, strict=True)
                         if d.kind in COMMAND_MODELS]
        self.now = 0.0
        self._memo: list[tuple[LaserScan | None, float | None, LaserScan | None,
                               float | None]] = [(None, None, None, None)] * len(self._scan)
        """Per scan model: its last input (scan, stamp) and what it returned for it."""

    def _tick(self, time: float) -> None:
        self.now = max(self.now, time)

    def scan(self, time: float, measured: LaserScan | None,
             measured_at: float | None) -> tuple[LaserScan | None, float | None]:
        self._tick(time)
        if measured is None or not self._scan:
            return measured, measured_at
        scan: LaserScan | None = measured
        stamp: float | None = measured_at if measured_at is not None else time
        for i, model in enumerate(self._scan):
            if scan is None or stamp is None:
                return None, None
            seen, seen_at, out, out_at = self._memo[i]
            if model.time_driven or seen is not scan or seen_at != stamp:
                out, out_at = model.apply(time, scan, stamp)
                self._memo[i] = (scan, stamp, out, out_at)
            scan, stamp = out, out_at
        return (scan, stamp) if scan is not None else (None, None)

    def odometry(self, time: float, pose: Pose, twist: Twist) -> tuple[Pose, Twist]:
        self._tick(time)
        for model in self._odometry:
            pose, twist = model.apply(time, pose, twist)
        return pose, twist

    def command(self, time: float, command: Command) -> Command:
        self._tick(time)
        for model in self._command:
            command = model.apply(time, command)
        return command

    def signal(self, time: float, name: str) -> None:
        self._tick(time)
        for tracker in self.trackers:
            tracker.signal(time, name)

    def timeline(self) -> tuple[tuple[str, float, float | None], ...]:
        rows: list[tuple[str, float, float | None, int]] = []
        for i, (d, tracker, model) in enumerate(zip(self.definitions, self.trackers,
                                                    self.models, strict=True)):
            pulses = getattr(model, "pulses", None)
            for start, end in tracker.timeline(self.now):
                # an impulse-switched fault lies only while its impulse is high
                spans = pulses(start, end, self.now) if pulses is not None else [(start, end)]
                rows.extend((d.name, a, b, i) for a, b in spans)
        rows.sort(key=lambda r: (r[1], r[3]))
        return tuple((name, start, end) for name, start, end, _ in rows)

    def active_now(self, time: float) -> tuple[str, ...]:
        """The faults acting at ``time``, in declaration order (an impulse-switched one only
        while its impulse is high): ``active_at(self.timeline(), ...)`` without building the
        whole timeline every control tick."""
        out = []
        for d, tracker, model in zip(self.definitions, self.trackers, self.models, strict=True):
            if not tracker.active(time):
                continue
            high = getattr(model, "pulse_high", None)
            if high is None or high(time):
                out.append(d.name)
        return tuple(out)

    def described(self) -> tuple[tuple[str, str], ...]:
        return tuple((d.name, d.text()) for d in self.definitions)

    def statistics(self) -> tuple[FaultStatistics, ...]:
        """What every fault did so far, in declaration order."""
        out = []
        for d, m in zip(self.definitions, self.models, strict=True):
            counts: list[tuple[str, int]] = []
            for attribute in ("occurrences", "corrupted", "dropped", "beams", "lost", "asked",
                              "jumps"):
                value = getattr(m, attribute, None)
                if isinstance(value, int):  # a counter (LaserSector.covers is a method)
                    counts.append((attribute, int(value)))
            out.append(FaultStatistics(d.name, d.kind, tuple(counts)))
        return tuple(out)


def fault_stage(definitions: Iterable[FaultDefinition], seed: int) -> FaultStage:
    """The stage a run with these faults and this seed uses (``NO_FAULTS`` without any)."""
    definitions = tuple(definitions)
    if not definitions:
        return NO_FAULTS
    return FaultPlan(definitions, seed)
