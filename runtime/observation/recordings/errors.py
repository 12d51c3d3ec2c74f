"""The recording stage's root error."""

from __future__ import annotations

from rei.runtime.trace import TraceError


class RecordingError(TraceError):
    """An MCAP recording cannot be written or read: not MCAP, damaged, or without the REI
    trace. A ``TraceError``: whatever reads a trace reports it the same way."""
