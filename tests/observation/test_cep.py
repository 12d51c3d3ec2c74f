"""Complex event semantics, each feature on its own: followed-by, OR, AND, NOT, multiplicity,
time windows on simulation time, and the three event contexts."""

from __future__ import annotations

from reactivex.scheduler import VirtualTimeScheduler
from reactivex.subject import Subject

from rei.lang.source import SourceText
from rei.lang.vepl import analyse_vepl
from rei.lang.vepl import model as m
from rei.runtime.observation.automata.patterns import Occurrence, match_pattern


def pattern(text: str) -> tuple[m.Pattern, m.ContextKind]:
    doc = analyse_vepl(SourceText("t.vepl", f"""query q() {{ laser_min < 1 }}
queryEvent a() as q found
queryEvent b() as q lost
queryEvent c() as q found
complexEvent x(){{ as {text} }}
"""))
    assert doc.spec is not None and doc.ok, doc.diagnostics
    ce = doc.spec.complex_events[0]
    return ce.pattern, ce.context


def run(text: str, events: list[tuple[str, float]], until: float | None = None
        ) -> list[tuple[float, tuple[str, ...]]]:
    """Feed (name, time) events; the matches as (time, names of the events consumed)."""
    p, context = pattern(text)
    scheduler = VirtualTimeScheduler(0.0)
    source: Subject[Occurrence] = Subject()
    out: list[Occurrence] = []
    source.pipe(match_pattern("x", p, context, scheduler)).subscribe(out.append)
    for serial, (name, t) in enumerate(events, start=1):
        scheduler.advance_to(t)
        source.on_next(Occurrence(name, t, (f"{name}{serial}",), serial))
    if until is not None:
        scheduler.advance_to(until)
    return [(o.time, o.objects) for o in out]


def test_followed_by_needs_the_order() -> None:
    assert run("a -> b", [("b", 1), ("a", 2), ("b", 3)]) == [(3, ("a2", "b3"))]


def test_or_and_and() -> None:
    assert run("a OR b", [("b", 1)]) == [(1, ("b1",))]
    assert run("a AND b", [("b", 1), ("c", 2), ("a", 3)]) == []  # immediate: c breaks it
    assert run("a AND b context chronicle", [("b", 1), ("c", 2), ("a", 3)]) == [
        (3, ("b1", "a3"))]


def test_not_between_forbids_the_event() -> None:
    assert run("a -> NOT b -> c", [("a", 1), ("b", 2), ("c", 3)]) == []
    assert run("a -> NOT b -> c", [("a", 1), ("c", 3)]) == [(3, ("a1", "c2"))]


def test_trailing_not_completes_when_the_window_closes_on_simulation_time() -> None:
    assert run("(a -> NOT b)[1000]", [("a", 1.0)], until=1.5) == []
    assert run("(a -> NOT b)[1000]", [("a", 1.0)], until=2.5) == [(2.0, ("a1",))]
    assert run("(a -> NOT b)[1000]", [("a", 1.0), ("b", 1.5)], until=5) == []


def test_multiplicity() -> None:
    assert run("a{3}", [("a", 1), ("a", 2)]) == []
    assert run("a{3}", [("a", 1), ("a", 2), ("a", 3)]) == [(3, ("a1", "a2", "a3"))]
    assert run("a{+} -> b", [("a", 1), ("a", 2), ("b", 3)]) == [(3, ("a1", "a2", "b3"))]
    assert run("a{*} -> b", [("b", 1)]) == [(1, ("b1",))]


def test_thesis_pattern_fires_once_per_transition() -> None:
    events = [("a", 1.0), ("b", 1.0), ("a", 5.0), ("b", 5.0)]
    assert run("(a -> b){+}[1000]", events) == [(1.0, ("a1", "b2")), (5.0, ("a3", "b4"))]


def test_window_is_simulation_time_and_inclusive() -> None:
    assert run("(a -> b)[1000]", [("a", 1.0), ("b", 2.0)]) == [(2.0, ("a1", "b2"))]
    assert run("(a -> b)[1000]", [("a", 1.0), ("b", 2.001)]) == []


def test_contexts_differ_on_overlapping_partial_matches() -> None:
    events = [("a", 1), ("a", 2), ("a", 3), ("b", 4)]
    # chronicle keeps every partial match: each a that can still reach b does
    assert run("a -> a -> b context chronicle", events) == [(4, ("a1", "a2", "b4")),
                                                            (4, ("a2", "a3", "b4"))]
    # immediate drops partial matches the latest event did not advance
    assert run("a -> a -> b context immediate", events) == [(4, ("a2", "a3", "b4"))]
    # strict immediate allows one partial match at a time: a1 a2 then a3 breaks it
    assert run("a -> a -> b context strict immediate", events) == []
    assert run("a -> a -> b context strict immediate",
               [("a", 1), ("a", 2), ("b", 3)]) == [(3, ("a1", "a2", "b3"))]


def test_immediate_consumes_the_events_of_a_match() -> None:
    events = [("a", 1), ("a", 2), ("a", 3)]
    assert run("a -> a context immediate", events) == [(2, ("a1", "a2"))]
    assert run("a -> a context chronicle", events) == [(2, ("a1", "a2")), (3, ("a2", "a3"))]
