"""What the network can do to a monitor (issue 23 item 5), on the trace of a real run: samples
missed (joined late, cut off, lost), duplicated or reordered are counted exactly in the
summary (by sequence number), and every requirement whose evidence they were is
inconclusive, never a pass. The stream is the bus's own payloads (``TracePublisher``'s
encoding) handed to ``TraceStream`` in the order a network might deliver them."""

from __future__ import annotations

import json
import threading
from pathlib import Path
from typing import Any

import pytest

from rei.runtime.bus.monitor import TraceStream, ranges
from rei.runtime.bus.run import KEYFRAME
from rei.runtime.collector.trace import TraceEncoder, read_trace, read_trace_end
from rei.runtime.commands.replay import judge_stream
from rei.runtime.commands.run import run_into
from rei.runtime.monitor import generate_automata
from tests.conftest import EXAMPLES

MISSION = EXAMPLES / "simple_wall" / "simple_wall.mission"


@pytest.fixture(scope="module")
def payloads(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[bytes]]:
    """A real run's folder, and its trace as the bus carries it."""
    out = tmp_path_factory.mktemp("faults") / "run"
    run_into(MISSION, out)
    header, samples = read_trace(out / "trace.jsonl")
    encoder = TraceEncoder("test")
    lines = [encoder.header(header),
             *(encoder.sample(s, whole=s.seq % KEYFRAME == 0) for s in samples)]
    end = read_trace_end(out / "trace.jsonl")
    assert end is not None
    lines += [json.dumps({"samples": len(lines) - 1}), encoder.end(*end)]
    return out, [line.encode() for line in lines]


def _judge(payloads: list[bytes], out: Path, header: bytes | None = None,
           silence: float = 30.0) -> tuple[dict[str, Any], dict[str, str]]:
    """Feed ``payloads`` as they would arrive; the summary's bus counts and the verdicts."""
    stream = TraceStream(lambda: header or b"", silence)
    for payload in payloads:
        stream.receive("rei/v1/trace", payload)
    head = stream.header()
    summary = judge_stream(head, stream.samples(), stream.read_end, None, out, {},
                           generate_automata(None, out / "automata", replace=True),
                           "the test stream", controller="bus",
                           measurements=lambda: {"bus": stream.measurements()})
    return summary.measurements["bus"], {v.requirement: v.status for v in summary.verdicts}


def _samples(payloads: list[bytes]) -> list[bytes]:
    return payloads[1:-2]


def test_a_whole_stream_is_judged_as_the_run(payloads: tuple[Path, list[bytes]],
                                             tmp_path: Path) -> None:
    run, lines = payloads
    bus, verdicts = _judge(lines, tmp_path)
    expected = json.loads((run / "summary.json").read_text())
    assert verdicts == {v["requirement"]: v["status"] for v in expected["verdicts"]}
    assert (tmp_path / "events.csv").read_bytes() == (run / "events.csv").read_bytes()
    assert bus == {"received": len(_samples(lines)), "missed": 0, "missed_samples": [],
                   "duplicated": 0, "reordered": 0, "malformed": 0}
    assert "pass" in verdicts.values()  # the lossy runs below have passes to lose


def _never_a_new_pass(lossy: dict[str, str], whole: dict[str, str]) -> None:
    """No requirement passes on less evidence unless it passed on all of it, and some that
    passed on all of it are inconclusive now (what was missed was their evidence)."""
    assert all(status != "pass" or whole[name] == "pass" for name, status in lossy.items())
    assert any(whole[name] == "pass" and status == "inconclusive"
               for name, status in lossy.items()), lossy


def test_lost_samples_are_named_and_make_verdicts_inconclusive(
        payloads: tuple[Path, list[bytes]], tmp_path: Path) -> None:
    _, lines = payloads
    _, whole = _judge(lines, tmp_path / "whole")
    samples = _samples(lines)
    lost = {5, 6, 7, 30, len(samples) - 1}
    kept = [lines[0], *(p for i, p in enumerate(samples) if i not in lost), *lines[-2:]]
    bus, lossy = _judge(kept, tmp_path / "lossy")
    # after a gap the monitor reads on from the next keyframe (seq 10, 40, ...)
    assert KEYFRAME == 10
    assert bus["missed_samples"] == [[5, 9], [30, 39], [len(samples) - 1, len(samples) - 1]]
    assert bus["missed"] == 16 and bus["received"] == len(samples) - 16
    _never_a_new_pass(lossy, whole)


def test_duplicated_and_reordered_samples_are_counted(payloads: tuple[Path, list[bytes]],
                                                      tmp_path: Path) -> None:
    _, lines = payloads
    samples = _samples(lines)
    shuffled = [*samples[:4], samples[3], samples[3], samples[5], samples[4], *samples[6:]]
    bus, _ = _judge([lines[0], *shuffled, *lines[-2:]], tmp_path)
    assert (bus["duplicated"], bus["reordered"]) == (2, 1)
    # 4 came after 5 (too late to be judged), and 5 to 9 rest on it: read on from 10
    assert bus["missed_samples"] == [[4, 9]]


def test_a_late_monitor_asks_for_the_header_and_names_what_it_missed(
        payloads: tuple[Path, list[bytes]], tmp_path: Path) -> None:
    _, lines = payloads
    _, whole = _judge(lines, tmp_path / "whole")
    bus, late = _judge(lines[21:], tmp_path / "late", header=lines[0])
    assert bus["missed_samples"] == [[0, 19]]
    _never_a_new_pass(late, whole)


def test_a_monitor_cut_off_ends_the_run_as_interrupted(payloads: tuple[Path, list[bytes]],
                                                       tmp_path: Path) -> None:
    _, lines = payloads
    _, whole = _judge(lines, tmp_path / "whole")
    bus, cut = _judge(lines[:41], tmp_path / "cut", silence=0.2)
    assert bus["cut"] == ("the bus went silent for 0.2 s after sample 39 (the monitor was "
                          "cut off, or the run died)")
    assert bus["missed"] == 0 and bus["received"] == 40
    summary = json.loads((tmp_path / "cut" / "summary.json").read_text())
    assert summary["outcome"] == "interrupted"
    _never_a_new_pass(cut, whole)


def test_the_last_samples_missed_are_known_from_the_count(payloads: tuple[Path, list[bytes]],
                                                          tmp_path: Path) -> None:
    _, lines = payloads
    _, whole = _judge(lines, tmp_path / "whole")
    n = len(_samples(lines))
    bus, tail = _judge([*lines[:-2 - 3], *lines[-2:]], tmp_path / "tail")
    assert bus["missed_samples"] == [[n - 3, n - 1]]
    assert bus["cut"] == (f"the monitor missed the last samples ({n - 3} to {n - 1}) before "
                          f"the run's end")
    _never_a_new_pass(tail, whole)


def test_malformed_lines_are_dropped_and_counted(payloads: tuple[Path, list[bytes]],
                                                 tmp_path: Path) -> None:
    _, lines = payloads
    samples = _samples(lines)
    bad = [b"\xff", b"{}", b'{"seq": "x"}', b'{"samples": -1}', samples[3][:-9] + b"]]]]]]]]}"]
    bus, _ = _judge([lines[0], *samples[:3], *bad, *samples[3:], *lines[-2:]], tmp_path)
    assert bus["malformed"] == 5
    assert bus["missed"] == 0  # the damaged copy of sample 3 was dropped, the good one used


def test_ranges() -> None:
    assert ranges([]) == [] and ranges([4, 0, 1, 2, 9]) == [[0, 2], [4, 4], [9, 9]]
    assert threading is not None
