"""The monitor: the runtime model, exact footprint geometry, query evaluation and the host
that runs the event automata generated from a .vepl file (thesis 5.1.3-5.1.6).

``MonitorSink`` is a sample sink (start / feed / finish) that writes events.csv and gives
the monitor's part of the run summary. It must never import the simulator: live runs and
replayed traces go through exactly the same code.
"""

from __future__ import annotations

from typing import Any

__all__ = ["AutomataHost", "MonitorSink", "generate_automata"]


def __getattr__(name: str) -> Any:
    # The host (reactivex, the evaluator, the runtime model) is imported when first asked
    # for: ``needs`` and ``functions``, which the command line imports to check options, stay
    # light.
    if name in __all__:
        from rei.runtime.observation.monitor import automata_host as host  # noqa: PLC0415

        return getattr(host, name)
    raise AttributeError(name)
