"""Where the data collector publishes the sample stream: the ``SampleSink`` protocol.

The trace writer is one sink; the monitor (event automata) and the evaluator attach as
others. A sink sees ``start`` once, ``feed`` for every sample in order, and ``finish`` once,
also when the run ends in an error or is interrupted. This module must never import pybullet.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from rei.runtime.messages import Sample, StreamHeader


@runtime_checkable
class SampleSink(Protocol):
    def start(self, header: StreamHeader) -> None: ...

    def feed(self, sample: Sample) -> None: ...

    def finish(self, end_time: float, outcome: str, reason: str) -> None: ...


class SampleList:
    """A sink that keeps everything in memory (tests, notebooks, small runs)."""

    def __init__(self) -> None:
        self.header: StreamHeader | None = None
        self.samples: list[Sample] = []
        self.end: tuple[float, str, str] | None = None

    def start(self, header: StreamHeader) -> None:
        self.header = header

    def feed(self, sample: Sample) -> None:
        self.samples.append(sample)

    def finish(self, end_time: float, outcome: str, reason: str) -> None:
        self.end = (end_time, outcome, reason)
