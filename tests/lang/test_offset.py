"""`offset DX DY` (grammars/common.tx): a static object, a trajectory vertex or a goal moved
from its floor's centre within the tile. Parsed, carried into the concrete model (what the
simulator and the monitors read), printed back, refused with a located error when it takes
the thing off its tile or is not a finite number."""

from __future__ import annotations

from pathlib import Path

import pytest

from rei.generators.concrete.build import concretise_room, load_concrete_mission
from rei.lang.printer import print_mission, print_room
from rei.lang.workspace import Workspace, load_mission, load_room

ROOM = """room hall {
    grid g {
        "#######"
        "#.....#"
        "#.....#"
        "#######"
    }
    robot r : turtlebot3_waffle on g_1_1
    object c : chair on g_2_3 CHAIR heading 90
    human h on g_1_3 trajectory total 8 stop {
        g_1_3 VERTEX
        g_1_5
    }
}
"""
MISSION = """mission m in "hall.room" {
    goal at g_1_1
    goal at g_2_5 GOAL tolerance 0.3
}
"""


def _files(tmp_path: Path, chair: str = "offset 0.1 -0.2", vertex: str = "offset 0 -0.25",
           goal: str = "offset 0.2 0.15") -> tuple[Path, Path]:
    tmp_path.mkdir(parents=True, exist_ok=True)
    room = tmp_path / "hall.room"
    room.write_text(ROOM.replace("CHAIR", chair).replace("VERTEX", vertex), encoding="utf-8")
    mission = tmp_path / "m.mission"
    mission.write_text(MISSION.replace("GOAL", goal), encoding="utf-8")
    return room, mission


def _errors(path: Path) -> list[str]:
    return [f"{d.span.line}:{d.rule}: {d.message}" for d in Workspace().check(path)
            if d.is_error]


def test_offsets_reach_the_concrete_model(tmp_path: Path) -> None:
    room, mission = _files(tmp_path)
    assert _errors(room) == [] and _errors(mission) == []
    concrete = load_concrete_mission(mission)
    world = concrete.world
    chair = next(o for o in world.objects if o.name == "c")
    floor = world.floor("g_2_3")
    assert (chair.pose.x, chair.pose.y) == pytest.approx((floor.x + 0.1, floor.y - 0.2))
    human = next(o for o in world.objects if o.name == "h")
    assert human.trajectory is not None
    first = human.trajectory.points[0]
    start = world.floor("g_1_3")
    assert (first.x, first.y) == pytest.approx((start.x, start.y - 0.25))
    goal = concrete.goals[1]
    end = world.floor("g_2_5")
    assert (goal.x, goal.y) == pytest.approx((end.x + 0.2, end.y + 0.15))
    # The comparison can fail: without offsets the same things sit at their floors' centres.
    _, plain_mission = _files(tmp_path / "plain", "", "", "")
    plain = load_concrete_mission(plain_mission)
    assert (plain.goals[1].x, plain.goals[1].y) == (end.x, end.y)
    assert next(o for o in plain.world.objects if o.name == "c").pose.x == floor.x


def test_offsets_print_back_to_the_same_model(tmp_path: Path) -> None:
    room, mission = _files(tmp_path)
    doc = load_room(room, Workspace())
    assert doc.room is not None
    again = tmp_path / "again"
    again.mkdir()
    (again / "hall.room").write_text(print_room(doc.room), encoding="utf-8")
    m_doc = load_mission(mission, Workspace())
    assert m_doc.mission is not None
    (again / "m.mission").write_text(print_mission(m_doc.mission, "hall.room"),
                                     encoding="utf-8")
    second = load_room(again / "hall.room", Workspace())
    assert second.ok and second.room is not None
    assert [o.offset for o in second.room.objects] == [o.offset for o in doc.room.objects]
    assert [v.offset for o in second.room.objects if o.trajectory
            for v in o.trajectory.vertices] == [(0.0, -0.25), (0.0, 0.0)]
    m_second = load_mission(again / "m.mission", Workspace())
    assert m_second.ok and m_second.mission is not None
    assert [g.offset for g in m_second.mission.goals] == [(0.0, 0.0), (0.2, 0.15)]
    assert concretise_room(second).objects == concretise_room(doc).objects


@pytest.mark.parametrize(("chair", "vertex", "goal", "line", "expected"), [
    # the chair's 0.45 m footprint leaves 0.275 m either way on a 1 m tile
    ("offset 0.3 0", "", "", 9, "OBJECT-FIT: 'c' (chair): expected an offset keeping a "
                                "footprint 0.45 x 0.45 m on its 1 m tile (at most 0.275 m in x "
                                "and 0.275 m in y), found offset 0.3 0"),
    ("", "offset 0.51 0", "", 11, "OFFSET-TILE: trajectory of 'h': expected an offset keeping "
                                  "a point on its 1 m tile"),
    ("offset nan 0", "", "", 9, "NUM-FINITE: offset of 'c' (x, metres): expected a finite "
                                "number, found 'nan'"),
    ("", "offset 0 inf", "", 11, "NUM-FINITE"),
])
def test_an_offset_off_its_tile_or_not_finite_is_a_located_error(
        tmp_path: Path, chair: str, vertex: str, goal: str, line: int, expected: str) -> None:
    room, _ = _files(tmp_path, chair, vertex, goal)
    errors = _errors(room)
    assert any(e.startswith(f"{line}:") and expected.split(": ", 1)[0] in e
               and expected.split(": ", 1)[-1] in e for e in errors), errors
    # and the room without it is clean: the error is the offset's doing
    clean, _ = _files(tmp_path / "clean", "", "", "")
    assert _errors(clean) == []


def test_a_goal_offset_off_its_tile_is_refused_at_the_goal(tmp_path: Path) -> None:
    _, mission = _files(tmp_path, goal="offset 0 -0.7")
    assert any(e.startswith("3:OFFSET-TILE: goal 'goal_2': expected an offset keeping a point "
                            "on its 1 m tile") for e in _errors(mission)), _errors(mission)
    _, mission = _files(tmp_path, goal="offset 0 0.5")  # the tile's edge is still on it
    assert _errors(mission) == []


def test_a_vertex_offset_moves_the_curve_into_a_wall_check(tmp_path: Path) -> None:
    """The walked curve is checked where the offsets put it: 0.2 m nearer the wall row the
    human's 0.25 m disc grazes it (TRAJ-CROSSES); at the centre it does not."""
    room = tmp_path / "hall.room"
    text = ROOM.replace("CHAIR", "").replace("VERTEX", "offset 0 0.3")
    text = text.replace("        g_1_5\n", "        g_1_5 offset 0 0.3\n")
    room.write_text(text, encoding="utf-8")
    assert any(":TRAJ-CROSSES:" in e for e in _errors(room)), _errors(room)
    room.write_text(ROOM.replace("CHAIR", "").replace("VERTEX", ""), encoding="utf-8")
    assert _errors(room) == []
