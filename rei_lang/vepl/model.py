"""Typed records of a checked .vepl specification (immutable; times in seconds).

Expressions and event patterns are small trees of frozen dataclasses; the code generator
(rei.generators.targets.rx) turns them into Python. This module must never import textX
objects into its records or anything of the runtime.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from rei.lang.errors import Span

Domain = Literal["object", "floor", "task"]
MAX_QUERY_PARAMS = 4
"""Parameters a query may have (the thesis's largest VIATRA pattern has four)."""
OBJECT_ROLES = ("wall", "static", "dynamic", "human")
"""Kinds an object parameter may name besides catalogue types (``object[human]``)."""
ContextKind = Literal["chronicle", "immediate", "strict"]
CompareOp = Literal["<", "<=", ">", ">=", "==", "!="]

TASK_STATES = ("pending", "active", "succeeded", "failed")
MISSION_STATES = ("pending", "running", "ended")
TASK_FAILURES = ("none", "aborted", "preempted", "timeout", "position", "heading", "abandoned",
                 "cut")
"""Why a task failed (``failure(t)``): none (it did not fail), aborted or preempted by the
robot, timeout (outlived its timeout), position (claimed success outside the goal's
tolerance), heading (claimed success with the wrong heading), abandoned (the mission's time
limit ran out first, or the run broke), cut (the run was stopped early by the user's
``--duration``: the task's end was never observed)."""
SCALAR_MEASURES = ("laser_min", "laser_clearance", "speed", "time", "odom_error",
                   "robot_inradius", "robot_circumradius", "cmd_speed", "cmd_turn",
                   "turn_rate", "yaw_rate", "yaw", "speed_limit", "turn_limit", "humans",
                   "dynamic_objects", "cycles", "headed_goals", "goals", "neighbouring_goals",
                   "own_speed", "own_turn_rate", "own_yaw_rate", "pushed", "settle_travel",
                   "hazard_clearance", "path_ratio", "time_ratio", "goal_spin",
                   "cmd_linear", "cmd_yaw_rate", "cmd_accel", "cmd_decel", "cmd_turn_accel",
                   "cmd_turn_decel", "settle_time", "accel_limit", "decel_limit",
                   "turn_accel_limit", "turn_decel_limit")
"""Names an expression may read from the robot description (and the scenario's facts)
without arguments; docs/vepl.md says what each means."""


# ---- query expressions -------------------------------------------------------------------

@dataclass(frozen=True)
class Num:
    value: float


@dataclass(frozen=True)
class Var:
    """A query parameter (an object, floor or task of the query's domain)."""

    name: str


@dataclass(frozen=True)
class Measure:
    """A scalar of the robot description (laser_min, speed, ...)."""

    name: str


@dataclass(frozen=True)
class StateName:
    """A task or mission state on the right of '==' (active, succeeded, running, ...)."""

    name: str


@dataclass(frozen=True)
class Call:
    """A built-in (distance, on, state, mission_state) or a registered user function."""

    function: str
    args: tuple[Expr, ...]
    user: bool = False


@dataclass(frozen=True)
class Arith:
    op: Literal["+", "-", "*", "/"]
    left: Expr
    right: Expr


@dataclass(frozen=True)
class Compare:
    op: CompareOp
    left: Expr
    right: Expr


@dataclass(frozen=True)
class BoolOp:
    op: Literal["and", "or"]
    operands: tuple[Expr, ...]


@dataclass(frozen=True)
class Not:
    operand: Expr


@dataclass(frozen=True)
class Find:
    """``find q(x, _)`` / ``neg find q(_)``: another query's matches, joined with this
    query's parameters on the variables they share (``_`` = any value there)."""

    query: str
    args: tuple[str | None, ...]
    """Per parameter of the other query: this query's variable bound to it, None for '_'."""
    negated: bool


Expr = Num | Var | Measure | StateName | Call | Arith | Compare | BoolOp | Not | Find


@dataclass(frozen=True)
class QueryParam:
    name: str
    domain: Domain
    kinds: tuple[str, ...] = ()
    """For objects: the roles or catalogue types it ranges over (empty: every object)."""


@dataclass(frozen=True)
class Query:
    name: str
    params: tuple[QueryParam, ...]
    """Up to MAX_QUERY_PARAMS parameters: a query matches per combination of objects, floors
    and tasks (the cross product of their domains, filtered by the condition), or just holds."""
    condition: Expr
    span: Span


@dataclass(frozen=True)
class QueryEvent:
    name: str
    query: str
    found: bool
    per_match: bool
    """True: one event per match (``e(o) as q(o) found``); False: the match set as a whole
    became non-empty (found) or empty (lost), thesis 9.2.2.1."""
    span: Span


# ---- event patterns ----------------------------------------------------------------------

@dataclass(frozen=True)
class EvRef:
    name: str


@dataclass(frozen=True)
class EvSeq:
    parts: tuple[Pattern, ...]


@dataclass(frozen=True)
class EvOr:
    options: tuple[Pattern, ...]


@dataclass(frozen=True)
class EvAnd:
    parts: tuple[Pattern, ...]


@dataclass(frozen=True)
class EvNot:
    operand: Pattern


@dataclass(frozen=True)
class EvRepeat:
    operand: Pattern
    low: int
    """At least this many (0 for {*}, 1 for {+}, n for {n})."""
    exact: bool
    """{n}: exactly n; otherwise any number above low."""


@dataclass(frozen=True)
class EvWindow:
    operand: Pattern
    seconds: float


Pattern = EvRef | EvSeq | EvOr | EvAnd | EvNot | EvRepeat | EvWindow


@dataclass(frozen=True)
class ComplexEvent:
    name: str
    pattern: Pattern
    context: ContextKind
    text: str
    """The pattern as written, for the generated module's comments."""
    span: Span


@dataclass(frozen=True)
class Signal:
    name: str
    event: str
    utility: float
    span: Span


# ---- requirements ------------------------------------------------------------------------

@dataclass(frozen=True)
class Never:
    event: str


@dataclass(frozen=True)
class Eventually:
    event: str


@dataclass(frozen=True)
class CountBound:
    event: str
    op: CompareOp
    bound: float


@dataclass(frozen=True)
class Whenever:
    trigger: str
    targets: tuple[str, ...]
    """Events/signals that must occur, or queries that must hold, after each trigger."""
    window: float | None
    """Seconds; None: by the end of the run."""


Clause = Never | Eventually | CountBound | Whenever


@dataclass(frozen=True)
class Requirement:
    name: str
    description: str
    clauses: tuple[Clause, ...]
    span: Span
    premise: str | None = None
    """A query: the requirement applies only to runs where it held at some time."""


@dataclass(frozen=True)
class Specification:
    name: str
    path: str
    parameters: dict[str, float]
    functions: dict[str, int]
    """User check functions by name -> arity; the runtime must register them."""
    queries: tuple[Query, ...]
    """In evaluation order (a query after every query it finds)."""
    query_events: tuple[QueryEvent, ...]
    complex_events: tuple[ComplexEvent, ...]
    signals: tuple[Signal, ...]
    requirements: tuple[Requirement, ...]
    function_spans: dict[str, Span] = field(default_factory=dict)
    """Where each user function is declared (errors about its registration point there)."""

    @property
    def hysteresis(self) -> float:
        return self.parameters.get("hysteresis", 0.0)
