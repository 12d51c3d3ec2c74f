"""Hostile files in the editor (issue 13.4-5): inputs that used to block the server or crash
a check now show located diagnostics, and the server goes on checking other files. A real
client drives the real ``rei-lsp`` subprocess (tests/lsp/test_internal_error.py: a check
that breaks shows as an INTERNAL diagnostic)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from lsprotocol import types

from tests.lsp.conftest import (
    Editor,
    RecordingClient,
    wait_published,
)
from tests.lsp.rooms import ROOM

pytestmark = pytest.mark.asyncio(loop_scope="module")


async def still_checks_others(editor: Editor, tmp_path: Path) -> None:
    """Diagnostics of an unrelated file still arrive, and are right."""
    path = tmp_path / "other.room"
    assert await editor.open(path, ROOM) == []
    assert [d.code for d in await editor.change(path, ROOM.replace("on start", "on strat"))] \
        == ["REF-UNRESOLVED"]
    await editor.close(path)


async def test_a_fifo_as_room_import_or_catalogue_never_blocks(client: RecordingClient,
                                                               tmp_path: Path) -> None:
    os.mkfifo(tmp_path / "pipe.room")
    os.mkfifo(tmp_path / "pipe.toml")
    editor = Editor(client)
    mission = tmp_path / "m.mission"
    published = await editor.open(mission, 'mission m in "pipe.room" {\n'
                                           "  goal a at x timeout 1\n  goal b at y timeout 1\n}\n")
    assert [d.code for d in published] == ["MISSION-ROOM"]
    assert "expected a regular file, found a FIFO" in published[0].message
    room = tmp_path / "c.room"
    published = await editor.open(room, ROOM.replace("tile 1.0", 'catalogue "pipe.toml"'))
    assert "CATALOGUE-FILE" in [d.code for d in published]
    await still_checks_others(editor, tmp_path)
    await editor.close(mission)
    await editor.close(room)


async def test_a_symlink_loop_and_a_thousand_suffixes_are_diagnostics(
        client: RecordingClient, tmp_path: Path) -> None:
    """Both used to escape the checker (RuntimeError, RecursionError): the editor showed
    these files clean."""
    (tmp_path / "loop_a.room").symlink_to(tmp_path / "loop_b.room")
    (tmp_path / "loop_b.room").symlink_to(tmp_path / "loop_a.room")
    editor = Editor(client)
    mission = tmp_path / "loop.mission"
    published = await editor.open(mission, 'mission m in "loop_a.room" {\n'
                                           "  goal a at x timeout 1\n  goal b at y timeout 1\n}\n")
    assert [d.code for d in published] == ["MISSION-ROOM"]
    assert "loop of symbolic links" in published[0].message
    # The editor may also open the looping file itself (its buffer is what is checked).
    uri = (tmp_path / "loop_a.room").as_uri()
    mark = len(client.published)
    client.text_document_did_open(types.DidOpenTextDocumentParams(
        text_document=types.TextDocumentItem(uri=uri, language_id="room", version=1,
                                             text="room r {\n}\n")))
    published = await wait_published(client, uri, after=mark, version=1)
    assert [d.code for d in published] == ["ROBOT-COUNT"]
    client.text_document_did_close(types.DidCloseTextDocumentParams(
        text_document=types.TextDocumentIdentifier(uri=uri)))
    vepl = tmp_path / "suffixes.vepl"
    text = ("query close() { laser_min < 1 }\nqueryEvent a() as close found\n"
            "complexEvent many(){ as a" + "{+}" * 1000 + " }\n")
    published = await editor.open(vepl, text)
    assert [d.code for d in published] == ["VEPL-LIMIT"]
    assert published[0].range.start.line == 2
    await still_checks_others(editor, tmp_path)
    await editor.close(mission)
    await editor.close(vepl)
