"""Requirement verdicts over signals, events and queries: pass, fail or inconclusive.

Clause meanings (docs/vepl.md): ``never E`` fails at the first E; ``eventually E`` passes
at the first E; ``count E OP N`` compares the number of E; ``whenever T expect A | B
within MS`` needs, after every T, one of the events A, B within MS (or by the end), or one
of the queries A, B holding within MS before or after T. A verdict that rests on something
*not* happening (a pass of never, a fail of eventually, ...) is inconclusive when samples
were bad or missing in the time it covers, or when the run did not finish: missing
evidence never turns into a pass. A verdict is data, never an exception.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

from rei.lang.vepl import model as vm
from rei.runtime.observation.automata.records import RequirementSpec
from rei.runtime.observation.model.sample_checks import SampleProblems
from rei.runtime.results import Verdict, VerdictStatus

_CMP: dict[str, Callable[[float, float], bool]] = {
    "<": lambda a, b: a < b, "<=": lambda a, b: a <= b, ">": lambda a, b: a > b,
    ">=": lambda a, b: a >= b, "==": lambda a, b: a == b, "!=": lambda a, b: a != b}


@dataclass
class _ClauseState:
    clause: vm.Clause
    status: VerdictStatus | None = None
    decided_at: float | None = None
    reason: str = ""
    absence: bool = False
    """Decided by something not happening (so bad samples make it inconclusive)."""
    span: tuple[float, float] = (0.0, math.inf)
    objects: tuple[str, ...] = ()
    count: int = 0
    pending: list[float] = field(default_factory=list)
    last_target: float = -math.inf

    def decide(self, status: VerdictStatus, at: float, reason: str, absence: bool = False,
               span: tuple[float, float] | None = None,
               objects: tuple[str, ...] = ()) -> None:
        if self.status is None:
            self.status, self.decided_at, self.reason, self.absence = status, at, reason, absence
            self.objects = objects
            if span is not None:
                self.span = span


class RequirementChecker:
    """Watches one run; ``verdicts()`` at the end."""

    def __init__(self, requirements: tuple[RequirementSpec, ...], queries: set[str],
                 describe: Callable[[tuple[str, ...]], str] | None = None) -> None:
        self.requirements = requirements
        self.queries = queries
        self.describe = describe or (lambda objects: ", ".join(objects))
        """Words for the objects of a deciding event (a failed task: the executor's reason)."""
        self.states = {r.name: [_ClauseState(c) for c in r.clauses] for r in requirements}
        self._whenever = [st for states in self.states.values() for st in states
                          if isinstance(st.clause, vm.Whenever)]
        """The ``whenever`` clauses, in order: the only ones a step concerns."""
        self._answered_by_queries = [
            st for st in self._whenever
            if isinstance(st.clause, vm.Whenever) and any(t in queries
                                                          for t in st.clause.targets)]
        """Those a query holding can answer (a step can answer no other: their expiry is
        decided at the window's end whenever it is checked)."""
        self.query_held: dict[str, float] = {}
        """The last time each watched query was seen holding (now, while it holds)."""
        self.holding: set[str] = set()

    def watched_events(self) -> set[str]:
        names: set[str] = set()
        for r in self.requirements:
            for c in r.clauses:
                if isinstance(c, vm.Whenever):
                    names.add(c.trigger)
                    names.update(t for t in c.targets if t not in self.queries)
                else:
                    names.add(c.event)
        return names

    def watched_queries(self) -> set[str]:
        premises = {r.premise for r in self.requirements if r.premise is not None}
        return premises | {t for r in self.requirements for c in r.clauses
                           if isinstance(c, vm.Whenever) for t in c.targets if t in self.queries}

    def _expire(self, st: _ClauseState, now: float) -> None:
        c = st.clause
        assert isinstance(c, vm.Whenever)
        if c.window is None or st.status is not None:
            return
        for t in st.pending:
            if now > t + c.window:
                st.pending = []  # decided: later triggers cannot change a failed clause
                st.decide("fail", t + c.window, f"{c.trigger} at t={t:g} s was not followed "
                          f"by {' or '.join(c.targets)} within {c.window * 1000:g} ms",
                          absence=True, span=(t, t + c.window))
                return

    def on_event(self, name: str, time: float, objects: tuple[str, ...] = ()) -> None:
        involved = f" ({self.describe(objects)})" if objects else ""
        for states in self.states.values():
            for st in states:
                c = st.clause
                if isinstance(c, vm.Never) and c.event == name:
                    st.decide("fail", time, f"{name} occurred at t={time:g} s{involved}",
                              objects=objects)
                elif isinstance(c, vm.Eventually) and c.event == name:
                    st.decide("pass", time, f"{name} occurred at t={time:g} s", objects=objects)
                elif isinstance(c, vm.CountBound) and c.event == name:
                    st.count += 1
                    if c.op in ("<", "<=") and not _CMP[c.op](st.count, c.bound):
                        st.decide("fail", time, f"{name} occurred {st.count} times by "
                                                f"t={time:g} s{involved}; expected {c.op} "
                                                f"{c.bound:g}", objects=objects)
                    elif c.op in (">", ">=") and _CMP[c.op](st.count, c.bound):
                        st.decide("pass", time, f"{name} occurred {st.count} times by "
                                                f"t={time:g} s")
                elif isinstance(c, vm.Whenever):
                    self._expire(st, time)
                    if name in c.targets:
                        st.last_target = time
                        st.pending = [t for t in st.pending
                                      if c.window is not None and time > t + c.window]
                    if name == c.trigger:
                        window = c.window if c.window is not None else 0.0
                        held = max((time if q in self.holding else
                                    self.query_held.get(q, -math.inf) for q in c.targets
                                    if q in self.queries), default=-math.inf)
                        if held < time - window and st.last_target < time:
                            st.pending.append(time)

    def waiting(self) -> bool:
        """True while a ``whenever`` trigger waits for an answer a query can give (a
        trigger waiting for events is answered, or expires, in ``on_event``, or at the
        end: a step changes nothing for it)."""
        return any(st.pending and st.status is None for st in self._answered_by_queries)

    def on_step(self, time: float, holding: dict[str, bool]) -> None:
        """After an evaluation step where a watched query changed (or while a trigger
        waits): which watched queries hold now."""
        for q, held in holding.items():
            if held or q in self.holding:
                self.query_held[q] = time  # held until now
            if held:
                self.holding.add(q)
            else:
                self.holding.discard(q)
        for st in self._whenever:
            if not st.pending:  # nothing to expire or answer
                continue
            c = st.clause
            assert isinstance(c, vm.Whenever)
            self._expire(st, time)
            if st.pending and any(holding.get(q) for q in c.targets):
                window = c.window if c.window is not None else math.inf
                st.pending = [t for t in st.pending if time > t + window]

    def verdicts(self, end_time: float, problems: SampleProblems, finished: bool,
                 why_unfinished: str = "") -> tuple[Verdict, ...]:
        out: list[Verdict] = []
        for req in self.requirements:
            # a query that ever held is in query_held (on_step records it the first time)
            if req.premise is not None and req.premise not in self.query_held:
                if problems.total:
                    out.append(Verdict(req.name, "inconclusive", None,
                                       f"its premise {req.premise} never held, but "
                                       f"{problems.total} sample(s) were bad or missing"))
                else:
                    out.append(Verdict(req.name, "not_applicable", None,
                                       f"not applicable: its premise {req.premise} never held "
                                       f"in this run"))
                continue
            for st in self.states[req.name]:
                self._finish(st, end_time)
                if st.absence and (problems.within(*st.span) or problems.counts["missing"]):
                    st.status = "inconclusive"
                    st.reason += (f"; but {problems.total} sample(s) were bad or missing, so "
                                  f"the evidence is incomplete")
                elif st.absence and not finished:
                    st.status = "inconclusive"
                    st.reason += f"; but the run did not finish ({why_unfinished})"
            states = self.states[req.name]
            fails = [s for s in states if s.status == "fail"]
            unknown = [s for s in states if s.status == "inconclusive"]
            if fails:
                first = min(fails, key=lambda s: s.decided_at or 0.0)
                out.append(Verdict(req.name, "fail", first.decided_at, first.reason,
                                   first.objects))
            elif unknown:
                out.append(Verdict(req.name, "inconclusive", unknown[0].decided_at,
                                   unknown[0].reason))
            else:
                at = max((s.decided_at for s in states if s.decided_at is not None),
                         default=end_time)
                out.append(Verdict(req.name, "pass", at,
                                   "; ".join(s.reason for s in states)))
        return tuple(out)

    def _finish(self, st: _ClauseState, end: float) -> None:
        c = st.clause
        whole = (0.0, end)
        if isinstance(c, vm.Never):
            st.decide("pass", end, f"{c.event} never occurred", absence=True, span=whole)
        elif isinstance(c, vm.Eventually):
            st.decide("fail", end, f"{c.event} never occurred", absence=True, span=whole)
        elif isinstance(c, vm.CountBound):
            ok = _CMP[c.op](st.count, c.bound)
            st.decide("pass" if ok else "fail", end, f"{c.event} occurred {st.count} times; "
                      f"expected {c.op} {c.bound:g}", absence=True, span=whole)
        elif isinstance(c, vm.Whenever):
            self._expire(st, end)
            if st.pending:
                t = st.pending[0]
                st.decide("fail", end, f"{c.trigger} at t={t:g} s was never followed by "
                                       f"{' or '.join(c.targets)}", absence=True,
                          span=(t, end))
            else:
                st.decide("pass", end, f"every {c.trigger} was followed by "
                                       f"{' or '.join(c.targets)}", absence=True, span=whole)
