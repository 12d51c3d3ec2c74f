"""A trajectory's start trigger (`when robot within D of FLOOR`): parsed, checked with
located errors, carried into the concrete model and world.json, printed back, offered by
completion, and exported to Gazebo as a planned start with a comment saying so."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest
from lxml import etree

from rei.generators.concrete.build import concretise_room
from rei.generators.output import write_tree
from rei.generators.targets import GenerationRequest, get_target
from rei.lang.lsp.completion import room_completions
from rei.lang.printer import print_room
from rei.lang.workspace import Workspace, load_room
from rei.runtime.artifacts.world import load_manifest
from tests.generators.test_gazebo_target import ign_check

ROOM = """room hall {
    grid g {
        "#########"
        "####.####"
        "#.......#"
        "#########"
    }
    robot r : turtlebot3_waffle on g_2_1
    human h on g_1_4 trajectory stop TRIGGER total 2 { g_1_4 g_2_4 g_2_7 }
}
"""
GOOD = "when robot within 1.2 of g_2_4"


def _write(tmp_path: Path, trigger: str, name: str = "hall.room") -> Path:
    path = tmp_path / name
    path.write_text(ROOM.replace("TRIGGER", trigger), encoding="utf-8")
    return path


def test_the_trigger_reaches_the_concrete_model_and_world_json(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD)
    doc = load_room(path, Workspace())
    assert doc.ok and doc.room is not None
    [human] = [o for o in doc.room.objects if o.role == "human"]
    assert human.trajectory is not None and human.trajectory.trigger is not None
    assert (human.trajectory.trigger.floor.name, human.trajectory.trigger.distance) == \
        ("g_2_4", 1.2)
    world = concretise_room(doc)
    start = world.humans[0].trajectory.start_when  # type: ignore[union-attr]
    floor = world.floor("g_2_4")
    assert start is not None and (start.x, start.y, start.within) == (floor.x, floor.y, 1.2)
    folder = tmp_path / "world"
    write_tree(get_target("pybullet").generate(GenerationRequest(path, world, None)), folder)
    data = json.loads((folder / "world.json").read_text())
    assert data["objects"][0]["trajectory"]["start_when"] == {
        "floor": "g_2_4", "x": floor.x, "y": floor.y, "within": 1.2}
    manifest = load_manifest(folder)
    assert manifest.objects[0].trajectory is not None
    assert manifest.objects[0].trajectory.start_when == (floor.x, floor.y, 1.2)
    # without a trigger, nothing of it is written (older worlds read the same)
    plain = _write(tmp_path, "", "plain.room")
    write_tree(get_target("pybullet").generate(
        GenerationRequest(plain, concretise_room(load_room(plain, Workspace())), None)),
        tmp_path / "plain")
    assert "start_when" not in (tmp_path / "plain" / "world.json").read_text()


@pytest.mark.parametrize(("trigger", "rule", "at", "message"), [
    ("when robot within 1.2 of g_2_44", "REF-UNRESOLVED", "g_2_44",
     "expected the name of a floor, found 'g_2_44'; did you mean 'g_2_4'"),
    ("when robot within 1.2 of g_0_0", "REF-KIND", "g_0_0",
     "'h': expected a floor to start the trajectory near, found the wall 'g_0_0'"),
    ("when robot within -1 of g_2_4", "NUM-RANGE", "when",
     "start distance of 'h's trajectory (m): expected a number > 0 and <= 1000, found -1"),
    ("when robot within 0 of g_2_4", "NUM-RANGE", "when",
     "expected a number > 0 and <= 1000, found 0"),
    ("when robot within nan of g_2_4", "NUM-FINITE", "when",
     "start distance of 'h's trajectory (m): expected a finite number, found 'nan'"),
    ("when robot within inf of g_2_4", "NUM-FINITE", "when", "found 'inf'"),
    (f"{GOOD} when robot within 2 of g_2_5", "OPTION-REPEAT",
     "when robot within 2",
     "trajectory of 'h': expected one 'when robot within', found another"),
])
def test_a_bad_trigger_is_a_located_error_with_exit_2(tmp_path: Path, trigger: str, rule: str,
                                                      at: str, message: str) -> None:
    """``at``: the text the error's column points at, on the human's line (9)."""
    path = _write(tmp_path, trigger)
    column = ROOM.replace("TRIGGER", trigger).splitlines()[8].index(at) + 1
    result = subprocess.run([sys.executable, "-m", "rei.lang.cli", "check", str(path)],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 2, result.stdout + result.stderr
    assert "Traceback" not in result.stderr
    line = next(ln for ln in result.stdout.splitlines() if f": {rule}: " in ln)
    assert line.startswith(f"{path}:9:{column}: {rule}: ") and message in line


def test_a_misspelt_trigger_is_a_syntax_error_naming_the_line(tmp_path: Path) -> None:
    path = _write(tmp_path, "when robot near 1.2 of g_2_4")
    result = subprocess.run([sys.executable, "-m", "rei.lang.cli", "check", str(path)],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 2 and f"{path}:9:" in result.stdout
    assert "SYNTAX" in result.stdout and "within" in result.stdout


def test_the_printer_round_trips_the_trigger(tmp_path: Path) -> None:
    doc = load_room(_write(tmp_path, GOOD), Workspace())
    assert doc.room is not None
    text = print_room(doc.room)
    assert "when robot within 1.2 of g_2_4" in text
    (tmp_path / "again.room").write_text(text, encoding="utf-8")
    again = load_room(tmp_path / "again.room", Workspace())
    assert again.ok and again.room is not None
    [human] = [o for o in again.room.objects if o.role == "human"]
    assert human.trajectory is not None and human.trajectory.trigger is not None
    assert (human.trajectory.trigger.floor.name, human.trajectory.trigger.distance) == \
        ("g_2_4", 1.2)


def test_completion_walks_through_the_trigger(tmp_path: Path) -> None:
    doc = load_room(_write(tmp_path, GOOD), Workspace())
    head = "room x {\n    human h on g_1_4 trajectory stop "

    def labels(before: str) -> list[str]:
        return [c.label for c in room_completions(head + before, doc.room, None)]

    assert {"when", "total", "loop", "stop"} <= set(labels(""))
    assert labels("when ") == ["robot"]
    assert labels("when robot ") == ["within"]
    assert labels("when robot within ") == []
    assert labels("when robot within 1.5 ") == ["of"]
    floors = labels("when robot within 1.5 of ")
    assert "g_2_4" in floors and "g_0_0" not in floors
    # the trigger's words are not offered as statements of the room
    statements = [c.label for c in room_completions("room x {\n    ", doc.room, None)]
    assert "human" in statements and not {"when", "within", "of"} & set(statements)


def test_gazebo_starts_the_actor_at_the_planned_time_and_says_so(tmp_path: Path) -> None:
    path = _write(tmp_path, GOOD)
    world = concretise_room(load_room(path, Workspace()))
    sdf = get_target("gazebo").generate(GenerationRequest(path, world, None)).files["world.sdf"]
    ign_check(tmp_path, sdf)
    root = etree.fromstring(sdf)
    actor = next(root.iter("actor"))
    robot, floor = world.robot, world.floor("g_2_4")
    assert robot.type.drive is not None
    planned = (math.hypot(floor.x - robot.pose.x, floor.y - robot.pose.y) - 1.2) / \
        robot.type.drive.max_linear
    assert float(actor.findtext("script/delay_start")) == pytest.approx(planned, abs=1e-3)
    comments = " ".join(str(c.text) for c in root.iter(etree.Comment))
    assert "starts when the robot comes within 1.2 m of floor 'g_2_4'" in comments
    assert f"planned time {planned:.3f} s" in comments
    # without a trigger the actor starts with the world, and no such comment
    plain = _write(tmp_path, "", "plain.room")
    sdf = get_target("gazebo").generate(GenerationRequest(
        plain, concretise_room(load_room(plain, Workspace())), None)).files["world.sdf"]
    root = etree.fromstring(sdf)
    assert float(next(root.iter("actor")).findtext("script/delay_start")) == 0.0
    assert "planned time" not in sdf.decode()
