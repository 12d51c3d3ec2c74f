"""`rei demo`'s suite (issue 22): on every seed it meets a navigator blind on either side with a
person appearing on that side (a doorway on the robot's left and one on its right), and its
small rooms use every level of every factor of the small preset (a speed-limited mission, a
goal heading, ...). Read back from the files `rei demo` writes, with the room language's own
parser, not from the generator's records."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import pytest

from rei.generators.rooms import PRESETS
from rei.lang.workspace import Workspace, load_mission
from rei.runtime.commands.demo import DEMO_ROOMS, doorway_share, generate_suite, stress_share


def _side_of_doorway_person(mission: Path, workspace: Workspace) -> str:
    """'left' or 'right': where the doorway's person steps out, looking along the robot's way
    (the straight line from its start to the second goal, which the doorway lies along)."""
    doc = load_mission(mission, workspace)
    assert doc.mission is not None and doc.room is not None and doc.room.room is not None
    cells = doc.room.layout.cells  # type: ignore[union-attr]
    start, goal = (cells[g.floor.name] for g in doc.mission.goals[:2])
    [person] = [o for o in doc.room.room.objects if o.name == "doorway_person"]
    assert person.trajectory is not None and person.trajectory.trigger is not None
    level = cells[person.trajectory.trigger.floor.name]
    door = cells[person.trajectory.vertices[-1].floor.name]
    d = (goal[0] - start[0], goal[1] - start[1])
    n = (door[0] - level[0], door[1] - level[1])
    assert abs(n[0]) + abs(n[1]) == 1  # the doorway is the tile beside the route's tile
    # the route's tile lies on the robot's straight way, between its start and the goal
    t = ((level[0] - start[0]) * d[0] + (level[1] - start[1]) * d[1]) / (d[0] ** 2 + d[1] ** 2)
    assert 0 < t < 1
    cross = d[0] * n[1] - d[1] * n[0]  # x east, y north: > 0 is to the left
    assert abs(cross) >= 0.9 * math.hypot(*d)  # across the way, not along it
    return "left" if cross > 0 else "right"


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_the_demo_suite_has_a_doorway_on_each_side_and_every_small_level(
        tmp_path: Path, seed: int) -> None:
    indexes = generate_suite(tmp_path / "suite", DEMO_ROOMS, "small", seed)
    assert [i.parent.name for i in indexes] == ["suite", "stress", "doorway"]
    rows = {i.parent.name: list(csv.DictReader(i.read_text(encoding="utf-8").splitlines()))
            for i in indexes}
    assert [r["stressor"] for r in rows["stress"]] == ["emerge", "crossing", "gap", "standing"]
    workspace = Workspace()
    sides = sorted(_side_of_doorway_person(indexes[2].parent / r["mission"], workspace)
                   for r in rows["doorway"])
    assert sides == ["left", "right"]
    # Balanced rows: the three small rooms use every level of every factor.
    for factor, levels in PRESETS["small"].items():
        assert {r[factor] for r in rows["suite"]} == set(levels), factor
    # A speed-limited mission and one without are really written (a speed limit is what
    # SPEED_LIMIT needs to catch a navigator ignoring it).
    limits = set()
    for r in rows["suite"]:
        mission = load_mission(indexes[0].parent / r["mission"], workspace).mission
        assert mission is not None
        limits.add(mission.max_speed)
    assert limits == {None, 0.18}


def test_smaller_demos_keep_their_rooms_and_the_default_adds_the_doorway_pair() -> None:
    shares = {count: (count - stress_share(count, "small") - doorway_share(count, "small"),
                      stress_share(count, "small"), doorway_share(count, "small"))
              for count in (1, 2, 4, 6, 7, 8, 9, 10)}
    assert shares == {1: (1, 0, 0), 2: (1, 1, 0), 4: (2, 2, 0), 6: (3, 3, 0), 7: (4, 3, 0),
                      8: (2, 4, 2), 9: (3, 4, 2), 10: (4, 4, 2)}
    assert DEMO_ROOMS == 9
    assert stress_share(8, "medium") == doorway_share(8, "medium") == 0


def test_the_demo_suite_is_a_pure_function_of_the_seed(tmp_path: Path) -> None:
    def files(folder: Path) -> dict[str, bytes]:
        generate_suite(folder, DEMO_ROOMS, "small", 2)
        return {p.relative_to(folder).as_posix(): p.read_bytes()
                for p in sorted(folder.rglob("*")) if p.is_file()}

    first, again = files(tmp_path / "a"), files(tmp_path / "b")
    assert first == again
    assert sum(name.startswith("doorway/") and name.endswith(".room") for name in first) == 2
