"""End to end: pytest-lsp's client drives ``rei-lsp`` over stdio (one server per module)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
from lsprotocol import types

from rei.lang.workspace import Workspace
from tests.lang.test_start_trigger import ROOM as TRIGGER_ROOM
from tests.lsp.conftest import (
    Editor,
    RecordingClient,
    position_of,
    publish_index,
    wait_published,
)
from tests.lsp.rooms import MISSION, ROOM

pytestmark = pytest.mark.asyncio(loop_scope="module")


@pytest.fixture(scope="module")
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("lsp")
    (path / "cafe.room").write_text(ROOM, encoding="utf-8")
    (path / "visit.mission").write_text(MISSION, encoding="utf-8")
    return path


def uri(path: Path) -> str:
    return path.resolve().as_uri()


def codes(diagnostics: list[types.Diagnostic]) -> list[str]:
    return [str(d.code) for d in diagnostics]


def as_tuple(r: types.Range) -> tuple[int, int, int, int]:
    return r.start.line, r.start.character, r.end.line, r.end.character


BROKEN_ROOM = """\
room broken {
    floor a { right b top a }
    floor b { left c }
    floor lonely
    wall w
    robot r : turtlebot3_waffle on a
    robot r2 : no_such_type on wall_or_not
    object o : table on w
}
"""


async def test_diagnostics_are_the_command_line_ones(client: RecordingClient, tmp_path: Path
                                                     ) -> None:
    path = tmp_path / "broken.room"
    path.write_text(BROKEN_ROOM, encoding="utf-8")
    editor = Editor(client)
    published = await editor.open(path)
    cli = subprocess.run([sys.executable, "-m", "rei.lang.cli", "check", "--format", "json",
                          str(path)], capture_output=True, text=True, check=False)
    expected = json.loads(cli.stdout)
    assert len(expected) >= 5
    assert [(d["rule"], d["line"] - 1, d["col"] - 1, d["end_line"] - 1, d["end_col"] - 1)
            for d in expected] == [(str(d.code), *as_tuple(d.range)) for d in published]
    assert {d.source for d in published} == {"rei"}
    assert all(d.severity == types.DiagnosticSeverity.Error for d in published)
    await editor.close(path)


async def test_syntax_error_is_located_and_fixing_it_clears_it(client: RecordingClient,
                                                               tmp_path: Path) -> None:
    path = tmp_path / "typing.room"
    editor = Editor(client)
    text = "room r {\n    floor a\n    robot x : turtlebot3_waffle on\n}\n"
    published = await editor.open(path, text)
    assert codes(published) == ["SYNTAX"]
    assert as_tuple(published[0].range) == (3, 0, 3, 1)  # the '}' where a name was expected
    assert "expected a name" in published[0].message
    fixed = await editor.edit(path, 2, len("    robot x : turtlebot3_waffle on"),
                              len("    robot x : turtlebot3_waffle on"), " a")
    assert fixed == []
    assert await editor.close(path) == []


async def test_ranges_count_utf16_code_units(client: RecordingClient, tmp_path: Path) -> None:
    path = tmp_path / "accents.room"
    line = "    /* café 😀 */ object cup : table on nowhere"
    text = f"room r {{\n    floor a\n    robot x : turtlebot3_waffle on a\n{line}\n}}\n"
    published = await Editor(client).open(path, text)
    unresolved = [d for d in published if d.code == "REF-UNRESOLVED"]
    assert len(unresolved) == 1
    # 'nowhere' starts after an accent (1 unit) and an emoji (2 units) in UTF-16.
    start = len(line[:line.index("nowhere")].encode("utf-16-le")) // 2
    assert as_tuple(unresolved[0].range) == (3, start, 3, start + len("nowhere"))


async def completion_labels(client: RecordingClient, path: Path, position: types.Position
                            ) -> list[str]:
    result = await client.text_document_completion_async(types.CompletionParams(
        text_document=types.TextDocumentIdentifier(uri=uri(path)), position=position))
    assert isinstance(result, types.CompletionList)
    return [item.label for item in result.items]


async def test_completion_of_names_types_and_keywords(client: RecordingClient, folder: Path
                                                      ) -> None:
    path = folder / "cafe.room"
    editor = Editor(client)
    await editor.open(path)
    # Half-typed: the file no longer parses, names come from the last version that did.
    text = ROOM[:-2] + "    object lamp : \n}\n"
    diagnostics = await editor.change(path, text)
    assert codes(diagnostics) == ["SYNTAX"]
    after_colon = position_of(text, "object lamp : ", offset=len("object lamp : "))
    types_offered = await completion_labels(client, path, after_colon)
    assert "table" in types_offered and "chair" in types_offered
    assert "turtlebot3_waffle" not in types_offered  # a robot type for a static object

    text = ROOM[:-2] + "    object lamp : chair on \n}\n"
    await editor.change(path, text)
    after_on = position_of(text, "chair on ", offset=len("chair on "))
    floors = await completion_labels(client, path, after_on)
    assert {"start", "porch", "yard", "hall_2_1"} <= set(floors)
    assert "fence" not in floors and "hall_0_0" not in floors  # walls are not floors

    text = ROOM[:-2] + "    ob\n}\n"
    await editor.change(path, text)
    keywords = await completion_labels(client, path, position_of(text, "    ob", offset=6))
    assert {"object", "robot", "floor", "grid", "human", "dynamic"} <= set(keywords)

    in_links = position_of(ROOM, "floor porch { ", offset=len("floor porch { "))
    await editor.change(path, ROOM)
    assert set(await completion_labels(client, path, in_links)) == {"top", "right", "bottom",
                                                                     "left"}
    after_side = position_of(ROOM, "top fence", offset=len("top "))
    assert "fence" in await completion_labels(client, path, after_side)
    in_trajectory = position_of(ROOM, "terrace at 5", offset=0)
    assert "terrace" in await completion_labels(client, path, in_trajectory)
    await editor.close(path)


# Issue 25: keywords are offered where the grammar accepts them. `offset` follows a placement
# (an object's floor, a trajectory vertex, a goal's floor), never a statement's start.
async def test_completion_offers_a_clause_only_where_the_grammar_accepts_it(
        client: RecordingClient, folder: Path) -> None:
    path = folder / "cafe.room"
    editor = Editor(client)
    await editor.open(path)
    text = ROOM.replace("    tile 1.0\n", "    tile 1.0\n    \n")
    await editor.change(path, text)
    at_start = await completion_labels(client, path, position_of(text, "1.0\n    ", offset=8))
    assert {"object", "human", "robot", "floor", "grid", "tile"} <= set(at_start)
    assert not {"offset", "heading", "behaviour", "trajectory", "at", "on"} & set(at_start)

    text = ROOM[:-2] + "    object lamp : table on hall_2_1 \n}\n"
    await editor.change(path, text)
    after = await completion_labels(client, path, position_of(text, "hall_2_1 \n", offset=9))
    assert {"offset", "heading", "object", "human"} <= set(after)
    assert "behaviour" not in after and "trajectory" not in after  # a human's, not an object's
    half = ROOM[:-2] + "    object lamp : table on hall_2_1 offset 0.2 \n}\n"
    await editor.change(path, half)
    assert await completion_labels(client, path, position_of(half, "0.2 \n", offset=4)) == []

    vertex = position_of(ROOM, "porch at 0", offset=len("porch "))
    await editor.change(path, ROOM)
    assert {"offset", "at"} <= set(await completion_labels(client, path, vertex))
    await editor.close(path)

    mission = folder / "visit.mission"
    await editor.open(mission)
    goal = await completion_labels(client, mission, position_of(MISSION, "at start\n", offset=9))
    assert {"offset", "tolerance", "goal"} <= set(goal)
    start = await completion_labels(client, mission, position_of(MISSION, "    goal first"))
    assert "goal" in start and "offset" not in start and "tolerance" not in start
    await editor.close(mission)


async def test_mission_completion_offers_the_floors_of_its_room(client: RecordingClient,
                                                                folder: Path) -> None:
    path = folder / "visit.mission"
    editor = Editor(client)
    assert await editor.open(path) == []
    labels = await completion_labels(client, path, position_of(MISSION, "at start", offset=3))
    assert {"start", "yard", "porch"} <= set(labels)
    keywords = await completion_labels(client, path, position_of(MISSION, "    goal last"))
    assert {"goal", "cycles", "time_limit", "max_speed"} <= set(keywords)
    rooms = await completion_labels(client, path, position_of(MISSION, '"cafe', offset=0))
    assert rooms == ['"cafe.room"']
    await editor.close(path)


async def definition(client: RecordingClient, path: Path, position: types.Position
                     ) -> list[types.Location]:
    result = await client.text_document_definition_async(types.DefinitionParams(
        text_document=types.TextDocumentIdentifier(uri=uri(path)), position=position))
    assert isinstance(result, list)
    return [r for r in result if isinstance(r, types.Location)]


async def test_definition_of_floors_grid_cells_and_types(client: RecordingClient, folder: Path
                                                         ) -> None:
    path = folder / "cafe.room"
    editor = Editor(client)
    await editor.open(path)
    # A link to an explicit floor jumps to that floor's name.
    [loc] = await definition(client, path, position_of(ROOM, "right terrace", offset=7))
    assert loc.uri == uri(path)
    assert loc.range == types.Range(start=position_of(ROOM, "terrace\n"),
                                    end=position_of(ROOM, "terrace\n", offset=7))
    # A reference to a grid floor jumps to its character in the grid.
    [loc] = await definition(client, path, position_of(ROOM, "on start", offset=4))
    assert loc.range == types.Range(start=position_of(ROOM, "S.."),
                                    end=position_of(ROOM, "S..", offset=1))
    [loc] = await definition(client, path, position_of(ROOM, "on hall_2_1", offset=5))
    assert loc.range.start == position_of(ROOM, '"#..."', offset=2)
    # An object's type jumps into the catalogue file that defines it.
    [loc] = await definition(client, path, position_of(ROOM, ": table", offset=3))
    assert loc.uri.endswith("/default.toml")
    catalogue_text = Path(loc.uri.removeprefix("file://")).read_text(encoding="utf-8")
    assert catalogue_text.split("\n")[loc.range.start.line].startswith("[types.table]")
    await editor.close(path)


async def test_definition_from_a_mission_goal_into_the_room(client: RecordingClient,
                                                            folder: Path) -> None:
    path = folder / "visit.mission"
    editor = Editor(client)
    await editor.open(path)
    [loc] = await definition(client, path, position_of(MISSION, "at yard", offset=4))
    assert loc.uri == uri(folder / "cafe.room")
    assert loc.range.start == position_of(ROOM, "yard {")
    [loc] = await definition(client, path, position_of(MISSION, '"cafe.room"', offset=2))
    assert loc.uri == uri(folder / "cafe.room")
    await editor.close(path)


async def hover_text(client: RecordingClient, path: Path, position: types.Position) -> str:
    result = await client.text_document_hover_async(types.HoverParams(
        text_document=types.TextDocumentIdentifier(uri=uri(path)), position=position))
    assert result is not None
    assert isinstance(result.contents, types.MarkupContent)
    return result.contents.value


async def test_hover_tells_position_neighbours_and_catalogue_facts(client: RecordingClient,
                                                                   folder: Path) -> None:
    path = folder / "cafe.room"
    mission = folder / "visit.mission"
    editor = Editor(client)
    await editor.open(path)
    text = await hover_text(client, path, position_of(ROOM, "left terrace", offset=6))
    assert "**floor** `terrace`" in text
    # start is the origin (0, 0); terrace is 4 cells right and 1 down, tiles of 1 m.
    assert "cell (4, -1)" in text and "(4, -1) m" in text
    assert "left `porch`" in text and "right `yard`" in text and "top —" in text
    text = await hover_text(client, path, position_of(ROOM, "S.."))
    assert "**floor** `start`" in text and "grid `hall`, row 1, column 1" in text
    assert "`bot` (turtlebot3_waffle)" in text
    text = await hover_text(client, path, position_of(ROOM, "desk", offset=1))
    assert "**static** `desk` : table" in text
    assert "footprint: box" in text and "mass" in text and "kg" in text
    text = await hover_text(client, path, position_of(ROOM, "fence", offset=2))
    assert "**wall** `fence`" in text
    await editor.open(mission)
    text = await hover_text(client, mission, position_of(MISSION, "at yard", offset=4))
    assert "**floor** `yard`" in text and "top `fence`" in text
    await editor.close(mission)
    await editor.close(path)


def flatten(symbols: list[types.DocumentSymbol]) -> dict[str, types.DocumentSymbol]:
    out: dict[str, types.DocumentSymbol] = {}
    for symbol in symbols:
        out[symbol.name] = symbol
        out.update(flatten(list(symbol.children or [])))
    return out


async def document_symbols(client: RecordingClient, path: Path) -> list[types.DocumentSymbol]:
    result = await client.text_document_document_symbol_async(types.DocumentSymbolParams(
        text_document=types.TextDocumentIdentifier(uri=uri(path))))
    assert result is not None
    return [s for s in result if isinstance(s, types.DocumentSymbol)]


async def test_outline_maps_grid_cells_to_floor_names(client: RecordingClient, folder: Path
                                                      ) -> None:
    path = folder / "cafe.room"
    editor = Editor(client)
    await editor.open(path)
    [room] = await document_symbols(client, path)
    assert room.name == "cafe" and room.kind == types.SymbolKind.Module
    children = {s.name: s for s in room.children or []}
    assert set(children) >= {"hall", "porch", "terrace", "fence", "yard", "bot", "desk",
                             "walker"}
    assert children["bot"].kind == types.SymbolKind.Class
    cells = {s.name: s for s in children["hall"].children or []}
    assert len(cells) == 12
    assert cells["start"].range == types.Range(start=position_of(ROOM, "S.."),
                                               end=position_of(ROOM, "S..", offset=1))
    assert cells["hall_0_0"].kind == types.SymbolKind.Constant  # a wall
    assert cells["start"].kind == types.SymbolKind.Field
    await editor.close(path)
    mission = folder / "visit.mission"
    await editor.open(mission)
    [outline] = await document_symbols(client, mission)
    assert [g.name for g in outline.children or []] == ["first", "last"]
    await editor.close(mission)


async def test_a_mission_rechecks_when_its_room_changes(client: RecordingClient, folder: Path
                                                        ) -> None:
    room_path = folder / "cafe.room"
    mission_path = folder / "visit.mission"
    editor = Editor(client)
    await editor.open(mission_path)
    mark = len(client.published)
    await editor.open(room_path)
    # Opening the room re-checks the mission that imports it (now against the buffer).
    assert await wait_published(client, uri(mission_path), after=mark) == []
    # Rename the floor 'yard' in the (unsaved) room: the mission's goal no longer resolves.
    # (Each wait is for the mission's re-check after the room's check of the new version.)
    await editor.change(room_path, ROOM.replace("yard", "garden"))
    mark = publish_index(client, uri(room_path), editor.versions[uri(room_path)])
    mission_diagnostics = await wait_published(client, uri(mission_path), after=mark)
    assert codes(mission_diagnostics) == ["REF-UNRESOLVED"]
    assert as_tuple(mission_diagnostics[0].range)[:2] == (2, MISSION.split("\n")[2].index("yard"))
    # Saving and editing back: the mission is clean again.
    editor.save(room_path)
    await editor.change(room_path, ROOM)
    mark = publish_index(client, uri(room_path), editor.versions[uri(room_path)])
    assert await wait_published(client, uri(mission_path), after=mark) == []
    # Break the room: the mission reports the room's problem at its import.
    await editor.change(room_path, ROOM.replace("on start", "on nowhere"))
    mark = publish_index(client, uri(room_path), editor.versions[uri(room_path)])
    mission_diagnostics = await wait_published(client, uri(mission_path), after=mark)
    assert codes(mission_diagnostics) == ["MISSION-ROOM"]
    # Closing the unsaved room: the mission reads the room from the disk again (valid).
    mark = len(client.published)
    await editor.close(room_path)
    assert await wait_published(client, uri(mission_path), after=mark) == []
    await editor.close(mission_path)


async def test_an_example_room_opens_clean(client: RecordingClient, examples_dir: Path) -> None:
    path = examples_dir / "navigation" / "navigation.room"
    editor = Editor(client)
    published = await editor.open(path)
    assert codes(published) == [d.rule for d in Workspace().check(path)]
    [room] = await document_symbols(client, path)
    assert room.name == "navigation"
    await editor.close(path)


async def test_vepl_diagnostics_completion_outline_and_definition(client: RecordingClient,
                                                                  tmp_path: Path) -> None:
    vepl = pytest.importorskip("rei.lang.vepl.document")
    text = Path(vepl.DEFAULT_VEPL).read_text(encoding="utf-8")
    path = tmp_path / "monitor.vepl"
    path.write_text(text, encoding="utf-8")
    editor = Editor(client)
    published = await editor.open(path)
    assert codes(published) == [d.rule for d in Workspace().check(path)]
    # Queries are completed by name, from the last version that parsed.
    half = text + "\nquery broken() { neg find \n"
    assert "SYNTAX" in codes(await editor.change(path, half))
    labels = await completion_labels(client, path, position_of(half, "neg find \n", offset=9))
    assert {"findCollisionToObject", "findCloseToObject", "queryEvent", "signal"} <= set(labels)
    kinds = text + "\nquery near(o: object[human, \n"
    await editor.change(path, kinds)
    labels = await completion_labels(client, path, position_of(kinds, "human, \n", offset=7))
    assert {"static", "robot", "table", "chair"} <= set(labels)
    assert "queryEvent" not in labels and "wall" not in labels
    await editor.change(path, text)
    outline = {s.name: s for s in await document_symbols(client, path)}
    assert outline["findCollisionToObject"].kind == types.SymbolKind.Function
    [loc] = await definition(client, path, position_of(text, "neg find findCollisionToObject",
                                                       offset=12))
    assert loc.range.start == position_of(text, "findCollisionToObject(o")
    hover = await hover_text(client, path, position_of(text, "as findFarObject", offset=5))
    assert "**query** `findFarObject`" in hover
    await editor.close(path)


async def test_a_room_changed_on_disk_rechecks_open_missions(client: RecordingClient,
                                                             tmp_path: Path) -> None:
    room_path = tmp_path / "cafe.room"
    mission_path = tmp_path / "visit.mission"
    room_path.write_text(ROOM, encoding="utf-8")
    mission_path.write_text(MISSION, encoding="utf-8")
    editor = Editor(client)
    assert await editor.open(mission_path) == []
    # Another program rewrites the room (the room is not open in the editor).
    room_path.write_text(ROOM.replace("floor yard", "floor garden"), encoding="utf-8")
    mark = len(client.published)
    client.workspace_did_change_watched_files(types.DidChangeWatchedFilesParams(changes=[
        types.FileEvent(uri=uri(room_path), type=types.FileChangeType.Changed)]))
    diagnostics = await wait_published(client, uri(mission_path), after=mark)
    assert codes(diagnostics) == ["REF-UNRESOLVED"]
    assert "did you mean 'garden'" in diagnostics[0].message
    await editor.close(mission_path)


OWN_CATALOGUE = """\
[types.lamp]
kind = "{kind}"
description = "A standing lamp."
footprint = {{ shape = "cylinder", radius = 0.2 }}
height = 1.6
mass = 4.0
colour = [1.0, 0.9, 0.6, 1.0]
"""
OWN_ROOM = """\
room lit {
    catalogue "own.toml"
    floor a { right b }
    floor b
    robot x : turtlebot3_waffle on a
    object l : lamp on b
}
"""


async def test_a_rooms_own_catalogue_problems_land_on_the_catalogue(client: RecordingClient,
                                                                    tmp_path: Path) -> None:
    catalogue = tmp_path / "own.toml"
    catalogue.write_text(OWN_CATALOGUE.format(kind="banana"), encoding="utf-8")
    room = tmp_path / "lit.room"
    editor = Editor(client)
    mark = len(client.published)
    assert "CATALOGUE-FILE" in codes(await editor.open(room, OWN_ROOM))
    on_catalogue = await wait_published(client, uri(catalogue), after=mark)
    assert codes(on_catalogue) == ["CATALOGUE-FIELD"]
    assert "banana" in on_catalogue[0].message
    # Fixed on disk: the room is clean, the catalogue's diagnostics are withdrawn, and the
    # room's own type is offered, described and found.
    catalogue.write_text(OWN_CATALOGUE.format(kind="static"), encoding="utf-8")
    mark = len(client.published)
    client.workspace_did_change_watched_files(types.DidChangeWatchedFilesParams(changes=[
        types.FileEvent(uri=uri(catalogue), type=types.FileChangeType.Changed)]))
    assert await wait_published(client, uri(room), after=mark) == []
    assert await wait_published(client, uri(catalogue), after=mark) == []
    text = OWN_ROOM.replace("object l : lamp on b", "object m : ")
    await editor.change(room, text)
    labels = await completion_labels(client, room, position_of(text, "m : ", offset=4))
    assert "lamp" in labels and "table" in labels
    await editor.change(room, OWN_ROOM)
    hover = await hover_text(client, room, position_of(OWN_ROOM, ": lamp", offset=3))
    assert "**static** type `lamp`" in hover and "cylinder of radius 0.2 m" in hover
    assert "mass 4 kg" in hover
    [loc] = await definition(client, room, position_of(OWN_ROOM, ": lamp", offset=3))
    assert loc.uri == uri(catalogue) and loc.range.start.line == 0
    await editor.close(room)


# A trajectory's start trigger: diagnostics located on it, completion of its words and floors.
async def test_trigger_diagnostics_and_completion(client: RecordingClient, tmp_path: Path
                                                  ) -> None:
    path = tmp_path / "hall.room"
    editor = Editor(client)
    good = TRIGGER_ROOM.replace("TRIGGER", "when robot within 1.2 of g_2_4")
    assert await editor.open(path, good) == []

    bad = TRIGGER_ROOM.replace("TRIGGER", "when robot within -2 of g_2_44")
    published = await editor.change(path, bad)
    found = {(str(d.code), d.range.start.line, d.range.start.character) for d in published}
    line = bad.splitlines()[8]
    assert ("NUM-RANGE", 8, line.index("when")) in found
    assert ("REF-UNRESOLVED", 8, line.index("g_2_44")) in found

    assert await editor.change(path, good) == []
    # the trigger's floor is a name like any other: go to its definition; the human's hover
    # says when it starts
    [loc] = await definition(client, path, position_of(good, "of g_2_4", offset=4))
    assert loc.range.start.line == 4  # the grid row holding g_2_4
    hover = await hover_text(client, path, position_of(good, "human h", offset=6))
    assert "starts when the robot is within 1.2 m of `g_2_4`" in hover
    half = TRIGGER_ROOM.replace("TRIGGER", "when robot within 1.2 of ")
    await editor.change(path, half)  # does not parse: floors come from the last good version
    floors = await completion_labels(client, path, position_of(half, "of  total", offset=3))
    assert {"g_2_4", "g_1_4"} <= set(floors) and "g_0_0" not in floors
    typed = TRIGGER_ROOM.replace("TRIGGER", "when ")
    await editor.change(path, typed)
    assert await completion_labels(client, path, position_of(typed, "when ", offset=5)) == ["robot"]
    await editor.close(path)
