"""Complex event matching: VEPL-style patterns as automata over simulation time, as RxPY
operators (thesis 6.1.3.3, appendix 9.2.2).

A partial match is a set of residual patterns (the states of an automaton built by
Brzozowski derivatives), the time it started and the events it consumed. Event contexts
keep VIATRA-CEP's meaning:

* chronicle: every partial match is kept until it completes or its window expires;
* immediate: a partial match the latest event (of those the pattern mentions) did not
  advance is dropped; events used by a match are consumed;
* strict immediate: additionally at most one partial match is alive, so matches never
  overlap.

A match fires once, as soon as the pattern is satisfied (the shortest match); a pattern
ending in NOT completes when its window closes, on a timer of the virtual-time scheduler
that the host advances with the simulation clock. This module must never read the wall
clock or import the simulator.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from functools import reduce
from typing import Any

import reactivex as rx
from reactivex import Observable, abc
from reactivex.scheduler import VirtualTimeScheduler

from rei.lang.vepl import model as vm

MAX_PARTIALS = 10_000
"""Chronicle context without windows can grow without bound; the oldest are dropped."""


@dataclass(frozen=True)
class Occurrence:
    """An event instance: a query match found/lost, a complex event match, or a signal."""

    name: str
    time: float
    objects: tuple[str, ...] = ()
    serial: int = 0
    """Position in the run's stream of atomic events (consumption bookkeeping)."""


# ---- residual patterns ---------------------------------------------------------------------

@dataclass(frozen=True)
class Eps:
    pass


@dataclass(frozen=True)
class Atom:
    name: str


@dataclass(frozen=True)
class Seq:
    first: Node
    rest: Node


@dataclass(frozen=True)
class Alt:
    options: frozenset[Node]


@dataclass(frozen=True)
class Both:
    left: Node
    right: Node


@dataclass(frozen=True)
class Absent:
    names: frozenset[str]


@dataclass(frozen=True)
class Star:
    body: Node


@dataclass(frozen=True)
class Window:
    body: Node
    seconds: float


@dataclass(frozen=True)
class Timed:
    body: Node
    deadline: float


Node = Eps | Atom | Seq | Alt | Both | Absent | Star | Window | Timed
EPS = Eps()


def compile_pattern(p: vm.Pattern) -> Node:
    """The automaton's start state for a checked pattern."""
    if isinstance(p, vm.EvRef):
        return Atom(p.name)
    if isinstance(p, vm.EvSeq):
        return reduce(lambda acc, x: _seq(x, acc), reversed([compile_pattern(x) for x in
                                                             p.parts[:-1]]),
                      compile_pattern(p.parts[-1]))
    if isinstance(p, vm.EvOr):
        return Alt(frozenset(compile_pattern(x) for x in p.options))
    if isinstance(p, vm.EvAnd):
        parts = [compile_pattern(x) for x in p.parts]
        return reduce(lambda a, b: Both(a, b), parts[1:], parts[0])
    if isinstance(p, vm.EvNot):
        return Absent(frozenset(mentioned(p.operand)))
    if isinstance(p, vm.EvRepeat):
        body = compile_pattern(p.operand)
        if p.exact:
            return reduce(lambda acc, _: _seq(body, acc), range(p.low - 1), body)
        tail: Node = Star(body)
        return reduce(lambda acc, _: _seq(body, acc), range(p.low), tail)
    if isinstance(p, vm.EvWindow):
        return Window(compile_pattern(p.operand), p.seconds)
    raise TypeError(p)


def mentioned(p: vm.Pattern) -> set[str]:
    """Every event name a pattern reads (the events its context counts as 'latest')."""
    if isinstance(p, vm.EvRef):
        return {p.name}
    if isinstance(p, vm.EvSeq | vm.EvAnd):
        return set().union(*(mentioned(x) for x in p.parts))
    if isinstance(p, vm.EvOr):
        return set().union(*(mentioned(x) for x in p.options))
    return mentioned(p.operand)


def _seq(a: Node, b: Node) -> Node:
    if isinstance(a, Eps):
        return b
    if isinstance(b, Eps):
        return a
    return Seq(a, b)


def _both(a: Node, b: Node) -> Node:
    if isinstance(a, Eps):
        return b
    if isinstance(b, Eps):
        return a
    return Both(a, b)


def _timed(a: Node, deadline: float) -> Node:
    return a if isinstance(a, Eps) else Timed(a, deadline)


def nullable(n: Node, absence_ok: bool) -> bool:
    """Satisfied now (absence_ok=False), or satisfied once pending NOTs time out (True)."""
    if isinstance(n, Eps | Star):
        return True
    if isinstance(n, Atom):
        return False
    if isinstance(n, Absent):
        return absence_ok
    if isinstance(n, Seq):
        return nullable(n.first, absence_ok) and nullable(n.rest, absence_ok)
    if isinstance(n, Both):
        return nullable(n.left, absence_ok) and nullable(n.right, absence_ok)
    if isinstance(n, Alt):
        return any(nullable(o, absence_ok) for o in n.options)
    return nullable(n.body, absence_ok)


def derive(n: Node, name: str, t: float) -> frozenset[Node]:
    """The residuals of ``n`` after an event ``name`` at time ``t`` (empty: no way on)."""
    if isinstance(n, Atom):
        return frozenset((EPS,)) if n.name == name else frozenset()
    if isinstance(n, Eps):
        return frozenset()
    if isinstance(n, Absent):
        return frozenset() if name in n.names else frozenset((n,))
    if isinstance(n, Seq):
        out = {_seq(r, n.rest) for r in derive(n.first, name, t)}
        if nullable(n.first, True):
            out |= derive(n.rest, name, t)
        return frozenset(out)
    if isinstance(n, Alt):
        return frozenset().union(*(derive(o, name, t) for o in n.options))
    if isinstance(n, Both):
        return frozenset({_both(r, n.right) for r in derive(n.left, name, t)}
                         | {_both(n.left, r) for r in derive(n.right, name, t)})
    if isinstance(n, Star):
        return frozenset(_seq(r, n) for r in derive(n.body, name, t))
    if isinstance(n, Window):
        return frozenset(_timed(r, t + n.seconds) for r in derive(n.body, name, t))
    if isinstance(n, Timed):
        if t > n.deadline:
            return frozenset()
        return frozenset(_timed(r, n.deadline) for r in derive(n.body, name, t))
    raise TypeError(n)


def _absence_deadline(states: frozenset[Node]) -> float | None:
    """When a partial waiting only on NOTs completes (the earliest window end), if ever."""
    times = [s.deadline for s in states if isinstance(s, Timed) and nullable(s, True)]
    return min(times) if times else None


def _expired(states: frozenset[Node], t: float) -> bool:
    return all(isinstance(s, Timed) and s.deadline < t for s in states)


@dataclass
class _Partial:
    states: frozenset[Node]
    events: tuple[Occurrence, ...]
    timer: Any = None


@dataclass
class PatternEngine:
    """The per-run state of one complex event's automaton (the definition stays immutable)."""

    name: str
    start: Node
    context: vm.ContextKind
    partials: list[_Partial] = field(default_factory=list)
    dropped: int = 0

    def _match(self, p: _Partial, time: float) -> Occurrence:
        objects: dict[str, None] = {}
        for e in p.events:
            objects.update(dict.fromkeys(e.objects))
        return Occurrence(self.name, time, tuple(objects))

    def on_event(self, e: Occurrence) -> tuple[list[Occurrence], list[_Partial]]:
        """Matches completed by ``e``, and partials that now wait on an absence deadline."""
        t = e.time
        matches: list[Occurrence] = []
        waiting: list[_Partial] = []
        consumed: set[int] = set()
        consuming = self.context != "chronicle"
        kept: list[_Partial] = []
        for p in self.partials:
            if consuming and any(x.serial in consumed for x in p.events):
                continue
            nxt = frozenset().union(*(derive(s, e.name, t) for s in p.states))
            if nxt:
                moved = _Partial(nxt, p.events + (e,))
                if any(nullable(s, False) for s in nxt):
                    matches.append(self._match(moved, t))
                    if consuming:
                        consumed.update(x.serial for x in moved.events)
                    continue
                kept.append(moved)
                if _absence_deadline(nxt) is not None:
                    waiting.append(moved)
            elif self.context == "chronicle" and not _expired(p.states, t):
                kept.append(p)
        if consuming:
            kept = [p for p in kept if not any(x.serial in consumed for x in p.events)]
        may_start = e.serial not in consumed and (self.context != "strict" or not kept)
        if may_start:
            first = derive(self.start, e.name, t)
            if first:
                fresh = _Partial(first, (e,))
                if any(nullable(s, False) for s in first):
                    matches.append(self._match(fresh, t))
                else:
                    kept.append(fresh)
                    if _absence_deadline(first) is not None:
                        waiting.append(fresh)
        if len(kept) > MAX_PARTIALS:
            self.dropped += len(kept) - MAX_PARTIALS
            kept = kept[-MAX_PARTIALS:]
        for p in self.partials:
            if p.timer is not None and p not in kept:
                p.timer.dispose()
        self.partials = kept
        return matches, waiting

    def on_deadline(self, p: _Partial, time: float) -> Occurrence | None:
        if p not in self.partials:
            return None
        self.partials.remove(p)
        if self.context != "chronicle":
            serials = {x.serial for x in p.events}
            self.partials = [q for q in self.partials
                             if not any(x.serial in serials for x in q.events)]
        return self._match(p, time)


def match_pattern(name: str, pattern: vm.Pattern, context: vm.ContextKind,
                  scheduler: VirtualTimeScheduler
                  ) -> Callable[[Observable[Occurrence]], Observable[Occurrence]]:
    """An Rx operator: the occurrences of a complex event, from the events it mentions.

    Every time-based step goes through ``scheduler`` (virtual simulation time); nothing
    here may fall back to the wall clock.
    """
    start = compile_pattern(pattern)

    def operator(source: Observable[Occurrence]) -> Observable[Occurrence]:
        def subscribe(observer: abc.ObserverBase[Occurrence],
                      _: abc.SchedulerBase | None = None) -> abc.DisposableBase:
            engine = PatternEngine(name, start, context)

            def arm(p: _Partial) -> None:
                deadline = _absence_deadline(p.states)
                if deadline is None or p.timer is not None:
                    return

                def fire(_s: abc.SchedulerBase, _st: Any) -> None:
                    match = engine.on_deadline(p, deadline)
                    if match is not None:
                        observer.on_next(match)

                p.timer = scheduler.schedule_absolute(deadline, fire)

            def on_next(e: Occurrence) -> None:
                matches, waiting = engine.on_event(e)
                for m in matches:
                    observer.on_next(m)
                for p in waiting:
                    arm(p)

            return source.subscribe(on_next, observer.on_error, observer.on_completed)

        return rx.create(subscribe)

    return operator


def of_names(names: Iterable[str]) -> Callable[[Occurrence], bool]:
    wanted = frozenset(names)
    return lambda e: e.name in wanted
