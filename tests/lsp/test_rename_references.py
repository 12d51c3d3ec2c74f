"""Rename and find-references across the workspace (issue 27.1): pytest-lsp's real client
drives the real ``rei-lsp``; every rename is applied to the texts and the result is checked
again with the command line's own checker (``Workspace.check``), so a rename that broke a
reference would show as a diagnostic."""

from __future__ import annotations

from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types
from pygls.exceptions import JsonRpcException

from rei.lang.workspace import Workspace
from tests.lsp.conftest import CONFIG, Editor, RecordingClient, initialize_params, position_of
from tests.lsp.rooms import MISSION, ROOM

pytestmark = pytest.mark.asyncio(loop_scope="module")

OTHER_MISSION = """\
// Another mission of the café, saved but not open in the editor.
mission back in "cafe.room" {
    goal home at porch   // porch, again
    goal out at start
}
"""

VEPL = """\
specification cafe_rules
parameters { margin = 0.5  eps_close = 0.25 }
function crowded(o)
query near(h: object[human]) { distance(robot, h) < margin }
query nearAny() { find near(_) }
queryEvent comes(h) as near(h) found
queryEvent goes(h) as near(h) lost
complexEvent pass() { as (comes -> goes)[2000] context immediate }
signal SIG_NEAR on comes utility -1
signal SIG_PASS on pass utility -2
requirement KEEP_AWAY "keep away" { never SIG_NEAR  count pass < 3 }
"""


@pytest_lsp.fixture(config=CONFIG, scope="module")
async def client(lsp_client: RecordingClient, tmp_path_factory: pytest.TempPathFactory
                 ):  # type: ignore[no-untyped-def]
    root = tmp_path_factory.getbasetemp() / "rename-workspace"
    root.mkdir(exist_ok=True)
    await lsp_client.initialize_session(initialize_params(root))
    yield
    await lsp_client.shutdown_session()


@pytest.fixture
def folder(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.getbasetemp() / "rename-workspace"
    path.mkdir(exist_ok=True)
    (path / "cafe.room").write_text(ROOM, encoding="utf-8")
    (path / "visit.mission").write_text(MISSION, encoding="utf-8")
    (path / "missions").mkdir(exist_ok=True)
    (path / "missions" / "back.mission").write_text(OTHER_MISSION.replace(
        '"cafe.room"', '"../cafe.room"'), encoding="utf-8")
    (path / "rules.vepl").write_text(VEPL, encoding="utf-8")
    return path


def ident(path: Path) -> types.TextDocumentIdentifier:
    return types.TextDocumentIdentifier(uri=path.resolve().as_uri())


def apply(text: str, edits: list[types.TextEdit]) -> str:
    """Apply LSP text edits (ASCII texts: UTF-16 units are characters)."""
    lines = text.split("\n")
    offsets = [0]
    for line in lines:
        offsets.append(offsets[-1] + len(line) + 1)
    spans = sorted(((offsets[e.range.start.line] + e.range.start.character,
                     offsets[e.range.end.line] + e.range.end.character, e.new_text)
                    for e in edits), reverse=True)
    for start, end, new in spans:
        text = text[:start] + new + text[end:]
    return text


async def rename(client: RecordingClient, path: Path, position: types.Position, new: str
                 ) -> dict[str, list[types.TextEdit]]:
    edit = await client.text_document_rename_async(types.RenameParams(
        text_document=ident(path), position=position, new_name=new))
    assert edit is not None and edit.changes is not None
    return dict(edit.changes)


def apply_all(changes: dict[str, list[types.TextEdit]]) -> dict[Path, str]:
    out = {}
    for uri, edits in changes.items():
        path = Path(uri.removeprefix("file://"))
        out[path] = apply(path.read_text(encoding="utf-8"), edits)
    return out


def still_valid(texts: dict[Path, str], *paths: Path) -> None:
    workspace = Workspace()
    for path, text in texts.items():
        workspace.set_text(path, text)
    for path in paths:
        assert [d.rule for d in workspace.check(path)] == [], path


async def test_renaming_a_legend_floor_changes_the_room_and_every_mission(
        client: RecordingClient, folder: Path) -> None:
    editor = Editor(client)
    room = folder / "cafe.room"
    await editor.open(room)
    changes = await rename(client, room, position_of(ROOM, "floor start", offset=7), "entry")
    texts = apply_all(changes)
    back = (folder / "missions" / "back.mission").resolve()
    assert set(texts) == {room.resolve(), (folder / "visit.mission").resolve(), back}
    assert 'floor entry' in texts[room.resolve()] and "on entry heading" in texts[room.resolve()]
    assert "goal out at entry" in texts[back]
    assert "start" not in texts[room.resolve()].split("legend")[1].split("}")[0]
    still_valid(texts, room.resolve(), back, (folder / "visit.mission").resolve())
    await editor.close(room)


async def test_references_of_an_explicit_floor_across_files(client: RecordingClient,
                                                            folder: Path) -> None:
    editor = Editor(client)
    mission = folder / "visit.mission"
    await editor.open(mission)
    # From a mission goal: the floor of the room, its declaration and every reference.
    found = await client.text_document_references_async(types.ReferenceParams(
        text_document=ident(mission), position=position_of(MISSION, "at yard", offset=4),
        context=types.ReferenceContext(include_declaration=True)))
    assert found is not None
    places = sorted((Path(loc.uri).name, loc.range.start.line, loc.range.start.character)
                    for loc in found)
    room_line = ROOM.split("\n").index("    floor yard { top fence left terrace }")
    assert places == [("cafe.room", room_line, 10), ("visit.mission", 2, 17)]
    # Without the declaration.
    found = await client.text_document_references_async(types.ReferenceParams(
        text_document=ident(mission), position=position_of(MISSION, "at yard", offset=4),
        context=types.ReferenceContext(include_declaration=False)))
    assert [Path(loc.uri).name for loc in found or []] == ["visit.mission"]
    await editor.close(mission)


async def test_renaming_objects_humans_walls_and_the_robot(client: RecordingClient,
                                                          folder: Path) -> None:
    editor = Editor(client)
    room = folder / "cafe.room"
    await editor.open(room)
    for needle, offset, new in (("wall fence", 5, "hedge"), ("human walker", 6, "visitor"),
                                ("robot bot", 6, "rover"), ("object desk", 7, "counter"),
                                ("floor porch", 6, "veranda"), ("grid hall", 5, "room2")):
        changes = await rename(client, room, position_of(ROOM, needle, offset=offset), new)
        texts = apply_all(changes)
        assert new in texts[room.resolve()]
        still_valid(texts, room.resolve())
    # The porch: its declaration, the walker on it, its trajectory, the unopened mission.
    changes = await rename(client, room, position_of(ROOM, "floor porch", offset=6), "veranda")
    assert sum(len(edits) for edits in changes.values()) == 4
    # A grid's new name renames the cells it names by position, and nothing else.
    texts = apply_all(await rename(client, room, position_of(ROOM, "grid hall", offset=5),
                                   "room2"))
    assert "left room2_2_3" in texts[room.resolve()] and "on room2_2_1" in texts[room.resolve()]
    await editor.close(room)


async def refused(client: RecordingClient, path: Path, position: types.Position, new: str
                  ) -> str:
    with pytest.raises(JsonRpcException) as raised:
        await client.text_document_rename_async(types.RenameParams(
            text_document=ident(path), position=position, new_name=new))
    return str(raised.value)


async def test_a_clash_a_keyword_or_a_non_identifier_is_refused(client: RecordingClient,
                                                                folder: Path) -> None:
    editor = Editor(client)
    room = folder / "cafe.room"
    await editor.open(room)
    at_porch = position_of(ROOM, "floor porch", offset=6)
    assert "already the name of a floor" in await refused(client, room, at_porch, "terrace")
    assert "already the name of a robot" in await refused(client, room, at_porch, "bot")
    assert "keyword" in await refused(client, room, at_porch, "goal")  # breaks the missions
    assert "expected an identifier" in await refused(client, room, at_porch, "two words")
    assert "expected an identifier" in await refused(client, room, at_porch, "9lives")
    cell = position_of(ROOM, "left hall_2_3", offset=6)
    message = await refused(client, room, cell, "corner")
    assert "give the cell a name in the grid's legend" in message
    # prepareRename says the same before the user types a name.
    with pytest.raises(JsonRpcException, match="legend"):
        await client.text_document_prepare_rename_async(types.PrepareRenameParams(
            text_document=ident(room), position=cell))
    prepared = await client.text_document_prepare_rename_async(types.PrepareRenameParams(
        text_document=ident(room), position=at_porch))
    assert isinstance(prepared, types.PrepareRenamePlaceholder)
    assert prepared.placeholder == "porch"
    # A keyword or a type is nothing to rename.
    with pytest.raises(JsonRpcException, match="nothing to rename"):
        await client.text_document_prepare_rename_async(types.PrepareRenameParams(
            text_document=ident(room), position=position_of(ROOM, "turtlebot3_waffle",
                                                             offset=2)))
    await editor.close(room)


async def test_vepl_names_rename_everywhere_they_are_used(client: RecordingClient,
                                                         folder: Path) -> None:
    editor = Editor(client)
    vepl = folder / "rules.vepl"
    await editor.open(vepl)
    cases = (("query near", 7, "close", 4), ("queryEvent comes", 12, "arrives", 3),
             ("complexEvent pass", 14, "closePass", 3), ("signal SIG_NEAR", 8, "SIG_CLOSE", 2),
             ("requirement KEEP", 13, "AWAY", 1), ("margin =", 1, "space", 2),
             ("function crowded", 10, "busy", 1))
    for needle, offset, new, count in cases:
        changes = await rename(client, vepl, position_of(VEPL, needle, offset=offset), new)
        assert sum(len(e) for e in changes.values()) == count, needle
        still_valid(apply_all(changes), vepl.resolve())
    # A query's parameter is renamed inside its query only.
    changes = await rename(client, vepl, position_of(VEPL, "(h: object", offset=1), "person")
    texts = apply_all(changes)
    assert "query near(person: object[human]) { distance(robot, person)" in texts[vepl.resolve()]
    assert "queryEvent comes(h) as near(h)" in texts[vepl.resolve()]
    # Clashes, builtins, and parameters the monitor reads by name.
    assert "already the name of a event" in await refused(
        client, vepl, position_of(VEPL, "query near", offset=7), "goes")
    assert "gives meaning to" in await refused(
        client, vepl, position_of(VEPL, "query near", offset=7), "distance")
    assert "read by name" in await refused(
        client, vepl, position_of(VEPL, "eps_close", offset=1), "closeness")
    await editor.close(vepl)


async def test_a_goal_renames_in_its_mission(client: RecordingClient, folder: Path) -> None:
    editor = Editor(client)
    mission = folder / "visit.mission"
    await editor.open(mission)
    changes = await rename(client, mission, position_of(MISSION, "goal first", offset=6),
                           "arrive")
    assert apply_all(changes)[mission.resolve()].count("goal arrive at start") == 1
    assert "already the name of a goal" in await refused(
        client, mission, position_of(MISSION, "goal first", offset=6), "last")
    await editor.close(mission)


async def test_requests_before_the_first_check_wait_for_it(client: RecordingClient,
                                                           folder: Path) -> None:
    """Hover, definition, outline and references sent right after didOpen (no wait for the
    diagnostics) answer about the file, not null."""
    room = folder / "cafe.room"
    uri = room.resolve().as_uri()
    client.text_document_did_open(types.DidOpenTextDocumentParams(
        text_document=types.TextDocumentItem(uri=uri, language_id="room", version=1,
                                             text=ROOM)))
    at_start = position_of(ROOM, "on start", offset=4)
    hover = await client.text_document_hover_async(types.HoverParams(
        text_document=ident(room), position=at_start))
    assert hover is not None and "start" in str(hover.contents)
    symbols = await client.text_document_document_symbol_async(
        types.DocumentSymbolParams(text_document=ident(room)))
    assert symbols
    client.text_document_did_close(types.DidCloseTextDocumentParams(text_document=ident(room)))


async def test_a_rename_edits_the_unsaved_buffer_not_the_saved_file(client: RecordingClient,
                                                                   folder: Path) -> None:
    """The room open with unsaved lines above: the edits land on the buffer's positions."""
    editor = Editor(client)
    room = folder / "cafe.room"
    buffer = "// two lines the editor\n// has not saved yet\n" + ROOM
    await editor.open(room, buffer)
    changes = await rename(client, room, position_of(buffer, "floor porch", offset=6),
                           "veranda")
    edits = changes[room.resolve().as_uri()]
    renamed = apply(buffer, edits)
    assert "floor veranda {" in renamed and "human walker on veranda" in renamed
    assert "veranda at 0" in renamed and "porch" not in renamed
    await editor.close(room)
