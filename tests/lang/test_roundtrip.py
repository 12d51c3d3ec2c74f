"""Roundtrip: load → print → load gives the same model, for every example and random grids."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from rei.lang.printer import print_mission, print_room
from rei.lang.room.document import RoomDocument
from rei.lang.workspace import Workspace
from tests.conftest import example_files
from tests.lang.test_grid_equivalence import grid_text, rows_strategy


def room_essence(doc: RoomDocument):  # type: ignore[no-untyped-def]
    room = doc.room
    assert room is not None
    named = {t for links in room.neighbours.values() for t in links.values()}
    named_walls = named & set(room.walls)
    return (room.name, room.tile_size, dict(room.neighbours), named_walls,
            [(o.name, o.role, o.type, o.floor.name, o.heading_deg,
              None if o.trajectory is None else (
                  [(v.floor.name, v.time) for v in o.trajectory.vertices],
                  o.trajectory.total_time, o.trajectory.loop))
             for o in room.objects],
            {n: doc.layout.cells[n] for n in room.floors if n in doc.layout.cells},
            sorted(d.rule for d in doc.diagnostics if d.rule != "WALL-ORPHAN"))


@pytest.mark.parametrize("path", example_files(".room"), ids=lambda p: p.name)
def test_room_roundtrip(path: Path, tmp_path: Path) -> None:
    first = Workspace().room(path)
    printed = tmp_path / path.name
    printed.write_text(print_room(first.room))  # type: ignore[arg-type]
    second = Workspace().room(printed)
    assert second.ok, second.diagnostics
    assert room_essence(first) == room_essence(second)


@pytest.mark.parametrize("path", example_files(".mission"), ids=lambda p: p.name)
def test_mission_roundtrip(path: Path, tmp_path: Path) -> None:
    first = Workspace().mission(path)
    assert first.mission is not None
    room_rel = os.path.relpath(first.mission.room_path, tmp_path)
    printed = tmp_path / path.name
    printed.write_text(print_mission(first.mission, room_rel))
    second = Workspace().mission(printed)
    assert second.ok, second.diagnostics
    a, b = first.mission, second.mission
    assert b is not None
    assert (a.name, a.cycles, a.time_limit, a.max_speed) == (b.name, b.cycles, b.time_limit,
                                                              b.max_speed)
    assert [(g.name, g.floor.name, g.tolerance, g.heading_deg, g.timeout) for g in a.goals] == [
        (g.name, g.floor.name, g.tolerance, g.heading_deg, g.timeout) for g in b.goals]


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=rows_strategy)
def test_random_grid_rooms_roundtrip(tmp_path: Path, rows: list[str]) -> None:
    source = tmp_path / "g.room"
    source.write_text(grid_text(rows))
    first = Workspace().room(source)
    printed = tmp_path / "p.room"
    printed.write_text(print_room(first.room))  # type: ignore[arg-type]
    assert room_essence(first) == room_essence(Workspace().room(printed))
