"""From a parsed .vepl to the typed Specification, with every semantic problem located.

Rules (ids in the report / rei.lang.rules): VEPL-UNKNOWN (a name that is not declared, or a
kind of object that is neither a role nor a catalogue type, with 'did you mean'), VEPL-ARITY
(too many query parameters, or uses whose arguments do not match the declaration), VEPL-ORDER
(an event used before it is defined), VEPL-WINDOW (a time window that is not positive),
VEPL-TYPE (an expression that mixes kinds of values), VEPL-NOT-WINDOW (a pattern ending in NOT
without a window), VEPL-MULTIPLICITY ({n} below 1 or not whole), VEPL-CYCLE (queries finding
each other in a circle), VEPL-PARAM (ε_collision < ε_close, hysteresis >= 0), VEPL-LIMIT (a
pattern or a condition too big for the generated automata to run), plus the shared
NAME-UNIQUE, NUM-FINITE and NUM-RANGE. This module must never import the runtime.
"""

from __future__ import annotations

from typing import Any, Literal

import networkx as nx

from rei.catalogue import default_catalogue
from rei.lang.errors import Diagnostic, Span
from rei.lang.numbers import read_number
from rei.lang.parsing import span_of
from rei.lang.source import SourceText
from rei.lang.suggest import did_you_mean
from rei.lang.vepl import model as m
from rei.lang.vepl_parameters import LIMIT, PARAM_OPTION, ParameterValues

MAX_WINDOW_MS = 1e9
MAX_PATTERN_SIZE = 500
"""Parts of a complex event's pattern once every {n} is written out n times and every {+}
as one copy followed by {*} (the automaton the runtime builds): matching one event costs
about 10 ms at this size, growing with its square, and nested {+} double the size at every
level."""
MAX_PATTERN_DEPTH = 50
"""Pattern operators nested in each other (each suffix counts): the generated automata and
the runtime walk patterns recursively."""
MAX_CONDITION_SIZE = 2000
"""Operators and operands in one query's condition: the generated condition is one Python
expression (a sum of 1,000 terms), and Python compiles a chain of a few thousand
operators only with a deeper stack than a run has to spare."""
BUILTINS = {"distance": 2, "on": 2, "state": 1, "failure": 1, "approach": 1, "goal": 1,
            "neighbours": 2}
_WHAT = {"Function": "function", "Query": "query", "QueryEvent": "query event",
         "ComplexEvent": "complex event", "Signal": "signal", "Requirement": "requirement"}
NAMED_STATES = {"mission_state": m.MISSION_STATES,
                "nav_state": ("idle", "pending", "active", "succeeded", "aborted", "preempted")}
ROBOT = "robot"

def object_kinds() -> tuple[str, ...]:
    """What ``object[...]`` may name: a role, or a type of the catalogue that ships with REI
    that an observed object can have (walls, furniture, people, moving objects)."""
    types = default_catalogue()
    return (*m.OBJECT_ROLES, *(n for n in types.names() if types.types[n].kind in m.OBJECT_ROLES
                               and n not in m.OBJECT_ROLES))


Kind = str
"""'num', 'bool', 'task_state', 'mission_state', 'nav_state', 'state_name', 'robot' or
'var:DOMAIN'."""


class _Linker:
    def __init__(self, source: SourceText, overrides: ParameterValues = ()) -> None:
        self.source = source
        self.overrides = overrides
        self.diagnostics: list[Diagnostic] = []

    def span(self, obj: Any) -> Span:
        return span_of(obj, self.source)

    def error(self, obj: Any, rule: str, message: str) -> None:
        self.diagnostics.append(Diagnostic(self.span(obj), rule, message))

    def number(self, text: str, obj: Any, what: str, **bounds: Any) -> float | None:
        return read_number(text, self.span(obj), what, self.diagnostics, **bounds)

    # ---- whole file ----------------------------------------------------------------------

    def link(self, tx: Any) -> m.Specification:
        items = list(tx.items)
        names: dict[str, str] = {}

        def declare(item: Any, kind: str) -> bool:
            if item.name in names:
                self.error(item, "NAME-UNIQUE", f"expected a new name, found '{item.name}' "
                                                f"already declared as a {names[item.name]}")
                return False
            names[item.name] = kind
            return True

        parameters: dict[str, float] = {}
        for item in items:
            if type(item).__name__ == "Parameters":
                for p in item.params:
                    value = self.number(p.value, p, f"parameter '{p.name}'", low=-LIMIT,
                                        high=LIMIT)
                    if declare(p, "parameter") and value is not None:
                        parameters[p.name] = value
        self._override_parameters(tx, items, parameters)
        self._check_parameters(items, parameters)
        functions: dict[str, int] = {}
        function_spans: dict[str, Span] = {}
        for item in items:
            if type(item).__name__ == "Function" and declare(item, "function"):
                functions[item.name] = len(item.params)
                function_spans[item.name] = self.span(item)
        tx_queries = {q.name: q for q in items if type(q).__name__ == "Query"
                      and declare(q, "query")}
        self.declared = {i.name: _WHAT.get(type(i).__name__, "name") for i in items
                         if getattr(i, "name", None) and type(i).__name__ != "Parameters"}
        self.declared.update({p.name: "parameter" for i in items
                              if type(i).__name__ == "Parameters" for p in i.params})
        self.parameters, self.functions, self.tx_queries = parameters, functions, tx_queries
        queries = self._queries(tx_queries)
        self.queries = {q.name: q for q in queries}

        events: dict[str, str] = {}  # defined so far: name -> 'query event' | 'complex event'
        signals: dict[str, m.Signal] = {}
        query_events: list[m.QueryEvent] = []
        complex_events: list[m.ComplexEvent] = []
        requirements: list[m.Requirement] = []
        later = {i.name: type(i).__name__ for i in items
                 if type(i).__name__ in ("QueryEvent", "ComplexEvent", "Signal")}
        for item in items:
            kind = type(item).__name__
            if kind == "QueryEvent" and declare(item, "query event"):
                qe = self._query_event(item)
                if qe is not None:
                    query_events.append(qe)
                events[item.name] = "query event"
            elif kind == "ComplexEvent" and declare(item, "complex event"):
                ce = self._complex_event(item, events, later)
                if ce is not None:
                    complex_events.append(ce)
                events[item.name] = "complex event"
            elif kind == "Signal" and declare(item, "signal"):
                if self._event_ref(item.event, item, events, later, "signal"):
                    utility = self.number(item.utility, item, f"utility of '{item.name}'",
                                          low=-1e9, high=1e9)
                    if utility is not None:
                        signals[item.name] = m.Signal(item.name, item.event, utility,
                                                      self.span(item))
            elif kind == "Requirement" and declare(item, "requirement"):
                req = self._requirement(item, {**events, **{s: "signal" for s in signals}},
                                        later)
                if req is not None:
                    requirements.append(req)
        return m.Specification(
            name=tx.name or "specification", path=self.source.path, parameters=parameters,
            functions=functions, queries=tuple(queries), query_events=tuple(query_events),
            complex_events=tuple(complex_events), signals=tuple(signals.values()),
            requirements=tuple(requirements), function_spans=function_spans)

    def _override_parameters(self, tx: Any, items: list[Any], params: dict[str, float]) -> None:
        """The values of ``--param NAME=VALUE`` in place of the file's; a name the file does
        not declare is an error located at the file's parameters (or its start)."""
        blocks = [i for i in items if type(i).__name__ == "Parameters"]
        for name, value in self.overrides:
            if name in params:
                params[name] = value
                continue
            declared = sorted(params)
            self.error(blocks[0] if blocks else tx, "VEPL-UNKNOWN",
                       f"{PARAM_OPTION} {name}: expected a parameter the specification declares "
                       f"({', '.join(declared) or 'it declares none'}), found '{name}'"
                       + did_you_mean(name, declared))

    def _check_parameters(self, items: list[Any], params: dict[str, float]) -> None:
        spans = {p.name: p for i in items if type(i).__name__ == "Parameters" for p in i.params}
        given = dict(self.overrides)

        def origin(name: str, lead: str = " (") -> str:
            return f"{lead}set by {PARAM_OPTION}" if name in given else ""

        close, collision = params.get("eps_close"), params.get("eps_collision")
        if close is not None and collision is not None and not collision < close:
            self.error(spans["eps_collision"], "VEPL-PARAM",
                       f"expected eps_collision below eps_close ({close:g}"
                       f"{origin('eps_close', ', ')}), found {collision:g}"
                       f"{origin('eps_collision', ' (')}{')' if 'eps_collision' in given else ''}")
        if params.get("hysteresis", 0.0) < 0:
            self.error(spans["hysteresis"], "VEPL-PARAM",
                       f"expected a hysteresis band >= 0 m, found {params['hysteresis']:g}"
                       f"{origin('hysteresis')}{')' if 'hysteresis' in given else ''}")

    # ---- queries ---------------------------------------------------------------------------

    def _queries(self, tx_queries: dict[str, Any]) -> list[m.Query]:
        linked: dict[str, m.Query] = {}
        graph: nx.DiGraph[str] = nx.DiGraph()
        for name, tx in tx_queries.items():
            graph.add_node(name)
            if len(tx.params) > m.MAX_QUERY_PARAMS:
                self.error(tx.params[m.MAX_QUERY_PARAMS], "VEPL-ARITY",
                           f"query '{name}': expected at most {m.MAX_QUERY_PARAMS} parameters, "
                           f"found {len(tx.params)}")
            params = self._params(name, tx.params[:m.MAX_QUERY_PARAMS])
            self.scope = {p.name: p for p in params}
            self.current = name
            self.finds: list[str] = []
            parts = [self._constraint(c) for c in tx.constraints]
            for part, c in zip(parts, tx.constraints, strict=False):
                if part is not None and self.kind_of(part) != "bool":
                    self.error(c, "VEPL-TYPE", f"query '{name}': expected a condition (true or "
                                               f"false), found a {self.kind_of(part)} value")
            for other in self.finds:
                graph.add_edge(other, name)
            valid = [p for p in parts if p is not None]
            condition: m.Expr = valid[0] if len(valid) == 1 else m.BoolOp("and", tuple(valid))
            size = condition_size(condition)
            if size > MAX_CONDITION_SIZE:
                self.error(tx, "VEPL-LIMIT", f"query '{name}': expected a condition of at most "
                                             f"{MAX_CONDITION_SIZE} operators and operands, "
                                             f"found {size}")
            linked[name] = m.Query(name, params, condition, self.span(tx))
        order = {n: i for i, n in enumerate(tx_queries)}
        for found in sorted(nx.simple_cycles(graph),
                            key=lambda c: sorted(map(order.__getitem__, c))):
            at = min(range(len(found)), key=lambda i: order[found[i]])
            cycle = found[at:] + found[:at]  # start where the reader meets it first
            first = tx_queries[cycle[0]]
            self.error(first, "VEPL-CYCLE", "expected queries that do not find each other in a "
                                            f"circle, found {' -> '.join(cycle + cycle[:1])}")
            return list(linked.values())
        return [linked[n] for n in nx.lexicographical_topological_sort(
            graph, key=order.__getitem__)]

    def _params(self, query: str, tx_params: list[Any]) -> tuple[m.QueryParam, ...]:
        params: list[m.QueryParam] = []
        for p in tx_params:
            if p.name in (ROBOT, "_") or any(q.name == p.name for q in params):
                shown = "a name of its own" if p.name in (ROBOT, "_") else "another name"
                self.error(p, "NAME-UNIQUE", f"query '{query}': expected {shown} for the "
                                             f"parameter, found '{p.name}'")
                continue
            kinds = tuple(p.kinds or ())
            if kinds and p.domain != "object":
                self.error(p, "VEPL-TYPE", f"expected kinds only on an object parameter, "
                                           f"found them on a {p.domain}")
                kinds = ()
            for kind in kinds:
                self._check_kind(p, kind)
            params.append(m.QueryParam(p.name, p.domain, kinds))
        return tuple(params)

    def _check_kind(self, where: Any, kind: str) -> None:
        known = object_kinds()
        if kind in known:
            return
        declared = self.declared.get(kind)
        if declared is not None:
            found = f"'{kind}', which is a {declared} of this file, not a kind of object"
        else:
            found = f"'{kind}'" + did_you_mean(kind, known)
        types = ", ".join(k for k in known if k not in m.OBJECT_ROLES)
        self.error(where, "VEPL-UNKNOWN", f"expected a kind of object: a role "
                                          f"({', '.join(m.OBJECT_ROLES)}) or a catalogue type "
                                          f"({types}), found {found}")

    def _constraint(self, c: Any) -> m.Expr | None:
        if type(c).__name__ == "Find":
            return self._find(c)
        return self._expr(c)

    def _find(self, c: Any) -> m.Expr | None:
        target = self.tx_queries.get(c.query)
        if target is None:
            self.error(c, "VEPL-UNKNOWN", f"expected a query name, found '{c.query}'"
                       + did_you_mean(c.query, self.tx_queries))
            return None
        self.finds.append(c.query)
        if len(c.args) != len(target.params):
            self.error(c, "VEPL-ARITY", f"find '{c.query}': expected {len(target.params)} "
                                        f"argument(s) as declared, found {len(c.args)}")
            return None
        args: list[str | None] = []
        for arg, param in zip(c.args, target.params, strict=True):
            if arg == "_":
                args.append(None)
                continue
            if arg not in self.scope:
                self.error(c, "VEPL-UNKNOWN", f"expected this query's parameter or '_', found "
                                              f"'{arg}'" + did_you_mean(arg, self.scope))
                return None
            if self.scope[arg].domain != param.domain:
                self.error(c, "VEPL-TYPE", f"find '{c.query}': expected a {param.domain} for "
                                           f"'{param.name}', found the "
                                           f"{self.scope[arg].domain} '{arg}'")
                return None
            if arg in args:
                self.error(c, "VEPL-ARITY", f"find '{c.query}': expected each parameter "
                                            f"passed once, found '{arg}' twice")
                return None
            args.append(arg)
        return m.Find(c.query, tuple(args), bool(c.negated))

    def kind_of(self, e: m.Expr) -> Kind:
        if isinstance(e, m.Num | m.Arith):
            return "num"
        if isinstance(e, m.Measure):
            return e.name if e.name in NAMED_STATES else "num"
        if isinstance(e, m.StateName):
            return "state_name"
        if isinstance(e, m.Var):
            return "var:" + self.scope[e.name].domain if e.name in self.scope else "robot"
        if isinstance(e, m.Call):
            return {"distance": "num", "on": "bool", "state": "task_state",
                    "failure": "task_failure", "approach": "num", "goal": "bool",
                    "neighbours": "bool"}.get(e.function, "num")
        return "bool"

    def _expr(self, e: Any) -> m.Expr | None:
        kind = type(e).__name__
        if kind == "OrExpr":
            return self._nary("or", [self._expr(o) for o in e.operands], e)
        if kind == "AndExpr":
            return self._nary("and", [self._expr(o) for o in e.operands], e)
        if kind == "NotExpr":
            inner = self._expr(e.operand)
            if inner is None or not e.negated:
                return inner
            if self.kind_of(inner) != "bool":
                self.error(e, "VEPL-TYPE", f"'not': expected a condition, found a "
                                           f"{self.kind_of(inner)} value")
                return None
            return m.Not(inner)
        if kind == "Comparison":
            return self._comparison(e)
        if kind in ("Sum", "Product"):
            operands = [self._expr(o) for o in e.operands]
            if any(o is None for o in operands):
                return None
            result = operands[0]
            for op, right in zip(e.ops, operands[1:], strict=False):
                assert result is not None and right is not None
                for side in (result, right):
                    if self.kind_of(side) != "num":
                        self.error(e, "VEPL-TYPE", f"'{op}': expected numbers, found a "
                                                   f"{self.kind_of(side)} value")
                        return None
                result = m.Arith(op, result, right)
            return result
        if kind == "Parenthesised":
            return self._expr(e.inner)
        if kind == "Literal":
            value = self.number(e.value, e, "number", low=-1e12, high=1e12)
            return None if value is None else m.Num(value)
        if kind == "Call":
            return self._call(e)
        if kind == "Name":
            return self._name(e)
        raise AssertionError(kind)

    def _nary(self, op: Literal["and", "or"], parts: list[m.Expr | None], e: Any) -> m.Expr | None:
        if any(p is None for p in parts):
            return None
        valid = [p for p in parts if p is not None]
        if len(valid) == 1:
            return valid[0]
        for p in valid:
            if self.kind_of(p) != "bool":
                self.error(e, "VEPL-TYPE", f"'{op}': expected conditions, found a "
                                           f"{self.kind_of(p)} value")
                return None
        return m.BoolOp(op, tuple(valid))

    def _comparison(self, e: Any) -> m.Expr | None:
        operands = [self._expr(o) for o in e.operands]
        if len(operands) == 1:
            return operands[0]
        # A state name on the right of == / != is only known once the left side is typed.
        if any(o is None for o in operands):
            return None
        parts: list[m.Expr] = []
        for op, left, right in zip(e.ops, operands, operands[1:], strict=False):
            assert left is not None and right is not None
            lk, rk = self.kind_of(left), self.kind_of(right)
            if lk in ("task_state", "task_failure", *NAMED_STATES):
                allowed = m.TASK_STATES if lk == "task_state" else (
                    m.TASK_FAILURES if lk == "task_failure" else NAMED_STATES[lk])
                name = right.name if isinstance(right, m.StateName) else None
                if op not in ("==", "!=") or name not in allowed:
                    self.error(e, "VEPL-TYPE", f"expected '== STATE' with STATE one of "
                                               f"{', '.join(allowed)}, found '{op}' "
                                               f"{name or rk}" + did_you_mean(name or "", allowed))
                    return None
            elif lk != "num" or rk != "num":
                bad = rk if lk == "num" else lk
                shown = f"the name '{right.name}'" if isinstance(right, m.StateName) else \
                    f"a {bad} value"
                self.error(e, "VEPL-TYPE" if not isinstance(right, m.StateName) else
                           "VEPL-UNKNOWN", f"'{op}': expected numbers, found {shown}")
                return None
            parts.append(m.Compare(op, left, right))
        return parts[0] if len(parts) == 1 else m.BoolOp("and", tuple(parts))

    def _call(self, e: Any) -> m.Expr | None:
        name = e.function
        args = [self._expr(a) for a in e.args]
        if name in BUILTINS:
            arity = BUILTINS[name]
        elif name in self.functions:
            arity = self.functions[name]
        else:
            self.error(e, "VEPL-UNKNOWN", f"expected a function ({', '.join(BUILTINS)} or one "
                                          f"declared with 'function'), found '{name}'"
                       + did_you_mean(name, [*BUILTINS, *self.functions]))
            return None
        if len(args) != arity:
            self.error(e, "VEPL-ARITY", f"'{name}': expected {arity} argument(s), found "
                                        f"{len(args)}")
            return None
        if any(a is None for a in args):
            return None
        typed = [a for a in args if a is not None]
        kinds = [self.kind_of(a) for a in typed]
        expected = {"distance": ["robot", "var:object"], "on": ["robot", "var:floor"],
                    "state": ["var:task"], "failure": ["var:task"],
                    "approach": ["var:object"], "goal": ["var:floor"],
                    "neighbours": ["var:floor", "var:floor"]}.get(name)
        if name == "on" and kinds == ["var:object", "var:floor"]:
            expected = kinds  # the inverse map: the floor an object stands on (thesis 5.1)
        if expected is not None and kinds != expected:
            shown = {"robot": "robot", "var:object": "an object parameter",
                     "var:floor": "a floor parameter", "var:task": "a task parameter"}
            wanted = ", ".join(shown[k] for k in expected)
            if name == "on":
                wanted = "robot or an object parameter, a floor parameter"
            got = ", ".join(shown.get(k, "a " + k) for k in kinds)
            self.error(e, "VEPL-TYPE", f"'{name}': expected ({wanted}), found ({got})")
            return None
        return m.Call(name, tuple(typed), user=name not in BUILTINS)

    def _name(self, e: Any) -> m.Expr | None:
        name = e.name
        if name in self.scope:
            return m.Var(name)
        if name in self.parameters:
            return m.Num(self.parameters[name])
        if name in m.SCALAR_MEASURES or name in NAMED_STATES:
            return m.Measure(name)
        if name == ROBOT:
            return m.Var(ROBOT)
        states = {*m.TASK_STATES, *m.TASK_FAILURES,
                  *(s for v in NAMED_STATES.values() for s in v)}
        if name in states:
            return m.StateName(name)
        known = [*self.scope, *self.parameters, *m.SCALAR_MEASURES, *NAMED_STATES, ROBOT]
        self.error(e, "VEPL-UNKNOWN", f"expected a parameter, a query parameter or one of "
                                      f"{', '.join(m.SCALAR_MEASURES)}, found '{name}'"
                   + did_you_mean(name, known))
        return None

    # ---- events ----------------------------------------------------------------------------

    def _query_event(self, tx: Any) -> m.QueryEvent | None:
        query = self.tx_queries.get(tx.query)
        if query is None:
            self.error(tx, "VEPL-UNKNOWN", f"queryEvent '{tx.name}': expected a query name, "
                                           f"found '{tx.query}'" + did_you_mean(tx.query,
                                                                                self.tx_queries))
            return None
        args = list(tx.args or ())
        if len(tx.params) != len(args) or (args and list(tx.params) != args):
            self.error(tx, "VEPL-ARITY", f"queryEvent '{tx.name}': expected the event's "
                                         f"parameters passed on to the query, found "
                                         f"({', '.join(tx.params)}) and ({', '.join(args)})")
            return None
        if args and len(args) != len(query.params):
            self.error(tx, "VEPL-ARITY", f"queryEvent '{tx.name}': query '{tx.query}' expected "
                                         f"{len(query.params)} argument(s), found {len(args)}")
            return None
        return m.QueryEvent(tx.name, tx.query, tx.change == "found", bool(args), self.span(tx))

    def _event_ref(self, name: str, where: Any, defined: dict[str, str], later: dict[str, str],
                   what: str) -> bool:
        if name in defined:
            return True
        if name in later:
            self.error(where, "VEPL-ORDER", f"{what}: expected '{name}' defined before it is "
                                            f"used, found it defined further down")
        else:
            self.error(where, "VEPL-UNKNOWN", f"{what}: expected an event name, found "
                                              f"'{name}'" + did_you_mean(name, defined))
        return False

    def _complex_event(self, tx: Any, defined: dict[str, str], later: dict[str, str]
                       ) -> m.ComplexEvent | None:
        self.ce_name = tx.name
        pattern = self._pattern(tx.pattern, defined, later)
        if pattern is None:
            return None
        if _ends_in_unwindowed_not(pattern):
            self.error(tx.pattern, "VEPL-NOT-WINDOW",
                       f"complexEvent '{tx.name}': expected a time window [ms] around a pattern "
                       f"that ends in NOT (absence needs a deadline), found none")
            return None
        raw = (tx.event_context or "immediate").split()
        # The grammar's ContextName allows only these three words first.
        context: m.ContextKind = ("strict" if raw[0] == "strict"
                                  else "chronicle" if raw[0] == "chronicle" else "immediate")
        start, end = tx.pattern._tx_position, tx.pattern._tx_position_end
        text = " ".join(self.source.text[start:end].split())
        return m.ComplexEvent(tx.name, pattern, context, text, self.span(tx))

    def _limited(self, pattern: m.Pattern, where: Any) -> m.Pattern | None:
        """The pattern, or None with a VEPL-LIMIT when it is too big or too deep to run."""
        size, depth = pattern_measure(pattern)
        if size > MAX_PATTERN_SIZE:
            self.error(where, "VEPL-LIMIT", f"complexEvent '{self.ce_name}': expected a pattern "
                                            f"of at most {MAX_PATTERN_SIZE} parts with every "
                                            f"{{n}} and {{+}} written out, found {size}")
            return None
        if depth > MAX_PATTERN_DEPTH:
            self.error(where, "VEPL-LIMIT", f"complexEvent '{self.ce_name}': expected operators "
                                            f"nested at most {MAX_PATTERN_DEPTH} deep, found "
                                            f"{depth}")
            return None
        return pattern

    def _pattern(self, e: Any, defined: dict[str, str], later: dict[str, str]
                 ) -> m.Pattern | None:
        kind = type(e).__name__
        if kind in ("EventOr", "EventAnd", "EventSeq"):
            parts = [self._pattern(o, defined, later) for o in e.operands]
            if any(p is None for p in parts):
                return None
            valid = tuple(p for p in parts if p is not None)
            if len(valid) == 1:
                return valid[0]
            if kind == "EventOr":
                return self._limited(m.EvOr(valid), e)
            if kind == "EventAnd":
                return self._limited(m.EvAnd(valid), e)
            return self._limited(m.EvSeq(valid), e)
        if kind == "EventNot":
            inner = self._pattern(e.operand, defined, later)
            if inner is None or not e.negated:
                return inner
            return self._limited(m.EvNot(inner), e)
        if kind == "EventPostfix":
            result = self._pattern(e.base, defined, later)
            for s in e.suffixes:
                if result is None:
                    return None
                if type(s).__name__ == "TimeWindow":
                    ms = self.number(s.ms, s, "time window (ms)", low=-1e18, high=1e18)
                    if ms is None:
                        return None
                    if not 0 < ms <= MAX_WINDOW_MS:
                        self.error(s, "VEPL-WINDOW", f"expected a time window of more than 0 "
                                                     f"and at most {MAX_WINDOW_MS:g} ms, found "
                                                     f"{s.ms}")
                        return None
                    result = m.EvWindow(result, ms / 1000.0)
                elif s.plus:
                    result = m.EvRepeat(result, 1, False)
                elif s.star:
                    result = m.EvRepeat(result, 0, False)
                else:
                    n = self.number(s.count, s, "multiplicity", low=-1e18, high=1e18)
                    if n is None:
                        return None
                    if not (n.is_integer() and 1 <= n <= 100):
                        self.error(s, "VEPL-MULTIPLICITY", f"expected a whole multiplicity from "
                                                           f"1 to 100, found {s.count}")
                        return None
                    result = m.EvRepeat(result, int(n), True)
                # Checked after every suffix: a chain of a thousand {+} stops at the first
                # that is too much, before anything walks the whole chain.
                result = self._limited(result, s)
            return result
        if kind == "EventGroup":
            return self._pattern(e.inner, defined, later)
        if kind == "EventRef":
            ok = self._event_ref(e.name, e, defined, later, f"complexEvent '{self.ce_name}'")
            return m.EvRef(e.name) if ok else None
        raise AssertionError(kind)

    # ---- requirements ----------------------------------------------------------------------

    def _requirement(self, tx: Any, events: dict[str, str], later: dict[str, str]
                     ) -> m.Requirement | None:
        clauses: list[m.Clause] = []
        ok = True
        what = f"requirement '{tx.name}'"

        def ref(name: str, where: Any, queries_too: bool = False) -> bool:
            if queries_too and name in self.queries:
                return True
            return self._event_ref(name, where, events, later, what)

        for c in tx.clauses:
            kind = type(c).__name__
            if kind == "Never":
                ok &= ref(c.event, c)
                clauses.append(m.Never(c.event))
            elif kind == "Eventually":
                ok &= ref(c.event, c)
                clauses.append(m.Eventually(c.event))
            elif kind == "CountClause":
                ok &= ref(c.event, c)
                bound: float | None
                if c.bound.parameter is not None:
                    bound = self.parameters.get(c.bound.parameter)
                    if bound is None:
                        self.error(c.bound, "VEPL-UNKNOWN", f"{what}: expected a parameter, "
                                                           f"found '{c.bound.parameter}'"
                                   + did_you_mean(c.bound.parameter, self.parameters))
                else:
                    bound = self.number(c.bound.value, c.bound, "count bound", low=0, high=1e12)
                ok &= bound is not None
                clauses.append(m.CountBound(c.event, c.op, bound or 0.0))
            else:
                ok &= ref(c.trigger, c)
                for t in c.targets:
                    ok &= ref(t, c, queries_too=True)
                window = None
                if c.window is not None:
                    ms = self.number(c.window, c, "within (ms)", low=-1e18, high=1e18)
                    if ms is not None and not 0 < ms <= MAX_WINDOW_MS:
                        self.error(c, "VEPL-WINDOW", f"expected a time window of more than 0 and"
                                                     f" at most {MAX_WINDOW_MS:g} ms, found "
                                                     f"{c.window}")
                        ms = None
                    ok &= ms is not None
                    window = None if ms is None else ms / 1000.0
                clauses.append(m.Whenever(c.trigger, tuple(c.targets), window))
        premise = getattr(tx, "premise", None) or None
        if premise is not None and premise not in self.queries:
            self.error(tx, "VEPL-UNKNOWN", f"{what}: 'when' expected a query, found "
                                           f"'{premise}'" + did_you_mean(premise, self.queries))
            ok = False
        return m.Requirement(tx.name, tx.description or "", tuple(clauses),
                             self.span(tx), premise) if ok else None


def pattern_measure(p: m.Pattern) -> tuple[int, int]:
    """(size, depth) of a pattern: size counts the parts of the automaton the runtime builds
    from it ({n} repeats its operand n times, {+} is one copy and a {*}), depth the
    operators nested in each other. Only called on patterns whose parts passed the limits,
    so its recursion is bounded by MAX_PATTERN_DEPTH."""
    if isinstance(p, m.EvRef):
        return 1, 1
    if isinstance(p, m.EvSeq | m.EvAnd | m.EvOr):
        parts = [pattern_measure(x) for x in (p.options if isinstance(p, m.EvOr) else p.parts)]
        glue = 1 if isinstance(p, m.EvOr) else len(parts) - 1
        return sum(s for s, _ in parts) + glue, 1 + max(d for _, d in parts)
    size, depth = pattern_measure(p.operand)
    if isinstance(p, m.EvRepeat):
        if p.exact:
            return p.low * size + p.low - 1, depth + 1
        return (p.low + 1) * size + p.low + 1, depth + 1
    return size + 1, depth + 1


def condition_size(e: m.Expr) -> int:
    """Operators and operands of a condition, counted without recursion (a sum of thousands of
    terms is a left-nested chain thousands deep)."""
    count, stack = 0, [e]
    while stack:
        node = stack.pop()
        count += 1
        if isinstance(node, m.BoolOp):
            stack.extend(node.operands)
        elif isinstance(node, m.Not):
            stack.append(node.operand)
        elif isinstance(node, m.Compare | m.Arith):
            stack.extend((node.left, node.right))
        elif isinstance(node, m.Call):
            stack.extend(node.args)
    return count


def _ends_in_unwindowed_not(p: m.Pattern) -> bool:
    """True when a match could end on a pending NOT with no window to close it."""
    if isinstance(p, m.EvNot):
        return True
    if isinstance(p, m.EvSeq):
        return _ends_in_unwindowed_not(p.parts[-1])
    if isinstance(p, m.EvOr | m.EvAnd):
        parts = p.options if isinstance(p, m.EvOr) else p.parts
        return any(_ends_in_unwindowed_not(x) for x in parts)
    if isinstance(p, m.EvRepeat):
        return _ends_in_unwindowed_not(p.operand)
    return False


def link_vepl(tx: Any, source: SourceText, overrides: ParameterValues = ()
              ) -> tuple[m.Specification, list[Diagnostic]]:
    """The typed specification and every diagnostic; ``overrides`` (``--param``) replace the
    file's parameter values before any rule reads them."""
    linker = _Linker(source, overrides)
    spec = linker.link(tx)
    return spec, linker.diagnostics

