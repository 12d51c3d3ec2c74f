"""A `grid` block means the same floors, walls and neighbour links as writing them out."""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from rei.lang.workspace import Workspace

OFFSETS = {"top": (-1, 0), "right": (0, 1), "bottom": (1, 0), "left": (0, -1)}


def explicit_text(rows: list[str], grid: str = "g") -> str:
    """The long form of a grid, written independently of REI's grid expansion."""
    cells = {(r, c): ch for r, row in enumerate(rows) for c, ch in enumerate(row)}
    floors = sorted(rc for rc, ch in cells.items() if ch == ".")
    lines = ["room explicit {"]
    walls_used: set[tuple[int, int]] = set()
    for r, c in floors:
        links = []
        for side, (dr, dc) in OFFSETS.items():
            other = cells.get((r + dr, c + dc))
            if other in (".", "#"):
                links.append(f"{side} {grid}_{r + dr}_{c + dc}")
                if other == "#":
                    walls_used.add((r + dr, c + dc))
        lines.append(f"    floor {grid}_{r}_{c} {{ {' '.join(links)} }}")
    for r, c in sorted(walls_used):
        lines.append(f"    wall {grid}_{r}_{c}")
    r0, c0 = floors[0]
    lines.append(f"    robot bot : turtlebot3_waffle on {grid}_{r0}_{c0}")
    lines.append("}")
    return "\n".join(lines) + "\n"


def grid_text(rows: list[str]) -> str:
    body = "\n".join(f'        "{row}"' for row in rows)
    first = next((r, c) for r, row in enumerate(rows) for c, ch in enumerate(row) if ch == ".")
    return (f"room gridded {{\n    grid g {{\n{body}\n    }}\n"
            f"    robot bot : turtlebot3_waffle on g_{first[0]}_{first[1]}\n}}\n")


def models(tmp: Path, rows: list[str]):  # type: ignore[no-untyped-def]
    (tmp / "grid.room").write_text(grid_text(rows))
    (tmp / "explicit.room").write_text(explicit_text(rows))
    ws = Workspace()
    return ws.room(tmp / "grid.room"), ws.room(tmp / "explicit.room")


def assert_same(gdoc, edoc) -> None:  # type: ignore[no-untyped-def]
    assert gdoc.room is not None and edoc.room is not None
    assert dict(gdoc.room.neighbours) == dict(edoc.room.neighbours)
    assert set(gdoc.room.floors) == set(edoc.room.floors)
    # Walls touching a floor are the same; a grid also places its corner walls.
    assert set(edoc.room.walls) <= set(gdoc.room.walls)
    for name, cell in edoc.layout.cells.items():
        assert gdoc.layout.cells[name] == cell
    assert sorted(d.rule for d in gdoc.diagnostics) == sorted(
        d.rule for d in edoc.diagnostics if d.rule != "WALL-ORPHAN")


def test_l_shaped_room_with_a_hole(tmp_path: Path) -> None:
    rows = ["#######",
            "#.....#",
            "#.#...#",
            "#..####",
            "#..#",
            "####"]
    gdoc, edoc = models(tmp_path, rows)
    assert gdoc.ok and edoc.ok
    assert_same(gdoc, edoc)


rows_strategy = st.lists(st.text(alphabet=".# ", min_size=1, max_size=7), min_size=1,
                         max_size=6).filter(lambda rows: any("." in r for r in rows))


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(rows=rows_strategy)
def test_random_grids_equal_their_long_form(tmp_path: Path, rows: list[str]) -> None:
    gdoc, edoc = models(tmp_path, rows)
    assert_same(gdoc, edoc)


def test_grid_and_explicit_floors_mix(write) -> None:  # type: ignore[no-untyped-def]
    path = write("mixed.room", """room mixed {
    grid g {
        "####"
        "#..#"
        "####"
    }
    floor annex { left g_1_2 right annex_wall }
    wall annex_wall
    robot bot : turtlebot3_waffle on g_1_1
}
""")
    doc = Workspace().room(path)
    # annex replaces the wall cell g_1_3 on the right of g_1_2: the grid's own link and the
    # explicit one disagree, and the checker says so.
    assert any(d.rule in ("LINK-ASYMMETRIC", "FLOOR-OVERLAP") for d in doc.diagnostics)

    path = write("mixed_ok.room", """room mixed {
    grid g {
        "###"
        "#.."
        "###"
    }
    floor annex { left g_1_2 right annex_wall }
    wall annex_wall
    robot bot : turtlebot3_waffle on g_1_1
}
""")
    doc = Workspace().room(path)
    assert doc.ok, doc.diagnostics
    assert doc.layout.cells["annex"] == (2, 0)
    assert doc.layout.cells["annex_wall"] == (3, 0)
