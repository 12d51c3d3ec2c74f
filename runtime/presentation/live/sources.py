"""Where a watched stream comes from: a recorded run (trace.jsonl or recording.mcap), paced,
or a run on the bus.

``RecordedSource`` reads a recording with the trace's own rules (``read_stream``: every
field checked, a damaged line refused with its path and line) and hands its samples on at
``speed`` times real time (0: as fast as they are read), so a recorded run plays on the
screen as it ran. Pacing is the only place a view touches the wall clock; the samples and
everything judged from them are the recording's. This module must never import the
simulator.
"""

from __future__ import annotations

import math
import time as wallclock
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.presentation.live.frames import End, WatchError

SILENCE = 60.0
"""Wall seconds without a sample after which a run on the bus counts as cut off (as `rei
monitor`'s default)."""
HEADER_TIMEOUT = 10.0
"""Wall seconds a viewer that joined a run under way waits for the header it asks for."""


class Pacer:
    """Holds a stream back so simulated time passes ``speed`` times faster than wall time."""

    def __init__(self, speed: float, clock: Callable[[], float] = wallclock.monotonic,
                 sleep: Callable[[float], None] = wallclock.sleep) -> None:
        if not math.isfinite(speed) or speed < 0:
            raise ValueError(f"a speed expected to be a finite number >= 0, found {speed!r}")
        self.speed = speed
        self.clock = clock
        self.sleep = sleep
        self._origin: tuple[float, float] | None = None

    def wait(self, sim_time: float) -> None:
        if self.speed == 0:
            return
        now = self.clock()
        if self._origin is None:
            self._origin = (now, sim_time)
            return
        wall0, sim0 = self._origin
        due = wall0 + (sim_time - sim0) / self.speed
        if due > now:
            self.sleep(due - now)


class RecordedSource:
    """A ``StreamSource`` reading a trace.jsonl or an MCAP recording (``rei run --record``)."""

    def __init__(self, path: Path, speed: float = 1.0,
                 clock: Callable[[], float] = wallclock.monotonic,
                 sleep: Callable[[float], None] = wallclock.sleep) -> None:
        self.path = path
        self.pacer = Pacer(speed, clock, sleep)
        self.speed: float | None = speed if speed > 0 else None
        self.where = f"the recording '{path}'"
        self._samples: Iterator[Sample] | None = None
        self._end: Callable[[], End | None] = lambda: None
        self._last = 0.0

    def open(self) -> tuple[StreamHeader, Iterator[Sample]]:
        from rei.runtime.observation.recordings import read_stream  # noqa: PLC0415

        header, samples, read_end = read_stream(self.path)
        self._samples, self._end = samples, read_end
        return header, self._paced(samples)

    def _paced(self, samples: Iterator[Sample]) -> Iterator[Sample]:
        for sample in samples:
            self.pacer.wait(sample.time)
            self._last = sample.time
            yield sample

    def end(self) -> End | None:
        """The end line; for a recording cut short by a crash, the run as interrupted where
        its last complete chunk ends (as `rei replay` judges it)."""
        end = self._end()
        cut = getattr(self._samples, "cut_short", "")
        if end is None and cut:
            return (self._last, "interrupted", cut)
        return end

    def close(self) -> None:
        close = getattr(self._samples, "close", None)
        if close is not None:
            close()


class BusSource:
    """A ``StreamSource``: the run a simulation publishes on a bus (`rei run --bus`), joined
    as a viewer (the role that only reads). The stream is the trace the simulation publishes
    on ``rei/v1/trace``, taken in by `rei monitor`'s own ``TraceStream``: decoded by the
    trace's rules, with what the network lost, duplicated or reordered counted (the summary's
    ``bus`` measurement); a viewer that joins a run under way asks for its header and
    watches from there (the samples it missed count as missing: no verdict rests on them).
    """

    speed: float | None = None

    def __init__(self, endpoint: str, credentials: Path | None,
                 silence: float = SILENCE) -> None:
        self.endpoint = endpoint
        self.credentials = credentials
        self.silence = silence
        self.where = f"the run on the bus at {endpoint}"
        self._session: Any = None
        self._stream: Any = None

    def open(self) -> tuple[StreamHeader, Iterator[Sample]]:
        from rei.runtime.bus import BusError, connect  # noqa: PLC0415  (the bus extra)
        from rei.runtime.bus.reception import TraceStream, ask_header  # noqa: PLC0415
        from rei.runtime.bus.schema import TRACE, config_key  # noqa: PLC0415

        try:
            self._session = connect(self.endpoint, role="viewer",
                                    credentials=self.credentials)
            self._stream = TraceStream(ask_header(self._session.call, config_key("trace"),
                                                  HEADER_TIMEOUT), self.silence)
            self._session.subscribe_raw(TRACE, self._stream.receive)
            header = self._stream.header()
        except BusError as exc:
            raise WatchError(str(exc)) from None
        return header, self._stream.samples()

    def end(self) -> End | None:
        return self._stream.read_end() if self._stream is not None else None

    def measurements(self) -> dict[str, Any]:
        """What the network did (`rei monitor`'s ``bus`` measurement)."""
        if self._stream is None:
            return {}
        dropped = self._session.dropped if self._session is not None else 0
        return {"bus": {**self._stream.measurements(), "dropped": dropped}}

    def close(self) -> None:
        session, self._session = self._session, None
        if session is not None:
            session.close()
