"""The language server knows a trajectory's start trigger: pytest-lsp's client drives
``rei-lsp`` over stdio; the diagnostics are located on the trigger, and completion offers its
words and the room's floors."""

from __future__ import annotations

from pathlib import Path

import pytest
import pytest_lsp
from lsprotocol import types

from tests.lsp.conftest import CONFIG, Editor, RecordingClient, initialize_params, position_of

pytestmark = pytest.mark.asyncio(loop_scope="module")

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


@pytest_lsp.fixture(config=CONFIG, scope="module")
async def client(lsp_client: RecordingClient):  # type: ignore[no-untyped-def]
    await lsp_client.initialize_session(initialize_params())
    yield
    await lsp_client.shutdown_session()


async def _labels(client: RecordingClient, path: Path, position: types.Position) -> list[str]:
    result = await client.text_document_completion_async(types.CompletionParams(
        text_document=types.TextDocumentIdentifier(uri=path.resolve().as_uri()),
        position=position))
    assert isinstance(result, types.CompletionList)
    return [item.label for item in result.items]


async def test_trigger_diagnostics_and_completion(client: RecordingClient, tmp_path: Path
                                                  ) -> None:
    path = tmp_path / "hall.room"
    editor = Editor(client)
    good = ROOM.replace("TRIGGER", "start when robot within 1.2 of g_2_4")
    assert await editor.open(path, good) == []

    bad = ROOM.replace("TRIGGER", "start when robot within -2 of g_2_44")
    published = await editor.change(path, bad)
    found = {(str(d.code), d.range.start.line, d.range.start.character) for d in published}
    line = bad.splitlines()[8]
    assert ("NUM-RANGE", 8, line.index("start")) in found
    assert ("REF-UNRESOLVED", 8, line.index("g_2_44")) in found

    assert await editor.change(path, good) == []
    half = ROOM.replace("TRIGGER", "start when robot within 1.2 of ")
    await editor.change(path, half)  # does not parse: floors come from the last good version
    floors = await _labels(client, path, position_of(half, "of  total", offset=3))
    assert {"g_2_4", "g_1_4"} <= set(floors) and "g_0_0" not in floors
    typed = ROOM.replace("TRIGGER", "start ")
    await editor.change(path, typed)
    assert await _labels(client, path, position_of(typed, "start ", offset=6)) == ["when"]
    await editor.close(path)
