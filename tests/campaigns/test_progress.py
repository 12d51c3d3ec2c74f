"""The progress line: counts, throughput and ETA; short logs when not on a terminal."""

from __future__ import annotations

import io

from rei.runtime.campaigns.progress import Progress


def test_progress_counts_resumed_runs_and_prints_sparsely_off_a_terminal() -> None:
    stream = io.StringIO()
    progress = Progress(total=50, already=10, stream=stream)
    for i in range(40):
        progress.update("pass" if i % 4 != 0 else "fail")
    progress.finish()
    lines = stream.getvalue().splitlines()
    assert len(lines) == 20  # every 2nd of 40 runs: CI logs stay short
    assert lines[-1].startswith("[" + "#" * 28 + "] 50/50 runs  pass 30  fail 10  ")
    assert "runs/min" in lines[-1] and lines[-1].endswith("ETA 0:00")
    assert "\r" not in stream.getvalue()
