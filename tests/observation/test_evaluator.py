"""The evaluator: mission signals through query events written in the default .vepl,
events.csv rows, requirement verdicts with the time that decided them, measurements."""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from rei.runtime.messages import MissionEvent
from rei.runtime.observation.evaluator.summary import merge_summary, write_summary
from rei.runtime.results import RESULTS_VERSION, RunSummary
from tests.observation.helpers import default_automata, monitor
from tests.observation.streams import drive, human, straight, wall


@pytest.fixture(scope="module")
def automata(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return default_automata(tmp_path_factory.mktemp("automata"))


def mission_events() -> dict[int, tuple[MissionEvent, ...]]:
    return {
        0: (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g1", 0)),
        10: (MissionEvent("task_success", 1.0, "g1", 0), MissionEvent("task_start", 1.0, "g2", 1)),
        15: (MissionEvent("task_fail", 1.5, "g2", 1, "timeout"),),
        19: (MissionEvent("end", 1.9),),
    }


def test_mission_signals_and_requirements(tmp_path: Path, automata: Path) -> None:
    h, samples = drive([wall("w", 10.0, 0.0)], straight(0.0, 1.0, 20), events=mission_events())
    rows, result = monitor(h, samples, tmp_path, automata=automata)
    assert [(r.time, r.signal, r.objects) for r in rows] == [
        (0.0, "SIG_MISSION_BEGIN", ()),
        (0.0, "SIG_MISSION_TASK_START", ("g1",)),
        (1.0, "SIG_MISSION_TASK_SUCCESS", ("g1",)),
        (1.0, "SIG_MISSION_TASK_START", ("g2",)),
        (1.5, "SIG_MISSION_TASK_FAIL", ("g2",)),
        (1.9, "SIG_MISSION_END", ()),
    ]
    assert [r.total_utility for r in rows] == [20, 25, 35, 40, -60, -40]
    verdicts = {v.requirement: v for v in result.verdicts}
    assert verdicts["MISSION_SEQUENCE"].status == "pass"
    assert verdicts["NO_ROBOT_COLLISION"].status == "pass"
    assert verdicts["NO_ROBOT_COLLISION"].decided_at == 1.9
    # a stream without a mission's goals is no pair of neighbouring goals
    assert verdicts["MISSION_SIMPLE"].status == "not_applicable"
    assert verdicts["GEOM_CLOSE_LASER_CORRECT"].status == "pass"  # never triggered
    goals = result.measurements["time_to_goal"]
    assert [(g["task"], g["status"], g["time_to_goal"]) for g in goals] == [
        ("g1", "succeeded", 1.0), ("g2", "failed", 0.5)]
    assert result.measurements["path_length"] == pytest.approx(1.0)


def test_events_csv_columns(tmp_path: Path, automata: Path) -> None:
    h, samples = drive([wall("w", 2.0, 0.0)], straight(0.0, 1.3, 14))
    monitor(h, samples, tmp_path, automata=automata)
    with open(tmp_path / "events.csv", newline="", encoding="utf-8") as handle:
        rows = list(csv.reader(handle))
    assert rows[0] == ["time", "signal", "utility", "total_utility", "objects"]
    assert rows[1][1:] == ["SIG_GEOM_FAR_TRANSIT_CLOSE", "-2", "-2", "w"]


def test_unanswered_task_fails_mission_sequence_at_the_end(tmp_path: Path, automata: Path) -> None:
    events = {0: (MissionEvent("begin", 0.0), MissionEvent("task_start", 0.0, "g1", 0))}
    h, samples = drive([wall("w", 10.0, 0.0)], straight(0.0, 1.0, 5), events=events)
    _, result = monitor(h, samples, tmp_path, automata=automata)
    v = {v.requirement: v for v in result.verdicts}["MISSION_SEQUENCE"]
    assert v.status == "fail" and v.decided_at == samples[-1].time


def test_human_collisions_are_counted_against_n_collision(tmp_path: Path,
                                                          automata: Path) -> None:
    h, samples = drive([human("walker", 1.0, 0.0)], straight(0.0, 0.7, 8))
    rows, result = monitor(h, samples, tmp_path, automata=automata)
    v = {v.requirement: v for v in result.verdicts}["MISSION_WITH_HUMAN_TRAJECTORY"]
    assert v.status == "fail"
    first_collision = next(r.time for r in rows if r.signal == "SIG_GEOM_CLOSE_TRANSIT_COLLISION")
    assert v.decided_at == first_collision
    assert result.measurements["min_distance_to_human"] < 0.05


def test_laser_requirement_passes_when_the_laser_agrees(tmp_path: Path, automata: Path) -> None:
    poses = straight(0.0, 1.2, 13)
    # a laser at the footprint centre sees the wall face at 1.5 - x along its forward beam
    laser = [1.5 - x for x, _, _ in poses]
    h, samples = drive([wall("w", 2.0, 0.0)], poses, laser=laser)
    _, result = monitor(h, samples, tmp_path, automata=automata)
    v = {v.requirement: v for v in result.verdicts}["GEOM_CLOSE_LASER_CORRECT"]
    assert v.status == "pass", v.reason


def test_summary_json_merges_the_monitor_result(tmp_path: Path, automata: Path) -> None:
    h, samples = drive([wall("w", 2.0, 0.0)], straight(0.0, 1.3, 14))
    _, result = monitor(h, samples, tmp_path, automata=automata)
    base = RunSummary(RESULTS_VERSION, "m", "r", 0, "reference", "completed", "", 1.3, 0.0, {},
                      ())
    path = write_summary(merge_summary(base, result), tmp_path)
    data = json.loads(path.read_text(encoding="utf-8"))
    assert data["signal_counts"]["SIG_GEOM_FAR_TRANSIT_CLOSE"] == 1
    assert data["total_utility"] == -2
    assert RunSummary.from_json(data).verdicts == result.verdicts


def test_same_stream_same_log(tmp_path: Path, automata: Path) -> None:
    h, samples = drive([wall("w", 2.0, 0.0), human("p", 0.5, 1.0)], straight(0.0, 1.4, 30))
    monitor(h, samples, tmp_path / "a", automata=automata)
    monitor(h, samples, tmp_path / "b", automata=automata)
    assert (tmp_path / "a/events.csv").read_bytes() == (tmp_path / "b/events.csv").read_bytes()


def test_user_functions_registered_from_python(tmp_path: Path) -> None:
    spec = tmp_path / "fn.vepl"
    spec.write_text("""function clearance(o)
query tight(o: object) { clearance(o) < 0.3 }
queryEvent tightening(o) as tight(o) found
signal SIG_TIGHT on tightening utility -1
requirement NEVER_TIGHT { never SIG_TIGHT }
""", encoding="utf-8")

    def clearance(w: object, objects: object) -> object:
        # an external check function: the footprint distance, reported by the user's code
        return w.distance  # type: ignore[attr-defined]

    h, samples = drive([wall("w", 2.0, 0.0)], straight(0.0, 1.3, 14))
    from rei.runtime.observation.errors import MonitorError
    from rei.runtime.observation.monitor import MonitorSink

    with pytest.raises(MonitorError, match="clearance"):
        MonitorSink(spec, tmp_path / "missing").start(h)
    sink = MonitorSink(spec, tmp_path / "out", functions={"clearance": clearance})
    sink.start(h)
    for s in samples:
        sink.feed(s)
    sink.finish(samples[-1].time, "completed", "")
    assert sink.result is not None
    assert sink.result.signal_counts == {"SIG_TIGHT": 1}
    assert sink.result.verdicts[0].status == "fail"


def test_hysteresis_band_stops_chattering(tmp_path: Path) -> None:
    # the robot wobbles by 1 cm around ε_close: without a band every wobble is a transition
    x0 = 1.5 - 0.281 / 2 - 0.25
    poses = [(x0 + (0.01 if i % 2 else -0.01), 0.0, 0.0) for i in range(20)]
    h, samples = drive([wall("w", 2.0, 0.0)], poses)
    counts = {}
    for band in ("0.0", "0.05"):
        spec = tmp_path / f"h{band}.vepl"
        spec.write_text(f"""parameters {{ eps_close = 0.25  hysteresis = {band} }}
query close(o: object) {{ distance(robot, o) < eps_close }}
queryEvent entering() as close found
signal SIG_ENTER on entering utility -2
""", encoding="utf-8")
        rows, _ = monitor(h, samples, tmp_path / band, vepl=spec)
        counts[band] = len(rows)
    assert counts["0.0"] == 10
    assert counts["0.05"] == 1


def test_floor_and_navigation_queries(tmp_path: Path) -> None:
    from dataclasses import replace as with_fields

    from rei.runtime.messages import NavState

    spec = tmp_path / "floors.vepl"
    spec.write_text("""query onFloor(f: floor) { on(robot, f) }
query navigating() { nav_state == active and speed > 0.1 }
queryEvent entering(f) as onFloor(f) found
queryEvent stopping() as navigating lost
signal SIG_FLOOR on entering utility 0
signal SIG_STOP on stopping utility 0
""", encoding="utf-8")
    h, samples = drive([wall("w", 10.0, 0.0)], straight(0.0, 2.0, 21))
    h = with_fields(h, floors=(("a", 0.0, 0.0), ("b", 1.0, 0.0), ("c", 2.0, 0.0)))
    moving = [with_fields(s, robot_twist=(1.0, 0.0, 0.0)) for s in samples[:15]]
    stopped = [with_fields(s, belief=with_fields(s.belief, nav_state=NavState.SUCCEEDED))
               for s in samples[15:]]
    rows, _ = monitor(h, moving + stopped, tmp_path / "out", vepl=spec)
    assert [(r.time, r.signal, r.objects) for r in rows] == [
        (0.0, "SIG_FLOOR", ("a",)), (0.6, "SIG_FLOOR", ("b",)), (1.5, "SIG_STOP", ()),
        (1.6, "SIG_FLOOR", ("c",))]
