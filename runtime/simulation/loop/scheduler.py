"""The scheduler: one simulated clock stepping the run's components at their declared rates.

Simulated time advances in fixed physics steps (``physics_rate`` per simulated second). A
component declares one or more *stages*: a function of the clock, the rate it runs at (every
n-th physics step; a rate must divide the physics rate) and whether it also runs in the tick
the run ends in. Each tick runs the due stages in the order they were declared, never
otherwise, so a run is a pure function of its inputs and seed. A stage may end the run
(``Clock.stop``): then every stage declared ``at_end`` that has not run in that tick runs
(in declared order, whatever its rate), the others are skipped, and the loop returns. In the
last tick the run may reach (``Clock.final``) the stages of rate None run as well: one of
them ends the run there.

The scheduler accounts each component's processor time (``time.process_time_ns`` read
where the running component changes, kept per component name): what a run costs, component
by component, never written into any output.
"""

from __future__ import annotations

import math
import time as cputime
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from rei.runtime.errors import RunError


def every(physics_rate: float, rate: float, what: str) -> int:
    """Physics steps between two runs of something at ``rate`` Hz (which must divide the
    physics rate)."""
    ratio = physics_rate / rate
    n = round(ratio)
    if n < 1 or abs(ratio - n) > 1e-9 * ratio:
        raise RunError(f"{what} of {rate:g} Hz expected to divide the physics rate of "
                       f"{physics_rate:g} Hz, found a ratio of {ratio:g}")
    return n


class Clock:
    """Simulated time, as the scheduler advances it: tick ``k`` is ``k / physics_rate`` s."""

    __slots__ = ("k", "last", "now", "rate", "reason", "stopped")

    def __init__(self, physics_rate: float, last: int) -> None:
        self.rate = physics_rate
        self.last = last
        """The last tick the run may reach (its time or duration limit)."""
        self.k = 0
        self.now = 0.0
        self.stopped = False
        self.reason = ""

    @property
    def final(self) -> bool:
        """This tick is the last one the run may reach."""
        return self.k == self.last

    def stop(self, reason: str) -> None:
        """End the run in this tick: only the ``at_end`` stages still run."""
        if not self.stopped:
            self.stopped = True
            self.reason = reason


@dataclass(frozen=True)
class Stage:
    """One declared piece of a component's work."""

    component: str
    """The component's name: its processor time is accounted under it."""
    run: Callable[[Clock], None]
    every: int | None
    """Physics steps between runs (1: every step); None: only in the tick the run ends."""
    at_end: bool = False
    """Also runs (whatever its rate) in the tick the run ends in."""


class Scheduler:
    """Steps the stages of one run; not reusable across runs."""

    def __init__(self, stages: Sequence[Stage], clock: Clock) -> None:
        self.stages = tuple(stages)
        self.clock = clock
        self.components = tuple(dict.fromkeys(s.component for s in self.stages))
        self._owner = tuple(self.components.index(s.component) for s in self.stages)
        self._ns = [0] * len(self.components)
        """Processor nanoseconds per component."""
        # The stages due at each phase of the rates' common period, precomputed (positions
        # in declared order): the loop only indexes, it allocates nothing per step.
        self._period = 1
        for stage in self.stages:
            if stage.every is not None:
                self._period = math.lcm(self._period, stage.every)
        self._due: list[tuple[int, ...]] | None = None
        if self._period <= 100_000:  # else rates without a small common period: no table
            self._due = [_due_at(self.stages, k) for k in range(self._period)]
        self._at_end = tuple(i for i, s in enumerate(self.stages) if s.at_end)
        self._running = 0
        """The component charged for the processor time since ``_since``."""
        self._since = 0

    def run(self) -> None:
        """Tick until a stage stops the run or the last tick ran."""
        clock = self.clock
        last, rate, period, due = clock.last, clock.rate, self._period, self._due
        self._since = cputime.process_time_ns()
        self._running = self._owner[0] if self.stages else 0
        try:
            for k in range(last):
                clock.k = k
                clock.now = k / rate
                if self._tick(due[k % period] if due is not None else _due_at(self.stages, k)):
                    return
            clock.k = last
            clock.now = last / rate
            ends = {i for i, s in enumerate(self.stages) if s.every is None or s.at_end}
            if not self._tick(tuple(sorted(set(_due_at(self.stages, last)) | ends))):
                clock.stop("final tick")
        finally:
            self._charge(self._running)

    def _tick(self, positions: tuple[int, ...]) -> bool:
        """Run one tick's stages; True when one of them stopped the run. The processor clock
        (a system call) is read only where the running component changes: a run of
        world-only ticks costs one reading, not one per step."""
        stages, owner, clock = self.stages, self._owner, self.clock
        for n, i in enumerate(positions):
            if owner[i] != self._running:
                self._charge(owner[i])
            stages[i].run(clock)
            if clock.stopped:
                self._end(positions[:n + 1])
                return True
        return False

    def _charge(self, then: int) -> None:
        """The time since the last reading to the running component; ``then`` runs next."""
        now = cputime.process_time_ns()
        self._ns[self._running] += now - self._since
        self._since, self._running = now, then

    def end(self) -> None:
        """End the run in the current tick from outside (a controller fault, an
        interruption): every ``at_end`` stage runs, in order."""
        self.clock.stop("ended from outside")
        self._since = cputime.process_time_ns()
        try:
            self._end(())
        finally:
            self._charge(self._running)

    def _end(self, ran: tuple[int, ...]) -> None:
        for i in self._at_end:
            if i not in ran:
                if self._owner[i] != self._running:
                    self._charge(self._owner[i])
                self.stages[i].run(self.clock)

    def cpu_seconds(self) -> dict[str, float]:
        """Processor seconds per component, in declaration order."""
        return {name: spent / 1e9 for name, spent in zip(self.components, self._ns, strict=True)}


def _due_at(stages: Sequence[Stage], k: int) -> tuple[int, ...]:
    """Positions of the stages due at tick ``k`` by their rates, in declared order."""
    return tuple(i for i, s in enumerate(stages) if s.every is not None and k % s.every == 0)
