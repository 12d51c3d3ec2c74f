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

The scheduler accounts each component's processor time (``time.process_time_ns`` between
stages, kept per component name): what a run costs, component by component, never written
into any output.
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
        self.cpu_ns: dict[str, int] = dict.fromkeys((s.component for s in stages), 0)
        n = len(self.stages)
        # The stages due at each phase of the rates' common period, precomputed (positions
        # in declared order): the loop only indexes, it allocates nothing per step.
        self._period = 1
        for stage in self.stages:
            if stage.every is not None:
                self._period = math.lcm(self._period, stage.every)
        self._due: list[tuple[int, ...]] | None = None
        if self._period <= 10_000:
            self._due = [self._due_positions(k) for k in range(self._period)]
        self._last = tuple(i for i in range(n) if self.stages[i].every is None
                           or self.stages[i].at_end)
        self._at_end = tuple(i for i in range(n) if self.stages[i].at_end)
        self._ran: set[int] = set()

    def _due_positions(self, k: int) -> tuple[int, ...]:
        return tuple(i for i, s in enumerate(self.stages)
                     if s.every is not None and k % s.every == 0)

    def _tick_positions(self, k: int) -> tuple[int, ...]:
        due = self._due[k % self._period] if self._due is not None else self._due_positions(k)
        if k != self.clock.last:
            return due
        return tuple(sorted(set(due) | set(self._last)))

    def run(self) -> None:
        """Tick until a stage stops the run or the last tick ran."""
        clock = self.clock
        stages = self.stages
        cpu = self.cpu_ns
        ns = cputime.process_time_ns
        rate = clock.rate
        for k in range(clock.last + 1):
            clock.k = k
            clock.now = k / rate
            before = ns()
            ran = self._ran
            for i in self._tick_positions(k):
                stage = stages[i]
                try:
                    stage.run(clock)
                finally:
                    after = ns()
                    cpu[stage.component] += after - before
                    before = after
                    ran.add(i)
                if clock.stopped:
                    self._end(ran)
                    return
            ran.clear()
        clock.stop("final tick")

    def end(self) -> None:
        """End the run in the current tick from outside (a controller fault, an
        interruption): every ``at_end`` stage runs, in order."""
        self.clock.stop("ended from outside")
        self._end(set())

    def _end(self, ran: set[int]) -> None:
        for i in self._at_end:
            if i not in ran:
                self._timed(self.stages[i])

    def _timed(self, stage: Stage) -> None:
        before = cputime.process_time_ns()
        try:
            stage.run(self.clock)
        finally:
            self.cpu_ns[stage.component] += cputime.process_time_ns() - before

    def cpu_seconds(self) -> dict[str, float]:
        """Processor seconds per component, in declaration order."""
        return {name: ns / 1e9 for name, ns in self.cpu_ns.items()}
