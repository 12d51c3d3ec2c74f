"""When a fault is active: a time window, or intervals opened and closed by ``.vepl`` signals.

A tracker keeps every interval its fault was active in, so models can ask about a past time
(the Poisson fault counts occurrences between two scans) and the stage can report its
timeline. Times are the simulation's seconds; an interval is half open, ``[start, end)``.
"""

from __future__ import annotations

from rei.lang.mission.faults import Activation


class ActivationTracker:
    """The active intervals of one fault (per run; mutable)."""

    def __init__(self, activation: Activation) -> None:
        self.activation = activation
        self.intervals: list[list[float | None]] = []
        """[start, end] pairs in start order; end None while open-ended."""
        if activation.signal is None:
            self.intervals.append([activation.start, activation.end])

    def _containing(self, time: float) -> list[float | None] | None:
        for interval in reversed(self.intervals):
            start, end = interval
            assert start is not None
            if start <= time and (end is None or time < end):
                return interval
        return None

    def active(self, time: float) -> bool:
        return self._containing(time) is not None

    def since(self, time: float) -> float | None:
        """The start of the interval active at ``time``, or None when inactive then."""
        interval = self._containing(time)
        return None if interval is None else interval[0]

    def signal(self, time: float, name: str) -> None:
        """The signal ``name`` fired at ``time``: open, extend or close an interval."""
        a = self.activation
        if a.signal is not None and name == a.signal:
            current = self._containing(time)
            end = time + a.duration if a.duration is not None else None
            if current is None:
                self.intervals.append([time, end])
            elif end is not None and current[1] is not None and current[1] < end:
                current[1] = end
        elif a.stop is not None and name == a.stop:
            for interval in self.intervals:
                start, stop = interval
                assert start is not None
                if stop is None or stop > time:
                    interval[1] = max(start, time)
            self.intervals = [i for i in self.intervals if i[1] is None or i[0] != i[1]]

    def timeline(self, now: float) -> list[tuple[float, float | None]]:
        """The intervals begun by ``now``: (start, end), end None while it still runs."""
        out: list[tuple[float, float | None]] = []
        for start, end in self.intervals:
            assert start is not None
            if start <= now:
                out.append((start, end if end is not None and end <= now else None))
        return out
