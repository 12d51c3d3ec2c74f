"""The server survives what editors send while people type: junk, half-typed files, huge files,
bursts of edits, positions outside the text, and files it does not know."""

from __future__ import annotations

import asyncio
import random
from pathlib import Path

import pytest
from lsprotocol import types

from tests.lsp.conftest import (
    Editor,
    RecordingClient,
    position_of,
    wait_published,
)
from tests.lsp.rooms import ROOM, explicit_room

pytestmark = pytest.mark.asyncio(loop_scope="module")


def ident(path: Path) -> types.TextDocumentIdentifier:
    return types.TextDocumentIdentifier(uri=path.resolve().as_uri())


async def every_request(client: RecordingClient, path: Path, position: types.Position) -> None:
    """Ask everything at one position; each request must be answered (possibly empty)."""
    doc = ident(path)
    await client.text_document_completion_async(
        types.CompletionParams(text_document=doc, position=position))
    await client.text_document_hover_async(
        types.HoverParams(text_document=doc, position=position))
    await client.text_document_definition_async(
        types.DefinitionParams(text_document=doc, position=position))
    await client.text_document_document_symbol_async(
        types.DocumentSymbolParams(text_document=doc))


async def assert_alive(client: RecordingClient, path: Path) -> None:
    """A real answer after the abuse: the outline of a valid room."""
    result = await client.text_document_document_symbol_async(
        types.DocumentSymbolParams(text_document=ident(path)))
    assert result is not None and [s.name for s in result] == ["cafe"]


@pytest.fixture(scope="module")
def valid_room(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("alive") / "cafe.room"
    path.write_text(ROOM, encoding="utf-8")
    return path


async def test_junk_is_a_diagnostic_not_a_crash(client: RecordingClient, tmp_path: Path,
                                                valid_room: Path) -> None:
    editor = Editor(client)
    await editor.open(valid_room)
    rng = random.Random(7)
    junk = "".join(chr(rng.randrange(0, 0x2FF)) for _ in range(20_000))
    path = tmp_path / "junk.room"
    published = await editor.open(path, junk)
    assert [d.code for d in published] in (["INPUT-ENCODING"], ["SYNTAX"])
    for line, character in ((0, 0), (3, 5), (10_000, 10_000)):
        await every_request(client, path, types.Position(line=line, character=character))
    text = "\x00\x01 room r { floor a }"
    assert [d.code for d in await editor.change(path, text)] == ["INPUT-ENCODING"]
    assert [d.code for d in await editor.change(path, "   \n")] == ["INPUT-EMPTY"]
    await editor.close(path)
    await assert_alive(client, valid_room)


async def test_every_half_typed_prefix_is_answered(client: RecordingClient, tmp_path: Path,
                                                   valid_room: Path) -> None:
    """Type the room a few characters at a time without waiting (a burst of edits): the
    server coalesces them, and the last version's diagnostics arrive (the full room is clean)."""
    path = tmp_path / "typing.room"
    editor = Editor(client)
    await editor.open(path, "r")
    versions = [editor.change_nowait(path, ROOM[:end]) for end in range(2, len(ROOM), 5)]
    last = editor.change_nowait(path, ROOM)
    await every_request(client, path, position_of(ROOM, "on start", offset=4))
    assert await wait_published(client, path.resolve().as_uri(), after=0, version=last) == []
    checked = {p.version for p in client.published if p.uri == path.resolve().as_uri()}
    assert checked <= {1, last, *versions}
    await assert_alive(client, valid_room)
    # Requests on each prefix of a mission, with the file open at that prefix.
    mission = tmp_path / "half.mission"
    await editor.open(mission, "m")
    text = 'mission m in "typing.room" {\n    goal a at start\n    goal b at hall_2_2\n}\n'
    for end in range(1, len(text), 9):
        await editor.change(mission, text[:end])
        lines = text[:end].split("\n")
        await every_request(client, mission,
                            types.Position(line=len(lines) - 1, character=len(lines[-1])))
    assert await editor.change(mission, text) == []
    await editor.close(mission)
    await editor.close(path)


async def test_a_two_megabyte_file_is_checked(client: RecordingClient, tmp_path: Path,
                                              valid_room: Path) -> None:
    editor = Editor(client)
    comment = "// " + "a long comment that pads the file " * 60 + "\n"
    body = comment * (2_000_000 // len(comment) + 1)
    text = ROOM.replace("room cafe {\n", "room cafe {\n" + body)
    assert len(text.encode("utf-8")) > 2_000_000
    path = tmp_path / "huge.room"
    assert await editor.open(path, text) == []
    end = text.count("\n")
    await every_request(client, path, types.Position(line=end - 3, character=10))
    junk = text + "@" * 100
    published = await editor.change(path, junk)
    assert [d.code for d in published] == ["SYNTAX"]
    assert published[0].range.start.line == end
    await editor.close(path)
    await assert_alive(client, valid_room)


async def test_unknown_and_unopened_files(client: RecordingClient, tmp_path: Path,
                                          valid_room: Path) -> None:
    editor = Editor(client)
    notes = tmp_path / "notes.txt"
    assert await editor.open(notes, "not a model") == []
    await every_request(client, notes, types.Position(line=0, character=3))
    await editor.close(notes)
    never_opened = tmp_path / "never.room"
    await every_request(client, never_opened, types.Position(line=0, character=0))
    await assert_alive(client, valid_room)


@pytest.mark.slow
async def test_a_huge_room_does_not_stall_other_requests(client: RecordingClient,
                                                         tmp_path: Path, valid_room: Path
                                                         ) -> None:
    """A room of 10,000 explicit floors (0.45 MB) takes seconds to check; meanwhile the
    server answers requests about other files (checking runs off the event loop)."""
    editor = Editor(client)
    await editor.open(valid_room)
    path = tmp_path / "huge_floors.room"
    uri = path.resolve().as_uri()
    mark = len(client.published)
    client.text_document_did_open(types.DidOpenTextDocumentParams(
        text_document=types.TextDocumentItem(uri=uri, language_id="room", version=1,
                                             text=explicit_room(10_000))))
    hover = await client.text_document_hover_async(types.HoverParams(
        text_document=ident(valid_room), position=position_of(ROOM, "on start", offset=4)))
    assert hover is not None
    assert not any(p.uri == uri for p in client.published[mark:])  # still being checked
    published = await wait_published(client, uri, after=mark, version=1)
    assert published == []
    client.text_document_did_close(types.DidCloseTextDocumentParams(text_document=ident(path)))
    await asyncio.sleep(0)
    await assert_alive(client, valid_room)
