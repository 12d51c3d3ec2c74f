"""A generated pair's continuous scenario parameters, beyond the room generator's factors:
when the humans start on their paths, when a stressor's mover sets off, and the sensor
faults the mission injects. `rei search` searches them as dimensions of the unit cube.

* ``phase`` (s): the time every generated human passes its first vertex. A human with an
  open path stands on its first tile until then; a looping human is already walking its
  loop and gets there at that time (its loop is shifted in time, its shape unchanged). The
  room file carries it as vertex times (``walker_1 ... at 4.2``) instead of a ``total``.
* ``stress_shift`` (s): the stressor's person sets off this much later (earlier when
  negative) than the generator timed it, so the encounter happens with the robot
  ``0.25 m/s x shift`` farther along its first leg (nearer the meeting point). The room
  file's mover times and its ``// stressor: meeting_s=`` carry it. A crossing cart is never
  delayed (it is timed to clear the robot's lane before a robot at top speed could be
  there); a shift that leaves a mover less than the generator's shortest wait is refused.
* ``KIND.PARAM`` (a fault kind of rei.lang.mission.faults and one of its parameters, e.g.
  ``laser_noise.sigma``): the mission gets a ``fault { }`` section with one entry per kind,
  active the whole run, its parameters set to the values chosen.

Each value is a ``LOW:HIGH`` range checked against the parameter's own limits (the fault
kinds' limits are the mission language's). The pair is written again and checked with the
`rei-gen check` rules by the caller. This module never touches files or random state.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace

from rei.generators.rooms.construct import RoomPlan
from rei.generators.rooms.descriptors import format_number
from rei.generators.rooms.space import Interval, ParameterError, parse_range
from rei.generators.rooms.stressors import MIN_WAIT, TimedMover, hold_times
from rei.lang.mission.faults import KINDS

PHASE = "phase"
STRESS_SHIFT = "stress_shift"
MAX_PHASE = 600.0
"""s: the latest start phase (a generated mission lasts minutes)."""
MAX_SHIFT = 60.0
"""s: the largest stressor shift either way."""


class ScenarioRefused(Exception):
    """These values cannot be put into this room (a candidate the search cannot build)."""


def fault_parameter(name: str) -> tuple[str, str] | None:
    """``KIND.PARAM`` -> (kind, parameter), or None for a name that is not a fault's."""
    kind, dot, param = name.partition(".")
    return (kind, param) if dot else None


def parse_scenario(name: str, text: str) -> Interval:
    """The range of one scenario parameter (an Interval called ``name``), checked;
    ParameterError names the option."""
    if name == PHASE:
        return parse_range("phase", name, text, 0.0, MAX_PHASE, False)
    if name == STRESS_SHIFT:
        return parse_range("stress-shift", name, text, -MAX_SHIFT, MAX_SHIFT, False)
    option = "fault-range"
    pair = fault_parameter(name)
    if pair is None:
        raise ParameterError(option, "KIND.PARAM=LOW:HIGH (e.g. laser_noise.sigma=0.01:0.1)",
                             f"'{name}={text}'")
    kind, param = pair
    spec = KINDS.get(kind)
    if spec is None:
        raise ParameterError(option, f"a fault kind ({', '.join(KINDS)})", f"'{kind}'")
    parameter = spec.parameter(param)
    if parameter is None:
        names = ", ".join(p.name for p in spec.parameters) or "none"
        raise ParameterError(option, f"a parameter of {kind} ({names})", f"'{param}'")
    return parse_range(option, name, text, parameter.low, parameter.high, parameter.low_open)


def check_faults(ranges: Sequence[Interval]) -> None:
    """Refuse fault kinds whose required parameters are not all searched (a fault entry
    with a parameter missing is not a mission), before any candidate is built."""
    searched: dict[str, set[str]] = {}
    for r in ranges:
        pair = fault_parameter(r.factor)
        if pair is not None:
            searched.setdefault(pair[0], set()).add(pair[1])
    for kind, params in searched.items():
        missing = [p.name for p in KINDS[kind].parameters
                   if p.default is None and p.name not in params]
        if missing:
            raise ParameterError("fault-range", f"a range for every required parameter of "
                                                f"{kind} (also {', '.join(missing)})",
                                 f"only {', '.join(sorted(params))}")


def apply_to_plan(plan: RoomPlan, values: Mapping[str, float]) -> RoomPlan:
    """The plan with the humans' phase and the stressor's shift put in; ScenarioRefused
    when this room cannot take them."""
    if PHASE in values:
        plan = replace(plan, humans=tuple(replace(h, start_s=values[PHASE])
                                          for h in plan.humans))
    shift = values.get(STRESS_SHIFT, 0.0)
    if STRESS_SHIFT in values and shift != 0.0:
        stress = plan.stressor
        if stress is None or stress.mover is None:
            raise ScenarioRefused("--stress-shift: expected a room with a stressor's mover "
                                  "(--stressor emerge, oncoming or crossing), found none")
        if stress.mover.role != "human" and shift > 0:
            raise ScenarioRefused("--stress-shift: a crossing cart is timed to clear the "
                                  "robot's lane first and cannot set off later; expected a "
                                  f"shift of at most 0 s, found {shift:g} s")
        plan = replace(plan, stressor=replace(stress, mover=shifted(stress.mover, shift),
                                              meeting_s=round(stress.meeting_s + shift, 3)))
    return plan


def shifted(mover: TimedMover, shift: float) -> TimedMover:
    """The mover setting off ``shift`` seconds later, its wait written as the generator
    writes it (``hold_times``)."""
    first = mover.vertices[0][0]
    hold = [t for c, t in mover.vertices if c == first]
    go = round(hold[-1] + shift, 3)  # the shift has 3 decimals: keep them all
    if go < MIN_WAIT:
        raise ScenarioRefused(f"--stress-shift: the mover would wait {go:g} s; expected at "
                              f"least {MIN_WAIT:g} s (a shift of at least "
                              f"{MIN_WAIT - hold[-1]:g} s here)")
    walk = [(c, round(t + shift, 3)) for c, t in mover.vertices[len(hold):]]
    return replace(mover, vertices=(*((first, t) for t in hold_times(go)), *walk))


def fault_section(values: Mapping[str, float]) -> list[str]:
    """The mission's ``fault { }`` lines for the fault parameters among ``values``."""
    entries: dict[str, list[str]] = {}
    for name in sorted(values):
        pair = fault_parameter(name)
        if pair is not None:
            entries.setdefault(pair[0], []).append(f"{pair[1]} {format_number(values[name])}")
    if not entries:
        return []
    return (["    fault {"] + [f"        {kind} {' '.join(params)}"
                               for kind, params in entries.items()] + ["    }"])


def with_faults(mission: str, values: Mapping[str, float]) -> str:
    """The mission text with its fault section before the first goal."""
    lines = fault_section(values)
    if not lines:
        return mission
    out = mission.splitlines()
    at = next(k for k, line in enumerate(out) if line.startswith("    goal "))
    return "\n".join([*out[:at], *lines, *out[at:]]) + "\n"


def comment(values: Mapping[str, float]) -> str:
    """The room file's ``// scenario:`` line (read back by ``read_metadata``)."""
    return "// scenario: " + " ".join(f"{k}={format_number(v)}" for k, v in sorted(values.items()))


__all__ = ["MAX_PHASE", "MAX_SHIFT", "PHASE", "STRESS_SHIFT",
           "ScenarioRefused", "apply_to_plan", "check_faults", "comment",
           "fault_section", "parse_scenario", "with_faults"]
