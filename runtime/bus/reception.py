"""A run's trace as it arrives over the bus, with what was lost on the way (`rei monitor`).

``TraceStream`` takes the payloads of ``rei/v1/trace`` in the order they arrive (from
Zenoh's thread: ``receive`` only queues) and gives the monitor the header and the samples,
decoded and checked by the trace's own rules (``TraceDecoder``). What the network did is
counted, never guessed over: a sample whose sequence number was already seen is a
duplicate, one older than the newest seen a reordered one (both dropped: the monitor's
clock only goes forward), and the numbers never seen are missed, as are those after a gap
until the next keyframe (every object's row; the lines carry only the changed ones) — the
monitor's own
``missing`` count then makes every verdict that rests on something not happening
inconclusive, never a pass. A monitor that joins late asks for the header
(``config/trace``) and misses the samples before its first; one the bus cuts off (nothing
for ``silence`` wall seconds) ends the stream as interrupted, naming the last sample seen.
This module must never import pybullet.
"""

from __future__ import annotations

import json
import queue
import time
from collections.abc import Callable, Iterator
from typing import Any

import numpy as np

from rei.runtime.bus.errors import BusError
from rei.runtime.messages import Sample, StreamHeader
from rei.runtime.trace import TraceDecoder, TraceError

End = tuple[float, str, str]


def ranges(numbers: list[int]) -> list[list[int]]:
    """Sorted whole numbers as [first, last] runs: [0, 1, 2, 5] -> [[0, 2], [5, 5]]."""
    out: list[list[int]] = []
    for n in sorted(numbers):
        if out and n == out[-1][1] + 1:
            out[-1][1] = n
        else:
            out.append([n, n])
    return out


class TraceStream:
    """The trace of one run from the bus (see the module's docstring)."""

    def __init__(self, ask_header: Callable[[], bytes], silence: float,
                 where: str = "rei/v1/trace") -> None:
        self._queue: queue.SimpleQueue[bytes] = queue.SimpleQueue()
        self._ask_header = ask_header
        self.silence = silence
        self.where = where
        self.decoder: TraceDecoder | None = None
        self.end: End | None = None
        self.received = 0
        self.missed: list[int] = []
        self.duplicated = 0
        self.reordered = 0
        self.malformed = 0
        self.last_problem = ""
        self._next = 0
        """The sequence number expected next."""
        self._seen: set[int] = set()
        self.cut = ""
        """Why the stream ended without its end line ('' when it has one)."""
        self._lost = False
        """A sample was missed and no keyframe has let the lines be read since."""
        self._keyframe: dict[str, Any] | None = None
        self.lines: list[bytes] = []
        """The lines judged (header first, end last when it came): trace.jsonl's own
        bytes when nothing was missed."""
        self.total: int | None = None
        """The samples the run published (its count line, just before the end line)."""
        self.last_time = 0.0

    def receive(self, key: str, payload: bytes) -> None:
        """Zenoh's thread: queue the payload."""
        self._queue.put(payload)

    def _get(self) -> bytes | None:
        try:
            return self._queue.get(timeout=self.silence)
        except queue.Empty:
            return None

    def header(self) -> StreamHeader:
        """The header: the stream's first line, or asked for when the first line is a
        sample (the monitor joined late). Waits as long as it takes for the first line."""
        first = self._queue.get()
        data = self._peek(first)
        if isinstance(data, dict) and "format" in data:
            head = first
        else:
            head = self._ask_header()
            self._queue_first = first
        self.decoder = TraceDecoder(head, f"{self.where}:header")
        self.lines.append(head)
        return self.decoder.header

    _queue_first: bytes | None = None

    @staticmethod
    def _peek(payload: bytes) -> Any:
        try:
            return json.loads(payload)
        except (UnicodeDecodeError, ValueError, RecursionError):
            return None

    def samples(self) -> Iterator[Sample]:
        """The samples in order, until the end line (``end``) or silence (``cut``)."""
        assert self.decoder is not None, "header() first"
        pending = self._queue_first
        while True:
            payload = pending if pending is not None else self._get()
            pending = None
            if payload is None:
                self.cut = (f"the bus went silent for {self.silence:g} s after sample "
                            f"{self._next - 1} (the monitor was cut off, or the run died)")
                return
            data = self._peek(payload)
            if isinstance(data, dict) and "keyframe" in data:
                self._keyframe = data
                continue
            if isinstance(data, dict) and set(data) == {"samples"}:
                total = data["samples"]
                if isinstance(total, int) and not isinstance(total, bool) and total >= 0:
                    self.total = total
                else:
                    self._malformed(f"{self.where}: a sample count expected, found {total!r}")
                continue
            if isinstance(data, dict) and "end" in data:
                try:
                    record = self.decoder.line(payload, f"{self.where}:end")
                except TraceError as exc:
                    self._malformed(str(exc))
                    continue
                assert not isinstance(record, Sample)
                if self.total is not None and self._next < self.total:
                    # the last samples never came: the run's end is known, what led to
                    # it is not, so the stream is judged as cut there
                    self.missed.extend(range(self._next, self.total))
                    self.cut = (f"the monitor missed the last samples ({self._next} to "
                                f"{self.total - 1}) before the run's end")
                    return
                self.end = record
                self.lines.append(payload)
                return
            seq = data.get("seq") if isinstance(data, dict) else None
            if not isinstance(seq, int) or isinstance(seq, bool) or seq < 0:
                self._malformed(f"{self.where}: a sample line with a seq expected")
                continue
            if seq < self._next:
                if seq in self._seen:
                    self.duplicated += 1
                else:  # it came after all, too late to be judged: still missed
                    self.reordered += 1
                continue
            if seq > self._next or self._lost:
                # rows are changes: after a gap only a keyframe of this very sample lets
                # the line be read
                self.missed.extend(range(self._next, seq))
                if not self._resume(seq):
                    self._lost = True
                    self.missed.append(seq)
                    self._next = seq + 1
                    continue
                self._lost = False
            try:
                sample = self.decoder.line(payload, f"{self.where}:seq {seq}")
            except TraceError as exc:
                self._malformed(str(exc))
                self._lost = True  # the rows of the next lines rest on this one
                self.missed.append(seq)
                self._next = seq + 1
                continue
            assert isinstance(sample, Sample)
            self._seen.add(seq)
            self._next = seq + 1
            self.received += 1
            self.last_time = sample.time
            self.lines.append(payload)
            yield sample

    def _resume(self, seq: int) -> bool:
        """Whether the last keyframe is of sample ``seq`` and the decoder now reads on
        from it."""
        assert self.decoder is not None
        frame = self._keyframe
        if frame is None or frame.get("keyframe") != seq:
            return False
        try:
            poses = self._rows(frame.get("poses"))
            twists = self._rows(frame.get("twists"))
            self.decoder.resume_at(seq, poses, twists)
        except (TraceError, ValueError, TypeError) as exc:
            self._malformed(f"{self.where}: keyframe {seq}: {exc}")
            return False
        return True

    @staticmethod
    def _rows(value: Any) -> np.ndarray:
        array = np.array(value, dtype=float)
        if array.ndim != 2 or array.shape[1] != 4 or not np.isfinite(array).all() \
                or not np.array_equal(array[:, 0], np.arange(len(array))):
            raise ValueError("expected every object's row [index, a, b, c], in order")
        return array[:, 1:]

    def _malformed(self, reason: str) -> None:
        self.malformed += 1
        self.last_problem = reason

    def read_end(self) -> End:
        """The end record; for a stream cut short, the run as interrupted at the last
        sample seen, for the reason ``cut`` gives (so no verdict resting on what was not
        seen can pass)."""
        if self.end is not None:
            return self.end
        return (self.last_time, "interrupted", self.cut)

    def measurements(self) -> dict[str, Any]:
        """What the network did, for the summary (``bus``)."""
        return {"received": self.received, "missed": len(self.missed),
                "missed_samples": ranges(self.missed), "duplicated": self.duplicated,
                "reordered": self.reordered, "malformed": self.malformed,
                **({"cut": self.cut} if self.cut else {})}


def ask_header(call: Callable[[str, bytes, float], bytes], key: str,
               timeout: float) -> Callable[[], bytes]:
    """A function asking for the trace's header, again while nobody answers yet (the
    simulation's answer may reach the router a moment after its first line), at most
    ``timeout`` wall seconds."""
    def ask() -> bytes:
        deadline = time.monotonic() + timeout
        while True:
            try:
                return call(key, b"", max(0.1, deadline - time.monotonic()))
            except BusError as exc:
                if "no answer" not in str(exc) or time.monotonic() >= deadline:
                    raise BusError(f"joined late and could not get the trace's header: "
                                   f"{exc}") from None
                time.sleep(0.05)
    return ask
