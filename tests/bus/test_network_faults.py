"""What the network can do to a monitor (issue 23 item 5), on the trace of a real run: samples
missed (joined late, cut off, lost), duplicated or reordered are counted exactly in the
summary (by sequence number), and every requirement whose evidence they were is
inconclusive, never a pass. The stream is the bus's own payloads (``TracePublisher``'s
encoding) handed to ``TraceStream`` in the order a network might deliver them."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import pytest

from rei.runtime.bus.distributed_run import KEYFRAME, keyframe
from rei.runtime.bus.reception import TraceStream, ranges
from rei.runtime.observation.judgement import judge_stream
from rei.runtime.observation.monitor import generate_automata
from rei.runtime.runs.session import run_into
from rei.runtime.trace import read_trace, read_trace_end
from tests.conftest import EXAMPLES

MISSION = EXAMPLES / "simple_wall" / "simple_wall.mission"


@pytest.fixture(scope="module")
def payloads(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Stream]:
    """A real run's folder, and its trace as the bus carries it (``TracePublisher``'s
    payloads: the header, per sample its keyframe (every 10th) and its line, the count,
    the end line)."""
    out = tmp_path_factory.mktemp("faults") / "run"
    run_into(MISSION, out)
    header, samples = read_trace(out / "trace.jsonl")
    lines = (out / "trace.jsonl").read_bytes().splitlines()
    per_sample = [([keyframe(s)] if s.seq % KEYFRAME == 0 else []) + [line]
                  for s, line in zip(samples, lines[1:-1], strict=True)]
    assert read_trace_end(out / "trace.jsonl") is not None
    count = json.dumps({"samples": len(per_sample)}).encode()
    return out, Stream(lines[0], per_sample, [count, lines[-1]])


class Stream:
    def __init__(self, header: bytes, samples: list[list[bytes]], tail: list[bytes]) -> None:
        self.header, self.samples, self.tail = header, samples, tail

    def payloads(self, order: list[int] | None = None, head: bool = True,
                 tail: bool = True) -> list[bytes]:
        """The payloads with the samples in ``order`` (indices; default all, in order)."""
        order = list(range(len(self.samples))) if order is None else order
        return [*([self.header] if head else []),
                *(p for i in order for p in self.samples[i]),
                *(self.tail if tail else [])]


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


def test_a_whole_stream_is_judged_as_the_run(payloads: tuple[Path, Stream],
                                             tmp_path: Path) -> None:
    run, stream = payloads
    bus, verdicts = _judge(stream.payloads(), tmp_path)
    expected = json.loads((run / "summary.json").read_text())
    assert verdicts == {v["requirement"]: v["status"] for v in expected["verdicts"]}
    assert (tmp_path / "events.csv").read_bytes() == (run / "events.csv").read_bytes()
    assert bus == {"received": len(stream.samples), "missed": 0, "missed_samples": [],
                   "duplicated": 0, "reordered": 0, "malformed": 0}
    assert "pass" in verdicts.values()  # the lossy runs below have passes to lose


def _never_a_new_pass(lossy: dict[str, str], whole: dict[str, str]) -> None:
    """No requirement passes on less evidence unless it passed on all of it, and some that
    passed on all of it are inconclusive now (what was missed was their evidence)."""
    assert all(status != "pass" or whole[name] == "pass" for name, status in lossy.items())
    assert any(whole[name] == "pass" and status == "inconclusive"
               for name, status in lossy.items()), lossy


def test_lost_samples_are_named_and_make_verdicts_inconclusive(
        payloads: tuple[Path, Stream], tmp_path: Path) -> None:
    _, stream = payloads
    _, whole = _judge(stream.payloads(), tmp_path / "whole")
    n = len(stream.samples)
    lost = {5, 6, 7, 30, n - 1}
    bus, lossy = _judge(stream.payloads([i for i in range(n) if i not in lost]),
                        tmp_path / "lossy")
    # after a gap the monitor reads on from the next keyframe (seq 10, 40, ...)
    assert KEYFRAME == 10
    assert bus["missed_samples"] == [[5, 9], [30, 39], [n - 1, n - 1]]
    assert bus["missed"] == 16 and bus["received"] == n - 16
    _never_a_new_pass(lossy, whole)


def test_duplicated_and_reordered_samples_are_counted(payloads: tuple[Path, Stream],
                                                      tmp_path: Path) -> None:
    _, stream = payloads
    n = len(stream.samples)
    bus, _ = _judge(stream.payloads([0, 1, 2, 3, 3, 3, 5, 4, *range(6, n)]), tmp_path)
    assert (bus["duplicated"], bus["reordered"]) == (2, 1)
    # 4 came after 5 (too late to be judged), and 5 to 9 rest on it: read on from 10
    assert bus["missed_samples"] == [[4, 9]]


def test_a_late_monitor_asks_for_the_header_and_names_what_it_missed(
        payloads: tuple[Path, Stream], tmp_path: Path) -> None:
    _, stream = payloads
    _, whole = _judge(stream.payloads(), tmp_path / "whole")
    n = len(stream.samples)
    bus, late = _judge(stream.payloads(list(range(20, n)), head=False), tmp_path / "late",
                       header=stream.header)
    assert bus["missed_samples"] == [[0, 19]]
    assert bus["received"] == n - 20
    _never_a_new_pass(late, whole)


def test_a_monitor_cut_off_ends_the_run_as_interrupted(payloads: tuple[Path, Stream],
                                                       tmp_path: Path) -> None:
    _, stream = payloads
    _, whole = _judge(stream.payloads(), tmp_path / "whole")
    bus, cut = _judge(stream.payloads(list(range(40)), tail=False), tmp_path / "cut",
                      silence=0.2)
    assert bus["cut"] == ("the bus went silent for 0.2 s after sample 39 (the monitor was "
                          "cut off, or the run died)")
    assert bus["missed"] == 0 and bus["received"] == 40
    summary = json.loads((tmp_path / "cut" / "summary.json").read_text())
    assert summary["outcome"] == "interrupted"
    _never_a_new_pass(cut, whole)


def test_the_last_samples_missed_are_known_from_the_count(payloads: tuple[Path, Stream],
                                                          tmp_path: Path) -> None:
    _, stream = payloads
    _, whole = _judge(stream.payloads(), tmp_path / "whole")
    n = len(stream.samples)
    bus, tail = _judge(stream.payloads(list(range(n - 3))), tmp_path / "tail")
    assert bus["missed_samples"] == [[n - 3, n - 1]]
    assert bus["cut"] == (f"the monitor missed the last samples ({n - 3} to {n - 1}) before "
                          f"the run's end")
    _never_a_new_pass(tail, whole)


def test_malformed_payloads_are_dropped_and_counted(payloads: tuple[Path, Stream],
                                                   tmp_path: Path) -> None:
    _, stream = payloads
    line = stream.samples[3][-1]
    bad = [b"\xff", b"{}", b'{"seq": "x"}', b'{"samples": -1}', line[:-9] + b"]]]]]]]]}"]
    everything = stream.payloads()
    at = everything.index(line)
    bus, _ = _judge([*everything[:at], *bad, *everything[at:]], tmp_path)
    assert bus["malformed"] == 5
    assert bus["missed"] == 0  # the damaged copy of sample 3 was dropped, the good one used


def test_a_damaged_keyframe_is_not_read_on_from(payloads: tuple[Path, Stream],
                                                tmp_path: Path) -> None:
    _, stream = payloads
    n = len(stream.samples)
    damaged = Stream(stream.header, [list(s) for s in stream.samples], stream.tail)
    damaged.samples[10][0] = b'{"keyframe": 10, "poses": [[0, 1, 2]], "twists": []}'
    bus, _ = _judge(damaged.payloads([*range(8), *range(10, n)]), tmp_path)
    assert bus["missed_samples"] == [[8, 19]] and bus["malformed"] == 1


def test_ranges() -> None:
    assert ranges([]) == [] and ranges([4, 0, 1, 2, 9]) == [[0, 2], [4, 4], [9, 9]]
