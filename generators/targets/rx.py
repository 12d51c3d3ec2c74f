"""The `rx` target: a .vepl specification as a Python module of RxPY event automata.

The module (``automata.py``) holds the queries as vectorised numpy functions, the query
events, complex events and signals as reactivex pipelines on a virtual-time scheduler, and
the requirements as data; rei.runtime.observation.monitor.automata_host loads it. Deterministic
text from the
same specification. This module must never import the runtime's host or write files itself.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

from rei.generators.errors import GenerationError
from rei.generators.output import OutputTree
from rei.generators.targets import GenerationRequest
from rei.generators.templating import make_environment, render, template_loader
from rei.lang.errors import LanguageError
from rei.lang.vepl import model as vm
from rei.lang.vepl.document import load_vepl
from rei.lang.vepl.linker import NAMED_STATES

OUTPUT = "automata.py"
FORMAT_VERSION = 5
"""Must equal rei.runtime.observation.automata.records.FORMAT_VERSION (3: commands, approach,
failure causes, scenario facts, requirement premises; 4: queries with several parameters, the
floors of objects and goals; 5: the runtime's records and patterns imported from
rei.runtime.observation.automata, issue 34)."""
INTERPOLATED = {"laser_min", "laser_clearance", "speed", "time", "odom_error", "turn_rate",
                "yaw_rate", "own_speed", "own_turn_rate", "own_yaw_rate", "settle_travel"}
"""Measures that change continuously between samples (crossings are replayed in order)."""


def _states(kind: str) -> tuple[str, ...]:
    if kind == "task_failure":
        return vm.TASK_FAILURES
    return vm.TASK_STATES if kind == "task_state" else NAMED_STATES[kind]


KEPT_READS = {
    # what a query reads -> the inputs field that decides it: the model hands out the
    # same object until the value changes (task arrays are copied on write, the states
    # and the scenario's facts are the same objects, the laser clearance is kept between
    # scans), so 'is' tells an unchanged input for sure
    "task_state": "task_state", "n_task": "task_state", "task_failure": "task_failure",
    "mission_state": "mission_state", "nav_state": "nav_state", "kind": "kind_masks",
    "goal_floor": "goal_floor", "humans": "humans", "dynamic_objects": "dynamic_objects",
    "cycles": "cycles", "headed_goals": "headed_goals", "goals": "goals",
    "neighbouring_goals": "neighbouring_goals", "speed_limit": "speed_limit",
    "turn_limit": "turn_limit", "accel_limit": "accel_limit", "decel_limit": "decel_limit",
    "turn_accel_limit": "turn_accel_limit", "turn_decel_limit": "turn_decel_limit",
    "robot_inradius": "robot_inradius",
    "robot_circumradius": "robot_circumradius", "laser_clearance": "laser_clearance",
    "hazard_clearance": "hazard_clearance",
}
"""Inputs that stay the same objects over many samples: a query reading nothing else (and
finding only such queries) keeps its matches from the previous step while they are the
same, instead of being evaluated again."""
_READS = re.compile(r"\bw\.(\w+)")
_FINDS = re.compile(r"\bq\['(\w+)'\]")


def kept_queries(queries: list[_QueryCode]) -> tuple[dict[str, tuple[str, ...]], list[str]]:
    """Per query that may keep its matches, the inputs fields that must be the same for it
    (its own reads and those of the queries it finds); and every such field, sorted."""
    kept: dict[str, tuple[str, ...]] = {}
    for q in queries:
        reads = _READS.findall(q.strict)
        finds = _FINDS.findall(q.strict)
        if q.relaxed is None and all(r in KEPT_READS for r in reads) \
                and all(f in kept for f in finds):
            fields = {KEPT_READS[r] for r in reads}
            for f in finds:
                fields.update(kept[f])
            kept[q.name] = tuple(sorted(fields))
    return kept, sorted({f for fields in kept.values() for f in fields})


@dataclass(frozen=True)
class _QueryCode:
    name: str
    domains: tuple[str, ...]
    kinds: tuple[tuple[str, ...], ...]
    signature: str
    strict: str
    relaxed: str | None
    shaped: bool
    """The condition already has the domain's shape (it reads the parameter)."""

    def shape(self, expr: str) -> str:
        """Queries with parameters return an array over the cross product of their domains
        (one axis per parameter, in order); others a boolean."""
        if not self.domains:
            return f"np.asarray({expr}, dtype=bool)"
        n = len(self.domains)
        masks = []
        for axis, kinds in enumerate(self.kinds):
            if kinds:
                mask = " | ".join(f"w.kind({k!r})" for k in kinds)
                mask = f"({mask})" if len(kinds) > 1 else mask
                masks.append(mask if n == 1 else f"w.along({mask}, {axis}, {n})")
        mask = "".join(f"{m} & " for m in masks)
        if self.shaped and n == 1:
            return f"{mask}{expr}"
        size = ", ".join(f"w.n_{d}" for d in self.domains) + ("," if n == 1 else "")
        code = f"{mask}np.broadcast_to({expr}, ({size}))"
        return code if n == 1 else _wrap(code)


def _wrap(code: str, indent: int = 8, width: int = 88) -> str:
    """Break a long expression after its ``&`` and ``|`` (and the commas of its outer call),
    only inside parentheses so the break is legal Python, lines about ``width`` long."""
    lines: list[str] = []
    depth = 0
    start = 0
    last_break = -1
    for i, ch in enumerate(code):
        depth += ch in "([{"
        depth -= ch in ")]}"
        if ch == " " and depth > 0 and (code[i - 1] in "&|" or (code[i - 1] == "," and depth == 1)):
            if i - start > width - indent and last_break > start:
                lines.append(code[start:last_break].rstrip())
                start = last_break + 1
            last_break = i
    lines.append(code[start:])
    return f"\n{' ' * indent}".join(line.strip() if k else line for k, line in enumerate(lines))


class _Writer:
    """Expressions as numpy code; ``relaxed`` widens every threshold by the hysteresis band
    in the direction that keeps a match (flipped under 'not')."""

    def __init__(self, query: vm.Query, hysteresis: float) -> None:
        self.query = query
        self.h = hysteresis
        self.axes = {p.name: i for i, p in enumerate(query.params)}
        self.n = len(query.params)

    def along(self, code: str, var: vm.Expr) -> str:
        """``code``, an array over the domain of ``var``, on that parameter's axis."""
        if self.n <= 1 or not isinstance(var, vm.Var):
            return code
        return f"w.along({code}, {self.axes[var.name]}, {self.n})"

    def code(self, e: vm.Expr, relaxed: bool, positive: bool = True) -> str:
        def c(x: vm.Expr) -> str:
            return self.code(x, relaxed, positive)

        if isinstance(e, vm.Num):
            return repr(e.value)
        if isinstance(e, vm.Measure):
            return f"w.{e.name}"
        if isinstance(e, vm.Var):
            domain = self.query.params[self.axes[e.name]].domain if self.n else "object"
            return self.along(f"w.indices({domain!r})", e)
        if isinstance(e, vm.Call):
            last = e.args[-1] if e.args else None
            if e.function == "distance":
                return self.along("w.distance", e.args[1])
            if e.function == "on":
                floor = e.args[1]
                if isinstance(e.args[0], vm.Var) and e.args[0].name in self.axes:
                    assert isinstance(floor, vm.Var)
                    return (f"w.on_floor({self.axes[e.args[0].name]}, "
                            f"{self.axes[floor.name]}, {self.n})")
                return self.along("w.robot_floor", floor)
            if e.function in ("state", "failure", "approach", "goal") and last is not None:
                array = {"state": "w.task_state", "failure": "w.task_failure",
                         "approach": "w.approach", "goal": "w.goal_floor"}[e.function]
                return self.along(array, last)
            if e.function == "neighbours":
                a, b = e.args
                assert isinstance(a, vm.Var) and isinstance(b, vm.Var)
                return (f"w.pair(w.floor_adjacent, {self.axes[a.name]}, {self.axes[b.name]}, "
                        f"{self.n})")
            args = "".join(", " + c(a) for a in e.args)
            return f"w.call({e.function!r}{args})"
        if isinstance(e, vm.Arith):
            # A sum or product of many terms is a chain nested to the left: written flat
            # (Python's + - and * / associate to the left too), never as nested brackets,
            # which Python refuses beyond 200 levels.
            terms: list[str] = []
            node: vm.Expr = e
            while isinstance(node, vm.Arith) and _same_level(node, e):
                terms.append(f" {node.op} {c(node.right)}")
                node = node.left
            return "(" + c(node) + "".join(reversed(terms)) + ")"
        if isinstance(e, vm.Compare):
            left = c(e.left)
            if isinstance(e.right, vm.StateName):
                kind = self._state_kind(e.left)
                code = _states(kind).index(e.right.name)
                return f"({left} {e.op} {code})"
            right = c(e.right)
            if relaxed and self.h > 0 and e.op in ("<", "<=", ">", ">="):
                widen = (e.op in ("<", "<=")) == positive
                right = f"{right} {'+' if widen else '-'} HYSTERESIS"
            return f"({left} {e.op} {right})"
        if isinstance(e, vm.BoolOp):
            joiner = " & " if e.op == "and" else " | "
            facts = [x for x in e.operands if not _reads_parameter(x)]
            if e.op == "and" and self.n > 1 and facts and len(facts) < len(e.operands):
                # Scenario facts first, and the arrays over the domains' cross product (a
                # large room's floors by floors) only when the facts hold.
                rest = [x for x in e.operands if _reads_parameter(x)]
                return (f"(np.bool_({' & '.join(c(x) for x in facts)}) and "
                        f"({' & '.join(c(x) for x in rest)}))")
            return "(" + joiner.join(c(x) for x in e.operands) + ")"
        if isinstance(e, vm.Not):
            return f"~{self.code(e.operand, relaxed, not positive)}"
        if isinstance(e, vm.Find):
            ref = f"q[{e.query!r}]"
            axes = tuple(None if a is None else self.axes[a] for a in e.args)
            if all(a is None for a in axes):
                inner = f"any_match({ref})"
            elif axes == (0,) and self.n == 1:
                inner = ref
            else:
                inner = f"w.bind({ref}, {axes!r}, {self.n})"
            return f"~{inner}" if e.negated else inner
        raise GenerationError(f"cannot generate code for {e!r}")

    @staticmethod
    def _state_kind(e: vm.Expr) -> str:
        if isinstance(e, vm.Call) and e.function == "state":
            return "task_state"
        if isinstance(e, vm.Call) and e.function == "failure":
            return "task_failure"
        assert isinstance(e, vm.Measure)
        return e.name

    def margins(self, e: vm.Expr, out: list[str]) -> None:
        stack = [e]  # pre-order without recursion, as _nodes, but not below a comparison
        while stack:
            node = stack.pop()
            if isinstance(node, vm.Compare) and not isinstance(node.right, vm.StateName):
                if _measured(node.left) or _measured(node.right):
                    base = f"{self.code(node.left, False)} - {self.code(node.right, False)}"
                    out.append(f"np.asarray({base}, dtype=float)")
                    if self.h > 0 and node.op in ("<", "<=", ">", ">="):
                        out.append(f"np.asarray({base} - HYSTERESIS, dtype=float)")
                        out.append(f"np.asarray({base} + HYSTERESIS, dtype=float)")
                continue
            stack.extend(reversed(_children(node)))


def _same_level(a: vm.Arith, b: vm.Arith) -> bool:
    return (a.op in "+-") == (b.op in "+-")


def _nodes(e: vm.Expr, into_call: Callable[[vm.Call], bool] = lambda _: True
           ) -> Iterator[vm.Expr]:
    """Every node of an expression in reading order (pre-order), without recursion: a sum of
    a thousand terms is a chain a thousand deep. ``into_call`` says whether to look inside a
    call's arguments."""
    stack = [e]
    while stack:
        node = stack.pop()
        yield node
        if isinstance(node, vm.Call) and not into_call(node):
            continue
        stack.extend(reversed(_children(node)))


def _children(e: vm.Expr) -> tuple[vm.Expr, ...]:
    if isinstance(e, vm.BoolOp):
        return e.operands
    if isinstance(e, vm.Not):
        return (e.operand,)
    if isinstance(e, vm.Compare | vm.Arith):
        return (e.left, e.right)
    if isinstance(e, vm.Call):
        return e.args
    return ()


def _reads_parameter(e: vm.Expr) -> bool:
    # distance(robot, o), on(robot, f), state(t): arrays over the domain
    return any(isinstance(n, vm.Var) or (isinstance(n, vm.Find) and any(n.args))
               or (isinstance(n, vm.Call) and not n.user) for n in _nodes(e))


def _measured(e: vm.Expr) -> bool:
    def counts(n: vm.Expr) -> bool:
        if isinstance(n, vm.Measure):
            return n.name in INTERPOLATED
        return isinstance(n, vm.Call) and (n.function == "distance" or n.user)

    # A built-in call other than distance reads no measure, whatever its arguments.
    return any(counts(n) for n in _nodes(e, into_call=lambda _: False))


def _constant(e: vm.Expr) -> float | None:
    if isinstance(e, vm.Num):
        return e.value
    if isinstance(e, vm.Arith):
        chain: list[vm.Arith] = []
        node: vm.Expr = e
        while isinstance(node, vm.Arith):  # down the left chain without recursion
            chain.append(node)
            node = node.left
        value = _constant(node)
        for link in reversed(chain):
            right = _constant(link.right)
            if value is None or right is None:
                return None
            value = {"+": value + right, "-": value - right, "*": value * right,
                     "/": value / right if right else math.inf}[link.op]
        return value
    return None


def distance_cutoff(spec: vm.Specification) -> float:
    """The largest threshold a footprint distance is compared with (inf if not constant)."""
    worst = 0.0
    for q in spec.queries:
        for e in _nodes(q.condition):
            if isinstance(e, vm.Compare):
                sides = (e.left, e.right)
                for side, other in (sides, sides[::-1]):
                    if isinstance(side, vm.Call) and side.function == "distance":
                        value = _constant(other)
                        worst = max(worst, math.inf if value is None else value)
                    elif _uses_distance(side):
                        worst = math.inf
    return worst + spec.hysteresis if math.isfinite(worst) else math.inf


def _uses_distance(e: vm.Expr) -> bool:
    return any(isinstance(n, vm.Call) and n.function == "distance" for n in _nodes(e))


def _pyrepr(value: Any, indent: int = 8, width: int = 96) -> str:
    """Python source for a value; records too long for one line get one field per line."""
    if isinstance(value, float):
        return "math.inf" if math.isinf(value) else repr(value)
    flat = _flat(value)
    if indent + len(flat) <= width:
        return flat
    pad = " " * (indent + 4)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        fields = [f"{pad}{f.name}={_pyrepr(getattr(value, f.name), indent + 4, width)},"
                  for f in dataclasses.fields(value)]
        return f"{type(value).__name__}(\n" + "\n".join(fields) + f"\n{' ' * indent})"
    if isinstance(value, tuple):
        items = [f"{pad}{_pyrepr(v, indent + 4, width)}," for v in value]
        return "(\n" + "\n".join(items) + f"\n{' ' * indent})"
    return flat


def _flat(value: Any) -> str:
    if isinstance(value, float):
        return "math.inf" if math.isinf(value) else repr(value)
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        inner = ", ".join(f"{f.name}={_flat(getattr(value, f.name))}"
                          for f in dataclasses.fields(value))
        return f"{type(value).__name__}({inner})"
    if isinstance(value, tuple):
        inner = ", ".join(_flat(v) for v in value)
        return f"({inner},)" if len(value) == 1 else f"({inner})"
    return repr(value)


def _signature(q: vm.Query, path: str) -> str:
    params = []
    for p in q.params:
        kinds = f"[{', '.join(p.kinds)}]" if p.kinds else ""
        params.append(f"{p.name}: {p.domain}{kinds}")
    return f"query {q.name}({', '.join(params)}), {path} line {q.span.line}."


def _event_refs(p: vm.Pattern) -> list[str]:
    if isinstance(p, vm.EvRef):
        return [p.name]
    parts: tuple[vm.Pattern, ...]
    if isinstance(p, vm.EvSeq | vm.EvAnd):
        parts = p.parts
    elif isinstance(p, vm.EvOr):
        parts = p.options
    else:
        parts = (p.operand,)
    out: list[str] = []
    for x in parts:
        for r in _event_refs(x):
            if r not in out:
                out.append(r)
    return out


def render_module(spec: vm.Specification, source_name: str) -> str:
    queries = []
    margins: list[str] = []
    for q in spec.queries:
        w = _Writer(q, spec.hysteresis)
        strict = w.code(q.condition, False)
        relaxed = w.code(q.condition, True) if spec.hysteresis > 0 else None
        if relaxed == strict:
            relaxed = None
        w.margins(q.condition, margins)
        queries.append(_QueryCode(q.name, tuple(p.domain for p in q.params),
                                  tuple(p.kinds for p in q.params),
                                  _signature(q, source_name), strict, relaxed,
                                  bool(q.params) and _reads_parameter(q.condition)))
    complex_events = [
        {"name": c.name, "text": c.text, "context": c.context,
         "context_text": "strict immediate" if c.context == "strict" else c.context,
         "refs": _event_refs(c.pattern)}
        for c in spec.complex_events]
    env = make_environment(template_loader("rx"), xml=False)
    env.filters["pyrepr"] = _pyrepr
    cutoff = distance_cutoff(spec)
    kept, kept_fields = kept_queries(queries)
    text = render(env, "automata.py.j2", spec=spec, source_name=source_name,
                  format_version=FORMAT_VERSION, queries=queries, kept=kept,
                  kept_fields=kept_fields,
                  margins=list(dict.fromkeys(margins)), complex=complex_events,
                  cutoff="math.inf" if math.isinf(cutoff) else repr(cutoff),
                  functions=repr(dict(spec.functions)))
    compile(text, OUTPUT, "exec")  # a template bug must fail here, not in a user's run
    return text


@dataclass(frozen=True)
class RxTarget:
    name: str = "rx"
    description: str = "RxPY event automata (a Python module) from a .vepl specification"
    accepts: tuple[str, ...] = (".vepl",)

    def generate(self, request: GenerationRequest) -> OutputTree:
        try:
            spec = load_vepl(request.source, request.parameters)
        except LanguageError as exc:
            raise GenerationError(str(exc)) from None
        tree = OutputTree()
        tree.add_text(OUTPUT, render_module(spec, request.source.name))
        return tree


TARGET = RxTarget()
