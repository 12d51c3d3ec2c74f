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
import queue
import time as wallclock
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.views.frames import End, WatchError


class WatchStopped(WatchError):
    """The user stopped watching before a stream began."""


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
        self._samples: Iterator[Sample] | None = None
        self._end: Callable[[], End | None] = lambda: None

    def open(self) -> tuple[StreamHeader, Iterator[Sample]]:
        from rei.runtime.recording import read_stream  # noqa: PLC0415

        header, samples, read_end = read_stream(self.path)
        self._samples, self._end = samples, read_end
        return header, self._paced(samples)

    def _paced(self, samples: Iterator[Sample]) -> Iterator[Sample]:
        for sample in samples:
            self.pacer.wait(sample.time)
            yield sample

    def end(self) -> End | None:
        return self._end()

    def close(self) -> None:
        close = getattr(self._samples, "close", None)
        if close is not None:
            close()


class BusSource:
    """A ``StreamSource``: the run a simulation publishes on a bus (`rei run --bus`), joined
    as a viewer (the role that only reads). The stream is the trace the simulation publishes
    on ``rei/v1/trace`` line by line, decoded by the trace's own rules; a viewer that joins
    while a run is under way waits for the next run's header. ``stop()`` is asked while
    waiting, so a user can give up."""

    speed: float | None = None

    def __init__(self, endpoint: str, credentials: Path | None,
                 stop: Callable[[], bool] = lambda: False) -> None:
        self.endpoint = endpoint
        self.credentials = credentials
        self.stop = stop
        self._session: Any = None
        self._lines: queue.Queue[bytes] = queue.Queue()
        self._end: End | None = None
        self.skipped = 0
        """Lines of a run already under way when the viewer joined."""

    def open(self) -> tuple[StreamHeader, Iterator[Sample]]:
        from rei.runtime.bus import BusError, connect  # noqa: PLC0415  (the bus extra)
        from rei.runtime.bus.schema import TRACE  # noqa: PLC0415
        from rei.runtime.collector.trace import TraceDecoder  # noqa: PLC0415

        try:
            self._session = connect(self.endpoint, role="viewer",
                                    credentials=self.credentials)
            self._session.subscribe_raw(TRACE, lambda _key, payload: self._lines.put(payload))
        except BusError as exc:
            raise WatchError(str(exc)) from None
        where = f"{self.endpoint} {TRACE}"
        while True:
            first = self._next()
            if first is None:
                raise WatchStopped("stopped waiting for a run on the bus")
            if first.startswith(b'{"format":'):
                break
            self.skipped += 1
        decoder = TraceDecoder(first, f"{where} (header)")
        return decoder.header, self._samples(decoder, where)

    def _next(self) -> bytes | None:
        while True:
            try:
                return self._lines.get(timeout=0.1)
            except queue.Empty:
                if self.stop():
                    return None

    def _samples(self, decoder: Any, where: str) -> Iterator[Sample]:
        n = 1
        while True:
            raw = self._next()
            if raw is None:
                return
            n += 1
            record = decoder.line(raw, f"{where} line {n}")
            if not isinstance(record, Sample):
                self._end = record
                return
            yield record

    def end(self) -> End | None:
        return self._end

    def close(self) -> None:
        session, self._session = self._session, None
        if session is not None:
            session.close()
