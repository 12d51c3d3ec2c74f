"""Queries over several parameters joined on shared variables, floor parameters, and the
inverse map from every observed body back to its floor (issue 14.9 and 14.12)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from rei.catalogue import Box
from rei.lang.source import SourceText
from rei.lang.vepl.document import analyse_vepl
from rei.runtime.messages import GoalFacts, MissionFacts, ObservedObject, Sample
from rei.runtime.observation.evaluator.signal_log import SignalRow
from rei.runtime.observation.model.floors import FloorMap
from tests.observation.helpers import monitor
from tests.observation.streams import header, human, sample

# A corridor of five floors f0..f4 at x = 0..4 (tile 1 m); the robot drives from f0 to f4.
FLOORS = tuple((f"f{i}", float(i), 0.0) for i in range(5))
CRATE = ObservedObject("crate", "static", "box", Box(0.4, 0.4), 0.5)
FACTS = MissionFacts((GoalFacts("g1", 3.0, 0.0, None, 0.3, 0.26, 60.0),), 1, 100.0, 0.26,
                     1.8, None)

SPEC = """specification floors
query humanOnRobotFloor(h: object[human], f: floor) { on(h, f) and on(robot, f) }
query objectOnGoalFloor(o: object, f: floor) { on(o, f) and goal(f) }
query humanBesideHuman(a: object[human], b: object[human], f: floor, g: floor) {
    on(a, f) and on(b, g) and neighbours(f, g)
}
query sharedWithSomeone(f: floor) { find humanOnRobotFloor(_, f) }
queryEvent humanJoinsRobot(h, f) as humanOnRobotFloor(h, f) found
queryEvent humanLeavesRobot(h, f) as humanOnRobotFloor(h, f) lost
queryEvent objectOnGoal(o, f) as objectOnGoalFloor(o, f) found
queryEvent neighbours(a, b, f, g) as humanBesideHuman(a, b, f, g) found
queryEvent robotFloorShared() as sharedWithSomeone found
signal SIG_JOIN on humanJoinsRobot utility -1
signal SIG_LEAVE on humanLeavesRobot utility 1
signal SIG_GOAL_OBJECT on objectOnGoal utility 0
signal SIG_BESIDE on neighbours utility 0
signal SIG_SHARED on robotFloorShared utility 0
"""


def run(tmp_path: Path, robot_x: list[float], walker_x: list[float]) -> list[SignalRow]:
    placed = [human("walker", walker_x[0], 0.0), human("stander", 4.0, 0.0)]
    objects = (*(o for o, _ in placed), CRATE)
    head = dataclasses.replace(header(objects, FLOORS), mission_facts=FACTS)
    samples: list[Sample] = []
    for k, (rx, wx) in enumerate(zip(robot_x, walker_x, strict=True)):
        poses = np.array([(wx, 0.0, 0.0), (4.0, 0.0, 0.0), (3.1, 0.1, 0.0)])
        samples.append(sample(k, 0.1 * (k + 1), (rx, 0.0, 0.0), poses))
    vepl = tmp_path / "floors.vepl"
    vepl.write_text(SPEC, encoding="utf-8")
    rows, _ = monitor(head, samples, tmp_path / "out", vepl=vepl)
    return rows


def test_a_human_on_the_robots_floor_and_an_object_on_the_goal_floor(tmp_path: Path) -> None:
    # the walker comes towards the robot: f3, f2, f1 (meeting it there), f0; robot stays on f1
    rows = run(tmp_path, [1.0, 1.0, 1.0, 1.1], [3.0, 2.0, 1.2, 0.2])
    got = [(round(r.time, 3), r.signal, r.objects) for r in rows]
    assert (0.1, "SIG_GOAL_OBJECT", ("crate", "f3")) in got
    assert (0.3, "SIG_JOIN", ("walker", "f1")) in got
    assert (0.3, "SIG_SHARED", ("f1",)) in got
    assert (0.4, "SIG_LEAVE", ("walker", "f1")) in got
    # the stander on f4 is beside the walker only while the walker is on f3
    beside = [r.objects for r in rows if r.signal == "SIG_BESIDE"]
    assert beside == [("walker", "stander", "f3", "f4"), ("stander", "walker", "f4", "f3")]
    assert [r.signal for r in rows].count("SIG_JOIN") == 1


def test_the_inverse_map_sends_every_body_to_its_floor() -> None:
    floors = FloorMap(np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0)]), 1.0)
    xy = np.array([(0.2, -0.4), (1.4, 0.1), (0.9, 1.3), (0.0, 1.0), (5.0, 5.0)])
    assert floors.of(xy).tolist() == [0, 1, 2, -1, -1]
    assert floors.adjacent().astype(int).tolist() == [[0, 1, 0], [1, 0, 1], [0, 1, 0]]
    # floors off a common grid fall back to looking at every floor's square
    loose = FloorMap(np.array([(0.0, 0.0), (1.3, 0.0)]), 1.0)
    assert not loose.on_grid
    assert loose.of(np.array([(1.5, 0.2), (0.6, 0.0)])).tolist() == [1, -1]


def check(text: str) -> list[tuple[str, int, str]]:
    doc = analyse_vepl(SourceText("t.vepl", text))
    return [(d.rule, d.span.line, d.message) for d in doc.diagnostics]


@pytest.mark.parametrize(("kinds", "expected"), [
    ("tabel", "found 'tabel'; did you mean 'table'?"),
    ("desk", "found 'desk', which is a query of this file, not a kind of object"),
])
def test_an_unknown_kind_is_located_with_did_you_mean(kinds: str, expected: str) -> None:
    found = check(f"query desk() {{ humans > 0 }}\n"
                  f"query near(o: object[human, {kinds}]) {{ distance(robot, o) < 1 }}\n")
    assert [(r, line) for r, line, _ in found] == [("VEPL-UNKNOWN", 2)]
    assert expected in found[0][2]
    assert "a role (wall, static, dynamic, human) or a catalogue type" in found[0][2]


def test_uses_must_match_the_declared_parameters() -> None:
    found = check("query pair(h: object[human], f: floor) { on(h, f) }\n"
                  "query one(f: floor) { find pair(f) }\n"
                  "query swapped(f: floor, h: object) { find pair(f, h) }\n"
                  "query twice(f: floor) { find side(f, f) }\n"
                  "query many(a: object, b: object, c: object, d: object, e: object) "
                  "{ humans > 0 }\n"
                  "query robotOn(o: object) { on(o, robot) }\n"
                  "query side(a: floor, b: floor) { neighbours(a, b) }\n")
    rules = [(r, line) for r, line, _ in found]
    assert ("VEPL-ARITY", 2) in rules
    assert ("VEPL-TYPE", 3) in rules
    assert ("VEPL-ARITY", 4) in rules
    assert ("VEPL-ARITY", 5) in rules
    assert ("VEPL-TYPE", 6) in rules
    messages = {line: message for _, line, message in found}
    assert "expected 2 argument(s) as declared, found 1" in messages[2]
    assert "find 'pair': expected a object for 'h', found the floor 'f'" in messages[3]
    assert "expected each parameter passed once, found 'f' twice" in messages[4]
    assert "expected at most 4 parameters, found 5" in messages[5]
    assert "robot or an object parameter, a floor parameter" in messages[6]
