"""Live views of a run (issue 23.6): `rei watch` in a terminal and a Foxglove server.

``Watcher`` (rei.runtime.presentation.live.frames) monitors a stream with the run's own automata and
hands every ``View`` a ``WatchFrame`` per sample; ``RecordedSource`` plays a recording at a
chosen pace; ``TerminalView``/``LineView`` draw frames in a terminal; ``FoxgloveView`` serves
them to Foxglove on the recording's channels. Views only show what the monitor judged: they
never judge, and never import the simulator.
"""

from __future__ import annotations

from rei.runtime.presentation.live.frames import (
    ObjectState,
    StreamSource,
    View,
    Watcher,
    WatchError,
    WatchFrame,
)
from rei.runtime.presentation.live.sources import RecordedSource

__all__ = ["ObjectState", "RecordedSource", "StreamSource", "View", "WatchError",
           "WatchFrame", "Watcher"]
