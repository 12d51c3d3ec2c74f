"""The campaign's progress line: done/total, counts per run verdict, throughput and ETA.

Runs are counted by their verdict (rei.runtime.results.judge): pass, fail, inconclusive and
error each have their own count, so a smoke test whose runs were all cut short reads
"inconclusive 16", never "fail 16". Interrupted and unjudged runs count as inconclusive (they
decided nothing).

On a terminal it redraws one line; otherwise (CI logs) it prints a line every few runs so logs
stay short. It must never influence what is run or recorded.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass, field
from typing import TextIO


def _clock(seconds: float) -> str:
    seconds = max(0, int(round(seconds)))
    hours, rest = divmod(seconds, 3600)
    return f"{hours}:{rest // 60:02d}:{rest % 60:02d}" if hours else f"{rest // 60}:{rest % 60:02d}"


@dataclass
class Progress:
    total: int
    already: int = 0
    stream: TextIO = field(default_factory=lambda: sys.stderr)
    width: int = 28
    passed: int = 0
    failed: int = 0
    inconclusive: int = 0
    errors: int = 0
    started: float = field(default_factory=time.monotonic)

    def __post_init__(self) -> None:
        self._tty = hasattr(self.stream, "isatty") and self.stream.isatty()
        self._every = max(1, (self.total - self.already) // 20)

    @property
    def done(self) -> int:
        return self.already + self.new

    @property
    def new(self) -> int:
        return self.passed + self.failed + self.inconclusive + self.errors

    def line(self) -> str:
        elapsed = time.monotonic() - self.started
        new = self.new
        fraction = self.done / self.total if self.total else 1.0
        filled = int(self.width * fraction)
        rate = new / elapsed * 60 if elapsed > 0 else 0.0
        left = self.total - self.done
        eta = _clock(left / (new / elapsed)) if new and elapsed > 0 else "?"
        bar = "#" * filled + "." * (self.width - filled)
        counts = f"pass {self.passed}  fail {self.failed}"
        if self.inconclusive:
            counts += f"  inconclusive {self.inconclusive}"
        if self.errors:
            counts += f"  error {self.errors}"
        return (f"[{bar}] {self.done}/{self.total} runs  {counts}"
                f"  {rate:.1f} runs/min  ETA {eta}")

    def update(self, verdict: str) -> None:
        """Count one recorded run by its verdict (RunRecord.verdict)."""
        if verdict == "pass":
            self.passed += 1
        elif verdict == "fail":
            self.failed += 1
        elif verdict == "error":
            self.errors += 1
        else:
            self.inconclusive += 1
        new = self.new
        if self._tty:
            self.stream.write("\r" + self.line())
            self.stream.flush()
        elif new % self._every == 0 or self.done == self.total:
            self.stream.write(self.line() + "\n")
            self.stream.flush()

    def finish(self) -> None:
        if self._tty:
            self.stream.write("\n")
            self.stream.flush()
