"""The search's continuous placement (generators/rooms/scenario.py): ``--object-shift``,
``--goal-shift`` and ``--path-shift``. For each: the candidate's files carry the move as
``offset DX DY`` within its range and towards what the documentation says, they pass the
`rei-gen check` rules on disk (nothing on a wall, off its tile or into another body), the
runtime reads the moved positions, and the same row gives the same bytes. Bad ranges (exit 2
naming the flag) are in test_search_input.py."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rei.catalogue import Cylinder, default_catalogue
from rei.generators.concrete.build import load_concrete_mission
from rei.generators.rooms.construct import ROBOT_TYPE, RoomPlan
from rei.generators.rooms.scenario import MAX_PLACEMENT, TILE, object_rooms, towards
from rei.generators.rooms.writer import read_metadata
from rei.lang.room.checks import offset_problem, rotated_half_extents
from tests.conftest import REPO
from tests.search.test_scenario_dimensions import (
    ONE_HUMAN,
    candidate,
    checked,
    same_bytes_and_table_row,
)

OFFSET = re.compile(r" offset (-?[\d.]+) (-?[\d.]+)")


def _offsets(text: str, head: str) -> dict[str, tuple[float, float]]:
    """``name -> offset`` for the lines starting with ``head`` (0, 0 when none)."""
    out = {}
    for line in text.splitlines():
        if line.strip().startswith(head):
            found = OFFSET.search(line)
            name = line.split()[1]
            out[name] = (float(found[1]), float(found[2])) if found else (0.0, 0.0)
    return out


def _plan(built) -> RoomPlan:  # type: ignore[no-untyped-def]
    assert built.pair is not None, built.problem
    return built.pair.plan


def test_objects_move_towards_the_route_within_their_tiles(tmp_path: Path) -> None:
    built = candidate(tmp_path / "a", [("object_shift", "-0.3:0.3")], 1.0)
    room, mission = checked(tmp_path / "a", built)
    text = room.read_text()
    assert read_metadata(text)["scenario"] == {"object_shift": "0.3"}
    plan = _plan(built)
    moved = _offsets(text, "object ")
    assert moved and set(moved) == {o.name for o in plan.objects}
    catalogue = default_catalogue()
    world = load_concrete_mission(mission).world
    for obj in plan.objects:
        dx, dy = moved[obj.name]
        assert 0 < math.hypot(dx, dy) <= 0.3 + 1e-9, obj
        hx, hy = rotated_half_extents(catalogue.types[obj.type], obj.heading)
        assert abs(dx) + hx <= TILE / 2 + 1e-9 and abs(dy) + hy <= TILE / 2 + 1e-9
        # towards the route: nearer its nearest tile than the tile's centre is
        nearest = min(plan.route, key=lambda c, o=obj: math.dist(c, o.cell))
        assert math.dist((obj.cell[0] + dx, obj.cell[1] + dy), nearest) < \
            math.dist(obj.cell, nearest)
        body = next(o for o in world.objects if o.name == obj.name)
        centre = world.floor(f"area_{-obj.cell[1]}_{obj.cell[0]}")
        assert (body.pose.x - centre.x, body.pose.y - centre.y) == pytest.approx((dx, dy))
    # The checks can fail: at the range's middle (0 m) nothing moves, and -0.3 moves away.
    still = candidate(tmp_path / "b", [("object_shift", "-0.3:0.3")], 0.5)
    assert " offset " not in checked(tmp_path / "b", still)[0].read_text()
    away = candidate(tmp_path / "c", [("object_shift", "-0.3:0.3")], 0.0)
    back = _offsets(checked(tmp_path / "c", away)[0].read_text(), "object ")
    assert all(back[n] == pytest.approx((-x, -y), abs=1e-3) for n, (x, y) in moved.items())


def test_goals_but_the_start_move_towards_the_nearest_wall_or_object(tmp_path: Path) -> None:
    built = candidate(tmp_path / "a", [("goal_shift", "0:0.4")], 1.0)
    room, mission = checked(tmp_path / "a", built)
    plan = _plan(built)
    goals = list(_offsets(mission.read_text(), "goal ").values())
    assert goals[0] == (0.0, 0.0)  # the robot's start stays where the robot is
    robot = default_catalogue().types[ROBOT_TYPE].footprint.circumradius()
    standing = {o.cell for o in plan.objects}
    concrete = load_concrete_mission(mission)
    for cell, (dx, dy), goal in zip(plan.goals[1:], goals[1:], concrete.goals[1:],
                                    strict=True):
        # cut short where the robot standing there would leave the goal's tile
        assert 0 < max(abs(dx), abs(dy)) <= TILE / 2 - robot + 1e-9
        blocked = [(cell[0] + i, cell[1] + j) for i in (-1, 0, 1) for j in (-1, 0, 1)
                   if (cell[0] + i, cell[1] + j) not in plan.floors
                   or (cell[0] + i, cell[1] + j) in standing]
        nearest = min(blocked, key=lambda c, g=cell: math.dist(c, g))
        assert math.dist((cell[0] + dx, cell[1] + dy), nearest) < math.dist(cell, nearest)
        centre = concrete.world.floor(goal.floor)
        assert (goal.x - centre.x, goal.y - centre.y) == pytest.approx((dx, dy))


def test_path_vertices_move_within_their_tiles(tmp_path: Path) -> None:
    built = candidate(tmp_path / "a", [("path_shift", "-0.2:0.2")], 0.0)
    room, mission = checked(tmp_path / "a", built)
    plan = _plan(built)
    [human] = plan.humans
    assert len(human.offsets) == len(human.vertices)
    half = max(default_catalogue().types["human"].footprint.half_extents())
    assert all(max(abs(x), abs(y)) <= TILE / 2 - half + 1e-9 for x, y in human.offsets)
    assert any(o != (0.0, 0.0) for o in human.offsets)
    world = load_concrete_mission(mission).world
    walker = next(o for o in world.objects if o.name == "walker_1")
    assert walker.trajectory is not None
    first = walker.trajectory.points[0]
    centre = world.floor(f"area_{-human.vertices[0][1]}_{human.vertices[0][0]}")
    assert (first.x - centre.x, first.y - centre.y) == pytest.approx(human.offsets[0])
    # and the human stands there at the start (no jump to its path on the first tick)
    assert (walker.pose.x, walker.pose.y) == pytest.approx((first.x, first.y))
    # The generator keeps its curves 0.35 m off walls and objects and the vertices move
    # towards the route (free floor), so the largest shift is built in every one of these
    # layouts; a curve it would push into something is refused by the checker
    # (TRAJ-CROSSES where the offsets put it: tests/lang/test_offset.py).
    for seed in range(6):
        far = candidate(tmp_path / f"l{seed}", [("path_shift", "0.24:0.25")], 1.0,
                        layout=seed)
        checked(tmp_path / f"l{seed}", far)


@settings(max_examples=15, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(u=st.floats(0.0, 1.0), layout=st.integers(0, 40))
def test_every_built_candidate_passes_the_checker(tmp_path: Path, u: float,
                                                  layout: int) -> None:
    """A property over shifts and layouts: a candidate is either refused with a problem or
    its files pass `rei-gen check` on disk (``checked``), its offsets inside their ranges."""
    folder = tmp_path / f"p{layout}-{u}"
    scenario = [("object_shift", "-0.5:0.5"), ("goal_shift", "-0.5:0.5"),
                ("path_shift", "-0.5:0.5")]
    built = candidate(folder, scenario, u, layout=layout)
    if built.pair is None:
        assert built.problem
        return
    room, mission = checked(folder, built)
    for text, head in ((room.read_text(), "object "), (mission.read_text(), "goal ")):
        assert all(max(abs(x), abs(y)) <= MAX_PLACEMENT for x, y in
                   _offsets(text, head).values())


def test_towards_is_cut_short_by_the_room_on_each_axis() -> None:
    assert towards((0, 0), [(3, 0)], 0.4, 0.1, 0.1) == (0.1, 0.0)
    assert towards((0, 0), [(3, 0)], -0.05, 0.1, 0.1) == (-0.05, 0.0)
    assert towards((0, 0), [(2, 2)], 0.3, 0.1, 0.2) == (0.1, 0.1)  # diagonal: x runs out
    assert towards((0, 0), [(0, 0)], 0.3, 0.1, 0.1) == (0.0, 0.0)  # on the target
    assert towards((0, 0), [], 0.3, 0.1, 0.1) == (0.0, 0.0)
    # the first of equally near targets, so the move does not depend on a set's order
    assert towards((0, 0), [(0, 1), (1, 0)], 0.2, 0.5, 0.5) == (0.0, 0.2)


def test_same_row_same_bytes_and_the_table_lists_each_shift(tmp_path: Path) -> None:
    scenario = [("object_shift", "-0.3:0.3"), ("goal_shift", "0:0.25"),
                ("path_shift", "-0.2:0.2")]
    head, row = same_bytes_and_table_row(tmp_path, scenario, 0.7, 0.8)
    assert head.endswith("object_shift,goal_shift,path_shift,problem")
    assert ",0.12,0.175,0.08," in row
    assert "object_shift=0.12" in (tmp_path / "t" / "index.csv").read_text()


@pytest.mark.slow
def test_a_real_search_with_the_shifts_runs_the_moved_scenario(tmp_path: Path) -> None:
    """`rei search` with the three shifts (two real pybullet runs): every candidate is built,
    checked and run, search.csv has a column per shift, the world each run simulated has the
    objects where the candidate's offsets put them, off their tiles' centres, and the same
    command again resumes to the same bytes."""
    import json  # noqa: PLC0415
    import subprocess  # noqa: PLC0415
    import sys  # noqa: PLC0415

    from tests.search.test_search_runs import SAFETY_LIMIT, outputs, table  # noqa: PLC0415

    out = tmp_path / "out"
    argv = [sys.executable, "-m", "rei.runtime.commands", "search", "-o", str(out), "--layout", "5",
            *(a for k, v in ONE_HUMAN for a in (f"--{k.replace('_', '-')}", v)),
            "--object-shift", "0.1:0.3", "--goal-shift", "0:0.25", "--path-shift=-0.2:0.2",
            "--budget", "2", "--batch", "2", "--workers", "1", "--strategy", "random",
            "--no-report", "-q"]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert done.returncode in (0, 1), done.stderr  # a verdict, not bad input or an error
    rows = table(out)
    assert len(rows) == 2 and all(r["verdict"] in ("pass", "fail") for r in rows), rows
    for row in rows:
        assert 0.1 <= float(row["object_shift"]) <= 0.3
        assert 0 <= float(row["goal_shift"]) <= 0.25
        assert -0.2 <= float(row["path_shift"]) <= 0.2
        mission = out / "candidates" / f"{row['candidate']}_0001.mission"
        concrete = load_concrete_mission(mission).world
        world = json.loads((out / "runs" / row["run_id"] / "world" / "world.json").read_text())
        simulated = {o["name"]: o["pose"][:2] for o in world["objects"]}
        statics = [o for o in concrete.objects if o.role == "static"]
        assert statics
        off = []
        for body in statics:
            centre = concrete.floor(body.floor)
            assert simulated[body.name] == pytest.approx([body.pose.x, body.pose.y], abs=1e-3)
            off.append(math.dist((body.pose.x, body.pose.y), (centre.x, centre.y)))
        assert max(off) > 0.05, off  # moved (a big table may have no room on its tile)
    # Run again: the search replays its recorded batch and changes no byte.
    before = outputs(out)
    again = subprocess.run(argv, capture_output=True, text=True, timeout=SAFETY_LIMIT)
    assert again.returncode == done.returncode, again.stderr
    assert outputs(out) == before


def test_an_objects_room_is_the_checkers_own_bound() -> None:
    """Issue 25: a table or shelf barely moves because it fills its tile. The generator's
    bound (``object_room``) is exactly OFFSET-TILE's: a move that far along an axis passes
    the checker, 2 mm more is refused, at every kind and heading the generator uses."""
    catalogue = default_catalogue()
    rooms = object_rooms(catalogue)
    assert set(rooms) == {"box", "chair", "pillar", "shelf", "table"}
    for name, by_heading in rooms.items():
        for heading, (room_x, room_y) in by_heading.items():
            hx, hy = rotated_half_extents(catalogue.types[name], heading)
            for offset, half in (((room_x, 0.0), (hx, hy)), ((0.0, room_y), (hx, hy))):
                assert offset_problem(offset, TILE, *half) == "", (name, heading)
            assert offset_problem((room_x + 0.002, 0.0), TILE, hx, hy) != ""
            assert offset_problem((0.0, room_y + 0.002), TILE, hx, hy) != ""
    assert rooms["table"][0.0] == pytest.approx((0.1, 0.2))  # 0.8 x 0.6 m on a 1 m tile


def room_table() -> list[str]:
    """docs/search.md's table of how far each kind can move (regenerate it from this)."""
    catalogue = default_catalogue()
    lines = ["| kind | footprint | farthest from its tile's centre, x × y (m), by heading |",
             "|---|---|---|"]
    for name, by_heading in object_rooms(catalogue).items():
        footprint = catalogue.types[name].footprint
        if isinstance(footprint, Cylinder):
            shape, where = f"disc, radius {footprint.radius:g} m", "any heading"
        else:
            hx, hy = footprint.half_extents()
            shape, where = f"{2 * hx:g} × {2 * hy:g} m", ""
        groups: dict[tuple[float, float], list[float]] = {}
        for heading, (x, y) in by_heading.items():
            groups.setdefault((_mm(x), _mm(y)), []).append(heading)
        text = "; ".join(f"{where or ', '.join(f'{h:g}°' for h in headings)}: {x:g} × {y:g}"
                         for (x, y), headings in groups.items())
        lines.append(f"| {name} | {shape} | {text} |")
    return lines


def _mm(value: float) -> float:
    return math.trunc(round(value * 1000.0, 6)) / 1000.0


def test_the_documented_table_of_object_room_is_the_catalogues() -> None:
    """docs/search.md says how far each catalogue kind can move; a catalogue or bound that
    changes fails here until the table is regenerated (``room_table()``)."""
    docs = (REPO / "docs" / "search.md").read_text(encoding="utf-8").splitlines()
    table = room_table()
    assert table[0] in docs, "\n".join(table)
    start = docs.index(table[0])
    assert docs[start:start + len(table)] == table, "\n".join(table)
