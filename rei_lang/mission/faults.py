"""Faults a mission injects (issue 17): what each kind is, its parameters, and their checks.

A fault is written as one entry of a mission's ``fault { }`` section, or as the text of one
``--fault`` option (the same grammar, ``grammars/mission_fault.tx``)::

    laser_poisson rate 20 gain 0.5 period 1 width 0.01
    laser_dropout as near_person share 0.3 when SIG_GEOM_FAR_TRANSIT_CLOSE for 2

``FaultDefinition`` is the checked, immutable definition: its kind, every parameter of that
kind (defaults filled in) and when it is active (``Activation``). The run-time models that
apply a definition live in ``rei.runtime.simulation.faults``; their semantics are in docs/faults.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Literal

from rei.lang.errors import Diagnostic, LanguageError, Span
from rei.lang.numbers import read_number
from rei.lang.suggest import did_you_mean

Channel = Literal["scan", "odometry", "command"]
MAX_FAULT_TIME = 1e7
"""Seconds: the latest a fault window may start or end, and the longest a duration or delay."""
MAX_NAME_LENGTH = 100
"""Characters of a fault's name at most (as a room's names): events.csv joins the active
faults' names into one field, which Python's csv reader refuses beyond 128 KiB."""
MIN_PERIOD = 0.01
"""Seconds: the shortest impulse period of ``laser_poisson``. The run lists every high phase
(timeline, samples), so a shorter one (1e-9 s) would make millions of phases a second and
hang the run; no sensor's impulse is faster than one physics step at 100 Hz."""


@dataclass(frozen=True)
class FaultParameter:
    """One parameter of a fault kind: its range, default (None: required), unit and meaning."""

    name: str
    low: float
    high: float
    default: float | None
    unit: str
    doc: str
    low_open: bool = False


@dataclass(frozen=True)
class FaultKind:
    kind: str
    channel: Channel
    """What the fault acts on: the robot's scans, its odometry, or its motors' commands."""
    summary: str
    parameters: tuple[FaultParameter, ...] = ()
    nonzero_one_of: tuple[str, ...] = ()
    """At least one of these parameters must be non-zero (a drift of nothing is a mistake)."""

    def parameter(self, name: str) -> FaultParameter | None:
        return next((p for p in self.parameters if p.name == name), None)


def _p(name: str, low: float, high: float, default: float | None, unit: str, doc: str,
       low_open: bool = False) -> FaultParameter:
    return FaultParameter(name, low, high, default, unit, doc, low_open)


FAULT_KINDS: tuple[FaultKind, ...] = (
    FaultKind("laser_poisson", "scan",
              "the thesis's error-prone proximity sensor (7.5): occurrences of a Poisson "
              "process, counted while an impulse is high, add gain x count to every range of "
              "the previous reading", (
                  _p("rate", 0.0, 1e4, None, "1/s", "occurrences per second while the impulse "
                     "is high", low_open=True),
                  _p("gain", -100.0, 100.0, None, "m", "metres added to every range per "
                     "occurrence (negative: obstacles look nearer)"),
                  _p("period", MIN_PERIOD, MAX_FAULT_TIME, 1.0, "s", "the impulse's period"),
                  _p("width", 0.0, 1.0, 1.0, "share", "the impulse's pulse width, a share of "
                     "the period (0.01 = 1 %)", low_open=True),
                  _p("phase", 0.0, MAX_FAULT_TIME, 0.0, "s", "delay of the first pulse after "
                     "the fault becomes active"),
              ), nonzero_one_of=("gain",)),
    FaultKind("laser_noise", "scan",
              "Gaussian noise on every range that hit something", (
                  _p("sigma", 0.0, 10.0, None, "m", "standard deviation", low_open=True),
              )),
    FaultKind("laser_dropout", "scan",
              "a share of beams, drawn anew for every scan, read the maximum range (nothing "
              "seen)", (
                  _p("share", 0.0, 1.0, None, "share", "probability that a beam is dropped",
                     low_open=True),
              )),
    FaultKind("laser_freeze", "scan",
              "the robot keeps getting the scan it had when the fault started (stamp "
              "included)"),
    FaultKind("laser_delay", "scan",
              "the robot gets the newest scan measured at least `seconds` ago", (
                  _p("seconds", 0.0, MAX_FAULT_TIME, None, "s", "the delay", low_open=True),
              )),
    FaultKind("laser_sector", "scan",
              "beams between two bearings (scanner frame, counter-clockwise from straight "
              "ahead) read a fixed distance: a blocked or dirty window", (
                  _p("min_deg", -360.0, 360.0, None, "deg", "first bearing of the sector"),
                  _p("max_deg", -360.0, 360.0, None, "deg", "last bearing of the sector"),
                  _p("distance", 0.0, 1e4, 0.0, "m", "what the blocked beams read (clipped to "
                     "the scanner's limits: 0 = its minimum range)"),
              )),
    FaultKind("odom_drift", "odometry",
              "odometry error that grows with the distance travelled and with time", (
                  _p("scale", -1.0, 1.0, 0.0, "share", "odometry reports (1 + scale) times "
                     "every step travelled"),
                  _p("yaw_per_metre", -360.0, 360.0, 0.0, "deg/m", "heading error added per "
                     "metre travelled"),
                  _p("walk", 0.0, 10.0, 0.0, "m/sqrt(s)", "random walk of the position: after "
                     "t seconds its standard deviation per axis is walk x sqrt(t)"),
              ), nonzero_one_of=("scale", "yaw_per_metre", "walk")),
    FaultKind("odom_jump", "odometry",
              "odometry jumps once, when the fault becomes active, and keeps the offset", (
                  _p("dx", -1e4, 1e4, 0.0, "m", "jump along the odometry frame's x"),
                  _p("dy", -1e4, 1e4, 0.0, "m", "jump along the odometry frame's y"),
                  _p("dyaw", -360.0, 360.0, 0.0, "deg", "turn of the reported heading"),
              ), nonzero_one_of=("dx", "dy", "dyaw")),
    FaultKind("cmd_drop", "command",
              "a share of velocity commands is lost: the motors keep the previous command "
              "that reached them", (
                  _p("share", 0.0, 1.0, None, "share", "probability that a command is lost",
                     low_open=True),
              )),
    FaultKind("cmd_delay", "command",
              "the motors get the command the robot asked for at least `seconds` ago (a stop "
              "before any is that old)", (
                  _p("seconds", 0.0, MAX_FAULT_TIME, None, "s", "the delay", low_open=True),
              )),
)
KINDS: dict[str, FaultKind] = {k.kind: k for k in FAULT_KINDS}
ACTIVATION_KEYWORDS = ("as", "from", "to", "when", "for", "until")


@dataclass(frozen=True)
class Activation:
    """When a fault acts. Without ``signal``: from ``start`` until ``end`` (None: the end of
    the run) or until ``stop`` fires. With ``signal``: each time it fires, for ``duration``
    seconds (a firing while active extends it), or until ``stop`` fires, or (neither) to the
    end of the run."""

    start: float = 0.0
    end: float | None = None
    signal: str | None = None
    duration: float | None = None
    stop: str | None = None

    def text(self) -> str:
        """The activation as written in a fault entry ('' when always active)."""
        if self.signal is not None:
            tail = (f" for {self.duration!r}" if self.duration is not None
                    else f" until {self.stop}" if self.stop is not None else "")
            return f"when {self.signal}{tail}"
        parts = []
        if self.start != 0.0:
            parts.append(f"from {self.start!r}")
        if self.end is not None:
            parts.append(f"to {self.end!r}")
        if self.stop is not None:
            parts.append(f"until {self.stop}")
        return " ".join(parts)


ALWAYS = Activation()


def activation_problems(a: Activation) -> list[str]:
    """What is wrong with an activation, as 'expected ..., found ...' messages."""
    out: list[str] = []
    for what, value in (("from", a.start), ("to", a.end), ("for", a.duration)):
        if value is not None and (not math.isfinite(value) or value < 0
                                  or value > MAX_FAULT_TIME):
            out.append(f"'{what}': expected a finite number >= 0 and <= {MAX_FAULT_TIME:g}, "
                       f"found {value!r}")
    if a.duration is not None and a.duration == 0:
        out.append(f"'for': expected a duration > 0, found {a.duration!r}")
    if a.end is not None and math.isfinite(a.start) and a.end <= a.start:
        out.append(f"'to': expected an end after the start {a.start!r}, found {a.end!r}")
    if a.signal is not None and (a.end is not None or a.start != 0.0):
        out.append("expected either a time window or a signal, found both")
    if a.signal is None and a.stop is not None and (a.end is not None or a.start != 0.0):
        out.append("'until': expected after 'when SIGNAL' or alone, found it with a time "
                   "window")
    if a.duration is not None and (a.signal is None or a.stop is not None):
        out.append("'for': expected after 'when SIGNAL' (and without 'until'), found it "
                   "elsewhere")
    if a.signal is not None and a.signal == a.stop:
        out.append(f"'until': expected a signal other than the one that starts the fault, "
                   f"found '{a.stop}' for both")
    for name in (a.signal, a.stop):
        if name is not None and not (name.isidentifier() and name.isascii()):
            out.append(f"expected a signal name (letters, digits, '_'), found '{name}'")
    return out


def parameter_problems(kind: str, values: dict[str, float]) -> list[tuple[str | None, str]]:
    """(parameter or None, message) for every problem of a kind's complete parameter set."""
    spec = KINDS.get(kind)
    if spec is None:
        return [(None, f"expected a fault kind ({', '.join(KINDS)}), found '{_shown(kind)}'"
                 + did_you_mean(kind, KINDS))]
    out: list[tuple[str | None, str]] = []
    for name, value in values.items():
        p = spec.parameter(name)
        if p is None:
            out.append((name, _unknown_parameter(spec, name)))
            continue
        too_low = value <= p.low if p.low_open else value < p.low
        if not math.isfinite(value) or too_low or value > p.high:
            out.append((name, f"{kind} {name} ({p.unit}): expected a finite number "
                        f"{'>' if p.low_open else '>='} {p.low:g} and <= {p.high:g}, found "
                        f"{value!r}"))
    for p in spec.parameters:
        if p.name not in values and p.default is None:
            out.append((None, f"{kind}: expected the parameter '{p.name}' ({p.doc}), found "
                       f"none"))
    defaults = {p.name: p.default for p in spec.parameters}
    given = all(n in values or defaults.get(n) is not None for n in spec.nonzero_one_of)
    if spec.nonzero_one_of and given and all(values.get(n, 0.0) == 0.0
                                             for n in spec.nonzero_one_of):
        out.append((None, f"{kind}: expected at least one of {', '.join(spec.nonzero_one_of)} "
                   f"not 0, found none (the fault would change nothing)"))
    if kind == "laser_sector" and values.get("min_deg", 0.0) > values.get("max_deg", 0.0):
        out.append(("max_deg", f"laser_sector: expected max_deg >= min_deg "
                    f"({values['min_deg']!r}), found {values['max_deg']!r}"))
    return out


def fault_name_problem(name: str) -> str | None:
    """What is wrong with a fault's name ('expected ..., found ...'), or None."""
    if not (name.isidentifier() and name.isascii()):
        return f"expected a fault name (letters, digits, '_'), found '{_shown(name)}'"
    if len(name) > MAX_NAME_LENGTH:
        return (f"expected a fault name of at most {MAX_NAME_LENGTH} characters, found "
                f"{len(name)} ('{_shown(name)}')")
    return None


def _unknown_parameter(spec: FaultKind, name: str) -> str:
    names = [p.name for p in spec.parameters]
    accepted = ", ".join(names) if names else "none"
    return (f"{spec.kind}: expected a parameter of {spec.kind} ({accepted}), found "
            f"'{_shown(name)}'" + did_you_mean(name, names))


def _shown(name: str) -> str:
    """A name as quoted in a message: a 100,000-letter one is not echoed whole."""
    return name if len(name) <= 60 else name[:57] + "..."


@dataclass(frozen=True)
class FaultDefinition:
    """One fault: its kind, every parameter of the kind (defaults filled in, in the kind's
    order), when it is active, and its name (the kind unless named with ``as``). Building one
    with a bad value raises LanguageError naming the field."""

    kind: str
    params: tuple[tuple[str, float], ...] = ()
    activation: Activation = ALWAYS
    name: str = ""
    span: Span | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        values = dict(self.params)
        problems = [m for _, m in parameter_problems(self.kind, values)]
        if len(values) != len(self.params):
            problems.append(f"{self.kind}: expected each parameter once, found "
                            f"{[n for n, _ in self.params]}")
        problems.extend(activation_problems(self.activation))
        if self.name and fault_name_problem(self.name) is not None:
            problems.append(str(fault_name_problem(self.name)))
        if problems:
            where = self.span or Span.point("<fault>")
            raise LanguageError([Diagnostic(where, "FAULT-PARAM", m) for m in problems])
        spec = KINDS[self.kind]
        full = tuple((p.name, float(values[p.name] if p.name in values
                                    else p.default))  # type: ignore[arg-type]
                     for p in spec.parameters)
        object.__setattr__(self, "params", full)
        object.__setattr__(self, "name", self.name or self.kind)

    @staticmethod
    def of(kind: str, activation: Activation = ALWAYS, name: str = "",
           **params: float) -> FaultDefinition:
        """A definition from Python: ``FaultDefinition.of("laser_dropout", share=0.3)``."""
        return FaultDefinition(kind, tuple(params.items()), activation, name)

    @property
    def channel(self) -> Channel:
        return KINDS[self.kind].channel

    def value(self, name: str) -> float:
        """A parameter's value; KeyError names the kind's parameters for a wrong name."""
        for key, value in self.params:
            if key == name:
                return value
        raise KeyError(_unknown_parameter(KINDS[self.kind], name))

    def text(self) -> str:
        """The definition as one fault entry (what ``parse_fault_option`` reads back)."""
        spec = KINDS[self.kind]
        words = [self.kind]
        if self.name != self.kind:
            words.append(f"as {self.name}")
        for p in spec.parameters:
            value = self.value(p.name)
            if p.default is None or value != p.default:
                words.append(f"{p.name} {value!r}")
        tail = self.activation.text()
        return " ".join(words + ([tail] if tail else []))


# ---- from the parsed text -------------------------------------------------------------------

Number = Callable[..., float | None]


def link_fault_entry(entry: Any, span: Callable[[Any], Span],
                     diagnostics: list[Diagnostic]) -> FaultDefinition | None:
    """One parsed fault entry as a definition, or None with located diagnostics."""
    before = len(diagnostics)

    def number(text: str, obj: Any, what: str, **bounds: Any) -> float | None:
        return read_number(text, span(obj), what, diagnostics, **bounds)

    kind = entry.kind.name
    spec = KINDS.get(kind)
    if spec is None:
        message = parameter_problems(kind, {})[0][1]
        if any(k.parameter(kind) for k in FAULT_KINDS):
            message += f" (a parameter is followed by its number: '{kind} 0.5')"
        diagnostics.append(Diagnostic(span(entry.kind), "FAULT-KIND", message))
        return None
    values: dict[str, float] = {}
    where: dict[str, Span] = {}
    for param in entry.params:
        p = spec.parameter(param.name)
        if p is None:
            diagnostics.append(Diagnostic(span(param), "FAULT-PARAM",
                                          _unknown_parameter(spec, param.name)))
            continue
        if param.name in where:
            diagnostics.append(Diagnostic(span(param), "OPTION-REPEAT",
                                          f"{kind}: expected one '{param.name}', found another "
                                          f"(first at line {where[param.name].line})"))
            continue
        where[param.name] = span(param)
        value = number(param.value, param, f"{kind} {param.name} ({p.unit})", low=p.low,
                       high=p.high, low_open=p.low_open)
        if value is not None:
            values[param.name] = value
    if len(diagnostics) == before:
        for name, message in parameter_problems(kind, values):
            diagnostics.append(Diagnostic(where[name] if name in where else span(entry.kind),
                                          "FAULT-PARAM", message))
    activation = _activation(entry.activation, span, number, diagnostics)
    wrong = fault_name_problem(entry.label) if entry.label else None
    if wrong is not None:
        diagnostics.append(Diagnostic(span(entry), "FAULT-PARAM", wrong))
    if len(diagnostics) != before or activation is None:
        return None
    return FaultDefinition(kind, tuple(values.items()), activation, entry.label or "",
                           span(entry))


def _activation(item: Any, span: Callable[[Any], Span], number: Number,
                diagnostics: list[Diagnostic]) -> Activation | None:
    if item is None:
        return ALWAYS
    kind = type(item).__name__
    if kind == "FaultTrigger":
        duration = None
        if item.duration is not None:
            duration = number(item.duration, item, "'for' (seconds)", low=0.0,
                              high=MAX_FAULT_TIME, low_open=True)
            if duration is None:
                return None
        activation = Activation(signal=item.signal, duration=duration, stop=item.stop)
    elif kind == "FaultUntil":
        activation = Activation(stop=item.stop)
    else:
        start = end = None
        if item.start is not None:
            start = number(item.start, item, "'from' (seconds)", low=0.0, high=MAX_FAULT_TIME)
        if item.end is not None:
            end = number(item.end, item, "'to' (seconds)", low=0.0, high=MAX_FAULT_TIME)
        if (item.start is not None and start is None) or (item.end is not None and end is None):
            return None
        activation = Activation(start=start or 0.0, end=end)
    problems = activation_problems(activation)
    for message in problems:
        diagnostics.append(Diagnostic(span(item), "FAULT-ACTIVATION", message))
    return None if problems else activation


def link_fault_section(section: Any, span: Callable[[Any], Span],
                       diagnostics: list[Diagnostic],
                       names: dict[str, Span]) -> list[FaultDefinition]:
    """The definitions of a ``fault { }`` section; every name unique across ``names``."""
    out: list[FaultDefinition] = []
    for entry in section.entries:
        name = entry.label or entry.kind.name
        where = span(entry)
        if name in names:
            hint = "" if entry.label else f"; name one with '{entry.kind.name} as NAME'"
            diagnostics.append(Diagnostic(where, "NAME-UNIQUE",
                                          f"expected a unique fault name, found '{name}' again "
                                          f"(first at line {names[name].line}){hint}"))
        names.setdefault(name, where)
        definition = link_fault_entry(entry, span, diagnostics)
        if definition is not None:
            out.append(definition)
    return out


def parse_fault_option(text: str) -> FaultDefinition:
    """One fault entry written on the command line (``--fault 'laser_dropout share 0.3'``),
    with the grammar and checks of a mission's fault section; LanguageError, located in the
    option's text (file ``--fault``), when it is not valid."""
    from rei.lang.parsing import parse, span_of
    from rei.lang.source import SourceText

    source = SourceText("--fault", text)
    if not text.strip():
        raise LanguageError([Diagnostic(Span.point("--fault"), "SYNTAX",
                                        "expected a fault kind and its parameters "
                                        "('laser_dropout share 0.3'), found nothing")])
    parsed = parse("mission_fault", source)
    if isinstance(parsed, Diagnostic):
        raise LanguageError([parsed])
    diagnostics: list[Diagnostic] = []
    definition = link_fault_entry(parsed.entry, lambda o: span_of(o, source), diagnostics)
    if definition is None:
        raise LanguageError(diagnostics)
    return definition


FAULT_OPTION_HELP = ("a fault to inject, written as one entry of a mission's fault section, "
                     "e.g. 'laser_dropout share 0.3 when SIG_GEOM_FAR_TRANSIT_CLOSE for 2' "
                     f"(repeatable; kinds: {', '.join(KINDS)}; see docs/faults.md)")
"""The ``--help`` text of a ``--fault`` option, for every command that takes one."""


def fault_argument(text: str) -> FaultDefinition:
    """``parse_fault_option`` as an argparse ``type``: a bad fault is a usage error whose
    message says where in the option's text, what was expected and what was found."""
    import argparse  # noqa: PLC0415

    try:
        return parse_fault_option(text)
    except LanguageError as err:
        raise argparse.ArgumentTypeError(
            "; ".join(f"column {d.span.col}: {d.message}" for d in err.diagnostics)) from None
