"""The faults of one run: the mission's fault section and ``--fault``, checked together.

Before a run is started, every fault it will inject is checked against what the run can
deliver: names unique across the mission and the command line (the summary, events.csv and
the report tell faults by name), and every signal that starts or stops a fault defined by
the monitoring specification. A fault waiting for a signal nobody raises would never act and
the run would look like a fault study while testing nothing: refused (``FAULT-SIGNAL``),
never silently run.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

import numpy as np

from rei.lang.errors import Diagnostic, LanguageError, Span
from rei.lang.mission.faults import FaultDefinition
from rei.lang.suggest import did_you_mean


def run_faults(mission: Iterable[FaultDefinition], extra: Iterable[FaultDefinition],
               signals: Sequence[str] | None, mission_file: str,
               specification: str, end: float | None = None,
               periods: tuple[float, float, float] | None = None,
               beams: tuple[float, float, int] | None = None) -> tuple[FaultDefinition, ...]:
    """The mission's faults then ``extra`` (``--fault``), checked: ``signals`` are the
    names the monitoring ``specification`` defines, None when the run is not monitored;
    ``end`` the simulated second the run stops at the latest (its time limit or duration);
    ``periods`` (seconds; see ``_too_short``): a window no fault call falls in is refused;
    ``beams`` the scanner's (angle_min, angle_increment, count): a sector holding none is.
    LanguageError (FAULT-NAME, FAULT-SIGNAL, FAULT-WINDOW), located at each fault, when a
    check fails."""
    own, added = tuple(mission), tuple(extra)
    problems: list[Diagnostic] = []
    seen: set[str] = set()
    for k, fault in enumerate(own + added):
        where = fault.span or Span.point(mission_file if k < len(own) else "--fault")
        if fault.name in seen:
            problems.append(Diagnostic(where, "FAULT-NAME", (
                f"expected a fault name no other fault of the run has, found '{fault.name}' "
                f"twice (the mission's fault section and --fault together; name one with "
                f"'as NAME')")))
        seen.add(fault.name)
        start = fault.activation.start
        if end is not None and fault.activation.signal is None and start >= end:
            problems.append(Diagnostic(where, "FAULT-WINDOW", (
                f"expected the fault '{fault.name}' to start before the run ends at {end:g} s "
                f"(the time limit or --duration), found 'from {start:g}' (the fault would "
                f"never act)")))
        short = None if periods is None else _too_short(fault, periods)
        if short is not None:
            problems.append(Diagnostic(where, "FAULT-WINDOW", short))
        if beams is not None and fault.kind == "laser_sector" and not _covers_a_beam(fault,
                                                                                      beams):
            low, high = fault.value("min_deg"), fault.value("max_deg")
            problems.append(Diagnostic(where, "FAULT-PARAM", (
                f"expected the sector of the fault '{fault.name}' to hold a beam of the "
                f"scanner (one every {math.degrees(beams[1]):g} deg), found "
                f"[{low:g}, {high:g}] deg between two (the fault would never act)")))
        for signal in (fault.activation.signal, fault.activation.stop):
            if signal is None:
                continue
            if signals is None:
                problems.append(Diagnostic(where, "FAULT-SIGNAL", (
                    f"expected a monitored run for the fault '{fault.name}', which waits for "
                    f"the signal {signal}, found --no-monitor (no signal ever fires)")))
            elif signal not in signals:
                hint = did_you_mean(signal, signals)
                problems.append(Diagnostic(where, "FAULT-SIGNAL", (
                    f"expected a signal of the specification {specification} for the fault "
                    f"'{fault.name}', found {signal}, which it does not define (the fault "
                    f"would never act){hint}")))
    if problems:
        raise LanguageError(problems)
    return own + added


def _too_short(fault: FaultDefinition, periods: tuple[float, float, float]) -> str | None:
    """Why ``fault``'s window is too short to act in, or None. ``periods``: the shortest
    time from a sample (where a signal fires) to the next control tick after it, the control
    tick and the scan period. The stage acts at control ticks (a scan fault once per new
    scan, a delay every tick); a signal fired at a sample acts from the next tick after it.
    A Poisson fault counts occurrences in continuous time: any window of it can act."""
    if fault.kind == "laser_poisson":
        return None
    gap, tick, scan = periods
    a = fault.activation
    if a.duration is not None and a.duration <= gap + 1e-9:
        return (f"expected 'for' longer than {gap:g} s for the fault '{fault.name}', found "
                f"{a.duration:g} s (a signal acts from the next control tick after the sample "
                f"it fired at, {gap:g} s later or more, so the fault would never act)")
    per_scan = fault.channel == "scan" and fault.kind != "laser_delay"
    period, what = (scan, "scan") if per_scan else (tick, "control tick")
    if a.signal is None and a.end is not None:
        first = math.ceil(a.start / period - 1e-9) * period
        if first >= a.end - 1e-9:
            return (f"expected the window of the fault '{fault.name}' to hold a {what} "
                    f"(every {period:g} s), found 'from {a.start:g} to {a.end:g}' (the fault "
                    f"would never act)")
    return None


def _covers_a_beam(fault: FaultDefinition, beams: tuple[float, float, int]) -> bool:
    """Whether a ``laser_sector`` covers at least one beam of a scanner laid out as
    ``beams``, by the model's own rule (``LaserSector.beams``)."""
    from rei.runtime.messages import LaserScan  # noqa: PLC0415
    from rei.runtime.simulation.faults.activation import ActivationTracker  # noqa: PLC0415
    from rei.runtime.simulation.faults.models import LaserSector  # noqa: PLC0415

    angle_min, increment, count = beams
    probe = LaserScan(angle_min, increment, 0.0, 1.0, np.zeros(count))
    return bool(LaserSector(fault, ActivationTracker(fault.activation),
                            np.random.default_rng(0)).covers(probe).any())
