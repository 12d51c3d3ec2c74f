"""Live equals replay (the same automata on a recorded trace), and bad samples are counted
and make the verdicts they touch inconclusive, never pass."""

from __future__ import annotations

import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from rei.runtime.commands.cli import main as rei
from rei.runtime.messages import MissionEvent
from rei.runtime.trace import write
from tests.observation.helpers import default_automata, monitor
from tests.observation.streams import drive, human, straight, wall


@pytest.fixture(scope="module")
def automata(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return default_automata(tmp_path_factory.mktemp("automata"))


def scenario() -> tuple:  # type: ignore[type-arg]
    poses = straight(0.0, 1.45, 30) + straight(1.45, 0.0, 30)
    events = {0: (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g", 0)),
              59: (MissionEvent("task_success", 5.9, "g", 0), MissionEvent("end", 5.9))}
    return drive([wall("w", 2.0, 0.0), human("h", 0.7, 0.6)], poses, events=events)


def test_replay_equals_live(tmp_path: Path, automata: Path) -> None:
    h, samples = scenario()
    live_rows, live = monitor(h, samples, tmp_path / "live", automata=automata)
    write(tmp_path / "trace.jsonl", h, samples, samples[-1].time, "completed", "")
    status = rei(["replay", str(tmp_path / "trace.jsonl"), "-o", str(tmp_path / "replay")])
    assert (tmp_path / "replay/events.csv").read_bytes() == \
        (tmp_path / "live/events.csv").read_bytes()
    summary = json.loads((tmp_path / "replay/summary.json").read_text(encoding="utf-8"))
    assert [(v["requirement"], v["status"], v["decided_at"]) for v in summary["verdicts"]] == \
        [(v.requirement, v.status, v.decided_at) for v in live.verdicts]
    assert status == (0 if all(v.status == "pass" for v in live.verdicts) else 1)
    assert len(live_rows) >= 6


def test_replay_with_a_given_specification(tmp_path: Path) -> None:
    h, samples = scenario()
    write(tmp_path / "trace.jsonl", h, samples, samples[-1].time, "completed", "")
    spec = tmp_path / "only_close.vepl"
    spec.write_text("""parameters { eps_close = 0.3 }
query near(o: object) { distance(robot, o) < eps_close }
queryEvent nearing(o) as near(o) found
signal SIG_NEAR on nearing utility -1
requirement NEVER_NEAR { never SIG_NEAR }
""", encoding="utf-8")
    assert rei(["replay", str(tmp_path / "trace.jsonl"), "--vepl", str(spec), "-o",
                str(tmp_path / "out")]) == 1
    text = (tmp_path / "out/events.csv").read_text(encoding="utf-8")
    assert "SIG_NEAR" in text and "SIG_GEOM" not in text


def test_replay_of_a_bad_specification_is_bad_input(tmp_path: Path) -> None:
    h, samples = scenario()
    write(tmp_path / "trace.jsonl", h, samples[:3], samples[2].time)
    bad = tmp_path / "bad.vepl"
    bad.write_text("queryEvent e() as nothing found\n", encoding="utf-8")
    assert rei(["replay", str(tmp_path / "trace.jsonl"), "--vepl", str(bad), "-o",
                str(tmp_path / "out")]) == 2


def _verdicts(result) -> dict[str, str]:  # type: ignore[no-untyped-def]
    return {v.requirement: v.status for v in result.verdicts}


@pytest.mark.parametrize("damage", ["non_finite", "duplicate", "out_of_order", "missing"])
def test_bad_samples_never_turn_into_a_pass(damage: str, tmp_path: Path, automata: Path) -> None:
    h, samples = drive([wall("w", 10.0, 0.0)], straight(0.0, 1.0, 20),
                       events={0: (MissionEvent("begin", 0.0),), 19: (MissionEvent("end", 1.9),)})
    _, clean = monitor(h, samples, tmp_path / "clean", automata=automata)
    assert _verdicts(clean)["NO_ROBOT_COLLISION"] == "pass"
    s = list(samples)
    if damage == "non_finite":
        poses = s[5].poses.copy()
        poses[0, 0] = np.nan
        s[5] = replace(s[5], poses=poses)
    elif damage == "duplicate":
        s.insert(6, s[5])
    elif damage == "out_of_order":
        s[5], s[6] = s[6], s[5]
    else:
        del s[5:8]
    _, result = monitor(h, s, tmp_path / "bad", automata=automata)
    counts = result.measurements["sample_problems"]
    assert counts[damage] >= 1
    verdicts = _verdicts(result)
    assert verdicts["NO_ROBOT_COLLISION"] == "inconclusive"
    assert "pass" not in {verdicts["MISSION_SEQUENCE_CYCLE"],
                          verdicts["MISSION_WITH_HUMAN_TRAJECTORY"]}


def test_a_run_that_did_not_finish_makes_absence_inconclusive(tmp_path: Path,
                                                              automata: Path) -> None:
    h, samples = drive([human("h", 10.0, 0.0)], straight(0.0, 1.0, 10))
    _, result = monitor(h, samples, tmp_path, automata=automata, outcome="interrupted")
    assert _verdicts(result)["MISSION_WITH_HUMAN_TRAJECTORY"] == "inconclusive"


def test_replay_without_a_needed_user_function_is_bad_input(tmp_path: Path) -> None:
    # located at the `function` line, before the trace is read (--functions names the module)
    h, samples = scenario()
    write(tmp_path / "trace.jsonl", h, samples[:3], samples[2].time)
    spec = tmp_path / "fn.vepl"
    spec.write_text("function check(o)\nquery q(o: object) { check(o) < 1 }\n",
                    encoding="utf-8")
    assert rei(["replay", str(tmp_path / "trace.jsonl"), "--vepl", str(spec), "-o",
                str(tmp_path / "out")]) == 2


def test_replay_of_a_missing_trace_is_bad_input(tmp_path: Path) -> None:
    assert rei(["replay", str(tmp_path / "nothing.jsonl"), "-o", str(tmp_path / "out")]) == 2


def test_mission_events_of_a_bad_sample_still_count(tmp_path: Path, automata: Path) -> None:
    events = {0: (MissionEvent("begin", 0.0),), 5: (MissionEvent("end", 0.5),)}
    h, samples = drive([wall("w", 10.0, 0.0)], straight(0.0, 1.0, 6), events=events)
    poses = samples[5].poses.copy()
    poses[0, 1] = np.inf
    samples[5] = replace(samples[5], poses=poses)
    rows, result = monitor(h, samples, tmp_path, automata=automata)
    assert [r.signal for r in rows] == ["SIG_MISSION_BEGIN", "SIG_MISSION_END"]
    assert result.measurements["sample_problems"]["non_finite"] == 1
