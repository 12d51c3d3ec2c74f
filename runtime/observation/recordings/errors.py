"""The recording stage's root error.

Every stage has an errors.py of its own (one error class per stage, all under
``rei.lang.errors.ReiError``, as STYLE.md asks), so this file name repeats on purpose.
"""

from __future__ import annotations

from rei.runtime.trace import TraceError


class RecordingError(TraceError):
    """An MCAP recording cannot be written or read: not MCAP, damaged, or without the REI
    trace. A ``TraceError``: whatever reads a trace reports it the same way."""
