"""Measure how long a diagnostics update takes in ``rei-lsp`` for 1,000-floor rooms.

Run: ``python -m tests.lsp.measure_updates`` (from the repository root). A real client
(pytest-lsp's, outside pytest) starts the real server over stdio, opens each room, then
times didChange → publishDiagnostics for that version, and a mission importing the room
(room edit → the mission's re-check). Prints a Markdown table. Not a test: no wall-clock
limits in tests.
"""

from __future__ import annotations

import asyncio
import statistics
import tempfile
import time
from pathlib import Path

from tests.lsp.conftest import (
    SERVER_COMMAND,
    Editor,
    initialize_params,
    make_client,
    publish_index,
    wait_published,
)
from tests.lsp.rooms import explicit_room, grid_room

EDITS = 15


async def measure() -> list[tuple[str, int, float, float, float]]:
    client = make_client()
    await client.start_io(*SERVER_COMMAND)
    await client.initialize_session(initialize_params())
    rows: list[tuple[str, int, float, float, float]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for name, text, goal in (("grid 40 × 25 with walls", grid_room(), "g_25_40"),
                                 ("1,000 explicit floors", explicit_room(), "f999")):
            room = folder / "big.room"
            mission = folder / "big.mission"
            room.write_text(text, encoding="utf-8")
            editor = Editor(client)
            await editor.open(room)
            times: list[float] = []
            for k in range(EDITS):
                edited = text + f"// edit {k}\n"
                start = time.perf_counter()
                await editor.change(room, edited)
                times.append(time.perf_counter() - start)
            rows.append((f"{name}: room edit → room diagnostics", len(text.encode()),
                         statistics.median(times), min(times), max(times)))
            mission.write_text(f'mission m in "big.room" {{\n goal a at r_floor\n'
                               f' goal b at {goal}\n}}\n'.replace("r_floor", goal), "utf-8")
            await editor.open(mission)
            room_uri = room.resolve().as_uri()
            mission_uri = mission.resolve().as_uri()
            times = []
            for k in range(EDITS):
                edited = text + f"// again {k}\n"
                start = time.perf_counter()
                await editor.change(room, edited)
                mark = publish_index(client, room_uri, editor.versions[room_uri])
                await wait_published(client, mission_uri, after=mark)
                times.append(time.perf_counter() - start)
            rows.append((f"{name}: room edit → room and mission diagnostics",
                         len(text.encode()), statistics.median(times), min(times), max(times)))
            await editor.close(mission)
            await editor.close(room)
    await client.shutdown_session()
    await client.stop()
    return rows


def main() -> None:
    rows = asyncio.run(measure())
    print("| update | file bytes | median ms | min ms | max ms |")
    print("|---|---:|---:|---:|---:|")
    for name, size, median, low, high in rows:
        print(f"| {name} | {size} | {median * 1000:.0f} | {low * 1000:.0f} | {high * 1000:.0f} |")


if __name__ == "__main__":
    main()
