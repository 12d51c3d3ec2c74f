"""Room and mission texts the LSP tests (and the update-time measurement) open."""

from __future__ import annotations

ROOM = """\
// A café room: explicit floors, a grid, objects and a walker.
room cafe {
    tile 1.0
    grid hall {
        legend {
            "S" = floor start
        }
        "####"
        "#S.."
        "#..."
    }
    floor porch { left hall_2_3 right terrace }
    floor terrace
    wall fence
    floor yard { top fence left terrace }
    robot bot : turtlebot3_waffle on start heading 0
    object desk : table on hall_2_1
    human walker on porch trajectory loop {
        porch at 0
        terrace at 5
    }
}
"""

MISSION = """\
mission visit in "cafe.room" {
    goal first at start
    goal last at yard tolerance 0.3
}
"""


def grid_room(width: int = 40, height: int = 25) -> str:
    """A room of width × height floors inside a ring of walls, written as one grid."""
    rows = ["#" * (width + 2)] + ["#" + "." * width + "#" for _ in range(height)]
    rows.append("#" * (width + 2))
    body = "\n".join(f'        "{row}"' for row in rows)
    return (f"room big_grid {{\n    grid g {{\n{body}\n    }}\n"
            f"    robot r : turtlebot3_waffle on g_1_1\n}}\n")


def explicit_room(floors: int = 1000, width: int = 40) -> str:
    """A room of ``floors`` explicit floors in rows of ``width``, linked right and down."""
    lines = ["room big_explicit {"]
    for i in range(floors):
        row, col = divmod(i, width)
        links = []
        if col + 1 < width and i + 1 < floors:
            links.append(f"right f{i + 1}")
        if i + width < floors:
            links.append(f"bottom f{i + width}")
        lines.append(f"    floor f{i} {{ {' '.join(links)} }}")
    lines.append("    robot r : turtlebot3_waffle on f0")
    lines.append("}")
    return "\n".join(lines) + "\n"
