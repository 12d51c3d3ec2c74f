"""The trace format's shared names: its tag and version, the older sample schema still read,
the outcomes and navigation states a line may name, and ``TraceError``. Every other module
of the package builds on these; this one imports none of them, and must never import the
simulation, pybullet or anything above the contracts.
"""

from __future__ import annotations

from typing import get_args

from rei.runtime.errors import RunError
from rei.runtime.messages import NavState
from rei.runtime.results import Outcome

FORMAT = "rei-trace"
TRACE_VERSION = 1
OUTCOMES: tuple[str, ...] = get_args(Outcome)
NAV_STATES: tuple[str, ...] = tuple(s.value for s in NavState)
PREVIOUS_SCHEMA = 3
"""The sample schema before the header named the collected data: read as collecting all."""


class TraceError(RunError):
    """A trace file cannot be read (or written): wrong format or version, or damaged."""
