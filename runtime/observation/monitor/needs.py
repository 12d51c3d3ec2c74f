"""Which collected data a specification reads, and refusing one the stream cannot serve.

A query that reads ``laser_min`` judged on a stream without laser data would see a value
nobody measured (thesis 6.1.2: the collector forwards only the configured subset). So before
a run (``rei run``) or a replay (``rei replay``) every query of the .vepl is walked, each term
mapped to the data it reads, and a specification needing data the mission does not collect
(or the trace does not carry) is refused with a located ``VEPL-DATA`` diagnostic per query:
never a verdict on missing data, which could be a false PASS. Ground truth is always
collected, so the geometry (distance, on, speed, yaw, ...) and the mission's facts from the
header (goal, goals, cycles, ...) need nothing more.
"""

from __future__ import annotations

from collections.abc import Iterator

from rei.lang.errors import Diagnostic, LanguageError, sorted_diagnostics
from rei.lang.vepl import model as m

MEASURE_DATA = {
    "laser_min": "laser",
    "laser_clearance": "laser",
    "hazard_clearance": "laser",  # the scan's beams, matched with the ground-truth footprints
    "odom_error": "odometry",
    "cmd_speed": "nav_state",
    "cmd_turn": "nav_state",
    "cmd_linear": "nav_state",
    "cmd_yaw_rate": "nav_state",
    "cmd_accel": "nav_state",  # the commands' changes, over the samples' times
    "cmd_decel": "nav_state",
    "cmd_turn_accel": "nav_state",
    "cmd_turn_decel": "nav_state",
    "settle_time": "mission_events",  # since the mission events' last task end
    # the robot's own motion is the ground truth capped at its command while it is pushed
    "own_speed": "nav_state",
    "own_turn_rate": "nav_state",
    "own_yaw_rate": "nav_state",
    "pushed": "nav_state",
    "settle_travel": "nav_state",  # own motion, after the mission events' last task end
    "path_ratio": "mission_events",  # judged when the mission events say a task succeeded
    "time_ratio": "mission_events",
    "goal_spin": "nav_state",  # own motion, near the running task's goal
    "nav_state": "nav_state",
    "mission_state": "mission_events",
}
"""The robot-description scalars that read more than ground truth, and what they read."""
CALL_DATA = {
    "approach": "nav_state",  # the robot's own commanded motion
    "state": "mission_events",  # task states come from the mission executor's events
    "failure": "mission_events",
}
"""The built-in functions that read more than ground truth, and what they read."""
TASK_DOMAIN_DATA = "mission_events"
"""A query over tasks ranges over the tasks the mission events announced."""


def _terms(e: m.Expr) -> Iterator[tuple[str, str]]:
    """(term as the user wrote it, data it needs) for every term of ``e`` beyond ground truth."""
    if isinstance(e, m.Measure):
        if e.name in MEASURE_DATA:
            yield e.name, MEASURE_DATA[e.name]
    elif isinstance(e, m.Call):
        if not e.user and e.function in CALL_DATA:
            yield f"{e.function}(...)", CALL_DATA[e.function]
        for arg in e.args:
            yield from _terms(arg)
    elif isinstance(e, (m.Arith, m.Compare)):
        yield from _terms(e.left)
        yield from _terms(e.right)
    elif isinstance(e, m.BoolOp):
        for operand in e.operands:
            yield from _terms(operand)
    elif isinstance(e, m.Not):
        yield from _terms(e.operand)


def query_needs(query: m.Query) -> dict[str, str]:
    """Data the query reads beyond ground truth -> the first term that reads it."""
    needs: dict[str, str] = {}
    for param in query.params:
        if param.domain == "task":
            needs.setdefault(TASK_DOMAIN_DATA, f"the task parameter '{param.name}'")
    for term, data in _terms(query.condition):
        needs.setdefault(data, term)
    return needs


def needed_data(spec: m.Specification) -> frozenset[str]:
    """Every kind of data some query of ``spec`` reads (ground truth left implicit)."""
    return frozenset(d for q in spec.queries for d in query_needs(q))


def check_needs(spec: m.Specification, collected: tuple[str, ...], source: str,
                hint: str) -> None:
    """``LanguageError`` (one ``VEPL-DATA`` diagnostic per query, at the query) when a query
    of ``spec`` reads data not in ``collected``; ``source`` says whose data they are ("the
    mission 'lab' to collect", "the trace 'run/trace.jsonl' to carry"), ``hint`` what to do
    about it."""
    problems = []
    for query in spec.queries:
        missing = [(term, data) for data, term in query_needs(query).items()
                   if data not in collected]
        if missing:
            reads = " and ".join(f"{term}, which needs the '{data}' data"
                                 for term, data in missing)
            problems.append(Diagnostic(
                query.span, "VEPL-DATA",
                f"query '{query.name}' reads {reads}; expected {source} "
                f"{'it' if len(missing) == 1 else 'them'}, found only {', '.join(collected)} "
                f"({hint})"))
    if problems:
        raise LanguageError(sorted_diagnostics(problems))
